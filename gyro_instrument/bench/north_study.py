"""Accuracy of the north-finding methods against observation time (issue 24, item 3's bench study).

Synthetic records from the analytic small-swing model (:func:`gyro_instrument.estimators.north.
damped_swing`: centre, amplitude, period, damping, drift of the centre) with white sensor noise, fed
to every method of :func:`gyro_instrument.estimators.north.north_methods`. Per observation time and
method: the rms error over seeds, the mean reported σ, the fit's Cramér–Rao bound, and the
systematic floor (the error on the noise-free record: damping and drift biases, which no amount of
averaging removes). No simulator and no CLI here: ``bench`` wires it in.
"""

import math

import numpy as np

from gyro_instrument.estimators import north


def _one(t, clean, noise_rad, seed, mark_rad):
    """The methods on one noisy copy of ``clean`` (seeded)."""
    rng = np.random.default_rng(seed)
    return north.north_methods(t, clean + rng.normal(0.0, noise_rad, t.size), noise_rad, mark_rad)[0]


def north_accuracy_vs_time(durations_s, period_s=20.0, amplitude_rad=0.05, damping_per_s=0.0,
                           drift_rad_s=0.0, noise_rad=2e-5, sample_rate_hz=20.0, centre_rad=0.0123,
                           mark_offset_rad=1e-3, seeds=20) -> list:
    """Rows ``{duration_s, method, rms_error_rad, mean_sigma_rad, crlb_rad, floor_rad, n_ok,
    refused}`` for each observation time and method (rad, s).

    ``floor_rad``: the method's error on the noise-free record (its systematic floor under the
    damping and drift given); ``crlb_rad``: :func:`~gyro_instrument.estimators.north.crlb_centre`
    at the true parameters (the same for every method: the best any method can do). The transit
    mark sits ``mark_offset_rad`` off the centre (a theodolite set near north).
    """
    rows = []
    w = 2.0 * math.pi / period_s
    for dur in durations_s:
        t = np.arange(0.0, float(dur), 1.0 / sample_rate_hz)
        clean = north.damped_swing(t, centre_rad, amplitude_rad, w, damping_per_s, 0.3, drift_rad_s, float(np.mean(t)))
        mark = centre_rad + mark_offset_rad
        crlb = north.crlb_centre(t, amplitude_rad, w, noise_rad, damping_per_s, 0.3, drift=bool(drift_rad_s))
        floor, refused = north.north_methods(t, clean, noise_rad, mark)
        if not floor:                      # too short for any reversal point: every method refused
            rows.append({"duration_s": float(dur), "method": "all", "refused": next(iter(refused.values()), "")})
            continue
        errs = {}
        for s in range(seeds):
            for name, est in _one(t, clean, noise_rad, s, mark).items():
                errs.setdefault(name, []).append((est.centre_rad - centre_rad, est.sigma_rad or math.nan))
        for name, vals in errs.items():
            e, sig = np.asarray(vals).T
            rows.append({"duration_s": float(dur), "method": name, "rms_error_rad": float(np.sqrt(np.mean(e ** 2))),
                         "mean_sigma_rad": float(np.nanmean(sig)), "crlb_rad": crlb,
                         "floor_rad": float(floor[name].centre_rad - centre_rad) if name in floor else math.nan,
                         "n_ok": int(e.size), "refused": ""})
    return rows


# ----------------------------------------------------------------------------- the emulated gyrotheodolite
#: The north methods of the estimate's ``north.methods``, in the order the tables show them.
METHODS = ("schuler_mean", "lavrov", "transit", "fit")
ARCSEC_PER_RAD = 648000.0 / math.pi


def _method_errors(result, truth_deg) -> dict:
    """{method: (azimuth error ″, reported σ ″)} of one estimate's ``north`` block (errors wrapped)."""
    block = result.get("north") or {}
    out = {}
    for name, m in (block.get("methods") or {}).items():
        if m.get("mount_azimuth_deg") is None:
            continue
        err = ((m["mount_azimuth_deg"] - truth_deg + 180.0) % 360.0 - 180.0) * 3600.0
        out[name.split("+")[0]] = (err, m.get("sigma_arcsec"))
    return out


def scene_north_rows(durations_s, seeds, scene="gyrotheodolite", overrides=(), executor=None) -> list:
    """Rows ``{duration_s, method, rms_error_arcsec, mean_sigma_arcsec, floor_arcsec, n_ok}`` of a shipped
    scene's north estimate (tape, drift, damping as the scene has them): the rms over ``seeds`` sensor
    draws (the sweep runner, :func:`~gyro_instrument.bench.sweep.run_grid`), the mean reported σ, and the
    systematic floor (the noise-free run's error: :func:`~gyro_instrument.estimators.planner.noise_free_estimate`)."""
    from gyro_instrument.bench.sweep import point_estimates, run_grid
    from gyro_instrument.estimators.planner import noise_free_estimate
    from gyro_instrument.scenes import build_instruments, load_scene
    sc = load_scene(scene, list(overrides))
    gyro = next(n for n, i in build_instruments(sc).items() if i.p.spin_rate_rad_s and getattr(i.p, "plane", "") ==
                "horizontal")
    truth = build_instruments(sc)[gyro].p.mount_azimuth_deg
    sweeps = [point_estimates(out) for out in run_grid(scene, list(overrides), ["duration_s"],
                                                  [(float(d),) for d in durations_s], range(seeds), executor)]
    rows = []
    for d, results in zip(durations_s, sweeps):
        floor = _method_errors(noise_free_estimate(scene, list(overrides), d)[1], truth)
        per = [_method_errors(r, truth) for r in results]
        for name in METHODS:
            vals = [p[name] for p in per if name in p]
            e = np.array([v[0] for v in vals])
            s = np.array([v[1] for v in vals if v[1] is not None])
            rows.append({"duration_s": float(d), "method": name, "n_ok": len(vals),
                         "rms_error_arcsec": float(np.sqrt(np.mean(e ** 2))) if e.size else math.nan,
                         "mean_sigma_arcsec": float(np.mean(s)) if s.size else math.nan,
                         "floor_arcsec": floor.get(name, (math.nan,))[0]})
    return rows


