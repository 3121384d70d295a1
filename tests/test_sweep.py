"""Sweeps (asekit.sweep): key-path editing, samplers, AIC reuse, the sample against the case
pipeline, failed rows, resume, statistics; serial = processes = a real dask LocalCluster bit for
bit, a failing task and a worker killed by PID mid-sweep."""

import copy
import csv
import dataclasses
import math
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from asekit import sweep as S
from asekit.case import case_from_dict
from asekit.case import pipeline as P
from asekit.util.paths import FIN_FILE

ROOT = Path(__file__).resolve().parent.parent
FAST_V = {"min": 150.0, "max": 350.0, "step": 10.0}


@pytest.fixture(autouse=True)
def _cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ASEKIT_CACHE_DIR", str(tmp_path / "cache"))


@pytest.fixture
def one_blas_thread():
    """The pipeline computations a test compares with run on one BLAS thread, as the sweep's
    samples do (multithreaded BLAS may differ in the last bits)."""
    from asekit.util.blas import one_blas_thread as one
    with one():
        yield


def sweep_dict(parameters, samples=None, outputs=None, seed=7, **sweep):
    s = {"name": "t", "case": str(FIN_FILE), "seed": seed, "mach": 0.6, "altitude": 0.0}
    if samples is not None:
        s["samples"] = samples
    if outputs is not None:
        s["outputs"] = outputs
    s.update(sweep)
    return {"sweep": s, "case": {"flight.velocities": dict(FAST_V)}, "parameter": parameters}


MC = [{"path": "material.youngs_modulus", "distribution": "truncated_normal", "mean": 70e9,
       "std": 1.75e9, "low": 66.5e9, "high": 73.5e9},
      {"path": "support.torsional_stiffness", "distribution": "lognormal", "median": 120.0,
       "sigma": 0.0912},
      {"path": "damping.modal_damping_ratio", "distribution": "uniform", "low": 0.0,
       "high": 0.01}]


def strip(df):
    return df.drop(columns=["wall_s"]).reset_index(drop=True)


def assert_identical(a, b):
    """Same columns, same cells, bit for bit (NaN == NaN), except the timing column."""
    a, b = strip(a), strip(b)
    assert list(a.columns) == list(b.columns)
    assert len(a) == len(b)
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if x.dtype.kind == "f" and y.dtype.kind == "f":
            nan = np.isnan(x)
            assert np.array_equal(nan, np.isnan(y)), c
            assert np.array_equal(x[~nan].view(np.uint64), y[~nan].view(np.uint64)), c
        else:
            assert list(map(str, x)) == list(map(str, y)), c


# ------------------------------------------------------------------------------------------
# key paths
# ------------------------------------------------------------------------------------------
def test_key_paths_edit_the_parsed_case():
    d = {"a": {"b": 1}, "panel": [{"tip_chord": 0.1}]}
    assert S.parse_key_path("panel[0].tip_chord") == ("panel", 0, "tip_chord")
    S.set_key(d, "panel[0].tip_chord", 0.2)
    S.set_key(d, "damping.modal_damping_ratio", 0.01)           # a missing table is created
    S.set_key(d, "a.b", 3)
    assert d == {"a": {"b": 3}, "panel": [{"tip_chord": 0.2}],
                 "damping": {"modal_damping_ratio": 0.01}}
    assert S.get_key(d, "panel[0].tip_chord") == 0.2
    for bad in ("", "a..b", "a.[0]", "1a.b"):
        with pytest.raises(S.SweepError, match="key path"):
            S.parse_key_path(bad)
    with pytest.raises(S.SweepError, match=r"index \[3\]"):
        S.set_key(d, "panel[3].tip_chord", 1.0)


def test_unknown_key_path_is_a_sweep_error_naming_it():
    d = sweep_dict([{"path": "material.youngs_modulu", "values": [70e9]}])
    with pytest.raises(S.SweepError, match=r"parameter\[0\].path 'material.youngs_modulu' is "
                                           r"not a case-file key: material.youngs_modulu is "
                                           r"not a known key"):
        S.sweep_from_dict(d)
    d = sweep_dict([{"path": "materal.density", "values": [2700.0]}])
    with pytest.raises(S.SweepError, match="materal is not a known key"):
        S.sweep_from_dict(d)


@pytest.mark.parametrize("param, message", [
    ({"distribution": "normal", "mean": 1.0, "std": -0.1},
     r"parameter\[0\] \(support.torsional_stiffness\).std must be > 0, got -0.1"),
    ({"distribution": "uniform", "low": 2.0, "high": 1.0}, r"low \(2\) must be < high \(1\)"),
    ({"distribution": "lognormal", "median": 120.0, "sigma": 0.0},
     r"\(support.torsional_stiffness\).sigma must be > 0, got 0"),
    ({"distribution": "normal", "mean": "a", "std": 1.0},
     r"\(support.torsional_stiffness\).mean must be a finite number, got 'a'"),
    ({"distribution": "normal", "mean": 1.0}, r"\(support.torsional_stiffness\).std is missing"),
    ({"range": {"min": 1.0, "max": 2.0, "num": 3, "stp": 1.0}},
     r"\(support.torsional_stiffness\).range.stp is not a known key"),
    ({"range": {"min": 1.0, "max": 2.0}}, r"\.range must be \{min, max, num\} or"),
    ({"range": {"min": 1.0, "max": 2.0, "num": 0}}, r"\.range.num must be an integer in \[1, "),
    ({"distribution": "truncated_normal", "mean": 0.0, "std": 1.0, "low": 1.0, "high": 0.5},
     r"low \(1\) must be < high \(0.5\)"),
    ({"distribution": "truncated_normal", "mean": 0.0, "std": 1.0, "low": 50.0, "high": 60.0},
     "holds no probability"),
    ({"distribution": "gamma", "mean": 1.0}, "distribution must be one of"),
    ({"distribution": "normal", "mean": 1.0, "std": 1.0, "low": 0.0}, "low is not a parameter"),
    ({"values": [1.0], "distribution": "normal"}, "not both"),
    ({"range": {"min": 2.0, "max": 1.0, "num": 3}}, r"min \(2\) must be <= max \(1\)"),
])
def test_invalid_distribution_parameters(param, message):
    d = sweep_dict([{"path": "support.torsional_stiffness", **param}], samples=3)
    with pytest.raises(S.SweepError, match=message):
        S.sweep_from_dict(d)


