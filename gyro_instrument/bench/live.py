"""``gyro-instrument run`` as it streams (issue 13 item 2), measured on child processes.

* time to first message: from the launch of ``gyro-instrument run SCENE --bag X.mcap`` to the first
  message committed to the bag on disk (the file is a complete MCAP after every commit, so the
  bench reads its provisional summary every 5 ms), for 1 h and 48 h of the same scene; the child
  is then killed (SIGKILL), so the 48 h run costs only its start. The launch includes the
  interpreter and rclpy's import (measured alone in the same run: ``import`` row);
* peak memory: the maximum resident set size (``wait4``'s ``ru_maxrss``) of whole runs of 1 h and
  48 h of the same scene, with the run's own account of what grows (``--stats``: the estimator's
  kept samples, ``estimator_bytes``) so the difference can be read against it.

Every child runs on loopback like the suite's other benchmark (discovery range LOCALHOST and, as
root, a loopback-only network namespace).
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

#: 48 h, the long run of the issue
LONG_S = 48 * 3600.0
#: 1 h, the reference run
SHORT_S = 3600.0


def _loopback(cmd):
    """(command, environment) kept on loopback (as :func:`.studies.suite_real_time_factor`)."""
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    if os.geteuid() == 0 and shutil.which("unshare") and shutil.which("ip") and not env.get("GYRO_IN_NETNS"):
        env["GYRO_IN_NETNS"] = "1"
        cmd = ["unshare", "-n", "sh", "-c", 'ip link set lo up && exec "$@"', "sh"] + cmd
    return cmd, env


def _run_command(scene, duration_s, bag, overrides=(), extra=()):
    cmd = [sys.executable, "-m", "gyro_instrument.ros.cli", "run", scene, "--duration-s", f"{duration_s:g}",
           "--bag", bag, *extra]
    for o in overrides:
        cmd += ["--set", o]
    return _loopback(cmd)


def _committed_messages(path):
    """Messages in the bag's (provisional) summary, 0 while there is none or it is being rewritten."""
    from mcap.reader import make_reader
    try:
        with open(path, "rb") as fh:
            summary = make_reader(fh).get_summary()
        return summary.statistics.message_count if summary and summary.statistics else 0
    except Exception:       # a commit in progress, or no file yet
        return 0


def time_to_first_message(scene, duration_s, overrides=(), timeout_s=60.0) -> tuple:
    """Seconds from launching ``run`` to its first message on disk, or None after ``timeout_s``;
    the child is killed at once. Returns (seconds or None, note)."""
    with tempfile.TemporaryDirectory() as tmp:
        bag = os.path.join(tmp, "first.mcap")
        cmd, env = _run_command(scene, duration_s, bag, overrides, ("--quiet",))
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            while time.monotonic() - t0 < timeout_s:
                if os.path.exists(bag) and _committed_messages(bag) > 0:
                    return time.monotonic() - t0, ""
                if p.poll() is not None:
                    err = p.stderr.read().strip().splitlines()
                    return None, f"run ended first: {err[-1] if err else p.returncode}"
                time.sleep(0.005)
            return None, f"no message within {timeout_s:g} s"
        finally:
            p.kill()
            p.wait()


def peak_rss(scene, duration_s, overrides=()) -> tuple:
    """(maximum RSS in MB, the run's ``--stats`` dict) of a whole ``run`` with a recording; (None,
    {"error": ...}) when it fails."""
    with tempfile.TemporaryDirectory() as tmp:
        bag = os.path.join(tmp, "rss.mcap")
        cmd, env = _run_command(scene, duration_s, bag, overrides, ("--stats",))
        with open(os.path.join(tmp, "out"), "w+") as out, open(os.path.join(tmp, "err"), "w+") as err:
            p = subprocess.Popen(cmd, env=env, stdout=out, stderr=err)
            _, status, usage = os.wait4(p.pid, 0)
            p.returncode = os.waitstatus_to_exitcode(status)
            err.seek(0)
            lines = err.read().strip().splitlines()
        if p.returncode != 0 or not lines:
            return None, {"error": lines[-1] if lines else f"exit {p.returncode}"}
        return usage.ru_maxrss / 1024.0, json.loads(lines[-1])


def import_time() -> float:
    """Seconds to start the interpreter and import the suite (rclpy included), in a child."""
    cmd, env = _loopback([sys.executable, "-c", "import gyro_instrument.ros.suite"])
    t0 = time.monotonic()
    subprocess.run(cmd, env=env, check=True, capture_output=True)
    return time.monotonic() - t0


def live_rows(quick=False, progress=print) -> list:
    """Rows (target, measured, unit, goal, met) for ``targets.csv``.

    Scenes: ``foucault_pantheon`` on its parareal fast path for the time to first message (the
    pendulum does not stream yet, ``STREAMS`` False: its whole run is integrated before the first
    block, 1.2 s for 48 h on this path; with the adaptive default the 48 h row waits for the full
    integration and is capped at 60 s), and ``foucault_pantheon`` at 1 Hz for the memory (172 800
    samples for 48 h through the whole suite in about a minute)."""
    import importlib.util
    if importlib.util.find_spec("rclpy") is None:
        return [("run: time to first message", float("nan"), "s (rclpy not installed)", "<= 2", False)]
    rows = []
    imp = import_time()
    rows.append(("run: interpreter start and import of the suite (rclpy), alone", imp, "s", "", True))
    fast = ("instruments.pendulum.integrator=parareal",)
    for label, over in (("parareal", fast),) + ((("adaptive default", ()),) if not quick else ()):
        for d in (SHORT_S, LONG_S):
            progress(f"  run foucault_pantheon {d / 3600:g} h ({label}): time to first message")
            s, note = time_to_first_message("foucault_pantheon", d, over)
            rows.append((f"run foucault_pantheon {d / 3600:g} h ({label}), launch to first message on disk",
                         s if s is not None else float("nan"), "s" + (f" ({note})" if note else ""),
                         "<= 2 after import", s is not None and s - imp <= 2.0))
    rate = ("sample_rate_hz=1",) + fast
    got = {}
    for d in (SHORT_S, LONG_S):
        progress(f"  run foucault_pantheon {d / 3600:g} h at 1 Hz: peak RSS")
        got[d] = peak_rss("foucault_pantheon", d, rate)
        mb, stats = got[d]
        rows.append((f"run foucault_pantheon {d / 3600:g} h at 1 Hz (parareal), peak RSS",
                     mb if mb is not None else float("nan"), "MB" + (f" ({stats['error']})" if mb is None else ""),
                     "", mb is not None))
    (a, sa), (b, sb) = got[SHORT_S], got[LONG_S]
    if a is not None and b is not None:
        kept = (sb.get("estimator_bytes", 0) - sa.get("estimator_bytes", 0)) / 2 ** 20
        rows.append(("run 48 h / 1 h peak RSS (foucault_pantheon, 1 Hz)", b / a, "x", "<= 1.10", b / a <= 1.10))
        rows.append(("run 48 h - 1 h peak RSS, of which the estimator's kept samples (--stats estimator_bytes)",
                     b - a, f"MB ({kept:.1f} MB kept by the estimator)", "", True))
    return rows
