"""Discrete-gust loads of a case (asekit.case.gust_loads) and the [gust] table (schema)."""

import dataclasses
import tomllib

import numpy as np
import pytest

from asekit.aero.gust import gust_aero_tables
from asekit.aero.spline import fe_spline
from asekit.atmosphere import standard_atmosphere
from asekit.case import CaseError, case_from_dict
from asekit.case import pipeline as P
from asekit.case.gust_loads import (
    _inertial_rows,
    _load_weights,
    gust_json,
    gust_loads,
    turbulence_json,
)
from asekit.case.schema import GustSpec
from asekit.util.paths import FIN_FILE

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


@pytest.fixture(scope="module")
def fin_gusts(fin_case):
    case = dataclasses.replace(fin_case, gust=GustSpec((0.3, 40.0), 10.0, 0.5, 0.0,
                                                       turbulence_sigma=1.0, scale_length=1e5))
    return case, gust_loads(case)


def _static_loads(case, x0, alpha):
    """Static aeroelastic root shear, bending and hinge moment at the gust angle alpha, from
    the k = 0 tables (no fit, no time integration; actuator clamped):
    (K_ss - q Q_ss(0)) zeta_s = q Qg_s(0) alpha, load = q (QL_s(0) zeta_s + QLg(0) alpha),
    hinge = q (Q_cs(0) zeta_s + Q_cg(0) alpha)."""
    modal, boxes = P.modal_model(case), P.box_mesh(case)
    y_root = float(np.min(boxes.corners[:, :, 1]))
    t = gust_aero_tables(fe_spline(modal, boxes), boxes, 0.5, [0.0], 0.078,
                         _load_weights(boxes, y_root), x0, "quartic")
    atm = standard_atmosphere(0.0)
    U = 0.5 * float(atm.speed_of_sound)
    q = 0.5 * float(atm.density) * U ** 2
    s = slice(1, None)
    zeta = np.linalg.solve(modal.K[s, s] - q * t.Q[0, s, s].real, q * t.Qg[0, s].real * alpha)
    shear, bending = q * (t.QL[0, :, s].real @ zeta + t.QLg[0].real * alpha)
    hinge = q * (t.Q[0, 0, s].real @ zeta + t.Qg[0, 0].real * alpha)
    return shear, bending, hinge, U


def test_very_long_turbulence_scale_gives_the_static_a_bar(fin_gusts):
    # With a scale length L = 100 km the von Karman spectrum's knee U / (1.339 L) = 1.3e-3
    # rad/s lies far below the fin's dynamics (its first elastic mode near 600 rad/s), so
    # A-bar tends to the static load per unit gust velocity, |H(0)| (the k = 0 tables above
    # divided by U). The spectrum's omega^-5/3 tail still reaches the fin's resonances and
    # adds a little: measured A-bar 0.3085 N m/(m/s) against 0.3063 (+0.7 %), shear +0.45 %,
    # hinge moment 0.06493 against 0.06417 (+1.2 %); held to 2 %.
    case, res = fin_gusts
    U = res.velocity
    shear, bending, hinge, _ = _static_loads(case, res.x0, 1.0 / U)
    t = res.turbulence
    assert t["root_bending"]["A_bar"] == pytest.approx(abs(bending), rel=0.02)
    assert t["root_shear"]["A_bar"] == pytest.approx(abs(shear), rel=0.02)
    assert t["hinge_moment"]["A_bar"] == pytest.approx(abs(hinge), rel=0.02)
    rows = turbulence_json(res)
    assert rows[0]["A_bar_hinge"] == t["hinge_moment"]["A_bar"] and rows[0]["N0_per_s"] > 0


