"""``gyro-instrument run`` as it streams (issue 13 item 2), measured on child processes.

* time to first message: from the launch of ``gyro-instrument run SCENE --bag X.mcap`` to the first
  message committed to the bag on disk (the file is a complete MCAP after every commit, so the
  bench reads its provisional summary every 5 ms), for 1 h and 48 h of the same scene; the child
  is then killed (SIGKILL), so a 48 h run costs only its start. The launch includes the
  interpreter and rclpy's import, measured alone in the same run (``import`` row);
* peak memory: the maximum resident set size (a wrapper's ``RUSAGE_CHILDREN`` ``ru_maxrss``) of whole runs of 1 h and
  48 h of the same scene, with the run's own account of what grows (``--stats``:
  ``estimator_bytes``, the estimator's kept samples).

Two kinds of instrument: ``foucault_pantheon``'s pendulum as shipped (it streams: ``integrator:
auto`` runs parareal window by window of whole swings; ``adaptive`` continues one DOP853 step
sequence), and ``quet_gyroscopes`` (:data:`LAYERS_SCENE`: two plane gyroscopes whose integration is
nearly free), which isolates what the layers downstream of ``Instrument.stream`` cost: simulator
blocks, estimator, recorder, DDS. Every child runs on loopback like the suite's other benchmark
(discovery range LOCALHOST and, as root, a loopback-only network namespace).
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


def loopback(cmd) -> tuple:
    """(command, environment) kept on loopback (as :func:`.work_precision.suite_real_time_factor`)."""
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
    return loopback(cmd)


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
        return _first_message_of(*_run_command(scene, duration_s, bag, overrides, ("--quiet",)), bag, timeout_s)


def _first_message_of(cmd, env, bag, timeout_s):
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


def peak_rss(scene, duration_s, overrides=(), extra=(), env=None) -> tuple:
    """(maximum RSS in MB, the run's ``--stats`` dict) of a whole ``run`` with a recording; (None,
    {"error": ...}) when it fails. ``env``: variables added to the child's environment."""
    with tempfile.TemporaryDirectory() as tmp:
        bag = os.path.join(tmp, "rss.mcap")
        cmd, child_env = _run_command(scene, duration_s, bag, overrides, ("--stats", *extra))
        return _peak_rss_of(cmd, dict(child_env, **(env or {})), tmp)


#: The shipped scene whose instruments are cheapest to integrate (two plane gyroscopes on the scalar
#: DOP853 driver, ~30 000x real time): its rows measure what the layers downstream of
#: ``Instrument.stream`` hold and cost (simulator blocks, estimator, recorder, DDS).
LAYERS_SCENE = "quet_gyroscopes"


def layers_first_message(duration_s, rate_hz=20.0, timeout_s=60.0) -> tuple:
    """:func:`time_to_first_message` of ``run`` :data:`LAYERS_SCENE` at ``rate_hz``."""
    return time_to_first_message(LAYERS_SCENE, duration_s, (f"sample_rate_hz={rate_hz:g}",), timeout_s)


def layers_peak_rss(duration_s, rate_hz=1.0, window_s=100.0) -> tuple:
    """:func:`peak_rss` of ``run`` :data:`LAYERS_SCENE` at ``rate_hz`` with windows of ``window_s``:
    the instruments' own state is a few floats, so what grows is what the layers keep."""
    return peak_rss(LAYERS_SCENE, duration_s, (f"sample_rate_hz={rate_hz:g}",), ("--window-s", f"{window_s:g}"))


