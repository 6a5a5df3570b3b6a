"""Puiseux's heavy body on a smooth horizontal plane (Puiseux 1852, J. math. pures appl. 17, 1-30).

A heavy rigid body rests on a perfectly polished (frictionless) horizontal plane; one principal
axis Gz of its centre of mass G is normal to the surface at the contact point A, so the body is
in equilibrium when Gz is vertical. It is spun at r about Gz and slightly tilted. Puiseux finds
when Gz stays near the vertical (sec. I for an ellipsoid with G at its centre, sec. II for any
body, through the principal curvature radii ρ, ρ' of the surface at A).

Earth rotation is ignored, as in the paper (``MECHANICS`` and so ``SUPPORTED_EFFECTS`` are
empty): the simulated model is the exact nonlinear rigid body on the frictionless plane, with no
small-angle or other approximation, so there is nothing to switch on or off.

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

Exact model (what ``simulate`` integrates)
------------------------------------------
Frictionless plane: the only horizontal force is zero, so the horizontal motion of G is
uniform (eqs. 1, 2) and decouples; it is taken as zero. G's height is fixed by the contact:
z = h(n), where h is the support function of the body's surface seen from G (the height of G
above the plane when the upward vertical in body axes is n). For an ellipsoid S = diag(α², β²,
γ²) whose centre sits at c = (0, 0, c_z) in body axes (c_z = 0 for sec. I)::

    h(n) = √(nᵀ S n) − c·n,     ∇h = S n/√(nᵀSn) − c = −x_P,

x_P the contact point in body axes (h is extended to all n as a degree-1 homogeneous function,
so ∇h is the contact point with its sign changed; its Hessian H = S/s − (Sn)(Sn)ᵀ/s³, s = √(nᵀSn)).
With the body angular velocity w, ṅ = n × w, so ż = ∇h·ṅ = k·w with k = ∇h × n. Lagrangian

    L = ½ M (k·w)² + ½ wᵀ I w − M g h(n).

The Euler-Poincaré equations for the rotation (equivalently Newton-Euler with the normal force
N at x_P: I ẇ + w × I w = N x_P × n, M z̈ = N − M g, z̈ = k̇·w + k·ẇ) give::

    (I + M k kᵀ) ẇ = −w × I w − M (g + k̇·w) k,      k̇ = (H ṅ) × n + ∇h × ṅ,
    N = M (g + k̇·w + k·ẇ),

solved in closed form with the Sherman-Morrison formula. The orientation is a quaternion q
(scalar first, body to world), q̇ = ½ q ⊗ (0, w); the right-hand side uses q/|q| so the exact flow
keeps |q| = 1 and the integrated |q| − 1 measures the integration error. No Euler angle appears,
so there is no singularity at θ = 0 (where Puiseux's ψ, φ are undefined).

Invariants (used by the tests): the energy E = ½ M (k·w)² + ½ wᵀ I w + M g h(n); the vertical
component of the angular momentum about G, n·(I w) (the normal force is vertical, so its moment
about G is horizontal, and gravity acts at G: no vertical torque about G, even though G
accelerates vertically, since dL_G/dt = Σ moments about G holds for the centre of mass); and for
a body of revolution (α = β, A = B) the spin r itself (eq. 6: the contact point lies in the
plane of n and the axis, so the torque has no component along Gz).

The normal force N must stay positive: a negative N means the body would leave the plane,
which this model does not describe (``extra['min_normal_force_N']``).

General body (``shape: curvature``)
-----------------------------------
Only ρ, ρ', γ (and δ) enter the small-tilt theory (sec. II). For the simulation the surface is
modelled by the ellipsoid that osculates the body at A: semi-axis γ_e = √(ρ ρ') along Gz, and
in the tangent plane semi-axes √(ρ γ_e), √(ρ' γ_e) along the principal directions (at angle δ
from Gx), so that its curvature radii at the vertex are exactly ρ, ρ' (the curvature radius of
an ellipsoid at a vertex is (tangent semi-axis)²/(normal semi-axis)); its centre is offset
along Gz, c_z = γ_e − γ, so that G stands at height γ above A. For ρ = ρ' this is a sphere of
radius ρ with G at ρ − γ below its centre (the weighted ball). Any other smooth surface with
the same ρ, ρ' gives the same small-tilt motion; large tilts depend on the choice.
"""

