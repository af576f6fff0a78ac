"""The modules of bayestribo.inference import downwards only: no import circles.

The graph is read from the source (the AST), so an import inside a function counts as
much as one at the top of a module; only imports under ``if TYPE_CHECKING:`` (never
run) are left out. A circle held apart by moving one of its imports into a function is
still a circle: the stages of a fit import the stages before them, never after.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import bayestribo.inference

PACKAGE = "bayestribo.inference"
FOLDER = Path(bayestribo.inference.__file__).resolve().parent


def _is_type_checking(test: ast.expr) -> bool:
    """Whether an ``if`` test is ``TYPE_CHECKING`` or ``typing.TYPE_CHECKING``."""
    if isinstance(test, ast.Name):
        return test.id == "TYPE_CHECKING"
    return isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"


def _runtime_imports(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    """Every import statement that can run, inside functions too, not TYPE_CHECKING's."""
    found: list[ast.Import | ast.ImportFrom] = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.append(node)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def _modules() -> dict[str, Path]:
    """The package's modules by short name (``__init__`` aside: it re-exports lazily)."""
    return {p.stem: p for p in sorted(FOLDER.glob("*.py")) if p.stem != "__init__"}


def _target(name: str, modules: dict[str, Path]) -> str | None:
    """The package module a dotted import name lands in, if any."""
    if not name.startswith(PACKAGE + "."):
        return None
    short = name[len(PACKAGE) + 1 :].split(".")[0]
    return short if short in modules else None


def import_graph() -> dict[str, set[str]]:
    """Each module of bayestribo.inference and the package modules it imports."""
    modules = _modules()
    lazy = bayestribo.inference._LAZY
    graph: dict[str, set[str]] = {}
    for short, path in modules.items():
        edges: set[str] = set()
        for node in _runtime_imports(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif node.level:  # relative: from . import x, from .x import y
                base = node.module or ""
                names = [f"{PACKAGE}.{base}".rstrip(".")]
                if not base:
                    names = [f"{PACKAGE}.{a.name}" for a in node.names]
            elif node.module == PACKAGE:  # from bayestribo.inference import name
                names = [lazy.get(a.name, f"{PACKAGE}.{a.name}") for a in node.names]
            else:
                names = [node.module or ""]
            for name in names:
                target = _target(name, modules)
                if target is not None and target != short:
                    edges.add(target)
        graph[short] = edges
    return graph


def cycles(graph: dict[str, set[str]]) -> list[tuple[list[str], list[str]]]:
    """Each strongly connected part of more than one module, with one circle in it.

    Tarjan's algorithm finds the parts; a breadth-first search inside each part gives
    a shortest circle through its first module, which names it.
    """
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    parts: list[list[str]] = []

    def connect(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                connect(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            part = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                part.append(top)
                if top == node:
                    break
            if len(part) > 1:
                parts.append(sorted(part))

    for node in sorted(graph):
        if node not in index:
            connect(node)

    circles = []
    for part in parts:
        start, members = part[0], set(part)
        previous: dict[str, str] = {}
        frontier = [start]
        found = None
        while frontier and found is None:
            following = []
            for node in frontier:
                for nxt in sorted(graph[node] & members):
                    if nxt == start:
                        found = node
                        break
                    if nxt not in previous:
                        previous[nxt] = node
                        following.append(nxt)
                if found is not None:
                    break
            frontier = following
        path = [found]
        while path[-1] != start:
            path.append(previous[path[-1]])
        circles.append(([*reversed(path), start], part))
    return circles


def test_the_search_finds_a_circle_and_only_circles():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [
        (["a", "b", "c", "a"], ["a", "b", "c"])
    ]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_the_graph_sees_imports_inside_functions_not_type_checking(tmp_path):
    source = (
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n"
        "    from bayestribo.inference.a import A\n"
        "def f():\n"
        "    from bayestribo.inference.b import B\n"
    )
    names = [n.module for n in _runtime_imports(ast.parse(source)) if isinstance(n, ast.ImportFrom)]
    assert names == ["typing", "bayestribo.inference.b"]


def test_the_graph_covers_every_module():
    graph = import_graph()
    assert set(graph) == set(_modules())
    assert any(graph.values()), "no import between the modules was found"


def test_no_import_circles():
    found = cycles(import_graph())
    if found:
        pytest.fail(
            "import circles in bayestribo.inference: "
            + "; ".join(
                f"{' -> '.join(c)} (in the circle of {', '.join(sorted(set(p)))})" for c, p in found
            )
        )
