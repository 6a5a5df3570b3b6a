"""No module imports a private name (``_x``) from another module of the package (issue 36): a name
another module needs is public where it is defined, so a reader finds the API by its names and a
file split leaves no re-export of private helpers. Checked by reading imports with ast (absolute
and relative ``from ... import``, and ``import a.b._c``)."""

import ast
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[1] / "gyro_instrument"

#: The imports of private names allowed, as (importing module, defining module, name): none. Add
#: nothing here: make the name public where it is defined instead.
ALLOWED = set()


def _private(name):
    return name.startswith("_") and not name.startswith("__")


def _module_name(path):
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def private_imports(path):
    """(importing module, defining module, name) for every private name ``path`` imports from the package."""
    here = _module_name(path)
    package = here if path.name == "__init__.py" else here.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            if source.split(".")[0] == "gyro_instrument":
                yield from ((here, source, a.name) for a in node.names if _private(a.name))
        elif isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                if parts[0] == "gyro_instrument" and any(_private(p) for p in parts):
                    yield here, a.name, next(p for p in parts if _private(p))


FOUND = {imp for path in sorted(ROOT.rglob("*.py")) for imp in private_imports(path)}


def test_the_reader_sees_relative_and_dotted_imports(tmp_path):
    # the checker itself: a relative import of a private name and a dotted import of a private module
    pkg = tmp_path / "gyro_instrument" / "sub"
    pkg.mkdir(parents=True)
    (pkg / "m.py").write_text("from .other import _hidden, shown\nimport gyro_instrument.sub._impl\n"
                              "from gyro_instrument.sub.other import __all__\n")
    global ROOT
    saved, ROOT = ROOT, tmp_path / "gyro_instrument"
    try:
        got = set(private_imports(pkg / "m.py"))
    finally:
        ROOT = saved
    assert got == {("gyro_instrument.sub.m", "gyro_instrument.sub.other", "_hidden"),
                   ("gyro_instrument.sub.m", "gyro_instrument.sub._impl", "_impl")}


def test_no_module_imports_a_private_name_of_another():
    new = sorted(FOUND - ALLOWED)
    assert not new, "make these names public where they are defined:\n" + "\n".join(
        f"{a} imports {c} from {b}" for a, b, c in new)


def test_the_allowlist_only_shrinks():
    gone = sorted(ALLOWED - FOUND)
    assert not gone, "these imports are gone: remove them from ALLOWED:\n" + "\n".join(
        f"{a} imports {c} from {b}" for a, b, c in gone)
