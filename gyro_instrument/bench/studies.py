"""The bench studies (see the package docstring)."""

import csv
import math
import os
import time

import numpy as np

from gyro_instrument.core.files import replaced_atomically
from gyro_instrument.core.parallel import process_executor
from gyro_instrument.core.scene import sample_times
from gyro_instrument.estimators.period import fit_oscillation
from gyro_instrument.estimators.pipeline import seed_sweep
from gyro_instrument.instruments.base import Simulation
from gyro_instrument.instruments.pendulum import binet_ellipse, pendulum_columns
from gyro_instrument.scenes import build_instruments, load_scene


def _cpu(f):
    c0 = time.process_time()
    out = f()
    return out, time.process_time() - c0


def _wrapped(d, period=math.pi):
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
        rows.append((name, tier, setting, cpu, nfev, abs(_wrapped(_end_swing_azimuth(sim) - ref))))

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
    p, t, _ = _pendulum(duration_s, rate_hz, rtol=1e-10, effects=("earth_rotation", "centrifugal"),
                        integrator="adaptive")
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
     (("Quet's closed form (sec. 4 §II)", {"model": "analytic"}), ("exact equations, DOP853", {"model": "numerical"})),
     {"model": "numerical"}),
    ("puiseux_spheroid", "spheroid", ("tilt", "tilt_azimuth"), (("exact equations, DOP853", {}),), {}),
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
    rng = np.random.default_rng(0)
    tt = np.arange(0, 600, 0.05)
    y = 0.1 * np.cos(0.245 * tt) + rng.normal(0, 1e-4, tt.size)
    k = 20
    _, cpu = _cpu(lambda: [fit_oscillation(tt, y, harmonics=(1, 3)) for _ in range(k)])
    rows.append(("estimator throughput (sine fit, 3rd harmonic)", k * tt.size / cpu, "samples/s", ">= 1e6",
                 k * tt.size / cpu >= 1e6))
    progress("  ROS suite, quet_paris at 100 Hz (subprocess on loopback)")
    rtf, note = suite_real_time_factor(duration_s=120.0 if quick else None)
    rows.append(("ROS suite, quet_paris at 100 Hz, nothing lost" + (" (120 s)" if quick else ""),
                 rtf if rtf is not None else float("nan"), "x real time" + (f" ({note})" if note else ""),
                 ">= 50", rtf is not None and rtf >= 50))
    return rows


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


def _obs_rows(minutes, results):
    out = []
    for r in results:
        truth = r["truth"]
        lat0 = abs(truth["latitude_deg"]) if r.get("latitude_is_absolute") else truth["latitude_deg"]
        cnt = r["methods"].get("item9_counting", {}).get("latitude_deg")
        lat, n = r.get("latitude_deg"), r.get("earth_rate_rad_s")
        crlb = r.get("crlb") or {}
        out.append((minutes, None if lat is None else lat - lat0, r.get("latitude_sigma_deg"),
                    crlb.get("latitude_deg"), None if cnt is None else cnt - abs(lat0),
                    None if n is None else n - truth["earth_rate_rad_s"], r.get("earth_rate_sigma_rad_s"),
                    crlb.get("earth_rate_rad_s"), _counting_earth_rate(r) - truth["earth_rate_rad_s"]))
    return out


def _meridian_gyro(r):
    """The estimate of the scene's meridian gyroscope (eq. 10's), or {}."""
    for e in r["instruments"].values():
        if isinstance(e, dict) and e.get("configuration") == "meridian" and e.get("swing_duration_s") is not None:
            return e
    return {}


def _counting_earth_rate(r):
    """Eq. (10) with Quet's counted meridian swing instead of the fitted one: n ∝ 1/T²."""
    g = _meridian_gyro(r)
    cnt = g.get("counting", {}).get("small_amplitude_swing_duration_s")
    if not cnt or r.get("earth_rate_rad_s") is None:
        return math.nan
    return r["earth_rate_rad_s"] * (g["small_amplitude_swing_duration_s"] / cnt) ** 2


