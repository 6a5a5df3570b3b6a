"""North from the swing of a horizontal gyroscope: the oscillation centre is the meridian.

Quet 1853, sec. 4 §1, item 1: a body of revolution spinning about its axis, the axis free to turn
in a *horizontal* directing plane, is in relative equilibrium only along the meridian (stable when
the spin is in the Earth's sense), and item 6: away from it the axis swings about the meridian like
a pendulum (eq. 8, small swings of duration T = π/√(μ n ρ0 sin ω), eq. 9, sin ω = cos γ). A
surveyor's gyrotheodolite (Wild GAK1, Fennel KT1, DMT Gyromat) is this gyroscope hung on a torsion
tape; the centre of its swing, read on the instrument's scale, gives north.

Sign convention (the scale of issue 24, item 1)
-----------------------------------------------
* Azimuth: clockwise from true north seen from above (east = +90°), in [0, 2π).
* ``mount_azimuth``: the azimuth of the instrument's scale zero.
* The swing angle ``u`` read on the scale (rad) is the azimuth of the rotor axis's north-seeking
  end (the end that rests on the meridian's north when the spin is in the Earth's sense) *less*
  the mount azimuth: u = azimuth(axis) − mount_azimuth, wrapped to (−π, π]. So u grows clockwise,
  like the azimuth (Quet's own u of eq. 4 is measured from ``ox`` toward ``oy``, to the *left* of
  ``ox``: counter-clockwise; u_here = −u_Quet for a scale whose zero is on ``ox``).
* True north (azimuth 0) therefore reads u_N = −mount_azimuth on the scale, and the estimate
  sought is mount_azimuth = (−u_N) mod 2π (:func:`mount_azimuth_rad`).
* Without a torsion tape the swing centre c *is* u_N. With a tape (torsion constant D_B, tape zero
  Z on the scale) the centre is pulled toward Z: c = (D_K u_N + D_B Z)/(D_K + D_B), hence
  u_N = c + (D_B/D_K)(c − Z) (:func:`tape_corrected`; physics_notes "North finding").

The methods (issue 24, item 3), each returning a :class:`NorthEstimate`
------------------------------------------------------------------------
=========================  ====================================  ===========================================
method                     needs                                 bias (first order)
=========================  ====================================  ===========================================
:func:`schuler_mean`       ≥ 3 reversal points (≥ 4 for a σ      none for a linear decay of the amplitude;
                           from the scatter)                     exponential decay q per swing: second order,
                                                                 d1 (1−q)² (1 − (−q)^(ν−2)) / (4 (1+q)(ν−2))
                                                                 (:func:`schuler_bias`); a linear drift of the
                                                                 centre gives the centre at the weighted mean
                                                                 time (symmetric weights)
:func:`lavrov`             ≥ 3 consecutive reversal points       none for an exponential (geometric) decay:
                           (≥ 4 for a σ from the scatter)        exact; a linear decay: second order
:func:`transit_method`     ≥ 3 transits of a mark inside the     none at the mark = centre (the zeros of a
                           swing (one period) and the            damped sine are equally spaced); the sine
                           amplitude (from reversal points)      law x0 = A sin(π Δt / (2T)) is exact undamped
:func:`fit_record`         ≥ 2 reversal points to start (about   none for the model c + A e^(−δt) cos(ωt + φ)
                           one swing); σ at the Cramér–Rao       (+ drift); var(c) ≈ σ²/N for a long record
                           bound                                 (:func:`crlb_centre`)
=========================  ====================================  ===========================================

Tape torque biases every centre alike (the swing centre is not north); :func:`tape_corrected`
removes it with the ratio from the rotor-on and rotor-off periods (:func:`tape_ratio`). Sources:
Quet 1853 sec. 4 §1; physics_notes.md "North finding" (the Schuler mean is Freiberger
Forschungshefte A 303 eq. 31b; the transit form N = N' + c·a·Δt with c ≈ π/(2T)); the GAK1
procedures are described in K. P. Logan, *Determining an azimuth with a gyrotheodolite*, U.S. Army
ETL-0440 (1986). The derivations used here are written out in each function's docstring.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

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
def _sides(u, level, band):
    """+1 / −1 for samples beyond level ± band, carried forward through the band (0 before the first
    sample that leaves it): hysteresis, so noise near the level makes no extra half swings."""
    side = np.where(u > level + band, 1, np.where(u < level - band, -1, 0))
    idx = np.where(side != 0, np.arange(u.size), 0)
    np.maximum.accumulate(idx, out=idx)
    return side[idx]


def _runs(side):
    """(start, stop, sign) of the runs of constant non-zero ``side``."""
    edges = np.concatenate([[0], np.nonzero(np.diff(side) != 0)[0] + 1, [side.size]])
    return [(int(a), int(b), int(side[a])) for a, b in zip(edges[:-1], edges[1:]) if side[a] != 0]


def _coarse_level(u):
    """Rough centre (median) and half-amplitude (half the 1–99 % range) of a swing record."""
    lo, hi = np.percentile(u, [1.0, 99.0])
    return float(np.median(u)), 0.5 * float(hi - lo)


def _local_poly(t, u, t0, h, degree):
    """Least-squares polynomial in x = (t − t0)/h over |x| ≤ 1: (coef, (XᵀX)⁻¹, rss, dof) or None."""
    sel = np.abs(t - t0) <= h
    x = (t[sel] - t0) / h
    if x.size < degree + 2 or x.min() > -0.5 or x.max() < 0.5:
        return None
    X = np.vander(x, degree + 1, increasing=True)
    coef, *_ = np.linalg.lstsq(X, u[sel], rcond=None)
    r = u[sel] - X @ coef
    return coef, np.linalg.inv(X.T @ X), float(r @ r), x.size - degree - 1


def _poly_root(coef, x0, order):
    """Root of the ``order``-th derivative of the polynomial ``coef`` (increasing powers) near x0,
    by Newton; None if it leaves (−0.9, 0.9)."""
    p = np.polynomial.Polynomial(coef).deriv(order)
    dp = p.deriv()
    x = x0
    for _ in range(50):
        d = dp(x)
        if d == 0:
            return None
        step = p(x) / d
        x -= step
        if abs(step) < 1e-13:
            break
    return x if abs(x) < 0.9 else None


def _basis(x, degree, order):
    """Row of d^order/dx^order of (1, x, …, x^degree) at x."""
    return np.array([math.perm(k, order) * x ** (k - order) if k >= order else 0.0 for k in range(degree + 1)])


def _coarse_extrema(t, u):
    """Indices of the coarse turning points (extreme sample of each half swing beyond the band) and
    the coarse half period (median spacing, s)."""
    level, amp = _coarse_level(u)
    if not amp > 0:
        raise SceneError("record", f"{u.size} samples", "no swing: the record is constant")
    runs = _runs(_sides(u, level, 0.2 * amp))
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
        fit = _local_poly(t, u, t[i], h, degree)
        x = None if fit is None else _poly_root(fit[0], 0.0, 1)
        if x is None:
            blocks.append(cur)
            cur = []
            continue
        coef, C, rss, dof = fit
        g0, g1, g2 = (_basis(x, degree, k) for k in range(3))
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
    t, u = _finite(t, u)
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


def _finite(t, u):
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


# ----------------------------------------------------------------------------- Schuler mean
def schuler_weights(nu) -> np.ndarray:
    """Weights (1, 3, 4, …, 4, 3, 1)/(4(ν−2)) of the Schuler mean over ν ≥ 3 reversal points.

    The Schuler mean is the average of the ν−2 consecutive triple means (a_i + 2a_(i+1) + a_(i+2))/4
    (each the mean of two successive midpoints); summing the triples gives the printed weights
    (Freiberger Forschungshefte A 303 eq. 31b; ν = 3 gives (1, 2, 1)/4).
    """
    if nu < 3:
        raise SceneError("reversal_points", nu, "the Schuler mean needs ≥ 3 reversal points")
    return np.convolve(np.ones(nu - 2), [1.0, 2.0, 1.0]) / (4.0 * (nu - 2))


def schuler_bias(first_deviation_rad, ratio, nu) -> float:
    """Bias of the Schuler mean for an exponentially damped swing (rad).

    Turning points of c + A e^(−δt) cos(ωt + φ) are equally spaced (tan(ωt + φ) = −δ/ω), so their
    deviations form a geometric sequence d_i = d1 (−q)^(i−1), q = e^(−δπ/ω). Each triple mean is
    d_i (1 − q)²/4, and the triples alternate in sign: the sum over ν−2 triples gives
    bias = d1 (1 − q)² (1 − (−q)^(ν−2)) / (4 (1 + q)(ν − 2)) — second order in the damping (zero for
    q = 1, and zero for a *linear* decay of the amplitude, where each triple sum vanishes).
    """
    q = float(ratio)
    return first_deviation_rad * (1 - q) ** 2 * (1 - (-q) ** (nu - 2)) / (4 * (1 + q) * (nu - 2))


def _scatter_sigma(a):
    """Reading σ from the scatter of the triple means m_j = (a_j + 2a_(j+1) + a_(j+2))/4 about their
    mean, (ν − 3 dof; None for ν < 4): each m_j estimates the centre (a linear decay cancels in each),
    so with independent readings of σ_a, E Σ(m_j − m̄)² = σ_a² tr(Bᵀ P B) (B the triple matrix, P the
    centring); hence σ̂_a² = Σ(m_j − m̄)² / tr(BᵀPB). Exponential damping leaves the m_j alternating by
    d_j (1 − q)²/4 (second order), which this σ then includes."""
    nu = a.size
    if nu < 4:
        return None, 0
    k = nu - 2
    B = np.zeros((k, nu))
    for j in range(k):
        B[j, j:j + 3] = [0.25, 0.5, 0.25]
    P = np.eye(k) - 1.0 / k
    r = P @ B @ a
    return math.sqrt(float(r @ r) / float(np.trace(B.T @ P @ B))), nu - 3


def _readings(readings, sigmas, least, method):
    a = np.asarray(readings, dtype=float)
    if a.ndim != 1 or a.size < least or not np.all(np.isfinite(a)):
        raise SceneError("reversal_points", a.size if a.ndim == 1 else a.shape,
                         f"{method} needs ≥ {least} finite reversal points")
    if sigmas is None:
        return a, None
    s = np.broadcast_to(np.asarray(sigmas, dtype=float), a.shape)
    if not np.all((s > 0) & np.isfinite(s)):
        raise SceneError("reversal_point_sigmas", sigmas, "must be finite and > 0 (rad)")
    return a, s


def schuler_mean(readings, sigmas=None) -> NorthEstimate:
    """Centre of a swing from ν ≥ 3 successive reversal points by the Schuler mean.

    L = (a1 + 3a2 + 4a3 + … + 4a(ν−2) + 3a(ν−1) + aν) / (4(ν−2)) (:func:`schuler_weights`).
    σ: with reading σ's, propagated (readings independent): σ_L² = Σ w_i² σ_i²; without (a field
    book), from the scatter of the triple means (:func:`_scatter_sigma`, ν − 3 dof, ν ≥ 4).
    Unbiased for a linear amplitude decay; second-order bias under exponential damping
    (:func:`schuler_bias`).
    """
    a, s = _readings(readings, sigmas, 3, "the Schuler mean")
    w = schuler_weights(a.size)
    centre = float(w @ a)
    if s is not None:
        sig, src = float(math.sqrt(np.sum(w ** 2 * s ** 2))), "propagated from the reading σ's"
    else:
        sr, dof = _scatter_sigma(a)
        sig = None if sr is None else sr * float(math.sqrt(w @ w))
        src = (f"from the scatter of the triple means ({dof} dof)" if sr is not None
               else "none: 3 readings leave no scatter and no reading σ was given")
    return NorthEstimate("schuler_mean", centre, sig, src, int(a.size), "≥ 3 reversal points (≥ 4 for a σ "
                         "from the scatter)")


# ----------------------------------------------------------------------------- Lavrov
def lavrov_triples(readings) -> np.ndarray:
    """Lavrov's centre from each triple of consecutive reversal points (rad).

    For an exponentially damped swing the deviations are geometric, a_i = c + d(−q)^(i−1); then
    a1 a3 − a2² = c d (1+q)² and a1 + a3 − 2a2 = d (1+q)², so c = (a1 a3 − a2²)/(a1 + a3 − 2a2)
    exactly. Computed as a2 + (a1 − a2)(a3 − a2)/((a1 − a2) + (a3 − a2)) (the same number, without
    cancelling large readings).
    """
    a = np.asarray(readings, dtype=float)
    p, m = a[:-2] - a[1:-1], a[2:] - a[1:-1]
    den = p + m
    if np.any(den == 0):
        raise SceneError("reversal_points", a.tolist(), "consecutive readings must alternate about the "
                         "centre (a1 + a3 − 2a2 ≠ 0)")
    return a[1:-1] + p * m / den


def _geometric(params, i):
    c, d, q = params
    return c + d * (-q) ** i


def _geometric_jac(params, i):
    _, d, q = params
    return np.column_stack([np.ones_like(i), (-q) ** i, d * i * (-1.0) ** i * q ** np.maximum(i - 1, 0)])


def lavrov(readings, sigmas=None) -> NorthEstimate:
    """Lavrov's damped-oscillation centre from ν ≥ 3 consecutive reversal points.

    ν = 3: the closed form of :func:`lavrov_triples`. ν ≥ 4: a weighted least-squares fit of the
    geometric sequence a_i = c + d(−q)^(i−1) (three parameters, Gauss–Newton from the median triple
    estimate), which is the generalisation by least squares over all the points. σ: from the
    reading σ's (the fit's covariance), else from the scatter (ν − 3 dof); None for ν = 3 without σ's.
    Exact for exponential damping; under a linear decay a second-order bias.
    """
    a, s = _readings(readings, sigmas, 3, "Lavrov's method")
    c0 = float(np.median(lavrov_triples(a)))
    i = np.arange(a.size, dtype=float)
    d0 = a[0] - c0
    q0 = float(np.median(-(a[1:] - c0) / (a[:-1] - c0))) if np.all(a[:-1] != c0) else 1.0
    wt = 1.0 / s if s is not None else np.ones_like(a)
    sol = least_squares(lambda p: wt * (_geometric(p, i) - a), [c0, d0, q0],
                        jac=lambda p: wt[:, None] * _geometric_jac(p, i), method="lm", xtol=1e-15, ftol=1e-15)
    J = wt[:, None] * _geometric_jac(sol.x, i)
    cov = np.linalg.pinv(J.T @ J)
    needs = "≥ 3 consecutive reversal points (≥ 4 for a σ from the scatter)"
    if s is not None:
        sig, src = math.sqrt(cov[0, 0]), "propagated from the reading σ's (the fit's covariance)"
    elif a.size >= 4:
        r = sol.fun
        sig = math.sqrt(cov[0, 0] * float(r @ r) / (a.size - 3))
        src = f"from the scatter about the geometric fit ({a.size - 3} dof)"
    else:
        sig, src = None, "none: 3 readings leave no scatter and no reading σ was given"
    notes = (f"damping ratio per swing q = {sol.x[2]:.6g}",)
    return NorthEstimate("lavrov", float(sol.x[0]), sig, src, int(a.size), needs, notes)


# ----------------------------------------------------------------------------- transit (timing) method
def transit_offset(dt_s, period_s, amplitude_rad) -> float:
    """Offset x0 = c − mark of the swing centre from a reference mark, by the transit method (rad).

    For u = c + A cos θ the swing is beyond the mark (u > mark) while cos θ > −x0/A, i.e. for
    |θ| < π/2 + arcsin(x0/A): a time t₊ = (T/π)(π/2 + arcsin(x0/A)) of each full period T, and
    t₋ = T − t₊ on the other side. With Δt = t₊ − t₋ (time on the + side less time on the − side,
    both within one full period): Δt = (2T/π) arcsin(x0/A), hence

        x0 = A sin(π Δt / (2T))   (exact for a sine),   x0 ≈ (π/(2T)) · A · Δt   (small offsets),

    the surveyors' N = N' + c·a·Δt with c = π/(2T) (physics_notes "North finding"; in the field c is
    calibrated). T is the full period (two of Quet's swings). An equivalent form with the half
    difference Δt/2 reads x0 = A sin(π (Δt/2) / T).
    """
    return float(amplitude_rad * math.sin(math.pi * dt_s / (2.0 * period_s)))


def transit_times(t, u, mark_rad, noise_sigma_rad, half_period_s, band_rad, window_fraction=0.125,
                  degree=4) -> tuple:
    """Times (s) the swing crosses ``mark_rad``, their σ (s) and the side (+1: u > mark) of the swing
    after each, from a local polynomial fitted over ±``window_fraction`` × the period about each.

    Hysteresis (``band_rad``) keeps noise from making extra crossings; σ_t = σ √(gᵀ(XᵀX)⁻¹g) h/|p'|.
    Degree 4, not 3: away from the centre the swing's quartic term is ∝ x0, and a cubic fit moves the
    root by (3/35)(that term)/slope — a relative error (ωh)⁴/280 of the offset x0 (2.7e-4 at ±T/12,
    measured); the quartic removes it at the same noise as a cubic over ±T/12.
    """
    runs = _runs(_sides(u, mark_rad, band_rad))
    h = window_fraction * 2.0 * half_period_s
    times, sig, side = [], [], []
    for (a, b, s0), (a1, b1, s1) in zip(runs[:-1], runs[1:]):
        seg = np.nonzero(s0 * (u[a:a1] - mark_rad) > 0)[0]     # the last sample still on the old side
        k = a + int(seg[-1]) if seg.size else a1
        fit = _local_poly(t, u - mark_rad, t[k], h, degree)
        x = None if fit is None else _poly_root(fit[0], 0.0, 0)
        if x is None:
            continue
        coef, C, _, _ = fit
        g0, g1 = _basis(x, degree, 0), _basis(x, degree, 1)
        times.append(t[k] + x * h)
        sig.append(noise_sigma_rad * math.sqrt(g0 @ C @ g0) * h / abs(g1 @ coef))
        side.append(s1)
    return np.asarray(times), np.asarray(sig), np.asarray(side)


def transit_method(t, u, mark_rad, noise_sigma_rad=None) -> NorthEstimate:
    """Swing centre from the timed transits of a reference mark (the transit or timing method).

    Each run of three consecutive transits t1 < t2 < t3 spans one full period T = t3 − t1; the
    time on the + side less that on the − side is Δt = ±((t2 − t1) − (t3 − t2)); the amplitude A is
    half the difference of the two reversal points between t1 and t3; then c = mark +
    A sin(πΔt/(2T)) (:func:`transit_offset`). The centre is the mean over all runs of three; σ is
    propagated from the transit times' σ (linearised; the amplitude's σ enters multiplied by x0/A
    and is left out). Needs a mark inside the swing (|c − mark| < A) and ≥ 3 transits.
    """
    t, u = _finite(t, u)
    rp = reversal_points(t, u, noise_sigma_rad)
    amp = 0.5 * np.abs(np.diff(rp.readings_rad))
    band = 0.2 * float(np.min(amp))
    tt, ts, side = transit_times(t, u, mark_rad, rp.noise_sigma_rad, rp.half_period_s, band)
    if tt.size < 3:
        raise SceneError("mark_rad", mark_rad, f"must lie inside the swing (between the reversal points "
                         f"{rp.readings_rad.min():.6g} and {rp.readings_rad.max():.6g} rad) and be crossed "
                         f"≥ 3 times; {tt.size} transits found")
    cs, grad = [], []
    for k in range(tt.size - 2):
        t1, t2, t3 = tt[k:k + 3]
        inside = (rp.times_s > t1) & (rp.times_s < t3)
        if inside.sum() != 2:          # a reversal point cut off by the record's ends: no amplitude
            continue
        A = 0.5 * float(np.ptp(rp.readings_rad[inside]))
        s, T = side[k], t3 - t1
        dt = s * ((t2 - t1) - (t3 - t2))
        cs.append(mark_rad + transit_offset(dt, T, A))
        k_dt = A * math.cos(math.pi * dt / (2 * T)) * math.pi / (2 * T)      # ∂x0/∂Δt
        k_T = -k_dt * dt / T                                                  # ∂x0/∂T
        grad.append(np.zeros(tt.size))
        grad[-1][k:k + 3] = [-s * k_dt - k_T, 2 * s * k_dt, -s * k_dt + k_T]
    if not cs:
        raise SceneError("record", f"{t[-1] - t[0]:.6g} s", "must hold a full period between transits "
                         "with both its reversal points; observe longer")
    g = np.mean(grad, axis=0)
    sig = float(math.sqrt(np.sum(g ** 2 * ts ** 2)))
    return NorthEstimate("transit", float(np.mean(cs)), sig, f"propagated from the transit times' σ (noise "
                         f"σ {rp.noise_source})", int(tt.size), "≥ 3 transits of a mark inside the swing and "
                         "its amplitude (reversal points)", period_s=float(np.mean(np.diff(tt[::2]))))


# ----------------------------------------------------------------------------- the full-record fit
def _fit_jacobian(tau, p, damping, drift):
    """Columns ∂u/∂(c, a, b, ω[, δ][, d]) of u = c + d τ + e^(−δτ)(a cos ωτ + b sin ωτ)."""
    _, a, b, w = p[:4]
    dl = p[4] if damping else 0.0
    E = np.exp(-dl * tau)
    co, si = np.cos(w * tau), np.sin(w * tau)
    cols = [np.ones_like(tau), E * co, E * si, E * tau * (b * co - a * si)]
    if damping:
        cols.append(-tau * E * (a * co + b * si))
    if drift:
        cols.append(tau)
    return np.column_stack(cols)


def _fit_model(tau, p, damping, drift):
    c, a, b, w = p[:4]
    dl = p[4] if damping else 0.0
    return c + (p[-1] * tau if drift else 0.0) + np.exp(-dl * tau) * (a * np.cos(w * tau) + b * np.sin(w * tau))


def _fit_start(tau, u, rp, damping, drift):
    """Starting parameters: ω from the reversal-point spacing, δ from the decay of their deviations,
    then c, a, b (and d) by linear least squares."""
    w = math.pi / rp.half_period_s
    dev = np.abs(rp.readings_rad - schuler_mean(rp.readings_rad).centre_rad)
    dl = float(-np.polyfit(rp.times_s, np.log(dev), 1)[0]) if damping and rp.readings_rad.size >= 3 else 0.0
    E = np.exp(-dl * tau)
    cols = [np.ones_like(tau), E * np.cos(w * tau), E * np.sin(w * tau)] + ([tau] if drift else [])
    lin, *_ = np.linalg.lstsq(np.column_stack(cols), u, rcond=None)
    return np.array(list(lin[:3]) + [w] + ([dl] if damping else []) + ([lin[3]] if drift else []))


def fit_record(t, u, noise_sigma_rad=None, damping=True, drift=False, t_ref_s=None) -> NorthEstimate:
    """Swing centre by nonlinear least squares of the whole record (at the Cramér–Rao bound).

    Model u(t) = c + d·τ + A e^(−δτ) cos(ωτ + φ), τ = t − t_ref (t_ref the mean sample time unless
    given; with ``drift`` the centre is reported at t_ref), written linearly in a = A cos φ,
    b = −A sin φ. Least squares is the maximum-likelihood estimate in white Gaussian noise, so its
    covariance σ² (JᵀJ)⁻¹ is the inverse Fisher information: σ(c) is the Cramér–Rao bound at the
    estimate (:func:`crlb_centre`; ≈ σ/√N for a long record). σ: the given sensor σ, else the
    residual rms with N − p degrees of freedom.
    """
    t, u = _finite(t, u)
    rp = reversal_points(t, u, noise_sigma_rad)
    t_ref = float(np.mean(t)) if t_ref_s is None else float(t_ref_s)
    tau = t - t_ref
    p0 = _fit_start(tau, u, rp, damping, drift)
    sol = least_squares(lambda p: _fit_model(tau, p, damping, drift) - u, p0,
                        jac=lambda p: _fit_jacobian(tau, p, damping, drift), method="lm", xtol=1e-14)
    J = _fit_jacobian(tau, sol.x, damping, drift)
    inv = np.linalg.inv(J.T @ J)
    if noise_sigma_rad is not None:
        sigma, src = float(noise_sigma_rad), "inverse Fisher information at the estimate (sensor σ given)"
    else:
        sigma = math.sqrt(2.0 * sol.cost / (t.size - sol.x.size))
        src = f"inverse Fisher information, σ from the residuals ({t.size - sol.x.size} dof)"
    sig_c = sigma * math.sqrt(inv[0, 0])
    w, sw = sol.x[3], sigma * math.sqrt(inv[3, 3])
    notes = (f"t_ref = {t_ref:.9g} s", f"amplitude {math.hypot(sol.x[1], sol.x[2]):.6g} rad at t_ref",
             f"damping {sol.x[4] if damping else 0.0:.6g} 1/s", f"residual rms {math.sqrt(2 * sol.cost / t.size):.6g} rad")
    return NorthEstimate("fit", float(sol.x[0]), sig_c, src, int(t.size), "about one swing (≥ 2 reversal points) "
                         "to start; any record after that", notes, TWO_PI / w, TWO_PI * sw / w ** 2, sig_c)


def crlb_centre(t, amplitude_rad, omega_rad_s, noise_sigma_rad, damping_per_s=0.0, phase_rad=0.0,
                fit_damping=True, drift=False, t_ref_s=None) -> float:
    """Cramér–Rao bound on σ(c) for the model of :func:`fit_record` sampled at ``t`` (rad).

    Fisher information I = JᵀJ/σ² (J the Jacobian of the model in (c, a, b, ω[, δ][, d]) at the true
    parameters, white Gaussian noise σ); bound √[I⁻¹]_cc. Closed form for an undamped record of
    many whole cycles: the constant column is orthogonal to cos, sin, τ cos and a centred τ, so
    [I⁻¹]_cc → σ²/N: σ(c) ≥ σ/√N (:func:`crlb_centre_long`). Next order, K whole cycles with ω (and
    δ) fitted: the ω/δ columns span τ cos ωτ and τ sin ωτ, and over τ ∈ [−L/2, L/2] the constant
    overlaps τ sin ωτ by L/ω against norms² L and L³/24: correlation² 24/(ωL)² = 6/(π²K²), so
    σ(c) ≈ (σ/√N)(1 + 3/(π²K²)) (checked in tests/test_north_methods.py).
    """
    t = np.asarray(t, dtype=float)
    t_ref = float(np.mean(t)) if t_ref_s is None else float(t_ref_s)
    tau = t - t_ref
    a, b = amplitude_rad * math.cos(phase_rad), -amplitude_rad * math.sin(phase_rad)
    J = _fit_jacobian(tau, np.array([0.0, a, b, omega_rad_s, damping_per_s] + ([0.0] if drift else [])), True, drift)
    if not fit_damping:                     # δ known: its column leaves the information matrix
        J = np.delete(J, 4, axis=1)
    return float(noise_sigma_rad * math.sqrt(np.linalg.inv(J.T @ J)[0, 0]))


def crlb_centre_long(noise_sigma_rad, n_samples) -> float:
    """σ/√N: the bound on σ(c) for an undamped record of many whole cycles (:func:`crlb_centre`)."""
    return float(noise_sigma_rad / math.sqrt(n_samples))


# ----------------------------------------------------------------------------- the torsion tape
def tape_ratio(period_on_s, period_off_s, period_on_sigma_s=0.0, period_off_sigma_s=0.0) -> tuple:
    """D_B/D_K from the rotor-on and rotor-off periods, and its σ.

    The suspended body (moment of inertia J about the vertical) swings rotor-off on the tape alone,
    a torsion pendulum ω_off² = D_B/J, and rotor-on under tape and directing torque,
    ω_on² = (D_K + D_B)/J (D_K = C ρ0 n cos γ, Quet sec. 4 §1 eq. 8 times A; physics_notes). Hence
    D_B/D_K = ω_off²/(ω_on² − ω_off²) = T_on²/(T_off² − T_on²) (note: T_on²/T_off² alone is
    D_B/(D_K + D_B), not D_B/D_K). Either both full periods or both half periods.

    Returns
    -------
    (ratio, sigma) : tuple of float
        σ propagated from the periods' σ: ∂r/∂T_on = 2 T_on T_off²/(T_off² − T_on²)²,
        ∂r/∂T_off = −2 T_off T_on²/(T_off² − T_on²)².
    """
    if not (period_on_s > 0 and math.isfinite(period_on_s)):
        raise SceneError("period_on_s", period_on_s, "must be a finite period > 0 (s)")
    if not (math.isfinite(period_off_s) and period_off_s > period_on_s):
        raise SceneError("period_off_s", period_off_s, f"must exceed the rotor-on period {period_on_s:.6g} s: "
                         "a tape at least as stiff as the directing torque cancels or reverses it "
                         "(D_K = J(ω_on² − ω_off²) ≤ 0)")
    x, y = period_on_s ** 2, period_off_s ** 2
    r = x / (y - x)
    dr_on, dr_off = 2 * period_on_s * y / (y - x) ** 2, -2 * period_off_s * x / (y - x) ** 2
    return float(r), float(math.hypot(dr_on * period_on_sigma_s, dr_off * period_off_sigma_s))


def tape_corrected(estimate, tape_zero_rad, ratio, ratio_sigma=0.0, tape_zero_sigma_rad=0.0) -> NorthEstimate:
    """The north reading from a swing centre under tape torsion: N = c + (D_B/D_K)(c − Z).

    The centre of the rotor-on swing is the torque balance c = (D_K N + D_B Z)/(D_K + D_B)
    (physics_notes "North finding"), solved for N. σ² = (1+r)² σ_c² + r² σ_Z² + (c − Z)² σ_r², the
    three independent (Z from the rotor-off swing, r from the two periods, c from the rotor-on
    swing). ``estimate``: a :class:`NorthEstimate` of the rotor-on centre.
    """
    c, r = estimate.centre_rad, float(ratio)
    if not (r >= 0 and math.isfinite(r)):
        raise SceneError("tape_ratio", ratio, "D_B/D_K must be finite and ≥ 0")
    north = c + r * (c - tape_zero_rad)
    sig = None if estimate.sigma_rad is None else float(math.sqrt(
        ((1 + r) * estimate.sigma_rad) ** 2 + (r * tape_zero_sigma_rad) ** 2 + ((c - tape_zero_rad) * ratio_sigma) ** 2))
    return NorthEstimate(estimate.method + "+tape", float(north), sig,
                         estimate.sigma_source + "; with the tape zero's and the ratio's σ", estimate.n_used,
                         estimate.needs + "; a rotor-off swing (tape zero and period)",
                         estimate.notes + (f"tape: D_B/D_K = {r:.6g}, zero {tape_zero_rad:.9g} rad",),
                         estimate.period_s, estimate.period_sigma_s, None)


# ----------------------------------------------------------------------------- all together
def north_methods(t, u, noise_sigma_rad=None, mark_rad=None, drift=False) -> tuple:
    """Every method on one record: ({name: NorthEstimate}, {name: why it was refused}).

    Names: ``schuler_mean`` and ``lavrov`` (on the reversal points, σ propagated from their σ),
    ``transit`` (the mark: ``mark_rad``, default the Schuler mean — a mark set near the centre, as
    a surveyor first sets the theodolite near north from a rough reversal-point reading) and ``fit``
    (with a linear drift of the centre when ``drift``: the centre at the mean sample time).
    """
    rp = reversal_points(t, u, noise_sigma_rad)
    out, refused = {}, {}
    runs = {"schuler_mean": lambda: schuler_mean(rp.readings_rad, rp.sigmas_rad),
            "lavrov": lambda: lavrov(rp.readings_rad, rp.sigmas_rad),
            "transit": lambda: transit_method(t, u, out["schuler_mean"].centre_rad if mark_rad is None
                                              else mark_rad, noise_sigma_rad),
            "fit": lambda: fit_record(t, u, noise_sigma_rad, drift=drift)}
    for name, run in runs.items():
        try:
            out[name] = run()
        except (SceneError, KeyError, np.linalg.LinAlgError) as exc:
            refused[name] = str(exc)
    return out, refused
