"""The thesis reproduction: every chapter asekit can compute, one thesis-vs-asekit table.

``python -m asekit reproduce [--json PATH|-] [--figures DIR] [--only CHAPTER ...] [--wide]
[--quiet] [--keep-going]``

Each chapter lives in ``asekit.reproduction.<name>`` and exposes
``run(figures: bool) -> ChapterResult``. Thesis values are looked up by key in
``data/thesis.toml``; asekit values are always computed by the chapter.

Every row gets a verdict (:func:`verdict`): a thesis value is compared as a value (within a
relative tolerance), as a bound (a requirement met or missed) or as a range, never a bound as a
percent difference. A chapter whose inputs failed (``ChapterResult.failures``, or an exception)
is reported with its reason and makes the command exit non-zero unless ``--keep-going``.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import logging
import math
import re
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

from asekit.reproduction.thesis import _load, all_keys, is_number, thesis_value
from asekit.util.paths import THESIS_FILE
from asekit.util.plotting import save_figure

_log = logging.getLogger(__name__)

#: Chapters in the thesis's order (its one-way data flow). A chapter whose module does not
#: exist yet is skipped; a chapter whose module exists but fails raises.
CHAPTERS: tuple[tuple[str, str], ...] = (
    ("servo", "Ch. 4 servo-actuator"),
    ("structure", "Ch. 3.1 structure"),
    ("aero", "Ch. 3.2 aerodynamics"),
    ("flutter", "Ch. 3.2.2-3.3 RFA and flutter"),
    ("ase", "Ch. 5 aeroservoelasticity"),
    ("supersonic", "beyond the thesis: the fin from M 0.4 to 3"),
    ("freeplay", "Sec. 6.2 freeplay in the actuator-fin connection (issue 14)"),
    ("design", "beyond Ch. 5: minimum-state RFA, controllers on the elastic fin"),
)


@dataclass(frozen=True)
class Quantity:
    """One computed value: ``key`` (dotted, stable), ``asekit`` (float, list, bool or None when
    the quantity does not exist, e.g. no flutter below the top of the sweep) and its ``unit``.
    ``note`` explains a difference or an assumption in a few words. ``computed`` is False for
    a row this run did not compute (e.g. the converged study without ``--converged``): its
    verdict is then "not computed" whether or not the thesis gives a number, and its note says
    how to compute it."""

    key: str
    asekit: float | list | bool | None
    unit: str
    note: str = ""
    computed: bool = True


@dataclass(frozen=True)
class ChapterResult:
    """A chapter's quantities and figures (``name -> matplotlib Figure``). ``failures`` holds
    the reasons for which some of the chapter's inputs could not be computed (e.g. an unusable
    GAF cache): the quantities then hold None and the command exits non-zero."""

    chapter: str
    quantities: tuple[Quantity, ...]
    figures: dict = field(default_factory=dict)
    failures: tuple[str, ...] = ()


def available_chapters() -> list[str]:
    """Names of the chapters whose module exists in :mod:`asekit.reproduction`."""
    return [name for name, _ in CHAPTERS
            if importlib.util.find_spec(f"asekit.reproduction.{name}") is not None]


def run_chapter(name: str, figures: bool = False) -> ChapterResult:
    """Run one chapter's reproduction."""
    module = importlib.import_module(f"asekit.reproduction.{name}")
    return module.run(figures=figures)


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    return f"{v:.5g}" if isinstance(v, (int, float)) else str(v)


