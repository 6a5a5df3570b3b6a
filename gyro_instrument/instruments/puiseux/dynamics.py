"""The exact rigid body on a smooth horizontal plane (Puiseux 1852, eqs. 1-6; no approximation).

Notation as in :mod:`gyro_instrument.instruments.puiseux`; the surface is an
:class:`~gyro_instrument.instruments.puiseux.surface.EllipsoidSurface`.

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
"""

import math

import numpy as np


def contact_dynamics(y, surf, inertia, M, g, sqrt) -> tuple:
    """Shared core of the right-hand side and of the diagnostics (scalar or array ``y``).

    ``y`` = [q_w, q_x, q_y, q_z, w_x, w_y, w_z] (quaternion body -> world, body rate); ``surf`` an
    :class:`~gyro_instrument.instruments.puiseux.surface.EllipsoidSurface`; ``sqrt`` is ``math.sqrt``
    for one state and ``numpy.sqrt`` for a history (shape (7, m)).

    Returns q̇ (4), ẇ (3), the normal force N (N), h (m), ż (m/s) and n (3).
    """
    qw, qx, qy, qz, wx, wy, wz = y
    A, B, C = inertia
    sxx, sxy, syy, szz, cz = surf.sxx, surf.sxy, surf.syy, surf.szz, surf.cz
    nx, ny, nz, ndx, ndy, ndz = vertical(qw, qx, qy, qz, wx, wy, wz)
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
    qdot, wdot, N, zdot = contact_response(qw, qx, qy, qz, wx, wy, wz, nx, ny, nz, ndx, ndy, ndz,
                                            gx, gy, gz, hx, hy, hz, A, B, C, M, g)
    return qdot, wdot, N, h, zdot, (nx, ny, nz)


def vertical(qw, qx, qy, qz, wx, wy, wz) -> tuple:
    """The upward vertical n in body axes (third row of R(q/|q|), body -> world) and its rate
    ṅ = n × w (n fixed in space, seen from the body): (nx, ny, nz, ṅx, ṅy, ṅz)."""
    nq = qw * qw + qx * qx + qy * qy + qz * qz
    nx = 2.0 * (qx * qz - qw * qy) / nq
    ny = 2.0 * (qy * qz + qw * qx) / nq
    nz = (qw * qw - qx * qx - qy * qy + qz * qz) / nq
    return nx, ny, nz, ny * wz - nz * wy, nz * wx - nx * wz, nx * wy - ny * wx


def contact_response(qw, qx, qy, qz, wx, wy, wz, nx, ny, nz, ndx, ndy, ndz, gx, gy, gz, hx, hy, hz,
                      A, B, C, M, g) -> tuple:
    """The rigid body's response to the plane, shared by :func:`contact_dynamics` and
    :func:`contact_dynamics_general` (the same operations in the same order for both): from the
    vertical n, its rate ṅ, ∇h and H ṅ, the body rate ẇ (Sherman–Morrison inverse of I + M k kᵀ), the
    normal force N, ż = k·w and q̇. Returns (q̇ (4), ẇ (3), N, ż)."""
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
    return qdot, (wdx, wdy, wdz), N, zdot


def reduced_rates(n, w, surf, inertia, M, g) -> np.ndarray:
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
    qdot, wdot, *_, nn = contact_dynamics(np.concatenate([q, w]), surf, inertia, M, g, math.sqrt)
    nn = np.array(nn)
    return np.concatenate([np.cross(nn, w), wdot])


def contact_dynamics_general(y, surf, inertia, M, g, sqrt) -> tuple:
    """:func:`contact_dynamics` for a surface of any orientation and centre (Puiseux sec. III).

    Same equations, with ``surf`` a
    :class:`~gyro_instrument.instruments.puiseux.surface.GeneralEllipsoidSurface` (full S and
    centre c in principal axes): h = √(nᵀSn) − c·n, ∇h = Sn/s − c, H ṅ = Sṅ/s − Sn (Sn·ṅ)/s³.
    The surface terms are kept apart so that the sec. I-II bodies keep their exact arithmetic; the
    body's response is shared (:func:`contact_response`). Returns the same tuple.
    """
    qw, qx, qy, qz, wx, wy, wz = y
    A, B, C = inertia
    sxx, sxy, sxz, syy, syz, szz = surf.sxx, surf.sxy, surf.sxz, surf.syy, surf.syz, surf.szz
    cx, cy, cz = surf.cx, surf.cy, surf.cz
    nx, ny, nz, ndx, ndy, ndz = vertical(qw, qx, qy, qz, wx, wy, wz)
    sx, sy, sz = general_sn(nx, ny, nz, sxx, sxy, sxz, syy, syz, szz)
    s = sqrt(nx * sx + ny * sy + nz * sz)
    gx, gy, gz, h, hx, hy, hz = general_surface_terms(nx, ny, nz, ndx, ndy, ndz, sx, sy, sz, s, sxx, sxy, sxz,
                                                       syy, syz, szz, cx, cy, cz)
    qdot, wdot, N, zdot = contact_response(qw, qx, qy, qz, wx, wy, wz, nx, ny, nz, ndx, ndy, ndz,
                                            gx, gy, gz, hx, hy, hz, A, B, C, M, g)
    return qdot, wdot, N, h, zdot, (nx, ny, nz)


def general_sn(nx, ny, nz, sxx, sxy, sxz, syy, syz, szz) -> tuple:
    """S n for the symmetric S of a :class:`~.surface.GeneralEllipsoidSurface` (floats or arrays)."""
    sx = sxx * nx + sxy * ny + sxz * nz
    sy = sxy * nx + syy * ny + syz * nz
    sz = sxz * nx + syz * ny + szz * nz
    return sx, sy, sz


def general_surface_terms(nx, ny, nz, ndx, ndy, ndz, sx, sy, sz, s, sxx, sxy, sxz, syy, syz, szz, cx, cy, cz) -> tuple:
    """From n, ṅ, S n and s = √(nᵀSn): ∇h = S n/s − c, h = s − c·n and H ṅ = S ṅ/s − S n (S n·ṅ)/s³
    (:func:`contact_dynamics_general`; plain float arithmetic, also compiled by :mod:`.kernels`).
    Returns (∇h (3), h, H ṅ (3))."""
    gx, gy, gz = sx / s - cx, sy / s - cy, sz / s - cz
    h = s - (cx * nx + cy * ny + cz * nz)
    tx = sxx * ndx + sxy * ndy + sxz * ndz
    ty = sxy * ndx + syy * ndy + syz * ndz
    tz = sxz * ndx + syz * ndy + szz * ndz
    f = (sx * ndx + sy * ndy + sz * ndz) / (s * s * s)
    hx, hy, hz = tx / s - sx * f, ty / s - sy * f, tz / s - sz * f
    return gx, gy, gz, h, hx, hy, hz