import math
from typing import NamedTuple

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import integrate
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import compass_azimuth_from_enu
from gyro_instrument.instruments.base import Column, Instrument, Simulation

TWO_PI = 2.0 * math.pi


class PairParam(Param):
    """A parameter holding two finite positive numbers (``kind = "pair"``), e.g. ρ, ρ'."""

    def describe_range(self):
        return "must be a list of 2 finite numbers > 0"

    def check(self, field, value):
        if (not isinstance(value, (list, tuple)) or len(value) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
                or not all(math.isfinite(float(v)) and float(v) > 0.0 for v in value)):
            raise SceneError(field, value, self.describe_range())
        return tuple(float(v) for v in value)


# --------------------------------------------------------------------------- analytic theory
def homogeneous_inertia(mass_kg, semi_axes_m):
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


def ellipsoid_coefficients(A, B, C, M, g, r, alpha, beta, gamma):
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


def curvature_coefficients(A, B, C, M, g, r, rho, rho_prime, gamma, delta_rad=0.0):
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


def classify_coefficients(A, B, D, E, F, G=0.0, rel_tol=1e-12):
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


def classify_stability(A, B, C, M, g, r, alpha, beta, gamma):
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


def classify_stability_curvature(A, B, C, M, g, r, rho, rho_prime, gamma, delta_rad=0.0):
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


def critical_spin_rad_s(alpha, beta, gamma, g):
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


def stable_spin_intervals_rad_s(A, B, C, M, g, rho, rho_prime, gamma, delta_rad=0.0):
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


def critical_spin_general_rad_s(A, B, C, M, g, rho, rho_prime, gamma, delta_rad=0.0):
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


# --------------------------------------------------------------------------- surface and dynamics
class EllipsoidSurface:
    """Support function h(n) = √(nᵀ S n) − c_z n_z of an ellipsoid centred at (0, 0, c_z).

    Parameters
    ----------
    semi_axes_m : sequence of 3 float
        Semi-axes along the principal directions in the tangent plane and along Gz, m.
    centre_z_m : float
        Body z of the ellipsoid centre relative to G, m (0 for Puiseux sec. I).
    delta_rad : float
        Angle from Gx to the first tangent semi-axis, rad.
    """

    def __init__(self, semi_axes_m, centre_z_m=0.0, delta_rad=0.0):
        a, b, c = (float(x) for x in semi_axes_m)
        cd, sd = math.cos(delta_rad), math.sin(delta_rad)
        self.sxx = a * a * cd * cd + b * b * sd * sd
        self.syy = a * a * sd * sd + b * b * cd * cd
        self.sxy = (a * a - b * b) * sd * cd
        self.szz = c * c
        self.cz = float(centre_z_m)
        self.semi_axes_m = (a, b, c)
        self.delta_rad = float(delta_rad)

    @classmethod
    def osculating(cls, rho, rho_prime, gamma, delta_rad=0.0):
        """The ellipsoid with curvature radii ρ, ρ' at its lowest vertex and G at height γ.

        Normal semi-axis γ_e = √(ρ ρ'), tangent semi-axes √(ρ γ_e), √(ρ' γ_e), centre at
        c_z = γ_e − γ above G (see the module docstring).
        """
        ge = math.sqrt(rho * rho_prime)
        return cls((math.sqrt(rho * ge), math.sqrt(rho_prime * ge), ge), ge - gamma, delta_rad)

    def height(self, nx, ny, nz):
        """h(n): height of G above the plane, m, for the upward vertical n in body axes."""
        return np.sqrt(self.sxx * nx * nx + 2.0 * self.sxy * nx * ny + self.syy * ny * ny
                       + self.szz * nz * nz) - self.cz * nz

    def contact_point(self, n):
        """Contact point x_P = −∇h(n) in body axes, m."""
        n = np.asarray(n, dtype=float)
        S = np.array([[self.sxx, self.sxy, 0.0], [self.sxy, self.syy, 0.0], [0.0, 0.0, self.szz]])
        Sn = S @ n
        return -(Sn / math.sqrt(n @ Sn) - np.array([0.0, 0.0, self.cz]))


