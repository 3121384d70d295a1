"""Sphinx extension of the asekit documentation site (loaded by ``docs/conf.py``).

- math offline: MathJax 2.7 of the ``jupyter-server-mathjax`` package is copied into the
  site's ``_static/mathjax`` (``conf.mathjax_path`` points there), so no page loads it from a
  CDN;
- ``|x|`` in docstrings (absolute values written as plain text) is escaped before
  reStructuredText reads it as a substitution reference;
- links between notebooks (``ch3_flutter.ipynb``) are mapped back to their documents under
  ``docs/notebooks`` (a symbolic link to ``notebooks/``, which Sphinx resolves).
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

from sphinx.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]


def mathjax_dir() -> Path:
    """The MathJax 2 tree (``MathJax.js``, ``config/``, ``jax/``, ``fonts/``) of the installed
    ``jupyter-server-mathjax`` package; ConfigError naming the ``pip install`` without it."""
    try:
        import jupyter_server_mathjax
    except ImportError:
        raise ConfigError("the docs need jupyter-server-mathjax (offline MathJax): "
                          "pip install -e '.[docs]'") from None
    path = Path(jupyter_server_mathjax.__file__).parent / "static"
    if not (path / "MathJax.js").is_file():
        raise ConfigError(f"MathJax.js not found in {path}: reinstall jupyter-server-mathjax")
    return path


_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")


def escape_bars(lines):
    """Escape ``|`` in the prose of a docstring (a list of lines, changed in place).

    The docstrings write absolute values and norms as plain text (``g = 2 Re p / |Im p|``),
    which reStructuredText reads as substitution references; only the rendered copy is changed
    (``help()`` and the doctests read the source). Literal blocks (after ``::``), doctest
    lines, inline literals and roles, and grid-table rows are left as they are.
    """
    literal_indent = None
    for i, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if stripped.endswith("::"):
            literal_indent = indent
        table_row = (stripped.startswith("|") and stripped.endswith("|")
                     and stripped.count("|") > 2)
        if (not stripped or table_row or stripped.startswith((">>>", "...", "+-", "+="))
                or "|" not in line):
            continue
        parts = _LITERAL.split(line)
        lines[i] = "".join(part if k % 2 else part.replace("|", r"\|")
                           for k, part in enumerate(parts))


def _escape_bars(app, what, name, obj, options, lines):
    escape_bars(lines)


def _copy_mathjax(app, exception):
    """Copy MathJax into ``_static/mathjax`` of an HTML build (``mathjax_path`` points there)."""
    if exception is None and app.builder.format == "html":
        shutil.copytree(mathjax_dir(), Path(app.outdir) / "_static" / "mathjax",
                        dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))


def _notebook_links(app, doctree):
    """Links between notebooks (``ch3_flutter.ipynb``) name documents of ``notebooks/``.

    ``docs/notebooks`` is a symbolic link; Sphinx resolves link targets through it to the real
    folder, outside the source tree, so they are mapped back to their documents here.
    """
    from sphinx import addnodes

    real = str(ROOT / "notebooks") + os.sep
    for node in doctree.findall(addnodes.pending_xref):
        target = node.get("reftarget", "")
        if node.get("reftype") == "myst" and target.startswith(real):
            node["reftarget"] = "notebooks/" + target[len(real):]


def setup(app):
    """Register the hooks (Sphinx extension entry point)."""
    mathjax_dir()                       # fail at the start, not after executing every notebook
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("doctree-read", _notebook_links)
    app.connect("build-finished", _copy_mathjax)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
