"""The marine gyrocompass's closed forms: tuning, period, settle points (issue 39 item 1).

The linearised equations of :mod:`.dynamics` for a compass at rest on a pier (α the north end's
azimuth east of true north, θ its tilt, north end up, both small; Ω the Earth rate, φ the latitude;
P_c/H the control torque per unit tilt over the rotor's angular momentum)::

    dα/dt = Ω sin φ − (P_c/H + Ω cos φ) θ            (drift; control torque)
    dθ/dt = Ω cos φ · α − (P_d/H) θ                   (tilting; damping in tilt, Sperry)

(derived here from H ds/dt = τ⊥ − H (Ω + ρ) × s, :mod:`.dynamics`; the structure of the pendulous
and damped models in Christou, *Evaluation of mathematical models for gyrocompass behaviour*, UNB
Tech. Rep. 100, 1983, §4.2; the term Ω cos φ θ is the one the usual form drops: its relative size
Ω cos φ H/P_c is Ω² cos² φ R/g ≈ 3.5e-3). Hence:

- the undamped period T(φ) = 2π / √((P_c/H + Ω cos φ) Ω cos φ): :func:`undamped_period_s`; the
  common form 2π √(H/(P_c Ω cos φ)) is its first order in Ω cos φ H/P_c (derived here, from the
  equation above); T ∝ 1/√(cos φ): longer toward the poles, ≈ 84.4 min √(cos φ_d/cos φ);
- Schuler tuning: a north–south speed change ΔV_N deflects the axis by −(P_c/(g H)) ΔV_N (the
  ballistic deflection) while the settle point moves by −ΔV_N/(R Ω cos φ) (the speed error's change);
  they are equal, and the change dead-beat, when P_c/H = g/(R Ω cos φ_d) at the design latitude
  φ_d (Chalmers, *The gyroscopic compass*, ch. X "The ballistic deflection": classically 40°), where
  T = 2π/√(g/R + Ω² cos² φ_d), shorter than 2π √(R/g) = 84.4 min by Ω² cos² φ_d R/(2g)
  (1.0e-3, 5.6 s at 40°): :func:`control_ratio_per_s`;
- damping in tilt settles east of north (north latitudes) by sin δ_d = (P_d/P_c) tan φ, P_d/P_c =
  1/40 on a Sperry compass ("Gyro Numerical Solved", scribd 598664583; sailorsknowit.com "damping in
  tilt, damping in azimuth"): :func:`damping_error_rad`; damping in azimuth (Anschütz) leaves none;
- on a ship of velocity (V_E, V_N), the frame turns at Ω + ρ, ρ = (−V_N, V_E, V_E tan φ)/R: the
  tilting equation settles when the axis lies in the plane of the vertical and the horizontal part of
  Ω + ρ, tan δ = −V_N / (R Ω cos φ + V_E): the north end west of north when steaming north, the
  compass reading high. δ = atan(V cos C / (R Ω cos φ + V sin C)) is the form the equations give
  exactly (for damping in azimuth; with damping in tilt its latitude error adds): :func:`speed_error_rad`.
  Teaching uses δ ≈ V cos C / (R Ω cos φ) (R Ω ≈ 900 kn); manufacturers' tables follow sin δ = V cos C /
  (R Ω cos φ) (C. Plath/Sperry *NAVIGAT X MK 1 Mod 10* manual, p. A-07, speed-error table;
  manualshive.com/en/manual/c-plath/navigat-x-mk-1-mod-10/3123976?page=73).

All functions take SI units and radians.
"""

import math

import numpy as np

from gyro_instrument.core.motion import EARTH_RADIUS_M


def control_ratio_per_s(gravity_m_s2, earth_rate_rad_s, design_latitude_rad, factor=1.0) -> float:
    """P_c/H (1/s) of a compass Schuler-tuned at ``design_latitude_rad``: ``factor`` · g / (R Ω cos φ_d)
    (factor 1: tuned; Chalmers ch. X)."""
    return factor * gravity_m_s2 / (EARTH_RADIUS_M * earth_rate_rad_s * math.cos(design_latitude_rad))


def undamped_period_s(control_per_s, earth_rate_rad_s, latitude_rad) -> float:
    """T = 2π / √((P_c/H + Ω cos φ) Ω cos φ), s (module docstring); inf at a pole or without Earth rate."""
    h = earth_rate_rad_s * math.cos(latitude_rad)
    k = (control_per_s + h) * h
    return 2.0 * math.pi / math.sqrt(k) if k > 0 else math.inf


