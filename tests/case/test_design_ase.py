"""AEM1 margins of the fin and their analytic design derivatives (issue 28), against central
differences of the whole chain: the case re-analysed at a perturbed thickness (plate matrices,
held-transmission modes, GAFs through the DLM, Roger refit, ASE loop, refined crossovers)."""

import copy
import tomllib

import numpy as np
import pytest

from asekit.case import case_from_dict
from asekit.case import pipeline as P
from asekit.case.design_ase import _operators, ase_margins
from asekit.case.schema import CaseError
from asekit.util.paths import FIN_FILE

pytestmark = pytest.mark.usefixtures("session_gaf_cache")
PATHS = ("thickness.root", "thickness.tip")


def _raw() -> dict:
    raw = tomllib.loads(FIN_FILE.read_text())
    raw["panel"][0].update(n_chord=4, n_span=4)
    raw["modes"] = {"count": 3, "keep_rigid": True}
    raw["aero"].update(machs=[0.4, 0.6], boxes=[{"n_chord": 4, "n_span": 4}],
                       reduced_frequencies=[0.001, 0.1, 0.25, 0.45, 0.8])
    return raw


CASE = case_from_dict(copy.deepcopy(_raw()), "small fin with actuator")


@pytest.fixture(scope="module")
def ops():
    return _operators(CASE, CASE.actuator.mach)


def test_margin_derivatives_match_central_differences(ops):
    r = ase_margins(CASE, PATHS, operators=ops)
    # the loop is the case's FWTF 2: its phase margin agrees with the pipeline's (grid +
    # linear interpolation there; FN2 fictitious-mass modes there, held-transmission modes
    # here, O(J_fin / I_f) apart)
    ref = P.ase(CASE).crossovers[2].phase_margin_deg
    assert r.phase_margin_deg == pytest.approx(ref, abs=0.05)
    for j in range(len(PATHS)):
        e = np.zeros(len(PATHS))
        e[j] = 1e-6 * r.values[j]
        up = ase_margins(CASE, PATHS, r.values + e, operators=ops).phase_margin_deg
        down = ase_margins(CASE, PATHS, r.values - e, operators=ops).phase_margin_deg
        fd = (up - down) / (2 * e[j])
        assert r.d_phase_margin_deg[j] == pytest.approx(fd, rel=1e-4), PATHS[j]


def test_needs_an_actuator():
    raw = _raw()
    raw.pop("actuator")
    with pytest.raises(CaseError, match=r"no \[actuator\]"):
        ase_margins(case_from_dict(raw, "no actuator"), PATHS)