OBS_HEADER = ("minutes", "rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg",
              "rms_fit_earth_rate_rad_s", "mean_sigma_earth_rate_rad_s", "crlb_earth_rate_rad_s",
              "rms_counting_earth_rate_rad_s", "noise_free_error_deg", "noise_free_earth_rate_error_rad_s")

FLOOR_HEADER = ("minutes", "left_out", "scope", "latitude_bias_deg", "earth_rate_bias_rad_s")

#: The floor scene: quet_paris with a spin decay added (τ = 1 h) so that all three corrections of
#: :data:`~gyro_instrument.estimators.pipeline.CORRECTIONS` have something to correct.
FLOOR_SCENE_EFFECTS = "effects={earth_rotation: {}, centrifugal: {}, finite_amplitude: {}, spin_decay: {time_constant_s: 3600}}"

#: What each scope of the floors measures, weight-free: the gyroscope pair is exactly determined
#: (item 9's cos γ from the ratio, eq. (10)'s n from the meridian configuration); the pendulum's
#: latitude is asin(k/n) with the true n, so only its own error enters.
GYRO_PAIR, PENDULUM_ALONE = "gyroscope pair (item 9, eq. 10)", "Foucault pendulum alone (asin k/n)"


def systematic_floor_rows(minutes) -> list:
    """:data:`FLOOR_HEADER` rows for one observation time: the noise-free bias of the estimates on
    the floor scene with every correction applied (``left_out`` = ``none``: the estimator's own
    floor with all three effects present) and with each correction of
    :data:`~gyro_instrument.estimators.pipeline.CORRECTIONS` left out (the floor a user would hit
    without it). One picklable argument, so it runs through any executor: ``minutes`` alone (the
    floor scene, quet_paris with a 1 h spin decay) or ``(scene, overrides, minutes)`` for any scene
    with its own effects."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    from gyro_instrument.estimators.pipeline import CORRECTIONS, estimate_records, measure, simulate_truth
    from gyro_instrument.scenes import load_scene
    if isinstance(minutes, tuple):
        name, overrides, minutes = minutes
        over = list(overrides)
    else:
        name, over = "quet_paris", [FLOOR_SCENE_EFFECTS]
    scene = load_scene(name, [f"duration_s={60.0 * minutes}"] + over + list(NOISE_FREE))
    truth = simulate_truth(scene)
    records = measure(scene, truth)
    lat0, n0 = scene.site.latitude_deg, scene.site.earth_rate_rad_s
    rows = []
    for left_out in ("none", "finite_amplitude", "spin_decay", "ellipse_precession"):
        r = estimate_records(scene, truth[1], records, corrections=CORRECTIONS - {left_out})
        if left_out != "ellipse_precession":
            lat = r["methods"].get("item9", {}).get("latitude_deg")
            n = r["methods"].get("item8_eq10", {}).get("earth_rate_rad_s")
            rows.append((minutes, left_out, GYRO_PAIR, None if lat is None else lat - lat0,
                         None if n is None else n - n0))
        if left_out in ("none", "ellipse_precession"):
            k = next((e.get("foucault_rate_rad_s") for e in r["instruments"].values()
                      if isinstance(e, dict) and "foucault_rate_rad_s" in e), None)
            lat = None if k is None or abs(k) > n0 else math.degrees(math.asin(k / n0))
            rows.append((minutes, left_out, PENDULUM_ALONE, None if lat is None else lat - lat0, None))
    return rows


def observation_time(minutes_list, n_seeds, executor=None, scene="quet_paris", overrides=()) -> tuple:
    """Rows :data:`OBS_HEADER` (rms over seeds of the fit, its reported σ, the Cramér–Rao bound
    and Quet's counting, for the latitude and eq. (10)'s Earth rate; the noise-free error is the
    estimator's own systematic floor) and :data:`FLOOR_HEADER` rows from
    :func:`systematic_floor_rows`: the bias left with every correction and without each of
    finite amplitude, spin decay and the Foucault ellipse precession. ``scene`` (name or YAML path)
    with ``overrides``: the study on any scene (its floors then with the scene's own effects)."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    over = list(overrides)
    jobs = [(scene, over + [f"duration_s={60.0 * m}"], range(n_seeds)) for m in minutes_list]
    free = [(scene, over + [f"duration_s={60.0 * m}"] + list(NOISE_FREE), [0]) for m in minutes_list]
    floor_jobs = list(minutes_list) if scene == "quet_paris" and not over else \
        [(scene, over, m) for m in minutes_list]
    own = executor is None
    executor = executor or process_executor()
    try:
        results = [_obs_rows(m, res) for m, res in zip(minutes_list, executor.map(seed_sweep, jobs))]
        noise_free = list(executor.map(seed_sweep, free))
        floor_rows = list(executor.map(systematic_floor_rows, floor_jobs))
    finally:
        if own:
            executor.shutdown()
    rows = []
    for res, nf in zip(results, noise_free):
        a = np.array([[x if x is not None else np.nan for x in r] for r in res], dtype=float)
        rms = lambda j: float(np.sqrt(np.nanmean(a[:, j] ** 2))) if np.isfinite(a[:, j]).any() else None  # noqa: E731
        mean = lambda j: float(np.nanmean(a[:, j])) if np.isfinite(a[:, j]).any() else None  # noqa: E731
        e = _obs_rows(a[0, 0], nf)[0]
        rows.append((a[0, 0], rms(1), mean(2), mean(3), rms(4), rms(5), mean(6), mean(7), rms(8), e[1], e[5]))
    # a scope the scene has no instrument for (no pendulum, no gyroscope pair) gives only empty rows
    scopes = {r[2] for rws in floor_rows for r in rws if r[3] is not None or r[4] is not None}
    fl = [row for rws in floor_rows for row in rws if row[2] in scopes]
    return rows, fl


SITE_HEADER = ("latitude_deg", "rms_error_deg", "mean_sigma_deg", "crlb_deg", "rms_earth_rate_error_rad_s",
               "crlb_earth_rate_rad_s")


def seed_sweeps(jobs, executor=None, workers=None) -> list:
    """``seed_sweep`` over ``jobs`` through ``executor`` (by default a process pool of ``workers``,
    shut down after): one list of estimates per job."""
    own = executor is None
    executor = executor or process_executor(workers)
    try:
        return list(executor.map(seed_sweep, jobs))
    finally:
        if own:
            executor.shutdown()


def site_sweep(latitudes_deg, n_seeds, minutes=10.0, executor=None) -> list:
    """Rows :data:`SITE_HEADER`: quet_paris moved to each latitude (10 min per configuration),
    rms errors over seeds against the reported σ and the Cramér–Rao bound — one
    ``seed_sweep`` job per site through the executor (any ``concurrent.futures`` executor)."""
    jobs = [("quet_paris", [f"site.latitude_deg={lat}", f"duration_s={60.0 * minutes}"], range(n_seeds))
            for lat in latitudes_deg]
    results = seed_sweeps(jobs, executor)
    rows = []
    for lat, res in zip(latitudes_deg, results):
        dl = [r["latitude_deg"] - r["truth"]["latitude_deg"] for r in res if r["latitude_deg"] is not None]
        dn = [r["earth_rate_rad_s"] - r["truth"]["earth_rate_rad_s"] for r in res if r["earth_rate_rad_s"] is not None]
        rms = lambda v: float(np.sqrt(np.mean(np.square(v)))) if v else math.nan  # noqa: E731
        mean = lambda v: float(np.mean(v)) if v else math.nan  # noqa: E731
        rows.append((float(lat), rms(dl), mean([r["latitude_sigma_deg"] for r in res if r["latitude_sigma_deg"]]),
                     mean([r["crlb"]["latitude_deg"] for r in res if r["crlb"].get("latitude_deg")]), rms(dn),
                     mean([r["crlb"]["earth_rate_rad_s"] for r in res if r["crlb"].get("earth_rate_rad_s")])))
    return rows


PLANNER_HEADER = ("scene", "target", "value", "planned_observation_s", "planned_sigma", "achieved_rms", "seeds",
                  "achieved_over_target")


def default_targets(scene, overrides=()) -> list:
    """Targets whose plans land near the scene's own duration_s: its latitude and Earth-rate bounds there,
    rounded to two significant digits (SceneError when the scene has no Earth-rate instrument)."""
    from gyro_instrument.estimators.planner import ARCSEC_RAD, Planner, SensorSpec, instrument_models
    sc = load_scene(scene, list(overrides))
    models = instrument_models(sc)[0]
    if not models:
        return []
    b = Planner(models, SensorSpec.from_scene(sc), sc.estimator.get("hemisphere")).bounds(sc.duration_s)[0]
    two = lambda x: format(x, ".2g")  # noqa: E731
    out = []
    if b.get("latitude_rad"):
        out.append("latitude_arcsec=" + two(b["latitude_rad"] / ARCSEC_RAD))
    if b.get("earth_rate_rad_s"):
        out.append("earth_rate_rad_s=" + two(b["earth_rate_rad_s"]))
    return out


def planner_accuracy(cases, n_seeds, executor=None, progress=print) -> list:
    """Rows :data:`PLANNER_HEADER`: for each (scene, overrides, target strings) the planned
    observation time and bound (:func:`gyro_instrument.estimators.planner.plan`) and the rms achieved
    over ``n_seeds`` seeded runs at that time (``verify_plan``, through the executor)."""
    from gyro_instrument.estimators.planner import parse_targets, plan, verify_plan
    own = executor is None
    executor = executor or process_executor()
    rows = []
    try:
        for scene, overrides, targets in cases:
            d = plan(scene, overrides, parse_targets(targets), noise_factors=(), rate_factors=(), floor=False)
            verify_plan(d, n_seeds, executor, progress=lambda m: progress(f"  {scene}: {m.strip()}"))
            for e in d["targets"]:
                v = e.get("verify") or {}
                rows.append((d["scene"], e["target"], e["value"], e.get("observation_s"), e.get("planned_sigma"),
                             v.get("achieved_rms"), n_seeds, v.get("achieved_over_target")))
    finally:
        if own:
            executor.shutdown()
    return rows


def _planner_lines(pl):
    lines = ["", "## How long must I observe? The planner against the Monte Carlo", "",
             "`gyro-instrument plan SCENE --target ...`: the observation time per configuration from the "
             "Cramér–Rao bound, and the rms achieved by seeded runs at that time.", "",
             "| scene | target | planned T (s) | planned σ | achieved rms | seeds | achieved / target |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {sc} | {t} = {v:g} | {_fmt(T, '.4g')} | {_fmt(s, '.3g')} | {_fmt(a, '.3g')} | {n} | {_fmt(r, '.3f')} |"
              for sc, t, v, T, s, a, n, r in pl]
    return lines


def run_scene_bench(out_dir, scene, overrides=(), quick=False, progress=print) -> str:
    """``bench --scene``: the observation-time study (with its systematic floors, the scene's own
    effects) and the planner's accuracy on any scene; CSVs, plot and summary.md. Returns the text."""
    os.makedirs(out_dir, exist_ok=True)
    name = load_scene(scene, list(overrides)).name
    progress(f"observation time ({name})")
    ot, floors = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40,
                                  scene=scene, overrides=overrides)
    _write(os.path.join(out_dir, "observation_time.csv"), OBS_HEADER, ot)
    _write(os.path.join(out_dir, "systematic_floors.csv"), FLOOR_HEADER, floors)
    progress(f"planner accuracy ({name})")
    targets = default_targets(scene, overrides)
    pl = planner_accuracy([(scene, list(overrides), targets)], 16 if quick else 100, progress=progress) if targets else []
    _write(os.path.join(out_dir, "planner.csv"), PLANNER_HEADER, pl)
    from gyro_instrument.bench.plots import write_plots
    pngs = write_plots(out_dir)
    lines = [f"# gyro-instrument bench --scene {scene}" + (" (quick)" if quick else ""), "",
             f"Regenerate: `gyro-instrument bench --scene {scene}" + "".join(f" --set {o}" for o in overrides)
             + (" --quick" if quick else "") + f" --out {out_dir}`.", ""]
    lines += _obs_lines(ot, floors, name, "the scene's own effects")
    lines += _planner_lines(pl)
    return _write_summary(out_dir, lines, pngs)


def _write_summary(out_dir, lines, pngs):
    """summary.md in ``out_dir`` from ``lines`` and the plots' PNG paths (written last, atomically:
    a bench directory without it is an interrupted bench); returns the text."""
    if pngs:
        lines = lines + ["", "## Plots", ""] + [f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs]
    text = "\n".join(lines) + "\n"
    with replaced_atomically(os.path.join(out_dir, "summary.md")) as tmp, open(tmp, "w") as fh:
        fh.write(text)
    return text


def _obs_lines(ot, floors, name, floor_scene):
    lines = ["## Error versus observation time (" + name + ", per configuration)", "",
             "| minutes | latitude rms, fit (deg) | reported σ | Cramér–Rao | rms, counting | noise-free error | "
             "Earth rate n rms, fit (rad/s) | reported σ | Cramér–Rao | rms, counting | noise-free error |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    obs_cols = ("rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg", "noise_free_error_deg",
                "rms_fit_earth_rate_rad_s", "mean_sigma_earth_rate_rad_s", "crlb_earth_rate_rad_s",
                "rms_counting_earth_rate_rad_s", "noise_free_earth_rate_error_rad_s")
    for r in ot:
        d = dict(zip(OBS_HEADER, r))
        lines.append("| {:g} | ".format(d["minutes"]) + " | ".join(
            _fmt(d[k], ".1e" if k.startswith("noise_free") else ".2e") for k in obs_cols) + " |")
    lines += ["", f"Systematic floors: the noise-free bias on {floor_scene}, with every "
              "correction of the estimator applied (left out: none) and with one left out:", "",
              "| minutes | correction left out | scope | latitude bias (deg) | Earth-rate bias (rad/s) |",
              "|---|---|---|---|---|"]
    lines += [f"| {m:g} | {e} | {sc} | {_fmt(a, '.2e')} | {_fmt(b, '.2e')} |" for m, e, sc, a, b in floors]
    return lines


def run_bench(out_dir, quick=False, progress=print, scene=None, overrides=(), executor=None) -> str:
    """Run every study, write CSVs, PNGs (with matplotlib) and summary.md; return the summary text.
    With ``scene``: only the observation-time study and the planner's accuracy on that scene
    (:func:`run_scene_bench`).

    ``executor``: where the sweeps run (observation time, site sweep, effect cost); default a
    spawned process pool per study (:func:`~gyro_instrument.core.parallel.process_executor`), e.g.
    a Dask client's executor for ``bench --scheduler``."""
    if scene is not None:
        return run_scene_bench(out_dir, scene, overrides, quick, progress)
    from gyro_instrument.bench.effect_cost import effect_cost_rows, write_effect_cost_csv
    from gyro_instrument.bench.plots import write_plots
    os.makedirs(out_dir, exist_ok=True)
    progress("work-precision (Foucault pendulum, plane gyroscope)")
    wp = work_precision(quick, progress)
    _write(os.path.join(out_dir, "work_precision.csv"),
           ("instrument", "method", "setting", "cpu_s", "nfev", "error_rad"), wp)
    tg, st, rt, gwp = _speed_studies(out_dir, wp, quick, progress)
    progress("observation time")
    ot, floors = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40,
                                  executor=executor)
    _write(os.path.join(out_dir, "observation_time.csv"), OBS_HEADER, ot)
    _write(os.path.join(out_dir, "systematic_floors.csv"), FLOOR_HEADER, floors)
    progress("planner accuracy (plan, then the Monte Carlo at the planned time)")
    pl = planner_accuracy([("quet_paris", [], ["latitude_arcsec=1", "earth_rate_rad_s=1e-10"])]
                          + ([] if quick else [("quet_gyroscopes", ["site.latitude_deg=60"], ["latitude_arcsec=1"])]),
                          16 if quick else 200, progress=progress)
    _write(os.path.join(out_dir, "planner.csv"), PLANNER_HEADER, pl)
    progress("site sweep")
    ss = site_sweep((-85, -60, -33.9, 5, 30, 48.8462, 70, 85) if not quick else (-33.9, 48.8462),
                    40 if not quick else 4, minutes=10.0 if not quick else 2.0, executor=executor)
    _write(os.path.join(out_dir, "site_sweep.csv"), SITE_HEADER, ss)
    progress("effect cost")
    ec = effect_cost_rows(["quet_paris", "foucault_pantheon"] if quick else None,
                          duration_s=120.0 if quick else None, executor=executor)
    write_effect_cost_csv(os.path.join(out_dir, "effect_cost.csv"), ec)
    progress("north: accuracy versus observation time per method, systematic floors, the gyrotheodolite")
    from gyro_instrument.bench.north_study import north_bench, north_lines, write_north_csv
    ns, nsc = north_bench(quick, executor=executor)
    write_north_csv(os.path.join(out_dir, "north_accuracy.csv"), os.path.join(out_dir, "north_gyrotheodolite.csv"),
                    ns, nsc, _write)
    pngs = write_plots(out_dir)
    if not pngs:
        progress("plots need matplotlib: pip install matplotlib (or the 'plot' extra); the CSVs are written")
    lines = _bench_summary_lines(out_dir, quick, tg, st, wp, rt, gwp, ot, floors, pl, ss, ec) + north_lines(ns, nsc)
    return _write_summary(out_dir, lines, pngs)


