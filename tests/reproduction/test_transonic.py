"""The fin through the transonic gap by the TSD (asekit.reproduction.transonic; issue 29,
tsdfin)."""

import numpy as np
import pytest

from asekit.reproduction import transonic as T


def test_the_gap_rows_are_not_computed_unless_asked(monkeypatch, tmp_path):
    """Without the cache and without ``--transonic`` nothing is computed: every row says
    how to compute it, and the keys are those of a computed run (the reproduce baseline)."""
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("ASEKIT_TRANSONIC_STUDY", raising=False)
    assert not T.transonic_study_requested()
    assert T.transonic_envelope() is None
    rows = T.quantities(None)
    keys = [r.key for r in rows]
    assert len(keys) == len(set(keys)) == 3 * len(T.MACHS) + len(T.JOINS)
    assert all(r.asekit is None and not r.computed and "--transonic" in r.note for r in rows)
    assert "flutter.envelope.tsd.M105.h0.speed_ms" in keys


def test_the_tsd_variant_of_the_fin():
    """The stand-in section has the fin's thickness ratio (4 mm / 156 mm, the case file's), the
    variant keeps the modes below MODE_F_MAX and every TSD Mach is inside the method's range."""
    from asekit.aero.methods import AERO_METHODS

    c = T.tsd_case()
    assert c.aero.section == ("biconvex", pytest.approx(0.004 / 0.156))
    assert c.aero.symmetry == "wall" and c.modes.f_max == T.MODE_F_MAX
    assert all(AERO_METHODS["tsd"].mach_range.contains(m) for m in c.aero.machs)
    assert min(c.aero.machs) <= 0.9 and max(c.aero.machs) >= 1.15     # overlaps both ranges


@pytest.mark.slow
def test_the_gap_joins_the_linear_methods():
    """The TSD's sea-level flutter speeds through the gap, against the DLM (M 0.8, 0.9) and the
    Mach-box method (M 1.15, 1.2) with the same root wall, boxes, k and modes. The TSD carries
    the 2.56 % biconvex background and is first order on its 8 x 4-cell grid, so the joins
    are not exact. Measured (2026-12-04): TSD 230.5, 223.4, 234.3, 230.5 m/s against DLM
    224.6, 222.6 and Mach box 223.0, 217.5 m/s: +2.6 %, +0.3 %, +5.1 %, +6.0 %; with zero
    thickness the TSD's linear limit gives 228.5 m/s at M 0.8 (+1.8 %) and 211.8 m/s at M 1.2
    (-2.6 %): the supersonic excess is the thickness background's. Tolerances about twice
    the measured: 6 % subsonic, 12 % supersonic. Every Mach has a converged background and a
    flutter point in the sweep. About 10 min the first time on a loaded 2-core machine (the
    GAFs and the result are cached)."""
    env = T.transonic_envelope(compute=True)
    assert env is not None and np.atleast_1d(env["failed"]).size == 0
    speed = env["flutter"][:, 0, 0]
    assert np.all(np.isfinite(speed))
    machs = list(env["machs"])
    for ij, m in enumerate(env["join_machs"]):
        lin = env["linear"][ij, 0, 0, 0]
        tol = 0.06 if m < 1 else 0.12
        assert abs(speed[machs.index(m)] / lin - 1) < tol, (m, speed[machs.index(m)], lin)


def test_reproduce_takes_the_transonic_flag():
    """``reproduce --transonic`` is the opt-in (it sets ASEKIT_TRANSONIC_STUDY for the chapter)."""
    from asekit.cli.main import build_parser

    p = build_parser()
    assert p.parse_args(["reproduce", "--transonic"]).transonic is True
    assert p.parse_args(["reproduce"]).transonic is False
