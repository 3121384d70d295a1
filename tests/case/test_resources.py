"""Fail early, in case-file terms, and resume (issue 30): asekit/case/resources.py, the
loader's and the pipeline's resource checks, ``boxes = "auto"`` with the mesh rule of the method
used at each Mach, and the per-(Mach, k) GAF entries of asekit/aero/gaf.py.

The reproducer is tests/case/data/clipped_delta_fin.toml, the case of the issue's first bullet
(a clipped-delta fin written from docs/case-format.md: method "auto", M 0.5-0.9 plus 1.5 and
2.5, f_max = 2000 Hz, u_min = 100 m/s, boxes "auto"). Before: it passed the loader, ran 3 min 41 s
(the issue's report) and died with a traceback about max_cells at M 1.5."""

from __future__ import annotations

import re
import subprocess
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from asekit.aero import gaf as G
from asekit.aero.boxes import MeshRuleWarning, check_mesh_rules
from asekit.aero.supersonic import BPW_MIN, grid_size, kernel_wavelength, mach_grid
from asekit.case import CaseError
from asekit.case import pipeline as P
from asekit.case.resources import auto_boxes, box_counts, resource_problem
from asekit.case.schema import case_from_dict
from asekit.util.validate import read_toml

DATA = Path(__file__).parent / "data"
CLIPPED = DATA / "clipped_delta_fin.toml"


def _dict(**aero) -> dict:
    d = read_toml(CLIPPED, CaseError)
    d["aero"].update(aero)
    return d


def _fix_values(message: str) -> tuple[float, float]:
    m = re.search(r"aero\.f_max <= ([0-9.e+]+) Hz or aero\.u_min >= ([0-9.e+]+) m/s fits",
                  message)
    assert m, message
    return float(m.group(1)), float(m.group(2))


# ---- refused early, in case-file terms --------------------------------------------------------
def test_clipped_delta_refused_by_the_command_line_in_one_line_with_exit_2():
    """The issue's case: one line naming aero.f_max / aero.u_min / aero.boxes and the values
    that fit, exit 2, within 30 s (the issue's "Done when"; measured 3.2 s, most of it
    imports), never the solver's options (max_cells, cells_per_box)."""
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "asekit", "analyse", str(CLIPPED)],
                       capture_output=True, text=True, timeout=120)
    elapsed = time.perf_counter() - t0
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    line = lines[0]
    for key in ("aero.machs[5] = 1.5", "aero.f_max", "aero.u_min", "aero.boxes", "fits"):
        assert key in line, line
    for internal in ("max_cells", "cells_per_box", "cells_per_wavelength"):
        assert internal not in line, line
    assert elapsed < 30.0, elapsed


def test_the_values_it_names_fit_and_are_close_to_the_limit():
    """The f_max and u_min the message gives load; 5 % beyond them is refused again (the
    bisection found the limit, not just some value that fits)."""
    with pytest.raises(CaseError) as exc:
        case_from_dict(_dict())
    f_fit, u_fit = _fix_values(str(exc.value))
    assert f_fit < 2000.0 and u_fit > 100.0
    case_from_dict(_dict(f_max=f_fit))
    case_from_dict(_dict(u_min=u_fit))
    for over in (_dict(f_max=1.05 * f_fit), _dict(u_min=u_fit / 1.05)):
        with pytest.raises(CaseError, match=r"aero\.machs\[\d\] = 1\.5"):
            case_from_dict(over)


def test_explicit_k_and_boxes_name_their_own_keys():
    """An explicit k list names aero.reduced_frequencies with its largest k that fits; explicit
    boxes are named with counts (the grid follows the box chords too)."""
    ks = [0.001, 0.1, 0.5, 1.0, 2.0, 5.0, 12.0]
    with pytest.raises(CaseError) as exc:
        case_from_dict(_dict(reduced_frequencies=ks, f_max=400.0))
    msg = str(exc.value)
    assert "aero.reduced_frequencies up to k = " in msg and "aero.f_max" in msg, msg
    k_fit = float(re.search(r"up to k = ([0-9.]+)", msg).group(1))
    assert 0.1 < k_fit < 12.0
    case_from_dict(_dict(reduced_frequencies=[k for k in ks if k < k_fit] + [k_fit],
                         f_max=400.0))
    # with f_max = 2000 Hz the automatic boxes alone (the DLM rule) are too fine for the grid:
    # no single key fits, and the line says so instead of naming a value that would not
    with pytest.raises(CaseError, match="no value of these keys alone fits"):
        case_from_dict(_dict(reduced_frequencies=ks))
    # explicit fine boxes at a low k: the box chords set the cells, coarser boxes fit
    boxes = [{"n_chord": 120, "n_span": 80}]
    with pytest.raises(CaseError) as exc:
        case_from_dict(_dict(reduced_frequencies=[0.001, 0.1], boxes=boxes))
    assert "aero.boxes = [{ n_chord = " in str(exc.value), str(exc.value)


