"""The package's layout (issue 37): no import circle inside it, counting the imports deferred into
functions as well as the module-level ones (a stage never reaches back into one above it), and
every subpackage's ``__init__`` names its public API (``__all__``)."""
import ast
import importlib
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "tca_casadi"


def _module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph():
    """``{module: {modules of the package it imports anywhere in its source}}``; ``from . import x``
    and ``from .pkg import name`` count as importing the submodule where one is named, else the
    package."""
    modules = {_module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        found = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                base = package[:len(package) - node.level + 1] if node.level else []
                target = ".".join(base + ([node.module] if node.module else [])) if node.level else node.module
                for alias in node.names:
                    full = f"{target}.{alias.name}"
                    found.add(full if full in modules else target)
            elif isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
        graph[name] = {m for m in found if m in modules and m != name}
    return graph


def circles(graph):
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
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
                out.append(sorted(component))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circle_in_the_package():
    graph = import_graph()
    assert len(graph) > 100 and "tca_casadi.solvers.newton" in graph["tca_casadi.solvers.collocation"]
    assert circles(graph) == []


def test_the_walk_finds_a_circle_where_there_is_one():
    """The checker itself: a circle through a deferred import is found."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert circles(graph) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []


def test_every_subpackage_names_its_public_api():
    for init in sorted(PACKAGE.rglob("__init__.py")):
        if init.parent == PACKAGE:
            continue
        module = importlib.import_module(_module_name(init))
        assert isinstance(getattr(module, "__all__", None), (list, tuple)) and module.__all__, init
        for name in module.__all__:
            assert getattr(module, name, None) is not None, (init, name)
