"""The gimbal's equations of motion in closed form on Python floats (the fast right-hand side).

The generic :class:`~gyro_instrument.instruments.chain.HingeChain` spends ~380 µs per evaluation
on numpy calls on 3-vectors (three links, partial velocities, a 3×3 ``numpy.linalg.solve``); the
free gimbal's fast nutation (sec. 4 §V eq. 14: C ρ0 / √(a u²) ≈ 840 rad/s for the shipped rotor)
needs ~1700 DOP853 steps per simulated second at rtol 1e-11 (atol 1e-13), so the chain ran at
0.13× real time. :func:`closed_form_rhs` (~3 µs per evaluation) evaluates the same Kane equations unrolled for this chain — outer ring
about ``oz`` (inertia diag(A2, C2, A2)), inner ring about ``NN'`` (diag(A1, C1, A1)), rotor about
``oQ`` (diag(A, A, C)) — with scalar arithmetic only, and solves M q̈ = f with the closed-form
inverse of M (sec. 4 §III eq. 12, first; :func:`~.theory.free_mass_matrix`)::

    θ̈ = f_θ / (A + A1),   ψ̈ = (f_ψ − cos θ f_φ) / u²,   φ̈ = f_φ / C − cos θ ψ̈,
    u² = (A + C1) sin²θ + A1 cos²θ + A2          (det M = (A + A1) C u²).

The rotor's terms are written in the inner ring's axes (Résal's frame): for an axisymmetric rotor
its inertia, angular velocity and Kane projections are the same there as in its own axes.

Each body's inertia torque is τ = I a + w × I w + c_l L(I, w, Ω) + c_q Ω × I Ω with
L = I(Ω × w) + w × IΩ + Ω × Iw (:mod:`gyro_instrument.effects.earth_rotation`, :mod:`.centrifugal`).
The coefficients c_l, c_q are not assumed: :func:`~.torques.rigid_body_coefficients` measures them on the
instrument's active effects' own ``rigid_body_torque`` terms and refuses (returns None) when their
sum is not of that form, so an effect added later is never silently dropped — the instrument then
falls back to the chain. Hinge torques are the effects' own ``damping_torque`` / ``spin_torque``
called with floats. ``tests/test_gimbal.py`` holds this function to the chain's right-hand side at
random states to round-off, for every configuration and effect list.

The same equations as numba kernels (:mod:`.kernels`: :func:`~.kernels.free_kernel`,
:func:`~.kernels.held_kernel`, floats and a parameter array from :func:`~.kernels.kernel_params`,
hinge torques linear in the rates — the forms :func:`~.torques.linear_hinge_coefficient` measures; an effect
of another form keeps the Python closed form) run through the compiled DOP853 of
:mod:`gyro_instrument.core.dop853_jit` (``integrator: compiled``; ``auto`` for the free rings):
~90 ns per evaluation instead of ~1.5 µs of Python callback, 200-500x real time for the free rings
where the Fortran driver reaches 11-21x (``gyro-instrument bench``: ``bench.spin_gimbal``).
``tests/test_gimbal_compiled.py`` holds the kernels to the chain and the compiled to the plain function bit for bit.

Two drivers of :mod:`gyro_instrument.core` run the Python closed form (``gimbal_work_precision.csv``;
:meth:`~.runs.GimbalRuns.closed_form_run`): :class:`~gyro_instrument.core.dop853_fortran.FortranRun`,
Hairer's Fortran DOP853 from sample to sample, for the free rings (tens of steps per sample: the stage
arithmetic in Fortran halves the CPU of the Python-float driver of :mod:`gyro_instrument.core.dop853`),
and :class:`~gyro_instrument.core.integrate.Integration` with no end (scipy's DOP853 with dense output)
for the slow locked and outer-fixed swings (a step covers many samples; ``auto``'s choice there: no
numba to load).
"""

import math
from collections.abc import Callable

from gyro_instrument.instruments.gimbal.torques import linear_hinge_coefficient, rhs_inputs, torque_constants

class _Floats(tuple):
    """A tuple of floats read like a numpy array's ``tolist()`` (the free rhs's scalar entry)."""

    def tolist(self):
        return self