def test_condition_out_of_range_is_a_sweep_error():
    with pytest.raises(S.SweepError, match=r"parameter\[0\] \(flight.mach\).values\[1\] = 1.2 "
                                           r"cannot be analysed with the base case's aero.method "
                                           r"= 'dlm' .*mach must be < 1 for the DLM"):
        S.sweep_from_dict(sweep_dict([{"path": "flight.mach", "values": [0.5, 1.2]}]))
    with pytest.raises(S.SweepError, match="sweep.altitude must be an altitude"):
        S.sweep_from_dict(sweep_dict([], altitude=1e6))


def test_unknown_output_and_sweep_keys():
    with pytest.raises(S.SweepError, match="'flutter_sped' is not an output"):
        S.sweep_from_dict(sweep_dict([], outputs=["flutter_sped"]))
    with pytest.raises(S.SweepError, match="sweep.sample is not a known key"):
        S.sweep_from_dict(sweep_dict([], sample=3))


# ------------------------------------------------------------------------------------------
# samplers
# ------------------------------------------------------------------------------------------
def test_samplers_match_their_distributions_and_the_seed():
    """Moments of 40000 draws against the analytic values: normal mean/std; uniform mean
    (a+b)/2, std (b-a)/sqrt(12); lognormal median and mean m exp(s^2/2); truncated normal mean
    mu + s (phi(a) - phi(b)) / (Phi(b) - Phi(a)) (Johnson, Kotz & Balakrishnan, Continuous
    Univariate Distributions 1, 2nd ed., Eq. 13.134) and its bounds. Tolerances: 5 standard
    errors."""
    from scipy.stats import norm
    n = 40000
    ps = [{"path": "material.youngs_modulus", "distribution": "normal", "mean": 70e9, "std": 2e9},
          {"path": "material.density", "distribution": "uniform", "low": 2600.0, "high": 2800.0},
          {"path": "support.torsional_stiffness", "distribution": "lognormal", "median": 120.0,
           "sigma": 0.2},
          {"path": "thickness.root", "distribution": "truncated_normal", "mean": 0.004,
           "std": 0.0002, "low": 0.0039, "high": 0.0045}]
    sw = S.sweep_from_dict(sweep_dict(ps, samples=n))
    rows = sw.design()
    assert len(rows) == n == sw.n_samples
    x = {p["path"]: np.array([r[p["path"]] for r in rows]) for p in ps}
    e = x["material.youngs_modulus"]
    assert abs(e.mean() - 70e9) < 5 * 2e9 / math.sqrt(n)
    assert abs(e.std() / 2e9 - 1) < 5 / math.sqrt(2 * n)
    r = x["material.density"]
    assert r.min() >= 2600 and r.max() <= 2800
    assert abs(r.mean() - 2700) < 5 * (200 / math.sqrt(12)) / math.sqrt(n)
    k = x["support.torsional_stiffness"]
    assert abs(np.log(k).mean() - math.log(120.0)) < 5 * 0.2 / math.sqrt(n)
    assert abs(np.log(k).std() - 0.2) < 5 * 0.2 / math.sqrt(2 * n)
    t = x["thickness.root"]
    a, b = (0.0039 - 0.004) / 0.0002, (0.0045 - 0.004) / 0.0002
    mean = 0.004 + 0.0002 * (norm.pdf(a) - norm.pdf(b)) / (norm.cdf(b) - norm.cdf(a))
    assert t.min() >= 0.0039 and t.max() <= 0.0045
    assert abs(t.mean() - mean) < 5 * 0.0002 / math.sqrt(n)
    # the same seed draws the same samples; another seed others
    again = S.sweep_from_dict(sweep_dict(ps, samples=n)).design()
    assert again == rows
    other = S.sweep_from_dict(sweep_dict(ps, samples=n, seed=8)).design()
    assert other[0] != rows[0]
    # a parameter added at the end leaves the draws of the others as they were
    more = S.sweep_from_dict(sweep_dict(ps + [{"path": "material.poisson_ratio",
                                               "distribution": "uniform", "low": 0.29,
                                               "high": 0.31}], samples=n)).design()
    assert all(m[p["path"]] == r0[p["path"]] for m, r0 in zip(more[:50], rows[:50]) for p in ps)


def test_grid_times_monte_carlo_design():
    ps = [{"path": "flight.mach", "values": [0.4, 0.6]},
          {"path": "flight.altitude", "range": {"min": 0.0, "max": 5000.0, "num": 3}},
          MC[2]]
    sw = S.sweep_from_dict(sweep_dict(ps, samples=4))
    rows = sw.design()
    assert sw.n_samples == len(rows) == 2 * 3 * 4
    assert [r["flight.altitude"] for r in rows[:12:4]] == [0.0, 2500.0, 5000.0]
    assert rows[0]["flight.mach"] == 0.4 and rows[12]["flight.mach"] == 0.6
    # common random numbers: the same draws at every grid point
    z = [r["damping.modal_damping_ratio"] for r in rows]
    assert z[:4] == z[4:8] == z[20:24]


# ------------------------------------------------------------------------------------------
# AIC reuse and one sample
# ------------------------------------------------------------------------------------------
def test_projected_gafs_equal_a_rebuilt_database_bit_for_bit(tmp_path, one_blas_thread):
    """The factored D(M, k) projected on a varied structure's modes gives the GAFs the
    pipeline builds from scratch (same operations, Eqs. 2.10-2.12)."""
    from asekit.aero.gaf import cached_gaf_database
    sw = S.sweep_from_dict(sweep_dict([]))
    fac = S.base_factors(sw)
    d, _, _ = sw.case_dict({"material.youngs_modulus": 66e9, "thickness.root": 0.0041})
    case = case_from_dict(d)
    model = P.modal_model(case)
    q = S.projected_gaf(model, case, fac, 0.6)
    db = cached_gaf_database(model, P.box_mesh(case), [0.6], P.reduced_frequencies(case),
                             case.aero.reference_semichord, progress=False, rebuild=True,
                             cache_dir=tmp_path)
    assert np.array_equal(q, db.Q[0])
    assert S.aero_key(case) == fac.key


