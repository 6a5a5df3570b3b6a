"""Foucault (spherical) pendulum and compound pendulum on the rotating Earth.

Quet 1853 sec. 2. The bob, at r (ENU, from the suspension point; |r| = l), obeys eq. (21)
in vector form::

    r̈ = g + [−2 Ω × ṙ]_(earth_rotation) + [−Ω × (Ω × (r − r_rest))]_(centrifugal)
        + [drag]_(air_drag) − λ r

with g = (0, 0, −g) the plumb-line gravity at the rest point r_rest = (0, 0, −l) (it holds the
centrifugal part there, sec. 2 §I) and the tension λ r from the constraint (23), |r| = l:
λ = (ṙ·ṙ + r·F + 2a r·ṙ + b² C)/|r|², C = (|r|² − l²)/2, where the Baumgarte terms (a, b of the
order of √(g/l)) damp any numerical drift of the constraint and vanish on the exact solution.
Cartesian coordinates have no singularity, so any launch and any amplitude up to the inverted
position is allowed. Without ``finite_amplitude`` the linear (small-angle) model is
integrated: the horizontal motion ẍ = −(g/l) x + Coriolis ..., whose exact solution is Binet's
ellipse turning at −k (:func:`binet_ellipse`).

Predictions (sec. 2): the swing plane turns at k = n sin γ, clockwise seen from above in the
north (compass azimuth increasing); the quarter period (42) — exact form
:func:`quarter_period_s`; released from rest at θ0, the minimum deflection β = √(l/g) k sin θ0
cos(θ0/2) (§II) and the apsides turn at k (1 − (3/8) θ0 sin θ0 cos(θ0/2)) (§III), a series;
the exact rate (any amplitude) is :func:`apsidal_rate_exact_rad_s` (elliptic integral of the third kind).

The compound pendulum (sec. 3 §VI) is a body of revolution hung from a point of its axis, CM
at distance l, moments A (about the pivot, transverse) and C (axial): it moves like a simple
pendulum of length λ = A / (M l) when μ = C/A is small and ρ0 ≈ 0 (eq. 57).
"""

import math
import time
from collections.abc import Callable, Iterator

import numpy as np
from scipy.special import elliprf, elliprj, ellipk

from gyro_instrument.core.angles import Unwrapper
from gyro_instrument.core.effect import DAMPING, POINT_MASS, RIGID_BODY, RESTORING_LAW, SPIN, Scales
from gyro_instrument.core.integrate import Trajectory, integration
from gyro_instrument.core.parareal import dense_output, hermite_rows
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import (Column, ExpectedSwing, Instrument, Simulation, check_period_count,
                                              run_span, with_notes)
from gyro_instrument.instruments.chain import HingeChain, Link

PENDULUM_COLUMNS = (
    Column("deflection", "rad", "θ: angle of the bob from the downward vertical"),
    Column("azimuth", "rad", "ψ: compass azimuth of the bob's horizontal position (0 north, clockwise), unwrapped"),
    Column("swing_azimuth", "rad", "instantaneous swing-plane azimuth (compass, modulo π, unwrapped) from the "
                                   "Fradkin tensor ω0² r rᵀ + v vᵀ of the horizontal motion"),
    Column("x_east", "m", "bob east of the suspension point"),
    Column("y_north", "m", "bob north of the suspension point"),
    Column("z_up", "m", "bob height relative to the suspension point (negative below)"),
)


#: What a pendulum's sensor reads and publishes (``Instrument.MEASURED_CHANNELS``, ``JOINTS``).
PENDULUM_MEASURED = ("deflection_east", "deflection_north")
PENDULUM_JOINTS = PENDULUM_MEASURED + ("deflection", "azimuth")


#: Fewest samples in one swing period for the Foucault estimator's second moments of the deflections
#: over that period (estimators/foucault.py): fewer leave windows it cannot use.
SWING_WINDOW_MIN_SAMPLES = 8

#: What a pendulum's observation needs of the sampling (:class:`ExpectedSwing`'s last two fields).
WINDOW_SAMPLING = (float(SWING_WINDOW_MIN_SAMPLES),
                   "the swing plane is measured from second moments of the deflections over each swing "
                   "period, which needs that many samples in it")


def quarter_period_s(length_m, gravity_m_s2, alpha_rad, beta_rad=0.0) -> float:
    """Exact time from maximum deflection α to minimum deflection β of a spherical pendulum.

    Quet's eq. (42) gives the series (π/2)√(l/g)(1 + (α² + β²)/16); the exact value, from the
    energy and area integrals (26)–(27) with z = cos θ, is

        T = √(2l/g) K(m) / √(z3 − z1),  m = (z3 − z2)/(z3 − z1),

    z2 = cos α, z3 = cos β, z1 = −(1 + z2 z3)/(z2 + z3) (the third root of the cubic).
    For β = 0 this is √(l/g) K(sin²(α/2)), the plane pendulum. A quarter period (sec. 2 convention).
    """
    z2, z3 = math.cos(alpha_rad), math.cos(beta_rad)
    if abs(z3 - z2) < 1e-15:
        # Conical pendulum: no radial oscillation; return the small-oscillation limit about it.
        z2 = z3 - 1e-15
    z1 = -(1.0 + z2 * z3) / (z2 + z3) if (z2 + z3) != 0.0 else -math.inf
    if not math.isfinite(z1):
        return math.inf
    m = (z3 - z2) / (z3 - z1)
    return math.sqrt(2.0 * length_m / gravity_m_s2) * float(ellipk(m)) / math.sqrt(z3 - z1)


def quarter_period_series_s(length_m, gravity_m_s2, alpha_rad, beta_rad=0.0) -> float:
    """Quet's series (42): T = (π/2) √(l/g) (1 + (α² + β²)/16) (a quarter period)."""
    return 0.5 * math.pi * math.sqrt(length_m / gravity_m_s2) * (1.0 + (alpha_rad ** 2 + beta_rad ** 2) / 16.0)


def apsidal_rate_from_rest_rad_s(k_rad_s, theta0_rad) -> float:
    """Quet's series for the apsides' rate after a release from rest at θ0 (sec. 2 §III, from the
    Ψ of eq. (42) with §II's β): k (1 − (3/8) θ0 sin θ0 cos(θ0/2)), good to O(θ0⁴) k; the paper's
    value, reported beside the exact :func:`apsidal_rate_from_rest_exact_rad_s`."""
    return k_rad_s * (1.0 - 0.375 * theta0_rad * math.sin(theta0_rad) * math.cos(theta0_rad / 2.0))


def _orbit_differences(alpha_rad, beta_rad) -> tuple:
    """Differences of the roots of the spherical pendulum's cubic, free of cancellation.

    With z = cos θ, Quet's energy and area integrals (26)–(27) (non-rotating frame) give
    ż² = 2ω0² (z − z1)(z − z2)(z3 − z) with z2 = cos α, z3 = cos β (α ≥ β the maximum and minimum
    deflections) and z1 = −(1 + z2 z3)/(z2 + z3) (as in :func:`quarter_period_s`). Returns
    (z3 − z2, z2 − z1, 1 − z2, 1 + z2, 1 − z3, z2 + z3), each from half-angle forms so that a
    minimum deflection of 1e-9 rad keeps its digits.
    """
    d32 = 2.0 * math.sin(0.5 * (alpha_rad + beta_rad)) * math.sin(0.5 * (alpha_rad - beta_rad))
    s23 = math.cos(alpha_rad) + math.cos(beta_rad)
    d21 = (s23 * s23 + math.sin(beta_rad) ** 2) / s23
    return (d32, d21, 2.0 * math.sin(0.5 * alpha_rad) ** 2, 2.0 * math.cos(0.5 * alpha_rad) ** 2,
            2.0 * math.sin(0.5 * beta_rad) ** 2, s23)


