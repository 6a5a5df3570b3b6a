"""The numbers of a sailing compass's record (issue 39 item 6): its settling curve fitted, its settle point
and its heading error along the track (the kind :class:`.compass_kind.CompassKind` writes them into the
estimate; the records are :mod:`.compass_entries`).

The heading error e(t) = wrap(reading − course) of a compass read against the ship's course (a real ship
has its course, latitude and speed from GNSS and the log). The settling curve is the compass's linear
theory (:mod:`gyro_instrument.instruments.marine_gyrocompass.theory`): on a steady course the linearised
equations are a damped oscillator about the settle point, so

    e(t) = e_s + A exp(−λ τ) cos(ω τ + φ) [+ B exp(−μ τ)],  τ = t − t_0

the bracket a real mode that damping in azimuth adds (the oil ballistic's lag makes the equations third
order, :mod:`.dynamics`; the speed filter's and the element's swing's transients are faster still): it
is kept when it lowers Akaike's criterion n ln(RSS/n) + 2k and its rate μ
is above the predicted ω0 (a fit that holds μ at that bound is dropped: a slower real mode is a drift
of the settle point the record cannot tell from e_s; with μ free the asymptote of a compass whose
latitude input is wrong wandered by 1.4° with σ 14°). The fit is
nonlinear least squares (scipy ``least_squares``, from the compass's predicted undamped period and three
starting frequencies); its covariance s² (JᵀJ)⁻¹ gives the σ, s the larger of the sensor's noise and the
residuals' rms (a model that misfits widens its σ). Derived: the damped period T_d = 2π/ω, the damping
ratio ζ = λ/√(λ² + ω²), the log decrement per period Λ = λ T_d and the ratio of successive swings to
either side exp(λ T_d / 2), their σ by the delta method (the gradient through the covariance).

Settle point (ISO 22090-1 §3.10–3.12, :mod:`gyro_instrument.instruments.marine_gyrocompass.iso`): settled
when three readings 30 min apart lie within 0.7° (readings every minute, or every sample when the record
is sparser); the settle-point error is the mean of every reading from then to the end of the record, σ =
σ_n / √N with σ_n the readings' noise (the larger of the sensor's and the settled readings' scatter
from their second differences, 1.4826 MAD / √6: a slow curve cancels in them); ISO's ten-reading figure
is given beside it. That σ holds only if the settled readings scatter about one value by their noise
alone; a compass that is still swinging within the 0.7° band, or whose settle point moves along the
track, wanders more slowly than the noise shows. The mean is ISO's statistic of this record, and σ_n/√N
is its uncertainty from the noise (calibrated over seeds against the noise-free record's same mean);
as an estimate of where the compass settles, the wander adds to it. So the settled readings' means over
blocks of ISO's reading interval (20 min) are tested against the noise (χ² of the block means about
their weighted mean, B − 1 degrees of freedom, at least 3 blocks); when the noise alone explains them
with probability below :data:`WANDER_P`, the check says so and the comparison with the closed-form
settle point (the track's measured − predicted) takes the block means' scatter / √B as its σ (batch
means: the blocks taken as independent, so still a lower bound when the wander is slower than a block).
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.instruments.marine_gyrocompass import iso

#: A swing whose amplitude is within this many σ of zero is no settling curve (z of a normal: 3).
AMPLITUDE_Z = 3.0
#: Significance below which the settled readings' block means are taken to wander (χ² test; a white-noise
#: record is flagged in 1 % of seeds and its σ then comes from B block means instead).
WANDER_P = 0.01
#: Starting frequencies of the fit, as multiples of the predicted undamped one.
START_FACTORS = (1.0, 0.7, 1.4)


def wrap_rad(x) -> np.ndarray:
    """``x`` wrapped to [−π, π), rad."""
    return np.mod(np.asarray(x, dtype=float) + math.pi, 2 * math.pi) - math.pi


def noise_of(e, sensor_sigma_rad) -> float:
    """σ_n of readings ``e`` (rad): the larger of the sensor's and 1.4826 MAD(Δ²e)/√6 (module docstring)."""
    d2 = np.diff(e, 2)
    robust = 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(6.0) if d2.size >= 5 else 0.0
    return max(float(sensor_sigma_rad), robust)