def _speed_studies(out_dir, wp, quick, progress) -> tuple:
    """The speed targets (targets.csv: work-precision targets, run as it streams, real time of every
    instrument configuration, plot of a day) and the streaming rows (streaming.csv); returns
    (targets, streaming rows, real-time rows, gimbal work-precision rows)."""
    progress("speed targets")
    tg = targets(wp, quick, progress)
    if not quick:       # child processes for minutes: the full bench only (issue 13: bench/live.py)
        from gyro_instrument.bench.live import live_rows
        progress("run as it streams: time to first message (1 h, 48 h), peak memory (1 h vs 48 h)")
        tg += live_rows(quick, progress)
    from gyro_instrument.bench.realtime import gimbal_work_precision_rows, realtime_rows, realtime_target, write_realtime
    progress("real-time factor of every instrument configuration; the gimbal's work-precision")
    rt, gwp = realtime_rows(quick, progress), gimbal_work_precision_rows(quick, progress)
    write_realtime(out_dir, rt, gwp)
    tg.append(realtime_target(rt))
    hours = 3.0 if quick else 24.0
    progress(f"  plot: {hours:g} h of Foucault pendulum data from Parquet")
    secs, n = plot_day_seconds(out_dir, hours=hours)
    tg.append((f"plot {hours:g} h of pendulum data at 20 Hz ({n} samples, Parquet, 4 views to PNG), wall time",
               secs if secs is not None else float("nan"), "s" + ("" if secs is not None else
                                                                   " (matplotlib or pyarrow missing)"),
               "<= 10", secs is not None and secs <= 10.0))
    _write(os.path.join(out_dir, "targets.csv"), ("target", "measured", "unit", "goal", "met"), tg)
    progress("streaming: whole simulate process against the textbook script, peak memory, output throughput")
    from gyro_instrument.bench.streaming import streaming_rows
    st = streaming_rows(wp, REFERENCE[(3600.0 if quick else 86164.0989, 20.0)], quick, progress)
    _write(os.path.join(out_dir, "streaming.csv"), ("target", "measured", "unit", "goal", "met"), st)
    return tg, st, rt, gwp


