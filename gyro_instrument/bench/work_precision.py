"""Work-precision and speed-target studies of the bench (``work_precision.csv``, ``targets.csv``; see
the package docstring): each instrument's error at the end of a run against a tight reference versus
CPU time, per fidelity tier and setting, and the speed targets measured in the same run (the fast
path's CPU and error, the plane gyroscopes' hour, the estimator's throughput, the ROS suite's real
time factor with its recording checked complete).
"""

import math
import os
import time

import numpy as np

from gyro_instrument.core.scene import sample_times
from gyro_instrument.estimators.period import fit_oscillation
from gyro_instrument.instruments.base import Simulation
from gyro_instrument.instruments.pendulum import binet_ellipse, pendulum_columns
from gyro_instrument.scenes import build_instruments, load_scene


def _cpu(f):
    c0 = time.process_time()
    out = f()
    return out, time.process_time() - c0


def wrapped(d, period=math.pi) -> float:
    """``d`` folded into (−period/2, period/2]: a swing plane is defined modulo π."""
    return (d + period / 2) % period - period / 2


def _end_swing_azimuth(sim):
    """Swing-plane azimuth (compass, rad) at the last sample, from the Fradkin tensor."""
    return float(sim.columns["swing_azimuth"][-1])


def _pendulum(duration_s, rate_hz, **params):
    over = [f"duration_s={duration_s}", f"sample_rate_hz={rate_hz}"]
    over += [f"instruments.pendulum.{k}={v}" for k, v in params.items() if k != "effects"]
    if "effects" in params:
        over.append("effects={" + ", ".join(f"{e}: {{}}" for e in params["effects"]) + "}")
    scene = load_scene("foucault_pantheon", over)
    return build_instruments(scene)["pendulum"], sample_times(scene), scene


def _linear_model_effects() -> tuple:
    """The Foucault scene's effects without those giving a restoring law (the sine law): the pendulum's
    small-angle (linear) model with the rest of its terms."""
    from gyro_instrument.core.effect import RESTORING_LAW
    return tuple(n for n, e in load_scene("foucault_pantheon").effects.items() if RESTORING_LAW not in e.MECHANICS)


#: (duration_s, rate_hz) -> the tight reference's swing azimuth at the last sample (rad), kept by
#: :func:`foucault_work_precision` for the whole-process comparison (:mod:`.streaming`).
REFERENCE = {}


