"""Conventions, result types and the reversal points (turning points) of a swing record.

Part of :mod:`gyro_instrument.estimators.north` (its docstring states the sign convention and
the sources).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.crossings import mean_interval


TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class NorthEstimate:
    """One method's swing centre (or north reading), with its σ.

    Attributes
    ----------
    method : str
        ``schuler_mean``, ``lavrov``, ``transit``, ``fit`` (``+tape`` appended once tape-corrected).
    centre_rad : float
        The scale reading of the swing centre (rad); after :func:`tape_corrected`, of true north.
    sigma_rad : float or None
        Its standard error (rad); None when it cannot be had (``sigma_source`` says why).
    sigma_source : str
        Where σ comes from (propagated reading σ's, the scatter with its degrees of freedom, the
        inverse Fisher information) or why it is None.
    n_used : int
        Reversal points, transits or samples used.
    needs : str
        What the method needs to observe.
    notes : tuple of str
    period_s, period_sigma_s : float or None
        The full period of the swing (2 × Quet's T) and its σ, when the method gives one.
    crlb_rad : float or None
        Cramér–Rao bound on σ(centre) (the fit only).
    """

    method: str
    centre_rad: float
    sigma_rad: float | None
    sigma_source: str
    n_used: int
    needs: str
    notes: tuple = ()
    period_s: float | None = None
    period_sigma_s: float | None = None
    crlb_rad: float | None = None

    @property
    def mount_azimuth_rad(self) -> float:
        """(−centre) mod 2π: the mount azimuth if ``centre_rad`` is the north reading (no tape, or
        after :func:`tape_corrected`)."""
        return mount_azimuth_rad(self.centre_rad)

    def to_dict(self) -> dict:
        """Plain-JSON form (rad, s); ``notes`` as a list."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["notes"] = list(self.notes)
        return out


@dataclass(frozen=True)
class ReversalPoints:
    """Turning points of a sampled swing (:func:`reversal_points`).

    Attributes
    ----------
    times_s, readings_rad : ndarray
        Refined times (s) and scale readings (rad), in time order, alternating sides.
    sigmas_rad, time_sigmas_s : ndarray
        Their standard errors from the sensor noise (local least-squares covariance).
    noise_sigma_rad : float
        The white-noise σ used (given, or pooled from the local fits' residuals).
    noise_source : str
    half_period_s, half_period_sigma_s : float
        Mean spacing of the turning points (Quet's T, one swing) and its standard error (nan with
        fewer than 3 points).
    """

    times_s: np.ndarray
    readings_rad: np.ndarray
    sigmas_rad: np.ndarray
    time_sigmas_s: np.ndarray
    noise_sigma_rad: float
    noise_source: str
    half_period_s: float
    half_period_sigma_s: float = field(default=math.nan)


def wrap_pi(angle_rad) -> float:
    """An angle wrapped to [−π, π) (rad)."""
    return float((float(angle_rad) + math.pi) % TWO_PI - math.pi)


def mount_azimuth_rad(north_reading_rad) -> float:
    """Mount azimuth from the scale reading of true north: (−u_N) mod 2π (module docstring)."""
    return float((-float(north_reading_rad)) % TWO_PI)


def damped_swing(t, centre_rad, amplitude_rad, omega_rad_s, damping_per_s=0.0, phase_rad=0.0,
                 drift_rad_s=0.0, t_ref_s=0.0) -> np.ndarray:
    """The small-swing record u(t) = c + d·τ + A e^(−δτ) cos(ωτ + φ), τ = t − t_ref (rad).

    Quet 1853 sec. 4 §1 eq. 8 linearised (a pendulum of small amplitude) with a viscous damping δ
    (1/s) and a slow drift d (rad/s) of the centre: the model :func:`fit_record` fits and the
    synthetic records of the tests and the bench study.
    """
    tau = np.asarray(t, dtype=float) - t_ref_s
    return (centre_rad + drift_rad_s * tau
            + amplitude_rad * np.exp(-damping_per_s * tau) * np.cos(omega_rad_s * tau + phase_rad))


# ----------------------------------------------------------------------------- reversal points
def level_sides(u, level, band) -> np.ndarray:
    """+1 / −1 for samples beyond level ± band, carried forward through the band (0 before the first
    sample that leaves it): hysteresis, so noise near the level makes no extra half swings."""
    side = np.where(u > level + band, 1, np.where(u < level - band, -1, 0))
    idx = np.where(side != 0, np.arange(u.size), 0)
    np.maximum.accumulate(idx, out=idx)
    return side[idx]


def sign_runs(side) -> list:
    """(start, stop, sign) of the runs of constant non-zero ``side``."""
    edges = np.concatenate([[0], np.nonzero(np.diff(side) != 0)[0] + 1, [side.size]])
    return [(int(a), int(b), int(side[a])) for a, b in zip(edges[:-1], edges[1:]) if side[a] != 0]


def _coarse_level(u):
    """Rough centre (median) and half-amplitude (half the 1–99 % range) of a swing record."""
    lo, hi = np.percentile(u, [1.0, 99.0])
    return float(np.median(u)), 0.5 * float(hi - lo)


def local_poly(t, u, t0, h, degree) -> tuple | None:
    """Least-squares polynomial in x = (t − t0)/h over |x| ≤ 1: (coef, (XᵀX)⁻¹, rss, dof) or None."""
    sel = np.abs(t - t0) <= h
    x = (t[sel] - t0) / h
    if x.size < degree + 2 or x.min() > -0.5 or x.max() < 0.5:
        return None
    X = np.vander(x, degree + 1, increasing=True)
    coef, *_ = np.linalg.lstsq(X, u[sel], rcond=None)
    r = u[sel] - X @ coef
    return coef, np.linalg.inv(X.T @ X), float(r @ r), x.size - degree - 1


def poly_root(coef, x0, order) -> float | None:
    """Root of the ``order``-th derivative of the polynomial ``coef`` (increasing powers) near x0,
    by Newton (Horner on floats); None if it leaves (−0.9, 0.9)."""
    p = [float(c) for c in coef]
    for _ in range(order):
        p = [k * p[k] for k in range(1, len(p))]
    dp = [k * p[k] for k in range(1, len(p))]

    def horner(c, x):
        v = 0.0
        for a in reversed(c):
            v = v * x + a
        return v
    x = x0
    for _ in range(50):
        d = horner(dp, x)
        if d == 0:
            return None
        step = horner(p, x) / d
        x -= step
        if abs(step) < 1e-13:
            break
    return x if abs(x) < 0.9 else None


def poly_derivative_row(x, degree, order) -> np.ndarray:
    """Row of d^order/dx^order of (1, x, …, x^degree) at x."""
    return np.array([math.perm(k, order) * x ** (k - order) if k >= order else 0.0 for k in range(degree + 1)])


def _coarse_extrema(t, u):
    """Indices of the coarse turning points (extreme sample of each half swing beyond the band) and
    the coarse half period (median spacing, s)."""
    level, amp = _coarse_level(u)
    if not amp > 0:
        raise SceneError("record", f"{u.size} samples", "no swing: the record is constant")
    runs = sign_runs(level_sides(u, level, 0.2 * amp))
    idx = [a + int(np.argmax(s * (u[a:b] - level))) for a, b, s in runs]
    if len(idx) < 2:
        raise SceneError("record", f"{t[-1] - t[0]:.6g} s", "must hold at least two reversal points "
                         "(about one swing of the gyroscope); observe longer")
    return np.asarray(idx), float(np.median(np.diff(t[idx])))


def _refined_extrema(t, u, idx, h, degree):
    """Local fits at each coarse extremum, the longest block of consecutive ones that refine:
    list of (t*, a*, g_value, g_slope, g_curv, coef, (XᵀX)⁻¹, rss, dof)."""
    blocks, cur = [], []
    for i in idx:
        fit = local_poly(t, u, t[i], h, degree)
        x = None if fit is None else poly_root(fit[0], 0.0, 1)
        if x is None:
            blocks.append(cur)
            cur = []
            continue
        coef, C, rss, dof = fit
        g0, g1, g2 = (poly_derivative_row(x, degree, k) for k in range(3))
        cur.append((t[i] + x * h, float(g0 @ coef), g0, g1, g2, coef, C, rss, dof))
    blocks.append(cur)
    return max(blocks, key=len)


def reversal_points(t, u, noise_sigma_rad=None, degree=4, window_fraction=0.125) -> ReversalPoints:
    """Turning points of a sampled swing, each refined by a local least-squares polynomial.

    Half swings are told apart with hysteresis (the side of the median, beyond 20 % of the
    half-amplitude); the extreme sample of each is refined by a polynomial of ``degree`` in time
    fitted over ±``window_fraction`` × the period, its turning point found by Newton on the
    derivative. A quadratic leaves the peak biased toward the centre by A(ωh)⁴/280 (the
    least-squares projection of the cosine's quartic term on {1, x²} over a uniform window is
    −3h⁴/35; ωh = π/4 gives 1.4e-3 A), so the default is degree 4 (the sextic term leaves ~1e-5 A).
    Half swings cut by the ends of the record are dropped.

    σ of each reading: σ √(gᵀ (XᵀX)⁻¹ g), g the basis at the turning point (the location's error
    enters at second order, the slope being zero there); of each time: σ √(g'ᵀ(XᵀX)⁻¹g') h / |p''|.

    Parameters
    ----------
    t, u : array_like
        Times (s, increasing) and scale readings (rad).
    noise_sigma_rad : float, optional
        White sensor noise σ (rad); else pooled from the local fits' residuals.
    degree : int
        Local polynomial degree (2 … 6).
    window_fraction : float
        Half-width of the local window in periods (0.05 … 0.2).

    Returns
    -------
    ReversalPoints
    """
    t, u = finite_samples(t, u)
    if not 2 <= degree <= 6:
        raise SceneError("degree", degree, "must be in [2, 6]")
    if not 0.05 <= window_fraction <= 0.2:
        raise SceneError("window_fraction", window_fraction, "must be in [0.05, 0.2] (periods)")
    idx, half = _coarse_extrema(t, u)
    fits = _refined_extrema(t, u, idx, window_fraction * 2.0 * half, degree)
    if len(fits) < 2:
        raise SceneError("record", f"{t[-1] - t[0]:.6g} s", "must hold at least two complete reversal "
                         "points (about one swing plus a quarter period at each end); observe longer")
    sigma, source = _noise(noise_sigma_rad, [f[7] for f in fits], [f[8] for f in fits])
    h = window_fraction * 2.0 * half
    times = np.array([f[0] for f in fits])
    vals = np.array([f[1] for f in fits])
    sig = np.array([sigma * math.sqrt(f[2] @ f[6] @ f[2]) for f in fits])
    tsig = np.array([sigma * math.sqrt(f[3] @ f[6] @ f[3]) * h / max(abs(f[4] @ f[5]), 1e-300) for f in fits])
    hp, hps = half_period(times)
    return ReversalPoints(times, vals, sig, tsig, sigma, source, hp, hps)


def half_period(times_s) -> tuple:
    """Mean spacing of successive turning-point times (one swing, Quet's T = half the period) and its
    standard error, by least squares of time against index (s); σ nan for 2 times."""
    times = np.asarray(times_s, dtype=float)
    if times.size < 2:
        raise SceneError("reversal_times", times.size, "a half period needs ≥ 2 turning-point times")
    return mean_interval(times) if times.size >= 3 else (float(times[1] - times[0]), math.nan)


def finite_samples(t, u) -> tuple:
    """(t, u) as 1-D float arrays of the samples where both are finite; raises SceneError as it says."""
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.shape != u.shape or t.ndim != 1:
        raise SceneError("record", f"shapes {t.shape} and {u.shape}", "t and u must be 1-D of equal length")
    ok = np.isfinite(t) & np.isfinite(u)
    t, u = t[ok], u[ok]
    if t.size < 8 or np.any(np.diff(t) <= 0):
        raise SceneError("record", f"{t.size} samples", "needs ≥ 8 finite samples at increasing times")
    return t, u


def _noise(given, rss, dof):
    if given is not None:
        if not (given > 0 and math.isfinite(given)):
            raise SceneError("noise_sigma_rad", given, "must be a finite number > 0 (rad)")
        return float(given), "given"
    if sum(dof) <= 0:
        raise SceneError("noise_sigma_rad", None, "give the sensor σ: the local fits leave no residual")
    return math.sqrt(sum(rss) / sum(dof)), f"pooled from the local fits' residuals ({sum(dof)} dof)"
