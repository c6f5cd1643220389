"""No import circle among impactcont's modules.

The graph is read from the source with :mod:`ast`: an edge ``a -> b`` for
every ``import`` that runs when ``a`` is imported (module body, class bodies,
``if``/``try`` blocks; not function bodies, not ``if TYPE_CHECKING:``).
``from pkg import name`` points at the submodule ``pkg.name`` when there is
one, else at ``pkg``. A package's own ``__init__`` is not an edge of its
submodules (Python runs it first, whoever imports them).
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import impactcont

PACKAGE = Path(impactcont.__file__).resolve().parent


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _module_level(body: list[ast.stmt]) -> Iterator[ast.stmt]:
    for node in body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            yield from _module_level(node.orelse)
            continue
        yield node
        for field in ("body", "orelse", "finalbody", "handlers"):
            inner = getattr(node, field, None)
            if isinstance(inner, list):
                yield from _module_level([n for n in inner if isinstance(n, ast.AST)
                                          and not isinstance(n, ast.ExceptHandler)])
        for handler in getattr(node, "handlers", []):
            yield from _module_level(handler.body)


def import_graph(*, functions: bool = False) -> dict[str, set[str]]:
    """``module -> modules it imports`` (only impactcont's); ``functions`` adds function bodies."""
    modules = _modules()
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        nodes = ast.walk(tree) if functions else _module_level(tree.body)
        for node in nodes:
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    anchor = package.split(".")
                    anchor = anchor[:len(anchor) - node.level + 1]
                    base = ".".join([*anchor, base] if base else anchor)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                           for a in node.names]
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name and not name.startswith(target + "."):
                    graph[name].add(target)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
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


def test_the_graph_is_read() -> None:
    graph = import_graph()
    assert "impactcont.scene.entries" in graph["impactcont.scene.schema"]
    assert "impactcont.scene.plugins" in graph["impactcont.scene.schema"]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_circle_at_module_level() -> None:
    assert cycles(import_graph()) == []


def test_no_import_circle_even_through_imports_inside_functions() -> None:
    # The circle of issue 12 (scene.schema -> scene.sections -> scene.twoparam ->
    # scene.tasks -> scene.schema) ran through imports deferred into functions.
    assert cycles(import_graph(functions=True)) == []


#: The layers of the package, bottom first (../shared/ARCHITECTURE.md): a module may import
#: its own layer and the layers below it, never one above ("arrows run down only").
LAYERS = (
    ("errors", "vocabulary", "threads", "progress"),
    ("kernel",),
    ("model",),
    ("orbit",),
    ("simulate",),
    ("core",),
    ("problems",),
    ("detection",),
    ("dataset",),
    ("analysis",),
    ("plots",),
    ("scene",),
    ("cli", "__main__"),
)


def layer_of(module: str) -> int | None:
    """The layer index of ``impactcont.<top>...`` (``None`` for the package itself)."""
    parts = module.split(".")
    if len(parts) < 2:
        return None
    for index, names in enumerate(LAYERS):
        if parts[1] in names:
            return index
    raise AssertionError(f"{module} is in no layer: add its top-level name to LAYERS")


def upward_arrows(graph: dict[str, set[str]]) -> list[str]:
    """Every ``a -> b`` whose target lies in a higher layer than its source."""
    out = []
    for source, targets in sorted(graph.items()):
        low = layer_of(source)
        for target in sorted(targets):
            high = layer_of(target)
            if low is not None and high is not None and high > low:
                out.append(f"{source} -> {target}")
    return out


def test_layers_are_read() -> None:
    assert upward_arrows({"impactcont.kernel.x": {"impactcont.scene.y"}}) == \
        ["impactcont.kernel.x -> impactcont.scene.y"]
    assert upward_arrows({"impactcont.scene.y": {"impactcont.kernel.x"}}) == []


def test_arrows_run_down_only_even_inside_functions() -> None:
    # The simulator (the independent witness) imported by the shooting code, the plugin
    # registry naming scene sections, the kernel imported by the model: each ran up.
    assert upward_arrows(import_graph(functions=True)) == []


def test_the_kernel_imports_nothing_of_the_package() -> None:
    graph = import_graph(functions=True)
    for module, targets in graph.items():
        if module.startswith("impactcont.kernel"):
            assert all(t.startswith("impactcont.kernel") for t in targets), (module, targets)
