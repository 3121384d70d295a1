"""The H-infinity design of the design chapter (issue 26): Table 2 at Mach 0.5 sea level, the
anti-windup state, the reduced order, and (slow) the 45 conditions against the mu bound."""

import numpy as np
import pytest

from asekit.reproduction import design as dz


@pytest.fixture(scope="module")
def data():
    return dz.load()


@pytest.fixture(scope="module")
def hinf(data):
    return dz.design_hinf(data)


def test_hinf_meets_table2_at_mach05_sea_level(data, hinf):
    ctl, d = hinf
    assert ctl.ss.nstates == dz.HINF_ORDER < d.continuous.nstates
    assert ctl.integrator_states == (0,)
    assert abs(np.array(ctl.ss.A)[0, 0] - 1.0) < 1e-2
    c = dz.check(ctl, dz.fin_model(0.5, 0.0, data=data), "AEM2")
    # Table 2 (dz.SETTLING 50 ms, 2 % steady error, no overshoot past the 2 % band, 24 V)
    assert c.table2_pass, c.passes
    assert c.settling_ms < 50.0 and c.steady_error_pct < 2.0 and c.overshoot_pct < 2.0


def test_quantities_without_the_robust_flag(data, hinf, monkeypatch):
    monkeypatch.delenv("ASEKIT_ROBUST_STUDY", raising=False)
    monkeypatch.setattr(dz, "design_hinf", lambda data=None, weights=None: hinf)
    q = {x.key: x for x in dz.hinf_quantities(data)}
    assert q["ase.design.hinf.table2_pass"].asekit is True
    assert q["ase.design.hinf.order"].asekit == dz.HINF_ORDER
    assert not q["ase.design.hinf.mu_peak"].computed
    assert not q["ase.design.hinf.mu_peak_real"].computed
    assert "--robust" in q["ase.design.hinf.conditions_passed"].note


@pytest.mark.slow
def test_mu_bound_agrees_with_the_sampled_conditions(data, hinf):
    """If a plant inside the stated uncertainty set is unstable in the exact sampled loop, the
    mu upper bound must be >= 1 (a bound below 1 would certify it stable): the +10 % elastic
    frequency cases go unstable, and mu peaks at the second elastic mode (about 150 Hz)."""
    ctl, _ = hinf
    checks = dz.hinf_conditions(ctl, data)
    assert len(checks) == 45
    unstable = [c for c in checks if not c.stable]
    mu = dz.hinf_mu(ctl, data)
    assert mu["mu_peak_lower"] <= mu["mu_peak"] + 1e-9
    if unstable:
        assert mu["mu_peak"] >= 1.0
    # every nominal condition passes (the design's envelope)
    assert all(c.table2_pass for c in checks if c.case == "nominal")
    assert 130.0 < mu["f_peak_hz"] < 170.0
    # which block drives it: the Mach-altitude cover alone (one complex scalar: mu = |m|,
    # exact) is above 1, while the mixed D-G bound of the shaft and elastic-frequency blocks
    # alone is below 1 at the design condition -- a certificate that every shaft / frequency
    # combination is stable there, which the exact sampled loop must confirm
    assert mu["mu_peak_flight"] > 1.0
    assert mu["mu_peak_parameters"] < 1.0
    M0, h0 = dz.HINF_CONDITION
    at_design = [dz.check(ctl, dz.fin_model(M0, h0, case=k, data=data), "AEM2")
                 for k in dz.ROBUSTNESS]
    assert all(c.stable for c in at_design)
    # soundness where the sampled loop is unstable: the parameter bound there must reach 1
    for c in unstable:
        grid = dz.parameter_mu_grid(ctl, data, machs=[c.mach], altitudes=[c.altitude])
        assert grid[(c.mach, c.altitude)][0] >= 1.0


def test_design_is_cached_bit_identically(data, hinf, tmp_path, monkeypatch):
    """The synthesis is cached in the user cache: a cold design (empty cache directory) and a
    warm one give the same controller to the bit."""
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path))
    cold, _ = dz.design_hinf(data)
    assert len(list(tmp_path.glob("hinf_*.npz"))) == 1
    warm, d = dz.design_hinf(data)
    for a, b in zip((cold.ss.A, cold.ss.B, cold.ss.C, cold.ss.D),
                    (warm.ss.A, warm.ss.B, warm.ss.C, warm.ss.D)):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    assert np.array_equal(np.asarray(warm.ss.A), np.asarray(hinf[0].ss.A))
    assert d.continuous.nstates > warm.ss.nstates