def _peak_rss_of(cmd, env, tmp):
    """Run ``cmd`` to its end; (its peak RSS in MB, the last stderr line as JSON) or (None, {"error": ...}).

    The command runs under a small wrapper process (:data:`~gyro_instrument.bench.streaming.MAXRSS_WRAPPER`,
    ``getrusage(RUSAGE_CHILDREN)``): a child forked straight from this process inherits its high-water
    RSS (Linux keeps it across ``execve``), which inside a whole ``bench`` run (~1.5 GB) hid every
    run's own peak, and the run's own ``--stats`` figure with it."""
    from gyro_instrument.bench.streaming import MAXRSS_WRAPPER
    with open(os.path.join(tmp, "out"), "w+") as out, open(os.path.join(tmp, "err"), "w+") as err:
        p = subprocess.run([sys.executable, "-c", MAXRSS_WRAPPER, *cmd], env=env, stdout=out, stderr=err)
        err.seek(0)
        lines = err.read().strip().splitlines()
    if p.returncode != 0 or len(lines) < 2:
        return None, {"error": lines[-2] if len(lines) > 1 else f"exit {p.returncode}"}
    return int(lines[-1]) / 1024.0, json.loads(lines[-2])


def import_time() -> float:
    """Seconds to start the interpreter and import the suite (rclpy included), in a child."""
    cmd, env = loopback([sys.executable, "-c", "import gyro_instrument.ros.suite"])
    t0 = time.monotonic()
    subprocess.run(cmd, env=env, check=True, capture_output=True)
    return time.monotonic() - t0


