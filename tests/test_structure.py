"""Where code lives: the import graph of pnrotor's sources (docs/architecture.md, "Layers"), read from their text."""

import ast
import functools
from pathlib import Path

import pnrotor

SOURCES = Path(pnrotor.__file__).parent


def _modules():
    """{dotted name: path} of every module of the package."""
    found = {}
    for path in SOURCES.rglob("*.py"):
        parts = ("pnrotor",) + path.relative_to(SOURCES).with_suffix("").parts
        found[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return found


@functools.cache
def import_graph():
    """{module: the pnrotor modules it imports}: every import, at module level or in a function, of a module or of
    a name from one; importing a.b.c also runs the packages a.b's ``__init__`` (outside the importer's own)."""
    modules = _modules()

    def owner(name):   # the module defining ``name`` (a module, or a name in one)
        while name not in modules:
            name = name.rpartition(".")[0]
        return name

    graph = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets |= {owner(a.name) for a in node.names if a.name.split(".")[0] == "pnrotor"}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:   # relative: from the package, up level - 1
                    head = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(head + [base] if base else head)
                if base.split(".")[0] == "pnrotor":
                    targets |= {owner(f"{base}.{a.name}") for a in node.names}
        for target in list(targets):
            parts = target.split(".")
            targets |= {".".join(parts[:i]) for i in range(2, len(parts))
                        if not name.startswith(".".join(parts[:i]) + ".")}
        graph[name] = targets - {name}
    return graph


def circles(graph):
    """The groups of modules (two or more) that import each other through some chain: the strongly connected
    components of the graph (Tarjan's algorithm)."""
    index, low, stack, on_stack, groups = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:   # v is the first of its group: the group is v and what is above it on the stack
            group = stack[stack.index(v):]
            del stack[stack.index(v):]
            on_stack.difference_update(group)
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return groups


def test_circles_are_found():
    """The search itself, on graphs whose circles are known."""
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set(), "c": {"d"}, "d": {"c"}}) == [["c", "d"]]
    assert circles({"a": {"b", "c"}, "b": {"c"}, "c": set()}) == []


def test_the_import_graph_has_no_circle():
    """No module imports, through any chain of imports, one that imports it back."""
    graph = import_graph()
    assert {"pnrotor.ode.dop853", "pnrotor.pn.many", "pnrotor.numba_cache"} <= set(graph)
    assert "pnrotor.ode.common" in graph["pnrotor.ode.dop853"] and "pnrotor.pn" in graph["pnrotor.batch.backends"]
    assert circles(graph) == []


def test_no_solver_imports_another():
    """The ODE solvers share only the modules of the solver layer (pnrotor.ode.common's protocol)."""
    graph = import_graph()
    shared = {f"pnrotor.ode.{name}" for name in ("common", "events", "result", "tableau")}
    for solver in ("dop853", "bulirsch_stoer"):
        assert graph[f"pnrotor.ode.{solver}"] <= shared, solver
