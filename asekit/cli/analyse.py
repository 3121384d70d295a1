"""``python -m asekit analyse CASE.toml|DECK.bdf [--units U] [--json PATH] [--report DIR]``: run a
case file (or a Nastran deck, :func:`asekit.io.bdf.read_bdf`) through
the pipeline (modes -> GAF database -> p-k flutter -> match points and margins -> ASE loop when
an actuator is given), print the summary table, and optionally write the JSON summary and an
HTML report. A bad case file gets one line naming the key and exit status 2. Modes, damping
and units follow docs/conventions.md (elastic modes from 1, "rigid pitch", g > 0 unstable)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from asekit.case import CaseError, load_case
from asekit.case.report import format_summary, run_analysis, summary, write_report
from asekit.io import bdf


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
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _check_writable(path: Path, what: str) -> str | None:
    target = path if path.is_dir() else path.parent
    target = target if str(target) else Path(".")
    probe = target
    while not probe.exists():
        probe = probe.parent
    import os
    if not os.access(probe, os.W_OK):
        return f"{what} {path}: folder {probe} is not writable"
    return None


#: File suffixes read as Nastran bulk data.
DECK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk")


def _read_case(args, load_case):
    """The case of ``args.case``: a Nastran deck (by suffix) through asekit.io.bdf, else TOML."""
    if Path(args.case).suffix.lower() in DECK_SUFFIXES:
        return bdf.read_bdf(args.case, units=getattr(args, "units", "SI"))
    return load_case(args.case)


def run(args) -> int:
    for opt, what in ((args.json, "--json"), (args.report, "--report")):
        if opt is not None and opt != "-" and (msg := _check_writable(Path(opt), what)):
            print(f"error: {msg}", file=sys.stderr)
            return 2
        if opt == "" :
            print(f"error: {what} needs a path", file=sys.stderr)
            return 2
    try:
        case = _read_case(args, load_case)
    except ImportError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except FileNotFoundError:
        print(f"error: case file {args.case} not found", file=sys.stderr)
        return 2
    except (CaseError, ValueError) as exc:
        print(f"error: {Path(args.case).name}: {exc}", file=sys.stderr)
        return 2
    try:
        analysis = run_analysis(case, progress=not args.quiet)
    except CaseError as exc:
        print(f"error: {Path(args.case).name}: {exc}", file=sys.stderr)
        return 2
    s = summary(analysis)
    to_stdout = args.json == "-"
    print(format_summary(s), file=sys.stderr if to_stdout else sys.stdout)
    if args.json:
        text = json.dumps(s, indent=2)
        if to_stdout:
            print(text)
        else:
            Path(args.json).write_text(text + "\n")
    if args.report:
        import matplotlib
        matplotlib.use("Agg")
        index = write_report(analysis, args.report)
        print(f"report: {index}", file=sys.stderr)
    return 0
