"""Puiseux §III: a heavy body of any form on the smooth plane, GA not a principal axis.

Puiseux 1852, sec. III (J. math. pures appl. 17, pp. 22-30). G the centre of mass, A the foot of
the normal drawn from G to the surface (the contact point at rest), γ = GA; Gx, Gy, Gz the
principal axes (moments A, B, C); Aξ, Aη, Aζ the frame at A with Aζ along the normal AG and
Aξ, Aη tangent to the principal normal sections, of curvature radii ρ, ρ'. Puiseux's Euler angles
θ1 (Gz from Aζ), φ1 (from Aξ to the line of nodes of the planes Aξη, Gxy) and ψ1 (from Gx to
that line) give the direction cosines of eq. (17)::

    a1  = cos φ1 cos ψ1 − sin φ1 sin ψ1 cos θ1,   a1' = sin φ1 cos ψ1 + cos φ1 sin ψ1 cos θ1,
    a1'' = sin ψ1 sin θ1,
    b1  = −cos φ1 sin ψ1 − sin φ1 cos ψ1 cos θ1,  b1' = −sin φ1 sin ψ1 + cos φ1 cos ψ1 cos θ1,
    b1'' = cos ψ1 sin θ1,
    c1 = sin φ1 sin θ1,   c1' = −cos φ1 sin θ1,   c1'' = cos θ1,

(a1, a1', a1'') the cosines of Gx with Aξ, Aη, Aζ, and so on): in principal axes the unit
vectors are ξ̂ = (a1, b1, c1), η̂ = (a1', b1', c1'), ζ̂ = u = (a1'', b1'', c1'').

Small motions (derived here in vector form, then checked against Puiseux's printed equations in
the tests). Only small velocities are given (no finite spin, unlike sec. I-II), so the products
of rates drop and the body turns about G with potential M g h(n), h the height of G. With n the
upward vertical in body axes, n = u + ε (ε ⊥ u first order), h = γ + ½ εᵀ(R − γ)ε with R the
tensor of curvature radii (ρ along ξ̂, ρ' along η̂); ϖ = ρ − γ, ϖ' = ρ' − γ (Puiseux's names).
With φ the small rotation vector in body axes, ε = u × φ and

    I φ̈ + K φ = 0,    K = M g (ϖ' ξ̂ξ̂ᵀ + ϖ η̂η̂ᵀ),

a generalised eigenproblem with one zero root (φ ∝ u: the turn about the vertical) and two
positive roots Ω'², Ω''² when ϖ, ϖ' > 0. Writing Ω² = M g ω / C, det(ω I − C K/(Mg)) = 0 is
exactly Puiseux's equation (after eq. 25, expanded)::

    AB ω² − [BC(ϖ a1'² + ϖ' a1²) + AC(ϖ b1'² + ϖ' b1²) + AB(ϖ c1'² + ϖ' c1²)] ω
          + C ϖ ϖ' (A a1''² + B b1''² + C c1''²) = 0,

so the two swings last π√(C/(Mgω')) and π√(C/(Mgω'')) (one swing: half a period). Puiseux's
proof that the roots are real writes the middle coefficient lϖ + l'ϖ' with
l = BC a1'² + AC b1'² + AB c1'², l' = BC a1² + AC b1² + AB c1², so K = (lϖ − l'ϖ')² +
4(BC a1a1' + AC b1b1' + AB c1c1')² ϖϖ'; the transcription defines l and l' the other way round
against its own ω equation (the tests hold the equation, which the eigenproblem reproduces).
His route through P, Q, R, S and λ', λ'' (eq. 24-25, the planes' equations, Λ') gives the same
roots and planes; the transcription's expansion of Λ' drops the term A(R cos ψ1 cos θ1 −
S sin ψ1)(PR + QS), with which Λ' = Cϖϖ'(ϖ − ϖ')cos²θ1(Aa1''² + Bb1''² + Cc1''²)(BC a1a1' +
AC b1b1' + AB c1c1') holds (tests/test_puiseux_general.py).

The planes Π', Π''. A body point x (body axes, from G) rises by Z − Z1 = x·ε (G's height changes
at second order only). In mode k, ε ∥ e_k (a fixed tangent direction: no gyroscopic term, the
modes are real), so the points of the plane through GA perpendicular to e'' move in mode ' only:
that is Π' (Puiseux: its points' vertical projections swing with the duration π√(C/(Mgω'))), and
Π'' ⊥ e'. The planes are fixed in the body and depend only on its form and constitution.
Π' ⊥ Π'' iff e' ⊥ e''; the e_k are eigenvectors of J·diag(ϖ, ϖ') in the (ξ̂, η̂) basis, J the
tangent block of (u×)I⁻¹(u×)ᵀ, K-orthogonal, so they are also perpendicular iff ϖ = ϖ' (ρ = ρ') or
J is diagonal: ξ̂ᵀI⁻¹η̂ = 0, i.e. Puiseux's BC a1 a1' + AC b1 b1' + AB c1 c1' = 0 (his two cases).

The slow turning. The zero mode's coordinate grows linearly: the turn about the vertical is
χ(t) = u·φ = α t + β + k' sin(Ω' t + ε') + k'' sin(Ω'' t + ε'') (Puiseux's expression for φ), with
α = L_v / (A a1''² + B b1''² + C c1''²), L_v = n·(I w) the vertical angular momentum about G, an
exact invariant (the modes are I-orthogonal to u). Without friction it grows without bound.

The contact point. Near A the surface is ζ = ξ²/(2ρ) + η²/(2ρ'); its normal is vertical where
ξ = −ρ ε_ξ, η = −ρ' ε_η (eq. 21 in vector form), ε_ξ = ξ̂·ε, ε_η = η̂·ε; on the plane, relative to
the vertical through G, the contact point is at −ϖ ε_ξ, −ϖ' ε_η along the rest directions of
Aξ, Aη (first order; G moves only vertically, eqs. 1-2 with no initial horizontal velocity).
"""

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh


def normal_frame(phi1_rad, theta1_rad, psi1_rad) -> np.ndarray:
    """Puiseux's direction cosines (eq. 17) as a rotation matrix.

    Parameters
    ----------
    phi1_rad, theta1_rad, psi1_rad : float
        φ1, θ1, ψ1 (Puiseux 1852, sec. III), rad.

    Returns
    -------
    ndarray (3, 3)
        P with rows ξ̂, η̂, ζ̂ in principal axes: [[a1, b1, c1], [a1', b1', c1'], [a1'', b1'', c1'']],
        so that (ξ, η, ζ − γ) = P (x, y, z) for a point at (x, y, z) from G (the substitution after
        eq. 18). A proper rotation (relations 18).
    """
    cf, sf = math.cos(phi1_rad), math.sin(phi1_rad)
    ct, st = math.cos(theta1_rad), math.sin(theta1_rad)
    cp, sp = math.cos(psi1_rad), math.sin(psi1_rad)
    a1, a1p, a1pp = cf * cp - sf * sp * ct, sf * cp + cf * sp * ct, sp * st
    b1, b1p, b1pp = -cf * sp - sf * cp * ct, -sf * sp + cf * cp * ct, cp * st
    c1, c1p, c1pp = sf * st, -cf * st, ct
    return np.array([[a1, b1, c1], [a1p, b1p, c1p], [a1pp, b1pp, c1pp]])


def puiseux_omega_quadratic(A, B, C, w, wp, P) -> tuple:
    """Coefficients (a, b, c) of Puiseux's printed equation a ω² − b ω + c = 0 (sec. III, after eq. 25).

    ``w``, ``wp`` are ϖ = ρ − γ, ϖ' = ρ' − γ (m); ``P`` from :func:`normal_frame`. Units: kg² m⁴,
    kg² m⁵, kg² m⁶ (ω in metres).
    """
    (a1, b1, c1), (a1p, b1p, c1p), (a1pp, b1pp, c1pp) = P
    a = A * B
    b = (B * C * (w * a1p ** 2 + wp * a1 ** 2) + A * C * (w * b1p ** 2 + wp * b1 ** 2)
         + A * B * (w * c1p ** 2 + wp * c1 ** 2))
    c = C * w * wp * (A * a1pp ** 2 + B * b1pp ** 2 + C * c1pp ** 2)
    return a, b, c


def inertia_conjugacy(A, B, C, P) -> float:
    """Puiseux's BC a1 a1' + AC b1 b1' + AB c1 c1' (kg² m⁴; = ABC ξ̂ᵀI⁻¹η̂): the planes Π', Π''
    are perpendicular when it vanishes or when ρ = ρ' (sec. III, last page)."""
    (a1, b1, c1), (a1p, b1p, c1p), _ = P
    return B * C * a1 * a1p + A * C * b1 * b1p + A * B * c1 * c1p


