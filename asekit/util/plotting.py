"""One figure style for every asekit plot.

Every chapter figure is made through :func:`new_figure`, so labels, fonts and sizes agree, and
its title carries the thesis figure number it reproduces.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

import matplotlib.pyplot as plt

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
    """Save ``fig`` as ``directory/name.png`` (tight layout) and close it; returns the path."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{name}.png"
    with matplotlib.rc_context(STYLE):
        fig.tight_layout()
        fig.savefig(path)
    plt.close(fig)
    return path
