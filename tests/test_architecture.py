"""Dependencies point one way (docs/architecture.md), checked by reading imports with ast:

core ← effects ← instruments/scenes ← sensors, estimators ← recording, bench, views ← cli ← ros

(the CLI is a front end: nothing below it reads its helpers; output checks live in core.files,
replay in recording.replay)

and rclpy or ROS message packages are imported only under gyro_instrument/ros/.
"""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1] / "gyro_instrument"
LAYER = {"core": 0, "effects": 1, "instruments": 2, "scenes": 2, "sensors": 3, "estimators": 3,
         "recording": 4, "bench": 4, "views": 4, "cli": 5, "api": 5, "ros": 6}
ROS_MODULES = ("rclpy", "std_msgs", "sensor_msgs", "geometry_msgs", "builtin_interfaces", "rosgraph_msgs",
               "diagnostic_msgs", "rcl_interfaces", "rosidl_runtime_py", "visualization_msgs")


def package_of(path):
    rel = path.relative_to(ROOT)
    return rel.parts[0].removesuffix(".py") if rel.parts else ""


def imports(path):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            yield node.module


FILES = sorted(p for p in ROOT.rglob("*.py"))


def test_there_are_files_to_check():
    assert len(FILES) > 20


@pytest.mark.parametrize("path", FILES, ids=lambda p: str(p.relative_to(ROOT)))
def test_layering_and_ros_isolation(path):
    me = package_of(path)
    for mod in imports(path):
        top = mod.split(".")[0]
        if top in ROS_MODULES:
            assert me == "ros", f"{path.relative_to(ROOT)} imports {mod}: ROS imports belong in gyro_instrument/ros/"
        if top == "gyro_instrument" and len(mod.split(".")) > 1:
            target = mod.split(".")[1]
            if me in LAYER and target in LAYER:
                assert LAYER[target] <= LAYER[me], \
                    f"{path.relative_to(ROOT)} ({me}) imports {mod} ({target}): arrow points the wrong way"
            if me == "effects" and target == "effects" and path.name != "__init__.py":
                pytest.fail(f"{path.relative_to(ROOT)}: effects never import each other ({mod})")