def apsidal_angle(alpha_rad, beta_rad) -> tuple:
    """Exact azimuth turned by a non-rotating spherical pendulum from a maximum deflection α to the
    next minimum β, and that quarter period in units of 1/ω0 (ω0 = √(g/l)): (Φ, ω0 T).

    From Quet's integrals (26)–(27) with z = cos θ: sin²θ φ̇ = h, h² = 2ω0² sin²α sin²β/(z2 + z3),
    and with z = z2 + (z3 − z2) s² (roots of :func:`_orbit_differences`)::

        ω0 T = √2 K(m)/√(z2 − z1),
        Φ = h/(ω0 √(2(z2 − z1))) [Π(n₊|m)/(1 − z2) + Π(n₋|m)/(1 + z2)],
        m = −(z3 − z2)/(z2 − z1) (≤ 0),  n± = ±(z3 − z2)/(1 ∓ z2),

    Π(n|m) = ∫₀^{π/2} dφ/((1 − n sin²φ)√(1 − m sin²φ)), the complete elliptic integral of the third
    kind (the apsidal angle of the spherical pendulum: Whittaker, *Analytical Dynamics* §48;
    Byrd & Friedman 1971, 233.xx), evaluated in Carlson's symmetric form
    Π(n|m) = R_F(0, 1 − m, 1) + (n/3) R_J(0, 1 − m, 1, 1 − n) (DLMF 19.25.2; ``scipy.special.elliprf``,
    ``elliprj``). Every term is positive, so β → 0 (n₊ → 1, Π → ∞, h → 0) loses no digits; Φ → π/2
    there (the plane swing through the vertical), and for small α, β Φ = (π/2)(1 + 3αβ/8): Quet's
    eq. (42). The conical limit α = β gives π/√(1 + 3 cos²α). Φ ≥ 0: the turn is in the sense of h.
    """
    a, b = (float(alpha_rad), float(beta_rad)) if alpha_rad >= beta_rad else (float(beta_rad), float(alpha_rad))
    if not (0.0 <= b and a < math.pi and math.cos(a) + math.cos(b) > 0.0):
        raise ValueError(f"no spherical-pendulum orbit with apsides {alpha_rad!r}, {beta_rad!r} rad "
                         f"(needs cos α + cos β > 0)")
    d32, d21, omz2, opz2, omz3, s23 = _orbit_differences(a, b)
    y = (d21 + d32) / d21                                   # 1 − m
    rf = float(elliprf(0.0, y, 1.0))
    w0T = math.sqrt(2.0 / d21) * rf
    if b == 0.0:
        return 0.5 * math.pi, w0T                           # through the vertical: half a turn per swing
    n_plus, n_minus = d32 / omz2, -d32 / opz2
    pi_plus = rf + n_plus / 3.0 * float(elliprj(0.0, y, 1.0, omz3 / omz2))
    pi_minus = rf + n_minus / 3.0 * float(elliprj(0.0, y, 1.0, (2.0 - omz3) / opz2))
    phi = math.sin(a) * math.sin(b) / math.sqrt(s23 * d21) * (pi_plus / omz2 + pi_minus / opz2)
    return phi, w0T


def areal_constant_over_omega0(alpha_rad, beta_rad) -> float:
    """|h|/ω0 = sin α sin β √(2/(cos α + cos β)): the area constant of eq. (27) (non-rotating frame,
    sin²θ φ̇ = h) of the orbit with apsides α, β, in units of ω0 = √(g/l)."""
    return math.sin(alpha_rad) * math.sin(beta_rad) * math.sqrt(2.0 / (math.cos(alpha_rad) + math.cos(beta_rad)))


def min_deflection_for_areal_constant(alpha_rad, h_over_omega0) -> float:
    """The minimum deflection β of the orbit with maximum deflection α and area constant |h|/ω0
    (the inverse of :func:`areal_constant_over_omega0`): with q = (h/ω0)²/(2 sin²α), cos β solves
    cos²β + q cos β + q cos α − 1 = 0, so 1 − cos β = 2q(1 + cos α)/(2 + q + √(q² + 4 − 4q cos α))
    (rationalised: no cancellation for small β). Valid while β ≤ α (q ≤ 1 ... the conical orbit)."""
    sa = math.sin(alpha_rad)
    if sa == 0.0:
        return 0.0
    q = h_over_omega0 ** 2 / (2.0 * sa * sa)
    ca = math.cos(alpha_rad)
    one_m = 2.0 * q * (1.0 + ca) / (2.0 + q + math.sqrt(q * q + 4.0 - 4.0 * q * ca))
    return 2.0 * math.asin(min(1.0, math.sqrt(0.5 * one_m)))


def apsidal_rate_exact_rad_s(omega0_rad_s, k_rad_s, alpha_rad, areal_rad_s) -> float:
    """Exact rate of the apse line of a finite-amplitude Foucault pendulum on the rotating Earth, rad/s
    (positive clockwise seen from above, compass azimuth increasing, as k).

    In the frame turning with −k about the vertical (k = n sin γ) the bob is a non-rotating
    spherical pendulum: the Coriolis term of the vertical rate is that frame's, and the model's
    centrifugal term −Ω × (Ω × (r − r_rest)) cancels its centrifugal part exactly. There Quet's area
    integral (27) reads c = sin²θ (ψ̇ − k) = const (ψ compass; c < 0 is counterclockwise) and the
    apsides advance by 2Φ − π per radial period 2T in the sense of the bob's motion
    (:func:`apsidal_angle`), so in the Earth frame::

        ψ̇_apse = k + sgn(c) (Φ(α, β) − π/2)/T,   β from α and |c|/ω0 (:func:`min_deflection_for_areal_constant`).

    For small α, β: k − (3/8) ω0 α β sgn(−c) (Airy; Quet sec. 2 §III–IV from eq. (42)). Released from
    rest at θ0 (Earth frame) c = −k sin²θ0 (:func:`apsidal_rate_from_rest_exact_rad_s`).

    Left out: the horizontal rate k' = n cos γ (the right side of (27), −2k' cos ψ sin²θ dθ), whose
    torque changes sign with the swing: it enters only through the area constant c, which it
    shifts for a release from rest (:func:`release_areal_constant_rad_s`: 3 % of k at 30° on 1 m
    released north) and then moves slowly; given the swing's actual c the formula holds to
    ~1.6e-6 k in the full model at 30° on 1 m (apocentres of 150 swings, any release azimuth),
    to 1e-11 k with the vertical rate alone (tests/test_apsidal_rate.py). The O(n² l/g) terms
    Quet drops from (26)–(27) are not in the model's frame change either.

    Parameters
    ----------
    omega0_rad_s : float
        √(g/l), rad/s.
    k_rad_s : float
        Vertical Earth rate n sin γ, rad/s (signed).
    alpha_rad : float
        Maximum deflection α, rad (in (0, π)).
    areal_rad_s : float
        c = sin²θ (ψ̇ − k), rad/s (signed, compass sense).
    """
    beta = min_deflection_for_areal_constant(alpha_rad, abs(areal_rad_s) / omega0_rad_s)
    phi, w0T = apsidal_angle(alpha_rad, beta)
    return k_rad_s + math.copysign(1.0, areal_rad_s) * (phi - 0.5 * math.pi) * omega0_rad_s / w0T


def release_areal_constant_rad_s(k_rad_s, theta0_rad, k_horizontal_rad_s=0.0, azimuth0_rad=0.0) -> float:
    """The area constant c = sin²θ (ψ̇ − k) (compass sense) of a swing released from rest at θ0 and
    compass azimuth ψ0, at the vertical: −k sin²θ0 from (27) with the vertical rate alone, plus the
    horizontal rate's term k' cos ψ0 (θ0 − sin θ0 cos θ0) that the right side of (27) adds over the
    fall (:func:`min_deflection_with_horizontal_rate_rad`). Beyond the paper (sec. 2 §II–III keep k)."""
    s, c = math.sin(theta0_rad), math.cos(theta0_rad)
    return -k_rad_s * s * s + k_horizontal_rad_s * math.cos(azimuth0_rad) * (theta0_rad - s * c)