def test_structural_sweep_builds_the_dlm_once_per_mach(monkeypatch):
    # every DLM matrix build, whole sweep or streamed batch, goes through _normalwash_batch
    import asekit.aero.dlm as dlm
    calls = []
    real = dlm._normalwash_batch
    monkeypatch.setattr(dlm, "_normalwash_batch",
                        lambda *a, **k: calls.append(a[1]) or real(*a, **k))
    sw = S.sweep_from_dict(sweep_dict(MC, samples=3, outputs=["f1_hz"]))
    df = S.run_sweep(sw)
    assert calls == [0.6]
    assert df["aic_reused"].all() and (df["status"] == "ok").all()
    # a planform change is not the base mesh: that sample gets its own factors
    calls.clear()
    sw = S.sweep_from_dict(sweep_dict([{"path": "panel[0].tip_chord", "values": [0.078, 0.07]}],
                                      outputs=["flutter_speed"]))
    df = S.run_sweep(sw)
    assert calls == [0.6, 0.6]
    assert df["aic_reused"].tolist() == [True, False]


def test_a_sample_is_the_pipeline_on_the_edited_case(one_blas_thread):
    """Row = asekit.case.pipeline on the case file edited by hand (same flutter speed,
    frequency, divergence speed and flags); flight.mach / flight.altitude pick the condition."""
    from asekit.aeroelastic.flutter import divergence_speeds
    from asekit.atmosphere import standard_atmosphere
    ps = [{"path": "support.torsional_stiffness", "values": [100.0]},
          {"path": "damping.modal_damping_ratio", "values": [0.005]},
          {"path": "flight.mach", "values": [0.5]}, {"path": "flight.altitude", "values": [2500.0]}]
    sw = S.sweep_from_dict(sweep_dict(ps, outputs=list(S.POINT_OUTPUTS)))
    row = S.run_sweep(sw).iloc[0]
    import tomllib
    d = tomllib.loads(FIN_FILE.read_text())
    d["support"]["torsional_stiffness"] = 100.0
    d["damping"] = {"modal_damping_ratio": 0.005}
    d["flight"]["velocities"] = dict(FAST_V)
    case = case_from_dict(d)
    db = P.gaf_database(case, progress=False)
    atm = standard_atmosphere(2500.0)
    cond = P.FlightCondition(2500.0, float(atm.density), float(atm.speed_of_sound))
    r = P.analyse_condition(case, db, 0.5, cond)
    assert row["status"] == "ok" and row["flight.mach"] == 0.5
    assert row["flutter_speed"] == r.flutter.speed
    assert row["flutter_frequency"] == r.flutter.frequency_hz
    assert row["flutter_mode"] == r.flutter.mode + 1        # user-facing: elastic modes from 1
    model = P.modal_model(case)
    div = divergence_speeds(model, db.at(0.5).Q[0].real, cond.density)
    assert row["divergence_speed"] == div[0]
    assert row["flight_speed"] == 0.5 * cond.speed_of_sound
    assert row["flutter_margin"] == r.flutter.speed / (0.5 * cond.speed_of_sound) - 1
    assert row["flutter_inside"] == (r.flutter.speed <= 0.5 * cond.speed_of_sound)
    assert row["f1_hz"] == model.frequencies_hz[1]


def test_envelope_and_ase_outputs_are_the_pipeline(one_blas_thread):
    """min_flutter_speed / envelope_margin / matched_mach = asekit.case.pipeline.flutter and
    the aem outputs = pipeline.ase on the edited case (two Machs, two altitudes)."""
    outs = list(S.ENVELOPE_OUTPUTS) + list(S.ASE_OUTPUTS)
    d = sweep_dict([{"path": "actuator.controller.k_p", "values": [250.0]}], outputs=outs)
    d["case"].update({"aero.machs": [0.5, 0.6], "flight.altitudes": [0.0, 5000.0],
                      "actuator.condition.mach": 0.55})
    sw = S.sweep_from_dict(d)
    row = S.run_sweep(sw).iloc[0]
    assert row["status"] == "ok", row["error"]
    case = case_from_dict(sw.case_dict({"actuator.controller.k_p": 250.0})[0])
    db = P.gaf_database(case, progress=False)
    fa = P.flutter(case, db=db)
    assert row["min_flutter_speed"] == min(r.flutter.speed for r in fa.results)
    assert row["envelope_margin"] == min(m["margin"] for m in fa.margins)
    for bound in ("min_flutter_speed_upper_bound", "envelope_margin_upper_bound",
                  "envelope_margin_lower_bound"):
        assert math.isnan(row[bound])                            # the values are known
    mm = [m["matched_mach"] for m in fa.match_points if m["matched_mach"] is not None]
    assert (math.isnan(row["matched_mach"]) and not mm) or row["matched_mach"] == min(mm)
    a = P.ase(case, db=db)
    for t in ("AEM1", "AEM2"):
        p = t.lower()
        assert row[f"{p}_stable"] == a.stable[t]
        assert row[f"{p}_max_real_pole"] == a.max_real_pole[t]
        assert row[f"{p}_settling_s"] == a.settling_s[t]
        assert row[f"{p}_corner_overshoot"] == max(a.corner_overshoot[t].values())


def test_failed_sample_is_a_row_with_its_error():
    sw = S.sweep_from_dict(sweep_dict([{"path": "material.youngs_modulus",
                                        "values": [70e9, -1.0]}], outputs=["f1_hz"]))
    df = S.run_sweep(sw)
    assert len(df) == 2
    assert df["status"].tolist() == ["ok", "failed"]
    assert "CaseError: material.youngs_modulus must be > 0 Pa, got -1" in df["error"][1]
    assert df["material.youngs_modulus"][1] == -1.0 and math.isnan(df["f1_hz"][1])


