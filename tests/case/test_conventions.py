"""docs/conventions.md in every user-facing output: the ``analyse`` JSON names the rigid mode and
numbers the elastic modes from 1, carries a unit for every numeric key, and the report's V-g
figures plot g = 2 Re p / |Im p| with "> 0 unstable" on the axis; the notebooks print modes
through the one converter (asekit.util.conventions.mode_number / mode_label), never ``mode + 1``."""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from asekit.util.conventions import (
    RIGID_MODE_NAME,
    damping_ratio,
    mode_label,
    mode_number,
    vg_damping,
    vg_damping_label,
)
from asekit.util.paths import CASES_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"
FV16 = CASES_DIR / "nafems_fv16.toml"
NOTEBOOKS = Path(__file__).resolve().parents[2] / "notebooks"


#: rebuilt GAF databases go to a session temporary folder (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("session_gaf_cache")


# ---------------------------------------------------------------------------------------------
# the converters
# ---------------------------------------------------------------------------------------------
def test_mode_names_rigid_named_elastic_from_one():
    assert [mode_number(j, 1) for j in range(4)] == [RIGID_MODE_NAME, 1, 2, 3]
    assert [mode_number(j, 0) for j in range(3)] == [1, 2, 3]          # FN1 / clamped
    assert [mode_label(j, 1) for j in range(3)] == ["rigid pitch", "mode 1", "mode 2"]
    assert mode_label(np.int64(2)) == "mode 3" and mode_number(np.int64(2)) == 3
    for bad in (-1, 1.0, True, None):
        with pytest.raises(ValueError, match="index"):
            mode_number(bad, 1)
    with pytest.raises(ValueError, match="n_rigid"):
        mode_number(0, -1)


def test_vg_damping_is_nastran_g_positive_unstable():
    """A pole of damping ratio zeta, p = omega_n (-zeta + i sqrt(1 - zeta^2)), has V-g damping
    g = -2 zeta / sqrt(1 - zeta^2) (Nastran's p = omega (g/2 + i)): negative when stable,
    positive when unstable; damping_ratio recovers zeta (> 0 stable)."""
    zeta = np.array([0.3, 0.02, 0.0, -0.02, -0.3])
    wn = 2 * math.pi * 140.0
    p = wn * (-zeta + 1j * np.sqrt(1 - zeta ** 2))
    g = vg_damping(p)
    assert np.allclose(g, -2 * zeta / np.sqrt(1 - zeta ** 2), rtol=1e-12, atol=1e-15)
    assert np.all((g > 0) == (p.real > 0))
    assert np.allclose(damping_ratio(p), zeta, rtol=1e-12, atol=1e-15)
    assert np.allclose(vg_damping(wn * (0.01 + 1j)), 0.02)                   # g = 2 gamma
    # real roots and roots beyond |g| = 2 are clipped, with their sign
    assert vg_damping([5.0 + 0j, -5.0 + 0j, 30 + 10j, -30 - 10j]).tolist() == [2, -2, 2, -2]
    assert vg_damping(0j) == 0.0
    assert "> 0 unstable" in vg_damping_label() and "2 Re p / |Im p|" in vg_damping_label()


# ---------------------------------------------------------------------------------------------
# analyse: JSON, table and report figures of the fin (rigid pitch mode) and FV16 (none)
# ---------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def fin_json(tmp_path_factory):
    from asekit.__main__ import main
    out = tmp_path_factory.mktemp("conv") / "fin.json"
    assert main(["analyse", str(FIN), "--json", str(out), "--quiet"]) == 0
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def fin_analysis():
    from asekit.case import load_case
    from asekit.case.report import run_analysis
    return run_analysis(load_case(FIN))


