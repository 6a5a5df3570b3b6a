"""Latitude γ and Earth rate n from the instruments' measurements, with honest uncertainty.

Each measurement is linear in the unknown rates for a fixed latitude:

* a gyroscope whose axis swings about a directing line (plane gyroscope, cone, locked gimbal):
  K = (π/T0)² = g n ρ s(γ) (Quet sec. 4 §1 eq. 9; §IV), g = C/J the known inertia gain, ρ the mean
  measured spin, T0 the small-amplitude swing duration, s(γ) = sin ω the sine of the angle between
  the directing plane's normal and Earth's axis: cos γ for a horizontal plane, 1 for the meridian.
  Dividing by g ρ gives y = n s(γ);
* a Foucault pendulum: k = n sin γ (sec. 2).

For each trial γ the best n (or, when the inertia gain is not trusted, n and G = g n) follows in
closed form, so the weighted χ² is profiled over γ alone; γ̂ is its minimum on [−90°, 90°] and
the 1-σ interval is where χ² rises by 1. This reproduces Quet's item 9 (cos γ = (T_m/T_h)² ρ_m/ρ_h)
and eq. (10) (n = π²/(μ ρ0 T_m²)) when only the two gyroscopes are given, and stays honest near the
equator (cos γ flat: the gyroscopes' interval widens as 1/sin γ) and the pole (sin γ flat: the
pendulum's widens as 1/cos γ) — the two instruments complement each other.
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar


@dataclass
class RateMeasurement:
    """y = n · s(γ) (``kind='gyro'``, y = K/(gρ)) or y = n sin γ (``kind='pendulum'``).

    ``geometry`` is the plane normal in ENU for a gyroscope (s = √(1 − (N·a(γ))²), a(γ) the unit
    Earth axis (0, cos γ, sin γ)); ``gain_known`` False means y = K/ρ and the gain is fitted.
    """

    name: str
    kind: str
    value: float
    sigma: float
    geometry: tuple = (0.0, 0.0, 1.0)
    gain_known: bool = True
    crlb_sigma: float = math.nan

    def shape(self, gamma):
        """s(γ): sin γ for a pendulum, sin ω(γ) for a gyroscope (γ scalar or array, rad)."""
        gamma = np.asarray(gamma, dtype=float)
        if self.kind == "pendulum":
            return np.sin(gamma)
        nx, ny, nz = self.geometry
        norm = math.sqrt(nx * nx + ny * ny + nz * nz)
        c = (ny * np.cos(gamma) + nz * np.sin(gamma)) / norm
        return np.sqrt(np.maximum(1.0 - c * c, 0.0))


def _chi2(gamma, meas, use_crlb=False):
    """Profiled χ²(γ) and the best rates at γ, by the closed-form normal equations.

    Unknowns: n alone, or (n, G) when some gyroscope's gain is not trusted (its rows are
    y = G s(γ), the pendulum's y = n sin γ). ``gamma`` may be an array (vectorised over a grid).
    """
    g = np.atleast_1d(np.asarray(gamma, dtype=float))
    two = any(m.kind == "gyro" and not m.gain_known for m in meas)
    # accumulate the 2x2 (or 1x1) normal equations Σ w a aᵀ θ = Σ w a y
    S = np.zeros((2, 2) + g.shape)
    b = np.zeros((2,) + g.shape)
    rows = []
    for m in meas:
        sig = m.crlb_sigma if use_crlb else m.sigma
        w = 1.0 / (sig * sig)
        s = m.shape(g)
        j = 1 if (two and m.kind == "gyro" and not m.gain_known) else 0
        S[j, j] += w * s * s
        b[j] += w * s * m.value
        rows.append((w, s, j, m.value))
    # the two blocks decouple (each row has one nonzero coefficient)
    with np.errstate(divide="ignore", invalid="ignore"):
        n = np.where(S[0, 0] > 0, b[0] / S[0, 0], 0.0)
        G = np.where(S[1, 1] > 0, b[1] / S[1, 1], 0.0) if two else np.zeros_like(n)
    theta = np.array([n, G])
    # χ² from the residuals, not as Σ w y² − θ·b: those two terms are ~(y/σ)² ~ 1e12 here and
    # their difference kept only ~1e-3 of χ², enough to move the latitude by 0.03 σ
    chi2 = np.zeros_like(n)
    for w, s, j, y in rows:
        r = y - theta[j] * s
        chi2 += w * r * r
    chi2 = np.maximum(chi2, 0.0)
    if np.ndim(gamma) == 0:
        return float(chi2[0]), theta[:, 0]
    return chi2, theta


@dataclass
class LatitudeResult:
    latitude_rad: float
    latitude_lo_rad: float
    latitude_hi_rad: float
    earth_rate_rad_s: float
    earth_rate_sigma_rad_s: float
    chi2: float
    dof: int
    carried_by: dict
    dropped: dict = None

    @property
    def latitude_sigma_rad(self):
        return 0.5 * (self.latitude_hi_rad - self.latitude_lo_rad)


def solve_latitude(meas, use_crlb=False, prefer_north=True, flat_sigma=3.0):
    """Like :func:`_solve`, but a gyroscope measured within ``flat_sigma`` σ of the flat maximum of
    its s(γ) (a horizontal gyroscope near the equator: cos γ ≈ 1) is left out of the latitude when
    a pendulum can carry it — there its information on γ is non-Gaussian and a Δχ² = 1 interval
    would under-cover. ``dropped`` on the result says which and why."""
    res = _solve(meas, use_crlb, prefer_north)
    has_pendulum = any(m.kind == "pendulum" for m in meas)
    grid = np.linspace(-math.pi / 2, math.pi / 2, 3601)
    dropped = {}
    for m in meas:
        if m.kind != "gyro" or not has_pendulum:
            continue
        sg = m.shape(grid)
        if np.ptp(sg) < 1e-12:
            continue
        sig = m.crlb_sigma if use_crlb else m.sigma
        if res.earth_rate_rad_s * float(np.max(sg)) - m.value < flat_sigma * sig:
            dropped[m.name] = (f"within {flat_sigma:g} sigma of the flat maximum of its directing factor "
                               f"(cos(latitude) ≈ 1 near the equator): no Gaussian latitude information")
    kept = [m for m in meas if m.name not in dropped]
    if dropped and len(kept) >= 2:
        res = _solve(kept, use_crlb, prefer_north)
    res.dropped = dropped
    return res


def _solve(meas, use_crlb=False, prefer_north=True):
    """Profile-likelihood latitude and Earth rate from :class:`RateMeasurement` objects.

    Returns
    -------
    LatitudeResult
        γ̂ with its Δχ² = 1 interval, n̂ with its standard error, and each instrument's share of the
        Fisher information on γ at γ̂ (``carried_by``).
    """
    if len(meas) < 2:
        raise ValueError("need at least two measurements to separate latitude and Earth rate")
    half = math.pi / 2
    f = lambda g: _chi2(g, meas, use_crlb)[0]  # noqa: E731
    grid = np.linspace(-half, half, 3601)
    vals = _chi2(grid, meas, use_crlb)[0]
    best = float(vals.min())
    # symmetric minima (no pendulum): prefer the northern one
    cands = np.nonzero(vals <= best + 1e-9 * max(best, 1.0) + 1e-12)[0]
    i = int(cands[-1] if prefer_north else cands[0]) if len(cands) > 1 else int(np.argmin(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]
    res = minimize_scalar(f, bounds=(lo, hi), method="bounded", options={"xatol": 1e-13})
    g_hat = float(res.x) if res.fun <= vals[i] else float(grid[i])
    c_min = f(g_hat)
    target = c_min + 1.0

    def edge(direction, center=None):
        step = 1e-9
        g_c = g_hat if center is None else center
        g = g_c
        while True:
            g2 = g_c + direction * step
            if abs(g2) >= half:
                g2 = math.copysign(half, g2)
                return g2 if f(g2) <= target else brentq(lambda x: f(x) - target, g, g2, xtol=1e-15)
            if f(g2) > target:
                return brentq(lambda x: f(x) - target, g, g2, xtol=1e-15)
            g = g2
            step *= 2.0

    g_lo, g_hi = edge(-1.0), edge(+1.0)
    # The gyroscopes' s(γ) are even in γ: when the mirror latitude −γ̂ is also allowed (the pendulum
    # cannot tell them apart, as near the equator), the interval spans both.
    if g_hat != 0.0 and f(-g_hat) <= target:
        g_lo, g_hi = min(g_lo, edge(-1.0, -g_hat)), max(g_hi, edge(+1.0, -g_hat))
    # A profile with several dips under the threshold (near the equator the gyroscopes' cos γ is
    # even and flat, so ±γ are both allowed): the interval spans every grid region below it.
    inside = np.nonzero(vals <= target)[0]
    if inside.size:
        a, b = int(inside[0]), int(inside[-1])
        if a > 0:
            g_lo = min(g_lo, brentq(lambda x: f(x) - target, grid[a - 1], grid[a], xtol=1e-15))
        else:
            g_lo = -half
        if b < len(grid) - 1:
            g_hi = max(g_hi, brentq(lambda x: f(x) - target, grid[b], grid[b + 1], xtol=1e-15))
        else:
            g_hi = half
    _, theta = _chi2(g_hat, meas, use_crlb)
    n_hat = float(theta[0])
    # σ(n) at fixed γ̂ plus the γ uncertainty propagated (numerical derivative of n̂(γ))
    has_gain = any(m.kind == "gyro" and not m.gain_known for m in meas)
    info_n = sum(float(m.shape(g_hat)) ** 2 / (m.crlb_sigma if use_crlb else m.sigma) ** 2
                 for m in meas if not (m.kind == "gyro" and not m.gain_known))
    sig_n_fixed = 1.0 / math.sqrt(info_n) if info_n > 0 else math.inf
    dg = 1e-7
    n_plus = _chi2(min(g_hat + dg, half), meas, use_crlb)[1][0]
    n_minus = _chi2(max(g_hat - dg, -half), meas, use_crlb)[1][0]
    dn_dg = (n_plus - n_minus) / (min(g_hat + dg, half) - max(g_hat - dg, -half))
    sig_g = 0.5 * (g_hi - g_lo)
    sig_n = math.sqrt(sig_n_fixed ** 2 + (dn_dg * sig_g) ** 2)
    # information share on γ (n held at n̂)
    info = {}
    for m in meas:
        sig = m.crlb_sigma if use_crlb else m.sigma
        ds = float(m.shape(min(g_hat + dg, half)) - m.shape(max(g_hat - dg, -half))) / (2 * dg)
        info[m.name] = (n_hat * ds / sig) ** 2
    total = sum(info.values()) or 1.0
    share = {k: v / total for k, v in info.items()}
    dof = len(meas) - (2 + (1 if has_gain else 0))
    return LatitudeResult(g_hat, g_lo, g_hi, n_hat, sig_n, c_min, dof, share)


def item9_cos_latitude(T_meridian_s, T_horizontal_s, spin_meridian=1.0, spin_horizontal=1.0):
    """Quet item 9: cos γ = (T_m / T_h)² · ρ_m / ρ_h (small-amplitude one-swing durations)."""
    return (T_meridian_s / T_horizontal_s) ** 2 * spin_meridian / spin_horizontal