def test_long_gust_tends_to_the_static_aeroelastic_load(fin_gusts):
    # A gust much longer than the fin's response times (H = 40 m at 170 m/s: 0.24 s to its
    # peak, the first elastic mode near 100 Hz) loads the fin quasi-statically: its peaks must
    # approach the static aeroelastic equilibrium at the incidence U_ds / U, computed here
    # from the k = 0 tables without any fit or time integration:
    #   (K_ss - q Q_ss(0)) zeta_s = q Qg_s(0) alpha,  load = q (QL_s(0) zeta_s + QLg(0) alpha),
    # hinge = q (Q_cs(0) zeta_s + Q_cg(0) alpha)  (actuator clamped, theta = 0).
    case, res = fin_gusts
    shear, bending, hinge, _ = _static_loads(case, res.x0, 10.0 / res.velocity)
    long = res.cases[1]
    # measured: 40.88 N, 3.063 N m, 0.6417 N m; the time domain within 0.04 % of them
    assert long.peak_root_shear == pytest.approx(shear, rel=0.01)
    assert long.peak_root_bending == pytest.approx(bending, rel=0.01)
    assert long.peak_hinge_moment == pytest.approx(hinge, rel=0.01)
    assert shear > 0 and bending > 0                  # an upward gust lifts and bends tip-up


def test_slow_gust_current_holds_the_hinge_moment(fin_gusts):
    # In a slow gust the AEM1 loop is quasi-static (omega, alpha ~ 0), so the motor holds the
    # hinge moment: K_t I N eta = -T_hinge (thesis Eqs. 2.30-2.37). Against the clamped
    # actuator's hinge-moment peak (a separate model: no loop) the current's peak differs only
    # by the loop's small pitch offset. Measured: -0.4076 A against -0.4016 A (+1.5 %).
    case, res = fin_gusts
    act, _, _ = P.actuator_setup(case)
    tr = act.transmission
    long = res.cases[1]
    held = -long.peak_hinge_moment / (tr.ratio * tr.efficiency * act.motor.torque_constant)
    assert long.peak_current == pytest.approx(held, rel=0.03)
    assert long.peak_current < 0 < long.peak_hinge_moment


def test_gust_json_rows(fin_gusts):
    case, res = fin_gusts
    rows = gust_json(res)
    assert [r["gust_length_m"] for r in rows] == [0.3, 40.0]
    for r in rows:
        assert set(r) == {"mach", "altitude_m", "gust_length_m", "peak_hinge_moment_Nm",
                          "peak_root_bending_Nm", "peak_root_shear_N", "peak_current_A",
                          "profile", "stations", "peak_voltage_V", "peak_current_limited_A",
                          "peak_voltage_limited_V", "saturated", "peak_current_aem2_A",
                          "peak_deflection_limited_deg",
                          "peak_current_aem2_limited_A", "saturated_aem2"}
        assert r["profile"] is None and r["stations"] == {}      # 1-cos rows, no stations
        assert r["mach"] == 0.5 and r["altitude_m"] == 0.0
        assert np.isfinite(r["peak_current_A"])                  # the fin has an [actuator]
        assert all(np.isfinite(r[k]) for k in ("peak_hinge_moment_Nm", "peak_root_bending_Nm"))
    assert res.tuned("root_bending").gradient_length in (0.3, 40.0)
    assert max(res.fit_errors.values()) < 0.05
    assert gust_json(None) == []


def test_inertial_rows_of_a_rigid_translation():
    # -u^T M Phi: a unit translation's inertial row is minus the modal participation of the
    # elastic modes; the rigid pitch (held) is left out, and the rows are finite
    from asekit.case import load_case
    case = load_case(FIN_FILE)
    modal = P.modal_model(case)
    rows = _inertial_rows(case, modal, 0.0)
    assert rows.shape == (2, modal.M.shape[0] - modal.n_rigid)
    assert np.all(np.isfinite(rows)) and np.abs(rows[0]).max() > 0
    # the FE mass matrix and the mode shapes share one DOF order: Phi^T M Phi is the modal
    # mass (measured: to 2e-16)
    _, M = P.mass_and_stiffness(case)
    phi = modal.shapes.reshape(3 * modal.nodes.shape[0], -1)
    assert np.abs(phi.T @ (M @ phi) - modal.M).max() < 1e-10 * np.abs(modal.M).max()


def _with_gust(**gust):
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    d["gust"] = gust
    return d