def difference(thesis, asekit) -> str:
    """Human-readable difference asekit - thesis (relative where meaningful)."""
    if thesis is None or asekit is None:
        return ""
    if isinstance(thesis, bool) or isinstance(asekit, bool):
        return "same" if thesis == asekit else "differs"
    if is_number(thesis) and is_number(asekit):
        if math.isinf(thesis) or math.isinf(asekit):
            return "same" if thesis == asekit else "differs"
        d = asekit - thesis
        return f"{d:+.4g} ({100 * d / thesis:+.1f} %)" if thesis != 0 else f"{d:+.4g}"
    if isinstance(thesis, list) and isinstance(asekit, list) and len(thesis) == len(asekit):
        rel = []
        for t, a in zip(thesis, asekit):
            if is_number(t) and is_number(a) and t != 0 and not math.isinf(t):
                rel.append(f"{100 * (a - t) / t:+.1f}")
            else:
                rel.append("?")
        return "[" + ", ".join(rel) + "] %"
    return ""



# --------------------------------------------------------------------------------------------
# verdicts
# --------------------------------------------------------------------------------------------
#: relative tolerance of a value read from a table of the thesis
DEFAULT_RTOL = 0.02
#: relative tolerance of a value the thesis gives as approximate (read off a figure)
APPROX_RTOL = 0.10


def comparison_kind(key: str) -> tuple[str, float]:
    """How the thesis value of ``key`` is compared: (kind, relative tolerance).

    ``kind`` is "value", "upper_bound" (asekit <= thesis: a requirement), "lower_bound"
    (asekit >= thesis), "range" (thesis [lo, hi]: asekit within), or "none" (not reported).
    An entry of ``data/thesis.toml`` may state ``kind`` and ``tolerance``; otherwise they are
    read from its ``source`` text: "upper bound" / "rule: below" -> upper bound, "rule: at
    least" -> lower bound, "range" -> range, "approximate" -> ``APPROX_RTOL``, else
    ``DEFAULT_RTOL``.
    """
    entry = _load(Path(THESIS_FILE)).get(key, {})
    src = str(entry.get("source", "")).lower()
    if "value" not in entry:
        kind = "none"
    elif "kind" in entry:
        kind = str(entry["kind"])
    elif "upper bound" in src or "rule: below" in src:
        kind = "upper_bound"
    elif "rule: at least" in src or "lower bound" in src:
        kind = "lower_bound"
    elif "range" in src:
        kind = "range"
    else:
        kind = "value"
    tol = float(entry.get("tolerance", APPROX_RTOL if "approximate" in src else DEFAULT_RTOL))
    return kind, tol


def _numbers(v):
    if is_number(v):
        return [float(v)]
    if isinstance(v, (list, tuple)) and v and all(is_number(x) for x in v):
        return [float(x) for x in v]
    return None


def _close(t: float, a: float, tol: float) -> bool:
    if math.isinf(t) or math.isinf(a):
        return t == a
    return abs(a - t) <= tol * abs(t) if t != 0 else abs(a) <= tol


def verdict(key: str, thesis, asekit, computed: bool = True) -> str:
    """Verdict of one row: "within tolerance", "explained difference" (outside tolerance, with
    an ``explained`` text in data/thesis.toml), "differs", "requirement met" / "requirement
    missed" (bounds), "in range" / "outside range", "not computed" (not computed in this run:
    ``computed`` False; or asekit None against a thesis number) or "not reported" (the thesis
    gives no number for a row asekit computed).

    >>> verdict("aero.boxes", None, 140)
    'not reported'
    >>> verdict("aero.boxes", None, None, computed=False)
    'not computed'
    """
    if not computed:
        return "not computed"
    kind, tol = comparison_kind(key)
    if thesis is None or kind == "none":
        return "not reported"
    if asekit is None:
        return "not computed"
    if isinstance(thesis, bool) or isinstance(asekit, bool):
        return "within tolerance" if thesis == asekit else "differs"
    t, a = _numbers(thesis), _numbers(asekit)
    if t is None or a is None:
        return "differs"
    if kind == "upper_bound":
        return "requirement met" if all(x <= t[0] for x in a) else "requirement missed"
    if kind == "lower_bound":
        return "requirement met" if all(x >= t[0] for x in a) else "requirement missed"
    if kind == "range":
        lo, hi = (min(t), max(t)) if len(t) == 2 else (t[0], t[0])
        return "in range" if all(lo - tol * abs(lo) <= x <= hi + tol * abs(hi) for x in a) \
            else "outside range"
    ok = len(t) == len(a) and all(_close(x, y, tol) for x, y in zip(t, a))
    if ok:
        return "within tolerance"
    if _load(Path(THESIS_FILE)).get(key, {}).get("explained"):
        return "explained difference"
    return "differs"