def _dynamics(y, surf, inertia, M, g, sqrt):
    """Shared core of the right-hand side and of the diagnostics (scalar or array ``y``).

    Returns q̇ (4), ẇ (3), the normal force N (N), h (m), ż (m/s) and n (3).
    """
    qw, qx, qy, qz, wx, wy, wz = y
    A, B, C = inertia
    sxx, sxy, syy, szz, cz = surf.sxx, surf.sxy, surf.syy, surf.szz, surf.cz
    nq = qw * qw + qx * qx + qy * qy + qz * qz
    # upward vertical in body axes: third row of R(q/|q|) (body -> world)
    nx = 2.0 * (qx * qz - qw * qy) / nq
    ny = 2.0 * (qy * qz + qw * qx) / nq
    nz = (qw * qw - qx * qx - qy * qy + qz * qz) / nq
    # n' = n x w (n fixed in space, seen from the body)
    ndx = ny * wz - nz * wy
    ndy = nz * wx - nx * wz
    ndz = nx * wy - ny * wx
    # gradient of h: S n / s - c
    sx = sxx * nx + sxy * ny
    sy = sxy * nx + syy * ny
    sz = szz * nz
    s = sqrt(nx * sx + ny * sy + nz * sz)
    gx, gy, gz = sx / s, sy / s, sz / s - cz
    h = s - cz * nz
    # Hessian times n': S n'/s - S n (S n . n')/s^3
    tx = sxx * ndx + sxy * ndy
    ty = sxy * ndx + syy * ndy
    tz = szz * ndz
    f = (sx * ndx + sy * ndy + sz * ndz) / (s * s * s)
    hx, hy, hz = tx / s - sx * f, ty / s - sy * f, tz / s - sz * f
    # k = grad h x n (z' = k.w) and its rate
    kx = gy * nz - gz * ny
    ky = gz * nx - gx * nz
    kz = gx * ny - gy * nx
    kdx = hy * nz - hz * ny + gy * ndz - gz * ndy
    kdy = hz * nx - hx * nz + gz * ndx - gx * ndz
    kdz = hx * ny - hy * nx + gx * ndy - gy * ndx
    # right-hand side: -w x I w - M (g + k'.w) k
    Lx, Ly, Lz = A * wx, B * wy, C * wz
    coef = M * (g + kdx * wx + kdy * wy + kdz * wz)
    bx = -(wy * Lz - wz * Ly) - coef * kx
    by = -(wz * Lx - wx * Lz) - coef * ky
    bz = -(wx * Ly - wy * Lx) - coef * kz
    # (I + M k k^T)^-1 b by Sherman-Morrison
    ux, uy, uz = bx / A, by / B, bz / C
    vx, vy, vz = kx / A, ky / B, kz / C
    fac = M * (kx * ux + ky * uy + kz * uz) / (1.0 + M * (kx * vx + ky * vy + kz * vz))
    wdx, wdy, wdz = ux - fac * vx, uy - fac * vy, uz - fac * vz
    N = M * (g + kdx * wx + kdy * wy + kdz * wz + kx * wdx + ky * wdy + kz * wdz)
    zdot = kx * wx + ky * wy + kz * wz
    # q' = 1/2 q (x) (0, w)
    qdot = (-0.5 * (qx * wx + qy * wy + qz * wz),
            0.5 * (qw * wx + qy * wz - qz * wy),
            0.5 * (qw * wy + qz * wx - qx * wz),
            0.5 * (qw * wz + qx * wy - qy * wx))
    return qdot, (wdx, wdy, wdz), N, h, zdot, (nx, ny, nz)


def reduced_rates(n, w, surf, inertia, M, g):
    """ṅ and ẇ for the vertical n and the rate w in body axes (the autonomous reduced system).

    The right-hand side of w depends on the orientation only through n, so (n, w) obey a closed
    6-dimensional system; its linearisation about n = (0, 0, 1), w = (0, 0, r) is eq. (14).

    Parameters
    ----------
    n : array (3,)
        Upward vertical in body axes (unit).
    w : array (3,)
        Body angular velocity, rad/s.
    surf : EllipsoidSurface
    inertia : sequence of 3 float
        A, B, C, kg m².
    M, g : float
        Mass (kg) and gravity (m/s²).

    Returns
    -------
    ndarray (6,)
        (ṅ, ẇ).
    """
    n = np.asarray(n, dtype=float)
    n = n / np.linalg.norm(n)
    # a quaternion whose third rotation-matrix row is n (rotation of e_z onto n, inverted)
    axis = np.cross(n, [0.0, 0.0, 1.0])
    sa = np.linalg.norm(axis)
    ang = math.atan2(sa, n[2])
    axis = axis / sa if sa > 0.0 else np.array([1.0, 0.0, 0.0])
    q = np.concatenate([[math.cos(ang / 2)], math.sin(ang / 2) * axis])
    qdot, wdot, *_, nn = _dynamics(np.concatenate([q, w]), surf, inertia, M, g, math.sqrt)
    nn = np.array(nn)
    return np.concatenate([np.cross(nn, w), wdot])