def readings(t, e_deg) -> tuple:
    """(times, errors) every :data:`iso.STEP_S` (or every sample when sparser): the first sample at or
    after each grid time, and the grid's step (s)."""
    dt = float(np.median(np.diff(t))) if t.size > 1 else iso.STEP_S
    step = max(iso.STEP_S, dt)
    grid = t[0] + step * np.arange(int((t[-1] - t[0]) // step) + 1)
    idx = np.minimum(np.searchsorted(t, grid - 1e-6), t.size - 1)
    return t[idx], e_deg[idx], step


@dataclass(frozen=True)
class SettlePoint:
    """The settle point from a record (module docstring); None fields when not settled."""

    settled_at_s: float | None
    mean_rad: float | None
    sigma_rad: float | None
    samples: int
    noise_rad: float
    iso_mean_rad: float | None
    iso_rms_rad: float | None
    reason: str | None
    #: the χ² test of the settled readings' 20-min block means: (blocks, statistic, p, σ of the mean from the
    #: block means, rad), None under 3 blocks
    wander: tuple | None = None


def block_wander(t, e, noise_rad) -> "tuple | None":
    """The settled readings ``e`` (rad) at times ``t`` (s) in blocks of :data:`iso.SP_INTERVAL_S`: (B, χ²
    of the block means about their weighted mean in units of the noise ``noise_rad``, p of χ²(B − 1),
    σ of the mean from the block means' scatter / √B, rad); None with fewer than 3 non-empty blocks."""
    from scipy.stats import chi2
    edges = t[0] + iso.SP_INTERVAL_S * np.arange(int((t[-1] - t[0]) // iso.SP_INTERVAL_S) + 1)
    idx = np.searchsorted(t, edges)
    pairs = [(a, b) for a, b in zip(idx[:-1], idx[1:]) if b > a]
    if len(pairs) < 3:
        return None
    means = np.array([e[a:b].mean() for a, b in pairs])
    n = np.array([b - a for a, b in pairs], dtype=float)
    centre = float(np.sum(n * means) / np.sum(n))
    stat = float(np.sum(n * (means - centre) ** 2)) / noise_rad ** 2
    B = len(pairs)
    return B, stat, float(chi2.sf(stat, B - 1)), float(np.std(means, ddof=1) / math.sqrt(B))


def settle_point(t, e, sensor_sigma_rad) -> SettlePoint:
    """The settle point of the heading errors ``e`` (rad) at times ``t`` (s) (module docstring)."""
    rt, re, step = readings(t, np.degrees(e))
    ts = iso.settle_time_s(rt, re, step)
    if ts is None:
        return SettlePoint(None, None, None, 0, noise_of(e, sensor_sigma_rad), None, None,
                           f"not settled within the record ({t[-1] - t[0]:.0f} s): no three readings 30 min apart "
                           f"within {iso.SETTLE_BAND_DEG:g} deg (ISO 22090-1 §3.10)")
    m = t >= ts
    sig_n = noise_of(e[m], sensor_sigma_rad)
    iso_pt = iso.settle_point(t, np.degrees(e), ts)
    return SettlePoint(ts, float(e[m].mean()), sig_n / math.sqrt(int(m.sum())), int(m.sum()), sig_n,
                       None if iso_pt is None else math.radians(iso_pt[0]),
                       None if iso_pt is None else math.radians(iso_pt[1]), None, block_wander(t[m], e[m], sig_n))


def _model(p, tau) -> np.ndarray:
    y = p[0] + p[1] * np.exp(-p[2] * tau) * np.cos(p[3] * tau + p[4])
    return y + p[5] * np.exp(-p[6] * tau) if p.size > 5 else y


def _fit_one(tau, e, p0, mu_min) -> "object | None":
    from scipy.optimize import least_squares
    lo = [-np.inf, -np.inf, 0.0, 1e-6, -np.inf] + ([-np.inf, mu_min] if len(p0) > 5 else [])
    try:
        r = least_squares(lambda p: _model(p, tau) - e, p0, bounds=(lo, np.inf), x_scale="jac", method="trf",
                          max_nfev=2000)
    except (ValueError, np.linalg.LinAlgError):
        return None
    return r if np.all(np.isfinite(r.x)) else None


@dataclass(frozen=True)
class CurveFit:
    """The settling curve fitted (module docstring): values and σ, or ``reason`` when not determined."""

    values: dict
    sigmas: dict
    model: str
    residual_rms_rad: float
    sigma_basis: str
    samples: int
    reason: str | None = None


def fit_curve(t, e, period_guess_s, sensor_sigma_rad, terms=(5, 7)) -> CurveFit:
    """Fit the settling curve to the errors ``e`` (rad) at ``t`` (s) from the predicted undamped period
    ``period_guess_s`` (module docstring), with 5 parameters (the damped sinusoid) or 7 (and the exponential
    mode), whichever of ``terms`` Akaike's criterion prefers; a :class:`CurveFit` with a reason when the
    record cannot give the period and the damping (shorter than one period, no swing above its noise, no
    convergence)."""
    span = float(t[-1] - t[0])
    if not (math.isfinite(period_guess_s) and period_guess_s > 0):
        return CurveFit({}, {}, "", math.nan, "", t.size, "the compass has no period here (no Earth rate, or a pole)")
    if span < period_guess_s:
        return CurveFit({}, {}, "", math.nan, "", t.size,
                        f"the record ({span:.0f} s) is shorter than one swing of the compass (about "
                        f"{period_guess_s:.0f} s): no settling curve to fit")
    tau = t - t[0]
    mu_min = 2 * math.pi / period_guess_s         # the extra mode decays faster than the swing turns a radian
    tail = e[tau >= 0.8 * span]
    es0 = float(np.median(tail))
    best = {}
    for k in terms:
        for f in START_FACTORS:
            w0 = f * 2 * math.pi / period_guess_s
            p0 = [es0, float(e[0] - es0), 0.25 * w0, w0, 0.0] + ([0.0, 4.0 * mu_min] if k == 7 else [])
            r = _fit_one(tau, e, p0, mu_min)
            if r is not None and k == 7 and r.x[6] <= 1.001 * mu_min:
                r = None                        # held at the bound: not a mode the record resolves
            if r is not None and (k not in best or r.cost < best[k].cost):
                best[k] = r
    if not best:
        return CurveFit({}, {}, "", math.nan, "", t.size, "the settling curve's fit did not converge")
    aic = {k: t.size * math.log(max(2 * r.cost, 1e-300) / t.size) + 2 * k for k, r in best.items()}
    k = min(aic, key=aic.get)
    return _curve_values(best[k], k, t.size, sensor_sigma_rad)


def _curve_values(r, k, n, sensor_sigma_rad) -> CurveFit:
    """The values, σ and reasons of a converged fit ``r`` with ``k`` parameters of ``n`` samples."""
    rms = math.sqrt(2 * r.cost / max(n - k, 1))
    s = max(float(sensor_sigma_rad), rms)
    basis = "sensor noise" if s == float(sensor_sigma_rad) else "residual scatter"
    model = "damped sinusoid" + (" + exponential mode" if k == 7 else "")
    J = r.jac
    try:
        cov = s * s * np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        return CurveFit({}, {}, model, rms, basis, n, "the settling curve's parameters are not determined "
                                                      "(singular fit)")
    es, A, lam, w = (float(v) for v in r.x[:4])
    sig_A = math.sqrt(max(cov[1, 1], 0.0))
    if abs(A) <= AMPLITUDE_Z * sig_A or not np.all(np.isfinite(cov[:4, :4])):
        return CurveFit({}, {}, model, rms, basis, n,
                        f"no settling swing above the noise (amplitude {math.degrees(A):.3g} +/- "
                        f"{math.degrees(sig_A):.2g} deg): the record starts settled, period and damping are not "
                        f"determined")
    derived = {"settle_point_rad": lambda p: p[0], "amplitude_rad": lambda p: abs(p[1]),
               "period_s": lambda p: 2 * math.pi / p[3],
               "undamped_period_s": lambda p: 2 * math.pi / math.hypot(p[2], p[3]),
               "damping_ratio": lambda p: p[2] / math.hypot(p[2], p[3]),
               "log_decrement": lambda p: 2 * math.pi * p[2] / p[3],
               "swing_ratio": lambda p: math.exp(math.pi * p[2] / p[3])}
    values, sigmas = {}, {}
    for name, f in derived.items():
        values[name] = float(f(r.x))
        g = np.zeros(r.x.size)
        for i in range(4):
            h = 1e-6 * max(abs(r.x[i]), 1e-9)
            xp, xm = r.x.copy(), r.x.copy()
            xp[i] += h
            xm[i] -= h
            g[i] = (f(xp) - f(xm)) / (2 * h)
        sigmas[name] = float(math.sqrt(max(g @ cov @ g, 0.0)))
    return CurveFit(values, sigmas, model, rms, basis, n)