def _bench_summary_lines(out_dir, quick, tg, st, wp, rt, gwp, ot, floors, pl, ss, ec) -> list:
    """summary.md's lines (every table of the full bench; the plots are appended by
    :func:`_write_summary`)."""
    from gyro_instrument.bench.effect_cost import HEADER as EC_HEADER
    from gyro_instrument.bench.realtime import summary_lines
    lines = ["# gyro-instrument bench" + (" (quick)" if quick else ""), "",
             "Regenerate: `gyro-instrument bench" + (" --quick" if quick else "") + f" --out {out_dir}`.", "",
             "## Speed targets (measured in this run)", "",
             "| target | measured | unit | goal | met |", "|---|---|---|---|---|"]
    lines += [f"| {a} | {b:.4g} | {c} | {d} | {'yes' if e else 'no'} |" for a, b, c, d, e in tg]
    lines += streaming_lines(st)
    lines += ["", "## Work-precision (error at the end against a tight reference)", "",
              "| instrument | method | setting | CPU s | RHS evaluations | error (rad) |", "|---|---|---|---|---|---|"]
    lines += [f"| {i} | {m} | {st} | {c:.3g} | {n} | {e:.2e} |" for i, m, st, c, n, e in wp]
    lines += [""] + summary_lines(rt, gwp)
    lines += [""] + _obs_lines(ot, floors, "quet_paris", "quet_paris with a 1 h spin decay added")
    lines += _planner_lines(pl)
    lines += ["", "## Error versus site latitude (quet_paris moved, rms over seeds)", "",
              "| latitude (deg) | rms error (deg) | reported σ (deg) | Cramér–Rao (deg) | n rms error (rad/s) | "
              "n Cramér–Rao (rad/s) |", "|---|---|---|---|---|---|"]
    lines += ["| {:g} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |".format(*r) for r in ss]
    lines += ["", "## Effect cost (leave one effect out; noise-free)", "",
              "| scene | effect | instrument | CPU with (s) | CPU without (s) | largest angle change (rad) | "
              "latitude change (deg) | Earth-rate change (rad/s) |", "|---|---|---|---|---|---|---|---|"]
    for r in ec:
        d = dict(zip(EC_HEADER, r))
        lines.append("| {scene} | {effect} | {instrument} | {a} | {b} | {c} | {dl} | {dn} |".format(
            scene=d["scene"], effect=d["effect"] or "— (" + (d.get("note") or "no effect to leave out") + ")",
            instrument=d["instrument"] or "—", a=_fmt(d["cpu_with_s"], ".3g"),
            b=_fmt(d["cpu_without_s"], ".3g"), c=_fmt(d["max_abs_diff_rad"], ".2e"),
            dl=_fmt(d["dlatitude_deg"], ".2e"), dn=_fmt(d["dearth_rate_rad_s"], ".2e")))
    return lines


