"""The documentation site: ``python -m asekit.cli.site OUTDIR``, a thin wrapper of sphinx-build.

Builds the Sphinx site of ``docs/`` (user guide, API reference, every notebook of
``notebooks/`` executed into the gallery; ``docs/conf.py``) with warnings as errors,

    sphinx-build -W --keep-going -b html docs OUTDIR/html

(the pages in ``OUTDIR/html``; myst-nb's executed notebooks and cache beside them, so nothing
is written outside OUTDIR), then checks the built pages offline (:func:`check_site`): every local link and image exists,
every ``#anchor`` names an element of its page, and no page loads a script, style sheet, image
or frame from the network. The sources live in a checkout of the repository, not in the
installed package: without them (e.g. from a wheel) the command says so in one line and exits 2.

Options: ``--timeout`` per notebook cell (s); ``--cache`` reuses notebooks executed by an
earlier build into the same OUTDIR (jupyter-cache); ``--check-only`` checks an existing build.
Exit status: 0 built and checked, 1 the build or the check failed, 2 bad input or missing
sources.
"""

from __future__ import annotations

import argparse
import re
import sys
import time
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

#: The repository root of this checkout (the package's parent folder).
ROOT = Path(__file__).resolve().parents[2]
#: Attributes that name a resource the page loads (not a link the reader follows).
_LOADED = {("script", "src"), ("link", "href"), ("img", "src"), ("iframe", "src"),
           ("source", "src"), ("video", "src"), ("audio", "src"), ("embed", "src"),
           ("object", "data"), ("input", "src")}
_URL_IN_CSS = re.compile(r"""url\(\s*['"]?([^'")]+)['"]?\s*\)|@import\s+['"]([^'"]+)['"]""")
#: MathJax files the offline math needs (loaded by MathJax.js at run time, so no page names
#: them): the loader, its configuration, the TeX input and the STIX-Web fonts' metrics.
MATHJAX_FILES = ("_static/mathjax/MathJax.js",
                 "_static/mathjax/config/TeX-AMS-MML_HTMLorMML-full.js",
                 "_static/mathjax/jax/output/HTML-CSS/fonts/STIX-Web/fontdata.js")


def docs_sources(root: Path | None = None) -> tuple[Path, Path]:
    """The documentation sources of a checkout: ``(docs, notebooks)`` folders.

    Parameters
    ----------
    root : pathlib.Path, optional
        The repository root (default :data:`ROOT`, the checkout this module is in).

    Returns
    -------
    tuple of pathlib.Path
        ``root / "docs"`` (with ``conf.py``) and ``root / "notebooks"`` (with the notebooks).

    Raises
    ------
    FileNotFoundError
        One of them is missing (an installed wheel has neither), with a one-line message.

    Examples
    --------
    >>> from pathlib import Path
    >>> docs_sources(Path("/nonexistent"))
    Traceback (most recent call last):
    ...
    FileNotFoundError: the documentation sources are not here (no /nonexistent/docs/conf.py): build the site from a checkout of the repository (git clone, then pip install -e '.[docs]')
    """
    root = ROOT if root is None else Path(root)
    docs, notebooks = root / "docs", root / "notebooks"
    for need in (docs / "conf.py", notebooks):
        if not need.exists():
            raise FileNotFoundError(
                f"the documentation sources are not here (no {need}): build the site from a "
                f"checkout of the repository (git clone, then pip install -e '.[docs]')")
    if not any(notebooks.glob("*.ipynb")):
        raise FileNotFoundError(f"no notebook in {notebooks}: the gallery needs them (build the "
                                f"site from a checkout of the repository)")
    return docs, notebooks


