"""The full-record fit at the Cramér–Rao bound, and the torsion tape's correction.

Part of :mod:`gyro_instrument.estimators.north` (its docstring states the sign convention and
the sources).
"""

import math

import numpy as np
from scipy.optimize import least_squares

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.north.base import TWO_PI, NorthEstimate, reversal_points, finite_samples
from gyro_instrument.estimators.north.means import schuler_mean


# ----------------------------------------------------------------------------- the full-record fit
def fit_jacobian(tau, p, damping, drift) -> np.ndarray:
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


def fit_model(tau, p, damping, drift) -> np.ndarray:
    """u(τ) = c + d τ + e^(−δτ)(a cos ωτ + b sin ωτ) (rad) at ``tau`` (s from the record's centre) for p = (c, a, b, ω[, δ][, d])."""
    c, a, b, w = p[:4]
    dl = p[4] if damping else 0.0
    return c + (p[-1] * tau if drift else 0.0) + np.exp(-dl * tau) * (a * np.cos(w * tau) + b * np.sin(w * tau))


def _fit_start(tau, u, rp, damping, drift):
    """Starting parameters: ω from the reversal-point spacing, δ from the decay of their deviations,
    then c, a, b (and d) by linear least squares."""
    w = math.pi / rp.half_period_s
    a = rp.readings_rad
    centre = schuler_mean(a).centre_rad if a.size >= 3 else float(np.mean(a))   # two points: their mean
    dl = float(-np.polyfit(rp.times_s, np.log(np.abs(a - centre)), 1)[0]) if damping and a.size >= 3 else 0.0
    E = np.exp(-dl * tau)
    cols = [np.ones_like(tau), E * np.cos(w * tau), E * np.sin(w * tau)] + ([tau] if drift else [])
    lin, *_ = np.linalg.lstsq(np.column_stack(cols), u, rcond=None)
    return np.array(list(lin[:3]) + [w] + ([dl] if damping else []) + ([lin[3]] if drift else []))


def sine_fit(t, u, noise_sigma_rad=None, damping=True, drift=False, t_ref_s=None) -> tuple:
    """(scipy OptimizeResult, t_ref) of the damped-sine least squares of :func:`fit_record`; the
    parameters ``x`` are (c, a, b, ω[, δ][, d]) of u = c + d τ + e^(−δτ)(a cos ωτ + b sin ωτ)."""
    rp = reversal_points(t, u, noise_sigma_rad)
    t_ref = float(np.mean(t)) if t_ref_s is None else float(t_ref_s)
    tau = t - t_ref
    p0 = _fit_start(tau, u, rp, damping, drift)
    sol = least_squares(lambda p: fit_model(tau, p, damping, drift) - u, p0,
                        jac=lambda p: fit_jacobian(tau, p, damping, drift), method="lm", xtol=1e-14)
    return sol, t_ref


def fit_record(t, u, noise_sigma_rad=None, damping=True, drift=False, t_ref_s=None) -> NorthEstimate:
    """Swing centre by nonlinear least squares of the whole record (at the Cramér–Rao bound).

    Model u(t) = c + d·τ + A e^(−δτ) cos(ωτ + φ), τ = t − t_ref (t_ref the mean sample time unless
    given; with ``drift`` the centre is reported at t_ref), written linearly in a = A cos φ,
    b = −A sin φ. Least squares is the maximum-likelihood estimate in white Gaussian noise, so its
    covariance σ² (JᵀJ)⁻¹ is the inverse Fisher information: σ(c) is the Cramér–Rao bound at the
    estimate (:func:`crlb_centre`; ≈ σ/√N for a long record). σ: the given sensor σ, else the
    residual rms with N − p degrees of freedom.
    """
    t, u = finite_samples(t, u)
    sol, t_ref = sine_fit(t, u, noise_sigma_rad, damping, drift, t_ref_s)
    J = fit_jacobian(t - t_ref, sol.x, damping, drift)
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
    J = fit_jacobian(tau, np.array([0.0, a, b, omega_rad_s, damping_per_s] + ([0.0] if drift else [])), True, drift)
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
    ω_on² = (D_K + D_B)/J (D_K = C ρ0 n cos γ, Quet sec. 4 §1 eq. 8 times A; the tape derived here). Hence
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


