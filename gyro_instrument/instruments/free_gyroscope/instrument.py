"""Free gyroscope: Quet 1853 sec. 4 §II (the axis moves like a parallactic telescope).

A body of revolution (transverse moment A, axial moment C, μ = C/A) turns freely about its
fixed centre of mass; no torque acts on it (Quet's problem; a mass unbalance and bearing
friction may be added, see "Torques" below, with ``model: numerical``). Its axis is held at rest relative to the Earth in
any direction, the body is given a relative spin ρ0 about the axis, and the axis is released
at the first sample time ``t[0]`` (Quet's problem statement, §II).

Frames and angles
-----------------
ENU at the site (x east, y north, z up); ê = (0, cos γ, sin γ) the north part of Earth's
axis. The initial axis is given by ``initial_axis_altitude_deg`` and
``initial_axis_azimuth_deg`` (compass: 0 north, 90 east, clockwise seen from above); the
positive spin ρ0 turns right-handed about that direction. θ0 below is the angle between the
axis and the NORTH part of Earth's axis, cos θ0 = k0·ê. Quet measures his θ from the SOUTH
part (his ``oz`` is "parallèle à la partie australe de l'axe terrestre"), so his
cos θ0 = −cos θ0 here; sin θ0 is the same. Output columns: ``axis_altitude`` and
``axis_azimuth`` (compass, unwrapped), the axis' equatorial coordinates relative to the Earth
``declination`` and ``hour_angle`` (from the local meridian, positive toward the west,
unwrapped: a star's hour angle grows at +n) and the relative spin ``spin_rate`` (Quet's ρ).

Closed form (``model: analytic``, default)
------------------------------------------
In an inertial frame (ENU frozen at release) the Earth turns at Ω = n ê, the body starts with
absolute angular velocity ω0 = ρ0 k0 + Ω and the torque-free symmetric top is solved exactly:

* the absolute spin ω3 = ω·k = ρ0 + n cos θ0 is constant (Quet eq. (1)–(2): d(ρ − n cos θ)
  = 0 in his sign convention);
* the angular momentum L = A ω0 + (C − A) ω3 k0 is constant;
* the axis precesses about L with angular velocity Λ = L/A: k(t) = Rot(Λ t) k0, on a cone of
  half-angle β, sin β = A n sin θ0 / |L|, at the rate λ = |L|/A =
  √(n² sin²θ0 + μ² ω3²) — Quet's h (eq. 22 exactly for μ = 1; eq. 50 to first order);
* the body turns about its own axis at (1 − μ) ω3 relative to that precessing frame.

The axis relative to the Earth is Rot(ê, −n t) k(t). Nothing is expanded in n/ρ0: the
inertial-frame solution carries every n² (centrifugal) term exactly, so there is no separate
``centrifugal`` switch; ``earth_rotation`` absent means n = 0 in the model (the axis stays
put). The cost is independent of the horizon, so a day or a year costs the same as a second:
this is the "averaging" that resolving the nutation numerically (~1e9 right-hand-side
evaluations per day) would otherwise need, and it is exact rather than averaged.

Everything is built from vectors (no Euler angles), so no initial direction is singular:
the axis may start on, or within any distance of, either part of Earth's axis. (Quet's
expansions, eqs. (11), (53), are stated to need cos θ0 away from −1; with ρ0 ≫ n the
condition 1 + cos θ0 > 2 n sin²θ0/(μ ρ0) actually holds arbitrarily near the pole, because
sin²θ0 vanishes as fast as 1 + cos θ0; what is singular there is the Euler angle ψ.) Only the
hour angle itself is undefined for an axis exactly on Earth's axis (it is then reported as the
``atan2`` of two roundoff-sized numbers, finite but meaningless).

Predictions (Quet eqs. 16, 19, 47, 48)
--------------------------------------
* Mean rate of the axis about Earth's axis: V = n, westward (opposite to the Earth's rotation;
  eq. 47). In the closed form it is exactly n whenever the nutation cone does not enclose
  Earth's axis (the inertial azimuth of k about ê is then periodic); otherwise n ∓ λ.
* Nutation: circular, diameter 2 n sin θ0/(μ ρ0) (eqs. 16, 19; exact: 2β), period
  2π/h ≈ 2π/(μ ρ0) (exact: 2π/λ, λ = |L|/A). The text once prints 2π/n: a misprint.
  ρ0 = 60 rad/s, μ = 1: 2n/ρ0 = 2.43e-6 rad = 0.50″.
* Zero spin: Quet (§II, item 1) concludes that the body stays in relative equilibrium. That
  holds to first order in n only. Exactly, a body co-rotating with the Earth keeps
  co-rotating only if Ω is a principal axis (μ = 1, or the axis along or across Earth's
  axis): otherwise L = I Ω is not parallel to Ω and the centrifugal torque (C − A) n² sin θ0
  cos θ0 — dropped by Quet's "relative vis viva" integral, eq. (2), which is exact only for
  μ = 1 (the exact integral is T_rel − ½ Ωᵀ I Ω) — turns the axis: its declination starts
  moving as ½ (μ − 1) n² sin θ0 cos θ0 t² (≈ 1° in an hour for μ = 2, θ0 = 45°).
  In general d²(cos θ)/dt² = n sin²θ0 [μ ρ0 + (μ − 1) n cos θ0] at release; Quet's eq. (9)
  gives only the first term.

Checks of the printed text (sec. 4 §II)
---------------------------------------
* Sphere (μ = 1), eqs. (20)–(46): these are exact (the Jacobi correction vanishes), and
  quadrature of eq. (21) over a half period along eq. (30) gives V = n to 1e-15 for any n/ρ0
  (checked at n/ρ0 = 1/2 … 1/60): eq. (47) is exact, not only first order. Eq. (42) reproduces
  this only with A2 = −n (cos θ0 − cos θ')/4 in eq. (32) (printed +); eq. (46) as printed
  gives 1.00012 n at n/ρ0 = 1/60. The first series (36) lacks the factor 2 on tan²μ cos 4x.
* Eqs. (12), (51) print d²θ/dt² for (dθ/dt)²; the integral of eq. (18) is garbled (it is
  n ρ0 (t − sin(ht)/h)/(ρ0 − 2n cos θ0)); the nutation period is once printed 2π/n (2π/h);
  "1/72000 mm" computes to 1/7200 mm (2n/ρ0 × 0.36 m/(2π) = 1.4e-4 mm).
* Eqs. (16), (19) agree with the closed form to ≤ 5 (n/(μρ0)) β, signs included.

Numerical path (``model: numerical``)
-------------------------------------
Run by :mod:`.runs` (the integrator choice, the drivers, the streamed run). The state
is the unit quaternion q (body → inertial, scalar first; body z is the figure axis) and
the body-axis angular velocity ω, in the inertial frame. Two integrators (``integrator``):

* ``splitting`` (``auto``): the exact flow of the torque-free symmetric top from any state
  (:mod:`gyro_instrument.core.rigid_body_flow`; the closed form above, restarted) composed with the
  exact flows of the torques at frozen attitude — angular-momentum kicks — as in Celledoni, Fassò,
  Säfström & Zanna, SIAM J. Sci. Comput. 30(4), 2008: Strang (order 2), Yoshida's triple jump (4) or
  his 7-stage solution A (6, the default ``splitting_order``). Without a torque it is one exact step
  per sample (the closed form to round-off). Under a torque across the axis the kicks excite
  nutation, so the measured axis error follows err ≈ K_p (s/λ)(λh)^p, s the torque's slow rate, λ
  the nutation rate (:meth:`FreeGyroscope.splitting_step` picks h for err ≈ rtol rad): the step
  resolves the nutation, but each step is exact in the spin and cheap (a compiled loop), so
  it runs thousands of times real time where DOP853 runs tens (``bench`` spin_free).
* ``dop853``: DOP853 on Euler's equations ω̇1 = (1 − μ) ω3 ω2 + τ1/A, ω̇2 = (μ − 1) ω3 ω1 + τ2/A,
  ω̇3 = τ3/C and q̇ = ½ q ⊗ (0, ω) plus a Baumgarte term κ (1 − |q|²) q that holds |q| at 1; q is
  renormalised before use. Its cost grows as the horizon times μ ρ0. The independent cross-check.
  With numba (:mod:`gyro_instrument.core.jit`) Hairer's DOP853 runs compiled, dense output and all
  (:mod:`gyro_instrument.core.dop853_jit`), on the compiled right-hand side
  :func:`~gyro_instrument.core.rigid_body_flow.rhs_kernel` (the arithmetic of :meth:`FreeGyroscope.rhs_scalar`,
  term for term): the same steps as the Python-float driver (``GYRO_INSTRUMENT_JIT=0``), ~100–300×
  faster (``bench`` spin_free, realtime).

Torques (``model: numerical`` only; the closed form refuses them through the scene checks)
------------------------------------------------------------------------------------------
* Mass unbalance: the centre of mass at d = ``center_of_mass_offset_m`` from the fixed point along
  the figure axis, mass m = ``rotor_mass_kg``: the gravity torque m g d k × (−up) (``up`` the local
  vertical, turning with the Earth in the inertial frame), the classic drift source of a free
  (two-gimbal) gyro: the axis precesses about the vertical at m g d / (C ω3). Mass-unbalance
  drift: D. Lawrence, "Modern Inertial Technology", 2nd ed., Springer 1998, ch. 8 (ASSUMED
  citation: not checked against the text here). A, C are the moments about the fixed point.
* ``spin_decay``: the bearing torque −C ρ/τ along the axis on the spin relative to the Earth,
  ρ = ω3 − n k·ê (:meth:`~gyro_instrument.effects.spin_decay.SpinDecay.spin_torque_per_inertia`).
Without earth_rotation and with an unbalance this is Lagrange's heavy top: the energy
T + m g d k·up, L·up and ω3 are constants (tests/test_free_gyroscope_splitting.py).
"""

