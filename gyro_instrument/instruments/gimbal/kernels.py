"""The gimbal's equations of motion as numba kernels: the compiled right-hand side of ``integrator: compiled``.

:func:`free_kernel` (the free rings) and :func:`held_kernel` (``locked``, ``outer_fixed``) are the
arithmetic of :func:`~.dynamics.closed_form_rhs` (Quet 1853 sec. 4 §III eq. 12, first; the Kane
equations unrolled for this chain, :mod:`.dynamics`) as right-hand sides ``f(t, y, p, dy)`` of
:mod:`gyro_instrument.core.dop853_jit`, on floats and a parameter array from :func:`kernel_params`,
with the hinge torques linear in the rates (the forms :func:`~.torques.linear_hinge_coefficient`
measures; an effect of another form keeps the Python closed form). :func:`compiled_kernel` compiles
them lazily through :func:`gyro_instrument.core.jit.compiled` (numba's on-disk cache, no fastmath),
or returns the plain functions under ``GYRO_INSTRUMENT_JIT=0``: nothing here imports numba at
import time. ``tests/test_gimbal_compiled.py`` holds the kernels to the chain and the compiled to the
plain function bit for bit.
"""

import functools
import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.instruments.gimbal.torques import linear_hinge_coefficient, rhs_inputs, torque_constants


def free_kernel(t, y, p, dy) -> None:
    """The free rings' right-hand side as a numba kernel (:mod:`gyro_instrument.core.dop853_jit`'s
    ``f(t, y, p, dy)``): the arithmetic of :func:`~.dynamics._free_rhs` with the hinge torques linear in the
    rates (``p``: :func:`kernel_params`; y = ψ, θ, φ, ψ̇, θ̇, φ̇ in rad, rad/s)."""
    (C, Ox, Oy, Oz, k_x, l_x, lx3, qx, k_y, ly1, l_y, lx2, qy, kz0, lz1, lz2, qz, q0, u2_0, u2_1,
     inv_inner, inv_C, k_outer, k_inner, k_spin) = (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9],
                                                    p[10], p[11], p[12], p[13], p[14], p[15], p[16], p[17],
                                                    p[18], p[19], p[20], p[21], p[22], p[23], p[24])
    psi, theta, v0, v1, v2 = y[0], y[1], y[3], y[4], y[5]
    cp, sp, c, s = math.cos(psi), math.sin(psi), math.cos(theta), math.sin(theta)
    oa, ob = Ox * cp + Oy * sp, Oy * cp - Ox * sp
    p2, p3 = ob * c + Oz * s, Oz * c - ob * s
    wy, wz = v0 * s, v0 * c
    cv2, lv2 = C * v2, lx2 * v2
    g1 = wy * (k_x * wz + cv2 + lx3 * p3) + p2 * (l_x * wz + lv2 + qx * p3) - k_inner * v1
    ty = v1 * (k_y * wz - cv2 + ly1 * p3) - oa * (l_y * wz + lv2 - qy * p3)
    tz = v1 * (kz0 * wy + lz1 * p2) + oa * (lz2 * wy + qz * p2)
    f2 = wy * (C * v1 - lx2 * oa) + lx2 * p2 * v1 + k_spin * v2
    f0 = k_outer * v0 - (q0 * oa * ob + s * ty + c * tz)
    psi_dd = (f0 - c * f2) / (u2_0 + u2_1 * s * s)
    dy[0], dy[1], dy[2] = v0, v1, v2
    dy[3], dy[4], dy[5] = psi_dd, g1 * inv_inner, f2 * inv_C - c * psi_dd


