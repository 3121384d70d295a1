"""The documentation site's sources (docs/, issue 30): every public module has an API page,
every notebook is in the gallery, the user guide holds the markdown guides, and the docstring
filter of docs/_ext/asekit_docs.py escapes only prose. Building the site (sphinx-build -W,
every notebook executed) is .ci/run's step, not a unit test."""

import importlib.util
import pkgutil
import re
from pathlib import Path

import pytest

import asekit

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _public_modules():
    return ["asekit"] + sorted(
        m.name for m in pkgutil.walk_packages(asekit.__path__, "asekit.")
        if not any(part.startswith("_") for part in m.name.split(".")[1:]))


def _toctree_entries(text):
    """Entries of the MyST (```{toctree}) and rst (.. toctree::) toctrees in ``text``."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        s = lines[i].strip()
        i += 1
        if s.startswith("```{toctree}"):
            while not lines[i].strip().startswith("```"):
                out.append(lines[i].strip())
                i += 1
        elif s.startswith(".. toctree::"):
            while i < len(lines) and (not lines[i].strip() or lines[i][0].isspace()):
                out.append(lines[i].strip())
                i += 1
    return [e for e in out if e and not e.startswith(":")]


def test_every_public_module_has_an_api_page_in_the_tree():
    pages = {p.stem for p in (DOCS / "api").glob("asekit*.rst")}
    modules = _public_modules()
    assert len(modules) > 70
    assert sorted(set(modules) - pages) == [], "run the page list again: a module has no page"
    assert sorted(pages - set(modules)) == [], "an API page names no module"
    for name in modules:
        text = (DOCS / "api" / f"{name}.rst").read_text()
        assert f".. automodule:: {name}" in text
        parent = name.rpartition(".")[0]
        if parent:                                # reachable: listed by its package's page
            assert name in _toctree_entries((DOCS / "api" / f"{parent}.rst").read_text())


def test_gallery_lists_every_notebook():
    notebooks = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert len(notebooks) >= 11
    listed = _toctree_entries((DOCS / "gallery.md").read_text())
    assert sorted(listed) == [f"notebooks/{n}" for n in notebooks]
    assert (DOCS / "notebooks").resolve() == (ROOT / "notebooks").resolve()


def test_user_guide_holds_the_markdown_guides():
    index = _toctree_entries((DOCS / "index.md").read_text())
    for page in ("getting-started", "case-format", "conventions", "sweeps", "nastran",
                 "architecture", "gallery", "api/index"):
        assert page in index
        assert any((DOCS / f"{page}{ext}").is_file() for ext in (".md", ".rst"))
    assert "{include} ../README.md" in (DOCS / "getting-started.md").read_text()


def test_conf_needs_no_network():
    conf = (DOCS / "conf.py").read_text()
    assert "sphinx.ext.intersphinx" not in conf
    assert not re.search(r"https?://", conf)
    assert re.search(r'^mathjax_path = "mathjax/MathJax\.js', conf, re.M)


@pytest.fixture(scope="module")
def ext():
    pytest.importorskip("sphinx", reason="the [docs] extra")
    spec = importlib.util.spec_from_file_location("asekit_docs", DOCS / "_ext" / "asekit_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_bars_escaped_in_prose_only(ext):
    lines = ["g = 2 Re p / |Im p| (``|x|`` and :math:`|y|` kept)",
             "|D_1| = amplitude",
             "A formula::",
             "",
             "    f = |d - p|",
             "",
             "Back to |prose|.",
             ">>> abs(-1) | 0",
             "| a | b | c |"]
    ext.escape_bars(lines)
    assert lines == [r"g = 2 Re p / \|Im p\| (``|x|`` and :math:`|y|` kept)",
                     r"\|D_1\| = amplitude",
                     "A formula::",
                     "",
                     "    f = |d - p|",
                     "",
                     r"Back to \|prose\|.",
                     ">>> abs(-1) | 0",
                     "| a | b | c |"]


def test_offline_mathjax_is_installed(ext):
    pytest.importorskip("jupyter_server_mathjax", reason="the [docs] extra (environment.txt)")
    path = ext.mathjax_dir()
    assert (path / "config" / "TeX-AMS-MML_HTMLorMML-full.js").is_file()
    assert (path / "jax" / "output" / "HTML-CSS" / "fonts" / "STIX-Web" / "fontdata.js").is_file()
