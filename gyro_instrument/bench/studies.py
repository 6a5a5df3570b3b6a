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


def foucault_work_precision(duration_s, rtols, parareal_settings, rate_hz=20.0, progress=print) -> list:
    """Rows (instrument, tier, setting, cpu_s, nfev, error_rad): the 67 m Foucault pendulum
    released at 2°, output at ``rate_hz``; error = swing-plane azimuth at the last sample against
    DOP853 at rtol 1e-13 on the full equations (the tight reference). Tiers: Binet's closed form
    (linear model), Quet's comparison pendulum (the first swing of the full model repeated and
    turned by its apsidal angle), the linear (small-angle) model, and the full model with DOP853
    (the textbook baseline) or the parareal fast path."""
    name = f"Foucault pendulum 67 m, {duration_s:g} s at {rate_hz:g} Hz"
    progress(f"  reference: DOP853 rtol 1e-13 over {duration_s:g} s")
    p, t, scene = _pendulum(duration_s, rate_hz, rtol=1e-13)
    ref = _end_swing_azimuth(p.simulate(t))
    rows = []

    def add(tier, setting, sim, cpu, nfev):
        rows.append((name, tier, setting, cpu, nfev, abs(_wrapped(_end_swing_azimuth(sim) - ref))))

    for rtol in rtols:
        p, t, _ = _pendulum(duration_s, rate_hz, rtol=rtol)
        sim, cpu = _cpu(lambda: p.simulate(t))
        add("full equations, DOP853", f"rtol {rtol:g}", sim, cpu, sim.trajectory.nfev)
        progress(f"  DOP853 rtol {rtol:g}: {cpu:.2f} s CPU, error {rows[-1][-1]:.2e} rad")
    for steps, tol in parareal_settings:
        p, t, _ = _pendulum(duration_s, rate_hz, integrator="parareal", segment_steps=steps, shooting_tol=tol)
        sim, cpu = _cpu(lambda: p.simulate(t))
        add("full equations, parareal RK8 (fast path)", f"{steps} steps/swing, tol {tol:g}", sim, cpu,
            sim.trajectory.nfev)
        progress(f"  parareal {steps} steps, tol {tol:g}: {cpu:.2f} s CPU, error {rows[-1][-1]:.2e} rad")
    p, t, _ = _pendulum(duration_s, rate_hz, rtol=1e-10, effects=("earth_rotation", "centrifugal"))
    sim, cpu = _cpu(lambda: p.simulate(t))
    add("linear (small-angle) model, DOP853", "rtol 1e-10", sim, cpu, sim.trajectory.nfev)
    p, t, _ = _pendulum(duration_s, rate_hz)
    (pos, vel, nfev), cpu = _cpu(lambda: p.comparison_solution(t))
    sim = Simulation(t, pendulum_columns(pos, vel, p.g / p.l), None)
    add("Quet's comparison pendulum (first swing turned by its apsidal angle)", "", sim, cpu, nfev)
    r0, v0 = p.initial_state()

    def binet():
        x, y, vx, vy = binet_ellipse(t, p.l, p.g, scene.site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1],
                                     velocity=True)
        z = -np.sqrt(np.maximum(p.l ** 2 - x * x - y * y, 0.0))
        return pendulum_columns(np.vstack([x, y, z]), np.vstack([vx, vy, 0 * vx]), p.g / p.l)
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
    k = math.sin(g.u0 / 2.0)
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
        gr += other_work_precision(60.0, (1e-6, 1e-9), progress=progress)
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
                      if recorded.get(tp, 0) != n or (tp.endswith("/joint_states") and n != stats["samples"]))
        if lost:
            return None, f"recording incomplete on {lost}"
        return stats["real_time_factor_achieved"], ""


def _obs_rows(minutes, results):
    out = []
    for r in results:
        truth = r["truth"]
        cnt = r["methods"].get("item9_counting", {}).get("latitude_deg")
        out.append((minutes, r["latitude_deg"] - truth["latitude_deg"], r["latitude_sigma_deg"],
                    r["crlb"]["latitude_deg"], None if cnt is None else cnt - truth["latitude_deg"],
                    r["earth_rate_rad_s"] - truth["earth_rate_rad_s"], r["earth_rate_sigma_rad_s"],
                    r["crlb"]["earth_rate_rad_s"], _counting_earth_rate(r) - truth["earth_rate_rad_s"]))
    return out


def _counting_earth_rate(r):
    """Eq. (10) with Quet's counted meridian swing instead of the fitted one: n ∝ 1/T²."""
    g = r["instruments"].get("gyro_meridian", {})
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
    without it). One picklable argument, so it runs through any executor."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    from gyro_instrument.estimators.pipeline import CORRECTIONS, estimate_records, measure, simulate_truth
    from gyro_instrument.scenes import load_scene
    scene = load_scene("quet_paris", [f"duration_s={60.0 * minutes}", FLOOR_SCENE_EFFECTS] + list(NOISE_FREE))
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
            k = r["instruments"].get("pendulum", {}).get("foucault_rate_rad_s")
            lat = None if k is None or abs(k) > n0 else math.degrees(math.asin(k / n0))
            rows.append((minutes, left_out, PENDULUM_ALONE, None if lat is None else lat - lat0, None))
    return rows