def _json_value(v):
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    return v


def comparison_rows(quantities) -> list[tuple[str, str, str, str, str, str, str]]:
    """(key, thesis, asekit, unit, difference, note, verdict) strings for computed quantities,
    the thesis values looked up in ``data/thesis.toml``. Bounds and ranges get no percent
    difference."""
    rows = []
    for q in quantities:
        tv = thesis_value(q.key)
        kind, _ = comparison_kind(q.key)
        diff = difference(tv.value, q.asekit) if kind == "value" else ""
        rows.append((q.key, _fmt(tv.value), _fmt(q.asekit), q.unit, diff, q.note,
                     verdict(q.key, tv.value, q.asekit, getattr(q, "computed", True))))
    return rows


# --------------------------------------------------------------------------------------------
# notes and "why" lines that cite other rows
# --------------------------------------------------------------------------------------------
#: a dotted row key (``flutter.pk.M075.h0.speed_ms``) or a family of rows (``flutter.converged.*``)
_CITATION = re.compile(r"\b[a-z][a-z0-9_]*(?:(?:\.[A-Za-z0-9_]+)+(?:\.\*)?|\.\*)")


def _cited_rows(text: str, known) -> list[list[str]]:
    """The rows each row citation in ``text`` names (a key of ``known``, or ``prefix.*``: every
    known key under the prefix); words that name no known row (file names, numbers) are no
    citations."""
    cited = []
    for token in _CITATION.findall(text):
        if token.endswith(".*"):
            keys = [k for k in known if k.startswith(token[:-1])]
        else:
            keys = [token] if token in known else []
        if keys:
            cited.append(keys)
    return cited


def without_empty_citations(text: str, empty, known) -> str:
    """``text`` without its clauses that cite a row that is empty in this run: a row of
    ``empty`` (no asekit value, or not run), or for ``prefix.*`` a family whose rows are all
    empty. Clauses are separated by ``"; "`` or ``", and "``; the clause after a dropped one
    takes the stronger of the two separators and loses a leading "and ".

    >>> known = {"a.x", "a.y", "b.z"}
    >>> without_empty_citations("the mesh is coarse; the fine one gives 254 m/s (a.*), and "
    ...                         "b.z agrees", empty={"a.x", "a.y"}, known=known)
    'the mesh is coarse; b.z agrees'
    """
    if not text:
        return text
    parts = re.split(r"(; |, and )", text)
    out, sep, dropped = "", "", False
    for i in range(0, len(parts), 2):
        piece = parts[i]
        own = parts[i - 1] if i else ""
        sep = "; " if "; " in (sep, own) and dropped else own
        if any(all(k in empty for k in keys) for keys in _cited_rows(piece, known)):
            dropped = True
            continue
        if dropped and piece.startswith("and "):
            piece = piece[4:]
        out += (sep if out else "") + piece
        dropped, sep = False, ""
    return out


def _empty_rows(rows) -> tuple[set, set]:
    """(the keys empty in the table of ``rows``: every thesis key without a row, or whose row
    has no asekit value; every key a citation may name)."""
    known = set(all_keys(Path(THESIS_FILE))) | {r[0] for r in rows}
    filled = {r[0] for r in rows if r[2] != "-"}
    return known - filled, known


_HEAD = ("quantity", "thesis", "asekit", "unit", "difference", "verdict")
#: column widths of the 100-column table (2 spaces between columns)
_WIDTHS = (30, 11, 11, 7, 11, 20)


