"""The ``ase.afs.*`` rows (issue 26): computed by the study, consistent with each other and
meeting the issue's targets (+20 % flutter speed, 6 dB / 45 deg, 24 V / 10 A)."""

import math

import pytest

from asekit.reproduction import afs as study_mod


@pytest.fixture(scope="module")
def study():
    return study_mod.compute()


@pytest.fixture(scope="module")
def rows(study):
    return {q.key: q for q in study_mod.quantities(study)}


def test_required_keys_are_computed(rows):
    for k in ("open_loop_flutter_ms", "closed_loop_flutter_ms", "gain_margin_db",
              "phase_margin_deg"):
        q = rows[f"ase.afs.{k}"]
        assert q.computed and isinstance(q.asekit, float) and math.isfinite(q.asekit)


def test_targets_met(study, rows):
    ol = rows["ase.afs.open_loop_flutter_ms"].asekit
    for pre in ("", "lqg."):
        assert rows[f"ase.afs.{pre}closed_loop_flutter_ms"].asekit >= 1.2 * ol
        assert rows[f"ase.afs.{pre}gain_margin_db"].asekit >= 6.0
        assert rows[f"ase.afs.{pre}phase_margin_deg"].asekit >= 45.0
        assert rows[f"ase.afs.{pre}peak_voltage_v"].asekit <= 24.0
        assert rows[f"ase.afs.{pre}peak_current_a"].asekit <= 10.0
    for d in study.designs.values():
        assert not d.release.saturated          # the release stays linear: limits not used


def test_open_loop_is_the_pk_boundary_of_the_same_fin(rows):
    # Roger fit (state space) against p-k on the tabulated GAFs: within 3 % (measured -1.9 %)
    assert rows["ase.afs.open_loop_flutter_ms"].asekit == pytest.approx(
        rows["ase.afs.pk_flutter_ms"].asekit, rel=0.03)


def test_the_pd_alone_moves_the_boundary_a_little(rows):
    # a free (PD-held) actuator is compliant: the boundary moves, but far less than 20 %
    ol = rows["ase.afs.open_loop_flutter_ms"].asekit
    assert ol < rows["ase.afs.pd_only_flutter_ms"].asekit < 1.2 * ol


def test_processor_rows(study, rows):
    # 5 kHz with one sample of delay keeps the +20 %; the thesis's 1 kHz processor with one
    # sample of delay (1.5 ms effective, ~78 deg at 144 Hz) does not keep the continuous
    # designs stable -- a finding, asserted so that a change is noticed
    ol = rows["ase.afs.open_loop_flutter_ms"].asekit
    for pre in ("", "lqg."):
        assert rows[f"ase.afs.{pre}sampled_5khz_flutter_ms"].asekit >= 1.2 * ol
        assert rows[f"ase.afs.{pre}stable_at_1khz"].asekit is False


def test_discrete_lqg_rows(rows):
    # the discrete LQG at the thesis's 1 kHz with one sample of delay meets the targets
    ol = rows["ase.afs.open_loop_flutter_ms"].asekit
    assert rows["ase.afs.dlqg_1khz.closed_loop_flutter_ms"].asekit >= 1.2 * ol
    assert rows["ase.afs.dlqg_1khz.gain_margin_db"].asekit >= 6.0
    assert rows["ase.afs.dlqg_1khz.phase_margin_deg"].asekit >= 45.0
    assert rows["ase.afs.dlqg_1khz.peak_voltage_v"].asekit <= 24.0
    assert rows["ase.afs.dlqg_1khz.peak_current_a"].asekit <= 10.0


def test_quantised_rows(rows):
    # the word lengths keep the loop moving (the ideal release decays to rest), boundedly:
    # a fraction of a degree, inside the supply
    amp = rows["ase.afs.dlqg_1khz.quantised_lco_amplitude_deg"].asekit
    assert 0.01 < amp < 1.0
    assert 0.0 < rows["ase.afs.dlqg_1khz.quantised_peak_voltage_v"].asekit <= 24.0


def test_root_locus_figure(study):
    fig = study_mod.fig_root_locus(study, velocities=[200.0, 300.0])
    ax = fig.axes[0]
    assert len(ax.collections) == 3 and ax.get_xlabel() == "real part (1/s)"


def test_sensed_rows(study, rows):
    # seeded sensor noise keeps the loop moving where the ideal release decays to rest
    # (ideal: < 1e-5 deg RMS over the last 0.1 s, measured 6.7e-7); boundedly, inside the
    # supply; the loop is linear below the clip, so the residual is the noise's response and
    # grows with it (1e-4 rad RMS on each angle: measured 0.006 deg, 0.31 V RMS)
    assert 1e-4 < rows["ase.afs.dlqg_1khz.sensed_residual_rms_deg"].asekit < 0.1
    assert 0.0 < rows["ase.afs.dlqg_1khz.sensed_residual_voltage_rms_v"].asekit < 24.0
    assert rows["ase.afs.dlqg_1khz.sensed_peak_voltage_v"].asekit <= 24.0
    assert rows["ase.afs.dlqg_1khz.sensed_peak_current_a"].asekit <= 10.0
    assert not study.digital.sensed.saturated
