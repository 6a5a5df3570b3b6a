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
The coefficients c_l, c_q are not assumed: :func:`rigid_body_coefficients` measures them on the
instrument's active effects' own ``rigid_body_torque`` terms and refuses (returns None) when their
sum is not of that form, so an effect added later is never silently dropped — the instrument then
falls back to the chain. Hinge torques are the effects' own ``damping_torque`` / ``spin_torque``
called with floats. ``tests/test_gimbal.py`` holds this function to the chain's right-hand side at
random states to round-off, for every configuration and effect list.

The same equations as numba kernels (:mod:`.kernels`: :func:`~.kernels.free_kernel`,
:func:`~.kernels.held_kernel`, floats and a parameter array from :func:`~.kernels.kernel_params`,
hinge torques linear in the rates — the forms :func:`linear_hinge_coefficient` measures; an effect
of another form keeps the Python closed form) run through the compiled DOP853 of
:mod:`gyro_instrument.core.dop853_jit` (``integrator: compiled``; ``auto`` for the free rings):
~90 ns per evaluation instead of ~1.5 µs of Python callback, 200-500x real time for the free rings
where the Fortran driver below reaches 11-21x (``gyro-instrument bench``: ``bench.spin_gimbal``).
``tests/test_gimbal_compiled.py`` holds the kernels to the chain and the compiled to the plain function bit for bit.

