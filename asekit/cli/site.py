"""A static HTML site of the executed chapter notebooks: ``python -m asekit.cli.site OUTDIR``.

Each chapter notebook (``notebooks/ch*.ipynb``, in reading order) is executed in a fresh kernel
with the inline matplotlib backend, as JupyterLab runs it, and converted to HTML with nbconvert
(figures embedded), so a reader can browse every figure without running anything.
The executed notebooks are written beside the pages. ``OUTDIR/index.html`` links the chapters
and lists how many figures each one displays; links between notebooks (``chX.ipynb``) are
rewritten to the HTML pages. Widgets (the live panels) are
shown as their static last state at most.

Options: ``--only ch4_servo_actuator ...`` builds selected notebooks; ``--timeout`` per cell (s).
"""

from __future__ import annotations

import argparse
import html
import os
import re
import sys
import time
from pathlib import Path

NOTEBOOK_DIR = Path(__file__).resolve().parents[2] / "notebooks"
#: Reading order of the chapter notebooks.
ORDER = ("ch2_theory", "ch3_structure", "ch3_aerodynamics", "ch3_flutter",
         "ch4_servo_actuator", "ch5_aeroservoelasticity")


def chapter_notebooks(only=None) -> list[Path]:
    """The chapter notebooks in reading order (``only``: a subset of their stems)."""
    found = {p.stem: p for p in NOTEBOOK_DIR.glob("ch*.ipynb")}
    names = [n for n in ORDER if n in found] + sorted(set(found) - set(ORDER))
    if only:
        unknown = sorted(set(only) - set(found))
        if unknown:
            raise ValueError(f"unknown notebook(s) {unknown}; valid: {names}")
        names = [n for n in names if n in set(only)]
    return [found[n] for n in names]


def execute_notebook(path: Path, timeout: float = 900.0):
    """Execute ``path`` in a fresh python3 kernel with the inline backend (the test session's or
    shell's MPLBACKEND is not passed on) in the notebook's directory; returns the notebook."""
    import nbclient
    import nbformat

    nb = nbformat.read(path, as_version=4)
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    # startup_timeout: on a loaded machine the kernel can take more than the default 60 s
    client = nbclient.NotebookClient(nb, timeout=timeout, startup_timeout=300,
                                     kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute(env=env)
    return nb


def figure_count(nb) -> int:
    """Number of figures (PNG outputs) a notebook displays."""
    return sum("image/png" in o.get("data", {}) for c in nb.cells if c.cell_type == "code"
               for o in c.get("outputs", []))


def _title(nb, fallback: str) -> str:
    for c in nb.cells:
        if c.cell_type == "markdown":
            for line in c.source.splitlines():
                if line.startswith("# "):
                    return line[2:].strip()
    return fallback


def _rewrite_links(text: str) -> str:
    """Links to sibling notebooks point to their HTML pages."""
    return re.sub(r'href="(\./)?(ch[\w-]+)\.ipynb(#[^"]*)?"',
                  lambda m: f'href="{m.group(2)}.html{m.group(3) or ""}"', text)


def build_site(outdir, only=None, timeout: float = 900.0, echo=print) -> list[dict]:
    """Execute the chapter notebooks and write ``outdir/<notebook>.html`` and
    ``outdir/index.html``. Returns one record per notebook: name, title, figures, seconds."""
    import nbformat
    from nbconvert import HTMLExporter

    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise ValueError(f"outdir must be a directory, got the file {outdir}")
    outdir.mkdir(parents=True, exist_ok=True)
    exporter = HTMLExporter()
    records = []
    for path in chapter_notebooks(only):
        t0 = time.perf_counter()
        nb = execute_notebook(path, timeout)
        body, _ = exporter.from_notebook_node(nb)
        (outdir / f"{path.stem}.html").write_text(_rewrite_links(body), encoding="utf-8")
        nbformat.write(nb, outdir / f"{path.stem}.ipynb")        # the executed notebook too
        rec = {"name": path.stem, "title": _title(nb, path.stem), "figures": figure_count(nb),
               "seconds": round(time.perf_counter() - t0, 1)}
        records.append(rec)
        echo(f"{path.stem}: {rec['figures']} figures, {rec['seconds']} s")
    items = "\n".join(
        f'<li><a href="{r["name"]}.html">{html.escape(r["title"])}</a> '
        f'<small>({r["figures"]} figures; executed in {r["seconds"]} s)</small></li>'
        for r in records)
    (outdir / "index.html").write_text(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>asekit chapter notebooks"
        "</title></head>\n<body style=\"font-family: sans-serif; max-width: 50em; margin: 2em "
        "auto\">\n<h1>asekit: the thesis reproduction, chapter by chapter</h1>\n<p>Executed "
        "notebooks of <code>notebooks/</code> (built "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
        ") with every figure displayed where it is drawn.</p>\n<ol>\n" + items
        + "\n</ol>\n</body></html>\n", encoding="utf-8")
    return records


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m asekit.cli.site", description=__doc__.splitlines()[0])
    ap.add_argument("outdir", help="directory for the HTML pages (created if absent)")
    ap.add_argument("--only", nargs="+", metavar="NOTEBOOK", help="notebook stems to build")
    ap.add_argument("--timeout", type=float, default=900.0, help="per-cell timeout (s)")
    args = ap.parse_args(argv)
    try:
        build_site(args.outdir, args.only, args.timeout)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"site written to {Path(args.outdir) / 'index.html'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
