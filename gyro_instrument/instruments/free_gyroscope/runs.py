"""The free gyroscope's runs: the integrator choice, the splitting's step, the drivers and the streamed simulation.

:class:`FreeGyroscopeRuns` is mixed into :class:`~gyro_instrument.instruments.free_gyroscope.FreeGyroscope`
(which supplies the parameters, the release state ``q0``, ``R0``, the axes ``e_axis``, ``eq_m``,
``eq_w``, the constants of motion, the model's Earth rate and whether a torque acts): it chooses the
integrator, sizes the splitting's step from its measured error law, builds the right-hand side and
the torques, runs the closed form (:meth:`~FreeGyroscopeRuns.analytic_state`), the splitting
(:class:`~gyro_instrument.core.rigid_body_flow.SplittingRun`) or DOP853 (compiled through
:mod:`gyro_instrument.core.dop853_jit`, or on Python floats) block by block, and turns states into
columns. The methods are described in :mod:`gyro_instrument.instruments.free_gyroscope` ("Numerical path").
"""

import math
import time
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.angles import NumpyUnwrapper
from gyro_instrument.core.dop853_jit import CompiledRun
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import Trajectory, integration
from gyro_instrument.core.quaternion import quat_from_rotvec, quat_mul, quat_to_matrix, rotate_about
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.rigid_body_flow import SplittingRun, compiled_rhs_kernel, rhs_params, to_body
from gyro_instrument.instruments.base import Simulation, run_span