def _keys_without_unit(node, units, out=None):
    """Keys of ``node`` (nested dicts / lists) holding a number, or a list of numbers, that
    ``units`` does not name. A key that ``units`` names covers everything below it (the
    AEM1/AEM2 or corner entries of ``settling_s``); other containers are searched."""
    out = set() if out is None else out
    if isinstance(node, list):
        for v in node:
            _keys_without_unit(v, units, out)
    elif isinstance(node, dict):
        for k, v in node.items():
            if k in units:
                continue
            vals = v if isinstance(v, list) else [v]
            if any(isinstance(x, (int, float)) and not isinstance(x, bool) for x in vals):
                out.add(k)
            _keys_without_unit(v, units, out)
    return out


def test_analyse_json_names_the_rigid_mode_and_numbers_elastic_modes_from_one(fin_json,
                                                                                fin_analysis):
    s = fin_json
    m = s["modes"]
    assert m["n_rigid"] == 1
    assert m["labels"] == ["rigid pitch"] + list(range(1, len(m["frequencies_hz"])))
    r0 = fin_analysis.flutter.results
    assert len(s["flutter"]) == len(r0)
    found = 0
    for row, r in zip(s["flutter"], r0):
        if r.flutter is None or r.unstable_at_start:
            assert row["mode"] is None
            continue
        found += 1
        # the p-k solution holds the rigid mode: column j is elastic mode j + 1
        assert r.pk.n_rigid == 0 and row["mode"] == r.flutter.mode + 1
        assert isinstance(row["mode"], int) and row["mode"] >= 1
        # the named mode is the one whose g crosses zero at the flutter speed
        j = [int(x.split()[-1]) for x in r.pk.mode_labels].index(row["mode"])
        g = r.pk.damping_g[:, j]
        U = r.pk.velocities
        assert g[U < 0.98 * row["speed_ms"]].max() < 0 < g[U > 1.02 * row["speed_ms"]].max()
        # and its frequency at flutter lies between its neighbours' structural frequencies
        f_el = m["frequencies_hz"][m["n_rigid"]:]
        lo = f_el[row["mode"] - 2] if row["mode"] >= 2 else 0.0
        hi = f_el[row["mode"]] if row["mode"] < len(f_el) else math.inf
        assert lo < row["frequency_hz"] < hi
    assert found


def test_analyse_json_gives_every_numeric_key_a_unit(fin_json):
    units = fin_json["units"]
    missing = _keys_without_unit({k: v for k, v in fin_json.items() if k != "units"}, units)
    assert not missing, f"keys without a unit in the JSON's units block: {sorted(missing)}"
    for key, suffix_unit in (("speed_ms", "m/s"), ("frequency_hz", "Hz"), ("altitude_m", "m"),
                             ("settling_s", "s"), ("fwtf_phase_margin_deg", "deg")):
        assert units[key].startswith(suffix_unit)
    assert "settling_ms" not in fin_json["ase"]          # a time, not m/s: seconds, as named
    assert all(v is None or 0 < v < 1 for v in fin_json["ase"]["settling_s"].values())


def test_analyse_table_names_modes(fin_json):
    from asekit.case.report import format_summary
    text = format_summary(fin_json)
    line = next(ln for ln in text.splitlines() if ln.startswith("modes (Hz):"))
    assert line.split(":", 1)[1].strip().startswith("mode 1 ") and "rigid pitch" in line
    assert "mode 0" not in text


def test_analyse_json_without_rigid_mode_numbers_from_one(tmp_path):
    """FV16 (n_rigid = 0: no rigid mode) numbers its first mode 1 too."""
    from asekit.__main__ import main
    out = tmp_path / "fv16.json"
    assert main(["analyse", str(FV16), "--json", str(out), "--quiet"]) == 0
    s = json.loads(out.read_text())
    assert s["modes"]["n_rigid"] == 0
    assert s["modes"]["labels"] == list(range(1, len(s["modes"]["frequencies_hz"]) + 1))
    assert all(r["mode"] is None or r["mode"] >= 1 for r in s["flutter"])


