"""Issue 38: ROS commands with HOME unset or read-only (ros2/rcl_logging#72). rcl's file logging
wants ``$HOME/.ros/log``; ``rclpy.init`` raised ``RCLError: failed to initialize logging`` and no
node started, no bag. ``run`` (and every node executable, ros/main.py) now points ``ROS_LOG_DIR`` at a
private temporary directory, or turns file logging off when none is writable, in one note line
(ros/log_dir.py). Runs under tools/loopback (conftest re-executes the session in a loopback-only
network namespace as root)."""

import os
import subprocess

from machine_env import needs_mount_ns, ros_cli as cli, run_readonly
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros.log_dir import NO_FILE_LOGS, ensure_log_dir, rcl_log_dir

#: 2 s at quet_paris's 20 Hz (scenes/quet_paris.yaml): samples per instrument, t = 0 included
SAMPLES = 2 * 20 + 1


def _notes(stderr):
    assert "Traceback" not in stderr and "RCLError" not in stderr, stderr
    return [ln for ln in stderr.splitlines() if ln.startswith("gyro-instrument: note: ROS log directory")]


def test_run_without_home_logs_to_a_temporary_directory_and_records(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("HOME", "ROS_HOME", "ROS_LOG_DIR")}
    env["TMPDIR"] = str(tmp_path / "tmp")
    (tmp_path / "tmp").mkdir()
    bag = tmp_path / "q.mcap"

    out = subprocess.run(cli("run", "quet_paris", "--duration-s", "2", "--bag", bag, "--quiet", "--json"),
                         env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    private = tmp_path / "tmp" / f"gyro_instrument-ros-log-{os.getuid()}"
    assert _notes(out.stderr) == [f"gyro-instrument: note: ROS log directory: HOME is not set; logging to {private} "
                                  "(ROS_LOG_DIR)"]
    assert any(private.glob("*.log"))                 # rcl's log file went there
    counts = {}
    for topic, *_ in read_messages(str(bag)):
        counts[topic] = counts.get(topic, 0) + 1
    assert counts["/pendulum/joint_states"] == SAMPLES and counts["/clock"] == SAMPLES


@needs_mount_ns
def test_run_with_read_only_home_and_temporary_directories_turns_file_logging_off(tmp_path):
    home = tmp_path / "home"
    (home / ".ros" / "log").mkdir(parents=True)
    env = {k: v for k, v in os.environ.items() if k not in ("ROS_HOME", "ROS_LOG_DIR", "TMPDIR")} | {"HOME": str(home)}
    temps = [d for d in ("/tmp", "/var/tmp", "/usr/tmp") if os.path.isdir(d)]   # tmp_path is under /tmp too
    out = run_readonly(cli("run", "quet_paris", "--duration-s", "2", "--json"), [home, *temps], env, text=True,
                       cwd=home)
    assert out.returncode == 0, out.stderr
    assert _notes(out.stderr) == [f"gyro-instrument: note: ROS log directory: {home}/.ros/log is not writable and no "
                                  "temporary directory is writable; ROS file logging off (console and /rosout "
                                  "logging on)"]
    assert not any((home / ".ros" / "log").iterdir())


def test_log_dir_follows_rcl_rules(tmp_path):
    # rcl_logging_interface: ROS_LOG_DIR, else ROS_HOME/log, else $HOME/.ros/log ("~" expanded to HOME)
    assert rcl_log_dir({"ROS_LOG_DIR": "~/x", "ROS_HOME": "/r", "HOME": "/h"}) == "/h/x"
    assert rcl_log_dir({"ROS_HOME": "/r", "HOME": "/h"}) == "/r/log"
    assert rcl_log_dir({"HOME": "/h"}) == "/h/.ros/log"
    assert rcl_log_dir({}) is None
    env = {"ROS_LOG_DIR": str(tmp_path / "logs")}
    assert ensure_log_dir(env) == [] and env == {"ROS_LOG_DIR": str(tmp_path / "logs")}   # writable: untouched
    assert NO_FILE_LOGS == ["--ros-args", "--disable-external-lib-logs"]
