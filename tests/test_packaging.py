"""The ament_python package: colcon build (colcon from PyPI) gives the executables under
lib/gyro_instrument/ and the ament index marker, and a node runs from there the way `ros2 run`
finds it (first prefix on AMENT_PREFIX_PATH holding the marker)."""

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
EXECUTABLES = ("gyrocompass_sim", "pendulum_sim", "top_sim", "marine_gyrocompass", "estimator", "recorder", "player")


@pytest.fixture(scope="module")
def colcon_install(tmp_path_factory):
    ws = tmp_path_factory.mktemp("ws")
    src = ws / "src" / "gyro_instrument"
    shutil.copytree(REPO, src, ignore=shutil.ignore_patterns(".git", ".venv", "venv", "build", "install", "log",
                                                             "out", "__pycache__", "bags", "*.mcap"))
    colcon = Path(sys.executable).parent / "colcon"
    r = subprocess.run([str(colcon), "build", "--base-paths", "src"], cwd=ws, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return ws / "install" / "gyro_instrument"


def ros2_run(prefixes, package, executable):
    """Resolve an executable as `ros2 run` does."""
    for prefix in prefixes:
        if (Path(prefix) / "share/ament_index/resource_index/packages" / package).exists():
            exe = Path(prefix) / "lib" / package / executable
            if exe.is_file() and os.access(exe, os.X_OK):
                return exe
    raise FileNotFoundError(executable)


def test_colcon_layout(colcon_install):
    assert (colcon_install / "share/ament_index/resource_index/packages/gyro_instrument").exists()
    assert (colcon_install / "share/gyro_instrument/package.xml").exists()
    # the formats --help points to (docs/formats/, moved out of msg_docs/ in issue 36) ship beside msg_docs
    for doc in ("msg_docs/topics.md", "msg_docs/parameters.md", "docs/formats/scene.md", "docs/formats/csv.md"):
        assert (colcon_install / "share/gyro_instrument" / doc).exists(), doc
    for exe in EXECUTABLES:
        assert os.access(colcon_install / "lib/gyro_instrument" / exe, os.X_OK), exe
    # the Fast DDS profile every node chooses before rclpy.init is installed beside the module that
    # names it (ros/dds_profile.py: a missing file would silently leave Fast DDS's 3 s heartbeat)
    site = next(colcon_install.glob("lib/python3*/site-packages"))
    assert (site / "gyro_instrument/ros/fastdds_profile.xml").is_file()


def _node_env(install):
    site = next(install.glob("lib/python3*/site-packages"))
    env = dict(os.environ)
    env["AMENT_PREFIX_PATH"] = os.pathsep.join([str(install), sys.prefix])
    env["PYTHONPATH"] = str(site)
    return env


def _run_node(install, exe_name, ros_args, until, timeout_s=180.0):
    """Start a node as `ros2 run` would, wait until its output contains ``until`` (or ``timeout_s``
    passes: a loaded CI machine may take tens of seconds to import numpy, scipy and rclpy), then
    send SIGINT as a user's Ctrl-C would; returns (exit status, whole output)."""
    import threading
    env = _node_env(install)
    exe = ros2_run(env["AMENT_PREFIX_PATH"].split(os.pathsep), "gyro_instrument", exe_name)
    p = subprocess.Popen([str(exe), "--ros-args", *ros_args], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    lines, seen = [], threading.Event()

    def read():
        for line in p.stdout:
            lines.append(line)
            if until in line:
                seen.set()
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    seen.wait(timeout_s)
    time.sleep(0.5)                    # the node keeps running after its message: it must stay up
    p.send_signal(2)
    p.wait(timeout=60)
    reader.join(timeout=10)
    return p.returncode, "".join(lines)


def test_ros2_run_gyrocompass_sim_from_colcon_install(colcon_install):
    rc, out = _run_node(colcon_install, "gyrocompass_sim",
                        ["-p", "scene:=quet_paris", "-p", "duration_s:=1.0", "-p", "real_time_factor:=0.0",
                         "-p", "publish_clock:=true", "-p", "wait_timeout_s:=0"], "published 21 samples")
    assert "published 21 samples of gyro_horizontal, gyro_meridian" in out, out
    assert "Traceback" not in out


def test_node_with_bad_parameter_logs_field_value_range_and_stays_up(colcon_install):
    rc, out = _run_node(colcon_install, "pendulum_sim",
                        ["-p", "scene:=quet_paris", "-p", "overrides:=['site.latitude_deg=95']"],
                        "site.latitude_deg = 95")
    assert "site.latitude_deg = 95" in out and "[-90, 90]" in out, out
    assert "Traceback" not in out


def test_params_file(colcon_install, tmp_path):
    # Issue 4: a parameters YAML works with --ros-args --params-file (scene, overrides, pacing).
    params = tmp_path / "params.yaml"
    params.write_text("gyrocompass_sim:\n  ros__parameters:\n    scene: quet_paris\n"
                      "    overrides: ['duration_s=0.5', 'instruments.gyro_meridian.spin_rate_rad_s=300.0']\n"
                      "    real_time_factor: 0.0\n    publish_clock: true\n    wait_timeout_s: 0\n")
    rc, out = _run_node(colcon_install, "gyrocompass_sim", ["--params-file", str(params)], "published 11 samples")
    assert "published 11 samples of gyro_horizontal, gyro_meridian" in out, out