def apsidal_rate_from_rest_exact_rad_s(length_m, gravity_m_s2, k_rad_s, theta0_rad, k_horizontal_rad_s=0.0,
                                       azimuth0_rad=0.0) -> float:
    """Exact apse-line rate after a release from rest at θ0 (Earth frame), rad/s, positive clockwise
    from above: :func:`apsidal_rate_exact_rad_s` with the area constant of
    :func:`release_areal_constant_rad_s` (c = −k sin²θ0 with the vertical rate alone). Quet's series
    for it (sec. 2 §III) is :func:`apsidal_rate_from_rest_rad_s`; they agree to O(θ0⁴) k.

    With k' = n cos γ given, the rate is the one at release: the horizontal rate's torque then
    makes the area constant drift slowly as the plane turns (measured at 30° on 1 m: an east
    release's mean rate over 1 h is 2.2e-4 k below this; a north release's rate at release is
    3 % of k above the k'-free value and agrees with this one to 1.6e-6 k)."""
    c = release_areal_constant_rad_s(k_rad_s, theta0_rad, k_horizontal_rad_s, azimuth0_rad)
    if c == 0.0 or math.sin(theta0_rad) == 0.0:
        return k_rad_s
    return apsidal_rate_exact_rad_s(math.sqrt(gravity_m_s2 / length_m), k_rad_s, theta0_rad, c)


def min_deflection_from_rest_rad(length_m, gravity_m_s2, k_rad_s, theta0_rad) -> float:
    """Minimum deflection after a release from rest, β = √(l/g) k sin θ0 cos(θ0/2) (sec. 2 §II)."""
    return math.sqrt(length_m / gravity_m_s2) * k_rad_s * math.sin(theta0_rad) * math.cos(theta0_rad / 2.0)


def min_deflection_with_horizontal_rate_rad(length_m, gravity_m_s2, k_rad_s, k_horizontal_rad_s, theta0_rad,
                                            azimuth0_rad) -> float:
    """Minimum deflection after a release from rest with the horizontal Earth rate too, rad (≥ 0).

    Quet's β (sec. 2 §II, :func:`min_deflection_from_rest_rad`) keeps only the vertical Earth
    rate k. The horizontal part k' = n cos γ (northward, ENU) adds −2k' ż to the eastward
    acceleration, a torque 2k' y ż about the vertical, so the area integral (27) becomes
    h + k ρ_h² − 2k' ∫ y ż dt = const (h = x ẏ − y ẋ, ENU). Along the swing from rest at θ0 and
    compass azimuth ψ0 to the bottom, y = l sin θ cos ψ0 and z = −l cos θ give
    2k' ∫ y ż dt = −k' l² cos ψ0 (θ0 − sin θ0 cos θ0); at the apsis h = l sin β √(2gl(cos β − cos θ0)),
    so to first order in β (~1e-5)::

        β = √(l/g) |k sin²θ0 − k' cos ψ0 (θ0 − sin θ0 cos θ0)| / (2 sin(θ0/2))

    which is Quet's β for an east–west release (cos ψ0 = 0) and differs from it by
    −(k'/k) cos ψ0 (θ0 − sin θ0 cos θ0)/sin²θ0 ≈ −(2/3)(k'/k) θ0 cos ψ0 otherwise (−2.0 % for a
    2° release toward north at Paris, +3.5 % at −33.87°). The half-swings after the first keep the
    same change (the torque's integral returns to it at every passage). The simulated minimum
    agrees to ~1e-6 relative (tests/test_pendulum.py). Valid at the equator (k = 0) too.

    Parameters
    ----------
    length_m, gravity_m_s2 : float
        l (m), g (m/s²).
    k_rad_s, k_horizontal_rad_s : float
        Vertical (n sin γ) and northward horizontal (n cos γ) Earth-rate components, rad/s.
    theta0_rad, azimuth0_rad : float
        Release deflection θ0 in (0, π) and compass azimuth ψ0 (0 north, clockwise), rad.
    """
    s, c = math.sin(theta0_rad), math.cos(theta0_rad)
    area = k_rad_s * s * s - k_horizontal_rad_s * math.cos(azimuth0_rad) * (theta0_rad - s * c)
    return math.sqrt(length_m / gravity_m_s2) * abs(area) / (2.0 * math.sin(theta0_rad / 2.0))


def precession_sense(rate_rad_s) -> str:
    """The sense of a rotation about the upward vertical at ``rate_rad_s`` (positive: clockwise seen
    from above, compass azimuth increasing — the swing plane's sense in the north, Quet sec. 2)."""
    if rate_rad_s > 0.0:
        return "clockwise seen from above"
    if rate_rad_s < 0.0:
        return "counterclockwise seen from above"
    return "none"


def binet_ellipse(t, length_m, gravity_m_s2, k_rad_s, x0, y0, vx0, vy0, velocity=False) -> tuple:
    """Exact solution of the linear model with the vertical Earth-rate component only.

    ẍ = −ω0² x + 2k ẏ, ÿ = −ω0² y − 2k ẋ (ENU, k = n sin γ) has, with z = x + i y,
    z = e^(−ikt) (P e^(iΩt) + Q e^(−iΩt)), Ω = √(ω0² + k²): Binet's ellipse of frequency Ω
    turning at −k (clockwise from above for k > 0). Returns (x, y), or (x, y, ẋ, ẏ) with
    ``velocity``.
    """
    w0sq = gravity_m_s2 / length_m
    W = math.sqrt(w0sq + k_rad_s ** 2)
    z0 = complex(x0, y0)
    zd0 = complex(vx0, vy0)
    # z(0) = P + Q; ż(0) = i(W − k) P − i(W + k) Q
    P = (zd0 + 1j * (W + k_rad_s) * z0) / (2j * W)
    Q = z0 - P
    t = np.asarray(t, dtype=float)
    rot = np.exp(-1j * k_rad_s * t)
    ep, em = np.exp(1j * W * t), np.exp(-1j * W * t)
    z = rot * (P * ep + Q * em)
    if not velocity:
        return z.real, z.imag
    zd = rot * (1j * (W - k_rad_s) * P * ep - 1j * (W + k_rad_s) * Q * em)
    return z.real, z.imag, zd.real, zd.imag


def _effects_with(effect_names, kind) -> list:
    """The registered effects among ``effect_names`` contributing to the mechanics ``kind``."""
    from gyro_instrument.effects import REGISTRY
    return [n for n in effect_names if n in REGISTRY and kind in REGISTRY[n].MECHANICS]


def _not_conservative(effect_names) -> list:
    """The effects among ``effect_names`` (registered names) that do not declare ``conservative``, sorted."""
    from gyro_instrument.effects import REGISTRY
    return sorted(n for n in effect_names if not (n in REGISTRY and REGISTRY[n].is_conservative()))


def pendulum_columns(pos, vel, omega0_sq, unwrappers=None) -> dict:
    """Derived columns from bob positions/velocities (arrays (3, m), ENU).

    ``unwrappers``: a pair of :class:`~gyro_instrument.core.angles.Unwrapper` (azimuth, swing
    azimuth) carried from block to block of a streamed run; fresh ones by default (one block)."""
    unwrap_az, unwrap_swing = unwrappers if unwrappers is not None else (Unwrapper(), Unwrapper())
    x, y, z = pos
    vx, vy = vel[0], vel[1]
    rh = np.hypot(x, y)
    deflection = np.arctan2(rh, -z)
    azimuth = unwrap_az(np.arctan2(x, y))
    # Fradkin tensor in (north, east) axes: its major axis is the swing plane.
    n, e, vn, ve = y, x, vy, vx
    tnn = omega0_sq * n * n + vn * vn
    tee = omega0_sq * e * e + ve * ve
    tne = omega0_sq * n * e + vn * ve
    swing = 0.5 * unwrap_swing(np.arctan2(2.0 * tne, tnn - tee))
    return {"deflection": deflection, "azimuth": azimuth, "swing_azimuth": swing,
            "x_east": x, "y_north": y, "z_up": z}


