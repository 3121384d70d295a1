"""``python -m asekit analyse CASE.toml|DECK.bdf [--units U] [--json PATH] [--report DIR]``: run a
case file (or a Nastran deck, :func:`asekit.io.bdf.read_bdf`) through
the pipeline (modes -> GAF database -> p-k flutter -> match points and margins -> ASE loop when
an actuator is given), print the summary table (a deck: every FLUTTER card with its own
method, K / KE / PK / PKNL as MSC Nastran defines them, its rows in the JSON's ``"flutter"``
and Nastran's FLUTTER SUMMARY printed), and optionally write the JSON summary and an
HTML report. A bad case file gets one line naming the key and exit status 2. Modes, damping
and units follow docs/conventions.md (elastic modes from 1, "rigid pitch", g > 0 unstable).
A CBAR stick-model deck is run by :func:`asekit.io.bdf_beam.stick_flutter` instead (modes and
the FLUTTER cards; no HTML report yet)."""

from __future__ import annotations

import json
import logging
import sys
from pathlib import Path

from asekit.cli import outputs
from asekit.cli.cases import resolve_case

_log = logging.getLogger(__name__)


def add_parser(sub) -> None:
    p = sub.add_parser("analyse", aliases=["analyze"],
                       help="analyse a case file (flutter, divergence, match points, ASE)")
    p.add_argument("case", metavar="CASE.toml",
                   help="the case file (see docs/case-format.md), or a Nastran deck (.bdf, "
                        ".dat, .nas: read by asekit.io.bdf.read_bdf, needs pyNastran)")
    p.add_argument("--units", default="SI", choices=("SI", "mm-t-s", "in-lbf-s"),
                   help="a Nastran deck's unit system (default SI)")
    p.add_argument("--json", metavar="PATH", help="write the summary as JSON ('-': stdout)")
    p.add_argument("--report", metavar="DIR", help="write index.html, figures and summary.json")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bars (modes, GAF database, p-k, ASE loop, report figures)")
    p.add_argument("--convergence", action="store_true",
                   help="also run the case on coarser meshes and report the extrapolated "
                        "flutter speed and frequency with error bars ([convergence] in the "
                        "case file; also when convergence.enabled = true)")
    p.set_defaults(func=run)


#: File suffixes read as Nastran bulk data.
DECK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk")


def _read_case(args, load_case):
    """The case of ``args.case``: a Nastran deck (by suffix) through asekit.io.bdf, else TOML;
    a path that does not exist may name a shipped case (:func:`asekit.cli.cases.resolve_case`:
    ``asekit analyse agard445_6`` from any directory)."""
    path = resolve_case(args.case)
    if path.suffix.lower() in DECK_SUFFIXES:
        from asekit.io import bdf
        return bdf.read_bdf(path, units=getattr(args, "units", "SI"))
    return load_case(path)


def _stick_deck(args):
    """The path of ``args.case`` when it is a CBAR stick-model deck
    (:func:`asekit.io.bdf_beam.is_stick_deck`), else None (a case file or a plate deck)."""
    try:
        path = resolve_case(args.case)
    except (FileNotFoundError, OSError):    # _run_case reports a missing or unreadable file
        return None
    if path.suffix.lower() not in DECK_SUFFIXES or not path.is_file():
        return None
    try:
        from asekit.io.bdf_beam import is_stick_deck
        return path if is_stick_deck(path) else None
    except ImportError:                 # no pyNastran: _read_case says so
        return None


def _run_stick(args, path) -> int:
    """A stick-model deck: its modes and every FLUTTER card with its own method
    (:func:`asekit.io.bdf_beam.stick_flutter`), the FLUTTER SUMMARY text and the JSON
    ``{"deck", "modes_hz", "flutter": [rows of asekit.io.bdf.flutter_rows]}``."""
    reason = outputs.check_file("--json", args.json)
    if reason or args.report:
        return _error(reason or "--report: the HTML report of a stick-model (CBAR) deck is "
                                "not supported yet; use --json")
    from asekit.case.report import write_text_atomic
    from asekit.io import bdf
    from asekit.io.bdf_beam import stick_flutter
    try:
        run = stick_flutter(path, units=getattr(args, "units", "SI"))
    except ValueError as exc:
        return _error(_named(path.name, exc))
    f = [float(x) for x in run.modes.frequencies_hz]
    s = {"deck": str(path), "modes_hz": f, "flutter": bdf.flutter_rows(list(run.results)),
         "notes": list(run.modes.notes)}
    text = (f"{path.name}: stick model, modes (Hz) " + ", ".join(f"{x:.4g}" for x in f)
            + "".join(f"\nnote: {n}" for n in run.modes.notes)
            + "\n\n" + bdf.format_flutter_summary(list(run.results)))
    _write_outputs(args, s, text, write_text_atomic)
    return 0


