"""Compiled runs of Puiseux's body (``integrator: axis_rk8``, ``rk8`` and ``dop853``; issue 27 item 1).

scipy's adaptive DOP853 (``integrator: dop853`` with ``GYRO_INSTRUMENT_JIT=0``) resolves every turn
of the spin with a Python right-hand side (16–21× real time for the shipped spheroid). Here the same
exact model is stepped by compiled kernels (:mod:`.kernels`):

* ``axis_rk8`` — a body of revolution (A = B and a surface of revolution about Gz: the ellipsoid with
  α = β, or ρ = ρ'; and A = B) through its exact reduction by the conserved
  spin r (Puiseux eq. 6): the figure axis u and its velocity in the world, the spin angle a
  quadrature (:mod:`.kernels`). The step is set by the nutation, not by the spin.
* ``rk8`` — any body: the exact equations of :mod:`.dynamics` (quaternion and body rate).
* ``dop853`` with numba on (:func:`gyro_instrument.core.jit.enabled`): :func:`compiled_dop853_run`, Hairer's
  adaptive DOP853 of :mod:`gyro_instrument.core.dop853_jit` on the same exact equations as a compiled
  kernel (:func:`.kernels._exact_rhs`): the method, tolerances and error control of scipy's DOP853
  (the run of ``GYRO_INSTRUMENT_JIT=0``), its steps run with no end rather than bounded by the run's
  end, so the two differ by round-off amplified over the run (≈ rtol × the scale of the angles;
  ``tests/test_puiseux_fast.py``).

Both take equal steps h of the 8th-order Runge–Kutta formula, the fewest per sample interval with
h Ω ≤ :data:`H_OMEGA` (rtol / 1e-10)^(1/8) (the global error goes as h⁸), Ω (s⁻¹) a bound on the
fastest rate of the motion: Ω_s + |C r|/A + |u̇(0)| for ``axis_rk8`` (the nutation), Ω_s +
|w(0)| max(A, B, C)/min(A, B, C) for ``rk8`` (the spin seen in body axes), with
Ω_s = √(M g max(|ρ − γ|, |ρ' − γ|)/min(A, B, C)) the fastest swing gravity can drive
(:meth:`~.runs.ContactRuns.integration_run`). :data:`H_OMEGA` was measured with both shipped scenes
sampled at 5 Hz (so that the step, not the sample spacing, sets h): the output angles stay at the
error floor of the DOP853 rtol 1e-13 reference (≤ 6e-11 rad over 20-30 s) up to h Ω ≈ 0.3-0.5 and
grow past it beyond; 0.25 keeps that margin. At the shipped 200 Hz one step per sample is already
shorter (:mod:`gyro_instrument.bench.spin_puiseux` has the rows). The samples do not depend on how
the run is cut into blocks.
"""

import functools
import math
import types

import numpy as np

from gyro_instrument.core import dop853
from gyro_instrument.core.dop853_jit import CompiledRun
from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.quaternion import quat_mul, quat_to_matrix
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

#: h Ω at rtol 1e-10 (dimensionless), for each fixed-step integrator.
H_OMEGA = {"axis_rk8": 0.25, "rk8": 0.25}


@functools.cache
def fixed_step_kernels() -> "types.ModuleType":
    """The module :mod:`.kernels`, imported (and so compiled) on first use only."""
    from gyro_instrument.instruments.puiseux import kernels  # noqa: PLC0415 - lazy: numba

    return kernels


@functools.cache
def dop853_kernel() -> "object":
    """The exact equations as a compiled DOP853 kernel (:func:`.kernels.exact_dop853_kernel`), once
    per process; the plain function when numba is off."""
    return fixed_step_kernels().exact_dop853_kernel()


def axis_state(y) -> tuple:
    """(x, r): the reduced state x = (u, u̇, φ) (7,) of a body of revolution and its spin r (rad/s)
    from y = (q (body → ENU), w (body)) (7,); φ = 2 atan2(z, w) of q_swing(u)⁻¹ ⊗ q."""
    q, w = np.asarray(y[:4], dtype=float), np.asarray(y[4:], dtype=float)
    R = quat_to_matrix(q)
    u = R[:, 2]
    v = np.cross(R @ w, u)
    rel = quat_mul(_swing(u[:, None]).T[0] * np.array([1.0, -1.0, -1.0, -1.0]), q / np.linalg.norm(q))
    phi = 2.0 * math.atan2(rel[3], rel[0])
    return np.concatenate([u, v, [phi]]), float(w[2])


def _swing(u) -> np.ndarray:
    """Quaternions (4, m) of the minimal rotations taking e_z to the unit vectors u (3, m)."""
    c = u[2]
    norm = np.sqrt(2.0 * (1.0 + c))
    return np.array([(1.0 + c) / norm, -u[1] / norm, u[0] / norm, np.zeros_like(c)])


def body_states(x, r) -> np.ndarray:
    """(q, w) (7, m) from reduced states x (7, m) (:func:`axis_state`): q = q_swing(u) ⊗ q_z(φ),
    w = Rᵀ (u × u̇ + r u)."""
    u = x[:3] / np.sqrt(np.sum(x[:3] * x[:3], axis=0))
    half = 0.5 * x[6]
    q = quat_mul(_swing(u).T, np.stack([np.cos(half), 0.0 * half, 0.0 * half, np.sin(half)], axis=-1))
    w_world = np.cross(u.T, x[3:6].T) + r * u.T
    w = np.einsum("mji,mj->im", quat_to_matrix(q), w_world)
    return np.vstack([q.T, w])


