"""The gimbal gyroscope's runs: its hinge chain, the choice of integrator, the closed form's drivers and the
streamed simulation.

:class:`GimbalRuns` is mixed into :class:`~gyro_instrument.instruments.gimbal.instrument.GimbalGyroscope`
(which supplies the parameters, the inertias as simulated, the configuration's initial angles and
the effects' rigid-body coefficients): it builds the generic
:class:`~gyro_instrument.instruments.chain.HingeChain` (outer ring about PP', inner ring about NN',
rotor about oQ; Quet 1853 sec. 4 §III), chooses the integrator, runs the closed form (:mod:`.kernels`
compiled through :mod:`gyro_instrument.core.dop853_jit`, or :mod:`.dynamics` on Python floats through
scipy's DOP853 drivers) or the chain, and turns states into columns and invariants (:mod:`.theory`).
"""

import math
from collections.abc import Iterator

import numpy as np

from gyro_instrument.core.effect import CARRIER_INERTIA, CENTRIFUGAL_TORQUE, DAMPING, GYROSCOPIC, RIGID_BODY, SPIN
from gyro_instrument.core.dop853_fortran import FortranRun
from gyro_instrument.core.dop853_jit import CompiledRun
from gyro_instrument.core.integrate import Integration, integrate, report
from gyro_instrument.core.solver import Solver
from gyro_instrument.instruments.base import Simulation
from gyro_instrument.instruments.chain import HingeChain, Link
from gyro_instrument.instruments.gimbal.dynamics import closed_form_rhs
from gyro_instrument.instruments.gimbal.kernels import compiled_kernel, kernel_params
from gyro_instrument.instruments.gimbal.theory import axial_momentum, quet_energy, spin_invariant, swing_inertias_kg_m2

#: Absolute tolerance of both integrators (rad, rad/s), as before the closed form existed.
ATOL = 1e-13


def dense_run(rhs, y0, t0, rtol, atol) -> Integration:
    """scipy's DOP853 on ``rhs(t, *y) -> tuple`` (:func:`~.dynamics.closed_form_rhs`) stepped with no
    end from ``t0`` (s), the samples read from each step's dense output as ``solve_ivp`` does
    (:class:`~gyro_instrument.core.integrate.Integration` with ``t_end`` = ∞): for a slow motion (the
    locked and outer-fixed swings: a step covers many samples) this costs nothing per sample. The steps
    never depend on the samples, so blocks concatenate to the one-shot run bit for bit."""
    def f(t, y):
        return np.array(rhs(t, *y.tolist()))
    return Integration(f, y0, t0, math.inf, method="DOP853", rtol=rtol, atol=atol,
                       meta={"driver": "DOP853 (scipy OdeSolver, dense output)"})


