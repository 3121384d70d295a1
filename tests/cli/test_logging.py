"""Logging (issue 30): the package logs through :mod:`logging`, a named logger per module, and
configures nothing at import (a NullHandler on ``asekit`` only); the command line shows the
messages with ``-v`` / ``-vv``, hides progress with ``--quiet``, writes every message to
``--log-file`` (checked before any work), draws warnings and messages as one line each through
``tqdm.write``, and restores the logging settings after the command. (The same options on
``reproduce`` with its chapters: tests/reproduction/test_reproduce_logging.py.)"""

import ast
import logging
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from asekit.cli.main import _Logging, _OneLineWarnings, console_level, main

PACKAGE = Path(__file__).resolve().parents[2] / "asekit"


def _get_logger_calls(tree):
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and node.func.attr == "getLogger"):
            yield node


def test_every_module_logs_to_its_own_named_logger():
    """A module's logger is ``logging.getLogger(__name__)`` (so its name is the module's and
    ``-v`` / a user's filter can pick it), never the root logger or a shared name, except the
    command line's handle on the package's logger ("asekit"), which it configures per command."""
    users, bad = [], []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for call in _get_logger_calls(tree):
            arg = call.args[0] if call.args else None
            name = path.relative_to(PACKAGE.parent).as_posix()
            if isinstance(arg, ast.Name) and arg.id == "__name__":
                users.append(name)
            elif not (name in ("asekit/cli/main.py", "asekit/__init__.py")
                      and isinstance(arg, ast.Constant) and arg.value == "asekit"):
                bad.append(f"{name}:{call.lineno}")
        for node in ast.walk(tree):          # no configuration by the library
            if isinstance(node, ast.Attribute) and node.attr == "basicConfig":
                bad.append(f"{path.name}: basicConfig")
    assert not bad, bad
    # the stages a user wants to see log: cache hits/misses, GAF database, pipeline, chapters
    for module in ("asekit/util/cache.py", "asekit/aero/gaf.py", "asekit/case/pipeline.py",
                   "asekit/reproduction/driver.py", "asekit/cli/main.py"):
        assert module in users, module