@pytest.mark.parametrize("gust,message", [
    ({"design_velocity": 10.0}, "gust.gradient_lengths is missing"),
    ({"gradient_lengths": [1.0, 0.5], "design_velocity": 10.0}, "strictly ascending"),
    ({"gradient_lengths": [-1.0], "design_velocity": 10.0}, r"gust.gradient_lengths\[0\]"),
    ({"gradient_lengths": [1.0], "design_velocity": 0.0}, "gust.design_velocity must be > 0"),
    ({"gradient_lengths": [1.0], "design_velocity": 5.0, "mach": 0.9},
     "gust.mach must lie within aero.machs"),
    ({"gradient_lengths": [1.0], "design_velocity": 5.0, "altitude": -1e5}, "gust.altitude"),
    ({"gradient_lengths": [1.0], "design_velocity": 5.0, "speed": 3}, "gust.speed is not a known"),
    ({"gradient_lengths": [1.0], "design_velocity": 5.0, "turbulence": {}},
     "gust.turbulence.sigma is missing"),
    ({"gradient_lengths": [1.0], "design_velocity": 5.0,
      "turbulence": {"sigma": 1.0, "spectrum": "kaimal"}}, "gust.turbulence.spectrum must be"),
])
def test_gust_table_errors(gust, message):
    with pytest.raises(CaseError, match=message):
        case_from_dict(_with_gust(**gust))


def test_gust_table_defaults_and_fingerprint(fin_case):
    c = case_from_dict(_with_gust(gradient_lengths=[1.0, 5.0], design_velocity=8.0))
    assert c.gust == GustSpec((1.0, 5.0), 8.0, fin_case.actuator.mach, fin_case.actuator.altitude)
    t = case_from_dict(_with_gust(gradient_lengths=[1.0], design_velocity=8.0,
                                  turbulence={"sigma": 2.0, "spectrum": "dryden"})).gust
    assert (t.turbulence_sigma, t.scale_length, t.spectrum) == (2.0, 762.0, "dryden")
    # a case without [gust] keeps its fingerprint (caches keyed on it stay valid)
    assert dataclasses.replace(c, gust=None).fingerprint() == fin_case.fingerprint()
    assert c.fingerprint() != fin_case.fingerprint()


def test_summary_lines(fin_gusts):
    from asekit.case.report import UNITS, _gust_lines, _turbulence_lines
    _, res = fin_gusts
    assert _turbulence_lines(turbulence_json(res))[0].startswith("turbulence at M 0.5, 0 m")
    for key in turbulence_json(res)[0]:
        assert key in UNITS or key == "mach"
    lines = _gust_lines(gust_json(res))
    assert lines[1].startswith("1-cos gusts at M 0.5, 0 m") and len(lines) == 3 + len(res.cases)
    assert _gust_lines([]) == []
    for key in gust_json(res)[0]:
        assert key in UNITS or key == "mach"


def test_report_figure(fin_gusts):
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import fig_gust_histories
    case, res = fin_gusts
    a = type("A", (), {"case": case, "gust": res})()
    f = fig_gust_histories(a)
    assert len(f.figure.axes) == 3 and "largest hinge moment" in f.alt
    assert "stays within the actuator's power limits" in f.alt
    assert f.section == "Gust loads"
    plt.close(f.figure)


def test_unstable_condition_is_refused():
    # AGARD 445.6 (weakened, clamped) at M 0.499 and 3000 m (q = 12 kPa) is beyond its flutter
    # dynamic pressure: the time response would grow without bound, so the gust analysis
    # refuses the condition naming the keys, instead of reporting a meaningless peak
    from asekit.case import load_case
    from asekit.util.paths import CASES_DIR
    c = load_case(CASES_DIR / "agard445_6.toml")
    c = dataclasses.replace(c, gust=GustSpec((1.0,), 10.0, 0.499, 3000.0))
    with pytest.raises(CaseError, match="gust.mach = 0.499, gust.altitude = 3000 m: the "
                                        "aeroelastic system"):
        gust_loads(c)
    ok = gust_loads(dataclasses.replace(c, gust=GustSpec((1.0,), 10.0, 0.499, 10000.0)))
    assert ok.cases[0].hinge_moment is None and ok.cases[0].current is None     # no shaft
    assert gust_json(ok)[0]["peak_hinge_moment_Nm"] is None


