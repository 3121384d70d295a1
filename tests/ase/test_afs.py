"""Active flutter suppression (issue 26): the closed-loop model against airspeed, its boundary,
the designs that move it, and refusals of bad input.

Reference numbers: the p-k flutter speed of the same fin at Mach 0.5, sea level
(:func:`asekit.aeroelastic.flutter.pk_flutter` on the tabulated GAFs; 210.0 m/s when written),
computed in the test, never typed in.
"""

import math

import control as ct
import numpy as np
import pytest
from small_cases import AFS_GRID as GRID

from asekit.aeroelastic.flutter import first_of, pk_flutter, pk_instabilities
from asekit.ase import afs
from asekit.ase import loop as ase
from asekit.ase.margins import nyquist_margins
from asekit.servo.actuator import SYSTEM_3
from asekit.util.blas import one_blas_thread


@pytest.fixture(scope="module")
def family(afs_family):
    """conftest's fin speed family (shared with test_sensors)."""
    return afs_family


@pytest.fixture(scope="module")
def open_loop(afs_open_loop):
    return afs_open_loop


def _boundary(family, K, tol=0.05):
    return afs.stability_boundary(lambda u: afs.closed_loop_matrix(family.model(u), K), GRID,
                                  tol=tol)


# ---------------------------------------------------------------------------------------------
# the boundary search
# ---------------------------------------------------------------------------------------------
def _two_mode(U):
    """Two oscillators coupled by a non-conservative (circulatory) stiffness growing with U:
    x'' + 0.1 x' + (K + U^2 Ka) x = 0, K = diag(1, 4), Ka = [[0, 1], [-1, 0]] -- the
    coalescence (binary) flutter model of Ziegler's follower-force column in its simplest form.
    """
    K = np.diag([1.0, 4.0]) + U ** 2 * np.array([[0.0, 1.0], [-1.0, 0.0]])
    return np.block([[np.zeros((2, 2)), np.eye(2)], [-K, -0.1 * np.eye(2)]])


def _two_mode_exact():
    """The boundary in closed form: with M = I and C = 0.1 I the system decouples in the
    eigenvectors of K + U^2 Ka, whose eigenvalues are kappa = 2.5 +- sqrt(2.25 - U^4). Past
    coalescence (U^4 > 2.25) kappa = 2.5 +- i b, b = sqrt(U^4 - 2.25); p^2 + 0.1 p + kappa = 0
    has the root p = i w exactly when w^2 = 2.5 and b = 0.1 w, i.e. U^4 = 2.25 + 0.025."""
    return 2.275 ** 0.25, math.sqrt(2.5) / (2 * math.pi)


def test_boundary_does_not_depend_on_the_grid():
    exact, f_exact = _two_mode_exact()
    for grid in ([0.5, 1.0, 1.5, 2.0, 3.0], np.linspace(0.1, 5.0, 7), [1.2, 1.25, 2.5]):
        b = afs.stability_boundary(_two_mode, grid, tol=1e-8)
        assert b.speed == pytest.approx(exact, abs=2e-8)
        assert b.bracket[0] < exact <= b.bracket[1] and not b.at_first_point
        assert b.frequency_hz == pytest.approx(f_exact, rel=1e-6)


def test_boundary_unstable_at_first_point_and_none():
    b = afs.stability_boundary(_two_mode, [3.0, 4.0])
    assert b.at_first_point and b.speed == 3.0 and b.bracket == ()
    b = afs.stability_boundary(_two_mode, [0.1, 0.5])
    assert b.speed is None and b.frequency_hz is None


@pytest.mark.parametrize("grid", [[2.0, 1.0], [0.0, 1.0], [1.0, np.nan], []])
def test_boundary_refuses_bad_grid(grid):
    with pytest.raises(ValueError, match="velocities"):
        afs.stability_boundary(_two_mode, grid)