def _wrap(text: str, width: int) -> list[str]:
    """Wrap a cell at ", " (lists) or spaces; a piece still too long is cut hard."""
    if len(text) <= width:
        return [text]
    sep = ", " if ", " in text else " "
    tokens = text.split(sep)
    lines, cur = [], ""
    for i, tok in enumerate(tokens):
        piece = tok + (sep.rstrip() if i < len(tokens) - 1 else "")
        cand = piece if not cur else cur + " " + piece
        if len(cand) <= width:
            cur = cand
            continue
        if cur:
            lines.append(cur)
        while len(piece) > width:
            lines.append(piece[:width])
            piece = piece[width:]
        cur = piece
    if cur:
        lines.append(cur)
    return lines


def _wrap_key(key: str, width: int) -> list[str]:
    parts = key.split(".")
    lines, cur = [], ""
    for i, part in enumerate(parts):
        piece = part + ("." if i < len(parts) - 1 else "")
        if cur and len(cur) + len(piece) > width:
            lines.append(cur)
            cur = "  " + piece
        else:
            cur += piece
    lines.append(cur)
    return [x for line in lines for x in _wrap(line, width)]


def format_table(rows, wide: bool = False, notes: bool = True) -> str:
    """The thesis-vs-asekit table of :func:`comparison_rows` as text.

    Default: at most 100 columns; long cells wrap inside their column and each note is folded
    onto indented lines under its row. ``wide``: one line per row with the note at its end
    (as wide as it needs). Rows of 6 strings (without a verdict) are accepted."""
    rows = [tuple(r) + ("",) * (7 - len(r)) for r in rows]
    empty, known = _empty_rows(rows)
    rows = [r[:5] + (without_empty_citations(r[5], empty, known),) + r[6:] for r in rows]
    cells = [(r[0], r[1], r[2], r[3], r[4], r[6]) for r in rows]
    if wide:
        widths = [max(len(c[i]) for c in cells + [_HEAD]) for i in range(6)]
        lines = ["  ".join(h.ljust(w) for h, w in zip(_HEAD, widths)).rstrip(),
                 "  ".join("-" * w for w in widths)]
        for c, r in zip(cells, rows):
            line = "  ".join(x.ljust(w) for x, w in zip(c, widths))
            why = _explanation(r[0], r[6], empty, known) if notes else ""
            lines.append((line + (f"  # {r[5]}" if notes and r[5] else "")
                          + (f"  why: {why}" if why else "")).rstrip())
        return "\n".join(lines)
    widths = _WIDTHS
    lines = ["  ".join(h.ljust(w) for h, w in zip(_HEAD, widths)).rstrip(),
             "  ".join("-" * w for w in widths)]
    for c, r in zip(cells, rows):
        cols = [_wrap_key(c[0], widths[0])] + [_wrap(x, w) for x, w in zip(c[1:], widths[1:])]
        for j in range(max(len(col) for col in cols)):
            parts = [(col[j] if j < len(col) else "").ljust(w) for col, w in zip(cols, widths)]
            lines.append("  ".join(parts).rstrip())
        if notes and r[5]:
            lines += textwrap.wrap(r[5], 100, initial_indent="    # ",
                                   subsequent_indent="      ", break_on_hyphens=False)
        why = _explanation(r[0], r[6], empty, known) if notes else ""
        if why:
            lines += textwrap.wrap(why, 100, initial_indent="    why: ",
                                   subsequent_indent="      ", break_on_hyphens=False)
    return "\n".join(lines)


def _explanation(key: str, verdict_text: str, empty=frozenset(), known=frozenset()) -> str:
    """The ``explained`` text of data/thesis.toml for a row whose verdict is "explained
    difference" (shown under the row), else "", without the clauses that cite a row of
    ``empty`` (:func:`without_empty_citations`)."""
    if verdict_text != "explained difference":
        return ""
    text = str(_load(Path(THESIS_FILE)).get(key, {}).get("explained", ""))
    return without_empty_citations(text, empty, known)


