"""AGARD 445.6 weakened wing 3 at M 0.96 with method "tsd" (data/cases/agard445_6_tsd.toml;
issue 29, tsdswept), through the command line as a user runs it."""

import json
import os
import subprocess
import sys

import pytest

from asekit.util.paths import CASES_DIR

#: Yates (1987), AGARD R-765 / NASA TM-100492, weakened wing 3 in air, M 0.960: the measured
#: flutter speed index.
FSI_EXPERIMENT = 0.3095


@pytest.mark.slow
def test_agard445_6_at_m096_with_tsd_lands_where_measured(tmp_path):
    """The number the shipped case reaches, not the experiment's: FSI 0.3995 on 8 x 8 boxes
    (16 x 8 TSD cells, 17784 nodes; about 90 s CPU on the project machine, measured with
    `asekit analyse data/cases/agard445_6_tsd.toml`), +29 % above the experiment's 0.3095.
    Measured on the same boxes: DLM 0.3419, TSD with zero thickness 0.4150, TSD without the
    cross-flow terms 0.4026. The bound is the swept linear limit's grid error
    (tests/aero/test_tsd_swept.py: the GAFs 28-63 % below the DLM's on the affordable grids),
    so this test holds the reached value (2 %: a change of solver or grid rule shows here) and
    that a supersonic pocket is present and stated; it does not claim the issue's 5 %."""
    env = dict(os.environ, ASEKIT_CACHE_DIR=str(tmp_path), MPLBACKEND="Agg")
    out = tmp_path / "s.json"
    run = subprocess.run([sys.executable, "-m", "asekit", "analyse", "--quiet", "--json",
                          str(out), str(CASES_DIR / "agard445_6_tsd.toml")],
                         capture_output=True, text=True, env=env, timeout=1800)
    assert run.returncode == 0, run.stderr[-2000:]
    s = json.loads(out.read_text())
    (row,) = s["flutter"]
    fsi = row["flutter_speed_index"]
    assert fsi == pytest.approx(0.3995, rel=0.02)
    assert fsi > FSI_EXPERIMENT            # the stated bound: not (yet) within 5 % of it
    (v,) = s["tsd_validity"]
    assert v["shock"] is True and v["mach"] == 0.96
