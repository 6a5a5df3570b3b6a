"""North in the same time: the rate-gyro north finders beside the gyrotheodolite (issue 35 item 3).

The study the rate gyro's kind runs for ``gyro-instrument bench`` (its optional ``bench`` member:
:meth:`.rate_gyro_kind.RateAzimuthKind.bench`): the bench asks every registered kind, never this module.

Each shipped rate-gyro scene is run for the gyrotheodolite's hour (``duration_s`` = 3600 s; the
two-position and carousel scenes ship shorter records) and estimated over seeded sensor draws (the
gyro's own error model: turn-on bias, bias instability, angle random walk): per scene the rms of the
mount azimuth's error, the mean reported σ, the planner's Cramér–Rao bound
(:func:`~gyro_instrument.estimators.north.rate_gyro_plan.sigma_mount_rad`) and the noise-free error. The
gyrotheodolite's row is the bench's own scene row (:func:`.north_study.scene_north_rows`: the fit at
60 min, as shipped). No simulator beyond each scene's closed form; seconds in all.
"""

import math
import os

import numpy as np

from gyro_instrument.estimators.north import rate_gyro as R
from gyro_instrument.estimators.measure import measure, simulate_truth
from gyro_instrument.estimators.north.rate_gyro_plan import sigma_mount_rad
from gyro_instrument.scenes import load_scene

#: the rate-gyro scenes compared and what they are
SCENES = {"rate_gyro_four_position": "FOG (KVH DSP-1760 figures), 4 positions x 170 s, repeated",
          "rate_gyro_two_position": "MEMS (ADIS16495-1), 2 positions x 140 s, repeated; compass prior",
          "rate_gyro_carousel": "MEMS (ADIS16495-1), carousel 36 deg/s"}
#: the gyrotheodolite scene's record (s): the time every row is given
SAME_TIME_S = 3600.0


def rate_gyro_rows(quick=False, duration_s=SAME_TIME_S) -> list:
    """Rows ``{scene, instrument, what, duration_s, rms_error_arcsec, mean_sigma_arcsec, crlb_arcsec,
    noise_free_error_arcsec, n_ok}`` (8 seeds with ``quick``, else 40)."""
    rows = []
    for name, what in SCENES.items():
        scene = load_scene(name, [f"duration_s={duration_s!r}"])
        truth = simulate_truth(scene)
        (iname, inst), = truth[1].items()
        obs, m = inst.observation(), math.radians(inst.p.mount_azimuth_deg)
        fits = [R.fit_record(obs, measure(scene, truth, s)[iname]) for s in range(8 if quick else 40)]
        ok = [f for f in fits if "reason" not in f and f.get("resolved", True)]
        err = np.array([R._wrap(f["mount_rad"] - m) for f in ok])
        clean = {"t": truth[0], "index": truth[2][iname].columns["index"], "rate": truth[2][iname].columns["rate"]}
        f0 = R.fit_record(obs, clean)
        rows.append({"scene": name, "instrument": inst.type_name, "what": what, "duration_s": duration_s,
                     "rms_error_arcsec": float(np.sqrt(np.mean(err ** 2))) * R.ARCSEC_PER_RAD if err.size else math.nan,
                     "mean_sigma_arcsec": float(np.mean([f["sigma_rad"] for f in ok])) * R.ARCSEC_PER_RAD,
                     "crlb_arcsec": sigma_mount_rad(inst, inst.p, duration_s, scene.sample_rate_hz) * R.ARCSEC_PER_RAD,
                     "noise_free_error_arcsec": R._wrap(f0["mount_rad"] - m) * R.ARCSEC_PER_RAD, "n_ok": len(ok)})
    return rows


def same_time_lines(rows, gyrotheodolite_rows) -> list:
    """summary.md's table: what each reaches in the gyrotheodolite's hour (arcsec)."""
    lines = ["", "## North in the same time: rate gyros beside the gyrotheodolite (60 min, arcsec)", "",
             "| instrument | set-up | rms error | mean σ | Cramér–Rao | noise-free error | seeds |",
             "|---|---|---|---|---|---|---|"]
    for r in gyrotheodolite_rows:
        if r.get("method") == "fit" and r["duration_s"] == SAME_TIME_S and r.get("setup", "").startswith("shipped"):
            lines.append(f"| gyrotheodolite (GAK1-like, tape) | {r.get('setup', '')}, the exact fit | "
                         f"{r['rms_error_arcsec']:.3g} | {r['mean_sigma_arcsec']:.3g} | = mean σ | "
                         f"{r['floor_arcsec']:+.2g} | {r['n_ok']} |")
    lines += [f"| {r['scene']} | {r['what']} | {r['rms_error_arcsec']:.4g} | {r['mean_sigma_arcsec']:.4g} | "
              f"{r['crlb_arcsec']:.4g} | {r['noise_free_error_arcsec']:+.2g} | {r['n_ok']} |" for r in rows]
    return lines


def write_rate_gyro_csv(path, rows, write) -> None:
    """The CSV through the bench's atomic writer ``write(path, header, rows)``."""
    h = ("scene", "instrument", "what", "duration_s", "rms_error_arcsec", "mean_sigma_arcsec", "crlb_arcsec",
         "noise_free_error_arcsec", "n_ok")
    write(path, h, [tuple(r[k] for k in h) for r in rows])


def bench(out_dir, quick, write, progress, reference_rows) -> list:
    """The bench's study (:meth:`~gyro_instrument.instruments.measurement.MeasurementKind.bench`):
    ``north_rate_gyro.csv`` in ``out_dir`` through the bench's writer, and the summary's table beside
    ``reference_rows`` (the bench's gyrotheodolite rows)."""
    progress("north in the same time: the rate gyros beside the gyrotheodolite")
    rows = rate_gyro_rows(quick)
    write_rate_gyro_csv(os.path.join(out_dir, "north_rate_gyro.csv"), rows, write)
    return same_time_lines(rows, reference_rows)
