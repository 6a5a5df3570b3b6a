"""Helpers of the any-machine tests (issue 38): run a command with some directories mounted
read-only in a private mount namespace (``unshare -m``, root only: CI runs as root), so the
install and HOME are as a container's or a shared install's are, while the rest of the machine
is untouched."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the mount namespace needs root and unshare
CAN_UNSHARE = os.geteuid() == 0 and shutil.which("unshare") is not None and shutil.which("mount") is not None
needs_mount_ns = pytest.mark.skipif(not CAN_UNSHARE, reason="a private mount namespace needs root and unshare")

_MOUNT = 'for d in "$@"; do [ "$d" = -- ] && break; mount --bind "$d" "$d" && mount -o remount,ro,bind "$d" || exit 97; ' \
         'shift; done; shift; exec "$@"'


def install_dirs() -> list:
    """The package's checkout (its source and ``__pycache__``), the interpreter's prefix (the venv)
    and HOME: what a read-only install with a read-only HOME makes unwritable."""
    dirs = [str(ROOT), sys.prefix, os.path.expanduser("~")]
    return [d for i, d in enumerate(dirs) if os.path.isdir(d) and d not in dirs[:i]]


def run_readonly(argv, readonly, env=None, timeout=120, **kwargs) -> subprocess.CompletedProcess:
    """Run ``argv`` with every directory of ``readonly`` bind-mounted read-only over itself in a new
    mount namespace (the mounts vanish with the process)."""
    cmd = ["unshare", "-m", "--propagation", "private", "sh", "-c", _MOUNT, "sh", *map(str, readonly), "--",
           *map(str, argv)]
    out = subprocess.run(cmd, env=env, capture_output=True, timeout=timeout, **kwargs)
    assert out.returncode != 97, f"could not mount read-only: {out.stderr!r}"
    return out


def cli(*args) -> list:
    """The command line of ``gyro-instrument ARGS`` in this interpreter."""
    return [sys.executable, "-m", "gyro_instrument.cli", *args]


def ros_cli(*args) -> list:
    """The command line of ``gyro-instrument ARGS`` with the ROS subcommand ``run`` (the console script's module)."""
    return [sys.executable, "-m", "gyro_instrument.ros.cli", *args]