# ---------------------------------------------------------------------------------------------
# the closed loop: independent interconnections agree
# ---------------------------------------------------------------------------------------------
def test_pd_only_closed_loop_is_the_chapter_5_aem1_loop(family):
    # u = -Kc (Kp theta + Kd omega) through closed_loop_matrix must have the eigenvalues of
    # asekit.ase.loop.closed_loop's AEM1 loop (python-control interconnect, another path)
    m = family.model(230.0)
    K = afs.classical_controller(SYSTEM_3.gain, SYSTEM_3.kp, SYSTEM_3.kd, 0.0)
    mine = np.sort_complex(np.linalg.eigvals(afs.closed_loop_matrix(m, K)))
    ref = np.sort_complex(np.linalg.eigvals(np.array(ase.closed_loop(m, SYSTEM_3, "AEM1").A)))
    np.testing.assert_allclose(mine, ref, rtol=1e-7, atol=1e-6)


def test_dynamic_controller_matches_python_control_feedback(family):
    m = family.model(260.0)
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    p = afs.plant(m)
    py = p[[list(p.output_labels).index(n) for n in K.input_labels], 0]
    ref = ct.feedback(py, K, sign=+1)
    got = np.sort_complex(np.linalg.eigvals(afs.closed_loop_matrix(m, K)))
    np.testing.assert_allclose(got, np.sort_complex(np.linalg.eigvals(np.array(ref.A))),
                               rtol=1e-7, atol=1e-6)


def test_fin_root_rate_is_the_derivative_of_the_root_pitch(family):
    p = afs.plant(family.model(200.0))
    n = list(p.output_labels)
    C, A = np.array(p.C), np.array(p.A)
    np.testing.assert_allclose(C[n.index("fin_root_rate")], C[n.index(ase.FIN_ROOT)] @ A,
                               rtol=1e-9, atol=1e-9 * np.abs(C[n.index("fin_root_rate")]).max())


# ---------------------------------------------------------------------------------------------
# the open-loop boundary against the p-k solution of the same fin
# ---------------------------------------------------------------------------------------------
def test_locked_boundary_agrees_with_pk(family, open_loop, fin_gafs):
    # Same fin, same Mach and density. The locked-actuator state-space model uses the Roger fit
    # (4 lags) of the GAFs; p-k uses the tabulated GAFs at the root's own k and its damping is
    # that of harmonic motion. Measured 206.1 vs 210.0 m/s (-1.9 %); the bound allows 3 %.
    g = fin_gafs.at(family.mach, interpolate=True)
    res = pk_flutter(family.modal, g, family.density, np.arange(150.0, 320.0, 5.0))
    pk = first_of(pk_instabilities(res, family.modal, g), "flutter")
    assert open_loop.speed == pytest.approx(pk.speed, rel=0.03)
    assert open_loop.frequency_hz == pytest.approx(pk.frequency_hz, rel=0.03)


# ---------------------------------------------------------------------------------------------
# the designs
# ---------------------------------------------------------------------------------------------
def _margins_ok(family, K, speed):
    # 50 points per decade: the crossings are then located by Brent's method, and
    # nyquist_margins checks its count against the closed-loop eigenvalues (measured: the same
    # margins to 1e-13 as with its default 400, in a third of the time on the 74-state LQG loop)
    with one_blas_thread():              # many small solves: one BLAS thread on a shared machine
        m = nyquist_margins(afs.loop_at_input(family.model(speed), K), points_per_decade=50)
    assert m.closed_loop_stable
    assert m.lower_gain_margin_db <= -6.0 and m.upper_gain_margin_db >= 6.0
    assert m.phase_margin_deg >= 45.0
    return m


def test_classical_design_raises_flutter_speed_20_percent(family, open_loop):
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    b = _boundary(family, K)
    assert not b.at_first_point and b.speed >= 1.2 * open_loop.speed
    _margins_ok(family, K, 1.05 * open_loop.speed)
    sim = afs.simulate_release(family.model(1.05 * open_loop.speed), K, t_final=0.1)
    assert sim.amplitude_ratio() < 0.1
    assert np.max(np.abs(sim.current)) <= 10.0 and np.max(np.abs(sim.voltage)) <= 24.0


