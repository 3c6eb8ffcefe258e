"""The package's import structure: no import circles, and synthesis stays pure.

The imports are read from the source (``ast``), not executed: both those at a
module's top and those inside its functions count, since a function-level
import that closes a circle is a circle all the same (it only hides it until
the function runs).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "ftc_mc"


def modules(package: Path | None = None) -> dict[str, tuple[Path, bool]]:
    """Dotted module name -> (file, is a package's ``__init__``)."""
    package = package or PACKAGE
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        is_init = parts[-1] == "__init__"
        if is_init:
            parts = parts[:-1]
        out[".".join(parts)] = (path, is_init)
    return out


def _targets(module: str, is_init: bool, node, known) -> list[str]:
    """The ftc_mc modules an import statement names (a name imported from a
    package counts as its submodule when there is one)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = module.split(".") if is_init else module.split(".")[:-1]
            base = base[:len(base) - (node.level - 1)]
            prefix = ".".join(base + ([node.module] if node.module else []))
        else:
            prefix = node.module or ""
        names = [f"{prefix}.{a.name}" if f"{prefix}.{a.name}" in known else prefix
                 for a in node.names]
    out = []
    for name in names:
        while name and name not in known:
            name = name.rpartition(".")[0]
        if name and name != module:
            out.append(name)
    return out


def import_graph(package: Path | None = None) -> dict[str, set[str]]:
    """Module -> the ftc_mc modules it imports anywhere in its source."""
    known = modules(package)
    graph = {}
    for module, (path, is_init) in known.items():
        graph[module] = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                graph[module].update(_targets(module, is_init, node, known))
    return graph


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_import_circles():
    graph = import_graph()
    assert len(graph) > 50 and "ftc_mc.sim.monitor" in graph["ftc_mc.sim.truth"]
    found = circles(graph)
    detail = ["  " + " <-> ".join(c) + ": " + "; ".join(
        f"{a} -> {b}" for a in c for b in sorted(graph[a]) if b in c) for c in found]
    assert not found, "import circles among ftc_mc modules:\n" + "\n".join(detail)


def test_no_circles_between_packages():
    """The packages (and the single modules of ``ftc_mc/``) form layers: a
    package imports only from those below it, never one that imports it back."""
    graph = import_graph()

    def package(module):
        return module.split(".")[1] if "." in module else module

    between = {}
    for a, targets in graph.items():
        for b in targets:
            if package(a) != package(b):
                between.setdefault(package(a), set()).add(package(b))
    found = circles(between)
    assert not found, "import circles between ftc_mc packages: " + "; ".join(
        " <-> ".join(c) + " (" + ", ".join(
            f"{a} -> {b}" for a in sorted(graph) for b in sorted(graph[a])
            if package(a) in c and package(b) in c and package(a) != package(b)) + ")"
        for c in found)


def test_the_circle_finder_finds_one():
    """The check can fail: a three-module circle is found, a module outside it is not."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert circles(graph) == [["a", "b", "c"]]


def test_synthesis_writes_no_files():
    """``ftc_mc/design`` computes designs; their on-disk cache is
    :mod:`ftc_mc.cache`, and files are :mod:`ftc_mc.io`'s."""
    graph = import_graph()
    bad = sorted(f"{a} -> {b}" for a, targets in graph.items() if a.startswith("ftc_mc.design")
                 for b in targets if b.split(".")[1] in ("io", "cache"))
    assert not bad, "ftc_mc/design imports file writing: " + ", ".join(bad)
