"""The chapter figures the notebooks and the site show follow docs/conventions.md: V-g axes plot
g = 2 Re/|Im| and say "> 0 unstable" (the thesis's damping ratio is not plotted), elastic modes
are named from 1, structural damping g and the modal damping ratio are named apart."""

from __future__ import annotations

import numpy as np

from asekit.aeroelastic.flutter import Instability, PkResult, RootLocusResult
from asekit.util.conventions import vg_damping, vg_damping_label


def _roots():
    """Two modes over 5 speeds: the second crosses to Re p > 0 at the fourth speed."""
    U = np.linspace(100.0, 300.0, 5)
    w = 2 * np.pi * np.array([90.0, 150.0])
    sigma = np.array([[-5, -20], [-8, -10], [-12, -3], [-18, 4], [-25, 12]], float)
    return U, sigma + 1j * w


def test_pk_and_root_locus_figures_plot_g_positive_unstable():
    import matplotlib.pyplot as plt

    from asekit.reproduction import flutter as rf
    U, p = _roots()
    pk = PkResult(velocities=U, p=p, k=np.zeros(p.shape), vectors=np.ones((5, 2, 2), complex),
                  converged=np.ones(p.shape, bool), structural_frequencies_hz=np.array([90, 150.]),
                  density=1.225)
    rl = RootLocusResult(velocities=U, eigenvalues=p, elastic=p, max_real=p.real.max(axis=1),
                         density=1.225)
    fl = Instability("flutter", 1, 262.0, 150.0, method="p-k")
    for fig, root in ((rf.fig_pk(pk, flutter=fl), "p"),
                      (rf.fig_root_locus_damping(rl, flutter=fl), "lambda")):
        try:
            ax_g = fig.axes[0]
            assert ax_g.get_ylabel() == vg_damping_label(root)
            assert "> 0 unstable" in ax_g.get_ylabel()
            lines = {ln.get_label(): ln for ln in ax_g.get_lines()}
            assert {"mode 1", "mode 2"} <= set(lines) and "mode 0" not in lines
            g2 = lines["mode 2"].get_ydata()
            assert np.allclose(g2, vg_damping(p[:, 1]))
            assert g2[2] < 0 < g2[3]                      # the unstable root plots positive
        finally:
            plt.close(fig)
    assert fl.describe().endswith("(mode 2, p-k)")


def test_damping_study_names_structural_g_and_modal_ratio_apart():
    import matplotlib.pyplot as plt

    from asekit.reproduction import flutter as rf
    rows = [{"kind": "zeta", "value": 0.0, "speed": 218.0, "freq": 141.0},
            {"kind": "zeta", "value": 0.01, "speed": 250.0, "freq": 142.0},
            {"kind": "g", "value": 0.02, "speed": 251.0, "freq": 142.0}]
    fig = rf.fig_damping_study(rows)
    try:
        labels = [ln.get_label() for ln in fig.axes[0].get_lines()]
        assert "modal damping ratio zeta" in labels
        assert any(lb.startswith("structural damping g") for lb in labels)
    finally:
        plt.close(fig)