class SphericalPendulum(Instrument):
    """Foucault pendulum: a point bob on a massless rod, Cartesian rotating-frame model."""

    type_name = "spherical_pendulum"
    summary = "Foucault pendulum, point bob, any launch and amplitude (Quet sec. 2)"
    PARAMS = (
        Param("length_m", default=67.0, low=0.0, high=1.0e4, open_low=True, doc="rod length l, m"),
        Param("initial_deflection_deg", default=2.0, low=0.0, high=180.0, doc="θ0 from the downward vertical"),
        Param("initial_azimuth_deg", default=90.0, low=-360.0, high=360.0,
              doc="compass azimuth of the release point (0 north, 90 east)"),
        Param("radial_speed_m_s", default=0.0, low=-1.0e3, high=1.0e3, doc="launch speed away from the vertical"),
        Param("transverse_speed_m_s", default=0.0, low=-1.0e3, high=1.0e3,
              doc="launch speed perpendicular to the release plane (u0 of sec. 2 §IV), positive clockwise "
                  "seen from above (toward increasing azimuth)"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance (adaptive)"),
        Param("integrator", kind="str", default="auto", choices=("auto", "adaptive", "parareal"),
              doc="auto: parareal whenever the model allows it (finite_amplitude listed, every effect conservative "
                  "as earth_rotation, centrifugal and finite_amplitude are, a release from rest at up to 10 degrees whose "
                  "amplitude is "
                  "above the round-off floor), "
                  "else adaptive ('describe' says which and why); adaptive: DOP853 swing after swing; parareal: "
                  "every swing period of a window at once (fixed-step RK8 batched over periods, Newton-parareal "
                  "from Quet's comparison pendulum), the fast path for long runs of the full model"),
        Param("segment_steps", kind="int", default=48, low=8, high=100000,
              doc="parareal: RK8 steps per swing period"),
        Param("shooting_tol", default=1e-9, low=1e-14, high=1e-3,
              doc="parareal: largest change of a swing's start state (relative to the amplitude) accepted"),
    )
    MECHANICS = frozenset({POINT_MASS, RESTORING_LAW})
    COLUMNS = PENDULUM_COLUMNS
    MEASURED_CHANNELS = PENDULUM_MEASURED
    JOINTS = PENDULUM_JOINTS
    IS_PENDULUM = True
    SIMULATOR_NODE = "pendulum_sim"

    @classmethod
    def check_effects(cls, prefix, p, effects) -> None:
        from gyro_instrument.core.errors import SceneError
        if p["integrator"] == "parareal":
            if not _effects_with(effects, RESTORING_LAW):
                raise SceneError(f"{prefix}.integrator", "parareal", "needs the effect finite_amplitude (the "
                                 "full model); the linear model has Binet's closed form")
            dissipative = _not_conservative(effects)
            if dissipative:
                raise SceneError(f"{prefix}.integrator", "parareal", f"needs a conservative motion: leave out "
                                 f"{', '.join(dissipative)} or use integrator: adaptive")
            if p["initial_deflection_deg"] >= 90.0 or p["initial_deflection_deg"] <= 0.0 \
                    or p["radial_speed_m_s"] != 0.0 or p["transverse_speed_m_s"] != 0.0:
                raise SceneError(f"{prefix}.integrator", "parareal", "needs a release from rest at a deflection "
                                 "in (0, 90) degrees (its period and precession come from that release)")

    #: The parareal fast path needs of the active effects (chosen by ``integrator: auto``, required by
    #: an explicit ``parareal``): a ``restoring_law`` effect (the full Cartesian model, whose right-hand
    #: side :meth:`rhs_exact` sums every active ``point_mass`` term, batched over swings as the hook's
    #: contract says) and every effect ``conservative`` (:data:`~gyro_instrument.core.effect.CONSERVATIVE`:
    #: its Newton iteration starts from the comparison pendulum, a conservative swing, and its period is
    #: that of the first swing). Any effect declaring it keeps the fast path; none is named here.
    #: Largest release deflection (deg) at which ``integrator: auto`` takes parareal at its default
    #: grid: against DOP853 at rtol 1e-12 (5 m, 20 min, full model) the largest position difference
    #: over the amplitude was 3.2e-10, 2.2e-10, 3.2e-10 at 2°, 5°, 10°, under the shooting tolerance
    #: 1e-9, then 1.3e-9 at 20°, 4.7e-9 at 30° and 6.1e-7 at 60° (48 RK8 steps per swing no longer
    #: resolve the large swing's harmonics): beyond 10° auto keeps the adaptive DOP853.
    PARAREAL_AUTO_MAX_DEG = 10.0

    def chosen_integrator(self, duration_s=None) -> tuple:
        """(integrator, reason): ``adaptive`` or ``parareal`` as the scene asks, or for ``auto`` the fast
        path parareal when the full model and a release from rest allow it (the conditions
        :meth:`check_effects` enforces for an explicit parareal: a restoring law and every active effect
        conservative), else adaptive with the reason."""
        if self.p.integrator != "auto":
            return self.p.integrator, "chosen in the scene"
        if self.restoring_law() is None:
            return "adaptive", "auto: the linear (small-angle) model has no parareal path (finite_amplitude not listed)"
        other = _not_conservative(self.effects)
        if other:
            return "adaptive", f"auto: parareal is for a conservative swing; {', '.join(other)} listed"
        if not (0.0 < self.p.initial_deflection_deg < 90.0) or self.p.radial_speed_m_s or self.p.transverse_speed_m_s:
            return "adaptive", "auto: parareal needs a release from rest between 0 and 90 degrees"
        # The bob's height (~l) carries round-off eps·l: relative to the swing amplitude l sin θ0 that is
        # eps / sin θ0, and Newton cannot move the swing starts by less (at θ0 = 1e-9 rad it stalled at
        # 1e-7 > shooting_tol 1e-9). Auto asks for a floor 100 times below the tolerance.
        floor = np.finfo(float).eps / math.sin(self.p.initial_deflection_rad)
        if 100.0 * floor > self.p.shooting_tol:
            return "adaptive", (f"auto: at a release of {self.p.initial_deflection_deg:.3g} deg the round-off of the "
                                f"bob's height is {floor:.1e} of the amplitude, too close to parareal's shooting "
                                f"tolerance {self.p.shooting_tol:g}")
        if self.p.initial_deflection_deg > self.PARAREAL_AUTO_MAX_DEG:
            return "adaptive", (f"auto: a release at {self.p.initial_deflection_deg:g} deg is beyond the "
                                f"{self.PARAREAL_AUTO_MAX_DEG:g} deg where parareal's {self.p.segment_steps}-step grid "
                                f"is validated to its shooting tolerance")
        return "parareal", ("auto: the full conservative model released from rest, the fast path (all swings of "
                            "a window at once; DOP853 with integrator: adaptive)")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)

    def pendulum_length_m(self) -> float:
        """The rod length l, m."""
        return self.p.length_m

    def expected_swing(self) -> "ExpectedSwing":
        """Four exact quarter periods of a plane swing (sec. 2 eq. 42 without its series:
        :func:`quarter_period_s`) and the release deflection θ0 (the Earth's k changes neither
        by more than (k/ω0)², below 1e-8 for any pendulum)."""
        return ExpectedSwing(4.0 * quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, 0.0), abs(self.p.initial_deflection_rad),
                             "length_m, initial_deflection_deg and the site's gravity", *WINDOW_SAMPLING)

    def initial_state(self) -> tuple:
        """Bob position and velocity (ENU) at release; velocity relative to the Earth."""
        st, ct = math.sin(self.p.initial_deflection_rad), math.cos(self.p.initial_deflection_rad)
        sp, cp = math.sin(self.p.initial_azimuth_rad), math.cos(self.p.initial_azimuth_rad)
        r = self.p.length_m * np.array([st * sp, st * cp, -ct])
        e_rad = np.array([ct * sp, ct * cp, st])        # ∂r/∂θ / l
        e_az = np.array([cp, -sp, 0.0])                 # ∂r/∂ψ direction (clockwise from above)
        if st == 0.0:
            e_az = np.array([cp, -sp, 0.0])
        v = self.p.radial_speed_m_s * e_rad + self.p.transverse_speed_m_s * e_az
        return r, v

    def predictions(self) -> dict:
        """Sec. 2 for the model as simulated: k = n sin γ (0 without ``earth_rotation``); with
        ``finite_amplitude`` the exact quarter period (42), β of §II and the exact apse-line rate
        ``apsidal_rate_from_rest_rad_s`` at release (:func:`apsidal_rate_from_rest_exact_rad_s`: the
        elliptic-integral apsidal angle of the spherical pendulum, the horizontal rate's share of the
        area constant included), beside Quet's series ``apsidal_rate_quet_series_rad_s`` of §III,
        k(1 − (3/8) θ0 sin θ0 cos(θ0/2)) (the paper's value; equal to k in the linear model); without it the linear model's Binet ellipse (quarter period π/(2Ω), Ω = √(g/l + k²),
        β = asin(sin θ0 · |k|/Ω), apsides turning at k). ``quarter_period_series_s`` is Quet's
        series (42) in every case.

        Rates (``foucault_rate_*``, ``apsidal_rate_*``) are signed components about the upward
        vertical, positive clockwise seen from above (k > 0 in the north); ``precession_sense`` says
        it in words. Magnitudes (β, periods, ``full_turn_h``) are ≥ 0 at every site.

        Beyond the paper (``finite_amplitude`` and ``earth_rotation``, release from rest):
        ``min_deflection_from_rest_exact_rad`` adds the horizontal Earth rate's term that §II's β
        drops (:func:`min_deflection_with_horizontal_rate_rad`), ``min_deflection_quet_relative_error``
        is β/that − 1 (0 for an east–west release), and ``beyond_the_paper`` (str) says so in words.
        """
        k_site = self.site.k_vertical_rad_s
        rotating = self.has("earth_rotation")
        k = k_site if rotating else 0.0
        if self.has("finite_amplitude"):
            beta = abs(min_deflection_from_rest_rad(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad))
            quarter = quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta)
            k_h = self.site.earth_rate_enu()[1] if rotating else 0.0
            apsidal = apsidal_rate_from_rest_exact_rad_s(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad, k_h, self.p.initial_azimuth_rad)
            series = apsidal_rate_from_rest_rad_s(k, self.p.initial_deflection_rad)
        else:
            W = math.sqrt(self.context.gravity_m_s2 / self.p.length_m + k * k)
            beta = math.asin(min(1.0, math.sin(self.p.initial_deflection_rad) * abs(k) / W))
            quarter = 0.5 * math.pi / W
            apsidal = series = k
        out = {"foucault_rate_rad_s": k,
               "foucault_rate_deg_h": math.degrees(k) * 3600.0,
               "precession_sense": precession_sense(k),
               "full_turn_h": (2 * math.pi / abs(k) / 3600.0) if k else math.inf,
               "quarter_period_s": quarter,
               "quarter_period_series_s": quarter_period_series_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta),
               "min_deflection_from_rest_rad": beta,
               "apsidal_rate_from_rest_rad_s": apsidal,
               "apsidal_rate_quet_series_rad_s": series}
        if self.has("finite_amplitude") and rotating and 0.0 < self.p.initial_deflection_rad < math.pi:
            out.update(self._horizontal_rate_beta(beta))
        return with_notes(out, self.missing_effect_note(
            "earth_rotation", f"the swing plane keeps its azimuth (k = 0; with it k = n sin γ = {k_site:.6g} rad/s "
                              f"= {math.degrees(k_site) * 3600.0:.4g} deg/h)"),
            self.missing_effect_note(
            "finite_amplitude", "small-angle (linear) model: Binet's ellipse, quarter period π/(2√(g/l + k²)), "
                                "apsides turning at k"))

    def _horizontal_rate_beta(self, beta) -> dict:
        """What sec. 2 §II could not include: the horizontal Earth rate's share of the minimum
        deflection (:func:`min_deflection_with_horizontal_rate_rad`), for this release."""
        k_h = self.site.earth_rate_enu()[1]
        exact = min_deflection_with_horizontal_rate_rad(self.p.length_m, self.context.gravity_m_s2, self.site.k_vertical_rad_s, k_h,
                                                        self.p.initial_deflection_rad, self.p.initial_azimuth_rad)
        err = beta / exact - 1.0 if exact > 0.0 else math.inf
        north = min_deflection_with_horizontal_rate_rad(self.p.length_m, self.context.gravity_m_s2, self.site.k_vertical_rad_s, k_h,
                                                        self.p.initial_deflection_rad, 0.0)
        err_north = beta / north - 1.0 if north > 0.0 else math.inf
        from_rest = self.p.radial_speed_m_s == 0.0 and self.p.transverse_speed_m_s == 0.0
        def off(e):
            return "equal to it" if abs(e) < 1e-12 else f"{100.0 * abs(e):.3g} % {'above' if e > 0 else 'below'} it"
        text = (f"sec. 2 §II's minimum deflection β = √(l/g) k sin θ0 cos(θ0/2) keeps only the vertical Earth "
                f"rate; the horizontal rate n cos γ = {k_h:.6g} rad/s acting on the bob's vertical velocity changes "
                f"the area integral by −n cos γ l² cos ψ0 (θ0 − sin θ0 cos θ0): for this release (azimuth "
                f"{math.degrees(self.p.initial_azimuth_rad):g}°) the minimum deflection is {exact:.6g} rad and β = {beta:.6g} rad "
                f"is {off(err)} (for a release toward north here: {off(err_north)})"
                + ("" if from_rest else "; both are for a release from rest, not this launch"))
        return {"min_deflection_from_rest_exact_rad": exact, "min_deflection_quet_relative_error": err,
                "beyond_the_paper": text}

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=None,
                restoring_rate_rad_s=math.sqrt(self.context.gravity_m_s2 / self.p.length_m), amplitude_rad=self.p.initial_deflection_rad,
                duration_s=duration_s)

    def point_mass_terms(self) -> list:
        """The active effects' ``point_mass`` terms f(δr, v) -> a (ENU, rotating frame), summing order."""
        terms = (e.point_mass_term(self.context) for e in self.effects_of(POINT_MASS))
        return [f for f in terms if f is not None]

    def rhs_exact(self) -> Callable:
        """Cartesian constrained right-hand side for y = [r, v] (ENU): gravity, the tension and the
        sum of the active effects' point-mass accelerations at δr = r − r_rest (module docstring).
        Accepts a batch of states (y of shape (6, m)) when every term does."""
        l2 = self.p.length_m * self.p.length_m
        g = self.context.gravity_m_s2
        terms = self.point_mass_terms()
        a_b = 2.0 * math.sqrt(g / self.p.length_m)
        b2 = g / self.p.length_m
        zr = -self.p.length_m

        half_b2 = 0.5 * b2

        def rhs(t, y):
            x, yy, z, vx, vy, vz = y
            fx, fy, fz = 0.0, 0.0, -g
            dz = z - zr
            for term in terms:
                ax, ay, az = term(x, yy, dz, vx, vy, vz)
                fx += ax
                fy += ay
                fz += az
            r2 = x * x + yy * yy + z * z
            rv = x * vx + yy * vy + z * vz
            lam = (vx * vx + vy * vy + vz * vz + x * fx + yy * fy + z * fz + a_b * rv
                   + half_b2 * (r2 - l2)) / r2
            return np.array([vx, vy, vz, fx - lam * x, fy - lam * yy, fz - lam * z])
        return rhs

    def rhs_linear(self) -> Callable:
        """Small-angle model for y = [x, y, vx, vy] (horizontal, ENU): ẍ = −(g/l) x plus the
        horizontal part of the active effects' point-mass accelerations, taken on the horizontal
        plane (δr = (x, y, 0), v = (vx, vy, 0): Coriolis from the vertical Earth-rate part, ...)."""
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        terms = self.point_mass_terms()

        def rhs(t, y):
            x, yy, vx, vy = y
            ax, ay = -w0sq * x, -w0sq * yy
            for term in terms:
                tx, ty, _ = term(x, yy, 0.0, vx, vy, 0.0)
                ax += tx
                ay += ty
            return np.array([vx, vy, ax, ay])
        return rhs

    STREAMS = True

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """Integrate block by block (:meth:`Instrument.stream`), carrying the exact state.

        The adaptive paths (full Cartesian model, linear model) continue one DOP853 step sequence
        bounded by the run's end (:class:`~gyro_instrument.core.integrate.Integration`): the blocks
        concatenate to :meth:`simulate` bit for bit. The parareal path converges windows of
        :attr:`WINDOW_SWINGS` whole swings one after the other, each from the end state of the
        last (:meth:`_stream_parareal`); the windows depend on the run, not on the blocks, so the
        blocks concatenate to :meth:`simulate` bit for bit there too. ``options``: ``progress``
        (callable taking a line of text: parareal passes), ``t_end``.

        Raises
        ------
        SceneError
            The run would hold more swings than can be integrated (``length_m``).
        IntegrationError
            A failed step or a non-finite state.
        """
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        r0, v0 = self.initial_state()
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        # Absolute tolerances scale with the motion, not the rod: a 1e-9 rad swing on 67 m moves
        # the bob 7e-8 m, which an atol of 1e-12 l would resolve to only 1e-3 of itself.
        w0 = math.sqrt(w0sq)
        check_period_count(f"instruments.{self.name}.length_m", self.p.length_m, 2.0 * math.pi / w0, t_end - t0)
        amp = max(self.p.length_m * math.sin(self.p.initial_deflection_rad), float(np.linalg.norm(v0)) / w0, 1e-12 * self.p.length_m)
        atol_r, atol_v = self.p.rtol * amp, self.p.rtol * amp * w0
        # Vertically tension and gravity cancel (g − λ z ≈ 0): z and v_z carry round-off at the ε g
        # level, which no tolerance may ask to resolve (an inverted bob took 7e6 evaluations).
        atol_z, atol_vz = max(atol_r, 1e-14 * self.p.length_m), max(atol_v, 1e-14 * self.p.length_m * w0)
        unwrappers = (Unwrapper(), Unwrapper())
        if self.chosen_integrator(t_end - t0)[0] == "parareal":
            yield from self._stream_parareal(blocks, t0, t_end, r0, v0, amp, options.get("progress"), unwrappers)
            return
        exact = self.restoring_law() is not None          # finite_amplitude: the exact (Cartesian) model
        if exact:
            run = integration(self.rhs_exact(), np.concatenate([r0, v0]), t0, t_end, rtol=self.p.rtol,
                              atol=np.array([atol_r, atol_r, atol_z, atol_v, atol_v, atol_vz]))
        else:
            run = integration(self.rhs_linear(), [r0[0], r0[1], v0[0], v0[1]], t0, t_end, rtol=self.p.rtol,
                              atol=np.array([atol_r] * 2 + [atol_v] * 2))
        for t in blocks:
            traj = run.advance(t)
            if exact:
                pos, vel = traj.y[:3], traj.y[3:]
            else:
                x, y, vx, vy = traj.y
                rh2 = x * x + y * y
                pos = np.vstack([x, y, -np.sqrt(np.maximum(self.p.length_m ** 2 - rh2, 0.0))])
                vel = np.vstack([vx, vy, np.zeros_like(vx)])
            cols = pendulum_columns(pos, vel, w0sq, unwrappers)
            yield Simulation(t, cols, traj, extra={"position_enu": pos, "velocity_enu": vel})

    def _first_swing(self, r0, v0):
        """Period and apsidal turn of the first swing, from the full equations (DOP853, rtol 1e-12).

        The guess is Quet's: T = 4 × the quarter period (42) between θ0 and the minimum deflection
        β of sec. 2 §II, and a turn of −k′ T with k′ the apsidal rate of sec. 2 §III. The swing is
        then integrated to its second apocentre (x ẋ + y ẏ = 0, decreasing) after 0.9 T: that time and
        the azimuth turned there are the comparison pendulum's period and turn, exact for this
        release, which the first guess of every swing start uses (sec. 2: the non-rotating
        motion turned by k t)."""
        from gyro_instrument.core.dop853 import first_crossing
        k = self.site.k_vertical_rad_s if self.has("earth_rotation") else 0.0
        beta = min_deflection_from_rest_rad(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad)
        guess = 4.0 * quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta)
        rhs = self.rhs_exact()

        def f(tt, *y):
            return tuple(rhs(tt, np.array(y)).tolist())

        def apocentre(y):
            return y[0] * y[3] + y[1] * y[4]                      # d(x² + y²)/dt / 2
        # DOP853 on floats (core/dop853.py: scipy's method and step control; not scipy.integrate,
        # whose import costs the command line 0.25-0.4 s), the apocentre by bisection on its dense output
        period, y1, sol, nfev = first_crossing(f, np.concatenate([r0, v0]), 1.2 * guess, apocentre,
                                               after=0.9 * guess, rtol=1e-12, atol=1e-14 * self.p.length_m)
        if period is None:
            return guess, -apsidal_rate_from_rest_rad_s(k, self.p.initial_deflection_rad) * guess, nfev, sol
        turn = math.atan2(r0[0] * y1[1] - r0[1] * y1[0], r0[0] * y1[0] + r0[1] * y1[1])
        return period, turn, nfev, sol

    def comparison_solution(self, t) -> tuple:
        """Quet's comparison pendulum (sec. 2): the first swing of the full model (DOP853, rtol
        1e-12), repeated every period and turned about the vertical by its apsidal angle each time
        — the non-rotating motion turned by k t, with the swing's exact period and turn. Exact
        for the first swing; it misses what the horizontal Earth rate and the slow change of the
        ellipse do later (the parareal fast path adds them). Returns (position, velocity, nfev)."""
        r0, v0 = self.initial_state()
        period, turn, nfev, sol = self._first_swing(r0, v0)
        t = np.asarray(t, dtype=float) - float(t[0])
        n = np.floor(t / period)
        y = sol(t - n * period)
        c, s = np.cos(n * turn), np.sin(n * turn)
        out = y.copy()
        for b in (0, 3):
            out[b] = c * y[b] - s * y[b + 1]
            out[b + 1] = s * y[b] + c * y[b + 1]
        return out[:3], out[3:], nfev

    #: Swings per parareal window of a streamed run: memory ~10 kB per swing at 48 steps (the grid
    #: of positions and derivatives, the Newton pass's stages), so a window of 2048 swings (9.3 h of
    #: the 67 m pendulum) holds ~20 MB whatever the duration; long enough that the Python overhead
    #: of a window (~600 batched right-hand-side calls per Newton pass) stays small against the
    #: numpy work it drives (the whole ``simulate`` of a sidereal day at 20 Hz to Parquet, median of 3
    #: with the CPU shared: one window of 5 247 swings 2.4 s and 203 MB peak RSS, windows of 2048
    #: swings 2.6 s and 164 MB, of 512 swings 2.6 s and 145 MB; the times differ within the noise).
    WINDOW_SWINGS = 2048

    def _parareal_window(self, y_start, n_seg, period, phi, scale, progress, span=(0.0, 1.0)):
        """Newton-parareal over ``n_seg`` whole swings from ``y_start`` (:func:`~gyro_instrument.core.
        parareal.parareal`); first guess of each swing's start: ``y_start`` turned about the vertical by
        ``phi`` per swing (Quet's comparison pendulum, sec. 2). Returns (grid, info, end state)."""
        from gyro_instrument.core.parareal import parareal
        ang = phi * np.arange(n_seg + 1)
        pred = np.empty((n_seg + 1, 6))
        for b in (0, 3):
            pred[:, b] = np.cos(ang) * y_start[b] - np.sin(ang) * y_start[b + 1]
            pred[:, b + 1] = np.sin(ang) * y_start[b] + np.cos(ang) * y_start[b + 1]
            pred[:, b + 2] = y_start[b + 2]
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        _, grid, info = parareal(self.rhs_exact(), y_start, period, pred, self.p.segment_steps, scale,
                                 tol=self.p.shooting_tol, align=lambda U: _swing_frames(U, w0sq), progress=progress,
                                 span=span)
        return grid, info, grid[0][-1, :, -1].copy()

    def _stream_parareal(self, blocks, t0, t_end, r0, v0, amp, progress, unwrappers):
        """The fast path (:mod:`gyro_instrument.core.parareal`), window by window of whole swings.

        Segments are one swing period T, measured on the first swing of the full model
        (:meth:`_first_swing`: Quet's quarter period (42) with the minimum deflection β of sec. 2 §II
        as the guess); the first guess of each swing's start is the window's start turned by the
        apsidal angle per period (sec. 2 §III: the comparison pendulum). Newton-parareal then
        converges the starts on the full equations (:meth:`rhs_exact`, every listed effect), so the
        result is the full model to ``shooting_tol``, not the comparison solution. The run's
        ceil((t_end − t0)/T) swings are cut into windows of :attr:`WINDOW_SWINGS`; window w + 1 starts
        from the fine end state of window w's last swing, so the state carried is the integrated one
        and the windows do not depend on how the samples are cut into blocks."""
        c0, w0t = time.process_time(), time.perf_counter()
        cpu = wall = 0.0                     # this generator's own time (not the consumer's between blocks)
        period, phi, evals, _ = self._first_swing(r0, v0)
        n_total = max(1, int(math.ceil((t_end - t0) / period)))
        per = self.WINDOW_SWINGS
        scale = np.array([amp] * 3 + [amp * math.sqrt(self.context.gravity_m_s2 / self.p.length_m)] * 3)
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        window, grid, info, y_next = -1, None, None, np.concatenate([r0, v0])
        passes = 0
        for t in blocks:
            if c0 is None:
                c0, w0t = time.process_time(), time.perf_counter()
            tau = t - t0
            seg = np.clip(np.floor(tau / period), 0, n_total - 1).astype(np.int64)
            win = seg // per
            y = np.empty((6, t.size))
            for w in range(int(win[0]), int(win[-1]) + 1):
                while window < w:            # every window in turn: the state is carried through all
                    window += 1
                    n_seg = min(per, n_total - window * per)
                    span = (window * per / n_total, (window * per + n_seg) / n_total)   # of the run, for progress
                    grid = rows = None               # the previous window's grid is not needed any more
                    grid, info, y_next = self._parareal_window(y_next, n_seg, period, phi, scale, progress, span)
                    rows = hermite_rows(grid, 3, period)  # once per window, for every block in it
                    evals += info["rhs_columns"]
                    passes += info["iterations"]
                sel = win == w
                if sel.any():
                    y[:, sel] = dense_output(grid, period, tau[sel] - (w * per) * period, 3, rows=rows)
            pos, vel = y[:3], y[3:]
            cols = pendulum_columns(pos, vel, w0sq, unwrappers)
            cpu, wall = cpu + time.process_time() - c0, wall + time.perf_counter() - w0t
            c0 = None
            traj = Trajectory(t, y, evals, wall, cpu,
                              f"parareal RK8 ({self.p.segment_steps} steps/period, {passes} passes in "
                              f"{window + 1} window{'s' if window else ''})")
            yield Simulation(t, cols, traj, extra={"position_enu": pos, "velocity_enu": vel, "parareal": info,
                                                   "period_s": period, "segments": n_total})