def foucault_work_precision(duration_s, rtols, parareal_settings, rate_hz=20.0, progress=print) -> list:
    """Rows (instrument, tier, setting, cpu_s, nfev, error_rad): the 67 m Foucault pendulum
    released at 2°, output at ``rate_hz``; error = swing-plane azimuth at the last sample against
    DOP853 at rtol 1e-13 on the full equations (the tight reference). Tiers: Binet's closed form
    (linear model), Quet's comparison pendulum (the first swing of the full model repeated and
    turned by its apsidal angle), the linear (small-angle) model, and the full model with DOP853
    (the textbook baseline) or the parareal fast path."""
    name = f"Foucault pendulum 67 m, {duration_s:g} s at {rate_hz:g} Hz"
    progress(f"  reference: DOP853 rtol 1e-13 over {duration_s:g} s")
    p, t, scene = _pendulum(duration_s, rate_hz, rtol=1e-13, integrator="adaptive")
    ref = _end_swing_azimuth(p.simulate(t))
    REFERENCE[(duration_s, rate_hz)] = ref
    rows = []

    def add(tier, setting, sim, cpu, nfev):
        rows.append((name, tier, setting, cpu, nfev, abs(wrapped(_end_swing_azimuth(sim) - ref))))

    for rtol in rtols:
        p, t, _ = _pendulum(duration_s, rate_hz, rtol=rtol, integrator="adaptive")
        sim, cpu = _cpu(lambda: p.simulate(t))
        add("full equations, DOP853", f"rtol {rtol:g}", sim, cpu, sim.trajectory.nfev)
        progress(f"  DOP853 rtol {rtol:g}: {cpu:.2f} s CPU, error {rows[-1][-1]:.2e} rad")
    for steps, tol in parareal_settings:
        p, t, _ = _pendulum(duration_s, rate_hz, integrator="parareal", segment_steps=steps, shooting_tol=tol)
        sim, cpu = _cpu(lambda: p.simulate(t))
        add("full equations, parareal RK8 (fast path)", f"{steps} steps/swing, tol {tol:g}", sim, cpu,
            sim.trajectory.nfev)
        progress(f"  parareal {steps} steps, tol {tol:g}: {cpu:.2f} s CPU, error {rows[-1][-1]:.2e} rad")
    p, t, _ = _pendulum(duration_s, rate_hz, rtol=1e-10, effects=_linear_model_effects(), integrator="adaptive")
    sim, cpu = _cpu(lambda: p.simulate(t))
    add("linear (small-angle) model, DOP853", "rtol 1e-10", sim, cpu, sim.trajectory.nfev)
    p, t, _ = _pendulum(duration_s, rate_hz)
    (pos, vel, nfev), cpu = _cpu(lambda: p.comparison_solution(t))
    sim = Simulation(t, pendulum_columns(pos, vel, p.context.gravity_m_s2 / p.p.length_m), None)
    add("Quet's comparison pendulum (first swing turned by its apsidal angle)", "", sim, cpu, nfev)
    r0, v0 = p.initial_state()

    def binet():
        x, y, vx, vy = binet_ellipse(t, p.p.length_m, p.context.gravity_m_s2, scene.site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1],
                                     velocity=True)
        z = -np.sqrt(np.maximum(p.p.length_m ** 2 - x * x - y * y, 0.0))
        return pendulum_columns(np.vstack([x, y, z]), np.vstack([vx, vy, 0 * vx]), p.context.gravity_m_s2 / p.p.length_m)
    cols, cpu = _cpu(binet)
    add("Binet's closed form (linear model)", "", Simulation(t, cols, None), cpu, 0)
    return rows


def gyroscope_work_precision(duration_s, rtols, progress=print) -> list:
    """Rows (instrument, tier, setting, cpu_s, nfev, error_rad) for quet_paris's horizontal
    directing-plane gyroscope: error = axis angle u at the last sample against the hinge chain
    (exact equations, Kane's method) at rtol 1e-13. Tiers: Quet's closed form (eq. 9 with the
    exact pendulum-like swing, :func:`plane_gyroscope_closed_form`), Quet's reduced equations
    (model: reduced) and the exact equations (model: chain), each across tolerances."""
    rows = []
    name = f"plane gyroscope (quet_paris gyro_horizontal), {duration_s:g} s at 20 Hz"

    def gyro(**params):
        over = [f"duration_s={duration_s}"] + [f"instruments.gyro_horizontal.{k}={v}" for k, v in params.items()]
        scene = load_scene("quet_paris", over)
        return build_instruments(scene)["gyro_horizontal"], sample_times(scene)

    progress(f"  reference: hinge chain rtol 1e-13 over {duration_s:g} s")
    g, t = gyro(model="chain", rtol=1e-13)
    ref = float(g.simulate(t).columns["angle"][-1])
    for model, tier in (("chain", "exact equations (hinge chain), DOP853"), ("reduced", "Quet's reduced equations, DOP853")):
        for rtol in rtols:
            g, t = gyro(model=model, rtol=rtol)
            sim, cpu = _cpu(lambda: g.simulate(t))
            rows.append((name, tier, f"rtol {rtol:g}", cpu, sim.trajectory.nfev,
                         abs(float(sim.columns["angle"][-1]) - ref)))
    g, t = gyro()
    u, cpu = _cpu(lambda: plane_gyroscope_closed_form(g, t))
    rows.append((name, "Quet's closed form (eq. 9, exact swing)", "", cpu, 0, abs(float(u[-1]) - ref)))
    return rows