Two resumable drivers run the Python closed form (``gimbal_work_precision.csv``):
:class:`ClosedFormRun`, Hairer's Fortran DOP853 from sample to sample, for the free rings (tens of
steps per sample: the stage arithmetic in Fortran halves the CPU of the Python-float driver of
:mod:`gyro_instrument.core.dop853`), and :class:`DenseRun`, scipy's DOP853 with dense output, for
the slow locked and outer-fixed swings (a step covers many samples; ``auto``'s choice there: no
numba to load).
"""

import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core.effect import DAMPING, RIGID_BODY, SPIN, bound_hooks
# The numba kernels live in kernels; re-exported here, where they were defined.
from gyro_instrument.instruments.gimbal.kernels import (KERNELS, compiled_kernel, free_kernel, held_kernel,
                                                        kernel_params)

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


class _Floats(tuple):
    """A tuple of floats read like a numpy array's ``tolist()`` (the free rhs's scalar entry)."""

    def tolist(self):
        return self


def _rhs_inputs(inertias, omega_base, coefficients, effects, swing_inertias, context=None):
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


def _torque_constants(A, C, A1, C1, A2, C2, cl, cq):
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


def _free_rhs(inputs) -> Callable:
    """:func:`closed_form_rhs` of the free rings (``inputs``: :func:`_rhs_inputs`), with its
    ``on_array(t, y)`` for the Fortran driver (the hot loop of the fast nutation)."""
    (A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner) = inputs
    a_inner = A + A1
    (kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s,
     u2_c) = _torque_constants(A, C, A1, C1, A2, C2, cl, cq)
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
        (c_l, c_q) of :func:`rigid_body_coefficients`.
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
    inputs = _rhs_inputs(inertias, omega_base, coefficients, effects, swing_inertias, context)
    (A, C, A1, C1, A2, C2, Ox, Oy, Oz, cl, cq, damp, spin, J_outer, J_inner) = inputs
    a_inner = A + A1
    (kx1, kx2, ky1, ky2, kz0, lx1, lx2, lx3, ly1, ly2, lz1, lz2, qx, qy, qz, q0, u2_s,
     u2_c) = _torque_constants(A, C, A1, C1, A2, C2, cl, cq)

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


#: Hairer's DOP853 return codes (IDID) on failure.
_DOP853_FAILURES = {-1: "input is not consistent", -2: "larger nsteps is needed", -3: "step size becomes too small",
                    -4: "problem is probably stiff (interrupted)"}


class ClosedFormRun:
    """A resumable run of :func:`closed_form_rhs` through Hairer's DOP853 (Fortran, in scipy as
    ``scipy.integrate.ode(...).set_integrator("dop853")``), from sample to sample.

    The Fortran driver does the stage arithmetic that costs ~60 µs per step on Python floats
    (:mod:`gyro_instrument.core.dop853`); only the right-hand side runs in Python. Each sample time
    is reached by one call of the driver from the previous sample (its last step lands on the
    sample; each call starts with Hairer's initial-step guess), so the states depend on the sample
    times only — never on how they are cut into blocks: :meth:`advance` over consecutive blocks
    gives the one-shot run bit for bit, in memory of one block. Method and error control are those
    of ``solve_ivp``'s DOP853 (the same 8(5,3) pair and error norm), the steps are not (they stop
    at the samples).

    Parameters
    ----------
    rhs : callable
        ``rhs(t, *y) -> tuple`` (:func:`closed_form_rhs`).
    y0 : array_like
        State at ``t0``.
    t0 : float
        Start, s.
    rtol, atol : float
        DOP853's tolerances.

    Raises
    ------
    IntegrationError
        From :meth:`advance`: the driver's failure (its message: step size too small, probably
        stiff...) or a non-finite state.
    """

    #: Most steps the driver may take between two samples (its ``nsteps``; a 32-bit integer).
    MAX_STEPS_PER_SAMPLE = 2 ** 31 - 1

    def __init__(self, rhs, y0, t0, rtol, atol) -> None:
        from scipy.integrate import ode

        count = self._count = [0]

        def counted(t, y):
            count[0] += 1
            return rhs(t, *y.tolist())
        # The free rings' RHS reads the driver's array itself, counted by the driver (Hairer's
        # NFCN, IWORK(17)) when scipy's integrator exposes it; otherwise the counting wrapper.
        on_array = getattr(rhs, "on_array", None)
        for f in ((on_array, counted) if on_array is not None else (counted,)):
            self.solver = ode(f).set_integrator("dop853", rtol=rtol, atol=atol, nsteps=self.MAX_STEPS_PER_SAMPLE)
            self.solver.set_solout(self._accepted)
            self.solver.set_initial_value(np.asarray(y0, dtype=float), float(t0))   # makes WORK, IWORK
            integrator = getattr(self.solver, "_integrator", None)
            self._iwork = getattr(integrator, "iwork", None) if f is on_array else None
            if f is counted or (self._iwork is not None and self._iwork.size > 16):
                break
        # The driver's first step of each call (its WORK(7), 0 = Hairer's initial guess): the last
        # step not cut short by a sample, so a call resumes the step sequence instead of ramping
        # up from a guess (~5 evaluations per sample saved). Left at 0 if scipy's layout differs.
        self._work = getattr(integrator, "work", None)
        self._t_step = self._target = None
        self._h = 0.0
        self.t, self.y = float(t0), np.asarray(y0, dtype=float).copy()
        self.meta = {"rtol": rtol, "atol": atol, "driver": "DOP853 (Fortran, scipy.integrate.ode)"}
        self.wall_time_s = self.cpu_time_s = 0.0

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""
        return self._count[0]

    def _accepted(self, t, y):
        """``solout``: after each accepted step (and at each call's start), keep the last step
        length that no sample cut short."""
        if self._t_step is not None and t != self._target and t > self._t_step:
            self._h = t - self._t_step
        self._t_step = t

    def advance(self, t, progress=None) -> np.ndarray:
        """States at the sample times ``t`` (1-D, non-decreasing, from the previous block's last
        sample on), shape (n, len(t)); ``progress(t_i)`` is called after each sample when given."""
        import time
        import warnings

        from gyro_instrument.core.errors import IntegrationError
        t = np.asarray(t, dtype=float)
        w0, c0 = time.perf_counter(), time.process_time()
        out = np.empty((self.y.size, t.size))
        solver = self.solver
        for i, ti in enumerate(t):
            if ti != self.t:
                self._target, self._t_step = ti, None
                if self._work is not None and self._work.size > 6:
                    self._work[6] = min(self._h, ti - self.t)
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")           # the failure is raised below instead
                    y = solver.integrate(ti)
                if self._iwork is not None:
                    self._count[0] += int(self._iwork[16])
                if not solver.successful():
                    code = solver.get_return_code()
                    msg = _DOP853_FAILURES.get(code, f"return code {code}")
                    raise IntegrationError(f"DOP853 failed between t = {self.t:.6g} s and {ti:.6g} s: {msg}")
                self.t, self.y = float(ti), y
                if progress is not None:
                    progress(ti)
            out[:, i] = self.y
        self.wall_time_s += time.perf_counter() - w0
        self.cpu_time_s += time.process_time() - c0
        if not np.all(np.isfinite(out)):
            raise IntegrationError("DOP853 produced a non-finite state")
        return out


class DenseRun:
    """A resumable run of :func:`closed_form_rhs` through scipy's DOP853 ``OdeSolver`` stepped with
    no end (``t_bound`` = ∞), the samples read from each step's dense output as ``solve_ivp`` does.

    For a slow motion (the locked and outer-fixed swings: a step covers many samples) this costs
    nothing per sample, where :class:`ClosedFormRun` spends at least one step on each. The steps
    never depend on the samples, and a step's dense output is kept across blocks, so
    :meth:`advance` over consecutive blocks gives the one-shot run bit for bit. Parameters and
    errors as :class:`ClosedFormRun`.
    """

    def __init__(self, rhs, y0, t0, rtol, atol) -> None:
        from scipy.integrate import DOP853

        def f(t, y):
            self.nfev += 1
            return np.array(rhs(t, *y.tolist()))
        self.nfev = 0
        self.y0 = np.asarray(y0, dtype=float)
        self.solver = DOP853(f, float(t0), self.y0, np.inf, rtol=rtol, atol=atol)
        self.stepped, self.dense = False, None
        self.meta = {"rtol": rtol, "atol": atol, "nsteps": 0, "driver": "DOP853 (scipy OdeSolver, dense output)"}
        self.wall_time_s = self.cpu_time_s = 0.0

    def advance(self, t, progress=None) -> np.ndarray:
        """States at the sample times ``t`` (1-D, non-decreasing, from the previous block's last
        sample on, not before ``t0``), shape (n, len(t)); ``progress(t_i)`` after each step."""
        import time

        from gyro_instrument.core.errors import IntegrationError
        t = np.asarray(t, dtype=float)
        w0, c0 = time.perf_counter(), time.process_time()
        out = np.empty((self.y0.size, t.size))
        solver, i = self.solver, 0
        while i < t.size:
            if self.stepped:
                j = int(np.searchsorted(t, solver.t, side="right"))     # the samples this step reaches
                if j > i:
                    if self.dense is None:
                        self.dense = solver.dense_output()
                    out[:, i:j] = self.dense(t[i:j])
                    i = j
                    continue
            message = solver.step()
            if solver.status == "failed":
                raise IntegrationError(f"DOP853 failed at t = {solver.t:.6g} s: {message}")
            self.stepped, self.dense = True, None
            self.meta["nsteps"] += 1
            if progress is not None:
                progress(solver.t)
        self.wall_time_s += time.perf_counter() - w0
        self.cpu_time_s += time.process_time() - c0
        if not np.all(np.isfinite(out)):
            raise IntegrationError("DOP853 produced a non-finite state")
        return out