def _swing_frames(U, w0sq):
    """Rotations about the vertical by each state's swing-plane angle (Fradkin tensor), acting on
    position and velocity: the frame in which a swing's one-period Jacobian varies slowly."""
    x, y, vx, vy = U[:, 0], U[:, 1], U[:, 3], U[:, 4]
    txx, tyy, txy = w0sq * x * x + vx * vx, w0sq * y * y + vy * vy, w0sq * x * y + vx * vy
    a = 0.5 * np.unwrap(np.arctan2(2 * txy, txx - tyy))
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((len(a), 6, 6))
    for b in (0, 3):
        R[:, b, b], R[:, b, b + 1], R[:, b + 1, b], R[:, b + 1, b + 1] = c, -s, s, c
        R[:, b + 2, b + 2] = 1.0
    return R


def relative_spin_rad_s(qb, qda, qds) -> np.ndarray:
    """Quet's ρ (sec. 3 §VI): the body's spin about its figure axis relative to the Earth, rad/s.

    The figure axis e points from the pivot to the centre of mass; the spin is right-handed
    about e (the ``spin_rate_rad_s`` parameter is ρ0). The body's angular velocity relative to
    the Earth is the east hinge's rate q̇a along east, the north hinge's q̇b along the hinge's
    north axis (perpendicular to e) and the spin hinge's q̇s along e; in the body's axes east is
    (cos qb, 0, sin qb) and e = (0, 0, −1), so ρ = q̇s − q̇a sin qb.

    Eq. (53), d(ρ − K cos θ + K' sin θ sin ψ) = 0, integrated in (55): ρ + Ω·e is constant (the
    body's absolute spin; no torque acts about the figure axis of a body of revolution).

    Parameters
    ----------
    qb, qda, qds : ndarray (m,)
        North-hinge angle (rad), east-hinge rate and spin-hinge rate (rad/s) of the chain.

    Returns
    -------
    ndarray (m,)
        ρ, rad/s.
    """
    return qds - qda * np.sin(qb)


