"""asekit.aero.validity: Mach numbers and reduced frequencies are real numbers (issue 22)."""

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import normalwash_matrix
from asekit.aero.validity import SUBSONIC, check_k, check_mach, mach_number


@pytest.mark.parametrize("k, error, word", [
    (0.1 + 0.5j, TypeError, "k must be real numbers"),
    (np.complex128(0.1 + 0.5j), TypeError, "k must be real numbers"),
    ([0.1, 0.2 + 1e-3j], TypeError, r"k\[1\]"),
    ("0.1", ValueError, "k must be real numbers, got the string"),
])
def test_check_k_refuses_complex_and_strings(k, error, word):
    with pytest.raises(error, match=word):
        check_k(k)


@pytest.mark.parametrize("mach, error", [("0.5", ValueError), (np.complex128(0.5 + 1j), TypeError),
                                         (True, TypeError)])
def test_mach_must_be_a_real_number(mach, error):
    with pytest.raises(error, match="mach must be a real number"):
        mach_number(mach)
    with pytest.raises(error, match="mach must be a real number"):
        check_mach(mach, SUBSONIC)


def test_numpy_reals_still_accepted():
    assert mach_number(np.float32(0.5)) == 0.5 and check_k(np.float64(0.2))[0] == 0.2


@pytest.mark.parametrize("kw, error, word", [
    ({"b_ref": "1.0"}, ValueError, "b_ref must be a real number"),
    ({"k": 0.1 + 0.5j}, TypeError, "k must be real numbers"),
    ({"mach": "0.5"}, ValueError, "mach must be a real number"),
])
def test_dlm_refuses_loose_types(kw, error, word):
    """Issue 22's reproducer: the DLM accepted b_ref = "1.0" (float("1.0")) and a complex k was
    an unnamed TypeError of float()."""
    mesh = mesh_surfaces([TrapezoidSurface((0.0, 0.1, 0.0), 1.0, (0.3, 1.5, 0.0), 0.6, 2, 2)])
    a = {"mach": 0.5, "k": 0.1, "b_ref": 1.0} | kw
    with pytest.raises(error, match=word):
        normalwash_matrix(mesh, a["mach"], a["k"], a["b_ref"])