def test_core_never_imports_rclpy_at_runtime():
    import subprocess
    import sys
    code = ("import sys, gyro_instrument.scenes, gyro_instrument.cli, gyro_instrument.estimators;"
            "bad=[m for m in sys.modules if m.split('.')[0] in ('rclpy','sensor_msgs','std_msgs')];"
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


# ----------------------------------------------------------------------------- issue 12: the protocol
#: What an instrument type can do is declared on its class (gyro_instrument/instruments/base.py);
#: outside instruments/ nothing may switch on a type's name or look for a hook by name.
#: The protocol's members are every public name the Instrument class declares (class attributes such as
#: COLUMNS, STREAMS, JOINTS and the hooks), read off the class so a member added there is covered here.
def _protocol_members():
    from gyro_instrument.instruments.base import Instrument
    return frozenset(n for n in vars(Instrument) if not n.startswith("_"))


PROTOCOL_HOOKS = _protocol_members()


def _type_names():
    from gyro_instrument.instruments import REGISTRY
    return set(REGISTRY)


def type_name_switches(tree, names):
    """(line, what) for every place a module switches on an instrument type's name: a comparison
    (==, !=, in, not in) with a type-name literal or a literal collection holding one, a dict keyed
    by type names, a literal collection of type names (a table), a comparison involving
    ``.type_name`` with a literal, and ``hasattr``/``getattr`` on a protocol member."""
    def literal_names(node):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in names:
            return [node.value]
        if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            return [e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in names]
        return []

    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            for side in [node.left] + node.comparators:
                if literal_names(side):
                    out.append((node.lineno, f"compares with {literal_names(side)}"))
        elif isinstance(node, ast.Dict):
            keys = [k.value for k in node.keys if isinstance(k, ast.Constant) and k.value in names]
            if keys:
                out.append((node.lineno, f"dict keyed by {keys}"))
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            hits = literal_names(node)
            if hits and len(hits) == len(node.elts):
                out.append((node.lineno, f"table of type names {hits}"))
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("hasattr", "getattr"):
            if len(node.args) >= 2 and isinstance(node.args[1], ast.Constant) and node.args[1].value in PROTOCOL_HOOKS:
                out.append((node.lineno, f"{node.func.id}(..., {node.args[1].value!r}): declared on Instrument"))
    return out


OUTSIDE_INSTRUMENTS = [p for p in FILES if package_of(p) != "instruments"]


@pytest.mark.parametrize("path", OUTSIDE_INSTRUMENTS, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_module_outside_instruments_switches_on_an_instrument_type(path):
    found = type_name_switches(ast.parse(path.read_text(encoding="utf-8")), _type_names())
    assert not found, (f"{path.relative_to(ROOT)} switches on instrument type names: {found}; ask the class "
                       f"instead (the protocol in gyro_instrument/instruments/base.py)")


def test_the_type_name_check_catches_the_tables_it_replaced():
    """The detector finds each pattern issue 12 removed (so the test above can fail)."""
    names = {"spherical_pendulum", "compound_pendulum", "plane_gyroscope"}
    cases = ['PENDULUMS = ("spherical_pendulum", "compound_pendulum")',
             'ANGLE_CHANNELS = {"plane_gyroscope": ("angle",)}',
             'ok = inst.type_name == "plane_gyroscope"',
             'ok = inst.type_name in ("spherical_pendulum", "x")',
             'm = getattr(inst, "directing_model", None)',
             'ok = hasattr(cls, "check_params")',
             'ok = getattr(REGISTRY.get(t), "STREAMS", False)',
             'known = [c.name for c in getattr(inst, "COLUMNS", ())]']
    for src in cases:
        assert type_name_switches(ast.parse(src), names), src
    assert not type_name_switches(ast.parse('help = "e.g. --set instruments.p2.type=spherical_pendulum"'), names)


def test_the_protocol_list_holds_what_the_class_declares():
    """The members issue 23 found missing are in it, and with them the older hooks."""
    assert {"STREAMS", "COLUMNS", "JOINTS", "MEASURED_CHANNELS", "OBSERVATION", "SIMULATOR_NODE", "MECHANICS",
            "check_params", "check_effects", "directing_model", "measured_angles", "pendulum_length_m"} <= PROTOCOL_HOOKS


def test_every_registered_instrument_declares_the_protocol():
    from gyro_instrument.core.effect import MECHANICS
    from gyro_instrument.instruments import REGISTRY
    from gyro_instrument.instruments.base import Instrument
    for name, cls in REGISTRY.items():
        assert cls.type_name == name and cls.summary and cls.SIMULATOR_NODE, name
        assert cls.MECHANICS <= MECHANICS, name
        layout = cls.OBSERVATION.layout_of(cls)
        assert layout.names == tuple(cls.JOINTS) and layout.measured == tuple(cls.MEASURED_CHANNELS), name
        if cls.OBSERVATION.SHOWS_BOB_POSITION:
            assert cls.pendulum_length_m is not Instrument.pendulum_length_m, name
            assert {"x_east", "y_north"} <= {c.name for c in cls.COLUMNS}, name
        else:
            assert set(cls.MEASURED_CHANNELS) <= {c.name for c in cls.COLUMNS}, name


# ----------------------------------------------------------------------------- issue 12: files that do one job
#: public functions and methods allowed without a return annotation: none (the list emptied once the
#: streaming branch merged). Nothing may be added to it.
UNANNOTATED_ALLOWED = {}
#: the most lines of code a function may have (its docstring not counted)
MAX_FUNCTION_LINES = 80
#: functions allowed over MAX_FUNCTION_LINES: none. Nothing may be added to it.
LONG_ALLOWED = {}


def public_functions(tree):
    """(qualified name, FunctionDef) of every public module-level function and every public method
    of a public class (nested public classes included); properties are methods."""
    def walk(body, prefix):
        for node in body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not node.name.startswith("_"):
                yield prefix + node.name, node
            elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                yield from walk(node.body, f"{prefix}{node.name}.")
    yield from walk(tree.body, "")


def code_lines(node):
    """Lines of a function from its ``def`` to its last line, its docstring left out."""
    n = node.end_lineno - node.lineno + 1
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        n -= first.end_lineno - first.lineno + 1
    return n


def rel(path):
    return path.relative_to(ROOT).as_posix()


def test_every_public_function_has_a_return_annotation():
    missing = {}
    for path in FILES:
        allowed = UNANNOTATED_ALLOWED.get(rel(path), set())
        names = [name for name, node in public_functions(ast.parse(path.read_text(encoding="utf-8")))
                 if node.returns is None and name not in allowed]
        if names:
            missing[rel(path)] = names
    assert not missing, f"public functions without a return annotation: {missing}"


def test_the_annotation_allow_list_holds_only_what_is_still_missing():
    """An entry goes once its function is annotated (or gone), so the list only shrinks."""
    stale = {}
    for file, allowed in UNANNOTATED_ALLOWED.items():
        tree = ast.parse((ROOT / file).read_text(encoding="utf-8"))
        still = {name for name, node in public_functions(tree) if node.returns is None}
        if allowed - still:
            stale[file] = sorted(allowed - still)
    assert not stale, f"annotated now: drop from UNANNOTATED_ALLOWED: {stale}"


def test_no_function_is_longer_than_the_limit():
    long = {}
    for path in FILES:
        allowed = LONG_ALLOWED.get(rel(path), set())
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name not in allowed:
                if code_lines(node) > MAX_FUNCTION_LINES:
                    long.setdefault(rel(path), []).append(f"{node.name} ({code_lines(node)} lines)")
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines of code: split them at their seams: {long}"


def test_the_checks_catch_what_they_look_for():
    src = ("def f(x):\n    return x\n\n"
           "class A:\n    @property\n    def p(self):\n        return 1\n\n    def _q(self):\n        pass\n\n"
           "class _B:\n    def r(self):\n        pass\n\n"
           "def g() -> None:\n    '''doc\n    string'''\n" + "    x = 1\n" * MAX_FUNCTION_LINES)
    tree = ast.parse(src)
    assert [n for n, node in public_functions(tree) if node.returns is None] == ["f", "A.p"]
    g = next(node for n, node in public_functions(tree) if n == "g")
    assert code_lines(g) == MAX_FUNCTION_LINES + 1
