"""Foucault precession from sampled bob deflections, corrected for the ellipse (Airy) precession.

Inputs are the bob's horizontal deflection components θ_e = x/l, θ_n = y/l (rad), as a sensor
measures them. Method:

1. the swing period from a sine fit of the dominant component;
2. one window per period: the second moments of (θ_e, θ_n) give the swing-plane azimuth ψ_i
   (compass, modulo π) and the shoelace sum gives the mean areal velocity
   H = ⟨θ_n θ̇_e − θ_e θ̇_n⟩ = ⟨sin²θ ψ̇⟩ (Quet sec. 2 eq. 27's left-hand side, Earth frame);
3. a least-squares line through ψ_i gives the measured rate m;
4. the ellipse precession (3/8) ω0 α β (Airy; Quet sec. 2 §III–IV) uses the areal constant of
   the comparison pendulum H_c = α β ω0 = ⟨H⟩ − k ⟨θ²⟩ (eq. 27: sin²θ (ψ̇ − k) is conserved), so
   m = k + (3/8)(⟨H⟩ − k ⟨θ²⟩) and

       k = (m − (3/8) ⟨H⟩) / (1 − (3/8) ⟨θ²⟩).

   Released from rest this removes exactly Quet's (3/8) θ0 sin θ0 cos(θ0/2) lag (to O(θ0⁴)).

The horizontal Earth-rate component n cos γ leaves a swing-direction-dependent residual of
~2e-5 k for north–south swings (the k' = n cos γ terms of Quet sec. 2 eq. 21), not corrected
here; it is far below the noise of any record shorter than days.

Cramér–Rao bound for the rate of a plane swinging with amplitude α (rad) in white noise σ on each
component, N samples over T_obs: var(k̂) ≥ 24 σ² / (α² N T_obs²) (the information
Σ (α cos ω0 t · t)² / σ² with the phase origin free).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, fit_oscillation


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


def estimate_foucault(t, theta_e, theta_n, correct_ellipse=True) -> FoucaultEstimate:
    """Estimate the Foucault rate from deflection samples; see module docstring.

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
    snr = fit.amplitude ** 2 * fit.n_samples / (4 * max(fit.residual_rms, 1e-300) ** 2)
    if snr < DETECTION_SNR:
        raise EstimationError(f"no swing detected (SNR {snr:.3g} < {DETECTION_SNR:g}): a bob at rest has no "
                              f"swing plane, so no Foucault rate")
    period = 2 * math.pi / fit.omega_rad_s
    n_win = int((t[-1] - t[0]) // period)
    if n_win < 3:
        raise EstimationError(f"record holds {n_win} swing periods; need at least 3 to fit a precession")
    psi, tc, H, r2, amp, minor, w = _swing_windows(t, e, nn, period, n_win)
    if len(psi) < 3:
        raise EstimationError("fewer than 3 complete swing periods with samples")
    m, sig_m = _plane_rate(psi, tc)
    Hm = float(np.average(H, weights=w))
    H_se = float(np.std(H, ddof=1) / math.sqrt(len(H))) if len(H) > 1 else 0.0
    r2m = float(np.average(r2, weights=w))
    alpha = float(np.mean(amp))
    if correct_ellipse:
        k = (m - 0.375 * Hm) / (1.0 - 0.375 * r2m)
        sig_k = math.hypot(sig_m, 0.375 * H_se) / (1.0 - 0.375 * r2m)
    else:
        k, sig_k = m, sig_m
    sigma_noise = fit.residual_rms
    span = float(t[-1] - t[0])
    crlb = math.sqrt(24.0 * sigma_noise ** 2 / (alpha ** 2 * t.size * span ** 2)) if alpha > 0 else math.inf
    return FoucaultEstimate(k, sig_k, m, m - k, alpha, float(np.median(minor)), period, len(psi), crlb, span, notes)


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


def _swing_windows(t, e, nn, period, n_win):
    """Per swing period (windows of 8 samples or more): the swing-plane azimuth ψ, the window's
    centre time, the areal velocity H, the mean squared deflection r², the major and minor
    semi-axes of the swing ellipse (second moments) and the sample count (lists)."""
    psi, tc, H, r2, amp, minor, w = [], [], [], [], [], [], []
    edges = t[0] + period * np.arange(n_win + 1)
    idx = np.searchsorted(t, edges)
    for i in range(n_win):
        a, b = idx[i], idx[i + 1]
        if b - a < 8:
            continue
        ee, en = e[a:b], nn[a:b]
        mee, mnn, men = np.mean(ee * ee), np.mean(en * en), np.mean(ee * en)
        psi.append(0.5 * math.atan2(2 * men, mnn - mee))
        tc.append(0.5 * (t[a] + t[b - 1]))
        lam = np.linalg.eigvalsh(np.array([[mee, men], [men, mnn]]))
        amp.append(math.sqrt(2 * max(lam[1], 0.0)))
        minor.append(math.sqrt(2 * max(lam[0], 0.0)))
        H.append(np.sum(en[:-1] * np.diff(ee) - ee[:-1] * np.diff(en)) / (t[b - 1] - t[a]))
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