def _free_rhs(inputs) -> Callable:
    """:func:`closed_form_rhs` of the free rings (``inputs``: :func:`rhs_inputs`), with its
    ``on_array(t, y)`` for the Fortran driver (the hot loop of the fast nutation)."""
    (A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner) = inputs
    a_inner = A + A1
    (kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s,
     u2_c) = torque_constants(A, C, A1, C1, A2, C2, cl, cq)
    cos, sin = math.cos, math.sin
    # the torques' constants regrouped for the hot loop (rz = wz + φ̇ expanded): fewer float
    # operations per call, the same terms (the test holds it to the chain to round-off)
    k_x, l_x, k_y, l_y = kx1 + kx2, lx1 + lx2, ky1 + ky2, ly2 + lx2
    u2_0, u2_1 = u2_c + A2, u2_s - u2_c                    # u² = u2_0 + u2_1 sin²θ
    inv_inner, inv_C = -1.0 / a_inner, 1.0 / C
    # hinge torques linear in the rates (viscous pivots, bearing): their coefficients, so the
    # hot loop multiplies instead of calling each effect's term (:func:`linear_hinge_coefficient`)
    k_outer, k_inner, k_spin = (linear_hinge_coefficient(terms, j)
                                for terms, j in ((damp, J_outer), (damp, J_inner), (spin, C)))
    if None not in (k_outer, k_inner, k_spin):
        damp = spin = ()
    else:
        k_outer = k_inner = k_spin = 0.0
    has_terms = bool(damp or spin or k_outer or k_inner or k_spin)

    def on_array(t, y):
        # the state read straight from the driver's array (the free gimbal's nutation makes this
        # the hot loop: ~2e4 calls per simulated second)
        psi, theta, phi, v0, v1, v2 = y.tolist()
        cp, sp, c, s = cos(psi), sin(psi), cos(theta), sin(theta)
        oa, ob = Ox * cp + Oy * sp, Oy * cp - Ox * sp
        p2, p3 = ob * c + Oz * s, Oz * c - ob * s
        wy, wz = v0 * s, v0 * c
        cv2, lv2 = C * v2, lx2 * v2
        # −f_θ = τ·e_x (kx1 wz + A φ̇ + kx2 rz = k_x wz + C φ̇; lx1 wz + lx2 rz = l_x wz + c_l C φ̇)
        g1 = wy * (k_x * wz + cv2 + lx3 * p3) + p2 * (l_x * wz + lv2 + qx * p3)
        ty = v1 * (k_y * wz - cv2 + ly1 * p3) - oa * (l_y * wz + lv2 - qy * p3)
        tz = v1 * (kz0 * wy + lz1 * p2) + oa * (lz2 * wy + qz * p2)
        f2 = wy * (C * v1 - lx2 * oa) + lx2 * p2 * v1
        if has_terms:
            f0 = k_outer * v0 - (q0 * oa * ob + s * ty + c * tz)
            g1 -= k_inner * v1
            f2 += k_spin * v2
            for term in damp:
                f0 += term(J_outer, v0)
                g1 -= term(J_inner, v1)
            for term in spin:
                f2 += term(C, v2)
            psi_dd = (f0 - c * f2) / (u2_0 + u2_1 * s * s)
        else:                             # f_ψ − cos θ f_φ with f_ψ = −(q0 oa ob + s ty + c tz)
            psi_dd = -(q0 * oa * ob + s * ty + c * (tz + f2)) / (u2_0 + u2_1 * s * s)
        return v0, v1, v2, psi_dd, g1 * inv_inner, f2 * inv_C - c * psi_dd

    def rhs(t, *y):
        return on_array(t, _Floats(y))
    rhs.on_array = on_array
    return rhs