def test_minimum_state_and_roger_fits_agree(fin_case):
    # the modal fit is the case's flutter.rfa: Karpel's minimum-state fit and Roger's are two
    # approximations of the same tables, so the gust peaks must agree (measured at H = 1 m,
    # M 0.5: hinge moment 0.2 %, root bending 0.1 %, shear 0.07 %, current 0.2 %)
    case = dataclasses.replace(fin_case, gust=GustSpec((1.0,), 10.0, 0.5, 0.0))
    rows = []
    for rfa in ("roger", "minimum_state"):
        c = dataclasses.replace(case, flutter=dataclasses.replace(case.flutter, rfa=rfa))
        rows.append(gust_json(gust_loads(c))[0])
    for key in ("peak_hinge_moment_Nm", "peak_root_bending_Nm", "peak_root_shear_N",
                "peak_current_A"):
        assert rows[1][key] == pytest.approx(rows[0][key], rel=0.02), key


# --- correlated loads and the report's turbulence figures (issue 27) -------------------------
def test_correlated_load_ellipse_projections_are_the_rms_values(fin_gusts):
    # Hoblit (Gust Loads on Aircraft, 1988, Ch. 7): the one-sigma equal-probability ellipse of
    # two jointly Gaussian loads has its extreme projection on each axis equal to that load's
    # RMS, and on any direction u equal to sqrt(u^T C u). The covariance's diagonal comes from
    # the cross-spectra (response_covariance); the RMS values from spectral_statistics
    # separately, so a wrong covariance (a missing 1/2, a conjugate on the wrong factor) fails.
    from asekit.aeroelastic.gust import correlated_load_ellipse
    _, res = fin_gusts
    t = res.turbulence
    assert t["covariance"]["names"] == ("hinge_moment", "root_bending")
    C = t["covariance"]["matrix"]
    e = correlated_load_ellipse(C, 20001)
    assert np.max(np.abs(e[0])) == pytest.approx(t["hinge_moment"]["rms"], rel=1e-6)
    assert np.max(np.abs(e[1])) == pytest.approx(t["root_bending"]["rms"], rel=1e-6)
    rho = C[0, 1] / np.sqrt(C[0, 0] * C[1, 1])
    assert -1 < rho < 1 and abs(rho) > 0.05              # correlated, not degenerate
    for ang in np.linspace(0, np.pi, 7):
        u = np.array([np.cos(ang), np.sin(ang)])
        assert np.max(u @ e) == pytest.approx(np.sqrt(u @ C @ u), rel=1e-6)


def test_turbulence_current_of_a_very_long_scale_holds_the_hinge_moment(fin_gusts):
    # With L = 100 km the turbulence is quasi-static for the AEM1 loop (as the slow 1-cos gust
    # above): the motor holds the hinge moment, K_t I N eta = -T_hinge, so the RMS current is the
    # RMS hinge moment over K_t N eta (thesis Eqs. 2.30-2.37), within the same 3 %.
    case, res = fin_gusts
    act, _, _ = P.actuator_setup(case)
    tr = act.transmission
    t = res.turbulence
    held = t["hinge_moment"]["rms"] / (tr.ratio * tr.efficiency * act.motor.torque_constant)
    assert t["current"]["rms"] == pytest.approx(held, rel=0.03)
    assert turbulence_json(res)[0]["rms_current_A"] == t["current"]["rms"]
    sp = t["spectra"]
    from scipy.integrate import trapezoid
    assert np.sqrt(trapezoid(sp["current"], sp["omega"])) == pytest.approx(
        t["current"]["rms"], rel=1e-12)


