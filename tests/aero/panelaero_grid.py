"""Convert an asekit BoxMesh to a PanelAero ``aerogrid`` dict (tests and benchmarks only).

PanelAero (DLR, PyPI ``panelaero``) is an independent doublet-lattice implementation; asekit
itself never imports it. Its reduced frequency is omega / U (1/m), so asekit's k = omega b / U
becomes k / b there, and its matrices carry the opposite sign convention (Qjj = -inv(Ajj) with
Ajj = our normalwash matrix D), see tests/aero/test_dlm.py.
"""

import numpy as np


def panelaero_grid(mesh):
    """The aerogrid dict PanelAero's VLM/DLM expect, built from the same boxes."""
    n = mesh.n
    return {
        "offset_j": np.array(mesh.control_point, float),
        "offset_k": np.array(mesh.load_point, float),
        "offset_l": np.array(mesh.load_point, float),
        "offset_P1": np.array(mesh.doublet_p1, float),
        "offset_P3": np.array(mesh.doublet_p3, float),
        "N": np.array(mesh.normal, float),
        "A": np.array(mesh.area, float),
        "l": np.array(mesh.chord, float),
        "n": n,
    }