def live_rows(quick=False, progress=print) -> list:
    """Rows (target, measured, unit, goal, met) for ``targets.csv``.

    * launch to first message on disk, 1 h and 48 h: ``foucault_pantheon`` as shipped (``integrator:
      auto``, parareal windows) and on its adaptive integrator, and over
      ``quet_gyroscopes`` (:func:`layers_first_message`: the layers downstream of ``stream``);
    * peak RSS of whole runs, 1 h vs 48 h: ``foucault_pantheon`` on its fast path at 0.5 Hz (both on
      numpy, ``GYRO_INSTRUMENT_JIT=0``: a 1 h run is never compiled; the 48 h as shipped, compiled,
      beside them with what numba adds), and
      ``quet_gyroscopes`` at 1 Hz with 100 s windows (172 800 samples for 48 h). The stated margin,
      while streaming and beyond the estimator's kept samples (``estimator_bytes``, 8 bytes per kept
      value: what grows with the duration by design, reported by ``--stats``): one parareal window
      for the pendulum (:data:`~gyro_instrument.bench.streaming.RSS_MARGIN_MB`, as for ``simulate``),
      10 % of the 1 h run for the layers; the ratio with the kept samples is reported beside it.
    """
    import importlib.util
    if importlib.util.find_spec("rclpy") is None:
        return [("run: time to first message", float("nan"), "s (rclpy not installed)", "<= 2", False)]
    rows = []
    imp = import_time()
    rows.append(("run: interpreter start and import of the suite (rclpy), alone", imp, "s", "", True))
    cases = [("foucault_pantheon, adaptive", ("instruments.pendulum.integrator=adaptive",)),
             ("foucault_pantheon as shipped (auto: parareal)", ())]
    for d in (SHORT_S, LONG_S):
        for label, over in cases[1 if quick else 0:]:
            progress(f"  run {label}, {d / 3600:g} h: time to first message")
            s, note = time_to_first_message("foucault_pantheon", d, over)
            rows.append(_first_row(f"{label}, {d / 3600:g} h", s, note, imp))
        progress(f"  run over a streaming instrument, {d / 3600:g} h: time to first message")
        s, note = layers_first_message(d)
        rows.append(_first_row(f"quet_gyroscopes (layers), {d / 3600:g} h", s, note, imp))
    # at 1 Hz the pendulum publishes its markers every sample (once per second): 0.5 Hz keeps its
    # 48 h run to 86 400 samples and 8.2 samples per 16.42 s swing, above the estimator's sampling
    # check for a pendulum (8 per period: 0.2 Hz, 3.3 per period, is refused since issue 22);
    # the gyroscopes have no markers and run 172 800 samples at 1 Hz
    # the pendulum's 1 h and 48 h on one code path, the numpy fast path: a run of >= 2048 swings is
    # compiled as shipped and a 1 h run never is, so the pair as shipped would count numba's runtime
    # (~90 MB) as growth with the duration; the 48 h as shipped is measured beside them
    fast = ("sample_rate_hz=0.5",)
    numpy_path = {"GYRO_INSTRUMENT_JIT": "0"}
    from gyro_instrument.bench.streaming import RSS_MARGIN_MB
    for label, rate, measure, margin_mb in (("foucault_pantheon, fast path on numpy (GYRO_INSTRUMENT_JIT=0)", 0.5,
                                             lambda d: peak_rss("foucault_pantheon", d, fast, ("--window-s", "500"),
                                                                numpy_path),
                                             lambda short_mb: RSS_MARGIN_MB),
                                            ("quet_gyroscopes (layers)", 1.0, layers_peak_rss,
                                             lambda short_mb: 0.10 * short_mb)):
        got = {}
        for d in (SHORT_S, LONG_S):
            progress(f"  run {label}, {d / 3600:g} h at {rate:g} Hz: peak RSS")
            got[d] = measure(d)
            mb, stats = got[d]
            rows.append((f"run {label}, {d / 3600:g} h at {rate:g} Hz, peak RSS", mb if mb is not None else float("nan"),
                         "MB" + (f" ({stats['error']})" if mb is None else ""), "", mb is not None))
        (a, sa), (b, sb) = got[SHORT_S], got[LONG_S]
        if a is not None and b is not None:
            kept = (sb.get("estimator_bytes", 0) - sa.get("estimator_bytes", 0)) / 2 ** 20
            sa_, sb_ = sa.get("peak_rss_streaming_mb"), sb.get("peak_rss_streaming_mb")
            if sa_ and sb_:
                rows.append((f"run {label}: peak RSS while streaming (before the estimate) 48 h / 1 h", sb_ / sa_,
                             f"x ({sa_:.1f} -> {sb_:.1f} MB; the estimator keeps {kept:.1f} MB more)", "", True))
                # the stated margin beyond the estimator's kept samples (8 bytes per kept value: they grow
                # with the duration by design, and --stats reports them): for the layers 10 % of the 1 h
                # run; for the pendulum one parareal window, as for simulate (RSS_MARGIN_MB)
                extra = sb_ - kept - sa_
                rows.append((f"run {label}: peak RSS while streaming, 48 h less the estimator's kept samples, "
                             f"- 1 h", extra, f"MB ({sb_:.1f} - {kept:.1f} MB against {sa_:.1f} MB)",
                             f"<= {margin_mb(sa_):.3g}", extra <= margin_mb(sa_)))
            rows.append((f"run {label}: peak RSS of the whole process, estimate included, 48 h / 1 h", b / a,
                         f"x ({a:.1f} -> {b:.1f} MB)", "", True))
        if label.startswith("foucault_pantheon") and b is not None:
            progress(f"  run foucault_pantheon as shipped (compiled), {LONG_S / 3600:g} h at 0.5 Hz: peak RSS")
            c, _ = peak_rss("foucault_pantheon", LONG_S, fast, ("--window-s", "500"))
            rows.append((f"run foucault_pantheon as shipped (auto: compiled), {LONG_S / 3600:g} h at 0.5 Hz, peak RSS",
                         c if c is not None else float("nan"),
                         "MB" + (f" (numba's runtime and kernels: {c - b:+.1f} MB on the numpy path's)" if c else ""),
                         "", c is not None))
    return rows


def _first_row(label, s, note, imp):
    """The issue's goal is from the process's start: the interpreter and imports count."""
    return (f"run {label}: launch to first message on disk (import alone {imp:.2f} s)",
            s if s is not None else float("nan"), "s" + (f" ({note})" if note else ""), "<= 2",
            s is not None and s <= 2.0)