class FixedStepRun(Solver):
    """A resumable fixed-step run (a :class:`~gyro_instrument.core.solver.Solver` with no end).

    :meth:`advance` integrates from sample to sample in equal substeps no longer than the step
    (``h_max``); :meth:`step` takes one step of ``h_max``, and :meth:`dense_output` integrates from
    that step's start to the times asked in one substep each (the formula's own 8th-order values
    there).

    Parameters
    ----------
    model : str
        ``axis_rk8`` (reduced body of revolution; ``params`` = (a, b, c_z, A, C, r, M, g)) or ``rk8``
        (exact equations; ``params`` = (A, B, C, M, g, S_xx, S_xy, S_xz, S_yy, S_yz, S_zz, c_x, c_y, c_z)).
    y0 : array (7,)
        (q, w) at ``t0``.
    t0 : float
        Start, s.
    params : sequence of float
    omega_rad_s : float
        Fastest rate of the motion, s⁻¹ (sets the step).
    rtol : float
        The scene's tolerance (scales :data:`H_OMEGA`).
    """

    def __init__(self, model, y0, t0, params, omega_rad_s, rtol) -> None:
        super().__init__(t0)
        self.model = self.method = model
        self.params = np.asarray(params, dtype=float)
        self.h_max = H_OMEGA[model] * (rtol / 1e-10) ** 0.125 / max(omega_rad_s, 1e-300)
        self.r = float(self.params[5]) if model == "axis_rk8" else None
        self.x = axis_state(y0)[0] if model == "axis_rk8" else np.asarray(y0, dtype=float).copy()
        self.y0 = np.asarray(y0, dtype=float)
        self.nsteps = 0
        self._x_old = None
        self.meta = {"rtol": rtol, "h_omega": H_OMEGA[model], "omega_rad_s": omega_rad_s}

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far (12 stages per step)."""
        return 12 * self.nsteps

    def _integrate(self, x, times):
        """States (the model's) at ``times`` from ``x`` at ``times[0]``, in equal substeps ≤ ``h_max``."""
        k = fixed_step_kernels()
        model = k.AXIS if self.model == "axis_rk8" else k.BODY
        xs = k.rk8_samples(model, x, times, self.h_max, self.params, dop853.A, dop853.B)
        if not np.all(np.isfinite(xs)):
            bad = times[np.argmax(~np.all(np.isfinite(xs), axis=0))]
            self._failed = True
            raise IntegrationError(f"{self.model}: non-finite state, or the axis tilted past "
                                   f"{math.degrees(k.MAX_TILT_RAD):g} deg (the reduction's limit), near "
                                   f"t = {bad:.6g} s; integrator: rk8 or dop853 have no such limit")
        return xs

    def _states(self, xs) -> np.ndarray:
        """(q, w) from the model's states."""
        return body_states(xs, self.r) if self.model == "axis_rk8" else xs

    def _step_impl(self):
        times = np.array([self.t, self.t + self.h_max])
        xs = self._integrate(self.x, times)
        self._x_old, self.x = self.x, xs[:, -1].copy()
        self.t_old, self.t = self.t, float(times[-1])
        self.nsteps += 1

    def _dense_output_impl(self):
        t_old, x_old = self.t_old, self._x_old

        def sol(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            xs = np.column_stack([x_old if ti == t_old else self._integrate(x_old, np.array([t_old, ti]))[:, -1]
                                  for ti in t]) if t.size else np.empty((x_old.size, 0))
            return self._states(xs)
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """States (q, w) at the sample times ``t`` (s, increasing, from the last one returned);
        ``progress(t_i)`` after the block."""
        with self.clock():
            t = np.asarray(t, dtype=float)
            times = t if t.size and t[0] == self.t else np.concatenate([[self.t], t])
            steps = np.maximum(1, np.ceil(np.diff(times) / self.h_max))
            sub = int(steps.max()) if steps.size else 0
            xs = self._integrate(self.x, times)
            self.x, self.t = xs[:, -1].copy(), float(times[-1])
            self.nsteps += int(steps.sum())
            y = self._states(xs[:, times.size - t.size:])
            self.t_old = self._x_old = self._dense = None          # the samples are not steps
            self.meta["nsteps"], self.meta["substeps"] = self.nsteps, sub
        if progress is not None and t.size:
            progress(t[-1])
        return Trajectory(t, y, self.nfev, self.wall_time_s, self.cpu_time_s, self.model, dict(self.meta))


def compiled_dop853_run(y0, t0, params, rtol, atol, compiled=True) -> CompiledRun:
    """The adaptive DOP853 run of the exact equations compiled (``integrator: dop853`` with numba on):
    :class:`~gyro_instrument.core.dop853_jit.CompiledRun` on :func:`dop853_kernel`.

    Parameters
    ----------
    y0 : array (7,)
        (q, w) at ``t0`` (quaternion body → ENU, body rate in rad/s).
    t0 : float
        Start, s.
    params : sequence of float
        (A, B, C, M, g, S_xx, S_xy, S_xz, S_yy, S_yz, S_zz, c_x, c_y, c_z) (SI; :func:`.kernels._body_rhs`).
    rtol, atol : float
        DOP853's tolerances (those of the scipy run).
    compiled : bool
        The compiled driver and kernel (default), or both as plain Python (the reference the tests
        hold them to; ~1000× slower).
    """
    kernel = dop853_kernel() if compiled else fixed_step_kernels()._exact_rhs
    return CompiledRun(kernel, params, np.asarray(y0, dtype=float), t0, rtol, atol, compiled=compiled)