# --------------------------------------------------------------------------- instrument
class PuiseuxBody(Instrument):
    """Heavy body spun on a smooth horizontal plane (Puiseux 1852): exact rigid-body model.

    World frame ENU (x east, y north, z up); the azimuths are compass azimuths (0 north,
    clockwise seen from above), as in :func:`~gyro_instrument.core.site.compass_azimuth_from_enu`.
    Initially the body is upright with its axes along ENU, then turned by ``initial_tilt_deg``
    about the horizontal line perpendicular to ``initial_tilt_azimuth_deg`` so that the axis Gz
    leans toward that azimuth; it spins at r about Gz (positive counter-clockwise seen from
    above when upright), and the axis moves at the given tilt and azimuth rates. Earth rotation
    and friction are ignored (the paper's hypotheses); nothing is approximated.
    """

    type_name = "puiseux_body"
    summary = "heavy body spun on a smooth horizontal plane (Puiseux 1852), exact rigid-body model"
    PARAMS = (
        Param("shape", kind="str", default="ellipsoid", choices=("ellipsoid", "curvature"),
              doc="ellipsoid with G at its centre (sec. I) or any body by its curvature radii at "
                  "the contact point (sec. II)"),
        Param("semi_axes_m", kind="vec3", default=None,
              doc="ellipsoid semi-axes alpha, beta, gamma along body x, y, z (z starts vertical), m"),
        Param("homogeneous", kind="bool", default=True,
              doc="ellipsoid: moments from mass and semi-axes, A = M(beta^2+gamma^2)/5 etc.; "
                  "false: give inertia_kg_m2"),
        Param("inertia_kg_m2", kind="vec3", default=None,
              doc="principal moments A, B, C about body x, y, z through G, kg m^2"),
        Param("mass_kg", default=1.0, low=0.0, open_low=True, doc="mass M, kg"),
        PairParam("curvature_radii_m", kind="pair", default=None,
                  doc="curvature: principal radii rho, rho' of the surface at the contact point "
                      "(rho in the body x direction when curvature_angle_deg = 0), m"),
        Param("com_height_m", default=None, low=0.0, open_low=True,
              doc="curvature: height gamma = GA of the centre of mass above the contact point at rest, m"),
        Param("curvature_angle_deg", default=0.0, low=-90.0, high=90.0,
              doc="curvature: angle delta from body x to the principal direction of rho, degrees"),
        Param("spin_rate_rad_s", default=None, low=-1.0e5, high=1.0e5,
              doc="initial spin r about the body axis Gz, rad/s (give this or spin_rate_turn_s)"),
        Param("spin_rate_turn_s", default=None, low=-1.0e4, high=1.0e4,
              doc="initial spin r about the body axis Gz, turns/s (give this or spin_rate_rad_s)"),
        Param("initial_tilt_deg", default=0.0, low=0.0, high=180.0, open_high=True,
              doc="initial angle theta0 between the body axis Gz and the upward vertical, degrees"),
        Param("initial_tilt_azimuth_deg", default=0.0, low=-360.0, high=360.0,
              doc="compass azimuth toward which the axis leans, degrees (0 north, 90 east)"),
        Param("initial_tilt_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial d(theta)/dt, degrees/s"),
        Param("initial_azimuth_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial rate of the axis' compass azimuth (clockwise from above), degrees/s"),
        Param("rtol", default=1e-10, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
    )
    MECHANICS = frozenset()
    MEASURED_CHANNELS = ("tilt", "tilt_azimuth")
    JOINTS = ("tilt", "tilt_azimuth", "spin")
    SIMULATOR_NODE = "top_sim"
    COLUMNS = (
        Column("tilt", "rad", "theta: angle between the body axis Gz and the upward vertical"),
        Column("tilt_azimuth", "rad", "compass azimuth of the axis' horizontal projection (0 north, clockwise)"),
        Column("spin_rate", "rad/s", "r: body angular velocity about Gz"),
        Column("com_height", "m", "height of the centre of mass above the plane, h(n)"),
        Column("vertical_body_x", "1", "a'' = theta sin psi: body-x component of the upward vertical (eq. 16)"),
        Column("vertical_body_y", "1", "b'' = theta cos psi: body-y component of the upward vertical (eq. 16)"),
    )

    @classmethod
    def check_params(cls, prefix, p):
        """Cross-field checks: the shape's required fields, one spin, a physical inertia."""
        if p["spin_rate_rad_s"] is not None and p["spin_rate_turn_s"] is not None:
            raise SceneError(f"{prefix}.spin_rate_turn_s", p["spin_rate_turn_s"],
                             "give either spin_rate_rad_s or spin_rate_turn_s, not both")
        own = {"ellipsoid": ("semi_axes_m",), "curvature": ("curvature_radii_m", "com_height_m")}
        for other, keys in own.items():
            if other != p["shape"]:
                for key in keys:
                    if p[key] is not None:
                        raise SceneError(f"{prefix}.{key}", p[key], f"applies only to shape = {other}")
        if p["shape"] == "ellipsoid":
            if p["homogeneous"] and p["inertia_kg_m2"] is not None:
                raise SceneError(f"{prefix}.inertia_kg_m2", list(p["inertia_kg_m2"]),
                                 "is computed from mass and semi-axes when homogeneous = true; "
                                 "set homogeneous: false to give it")
            if p["semi_axes_m"] is None:
                raise SceneError(f"{prefix}.semi_axes_m", None,
                                 "is required when shape = ellipsoid (3 numbers > 0, m)")
            if min(p["semi_axes_m"]) <= 0.0:
                raise SceneError(f"{prefix}.semi_axes_m", list(p["semi_axes_m"]),
                                 "must be 3 numbers > 0, m")
            if not p["homogeneous"] and p["inertia_kg_m2"] is None:
                raise SceneError(f"{prefix}.inertia_kg_m2", None,
                                 "is required when homogeneous = false (A, B, C > 0, kg m^2)")
        else:
            for key, what in (("curvature_radii_m", "2 numbers > 0, m"), ("com_height_m", "a number > 0, m"),
                              ("inertia_kg_m2", "A, B, C > 0, kg m^2")):
                if p[key] is None:
                    raise SceneError(f"{prefix}.{key}", None, f"is required when shape = curvature ({what})")
        I = p["inertia_kg_m2"]
        if I is not None and (p["shape"] == "curvature" or not p["homogeneous"]):
            A, B, C = I
            if min(I) <= 0.0 or A + B < C or B + C < A or A + C < B:
                raise SceneError(f"{prefix}.inertia_kg_m2", list(I),
                                 "must be 3 numbers > 0 obeying the triangle inequalities "
                                 "(A + B >= C, B + C >= A, C + A >= B) of a rigid body")

    def __init__(self, name, site, params, effects):
        super().__init__(name, site, params, effects)
        self.g = float(site.gravity_m_s2)
        self.M = float(self.mass_kg)
        if self.shape == "ellipsoid":
            self.alpha, self.beta, self.gamma = self.semi_axes_m
            self.rho = self.alpha ** 2 / self.gamma
            self.rho_prime = self.beta ** 2 / self.gamma
            self.delta = 0.0
            self.surface = EllipsoidSurface(self.semi_axes_m)
            self.inertia = (homogeneous_inertia(self.M, self.semi_axes_m) if self.homogeneous
                            else tuple(self.inertia_kg_m2))
        else:
            self.rho, self.rho_prime = self.curvature_radii_m
            self.gamma = float(self.com_height_m)
            self.delta = math.radians(self.curvature_angle_deg)
            self.surface = EllipsoidSurface.osculating(self.rho, self.rho_prime, self.gamma, self.delta)
            self.inertia = tuple(self.inertia_kg_m2)
        if self.spin_rate_rad_s is not None:
            self.r0 = float(self.spin_rate_rad_s)
        elif self.spin_rate_turn_s is not None:
            self.r0 = TWO_PI * float(self.spin_rate_turn_s)
        else:
            self.r0 = 0.0
        self.theta0 = math.radians(self.initial_tilt_deg)
        self.azimuth0 = math.radians(self.initial_tilt_azimuth_deg)
        self.thetadot0 = math.radians(self.initial_tilt_rate_deg_s)
        self.azimuthdot0 = math.radians(self.initial_azimuth_rate_deg_s)

    # ---------------------------------------------------------------- predictions
    def coefficients(self, r=None):
        """D, E, F, G of eq. (14) at spin ``r`` (rad/s; default the initial spin)."""
        A, B, C = self.inertia
        r = self.r0 if r is None else r
        if self.shape == "ellipsoid":
            return (*ellipsoid_coefficients(A, B, C, self.M, self.g, r, self.alpha, self.beta, self.gamma), 0.0)
        return curvature_coefficients(A, B, C, self.M, self.g, r, self.rho, self.rho_prime, self.gamma,
                                      self.delta)

    def predictions(self):
        """Small-tilt theory for this body and spin (Puiseux 1852, eqs. 14-16, sec. I-II).

        Returns
        -------
        dict
            ``omega_sq_rad2_s2`` (the two roots of eq. 15), ``frequencies_rad_s`` (their square
            roots when stable: angular frequencies of a'', b'' in body axes), ``periods_s``,
            ``verdict`` (three inequalities), ``inequalities``, ``coefficients`` (D, E, F, G),
            ``stable_at_rest`` (γ < ρ and γ < ρ'), ``critical_spin_rad_s`` and
            ``critical_spin_turn_s`` (from the inequalities' polynomials in r²),
            ``critical_spin_closed_form_rad_s`` (homogeneous ellipsoid only), the curvature radii
            and the initial invariants (energy, vertical angular momentum about G).
        """
        A, B, C = self.inertia
        D, E, F, G = self.coefficients()
        v = classify_coefficients(A, B, D, E, F, G)
        rcrit = critical_spin_general_rad_s(A, B, C, self.M, self.g, self.rho, self.rho_prime, self.gamma,
                                            self.delta)
        out = {
            "omega_sq_rad2_s2": v.omega_sq,
            "frequencies_rad_s": v.frequencies_rad_s,
            "periods_s": tuple(TWO_PI / f if f > 0 else math.inf for f in v.frequencies_rad_s),
            "verdict": v.verdict,
            "inequalities": v.inequalities,
            "coefficients": {"D": D, "E": E, "F": F, "G": G},
            "stable_at_rest": self.gamma < self.rho and self.gamma < self.rho_prime,
            "critical_spin_rad_s": rcrit,
            "critical_spin_turn_s": rcrit / TWO_PI,
            "rho_m": self.rho,
            "rho_prime_m": self.rho_prime,
            "spin_rate_rad_s": self.r0,
        }
        if self.shape == "ellipsoid" and self.homogeneous:
            rc = critical_spin_rad_s(self.alpha, self.beta, self.gamma, self.g)
            out["critical_spin_closed_form_rad_s"] = rc
            out["critical_spin_closed_form_turn_s"] = rc / TWO_PI
        y0 = self.initial_state()
        diag = self.diagnostics(y0[:, None])
        out["energy_J"] = float(diag["energy_J"][0])
        out["angular_momentum_vertical_kg_m2_s"] = float(diag["angular_momentum_vertical_kg_m2_s"][0])
        return out

    def scales(self, duration_s):
        """Characteristic scales: spin, small-tilt restoring rate at rest, amplitude, duration."""
        A, B, _ = self.inertia
        w0 = math.sqrt(self.M * self.g * min(abs(self.rho - self.gamma), abs(self.rho_prime - self.gamma))
                       / max(A, B))
        return {"earth_rate_rad_s": self.site.earth_rate_rad_s, "gyro_rate_rad_s": abs(self.r0) or None,
                "restoring_rate_rad_s": w0, "amplitude_rad": self.theta0, "duration_s": duration_s}

    # ---------------------------------------------------------------- model
    def initial_state(self):
        """State [q_w, q_x, q_y, q_z, w_x, w_y, w_z] at t = 0 (quaternion body -> ENU, w in body axes)."""
        th, az = self.theta0, self.azimuth0
        # axis u in ENU, leaning toward compass azimuth az: (sin az, cos az) horizontally
        e_th = np.array([math.cos(th) * math.sin(az), math.cos(th) * math.cos(az), -math.sin(th)])
        e_az = np.array([math.cos(az), -math.sin(az), 0.0])  # direction of increasing compass azimuth
        u = np.array([math.sin(th) * math.sin(az), math.sin(th) * math.cos(az), math.cos(th)])
        udot = self.thetadot0 * e_th + self.azimuthdot0 * math.sin(th) * e_az
        w_world = self.r0 * u + np.cross(u, udot)
        # rotation by th about e_z x u / |...| = (-cos az, sin az, 0) (horizontal, perpendicular to az)
        axis = np.array([-math.cos(az), math.sin(az), 0.0])
        q = np.concatenate([[math.cos(th / 2)], math.sin(th / 2) * axis])
        R = _rotation_matrix(q)
        return np.concatenate([q, R.T @ w_world])

    def rhs(self):
        """Right-hand side f(t, y) of the exact model (see the module docstring)."""
        surf, inertia, M, g = self.surface, self.inertia, self.M, self.g
        sqrt = math.sqrt

        def f(t, y):
            qdot, wdot, *_ = _dynamics(y, surf, inertia, M, g, sqrt)
            return np.array([*qdot, *wdot])
        return f

    def diagnostics(self, y):
        """Derived quantities along a state history ``y`` (shape (7, m)).

        Returns
        -------
        dict of ndarray
            ``n`` (3, m) vertical in body axes, ``axis_enu`` (3, m), ``com_height_m``,
            ``com_velocity_m_s`` (ż), ``normal_force_N``, ``energy_J``,
            ``angular_momentum_vertical_kg_m2_s`` (n·Iw), ``quaternion_norm``.
        """
        y = np.asarray(y, dtype=float)
        _, _, N, h, zdot, n = _dynamics(y, self.surface, self.inertia, self.M, self.g, np.sqrt)
        q = y[:4]
        qn2 = np.sum(q * q, axis=0)
        qw, qx, qy, qz = q
        axis = np.array([2.0 * (qx * qz + qw * qy), 2.0 * (qy * qz - qw * qx), qw * qw - qx * qx - qy * qy + qz * qz]) / qn2
        A, B, C = self.inertia
        w = y[4:]
        rot = 0.5 * (A * w[0] ** 2 + B * w[1] ** 2 + C * w[2] ** 2)
        energy = 0.5 * self.M * zdot ** 2 + rot + self.M * self.g * h
        lz = n[0] * A * w[0] + n[1] * B * w[1] + n[2] * C * w[2]
        return {"n": np.array(n), "axis_enu": axis, "com_height_m": h, "com_velocity_m_s": zdot,
                "normal_force_N": N, "energy_J": energy, "angular_momentum_vertical_kg_m2_s": lz,
                "quaternion_norm": np.sqrt(qn2)}

    def simulate(self, t, rtol=None, atol=1e-12):
        """Integrate the exact model (DOP853) and sample at times ``t`` (s, from t[0]).

        Returns
        -------
        Simulation
            Columns as in ``COLUMNS``; ``extra`` holds ``energy_J``,
            ``angular_momentum_vertical_kg_m2_s``, ``quaternion_norm``, ``normal_force_N``,
            ``min_normal_force_N`` (negative: the body would leave the plane, outside the model)
            and ``state`` (7, m).
        """
        t = np.asarray(t, dtype=float)
        traj = integrate(self.rhs(), self.initial_state(), t, method="DOP853",
                         rtol=self.rtol if rtol is None else rtol, atol=atol)
        d = self.diagnostics(traj.y)
        n, axis = d["n"], d["axis_enu"]
        tilt = np.arctan2(np.hypot(n[0], n[1]), n[2])
        columns = {"tilt": tilt,
                   "tilt_azimuth": compass_azimuth_from_enu(axis[0], axis[1]),
                   "spin_rate": traj.y[6].copy(),
                   "com_height": d["com_height_m"],
                   "vertical_body_x": n[0], "vertical_body_y": n[1]}
        extra = {k: d[k] for k in ("energy_J", "angular_momentum_vertical_kg_m2_s", "quaternion_norm",
                                   "normal_force_N", "com_velocity_m_s")}
        extra["min_normal_force_N"] = float(np.min(d["normal_force_N"]))
        extra["state"] = traj.y
        return Simulation(t, columns, traj, extra=extra)


def _rotation_matrix(q):
    """Rotation matrix (body -> world) of the quaternion q = (w, x, y, z), normalised first."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
