"""Puiseux's small-tilt theory (Puiseux 1852, sec. I and II): eq. (14)/(15) and stability.

Notation (the paper's)
----------------------
Body axes Gx, Gy, Gz (principal, moments A, B, C); mass M; gravity g. The upward vertical in
body axes is n = (a'', b'', c''), with a'' = θ sin ψ, b'' = θ cos ψ for small tilts θ; r the
body-axis spin. Ellipsoid semi-axes α, β, γ along x, y, z (γ along the axis that starts
vertical).

Small tilts (sec. I, eq. 14 and 15)
-----------------------------------
    A b''¨ + D a''˙ + E b'' − G a'' = 0,     B a''¨ − D b''˙ + F a'' − G b'' = 0,
    AB ω⁴ − (AF + BE + D²) ω² + EF − G² = 0                          (15; G = 0 for sec. I)

with D = (A + B − C) r and, for the ellipsoid (sec. I),
E = (C − B) r² + Mg(β² − γ²)/γ, F = (C − A) r² + Mg(α² − γ²)/γ, G = 0; for a general body
(sec. II), with γ = GA and δ the angle from the plane Gxz to the principal section of radius ρ,
E = (C − B) r² + Mg[(ρ − γ) sin²δ + (ρ' − γ) cos²δ],
F = (C − A) r² + Mg[(ρ − γ) cos²δ + (ρ' − γ) sin²δ],
G = Mg(ρ' − ρ) sin δ cos δ.
The ellipsoid is the case ρ = α²/γ, ρ' = β²/γ, δ = 0 (the radius of curvature of the ellipse
of semi-axes α, γ at its vertex is α²/γ): both forms give the same E, F (checked in the tests).
Note the pairing: E (which goes with A and b'') holds ρ', the curvature in the y direction.
The transcription writes ϑ for δ in sec. II; they are the same angle.

Stability: both ω² real and positive, i.e. the three inequalities of sec. I/II

    (AF + BE + D²)² − 4AB(EF − G²) > 0,   EF − G² > 0,   AF + BE + D² > 0.

Homogeneous ellipsoid (A = M(β² + γ²)/5, ...) standing on its long axis: stable iff
γ r²/(5g) > ((√(γ⁴ − α⁴) + √(γ⁴ − β⁴))/(α² + β²))², i.e.

    r > √(5g/γ) · (√(γ⁴ − α⁴) + √(γ⁴ − β⁴)) / (α² + β²).

The transcription prints the whole product under one square root; that contradicts the line
before it and gives 4.9 turn/s for the paper's example. The form above gives 9.65 turn/s for
the paper's spheroid (equatorial radius 1 dm, axis 4 dm), the paper's "at least ten turns per
second", and the direct simulation agrees (tests): from 0.01 rad the axis stays within 0.042 rad
for 20 s at 1.03 r_crit and swings out to 0.44 rad within 4 s at 0.97 r_crit. Below r_crit the
axis leaves the vertical but, for a body of revolution, does not necessarily fall: energy, n·Iw
and r bound the tilt at the root θ_max of (C r)²(cos θ0 − cos θ)²/(2A sin²θ) = Mg(h(θ0) − h(θ))
(0.439 rad at 0.97 r_crit, 0.794 rad at 0.90 r_crit, for θ0 = 0.01 rad and no initial tilt
rate), and it nutates back to θ0. Puiseux's "ne pourra pas rester toujours très-voisin de la
verticale" is exactly that; "falls" (tilt past 0.5 rad) needs r below 0.961 r_crit.
"""

import math
from typing import NamedTuple

import numpy as np