class GimbalRuns:
    """The chain, the integrators and the columns of :class:`~.instrument.GimbalGyroscope`."""

    #: The hinge chain sums every term through the hooks; the closed form (:mod:`.dynamics`, Python or
    #: compiled) the Ω-linear and quadratic inertia torques (coefficients measured) and the hinge hooks.
    MODELS = {"hinge_chain": frozenset({RIGID_BODY, DAMPING, SPIN, CARRIER_INERTIA}),
              "closed_form": frozenset({GYROSCOPIC, CENTRIFUGAL_TORQUE, DAMPING, SPIN, CARRIER_INERTIA})}

    @classmethod
    def model_taken(cls, params, effects) -> str:
        """``hinge_chain`` if asked, or under ``auto`` for a term the closed form lacks; else ``closed_form``."""
        chosen = params.get("integrator", "auto")
        if chosen == "hinge_chain" or (chosen == "auto" and cls.uncarried_effects("closed_form", effects)):
            return "hinge_chain"
        return "closed_form"

    # ---------------------------------------------------------------- model
    def swing_inertias(self) -> tuple:
        """(J_outer, J_inner): A + C1 + A2 about PP' (rings perpendicular) and A + A1 about NN', kg m²."""
        _, J_thick, J_fixed = swing_inertias_kg_m2(self.p.transverse_inertia_kg_m2, self.A1, self.C1, self.A2)
        return J_thick, J_fixed

    def build_chain(self) -> HingeChain:
        """Hinge chain outer ring (about oz) → inner ring (about NN') → rotor (about oQ).

        ``pivot_damping`` puts −(2/τ) J q̇ on the outer and inner hinges with the constant swing
        inertias of :meth:`swing_inertias` (small swings decay as e^(−t/τ)); ``spin_decay`` puts
        −C φ̇ / τ on the rotor bearing (φ̇ the rotor's rate relative to the inner ring; an internal
        torque, so it enters the rotor's equation only).
        """
        conf = self.p.configuration
        links = [
            Link("outer_ring", np.array([0.0, 0.0, 1.0]), np.diag([self.A2, self.C2, self.A2]),
                 locked=(conf == "outer_fixed"), locked_angle=self.p.outer_fixed_angle_rad + math.pi / 2),
            Link("inner_ring", np.array([1.0, 0.0, 0.0]), np.diag([self.A1, self.C1, self.A1]),
                 locked=(conf == "locked"), locked_angle=math.pi / 2),
            Link("rotor", np.array([0.0, 0.0, 1.0]), np.diag([self.p.transverse_inertia_kg_m2, self.p.transverse_inertia_kg_m2, self.C]), spin_inertia=self.C),
        ]
        links[0].swing_inertia, links[1].swing_inertia = self.swing_inertias()
        g = np.array([0.0, 0.0, -self.site.gravity_m_s2])
        return HingeChain(links, self.frame, self.site.earth_rate_enu(), g, self.effects.values(), self.context)

    def initial_state(self, chain) -> np.ndarray:
        """y0 = [q_free, q̇_free] at release: ψ0, θ0, φ0 = 0, ψ̇0, θ̇0, φ̇0 = ρ0 − ψ̇0 cos θ0."""
        q = np.array([self.psi0, self.theta0, 0.0])
        qd = np.array([self.p.initial_outer_rate_rad_s, self.p.initial_inner_rate_rad_s,
                       self.p.spin_rate_rad_s - self.p.initial_outer_rate_rad_s * math.cos(self.theta0)])
        return np.concatenate([q[chain.free], qd[chain.free]])

    # ---------------------------------------------------------------- integrator
    def kernels_fit(self) -> bool:
        """True when the compiled kernels (:func:`~.kernels.free_kernel`, :func:`~.kernels.held_kernel`)
        hold every active term: rigid-body terms c_l L + c_q Ω × IΩ and hinge torques linear in the rates."""
        if self.rigid_body_coefficients is None:
            return False
        return self.kernel_params(self.build_chain()) is not None

    def integrator_choice(self) -> tuple:
        """(integrator, reason): what ``integrator`` (``auto`` by default) runs and why.

        ``compiled`` (numba kernels through :mod:`gyro_instrument.core.dop853_jit`) for the free
        rings (whose nutation needs ~1700 steps per simulated second) when numba is enabled and
        :meth:`kernels_fit`; else ``closed_form`` (:mod:`.dynamics`) whenever the
        active effects' rigid-body terms are c_l L + c_q Ω × IΩ
        (:func:`~.dynamics.rigid_body_coefficients`: true of every registered effect);
        ``hinge_chain`` otherwise, or when the scene asks for it."""
        from gyro_instrument.core import jit
        if self.p.integrator == "hinge_chain":
            return "hinge_chain", "chosen in the scene"
        if self.rigid_body_coefficients is None:
            return "hinge_chain", ("auto: an active effect's rigid-body terms are not the Earth rate's first- and "
                                   "second-order terms, which only the generic chain sums")
        if self.p.integrator != "auto":
            return self.p.integrator, f"chosen in the scene ({jit.status()})" if self.p.integrator == "compiled" \
                else "chosen in the scene"
        if self.p.configuration != "free":
            return "closed_form", ("auto: the locked or outer-fixed swing is slow (a DOP853 step covers many samples): "
                                   "scipy's DOP853 with dense output runs it thousands of times faster than real "
                                   "time without loading numba (~0.6 s)")
        if not self.kernels_fit():
            return "closed_form", ("auto: an active hinge torque is not linear in its rate, which only the Python "
                                   "closed form calls (16-75x less CPU than the chain at the same rtol)")
        if not jit.enabled():
            return "closed_form", f"auto: the compiled kernels would run uncompiled ({jit.status()})"
        return "compiled", (f"auto: the free rings' nutation needs ~1700 DOP853 steps per simulated second and the "
                            f"effects' terms fit the compiled kernels ({jit.status()}; the first run on a machine "
                            f"compiles for ~15 s, later processes load numba and the cache in ~0.6 s): 15-30x less "
                            f"CPU than the closed form on Python floats at the same rtol")

    def chosen_integrator(self, duration_s=None) -> tuple:
        """:meth:`integrator_choice` (``describe`` shows it)."""
        return self.integrator_choice()

    # ---------------------------------------------------------------- drivers
    def closed_form(self, chain) -> tuple:
        """(rhs, y0) of :func:`~.dynamics.closed_form_rhs` for this gimbal, in ``chain``'s state layout."""
        held = {"locked": chain.links[1].locked_angle, "outer_fixed": chain.links[0].locked_angle}
        inertias = (self.p.transverse_inertia_kg_m2, self.C, self.A1, self.C1, self.A2, self.C2)
        rhs = closed_form_rhs(self.p.configuration, inertias, chain.omega_base, self.rigid_body_coefficients,
                              self.effects.values(), held.get(self.p.configuration, 0.0), self.swing_inertias(),
                              self.context)
        return rhs, [float(v) for v in self.initial_state(chain)]

    def kernel_params(self, chain) -> "tuple | None":
        """(kernel name, parameter array) of :func:`~.kernels.kernel_params` for this gimbal, or None
        when an effect's hinge torque is not linear in its rate (the compiled kernels do not fit)."""
        held = {"locked": chain.links[1].locked_angle, "outer_fixed": chain.links[0].locked_angle}
        inertias = (self.p.transverse_inertia_kg_m2, self.C, self.A1, self.C1, self.A2, self.C2)
        return kernel_params(self.p.configuration, inertias, chain.omega_base, self.rigid_body_coefficients,
                             self.effects.values(), held.get(self.p.configuration, 0.0), self.swing_inertias(),
                             self.context)

    def compiled_run(self, chain, t0) -> CompiledRun:
        """The compiled closed form's resumable run from ``t0`` (s): :func:`~.kernels.free_kernel` or
        :func:`~.kernels.held_kernel` through :class:`~gyro_instrument.core.dop853_jit.CompiledRun`
        (DOP853 with dense output, steps never steered by the samples)."""
        name, params = self.kernel_params(chain)
        y0 = [float(v) for v in self.initial_state(chain)]
        return CompiledRun(compiled_kernel(name), params, y0, t0, self.p.rtol, ATOL)

    def closed_form_run(self, chain, t0) -> Solver:
        """The closed form's resumable run from ``t0`` (s): sample to sample through Hairer's Fortran
        DOP853 (:class:`~gyro_instrument.core.dop853_fortran.FortranRun`) for the free rings, whose
        nutation takes tens of steps per sample; scipy's DOP853 stepped with no end, the samples read
        from its dense output (:class:`~gyro_instrument.core.integrate.Integration`, ``t_end`` = ∞),
        for the slow locked and outer-fixed swings, whose steps cover many samples
        (``gyro-instrument bench``, realtime.csv: the work-precision rows of both drivers)."""
        rhs, y0 = self.closed_form(chain)
        if self.p.configuration == "free":
            return FortranRun(rhs, y0, t0, self.p.rtol, ATOL)
        return dense_run(rhs, y0, t0, self.p.rtol, ATOL)

    def simulate(self, t) -> Simulation:
        """Integrate from the initial angles and rates (relative to the Earth) with spin ρ0.

        Parameters
        ----------
        t : array_like
            Increasing sample times, s.

        Returns
        -------
        Simulation
            ``columns`` as in ``COLUMNS``; ``extra`` holds ``psi``, ``theta`` (Quet's angles,
            rad), ``rotor_joint_rate`` (φ̇, rad/s) and the ``chain``. ``trajectory.meta`` names
            the ``integrator`` and why (:meth:`integrator_choice`).

        Raises
        ------
        IntegrationError
            When the integrator fails (a step size below round-off).
        """
        t = np.asarray(t, dtype=float)
        chain = self.build_chain()
        choice, why = self.integrator_choice()
        if choice == "hinge_chain":
            traj = integrate(chain.rhs, self.initial_state(chain), t, rtol=self.p.rtol, atol=ATOL)
            traj.meta.update(integrator=choice, reason=why)
            return self._simulation(traj.t, traj.y, traj, chain)
        run = self._run(choice, chain, t[0])
        span = float(t[-1] - t[0]) or 1.0
        traj = run.advance(t, progress=lambda ti: report((ti - t[0]) / span))
        traj.meta.update(integrator=choice, reason=why)
        return self._simulation(t, traj.y, traj, chain)

    def _run(self, choice, chain, t0):
        """The resumable run of ``choice`` (``compiled`` or ``closed_form``) from ``t0``."""
        return self.compiled_run(chain, t0) if choice == "compiled" else self.closed_form_run(chain, t0)

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """:meth:`simulate` block by block (see :meth:`Instrument.stream`).

        With the closed form, one run (:meth:`compiled_run` or :meth:`closed_form_run`) advances over
        the blocks, its steps never steered by the blocks, so the concatenated blocks equal :meth:`simulate` over the
        concatenated times bit for bit (``tests/test_gimbal.py``), and memory is one block.
        ``hinge_chain`` (the reference) integrates the whole run at once and slices it.
        """
        choice, why = self.integrator_choice()
        if choice == "hinge_chain":
            yield from super().stream(blocks, **options)
            return
        chain, run = self.build_chain(), None
        for b in blocks:
            b = np.asarray(b, dtype=float)
            if run is None:
                if b.size == 0:
                    continue
                run = self._run(choice, chain, b[0])
            traj = run.advance(b)
            traj.meta.update(integrator=choice, reason=why)
            yield self._simulation(b, traj.y, traj, chain)

    def _simulation(self, t, y, traj, chain) -> Simulation:
        """Columns and Quet's angles from states ``y`` (chain layout, shape (2 nf, m))."""
        nf = chain.nf
        m = y.shape[1]
        q = np.array([[L.locked_angle] * m for L in chain.links], dtype=float)
        qd = np.zeros((3, m))
        q[chain.free] = y[:nf]
        qd[chain.free] = y[nf:]
        psi, theta, phi = q
        psid, thetad, phid = qd
        rho = phid + psid * np.cos(theta)
        cols = {"outer_angle": psi - math.pi / 2, "inner_angle": theta - self.theta_ref, "rotor_angle": phi,
                "outer_rate": psid, "inner_rate": thetad, "spin_rate": rho}
        return Simulation(t, cols, traj, extra={"psi": psi, "theta": theta, "rotor_joint_rate": phid, "chain": chain})

    def mass_matrix(self, chain, qf) -> np.ndarray:
        """Mass matrix M(q) of the free coordinates (Kane: M_ab = Σ_k P_kaᵀ I_k P_kb), kg m².

        For the free configuration, from eq. (12, first), M = [[u² + C cos²θ, 0, C cos θ],
        [0, a, 0], [C cos θ, 0, C]] in (ψ, θ, φ), so det M = a C u² with u² ≥ A1 + A2: the
        rings keep M regular at gimbal lock (θ → 0), where massless rings give a C A sin²θ → 0.
        """
        q, qd = chain.full_coordinates(np.asarray(qf, dtype=float), np.zeros(chain.nf))
        _, _, _, P = chain.kinematics(q, qd)
        M = np.zeros((chain.nf, chain.nf))
        for k, L in enumerate(chain.links):
            for a, j in enumerate(chain.free):
                for b, i in enumerate(chain.free):
                    if j <= k and i <= k:
                        M[a, b] += P[k][j] @ L.inertia @ P[k][i]
        return M

    # ---------------------------------------------------------------- invariants
    def invariants(self, sim) -> dict:
        """Quet's integrals along a simulation (arrays over the samples).

        Returns
        -------
        dict
            ``spin_13_rad_s``: eq. (13), ρ − k cos θ + k' sin θ sin ψ; ``energy_12_J``: eq. (12,
            first), a θ̇² + u²ψ̇² + Cρ² (twice the relative kinetic energy); ``jacobi_J``: the
            exact integral T_rel − ½ Σ Ωᵀ I Ω (J); ``axial_momentum_kg_m2_s``: §V eq. (2, second)
            (conserved when k' = 0).
        """
        psi, theta = sim.extra["psi"], sim.extra["theta"]
        c = sim.columns
        A, C, A1, C1, A2 = self.p.transverse_inertia_kg_m2, self.C, self.A1, self.C1, self.A2
        e12 = quet_energy(theta, c["inner_rate"], c["outer_rate"], c["spin_rate"], A, C, A1, C1, A2)
        chain = sim.extra["chain"]
        om = chain.omega_base
        t0 = np.empty_like(e12)
        for i in range(e12.size):
            qf = np.array([psi[i], theta[i], 0.0])[chain.free]
            Bs = chain.orientations(chain.full_coordinates(qf, np.zeros(chain.nf))[0])
            t0[i] = 0.5 * sum((B.T @ om) @ L.inertia @ (B.T @ om) for B, L in zip(Bs, chain.links))
        return {"spin_13_rad_s": spin_invariant(c["spin_rate"], theta, psi, self.k, self.k_prime),
                "energy_12_J": e12,
                "jacobi_J": 0.5 * e12 - t0,
                "axial_momentum_kg_m2_s": axial_momentum(theta, c["outer_rate"], c["spin_rate"], self.k,
                                                         A, C, A1, C1, A2)}