def test_grid_size_counts_what_mach_grid_builds():
    """The cheap count (corners only, no mesh, no grid) equals the cells of the grid the solver
    builds, and says "does not fit" exactly when mach_grid refuses."""
    case = case_from_dict(_dict(f_max=400.0))
    mesh = P.box_mesh(case)
    k = P.reduced_frequencies(case)[-1]
    for mach, kk, sym in ((1.5, k, False), (2.5, k, False), (1.5, 3 * k, True)):
        g = grid_size(mesh.corners, mesh.strip, mach, kk, 0.1, sym)
        if g.fits:
            assert mach_grid(mesh, mach, kk, 0.1, sym).n_cells == g.n_relevant
        else:
            with pytest.raises(ValueError, match="max_cells"):
                mach_grid(mesh, mach, kk, 0.1, sym)


def test_a_case_built_in_python_is_refused_at_the_pipeline_door(monkeypatch):
    """A case built in Python skips the loader: gaf_database refuses it before the modes."""
    case = case_from_dict(_dict(f_max=400.0))
    big = replace(case, aero=replace(case.aero, f_max=2000.0))

    def ran(*a, **k):
        pytest.fail("the modal model was computed before the check")
    monkeypatch.setattr(P, "modal_model", ran)
    with pytest.raises(CaseError, match=r"aero\.f_max <= .* Hz or aero\.u_min >= "):
        P.gaf_database(big)


def test_dlm_matrix_refusal_names_the_values_that_fit():
    """The DLM matrix check (issue 22) now also gives the f_max / u_min that fit."""
    d = _dict(machs=[0.5, 0.8], f_max=40000.0)
    with pytest.raises(CaseError) as exc:
        case_from_dict(d)
    msg = str(exc.value)
    assert "DLM matrix" in msg and "from the mesh rules" in msg, msg
    f_fit, u_fit = _fix_values(msg)
    case_from_dict(_dict(machs=[0.5, 0.8], f_max=f_fit))
    with pytest.raises(CaseError, match="DLM matrix"):
        case_from_dict(_dict(machs=[0.5, 0.8], f_max=1.05 * f_fit))


# ---- boxes = "auto" follows the method used at each Mach -------------------------------------
def test_auto_boxes_meet_the_mach_box_rule_at_a_supersonic_mach():
    """With M 1.2 among the Machs the automatic boxes resolve the Mach-box kernel's shortest
    wavelength 2 pi b (M - 1) / (k M) with BPW_MIN = 6 boxes (asekit.aero.supersonic: the rule
    its MeshRuleWarning names) and still meet the DLM rules; the DLM rule alone did not."""
    case = case_from_dict(_dict(machs=[0.8, 1.2], f_max=200.0))
    a = case.aero
    mesh = P.box_mesh(case)
    k_max = P.reduced_frequencies(case)[-1]
    lam = kernel_wavelength(1.2, k_max, a.reference_semichord)
    assert lam / mesh.chord.max() >= BPW_MIN
    dlm_only = auto_boxes(case.panels[0].planform, a.u_min, a.f_max)
    assert lam / (case.panels[0].planform.root_chord / dlm_only[0]) < BPW_MIN   # too coarse
    with warnings.catch_warnings():
        warnings.simplefilter("error", MeshRuleWarning)
        assert check_mesh_rules(mesh, a.u_min, a.f_max).ok
        P.gaf_database(replace(case, aero=replace(a, machs=(1.2,))), progress=False)


def test_auto_boxes_of_dlm_machs_unchanged():
    """Subsonic-only cases keep the DLM rule's boxes (so the shipped fin's fingerprint and
    data/gaf_fin.npz stay valid)."""
    case = case_from_dict(_dict(machs=[0.5, 0.9], f_max=300.0))
    a = case.aero
    assert box_counts(case.panels, a) == (auto_boxes(case.panels[0].planform, a.u_min,
                                                     a.f_max),)
    assert resource_problem(case.panels, a) is None


# ---- per-(Mach, k) GAF entries: reuse and resume ---------------------------------------------
def _small(**aero) -> object:
    """The clipped delta at one subsonic and one supersonic Mach with a short k list: both
    paths of the entry cache (the DLM's streamed k, the Mach box's k by k)."""
    d = _dict(machs=[0.8, 1.5], f_max=150.0, reduced_frequencies=[0.001, 0.1, 0.3, 0.6],
              boxes=[{"n_chord": 8, "n_span": 6}], **aero)
    d["modes"] = {"count": 3, "keep_rigid": True}
    return case_from_dict(d)


