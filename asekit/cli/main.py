"""Command line: ``python -m asekit <command>`` (``asekit/__main__.py`` calls :func:`main`).

Commands (argparse subcommands; each sets ``func(args) -> exit code``, so more can be added):

* ``reproduce [--json PATH|-] [--figures DIR] [--only CHAPTER ...] [--wide] [--quiet]
  [--keep-going]``: the thesis reproduction table (see :mod:`asekit.reproduction.driver`);
* ``analyse CASE.toml [--json PATH] [--report DIR]``: a case file (see :mod:`asekit.cli.analyse`);
* ``sweep SWEEP.toml --out PATH``: a sweep file (see :mod:`asekit.cli.sweep`);
* ``cases [--copy NAME DIR]``: the shipped case files (see :mod:`asekit.cli.cases`);
* ``--version``.

Output paths are checked (and their missing folders made) before any work
(:mod:`asekit.cli.outputs`). Every error is one line on standard error, never a traceback
(``--debug`` shows it). Exit codes: 0 success; 2 bad input (arguments, a case, sweep or deck
file the loader refuses -- a ValueError such as CaseError or BdfError --, a numerical failure
of a case, :class:`asekit.case.SolverError`, or an unusable file); 1 a chapter of ``reproduce``
failed (without ``--keep-going``) or an internal error (a bug: one line saying so; rerun with
``--debug``); 130 interrupted.

The heavy modules (the pipeline, the reproduction, matplotlib) are imported by the command
that needs them, so that a refused input is reported within a second or two.
"""

from __future__ import annotations

import argparse
import os
import sys

from asekit.cli import outputs
from asekit.cli.analyse import add_parser as add_analyse
from asekit.cli.cases import add_parser as add_cases
from asekit.cli.sweep import add_parser as add_sweep
from asekit.util.version import __version__


def _chapter_names() -> list[str]:
    from asekit.reproduction.driver import CHAPTERS
    return [n for n, _ in CHAPTERS]


class _ChapterList:
    """The chapter names for the ``--only`` help, read when the help is printed (so that
    building the parser does not import the reproduction)."""

    def __str__(self) -> str:
        return ", ".join(_chapter_names())


def _chapter(name: str) -> str:
    valid = _chapter_names()
    if name not in valid:
        raise argparse.ArgumentTypeError(f"unknown chapter {name!r}; choose from "
                                         f"{', '.join(valid)}")
    return name


def _check_outputs(parser: argparse.ArgumentParser, args) -> None:
    """Refuse unusable --json / --figures paths before any chapter runs (argparse's error,
    exit 2); their missing folders are made."""
    for reason in (outputs.check_file("--json", args.json),
                   outputs.check_dir("--figures", args.figures, "the PNG figures")):
        if reason:
            parser.error(reason)


def _reproduce(args) -> int:
    _check_outputs(args.parser, args)
    if args.converged:             # read by asekit.reproduction.flutter.converged_study_requested
        os.environ["ASEKIT_CONVERGED_STUDY"] = "1"
    import matplotlib
    matplotlib.use("Agg")
    from asekit.reproduction.driver import ChapterFailed, reproduce

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
    prog = "asekit" if os.path.basename(sys.argv[0]) == "asekit" else "python -m asekit"
    parser = argparse.ArgumentParser(prog=prog,
                                     description="asekit: aeroservoelastic workbench")
    parser.add_argument("--version", action="version", version=f"asekit {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    rep = sub.add_parser("reproduce", help="run the thesis reproduction and print the "
                                           "thesis-vs-asekit table",
                         description="Run the thesis reproduction: a thesis-vs-asekit table "
                                     "with a verdict per row, at most 100 columns wide.")
    rep.add_argument("--json", metavar="PATH", help="also write the table as JSON ('-': to "
                                                    "standard output; the table goes to "
                                                    "standard error)")
    rep.add_argument("--figures", metavar="DIR", help="write every chapter figure as PNG")
    only = rep.add_argument("--only", nargs="+", metavar="CHAPTER", type=_chapter,
                            help="run only these chapters (%(chapters)s)")
    only.chapters = _ChapterList()
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
    add_cases(sub)
    parser.add_argument("--debug", action="store_true", help=_DEBUG_HELP)
    seen = set()
    for p in sub.choices.values():              # also after the command (aliases: once)
        if id(p) not in seen:
            seen.add(id(p))
            p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                           help=_DEBUG_HELP)
    return parser


