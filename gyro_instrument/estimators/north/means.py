"""The Schuler mean and Lavrov's damped-oscillation method over reversal points.

Part of :mod:`gyro_instrument.estimators.north` (its docstring states the sign convention and
the sources).
"""

import math
from dataclasses import field

import numpy as np
from scipy.optimize import least_squares

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north.base import NorthEstimate, reversal_points


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


def scatter_sigma(a) -> tuple:
    """(σ, dof): the reading σ from the scatter of the triple means m_j = (a_j + 2a_(j+1) + a_(j+2))/4 about their
    mean, (ν − 3 dof; None for ν < 4): each m_j estimates the centre (a linear decay cancels in each),
    so with independent readings of σ_a, E Σ(m_j − m̄)² = σ_a² tr(Bᵀ P B) (B the triple matrix, P the
    centring); hence σ̂_a² = Σ(m_j − m̄)² / tr(BᵀPB). Exponential damping leaves the m_j alternating by
    d_j (1 − q)²/4 (second order), which this σ then includes."""
    nu = a.size
    if nu < 4:
        return None, 0
    k = nu - 2
    # B a and tr(BᵀPB) without forming B (k × ν) or BᵀPB (ν × ν), O(ν²) memory: a day of a fast swing
    # has ~10⁴ reversal points. Each row of B has squared norm 3/8, and with P = I − 11ᵀ/k,
    # tr(BᵀPB) = tr(BBᵀ) − |Bᵀ1|²/k, Bᵀ1 the column sums of B.
    m = 0.25 * a[:-2] + 0.5 * a[1:-1] + 0.25 * a[2:]
    r = m - m.mean()
    cols = np.convolve(np.ones(k), [0.25, 0.5, 0.25])
    trace = 0.375 * k - float(cols @ cols) / k
    return math.sqrt(float(r @ r) / trace), nu - 3


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
    book), from the scatter of the triple means (:func:`scatter_sigma`, ν − 3 dof, ν ≥ 4).
    Unbiased for a linear amplitude decay; second-order bias under exponential damping
    (:func:`schuler_bias`).
    """
    a, s = _readings(readings, sigmas, 3, "the Schuler mean")
    w = schuler_weights(a.size)
    centre = float(w @ a)
    if s is not None:
        sig, src = float(math.sqrt(np.sum(w ** 2 * s ** 2))), "propagated from the reading σ's"
    else:
        sr, dof = scatter_sigma(a)
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


def geometric_sequence(params, i) -> np.ndarray:
    """Lavrov's reversal points a_i = c + d (−q)^i at the points' numbers ``i`` (rad), params (c, d, q)."""
    c, d, q = params
    return c + d * (-q) ** i


def geometric_sequence_jac(params, i) -> np.ndarray:
    """Columns ∂a_i/∂(c, d, q) of :func:`geometric_sequence`."""
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
    sol = least_squares(lambda p: wt * (geometric_sequence(p, i) - a), [c0, d0, q0],
                        jac=lambda p: wt[:, None] * geometric_sequence_jac(p, i), method="lm", xtol=1e-15, ftol=1e-15)
    J = wt[:, None] * geometric_sequence_jac(sol.x, i)
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
