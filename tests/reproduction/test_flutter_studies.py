"""The damping and converged-mesh flutter studies of asekit.reproduction.flutter (issue 10).

References: a damped single-degree-of-freedom oscillator m x'' + c x' + k x = 0 has the roots
p = omega (-zeta +- i sqrt(1 - zeta^2)) with c = 2 zeta omega m, so at vanishing dynamic pressure
the p-k roots of every elastic mode must show the damping ratio zeta put in; hysteretic damping
i g K equals the viscous c = g k / omega at the frequency omega.
"""

import numpy as np
import pytest

import asekit.reproduction.flutter as rf
from asekit.aeroelastic.flutter import pk_flutter
from asekit.aeroelastic.statespace import modal_arrays
from asekit.util.paths import user_cache_dir

DATA, REASON = rf.load_fin_gafs()
needs_db = pytest.mark.skipif(DATA is None, reason=REASON or "no GAF database")


def _toy():
    return modal_arrays(M=np.diag([2.0, 1.0, 1.0]), K=np.diag([0.0, 4.0, 9.0]), n_rigid=1)


def test_damped_modal_matrices():
    m = rf.damped_modal(_toy(), zeta=0.01)
    assert np.allclose(np.diag(m.C), [0.0, 2 * 0.01 * 2.0, 2 * 0.01 * 3.0])
    g = rf.damped_modal(_toy(), g=0.02, omega_ref=3.0)
    assert np.allclose(np.diag(g.C), [0.0, 0.02 * 4.0 / 3.0, 0.02 * 9.0 / 3.0])
    # at omega = omega_ref the viscous equivalent gives the mode g/2 = zeta (resonance)
    assert np.isclose(g.C[2, 2] / (2 * 3.0), 0.01)


def test_damped_modal_rejects_bad_input():
    with pytest.raises(ValueError, match="zeta"):
        rf.damped_modal(_toy(), zeta=-0.1)
    with pytest.raises(ValueError, match="g must"):
        rf.damped_modal(_toy(), g=float("nan"))
    with pytest.raises(ValueError, match="omega_ref"):
        rf.damped_modal(_toy(), g=0.01)


@needs_db
def test_pk_roots_carry_the_modal_damping_at_zero_airspeed():
    db, modal = DATA
    zeta = 0.01
    res = pk_flutter(rf.damped_modal(modal, zeta=zeta), db.at(0.75), 1.225,
                     [0.5, 1.0])
    # q = 0.15 Pa: the aerodynamic damping is negligible against 1 % structural damping
    assert np.allclose(res.damping_ratio[0], zeta, rtol=0.02)


@needs_db
def test_damping_raises_the_flutter_speed_monotonically():
    db, modal = DATA
    rows = rf.damping_study(modal, db, ratios=(0.0, 0.005, 0.01), gs=(0.0, 0.01),
                            velocities=rf.DAMPING_VELOCITIES)
    z = [r["speed"] for r in rows if r["kind"] == "zeta"]
    assert all(s is not None for s in z) and z[0] < z[1] < z[2]
    g = [r["speed"] for r in rows if r["kind"] == "g"]
    assert g[0] == pytest.approx(z[0]) and g[1] > g[0]
    # g = 0.01 at the flutter frequency ~ zeta = 0.5 % at resonance (the modes sit near it)
    assert abs(g[1] / z[1] - 1) < 0.03


def test_user_cache_dir_override(monkeypatch, tmp_path):
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path / "c"))
    assert user_cache_dir() == tmp_path / "c"
    monkeypatch.delenv("ASEKIT_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert user_cache_dir() == tmp_path / "x" / "asekit"


@needs_db
def test_converged_study_is_cached_and_verified(monkeypatch, tmp_path):
    db, _ = DATA
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    kw = dict(structure=((6, 7), (12, 14)), aero=((14, 10),), tol=0.5,
              velocities=np.arange(150.0, 260.0, 4.0))
    first = rf.converged_flutter_study(db, **kw)
    files = list(tmp_path.glob("flutter_convergence_*.npz"))
    assert len(files) == 1
    # the 6x7 distributed model is the single-node one (one node in the 5 mm region): the
    # reproduction's 218 m/s; 12x14 moves it by more than 10 %
    assert first["rows"][0][3] == pytest.approx(218.09, abs=0.5)
    assert abs(first["rows"][1][3] / first["rows"][0][3] - 1) > 0.1

    def boom(*a, **k):
        raise AssertionError("recomputed although cached")

    monkeypatch.setattr(rf, "_mesh_flutter", boom)
    again = rf.converged_flutter_study(db, **kw)
    assert again["speed"] == first["speed"] and again["rows"] == first["rows"]
    # a corrupted file is detected (checksum) and recomputed, not trusted
    files[0].write_bytes(b"not an npz")
    with pytest.raises(AssertionError, match="recomputed"):
        rf.converged_flutter_study(db, **kw)


@needs_db
def test_extrapolated_flutter_is_cached_and_verified(monkeypatch, tmp_path):
    """The default reproduce's extrapolated rows (issue 23) on small graded meshes: computed
    once, then read from the user cache; a corrupted file is recomputed, not trusted."""
    import asekit.case.convergence as conv
    db, _ = DATA
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    kw = dict(structure=(24, 18), aero=(14, 10), velocities=np.arange(150.0, 300.0, 4.0))
    first = rf.extrapolated_flutter(db, **kw)
    files = list(tmp_path.glob("flutter_extrapolated_*.npz"))
    assert len(files) == 1
    assert first["meshes"] == [[24, 18, 14, 10], [16, 12, 9, 7], [11, 8, 6, 4]]
    assert len(first["speeds"]) == 3 and first["speed_error"] > 0
    q = {x.key: x for x in rf.extrapolated_quantities(first)}
    assert q["flutter.extrapolated.pk.M075.h0.speed_ms"].asekit == first["speed"]
    assert q["flutter.extrapolated.pk.M075.h0.freq_error_hz"].unit == "Hz"

    def boom(*a, **k):
        raise AssertionError("recomputed although cached")

    monkeypatch.setattr(conv, "convergence_study", boom)
    again = rf.extrapolated_flutter(db, **kw)
    assert again == first
    files[0].write_bytes(b"not an npz")
    with pytest.raises(AssertionError, match="recomputed"):
        rf.extrapolated_flutter(db, **kw)