def test_undecidable_flutter_inside_is_a_failed_row_not_false():
    d = sweep_dict([{"path": "support.torsional_stiffness", "values": [120.0]}],
                   outputs=["flutter_inside"])
    d["case"]["flight.velocities"] = {"min": 100.0, "max": 180.0, "step": 10.0}
    df = S.run_sweep(S.sweep_from_dict(d))
    assert df["status"][0] == "failed" and "extend the velocity sweep" in df["error"][0]


def test_resume_from_a_partial_file(tmp_path):
    sw = S.sweep_from_dict(sweep_dict([MC[1]], samples=3, outputs=["f1_hz", "flutter_speed"]))
    out = tmp_path / "r.csv"
    full = S.run_sweep(sw, out=out)
    lines = out.read_text().splitlines(keepends=True)
    assert len(lines) == 4
    out.write_text(lines[0] + lines[2] + lines[3][:20])          # one row, one cut-off row
    again = S.run_sweep(sw, out=out)
    assert_identical(full, again)
    assert again["wall_s"][1] == full["wall_s"][1]                 # the kept row was not rerun
    other = S.sweep_from_dict(sweep_dict([MC[1]], samples=3, seed=99,
                                         outputs=["f1_hz", "flutter_speed"]))
    with pytest.raises(S.SweepError, match="rows of another sweep"):
        S.run_sweep(other, out=out)


def _mark_second_row_failed(out, error: str, output: str) -> None:
    """Rewrite the second sample of a two-sample output CSV as a failed row (``error``, the
    ``output`` cell emptied), as a lost worker leaves it."""
    lines = out.read_text().splitlines(keepends=True)
    cols = next(csv.reader([lines[0]]))
    cells = next(csv.reader([lines[2]]))
    cells[cols.index("status")], cells[cols.index("error")] = "failed", error
    cells[cols.index(output)] = ""
    out.write_text(lines[0] + lines[1] + ",".join(cells) + "\n")


def test_resume_keeps_or_retries_failed_rows(tmp_path):
    sw = S.sweep_from_dict(sweep_dict([{"path": "support.torsional_stiffness",
                                        "values": [100.0, 120.0]}], outputs=["f1_hz"]))
    out = tmp_path / "r.csv"
    full = S.run_sweep(sw, out=out)
    _mark_second_row_failed(out, "KilledWorker: lost", "f1_hz")
    kept = S.run_sweep(sw, out=out, retry_failed=False)
    assert kept["status"].tolist() == ["ok", "failed"]           # a finished row is kept
    again = S.run_sweep(sw, out=out)                             # the default: rerun failed
    assert_identical(full, again)
    assert again["wall_s"][0] == full["wall_s"][0]               # the ok row was not rerun


# ------------------------------------------------------------------------------------------
# statistics
# ------------------------------------------------------------------------------------------
def test_clopper_pearson_interval():
    """k = 0: high = 1 - (alpha/2)^(1/n) exactly; k = 5 of 10: [0.187086, 0.812914] (R
    binom.test(5, 10)); and the defining tail equations P(X >= k | low) = P(X <= k | high) =
    alpha / 2 (Clopper & Pearson 1934)."""
    from scipy.stats import binom
    r = S.clopper_pearson(0, 10)
    assert r.low == 0.0 and math.isclose(r.high, 1 - 0.025 ** 0.1, rel_tol=1e-12)
    r = S.clopper_pearson(5, 10)
    assert abs(r.low - 0.187086) < 1e-6 and abs(r.high - 0.812914) < 1e-6
    r = S.clopper_pearson(7, 40, 0.9)
    assert math.isclose(binom.sf(6, 40, r.low), 0.05, rel_tol=1e-9)
    assert math.isclose(binom.cdf(7, 40, r.high), 0.05, rel_tol=1e-9)
    for bad in ((11, 10), (-1, 10), (1, 0)):
        with pytest.raises(ValueError):
            S.clopper_pearson(*bad)


def test_standardised_regression_coefficients_of_a_linear_model():
    """y = 2 x1 - 0.5 x2 + 0 x3 with sd(x) = 1, 4, 3: SRC = b_j sd_j / sd_y = 2/sqrt(8),
    -2/sqrt(8), 0 (Saltelli et al. 2008, Eq. 1.8), R^2 = 1."""
    import pandas as pd
    g = np.random.default_rng(1)
    x = g.standard_normal((5000, 3)) * [1.0, 4.0, 3.0]
    y = 2 * x[:, 0] - 0.5 * x[:, 1]
    t = pd.DataFrame({"a": x[:, 0], "b": x[:, 1], "c": x[:, 2], "y": y, "status": "ok"})
    s = S.standardised_regression_coefficients(t, ["c", "b", "a"], "y")
    names = [n for n, _ in s.ranking]
    assert names[2] == "c" and abs(s.ranking[2][1]) < 0.01
    src = dict(s.ranking)
    assert abs(src["a"] - 2 / math.sqrt(8)) < 0.02 and abs(src["b"] + 2 / math.sqrt(8)) < 0.02
    assert s.r2 > 1 - 1e-12


# ------------------------------------------------------------------------------------------
# processes and a real dask.distributed LocalCluster (2 worker processes)
# ------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    cl = distributed.Client(cluster)
    yield cl
    cl.close()
    cluster.close()


def test_serial_processes_and_dask_give_identical_tables(client):
    sw = S.sweep_from_dict(sweep_dict(MC, samples=4))
    serial = S.run_sweep(sw)
    assert (serial["status"] == "ok").all() and serial["flutter_speed"].notna().all()
    assert_identical(serial, S.run_sweep(sw, executor="processes", workers=2))
    assert_identical(serial, S.run_sweep(sw, executor="dask", client=client))


