"""One figure style for every asekit plot.

Every chapter figure is made through :func:`new_figure`, so labels, fonts and sizes agree, and
its title carries the thesis figure number it reproduces. Every V-g / V-f figure draws its
curves through :func:`plot_vg`, so the damping convention of docs/conventions.md (g = 2 Re p /
|Im p|, > 0 unstable, stated on the axis; elastic modes named from 1) lives in one place.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

from asekit.util.conventions import vg_damping, vg_damping_label

STYLE = {
    "figure.dpi": 100,
    "savefig.dpi": 120,
    "font.size": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.titlesize": 11,
    "legend.fontsize": 9,
    "lines.linewidth": 1.5,
}

THESIS_COLOR = "0.45"   # grey: thesis values / rigid-fin references
ASEKIT_COLOR = "C0"


def new_figure(title: str, thesis_figure: str | None = None, nrows: int = 1, ncols: int = 1,
               figsize: tuple[float, float] | None = None, **subplot_kw):
    """Create a figure in the asekit style.

    Parameters
    ----------
    title : what the figure shows.
    thesis_figure : the thesis figure it reproduces, e.g. ``"Fig 53"``; prefixed to the title.
    nrows, ncols, figsize, subplot_kw : passed to :func:`matplotlib.pyplot.subplots`.

    Returns
    -------
    (fig, axes) as from :func:`matplotlib.pyplot.subplots`.
    """
    if figsize is None:
        figsize = (6.4 * ncols if ncols > 1 else 6.4, 3.6 * nrows + 0.6)
    # The first figure of a Jupyter session loads the inline backend, which switches interactive
    # mode on (that is what makes the kernel show figures at the end of a cell). Done inside
    # ``rc_context`` that switch would be undone on exit (rc_context restores every rcParam but
    # the backend, ``interactive`` included) and no later figure would be shown; so the style
    # stays local to the figure's creation and the interactive state is carried out of it.
    with matplotlib.rc_context(STYLE):
        fig, axes = plt.subplots(nrows, ncols, figsize=figsize, squeeze=True, **subplot_kw)
        full = f"{thesis_figure}: {title}" if thesis_figure else title
        fig.suptitle(full)
        for ax in (axes.flat if hasattr(axes, "flat") else [axes]):
            if hasattr(ax, "grid"):
                ax.grid(True, alpha=STYLE["grid.alpha"])
        interactive = matplotlib.is_interactive()
    matplotlib.interactive(interactive)
    return fig, axes


def save_figure(fig, directory: str | Path, name: str) -> Path:
    """Save ``fig`` as ``directory/name.png`` and close it; returns the path.

    A figure made with ``layout="constrained"`` keeps its title, legends and colour bars inside
    the image by its own layout; any other figure gets
    :meth:`~matplotlib.figure.Figure.tight_layout` and is cut to its drawn content
    (``bbox_inches="tight"``, one more draw) so that a title or a legend outside the axes is
    never clipped.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.png"
    with matplotlib.rc_context(STYLE):
        if fig.get_layout_engine() is None:
            fig.tight_layout()
            fig.savefig(path, bbox_inches="tight", pad_inches=0.1)
        else:
            fig.savefig(path)
    plt.close(fig)
    return path


def plot_vg(ax_g, ax_f, velocities, roots, labels, root: str = "p", g_limits=(-1.0, 0.5)):
    """V-g and V-f curves of tracked roots on two axes, in the convention of
    docs/conventions.md.

    Parameters
    ----------
    ax_g, ax_f : matplotlib axes for the damping g and the frequency (Hz).
    velocities : (n_v,) airspeeds (any unit; the caller labels the x axis).
    roots : (n_v, n_t) complex roots p = sigma + i omega (1/s), one column per tracked mode.
    labels : n_t legend labels (use :func:`asekit.util.conventions.mode_label`, e.g.
        ``PkResult.mode_labels``: "mode 1", "mode 2", ..., "rigid pitch").
    root : the eigenvalue's symbol in the axis label ("p" for p-k, "lambda" for A_sys).
    g_limits : (low, high) clip of the g axis to the data (None: matplotlib's limits).

    Plotted: g = 2 Re p / |Im p| (:func:`asekit.util.conventions.vg_damping`, > 0 unstable) on
    ``ax_g`` with the zero line, f = |Im p| / 2 pi on ``ax_f``; the g axis label says
    "damping g = 2 Re p / |Im p| (-), > 0 unstable". Returns the g array (n_v, n_t).
    """
    p = np.asarray(roots, dtype=complex)
    if p.ndim != 2 or p.shape[0] != np.size(velocities) or len(labels) != p.shape[1]:
        raise ValueError(f"roots must be (n_v, n_t) with n_v = len(velocities) and n_t = "
                         f"len(labels); got roots {p.shape}, {np.size(velocities)} velocities, "
                         f"{len(labels)} labels")
    g = vg_damping(p)
    f = np.abs(p.imag) / (2 * np.pi)
    for j, name in enumerate(labels):
        ax_g.plot(velocities, g[:, j], label=name)
        ax_f.plot(velocities, f[:, j])
    ax_g.axhline(0.0, color="k", lw=0.8)
    ax_g.set_ylabel(vg_damping_label(root))
    ax_f.set_ylabel("frequency (Hz)")
    if g_limits is not None:
        lo, hi = ax_g.get_ylim()
        ax_g.set_ylim(max(lo, g_limits[0]), min(hi, g_limits[1]))
    return g
