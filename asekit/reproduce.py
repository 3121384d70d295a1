"""The thesis reproduction: every chapter asekit can compute, one thesis-vs-asekit table.

``python -m asekit reproduce [--json PATH] [--figures DIR] [--only CHAPTER ...]``

Each chapter lives in ``asekit.reproduction.<name>`` and exposes
``run(figures: bool) -> ChapterResult``. Thesis values are looked up by key in
``data/thesis.toml``; asekit values are always computed by the chapter.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

from .thesis import is_number, thesis_value

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
    ``note`` explains a difference or an assumption in a few words."""

    key: str
    asekit: float | list | bool | None
    unit: str
    note: str = ""


@dataclass(frozen=True)
class ChapterResult:
    """A chapter's quantities and figures (``name -> matplotlib Figure``)."""

    chapter: str
    quantities: tuple[Quantity, ...]
    figures: dict = field(default_factory=dict)


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


def _json_value(v):
    if isinstance(v, float) and math.isinf(v):
        return "inf" if v > 0 else "-inf"
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    return v


def comparison_rows(quantities) -> list[tuple[str, str, str, str, str, str]]:
    """(key, thesis, asekit, unit, difference, note) strings for computed quantities, the
    thesis values looked up in ``data/thesis.toml``."""
    rows = []
    for q in quantities:
        tv = thesis_value(q.key)
        rows.append((q.key, _fmt(tv.value), _fmt(q.asekit), q.unit,
                     difference(tv.value, q.asekit), q.note))
    return rows


def format_table(rows) -> str:
    """The thesis-vs-asekit table of :func:`comparison_rows` as aligned text."""
    head = ("quantity", "thesis", "asekit", "unit", "difference")
    widths = [max(len(r[i]) for r in list(rows) + [head]) for i in range(5)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head, widths)),
             "  ".join("-" * w for w in widths)]
    for r in rows:
        line = "  ".join(c.ljust(w) for c, w in zip(r[:5], widths))
        lines.append(line + (f"  # {r[5]}" if r[5] else ""))
    return "\n".join(lines)


def comparison_table(quantities) -> str:
    """Thesis-vs-asekit text table for a chapter's quantities (as in ``reproduce``)."""
    return format_table(comparison_rows(quantities))


def reproduce(chapters: list[str] | None = None, figures_dir: str | Path | None = None,
              json_path: str | Path | None = None, echo=print) -> dict:
    """Run the chapters, print the table, optionally write JSON and PNG figures.

    Returns the JSON-ready dict ``{"quantities": {...}, "seconds": {...}}``.
    """
    names = chapters if chapters else available_chapters()
    unknown = [n for n in names if n not in dict(CHAPTERS)]
    if unknown:
        raise ValueError(f"unknown chapter(s) {unknown}; valid: {[n for n, _ in CHAPTERS]}")
    out = {"quantities": {}, "seconds": {}}
    rows = []
    for name in names:
        t0 = time.perf_counter()
        result = run_chapter(name, figures=figures_dir is not None)
        out["seconds"][name] = round(time.perf_counter() - t0, 3)
        for q in result.quantities:
            out["quantities"][q.key] = {"thesis": _json_value(thesis_value(q.key).value),
                                        "asekit": _json_value(q.asekit), "unit": q.unit}
        rows += comparison_rows(result.quantities)
        if figures_dir is not None:
            from .plotting import save_figure
            for fig_name, fig in result.figures.items():
                save_figure(fig, figures_dir, fig_name)
    echo(format_table(rows))
    echo("")
    echo("seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in out["seconds"].items()))
    if json_path is not None:
        Path(json_path).parent.mkdir(parents=True, exist_ok=True)
        Path(json_path).write_text(json.dumps(out, indent=2))
    return out