def homogeneous_inertia(mass_kg, semi_axes_m) -> tuple:
    """Principal moments of a homogeneous ellipsoid (Puiseux 1852, sec. I, before the last example).

    Parameters
    ----------
    mass_kg : float
        Mass M, kg.
    semi_axes_m : sequence of 3 float
        Semi-axes α, β, γ along x, y, z, m.

    Returns
    -------
    tuple of float
        A = M(β² + γ²)/5, B = M(α² + γ²)/5, C = M(α² + β²)/5, kg m².
    """
    a, b, c = semi_axes_m
    m = mass_kg / 5.0
    return (m * (b * b + c * c), m * (a * a + c * c), m * (a * a + b * b))


def ellipsoid_coefficients(A, B, C, M, g, r, alpha, beta, gamma) -> tuple:
    """D, E, F of eq. (14) for an ellipsoid with G at its centre (Puiseux 1852, sec. I).

    Parameters
    ----------
    A, B, C : float
        Principal moments about Gx, Gy, Gz, kg m².
    M : float
        Mass, kg.
    g : float
        Gravity, m/s².
    r : float
        Spin about Gz, rad/s.
    alpha, beta, gamma : float
        Semi-axes along Gx, Gy, Gz, m (Gz near vertical).

    Returns
    -------
    tuple of float
        D = (A + B − C) r (kg m²/s), E = (C − B) r² + Mg(β² − γ²)/γ,
        F = (C − A) r² + Mg(α² − γ²)/γ (N m).
    """
    D = (A + B - C) * r
    E = (C - B) * r * r + M * g * (beta * beta - gamma * gamma) / gamma
    F = (C - A) * r * r + M * g * (alpha * alpha - gamma * gamma) / gamma
    return D, E, F


def curvature_coefficients(A, B, C, M, g, r, rho, rho_prime, gamma, delta_rad=0.0) -> tuple:
    """D, E, F, G of the small-tilt equations for any body (Puiseux 1852, sec. II).

    Parameters
    ----------
    A, B, C, M, g, r : float
        As in :func:`ellipsoid_coefficients`.
    rho, rho_prime : float
        Principal curvature radii ρ, ρ' of the surface at the contact point A, m.
    gamma : float
        GA, height of the centre of mass above the contact point at rest, m.
    delta_rad : float
        Angle δ (the transcription's ϑ) from the plane Gxz to the principal normal section of
        radius ρ, rad. δ = 0: ρ in the Gxz plane, ρ' in the Gyz plane.

    Returns
    -------
    tuple of float
        D = (A + B − C) r, E = (C − B) r² + Mg[(ρ − γ) sin²δ + (ρ' − γ) cos²δ],
        F = (C − A) r² + Mg[(ρ − γ) cos²δ + (ρ' − γ) sin²δ], G = Mg(ρ' − ρ) sin δ cos δ.
        With ρ = α²/γ, ρ' = β²/γ, δ = 0 these are the ellipsoid's D, E, F and G = 0.
    """
    s2, c2 = math.sin(delta_rad) ** 2, math.cos(delta_rad) ** 2
    w, wp = rho - gamma, rho_prime - gamma
    D = (A + B - C) * r
    E = (C - B) * r * r + M * g * (w * s2 + wp * c2)
    F = (C - A) * r * r + M * g * (w * c2 + wp * s2)
    G = M * g * (rho_prime - rho) * math.sin(delta_rad) * math.cos(delta_rad)
    return D, E, F, G


class StabilityVerdict(NamedTuple):
    """Result of the three-inequality test (Puiseux 1852, sec. I and II).

    Attributes
    ----------
    verdict : str
        ``"stable"`` (all three inequalities strict), ``"unstable"`` (one fails) or
        ``"marginal"`` (one is an equality within rounding: double or zero root).
    omega_sq : tuple
        The two roots ω² of eq. (15), rad²/s², ascending when real (complex when the first
        inequality fails).
    inequalities : tuple of float
        (AF + BE + D²)² − 4AB(EF − G²), EF − G², AF + BE + D².
    frequencies_rad_s : tuple of float
        √ω² for both roots when stable (the angular frequencies of a'', b'' in body axes,
        eq. 16), else NaNs.
    """

    verdict: str
    omega_sq: tuple
    inequalities: tuple
    frequencies_rad_s: tuple


