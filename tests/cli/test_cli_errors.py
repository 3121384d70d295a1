"""The command line's errors and output paths (issue 22): one line per error, never a
traceback; exit 2 for input errors, 1 for a bug (``--debug`` shows its traceback), 130 for an
interrupt; output paths checked, and their folders made, before any work, the same way in every
command; reports and JSON written atomically."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from asekit.case import pipeline as P
from asekit.case import report as R
from asekit.cli.main import main
from asekit.util.paths import CASES_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"
AGARD = CASES_DIR / "agard445_6.toml"
FV16 = CASES_DIR / "nafems_fv16.toml"


#: rebuilt GAF databases go to a session temporary folder (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("session_gaf_cache")


@pytest.fixture
def no_work(monkeypatch):
    """Any step of the pipeline fails the test: the error must come before any work."""
    def ran(*a, **k):
        pytest.fail("the pipeline ran")
    for name in ("modal_model", "gaf_database", "flutter", "box_mesh"):
        monkeypatch.setattr(P, name, ran)


def _one_line(capsys, *fragments) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for f in fragments:
        assert f in lines[0], lines[0]
    return lines[0]


def _edit(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new)


_AGARD = AGARD.read_text()
_FIN = FIN.read_text()
#: name -> (case file text, what the one line must name). The issue's reproducers.
REPRODUCERS = {
    "altitude_50km": (_edit(_AGARD, "densities = [0.4278]", "altitudes = [50000.0]\n#"),
                      "flight.altitudes[0] must be <= 47000 m"),
    "point_mass_off_planform": (_FIN + "\n[[point_mass]]\nposition = [5.0, 5.0]\nmass = 0.01\n",
                                "point_mass[0].position [5.0, 5.0] m is off the planform"),
    "boxes_200x200": (_edit(_AGARD, "n_chord = 16, n_span = 16", "n_chord = 200, n_span = 200"),
                      "aero.boxes: 200 x 200 = 40000 boxes need a 23.8 GiB"),
    "mesh_500x500": (_edit(_AGARD, "n_chord = 20\nn_span = 20", "n_chord = 500\nn_span = 500"),
                     "500 x 500 elements"),
    "tiny_modulus": (_edit(_FIN, "youngs_modulus = 70.0e9", "youngs_modulus = 1e-30"),
                     "material.youngs_modulus = 1e-30 Pa is outside"),
    "tiny_density": (_edit(_FIN, "density = 2700.0", "density = 1e-30"),
                     "material.density = 1e-30 kg/m^3 is outside"),
    "folded_planform": (_edit(_FIN, "tip_leading_edge = [0.078, 0.150]",
                              "tip_leading_edge = [30.0, 0.150]"), "panel[0]: the leading edge"),
}


@pytest.mark.parametrize("name", sorted(REPRODUCERS))
def test_reproducer_is_one_line_exit_2_before_any_work(name, tmp_path, capsys, no_work):
    text, fragment = REPRODUCERS[name]
    f = tmp_path / f"{name}.toml"
    f.write_text(text)
    assert main(["analyse", str(f), "--quiet"]) == 2
    _one_line(capsys, f"error: {name}.toml: ", fragment)


def test_latin1_case_is_one_line_exit_2(tmp_path, capsys, no_work):
    f = tmp_path / "latin1.toml"
    f.write_bytes(("# caf\u00e9\n" + _FIN).encode("latin-1"))
    assert main(["analyse", str(f), "--quiet"]) == 2
    _one_line(capsys, "latin1.toml is not UTF-8 (byte 0xe9 on line 1)")


def test_directory_as_case_is_one_line_exit_2(tmp_path, capsys, no_work):
    d = tmp_path / "case.toml"
    d.mkdir()
    assert main(["analyse", str(d), "--quiet"]) == 2
    _one_line(capsys, "is a directory")


def test_directory_as_case_in_a_fresh_process():
    """The whole command, as a user runs it: one line, exit 2, and quick (no pipeline import
    is needed to refuse it; the bound is loose for a loaded machine)."""
    t = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "asekit", "analyse", str(CASES_DIR), "--quiet"],
                       capture_output=True, text=True, timeout=120)
    elapsed = time.perf_counter() - t
    assert p.returncode == 2 and p.stdout == "", p
    assert len(p.stderr.strip().splitlines()) == 1 and "is a directory" in p.stderr
    assert elapsed < 30.0


def test_bom_case_is_read(tmp_path, capsys):
    """A UTF-8 file with a BOM is read (FV16: a few seconds)."""
    f = tmp_path / "bom.toml"
    f.write_bytes(b"\xef\xbb\xbf" + FV16.read_bytes())
    out = tmp_path / "o.json"
    assert main(["analyse", str(f), "--quiet", "--json", str(out)]) == 0
    from asekit.case import load_case
    assert json.loads(out.read_text())["case"] == load_case(FV16).name


# ---- exit codes ------------------------------------------------------------------------------
def test_internal_error_is_one_line_exit_1_and_debug_shows_the_traceback(monkeypatch, capsys):
    def bug(*a, **k):
        raise KeyError("oops")
    monkeypatch.setattr(R, "run_analysis", bug)
    assert main(["analyse", str(FV16), "--quiet"]) == 1
    _one_line(capsys, "internal error (a bug in asekit", "KeyError", "rerun with --debug")
    assert main(["analyse", str(FV16), "--quiet", "--debug"]) == 1
    err = capsys.readouterr().err
    assert "Traceback" in err and "KeyError" in err.strip().splitlines()[-1]
    assert main(["--debug", "analyse", str(FV16), "--quiet"]) == 1
    assert "Traceback" in capsys.readouterr().err


def test_solver_error_is_exit_2(monkeypatch, capsys):
    from asekit.case import SolverError

    def fail(*a, **k):
        raise SolverError("the modal model failed (ArpackError: ARPACK error 3): check material")
    monkeypatch.setattr(R, "run_analysis", fail)
    assert main(["analyse", str(FV16), "--quiet"]) == 2
    _one_line(capsys, "error: nafems_fv16.toml: the modal model failed")


def test_keyboard_interrupt_is_130(monkeypatch, capsys):
    def stop(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(R, "run_analysis", stop)
    assert main(["analyse", str(FV16), "--quiet"]) == 130
    assert capsys.readouterr().err.strip() == "interrupted"


def test_interrupt_turned_into_another_error_is_still_130(monkeypatch, capsys):
    """Seen with a real SIGINT during --report: matplotlib turned it into "ValueError: Invalid
    bounding box" (exit 2, a wrong reason)."""
    import signal

    def figures_interrupted(*a, **k):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)
        except KeyboardInterrupt:
            raise ValueError("Invalid bounding box") from None
        pytest.fail("no KeyboardInterrupt")
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        pytest.skip("SIGINT is not Python's default handler here")
    monkeypatch.setattr(R, "run_analysis", figures_interrupted)      # analyse reports it
    assert main(["analyse", str(FV16), "--quiet"]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "interrupted"
    monkeypatch.setattr(R, "run_analysis", lambda *a, **k: None)      # main sees it
    monkeypatch.setattr(R, "summary", figures_interrupted)
    assert main(["analyse", str(FV16), "--quiet"]) == 130
    assert capsys.readouterr().err.strip() == "interrupted"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler     # restored


# ---- output paths ----------------------------------------------------------------------------
def test_json_into_a_missing_folder_is_created(tmp_path, capsys):
    """Reproducer: `analyse ... --json nodir/o.json` ran the analysis, then a traceback."""
    out = tmp_path / "nodir" / "deeper" / "o.json"
    assert main(["analyse", str(FV16), "--quiet", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    assert data["modes"]["frequencies_hz"]
    assert [p.name for p in out.parent.iterdir()] == ["o.json"]      # no temporary file left


@pytest.mark.parametrize("option", ["--report", "--json"])
def test_existing_file_or_folder_refused_before_any_work(option, tmp_path, capsys, no_work):
    """Reproducer: `--report README.md` (a file) ran the whole analysis, then a traceback."""
    f = tmp_path / "README.md"
    f.write_text("x")
    target = str(f) if option == "--report" else str(tmp_path)
    assert main(["analyse", str(FIN), "--quiet", option, target]) == 2
    _one_line(capsys, f"error: {option} ")
    assert f.read_text() == "x"


def test_output_under_a_file_refused_before_any_work(tmp_path, capsys, no_work):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["analyse", str(FIN), "--quiet", "--json", str(f / "o.json")]) == 2
    _one_line(capsys, "not a directory")


def test_sweep_out_checked_and_created_the_same_way(tmp_path, capsys, monkeypatch):
    import asekit.sweep as S
    monkeypatch.setattr(S, "load_sweep", lambda *a: pytest.fail("read the sweep file"))
    assert main(["sweep", "x.toml", "--out", str(tmp_path)]) == 2     # a folder
    _one_line(capsys, "--out", "give a .csv or .parquet path")
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["sweep", "x.toml", "--out", str(f / "r.csv")]) == 2
    _one_line(capsys, "--out", "not a directory")
    monkeypatch.setattr(S, "load_sweep", lambda *a: (_ for _ in ()).throw(FileNotFoundError()))
    assert main(["sweep", "x.toml", "--out", str(tmp_path / "new" / "r.csv")]) == 2
    _one_line(capsys, "sweep file x.toml not found")
    assert (tmp_path / "new").is_dir()                          # made before the work


# ---- atomic outputs --------------------------------------------------------------------------
def _fake_report(monkeypatch, interrupt_at: int | None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setattr(R, "summary", lambda a: {"case": "fake"})
    monkeypatch.setattr(R, "format_summary", lambda s, width=100: "table")
    monkeypatch.setattr(R, "figures", lambda a: {f"f{i}": plt.figure() for i in range(3)})
    calls = []
    real = R.save_figure

    def save(fig, d, name):
        calls.append(name)
        if len(calls) == interrupt_at:
            plt.close(fig)
            raise KeyboardInterrupt
        return real(fig, d, name)
    monkeypatch.setattr(R, "save_figure", save)


def test_interrupted_report_leaves_no_half_report(tmp_path, monkeypatch):
    """Reproducer: SIGINT during --report left PNGs and summary.json without index.html."""
    d = tmp_path / "rep"
    _fake_report(monkeypatch, interrupt_at=2)
    with pytest.raises(KeyboardInterrupt):
        R.write_report(None, d)
    assert list(tmp_path.iterdir()) == []                       # nothing, not half
    _fake_report(monkeypatch, interrupt_at=None)
    index = R.write_report(None, d)
    assert sorted(p.name for p in d.iterdir()) == ["f0.png", "f1.png", "f2.png", "index.html",
                                                   "summary.json"]
    umask = os.umask(0)
    os.umask(umask)
    assert index == d / "index.html" and (d.stat().st_mode & 0o777) == 0o777 & ~umask
    first = index.read_text()
    _fake_report(monkeypatch, interrupt_at=1)
    with pytest.raises(KeyboardInterrupt):
        R.write_report(None, d)
    assert index.read_text() == first and [p.name for p in tmp_path.iterdir()] == ["rep"]
    _fake_report(monkeypatch, interrupt_at=None)
    (d / "stale.png").write_text("old")
    R.write_report(None, d)                                     # a new report replaces it
    assert not (d / "stale.png").exists() and [p.name for p in tmp_path.iterdir()] == ["rep"]


def test_atomic_json_keeps_the_old_file_when_the_write_fails(tmp_path, monkeypatch):
    f = tmp_path / "o.json"
    R.write_text_atomic(f, "old")

    def broken(src, dst):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", broken)
    with pytest.raises(OSError):
        R.write_text_atomic(f, "new")
    assert f.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["o.json"]