def test_blas_threads_do_not_change_the_table(tmp_path):
    """A serial run with two BLAS threads (OMP/OPENBLAS_NUM_THREADS=2) equals the in-process
    table bit for bit: samples and factors run on one BLAS thread whatever the environment."""
    d = sweep_dict(MC, samples=3, outputs=["flutter_speed", "divergence_speed", "f1_hz"])
    f = tmp_path / "s.toml"
    f.write_text(_toml(d))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "2",
           "OPENBLAS_NUM_THREADS": "2"}
    r = subprocess.run([sys.executable, "-m", "asekit", "sweep", str(f), "--out", "o.csv",
                        "--quiet"], env=env, cwd=tmp_path, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert_identical(S.read_table(tmp_path / "o.csv"), S.run_sweep(S.sweep_from_dict(d)))


def test_failing_task_on_dask_is_a_failed_row(client):
    sw = S.sweep_from_dict(sweep_dict([{"path": "damping.modal_damping_ratio",
                                        "values": [0.0, 1.5]}], outputs=["flutter_speed"]))
    df = S.run_sweep(sw, executor="dask", client=client)
    assert df["status"].tolist() == ["ok", "failed"]
    assert "damping.modal_damping_ratio[0] must be < 1" in df["error"][1]
    assert_identical(df, S.run_sweep(sw))


def test_worker_killed_mid_sweep_loses_no_rows(client, tmp_path):
    """SIGKILL one worker process by PID once the first rows are in the file: the finished
    rows stay, dask reruns the lost tasks on the restarted worker, and the table equals the
    serial one."""
    sw = S.sweep_from_dict(sweep_dict(MC, samples=8, outputs=["flutter_speed", "f1_hz"]))
    out = tmp_path / "killed.csv"
    pids = list(client.run(os.getpid).values())
    seen = {}

    def killer():
        t0 = time.time()
        while time.time() - t0 < 120:
            if out.exists() and len(out.read_text().splitlines()) >= 3:
                seen["rows"] = out.read_text().splitlines()[1:]
                os.kill(pids[0], signal.SIGKILL)
                return
            time.sleep(0.02)

    th = threading.Thread(target=killer)
    th.start()
    df = S.run_sweep(sw, out=out, executor="dask", client=client)
    th.join()
    assert "rows" in seen, "the worker was never killed"
    assert pids[0] not in client.run(os.getpid).values()         # it died (and was replaced)
    final = out.read_text().splitlines()
    assert all(r in final for r in seen["rows"])                 # no finished row lost
    assert len(df) == 8
    assert_identical(df, S.run_sweep(sw))


def test_interrupted_sweep_resumes_on_dask(tmp_path):
    """The CLI killed (SIGKILL) mid-sweep leaves its finished rows; rerunning it with
    --executor dask (a LocalCluster it starts) completes the table, identical to serial."""
    pytest.importorskip("dask.distributed")
    d = sweep_dict(MC, samples=6, outputs=["flutter_speed", "f1_hz"])
    sw_file = tmp_path / "s.toml"
    sw_file.write_text(_toml(d))
    out = tmp_path / "out.csv"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    cmd = [sys.executable, "-m", "asekit", "sweep", str(sw_file), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(cmd, env=env, cwd=tmp_path)
    t0 = time.time()
    while time.time() - t0 < 120 and proc.poll() is None:
        if out.exists() and len(out.read_text().splitlines()) >= 3:
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    kept = out.read_text().splitlines()[1:]
    assert 2 <= len(kept) < 6
    r = subprocess.run(cmd + ["--executor", "dask", "--workers", "2"], env=env, cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    final = out.read_text().splitlines()
    assert set(kept) <= set(final)
    assert_identical(S.read_table(out), S.run_sweep(S.sweep_from_dict(d)))


def _toml(d) -> str:
    """A minimal TOML writer for the test sweeps (tables of scalars, lists, inline tables)."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)
    out = ["[sweep]"] + [f"{k} = {val(v)}" for k, v in d["sweep"].items()]
    out += ["[case]"] + [f'"{k}" = {val(v)}' for k, v in d["case"].items()]
    for p in d["parameter"]:
        out += ["[[parameter]]"] + [f"{k} = {val(v)}" for k, v in p.items()]
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------
def _cli(args, tmp_path, timeout=120):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, "-m", "asekit", "sweep", *args], env=env,
                          cwd=tmp_path, capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["parameter"][0].update(path="material.youngs_modulos"),
     "'material.youngs_modulos' is not a case-file key"),
    (lambda d: d["parameter"][0].update(sigma=-0.1),
     r"parameter\[0\] \(support.torsional_stiffness\).sigma must be > 0, got -0.1"),
    (lambda d: d["parameter"][0].update(distribution="uniform", low=130.0, high=110.0),
     None),
    (lambda d: d["sweep"].update(outputs=["flutter_speed", "q_dyn"]), "'q_dyn' is not an output"),
])
def test_cli_bad_input_is_one_line_and_exit_2(tmp_path, edit, message):
    d = sweep_dict([copy.deepcopy(MC[1])], samples=2)
    edit(d)
    if d["parameter"][0]["distribution"] == "uniform":
        del d["parameter"][0]["median"], d["parameter"][0]["sigma"]
        message = r"low \(130\) must be < high \(110\)"
    f = tmp_path / "bad.toml"
    f.write_text(_toml(d))
    r = _cli([str(f), "--out", "o.csv", "--quiet"], tmp_path)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: bad.toml: ")
    import re
    assert re.search(message, lines[0]), lines[0]
    assert not (tmp_path / "o.csv").exists()


def test_cli_unreachable_scheduler_fails_fast(tmp_path):
    pytest.importorskip("dask.distributed")
    f = tmp_path / "s.toml"
    f.write_text(_toml(sweep_dict([MC[1]], samples=2)))
    t0 = time.perf_counter()
    r = _cli([str(f), "--out", "o.csv", "--executor", "dask", "--scheduler",
              "tcp://127.0.0.1:9", "--quiet"], tmp_path)
    assert time.perf_counter() - t0 < 30
    assert r.returncode == 2
    assert r.stderr.strip().splitlines()[-1].startswith(
        "error: cannot reach the Dask scheduler at tcp://127.0.0.1:9 within 5 s")


# ------------------------------------------------------------------------------------------
# the aero method of the base case (issue 21): supersonic and piston sweeps
# ------------------------------------------------------------------------------------------
AGARD_SWEEP = ROOT / "data" / "sweeps" / "agard445_6_supersonic_stiffness.toml"


def test_supersonic_sweep_runs_and_its_nominal_sample_is_the_pipeline():
    """The shipped sweep over data/cases/agard445_6_supersonic.toml (aero.method = "supersonic",
    M 1.072, a density case): every sample runs with the Mach-box method; the nominal sample
    (E1 = 3.1511 GPa) has the flutter speed and frequency of the pipeline (its database and
    its per-condition p-k, asekit.case.pipeline.analyse_condition, the step of
    pipeline.flutter) on the unmodified case at (M 1.072, rho 0.055146 kg/m^3); the flutter
    speed and the first (bending) frequency rise with the fibre-direction modulus E1."""
    import warnings

    from asekit.aero.methods import TransonicWarning
    from asekit.case import load_case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        sw = S.load_sweep(AGARD_SWEEP)
        df = S.run_sweep(sw)
        case = load_case(ROOT / "data" / "cases" / "agard445_6_supersonic.toml")
        ref = P.analyse_condition(case, P.gaf_database(case, progress=False), 1.072,
                                  P.flight_conditions(case)[1])
    assert sw.density == 0.055146 and sw.condition_path == "flight.density"
    assert (df["status"] == "ok").all(), df["error"].tolist()
    assert not df["aic_reused"].any()           # 3 samples x 4 modes: rebuilt per sample
    assert ref.condition.density == 0.055146
    nominal = df[df["material.e1"] == 3.1511e9].iloc[0]
    assert math.isclose(nominal["flutter_speed"], ref.flutter.speed, rel_tol=1e-12)
    assert math.isclose(nominal["flutter_frequency"], ref.flutter.frequency_hz, rel_tol=1e-12)
    assert np.all(np.diff(df["flutter_speed"]) > 0) and np.all(np.diff(df["f1_hz"]) > 0)
    assert df["flight.density"].tolist() == [0.055146] * 3


def _piston_plate(tmp_path):
    """A clamped square aluminium plate with piston theory at M 2.5 (a small supersonic case)."""
    case = tmp_path / "plate.toml"
    case.write_text('''[case]
name = "piston plate"
[[panel]]
root_leading_edge = [0.0, 0.0]
root_chord = 0.3
tip_leading_edge = [0.0, 0.3]
tip_chord = 0.3
n_chord = 8
n_span = 8
[thickness]
root = 0.002
tip = 0.002
[material]
youngs_modulus = 70.0e9
poisson_ratio = 0.3
density = 2700.0
[support]
kind = "clamped_root"
[modes]
count = 4
[aero]
method = "piston"
machs = [2.5]
reference_semichord = 0.15
boxes = [{ n_chord = 8, n_span = 8 }]
reduced_frequencies = [0.001, 0.05, 0.1, 0.2, 0.4, 0.8]
[flight]
densities = [0.4]
velocities = { min = 100.0, max = 1500.0, step = 20.0 }
''')
    return case


def _plate_sweep(tmp_path, case, **sweep):
    f = tmp_path / "s.toml"
    extra = "".join(f"{k} = {v!r}\n" for k, v in sweep.items())
    extra += "" if "mach" in sweep else "mach = 2.5\n"
    f.write_text(f'[sweep]\ncase = "{case.name}"\n{extra}'
                 'outputs = ["flutter_speed", "flutter_frequency", "f1_hz"]\n'
                 '[[parameter]]\npath = "thickness.root"\nvalues = [0.0018, 0.002, 0.0022]\n')
    return S.load_sweep(f)


def test_piston_sweep_reuses_its_matrices_and_equals_the_pipeline(tmp_path, monkeypatch,
                                                                  one_blas_thread):
    """Piston theory's pressure matrix depends on the boxes and Mach only (a local law): the
    sweep forms it once and projects each sample's modes (aic_reused), bit-identical to the
    pipeline's database; with the registry saying "structure-dependent" the GAFs are rebuilt
    per sample, with the same numbers. A thicker root stiffens the plate: f1 and the flutter
    speed rise."""
    import dataclasses

    import asekit.aero.methods as M
    case = _piston_plate(tmp_path)
    calls = []
    real = M.piston_pressure_matrices
    monkeypatch.setattr(M, "piston_pressure_matrices",
                        lambda *a, **k: calls.append(a[1]) or real(*a, **k))
    sw = _plate_sweep(tmp_path, case)
    assert sw.condition_path == "flight.density" and sw.density == 0.4
    df = S.run_sweep(sw)
    assert calls == [2.5]                                   # one matrix for three samples
    assert (df["status"] == "ok").all(), df["error"].tolist()
    assert df["aic_reused"].all()
    assert np.all(np.diff(df["f1_hz"]) > 0) and np.all(np.diff(df["flutter_speed"]) > 0)
    d, mach, rho = sw.case_dict({"thickness.root": 0.0022})
    c = case_from_dict(d)
    r = P.analyse_condition(c, P.gaf_database(c, progress=False), mach,
                            P.FlightCondition(None, rho, None))
    assert df["flutter_speed"].iloc[2] == r.flutter.speed
    monkeypatch.setitem(M.AERO_METHODS, "piston", dataclasses.replace(
        M.AERO_METHODS["piston"], structure_independent=False))
    calls.clear()
    df2 = S.run_sweep(sw)
    assert calls == [2.5, 2.5, 2.5] and not df2["aic_reused"].any()
    assert df2["flutter_speed"].tolist() == df["flutter_speed"].tolist()


def test_impossible_method_and_condition_name_both_key_paths(tmp_path):
    case = _piston_plate(tmp_path)
    with pytest.raises(S.SweepError, match=r"sweep.mach = 0.8 cannot be analysed with the base "
                                           r"case's aero.method = 'piston' .*mach must be > 1"):
        _plate_sweep(tmp_path, case, mach=0.8)
    f = tmp_path / "m.toml"
    f.write_text(f'[sweep]\ncase = "{case.name}"\n[[parameter]]\npath = "flight.mach"\n'
                 'values = [2.0, 0.9]\n')
    with pytest.raises(S.SweepError, match=r"parameter\[0\] \(flight.mach\).values\[1\] = 0.9 "
                                           r"cannot be analysed .*aero.method = 'piston'"):
        S.load_sweep(f)
    with pytest.raises(S.SweepError, match=r"flight.altitude .* or as flight.density .*not both"):
        _plate_sweep(tmp_path, case, altitude=0.0, density=0.4)
    f.write_text(f'[sweep]\ncase = "{case.name}"\noutputs = ["flutter_margin"]\n')
    with pytest.raises(S.SweepError, match=r"flutter_margin needs the speed of sound .*give "
                                           r"sweep.altitude"):
        S.load_sweep(f)
    # a sample that varies the method itself into an impossible combination: a failed row
    # naming the case key paths (the case file is valid, the sample's case is not)
    f.write_text(f'[sweep]\ncase = "{case.name}"\noutputs = ["flutter_speed"]\n'
                 '[[parameter]]\npath = "aero.method"\nvalues = ["piston", "dlm"]\n')
    df = S.run_sweep(S.load_sweep(f))
    assert df["status"].tolist() == ["ok", "failed"]
    assert re.search(r"aero.machs\[0\] = 2.5 with aero.method = 'dlm': mach must be < 1 for the "
                     r"DLM", df["error"].iloc[1]), df["error"].iloc[1]


# ------------------------------------------------------------------------------------------
# the processes executor with dying workers (issue 22)
# ------------------------------------------------------------------------------------------
CHEAP = {"aero.boxes": [{"n_chord": 4, "n_span": 4}]}     # 16 boxes: factors in ~1 s
K_GRID = [100.0, 110.0, 120.0, 130.0]


@dataclasses.dataclass(frozen=True)
class KillingSweep(S.Sweep):
    """A sweep whose sample with support.torsional_stiffness = ``kill_value`` SIGKILLs the
    worker process computing it (never the test's process ``parent``): once if ``marker`` is a
    file path (created before the kill, so the rerun computes the row), every time if it is
    empty. Each kill appends a line to ``log``. Pickled to the spawned workers by reference
    (this module is on their sys.path)."""

    kill_value: float = 0.0
    marker: str = ""
    log: str = ""
    parent: int = 0

    def case_dict(self, values):
        if (values.get("support.torsional_stiffness") == self.kill_value
                and os.getpid() != self.parent
                and not (self.marker and os.path.exists(self.marker))):
            if self.marker:
                Path(self.marker).touch()
            with open(self.log, "a") as fh:
                fh.write(f"{os.getpid()}\n")
            os.kill(os.getpid(), signal.SIGKILL)
        return super().case_dict(values)


def killing_sweep_dict():
    d = sweep_dict([{"path": "support.torsional_stiffness", "values": K_GRID}],
                   outputs=["f1_hz"])
    d["case"].update(CHEAP)
    return d


def killing_sweep(tmp_path, once: bool):
    sw = S.sweep_from_dict(killing_sweep_dict())
    ks = KillingSweep(**{f.name: getattr(sw, f.name) for f in dataclasses.fields(sw)},
                      kill_value=K_GRID[1], marker=str(tmp_path / "killed") if once else "",
                      log=str(tmp_path / "kills.log"), parent=os.getpid())
    return sw, ks


def test_worker_killed_by_its_sample_is_replaced_and_the_sample_rerun(tmp_path):
    """Sample 1 SIGKILLs its worker once: the worker is replaced, sample 1 computed again, and
    the table (4 rows, each sample journaled once) equals the serial one."""
    sw, ks = killing_sweep(tmp_path, once=True)
    out = tmp_path / "o.csv"
    df = S.run_sweep(ks, out=out, executor="processes", workers=2)
    assert (tmp_path / "killed").exists(), "the worker was never killed"
    assert len((tmp_path / "kills.log").read_text().split()) == 1
    assert df["status"].tolist() == ["ok"] * 4
    samples = [r["sample"] for r in csv.DictReader(out.open())]
    assert samples == ["0", "1", "2", "3"]
    assert_identical(df, S.run_sweep(sw))


def test_sample_that_always_kills_its_worker_fails_with_exit_1(tmp_path, monkeypatch, capsys):
    """Sample 1 SIGKILLs every worker that computes it: it is tried MAX_WORKER_DEATHS times,
    then a failed WorkerLost row naming it; the other rows are ok, and the CLI exits 1 with one
    line giving the count and how to retry."""
    from asekit.cli.main import main
    _, ks = killing_sweep(tmp_path, once=False)
    f = tmp_path / "k.toml"                       # the file the CLI reads: the sweep without
    f.write_text(_toml(killing_sweep_dict()))     # its killer, which load_sweep returns
    monkeypatch.setattr(S, "load_sweep", lambda path: ks)
    rc = main(["sweep", str(f), "--out", str(tmp_path / "o.csv"), "--executor", "processes",
               "--workers", "2", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1
    assert len(err) == 1 and err[0].startswith("error: 1 of 4 samples failed"), err
    assert "run the same command again to retry" in err[0]
    kills = (tmp_path / "kills.log").read_text().split()
    assert len(kills) == S.MAX_WORKER_DEATHS == 3 and len(set(kills)) == 3   # 3 processes
    df = S.read_table(tmp_path / "o.csv")
    assert df["status"].tolist() == ["ok", "failed", "ok", "ok"]
    assert df["error"][1].startswith("WorkerLost: sample 1: its worker process died 3 times")


def test_a_plain_resume_retries_failed_rows_and_keep_failed_keeps_them(tmp_path, capsys):
    """A journal with a failed row (a worker lost): `sweep --keep-failed` keeps it (exit 1),
    the plain command reruns it (exit 0), and the table is the serial one."""
    from asekit.cli.main import main
    d = sweep_dict([{"path": "support.torsional_stiffness", "values": [100.0, 120.0]}],
                   outputs=["f1_hz"])
    f = tmp_path / "s.toml"
    f.write_text(_toml(d))
    out = tmp_path / "r.csv"
    full = S.run_sweep(S.sweep_from_dict(d), out=out)
    _mark_second_row_failed(out, "WorkerLost: lost", "f1_hz")
    args = ["sweep", str(f), "--out", str(out), "--quiet"]
    assert main(args + ["--keep-failed"]) == 1
    assert "error: 1 of 2 samples failed" in capsys.readouterr().err
    assert S.read_table(out)["status"].tolist() == ["ok", "failed"]
    assert main(args) == 0
    assert capsys.readouterr().err.strip() == f"2 samples (0 failed) -> {out}"
    assert_identical(S.read_table(out), full)


def _children(pid: int) -> list[int]:
    """The live (not zombie) processes whose parent is ``pid``, from /proc."""
    out = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                stat = (p / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(stat[1]) == pid and stat[0] != "Z":
                out.append(int(p.name))
    return out


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_parent_killed_leaves_no_worker_alive(tmp_path):
    """`sweep --executor processes` SIGKILLed mid-sweep: its worker processes (and the
    multiprocessing resource tracker) are gone within 5 s (PR_SET_PDEATHSIG, the watchdog)."""
    d = sweep_dict([{"path": "support.torsional_stiffness", "values": K_GRID * 10}],
                   outputs=["f1_hz", "flutter_speed"])
    d["parameter"][0]["values"] = [100.0 + i for i in range(40)]
    d["case"].update(CHEAP)
    f = tmp_path / "s.toml"
    f.write_text(_toml(d))
    out = tmp_path / "o.csv"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "asekit", "sweep", str(f), "--out", str(out),
                             "--executor", "processes", "--workers", "2", "--quiet"], env=env,
                            cwd=tmp_path, stderr=subprocess.DEVNULL)
    try:
        t0 = time.time()
        while time.time() - t0 < 120 and proc.poll() is None:
            if out.exists() and len(out.read_text().splitlines()) >= 2:
                break
            time.sleep(0.02)
        kids = _children(proc.pid)
    finally:
        proc.kill()
        proc.wait()
    assert len(kids) >= 2, kids                       # two workers (and the resource tracker)
    t0 = time.time()
    while time.time() - t0 < 5 and any(_alive(k) for k in kids):
        time.sleep(0.05)
    left = [k for k in kids if _alive(k)]
    for k in left:
        os.kill(k, signal.SIGKILL)
    assert not left, f"alive {time.time() - t0:.1f} s after the parent's SIGKILL: {left}"


# ------------------------------------------------------------------------------------------
# sweeps that start above the flutter speed: the case summary's bounds (issue 22)
# ------------------------------------------------------------------------------------------
def test_bounded_minimum_gives_the_value_only_when_it_is_determined():
    """min over quantities known as a value, an upper or a lower bound, or unknown."""
    bm = S.bounded_minimum
    assert bm([("value", 0.3), ("value", 0.1)]) == (0.1, None, None)
    assert bm([("value", 0.3), ("lower", 0.5)]) == (0.3, None, None)   # 0.5 < x: not the min
    assert bm([("value", 0.3), ("lower", 0.2)]) == (None, 0.3, 0.2)    # min in [0.2, 0.3]
    assert bm([("value", 0.3), ("upper", 0.5)]) == (None, 0.3, None)   # the other may be lower
    assert bm([("value", 0.3), ("upper", 0.1)]) == (None, 0.1, None)
    assert bm([("value", 0.3), (None, None)]) == (None, 0.3, None)     # one unknown
    assert bm([("lower", 0.4), ("lower", 0.2)]) == (None, None, 0.2)
    assert bm([]) == (None, None, None)


def test_sweep_above_flutter_gives_the_case_summary_bounds(one_blas_thread):
    """flight.velocities from 230 m/s, above the sea-level flutter speed of the 16-box fin: the
    envelope outputs are the bounds of asekit.case.pipeline.flutter's summary (its
    margin_upper_bound, flutter at or below 230 m/s), not a value taken from the other
    altitude; flutter_inside is True where M a >= 230 m/s (M 0.75: 255 m/s) and a failed row
    where M a < 230 m/s (M 0.6: 204 m/s), which the sweep cannot decide."""
    outs = list(S.ENVELOPE_OUTPUTS) + ["unstable_at_start", "flutter_margin", "flutter_inside"]
    d = sweep_dict([{"path": "flight.mach", "values": [0.6, 0.75]}], outputs=outs)
    d["case"].update({**CHEAP, "aero.machs": [0.5, 0.6], "flight.altitudes": [0.0, 5000.0],
                      "flight.velocities": {"min": 230.0, "max": 400.0, "step": 10.0}})
    sw = S.sweep_from_dict(d)
    df = S.run_sweep(sw)
    case = case_from_dict(sw.case_dict({})[0])
    fa = P.flutter(case, db=P.gaf_database(case, progress=False))
    sea = next(m for m in fa.margins if m["altitude_m"] == 0.0)
    assert sea["margin"] is None and sea["margin_upper_bound"] is not None      # the setup
    assert fa.match_points[0]["flutter_at_or_below_ms"] == 230.0
    bounds = [m["margin"] if m["margin"] is not None else m["margin_upper_bound"]
              for m in fa.margins]
    assert df["status"].tolist() == ["failed", "ok"]
    assert "unstable at 230 m/s, the first speed of flight.velocities, above the flight " \
           "speed M a = 204.176 m/s: start the velocity sweep lower" in df["error"][0]
    row = df.iloc[1]
    assert math.isnan(row["envelope_margin"]) and math.isnan(row["envelope_margin_lower_bound"])
    assert row["envelope_margin_upper_bound"] == min(bounds)
    assert math.isnan(row["min_flutter_speed"]) and row["min_flutter_speed_upper_bound"] == 230.0
    assert row["unstable_at_start"] and row["flutter_inside"]
    assert math.isnan(row["flutter_margin"])
