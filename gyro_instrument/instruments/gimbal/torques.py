"""The gimbal's torques reduced to constants: what the closed form on floats (:mod:`.dynamics`) and its
numba kernels (:mod:`.kernels`) both evaluate.

Each body's inertia torque is τ = I a + w × I w + c_l L(I, w, Ω) + c_q Ω × I Ω with
L = I(Ω × w) + w × IΩ + Ω × Iw (:mod:`gyro_instrument.effects.earth_rotation`, :mod:`.centrifugal`).
:func:`rigid_body_coefficients` measures c_l, c_q on the active effects' own ``rigid_body_torque``
terms (None when their sum is not of that form); :func:`linear_hinge_coefficient` measures a hinge
torque's coefficient when it is linear in its rate; :func:`rhs_inputs` and :func:`torque_constants`
give the closed form's arguments as floats and its unrolled torques' constants by monomial (Quet 1853
sec. 4 §III eq. 12, first; the Kane equations unrolled for the gimbal's chain, :mod:`.dynamics`).
"""

import numpy as np

from gyro_instrument.core.effect import DAMPING, RIGID_BODY, SPIN, bound_hooks

#: Relative residual above which the active effects' rigid-body torques are not c_l L + c_q Q
#: (the probes are O(1) numbers; a sum of the two exact forms agrees to ~1e-16).
_FORM_TOLERANCE = 1e-12


def _linear(I, w, om):
    """The inertia torque's part linear in Ω: I(Ω × w) + w × IΩ + Ω × Iw (body axes)."""
    return I @ np.cross(om, w) + np.cross(w, I @ om) + np.cross(om, I @ w)


def _quadratic(I, om):
    """The inertia torque's part quadratic in Ω: Ω × IΩ (body axes)."""
    return np.cross(om, I @ om)


def rigid_body_coefficients(effects, context=None) -> tuple | None:
    """(c_l, c_q) with Σ rigid_body_torque(I, w, Ω) = c_l L(I, w, Ω) + c_q Ω × IΩ over ``effects``.

    Measured on the effects' own terms at fixed O(1) probes (a full inertia tensor, angular
    velocity and frame rate), then checked at two more probes (another state, and Ω tripled so a
    term of another degree in Ω shows). ``earth_rotation`` gives (1, 0), ``centrifugal`` (0, 1),
    both (1, 1), none (0, 0). ``context``: the EffectContext the hooks receive.

    Returns
    -------
    tuple of float or None
        None when the sum is not of that form to :data:`_FORM_TOLERANCE` (relative).
    """
    terms = bound_hooks(effects, RIGID_BODY, context)
    I = np.array([[2.0, 0.3, -0.2], [0.3, 1.5, 0.1], [-0.2, 0.1, 1.1]])

    def total(w, om):
        out = np.zeros(3)
        for term in terms:
            out = out + np.asarray(term(I, w, om), dtype=float)
        return out
    w, om = np.array([0.7, -1.3, 2.1]), np.array([0.4, 0.9, -0.6])
    S0 = total(np.zeros(3), om)                   # the linear part vanishes at w = 0
    Q, L = _quadratic(I, om), _linear(I, w, om)
    cq = float(S0 @ Q / (Q @ Q))
    cl = float((total(w, om) - S0) @ L / (L @ L))
    # an integer (each effect contributes its term once) is recovered exactly, not to round-off
    cq, cl = (float(round(c)) if abs(c - round(c)) < _FORM_TOLERANCE else c for c in (cq, cl))
    for w2, om2 in ((np.array([-1.1, 0.4, 0.8]), np.array([-0.5, 0.2, 1.3])), (w, 3.0 * om)):
        want = cl * _linear(I, w2, om2) + cq * _quadratic(I, om2)
        got = total(w2, om2)
        if np.max(np.abs(got - want)) > _FORM_TOLERANCE * max(1.0, float(np.max(np.abs(want)))):
            return None
    return cl, cq




#: Rates (rad/s) at which :func:`linear_hinge_coefficient` checks a hinge torque's linearity.
_RATE_PROBES = (-3.7, 0.25, 1.3e3)


def linear_hinge_coefficient(terms, inertia) -> float | None:
    """k with Σ term(inertia, q̇) = k q̇ over the hinge ``terms`` (each ``term(J, q̇) -> N m``), or None.

    Measured on the effects' own terms at q̇ = 1 rad/s and checked at :data:`_RATE_PROBES` to
    :data:`_FORM_TOLERANCE` (relative), as :func:`rigid_body_coefficients` does for the rigid-body
    torques: a viscous pivot or bearing (``pivot_damping``, ``spin_decay``) is linear, and the hot
    loop then multiplies instead of calling every term; a term of another form is called as is.
    No terms: 0.0. ``inertia``: J (kg m²) passed to the terms."""
    if not terms:
        return 0.0
    k = sum(float(term(inertia, 1.0)) for term in terms)
    for rate in _RATE_PROBES:
        got = sum(float(term(inertia, rate)) for term in terms)
        if abs(got - k * rate) > _FORM_TOLERANCE * max(abs(k * rate), abs(got), 1e-300):
            return None
    return k


def rhs_inputs(inertias, omega_base, coefficients, effects, swing_inertias, context=None) -> tuple:
    """:func:`closed_form_rhs`'s arguments as Python floats, flat: (A, C, A1, C1, A2, C2) the
    inertias, (Ox, Oy, Oz) the Earth rate, (c_l, c_q) the coefficients, the effects' damping and
    spin hinge terms (their hooks with ``context`` bound), and the swinging inertias (J_outer, J_inner)."""
    A, C, A1, C1, A2, C2 = (float(v) for v in inertias)
    Ox, Oy, Oz = (float(v) for v in omega_base)
    cl, cq = (float(v) for v in coefficients)
    effects = list(effects)
    damp = bound_hooks(effects, DAMPING, context)
    spin = bound_hooks(effects, SPIN, context)
    J_outer, J_inner = (float(v) for v in swing_inertias)
    return A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner


def torque_constants(A, C, A1, C1, A2, C2, cl, cq) -> tuple:
    """The constants of :func:`closed_form_rhs`'s unrolled torques, by monomial, from the inertias
    (kg m²) and the coefficients (c_l, c_q) of :func:`rigid_body_coefficients`: the k (inertia and
    gyroscopic terms), l (c_l terms) and q (c_q terms) factors and the (u2_s, u2_c) of the
    effective moment about the outer hinge, as one flat tuple in that order."""
    # Constants of the unrolled torques τ = I a + w × I w + c_l L(I, w, Ω) + c_q Ω × IΩ of the inner
    # ring, diag(A1, C1, A1), plus that of the rotor, diag(A, A, C), both in the inner ring's axes,
    # collected by monomial (the outer ring enters through τ·e_z only). I a + w × I w:
    kx1, kx2, ky1, ky2, kz0 = A1 - C1, C - A, C1 + A, A - C, C1 - 2.0 * A1 - C
    # c_l [I(Ω × w) + w × IΩ + Ω × Iw]:
    lx1, lx2, lx3 = cl * (2.0 * A1 - C1), cl * C, cl * (C - 2.0 * A - C1)
    ly1, ly2 = cl * (C1 + 2.0 * A - C), cl * C1
    lz1, lz2 = cl * (C1 - 2.0 * A1 - C), cl * (C1 + C)
    # c_q Ω × IΩ:
    qx, qy, qz, q0 = cq * (A1 - C1 + C - A), cq * (A - C), cq * (C1 - A1), cq * (C2 - A2)
    u2_s, u2_c = A + C1, A1
    return kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s, u2_c
