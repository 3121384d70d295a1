"""A user-given gust profile (``[gust] profile``, issue 27): the CSV reader's checks and the
profile run through the same response and loads path as the 1-cos gusts."""

import dataclasses

import numpy as np
import pytest

from asekit.aeroelastic.gust import one_minus_cosine
from asekit.atmosphere import standard_atmosphere
from asekit.case import CaseError, case_from_dict
from asekit.case.gust_loads import gust_json, gust_loads, profile_gust
from asekit.case.schema import GustProfile, GustSpec, read_gust_profile

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


def test_profile_sampling_a_one_minus_cosine_gives_its_peaks(fin_case):
    # The same gust twice: as the analytic 1-cos (H = 2 m, U_ds = 10 m/s, M 0.5 at sea level)
    # and as a profile of 401 samples of it. Both run on the same time grid (a 1-cos gust's
    # rule for the profile's duration 2 H / U), so the only difference is the spline's
    # w_g, w_g', w_g'' against the analytic ones; every peak must agree to 1e-6 relative
    # (measured: 1e-9 on the root shear, 3e-10 bending, 1e-11 hinge moment, 1e-10 current).
    H, wds = 2.0, 10.0
    U = 0.5 * float(standard_atmosphere(0.0).speed_of_sound)       # as gust_loads computes it
    tp = np.linspace(0.0, 2 * H / U, 401)
    wp = one_minus_cosine(tp, U, H, wds)[0]
    prof = GustProfile("one_minus_cosine.csv", tuple(tp), tuple(wp))
    case = dataclasses.replace(fin_case, gust=GustSpec((H,), wds, 0.5, 0.0, profile=prof))
    res = gust_loads(case)
    cos, pro = gust_json(res)
    assert pro["gust_length_m"] is None and pro["profile"] == "one_minus_cosine.csv"
    assert cos["gust_length_m"] == H and cos["profile"] is None
    np.testing.assert_array_equal(res.cases[0].t, res.cases[1].t)
    for key in ("peak_hinge_moment_Nm", "peak_root_bending_Nm", "peak_root_shear_N",
                "peak_current_A"):
        assert pro[key] == pytest.approx(cos[key], rel=1e-6), key
    # the report's figure names the profile's curve by its file
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import fig_gust_histories
    f = fig_gust_histories(type("A", (), {"case": case, "gust": res})())
    labels = [t.get_text() for t in f.figure.axes[0].get_legend().get_texts()]
    assert labels == ["H = 2 m", "one_minus_cosine.csv"] and "H = 2 m, one_minus" in f.alt
    plt.close(f.figure)


def test_profile_gust_derivatives_of_a_sampled_cosine():
    # the spline's derivatives of a densely sampled 1-cos approach the analytic ones; zero
    # before the first row, the last velocity held after the last
    U, H, wds = 100.0, 5.0, 2.0
    tp = np.linspace(0.0, 2 * H / U, 2001)
    t = np.linspace(-0.01, 0.2, 777)
    w = profile_gust(tp, one_minus_cosine(tp, U, H, wds)[0], t)
    ref = one_minus_cosine(t, U, H, wds)
    om = np.pi * U / H
    for d in range(3):
        scale = wds / 2 * om ** d
        assert np.max(np.abs(w[d] - ref[d])) < 1e-4 * scale, d
    w = profile_gust([0.0, 1.0], [0.0, 3.0], [-1.0, 2.0])
    assert list(w[0]) == [0.0, 3.0] and list(w[1]) == [0.0, 0.0]


def _case_dict(fin_case_dict, profile):
    d = dict(fin_case_dict)
    d["gust"] = {"mach": 0.5, "profile": profile}
    return d


@pytest.fixture()
def fin_dict():
    import tomllib

    from asekit.util.paths import FIN_FILE
    return tomllib.loads(FIN_FILE.read_text())


def test_profile_key_is_read_relative_to_the_case_file(tmp_path, fin_dict):
    (tmp_path / "gusts").mkdir()
    (tmp_path / "gusts" / "g.csv").write_text("time_s,velocity_ms\n0,0\n0.01,1.5\n0.02,0\n")
    case = case_from_dict(_case_dict(fin_dict, "gusts/g.csv"), source=str(tmp_path / "c.toml"))
    assert case.gust.profile.name == "g.csv" and case.gust.gradient_lengths == ()
    assert case.gust.profile.velocity == (0.0, 1.5, 0.0)


@pytest.mark.parametrize("text, match", [
    ("t,v\n0,0\n1,0\n", "first row must name the columns time_s and velocity_ms"),
    ("time_s,velocity_ms\n0,0\n", "2 to 200000 data rows"),
    ("time_s,velocity_ms\n0,0\n0.1,abc\n", r"row 2 column velocity_ms must be a number "
                                            r"within \[-100, 100\] m/s, got 'abc'"),
    ("time_s,velocity_ms\n0,0\n0.1,150\n", "row 2 column velocity_ms"),
    ("time_s,velocity_ms\n0,0\n-1,0\n", r"row 2 column time_s must be a number within \[0, "),
    ("time_s,velocity_ms\n0,0\n0.2,1\n0.1,0\n", "row 3 column time_s must exceed the previous"),
    ("time_s,velocity_ms\n0,0\n0.1\n", "row 2 must hold 2 values"),
    ("time_s,velocity_ms\n0,0\nnan,0\n", "row 2 column time_s"),
])
def test_profile_rows_are_checked(tmp_path, text, match):
    f = tmp_path / "g.csv"
    f.write_text(text)
    with pytest.raises(CaseError, match=r"gust.profile g.csv.*" + match):
        read_gust_profile(f)


def test_missing_profile_file_names_the_key(tmp_path, fin_dict):
    with pytest.raises(CaseError, match="gust.profile: cannot read"):
        case_from_dict(_case_dict(fin_dict, "none.csv"), source=str(tmp_path / "c.toml"))
    with pytest.raises(CaseError, match="gust.gradient_lengths is missing"):
        d = _case_dict(fin_dict, "x")
        del d["gust"]["profile"]
        case_from_dict(d, source=str(tmp_path / "c.toml"))


def test_bad_profile_row_is_one_cli_line_exit_2_before_any_work(tmp_path, capsys,
                                                                 monkeypatch):
    # the command line: one line naming the case, the key, the file, the row and the column
    # (exit 2), and no pipeline step runs
    from asekit.case import pipeline as P
    from asekit.cli.main import main
    from asekit.util.paths import FIN_FILE

    def ran(*a, **k):
        pytest.fail("the pipeline ran")
    for name in ("modal_model", "gaf_database", "flutter", "box_mesh"):
        monkeypatch.setattr(P, name, ran)
    (tmp_path / "g.csv").write_text("time_s,velocity_ms\n0,0\n0.01,1\n0.02,-250\n")
    f = tmp_path / "c.toml"
    f.write_text(FIN_FILE.read_text() + '\n[gust]\nprofile = "g.csv"\n')
    assert main(["analyse", str(f), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        "error: c.toml: gust.profile g.csv row 3 column velocity_ms must be a number within "
        "[-100, 100] m/s, got '-250'"]