def test_flight_lft_reproduces_the_fin_over_the_envelope(data):
    """Mach and altitude as real parameters (dz.flight_lft, issue 26): the LFT's state matrix
    at the envelope's corners and at points used by neither the fit nor its cover (M 0.43, 0.57
    x 700, 4300 m) gives OPLOOP 3's frequency response within 15 % of the direct model (the
    stated fit error, measured 13.5 % on the 3 x 3 fit grid and its cell centres; its cover
    holds it), and every envelope point lies inside the LFT's parameter box."""
    from asekit.ase import robust

    f = np.logspace(0, np.log10(490.0), 60)
    fl = dz.flight_lft(data, n_grid=3, f_hz=f)
    assert 0.0 < fl.cover.max() < 0.15
    assert fl.lft.A0.shape == (37, 37) and np.allclose(fl.deltas(0.5, 2500.0), 0.0)
    assert fl.lft.names == ("Mach", "altitude") and min(fl.lft.sizes) >= 1
    for M, h in [(0.4, 0.0), (0.4, 5000.0), (0.6, 0.0), (0.6, 5000.0), (0.43, 700.0),
                 (0.57, 700.0), (0.43, 4300.0), (0.57, 4300.0)]:
        d = fl.deltas(M, h)
        assert np.all(np.abs(d) <= 1 + 1e-12)
        A_dir = dz._plant_A(dz.fin_model(M, h, data=data))[0]
        P = dz._response(A_dir, fl.B, fl.C, f)
        P_l = dz._response(robust.lft_state_matrix(fl.lft, d), fl.B, fl.C, f)
        assert np.max(np.abs(P / P_l - 1)) < 0.15, (M, h)
        # the unstable real pole (the free actuator's divergence, moving with q) is reproduced
        lam = np.linalg.eigvals(A_dir).real.max()
        lam_l = np.linalg.eigvals(robust.lft_state_matrix(fl.lft, d)).real.max()
        assert lam_l == pytest.approx(lam, rel=0.05)


def test_lowrank_flight_lft_has_small_blocks_and_a_measured_cover(data):
    """The low-rank LFT of the same fit (dz.flight_lft(lowrank=dz.LOWRANK_RTOL), issue 26):
    repeated blocks (40, 48) against the per-term LFT's (80, 116) (measured; each quadratic
    term has rank 29 at 1e-8), the dropped part bounded (``truncation``, below 1e-2 of the
    largest coefficient) and inside the measured fit-error cover, which stays the stated 15 %
    at the 3 x 3 grid's points."""
    f = np.logspace(0, np.log10(490.0), 60)
    full = dz.flight_lft(data, n_grid=3, f_hz=f)
    low = dz.flight_lft(data, n_grid=3, f_hz=f, lowrank=dz.LOWRANK_RTOL)
    assert sum(low.lft.sizes) <= 0.5 * sum(full.lft.sizes)
    assert max(low.lft.sizes) <= 48
    scale = max(np.linalg.norm(low.lft.Bw[:, i]) * np.linalg.norm(low.lft.Cz[i])
                for i in range(low.lft.Bw.shape[1]))
    assert 0 < low.lft.truncation < 1e-2 * scale
    assert np.all(low.cover >= 0) and low.cover.max() < 0.15
    # the low-rank LFT stays within its truncation bound of the per-term one inside the box
    from asekit.ase import robust
    for d in [(-1.0, -1.0), (1.0, -1.0), (0.3, 0.7), (-0.5, 1.0)]:
        diff = robust.lft_state_matrix(low.lft, d) - robust.lft_state_matrix(full.lft, d)
        assert np.linalg.norm(diff, 2) <= low.lft.truncation * (1 + 1e-9) + 1e-6 * scale


def test_mu_real_row_states_the_margin_only_below_one():
    """The ``ase.design.hinf.mu_peak_real`` note says "stable for 1/mu times the stated
    uncertainty" only when the bound is below 1 (issue 26), else that there is no certificate;
    it names the bound used."""
    r = {"mu_peak": 0.8, "f_peak_hz": 155.0, "sizes": (40, 48), "fit_cover": 0.9,
         "bound": "full", "mu_peak_parameters": 0.7, "mu_peak_flight": 0.6,
         "f_peak_flight_hz": 95.0, "mu_peak_fit": 0.2}
    q = dz._mu_real_quantity(r)
    assert q.asekit == 0.8 and "stable for 1.2 x" in q.note and "full D-G" in q.note
    q = dz._mu_real_quantity(dict(r, mu_peak=3.0, bound="per_block"))
    assert "no certificate" in q.note and "stable for" not in q.note
    with pytest.raises(ValueError, match="bound"):
        dz.hinf_mu_real(None, data=object(), bound="diagonal")
