"""The command line as a newcomer meets it (issue 11): argparse errors instead of tracebacks,
progress on stderr and --quiet. (The reproduce command's table, verdicts, output paths and exit
codes: tests/reproduction/test_reproduce_cli.py.)"""

import subprocess
import sys

import pytest

from asekit.cli.main import main


def _run(*args, timeout=120):
    return subprocess.run([sys.executable, "-m", "asekit", *args], capture_output=True,
                          text=True, timeout=timeout)


# ---- arguments -------------------------------------------------------------------------------
def test_unknown_chapter_is_an_argparse_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--only", "foo"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "unknown chapter 'foo'; choose from servo, structure, aero, flutter, ase" in err


# ---- streams ---------------------------------------------------------------------------------
def test_progress_on_stderr_and_quiet():
    p = _run("reproduce", "--only", "servo")
    assert p.returncode == 0 and "chapter" in p.stderr and "servo" not in p.stdout.splitlines()[0]
    q = _run("reproduce", "--only", "servo", "--quiet")
    assert q.returncode == 0 and "chapter" not in q.stderr
    assert max(len(line) for line in q.stdout.splitlines()) <= 100


def test_sweep_without_pandas_names_the_pip_install_before_any_work(tmp_path):
    """issue 30: `sweep` without its extra printed a raw ModuleNotFoundError."""
    from pathlib import Path
    code = ("import sys; sys.modules['pandas'] = None; from asekit.cli.main import main; "
            "sys.exit(main(['sweep', 'data/sweeps/fin_envelope.toml', '--out', "
            f"{str(tmp_path / 'o.csv')!r}]))")
    root = Path(__file__).resolve().parents[2]
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root,
                       timeout=120)
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [
        "error: asekit sweep (the results table) needs pandas: pip install 'asekit-aero[sweep]'"]
    assert not (tmp_path / "o.csv").exists()


def test_warnings_are_one_line_each_shown_once_and_restored(capsys):
    """issue 30: library warnings came with source lines, into the progress bar, every time."""
    import logging
    import warnings

    from asekit.cli.main import _Logging, _OneLineWarnings
    before = warnings.showwarning
    package = logging.getLogger("asekit")
    handlers, level = list(package.handlers), package.level
    with _Logging(), _OneLineWarnings():
        for _ in range(3):
            warnings.warn("p-k: the k-iteration did not\n  converge at U = 17400 m/s",
                          RuntimeWarning, stacklevel=1)
        warnings.warn("another", UserWarning, stacklevel=1)
    assert warnings.showwarning is before
    assert package.handlers == handlers and package.level == level
    err = capsys.readouterr().err.splitlines()
    assert err == ["warning: RuntimeWarning: p-k: the k-iteration did not converge at U = "
                   "17400 m/s", "warning: UserWarning: another"]