def streaming_lines(rows) -> list:
    """summary.md's section of the streaming rows (:mod:`.streaming`)."""
    lines = ["", "## Streaming: whole simulate process, peak memory, output (measured in this run)", "",
             "| target | measured | unit | goal | met |", "|---|---|---|---|---|"]
    return lines + [f"| {a} | {b:.4g} | {c} | {d} | {'yes' if e else ('—' if d == '—' else 'no')} |"
                    for a, b, c, d, e in rows]


def plot_day_seconds(out_dir, hours=24.0, rate_hz=20.0) -> tuple:
    """Wall time of ``gyro-instrument plot`` on a day of pendulum data: the 67 m Foucault pendulum
    of ``foucault_pantheon`` from Binet's closed form over ``hours`` at ``rate_hz`` (1.7 million
    samples for a day at 20 Hz), written as Parquet, then every view drawn from the file (read,
    swing-plane azimuth per period, bob path, residuals). Returns (seconds, samples); (None, n)
    without matplotlib or pyarrow."""
    import tempfile
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.estimators.data_io import write_table
    from gyro_instrument.views import plot_file
    scene = load_scene("foucault_pantheon", [f"duration_s={hours * 3600.0}", f"sample_rate_hz={rate_hz}"])
    p = build_instruments(scene)["pendulum"]
    t = sample_times(scene)
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, p.p.length_m, p.context.gravity_m_s2, scene.site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "day.parquet")
        try:
            write_table(data, t, {"pendulum.x_east": x, "pendulum.y_north": y})
            t0 = time.perf_counter()
            plot_file(data, os.path.join(out_dir, "plot_day"), "foucault_pantheon", overwrite=True)
        except SceneError:
            return None, t.size
        return time.perf_counter() - t0, t.size


def _fmt(x, spec):
    return "—" if x is None else format(x, spec)


def _write(path, header, rows):
    with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
