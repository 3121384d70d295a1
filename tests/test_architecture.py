"""The package's shape (issue 21, ``docs/architecture.md``), checked with the standard library's
``ast``: few top-level modules, no import cycle between asekit's modules (imports inside
functions included), and the layers one way: physics <- case <- applications.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "asekit"

#: the layers, lowest first; a module may import only from its own layer or the ones below.
#: ``asekit.io`` reads decks into cases, so it sits above the case layer.
LAYERS = (
    ("utilities", ("asekit.util",)),
    ("physics", ("asekit.geometry", "asekit.atmosphere", "asekit.structure", "asekit.aero",
                 "asekit.rfa", "asekit.aeroelastic", "asekit.servo", "asekit.ase")),
    ("case", ("asekit.case",)),
    ("io and sweeps", ("asekit.io", "asekit.sweep")),
    ("applications", ("asekit.reproduction", "asekit.cli", "asekit.__main__")),
)


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = p.relative_to(ROOT).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    return out


MODULES = _modules()


def _resolve(name: str) -> str | None:
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def _imports(path: Path, module: str) -> list[tuple[int, str]]:
    """(line, imported asekit module) of every import in the file, wherever it stands."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            names = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        for n in names:
            r = _resolve(n) if n.startswith("asekit") else None
            if r and r != module and not module.startswith(r + "."):
                found.append((node.lineno, r))
    return found


GRAPH = {m: {r for _, r in _imports(p, m)} for m, p in MODULES.items()}


def _layer(module: str) -> int:
    for i, (_, prefixes) in enumerate(LAYERS):
        if any(module == p or module.startswith(p + ".") for p in prefixes):
            return i
    if module == "asekit":
        return len(LAYERS)                   # the public API may re-export anything
    raise AssertionError(f"{module} belongs to no layer of tests/test_architecture.py: add it")


def test_top_level_holds_at_most_ten_modules():
    top = sorted(p.name for p in PKG.glob("*.py"))
    assert len(top) <= 10, f"asekit/ has {len(top)} top-level modules: {top}"


def test_every_module_has_a_layer():
    for m in MODULES:
        _layer(m)


def test_no_import_cycle():
    """Tarjan's strongly connected components of the module import graph."""
    index, low, stack, on, cycles = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m != "asekit"))
def test_imports_go_down_the_layers(module):
    """Physics knows no case, the case layer no application; nothing below the applications
    imports the thesis reproduction."""
    mine = _layer(module)
    up = [(line, r) for line, r in _imports(MODULES[module], module)
          if r != "asekit" and _layer(r) > mine]
    assert not up, (f"{module} ({LAYERS[mine][0]}) imports from a higher layer: "
                    + ", ".join(f"line {line}: {r} ({LAYERS[_layer(r)][0]})" for line, r in up))


def _top_level_imports(tree):
    """The import statements that run when the module is imported: at its top, also inside
    top-level ``try`` / ``if`` blocks (not inside functions or classes)."""
    out, todo = [], list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            out.append(node)
        elif isinstance(node, (ast.Try, ast.If, ast.With)):
            todo += node.body + getattr(node, "orelse", []) + getattr(node, "finalbody", [])
            for h in getattr(node, "handlers", []):
                todo += h.body
    return out


def test_optional_packages_are_not_imported_at_module_top():
    """The wheel's dependencies are numpy, scipy, control, matplotlib, tqdm and threadpoolctl
    (pyproject.toml); numba, pandas, dask, pyNastran, ipywidgets and the notebook tools are
    optional, so no asekit module imports them at its top (a function imports them when
    used)."""
    import sys
    allowed = {"numpy", "scipy", "control", "matplotlib", "tqdm", "threadpoolctl", "asekit"}
    optional_only = {"asekit.aero._dlm_compiled"}        # the numba kernel itself
    bad = []
    for module, path in MODULES.items():
        if module in optional_only:
            continue
        for node in _top_level_imports(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0
                     else [])
            for n in names:
                top = n.split(".")[0]
                if top not in allowed and top not in sys.stdlib_module_names and top != "__future__":
                    bad.append(f"{module}: {n}")
    assert not bad, f"optional packages imported at module top: {bad}"
    # and the numba kernel is reached only from inside functions
    for module in ("asekit.aero.dlm", "asekit.aero.vlm"):
        top = [n for n in _top_level_imports(ast.parse(MODULES[module].read_text()))
               if "_dlm_compiled" in ast.unparse(n)]
        assert not top, f"{module} imports the numba kernel at its top"
