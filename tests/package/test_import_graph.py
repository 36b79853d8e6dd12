"""The package's import graph: no circle of imports between wmiltrack's modules, and the
network code (``wmiltrack.networks``) below the engine, the command line and the evaluation.

Every ``import`` counts, at the top of a module or inside a function: a circle closed by a
function-level import still ties the modules together (neither can be understood, tested or
moved without the other), and only works by the accident of when the function runs."""

from __future__ import annotations

import ast
from pathlib import Path

from conftest import REPO_ROOT

PKG = REPO_ROOT / "src" / "wmiltrack"

#: Packages the network code must not import: they are built on it.
ABOVE_NETWORKS = ("wmiltrack.engine", "wmiltrack.cli", "wmiltrack.eval")


def _module_name(path: Path) -> str:
    parts = ("wmiltrack", *path.relative_to(PKG).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in sorted(PKG.rglob("*.py"))}


def _known() -> set[str]:
    """The module names of the package: its Python files and its compiled modules (by their
    stubs, ``_core.pyi``), which import nothing of wmiltrack."""
    return set(_modules()) | {_module_name(p) for p in PKG.rglob("*.pyi")}


def _targets(node: ast.Import | ast.ImportFrom, module: str, is_package: bool,
             known: set[str]) -> set[str]:
    """The wmiltrack modules one import statement reaches (``from . import x`` reaches the
    module ``x`` where it is one, else the package)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = module.split(".") if is_package else module.split(".")[:-1]
            base = base[: len(base) - (node.level - 1)]
            mod = ".".join(base + ([node.module] if node.module else []))
        else:
            mod = node.module or ""
        names = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in known else mod for a in node.names]
    out = set()
    for name in names:
        while name and name not in known:  # `import wmiltrack.eval.metrics as m`: that module
            name = name.rpartition(".")[0]
        if name.startswith("wmiltrack"):
            out.add(name)
    return out


def import_graph() -> dict[str, set[str]]:
    """Each module of wmiltrack -> the wmiltrack modules it imports (anywhere in it; a
    package's ``__init__`` reached through ``a.b.c`` is not counted as an edge to ``a.b``)."""
    modules = _modules()
    known = _known()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        edges: set[str] = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                edges |= _targets(node, name, path.name == "__init__.py", known)
        edges.discard(name)
        graph[name] = edges
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One circle of ``graph`` as the list of its modules (the first repeated at the end), or
    None."""
    colour: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        colour[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if colour.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in colour:
                found = visit(nxt)
                if found:
                    return found
        path.pop()
        colour[node] = 2
        return None

    for start in sorted(graph):
        if start not in colour:
            found = visit(start)
            if found:
                return found
    return None


def test_the_package_has_no_import_circle() -> None:
    graph = import_graph()
    assert len(graph) > 50 and "wmiltrack.engine.tracker" in graph
    cycle = find_cycle(graph)
    assert cycle is None, "import circle: " + " -> ".join(cycle or [])


def test_the_network_code_imports_no_higher_layer() -> None:
    graph = import_graph()
    networks = {m: e for m, e in graph.items() if m.startswith("wmiltrack.networks")}
    assert "wmiltrack.networks.files" in networks
    bad = {m: sorted(t for t in e if t.startswith(ABOVE_NETWORKS)) for m, e in networks.items()}
    bad = {m: t for m, t in bad.items() if t}
    assert not bad, f"the network code imports from above it: {bad}"


def test_the_checks_see_function_level_imports_and_circles() -> None:
    """The checker itself: a circle closed by an import inside a function is found, and
    relative imports resolve to the modules they name."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None
    tree = ast.parse("def f():\n    from ..engine.frames import as_frame\n    from . import cli\n")
    known = {"wmiltrack.engine.frames", "wmiltrack.cli", "wmiltrack.trackers", "wmiltrack"}
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found |= _targets(node, "wmiltrack.cli.options", False, known)
    assert found == {"wmiltrack.engine.frames", "wmiltrack.cli"}