#: (scene, instrument, angle columns, fidelity tiers as (label, parameter overrides), reference
#: overrides besides rtol 1e-13) for the other instruments' work-precision: the gimbal (exact chain
#: only: Quet's T, T', T'' are period formulas, checked in tests/test_gimbal.py), the free gyroscope
#: (Quet's closed form, sec. 4 §II, against the numerical solution) and Puiseux's body (numerical only).
OTHER_INSTRUMENTS = (
    ("gimbal_paris", "gimbal_locked", ("outer_angle", "inner_angle"), (("exact equations (hinge chain), DOP853", {}),),
     {}),
    ("free_gyroscope", "free_gyro", ("axis_altitude", "axis_azimuth"),
     (("Quet's closed form (sec. 4 §II)", {"model": "analytic"}),
      ("exact equations, DOP853", {"model": "numerical", "integrator": "dop853"})),
     {"model": "numerical", "integrator": "dop853"}),
    ("puiseux_spheroid", "spheroid", ("tilt", "tilt_azimuth"),
     (("exact equations, DOP853", {"integrator": "dop853"}),), {"integrator": "dop853"}),
)


def other_work_precision(duration_s, rtols, progress=print) -> list:
    """Rows (instrument, tier, setting, cpu_s, nfev, error_rad) for :data:`OTHER_INSTRUMENTS`:
    largest end-of-run difference of the angle columns against the exact equations at rtol 1e-13
    (``model: numerical`` for the free gyroscope)."""
    rows = []
    for scene_name, iname, columns, tiers, reference in OTHER_INSTRUMENTS:
        dur = duration_s if scene_name != "puiseux_spheroid" else min(duration_s, 60.0)

        def inst(**params):
            over = [f"duration_s={dur}"] + [f"instruments.{iname}.{k}={v}" for k, v in params.items()]
            scene = load_scene(scene_name, over)
            return build_instruments(scene)[iname], sample_times(scene)
        progress(f"  {scene_name}/{iname}: reference rtol 1e-13 over {dur:g} s")
        ref_params = {"rtol": 1e-13, **reference}
        g, t = inst(**ref_params)
        ref = g.simulate(t)
        name = f"{iname} ({scene_name}), {dur:g} s"
        for label, params in tiers:
            settings = [None] if params.get("model") == "analytic" else rtols
            for rtol in settings:
                g, t = inst(**params, **({"rtol": rtol} if rtol else {}))
                sim, cpu = _cpu(lambda: g.simulate(t))
                err = max(abs(float(sim.columns[c][-1]) - float(ref.columns[c][-1])) for c in columns)
                rows.append((name, label, f"rtol {rtol:g}" if rtol else "", cpu, sim.trajectory.nfev, err))
    return rows


def plane_gyroscope_closed_form(g, t) -> np.ndarray:
    """Axis angle u(t) of Quet's reduced equation in closed form: with the small-swing duration T0
    of eq. (9), u obeys the plane pendulum's law ü = −(π/T0)² sin u, whose release from rest at u0
    is u = 2 arcsin(k sn(K(m) − π t/T0 | m)), k = sin(u0/2), m = k² (Jacobi's sn)."""
    from scipy.special import ellipj, ellipk
    pred = g.predictions()
    w = math.pi / pred["swing_duration_small_s"]
    k = math.sin(g.p.initial_angle_rad / 2.0)
    m = k * k
    sn, _, _, _ = ellipj(float(ellipk(m)) - w * np.asarray(t, dtype=float), m)
    return 2.0 * np.arcsin(k * sn)


