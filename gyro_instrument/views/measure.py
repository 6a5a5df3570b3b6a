"""The numbers the views draw: swing-plane azimuth per swing, the expected line anchored at the
release, a gyroscope's residual from its fitted oscillation, the dominant period."""

import math

import numpy as np

from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S  # noqa: F401  (the IERS value, re-exported by views)
from gyro_instrument.views.series import finite


def dominant_period(t, y) -> float | None:
    """The strongest oscillation's period in ``y`` (s; FFT peak of the first 20000 finite samples),
    None when there is none (constant or all-zero channel, too few samples)."""
    from gyro_instrument.estimators.period import EstimationError, fft_guess
    t, y = finite(t, y)
    if t.size < 20 or not np.ptp(y) > 0:
        return None
    head = min(t.size, 20000)
    try:
        omega = fft_guess(t[:head], y[:head] - np.mean(y[:head]))
    except (EstimationError, ValueError):
        return None
    return 2 * math.pi / omega if omega and math.isfinite(omega) and omega > 0 else None


def swing_azimuth(t, east, north) -> tuple:
    """Swing-plane azimuth per swing period: (window centre times s, compass azimuth rad, unwrapped
    modulo π, period s); the principal axis of the deflection about its mean over each period (as
    the Foucault estimator measures it, whose rest point is fitted: the track's origin is irrelevant), the first value in [0, π). Empty arrays (and a None period) when there
    is no swing (a still, all-zero or constant bob)."""
    t, e, n = finite(t, east, north)
    main = e if np.var(e) >= np.var(n) else n
    period = dominant_period(t, main)
    if period is None:
        return np.array([]), np.array([]), None
    n_win = int((t[-1] - t[0]) // period)
    if n_win < 1:
        return np.array([]), np.array([]), period
    idx = np.searchsorted(t, t[0] + period * np.arange(n_win + 1))
    a, b = idx[:-1], idx[1:]
    good = (b - a) >= 8
    cnt = np.maximum((b - a).astype(float), 1.0)
    end = int(b[-1])                      # segments a[i]:a[i+1], the last one a[-1]:b[-1]
    e, n = e[:end], n[:end]
    me, mn = np.add.reduceat(e, a) / cnt, np.add.reduceat(n, a) / cnt     # each swing's centre: an offset
    see = np.add.reduceat(e * e, a) / cnt - me * me                        # origin is no minor axis
    snn = np.add.reduceat(n * n, a) / cnt - mn * mn
    sen = np.add.reduceat(e * n, a) / cnt - me * mn
    psi = 0.5 * np.arctan2(2 * sen, snn - see)
    tc = 0.5 * (t[a] + t[np.maximum(b - 1, a)])
    psi, tc = psi[good], tc[good]
    az = np.unwrap(2 * psi) / 2
    if az.size:
        az = az - math.pi * math.floor(az[0] / math.pi)      # first value in [0, π): compass, mod 180°
    return tc, az, period


def anchored(tc, az, rate_rad_s, anchor_t_s, anchor_az_rad) -> np.ndarray:
    """``az`` (modulo π) shifted by the whole number of half turns that puts its first value nearest
    the expected line ``anchor_az + rate (t - anchor_t)``: a release at 0° stays at 0°, never 180°."""
    if not az.size:
        return az
    line0 = anchor_az_rad + rate_rad_s * (tc[0] - anchor_t_s)
    return az + math.pi * round((line0 - az[0]) / math.pi)


def expected_line(scene, name) -> dict | None:
    """The swing plane's expected line for the scene pendulum ``name``: ``rate_rad_s`` (the exact
    finite-amplitude apse-line rate ``apsidal_rate_from_rest_rad_s`` of its predictions, k = n sin γ
    with the ellipse's precession; positive clockwise seen from above), ``k_rad_s`` (n sin γ),
    ``latitude_deg``, ``release`` (deflection, compass azimuth, rad) and ``full_turn_h``; None
    without a scene or such a pendulum."""
    if scene is None:
        return None
    try:
        from gyro_instrument.scenes import build_instruments
        inst = build_instruments(scene).get(name)
        obs = inst.observation() if inst is not None else None
        pred = inst.predictions() if obs is not None and obs.SHOWS_BOB_POSITION else None
    except Exception:                   # noqa: BLE001 - a scene that does not build draws no line
        return None
    if not pred or pred.get("apsidal_rate_from_rest_rad_s") is None or obs.release() is None:
        return None
    rate = float(pred["apsidal_rate_from_rest_rad_s"])
    return {"rate_rad_s": rate, "k_rad_s": float(pred["foucault_rate_rad_s"]),
            "latitude_deg": scene.site.latitude_deg, "release": tuple(float(v) for v in obs.release()),
            "full_turn_h": 2 * math.pi / abs(rate) / 3600.0 if rate else math.inf,
            "exact_amplitude": obs.models_finite_amplitude()}


def oscillation_residuals(t, y) -> tuple | None:
    """(t, residual) of a gyroscope angle less its fitted oscillation (fundamental and third
    harmonic at the frequency :func:`~gyro_instrument.estimators.period.fit_oscillation` finds,
    plus a constant); None when no oscillation can be fitted (a constant channel)."""
    from gyro_instrument.estimators.period import EstimationError, fit_oscillation
    t, y = finite(t, y)
    if t.size < 20 or not np.ptp(y) > 0:
        return None
    try:
        fit = fit_oscillation(t, y, harmonics=(1, 3))
    except (EstimationError, ValueError, np.linalg.LinAlgError):
        return None
    tau = t - np.mean(t)
    w = fit.omega_rad_s
    X = np.column_stack([np.ones_like(tau), np.cos(w * tau), np.sin(w * tau), np.cos(3 * w * tau),
                         np.sin(3 * w * tau)])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return t, y - X @ coef


def deg_per_h(rate_rad_s) -> float:
    """rad/s to °/h."""
    return math.degrees(rate_rad_s) * 3600.0


def sense_words(rate_rad_s) -> str:
    """The sense of a rate about the upward vertical (positive clockwise seen from above), in words."""
    if rate_rad_s == 0:
        return "does not turn"
    return "clockwise seen from above" if rate_rad_s > 0 else "counter-clockwise seen from above"


def latitude_words(latitude_deg) -> str:
    """``48.85° N``, ``37.80° S``, ``0.00° (equator)``."""
    if abs(latitude_deg) < 5e-3:
        return f"{abs(latitude_deg):.2f}° (equator)"
    return f"{abs(latitude_deg):.2f}° {'N' if latitude_deg > 0 else 'S'}"
