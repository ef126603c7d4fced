"""The package's import graph has no cycles, counting imports inside functions: every
``import`` and ``from ... import`` of a ``liegroup_int`` module is an edge, and the graph's
strongly connected components must all be single modules."""

from __future__ import annotations

import ast
from pathlib import Path

import liegroup_int

ROOT = Path(liegroup_int.__file__).parent


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _targets(node, module: str, is_package: bool, modules: set[str]) -> set[str]:
    """The package modules an import statement loads (a ``from pkg import name`` of a
    submodule counts as that submodule)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = module if is_package else module.rpartition(".")[0]
        for _ in range(node.level - 1):
            base = base.rpartition(".")[0]
        src = (base + "." + node.module if node.module else base) if node.level else (node.module or "")
        names = [src] + [src + "." + a.name for a in node.names]
    return {n for n in names if n in modules}


def import_graph() -> dict[str, set[str]]:
    files = {_module_name(p): p for p in ROOT.rglob("*.py")}
    modules = set(files)
    graph = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        edges = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                edges |= _targets(node, name, path.name == "__init__.py", modules)
        graph[name] = edges - {name}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
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
                out.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return out


def _ignoring_packages(graph):
    """Package ``__init__`` modules re-export their children; an edge into a package's own
    ``__init__`` from inside it is the re-export direction, not a layer breach."""
    return {m: {t for t in ts if not (m.startswith(t + "."))} for m, ts in graph.items()}


def test_the_graph_sees_known_edges():
    g = import_graph()
    assert "liegroup_int.integrators.engine" in g["liegroup_int.integrators.compiled_group"]
    assert "liegroup_int.groups" in g["liegroup_int.integrators.compiled_group"]


def test_no_import_cycles():
    cycles = _cycles(_ignoring_packages(import_graph()))
    assert cycles == [], "import cycles: " + "; ".join(" <-> ".join(c) for c in cycles)