def undamped_omega(omega_rad_s, damping_per_s=0.0, omega_sigma=0.0, damping_sigma=0.0) -> tuple:
    """The undamped angular frequency of a damped swing, (ω_u, σ): ω_u² = ω_d² + δ² (rad/s).

    A damped oscillator ü + 2δu̇ + ω_u² u = 0 swings at ω_d = √(ω_u² − δ²) with amplitude ∝ e^(−δt).
    The tape relation needs the stiffnesses ω_u² (:func:`tape_ratio`: T_on²/(T_off² − T_on²) from
    *damped* periods carries −δ²/(D_K/A), as ω_d² = ω_u² − δ² above shows: derived here).
    """
    w, d = float(omega_rad_s), float(damping_per_s)
    wu = math.sqrt(w * w + d * d)
    return wu, float(math.hypot(w * omega_sigma, d * damping_sigma) / wu)


def tape_north(centre_rad, tape_zero_rad, ratio) -> float:
    """The north reading N from the swing's equilibrium c under tape torsion, exact (rad).

    The horizontal gyroscope's restoring torque is D_K sin(u − N) + D_B (u − Z) (Quet 1853 sec. 4 §1
    eq. 2 with the sine law, times A, plus the tape; the rest derived here). At the
    equilibrium c: D_K sin(c − N) = D_B (Z − c). Linearised about c the rotor-on swing has
    ω_on² = (D_K cos(c − N) + D_B)/A and the rotor-off swing ω_off² = D_B/A, so the measured ratio
    x = ω_off²/(ω_on² − ω_off²) = T_on²/(T_off² − T_on²) (:func:`tape_ratio`, undamped small-swing
    periods) is D_B/(D_K cos(c − N)), and dividing the two: tan(c − N) = x (Z − c), hence
    N = c − atan(x (Z − c)). Near north this is the linear law N = c + x (c − Z); a scale some
    degrees from north needs the arctangent (the linear law errs by x³(Z − c)³/3).
    """
    return float(centre_rad - math.atan(float(ratio) * (tape_zero_rad - centre_rad)))


def tape_corrected(estimate, tape_zero_rad, ratio, ratio_sigma=0.0, tape_zero_sigma_rad=0.0) -> NorthEstimate:
    """The north reading from a swing centre under tape torsion (:func:`tape_north`, exact):
    N = c − atan(x (Z − c)), x = D_B/(D_K cos(c − N)) from the undamped periods.

    σ² = (∂N/∂c)² σ_c² + (∂N/∂Z)² σ_Z² + (∂N/∂x)² σ_x², the three independent (Z from the rotor-off
    swing, x from the two periods, c from the rotor-on swing), with g = 1/(1 + x²(Z − c)²):
    ∂N/∂c = 1 + x g, ∂N/∂Z = −x g, ∂N/∂x = −(Z − c) g. ``estimate``: a :class:`NorthEstimate` of
    the rotor-on centre.
    """
    c, r = estimate.centre_rad, float(ratio)
    if not (r >= 0 and math.isfinite(r)):
        raise SceneError("tape_ratio", ratio, "D_B/D_K must be finite and ≥ 0")
    north = tape_north(c, tape_zero_rad, r)
    g = 1.0 / (1.0 + (r * (tape_zero_rad - c)) ** 2)
    sig = None if estimate.sigma_rad is None else float(math.sqrt(
        ((1 + r * g) * estimate.sigma_rad) ** 2 + (r * g * tape_zero_sigma_rad) ** 2
        + ((c - tape_zero_rad) * g * ratio_sigma) ** 2))
    return NorthEstimate(estimate.method + "+tape", float(north), sig,
                         estimate.sigma_source + "; with the tape zero's and the ratio's σ", estimate.n_used,
                         estimate.needs + "; a rotor-off swing (tape zero and period)",
                         estimate.notes + (f"tape: D_B/D_K = {r:.6g}, zero {tape_zero_rad:.9g} rad "
                                           "(exact relation N = c - atan(x (Z - c)))",),
                         estimate.period_s, estimate.period_sigma_s, None)
