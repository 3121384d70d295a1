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
    """The number the shipped case reaches: FSI 0.3237 on 8 x 8 boxes (16 x 8 TSD cells, 17784
    nodes; 79 s CPU on the project machine, measured with `asekit analyse
    data/cases/agard445_6_tsd.toml`), +4.6 % from the experiment's 0.3095 (Yates 1987), inside
    the issue's 5 % (0.3223, +4.1 %, before issue 29's tsdfin step made the harmonic time term
    upwind at the 110 supersonic-pocket nodes; 251 s wall on the loaded machine, 2026-12-04). Measured on the same boxes: DLM 0.3419 (+10.5 %). The tolerance (2 %)
    holds the reached value so that a change of solver or grid rule shows here; the grid is
    coarse (the swept linear limit's GAFs +1.9 % to +30 % from the DLM's on 16 x 8 to 8 x 4
    cells, tests/aero/test_tsd_swept.py). A supersonic pocket is present and stated."""
    env = dict(os.environ, ASEKIT_CACHE_DIR=str(tmp_path), MPLBACKEND="Agg")
    out = tmp_path / "s.json"
    run = subprocess.run([sys.executable, "-m", "asekit", "analyse", "--quiet", "--json",
                          str(out), str(CASES_DIR / "agard445_6_tsd.toml")],
                         capture_output=True, text=True, env=env, timeout=1800)
    assert run.returncode == 0, run.stderr[-2000:]
    s = json.loads(out.read_text())
    (row,) = s["flutter"]
    fsi = row["flutter_speed_index"]
    assert fsi == pytest.approx(0.3237, rel=0.02)
    assert abs(fsi / FSI_EXPERIMENT - 1.0) < 0.05          # issue 29's "Done when" criterion
    (v,) = s["tsd_validity"]
    assert v["shock"] is True and v["mach"] == 0.96