def classify_coefficients(A, B, D, E, F, G=0.0, rel_tol=1e-12) -> StabilityVerdict:
    """Verdict of the three inequalities for given coefficients of eq. (14)/(15).

    Parameters
    ----------
    A, B : float
        Transverse moments, kg m².
    D, E, F, G : float
        Coefficients from :func:`ellipsoid_coefficients` or :func:`curvature_coefficients`.
    rel_tol : float
        An inequality whose value is below ``rel_tol`` times the size of its terms is an
        equality (``"marginal"``).

    Returns
    -------
    StabilityVerdict
    """
    P3 = A * F + B * E + D * D
    P2 = E * F - G * G
    P1 = P3 * P3 - 4.0 * A * B * P2
    s3 = abs(A * F) + abs(B * E) + D * D
    s2 = abs(E * F) + G * G
    s1 = s3 * s3 + 4.0 * A * B * s2
    values = (P1, P2, P3)
    zero = [abs(v) <= rel_tol * s for v, s in zip(values, (s1, s2, s3))]
    if any(v < 0.0 and not z for v, z in zip(values, zero)):
        verdict = "unstable"
    elif any(zero):
        verdict = "marginal"
    else:
        verdict = "stable"
    disc = complex(max(P1, 0.0) if zero[0] else P1) ** 0.5
    roots = ((P3 - disc) / (2.0 * A * B), (P3 + disc) / (2.0 * A * B))
    if abs(disc.imag) == 0.0:
        roots = tuple(sorted(float(x.real) for x in roots))
    if verdict == "stable":
        freqs = tuple(math.sqrt(x) for x in roots)
    else:
        freqs = (math.nan, math.nan)
    return StabilityVerdict(verdict, roots, values, freqs)


def classify_stability(A, B, C, M, g, r, alpha, beta, gamma) -> StabilityVerdict:
    """Puiseux's three inequalities for a spinning ellipsoid (sec. I, after eq. 16).

    Parameters
    ----------
    A, B, C : float
        Principal moments about Gx, Gy, Gz, kg m².
    M : float
        Mass, kg.
    g : float
        Gravity, m/s².
    r : float
        Spin about the axis Gz that starts vertical, rad/s.
    alpha, beta, gamma : float
        Semi-axes along Gx, Gy, Gz, m.

    Returns
    -------
    StabilityVerdict
        Verdict, the two roots ω² of eq. (15) and the three inequality values.
    """
    D, E, F = ellipsoid_coefficients(A, B, C, M, g, r, alpha, beta, gamma)
    return classify_coefficients(A, B, D, E, F, 0.0)


def classify_stability_curvature(A, B, C, M, g, r, rho, rho_prime, gamma,
                                 delta_rad=0.0) -> StabilityVerdict:
    """Puiseux's three inequalities for any body through its curvature radii (sec. II).

    Parameters
    ----------
    A, B, C, M, g, r : float
        As in :func:`classify_stability`.
    rho, rho_prime : float
        Principal curvature radii at the contact point, m.
    gamma : float
        Height GA of the centre of mass above the contact point, m.
    delta_rad : float
        Angle from Gxz to the principal section of radius ρ, rad.

    Returns
    -------
    StabilityVerdict
        At r = 0 the verdict is ``"stable"`` exactly when γ < ρ and γ < ρ' (end of sec. II).
    """
    D, E, F, G = curvature_coefficients(A, B, C, M, g, r, rho, rho_prime, gamma, delta_rad)
    return classify_coefficients(A, B, D, E, F, G)


