"""ISO 22090-1's definitions of a settled compass and its settle point (issue 39 items 3 and 6), read by
the type test (:mod:`gyro_instrument.bench.typetest_runs`) and the estimator
(:mod:`gyro_instrument.estimators.compass`).

ISO 22090-1 (nippon.zaidan.info/seikabutsu/2000/00393/contents/003.htm): settled (§3.10) = three readings
taken 30 min apart within a 0.7° band, the settling time being switch-on to the third of the first such
three (any three: the readings slide on a grid of readings ``step`` apart); settle point heading (§3.11) =
the mean of ten readings at 20-min intervals after settling; settle point error (§3.12) = it less the true
heading; error (§3.13) = a reading less the settle point heading.
"""

import numpy as np

#: Reading interval of the type test, s (the settle criterion slides on it).
STEP_S = 60.0
#: §3.10: readings 30 min apart, within 0.7°.
SETTLE_INTERVAL_S, SETTLE_BAND_DEG = 1800.0, 0.7
#: §3.11: ten readings, 20 min apart.
SP_READINGS, SP_INTERVAL_S = 10, 1200.0


def settle_time_s(t, error_deg, step_s=STEP_S) -> "float | None":
    """§3.10: the time of the third of the first three readings 30 min apart within 0.7°, s; None if none.

    ``t`` (s) and ``error_deg`` are readings on a uniform grid ``step_s`` apart (s)."""
    k = int(round(SETTLE_INTERVAL_S / step_s))
    if t.size <= 2 * k:
        return None
    a, b, c = error_deg[:-2 * k], error_deg[k:-k], error_deg[2 * k:]
    spread = np.maximum(np.maximum(a, b), c) - np.minimum(np.minimum(a, b), c)
    hit = np.flatnonzero(spread <= SETTLE_BAND_DEG)
    return float(t[hit[0] + 2 * k]) if hit.size else None


def settle_readings(t, after_s) -> "np.ndarray | None":
    """§3.11: the indices into the sorted times ``t`` (s) of the ten readings 20 min apart after ``after_s``
    (the first sample at or after each), or None when the record is too short."""
    want = after_s + SP_INTERVAL_S * np.arange(1, SP_READINGS + 1)
    idx = np.searchsorted(t, want - 1e-6)
    return None if idx[-1] >= t.size else idx


def settle_point(t, error_deg, after_s) -> "tuple | None":
    """§3.11–3.12: (mean, rms about it) of the ten readings 20 min apart after ``after_s``, deg; None when
    the run is too short."""
    idx = settle_readings(t, after_s)
    if idx is None:
        return None
    r = error_deg[idx]
    return float(r.mean()), float(np.sqrt(np.mean((r - r.mean()) ** 2)))
