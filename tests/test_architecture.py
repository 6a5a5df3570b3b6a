"""Dependencies point one way (shared/architecture.md), checked by reading imports with ast:

core ← effects ← instruments/scenes ← sensors, estimators ← recording, bench, cli ← ros

and rclpy or ROS message packages are imported only under gyro_instrument/ros/.
"""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1] / "gyro_instrument"
LAYER = {"core": 0, "effects": 1, "instruments": 2, "scenes": 2, "sensors": 3, "estimators": 3,
         "recording": 4, "bench": 4, "cli": 4, "ros": 5}
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
