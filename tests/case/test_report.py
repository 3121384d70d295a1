"""The HTML report of ``asekit analyse`` (asekit/case/report.py, asekit/case/report_figures.py),
issue 30 "the report for a person": the summary first with the critical condition named, a
link to the JSON, the flutter-against-Mach figure, V-g / V-f and root locus for every analysed
condition, every <img> an existing, non-empty PNG with an alt text that says what it shows,
and progress bars for the stages of ``analyse``.

Reference numbers: AGARD 445.6 weakened wing 3 at M 0.499 (data/cases/agard445_6.toml) flutters
at 181.9 m/s in asekit's p-k (the doctest of asekit.case.pipeline.flutter; Yates 1987 measured
172 m/s); the flutter speed is read from the run's own JSON, the test checks that the report
says what the JSON says.
"""

from __future__ import annotations

import json
import math
from html.parser import HTMLParser
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

#: rebuilt GAF databases go to a session temporary folder (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("session_gaf_cache")

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


class _Page(HTMLParser):
    """The <img> (src, alt), <a href> and the text before the first <img> of a page."""

    def __init__(self):
        super().__init__()
        self.imgs, self.links, self.before_first_img = [], [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append((a.get("src"), a.get("alt")))
        elif tag == "a":
            self.links.append(a.get("href"))

    def handle_data(self, data):
        if not self.imgs:
            self.before_first_img.append(data)


def _read_report(d: Path):
    page = _Page()
    page.feed((d / "index.html").read_text())
    return page, json.loads((d / "summary.json").read_text())


def _check_images(d: Path, page: _Page):
    """Every <img> is a PNG that exists, decodes, is larger than a thumbnail and not blank,
    and has an alt text that is more than its file name."""
    import matplotlib.image as mpimg
    assert page.imgs
    for src, alt in page.imgs:
        f = d / src
        assert f.is_file(), src
        assert f.read_bytes()[:8] == PNG_MAGIC, src
        img = mpimg.imread(f)
        assert img.shape[0] > 200 and img.shape[1] > 300, (src, img.shape)
        assert float(np.ptp(img[..., :3])) > 0.5, f"{src} is blank"
        assert alt and alt != src and len(alt) > 30, (src, alt)


def _check_conditions(page: _Page, s: dict):
    """A V-g figure and a root locus per analysed Mach whose alt texts name every condition
    analysed there with what the p-k sweep found (the flutter speed of the JSON, 0.1 m/s)."""
    alts = dict(page.imgs)
    for mach in sorted({r["mach"] for r in s["flutter"]}):
        vg = [alt for src, alt in alts.items() if src.startswith("vg_")
              and alt.startswith(f"V-g and V-f at M {mach:g}: ")]
        rl = [alt for src, alt in alts.items() if src.startswith("root_locus_")
              and alt.startswith(f"Root locus at M {mach:g} ")]
        assert len(vg) == 1 and len(rl) == 1, (mach, sorted(alts))
        for r in (r for r in s["flutter"] if r["mach"] == mach):
            where = (f"{r['altitude_m']:g} m" if r["altitude_m"] is not None
                     else f"rho {r['density']:.4g} kg/m^3")
            assert f"at {where} " in vg[0] and f"at {where} " in rl[0]
            if r["speed_ms"] is not None:
                assert (f"mode {r['mode']} crosses g = 0 at {r['speed_ms']:.1f} m/s"
                        in vg[0]), vg[0]


def _check_report(d: Path):
    page, s = _read_report(d)
    _check_images(d, page)
    srcs = [src for src, _ in page.imgs]
    assert srcs[0] == "flutter_mach.png"                 # the picture users look for first
    assert {"planform.png", "modes.png"} <= set(srcs)
    assert "summary.json" in page.links
    head = " ".join(page.before_first_img)
    assert "Critical condition:" in head and s["critical"]["text"] in head
    _check_conditions(page, s)
    return page, s


# ---------------------------------------------------------------------------------------------
# the shipped cases, through the command line
# ---------------------------------------------------------------------------------------------
def test_agard445_6_report_for_a_person(tmp_path, monkeypatch, capsys):
    """Issue 30's "done when": `asekit analyse agard445_6 --json out.json --report rep/` from a
    directory outside the checkout holds the flutter-against-Mach figure and a V-g figure for
    every condition; the progress bars name each stage (p-k included), --quiet hides them."""
    from asekit.__main__ import main
    monkeypatch.chdir(tmp_path)
    assert main(["analyse", "agard445_6", "--json", "out.json", "--report", "rep"]) == 0
    err = capsys.readouterr().err
    for stage in ("modes", "p-k flutter (Mach x condition)", "report figures"):
        assert stage in err, stage
    page, s = _check_report(tmp_path / "rep")
    assert json.loads(Path("out.json").read_text())["flutter"] == s["flutter"]
    (row,) = s["flutter"]
    assert s["critical"]["speed_ms"] == row["speed_ms"]          # no envelope: lowest U_f
    assert f"{row['speed_ms']:.1f} m/s" in s["critical"]["text"]
    assert math.isclose(row["speed_ms"], 181.9, abs_tol=0.5)    # pipeline.flutter's doctest
    assert main(["analyse", "agard445_6", "--report", "rep2", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "p-k flutter" not in err and "report figures" not in err


@pytest.mark.slow
@pytest.mark.parametrize("name", ["nalci2013_fin", "agard445_6_supersonic"])
def test_shipped_case_report(name, tmp_path):
    """The fin (4 Machs x 3 altitudes, envelope and match points, ASE figures) and the
    supersonic AGARD case (2 Machs x 5 densities in the transonic gap) hold the same figures."""
    from asekit.__main__ import main
    d = tmp_path / "rep"
    assert main(["analyse", name, "--report", str(d), "--quiet"]) == 0
    page, s = _check_report(d)
    if name == "nalci2013_fin":
        assert {"ase_bode.png", "ase_steps.png"} <= {src for src, _ in page.imgs}
        alt = dict(page.imgs)["flutter_mach.png"]
        for m in s["match_points"]:
            if m["matched_mach"] is not None:
                assert f"M {m['matched_mach']:.3f} ({m['matched_speed_ms']:.1f} m/s)" in alt
        assert s["critical"]["margin"] == min(m["margin"] for m in s["flutter_margins"])


# ---------------------------------------------------------------------------------------------
# the figures
# ---------------------------------------------------------------------------------------------
def _fake_analysis(points, envelope=(0.5, 1.3)):
    """An analysis with flutter speeds ``points`` [(Mach, U_f)] at one altitude (0 m, a = 340.3
    m/s), a divergence speed 2 U_f, no match point: enough for the Mach figure."""
    from asekit.case.pipeline import FlightCondition
    c = FlightCondition(0.0, 1.225, 340.3)
    res = [SimpleNamespace(mach=m, condition=c, unstable_at_start=False, instabilities=(),
                           flutter=SimpleNamespace(speed=u)) for m, u in points]
    flight = SimpleNamespace(velocities=(50.0, 800.0), envelope_mach=envelope,
                             envelope_altitude=None)
    return SimpleNamespace(
        case=SimpleNamespace(name="fake", flight=flight),
        flutter=SimpleNamespace(results=tuple(res), match_points=(), divergence=tuple(
            {"mach": m, "altitude_m": 0.0, "density": 1.225, "speed_ms": 2 * u}
            for m, u in points)))


def test_mach_figure_leaves_the_transonic_gap_open():
    """Speeds at M 0.8, 0.9 and 1.2, 1.5: no drawn segment joins a subsonic to a supersonic
    point (the issue: a match point interpolated across the 0.9-1.15 gap), the gap is shaded."""
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import fig_flutter_mach
    a = _fake_analysis([(0.8, 300.0), (0.9, 280.0), (1.2, 420.0), (1.5, 500.0)])
    a.flutter.match_points = ({"altitude_m": 0.0, "matched_mach": None,
                               "matched_speed_ms": None, "match_across_sonic": [0.9, 1.2]},)
    rf = fig_flutter_mach(a)
    try:
        ax = rf.figure.axes[0]
        joined = 0
        for ln in (x for x in ax.get_lines() if x.get_marker() in ("o", "x")):   # the data
            x = np.asarray(ln.get_xdata(), float)
            y = np.asarray(ln.get_ydata(), float)
            ok = np.isfinite(x) & np.isfinite(y)
            seg = ok[:-1] & ok[1:] & (ln.get_linestyle() not in ("None", "none", ""))
            across = seg & ((x[:-1] - 1.0) * (x[1:] - 1.0) <= 0)
            assert not across.any(), (ln.get_label(), x)
            joined += int((seg & (x[:-1] == 0.8) & (x[1:] == 0.9)).sum())
        assert joined == 2                   # flutter and divergence are lines on each side
        assert "transonic gap M 0.9-1.15 (never interpolated)" in [
            t.get_text() for t in ax.get_legend().get_texts()]
        assert len(ax.patches) == 1                                  # the shaded gap
        assert "transonic gap is left open" in rf.alt
        assert "U_f = M a inside the transonic gap (not interpolated) at 0 m (M 0.9-1.2)" in rf.alt
        assert ax.get_xlabel() == "Mach number M (-)" and ax.get_ylabel() == "speed (m/s)"
    finally:
        plt.close(rf.figure)


def test_mach_figure_without_the_gap_shades_nothing():
    import matplotlib.pyplot as plt

    from asekit.case.report_figures import fig_flutter_mach
    rf = fig_flutter_mach(_fake_analysis([(0.4, 200.0), (0.6, 210.0)], envelope=(0.4, 0.6)))
    try:
        ax = rf.figure.axes[0]
        assert ax.get_xlim()[1] < 0.9 and not ax.patches
        assert "envelope M 0.4-0.6" in rf.alt and "no match point" in rf.alt
    finally:
        plt.close(rf.figure)


# ---------------------------------------------------------------------------------------------
# the critical condition
# ---------------------------------------------------------------------------------------------
def _row(mach, alt, speed, f_hz=100.0, mode=2, first=False):
    return {"mach": mach, "altitude_m": alt, "density": 1.0, "speed_ms": None if first else speed,
            "frequency_hz": None if first else f_hz, "mode": mode,
            "unstable_at_first_point": first, "speed_upper_bound_ms": speed if first else None}


def test_critical_condition_is_the_lowest_margin():
    from asekit.case.report import critical_condition
    rows = [_row(0.6, 0.0, 213.0, 142.4), _row(0.6, 5000.0, 190.0, 139.0, mode=1)]
    margins = [{"altitude_m": 0.0, "envelope_mach": 0.6, "envelope_speed_ms": 204.2,
                "margin": 213.0 / 204.2 - 1, "flutter_speed_ms": 213.0},
               {"altitude_m": 5000.0, "envelope_mach": 0.6, "envelope_speed_ms": 192.3,
                "margin": 190.0 / 192.3 - 1, "flutter_speed_ms": 190.0}]
    c = critical_condition({"flutter": rows, "flutter_margins": margins})
    assert (c["altitude_m"], c["mach"], c["speed_ms"], c["mode"]) == (5000.0, 0.6, 190.0, 1)
    assert c["text"].endswith("flutter inside the envelope by 1.2 %")
    assert "5000 m" in c["text"] and "139 Hz" in c["text"] and "mode 1" in c["text"]
    c = critical_condition({"flutter": rows, "flutter_margins": margins[:1]})
    assert c["text"].endswith("flutter outside the envelope by 4.3 %")


def test_critical_condition_bounds_and_no_envelope():
    from asekit.case.report import critical_condition
    upper = [{"altitude_m": 0.0, "envelope_mach": 0.6, "envelope_speed_ms": 204.2,
              "margin": None, "margin_upper_bound": 100.0 / 204.2 - 1,
              "flutter_speed_upper_bound_ms": 100.0}]
    c = critical_condition({"flutter": [_row(0.6, 0.0, 100.0, first=True)],
                            "flutter_margins": upper})
    assert "flutter at or below 100.0 m/s" in c["text"]
    assert c["text"].endswith("flutter inside the envelope by at least 51.0 %")
    rows = [_row(0.5, 0.0, 250.0), _row(0.7, 0.0, 230.0, mode=1)]
    c = critical_condition({"flutter": rows, "flutter_margins": []})
    assert c["mach"] == 0.7 and c["speed_ms"] == 230.0 and "no envelope" in c["text"]
    c = critical_condition({"flutter": [_row(0.5, 0.0, 100.0, first=True)] + rows})
    assert "unstable at the first point" in c["text"] and c["speed_ms"] == 100.0
    assert critical_condition({"flutter": []})["text"].startswith("no flutter")


def test_single_condition_figures_keep_their_api():
    """``fig_vg(a, result)`` and friends (notebooks/bring_your_own_surface.ipynb) draw one
    condition: V-g over V-f, the flutter point starred at the crossing the result names."""
    import matplotlib.pyplot as plt

    from asekit.case import load_case
    from asekit.case.report import fig_modes, fig_planform, fig_root_locus, fig_vg, run_analysis
    from asekit.util.conventions import vg_damping_label
    from asekit.util.paths import CASES_DIR
    a = run_analysis(load_case(CASES_DIR / "agard445_6.toml"))
    (r,) = a.flutter.results
    figs = [fig_vg(a, r), fig_root_locus(a, r), fig_planform(a), fig_modes(a)]
    try:
        ax_g, ax_f = figs[0].axes
        assert ax_g.get_ylabel() == vg_damping_label("p") and ax_f.get_ylabel() == "frequency (Hz)"
        star = [ln for ln in ax_g.get_lines() if ln.get_label() == "flutter point"]
        assert star and star[0].get_xdata()[0] == r.flutter.speed
        assert len(figs[3].axes) == len(a.modal.frequencies_hz) + 1          # + the colour bar
    finally:
        for f in figs:
            plt.close(f)


def test_critical_condition_by_density():
    """Conditions given by density and speed of sound (no altitude) are named by density."""
    from asekit.case.report import critical_condition
    row = {**_row(0.6, None, 213.0, 142.4), "density": 0.5}
    margin = {"altitude_m": None, "envelope_mach": 0.6, "envelope_speed_ms": 204.2,
              "margin": 213.0 / 204.2 - 1, "flutter_speed_ms": 213.0}
    c = critical_condition({"flutter": [row], "flutter_margins": [margin]})
    assert "rho 0.5 kg/m^3" in c["text"] and c["text"].endswith("outside the envelope by 4.3 %")
