"""The transit (timing) method: the centre from the times the swing spends either side of a mark.

Part of :mod:`gyro_instrument.estimators.north` (its docstring states the sign convention and
the sources).
"""

import math
from dataclasses import field

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north.base import NorthEstimate, level_sides, sign_runs, local_poly, poly_root, poly_derivative_row, reversal_points, finite_samples


# ----------------------------------------------------------------------------- transit (timing) method
def transit_offset(dt_s, period_s, amplitude_rad) -> float:
    """Offset x0 = c − mark of the swing centre from a reference mark, by the transit method (rad).

    For u = c + A cos θ the swing is beyond the mark (u > mark) while cos θ > −x0/A, i.e. for
    |θ| < π/2 + arcsin(x0/A): a time t₊ = (T/π)(π/2 + arcsin(x0/A)) of each full period T, and
    t₋ = T − t₊ on the other side. With Δt = t₊ − t₋ (time on the + side less time on the − side,
    both within one full period): Δt = (2T/π) arcsin(x0/A), hence

        x0 = A sin(π Δt / (2T))   (exact for a sine),   x0 ≈ (π/(2T)) · A · Δt   (small offsets),

    the surveyors' N = N' + c·a·Δt with c = π/(2T) (derived here from the sine; in the field c is
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
    runs = sign_runs(level_sides(u, mark_rad, band_rad))
    h = window_fraction * 2.0 * half_period_s
    times, sig, side = [], [], []
    for (a, b, s0), (a1, b1, s1) in zip(runs[:-1], runs[1:]):
        seg = np.nonzero(s0 * (u[a:a1] - mark_rad) > 0)[0]     # the last sample still on the old side
        k = a + int(seg[-1]) if seg.size else a1
        fit = local_poly(t, u - mark_rad, t[k], h, degree)
        x = None if fit is None else poly_root(fit[0], 0.0, 0)
        if x is None:
            continue
        coef, C, _, _ = fit
        g0, g1 = poly_derivative_row(x, degree, 0), poly_derivative_row(x, degree, 1)
        times.append(t[k] + x * h)
        sig.append(noise_sigma_rad * math.sqrt(g0 @ C @ g0) * h / abs(g1 @ coef))
        side.append(s1)
    return np.asarray(times), np.asarray(sig), np.asarray(side)


def transit_method(t, u, mark_rad, noise_sigma_rad=None, rp=None) -> NorthEstimate:
    """Swing centre from the timed transits of a reference mark (the transit or timing method).

    Each run of three consecutive transits t1 < t2 < t3 spans one full period T = t3 − t1; the
    time on the + side less that on the − side is Δt = ±((t2 − t1) − (t3 − t2)); the amplitude A is
    half the difference of the two reversal points between t1 and t3; then c = mark +
    A sin(πΔt/(2T)) (:func:`transit_offset`). The centre is the mean over all runs of three; σ is
    propagated from the transit times' σ (linearised; the amplitude's σ enters multiplied by x0/A
    and is left out). Needs a mark inside the swing (|c − mark| < A) and ≥ 3 transits. ``rp``: the
    record's :func:`reversal_points` when the caller has them.
    """
    t, u = finite_samples(t, u)
    rp = reversal_points(t, u, noise_sigma_rad) if rp is None else rp
    amp = 0.5 * np.abs(np.diff(rp.readings_rad))
    band = 0.2 * float(np.min(amp))
    tt, ts, side = transit_times(t, u, mark_rad, rp.noise_sigma_rad, rp.half_period_s, band)
    if tt.size < 3:
        raise SceneError("mark_rad", mark_rad, f"must lie inside the swing (between the reversal points "
                         f"{rp.readings_rad.min():.6g} and {rp.readings_rad.max():.6g} rad) and be crossed "
                         f"≥ 3 times; {tt.size} transits found")
    # g: the gradient of the mean centre with respect to the transit times, accumulated run by run
    # (one vector of the transits' size, not one per run: a 48 h record has thousands of runs)
    cs, g = [], np.zeros(tt.size)
    lo = np.searchsorted(rp.times_s, tt, side="right")      # first reversal point after each transit
    hi = np.searchsorted(rp.times_s, tt, side="left")       # first reversal point at or after it
    for k in range(tt.size - 2):
        t1, t2, t3 = tt[k:k + 3]
        i, j = lo[k], hi[k + 2]                                # the reversal points inside (t1, t3)
        if j - i != 2:                 # a reversal point cut off by the record's ends: no amplitude
            continue
        A = 0.5 * float(np.ptp(rp.readings_rad[i:j]))
        s, T = side[k], t3 - t1
        dt = s * ((t2 - t1) - (t3 - t2))
        cs.append(mark_rad + transit_offset(dt, T, A))
        k_dt = A * math.cos(math.pi * dt / (2 * T)) * math.pi / (2 * T)      # ∂x0/∂Δt
        k_T = -k_dt * dt / T                                                  # ∂x0/∂T
        g[k:k + 3] += [-s * k_dt - k_T, 2 * s * k_dt, -s * k_dt + k_T]
    if not cs:
        raise SceneError("record", f"{t[-1] - t[0]:.6g} s", "must hold a full period between transits "
                         "with both its reversal points; observe longer")
    g /= len(cs)
    sig = float(math.sqrt(np.sum(g ** 2 * ts ** 2)))
    return NorthEstimate("transit", float(np.mean(cs)), sig, f"propagated from the transit times' σ (noise "
                         f"σ {rp.noise_source})", int(tt.size), "≥ 3 transits of a mark inside the swing and "
                         "its amplitude (reversal points)", period_s=float(np.mean(np.diff(tt[::2]))))
