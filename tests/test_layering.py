"""The tests' layering (issue 21): outside ``tests/reproduction*`` no test imports the thesis
reproduction (``asekit.reproduction`` and its sub-modules: the chapters, the driver, the thesis
table, the widgets). The physics tests
take the reference fin from ``tests/conftest.py`` through ``asekit.case``; the reproduction
tests live in ``tests/reproduction/``.

Checked with the standard library's :mod:`ast` on every ``.py`` file under ``tests/``: ``import``
and ``from ... import`` statements (also ``from asekit import reproduction``) and calls whose
first argument is a string naming such a module (``importlib.import_module``, ``__import__``,
``pytest.importorskip``, ``monkeypatch.setattr("asekit.reproduction.x.y", ...)``,
``unittest.mock.patch``).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent

#: The reproduction layer: these modules and everything below them.
FORBIDDEN = ("asekit.reproduction",)

#: Files (relative to tests/) allowed to import the reproduction besides tests/reproduction*/:
#: the reproduction's own benchmarks (bench_freeplay times the freeplay chapter's
#: FinFreeplayModel, asekit.reproduction.freeplay).
EXEMPT = {"benchmarks/bench_reproduce.py", "benchmarks/bench_freeplay.py"}

#: Reproduction tests still outside tests/reproduction/ until the issue-21 layout moves them
#: there (a shrinking list: an entry whose file is gone fails test_pending_moves_exist).
PENDING_MOVE: set[str] = set()

_DOTTED = re.compile(r"asekit(\.\w+)+")


def _forbidden(module: str) -> bool:
    return any(module == f or module.startswith(f + ".") for f in FORBIDDEN)


def reproduction_imports(source: str, filename: str = "<source>") -> list[tuple[int, str]]:
    """(line, what) of every import of the reproduction layer in Python ``source``.

    Parameters
    ----------
    source : str
        The text of a Python file.
    filename : str
        Its name (for syntax errors).

    Returns
    -------
    list of (int, str)
        The line number and the statement or call found, in source order.
    """
    hits = []
    for node in ast.walk(ast.parse(source, filename)):
        if isinstance(node, ast.Import):
            hits += [(node.lineno, f"import {a.name}") for a in node.names if _forbidden(a.name)]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [a.name for a in node.names]
            if _forbidden(node.module):
                hits.append((node.lineno, f"from {node.module} import {', '.join(names)}"))
            else:
                bad = [n for n in names if _forbidden(f"{node.module}.{n}")]
                if bad:
                    hits.append((node.lineno, f"from {node.module} import {', '.join(bad)}"))
        elif isinstance(node, ast.Call) and node.args:
            a = node.args[0]
            if (isinstance(a, ast.Constant) and isinstance(a.value, str)
                    and _DOTTED.fullmatch(a.value) and _forbidden(a.value)):
                hits.append((node.lineno, f"{ast.unparse(node.func)}({a.value!r}, ...)"))
    return sorted(hits)


def _checked_files() -> list[Path]:
    out = []
    for path in sorted(TESTS.rglob("*.py")):
        rel = path.relative_to(TESTS)
        if any(part.startswith("reproduction") for part in rel.parts[:-1]):
            continue
        if rel.as_posix() in EXEMPT or (len(rel.parts) == 1 and rel.name in PENDING_MOVE):
            continue
        out.append(path)
    return out


def test_no_test_outside_tests_reproduction_imports_the_reproduction():
    files = _checked_files()
    assert len(files) > 30, f"only {len(files)} test files found under {TESTS}"
    found = []
    for path in files:
        rel = path.relative_to(TESTS).as_posix()
        found += [f"tests/{rel}:{line}: {what}"
                  for line, what in reproduction_imports(path.read_text(), str(path))]
    assert not found, ("these tests import the thesis reproduction; take the fin from "
                       "tests/conftest.py (asekit.case) or move the test to tests/reproduction/:"
                       "\n" + "\n".join(found))


def test_pending_moves_exist():
    gone = sorted(n for n in PENDING_MOVE if not (TESTS / n).exists())
    assert not gone, f"moved (remove them from PENDING_MOVE in tests/test_layering.py): {gone}"


@pytest.mark.parametrize("source, line", [
    ("import asekit.reproduction.fin", 1),
    ("import asekit.reproduction.driver as rp", 1),
    ("from asekit.reproduction.fin import load_fin", 1),
    ("from asekit.reproduction import design as dz", 1),
    ("from asekit import reproduction", 1),
    ("from asekit import case, reproduction", 1),
    ("from asekit.reproduction import thesis", 1),
    ("from asekit.reproduction.widgets import servo_panel", 1),
    ("from asekit.reproduction.thesis import all_keys", 1),         # after the move
    ("import importlib\n\nm = importlib.import_module('asekit.reproduction.flutter')", 3),
    ("m = __import__('asekit.reproduction.thesis')", 1),
    ("def f(mp):\n    mp.setattr('asekit.reproduction.flutter.load_fin_gafs', None)", 2),
    ("import pytest\npytest.importorskip('asekit.reproduction.widgets')", 2),
])
def test_the_check_finds_every_form(source, line):
    hits = reproduction_imports(source)
    assert [h[0] for h in hits] == [line], hits


@pytest.mark.parametrize("source", [
    "import asekit.case\nfrom asekit.case import pipeline",
    "from asekit import ase, case, structure",
    "import asekit.reproductions_of_nothing",       # a different name, not a sub-module
    "from asekit.thesis_free import x",
    '"""Compare with asekit.reproduction.design.elastic_problem."""',   # prose, no import
    "x = dict(reason='the removed asekit.reproduction.fin.fin_surface')",
])
def test_the_check_passes_other_code(source):
    assert reproduction_imports(source) == []