def test_lqg_design_raises_flutter_speed_20_percent(family, open_loop):
    K = afs.lqg_controller(family.model(1.35 * open_loop.speed), 1e4, 1e4, 1.0)
    b = _boundary(family, K, tol=1.0)
    assert not b.at_first_point and b.speed >= 1.2 * open_loop.speed
    _margins_ok(family, K, 1.05 * open_loop.speed)


def test_release_is_linear_below_the_clip_and_grows_without_control(family, open_loop):
    # the PD alone (no flutter feedback) above its own boundary: the motion grows
    pd = afs.classical_controller(10.0, 275.0, 1.0, 0.0)
    u_pd = _boundary(family, pd).speed
    m = family.model(1.35 * u_pd)
    small = afs.simulate_release(m, pd, root_twist=math.radians(0.01), t_final=0.15)
    double = afs.simulate_release(m, pd, root_twist=math.radians(0.02), t_final=0.15)
    assert not small.saturated and not double.saturated
    np.testing.assert_allclose(double.fin_root, 2 * small.fin_root, rtol=1e-9, atol=1e-15)
    assert small.amplitude_ratio() > 1.0
    # starts from the requested root twist with the transmission at rest
    assert small.fin_root[0] == pytest.approx(math.radians(0.01), rel=1e-12)
    assert small.theta[0] == 0.0


# ---------------------------------------------------------------------------------------------
# refusals
# ---------------------------------------------------------------------------------------------
def test_refusals(family):
    m = family.model(200.0)
    bad = ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]],
                inputs=["zeta1"])
    with pytest.raises(ValueError, match="controller must map measurements"):
        afs.closed_loop_matrix(m, bad)
    with pytest.raises(ValueError, match="velocity"):
        family.model(-1.0)
    with pytest.raises(ValueError, match="lowpass_hz"):
        afs.classical_controller(1.0, 1.0, 0.0, 1.0, lowpass_hz=0.0)
    with pytest.raises(ValueError, match="weight_voltage"):
        afs.lqg_controller(m, 1.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="measurements"):
        afs.lqg_controller(m, 1.0, 1.0, 1.0, measurements=("zeta1",))
    with pytest.raises(ValueError, match="root_twist"):
        afs.simulate_release(m, afs.classical_controller(1.0, 1.0, 0.0, 0.0), root_twist=0.0)


# ---------------------------------------------------------------------------------------------
# the processor: sampling and computational delay
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("delay", [0, 1, 2])
def test_sampled_loop_matches_chapter_5_sampled_matrix(family, delay):
    # a static position law u = Kc Kp (0 - theta) through sampled_closed_loop_matrix against
    # asekit.ase.loop.closed_loop_sampled_matrix (its own ZOH plant, delay chain and
    # DigitalController): the same eigenvalues
    from asekit.servo.controllers import DigitalController

    m = family.model(230.0)
    g = 400.0
    K = ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[-g]], inputs=["theta"])
    mine = np.linalg.eigvals(afs.sampled_closed_loop_matrix(m, K, 1e-3, delay))
    d = DigitalController(ct.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)),
                                [[g, -g, 0.0]], dt=1e-3))
    phi, _ = ase.closed_loop_sampled_matrix(ase.sampled_plant(m, "AEM1", 1e-3, substeps=1), d,
                                            delay)
    ref = np.linalg.eigvals(phi)
    assert mine.size == ref.size
    np.testing.assert_allclose(np.sort(np.abs(mine)), np.sort(np.abs(ref)), rtol=1e-8,
                               atol=1e-12)


