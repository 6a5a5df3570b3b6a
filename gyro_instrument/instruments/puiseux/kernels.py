"""Compiled kernels for Puiseux's body on the smooth plane (``integrator: axis_rk8``, ``rk8``, ``dop853``).

Imported lazily (by :func:`gyro_instrument.instruments.puiseux.runs.fixed_step_kernels`), never by
``import gyro_instrument``: the functions below are compiled with
:func:`gyro_instrument.core.jit.compiled` (numba, on-disk cache, no fastmath) when this module is
first imported, or left as plain Python under ``GYRO_INSTRUMENT_JIT=0``
(tests/test_puiseux_fast.py holds the two equal).

Two right-hand sides, one stepper (and the exact one for DOP853)
----------------------------------------------------------------
* :func:`body_rhs` (model 0) — the exact equations of :mod:`.dynamics` (quaternion q, body rate w;
  the general surface S, c, which holds every shape), sharing their float arithmetic
  (``vertical``, ``general_sn``, ``general_surface_terms``, ``contact_response``).
* :func:`axis_rhs` (model 1) — the exact reduction of a body of revolution (A = B, S = diag(a, a, b),
  c = (0, 0, c_z): the ellipsoid of revolution, or ρ = ρ' with equal transverse moments). The
  torque about G of the normal force N at the contact point is N κ(c) e_z × u, with u the figure
  axis in the world (ENU), c = u_z = cos θ and κ = h'(c) = (b − a) c / s − c_z,
  s = √(a (1 − c²) + b c²) (h(c) = s − c_z c the height of G): it has no component along u, so the
  spin r = w·u is constant (Puiseux eq. 6), and none along e_z, so the vertical angular momentum
  L·e_z is constant. With L = A u × u̇ + C r u (A the transverse moment) and v = u̇::

      A u × v̇ + C r v = N κ e_z × u   ⇒   v̇ = −|v|² u + (C r / A) u × v − N κ (e_z − c u) / A,
      N = M (g + z̈),  z̈ = h''(c) v_z² + κ v̇_z,  h''(c) = (b − a) a / s³,

  N solved in closed form from the linear relation: N (1 + M κ² (1 − c²)/A) = M (g + h'' v_z² +
  κ a0_z), a0 = −|v|² u + (C r/A) u × v. The state is (u, v, φ): φ the spin angle of the body
  about u relative to the minimal ("swing") rotation that takes e_z to u, φ̇ = r + e_z·(u × v)/(1 + c)
  (the swing frame turns about u at −e_z·(u × v)/(1 + c)); the orientation is
  q = q_swing(u) ⊗ (cos φ/2, 0, 0, sin φ/2). The spin r itself appears only through the
  gyroscopic term C r/A u × v: the fastest motion left is the nutation (≈ C r/A), not the spin, and
  the spin angle is a quadrature. Singular at u = −e_z (the body upside down: the swing frame then
  twists without bound), so the run stops once the tilt passes :data:`MAX_TILT_RAD`.

:func:`_exact_rhs` is :func:`body_rhs` as the right-hand side ``f(t, y, p, dy)`` of
:mod:`gyro_instrument.core.dop853_jit` (``integrator: dop853`` with numba on), compiled on first use
with that module's signature (:func:`exact_dop853_kernel`).

The stepper :func:`rk8_samples` integrates either with a fixed-step 8th-order Runge–Kutta (the
12-stage 8th-order formula of DOP853, Hairer, Nørsett & Wanner, Solving ODE I, sec. II.10: the
tableau of :mod:`gyro_instrument.core.dop853`, passed in), equal steps no longer than ``h_max`` in
each sample interval, and writes the state at every sample time. The reduced state is projected back onto
|u| = 1, u·v = 0 after every step (Hairer, Lubich & Wanner, Geometric Numerical Integration,
sec. IV.4, standard projection: the order is kept; without it the drift off the manifold grows
until the axis falls over within seconds).
"""

import math

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.instruments.puiseux import dynamics

#: Index of the right-hand side in :func:`rk8_samples`.
BODY, AXIS = 0, 1
#: Largest tilt of the reduced model's axis (rad, 170°: 1 + cos θ = 0.015 bounds the swing frame's twist rate).
MAX_TILT_RAD = math.radians(170.0)
MIN_COS_TILT = math.cos(MAX_TILT_RAD)

vertical = jit.compiled(dynamics.vertical)
general_sn = jit.compiled(dynamics.general_sn)
general_surface_terms = jit.compiled(dynamics.general_surface_terms)
contact_response = jit.compiled(dynamics.contact_response)


def _body_rhs(y, p, out):
    """Exact equations (:mod:`.dynamics`): y = (q (4), w (3)); p = (A, B, C, M, g, S_xx, S_xy, S_xz,
    S_yy, S_yz, S_zz, c_x, c_y, c_z); writes ẏ into ``out``."""
    nx, ny, nz, ndx, ndy, ndz = vertical(y[0], y[1], y[2], y[3], y[4], y[5], y[6])
    sx, sy, sz = general_sn(nx, ny, nz, p[5], p[6], p[7], p[8], p[9], p[10])
    s = math.sqrt(nx * sx + ny * sy + nz * sz)
    gx, gy, gz, _, hx, hy, hz = general_surface_terms(nx, ny, nz, ndx, ndy, ndz, sx, sy, sz, s, p[5], p[6], p[7],
                                                      p[8], p[9], p[10], p[11], p[12], p[13])
    qdot, wdot, _, _ = contact_response(y[0], y[1], y[2], y[3], y[4], y[5], y[6], nx, ny, nz, ndx, ndy, ndz,
                                        gx, gy, gz, hx, hy, hz, p[0], p[1], p[2], p[3], p[4])
    out[0], out[1], out[2], out[3] = qdot
    out[4], out[5], out[6] = wdot