def test_turbulence_report_figures(fin_gusts):
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import figures_of_gust
    case, res = fin_gusts
    a = type("A", (), {"case": case, "gust": res})()
    figs = figures_of_gust(a)
    assert list(figs) == ["gust_histories", "gust_psd", "gust_ellipse"]
    psd, ell = figs["gust_psd"], figs["gust_ellipse"]
    labels = [ax.get_ylabel() for ax in psd.figure.axes]
    assert len(labels) == 3 and "(N m)^2/Hz" in labels[0] and "A^2/Hz" in labels[2]
    assert psd.figure.axes[-1].get_xlabel() == "frequency (Hz)"
    ax = ell.figure.axes[0]
    assert ax.get_xlabel() == "hinge moment (N m)" and "(N m)" in ax.get_ylabel()
    assert f"{res.turbulence['hinge_moment']['rms']:.3g}" in ell.alt
    for f in figs.values():
        assert f.section == "Gust loads" and f.figure._suptitle.get_text()
        plt.close(f.figure)


def test_power_limited_current_in_the_gust_rows(fin_gusts):
    # the fin's actuator (thesis Table 16: 24 V, 10 A as the voltage clip |V| <= I_lim R) in a
    # 10 m/s gust: the linear AEM1 demand stays far below both limits, so the limited run
    # (exact piecewise-affine propagation) equals the linear one (lsim) and nothing saturates;
    # the fin's AEM2 loop has a growing pole at M 0.5, sea level (the thesis's AEM2 finding,
    # Ch. 5), so its rows are null rather than an unbounded number.
    case, res = fin_gusts
    act, _, lim = P.actuator_setup(case)
    for r, c in zip(gust_json(res), res.cases):
        assert abs(r["peak_voltage_V"]) < lim.current_limit * act.motor.resistance
        assert r["saturated"] is False
        assert r["peak_current_limited_A"] == pytest.approx(r["peak_current_A"], rel=1e-6)
        np.testing.assert_allclose(c.servo["AEM1"]["voltage_limited"],
                                   c.servo["AEM1"]["voltage"], rtol=0,
                                   atol=1e-6 * abs(r["peak_voltage_V"]))
        assert "AEM2" not in c.servo and r["peak_current_aem2_A"] is None
        assert r["saturated_aem2"] is None


def test_tight_current_limit_bounds_the_gust_voltage(fin_case):
    # a current limit at half the linear demand of a short gust (H = 0.3 m: a dynamic peak,
    # about 0.16 A), and below the holding current of a long one (H = 40 m: about 0.40 A to
    # hold the quasi-static hinge moment, thesis Eqs. 2.30-2.37). Both rows say saturated and
    # the applied voltage never exceeds I_lim R (Eqs. 4.14-4.15). In the short gust the
    # limited loop still returns the fin (a smaller current peak, a larger deflection); in the
    # long gust the motor cannot hold the hinge moment and the fin is blown past the 15 deg
    # stop (thesis Table 2), which the deflection key reports.
    base = dataclasses.replace(fin_case, gust=GustSpec((0.3, 40.0), 10.0, 0.5, 0.0,
                                                       settle_time=0.02))
    short = gust_json(gust_loads(base))[0]
    i_lim = 0.5 * abs(short["peak_current_A"])
    act = dataclasses.replace(fin_case.actuator, current_limit=i_lim)
    case = dataclasses.replace(base, actuator=act)
    res = gust_loads(case)
    rows = gust_json(res)
    a, _, lim = P.actuator_setup(case)
    for r in rows:
        assert r["saturated"] is True
        assert abs(r["peak_voltage_limited_V"]) <= i_lim * a.motor.resistance * (1 + 1e-12)
    r0, r1 = rows
    assert abs(r0["peak_current_limited_A"]) < abs(r0["peak_current_A"])
    assert abs(r0["peak_deflection_limited_deg"]) < 15.0
    assert abs(r1["peak_current_A"]) > 1.4 * i_lim and abs(r1["peak_deflection_limited_deg"]) > 15
    # the report's histories mark the limit and the limited current, and say which gusts saturate
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import fig_gust_histories
    f = fig_gust_histories(type("A", (), {"case": case, "gust": res})())
    assert "saturates in H = 0.3 m, H = 40 m" in f.alt
    lo, hi = f.figure.axes[-1].get_ylim()
    assert hi == pytest.approx(1.3 * abs(r0["peak_current_A"]))     # the runaway off-scale
    plt.close(f.figure)