def observation_time(minutes_list, n_seeds, executor=None) -> tuple:
    """Rows :data:`OBS_HEADER` (rms over seeds of the fit, its reported σ, the Cramér–Rao bound
    and Quet's counting, for the latitude and eq. (10)'s Earth rate; the noise-free error is the
    estimator's own systematic floor) and :data:`FLOOR_HEADER` rows from
    :func:`systematic_floor_rows`: the bias left with every correction and without each of
    finite amplitude, spin decay and the Foucault ellipse precession."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    jobs = [("quet_paris", [f"duration_s={60.0 * m}"], range(n_seeds)) for m in minutes_list]
    free = [("quet_paris", [f"duration_s={60.0 * m}"] + list(NOISE_FREE), [0]) for m in minutes_list]
    own = executor is None
    executor = executor or process_executor()
    try:
        results = [_obs_rows(m, res) for m, res in zip(minutes_list, executor.map(seed_sweep, jobs))]
        noise_free = list(executor.map(seed_sweep, free))
        floor_rows = list(executor.map(systematic_floor_rows, minutes_list))
    finally:
        if own:
            executor.shutdown()
    rows = []
    for res, nf in zip(results, noise_free):
        a = np.array([[x if x is not None else np.nan for x in r] for r in res], dtype=float)
        rms = lambda j: float(np.sqrt(np.nanmean(a[:, j] ** 2)))  # noqa: E731
        mean = lambda j: float(np.mean(a[:, j]))  # noqa: E731
        e = nf[0]
        rows.append((a[0, 0], rms(1), mean(2), mean(3), rms(4), rms(5), mean(6), mean(7), rms(8),
                     e["latitude_deg"] - e["truth"]["latitude_deg"],
                     e["earth_rate_rad_s"] - e["truth"]["earth_rate_rad_s"]))
    fl = [row for rws in floor_rows for row in rws]
    return rows, fl


SITE_HEADER = ("latitude_deg", "rms_error_deg", "mean_sigma_deg", "crlb_deg", "rms_earth_rate_error_rad_s",
               "crlb_earth_rate_rad_s")


def site_sweep(latitudes_deg, n_seeds, minutes=10.0, executor=None) -> list:
    """Rows :data:`SITE_HEADER`: quet_paris moved to each latitude (10 min per configuration),
    rms errors over seeds against the reported σ and the Cramér–Rao bound — one
    ``seed_sweep`` job per site through the executor (any ``concurrent.futures`` executor)."""
    jobs = [("quet_paris", [f"site.latitude_deg={lat}", f"duration_s={60.0 * minutes}"], range(n_seeds))
            for lat in latitudes_deg]
    own = executor is None
    executor = executor or process_executor()
    try:
        results = list(executor.map(seed_sweep, jobs))
    finally:
        if own:
            executor.shutdown()
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


def run_bench(out_dir, quick=False, progress=print) -> str:
    """Run every study, write CSVs, PNGs (with matplotlib) and summary.md; return the summary text."""
    from gyro_instrument.bench.effect_cost import effect_cost_rows, write_effect_cost_csv
    from gyro_instrument.bench.plots import write_plots
    os.makedirs(out_dir, exist_ok=True)
    progress("work-precision (Foucault pendulum, plane gyroscope)")
    wp = work_precision(quick, progress)
    _write(os.path.join(out_dir, "work_precision.csv"),
           ("instrument", "method", "setting", "cpu_s", "nfev", "error_rad"), wp)
    progress("speed targets")
    tg = targets(wp, quick, progress)
    _write(os.path.join(out_dir, "targets.csv"), ("target", "measured", "unit", "goal", "met"), tg)
    progress("observation time")
    ot, floors = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40)
    _write(os.path.join(out_dir, "observation_time.csv"), OBS_HEADER, ot)
    _write(os.path.join(out_dir, "systematic_floors.csv"), FLOOR_HEADER, floors)
    progress("site sweep")
    ss = site_sweep((-85, -60, -33.9, 5, 30, 48.8462, 70, 85) if not quick else (-33.9, 48.8462),
                    40 if not quick else 4, minutes=10.0 if not quick else 2.0)
    _write(os.path.join(out_dir, "site_sweep.csv"), SITE_HEADER, ss)
    progress("effect cost")
    ec = effect_cost_rows(["quet_paris", "foucault_pantheon"] if quick else None,
                          duration_s=120.0 if quick else None)
    write_effect_cost_csv(os.path.join(out_dir, "effect_cost.csv"), ec)
    pngs = write_plots(out_dir)
    if not pngs:
        progress("plots need matplotlib: pip install matplotlib (or the 'plot' extra); the CSVs are written")
    text = _summary(out_dir, quick, wp, tg, ot, floors, ss, ec, pngs)
    with replaced_atomically(os.path.join(out_dir, "summary.md")) as tmp, open(tmp, "w") as fh:
        fh.write(text)
    return text


def _summary(out_dir, quick, wp, tg, ot, floors, ss, ec, pngs):
    """summary.md: the speed targets, work-precision, observation-time, systematic-floor, site and
    effect-cost tables and the plots."""
    lines = ["# gyro-instrument bench" + (" (quick)" if quick else ""), "",
             "Regenerate: `gyro-instrument bench" + (" --quick" if quick else "") + f" --out {out_dir}`.", "",
             "## Speed targets (measured in this run)", "",
             "| target | measured | unit | goal | met |", "|---|---|---|---|---|"]
    lines += [f"| {a} | {b:.4g} | {c} | {d} | {'yes' if e else 'no'} |" for a, b, c, d, e in tg]
    lines += ["", "## Work-precision (error at the end against a tight reference)", "",
              "| instrument | method | setting | CPU s | RHS evaluations | error (rad) |", "|---|---|---|---|---|---|"]
    lines += [f"| {i} | {m} | {st} | {c:.3g} | {n} | {e:.2e} |" for i, m, st, c, n, e in wp]
    lines += ["", "## Error versus observation time (quet_paris, per configuration)", "",
              "| minutes | latitude rms, fit (deg) | reported σ | Cramér–Rao | rms, counting | noise-free error | "
              "Earth rate n rms, fit (rad/s) | reported σ | Cramér–Rao | rms, counting | noise-free error |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    lines += _observation_rows(ot)
    lines += ["", "Systematic floors: the noise-free bias on quet_paris with a 1 h spin decay added, with every "
              "correction of the estimator applied (left out: none) and with one left out:", "",
              "| minutes | correction left out | scope | latitude bias (deg) | Earth-rate bias (rad/s) |",
              "|---|---|---|---|---|"]
    lines += [f"| {m:g} | {e} | {sc} | {_fmt(a, '.2e')} | {_fmt(b, '.2e')} |" for m, e, sc, a, b in floors]
    lines += ["", "## Error versus site latitude (quet_paris moved, rms over seeds)", "",
              "| latitude (deg) | rms error (deg) | reported σ (deg) | Cramér–Rao (deg) | n rms error (rad/s) | "
              "n Cramér–Rao (rad/s) |", "|---|---|---|---|---|---|"]
    lines += ["| {:g} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |".format(*r) for r in ss]
    lines += ["", "## Effect cost (leave one effect out; noise-free)", "",
              "| scene | effect | instrument | CPU with (s) | CPU without (s) | largest angle change (rad) | "
              "latitude change (deg) | Earth-rate change (rad/s) |", "|---|---|---|---|---|---|---|---|"]
    lines += _effect_cost_rows(ec)
    if pngs:
        lines += ["", "## Plots", ""] + [f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs]
    return "\n".join(lines) + "\n"


def _observation_rows(ot):
    """Markdown rows of the error-versus-observation-time table."""
    lines = []
    obs_cols = ("rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg", "noise_free_error_deg",
                "rms_fit_earth_rate_rad_s", "mean_sigma_earth_rate_rad_s", "crlb_earth_rate_rad_s",
                "rms_counting_earth_rate_rad_s", "noise_free_earth_rate_error_rad_s")
    for r in ot:
        d = dict(zip(OBS_HEADER, r))
        lines.append("| {:g} | ".format(d["minutes"]) + " | ".join(
            _fmt(d[k], ".1e" if k.startswith("noise_free") else ".2e") for k in obs_cols) + " |")
    return lines


def _effect_cost_rows(ec):
    """Markdown rows of the effect-cost table."""
    from gyro_instrument.bench.effect_cost import HEADER as EC_HEADER
    lines = []
    for r in ec:
        d = dict(zip(EC_HEADER, r))
        lines.append("| {scene} | {effect} | {instrument} | {a} | {b} | {c} | {dl} | {dn} |".format(
            scene=d["scene"], effect=d["effect"] or "— (" + (d.get("note") or "no effect to leave out") + ")",
            instrument=d["instrument"] or "—", a=_fmt(d["cpu_with_s"], ".3g"),
            b=_fmt(d["cpu_without_s"], ".3g"), c=_fmt(d["max_abs_diff_rad"], ".2e"),
            dl=_fmt(d["dlatitude_deg"], ".2e"), dn=_fmt(d["dearth_rate_rad_s"], ".2e")))
    return lines


def _fmt(x, spec):
    return "—" if x is None else format(x, spec)


def _write(path, header, rows):
    with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