def _error(msg: str) -> int:
    return outputs.print_error(f"error: {msg}", 2, _log)


def _named(name: str, exc: BaseException) -> str:
    """``exc``'s message prefixed with the case file's name (unless it starts with it)."""
    text = " ".join(str(exc).split())
    return text if text.startswith(name) else f"{name}: {text}"


def _deck_cards(case, s: dict) -> tuple[dict, str]:
    """A Nastran deck's summary: ``s["flutter"]`` becomes one row per FLUTTER card crossing,
    each card with its own method (:func:`asekit.io.bdf.deck_flutter`: K, KE, PK, PKNL as
    MSC Nastran defines them), asekit's own p-k rows of the pipeline move to
    ``s["flutter_asekit_pk"]``; and the cards' FLUTTER SUMMARY text."""
    from asekit.case.report import critical_condition
    from asekit.io import bdf
    solved = bdf.deck_flutter(case)
    if not solved:
        return s, ""
    s = dict(s, flutter_asekit_pk=s["flutter"], flutter=bdf.flutter_rows(solved))
    s["critical"] = critical_condition(s)          # from the cards' rows
    return s, bdf.format_flutter_summary(solved)


def _write_outputs(args, s: dict, text: str, write_text_atomic) -> None:
    """The summary text (standard output, or standard error when the JSON goes there) and
    the JSON summary (``--json PATH`` or ``-``)."""
    to_stdout = args.json == "-"
    print(text, file=sys.stderr if to_stdout else sys.stdout)
    if args.json:
        dumped = json.dumps(s, indent=2)
        if to_stdout:
            print(dumped)
        else:
            write_text_atomic(args.json, dumped + "\n")


def run(args) -> int:
    """The command: a CBAR stick-model deck by :func:`_run_stick`, anything else by
    :func:`_run_case`."""
    stick = _stick_deck(args)
    return _run_stick(args, stick) if stick is not None else _run_case(args)


def _run_case(args) -> int:
    """The command for a case file or a plate deck: output paths first, then the case (the loader's checks), then the
    pipeline; an input error or a numerical failure of the case is one line and exit 2 (other
    exceptions reach :func:`asekit.cli.main.main`: one line, exit 1)."""
    for reason in (outputs.check_file("--json", args.json),
                   outputs.check_dir("--report", args.report, "the HTML report")):
        if reason:
            return _error(reason)
    from asekit.case import CaseError, load_case
    from asekit.case.schema import SolverError
    name = Path(args.case).name
    try:
        case = _read_case(args, load_case)
    except ImportError as exc:
        return _error(str(exc))
    except FileNotFoundError as exc:
        return _error(f"case file {exc}" if str(exc).startswith(args.case) else
                      f"case file {args.case} not found")
    except (CaseError, ValueError) as exc:
        return _error(_named(name, exc))
    except OSError as exc:
        return _error(f"{name}: cannot read the case file ({exc.strerror or exc})")
    from asekit.case.report import (
        format_summary,
        run_analysis,
        summary,
        write_report,
        write_text_atomic,
    )
    study = getattr(args, "convergence", False) or case.convergence.enabled
    try:
        if study and getattr(case, "beam", None) is not None:
            raise CaseError("--convergence / convergence.enabled: the mesh study of a [[beam]] "
                            "case is not supported yet (plate cases only)")
        if study:                       # the study's meshes checked before any computation
            from asekit.case import convergence
            convergence.check_study(case)
        analysis = run_analysis(case, progress=not args.quiet)
    except (ValueError, SolverError) as exc:
        return _error(_named(name, exc))
    s = summary(analysis)
    cards = None
    if getattr(case.structure, "deck", None) is not None:         # a Nastran deck
        try:
            s, cards = _deck_cards(case, s)
        except (ValueError, SolverError) as exc:
            return _error(_named(name, exc))
    if study:
        try:
            conv = convergence.convergence_study(case, finest=analysis.flutter,
                                                 progress=not args.quiet)
        except (ValueError, SolverError) as exc:
            return _error(_named(name, exc))
        s = convergence.add_to_summary(s, conv)
    texts = [format_summary(s)] + ([convergence.format_study(conv)] if study else []) + (
        [cards] if cards else [])
    _write_outputs(args, s, "\n\n".join(texts), write_text_atomic)
    if args.report:
        import matplotlib
        matplotlib.use("Agg")
        index = write_report(analysis, args.report, progress=not args.quiet, s=s)
        print(f"report: {index}", file=sys.stderr)
    return 0
