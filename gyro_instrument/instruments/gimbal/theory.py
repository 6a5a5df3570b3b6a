"""Quet's theory of the two-ring gimbal gyroscope (Quet 1853, sec. 4 §III–V): the swing
durations T, T', T'', T''', the locked-ring inertia, the exact small-oscillation constants, the
free gimbal's mass matrix and the integrals (12), (13) and §V (2).

Axes and angles as in :mod:`gyro_instrument.instruments.gimbal.instrument`: ``oz`` along ``PP'``,
k = n cos ω, k' = n sin ω (sec. 4 eq. 11), θ the inner ring's angle, ψ the outer ring's.

Periods (every "T" is one swing, HALF the period, π/√K)
-------------------------------------------------------
Locked rings: the swinging inertia about ``PP'`` is A (rotor) + C1 (inner ring, whose figure
axis ``oD`` is then along ``PP'``) + A2. Quet's eq. (14) writes A + 2A1 + A2, which is exact
for thin rings only (C1 = 2A1): eq. (11) gives u² = b sin²θ + γ = A + C1 + A2 at θ = 90°, so
the printed (14) has silently put C1 = 2A1. Outer ring fixed: the swinging inertia about
``NN'`` is A + A1 (exact for any ring). Hence::

    T   = π √((A + C1 + A2) / (C n ρ0 sin ω))      (Quet: A + 2A1 + A2)
    T'  = π √((A + C1 + A2) / (C n ρ0 cos γ))      PP' vertical, sin ω = cos γ
    T'' = π √((A + A1) / (C n ρ0))                  outer ring fixed across the meridian
    T'''= π √((A + C1 + A2) / (C n ρ0))            PP' horizontal east–west, sin ω = 1

With both ``earth_rotation`` and ``centrifugal`` the chain is the exact rigid-body motion;
the small-oscillation constant then gains O(n²) terms (derived from the Routhian, see
:func:`locked_swing_constant` and :func:`outer_fixed_swing_constant`) whose relative size is
~ n / (μ ρ0) ≈ 1e-7.

Invariants (used by the tests)
------------------------------
(13) d(ρ − k cos θ + k' sin θ sin ψ) = 0 is exact: it is the constancy of the rotor's absolute
spin ρ + Ω·oQ (axisymmetric rotor, frictionless bearing). (12, first) a θ̇² + u² ψ̇² + Cρ²
= const is twice the relative kinetic energy; it drops the O(n²) centrifugal potential, the
exact (Jacobi) integral being T_rel − ½ Σ Ωᵀ I Ω. With ``PP'`` along Earth's axis (§V, k' = 0)
the second of (12) integrates to u²ψ̇ + Cρ cos θ − k(b − C) sin²θ = const (§V eq. 2), the
absolute angular momentum about ``PP'`` (exact).
"""

import math

import numpy as np


def swing_inertias_kg_m2(A, A1, C1, A2) -> tuple:
    """Swinging inertias of Quet sec. 4 §IV, kg m².

    Returns
    -------
    tuple of float
        (J_quet, J_thick, J_fixed): the locked rings about ``PP'`` in Quet's printed form
        A + 2A1 + A2 (eq. 14, thin rings) and in the correct form A + C1 + A2; the outer ring
        fixed, about ``NN'``: A + A1.
    """
    return A + 2.0 * A1 + A2, A + C1 + A2, A + A1


def swing_duration_s(inertia_kg_m2, axial_inertia_kg_m2, earth_rate_component_rad_s,
                     spin_rad_s) -> float:
    """One swing (half period) of small oscillations, T = π √(J / (C n ρ0 sin ω)).

    Quet 1853 sec. 4 §IV (T, T', T'', T''' differ only in J and in the Earth-rate component
    n sin ω). Returns ``inf`` when there is no restoring torque about the reference line.

    Parameters
    ----------
    inertia_kg_m2 : float
        Swinging inertia J, kg m².
    axial_inertia_kg_m2 : float
        Rotor's axial moment C, kg m².
    earth_rate_component_rad_s : float
        Component of the Earth rate along the equilibrium line (n sin ω, n cos γ, n, ...), rad/s.
    spin_rad_s : float
        Relative spin ρ0, rad/s.
    """
    K = axial_inertia_kg_m2 * earth_rate_component_rad_s * spin_rad_s / inertia_kg_m2
    return math.pi / math.sqrt(K) if K > 0.0 else math.inf


def quet_swing_durations_s(J_quet, J_thick, J_fixed, C, rho0, n, k_prime, cos_latitude) -> dict:
    """Quet's four swing durations (sec. 4 §IV, one swing each) in the printed and thick-ring forms, s.

    Parameters
    ----------
    J_quet, J_thick, J_fixed : float
        The swinging inertias of :func:`swing_inertias_kg_m2`, kg m².
    C : float
        Rotor's axial moment, kg m².
    rho0 : float
        Relative spin, rad/s.
    n, k_prime : float
        Earth rate and its component n sin ω across ``PP'`` (0 for a non-rotating Earth), rad/s.
    cos_latitude : float
        cos γ of the site.

    Returns
    -------
    dict
        ``T_quet_s``/``T_thick_s`` (this PP', rate k'), ``T_prime_*`` (PP' vertical, n cos γ),
        ``T_third_*`` (PP' east–west, n), with J_quet / J_thick; ``T_second_quet_s`` =
        ``T_second_thick_s`` (outer ring fixed across the meridian, J_fixed, n).
    """
    out = {}
    for key, rate in (("T", k_prime), ("T_prime", n * cos_latitude), ("T_third", n)):
        out[f"{key}_quet_s"] = swing_duration_s(J_quet, C, rate, rho0)
        out[f"{key}_thick_s"] = swing_duration_s(J_thick, C, rate, rho0)
    out["T_second_quet_s"] = out["T_second_thick_s"] = swing_duration_s(J_fixed, C, n, rho0)
    return out


