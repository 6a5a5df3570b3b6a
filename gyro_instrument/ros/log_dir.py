"""A writable ROS log directory before ``rclpy.init`` (issue 38, ros2/rcl_logging#72).

rcl's file logging writes to ``ROS_LOG_DIR``, else ``ROS_HOME/log``, else ``$HOME/.ros/log``; with
HOME unset or read-only (containers, shared accounts, systemd units) ``rclpy.init`` raised
``RCLError: failed to initialize logging`` and no node started. :func:`ensure_log_dir` checks the
directory rcl would use and, when it cannot be written, points ``ROS_LOG_DIR`` at a private
directory in the temporary directory (one note line on stderr); when none can be written it turns
rcl's file logging off (``--disable-external-lib-logs``; console and ``/rosout`` logging stay).
"""

import os
import sys

from gyro_instrument.core.files import private_temp_dir, writable_dir

#: the extra ROS arguments that turn rcl's file logging off
NO_FILE_LOGS = ["--ros-args", "--disable-external-lib-logs"]


def rcl_log_dir(environ=os.environ) -> str | None:
    """The directory rcl's file logging would use under ``environ``, or None when it has none
    (no ``ROS_LOG_DIR``, no ``ROS_HOME``, no HOME). ``~`` at the start is HOME, as rcl expands it."""
    def expand(path):
        home = environ.get("HOME")
        if path.startswith("~"):
            return None if not home else home + path[1:]
        return path
    if environ.get("ROS_LOG_DIR"):
        return expand(environ["ROS_LOG_DIR"])
    if environ.get("ROS_HOME"):
        return expand(os.path.join(environ["ROS_HOME"], "log"))
    return os.path.join(environ["HOME"], ".ros", "log") if environ.get("HOME") else None


def ensure_log_dir(environ=os.environ, stream=None) -> list:
    """Make sure rcl can write its log file: nothing to do when its directory is writable; else
    ``ROS_LOG_DIR`` set in ``environ`` to a private temporary directory, or (none writable) the ROS
    arguments :data:`NO_FILE_LOGS` returned to add to ``rclpy.init``'s; one note line on ``stream``
    (stderr) when anything changed. Returns the extra ROS arguments (empty or :data:`NO_FILE_LOGS`)."""
    stream = stream or sys.stderr
    current = rcl_log_dir(environ)
    if current is not None and writable_dir(current):
        return []
    why = "HOME is not set" if current is None else f"{current} is not writable"
    path = private_temp_dir("ros-log")
    if path is not None:
        environ["ROS_LOG_DIR"] = path
        print(f"gyro-instrument: note: ROS log directory: {why}; logging to {path} (ROS_LOG_DIR)", file=stream)
        return []
    print(f"gyro-instrument: note: ROS log directory: {why} and no temporary directory is writable; "
          "ROS file logging off (console and /rosout logging on)", file=stream)
    return list(NO_FILE_LOGS)
