"""A published CBAR + CBEAM deck with PBARL / PBEAML ROD sections against its f06 (issue 24).

Reference: data/benchmarks/beam_modes (pyNastran's models/beam_modes deck and its Simcenter
Nastran 2019.2 f06): the REAL EIGENVALUES table's CYCLES column, printed to 7 digits.
"""

import os

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.io.bdf_beam import read_stick_deck, stick_modes  # noqa: E402
from asekit.util.paths import DATA_DIR  # noqa: E402

HERE = DATA_DIR / "benchmarks" / "beam_modes"
# beam_modes_f06_excerpt.txt, CYCLES (Hz), modes 1-10
F06_HZ = np.array([456.6603, 456.6603, 2674.588, 2674.588, 3554.923, 4507.487, 6626.104,
                   6626.104, 11111.59, 11111.59])


def _deck(tmp_path):
    """The deck with its include inlined and the README's edits (none changes Nastran's
    modes): $ASSIGN, USET, the unreferenced PROD and the unconnected GRID 12 dropped."""
    keep = []
    for line in (HERE / "beam_modes.dat").read_text().splitlines():
        if line.startswith(("$ASSIGN", "USET")):
            continue
        if line.startswith("INCLUDE"):
            keep += [x for x in (HERE / "cbar_cbeam.blk").read_text().splitlines()
                     if not x.startswith(("PROD", "GRID          12"))]
            continue
        keep.append(line)
    path = tmp_path / "beam_modes.bdf"
    path.write_text("\n".join(keep) + "\n")
    return path


def test_beam_modes_deck_matches_its_f06(tmp_path):
    """All ten modes (bending pairs, torsion, axial) to the f06's printed 7 digits: the PBARL
    / PBEAML ROD's shear factor 0.9 and the CBEAM's lumped polar mass as Nastran has them."""
    sm = read_stick_deck(_deck(tmp_path), units="in-lbf-s")
    assert not sm.coupled and "9 CBAR, 1 CBEAM" in sm.notes[0]
    f = stick_modes(sm, 10).frequencies_hz
    np.testing.assert_allclose(f, F06_HZ, rtol=2e-6)