def test_fast_sampling_recovers_the_continuous_boundary(family):
    # T = 20 us, no delay: the sampled classical loop's boundary within 0.5 % of the continuous
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    cont = _boundary(family, K, tol=0.5).speed
    ts = 2e-5
    samp = afs.stability_boundary(
        lambda u: afs.sampled_closed_loop_matrix(family.model(u), K, ts, 0), GRID, tol=0.5,
        sample_time=ts)
    assert samp.speed == pytest.approx(cont, rel=5e-3)


def test_one_millisecond_delay_destabilises_the_continuous_designs(family, open_loop):
    # 1 kHz with one sample of delay: half a sample of ZOH plus one of computation, 1.5 ms,
    # about 78 deg of lag at the 144 Hz flutter frequency; the classical law designed in
    # continuous time is unstable already at the first airspeed of the grid
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    b = afs.stability_boundary(
        lambda u: afs.sampled_closed_loop_matrix(family.model(u), K, 1e-3, 1), GRID,
        sample_time=1e-3)
    assert b.at_first_point


def test_sampled_refusals(family):
    m = family.model(200.0)
    K = afs.classical_controller(1.0, 1.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="sample_time"):
        afs.sampled_closed_loop_matrix(m, K, 0.0)
    with pytest.raises(ValueError, match="delay_samples"):
        afs.sampled_closed_loop_matrix(m, K, 1e-3, -1)


def test_sampled_margins_at_fast_sampling_are_the_continuous_ones(family, open_loop):
    # the sampled loop's margins (frequency response on the unit circle; gain margins from the
    # eigenvalues with the controller scaled) at 50 kHz, no delay, against nyquist_margins of
    # the continuous loop (another path): ZOH + Tustin lag ~ w T / 2 = 0.5 deg at 140 Hz
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    m = family.model(1.05 * open_loop.speed)
    cont = nyquist_margins(afs.loop_at_input(m, K), points_per_decade=50)
    ts = 2e-5
    pm = afs.sampled_phase_margin(afs.sampled_loop_at_input(m, K, ts, 0))
    assert pm == pytest.approx(cont.phase_margin_deg, abs=1.0)

    def scaled(k):
        Kk = ct.ss(K.A, K.B, k * np.array(K.C), k * np.array(K.D), inputs=list(K.input_labels))
        return afs.sampled_closed_loop_matrix(m, Kk, ts, 0)

    lo, hi = afs.sampled_gain_margins(scaled, k_max=1e3, tol=1e-5)
    assert lo == pytest.approx(cont.lower_gain_margin, rel=0.02)
    # continuous: no upper limit; sampled, a loop always has one (the phase lag of ZOH and
    # Tustin grows to the Nyquist frequency), here far above the 6 dB asked (measured 42 dB)
    assert cont.upper_gain_margin == math.inf and 20 * math.log10(hi) > 30.0


def test_discrete_lqg_suppresses_flutter_at_1khz_with_delay(family, open_loop):
    # designed on the 1 kHz ZOH plant with its one-sample delay at 1.35 x the open-loop speed:
    # +20 % at least, 6 dB / 45 deg at 1.05 x, where the continuous designs fail at 1 kHz
    ts = 1e-3
    K = afs.discrete_lqg_controller(family.model(1.35 * open_loop.speed), ts, 1e4, 1e4, 0.1)
    assert K.isdtime() and float(K.dt) == ts
    b = afs.stability_boundary(
        lambda u: afs.sampled_closed_loop_matrix(family.model(u), K, ts, 1), GRID, tol=1.0,
        sample_time=ts)
    assert not b.at_first_point and b.speed >= 1.2 * open_loop.speed
    m = family.model(1.05 * open_loop.speed)
    assert afs.sampled_phase_margin(afs.sampled_loop_at_input(m, K, ts, 1)) >= 45.0

    def scaled(k):
        Kk = ct.ss(K.A, K.B, k * np.array(K.C), k * np.array(K.D), ts,
                   inputs=list(K.input_labels))
        return afs.sampled_closed_loop_matrix(m, Kk, ts, 1)

    lo, hi = afs.sampled_gain_margins(scaled, tol=1e-3)
    assert 20 * math.log10(lo) <= -6.0 and 20 * math.log10(hi) >= 6.0
    # the processor's release from 0.1 deg of root twist decays inside 24 V / 10 A unclipped
    sim = afs.simulate_release_sampled(m, K, ts, 1, root_twist=math.radians(0.1), t_final=0.1)
    assert not sim.saturated and sim.amplitude_ratio() < 0.1
    assert np.max(np.abs(sim.current)) < 10.0
    with pytest.raises(ValueError, match="controller.dt"):
        afs.sampled_closed_loop_matrix(m, K, 2e-3, 1)