def test_import_configures_nothing_but_a_null_handler():
    """Library etiquette: importing asekit (and running a pipeline step) adds no handler to the
    root logger and leaves levels alone; the package logger has a NullHandler."""
    code = ("import logging, asekit\n"
            "from asekit.case import pipeline\n"
            "root = logging.getLogger(); pkg = logging.getLogger('asekit')\n"
            "print(len(root.handlers), root.level, pkg.level, pkg.propagate,\n"
            "      [type(h).__name__ for h in pkg.handlers])\n"
            "print(logging.getLogger('asekit.case.pipeline').getEffectiveLevel())\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    first, second = r.stdout.splitlines()
    assert first == "0 30 0 True ['NullHandler']"
    assert second == "30"                    # WARNING, inherited from the root: nothing set


def test_console_levels():
    assert console_level() == console_level(0, quiet=True) == logging.WARNING
    assert console_level(1) == logging.INFO and console_level(3) == logging.DEBUG
    assert console_level(2, quiet=True) == logging.WARNING


def test_messages_by_level_and_settings_restored(capsys, tmp_path):
    """-v shows info lines, -vv debug lines (with the logger's name), the default only
    warnings; the log file gets every level; the package logger is as before afterwards."""
    log = logging.getLogger("asekit.aero.gaf")
    pkg = logging.getLogger("asekit")
    before = (pkg.level, list(pkg.handlers), pkg.propagate)
    shown = {}
    for verbose in (0, 1, 2):
        with _Logging(verbose=verbose, log_file=str(tmp_path / f"{verbose}.log")):
            log.debug("cache read and verified: /x.npz")
            log.info("GAF database built in 3.4 s")
            log.warning("a warning")
        shown[verbose] = capsys.readouterr().err.splitlines()
        assert (pkg.level, list(pkg.handlers), pkg.propagate) == before
    assert shown[0] == ["warning: a warning"]
    assert shown[1] == ["info: GAF database built in 3.4 s", "warning: a warning"]
    assert shown[2][0] == "debug: asekit.aero.gaf: cache read and verified: /x.npz"
    text = (tmp_path / "0.log").read_text()
    assert "DEBUG asekit.aero.gaf: cache read and verified: /x.npz" in text
    assert "INFO asekit.aero.gaf: GAF database built in 3.4 s" in text


def test_a_warning_during_a_progress_bar_is_one_line_once(capsys, tmp_path):
    """issue 30: warnings were printed into the middle of the progress bar. tqdm.write clears
    the bar, writes the line and redraws the bar: the warning is one whole line of stderr (the
    bar's redraws are separated by carriage returns), shown once, and in the log file."""
    from tqdm import tqdm
    log = tmp_path / "run.log"
    with _Logging(log_file=str(log)), _OneLineWarnings():
        bar = tqdm(total=4, file=sys.stderr, mininterval=0, ascii=True, desc="stage")
        for _ in range(4):
            bar.update(1)
            warnings.warn("p-k: the k-iteration did not converge at 17400 m/s", RuntimeWarning,
                          stacklevel=1)
        bar.close()
    err = capsys.readouterr().err
    pieces = [p.strip() for line in err.split("\n") for p in line.split("\r")]
    line = "warning: RuntimeWarning: p-k: the k-iteration did not converge at 17400 m/s"
    assert pieces.count(line) == 1, err
    assert "stage" in err                                    # the bar was drawn
    assert sum("17400 m/s" in p for p in pieces) == 1        # never inside a bar's line
    assert log.read_text().count("WARNING asekit.cli.main: RuntimeWarning: p-k") == 1


def test_unusable_log_file_is_refused_first_in_one_line(tmp_path, capsys):
    """--log-file is an output path like --json: checked before the command reads anything
    (here the case file does not exist: the error must be about the log file), one line,
    exit 2, for every command, before or after its name."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for argv in (["analyse", str(tmp_path / "missing.toml"), "--log-file",
                  str(blocker / "run.log")],
                 ["--log-file", str(tmp_path), "cases"],
                 ["cases", "--log-file", "  "]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and err[0].startswith("error: --log-file"), err
    assert not (tmp_path / "missing.toml").exists()


def test_log_file_gets_the_error_line(tmp_path, capsys):
    """An input error is one line on stderr (no traceback), and the same line in the log file
    after the command's debug lines."""
    log = tmp_path / "sub" / "run.log"                      # a missing folder is made
    case = tmp_path / "bad.toml"
    case.write_text("name = 'x'\n")
    assert main(["analyse", str(case), "--log-file", str(log), "-v"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: "), err
    text = log.read_text()
    assert "DEBUG asekit.cli.main: asekit " in text          # the command line, first
    assert f"ERROR asekit.cli.analyse: {err[0]}" in text


def test_quiet_and_verbose_before_or_after_the_command():
    from asekit.cli.main import build_parser
    p = build_parser()
    for argv in (["--quiet", "reproduce"], ["reproduce", "--quiet"]):
        assert p.parse_args(argv).quiet is True
    assert p.parse_args(["reproduce"]).quiet is False
    assert p.parse_args(["-vv", "cases"]).verbose == 2
    assert p.parse_args(["cases", "-v"]).verbose == 1
    assert p.parse_args(["cases", "--log-file", "a.log"]).log_file == "a.log"
    assert p.parse_args(["--log-file", "a.log", "cases"]).log_file == "a.log"


def test_handler_writes_through_tqdm(monkeypatch):
    """The console handler goes through tqdm.write (the one writer that keeps bars whole)."""
    from tqdm import tqdm
    calls = []
    monkeypatch.setattr(tqdm, "write", classmethod(lambda cls, s, file=None, **k:
                                                   calls.append(s)))
    with _Logging(verbose=1):
        logging.getLogger("asekit.x").info("hello\n  world")
    assert calls == ["info: hello world"]


@pytest.fixture(autouse=True)
def _restore_showwarning():
    saved = warnings.showwarning
    yield
    warnings.showwarning = saved



def test_main_restores_the_logging_settings(tmp_path, capsys):
    """main() in-process leaves the package logger as it found it (handlers, level,
    propagation) and closes the log file, whatever the command's exit."""
    pkg = logging.getLogger("asekit")
    before = (pkg.level, list(pkg.handlers), pkg.propagate)
    log = tmp_path / "cases.log"
    assert main(["cases", "-vv", "--log-file", str(log)]) == 0
    assert (pkg.level, list(pkg.handlers), pkg.propagate) == before
    assert main(["analyse", str(tmp_path / "missing.toml"), "-v"]) == 2
    assert (pkg.level, list(pkg.handlers), pkg.propagate) == before
    assert "DEBUG asekit.cli.main: asekit " in log.read_text()
    capsys.readouterr()