def closed_form_rhs(configuration, inertias, omega_base, coefficients, effects, held_angle, swing_inertias,
                    context=None) -> Callable:
    """Right-hand side ``f(t, *y) -> tuple`` of the gimbal on floats, the chain's state layout.

    Parameters
    ----------
    configuration : str
        ``free`` (y = ψ, θ, φ, ψ̇, θ̇, φ̇), ``locked`` (θ held at ``held_angle``; y = ψ, φ, ψ̇, φ̇)
        or ``outer_fixed`` (ψ held at ``held_angle``; y = θ, φ, θ̇, φ̇); rad and rad/s.
    inertias : tuple of float
        (A, C, A1, C1, A2, C2) as simulated, kg m².
    omega_base : array_like, shape (3,)
        Earth rate in Quet's base axes (``HingeChain.omega_base``), rad/s.
    coefficients : tuple of float
        (c_l, c_q) of :func:`~.torques.rigid_body_coefficients`.
    effects : iterable of Effect
        The active effects: their ``damping_torque`` act on the ring hinges (swinging inertias
        ``swing_inertias`` = (J_outer, J_inner), kg m²) and their ``spin_torque`` on the rotor's
        bearing (moment C, rate φ̇), as :func:`~gyro_instrument.instruments.chain.effect_hinge_torques`.
    held_angle : float
        The held ring's angle (Quet's θ or ψ), rad; ignored for ``free``.
    context : EffectContext, optional
        What the effects' hooks receive first (``Instrument.context``).

    Returns
    -------
    callable
        For :func:`gyro_instrument.core.integrate.integrate` with ``method="DOP853-scalar"``; the
        free configuration's also has ``on_array(t, y)`` taking the state as an ndarray (the
        Fortran driver's call, one Python frame less per evaluation).
    """
    inputs = rhs_inputs(inertias, omega_base, coefficients, effects, swing_inertias, context)
    (A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner) = inputs
    a_inner = A + A1
    (kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s,
     u2_c) = torque_constants(A, C, A1, C1, A2, C2, cl, cq)

    def forces(psi, theta, v0, v1, v2):
        """(f_ψ, f_θ, f_φ, cos θ, u²): Kane's generalised forces less the inertia terms (the hot loop).

        In the inner ring's axes (x = NN', z = oQ): the ring turns at w = (θ̇, ψ̇ sin θ, ψ̇ cos θ),
        the rotor at (θ̇, ψ̇ sin θ, ψ̇ cos θ + φ̇); Ω = (oa, p2, p3) there. τ = (tx, ty, tz) is the
        ring's and the rotor's inertia torque summed; f_ψ = −τ·(0, sin θ, cos θ) − τ_outer·e_z,
        f_θ = −τ·e_x, f_φ = −τ_rotor·e_z, plus the hinge torques."""
        cp, sp = math.cos(psi), math.sin(psi)
        c, s = math.cos(theta), math.sin(theta)
        oa, ob = Ox * cp + Oy * sp, Oy * cp - Ox * sp              # Ω, outer ring's axes
        p2, p3 = ob * c + Oz * s, Oz * c - ob * s                  # Ω, inner ring's axes
        wy, wz = v0 * s, v0 * c
        rz = wz + v2
        tx = wy * (kx1 * wz + A * v2 + kx2 * rz) + p2 * (lx1 * wz + lx2 * rz) + lx3 * p3 * wy + qx * p2 * p3
        ty = v1 * (ky1 * wz - A * v2 + ky2 * rz + ly1 * p3) - oa * (ly2 * wz + lx2 * rz - qy * p3)
        tz = v1 * (kz0 * wy + lz1 * p2) + oa * (lz2 * wy + qz * p2)
        f0 = -(q0 * oa * ob + s * ty + c * tz)
        f1 = -tx
        f2 = C * v1 * wy - lx2 * (oa * wy - p2 * v1)             # −C (a_z + c_l (Ω × w)_z), rotor
        for term in damp:
            f0 += term(J_outer, v0)
            f1 += term(J_inner, v1)
        for term in spin:
            f2 += term(C, v2)
        return f0, f1, f2, c, u2_s * s * s + u2_c * c * c + A2

    if configuration == "free":
        return _free_rhs(inputs)
    elif configuration == "locked":
        theta_held = float(held_angle)

        def rhs(t, psi, phi, v0, v2):
            f0, _, f2, c, u2 = forces(psi, theta_held, v0, 0.0, v2)
            psi_dd = (f0 - c * f2) / u2
            return v0, v2, psi_dd, f2 / C - c * psi_dd
    elif configuration == "outer_fixed":
        psi_held = float(held_angle)

        def rhs(t, theta, phi, v1, v2):
            _, f1, f2, _, _ = forces(psi_held, theta, 0.0, v1, v2)
            return v1, v2, f1 / a_inner, f2 / C
    else:
        raise ValueError(f"configuration must be free, locked or outer_fixed (got {configuration!r})")
    return rhs
