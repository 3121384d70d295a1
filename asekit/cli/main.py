"""Command line: ``python -m asekit <command>`` (``asekit/__main__.py`` calls :func:`main`).

Commands (argparse subcommands; each sets ``func(args) -> exit code``, so more can be added):

* ``reproduce [--json PATH|-] [--figures DIR] [--only CHAPTER ...] [--wide] [--quiet]
  [--keep-going]``: the thesis reproduction table (see :mod:`asekit.reproduction.driver`);
* ``analyse CASE.toml [--json PATH] [--report DIR]``: a case file (see :mod:`asekit.cli.analyse`).

Exit codes: 0 success, 1 a chapter's inputs failed (without ``--keep-going``), 2 bad arguments
(argparse), 130 interrupted.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from asekit.cli.analyse import add_parser as add_analyse
from asekit.cli.sweep import add_parser as add_sweep
from asekit.reproduction.driver import CHAPTERS, ChapterFailed, reproduce


def _chapter(name: str) -> str:
    valid = [n for n, _ in CHAPTERS]
    if name not in valid:
        raise argparse.ArgumentTypeError(f"unknown chapter {name!r}; choose from "
                                         f"{', '.join(valid)}")
    return name


def _writable_dir(path: Path) -> str | None:
    """None if ``path`` is (or can be made) a writable directory, else the reason."""
    if path.exists() and not path.is_dir():
        return f"{path} exists and is not a directory"
    probe = path
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        return f"{probe} is not a directory"
    if not os.access(probe, os.W_OK | os.X_OK):
        return f"{probe} is not writable"
    return None


def _check_outputs(parser: argparse.ArgumentParser, args) -> None:
    """Refuse unusable --json / --figures paths before any chapter runs."""
    if args.json is not None and args.json != "-":
        j = Path(args.json)
        if args.json == "" or j.is_dir():
            parser.error(f"--json {args.json!r}: give a file path (or '-' for standard output)")
        if j.exists() and not os.access(j, os.W_OK):
            parser.error(f"--json {args.json}: the file is not writable")
        reason = _writable_dir(j.parent if str(j.parent) else Path("."))
        if reason:
            parser.error(f"--json {args.json}: {reason}")
    if args.figures is not None:
        if not args.figures.strip():
            parser.error("--figures '': give a directory for the PNG figures")
        reason = _writable_dir(Path(args.figures))
        if reason:
            parser.error(f"--figures {args.figures}: {reason}")


def _reproduce(args) -> int:
    _check_outputs(args.parser, args)
    if args.converged:             # read by asekit.reproduction.flutter.converged_study_requested
        os.environ["ASEKIT_CONVERGED_STUDY"] = "1"
    import matplotlib
    matplotlib.use("Agg")

    to_stderr = args.json == "-"

    def echo(text=""):
        print(text, file=sys.stderr if to_stderr else sys.stdout)

    try:
        out = reproduce(chapters=args.only, figures_dir=args.figures, json_path=args.json,
                        echo=echo, wide=args.wide, progress=not args.quiet,
                        keep_going=args.keep_going)
    except ChapterFailed as exc:
        print(f"asekit reproduce: {exc}", file=sys.stderr)
        return 1
    if out["failures"] and not args.keep_going:      # a failure in the last chapter run
        print("asekit reproduce: chapter(s) failed: " + ", ".join(out["failures"])
              + "; pass --keep-going to accept", file=sys.stderr)
        return 1
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with its subcommands (each sets ``func``)."""
    parser = argparse.ArgumentParser(prog="python -m asekit",
                                     description="asekit: aeroservoelastic workbench")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    rep = sub.add_parser("reproduce", help="run the thesis reproduction and print the "
                                           "thesis-vs-asekit table",
                         description="Run the thesis reproduction: a thesis-vs-asekit table "
                                     "with a verdict per row, at most 100 columns wide.")
    rep.add_argument("--json", metavar="PATH", help="also write the table as JSON ('-': to "
                                                    "standard output; the table goes to "
                                                    "standard error)")
    rep.add_argument("--figures", metavar="DIR", help="write every chapter figure as PNG")
    rep.add_argument("--only", nargs="+", metavar="CHAPTER", type=_chapter,
                     help=f"run only these chapters ({', '.join(n for n, _ in CHAPTERS)})")
    rep.add_argument("--wide", action="store_true",
                     help="one line per row with its note at the end (wider than 100 columns)")
    rep.add_argument("--quiet", action="store_true", help="no progress bar on standard error")
    rep.add_argument("--keep-going", action="store_true",
                     help="run the other chapters when one's inputs fail, and exit 0")
    rep.add_argument("--converged", action="store_true",
                     help="also compute the fin's mesh-converged flutter study if it is not "
                          "cached (about 8 min and 7 GB of memory the first time)")
    rep.set_defaults(func=_reproduce, parser=rep)
    add_analyse(sub)
    add_sweep(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