def schuler_period_s(gravity_m_s2) -> float:
    """2π √(R/g), s: 84.4 min (5064 s at g = 9.806 m/s²)."""
    return 2.0 * math.pi * math.sqrt(EARTH_RADIUS_M / gravity_m_s2)


def damping_error_rad(damping_ratio, latitude_rad) -> float:
    """δ_d = asin((P_d/P_c) tan φ), rad: the settle point of damping in tilt, east of north for φ > 0."""
    x = damping_ratio * math.tan(latitude_rad)
    return math.asin(max(-1.0, min(1.0, x)))


def speed_error_rad(v_east_m_s, v_north_m_s, earth_rate_rad_s, latitude_rad) -> "float | np.ndarray":
    """The north end's settled azimuth on a moving ship, rad (negative: west of north):
    atan2(−V_N, R Ω cos φ + V_E) (module docstring). Works on floats or arrays."""
    import numpy as np
    return np.arctan2(-np.asarray(v_north_m_s), EARTH_RADIUS_M * earth_rate_rad_s * np.cos(latitude_rad)
                      + np.asarray(v_east_m_s))


def speed_correction_rad(reading_rad, speed_m_s, earth_rate_rad_s, latitude_rad) -> "float | np.ndarray":
    """The speed correction from the compass's own uncorrected reading G, rad (added to the reading):
    −asin(V cos G / (R Ω cos φ)). Exactly the settle point of :func:`speed_error_rad`: with C the
    course and δ that settle point, G = C − δ, and the law of sines in the triangle of the horizontal
    Earth rate R Ω cos φ and the ship's velocity V gives sin(−δ) = V cos G / (R Ω cos φ) (the form of
    the NAVIGAT X MK 1 manual's table, p. A-07; docs/marine_checks.md). No iteration: a fixed point in
    the corrected heading converges slowly near the poles (0.9° off at 81°, 50 kn after 3 steps).
    Clipped to ±90° where V cos G exceeds R Ω cos φ (no settle point). Works on floats or arrays."""
    import numpy as np
    ratio = np.asarray(speed_m_s) * np.cos(reading_rad) / (EARTH_RADIUS_M * earth_rate_rad_s * np.cos(latitude_rad))
    return -np.arcsin(np.clip(ratio, -1.0, 1.0))


def settled_tilt_rad(control_per_s, earth_rate_rad_s, latitude_rad) -> float:
    """The settled tilt of the north end, θ = Ω sin φ / (P_c/H + Ω cos φ), rad (up in north
    latitudes): the tilt at which the control torque's precession follows the vertical component
    of the Earth rate (the drift)."""
    return earth_rate_rad_s * math.sin(latitude_rad) / (control_per_s + earth_rate_rad_s * math.cos(latitude_rad))


def damping_ratio_tilt(damping_ratio, control_per_s, earth_rate_rad_s, latitude_rad) -> float:
    """ζ of damping in tilt: the characteristic equation s² + (P_d/H) s + (P_c/H + Ω cos φ) Ω cos φ = 0
    gives ζ = (P_d/H) / (2 ω0)."""
    w0 = 2.0 * math.pi / undamped_period_s(control_per_s, earth_rate_rad_s, latitude_rad)
    return damping_ratio * control_per_s / (2.0 * w0)


def follow_up_lag_rad(pieces, t_s, bandwidth_rad_s) -> np.ndarray:
    """The lag e_f of a first-order follow-up behind the ship's heading at the sorted times ``t_s``, rad
    (positive behind a turn to starboard): de_f/dt = r − ω_b e_f with the turn rate r constant over
    each of the schedule's ``pieces`` (:class:`~gyro_instrument.core.motion.Piece`), e_f = 0 at the first
    piece's start; within a piece e_f = r/ω_b + (e_0 − r/ω_b) exp(−ω_b (t − t_0)) (exact). A steady turn
    lags by r/ω_b (ISO 22090-1 §3.9's follow-up error, §5.3.4 its limits)."""
    t = np.asarray(t_s, dtype=float)
    out = np.zeros_like(t)
    e0, w = 0.0, float(bandwidth_rad_s)
    for p in pieces:
        if not t.size or p.t0 > t[-1]:
            break
        m = (t >= p.t0) & (t < p.t1)
        steady = p.r / w
        out[m] = steady + (e0 - steady) * np.exp(-w * (t[m] - p.t0))
        if math.isfinite(p.t1):
            e0 = steady + (e0 - steady) * math.exp(-w * (p.t1 - p.t0))
    return out