_DEBUG_HELP = "show the traceback of an error (for a bug report)"


def _input_error(exc: BaseException) -> bool:
    """Whether ``exc`` is the user's to fix (exit 2): a refused input (ValueError: CaseError,
    BdfError, SweepError, ...), a numerical failure of a checked case (SolverError) or a file
    the system refuses (OSError)."""
    from asekit.case.schema import SolverError
    return isinstance(exc, (ValueError, SolverError, OSError))


def error_line(exc: BaseException, command: str = "") -> tuple[str, int]:
    """(the one line printed for ``exc``, the exit code): 2 for an input error, 1 for a bug."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    where = f"asekit {command}: " if command else ""
    if _input_error(exc):
        return f"error: {where}{text}", 2
    return (f"internal error (a bug in asekit, please report it): {where}"
            f"{type(exc).__name__}: {text[:300]}; rerun with --debug for the traceback"), 1


class _Interrupts:
    """Remembers a SIGINT while a command runs: a library that turns the KeyboardInterrupt into
    an error of its own (matplotlib: "Invalid bounding box") is still reported as interrupted."""

    def __init__(self):
        self.seen = False

    def __enter__(self):
        import signal
        self.previous = signal.getsignal(signal.SIGINT)
        if self.previous is signal.default_int_handler:     # not when SIGINT is ignored
            try:
                signal.signal(signal.SIGINT, self._handler)
            except ValueError:                              # not the main thread
                self.previous = None
        return self

    def _handler(self, signum, frame):
        self.seen = True
        raise KeyboardInterrupt

    def __exit__(self, *exc):
        import signal
        if self.previous is signal.default_int_handler:
            signal.signal(signal.SIGINT, self.previous)
        return False


class _OneLineWarnings:
    """While a command runs, every warning is shown once, as one line ``warning: <Category>:
    <message>`` on standard error, without the source file and line, through ``tqdm.write`` so
    that it never breaks a progress bar (issue 30). ``--debug`` keeps Python's own display.
    The previous warning settings are restored on exit (``warnings.catch_warnings``)."""

    def __init__(self, debug: bool = False):
        self.debug = debug
        self.seen: set = set()
        self._catch = None

    def show(self, message, category, filename, lineno, file=None, line=None):
        text = " ".join(str(message).split())
        if (category, text) in self.seen:
            return
        self.seen.add((category, text))
        from tqdm import tqdm
        tqdm.write(f"warning: {category.__name__}: {text}", file=sys.stderr)

    def __enter__(self):
        import warnings
        self._catch = warnings.catch_warnings()
        self._catch.__enter__()
        if not self.debug:
            warnings.showwarning = self.show
        return self

    def __exit__(self, *exc):
        return self._catch.__exit__(*exc)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with _Interrupts() as interrupts, _OneLineWarnings(getattr(args, "debug", False)):
        try:
            code = args.func(args)
            if code and interrupts.seen:    # the command reported the error it was turned into
                print("interrupted", file=sys.stderr)
                return 130
            return code
        except KeyboardInterrupt:
            print("interrupted", file=sys.stderr)
            return 130
        except Exception as exc:            # one line, never a traceback (unless --debug)
            if interrupts.seen:
                print("interrupted", file=sys.stderr)
                return 130
            if getattr(args, "debug", False):
                import traceback
                traceback.print_exc()
            line, code = error_line(exc, args.command)
            print(line, file=sys.stderr)
            return code


if __name__ == "__main__":
    sys.exit(main())