import math

import numpy as np

from gyro_instrument.core.effect import FRAME_RATE, SPIN, VISCOUS_SPIN, Scales
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.rigid_body_flow import COMPOSITIONS
from gyro_instrument.core.params import Param
from gyro_instrument.core.quaternion import quat_from_matrix
from gyro_instrument.instruments.base import Column, Instrument, with_notes
from gyro_instrument.instruments.observation import RotorObservation
# The geometry and the closed form live in .theory; re-exported here, where they were defined.
from gyro_instrument.instruments.free_gyroscope.theory import (angle_between, axis_from_alt_az, axis_relative_to_earth,
                                                               body_frame, equatorial_basis)
# The integrator choice, the drivers and the streamed run live in .runs (FreeGyroscopeRuns).
from gyro_instrument.instruments.free_gyroscope.runs import FreeGyroscopeRuns

__all__ = ["FreeGyroscope", "angle_between", "axis_from_alt_az", "axis_relative_to_earth", "body_frame",
           "equatorial_basis"]

# ----------------------------------------------------------------------------- instrument


class FreeGyroscope(FreeGyroscopeRuns, Instrument):
    """Body of revolution about its fixed point, released with its axis at rest relative to the Earth;
    torque-free unless a mass unbalance or ``spin_decay`` is given.

    Parameters (``PARAMS``)
    -----------------------
    initial_axis_altitude_deg, initial_axis_azimuth_deg : float
        Initial direction of the (positive-spin) figure axis: altitude above the horizon and
        compass azimuth (0 north, clockwise), degrees.
    inertia_ratio : float
        μ = C/A, in (0, 2].
    transverse_inertia_kg_m2 : float
        A, kg m² (sets the scale of L and of the energy only; the motion depends on μ).
    spin_rate_rad_s : float
        ρ0, the initial spin about the axis relative to the Earth, rad/s (Quet's ρ0).
    model : {"analytic", "numerical"}
        Exact closed form (default; torque-free only) or time stepping by ``integrator``.
    rtol : float
        Relative tolerance of the numerical path (the splitting: the axis error aimed at, rad).
    integrator : {"auto", "splitting", "dop853"}
        ``model: numerical`` only: the splitting (``auto``) or DOP853 (module docstring).
    splitting_order : {2, 4, 6}
        Order of the splitting's composition (default 6).
    rotor_mass_kg, center_of_mass_offset_m : float
        m (kg) and the mass unbalance d (m, along the figure axis): gravity torque m g d k × (−up).
    """

    type_name = "free_gyroscope"
    summary = ("free body of revolution: parallactic motion and nutation (Quet sec. 4 §II); mass unbalance "
               "drift and spin decay with the numerical model")
    PARAMS = (
        Param("initial_axis_altitude_deg", default=0.0, low=-90.0, high=90.0,
              doc="initial axis altitude above the horizon, degrees"),
        Param("initial_axis_azimuth_deg", default=90.0, low=-360.0, high=360.0,
              doc="initial axis compass azimuth (0 north, 90 east, clockwise), degrees"),
        Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True,
              doc="μ = C/A, axial over transverse moment (≤ 2 for a rigid body of revolution)"),
        Param("transverse_inertia_kg_m2", default=1.0e-3, low=0.0, open_low=True, doc="A, kg m^2"),
        Param("spin_rate_rad_s", default=60.0, low=-1.0e6, high=1.0e6,
              doc="initial spin ρ0 about the axis relative to the Earth, rad/s (right-handed "
                  "about the axis direction; Quet's example 60)"),
        Param("model", kind="str", default="analytic", choices=("analytic", "numerical"),
              doc="analytic: exact torque-free closed form (refused under a torque: spin_decay or "
                  "center_of_mass_offset_m); numerical: time stepping by the integrator parameter"),
        Param("rtol", default=1e-12, low=1e-14, high=1e-3,
              doc="numerical path tolerance: DOP853's relative tolerance; the splitting's aimed axis error, rad"),
        Param("integrator", kind="str", default="auto", choices=("auto", "splitting", "dop853"),
              doc="model numerical: splitting (exact torque-free flow composed with torque kicks: one step "
                  "per sample without a torque; under one, steps from rtol that resolve the nutation it "
                  "excites), dop853 (quaternion + Euler equations, resolves spin and nutation), auto "
                  "(splitting)"),
        Param("splitting_order", kind="int", default=6, low=2, high=6,
              doc="order of the splitting composition: 2 Strang, 4 Yoshida triple jump, 6 Yoshida"),
        Param("rotor_mass_kg", default=1.0, low=0.0, open_low=True,
              doc="mass of the rotor, kg (with center_of_mass_offset_m: the unbalance torque)"),
        Param("center_of_mass_offset_m", default=0.0, low=-1.0, high=1.0,
              doc="mass unbalance: centre of mass at this distance from the fixed point along the "
                  "figure axis (positive toward the spin axis direction), m; gravity torque "
                  "m g d k × (−up)"),
    )
    MECHANICS = frozenset({FRAME_RATE, SPIN})
    #: The closed form is torque-free (the frame rate only); the numerical paths (splitting's kicks,
    #: DOP853) carry a viscous spin friction −C ρ/τ by its τ (:meth:`viscous_spin_time_s`).
    MODELS = {"analytic": frozenset({FRAME_RATE}), "numerical": frozenset({FRAME_RATE, VISCOUS_SPIN})}

    @classmethod
    def model_taken(cls, params, effects) -> str:
        """The ``model`` parameter: ``analytic`` (default) or ``numerical``."""
        return params.get("model", "analytic")
    MEASURED_CHANNELS = ("axis_altitude", "axis_azimuth")
    JOINTS = ("axis_altitude", "axis_azimuth", "rotor")
    OBSERVATION = RotorObservation
    SHOWS_AXIS = True
    STREAMS = True

    def axis_direction_enu(self, position) -> np.ndarray:
        """Rotor axis in ENU, (m, 3), from the ``axis_altitude`` and ``axis_azimuth`` (compass) joints, rad."""
        import numpy as np
        alt, az = np.asarray(position)[:, 0], np.asarray(position)[:, 1]
        return np.column_stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])
    SIMULATOR_NODE = "gyrocompass_sim"
    COLUMNS = (
        Column("axis_altitude", "rad", "altitude of the figure axis above the horizon"),
        Column("axis_azimuth", "rad", "compass azimuth of the axis (0 north, clockwise), unwrapped"),
        Column("hour_angle", "rad", "hour angle of the axis relative to the Earth (westward), unwrapped"),
        Column("declination", "rad", "declination of the axis (angle above the equatorial plane)"),
        Column("spin_rate", "rad/s", "ρ: spin of the body about its axis relative to the Earth"),
    )

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        self.C = self.p.inertia_ratio * self.p.transverse_inertia_kg_m2
        self.k0 = axis_from_alt_az(math.radians(self.p.initial_axis_altitude_deg),
                                   math.radians(self.p.initial_axis_azimuth_deg))
        self.e_axis = site.earth_axis_north_enu()
        self.eq_m, self.eq_w, _ = equatorial_basis(site)
        self.R0 = body_frame(self.k0)
        self.q0 = quat_from_matrix(self.R0)
        self.theta0 = angle_between(self.k0, self.e_axis)

    @classmethod
    def check_params(cls, prefix, p) -> None:
        """Refuse a splitting order other than 2, 4, 6 and an explicit integrator with the closed form
        (the integrator steps ``model: numerical`` only); raises SceneError."""
        if p.get("splitting_order", 4) not in COMPOSITIONS:
            raise SceneError(f"{prefix}.splitting_order", p["splitting_order"],
                             f"must be one of {', '.join(str(o) for o in COMPOSITIONS)}")
        if p.get("model", "analytic") == "analytic" and p.get("integrator", "auto") != "auto":
            raise SceneError(f"{prefix}.integrator", p["integrator"],
                             "must be auto with model = analytic (the closed form has no integrator; set "
                             "model: numerical to choose one)")

    @classmethod
    def check_effects(cls, prefix, p, effect_names) -> None:
        """Refuse an effect the model taken cannot carry (a spin torque under the torque-free closed form,
        ``model: analytic``; one of general form under either: :data:`MODELS`) and the closed form under
        a mass unbalance (``center_of_mass_offset_m`` ≠ 0; use ``model: numerical``); raises SceneError."""
        super().check_effects(prefix, p, effect_names)
        if p.get("model", "analytic") == "analytic" and p.get("center_of_mass_offset_m", 0.0):
            raise SceneError(f"{prefix}.center_of_mass_offset_m", p["center_of_mass_offset_m"],
                             "must be 0 with model = analytic: the mass unbalance's gravity torque has no closed "
                             "form here (set model: numerical)")

    def torqued(self) -> bool:
        """True when a torque acts: a viscous spin friction (``spin_decay``) or a mass unbalance
        (``center_of_mass_offset_m``)."""
        return self.has_term(VISCOUS_SPIN) or self.p.center_of_mass_offset_m != 0.0

    def viscous_spin_time_s(self) -> "float | None":
        """τ (s) of the active viscous spin friction (the bearing torque −C ρ/τ), None without one."""
        return self.spin_decay_time_s(self.C)

    def unbalance_torque_per_inertia(self) -> float:
        """m g d / A, rad/s²: the gravity torque of the mass unbalance over the transverse moment."""
        return self.p.rotor_mass_kg * self.site.gravity_m_s2 * self.p.center_of_mass_offset_m / \
            self.p.transverse_inertia_kg_m2

    # ---------------------------------------------------------------- constants of motion
    def model_rate(self) -> float:
        """n used by the model: the active ``frame_rate`` effects' rate (``earth_rotation``: the
        site's Earth rate), else 0 (:meth:`Instrument.model_earth_rate`)."""
        return self.model_earth_rate()

    def motion_constants(self, n=None) -> dict:
        """Exact constants of the torque-free motion (inertial frame = ENU at release).

        Parameters
        ----------
        n : float, optional
            Earth rate, rad/s (default: :meth:`model_rate`).

        Returns
        -------
        dict
            ``omega0`` absolute angular velocity at release (rad/s, ENU); ``omega3`` absolute
            spin ρ0 + n cos θ0 (rad/s, constant); ``Lambda`` = L/A (rad/s, the precession
            vector of the axis); ``lam`` = |L|/A (rad/s); ``sigma`` = (1 − μ) ω3, the body's
            rate about its axis relative to the precessing frame (rad/s); ``beta`` the cone
            half-angle between k0 and L (rad).
        """
        n = self.model_rate() if n is None else n
        omega0 = self.p.spin_rate_rad_s * self.k0 + n * self.e_axis
        omega3 = float(np.dot(omega0, self.k0))
        Lam = omega0 + (self.p.inertia_ratio - 1.0) * omega3 * self.k0
        lam = float(np.linalg.norm(Lam))
        beta = angle_between(self.k0, Lam) if lam > 0.0 else 0.0
        return {"omega0": omega0, "omega3": omega3, "Lambda": Lam, "lam": lam,
                "sigma": (1.0 - self.p.inertia_ratio) * omega3, "beta": beta}

    # ---------------------------------------------------------------- predictions
    def predictions(self) -> dict:
        """Quet's predictions (eqs. 16, 19, 22, 47, 48, 50) beside the exact closed-form values.

        Returns
        -------
        dict
            ``theta0_rad``: angle between the axis and the north part of Earth's axis;
            ``theta0_quet_rad``: Quet's θ0, from the south part (π − θ0);
            ``mean_axis_rate_rad_s``: V = n, westward (eq. 47: hour angle grows at +n);
            ``mean_hour_angle_rate_exact_rad_s``: the closed form's long-run rate (n unless the
            nutation cone encloses Earth's axis);
            ``nutation_diameter_rad``: 2 n sin θ0/(μ ρ0) (eqs. 16, 19; printed 2n sin θ0/ρ0 for
            μ = 1 in eq. 48); ``nutation_diameter_exact_rad``: 2β;
            ``nutation_period_s``: 2π/(μ ρ0); ``nutation_period_quet_h_s``: 2π/h with Quet's
            h (eq. 22 for μ = 1, eq. 50 otherwise); ``nutation_period_exact_s``: 2π A/|L|;
            ``relative_spin_law``: ρ = ρ0 + n (cos θ_Q − cos θ0_Q) (eq. 7; printed here in the
            north-axis form ρ0 + n (cos θ0 − cos θ));
            ``initial_cos_theta_acceleration_rad_s2``: d²(cos θ)/dt² at release, exact,
            n sin²θ0 [μ ρ0 + (μ − 1) n cos θ0] (Quet's eq. 9 keeps only n μ ρ0 sin²θ0);
            ``relative_equilibrium_exact``: True when the zero-spin body stays at rest relative
            to the Earth exactly (μ = 1, axis along or across Earth's axis, or n = 0);
            with n ≠ 0, what the paper could not know (:meth:`_zero_spin_departure`):
            ``zero_spin_departure_1h_rad`` (≥ 0, exact), ``zero_spin_departure_1h_leading_rad``,
            ``initial_cos_theta_acceleration_quet_relative_error`` and ``beyond_the_paper`` (str).
            Rates are signed (the hour angle grows at +n: westward); magnitudes are ≥ 0.
            With a mass unbalance: ``unbalance_precession_rate_rad_s`` = m g d / (C ω3), the axis'
            precession about the vertical (counterclockwise seen from above when positive; the
            steady precession of a fast top, exact for a horizontal axis: m g d = Ω (C ω3 − A Ω cos θ),
            θ from the vertical; e.g. Goldstein, Classical Mechanics, §5.7).
        """
        n = self.model_rate()
        mu, rho0, th = self.p.inertia_ratio, self.p.spin_rate_rad_s, self.theta0
        s, c = math.sin(th), math.cos(th)
        k = self.motion_constants(n)
        lam, beta, Lam = k["lam"], k["beta"], k["Lambda"]
        # Winding of the inertial azimuth of k about ê: ±λ when the cone encloses ±ê.
        mean_rate = n
        if lam > 0.0:
            if angle_between(Lam, self.e_axis) < beta:
                mean_rate = n - lam
            elif angle_between(Lam, -self.e_axis) < beta:
                mean_rate = n + lam
        cq = -c          # Quet's cos θ0 (θ from the south part of Earth's axis)
        h_quet = math.sqrt(max(rho0 * (rho0 - 2 * n * cq) + n * n, 0.0)) if mu == 1.0 else \
            mu * math.sqrt(max(rho0 * (rho0 - 2 * n * cq), 0.0))
        gyro = mu * abs(rho0)
        out = {
            "theta0_rad": th,
            "theta0_quet_rad": math.pi - th,
            "mean_axis_rate_rad_s": n,
            "mean_hour_angle_rate_exact_rad_s": mean_rate,
            "nutation_diameter_rad": 2.0 * n * s / gyro if gyro > 0 else math.inf,
            "nutation_diameter_exact_rad": 2.0 * beta,
            "nutation_period_s": 2.0 * math.pi / gyro if gyro > 0 else math.inf,
            "nutation_period_quet_h_s": 2.0 * math.pi / h_quet if h_quet > 0 else math.inf,
            "nutation_period_exact_s": 2.0 * math.pi / lam if lam > 0 else math.inf,
            "absolute_spin_rad_s": k["omega3"],
            "initial_cos_theta_acceleration_rad_s2": n * s * s * (mu * rho0 + (mu - 1.0) * n * c),
            "relative_equilibrium_exact": bool(n == 0.0 or mu == 1.0 or s < 1e-15 or abs(c) < 1e-15),
        }
        if n != 0.0:
            out.update(self._zero_spin_departure(n))
        if self.p.center_of_mass_offset_m != 0.0 and k["omega3"] != 0.0:
            # gyroscopic (fast-top) precession of the axis about the vertical under the unbalance torque
            out["unbalance_precession_rate_rad_s"] = self.unbalance_torque_per_inertia() / (mu * k["omega3"])
        return with_notes(out, self.missing_term_note(
            FRAME_RATE, f"n = 0 in the model: the axis keeps its direction relative to the Earth (no "
                              f"parallactic motion; with it the hour angle grows at n = {self.site.earth_rate_rad_s:.8g} "
                              f"rad/s)"))

    #: The horizon over which the zero-spin departure from relative equilibrium is stated, s.
    ZERO_SPIN_HORIZON_S = 3600.0

    def _zero_spin_departure(self, n) -> dict:
        """What sec. 4 §II item 1 could not know, for this axis, μ and site: released with zero spin
        the body stays in relative equilibrium only when Ω is a principal axis (μ = 1, the axis
        along or across Earth's axis). Otherwise the centrifugal torque (C − A) n² sin θ0 cos θ0,
        which Quet's relative vis viva (eq. 2) drops, turns the axis; it leaves its place by
        ``zero_spin_departure_1h_rad`` in the first hour (exact closed form,
        :func:`axis_relative_to_earth` with ρ0 = 0), ½ |μ − 1| n² sin θ0 |cos θ0| t² to leading order
        (``zero_spin_departure_1h_leading_rad``). With the configured spin the same term changes the
        initial acceleration of cos θ by the relative amount (μ − 1) n cos θ0 / (μ ρ0)
        (``initial_cos_theta_acceleration_quet_relative_error``: Quet's eq. 9 over the exact value − 1).
        """
        T = self.ZERO_SPIN_HORIZON_S
        k1 = axis_relative_to_earth(self.k0, self.e_axis, n, self.p.inertia_ratio, 0.0, [T])[0]
        exact = angle_between(self.k0, k1)
        s, c = math.sin(self.theta0), math.cos(self.theta0)
        lead = 0.5 * abs(self.p.inertia_ratio - 1.0) * n * n * s * abs(c) * T * T
        quet_acc = n * s * s * self.p.inertia_ratio * self.p.spin_rate_rad_s
        full_acc = n * s * s * (self.p.inertia_ratio * self.p.spin_rate_rad_s + (self.p.inertia_ratio - 1.0) * n * c)
        acc_err = quet_acc / full_acc - 1.0 if full_acc != 0.0 else (0.0 if quet_acc == 0.0 else math.inf)
        worst = 0.25 * abs(self.p.inertia_ratio - 1.0) * n * n * T * T          # θ0 = 45°, leading order
        if exact < 1e-12:
            here = (f"for this axis (θ0 = {math.degrees(self.theta0):.6g}° from Earth's north axis) and μ = {self.p.inertia_ratio:g} "
                    f"Ω is a principal axis and a zero-spin release stays put (departure after 1 h below 1e-12 rad: "
                    f"round-off)")
        else:
            here = (f"for this axis (θ0 = {math.degrees(self.theta0):.6g}° from Earth's north axis) and μ = {self.p.inertia_ratio:g} "
                    f"a zero-spin release leaves its place by {math.degrees(exact):.4g}° in the first hour (leading "
                    f"order ½|μ − 1| n² sin θ0 |cos θ0| t² = {math.degrees(lead):.4g}°)")
        text = (f"sec. 4 §II item 1: released with zero spin the body stays in relative equilibrium (Quet); exact "
                f"only for μ = 1 or an axis along or across Earth's axis, because the relative vis viva (eq. 2) drops "
                f"the centrifugal torque (C − A) n² sin θ0 cos θ0: {here}")
        if self.p.inertia_ratio != 1.0:
            text += f"; with this μ an axis at 45° from Earth's axis would leave by {math.degrees(worst):.4g}° in the first hour"
        if self.p.spin_rate_rad_s != 0.0 and acc_err != 0.0:
            text += (f"; with ρ0 = {self.p.spin_rate_rad_s:g} rad/s the same term makes Quet's eq. (9) initial acceleration of "
                     f"cos θ off by {acc_err:+.3g} relative")
        return {"zero_spin_departure_1h_rad": exact, "zero_spin_departure_1h_leading_rad": lead,
                "initial_cos_theta_acceleration_quet_relative_error": acc_err, "beyond_the_paper": text}

    def scales(self, duration_s) -> Scales:
        """Scales for effect-size estimates. There is no restoring torque; the free-precession
        (nutation) rate |L|/A stands in for ``restoring_rate_rad_s`` (inf if the body is at rest
        in a non-rotating world), and ``amplitude_rad`` is the nutation radius β."""
        n = self.site.earth_rate_rad_s
        k = self.motion_constants(n)
        lam = k["lam"] if k["lam"] > 0.0 else math.inf
        return Scales(earth_rate_rad_s=n, gyro_rate_rad_s=abs(self.p.inertia_ratio * self.p.spin_rate_rad_s) or None,
                restoring_rate_rad_s=lam, amplitude_rad=k["beta"], duration_s=duration_s)