def _axis_rhs(x, p, out):
    """Reduced body of revolution (module docstring): x = (u (3), v (3), φ); p = (a, b, c_z, A, C, r,
    M, g); writes ẋ into ``out``. Returns the normal force N (N)."""
    ux, uy, uz, vx, vy, vz = x[0], x[1], x[2], x[3], x[4], x[5]
    a, b, cz, A, C, r, M, g = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    c = uz
    s = math.sqrt(a * (1.0 - c * c) + b * c * c)
    kappa = (b - a) * c / s - cz
    hpp = (b - a) * a / (s * s * s)
    v2 = vx * vx + vy * vy + vz * vz
    gyro = C * r / A
    a0x = -v2 * ux + gyro * (uy * vz - uz * vy)
    a0y = -v2 * uy + gyro * (uz * vx - ux * vz)
    a0z = -v2 * uz + gyro * (ux * vy - uy * vx)
    N = M * (g + hpp * vz * vz + kappa * a0z) / (1.0 + M * kappa * kappa * (1.0 - c * c) / A)
    k = N * kappa / A
    out[0], out[1], out[2] = vx, vy, vz
    out[3] = a0x + k * c * ux
    out[4] = a0y + k * c * uy
    out[5] = a0z - k * (1.0 - c * uz)
    out[6] = r + (ux * vy - uy * vx) / (1.0 + c)
    return N


body_rhs = jit.compiled(_body_rhs)
axis_rhs = jit.compiled(_axis_rhs)


def _exact_rhs(t, y, p, dy):
    """:func:`body_rhs` as a kernel ``f(t, y, p, dy)`` of :mod:`gyro_instrument.core.dop853_jit`
    (``integrator: dop853``; the equations do not depend on t): compiled by
    :func:`exact_dop853_kernel` with :func:`~gyro_instrument.core.dop853_jit.rhs_signature`."""
    body_rhs(y, p, dy)


def exact_dop853_kernel() -> "object":
    """:func:`_exact_rhs` compiled with :func:`~gyro_instrument.core.dop853_jit.rhs_signature` (numba's
    cache), or the plain function when :func:`gyro_instrument.core.jit.enabled` is False. Call it
    through :func:`gyro_instrument.instruments.puiseux.fixed_step.dop853_kernel` (cached)."""
    from gyro_instrument.core import dop853_jit  # noqa: PLC0415
    if not jit.enabled():
        return _exact_rhs
    return jit.compiled(_exact_rhs, signature_or_function=dop853_jit.rhs_signature())


def _rhs(model, y, p, out):
    """:func:`body_rhs` (``model`` 0) or :func:`axis_rhs` (1)."""
    if model == BODY:
        body_rhs(y, p, out)
    else:
        axis_rhs(y, p, out)


rhs = jit.compiled(_rhs)


def _rk8_step(model, y, h, p, a, b, k, tmp):
    """One step of the 8th-order formula (tableau ``a`` (12, 12), weights ``b`` (12)) in place on ``y``;
    ``k`` (12, n) and ``tmp`` (n) are work arrays."""
    n = y.size
    for i in range(b.size):
        for j in range(n):
            acc = 0.0
            for m in range(i):
                acc += a[i, m] * k[m, j]
            tmp[j] = y[j] + h * acc
        rhs(model, tmp, p, k[i])
    for j in range(n):
        acc = 0.0
        for i in range(b.size):
            acc += b[i] * k[i, j]
        y[j] += h * acc


rk8_step = jit.compiled(_rk8_step)


def _project_axis(x):
    """Back onto the reduced model's manifold after a step, in place: |u| = 1, u·v = 0 (the exact
    flow keeps both; off them the ambient equations drift away, so each step is projected)."""
    norm = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    x[0], x[1], x[2] = x[0] / norm, x[1] / norm, x[2] / norm
    uv = x[0] * x[3] + x[1] * x[4] + x[2] * x[5]
    x[3], x[4], x[5] = x[3] - uv * x[0], x[4] - uv * x[1], x[5] - uv * x[2]


project_axis = jit.compiled(_project_axis)


def _rk8_samples(model, y0, t, h_max, p, a, b):
    """States at the sample times ``t`` (s; t[0] the initial time) from ``y0``: in each sample
    interval, the fewest equal steps of the 8th-order formula not longer than ``h_max`` (s). Returns (n, m). Stops (the rest NaN) at a
    non-finite state or, for the reduced model, when the tilt passes :data:`MAX_TILT_RAD` (cos θ < :data:`MIN_COS_TILT`)."""
    n, m = y0.size, t.size
    out = np.full((n, m), np.nan)
    y = y0.copy()
    k = np.empty((b.size, n))
    tmp = np.empty(n)
    for j in range(n):
        out[j, 0] = y[j]
    for i in range(1, m):
        substeps = max(1, math.ceil((t[i] - t[i - 1]) / h_max))
        h = (t[i] - t[i - 1]) / substeps
        for _ in range(substeps):
            rk8_step(model, y, h, p, a, b, k, tmp)
            if model == AXIS:
                project_axis(y)
        bad = model == AXIS and y[2] < MIN_COS_TILT
        for j in range(n):
            bad = bad or not math.isfinite(y[j])
        if bad:
            return out
        for j in range(n):
            out[j, i] = y[j]
    return out


rk8_samples = jit.compiled(_rk8_samples)
