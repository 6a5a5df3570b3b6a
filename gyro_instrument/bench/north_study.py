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
        try:
            floor, _ = north.north_methods(t, clean, noise_rad, mark)
        except ValueError as exc:          # too short for any reversal point
            rows.append({"duration_s": float(dur), "method": "all", "refused": str(exc)})
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