class _Page(HTMLParser):
    """The ids, the loaded resources and the followed links of one HTML page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.loaded: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if value is None:
                continue
            if name in ("id", "name") and (name == "id" or tag == "a"):
                self.ids.add(value)
            elif (tag, name) in _LOADED:
                self.loaded.append(value)
            elif name == "href":
                self.links.append(value)
            elif name == "srcset":
                self.loaded += [part.split()[0] for part in value.split(",") if part.strip()]


def _is_remote(url: str) -> bool:
    parts = urlsplit(url)
    return bool(parts.scheme in ("http", "https", "ftp") or url.startswith("//"))


def _is_local(url: str) -> bool:
    parts = urlsplit(url)
    return not parts.scheme and not url.startswith("//")


def _target(page: Path, url: str) -> tuple[Path, str]:
    """The file a local ``url`` of ``page`` names (a folder's index.html) and its fragment."""
    parts = urlsplit(url)
    path = page if not parts.path else (page.parent / unquote(parts.path))
    if parts.path.endswith("/") or path.is_dir():
        path = path / "index.html"
    return path, unquote(parts.fragment)


def _css_problems(css: Path, root: Path) -> list[str]:
    problems = []
    text = css.read_text(encoding="utf-8", errors="replace")
    for m in _URL_IN_CSS.finditer(text):
        url = (m.group(1) or m.group(2) or "").strip()
        if _is_remote(url):
            problems.append(f"{css.relative_to(root)}: loads {url} from the network")
        elif _is_local(url) and not url.startswith("data:") and urlsplit(url).path \
                and not _target(css, url)[0].exists():
            problems.append(f"{css.relative_to(root)}: missing {url}")
    return problems


def _page_problems(html: Path, page: _Page, root: Path, pages: dict) -> list[str]:
    """The problems of one parsed page ``html`` of the site in ``root`` (all pages: ``pages``)."""
    name, problems = html.relative_to(root), []
    for url in page.loaded:
        if _is_remote(url):
            problems.append(f"{name}: loads {url} from the network")
        elif _is_local(url) and not url.startswith("data:") and not _target(html, url)[0].exists():
            problems.append(f"{name}: missing {url}")
    for url in page.links:
        if not _is_local(url) or url.startswith(("data:", "javascript:")):
            continue
        path, fragment = _target(html, url)
        if not path.exists():
            problems.append(f"{name}: broken link {url}")
        elif fragment and path.suffix == ".html":
            target = pages.get(path.resolve())
            if target is not None and fragment not in target.ids:
                problems.append(f"{name}: broken link {url} (no id {fragment!r} in "
                                f"{path.resolve().relative_to(root)})")
    return problems


def check_site(outdir) -> list[str]:
    """Offline check of a built HTML site: one line per problem, none when it is sound.

    A page is an HTML file outside ``_static`` (which holds the theme's templates). A problem
    is a page that loads a script, style sheet, image, frame or media file from the
    network (``http(s)://`` or ``//``; links the reader may follow to the web are allowed), a
    local link or loaded file that does not exist, a ``#fragment`` naming no element of its
    target page, a style sheet whose ``url()`` or ``@import`` points to the network or to a
    missing file, or a missing file of the offline MathJax (:data:`MATHJAX_FILES`, when any
    page loads MathJax).

    Parameters
    ----------
    outdir : str or pathlib.Path
        The folder of the built site (sphinx-build's output folder, with ``index.html``), or
        the folder of :func:`build` holding it as ``html/``.

    Returns
    -------
    list of str
        The problems, each ``page: what``; empty for a sound site.

    Raises
    ------
    ValueError
        ``outdir`` is not a folder holding ``index.html``.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "index.html").write_text('<a href="gone.html">x</a><a href="#top">y</a>'
    ...                                   '<script src="https://cdn.example/m.js"></script>')
    >>> for line in check_site(d): print(line)
    index.html: loads https://cdn.example/m.js from the network
    index.html: broken link gone.html
    index.html: broken link #top (no id 'top' in index.html)
    """
    root = Path(outdir)
    if not (root / "index.html").is_file() and (root / "html" / "index.html").is_file():
        root = root / "html"
    if not (root / "index.html").is_file():
        raise ValueError(f"outdir must be a built site holding index.html, got {root}")
    pages, problems = {}, []
    for html in sorted(root.rglob("*.html")):
        if "_static" in html.relative_to(root).parts:    # theme templates, not pages
            continue
        page = _Page()
        page.feed(html.read_text(encoding="utf-8", errors="replace"))
        pages[html.resolve()] = page
    uses_mathjax = False
    for html, page in pages.items():
        problems += _page_problems(html, page, root.resolve(), pages)
        uses_mathjax |= any("mathjax/MathJax.js" in url for url in page.loaded)
    for css in sorted(root.rglob("*.css")):
        problems += _css_problems(css, root)
    if uses_mathjax:
        problems += [f"offline MathJax: missing {f}" for f in MATHJAX_FILES
                     if not (root / f).is_file()]
    return problems


def build(outdir, timeout: float = 900.0, cache: bool = False, echo=print) -> int:
    """Build the site into ``outdir/html`` with sphinx-build (warnings are errors), then check it.

    Parameters
    ----------
    outdir : str or pathlib.Path
        Output folder (created if absent; must not be a file): the pages go to ``html/``,
        myst-nb's executed notebooks (``jupyter_execute/``) and cache (``.jupyter_cache/``)
        beside them.
    timeout : float
        Per-cell timeout of the notebook execution (s), > 0.
    cache : bool
        Reuse notebooks executed by an earlier build into the same ``outdir``
        (``nb_execution_mode=cache``; jupyter-cache beside ``outdir``) instead of executing
        every notebook afresh.
    echo : callable
        Where the summary line goes.

    Returns
    -------
    int
        sphinx-build's exit status, or 1 when the built site fails :func:`check_site`.

    Raises
    ------
    FileNotFoundError
        The documentation sources are not present (:func:`docs_sources`).
    ValueError
        A bad ``outdir`` or ``timeout``.
    ImportError
        Sphinx (the ``[docs]`` extra) is not installed.
    """
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise ValueError(f"outdir must be a directory, got the file {outdir}")
    if not timeout > 0:
        raise ValueError(f"--timeout must be > 0 s, got {timeout}")
    docs, _ = docs_sources()
    try:
        from sphinx.cmd.build import build_main
    except ImportError:
        raise ImportError("the documentation site needs Sphinx: pip install -e '.[docs]'") \
            from None
    t0 = time.perf_counter()
    status = build_main(["-W", "--keep-going", "-b", "html",
                         "-D", f"nb_execution_timeout={int(round(timeout))}",
                         "-D", f"nb_execution_mode={'cache' if cache else 'force'}",
                         str(docs), str(outdir / "html")])
    if status:
        return status
    problems = check_site(outdir / "html")
    for line in problems:
        print(f"error: {line}", file=sys.stderr)
    pages = sum(1 for f in (outdir / "html").rglob("*.html") if "_static" not in f.parts)
    echo(f"site written to {outdir / 'html' / 'index.html'}: {pages} pages in "
         f"{time.perf_counter() - t0:.0f} s" + (f", {len(problems)} problems" if problems else ""))
    return 1 if problems else 0


def main(argv=None) -> int:
    """The command line: ``python -m asekit.cli.site OUTDIR [--timeout S] [--cache]
    [--check-only]``; returns the exit status."""
    ap = argparse.ArgumentParser(prog="python -m asekit.cli.site",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("outdir", help="output folder (created if absent): the pages go to "
                    "OUTDIR/html")
    ap.add_argument("--timeout", type=float, default=900.0,
                    help="per-cell timeout of the notebook execution (s)")
    ap.add_argument("--cache", action="store_true",
                    help="reuse notebooks executed by an earlier build into OUTDIR")
    ap.add_argument("--check-only", action="store_true",
                    help="only check an existing build in OUTDIR (links, images, no network)")
    args = ap.parse_args(argv)
    try:
        if args.check_only:
            problems = check_site(args.outdir)
            for line in problems:
                print(f"error: {line}", file=sys.stderr)
            print(f"{args.outdir}: {len(problems)} problems")
            return 1 if problems else 0
        return build(args.outdir, args.timeout, args.cache)
    except (ValueError, FileNotFoundError, ImportError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