@dataclass(frozen=True)
class GeneralModes:
    """The small motions of Puiseux's general body (sec. III); see the module docstring.

    Attributes
    ----------
    omega_m : tuple of float
        Puiseux's roots ω' ≤ ω'' (m).
    frequencies_rad_s : tuple of float
        Ω = √(M g ω / C) (rad/s), ascending.
    swing_durations_s : tuple of float
        π √(C/(M g ω)) (s): one swing, half a period, Puiseux's "durée des oscillations".
    rotations : ndarray (3, 3)
        Columns: the I-normalised modal rotation vectors in body axes, the zero mode u/√(uᵀIu) first.
    tilt_directions : ndarray (2, 2)
        Rows: the unit tilt directions e', e'' in the (ξ̂, η̂) basis.
    plane_angles_rad : tuple of float
        Angle from Aξ toward Aη of the trace of Π' (swinging at Ω') and of Π'' on the tangent
        plane, in [0, π).
    angle_between_planes_rad : float
        In [0, π/2].
    inertia_about_normal_kg_m2 : float
        A a1''² + B b1''² + C c1''² (the moment about GA).
    """

    omega_m: tuple
    frequencies_rad_s: tuple
    swing_durations_s: tuple
    rotations: np.ndarray
    tilt_directions: np.ndarray
    plane_angles_rad: tuple
    angle_between_planes_rad: float
    inertia_about_normal_kg_m2: float


def general_modes(inertia, M, g, rho, rho_prime, gamma, P) -> GeneralModes:
    """Modes of the linearised general body (Puiseux 1852, sec. III).

    Parameters
    ----------
    inertia : sequence of 3 float
        A, B, C, kg m².
    M, g : float
        Mass (kg), gravity (m/s²).
    rho, rho_prime : float
        Principal curvature radii at A along Aξ, Aη, m.
    gamma : float
        GA, m; must be below both radii (stable equilibrium; the caller checks).
    P : ndarray (3, 3)
        :func:`normal_frame`.

    Returns
    -------
    GeneralModes
    """
    A, B, C = inertia
    I = np.diag([A, B, C])
    xi, eta, u = P
    w, wp = rho - gamma, rho_prime - gamma
    K = M * g * (wp * np.outer(xi, xi) + w * np.outer(eta, eta))
    vals, vecs = eigh(K, I)
    iu = float(u @ I @ u)
    order = np.argsort(vals)
    vecs = vecs[:, order]
    vecs[:, 0] = u / math.sqrt(iu)                           # the zero mode, exactly
    om2 = np.maximum(vals[order][1:], 0.0)
    freqs = tuple(float(x) for x in np.sqrt(om2))
    tilts = []
    for k in (1, 2):
        eps = np.cross(u, vecs[:, k])
        e = np.array([eps @ xi, eps @ eta])
        tilts.append(e / np.linalg.norm(e))
    tilts = np.array(tilts)
    # Π' (mode ') is perpendicular to e'': its trace on the tangent plane is e'' turned by 90°
    angles = tuple(float(np.mod(math.atan2(tilts[1 - k][1], tilts[1 - k][0]) + 0.5 * math.pi, math.pi))
                   for k in (0, 1))
    between = abs(angles[0] - angles[1])
    between = float(min(between, math.pi - between))
    return GeneralModes(tuple(C * x / (M * g) for x in om2), freqs,
                        tuple(math.pi / f if f > 0 else math.inf for f in freqs), vecs, tilts, angles,
                        between, iu)


def linear_rotation(modes, t, phi0, phidot0) -> np.ndarray:
    """Small rotation vector φ(t) in body axes from φ(0), φ̇(0) (sec. III, first order).

    Parameters
    ----------
    modes : GeneralModes
    t : ndarray (m,)
        Times, s.
    phi0, phidot0 : array (3,)
        Initial rotation vector (rad) and its rate (rad/s) in body axes, from the rest orientation.

    Returns
    -------
    ndarray (3, m)
        φ(t): the two swings plus the zero mode growing as its initial rate times t.
    """
    V = modes.rotations
    t = np.asarray(t, dtype=float)
    Vinv = np.linalg.inv(V)                # = Vᵀ I: modal coordinates
    q0, qd0 = Vinv @ np.asarray(phi0, dtype=float), Vinv @ np.asarray(phidot0, dtype=float)
    out = np.outer(V[:, 0], q0[0] + qd0[0] * t)
    for k, om in zip((1, 2), modes.frequencies_rad_s):
        out += np.outer(V[:, k], q0[k] * np.cos(om * t) + qd0[k] / om * np.sin(om * t))
    return out
