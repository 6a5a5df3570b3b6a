"""Issue 36: no import circle anywhere in the package.

The module import graph is read with ``ast`` from every file of ``gyro_instrument/`` — module-level
imports and the lazy ones inside functions alike (a lazy import only hides a circle until the
function runs) — and every strongly connected component of more than one module (or a module
importing itself) fails the test, named module by module. An edge goes to the module a statement
names: ``from pkg import name`` to ``pkg.name`` when that is a module of the package, else to
``pkg``; relative imports are resolved against the importing file's package. The implicit import of
parent packages (``import a.b`` runs ``a/__init__``) is not an edge: an ``__init__`` that gathers
its package's names is not a circle of the code.
"""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "gyro_instrument"
PACKAGE = ROOT.name


def module_name(path) -> str:
    """``gyro_instrument.a.b`` for ROOT/a/b.py and for ROOT/a/b/__init__.py."""
    parts = (PACKAGE,) + path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _package_of(name, path):
    return name if path.name == "__init__.py" else name.rpartition(".")[0]


def imported_modules(name, path):
    """The package's modules that ``path`` (module ``name``) imports, anywhere in the file."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = _package_of(name, path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in MODULES else mod for a in node.names]
        else:
            continue
        for target in targets:
            while target and target not in MODULES:      # import a.b.c of a non-module name: its module
                target = target.rpartition(".")[0]
            if target:
                yield target


def import_graph() -> dict:
    return {name: sorted(set(imported_modules(name, path))) for name, path in MODULES.items()}


def cycles(graph) -> list:
    """Strongly connected components (Tarjan, iterative) with a circle: more than one module, or one
    that imports itself; each as a sorted list of module names."""
    index, low, on_stack, stack, out = {}, {}, set(), [], []
    counter = [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(graph[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(graph.get(child, ()))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1 or node in graph.get(node, ()):
                    out.append(sorted(component))
    return out


def test_the_graph_is_read():
    graph = import_graph()
    assert len(graph) > 100
    # a lazy import inside a function is an edge (core/parareal.py imports core.jit in a function)
    assert "gyro_instrument.core.jit" in graph["gyro_instrument.core.parareal"]


def test_the_finder_names_a_circle():
    # a ⇄ b through a lazy import, c outside: the one component found is a and b
    graph = {"a": ["b"], "b": ["a"], "c": ["a"], "d": ["d"]}
    assert sorted(cycles(graph)) == [["a", "b"], ["d"]]


def test_no_import_circle():
    found = cycles(import_graph())
    assert not found, "import circles (each a set of modules importing one another): " + "; ".join(
        " ⇄ ".join(c) for c in found)
