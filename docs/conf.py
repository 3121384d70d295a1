"""Sphinx configuration of the asekit documentation site (issue 30).

Build (from the repository root, after ``pip install -e '.[docs]'``)::

    sphinx-build -W --keep-going -b html docs docs/_build/html

or ``python -m asekit.cli.site OUTDIR``. The site is built without the network: the API reference
comes from the docstrings (numpydoc), the user guide from the markdown files of ``docs/`` and the
README (MyST), the gallery from every notebook of ``notebooks/`` executed during the build
(myst-nb; ``docs/notebooks`` is a link to that folder), and the math is typeset by the MathJax 2
that the ``jupyter-server-mathjax`` package ships, copied into the site's ``_static/mathjax``.
No intersphinx, no CDN. ``-D nb_execution_mode=cache`` reuses executed notebooks between builds
(jupyter-cache, beside the output folder); the default executes every notebook afresh.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))        # the checkout's asekit, also when it is not installed
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import asekit  # noqa: E402

project = "asekit"
author = "The asekit developers"
copyright = "2026, The asekit developers"
release = asekit.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
    "asekit_docs",
]

root_doc = "index"
exclude_patterns = ["_build", "**/.ipynb_checkpoints", "notebooks/img/*"]
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}

# --- API reference: autodoc + numpydoc; the stub pages are committed (docs/api/), so the build
# never writes into the source tree (autosummary_generate off)
autosummary_generate = False
autodoc_default_options = {"members": True, "member-order": "bysource"}
autodoc_typehints = "none"          # the numpydoc Parameters sections carry the types and units
autodoc_mock_imports: list[str] = []
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# --- MyST (markdown pages and notebooks)
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
myst_update_mathjax = False          # MathJax 2 below is configured through mathjax2_config

# --- notebooks: executed during the build, each cell at most nb_execution_timeout seconds; an
# error in any cell fails the build
nb_execution_mode = "force"
nb_execution_timeout = 900
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
nb_ipywidgets_js: dict = {}          # no widget manager from a CDN: panels show their last state
# figures inline: the kernels inherit this process's environment (a shell's MPLBACKEND=Agg would
# leave every figure undrawn)
os.environ.pop("MPLBACKEND", None)

# --- math offline: MathJax 2.7 of the jupyter-server-mathjax package, copied into _static by
# the asekit_docs extension (docs/_ext/asekit_docs.py)
mathjax_path = "mathjax/MathJax.js?config=TeX-AMS-MML_HTMLorMML-full"
# the package ships the STIX-Web fonts only (as the Jupyter notebook configures them)
mathjax2_config = {
    "HTML-CSS": {"availableFonts": [], "preferredFont": None, "webFont": "STIX-Web",
                 "imageFont": None},
    "SVG": {"font": "STIX-Web"},
    "menuSettings": {"zoom": "None"},
}

# --- HTML
html_theme = "pydata_sphinx_theme"
html_title = f"asekit {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_static_path: list[str] = []
html_show_sourcelink = False
html_copy_source = False