def locked_swing_constant(A, C, C1, A2, C2, k_prime, rho_eq) -> float:
    """Exact small-oscillation constant K (v'' = −K v) of the locked gimbal, s⁻².

    Routhian of the rigid assembly turning about ``PP'`` with the rotor's absolute spin
    s = ρ + k' cos v conserved (v = ``outer_angle``); inner ring locked at θ = 90°, so ``oQ``
    lies along the outer ring's figure axis and ``oD`` along ``PP'``::

        K = [C ρ_eq k' + (C + C2 − A − A2) k'²] / (A + C1 + A2)

    The first term is Quet's eq. (14) (thick-ring inertia); the second is the O(n²) term
    that eq. (14) drops (with massless rings it is the directing-plane (μ − 1) n² sin² ω).

    Parameters
    ----------
    A, C : float
        Rotor's transverse and axial moments, kg m².
    C1 : float
        Inner ring's moment about its figure axis ``oD``, kg m².
    A2, C2 : float
        Outer ring's moments about a diameter (``PP'``, ``NN'``) and about its figure axis.
    k_prime : float
        n sin ω, rad/s.
    rho_eq : float
        Relative spin at the equilibrium line, rad/s.
    """
    return (C * rho_eq * k_prime + (C + C2 - A - A2) * k_prime ** 2) / (A + C1 + A2)


def outer_fixed_swing_constant(A, C, A1, C1, m_rate, rho_eq) -> float:
    """Exact small-oscillation constant K of the inner swing with the outer ring fixed, s⁻².

    The rotor and inner ring turn about ``NN'`` (a principal axis of both), ``oQ`` in the
    plane perpendicular to ``NN'``; m_rate = n·|projection of Earth's axis on that plane|::

        K = [C ρ_eq m + (C + A1 − A − C1) m²] / (A + A1)

    First term: Quet's T'' (sec. 4 §IV, with m = n); second: the dropped O(n²) term.
    """
    return (C * rho_eq * m_rate + (C + A1 - A - C1) * m_rate ** 2) / (A + A1)


def free_mass_matrix(A, C, A1, C1, A2, theta) -> np.ndarray:
    """Mass matrix of the free gimbal in (ψ, θ, φ), kg m² (from eq. 12, first; equal to
    :meth:`~gyro_instrument.instruments.gimbal.instrument.GimbalGyroscope.mass_matrix` to rounding)::

        [[u² + C cos²θ, 0, C cos θ], [0, a, 0], [C cos θ, 0, C]],  a = A + A1,
        u² = (A + C1 − A1) sin²θ + A1 + A2 = (A + C1) sin²θ + A1 cos²θ + A2.

    det M = a C u², so with A, C > 0 it is singular exactly when A2 = 0, A1 = 0 and sin θ = 0:
    massless rings (``ring_inertia`` absent, or both diametral moments 0) with the rotor axis
    along ``PP'`` (gimbal lock, inner_angle = ±90°). It does not depend on ψ, φ or C2.
    """
    c, s2 = math.cos(theta), math.sin(theta) ** 2
    u2 = (A + C1) * s2 + A1 * c * c + A2
    return np.array([[u2 + C * c * c, 0.0, C * c], [0.0, A + A1, 0.0], [C * c, 0.0, C]])


def spin_invariant(rho, theta, psi, k, k_prime) -> np.ndarray | float:
    """Quet's eq. (13): ρ − k cos θ + k' sin θ sin ψ (rad/s), constant without bearing torque.

    It is ρ + Ω·oQ, the rotor's absolute spin, with Ω = (k', 0, −k) and
    oQ = (sin θ sin ψ, −sin θ cos ψ, cos θ) in Quet's axes.
    """
    return rho - k * np.cos(theta) + k_prime * np.sin(theta) * np.sin(psi)


def quet_energy(theta, theta_dot, psi_dot, rho, A, C, A1, C1, A2) -> np.ndarray | float:
    """Quet's eq. (12, first): a θ̇² + u² ψ̇² + C ρ² (J, twice the relative kinetic energy).

    a = A + A1, b = A + C1 − A1, γ = A1 + A2, u² = b sin²θ + γ (eq. 11).
    """
    a = A + A1
    u2 = (A + C1 - A1) * np.sin(theta) ** 2 + A1 + A2
    return a * theta_dot ** 2 + u2 * psi_dot ** 2 + C * rho ** 2


def axial_momentum(theta, psi_dot, rho, k, A, C, A1, C1, A2) -> np.ndarray | float:
    """§V eq. (2, second): u² ψ̇ + C ρ cos θ − k (b − C) sin² θ, kg m²/s.

    The absolute angular momentum about ``PP'`` less a constant; conserved when ``PP'`` is
    parallel to Earth's axis (k' = 0). b = A + C1 − A1.
    """
    b = A + C1 - A1
    u2 = b * np.sin(theta) ** 2 + A1 + A2
    return u2 * psi_dot + C * rho * np.cos(theta) - k * (b - C) * np.sin(theta) ** 2
