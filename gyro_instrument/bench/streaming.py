"""Streaming benchmarks (issue 13): whole ``simulate`` processes against a textbook script, peak
memory against the duration, and output throughput.

* :func:`whole_process_rows` — the shipped ``foucault_pantheon`` for one sidereal day (1 h with
  ``--quick``) through ``gyro-instrument simulate --out X.parquet`` in a child process, against a
  textbook script in another (:data:`TEXTBOOK_SCRIPT`: ``solve_ivp`` DOP853 on the Cartesian
  rotating-frame pendulum — gravity, Coriolis, the centrifugal gradient, the rod tension — sampled
  at the scene's 20 Hz and saved with ``numpy.save``), its ``rtol`` chosen from the work-precision
  rows of the same run as the largest whose end error is at most twice the fast path's (the
  tightest row when none is: the ratio then understates the fast path's advantage). Both end
  errors are measured against the same tight reference (DOP853 rtol 1e-13). Wall clock, in the
  same run, on the same machine.
* :func:`peak_memory_rows` — maximum resident set size of ``simulate`` for 1 h, 24 h and 48 h
  (1 h and 2 h with ``--quick``) of foucault_pantheon, each in its own child process
  (:func:`run_child`), on one code path (numpy): a streamed run holds one block and one parareal
  window, so 48 h exceeds 1 h by at most one window (:data:`RSS_MARGIN_MB`) and equals 24 h; and
  24 h against 48 h as shipped (compiled), with what numba adds to the process.
* :func:`throughput_rows` — MB/s of the CSV and Parquet writers
  (:class:`gyro_instrument.estimators.data_io.TableWriter`) on foucault_pantheon's seven columns.
"""

import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

#: The textbook baseline: what one would write from the equations of Quet sec. 2 (eq. 21 in vector
#: form, the tension from the constraint |r| = l) with scipy alone. argv: latitude_deg, length_m,
#: gravity_m_s2, deflection_deg, azimuth_deg, duration_s, rate_hz, rtol, earth_rate_rad_s, out.npy.
TEXTBOOK_SCRIPT = r"""
import math, sys
import numpy as np
from scipy.integrate import solve_ivp
lat, l, g, th, az, T, f, rtol, n = map(float, sys.argv[1:10])
out = sys.argv[10]
lat, th, az = math.radians(lat), math.radians(th), math.radians(az)
om = n * np.array([0.0, math.cos(lat), math.sin(lat)])          # Earth rate in ENU
rest = np.array([0.0, 0.0, -l])

def rhs(t, y):
    r, v = y[:3], y[3:]
    a = np.array([0.0, 0.0, -g]) - 2.0 * np.cross(om, v) - np.cross(om, np.cross(om, r - rest))
    lam = (v @ v + r @ a) / (r @ r)                             # tension keeping |r| = l
    return np.concatenate([v, a - lam * r])

r0 = l * np.array([math.sin(th) * math.sin(az), math.sin(th) * math.cos(az), -math.cos(th)])
t = np.round(np.arange(int(math.floor(T * f + 1e-9)) + 1) * (1e9 / f)) / 1e9
sol = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([r0, np.zeros(3)]), method="DOP853", t_eval=t,
                rtol=rtol, atol=rtol * l * math.sin(th))
np.save(out, np.vstack([t, sol.y]))
"""


def swing_azimuth(x, y, vx, vy, omega0_sq) -> float:
    """Compass azimuth (rad, modulo π) of the swing plane from the Fradkin tensor ω0² r rᵀ + v vᵀ of
    one horizontal state (east x, north y)."""
    tnn, tee, tne = omega0_sq * y * y + vy * vy, omega0_sq * x * x + vx * vx, omega0_sq * y * x + vy * vx
    return 0.5 * math.atan2(2.0 * tne, tnn - tee)


def _wrapped(d, period=math.pi):
    return (d + period / 2) % period - period / 2


#: Runs argv[1:] and prints its maximum RSS (kB). A child forked from this (large) process would
#: start with this process's pages resident and report them as its own ``ru_maxrss``; a small
#: wrapper that forks the command gives the command's own peak.
MAXRSS_WRAPPER = ("import resource, subprocess, sys; rc = subprocess.call(sys.argv[1:]); "
                   "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr); sys.exit(rc)")


def run_child(cmd, env=None) -> tuple:
    """Run ``cmd``; return (wall s, maximum RSS in MB of ``cmd`` alone, measured by a small wrapper
    process with ``getrusage(RUSAGE_CHILDREN)``).

    Raises
    ------
    RuntimeError
        The child failed (its last stderr line).
    """
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", MAXRSS_WRAPPER, *cmd], stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True, env=env)
    wall = time.perf_counter() - t0
    lines = p.stderr.strip().splitlines()
    if p.returncode != 0 or not lines:
        raise RuntimeError(f"{cmd[:4]} failed ({p.returncode}): {lines[-2] if len(lines) > 1 else ''}")
    return wall, int(lines[-1]) / 1024.0