def comparison_table(quantities, wide: bool = False) -> str:
    """Thesis-vs-asekit text table for a chapter's quantities (as in ``reproduce``)."""
    return format_table(comparison_rows(quantities), wide=wide)


# --------------------------------------------------------------------------------------------
# the run
# --------------------------------------------------------------------------------------------
class ChapterFailed(RuntimeError):
    """A chapter's inputs failed and the run was not asked to keep going."""


def _chapter_label(name: str) -> str:
    return dict(CHAPTERS).get(name, name)


def _run_chapter_safely(name: str, figures: bool) -> ChapterResult:
    """:func:`run_chapter`, an exception reported as the chapter's failure."""
    try:
        return run_chapter(name, figures=figures)
    except KeyboardInterrupt:
        raise
    except Exception as exc:      # noqa: BLE001 - reported as the chapter's failure
        _log.debug("chapter %s raised", name, exc_info=True)
        return ChapterResult(chapter=name, quantities=(),
                             failures=(f"{type(exc).__name__}: {exc}",))


def _run_chapters(names, figures_dir, progress: bool, keep_going: bool, out: dict):
    """Run ``names`` in order, filling ``out`` (quantities, seconds, failures): (the table
    rows, the chapter the run stopped at or None)."""
    rows, stopped, bar = [], None, None
    if progress:
        from tqdm.auto import tqdm
        bar = tqdm(total=len(names), unit="chapter", leave=False, file=None)
    try:
        for name in names:
            if bar is not None:
                bar.set_description(_chapter_label(name))
            _log.info("chapter %s (%s) ...", name, _chapter_label(name))
            t0 = time.perf_counter()
            result = _run_chapter_safely(name, figures_dir is not None)
            out["seconds"][name] = round(time.perf_counter() - t0, 3)
            _log.info("chapter %s: %d rows in %.1f s%s", name, len(result.quantities),
                      out["seconds"][name], " (failed)" if result.failures else "")
            for q, row in zip(result.quantities, comparison_rows(result.quantities)):
                out["quantities"][q.key] = {"thesis": _json_value(thesis_value(q.key).value),
                                            "asekit": _json_value(q.asekit), "unit": q.unit,
                                            "note": q.note, "verdict": row[6]}
                rows.append(row)
            if result.failures:
                out["failures"][name] = list(result.failures)
            if figures_dir is not None:
                for fig_name, fig in result.figures.items():
                    save_figure(fig, figures_dir, fig_name)
                    _log.debug("figure %s written to %s", fig_name, figures_dir)
            if bar is not None:
                bar.update(1)
            if result.failures and not keep_going:
                stopped = name
                break
    finally:
        if bar is not None:
            bar.close()
    return rows, stopped


#: verdicts that are no comparison: the row has no asekit value in this run, or no thesis value
NOT_COMPARED = ("not computed", "not reported")


def table_counts(rows, names) -> dict:
    """The counts of a run's table: one per verdict (rows of the table), ``"not run"`` (the
    rows of data/thesis.toml that no chapter of this run produced: chapters left out with
    ``--only``, or stopped or failed) and ``"chapters not run"`` (their names, in order).
    "not computed" (asekit has no value in this run) and "not reported" (the thesis gives no
    number) are counted apart.

    >>> table_counts([("aero.boxes", "-", "140", "-", "", "", "not reported")], ["aero"])[
    ...     "not reported"]
    1
    """
    counts: dict = {}
    for r in rows:
        counts[r[6]] = counts.get(r[6], 0) + 1
    in_run = {r[0] for r in rows}
    counts["not run"] = sum(1 for k in all_keys(Path(THESIS_FILE)) if k not in in_run)
    counts["chapters not run"] = [n for n, _ in CHAPTERS if n not in names]
    return counts