def work_precision(quick=False, progress=print) -> list:
    """All work-precision rows (see :func:`foucault_work_precision`, :func:`gyroscope_work_precision`)."""
    day = 86164.0989                           # a sidereal day (2π / n)
    if quick:
        fr = foucault_work_precision(3600.0, (1e-6, 1e-8, 1e-10, 1e-12), ((24, 1e-7), (48, 1e-9)),
                                     progress=progress)
        gr = gyroscope_work_precision(600.0, (1e-6, 1e-9), progress=progress)
        gr += other_work_precision(20.0, (1e-6, 1e-9), progress=progress)
    else:
        fr = foucault_work_precision(day, (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12),
                                     ((16, 1e-6), (24, 1e-7), (32, 1e-9), (48, 1e-9), (64, 1e-12)),
                                     progress=progress)
        gr = gyroscope_work_precision(3600.0, (1e-5, 1e-7, 1e-9, 1e-11), progress=progress)
        gr += other_work_precision(600.0, (1e-6, 1e-8, 1e-10, 1e-12), progress=progress)
    return fr + gr


def matched_error_ratio(rows, fast_row) -> float | None:
    """CPU of DOP853 on the full equations at the fast path's error (log-log interpolation of
    its work-precision line; at its most accurate point if the fast path is more accurate
    still, which understates the ratio) divided by the fast path's CPU."""
    pts = sorted((r[5], r[3]) for r in rows if r[0] == fast_row[0] and r[1].endswith("DOP853")
                 and r[1].startswith("full") and r[5] > 0)
    err = max(fast_row[5], 1e-300)
    if not pts:
        return None
    if err <= pts[0][0]:
        cpu = pts[0][1]
    elif err >= pts[-1][0]:
        cpu = pts[-1][1]
    else:
        le, lc = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
        cpu = float(np.exp(np.interp(math.log(err), le, lc)))
    return cpu / fast_row[3]


def targets(wp_rows, quick=False, progress=print) -> list:
    """Rows (target, measured, unit, goal, met) of issue 5's speed targets, measured in this run."""
    rows = []
    fast = [r for r in wp_rows if r[1].startswith("full equations, parareal") and r[2].startswith("48 steps")]
    if fast:
        f = fast[0]
        what = f"{f[0]}: parareal fast path"
        if not quick:
            rows.append((f"{what}, CPU", f[3], "s", "<= 2", f[3] <= 2.0))
        rows.append((f"{what}, end azimuth error", f[5], "rad", "<= 1e-6", f[5] <= 1e-6))
        ratio = matched_error_ratio(wp_rows, f)
        rows.append((f"{what}, DOP853 CPU at the same error / fast path CPU", ratio, "x", ">= 10",
                     ratio is not None and ratio >= 10))
    scene = load_scene("quet_paris", ["duration_s=3600"])
    insts = build_instruments(scene)
    t = sample_times(scene)
    _, cpu = _cpu(lambda: [insts[n].simulate(t) for n in ("gyro_horizontal", "gyro_meridian")])
    rows.append(("1 h of both plane-gyroscope configurations at 20 Hz", cpu, "s CPU", "<= 0.5", cpu <= 0.5))
    rate, note = estimator_throughput_one_blas_thread()
    rows.append(("estimator throughput (sine fit, 3rd harmonic), one BLAS thread", rate,
                 "samples/s" + (f" ({note})" if note else ""), ">= 1e6", rate >= 1e6))
    progress("  ROS suite, quet_paris at 100 Hz (subprocess on loopback)")
    rtf, note = suite_real_time_factor(duration_s=120.0 if quick else None)
    rows.append(("ROS suite, quet_paris at 100 Hz, nothing lost" + (" (120 s)" if quick else ""),
                 rtf if rtf is not None else float("nan"), "x real time" + (f" ({note})" if note else ""),
                 ">= 50", rtf is not None and rtf >= 50))
    if not quick:           # the route ROS users take, beside the one-process run (about a minute)
        from gyro_instrument.bench.ros_route import ros_route_rows
        rows += ros_route_rows(progress=progress)
    return rows