class FreeGyroscopeRuns:
    """The integrator choice, the step law, the drivers and the columns of
    :class:`~gyro_instrument.instruments.free_gyroscope.FreeGyroscope`."""

    # ---------------------------------------------------------------- integrator choice and step
    def chosen_integrator(self, duration_s=None) -> tuple:
        """(integrator, reason): ``analytic`` for the closed form; for ``model: numerical`` the
        ``integrator`` parameter, ``auto`` meaning splitting (its step from :meth:`splitting_step`)."""
        if self.p.model == "analytic":
            return "analytic", "model analytic: the exact torque-free closed form, cost independent of the horizon"
        if self.p.integrator == "dop853":
            driver = f"compiled, core.dop853_jit, {jit.status()}" if jit.enabled() else \
                f"Python floats: {jit.status()}"
            return "dop853", (f"chosen in the scene: DOP853 on quaternion + Euler equations (resolves every "
                              f"nutation; {driver})")
        how = "chosen in the scene" if self.p.integrator == "splitting" else \
            "auto: the exact torque-free flow carries the spin and the free nutation (faster than DOP853 at equal error: bench spin_free)"
        if not self.torqued():
            return "splitting", f"{how}; no torque acts: one exact step per sample"
        return "splitting", (f"{how}; order {self.p.splitting_order} composition with torque kicks, step "
                             f"{self.splitting_step():.3g} s from rtol {self.p.rtol:g}, the torque's slow rate "
                             f"{self.slow_rate():.3g} rad/s and the nutation rate {self.motion_constants()['lam']:.4g} "
                             f"rad/s (a torque across the axis excites nutation: the step resolves it)")

    #: Error constants K_p of the splitting's measured axis-error law (order p: constant), bounded in
    #: time: err ≈ K_p (s/λ) (λ h)^p rad, λ = |L|/A the nutation rate, s the torque's slow rate
    #: (:meth:`slow_rate`), so s/λ is the amplitude of the nutation the torque forces. Fitted on a
    #: mass unbalance (d = 1e-4 and 1e-6 m, 60 rad/s, 60 and 600 s; tests/test_free_gyroscope_splitting.py
    #: checks the law): the kicks of a torque across the axis excite nutation, so the step must resolve
    #: the nutation (λ h ≲ 1), not only the slow motion; torques along the axis (spin_decay) err far less.
    STEP_ERROR_CONSTANT = {2: 0.2, 4: 0.01, 6: 1e-5}

    def slow_rate(self) -> float:
        """s, rad/s: the fastest of the torques' slow rates — the unbalance's precession rate
        m g |d| / |L| (|L| at release; √(m g |d| / A) for a body at rest) and the spin decay rate 1/τ."""
        L = self.p.transverse_inertia_kg_m2 * self.motion_constants()["lam"]
        torque = abs(self.unbalance_torque_per_inertia()) * self.p.transverse_inertia_kg_m2
        rates = [torque / L if L > 0.0 else math.sqrt(abs(self.unbalance_torque_per_inertia()))]
        tau = self.viscous_spin_time_s()
        if tau:
            rates.append(1.0 / tau)
        return max(rates)

    def splitting_step(self) -> float:
        """Largest splitting step h = (rtol / (K_p s/λ))^(1/p) / λ, s: :meth:`slow_rate`, λ = |L|/A,
        p: ``splitting_order``, K_p: :data:`STEP_ERROR_CONSTANT` (axis error ≈ rtol rad); inf without a
        torque (the free flow is exact: one step per sample)."""
        s, lam = self.slow_rate(), self.motion_constants()["lam"]
        if not self.torqued() or s <= 0.0:
            return math.inf
        lam = max(lam, s)
        order = self.p.splitting_order
        return (self.p.rtol / (self.STEP_ERROR_CONSTANT[order] * s / lam)) ** (1.0 / order) / lam

    def torque_array(self) -> np.ndarray:
        """The torques as :func:`~gyro_instrument.core.rigid_body_flow.kick` reads them: [γ = m g d / A,
        n, 1/τ (0 without ``spin_decay``), ê, up_par, up_perp, up_cross] with the local up in the inertial
        frame (ENU frozen at release) up(t) = Rot(ê, n t) ẑ = up_par + cos(nt) up_perp + sin(nt) up_cross;
        empty without a torque."""
        if not self.torqued():
            return np.empty(0)
        n, e = self.model_rate(), self.e_axis
        z = np.array([0.0, 0.0, 1.0])
        par = float(z @ e) * e
        tau = self.viscous_spin_time_s()
        rate = 1.0 / tau if tau else 0.0
        return np.concatenate([[self.unbalance_torque_per_inertia(), n, rate], e, par, z - par, np.cross(e, z)])

    # ---------------------------------------------------------------- solution paths
    def analytic_state(self, tau) -> np.ndarray:
        """Closed-form state at times ``tau`` (s since release), as rows of
        [q (body → inertial, scalar first, 4), ω in body axes (3)], shape (7, m)."""
        k = self.motion_constants()
        lam = k["lam"]
        Lhat = k["Lambda"] / lam if lam > 0.0 else np.array([0.0, 0.0, 1.0])
        qL = quat_from_rotvec(Lhat, lam * tau)                       # precession about L
        qs = quat_from_rotvec([0.0, 0.0, 1.0], k["sigma"] * tau)      # body about its own axis
        q = quat_mul(quat_mul(qL, self.q0), qs)
        wb0 = self.R0.T @ k["omega0"]
        ang = -k["sigma"] * tau
        ca, sa = np.cos(ang), np.sin(ang)
        wb = np.stack([ca * wb0[0] - sa * wb0[1], sa * wb0[0] + ca * wb0[1],
                       np.full_like(tau, wb0[2])])
        return np.vstack([q.T, wb])

    def rhs(self) -> Callable:
        """Right-hand side for y = [q (4), ω_body (3)] in the inertial frame (Euler's equations
        for A = A, C = μA, and q̇ = ½ q ⊗ (0, ω) + κ (1 − |q|²) q with κ = |ω0|), as an array:
        :meth:`rhs_scalar`'s terms (``solve_ivp`` and the effect-size probes call this one)."""
        g = self.rhs_scalar()

        def f(t, y):
            return np.array(g(t, *y))
        return f

    #: DOP853's absolute tolerance on the state [q, ω (rad/s)] of the numerical path.
    DOP853_ATOL = 1e-14

    def dop853_run(self, span_s, rtol, compiled=True) -> Solver:
        """DOP853 from the release state (τ = 0) over ``span_s`` seconds at ``rtol`` (atol
        :data:`DOP853_ATOL`): Hairer's DOP853 compiled with its dense output
        (:class:`~gyro_instrument.core.dop853_jit.CompiledRun`, run with no end) on the compiled
        :func:`~gyro_instrument.core.rigid_body_flow.rhs_kernel` when ``compiled`` and
        :func:`gyro_instrument.core.jit.enabled`; else the same method on Python floats over
        :meth:`rhs_scalar` (``integrate(method="DOP853-scalar")``, which ends its last step on
        ``span_s``). The two take the same steps up to round-off (and the scalar one's last)."""
        y0 = np.concatenate([self.q0, self.R0.T @ self.motion_constants()["omega0"]])
        if compiled and jit.enabled():
            params = rhs_params(self.p.inertia_ratio, self.baumgarte_rate(), self.viscous_spin_time_s() or 0.0,
                                self.torque_array())
            return CompiledRun(compiled_rhs_kernel(), params, y0, 0.0, rtol, self.DOP853_ATOL)
        return integration(self.rhs_scalar(), y0, 0.0, span_s, method="DOP853-scalar", rtol=rtol,
                           atol=self.DOP853_ATOL)

    def baumgarte_rate(self) -> float:
        """κ = |ω0|, 1/s: the rate of the Baumgarte term κ (1 − |q|²) q of the DOP853 path's q̇."""
        return float(np.linalg.norm(self.motion_constants()["omega0"]))

    def rhs_scalar(self) -> Callable:
        """The right-hand side on Python floats, ``f(t, qw, qx, qy, qz, w1, w2, w3) -> tuple``, for the
        scalar DOP853 driver (``integrate(method="DOP853-scalar")``): a 7-element state is evaluated
        ~5x faster without numpy's per-call overhead. Euler's equations for A = A, C = μA, and
        q̇ = ½ q ⊗ (0, ω) + κ (1 − |q|²) q with κ = |ω0|."""
        a = 1.0 - self.p.inertia_ratio
        kappa = self.baumgarte_rate()
        torque = self.torque_rates()

        def f(t, qw, qx, qy, qz, w1, w2, w3):
            corr = kappa * (1.0 - (qw * qw + qx * qx + qy * qy + qz * qz))
            d1, d2, d3 = torque(t, (qw, qx, qy, qz), w3) if torque is not None else (0.0, 0.0, 0.0)
            return (0.5 * (-qx * w1 - qy * w2 - qz * w3) + corr * qw,
                    0.5 * (qw * w1 + qy * w3 - qz * w2) + corr * qx,
                    0.5 * (qw * w2 - qx * w3 + qz * w1) + corr * qy,
                    0.5 * (qw * w3 + qx * w2 - qy * w1) + corr * qz,
                    a * w2 * w3 + d1,
                    -a * w1 * w3 + d2,
                    d3)
        return f

    def torque_rates(self) -> Callable | None:
        """``f(t, q, ω3) -> (ω̇1, ω̇2, ω̇3)``: the torques over the body moments, rad/s² — the mass
        unbalance m g d (up_b × e3) / A and the viscous spin friction's −ρ/τ (``spin_decay``: τ from
        :meth:`viscous_spin_time_s`) on ρ = ω3 − n k·ê; None without a torque (the torque-free equations are then unchanged)."""
        if not self.torqued():
            return None
        tq = self.torque_array()
        gam, n, par, perp, cross = tq[0], tq[1], tuple(tq[6:9]), tuple(tq[9:12]), tuple(tq[12:15])
        e = tuple(float(v) for v in self.e_axis)
        tau = self.viscous_spin_time_s()

        def f(t, q, w3):
            c, s = math.cos(n * t), math.sin(n * t)
            ux, uy, _ = to_body(q, [par[i] + c * perp[i] + s * cross[i] for i in range(3)])
            d3 = -(w3 - n * to_body(q, e)[2]) / tau if tau else 0.0
            return gam * uy, -gam * ux, d3
        return f

    def columns_from_state(self, tau, y, unwrappers=None) -> tuple:
        """Columns and diagnostics from states ``y`` (7, m) at times ``tau`` since release.

        ``unwrappers``: a pair of :class:`~gyro_instrument.core.angles.NumpyUnwrapper` (azimuth, hour
        angle) carried across the blocks of a streamed run; fresh ones (``numpy.unwrap``) by default.

        Returns
        -------
        columns : dict
            The ``COLUMNS`` arrays (rad, rad/s).
        extra : dict
            ``axis_enu`` (m, 3) the axis relative to the Earth; ``axis_inertial`` (m, 3);
            ``attitude_enu`` (m, 3, 3) body → ENU; ``angular_momentum`` (m, 3) inertial, kg m²/s;
            ``kinetic_energy_j`` (m,); ``quaternion_norm`` (m,) before renormalisation.
        """
        unwrap_az, unwrap_ha = unwrappers if unwrappers is not None else (NumpyUnwrapper(), NumpyUnwrapper())
        n = self.model_rate()
        q = y[:4].T
        wb = y[4:].T
        R = quat_to_matrix(q)
        k_in = R[..., :, 2]
        k_enu = rotate_about(k_in, self.e_axis, -n * tau)
        e, nn, u = k_enu[:, 0], k_enu[:, 1], k_enu[:, 2]
        dm, dw, de = k_enu @ self.eq_m, k_enu @ self.eq_w, k_enu @ self.e_axis
        ib = np.array([self.p.transverse_inertia_kg_m2, self.p.transverse_inertia_kg_m2, self.C])
        Lb = wb * ib
        # Attitude relative to the Earth: Rot(ê, −n τ) R.
        Re = quat_to_matrix(quat_from_rotvec(self.e_axis, -n * tau)) @ R
        columns = {
            "axis_altitude": np.arctan2(u, np.hypot(e, nn)),
            "axis_azimuth": unwrap_az(np.arctan2(e, nn)),
            "hour_angle": unwrap_ha(np.arctan2(dw, dm)),
            "declination": np.arctan2(de, np.hypot(dm, dw)),
            "spin_rate": wb[:, 2] - n * (k_in @ self.e_axis),
        }
        extra = {"axis_enu": k_enu, "axis_inertial": k_in, "attitude_enu": Re,
                 "angular_momentum": np.einsum("mij,mj->mi", R, Lb),
                 "kinetic_energy_j": 0.5 * np.sum(Lb * wb, axis=1),
                 "quaternion_norm": np.linalg.norm(q, axis=1)}
        return columns, extra

    def simulate(self, t, model=None, rtol=None, **options) -> Simulation:
        """Release at ``t[0]`` and sample at ``t`` (s): one block of :meth:`stream`.

        Parameters
        ----------
        t : array_like
            Increasing sample times, s; the axis is released at ``t[0]``.
        model : {"analytic", "numerical"}, optional
            Overrides the ``model`` parameter.
        rtol : float, optional
            Overrides the ``rtol`` parameter (numerical path).
        **options
            ``integrator`` ("splitting" or "dop853") and ``splitting_order`` override the parameters;
            ``step_s`` forces the splitting's largest step, s (the work-precision study);
            ``compiled=False`` runs ``dop853`` on Python floats even with numba (:meth:`dop853_run`).

        Returns
        -------
        Simulation
            ``columns`` as in ``COLUMNS``; ``trajectory.y`` rows [q (4), ω_body (3)] in the
            inertial frame (ENU frozen at release); ``extra`` as in :meth:`columns_from_state`.
        """
        return super().simulate(t, model=model, rtol=rtol, **options)

    def stream(self, blocks, model=None, rtol=None, **options) -> Iterator[Simulation]:
        """Block by block (:meth:`Instrument.stream`), released at the first sample: the closed form
        at each block's times, or the numerical path's state carried across blocks (the splitting's
        state and time, :class:`~gyro_instrument.core.rigid_body_flow.SplittingRun`, or DOP853's step
        sequence, :meth:`dop853_run`); the unwrapped angles continue
        across blocks. The blocks concatenate to :meth:`simulate` bit for bit."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        model = model or self.p.model
        if model == "analytic" and self.torqued():
            raise SceneError(f"instruments.{self.name}.model", model, "is torque-free: a mass unbalance or "
                             "spin_decay needs model numerical")
        integrator = options.pop("integrator", None) or self.chosen_integrator()[0]
        unwrappers = (NumpyUnwrapper(), NumpyUnwrapper())
        rtol = self.p.rtol if rtol is None else rtol
        run = None
        wb0 = self.R0.T @ self.motion_constants()["omega0"]
        if model != "analytic" and integrator == "dop853":
            run = self.dop853_run(t_end - t0, rtol, options.pop("compiled", True))
        elif model != "analytic":
            order = options.pop("splitting_order", None) or self.p.splitting_order
            h = options.pop("step_s", None) or self.splitting_step()
            run = SplittingRun(np.concatenate([self.q0, wb0]), 0.0, h, order, self.p.inertia_ratio,
                               self.torque_array())
        for t in blocks:
            tau = t - t0
            w0, c0 = time.perf_counter(), time.process_time()
            if run is not None:
                traj = run.advance(tau)
                traj.t, y = t, traj.y
                if isinstance(run, CompiledRun):
                    traj.method = "DOP853 (compiled)"
            else:
                y = self.analytic_state(tau)
                traj = Trajectory(t, y, 0, time.perf_counter() - w0, time.process_time() - c0, "analytic")
            columns, extra = self.columns_from_state(tau, y, unwrappers)
            extra["motion_constants"] = self.motion_constants()
            yield Simulation(t, columns, traj, extra)