class CompoundPendulum(Instrument):
    """Compound pendulum (Quet sec. 3 §VI): a body of revolution hung from a point of its axis.

    Integrated with the generic :class:`HingeChain`: two massless Cardan hinges (about east,
    then about the new north) carry the body, which spins about its own axis. The Cardan pair
    is singular only with the axis horizontal along east–west, so deflections stay below 90°.
    """

    type_name = "compound_pendulum"
    summary = "body of revolution hung from a point of its axis (Quet sec. 3 §VI)"
    PARAMS = (
        Param("mass_kg", default=10.0, low=0.0, open_low=True, doc="M"),
        Param("com_distance_m", default=1.0, low=0.0, open_low=True, doc="l: pivot to centre of mass"),
        Param("transverse_inertia_kg_m2", default=10.0, low=0.0, open_low=True,
              doc="A: moment about a transverse axis through the pivot (≥ M l²)"),
        Param("axial_inertia_kg_m2", default=0.01, low=0.0, open_low=True, doc="C: moment about the figure axis"),
        Param("spin_rate_rad_s", default=0.0, low=-1.0e5, high=1.0e5, doc="initial relative spin ρ0"),
        Param("initial_deflection_deg", default=5.0, low=0.0, high=80.0, open_low=False,
              doc="θ0 (below 90°: Cardan hinges)"),
        Param("initial_azimuth_deg", default=90.0, low=-360.0, high=360.0, doc="compass azimuth of the release"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
    )
    MECHANICS = frozenset({RIGID_BODY, DAMPING, SPIN})
    COLUMNS = PENDULUM_COLUMNS + (Column("spin_rate", "rad/s", "ρ: spin about the figure axis (pivot to centre of "
                                                             "mass, right-handed) relative to the Earth; ρ + Ω·e "
                                                             "is constant (sec. 3 §VI eq. 55)"),)
    MEASURED_CHANNELS = PENDULUM_MEASURED
    JOINTS = PENDULUM_JOINTS
    IS_PENDULUM = True
    SIMULATOR_NODE = "pendulum_sim"

    @classmethod
    def check_params(cls, prefix, p) -> None:
        from gyro_instrument.core.errors import SceneError
        ml = p["mass_kg"] * p["com_distance_m"]
        if not (ml > 0.0 and math.isfinite(p["transverse_inertia_kg_m2"] / ml)):
            raise SceneError(f"{prefix}.com_distance_m", p["com_distance_m"],
                             f"with mass_kg = {p['mass_kg']:g} gives M l = {ml:g}: the equivalent length A/(M l) is "
                             f"not a finite number")
        ml2 = p["mass_kg"] * p["com_distance_m"] ** 2
        if p["transverse_inertia_kg_m2"] < ml2 * (1 - 1e-12):
            raise SceneError(f"{prefix}.transverse_inertia_kg_m2", p["transverse_inertia_kg_m2"],
                             f"must be >= M l^2 = {ml2:g} (parallel-axis theorem)")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        self.equivalent_length_m = self.p.transverse_inertia_kg_m2 / (self.p.mass_kg * self.p.com_distance_m)

    def pendulum_length_m(self) -> float:
        """The pivot–centre-of-mass distance l, m (the deflections are those of the centre of mass)."""
        return self.p.com_distance_m

    def expected_swing(self) -> "ExpectedSwing":
        """Four quarter periods of the simple pendulum of the equivalent length λ (sec. 3 §VI eq. 57)
        and the release deflection θ0."""
        return ExpectedSwing(4.0 * quarter_period_s(self.equivalent_length_m, self.site.gravity_m_s2, self.p.initial_deflection_rad, 0.0),
                             abs(self.p.initial_deflection_rad), "the body's inertia, mass, centre of mass and initial deflection",
                             *WINDOW_SAMPLING)

    def predictions(self) -> dict:
        """Sec. 3 §VI: equivalent length λ = A/(M l) (eq. 57), k = n sin γ (0 without
        ``earth_rotation``; signed, positive clockwise seen from above, as ``precession_sense``
        says in words), the quarter period of the simple pendulum of length λ, and
        ``absolute_spin_rad_s`` = ρ0 + Ω·e0, the constant of eq. (55) (ρ + Ω·e, e the figure axis
        from the pivot to the centre of mass, Ω the Earth rate as simulated), rad/s."""
        k_site = self.site.k_vertical_rad_s
        k = k_site if self.has("earth_rotation") else 0.0
        lam = self.equivalent_length_m
        g = self.site.gravity_m_s2
        e0 = np.array([math.sin(self.p.initial_deflection_rad) * math.sin(self.p.initial_azimuth_rad), math.sin(self.p.initial_deflection_rad) * math.cos(self.p.initial_azimuth_rad),
                       -math.cos(self.p.initial_deflection_rad)])
        om = self.site.earth_rate_enu() if self.has("earth_rotation") else np.zeros(3)
        out = {"equivalent_length_m": lam, "foucault_rate_rad_s": k, "precession_sense": precession_sense(k),
               "quarter_period_s": quarter_period_s(lam, g, self.p.initial_deflection_rad, 0.0),
               "absolute_spin_rad_s": self.p.spin_rate_rad_s + float(om @ e0)}
        return with_notes(out, self.missing_effect_note(
            "earth_rotation", f"the swing plane keeps its azimuth (k = 0; with it k = n sin γ = {k_site:.6g} rad/s)"))

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=None,
                restoring_rate_rad_s=math.sqrt(self.site.gravity_m_s2 / self.equivalent_length_m),
                amplitude_rad=self.p.initial_deflection_rad, duration_s=duration_s)

    def build_chain(self) -> HingeChain:
        A, C = self.p.transverse_inertia_kg_m2, self.p.axial_inertia_kg_m2
        links = [Link("cardan_east", np.array([1.0, 0.0, 0.0]), np.zeros((3, 3))),
                 Link("cardan_north", np.array([0.0, 1.0, 0.0]), np.zeros((3, 3))),
                 Link("body", np.array([0.0, 0.0, -1.0]), np.diag([A, A, C]),
                      mass_kg=self.p.mass_kg, com_m=np.array([0.0, 0.0, -self.p.com_distance_m]), spin_inertia=C)]
        links[0].swing_inertia = links[1].swing_inertia = A
        return HingeChain(links, np.eye(3), self.site.earth_rate_enu(),
                          np.array([0.0, 0.0, -self.context.gravity_m_s2]), self.effects.values(), self.context)

    STREAMS = True

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """Integrate the hinge chain block by block (:meth:`Instrument.stream`): one DOP853 step
        sequence bounded by the run's end, carried across blocks, so the blocks concatenate to
        :meth:`simulate` bit for bit. Raises SceneError (``transverse_inertia_kg_m2``) for a run of
        more swings than can be integrated."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        check_period_count(f"instruments.{self.name}.transverse_inertia_kg_m2", self.p.transverse_inertia_kg_m2,
                           2.0 * math.pi * math.sqrt(self.equivalent_length_m / self.site.gravity_m_s2), t_end - t0)
        chain = self.build_chain()
        d = np.array([math.sin(self.p.initial_deflection_rad) * math.sin(self.p.initial_azimuth_rad), math.sin(self.p.initial_deflection_rad) * math.cos(self.p.initial_azimuth_rad),
                      -math.cos(self.p.initial_deflection_rad)])
        # Body axis (0,0,-1) after Rx(a) Ry(b) is (−sin b, cos b sin a, −cos b cos a).
        b = math.asin(-d[0])
        a = math.atan2(d[1], -d[2])
        run = integration(chain.rhs, [a, b, 0.0, 0.0, 0.0, self.p.spin_rate_rad_s], t0, t_end, rtol=self.p.rtol,
                          atol=1e-13)
        unwrappers = (Unwrapper(), Unwrapper())
        for t in blocks:
            traj = run.advance(t)
            qa, qb, qs, qda, qdb, qds = traj.y
            lc = self.p.com_distance_m
            pos = lc * np.vstack([-np.sin(qb), np.cos(qb) * np.sin(qa), -np.cos(qb) * np.cos(qa)])
            # velocity of the CM by differentiating the expression
            vel = lc * np.vstack([-np.cos(qb) * qdb,
                                  -np.sin(qb) * qdb * np.sin(qa) + np.cos(qb) * np.cos(qa) * qda,
                                  np.sin(qb) * qdb * np.cos(qa) + np.cos(qb) * np.sin(qa) * qda])
            cols = pendulum_columns(pos, vel, self.site.gravity_m_s2 / self.equivalent_length_m, unwrappers)
            cols["spin_rate"] = relative_spin_rad_s(qb, qda, qds)
            yield Simulation(t, cols, traj, extra={"chain": chain})
