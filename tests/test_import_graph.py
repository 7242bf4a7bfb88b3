"""The project's import graph: no module imports itself back through others (imports
deferred into functions and ``TYPE_CHECKING`` blocks included), and nothing imports
upward (the objects describe furniture and never import the world that holds it)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("planners", "strug_manip", "perception")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in (ROOT / pkg).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out[name] = path
    return out


def _graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports anywhere in its text. ``from pkg import
    name`` counts as importing ``pkg`` (its ``__init__`` runs) and ``pkg.name`` if that
    is a module."""
    mods = _modules()

    def known(name: str) -> str | None:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name or None

    edges: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                targets = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            for t in targets:
                hit = known(t)
                if hit is not None and hit != mod:
                    edges[mod].add(hit)
    return edges


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def test_no_module_imports_itself_back() -> None:
    assert _cycles(_graph()) == []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_nothing_imports_upward() -> None:
    edges = _graph()
    below = {  # a layer -> the layers it must not import
        "planners": ("strug_manip", "perception"),
        "perception": ("strug_manip", "planners"),
        "strug_manip.objects": (
            "strug_manip.world",
            "strug_manip.control",
            "strug_manip.domains",
            "strug_manip.experiments",
        ),
        "strug_manip.world": ("strug_manip.control", "strug_manip.domains"),
        "strug_manip.control": ("strug_manip.domains", "strug_manip.experiments"),
    }
    wrong = [
        (mod, dep)
        for mod, deps in edges.items()
        for dep in deps
        for layer, banned in below.items()
        if (mod == layer or mod.startswith(layer + "."))
        and any(dep == b or dep.startswith(b + ".") for b in banned)
    ]
    assert wrong == []
