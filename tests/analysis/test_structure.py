"""Import structure of the analysis package's top-level modules (issue #14).

Imports run one way (no cycle, not even through function-level imports), no module imports
another module's private (``_name``) names, and analysis modules are imported at module level
only (imports under ``if TYPE_CHECKING:`` are for annotations and do not count), except in the
accessor, which imports on use (issue 16).
"""

from __future__ import annotations

import ast
from pathlib import Path

import analysis

PACKAGE = Path(analysis.__file__).parent
MODULES = sorted(p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__")


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(path: Path) -> list[tuple[str, list[str], bool]]:
    """``(module, names, at_module_level)`` of every runtime ``analysis.*`` import."""
    found: list[tuple[str, list[str], bool]] = []

    def visit(node: ast.AST, top: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                continue
            if isinstance(child, ast.ImportFrom) and (child.module or "").startswith("analysis"):
                found.append((child.module or "", [a.name for a in child.names], top))
            elif isinstance(child, ast.Import):
                for a in child.names:
                    if a.name.startswith("analysis"):
                        found.append((a.name, [], top))
            inner = top and not isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef
            )
            visit(child, inner)

    visit(ast.parse(path.read_text()), True)
    return found


def _graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for m in MODULES:
        deps = set()
        for module, _names, _top in _imports(PACKAGE / f"{m}.py"):
            parts = module.split(".")
            if len(parts) >= 2 and parts[1] in MODULES:
                deps.add(parts[1])
        graph[m] = deps
    return graph


def test_no_private_names_imported_across_modules():
    bad = [
        f"{m}: from {module} import {name}"
        for m in MODULES
        for module, names, _top in _imports(PACKAGE / f"{m}.py")
        for name in names
        if name.startswith("_")
    ]
    assert not bad, bad


# The accessor is registered by `import analysis`; it imports the modules it forwards to when
# a method is called, so that importing the package costs xarray only (issue 16: 0.3 s instead
# of 1.8 s). Its imports still count for the one-way layering below.
LAZY = {"accessor", "checks"}  # checks: the memory budget lives in analysis.readers, which
# imports checks (a module-level import would be a cycle)


def test_analysis_modules_are_imported_at_module_level_only():
    bad = [
        f"{m}: {module}"
        for m in MODULES
        if m not in LAZY
        for module, _names, top in _imports(PACKAGE / f"{m}.py")
        if not top
    ]
    assert not bad, bad


def test_imports_run_one_way():
    graph = _graph()
    order: list[str] = []
    state: dict[str, int] = {}

    def visit(m: str, path: list[str]) -> None:
        if state.get(m) == 1:
            raise AssertionError("import cycle: " + " -> ".join([*path, m]))
        if state.get(m) == 2:
            return
        state[m] = 1
        for d in sorted(graph[m]):
            visit(d, [*path, m])
        state[m] = 2
        order.append(m)

    for m in MODULES:
        visit(m, [])
    # the layering this package promises: a module imports only modules listed before it
    layers = ["checks", "jit", "fft", "windows", "levels", "plots", "inputs", "spectrum",
              "sinc", "resample", "frames", "maps", "orders", "accessor"]
    for i, m in enumerate(layers):
        assert not graph[m] & set(layers[i + 1 :]), f"{m} imports {graph[m] & set(layers[i:])}"


def _all_modules() -> list[Path]:
    """Every module of both packages (gearvib and analysis, sub-packages included)."""
    import gearvib

    roots = [PACKAGE, Path(gearvib.__file__).parent]
    return sorted(p for root in roots for p in root.rglob("*.py"))


def test_no_private_names_imported_anywhere():
    """No module of gearvib or analysis imports another module's private (``_name``) names."""
    bad = []
    for path in _all_modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] in (
                    "gearvib", "analysis"):
                bad += [f"{path.name}: from {node.module} import {a.name}" for a in node.names
                        if a.name.startswith("_") and not a.name.startswith("__")]
    assert not bad, bad