def north_bench(quick=False, executor=None) -> tuple:
    """The bench's north study: (synthetic rows, scene rows).

    Synthetic (:func:`north_accuracy_vs_time`): a swing like the gyrotheodolite scene's (full period
    480 s, amplitude 0.017 rad, 20″ noise at 1 Hz), undamped; damped (δ = 9.26e-5 1/s, the scene's
    pivot damping at τ = 3 h); damped with a centre drifting 20″/h — accuracy against observation time
    per method and each method's systematic floor under each (28 min: seven turning points, as the
    Fennel KT1's figure). Scene (:func:`scene_north_rows`): the ``gyrotheodolite`` (tape, its drift,
    damping) in each of :data:`SETUPS` (``quick``: the shipped one) at 50 min (the rotor-off swing's fit
    needs three of its reversal points) and 60 min.
    """
    seeds = 8 if quick else 40
    durations = (1680.0, 3600.0) if quick else (960.0, 1680.0, 2400.0, 3600.0, 7200.0)
    cases = {"undamped": {}, "damped": {"damping_per_s": 9.26e-5},
             "damped+drift": {"damping_per_s": 9.26e-5, "drift_rad_s": 20.0 / ARCSEC_PER_RAD / 3600.0}}
    synth = []
    for label, kw in cases.items():
        for r in north_accuracy_vs_time(durations, period_s=480.0, amplitude_rad=0.017, noise_rad=1e-4,
                                        sample_rate_hz=1.0, mark_offset_rad=2e-4, seeds=seeds, **kw):
            synth.append({"case": label, **r})
    scene = []
    for label, sets in (list(SETUPS.items())[:1] if quick else SETUPS.items()):
        scene += [{"setup": label, **r} for r in scene_north_rows((3000.0, 3600.0), 8 if quick else 40, overrides=sets,
                                                                  executor=executor)]
    return synth, scene


#: The gyrotheodolite set-ups of the scene rows: as shipped (the scale 0.25° west of north), a rough
#: pre-orientation far from north (45° at 51.5° N), and the southern set-up of issue 33 (301.7° at 52.7° S),
#: where the linear tape reduction erred by 23 and 13 σ.
SETUPS = {"shipped (mount 359.75, 47.41 N)": (),
          "mount 45, 51.5 N": ("instruments.gak1.mount_azimuth_deg=45", "site.latitude_deg=51.5"),
          "mount 301.7, 52.7 S": ("instruments.gak1.mount_azimuth_deg=301.7", "site.latitude_deg=-52.7")}


def north_lines(synth, scene) -> list:
    """summary.md's north tables (″)."""
    a = ARCSEC_PER_RAD
    lines = ["", "## North: accuracy versus observation time per method (synthetic swing, arcsec)", "",
             "| case | T (min) | method | rms error | mean σ | Cramér–Rao | systematic floor |", "|---|---|---|---|---|---|---|"]
    for r in synth:
        if r.get("method") == "all":
            continue
        lines.append(f"| {r['case']} | {r['duration_s'] / 60:.0f} | {r['method']} | {r['rms_error_rad'] * a:.3g} | "
                     f"{r['mean_sigma_rad'] * a:.3g} | {r['crlb_rad'] * a:.3g} | {r['floor_rad'] * a:+.2g} |")
    lines += ["", "## North: the gyrotheodolite scene (tape, drift, damping; arcsec)", "",
              "| set-up | T (min) | method | rms error | mean σ | noise-free error (floor) | seeds |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| {r.get('setup', '')} | {r['duration_s'] / 60:.0f} | {r['method']} | {r['rms_error_arcsec']:.3g} | "
              f"{r['mean_sigma_arcsec']:.3g} | {r['floor_arcsec']:+.2g} | {r['n_ok']} |" for r in scene]
    return lines


def write_north_csv(path_synth, path_scene, synth, scene, write) -> None:
    """The two CSVs through the bench's atomic writer ``write(path, header, rows)``."""
    h1 = ("case", "duration_s", "method", "rms_error_rad", "mean_sigma_rad", "crlb_rad", "floor_rad", "n_ok", "refused")
    write(path_synth, h1, [tuple(r.get(k, "") for k in h1) for r in synth])
    h2 = ("setup", "duration_s", "method", "rms_error_arcsec", "mean_sigma_arcsec", "floor_arcsec", "n_ok")
    write(path_scene, h2, [tuple(r.get(k, "") for k in h2) for r in scene])