def _simulate_cmd(duration_s, out, extra=()):
    return [sys.executable, "-m", "gyro_instrument.cli", "simulate", "foucault_pantheon", "--duration-s",
            repr(duration_s), "--quiet", "--out", out, *extra]


def _env():
    """The child's environment: this package first on the path (the tree under test)."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return dict(os.environ, PYTHONPATH=os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))


def textbook_rtol(wp_rows, duration_s, fast_error) -> float:
    """The largest DOP853 rtol of the work-precision rows (full equations, this duration) whose end
    error is at most twice ``fast_error``, else the tightest one."""
    dop = sorted(((float(r[2].split()[1]), r[5]) for r in wp_rows
                  if r[1] == "full equations, DOP853" and f"{duration_s:g} s" in r[0]), reverse=True)
    for rtol, err in dop:
        if err <= 2.0 * fast_error:
            return rtol
    return dop[-1][0] if dop else 1e-12


def whole_process_rows(wp_rows, reference, duration_s, progress=print) -> list:
    """Rows (target, measured, unit, goal, met): whole ``simulate --out X.parquet`` of
    foucault_pantheon for ``duration_s`` against :data:`TEXTBOOK_SCRIPT` at the rtol that matches
    its end error (:func:`textbook_rtol`); ``reference`` is the tight reference's swing azimuth at
    the last sample (rad)."""
    from gyro_instrument.estimators.data_io import read_table
    from gyro_instrument.scenes import build_instruments, load_scene
    scene = load_scene("foucault_pantheon", [f"duration_s={duration_s!r}"])
    p = build_instruments(scene)["pendulum"]
    w0sq = p.context.gravity_m_s2 / p.p.length_m
    env = _env()
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "x.parquet")
        progress(f"  whole process: simulate foucault_pantheon {duration_s:g} s --out x.parquet")
        wall, _ = run_child(_simulate_cmd(duration_s, out), env)
        cols = read_table(out)
        fast_err = abs(_wrapped(float(cols["pendulum.swing_azimuth"][-1]) - reference))
        del cols
        rtol = textbook_rtol(wp_rows, duration_s, fast_err)
        progress(f"  whole process: textbook solve_ivp DOP853 rtol {rtol:g}")
        npy = os.path.join(tmp, "textbook.npy")
        args = [scene.site.latitude_deg, p.p.length_m, p.context.gravity_m_s2, p.p.initial_deflection_deg,
                p.p.initial_azimuth_deg, duration_s,
                scene.sample_rate_hz, rtol, scene.site.earth_rate_rad_s]
        tb_wall, _ = run_child([sys.executable, "-c", TEXTBOOK_SCRIPT, *map(repr, map(float, args)), npy], env)
        y = np.load(npy)[:, -1]
        tb_err = abs(_wrapped(swing_azimuth(y[1], y[2], y[4], y[5], w0sq) - reference))
    what = f"foucault_pantheon {duration_s:g} s at 20 Hz, whole process"
    ratio = tb_wall / wall
    return [(f"{what}: simulate --out X.parquet wall (end swing-azimuth error {fast_err:.1e} rad)", wall, "s",
             "<= 3", wall <= 3.0),
            (f"{what}: textbook solve_ivp DOP853 script (rtol {rtol:g}, end error {tb_err:.1e} rad) wall / "
             f"simulate wall", ratio, "x", ">= 10", ratio >= 10.0)]


#: The margin stated for peak memory: a streamed simulate holds one block (65 536 rows) and one
#: parareal window; a run of fewer swings than a window (1 h: 220 swings of the 67 m pendulum) holds
#: a smaller one. Measured ~23 kB per swing of window (Newton pass: states, derivatives and stages of
#: every swing and its Jacobian columns; the Hermite rows), so a full window of 2048 swings adds ~48 MB
#: to a 1 h run (138 MB); beyond two windows the peak no longer grows: 186, 186, 189 MB at 24, 48, 96 h
#: (2026-11-30, 2 shared cores). Margin: 60 MB.
RSS_MARGIN_MB = 60.0


def peak_memory_rows(short_s, long_s, middle_s=None, progress=print) -> list:
    """Rows: peak RSS (MB) of ``simulate foucault_pantheon --out X.parquet`` for ``short_s``,
    ``middle_s`` (optional) and ``long_s`` seconds on one code path, the numpy fast path
    (``GYRO_INSTRUMENT_JIT=0``): the long run against the short one within :data:`RSS_MARGIN_MB`,
    and (with ``middle_s``, a run of full windows too) long / middle within 5 %: memory does not
    grow with the duration. With ``middle_s``, also the shipped path (runs of ≥ 2048 swings compiled
    with numba, :attr:`~gyro_instrument.instruments.pendulum.dynamics.SwingDynamics.COMPILED_MIN_SWINGS`)
    for the middle and long runs: long / middle within 5 %, and what numba's runtime and kernels
    add to a process (compiled less numpy at the long duration; stated, no goal). A 1 h run is never
    compiled, so comparing it with a compiled 48 h would count numba's runtime as growth."""
    env = _env()
    numpy_env = dict(env, GYRO_INSTRUMENT_JIT="0")
    rss, compiled = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for d in [x for x in (short_s, middle_s, long_s) if x]:
            progress(f"  peak memory: simulate foucault_pantheon {d:g} s (numpy path)")
            _, rss[d] = run_child(_simulate_cmd(d, os.path.join(tmp, f"{d:g}.parquet")), numpy_env)
        for d in [x for x in (middle_s, long_s) if x and middle_s]:
            progress(f"  peak memory: simulate foucault_pantheon {d:g} s (as shipped: compiled)")
            _, compiled[d] = run_child(_simulate_cmd(d, os.path.join(tmp, f"c{d:g}.parquet")), env)
    rows = [(f"simulate foucault_pantheon {d / 3600:g} h --out X.parquet, numpy path, peak RSS", rss[d], "MB", "—",
             True) for d in rss]
    extra = rss[long_s] - rss[short_s]
    rows.append((f"peak RSS {long_s / 3600:g} h - {short_s / 3600:g} h, numpy path (margin: one parareal window)",
                 extra, "MB", f"<= {RSS_MARGIN_MB:g}", extra <= RSS_MARGIN_MB))
    if middle_s:
        ratio = rss[long_s] / rss[middle_s]
        rows.append((f"peak RSS {long_s / 3600:g} h / {middle_s / 3600:g} h, numpy path", ratio, "x", "<= 1.05",
                     ratio <= 1.05))
        rows += [(f"simulate foucault_pantheon {d / 3600:g} h --out X.parquet, as shipped (compiled), peak RSS",
                  compiled[d], "MB", "—", True) for d in compiled]
        ratio = compiled[long_s] / compiled[middle_s]
        rows.append((f"peak RSS {long_s / 3600:g} h / {middle_s / 3600:g} h, as shipped (compiled)", ratio, "x",
                     "<= 1.05", ratio <= 1.05))
        rows.append((f"numba's runtime and kernels in the process: compiled less numpy path, {long_s / 3600:g} h",
                     compiled[long_s] - rss[long_s], "MB", "—", True))
    return rows