def count_lines(counts: dict) -> list[str]:
    """The two summary lines of the table: the verdicts of the compared rows, then the rows
    with nothing to compare, "not computed" (in the table, and the rows of the chapters not
    run) apart from "not reported".

    >>> count_lines({"within tolerance": 3, "not computed": 1, "not reported": 2,
    ...              "not run": 5, "chapters not run": ["servo"]})[1]
    'not computed in this run: 6 rows (1 in the table, 5 of the chapters not run: servo); \
not reported (the thesis gives no number): 2 rows'
    """
    compared = [f"{v} {k}" for k, v in counts.items()
                if k not in NOT_COMPARED and k not in ("not run", "chapters not run")]
    table, not_run = counts.get("not computed", 0), counts.get("not run", 0)
    where = ""
    if not_run:
        chapters = ", ".join(counts.get("chapters not run", [])) or "failed or stopped"
        where = f" ({table} in the table, {not_run} of the chapters not run: {chapters})"
    return ["verdicts: " + (", ".join(compared) or "no row compared"),
            f"not computed in this run: {table + not_run} rows{where}; not reported (the thesis "
            f"gives no number): {counts.get('not reported', 0)} rows"]


def _write_json(out: dict, json_path) -> None:
    text = json.dumps(out, indent=2)
    if str(json_path) == "-":
        import sys
        sys.stdout.write(text + "\n")
    else:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(text)
        _log.info("JSON written to %s", json_path)


def reproduce(chapters: list[str] | None = None, figures_dir: str | Path | None = None,
              json_path: str | Path | None = None, echo=print, wide: bool = False,
              progress: bool = False, keep_going: bool = True) -> dict:
    """Run the chapters, print the table, optionally write JSON and PNG figures.

    Parameters
    ----------
    chapters : names among :data:`CHAPTERS` (default: every available chapter).
    figures_dir : write each chapter's figures as PNG there.
    json_path : write the JSON there; ``"-"`` writes it to standard output (pass an ``echo``
        that writes to standard error then, as the command line does, to keep stdout pure JSON).
    echo : printer of the table and the messages.
    wide : one line per row with the notes at the end (see :func:`format_table`).
    progress : a tqdm bar per chapter on standard error.
    keep_going : run the remaining chapters after a failed one; if False, stop at the first
        failure and raise :class:`ChapterFailed` after printing what ran.

    Returns the JSON-ready dict ``{"quantities": {key: {thesis, asekit, unit, note,
    verdict}}, "seconds": {...}, "failures": {chapter: [reasons]}, "counts": {verdict: rows,
    "not run": rows, "chapters not run": [names]}}`` (:func:`table_counts`). A note that cites
    a row empty in this run loses that clause (:func:`without_empty_citations`).
    """
    names = list(chapters) if chapters else available_chapters()
    unknown = [n for n in names if n not in dict(CHAPTERS)]
    if unknown:
        raise ValueError(f"unknown chapter(s) {unknown}; valid: {[n for n, _ in CHAPTERS]}")
    out = {"quantities": {}, "seconds": {}, "failures": {}}
    rows, stopped = _run_chapters(names, figures_dir, progress, keep_going, out)
    empty, known = _empty_rows(rows)
    for entry in out["quantities"].values():
        entry["note"] = without_empty_citations(entry["note"], empty, known)
    ran = list(out["seconds"])
    out["counts"] = table_counts(rows, ran)
    echo(format_table(rows, wide=wide))
    echo("")
    summary = ["seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in out["seconds"].items()),
               *count_lines(out["counts"])]
    summary += [f"FAILED chapter {name} ({_chapter_label(name)}): {reason}"
                for name, reasons in out["failures"].items() for reason in reasons]
    for line in summary:
        echo("\n".join(textwrap.wrap(line, 100, subsequent_indent="  ")) if not wide
             else line)
    if json_path is not None:
        _write_json(out, json_path)
    if stopped is not None:
        rest = names[names.index(stopped) + 1:]
        raise ChapterFailed(f"chapter {stopped} failed: {'; '.join(out['failures'][stopped])}"
                            + (f" (not run: {', '.join(rest)})" if rest else "")
                            + "; pass --keep-going to run the other chapters anyway")
    return out
