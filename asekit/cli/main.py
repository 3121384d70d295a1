"""Command line: ``python -m asekit <command>`` (``asekit/__main__.py`` calls :func:`main`).

Commands (argparse subcommands; each sets ``func(args) -> exit code``, so more can be added):

* ``reproduce [--json PATH|-] [--figures DIR] [--only CHAPTER ...] [--wide] [--quiet]
  [--keep-going]``: the thesis reproduction table (see :mod:`asekit.reproduction.driver`);
* ``analyse CASE.toml [--json PATH] [--report DIR]``: a case file (see :mod:`asekit.cli.analyse`);
* ``sweep SWEEP.toml --out PATH``: a sweep file (see :mod:`asekit.cli.sweep`);
* ``cases [--copy NAME DIR]``: the shipped case files (see :mod:`asekit.cli.cases`);
* ``optimise CASE.toml DESIGN.toml [--json PATH] [--out-case PATH]``: minimum-mass design under
  the flutter margin (see :mod:`asekit.cli.optimise`);
* ``trajectory CASE PROFILE.csv [--json PATH] [--plot PATH]``: margins, dynamic pressure and
  hinge moment along a flight trajectory (see :mod:`asekit.cli.trajectory`);
* ``convert DECK.bdf CASE.toml [--units U] [--name NAME]``: a Nastran stick-model deck as a
  ``[[beam]]`` case file (see :mod:`asekit.cli.convert`);
* ``--version``.

Options of every command (before or after its name): ``-v/--verbose`` (the package's info
messages: stages, cache hits and misses, times; ``-vv`` debug), ``--quiet`` (warnings and
errors only, and no progress bar where the command draws one), ``--log-file PATH`` (every
message at debug level, warnings and the error line included, written to PATH; checked like the
other outputs before any work), ``--debug`` (the traceback of an error). Messages and warnings
reach standard error through ``tqdm.write``, one line each, so that they never break a progress
bar; the logging and warning settings are restored when the command returns.

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
import logging
import os
import sys

from asekit.cli import outputs
from asekit.cli.analyse import add_parser as add_analyse
from asekit.cli.cases import add_parser as add_cases
from asekit.cli.convert import add_parser as add_convert
from asekit.cli.optimise import add_parser as add_optimise
from asekit.cli.sweep import add_parser as add_sweep
from asekit.cli.trajectory import add_parser as add_trajectory
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
    if getattr(args, "robust", False):     # asekit.reproduction.design.robust_study_requested
        os.environ["ASEKIT_ROBUST_STUDY"] = "1"
    if getattr(args, "transonic", False):  # asekit.reproduction.transonic (issue 29, tsdfin)
        os.environ["ASEKIT_TRANSONIC_STUDY"] = "1"
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
        return _report(f"asekit reproduce: {exc}", 1)
    if out["failures"] and not args.keep_going:      # a failure in the last chapter run
        return _report("asekit reproduce: chapter(s) failed: " + ", ".join(out["failures"])
                       + "; pass --keep-going to accept", 1)
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
    rep.add_argument("--robust", action="store_true",
                     help="also check the H-infinity design on the 45 conditions and compute "
                          "its mu bound (about a minute)")
    rep.add_argument("--transonic", action="store_true",
                     help="also compute the fin through the transonic gap with the TSD "
                          "(M 0.8-1.2) if it is not cached (a few CPU-minutes)")
    rep.set_defaults(func=_reproduce, parser=rep)
    add_analyse(sub)
    add_sweep(sub)
    add_cases(sub)
    add_optimise(sub)
    add_trajectory(sub)
    add_convert(sub)
    _add_common(parser, top=True)
    seen = set()
    for p in sub.choices.values():              # also after the command (aliases: once)
        if id(p) not in seen:
            seen.add(id(p))
            _add_common(p, top=False)
    return parser


_DEBUG_HELP = "show the traceback of an error (for a bug report)"


def _add_common(p: argparse.ArgumentParser, top: bool) -> None:
    """The options of every command: --debug, -v/--verbose, --quiet, --log-file. On a
    subcommand their default is SUPPRESS, so that one given before the command is not reset
    by the subcommand's default; a subcommand's own --quiet (its progress bar) is kept and
    gets the same default."""
    default = (lambda value: value) if top else (lambda value: argparse.SUPPRESS)
    p.add_argument("--debug", action="store_true", default=default(False), help=_DEBUG_HELP)
    p.add_argument("-v", "--verbose", action="count", default=default(0),
                   help="show the package's info messages (stages, caches, times); -vv: "
                        "debug messages too")
    own = p._option_string_actions.get("--quiet")
    if own is None:
        p.add_argument("--quiet", action="store_true", default=default(False),
                       help="warnings and errors only (no progress bar)")
    elif not top:
        own.default = argparse.SUPPRESS
        own.help = "warnings and errors only, no progress bar"
    p.add_argument("--log-file", metavar="PATH", default=default(None),
                   help="also write every message at debug level (warnings and errors "
                        "included) to PATH")


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
    <message>`` on standard error, without the source file and line, through the
    ``asekit.cli.main`` logger (:class:`_TqdmHandler`: ``tqdm.write``, so that it never breaks a
    progress bar; and the ``--log-file``) (issue 30). ``--debug`` keeps Python's own display.
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
        _log.warning("%s: %s", category.__name__, text)

    def __enter__(self):
        import warnings
        self._catch = warnings.catch_warnings()
        self._catch.__enter__()
        if not self.debug:
            warnings.showwarning = self.show
        return self

    def __exit__(self, *exc):
        return self._catch.__exit__(*exc)


class _TqdmHandler(logging.Handler):
    """A logging handler that writes each record as one line through ``tqdm.write`` (standard
    error), so that a message never breaks a progress bar: ``info: message``, ``warning:
    message``; at debug level the logger's name follows the level (``debug: asekit.aero.gaf:
    message``). Records marked ``file_only`` (the error line the command prints itself) are
    left to the log file."""

    def __init__(self, level: int):
        super().__init__(level)
        self.addFilter(lambda record: not getattr(record, "file_only", False))

    def format(self, record: logging.LogRecord) -> str:
        text = " ".join(record.getMessage().split())
        name = f"{record.name}: " if self.level <= logging.DEBUG else ""
        return f"{record.levelname.lower()}: {name}{text}"

    def emit(self, record: logging.LogRecord) -> None:
        try:
            from tqdm import tqdm
            tqdm.write(self.format(record), file=sys.stderr)
        except Exception:           # noqa: BLE001 - logging must not raise (logging's rule)
            self.handleError(record)


#: the logger of the package (every module logs to a child: ``logging.getLogger(__name__)``)
_PACKAGE = logging.getLogger("asekit")
_log = logging.getLogger(__name__)


def console_level(verbose: int = 0, quiet: bool = False) -> int:
    """The level shown on standard error: WARNING by default and with ``--quiet``, INFO with
    ``-v``, DEBUG with ``-vv``.

    >>> console_level(), console_level(1), console_level(2), console_level(2, quiet=True)
    (30, 20, 10, 30)
    """
    if quiet or verbose <= 0:
        return logging.WARNING
    return logging.INFO if verbose == 1 else logging.DEBUG


class _Logging:
    """While a command runs, the ``asekit`` logger writes to standard error through
    :class:`_TqdmHandler` at :func:`console_level`, and with ``log_file`` every record at
    debug level to that file (opened when the command starts, so that an unusable path is an
    error before any work). The logger's level, handlers and propagation are restored on
    exit (tests call :func:`main` in-process)."""

    def __init__(self, verbose: int = 0, quiet: bool = False, log_file: str | None = None):
        self.console = console_level(verbose, quiet)
        self.log_file = log_file
        self.handlers: list[logging.Handler] = []

    def __enter__(self):
        self.saved = (_PACKAGE.level, list(_PACKAGE.handlers), _PACKAGE.propagate)
        self.handlers = [_TqdmHandler(self.console)]
        if self.log_file:
            fh = logging.FileHandler(self.log_file, mode="w", encoding="utf-8", delay=False)
            fh.setLevel(logging.DEBUG)
            fh.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: "
                                              "%(message)s"))
            self.handlers.append(fh)
        for h in self.handlers:
            _PACKAGE.addHandler(h)
        _PACKAGE.setLevel(min(h.level for h in self.handlers))
        _PACKAGE.propagate = False       # one line per message, whatever the root logger has
        return self

    def __exit__(self, *exc):
        level, handlers, propagate = self.saved
        for h in self.handlers:
            _PACKAGE.removeHandler(h)
            h.close()
        _PACKAGE.setLevel(level)
        _PACKAGE.propagate = propagate
        for h in handlers:
            if h not in _PACKAGE.handlers:
                _PACKAGE.addHandler(h)
        return False


def _log_file_error(args) -> str | None:
    """Why ``--log-file`` cannot be written (its missing folders are made), else None."""
    path = getattr(args, "log_file", None)
    reason = outputs.check_file("--log-file", path, dash=False)
    if reason is None and path is not None:
        try:
            with open(path, "a", encoding="utf-8"):
                pass
        except OSError as exc:
            reason = f"--log-file {path}: cannot write the file ({exc.strerror or exc})"
    return reason


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    reason = _log_file_error(args)
    if reason:
        print(f"error: {reason}", file=sys.stderr)
        return 2
    debug = getattr(args, "debug", False)
    with _Logging(getattr(args, "verbose", 0), getattr(args, "quiet", False),
                  getattr(args, "log_file", None)), \
            _Interrupts() as interrupts, _OneLineWarnings(debug):
        _log.debug("asekit %s: %s", __version__, " ".join(sys.argv[:1] + list(
            sys.argv[1:] if argv is None else argv)))
        return _run(args, interrupts, debug)


def _report(line: str, code: int) -> int:
    """Print the one line of a failed command on standard error (and log it to the file)."""
    return outputs.print_error(line, code, _log)


def _run(args, interrupts: _Interrupts, debug: bool) -> int:
    """The command, its errors turned into one line and an exit code."""
    try:
        code = args.func(args)
        if code and interrupts.seen:    # the command reported the error it was turned into
            return _report("interrupted", 130)
        return code
    except KeyboardInterrupt:
        return _report("interrupted", 130)
    except Exception as exc:            # one line, never a traceback (unless --debug)
        if interrupts.seen:
            return _report("interrupted", 130)
        if debug:
            import traceback
            traceback.print_exc()
        _log.debug("traceback", exc_info=True, extra={"file_only": True})
        return _report(*error_line(exc, args.command))


if __name__ == "__main__":
    sys.exit(main())