class _Counter:
    """Counts the GAF entries computed (each is projected on the modes once)."""

    def __init__(self, monkeypatch, fail_after: int | None = None):
        self.n = 0
        self.fail_after = fail_after
        real = G.modal_forces

        def counted(*a, **k):
            if self.fail_after is not None and self.n >= self.fail_after:
                raise KeyboardInterrupt("simulated interruption")
            self.n += 1
            return real(*a, **k)
        monkeypatch.setattr(G, "modal_forces", counted)


def test_second_run_reuses_the_cached_entries(tmp_path, monkeypatch):
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    case = _small()
    count = _Counter(monkeypatch)
    db = P.gaf_database(case, progress=False)
    assert count.n == 2 * 4                       # every (Mach, k) computed once
    next(tmp_path.glob("gaf_*.npz")).unlink()     # the whole database; the entries stay
    again = P.gaf_database(case, progress=False)   # from the entries alone
    assert count.n == 8 and np.array_equal(again.Q, db.Q)
    P.gaf_database(case, progress=False)           # and from the whole database
    assert count.n == 8


@pytest.mark.parametrize("fail_after", [3, 6])
def test_interrupted_build_resumes_bit_for_bit(tmp_path, monkeypatch, fail_after):
    """An interruption after n entries (inside the DLM Mach: 3; inside the Mach box's: 6):
    the next run computes the 8 - n others only and equals an uninterrupted run bit for bit."""
    case = _small()
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path / "whole"))
    ref = P.gaf_database(case, progress=False)
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path / "resumed"))
    count = _Counter(monkeypatch, fail_after=fail_after)
    with pytest.raises(KeyboardInterrupt):
        P.gaf_database(case, progress=False)
    assert count.n == fail_after
    assert not list((tmp_path / "resumed").glob("gaf_*.npz"))      # no database yet
    count.fail_after, count.n = None, 0
    resumed = P.gaf_database(case, progress=False)
    assert count.n == 8 - fail_after
    assert np.array_equal(resumed.Q, ref.Q) and np.array_equal(resumed.k, ref.k)


def test_a_corrupt_entry_is_recomputed(tmp_path, monkeypatch):
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    case = _small()
    ref = P.gaf_database(case, progress=False)
    next(tmp_path.glob("gaf_*.npz")).unlink()
    entry = sorted((tmp_path / G.ENTRY_FOLDER).glob("gafk_*.npz"))[0]
    entry.write_bytes(entry.read_bytes()[:-40])                    # truncated
    count = _Counter(monkeypatch)
    again = P.gaf_database(case, progress=False)
    assert count.n == 1 and np.array_equal(again.Q, ref.Q)


def test_huge_pk_work_refused_with_the_step_that_fits():
    """7 Machs x 40 altitudes x 18001 speeds = 5.0e6 p-k points (about 28 h at the 20 ms a
    point measured on the clipped-delta fin) is refused by the loader; the step it names
    fits and a step 5 % finer does not."""
    d = _dict(f_max=400.0)
    d["flight"]["altitudes"] = [250.0 * i for i in range(40)]
    d["flight"]["velocities"] = {"min": 100.0, "max": 1900.0, "step": 0.1}
    with pytest.raises(CaseError) as exc:
        case_from_dict(d)
    msg = str(exc.value)
    assert msg.startswith("flight.velocities: 7 Mach numbers x 40 flight conditions x 18001 "
                          "speeds"), msg
    step = float(re.search(r"flight\.velocities\.step >= ([0-9.]+) m/s fits", msg).group(1))
    d["flight"]["velocities"]["step"] = step
    case_from_dict(d)
    d["flight"]["velocities"]["step"] = step / 1.05
    with pytest.raises(CaseError, match="p-k points"):
        case_from_dict(d)


@pytest.mark.slow
def test_the_issues_case_with_the_values_it_names_runs_and_is_reused(tmp_path, monkeypatch):
    """The issue's "Done when": with the f_max the refusal names, the clipped-delta fin's GAF
    database is computed (7 Machs x 15 k = 105 entries; 75 s measured on the shared 2-core
    machine) and a second run computes none of them (read from the cache)."""
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    with pytest.raises(CaseError) as exc:
        case_from_dict(_dict())
    f_fit, _ = _fix_values(str(exc.value))
    case = case_from_dict(_dict(f_max=f_fit))
    count = _Counter(monkeypatch)
    db = P.gaf_database(case, progress=False)
    assert count.n == 7 * 15 and db.Q.shape[:2] == (7, 15)
    assert np.all(np.isfinite(db.Q))
    again = P.gaf_database(case, progress=False)
    assert count.n == 7 * 15 and np.array_equal(again.Q, db.Q)