def estimator_throughput(fits=20) -> float:
    """Samples per CPU second of :func:`fit_oscillation` with the third harmonic on a 600 s record
    at 20 Hz (12 000 samples: a 0.1 rad swing at 0.245 rad/s in 1e-4 rad of white noise, seed 0),
    ``fits`` fits after one untimed (first-call imports and caches); CPU time of this process
    (``time.process_time``, so BLAS threads count too)."""
    rng = np.random.default_rng(0)
    tt = np.arange(0, 600, 0.05)
    y = 0.1 * np.cos(0.245 * tt) + rng.normal(0, 1e-4, tt.size)
    fit_oscillation(tt, y, harmonics=(1, 3))
    _, cpu = _cpu(lambda: [fit_oscillation(tt, y, harmonics=(1, 3)) for _ in range(fits)])
    return fits * tt.size / cpu


def estimator_throughput_one_blas_thread(fits=20) -> tuple:
    """:func:`estimator_throughput` in a fresh interpreter whose BLAS has one thread: the
    ``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` variables are set to 1
    before numpy loads (a BLAS library reads them once, at load), so the rate does not depend on
    how many threads this process's BLAS started, and idle-spinning BLAS threads are not counted.
    Returns (samples per CPU second, note; NaN and the reason if the child failed)."""
    import subprocess
    import sys
    import gyro_instrument
    root = os.path.dirname(os.path.dirname(os.path.abspath(gyro_instrument.__file__)))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               PYTHONPATH=os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    code = ("from gyro_instrument.bench.work_precision import estimator_throughput; "
            f"print(repr(estimator_throughput({int(fits)})))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    if p.returncode != 0:
        last = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
        return float("nan"), f"measuring process failed: {last}"
    return float(p.stdout.strip().splitlines()[-1]), ""


def suite_real_time_factor(duration_s=None, rate_hz=100.0) -> tuple:
    """Real-time factor of ``gyro-instrument run quet_paris`` at ``rate_hz`` with a recording,
    in a subprocess kept on loopback (discovery range LOCALHOST and, as root, a loopback-only
    network namespace), after checking that the recording holds every published message.
    Returns (factor or None, note)."""
    import json
    import shutil
    import subprocess
    import sys
    import tempfile
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.recording.topics import is_joint_topic
    import importlib.util
    if importlib.util.find_spec("rclpy") is None:
        return None, "rclpy not installed"
    with tempfile.TemporaryDirectory() as tmp:
        bag = os.path.join(tmp, "suite.mcap")
        cmd = [sys.executable, "-m", "gyro_instrument.ros.cli", "run", "quet_paris", "--set",
               f"sample_rate_hz={rate_hz:g}", "--bag", bag, "--json", "--stats"]
        if duration_s:
            cmd += ["--duration-s", f"{duration_s:g}"]
        env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
        if os.geteuid() == 0 and shutil.which("unshare") and shutil.which("ip") and not env.get("GYRO_IN_NETNS"):
            env["GYRO_IN_NETNS"] = "1"
            cmd = ["unshare", "-n", "sh", "-c", 'ip link set lo up && exec "$@"', "sh"] + cmd
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if p.returncode != 0:
            return None, f"run failed: {p.stderr.strip().splitlines()[-1] if p.stderr.strip() else p.returncode}"
        stats = json.loads(p.stderr.strip().splitlines()[-1])
        recorded = {}
        for topic, _, _, _ in read_messages(bag):
            recorded[topic] = recorded.get(topic, 0) + 1
        # every joint stream holds one message per sample, and the file holds what the recorder counted
        lost = sorted(tp for tp, n in stats["recorded"].items()
                      if recorded.get(tp, 0) != n or (is_joint_topic(tp) and n != stats["samples"]))
        if lost:
            return None, f"recording incomplete on {lost}"
        return stats["real_time_factor_achieved"], ""
