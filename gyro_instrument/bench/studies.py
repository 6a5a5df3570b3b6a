"""The bench studies (see the package docstring)."""

import csv
import math
import os
import time

import numpy as np

from gyro_instrument.core.parallel import process_executor
from gyro_instrument.core.scene import sample_times
from gyro_instrument.estimators.period import fit_oscillation
from gyro_instrument.estimators.pipeline import seed_sweep
from gyro_instrument.instruments.pendulum import binet_ellipse
from gyro_instrument.scenes import build_instruments, load_scene


def _cpu(f):
    c0 = time.process_time()
    out = f()
    return out, time.process_time() - c0


def _swing_azimuth_end(pos, vel, w0sq):
    n, e, vn, ve = pos[1, -1], pos[0, -1], vel[1, -1], vel[0, -1]
    return 0.5 * math.atan2(2 * (w0sq * n * e + vn * ve), (w0sq * n * n + vn * vn) - (w0sq * e * e + ve * ve))


def work_precision(duration_s, tolerances):
    """Rows (method, rtol, cpu_s, nfev, azimuth_error_rad) for the Foucault pendulum."""
    rows = []
    scene = load_scene("foucault_pantheon", [f"duration_s={duration_s}", "sample_rate_hz=1"])
    t = sample_times(scene)

    def run(rtol, effects=None):
        over = [f"duration_s={duration_s}", "sample_rate_hz=1", f"instruments.pendulum.rtol={rtol}"]
        if effects is not None:
            over.append("effects={" + ", ".join(f"{e}: {{}}" for e in effects) + "}")
        p = build_instruments(load_scene("foucault_pantheon", over))["pendulum"]
        sim, cpu = _cpu(lambda: p.simulate(t))
        return p, sim, cpu

    p, ref, _ = run(1e-13)
    w0sq = p.g / p.l
    ref_az = _swing_azimuth_end(ref.extra["position_enu"], ref.extra["velocity_enu"], w0sq)
    for rtol in tolerances:
        _, sim, cpu = run(rtol)
        az = _swing_azimuth_end(sim.extra["position_enu"], sim.extra["velocity_enu"], w0sq)
        rows.append(("DOP853 full equations", rtol, cpu, sim.trajectory.nfev, abs(az - ref_az)))
    r0, v0 = p.initial_state()

    def binet():
        return binet_ellipse(t, p.l, p.g, scene.site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    (x, y), cpu = _cpu(binet)
    # velocities of the closed form by differencing the last two samples' neighbourhood
    xe, ye = binet_ellipse(t[-1:] + np.array([-1e-3, 1e-3]), p.l, p.g, scene.site.k_vertical_rad_s,
                           r0[0], r0[1], v0[0], v0[1])
    pos = np.array([[x[-1]], [y[-1]]])
    vel = np.array([[(xe[1] - xe[0]) / 2e-3], [(ye[1] - ye[0]) / 2e-3]])
    az = _swing_azimuth_end(np.vstack([pos, [[0.0]]]), np.vstack([vel, [[0.0]]]), w0sq)
    rows.append(("Binet closed form (linear model)", 0.0, cpu, 0, abs(az - ref_az)))
    return rows


def targets():
    """Rows (target, measured, unit, goal)."""
    rows = []
    scene = load_scene("quet_paris", ["duration_s=3600"])
    insts = build_instruments(scene)
    t = sample_times(scene)
    _, cpu = _cpu(lambda: [insts[n].simulate(t) for n in ("gyro_horizontal", "gyro_meridian")])
    rows.append(("1 h of both plane-gyroscope configurations at 20 Hz", cpu, "s CPU", "<= 0.5"))
    rng = np.random.default_rng(0)
    tt = np.arange(0, 600, 0.05)
    y = 0.1 * np.cos(0.245 * tt) + rng.normal(0, 1e-4, tt.size)
    k = 20
    _, cpu = _cpu(lambda: [fit_oscillation(tt, y, harmonics=(1, 3)) for _ in range(k)])
    rows.append(("estimator throughput (sine fit, 3rd harmonic)", k * tt.size / cpu, "samples/s", ">= 1e6"))
    return rows


def _obs_rows(minutes, results):
    out = []
    for r in results:
        truth = r["truth"]["latitude_deg"]
        cnt = r["methods"].get("item9_counting", {}).get("latitude_deg")
        out.append((minutes, r["latitude_deg"] - truth, r["latitude_sigma_deg"], r["crlb"]["latitude_deg"],
                    None if cnt is None else cnt - truth))
    return out


def observation_time(minutes_list, n_seeds, executor=None):
    """Rows (minutes, rms_fit_deg, mean_sigma_deg, crlb_deg, rms_counting_deg)."""
    jobs = [("quet_paris", [f"duration_s={60.0 * m}"], range(n_seeds)) for m in minutes_list]
    own = executor is None
    executor = executor or process_executor()
    try:
        results = [_obs_rows(m, res) for m, res in zip(minutes_list, executor.map(seed_sweep, jobs))]
    finally:
        if own:
            executor.shutdown()
    rows = []
    for res in results:
        a = np.array([[x if x is not None else np.nan for x in r] for r in res], dtype=float)
        rows.append((a[0, 0], float(np.sqrt(np.mean(a[:, 1] ** 2))), float(np.mean(a[:, 2])),
                     float(np.mean(a[:, 3])), float(np.sqrt(np.nanmean(a[:, 4] ** 2)))))
    return rows


def run_bench(out_dir, quick=False, progress=print):
    """Run every study, write CSVs and summary.md; return the summary text."""
    os.makedirs(out_dir, exist_ok=True)
    dur = 600.0 if quick else 3600.0
    tols = (1e-6, 1e-8, 1e-10) if quick else (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
    progress("work-precision (Foucault pendulum)")
    wp = work_precision(dur, tols)
    _write(os.path.join(out_dir, "work_precision.csv"), ("method", "rtol", "cpu_s", "nfev", "azimuth_error_rad"), wp)
    progress("speed targets")
    tg = targets()
    _write(os.path.join(out_dir, "targets.csv"), ("target", "measured", "unit", "goal"), tg)
    progress("observation time")
    ot = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40)
    _write(os.path.join(out_dir, "observation_time.csv"),
           ("minutes", "rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg"), ot)
    lines = ["# gyro-instrument bench" + (" (quick)" if quick else ""), "",
             f"## Work-precision: Foucault pendulum, 67 m, 2°, {dur:g} s (azimuth error at the end vs rtol 1e-13)", "",
             "| method | rtol | CPU s | RHS evaluations | azimuth error (rad) |", "|---|---|---|---|---|"]
    lines += [f"| {m} | {r:g} | {c:.3f} | {n} | {e:.2e} |" for m, r, c, n, e in wp]
    lines += ["", "## Speed targets", "", "| target | measured | unit | goal |", "|---|---|---|---|"]
    lines += [f"| {a} | {b:.4g} | {c} | {d} |" for a, b, c, d in tg]
    lines += ["", "## Latitude error versus observation time (quet_paris)", "",
              "| minutes | rms error, fit (deg) | reported σ (deg) | Cramér–Rao (deg) | rms error, counting (deg) |",
              "|---|---|---|---|---|"]
    lines += [f"| {m:g} | {a:.2e} | {b:.2e} | {c:.2e} | {d:.2e} |" for m, a, b, c, d in ot]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out_dir, "summary.md"), "w") as fh:
        fh.write(text)
    return text


def _write(path, header, rows):
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