def critical_spin_rad_s(alpha, beta, gamma, g) -> float:
    """Least spin keeping a homogeneous ellipsoid's axis 2γ near the vertical (sec. I).

    r_crit = √(5g/γ) · (√(γ⁴ − α⁴) + √(γ⁴ − β⁴)) / (α² + β²) when γ is the longest semi-axis
    (the reading consistent with the paper's preceding line γr²/5g > (...)², not the
    transcription's single root; see the module docstring).

    Parameters
    ----------
    alpha, beta, gamma : float
        Semi-axes, m; γ along the spin axis.
    g : float
        Gravity, m/s².

    Returns
    -------
    float
        r_crit in rad/s; 0 when γ is the shortest semi-axis (stable at any spin), ``inf`` when
        γ is the middle one (never stable). The mass cancels.
    """
    if gamma < min(alpha, beta):
        return 0.0
    if gamma < max(alpha, beta):
        return math.inf
    g4 = gamma ** 4
    return math.sqrt(5.0 * g / gamma) * (math.sqrt(g4 - alpha ** 4) + math.sqrt(g4 - beta ** 4)) \
        / (alpha * alpha + beta * beta)


def stable_spin_intervals_rad_s(A, B, C, M, g, rho, rho_prime, gamma, delta_rad=0.0) -> list:
    """Spin ranges where all three inequalities hold (sec. II, ordered in r as the paper does).

    The inequalities are polynomials in s = r²: P3 = [(C − A)(C − B) + AB] s + K,
    P2 = EF − G² = (C − A)(C − B) s² + H' s + I', P1 = P3² − 4AB·P2. Their positive roots cut
    the s axis into intervals; each is tested at an interior point.

    Parameters
    ----------
    A, B, C, M, g, rho, rho_prime, gamma, delta_rad : float
        As in :func:`classify_stability_curvature` (use ρ = α²/γ, ρ' = β²/γ for an ellipsoid).

    Returns
    -------
    list of tuple
        (r_low, r_high) in rad/s (|r|; r_high may be ``inf``), merged and ascending.
    """
    _, e0, f0, G = curvature_coefficients(A, B, C, M, g, 0.0, rho, rho_prime, gamma, delta_rad)
    e1, f1, d2 = C - B, C - A, (A + B - C) ** 2
    p3 = np.array([A * f1 + B * e1 + d2, A * f0 + B * e0])
    p2 = np.array([e1 * f1, e1 * f0 + e0 * f1, e0 * f0 - G * G])
    p1 = np.polysub(np.polymul(p3, p3), 4.0 * A * B * p2)
    cuts = [0.0]
    for p in (p1, p2, p3):
        p = np.trim_zeros(p, "f")
        if p.size > 1:
            cuts += [float(x.real) for x in np.roots(p) if abs(x.imag) <= 1e-12 * abs(x) and x.real > 0.0]
    cuts = sorted(set(cuts))
    bounds = cuts + [math.inf]

    def ok(s):
        r = math.sqrt(s)
        return classify_stability_curvature(A, B, C, M, g, r, rho, rho_prime, gamma,
                                            delta_rad).verdict == "stable"

    out = []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        mid = 2.0 * lo + 1.0 if math.isinf(hi) else 0.5 * (lo + hi)
        if ok(mid):
            rlo, rhi = math.sqrt(lo), math.sqrt(hi)
            if out and out[-1][1] == rlo:
                out[-1] = (out[-1][0], rhi)
            else:
                out.append((rlo, rhi))
    return out


def critical_spin_general_rad_s(A, B, C, M, g, rho, rho_prime, gamma, delta_rad=0.0) -> float:
    """Spin above which the axis stays near the vertical for every larger spin (sec. II).

    Returns
    -------
    float
        The lower end of the unbounded stable interval of :func:`stable_spin_intervals_rad_s`,
        rad/s; ``inf`` when no spin is large enough (Gz the middle moment of inertia).
    """
    iv = stable_spin_intervals_rad_s(A, B, C, M, g, rho, rho_prime, gamma, delta_rad)
    if iv and math.isinf(iv[-1][1]):
        return iv[-1][0]
    return math.inf
