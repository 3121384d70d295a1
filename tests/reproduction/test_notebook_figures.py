"""Every chapter figure reaches the reader: the notebooks executed as JupyterLab runs them.

nbval runs the notebooks with the Agg backend and compares no images, so it cannot see a figure
that is drawn but never displayed. This test executes each chapter notebook in a fresh kernel
with the *inline* backend (the kernel's default, as in JupyterLab) and a probe cell prepended
that records, for every cell, which figures are open when it starts and which are still open
after the inline backend has displayed (and closed) the cell's figures. It checks that

* no figure is left undisplayed: after every cell no figure is open (the inline backend closes
  each figure it displays);
* every figure a cell displays was created by that cell: no figure is open when a cell starts;
* the import cell (the first code cell) displays no figure.

Slow (all six chapter notebooks: about 100 s on an idle two-core machine, 4 min on a loaded
one; the first run after a change to the physics also recomputes the cached converged-flutter
study of ch3_flutter, several minutes): marked ``slow``; the default ``pytest`` deselects it,
``pytest -m slow`` (and CI, .ci/run) runs it.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NOTEBOOKS = sorted((Path(__file__).resolve().parents[2] / "notebooks").glob("ch*.ipynb"))

# Runs first in the kernel: records the open figures when each later cell starts and after it
# ends (post_run_cell comes after the inline backend's end-of-cell flush, which closes every
# figure it displays).
PROBE = r'''
import matplotlib._pylab_helpers as _asekit_ph
_asekit_probe = []          # one record per executed cell after this one, in order
def _asekit_open():
    return sorted(m.num for m in _asekit_ph.Gcf.get_all_fig_managers())
def _asekit_pre(info):
    _asekit_probe.append({"open_at_start": _asekit_open()})
def _asekit_post(result):
    if _asekit_probe:
        _asekit_probe[-1]["open_after_flush"] = _asekit_open()
get_ipython().events.register("pre_run_cell", _asekit_pre)
get_ipython().events.register("post_run_cell", _asekit_post)
'''
REPORT = "import json; print(json.dumps(_asekit_probe))"


#: Per-cell timeout (s). A cell that builds an ipywidgets panel gets a short one: nbclient can
#: block on such a cell, intermittently, with the kernel already idle (jupyter/nbclient issue
#: 312, open; seen here twice in CI, the second time in ch4_servo_actuator's servo-panel cell,
#: 920 s of a 1069 s slow run), and the panels take about a second to build, so the retry of
#: :func:`_execute_probed` starts after 120 s instead of 900 s. The other cells keep 900 s (the
#: first run after a physics change recomputes ch3_flutter's cached converged study).
TIMEOUT_S, WIDGET_TIMEOUT_S = 900, 120


def _cell_timeout(cell) -> int:
    return WIDGET_TIMEOUT_S if "widgets" in cell.get("source", "") else TIMEOUT_S


def _execute(path: Path):
    """Execute ``path`` with the inline backend and the probe cells; returns the notebook."""
    nb = nbformat.read(path, as_version=4)
    nb.cells.insert(0, nbformat.v4.new_code_cell(PROBE))
    nb.cells.append(nbformat.v4.new_code_cell(REPORT))
    # the test session's MPLBACKEND=Agg (conftest) must not reach the kernel: ipykernel then
    # selects matplotlib-inline itself, as in JupyterLab
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    # startup_timeout: on a loaded machine the kernel can take more than the default 60 s
    client = nbclient.NotebookClient(nb, timeout=TIMEOUT_S, timeout_func=_cell_timeout,
                                     startup_timeout=300,
                                     kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute(env=env)
    return nb


def _execute_probed(path: Path):
    """:func:`_execute`, once more in a fresh kernel if the first run's client waited for a
    cell past its timeout or lost its kernel: seen once in CI (2026-12-03), a kernel idle in
    its event loop while nbclient still waited for the cell's reply (a lost message, not the
    notebook: the same notebook passed in the default run's nbval). A notebook that hangs or
    dies twice fails."""
    try:
        nb = _execute(path)
    except (nbclient.exceptions.CellTimeoutError, nbclient.exceptions.DeadKernelError):
        nb = _execute(path)
    text = "".join(o.get("text", "") for o in nb.cells[-1].outputs if o.get("name") == "stdout")
    return nb, json.loads(text)


def _images(cell) -> int:
    return sum("image/png" in o.get("data", {}) for o in cell.get("outputs", []))


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_every_figure_is_displayed_by_the_cell_that_draws_it(path):
    nb, probe = _execute_probed(path)
    code = [c for c in nb.cells[1:-1] if c.cell_type == "code" and c.source.strip()]
    assert code, f"{path.name}: no code cells"
    assert len(probe) == len(code) + 1, "the probe did not see every cell"
    problems = []
    for i, cell in enumerate(code):
        rec = probe[i]
        head = cell.source.strip().splitlines()[0][:70] if cell.source.strip() else ""
        if rec["open_at_start"]:
            problems.append(f"cell {i} ({head!r}) starts with figures {rec['open_at_start']} "
                            "left open by an earlier cell")
        if rec.get("open_after_flush"):
            problems.append(f"cell {i} ({head!r}) leaves {len(rec['open_after_flush'])} "
                            "figure(s) undisplayed")
    n_import = _images(code[0])
    if n_import:
        problems.append(f"the import cell displays {n_import} figure(s)")
    assert not problems, f"{path.name}:\n  " + "\n  ".join(problems)
    # the notebook draws something at all (every chapter notebook reproduces figures)
    assert sum(_images(c) for c in code) > 0, f"{path.name}: no figure displayed"