def test_sampled_release_at_fast_sampling_is_the_continuous_release(family, open_loop):
    # two paths: the processor loop at 50 kHz without delay against the continuous controller's
    # release (both unclipped): the same history to the O(T) of ZOH + Tustin
    K = afs.classical_controller(10.0, 275.0, 1.0, 5.0, lowpass_hz=300.0)
    m = family.model(1.05 * open_loop.speed)
    ref = afs.simulate_release(m, K, root_twist=math.radians(0.1), t_final=0.05)
    sim = afs.simulate_release_sampled(m, K, 2e-5, 0, root_twist=math.radians(0.1),
                                       t_final=0.05, substeps=1)
    n = min(sim.t.size, ref.t.size)
    np.testing.assert_allclose(sim.t[:n], ref.t[:n], atol=1e-12)
    assert np.max(np.abs(sim.fin_root[:n] - ref.fin_root[:n])) < 1e-4 * np.max(
        np.abs(ref.fin_root))
    with pytest.raises(ValueError, match="substeps"):
        afs.simulate_release_sampled(m, K, 1e-3, substeps=0)


# ---------------------------------------------------------------------------------------------
# word lengths: the quantisation-induced limit cycle
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def dlqg(family, open_loop):
    return afs.discrete_lqg_controller(family.model(1.35 * open_loop.speed), 1e-3, 1e4, 1e4, 0.1)


def test_fine_quantisers_are_the_ideal_loop(family, open_loop, dlqg):
    m = family.model(1.05 * open_loop.speed)
    kw = dict(root_twist=math.radians(0.1), t_final=0.05)
    ideal = afs.simulate_release_sampled(m, dlqg, 1e-3, 1, **kw)
    fine = afs.simulate_release_sampled(m, dlqg, 1e-3, 1, quantisers=afs.Quantisers(
        encoder_resolution=1e-13, adc_bits=32, dac_bits=32), **kw)
    np.testing.assert_allclose(fine.fin_root, ideal.fin_root, rtol=0,
                               atol=1e-6 * np.max(np.abs(ideal.fin_root)))


def test_adc_quantisation_sustains_a_limit_cycle(family, open_loop, dlqg):
    # ideal loop: the release decays to nothing; with a 10-bit fin-root ADC (step 2 pi / 1024)
    # the motion persists at a fraction of a few quanta and stays bounded (no growth, no clip)
    m = family.model(1.05 * open_loop.speed)
    kw = dict(root_twist=math.radians(0.1), t_final=0.4)
    ideal = afs.simulate_release_sampled(m, dlqg, 1e-3, 1, **kw)
    q = afs.Quantisers(adc_bits=10)
    quant = afs.simulate_release_sampled(m, dlqg, 1e-3, 1, quantisers=q, **kw)
    step = 2 * math.pi / 2 ** 10
    last = ideal.t >= 0.3
    amp_ideal = np.ptp(ideal.fin_root[last]) / 2
    amp_q = np.ptp(quant.fin_root[last]) / 2
    assert amp_ideal < 1e-3 * step
    assert 0.1 * step < amp_q < 10 * step
    assert not quant.saturated


def test_quantiser_refusals():
    with pytest.raises(ValueError, match="adc_bits"):
        afs.Quantisers(adc_bits=1)
    with pytest.raises(ValueError, match="encoder_resolution"):
        afs.Quantisers(encoder_resolution=0.0)
