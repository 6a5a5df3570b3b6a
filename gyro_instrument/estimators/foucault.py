"""Foucault precession from sampled bob deflections, corrected for the ellipse (Airy) precession.

Inputs are the bob's horizontal deflection components θ_e = x/l, θ_n = y/l (rad), as a sensor
measures them. Method:

1. the swing period from a sine fit of the dominant component;
2. one window per period: the second moments of (θ_e, θ_n) give the swing-plane azimuth ψ_i
   (compass, modulo π) and the shoelace sum gives the mean areal velocity
   H = ⟨θ_n θ̇_e − θ_e θ̇_n⟩ = ⟨sin²θ ψ̇⟩ (Quet sec. 2 eq. 27's left-hand side, Earth frame);
3. a least-squares line through ψ_i gives the measured rate m;
4. the ellipse correction is exact (Quet sec. 2 (26)–(27), §III–IV; the elliptic-integral
   apsidal angle of :func:`~gyro_instrument.instruments.pendulum.apsidal_rate_exact_rad_s`): the
   area constant c = ⟨H⟩ − k⟨sin²θ⟩ ((27): sin²θ (ψ̇ − k) is conserved), the amplitude α from
   ⟨sin²θ⟩ (:func:`mean_sin2_deflection`) and ω0 from the swing period give the apse rate
   m = k + sgn(c)(Φ − π/2)/T, solved for k (:func:`invert_apse_rate`) for any swing, planar or
   not. For small swings this is k = (m − (3/8)⟨H⟩)/(1 − (3/8)⟨θ²⟩) (Airy); at 30° on 1 m that
   series was 85σ off on noise-free data. H per sample uses 6th-order central differences.

The horizontal Earth-rate component n cos γ enters through c (which ⟨H⟩ measures); given c the
law holds to ~1.6e-6 k at 30° on 1 m (tests/test_apsidal_rate.py).

Cramér–Rao bound (``crlb_k_rad_s``) from white noise σ on each component — the sensor model's
√(σ² + q²/12) passed as ``noise_rad``, else estimated from 6th differences of the samples (blind to
the swing and its precession): var(m̂) ≥ 12σ²/(⟨sin²θ⟩ N T²) (24σ²/(α² N T²) for a small swing) and
var⟨H⟩ ≥ 4σ²⟨θ̇²⟩/N, through the inversion's slopes ∂k/∂m, ∂k/∂⟨H⟩. σ = 0 gives 0.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from scipy.optimize import brentq
from scipy.special import ellipe, ellipk

from gyro_instrument.estimators.adequacy import detection_snr
from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, NoSignal, fit_oscillation
from gyro_instrument.estimators.scatter import WHITE, line_with_record_sigma, newey_west_mean_sigma, nw_lags, slope
from gyro_instrument.instruments.pendulum import (SWING_WINDOW_MIN_SAMPLES, apsidal_angle, areal_constant_over_omega0,
                                                  min_deflection_for_areal_constant)


@dataclass
class FoucaultEstimate:
    """Foucault rate k (rad/s, positive: compass azimuth increasing) and its diagnostics."""

    k_rad_s: float
    k_sigma_rad_s: float
    measured_rate_rad_s: float
    airy_correction_rad_s: float
    amplitude_rad: float
    minor_axis_rad: float
    period_s: float
    windows: int
    crlb_k_rad_s: float
    observation_s: float
    notes: list = field(default_factory=list)
    noise_rad: float = math.nan
    plane_chi2_per_dof: float = math.nan
    plane_dof: int = 0
    measured_rate_sigma_rad_s: float = math.nan
    sigma_basis: str = "white"
    sigma_basis_text: str = ""
    plane_line: object = None
    period_sigma_s: float = math.nan
    rest_point: dict = field(default_factory=dict)


def estimate_foucault(t, theta_e, theta_n, correct_ellipse=True, noise_rad=None) -> FoucaultEstimate:
    """Estimate the Foucault rate from deflection samples; see module docstring.

    ``noise_rad``: the standard deviation of the white noise on each deflection component when the
    sensor model is known (√(σ² + q²/12) with quantization q: ``SensorModel.effective_sigma_rad``);
    ``None`` estimates it from the data (:func:`noise_from_differences`, blind to the swing and its
    precession). It sets the Cramér–Rao bound ``crlb_k_rad_s`` (0 for noise-free data).

    Raises
    ------
    EstimationError
        When the record holds fewer than 3 periods or the swing has no measurable plane.
    """
    t, e, nn, notes = _clean_deflections(t, theta_e, theta_n)
    if t.size < 20:
        raise EstimationError(f"too few valid pendulum samples ({t.size})")
    main = e if np.var(e) >= np.var(nn) else nn
    fit = fit_oscillation(t, main)
    snr = detection_snr(fit.amplitude, fit.n_samples, fit.residual_rms)   # the same rule as a gyroscope's
    if snr < DETECTION_SNR:
        raise NoSignal(f"no swing detected (SNR {snr:.3g} < {DETECTION_SNR:g}): a bob at rest has no "
                              f"swing plane, so no Foucault rate")
    period = 2 * math.pi / fit.omega_rad_s
    n_win = int((t[-1] - t[0]) // period)
    if n_win < 3:
        raise EstimationError(f"record holds {n_win} swing periods; need at least 3 to fit a precession")
    e, nn, rest = _centred(t, e, nn, period, n_win)
    # σ (a local uncertainty) from the record's own noise; the bound from the sensor model's
    noise_data = noise_from_differences(t, e, nn)
    if noise_rad is None:
        sigma_noise = noise_data
        notes.append(f"noise {sigma_noise:.3g} rad estimated from 6th divided differences of the samples (no sensor "
                     "model)")
    else:
        sigma_noise = float(noise_rad)
    h_seg, v2 = areal_segments(t, e, nn, 2.0 * math.pi / period, speed2=True)
    psi, tc, H, r2, amp, minor, w = _swing_windows(t, e, nn, period, n_win, h_seg)
    if len(psi) < 3:
        raise EstimationError("fewer than 3 complete swing periods with samples")
    ok = np.isfinite(H)
    Hm = float(np.average(np.asarray(H)[ok], weights=np.asarray(w)[ok])) if ok.any() else 0.0
    # σ of ⟨H⟩ from the noise: per sample the noise enters as 2 θ̇ × (noise across the swing) once
    # the derivative's noise is summed by parts, var ⟨H⟩ = 4σ²⟨θ̇²⟩/N — also the Cramér–Rao bound
    # of the areal velocity (the minor axis b of a thin swing α cos ωt: σ_b² = 2σ²/N, H = α b ω).
    # (Window-to-window scatter overstates it: adjacent windows share the summed-by-parts edges.)
    # less the noise's share: each interval's |Δθ|² holds 4σ² of it
    v2m = max(float(np.mean(v2 - 4.0 * noise_data ** 2 / np.diff(t) ** 2)), 0.0) if v2.size else 0.0
    H_se = 2.0 * noise_data * math.sqrt(v2m / max(v2.size, 1))
    H_bound = 2.0 * sigma_noise * math.sqrt(v2m / max(v2.size, 1))
    # ⟨sin²θ⟩ less the noise's share 2σ² (both components)
    r2m = max(float(np.average(r2, weights=w)) - 2.0 * sigma_noise ** 2, 0.0)
    # the plane rate's σ from the noise the record shows (the window estimator is efficient: its
    # scatter matches this bound over seeds) while the azimuths scatter about their line as white
    # noise does; otherwise (χ²/dof, swing-to-swing correlation, halves that disagree) from the
    # record's own scatter (estimators/scatter.py), and ⟨H⟩'s σ from its windows' (Newey–West)
    span = float(t[-1] - t[0])
    line = line_with_record_sigma(tc, np.unwrap(2.0 * np.asarray(psi)) / 2.0,
                                  foucault_crlb_rad_s(noise_data, r2m, t.size, span))
    m, sig_m = line.rate, line.sigma
    if line.sigma_basis != WHITE:
        notes.append(f"sigma of the plane rate from the record's scatter ({'; '.join(line.reasons)})")
        if ok.sum() > 2:
            H_se = max(H_se, newey_west_mean_sigma(np.asarray(H)[ok], nw_lags(int(ok.sum()))))
    alpha = float(np.mean(amp))
    dk_dm = 1.0
    if correct_ellipse:
        k = invert_apse_rate(m, Hm, r2m, period)
        hm = 1e-6 * max(abs(m), abs(Hm), 1e-12)
        dk_dm = (invert_apse_rate(m + hm, Hm, r2m, period) - invert_apse_rate(m - hm, Hm, r2m, period)) / (2 * hm)
        dk_dH = (invert_apse_rate(m, Hm + hm, r2m, period) - invert_apse_rate(m, Hm - hm, r2m, period)) / (2 * hm)
        sig_k = math.hypot(dk_dm * sig_m, dk_dH * H_se)
    else:
        k, sig_k = m, sig_m
    crlb = foucault_crlb_rad_s(sigma_noise, r2m, t.size, span, dk_dm)
    if correct_ellipse:
        crlb = math.hypot(crlb, dk_dH * H_bound)
    sig_p = _period_sigma(t, main, fit, line.sigma_basis != WHITE)
    return FoucaultEstimate(k, sig_k, m, m - k, alpha, float(np.median(minor)), period, len(psi), crlb, span, notes,
                            noise_data, line.chi2_per_dof, line.dof, sig_m, line.sigma_basis, line.basis_text(), line,
                            sig_p, rest)


def foucault_crlb_rad_s(sigma_rad, mean_sin2, n_samples, span_s, dk_dm=1.0) -> float:
    """Cramér–Rao bound on the Foucault rate from white noise σ on each deflection component:
    the swing plane's rate m moves the components by sin θ per radian of azimuth, so its Fisher
    information is Σ sin²θ_i (t_i − t̄)²/σ² ≈ N ⟨sin²θ⟩ T²/(12σ²): var(m̂) ≥ 12σ²/(⟨sin²θ⟩ N T²)
    (= 24σ²/(α² N T²) for a small swing of amplitude α, ⟨sin²θ⟩ = α²/2), and k's bound is
    |∂k/∂m| times it (the ellipse correction's slope, :func:`invert_apse_rate`). 0 for σ = 0."""
    if sigma_rad == 0.0:
        return 0.0
    if not (mean_sin2 > 0.0 and n_samples > 0 and span_s > 0.0):
        return math.inf
    return abs(dk_dm) * math.sqrt(12.0 * sigma_rad ** 2 / (mean_sin2 * n_samples * span_s ** 2))


def foucault_crlb_small_swing_rad_s(sigma_rad, alpha_rad, omega_rad_s, n_samples, span_s) -> float:
    """The estimator's bound (:func:`estimate_foucault`) for a small swing α cos ωt planned from a
    sensor model (the planner): ⟨sin²θ⟩ = α²/2, ⟨θ̇²⟩ = α²ω²/2, the ellipse correction's slopes
    ∂k/∂m = −∂k/∂⟨H⟩/(3/8) = 1/(1 − (3/8)⟨sin²θ⟩) (Airy's (3/8) c), so
    σ_k² = (∂k/∂m)² [12σ²/(⟨sin²θ⟩ N T²) + (3/8)² 4σ²⟨θ̇²⟩/N]."""
    if sigma_rad == 0.0:
        return 0.0
    r2 = 0.5 * alpha_rad ** 2
    if not (r2 > 0.0 and n_samples > 0 and span_s > 0.0):
        return math.inf
    dk_dm = 1.0 / (1.0 - 0.375 * r2)
    h_se = 2.0 * sigma_rad * math.sqrt(r2 * omega_rad_s ** 2 / n_samples)
    return math.hypot(foucault_crlb_rad_s(sigma_rad, r2, n_samples, span_s, dk_dm), 0.375 * dk_dm * h_se)


#: Samples in one divided-difference stencil of the noise estimate (a polynomial of degree 5 is
#: annihilated: a smooth swing of ω Δt leaves a relative (ω Δt)⁶ of it, 1e-5 at 40 samples a period).
_STENCIL = 7

#: A stencil spanning more than this many median intervals (a gap in the record) is not used: the
#: swing's 6th derivative over a long span would pass for noise.
_MAX_STENCIL_STEPS = 12.0


def noise_from_differences(t, e, nn) -> float:
    """White-noise σ of the deflection components estimated without a model of the swing, for any
    sampling (dropouts, gaps, clock jitter): over every run of 7 consecutive samples the 6th divided
    difference Σ w_j y_j, w_j = 1/Π_(k≠j)(τ_j − τ_k), annihilates any polynomial of degree 5 (the
    swing and its precession are smooth), and white noise gives it a variance σ² Σ w_j²; so
    σ² = mean((Σ w_j y_j)² / Σ w_j²). For uniform spacing this is the 6th difference / √924. Both
    components pooled; runs spanning more than :data:`_MAX_STENCIL_STEPS` median intervals skipped."""
    L = _STENCIL
    if t.size < L:
        return 0.0
    step = float(np.median(np.diff(t)))
    idx = np.arange(t.size - L + 1)[:, None] + np.arange(L)
    tau = (t[idx] - t[idx[:, L // 2]][:, None]) / step
    keep = (tau[:, -1] - tau[:, 0]) <= _MAX_STENCIL_STEPS
    tau = tau[keep]
    diff = tau[:, :, None] - tau[:, None, :]
    diff[:, np.arange(L), np.arange(L)] = 1.0
    w = 1.0 / np.prod(diff, axis=2)
    w2 = np.sum(w * w, axis=1)
    vals = [np.sum(w * x[idx[keep]], axis=1) ** 2 / w2 for x in (e, nn)]
    v = np.concatenate(vals)
    return float(math.sqrt(np.mean(v))) if v.size else 0.0


def areal_segments(t, e, nn, omega_rad_s, speed2=False) -> "np.ndarray | tuple":
    """The area swept in each sampling interval per second, θ_n θ̇_e − θ_e θ̇_n averaged over it
    (compass sense: sin²θ ψ̇, the Earth frame's eq. (27) left side), for any spacing.

    The shoelace term θ_n,i θ_e,i+1 − θ_e,i θ_n,i+1 is the chord's area, short of the arc's by
    D ≈ κ h³/6 (h = Δt, κ the curve's r' × r'': (ωh)²/6 of it on an ellipse, 4e-3 at 40 samples a
    period — a 10σ bias on a 30° swing). Over two consecutive intervals h1, h2 the triangle of the
    three samples is the difference of the two chords' and the long chord's deficits,
    κ[(h1 + h2)³ − h1³ − h2³]/6, so each interval's deficit follows from the triangles it belongs to
    (Richardson's step halving generalised to unequal steps; exact for any smooth curve to
    O(h⁴), harmonics included). The noise still telescopes over consecutive samples: var ⟨H⟩ ≈
    4σ²⟨θ̇²⟩/N. With ``speed2`` also |Δθ|²/Δt² / sinc²(ωΔt/2) per interval (the speed at its middle
    for a swing of phase rate ω, noise not removed). Arrays of length N − 1."""
    h = np.diff(t)
    de, dn = np.diff(e), np.diff(nn)
    chord = e[:-1] * nn[1:] - nn[:-1] * e[1:]                  # r_i × r_(i+1), r = (θ_e, θ_n)
    tri = de[:-1] * dn[1:] - dn[:-1] * de[1:]                  # (r_(i+1) − r_i) × (r_(i+2) − r_(i+1))
    h1, h2 = h[:-1], h[1:]
    scale = tri / (3.0 * (h1 + h2))
    corr = np.zeros_like(chord)
    count = np.zeros_like(chord)
    corr[:-1] += scale * h1 * h1 / h2                           # interval i as the triangle's first
    corr[1:] += scale * h2 * h2 / h1                            # interval i + 1 as its second
    count[:-1] += 1.0
    count[1:] += 1.0
    area = chord + corr / np.maximum(count, 1.0)
    out = -area / h                                             # compass sense (clockwise from above)
    if not speed2:
        return out
    half = np.sinc(0.5 * omega_rad_s * h / math.pi)
    return out, (de * de + dn * dn) / (h * half) ** 2


def mean_sin2_deflection(alpha_rad, beta_rad) -> float:
    """Time mean of sin²θ over the spherical pendulum's orbit with apsides α ≥ β (exact).

    With z = cos θ, ż² = 2ω0²(z − z1)(z − z2)(z3 − z) (Quet (26)–(27)); the mean of z̈ = f'(z)/2 over
    a period vanishes, so ⟨3z² − 2 s1 z − 1⟩ = 0 (s1 = z1 + z2 + z3, z1z2 + z1z3 + z2z3 = −1), and
    ⟨z⟩ = z1 + (z3 − z1) E(m)/K(m), m = (z3 − z2)/(z3 − z1): ⟨sin²θ⟩ = (2/3)(1 − s1 ⟨z⟩).
    """
    z2, z3 = math.cos(alpha_rad), math.cos(beta_rad)
    z1 = -(1.0 + z2 * z3) / (z2 + z3)
    m = (z3 - z2) / (z3 - z1)
    zbar = z1 + (z3 - z1) * float(ellipe(m)) / float(ellipk(m))
    return 2.0 / 3.0 * (1.0 - (z1 + z2 + z3) * zbar)


#: ⟨sin²θ⟩ grows with the amplitude α up to α ≈ 1.92 rad (110°; beyond, the bob lingers near the top):
#: the estimator inverts it for swings up to 1.9 rad.
MAX_SWING_RAD = 1.9


def swing_orbit(mean_sin2, areal_abs_rad_s, period_s) -> tuple:
    """(α, β, ω0): the orbit whose time means are the measured ⟨sin²θ⟩ and |c| = |⟨sin²θ (ψ̇ − k)⟩|
    and whose swing period (two radial periods, 4T) is ``period_s`` — α from
    :func:`mean_sin2_deflection`, ω0 = 4 (ω0 T)/P (:func:`~gyro_instrument.instruments.pendulum.
    apsidal_angle`), β from |c|/ω0; fixed-point on β (it moves α and ω0 only at O(β²))."""
    beta, omega0 = 0.0, 2.0 * math.pi / period_s
    alpha = 0.0
    for _ in range(30):
        hi = max(min(MAX_SWING_RAD, math.pi - beta - 1e-6), beta)
        f = lambda a: mean_sin2_deflection(a, beta) - mean_sin2
        if f(hi) < 0.0:
            raise EstimationError(f"mean squared deflection {mean_sin2:.6g} beyond a swing of "
                                  f"{math.degrees(MAX_SWING_RAD):.0f} degrees (the largest this estimator inverts)")
        alpha = brentq(f, beta, hi, xtol=1e-16, rtol=1e-15) if f(beta) < 0.0 else beta
        omega0 = 4.0 * apsidal_angle(alpha, beta)[1] / period_s
        new = min(min_deflection_for_areal_constant(alpha, areal_abs_rad_s / omega0), alpha)
        if abs(new - beta) <= 1e-15 * max(alpha, 1e-300):
            beta = new
            break
        beta = new
    return alpha, beta, omega0


def ellipse_rate_rad_s(mean_sin2, areal_rad_s, period_s) -> float:
    """The apse line's turn relative to k, (apse rate) − k = sgn(c)(Φ − π/2)/T (exact, see
    :func:`~gyro_instrument.instruments.pendulum.apsidal_rate_exact_rad_s`), from the measured
    ⟨sin²θ⟩, area constant c and swing period."""
    if areal_rad_s == 0.0:
        return 0.0
    alpha, beta, omega0 = swing_orbit(mean_sin2, abs(areal_rad_s), period_s)
    if beta == 0.0:
        return 0.0
    phi, w0T = apsidal_angle(alpha, beta)
    return math.copysign((phi - 0.5 * math.pi) * omega0 / w0T, areal_rad_s)


def invert_apse_rate(m_rad_s, mean_H_rad_s, mean_sin2, period_s) -> float:
    """k from the measured apse-line rate m, mean areal velocity ⟨H⟩ = ⟨sin²θ ψ̇⟩ (Earth frame,
    compass), ⟨sin²θ⟩ and the swing period: the root of k + A(⟨H⟩ − k ⟨sin²θ⟩) = m, A the exact
    :func:`ellipse_rate_rad_s` (area constant c = ⟨H⟩ − k ⟨sin²θ⟩ from (27)). Any swing, planar or
    not: nothing assumes a release from rest. Fixed point (A changes by ≈ (3/8)⟨sin²θ⟩ per unit k:
    a contraction), then secant steps."""
    def F(k):
        return k + ellipse_rate_rad_s(mean_sin2, mean_H_rad_s - k * mean_sin2, period_s) - m_rad_s
    k0 = m_rad_s
    k1 = m_rad_s - ellipse_rate_rad_s(mean_sin2, mean_H_rad_s - k0 * mean_sin2, period_s)
    f0, f1 = F(k0), F(k1)
    for _ in range(60):
        if f1 == 0.0 or f1 == f0:
            break
        k0, k1 = k1, k1 - f1 * (k1 - k0) / (f1 - f0)
        f0, f1 = f1, F(k1)
        if abs(k1 - k0) <= 1e-14 * max(abs(k1), abs(m_rad_s), 1e-300):
            break
    return k1


def _clean_deflections(t, theta_e, theta_n):
    """Drop samples with a NaN, sort by time, drop duplicated stamps: (t, east, north, notes)."""
    t = np.asarray(t, dtype=float)
    e = np.asarray(theta_e, dtype=float)
    nn = np.asarray(theta_n, dtype=float)
    ok = np.isfinite(t) & np.isfinite(e) & np.isfinite(nn)
    notes = []
    if not ok.all():
        notes.append(f"{int((~ok).sum())} samples with NaN dropped")
    t, e, nn = t[ok], e[ok], nn[ok]
    order = np.argsort(t, kind="stable")
    t, e, nn = t[order], e[order], nn[order]
    keep = np.concatenate([[True], np.diff(t) > 0]) if t.size else np.array([], bool)
    return t[keep], e[keep], nn[keep], notes


def swing_centre(t, e, nn, period, n_win) -> tuple:
    """The swing's rest point as a line in time (centre and slow drift): each component's mean over
    exactly one period per window (the integral of its piecewise-linear interpolant between the
    window's edges: a swing about its centre averages to zero over a period), then a least-squares
    line through the windows' means. Returns (east centre at each t, north centre at each t, dict of
    the centre at the record's middle and its drift, rad and rad/s)."""
    edges = t[0] + period * np.arange(n_win + 1)
    tc = 0.5 * (edges[:-1] + edges[1:])
    out, info = [], {}
    for key, x in (("east", e), ("north", nn)):
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * np.diff(t))])
        means = np.diff(np.interp(edges, t, cum)) / period
        drift, mid, *_ = slope(tc, means)
        out.append(mid + drift * (t - tc.mean()))
        info[f"{key}_rad"], info[f"drift_{key}_rad_s"] = mid, drift
    info["at_time_s"] = float(tc.mean())
    return out[0], out[1], info


def _centred(t, e, nn, period, n_win):
    """The deflections about the fitted rest point (:func:`swing_centre`): (east, north, rest point)."""
    ce, cn, info = swing_centre(t, e, nn, period, n_win)
    return e - ce, nn - cn, info


def _period_sigma(t, y, fit, scatter) -> float:
    """σ of the full swing period: the sine fit's (white residuals), or with ``scatter`` (the record
    is not white) at least half the difference of its halves' periods (batch means over two batches:
    B. Schmeiser, Oper. Res. 30 (1982) 556–568)."""
    sig = 2.0 * math.pi * fit.omega_sigma_rad_s / fit.omega_rad_s ** 2
    if not scatter:
        return sig
    mid = 0.5 * (t[0] + t[-1])
    try:
        p = [2.0 * math.pi / fit_oscillation(t[s], y[s], omega_guess=fit.omega_rad_s).omega_rad_s
             for s in (t <= mid, t > mid)]
    except EstimationError:
        return sig
    return max(sig, 0.5 * abs(p[1] - p[0]))


def _swing_windows(t, e, nn, period, n_win, areal_rate=None):
    """Per swing period (windows of 8 samples or more): the swing-plane azimuth ψ, the window's
    centre time, the areal velocity H, the mean squared deflection r², the major and minor
    semi-axes of the swing ellipse (second moments) and the sample count (lists). ``areal_rate``:
    :func:`areal_segments` of the record when the caller has it."""
    psi, tc, H, r2, amp, minor, w = [], [], [], [], [], [], []
    # the swept area as a function of time (each interval's at its constant mean rate), so that
    # every window's H is the mean over exactly one period, whatever the sampling
    if areal_rate is None:
        areal_rate = areal_segments(t, e, nn, 2.0 * math.pi / period)
    swept = np.concatenate([[0.0], np.cumsum(areal_rate * np.diff(t))])
    edges = t[0] + period * np.arange(n_win + 1)
    swept_at = np.interp(edges, t, swept)
    idx = np.searchsorted(t, edges)
    for i in range(n_win):
        a, b = idx[i], idx[i + 1]
        if b - a < SWING_WINDOW_MIN_SAMPLES:
            continue
        ee, en = e[a:b], nn[a:b]
        mee, mnn, men = np.mean(ee * ee), np.mean(en * en), np.mean(ee * en)
        psi.append(0.5 * math.atan2(2 * men, mnn - mee))
        tc.append(0.5 * (t[a] + t[b - 1]))
        lam = np.linalg.eigvalsh(np.array([[mee, men], [men, mnn]]))
        amp.append(math.sqrt(2 * max(lam[1], 0.0)))
        minor.append(math.sqrt(2 * max(lam[0], 0.0)))
        H.append(float((swept_at[i + 1] - swept_at[i]) / period))
        r2.append(mee + mnn)
        w.append(b - a)
    return psi, tc, H, r2, amp, minor, w


def _plane_rate(psi, tc):
    """Least-squares rate of the (unwrapped, modulo π) swing-plane azimuth and its standard error."""
    psi = np.unwrap(2.0 * np.asarray(psi)) / 2.0
    tc = np.asarray(tc)
    A = np.vstack([tc - tc.mean(), np.ones_like(tc)]).T
    coef, *_ = np.linalg.lstsq(A, psi, rcond=None)
    m = float(coef[0])
    resid = psi - A @ coef
    s2 = float(resid @ resid) / max(len(psi) - 2, 1)
    return m, math.sqrt(s2 / np.sum((tc - tc.mean()) ** 2))
