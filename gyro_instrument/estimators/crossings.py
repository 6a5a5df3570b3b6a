"""Event times from sampled signals: zero crossings and extrema, refined by interpolation.

Used to measure swing durations (Quet's T: the time between successive passages through
equilibrium, HALF the period) and the apsides of a pendulum (maximum deflection).
"""

import numpy as np


def zero_crossings(t, u, ud=None) -> np.ndarray:
    """Times where ``u`` crosses zero.

    With the derivative ``ud`` the root is found on the cubic Hermite interpolant between
    samples (error O(h⁴)); without it, by linear interpolation.

    Parameters
    ----------
    t, u : ndarray
        Sample times (s) and signal.
    ud : ndarray, optional
        du/dt at the samples.

    Returns
    -------
    ndarray
        Crossing times in seconds, increasing.
    """
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    ok = np.isfinite(u)
    idx = np.nonzero(ok[:-1] & ok[1:] & (np.sign(u[:-1]) * np.sign(u[1:]) < 0))[0]
    out = []
    for i in idx:
        t0, t1 = t[i], t[i + 1]
        h = t1 - t0
        if ud is None:
            out.append(t0 - u[i] * h / (u[i + 1] - u[i]))
            continue
        p0, p1, m0, m1 = u[i], u[i + 1], ud[i] * h, ud[i + 1] * h
        # Hermite cubic in s ∈ [0, 1]: coefficients of s^3, s^2, s, 1
        c = [2 * p0 - 2 * p1 + m0 + m1, -3 * p0 + 3 * p1 - 2 * m0 - m1, m0, p0]
        s = -p0 / (p1 - p0)
        for _ in range(30):  # Newton on the cubic, started from the linear root
            f = ((c[0] * s + c[1]) * s + c[2]) * s + c[3]
            df = (3 * c[0] * s + 2 * c[1]) * s + c[2]
            if df == 0:
                break
            step = f / df
            s -= step
            if abs(step) < 1e-15:
                break
        out.append(t0 + min(max(s, 0.0), 1.0) * h)
    return np.asarray(out)


def local_maxima(t, y) -> tuple:
    """Refined times and values of the local maxima of ``y`` (parabola through 3 samples)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    i = np.nonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]))[0] + 1
    y0, y1, y2 = y[i - 1], y[i], y[i + 1]
    den = y0 - 2 * y1 + y2
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(den != 0, 0.5 * (y0 - y2) / den, 0.0)
    h = t[i + 1] - t[i]
    return t[i] + s * h, y1 - 0.25 * (y0 - y2) * s


def mean_interval(times) -> tuple:
    """Least-squares slope of event time versus event index (the mean interval) and its
    standard error; robust to a constant offset in the event times."""
    times = np.asarray(times, dtype=float)
    k = np.arange(times.size, dtype=float)
    if times.size < 3:
        raise ValueError(f"need at least 3 events to estimate an interval, got {times.size}")
    A = np.vstack([k, np.ones_like(k)]).T
    coef, res, *_ = np.linalg.lstsq(A, times, rcond=None)
    resid = times - A @ coef
    s2 = resid @ resid / max(times.size - 2, 1)
    se = np.sqrt(s2 / np.sum((k - k.mean()) ** 2))
    return float(coef[0]), float(se)