def held_kernel(t, y, p, dy) -> None:
    """The locked (p[0] = 1: y = ψ, φ, ψ̇, φ̇) or outer-fixed (p[0] = 2: y = θ, φ, θ̇, φ̇) gimbal's
    right-hand side as a numba kernel: :func:`~.dynamics.closed_form_rhs`'s ``forces`` with the hinge torques
    linear in the rates (``p``: :func:`kernel_params`; p[1] the held angle, rad)."""
    (held, A, C, Ox, Oy, Oz, kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0,
     u2_s, u2_c, A2, a_inner, k_outer, k_inner, k_spin) = (
        p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11], p[12], p[13], p[14], p[15], p[16],
        p[17], p[18], p[19], p[20], p[21], p[22], p[23], p[24], p[25], p[26], p[27], p[28], p[29])
    locked = p[0] == 1.0
    psi, theta = (y[0], held) if locked else (held, y[0])
    v0, v1, v2 = (y[2], 0.0, y[3]) if locked else (0.0, y[2], y[3])
    cp, sp, c, s = math.cos(psi), math.sin(psi), math.cos(theta), math.sin(theta)
    oa, ob = Ox * cp + Oy * sp, Oy * cp - Ox * sp
    p2, p3 = ob * c + Oz * s, Oz * c - ob * s
    wy, wz = v0 * s, v0 * c
    rz = wz + v2
    tx = wy * (kx1 * wz + A * v2 + kx2 * rz) + p2 * (lx1 * wz + lx2 * rz) + lx3 * p3 * wy + qx * p2 * p3
    ty = v1 * (ky1 * wz - A * v2 + ky2 * rz + ly1 * p3) - oa * (ly2 * wz + lx2 * rz - qy * p3)
    tz = v1 * (kz0 * wy + lz1 * p2) + oa * (lz2 * wy + qz * p2)
    f0 = -(q0 * oa * ob + s * ty + c * tz) + k_outer * v0
    f1 = -tx + k_inner * v1
    f2 = C * v1 * wy - lx2 * (oa * wy - p2 * v1) + k_spin * v2
    dy[0], dy[1] = y[2], y[3]
    if locked:
        psi_dd = (f0 - c * f2) / (u2_s * s * s + u2_c * c * c + A2)
        dy[2], dy[3] = psi_dd, f2 / C - c * psi_dd
    else:
        dy[2], dy[3] = f1 / a_inner, f2 / C


#: The kernels by the name :func:`kernel_params` gives.
KERNELS = {"free": free_kernel, "held": held_kernel}


@functools.cache
def compiled_kernel(name) -> Callable:
    """:data:`KERNELS` [``name``] compiled with :func:`~gyro_instrument.core.dop853_jit.rhs_signature`
    (numba's cache: ~0.05 s to load), or the plain function when :func:`gyro_instrument.core.jit.enabled`
    is False."""
    from gyro_instrument.core import dop853_jit, jit
    if not jit.enabled():
        return KERNELS[name]
    return jit.compiled(KERNELS[name], signature_or_function=dop853_jit.rhs_signature())


def kernel_params(configuration, inertias, omega_base, coefficients, effects, held_angle, swing_inertias,
                  context=None) -> "tuple | None":
    """("free" or "held", p): the kernel and its parameter array for the arguments of
    :func:`~.dynamics.closed_form_rhs`; None when an effect's hinge torque is not linear in its rate
    (:func:`~.torques.linear_hinge_coefficient`), which only the Python closed form calls."""
    inputs = rhs_inputs(inertias, omega_base, coefficients, effects, swing_inertias, context)
    (A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner) = inputs
    ks = [linear_hinge_coefficient(terms, j) for terms, j in ((damp, J_outer), (damp, J_inner), (spin, C))]
    if None in ks:
        return None
    (kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s,
     u2_c) = torque_constants(A, C, A1, C1, A2, C2, cl, cq)
    if configuration == "free":
        p = (C, Ox, Oy, Oz, kx1 + kx2, lx1 + lx2, lx3, qx, ky1 + ky2, ly1, ly2 + lx2, lx2, qy, kz0, lz1, lz2, qz,
             q0, u2_c + A2, u2_s - u2_c, -1.0 / (A + A1), 1.0 / C, *ks)
        return "free", np.array(p, dtype=float)
    code = {"locked": 1.0, "outer_fixed": 2.0}[configuration]
    p = (code, float(held_angle), A, C, Ox, Oy, Oz, kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2,
         qx, qy, qz, q0, u2_s, u2_c, A2, A + A1, *ks)
    return "held", np.array(p, dtype=float)