def throughput_rows(rows, progress=print) -> list:
    """Rows: MB/s of :class:`~gyro_instrument.estimators.data_io.TableWriter` writing ``rows`` rows of
    foucault_pantheon's seven columns (time and six pendulum channels, from a streamed simulation)
    as CSV and as Parquet, wall clock, file size over time."""
    from gyro_instrument.estimators.data_io import TableWriter
    from gyro_instrument.estimators.pipeline import simulate_truth
    from gyro_instrument.scenes import load_scene
    rate = 20.0
    t, insts, sims = simulate_truth(load_scene("foucault_pantheon", [f"duration_s={(rows - 1) / rate!r}"]))
    cols = {f"{n}.{c.name}": sims[n].columns[c.name] for n, inst in insts.items() for c in inst.COLUMNS}
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in ("csv", "parquet"):
            path = os.path.join(tmp, f"x.{kind}")
            progress(f"  output throughput: {t.size} rows to {kind}")
            t0 = time.perf_counter()
            with TableWriter(path, list(cols)) as w:
                for a in range(0, t.size, 65536):
                    w.write(t[a:a + 65536], {k: v[a:a + 65536] for k, v in cols.items()})
            wall = time.perf_counter() - t0
            mb = os.path.getsize(path) / 1e6
            name = {"csv": "CSV", "parquet": "Parquet"}[kind]
            out.append((f"{name} writer, {t.size} rows x {len(cols) + 1} columns ({mb:.0f} MB)", mb / wall, "MB/s",
                        "—", True))
    return out


def streaming_rows(wp_rows, reference, quick=False, progress=print) -> list:
    """Every streaming row (:func:`whole_process_rows`, :func:`peak_memory_rows`,
    :func:`throughput_rows`); quick: 1 h against the textbook, 1 h vs 2 h of memory, 2e5 rows."""
    day = 86164.0989
    rows = whole_process_rows(wp_rows, reference, 3600.0 if quick else day, progress)
    rows += peak_memory_rows(3600.0, (2.0 if quick else 48.0) * 3600.0, None if quick else 24.0 * 3600.0,
                             progress)
    rows += throughput_rows(200_001 if quick else int(math.floor(day * 20.0)) + 1, progress)
    return rows
