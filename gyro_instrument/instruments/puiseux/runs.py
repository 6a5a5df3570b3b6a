"""The body on the plane's model: initial state, right-hand side, diagnostics and the streamed run.

:class:`ContactRuns` is mixed into :class:`~gyro_instrument.instruments.puiseux.instrument.PuiseuxBody`
(which supplies the parameters, the surface, the inertia and the initial tilt and spin): the state
is the unit quaternion (body → ENU) and the body-axis angular velocity, integrated with the contact
dynamics of :mod:`.dynamics` (Puiseux 1852) by the integrator the ``integrator`` parameter names
(adaptive DOP853, compiled when numba is on, or a compiled fixed-step run of :mod:`.fixed_step`), and
turned into columns here.
"""

import math
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.angles import NumpyUnwrapper
from gyro_instrument.core.integrate import integration
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.quaternion import quat_from_matrix, quat_mul, quat_to_matrix, rotation_matrix
from gyro_instrument.core.site import compass_azimuth_from_enu
from gyro_instrument.instruments.base import Simulation, run_span
from gyro_instrument.instruments.puiseux.dynamics import contact_dynamics
from gyro_instrument.instruments.puiseux.fixed_step import FixedStepRun, axis_state, compiled_dop853_run


class ContactRuns:
    """The state, the right-hand side and the columns of :class:`~.instrument.PuiseuxBody`."""

    # ---------------------------------------------------------------- model
    def initial_state(self) -> np.ndarray:
        """State [q_w, q_x, q_y, q_z, w_x, w_y, w_z] at t = 0 (quaternion body -> ENU, w in body axes).

        At rest the body's axes lie along ENU (ellipsoid, curvature) or, for the general body, its
        normal frame A-xi, A-eta, A-zeta does (so GA is vertical); then it is tilted and set moving as
        the class docstring says, the line GA (= Gz but for the general body) playing the axis.
        """
        th, az = self.p.initial_tilt_rad, self.p.initial_tilt_azimuth_rad
        # axis u in ENU, leaning toward compass azimuth az: (sin az, cos az) horizontally
        e_th = np.array([math.cos(th) * math.sin(az), math.cos(th) * math.cos(az), -math.sin(th)])
        e_az = np.array([math.cos(az), -math.sin(az), 0.0])  # direction of increasing compass azimuth
        u = np.array([math.sin(th) * math.sin(az), math.sin(th) * math.cos(az), math.cos(th)])
        udot = self.p.initial_tilt_rate_rad_s * e_th + self.p.initial_azimuth_rate_rad_s * math.sin(th) * e_az
        w_world = self.r0 * u + np.cross(u, udot)
        # rotation by th about e_z x u / |...| = (-cos az, sin az, 0) (horizontal, perpendicular to az)
        axis = np.array([-math.cos(az), math.sin(az), 0.0])
        q = np.concatenate([[math.cos(th / 2)], math.sin(th / 2) * axis])
        R = rotation_matrix(q)
        if self.general:
            R = R @ self.P                      # body -> normal frame (eq. 17) -> tilted ENU
            q = quat_from_matrix(R)
        return np.concatenate([q, R.T @ w_world])

    def rest_quaternion(self) -> np.ndarray:
        """Orientation at rest (GA vertical, no turn), body -> ENU: identity but for the general body."""
        return quat_from_matrix(self.P) if self.general else np.array([1.0, 0.0, 0.0, 0.0])

    def contact_points_body(self, n) -> np.ndarray:
        """Contact point x_P = −∇h(n) in body axes (from G), m, shape (3, m), for verticals n (3, m)."""
        n = np.asarray(n, dtype=float)
        if self.general:
            return self.surface.contact_point(n)
        sf = self.surface
        sx, sy, sz = sf.sxx * n[0] + sf.sxy * n[1], sf.sxy * n[0] + sf.syy * n[1], sf.szz * n[2]
        s = np.sqrt(n[0] * sx + n[1] * sy + n[2] * sz)
        return -np.array([sx / s, sy / s, sz / s - sf.cz])

    def rhs(self) -> Callable:
        """Right-hand side f(t, y) of the exact model (:mod:`.dynamics`)."""
        surf, inertia, M, g = self.surface, self.inertia, self.p.mass_kg, self.context.gravity_m_s2
        sqrt = math.sqrt
        contact_dynamics = self.dynamics

        def f(t, y):
            qdot, wdot, *_ = contact_dynamics(y, surf, inertia, M, g, sqrt)
            return np.array([*qdot, *wdot])
        return f

    def diagnostics(self, y) -> dict:
        """Derived quantities along a state history ``y`` (shape (7, m)).

        Returns
        -------
        dict of ndarray
            ``n`` (3, m) vertical in body axes, ``axis_enu`` (3, m), ``com_height_m``,
            ``com_velocity_m_s`` (ż), ``normal_force_N``, ``energy_J``,
            ``angular_momentum_vertical_kg_m2_s`` (n·Iw), ``quaternion_norm``.
        """
        y = np.asarray(y, dtype=float)
        _, _, N, h, zdot, n = self.dynamics(y, self.surface, self.inertia, self.p.mass_kg, self.context.gravity_m_s2, np.sqrt)
        q = y[:4]
        qn2 = np.sum(q * q, axis=0)
        qw, qx, qy, qz = q
        axis = np.array([2.0 * (qx * qz + qw * qy), 2.0 * (qy * qz - qw * qx), qw * qw - qx * qx - qy * qy + qz * qz]) / qn2
        if self.general:                        # the line GA, not Gz
            axis = np.einsum("mij,j->im", quat_to_matrix(q.T), self.u_body)
        A, B, C = self.inertia
        w = y[4:]
        rot = 0.5 * (A * w[0] ** 2 + B * w[1] ** 2 + C * w[2] ** 2)
        energy = 0.5 * self.p.mass_kg * zdot ** 2 + rot + self.p.mass_kg * self.context.gravity_m_s2 * h
        lz = n[0] * A * w[0] + n[1] * B * w[1] + n[2] * C * w[2]
        return {"n": np.array(n), "axis_enu": axis, "com_height_m": h, "com_velocity_m_s": zdot,
                "normal_force_N": N, "energy_J": energy, "angular_momentum_vertical_kg_m2_s": lz,
                "quaternion_norm": np.sqrt(qn2)}

    def simulate(self, t, rtol=None, atol=1e-12, **options) -> Simulation:
        """Integrate the exact model (the chosen integrator, :meth:`integration_run`) and sample at
        times ``t`` (s, from t[0]): one block of :meth:`stream`. ``rtol`` overrides the parameter,
        ``integrator=`` (a keyword option) the ``integrator`` parameter, and ``compiled=False`` runs
        ``dop853`` as scipy's DOP853 on :meth:`rhs` even with numba on.

        Returns
        -------
        Simulation
            Columns as in ``COLUMNS``; ``extra`` holds ``energy_J``,
            ``angular_momentum_vertical_kg_m2_s``, ``quaternion_norm``, ``normal_force_N``,
            ``min_normal_force_N`` (negative: the body would leave the plane, outside the model)
            and ``state`` (7, m).
        """
        return super().simulate(t, rtol=rtol, atol=atol, **options)

    def stream(self, blocks, rtol=None, atol=1e-12, **options) -> Iterator[Simulation]:
        """Block by block (:meth:`Instrument.stream`): one run of the chosen integrator (DOP853's step
        sequence, with no end when compiled, bounded by the run's end for scipy's; or the fixed steps
        of :mod:`.fixed_step`), carried across
        blocks (the blocks concatenate to :meth:`simulate` bit for bit; the turn about the vertical
        is unwrapped across blocks); ``extra["min_normal_force_N"]`` is the block's minimum."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        run = self.integration_run(t0, t_end, self.p.rtol if rtol is None else rtol, atol, options.pop("integrator", None),
                                   options.pop("compiled", None))
        carry = {"unwrap": NumpyUnwrapper(), "turn0": None}
        for t in blocks:
            traj = run.advance(t)
            d = self.diagnostics(traj.y)
            n, axis = d["n"], d["axis_enu"]
            if self.general:
                u = self.u_body      # elementwise sums, not BLAS: the same floats whatever the block
                w = traj.y[4:]
                cross = np.cross(n.T, u)
                tilt = np.arctan2(np.sqrt(cross[:, 0] ** 2 + cross[:, 1] ** 2 + cross[:, 2] ** 2),
                                  u[0] * n[0] + u[1] * n[1] + u[2] * n[2])
                spin = u[0] * w[0] + u[1] * w[1] + u[2] * w[2]
            else:
                tilt = np.arctan2(np.hypot(n[0], n[1]), n[2])
                spin = traj.y[6].copy()
            columns = {"tilt": tilt,
                       "tilt_azimuth": compass_azimuth_from_enu(axis[0], axis[1]),
                       "spin_rate": spin,
                       "com_height": d["com_height_m"],
                       "vertical_body_x": n[0], "vertical_body_y": n[1]}
            columns.update(self.contact_columns(traj.y, n, carry))
            extra = {k: d[k] for k in ("energy_J", "angular_momentum_vertical_kg_m2_s", "quaternion_norm",
                                       "normal_force_N", "com_velocity_m_s")}
            extra["min_normal_force_N"] = float(np.min(d["normal_force_N"]))
            extra["state"] = traj.y
            yield Simulation(t, columns, traj, extra=extra)

    def integration_run(self, t0, t_end, rtol, atol, integrator=None, compiled=None
                        ) -> Solver:
        """The resumable run (``advance(block)``) of the chosen integrator (:meth:`integrator_choice`;
        ``integrator`` overrides the parameter): DOP853 — compiled (:func:`.fixed_step.compiled_dop853_run`,
        when ``compiled`` is None or True and numba is on) or scipy's on :meth:`rhs` (``compiled=False``,
        or numba off) — or a fixed-step run of :mod:`.fixed_step` with the same initial state, its step
        set by ``rtol`` and the fastest rate Ω of the motion (:mod:`.fixed_step`; ``atol`` applies to
        DOP853 only)."""
        name = integrator or self.integrator_choice()[0]
        y0 = self.initial_state()
        if name == "dop853":
            if compiled is False or not jit.enabled():
                return integration(self.rhs(), y0, t0, t_end, method="DOP853", rtol=rtol, atol=atol)
            return compiled_dop853_run(y0, t0, self.exact_params(), rtol, atol)
        A, B, C = self.inertia
        M, g, sf = self.p.mass_kg, self.context.gravity_m_s2, self.surface
        w0 = float(np.linalg.norm(y0[4:]))
        # the fastest swing the gravity couple can drive, at most √(M g max|ρ − γ| / min moment)
        swing = math.sqrt(M * g * max(abs(self.rho - self.gamma), abs(self.rho_prime - self.gamma)) / min(A, B, C))
        if name == "axis_rk8":
            x0, r = axis_state(y0)
            params = (sf.sxx, sf.szz, sf.cz, A, C, r, M, g)
            omega = abs(C * r) / A + swing + float(np.linalg.norm(x0[3:6]))
        else:
            params = self.exact_params()
            omega = w0 * max(A, B, C) / min(A, B, C) + swing
        return FixedStepRun(name, y0, t0, params, omega, rtol)

    def exact_params(self) -> tuple:
        """The exact equations' kernel parameters (:func:`.kernels._body_rhs`): (A, B, C (kg m²), M (kg),
        g (m/s²), S_xx, S_xy, S_xz, S_yy, S_yz, S_zz (m), c_x, c_y, c_z (m))."""
        A, B, C = self.inertia
        sf = self.surface
        S = (sf.sxx, sf.sxy, getattr(sf, "sxz", 0.0), sf.syy, getattr(sf, "syz", 0.0), sf.szz)
        return (A, B, C, self.p.mass_kg, self.context.gravity_m_s2, *S, getattr(sf, "cx", 0.0),
                getattr(sf, "cy", 0.0), sf.cz)

    def contact_columns(self, y, n, carry=None) -> dict:
        """The contact point and the turn about the vertical along a state history (sec. I and III).

        Parameters
        ----------
        y : ndarray (7, m)
            States.
        n : ndarray (3, m)
            Upward vertical in body axes.
        carry : dict, optional
            Across consecutive blocks of one run: ``{"unwrap": NumpyUnwrapper(), "turn0": None}``,
            updated in place (the turn is unwrapped across blocks and measured from the run's first
            sample); None for a whole history at once.

        Returns
        -------
        dict of ndarray (m,)
            ``contact_x``, ``contact_y``, ``contact_z``: x_P = −∇h(n) in principal axes from G, m;
            ``contact_east``, ``contact_north``: R x_P on the plane from the vertical through G, m
            (G moves only vertically: eqs. 1-2 with no initial horizontal velocity);
            ``turn_angle``: the twist of the rotation from the rest orientation about the vertical,
            2·atan2(q_z, q_w) of q ⊗ q_rest⁻¹ (swing-twist decomposition), unwrapped, rad (the
            unwrapping needs less than a turn per sample: |r| / sample rate < 2π).
        """
        xp = self.contact_points_body(n)
        q = np.asarray(y[:4], dtype=float).T
        R = quat_to_matrix(q)
        world = [R[:, i, 0] * xp[0] + R[:, i, 1] * xp[1] + R[:, i, 2] * xp[2] for i in (0, 1)]   # R x_P, per sample
        rest = self.rest_quaternion()
        rel = quat_mul(q, rest * np.array([1.0, -1.0, -1.0, -1.0]))
        raw = np.arctan2(rel[:, 3], rel[:, 0])
        if carry is None:
            turn = 2.0 * np.unwrap(raw)
            turn0 = turn[0]
        else:
            turn = 2.0 * carry["unwrap"](raw)
            if carry["turn0"] is None:
                carry["turn0"] = turn[0]
            turn0 = carry["turn0"]
        return {"contact_x": xp[0], "contact_y": xp[1], "contact_z": xp[2],
                "contact_east": world[0], "contact_north": world[1], "turn_angle": turn - turn0}
