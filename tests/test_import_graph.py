"""The package's import graph has no cycle (issue 30).

The graph is built from the source with ``ast``: every ``import`` and ``from ... import``
statement of every module, at module level or inside a function (a function-level import
that closes a cycle still ties the two modules together), except those under
``if TYPE_CHECKING:``, which never run. ``from . import x`` is an edge to the submodule ``x``
where one exists, else to the package. Modules inside the package import the submodules they
need, never the facade ``brdfkit`` itself: the facade imports them.
"""

from __future__ import annotations

import ast
from pathlib import Path

import brdfkit

SRC = Path(brdfkit.__file__).parent


def _modules() -> dict[str, Path]:
    out = {}
    for path in SRC.rglob("*.py"):
        parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _imports(tree: ast.AST):
    """Every import statement, skipping the bodies of ``if TYPE_CHECKING:``."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node):
            stack.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        stack.extend(ast.iter_child_nodes(node))


def _longest_known(name: str, mods) -> str | None:
    while name and name not in mods:
        name = name.rpartition(".")[0]
    return name or None


def _targets(mod: str, is_pkg: bool, node, mods) -> set[str]:
    out = set()
    if isinstance(node, ast.Import):
        for a in node.names:
            t = _longest_known(a.name, mods)
            if t:
                out.add(t)
        return out
    if node.level:
        base = (mod if is_pkg else mod.rpartition(".")[0]).split(".")
        base = base[: len(base) - (node.level - 1)]
        full = ".".join(base + ([node.module] if node.module else []))
    else:
        full = node.module or ""
    for a in node.names:
        t = f"{full}.{a.name}" if f"{full}.{a.name}" in mods else _longest_known(full, mods)
        if t:
            out.add(t)
    return out


def import_graph() -> dict[str, set[str]]:
    mods = _modules()
    graph = {}
    for mod, path in mods.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        is_pkg = path.name == "__init__.py"
        graph[mod] = {t for node in _imports(tree) for t in _targets(mod, is_pkg, node, mods) if t != mod}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each as a sorted list."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_the_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_the_graph_sees_function_level_and_relative_imports():
    g = import_graph()
    assert "brdfkit.registry" in g["brdfkit.models.ward"]  # from ..registry import register
    assert "brdfkit.sources" in g["brdfkit.cli_common"]  # a function-level import
    assert len(g) > 60


def test_no_import_cycle():
    found = cycles(import_graph())
    detail = "; ".join(" <-> ".join(c) for c in found)
    assert not found, f"import cycles: {detail}"


def test_no_module_imports_the_facade():
    g = import_graph()
    users = sorted(m for m, ts in g.items() if "brdfkit" in ts and m not in ("brdfkit.__main__",))
    assert users == [], f"modules importing the brdfkit facade (import the submodule instead): {users}"
