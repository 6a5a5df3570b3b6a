"""The spherical pendulum's theory on the rotating Earth (Quet 1853 sec. 2): closed forms.

The quarter period (42) exact and as Quet's series, the minimum deflection β of §II (and with the
horizontal Earth rate, beyond the paper), the apse line's rate (§III series; exact through the
elliptic integral of the third kind), the sense of the precession and Binet's ellipse, the exact
solution of the linear model. Pure functions of SI arguments; the instrument
(:mod:`gyro_instrument.instruments.pendulum`) and its dynamics
(:mod:`gyro_instrument.instruments.pendulum.dynamics`) call them.
"""

import math

import numpy as np
from scipy.special import elliprf, elliprj, ellipk


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