def test_report_figures_state_the_damping_convention(fin_analysis):
    import matplotlib.pyplot as plt

    from asekit.case.report import figures
    figs = {n: f.figure for n, f in figures(fin_analysis).items()}
    try:
        vg = [f for n, f in figs.items() if n.startswith("vg_")]
        assert len(vg) == len(fin_analysis.case.aero.machs)          # one per Mach
        for fig in vg:
            ax_g = fig.axes[0]                  # the first condition's g; f below it
            assert ax_g.get_ylabel() == vg_damping_label("p")
            assert "> 0 unstable" in ax_g.get_ylabel()
            assert "frequency (Hz)" in [ax.get_ylabel() for ax in fig.axes]
            names = [ln.get_label() for ln in ax_g.get_lines() if ln.get_label().startswith("mode")]
            assert names[:2] == ["mode 1", "mode 2"] and "mode 0" not in names
        # the curves are g of the p-k roots (not the damping ratio, not -g): the last Mach's
        # figure, its first panel is the first flight condition
        r = next(x for x in fin_analysis.flutter.results
                 if x.mach == fin_analysis.case.aero.machs[-1])
        lines = [ln for ln in vg[-1].axes[0].get_lines() if ln.get_label() == "mode 2"]
        assert np.allclose(lines[0].get_ydata(), vg_damping(r.pk.p[:, 1]))
        titles = [ax.get_title() for ax in figs["modes"].axes if ax.get_title()]
        assert titles[0].startswith(f"{RIGID_MODE_NAME}:") and titles[1].startswith("mode 1:")
        assert all("mode 0" not in t for t in titles)
        rl = [f for n, f in figs.items() if n.startswith("root_locus_")]
        assert rl and all("> 0 unstable" in f.axes[0].get_xlabel() for f in rl)
    finally:
        for f in figs.values():
            plt.close(f)


# ---------------------------------------------------------------------------------------------
# notebooks: printed mode lines go through the converter
# ---------------------------------------------------------------------------------------------
#: Patterns that number a mode by hand (bypassing asekit.util.conventions.mode_number/mode_label) or
#: plot a damping ratio as a V-g curve.
BYPASS = {
    "mode + 1": re.compile(r"\bmode\w*\s*\+\s*1\b"),
    "'elastic ' + str(...)": re.compile(r"""['"]elastic\s*['"]\s*\+\s*str\("""),
    "f'mode {j + 1}'": re.compile(r"""mode\s*\{\s*\w+\s*[+-]"""),
    "damping ratio on a V-g axis": re.compile(r"plot\([^)]*damping_ratio"),
}


def _code_cells():
    for nb in sorted(NOTEBOOKS.glob("*.ipynb")):
        for i, cell in enumerate(json.loads(nb.read_text())["cells"]):
            if cell["cell_type"] == "code":
                yield nb.name, i, "".join(cell["source"])


def test_notebooks_number_modes_through_the_converter():
    cells = list(_code_cells())
    assert len(cells) > 50
    bad = [(nb, i, what) for nb, i, src in cells for what, rx in BYPASS.items()
           if rx.search(src)]
    # a mode table counted with enumerate(..., 1) next to a 'mode' header also bypasses it
    bad += [(nb, i, "enumerate(..., 1) in a mode table") for nb, i, src in cells
            if "'mode'" in src and re.search(r"enumerate\(.*,\s*1\)\s*:", src)]
    assert not bad, f"notebook cells numbering modes by hand: {bad}"


def test_notebook_mode_table_prints_one_based_names():
    """Execute bring_your_own_surface's FV16 frequency table (cheap: one FE eigen-solution)
    and read its printed mode column: 1, 2, ..., 6."""
    src = next(s for nb, _, s in _code_cells() if nb == "bring_your_own_surface.ipynb"
               and "nafems_fv16.toml" in s and "NAFEMS Hz" in s)
    from asekit.case import load_case, pipeline
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(src, {"np": np, "pipeline": pipeline, "load_case": load_case,  # noqa: S102 (the cell)
                   "CASES_DIR": CASES_DIR})
    rows = buf.getvalue().splitlines()[1:]
    assert [r.split()[0] for r in rows] == [str(j) for j in range(1, 7)]
