"""Two-ring gimbal gyroscope: Quet 1853, sec. 4 §III–V.

Geometry (Quet sec. 4 §III)
---------------------------
``PP'`` is the axis fixed on the Earth about which the outer ring turns; ``NN'`` the outer
ring's diameter perpendicular to ``PP'``, about which the inner ring turns; ``oQ`` the rotor's
figure axis, carried by the inner ring perpendicular to ``NN'``; ``oD`` the inner ring's
figure axis (perpendicular to ``NN'`` and to ``oQ``); the outer ring's figure axis is
perpendicular to ``PP'`` and ``NN'``.

Base axes are Quet's: ``oz`` along ``PP'``, ``ox`` the projection of the north part of Earth's
axis on the plane perpendicular to ``PP'`` (:func:`~gyro_instrument.core.site.plane_frame`),
``oy = oz × ox``. ω is the angle between ``oz`` and the *south* part of Earth's axis, so the
Earth rate in these axes is (p, q, r) = (n sin ω, 0, −n cos ω) (sec. 1 eq. 17) and
k = n cos ω, k' = n sin ω (sec. 4 eq. 11).

Quet's angles: θ is the angle between ``oQ`` and ``oz``; ``oN`` (one half of ``NN'``) makes
the angle ψ with ``ox``, and the projection ``oA`` of ``oQ`` on ``xoy`` is at ψ − 90°::

    oN = (cos ψ, sin ψ, 0),   oQ = (sin θ sin ψ, −sin θ cos ψ, cos θ).

The chain (:class:`~gyro_instrument.instruments.chain.HingeChain`) is: outer ring, hinge
``oz`` (angle ψ, body axes x = ``oN``, y = outer figure axis, z = ``PP'``, inertia
diag(A2, C2, A2)); inner ring, hinge x = ``NN'`` (angle θ, body axes x = ``NN'``, y = ``oD``
up to sign, z = ``oQ``, inertia diag(A1, C1, A1)); rotor, hinge z = ``oQ`` (angle φ,
inertia diag(A, A, C)). ρ = φ̇ + ψ̇ cos θ is Quet's ρ, the component along ``oQ`` of the
rotor's angular velocity relative to the Earth (sec. 4 eq. 4 and 6).

Output angles (a ``sensor_msgs/JointState`` of outer ring, inner ring, rotor)
-----------------------------------------------------------------------------
* ``outer_angle`` = ψ − 90°: the azimuth of ``oA`` (the rotor axis' projection on the plane
  perpendicular to ``PP'``) from ``ox``, counter-clockwise about ``oz`` (a right-handed
  rotation of the outer ring about ``PP'``). With the rings locked the stable equilibrium
  line is ``ox`` (sec. 4 §IV: "l'axe oQ oscillera autour de ox"), so small swings are about
  0; it is the directing-plane gyroscope's u for the plane perpendicular to ``PP'``.
* ``inner_angle`` = θ − θ_ref: a right-handed rotation of the inner ring about ``NN'`` from
  a reference pose. θ_ref = 90° (rings perpendicular) for ``locked`` (where the column is
  then 0) and ``free``; for ``outer_fixed`` θ_ref is the equilibrium line of the inner swing,
  the projection of the north part of Earth's axis on the plane of the swing,
  θ_ref = atan2(sin ω cos α, −cos ω) with α the fixed ``outer_angle`` (θ_ref = 180° − ω for
  Quet's case α = 0). Quet's u of §IV (angle of ``oQ`` from the north part of Earth's axis)
  is −``inner_angle`` there.
* ``rotor_angle`` = φ (the rotor joint), ``outer_rate`` = ψ̇, ``inner_rate`` = θ̇ and
  ``spin_rate`` = ρ (not the joint rate φ̇ = ρ − ψ̇ cos θ, which is in ``extra``).

Configurations
--------------
``free`` (both rings free: sec. 4 §III eqs. 10–13 and §V), ``locked`` (inner ring held at
θ = 90°, outer ring free: §IV, periods T, T', T'''), ``outer_fixed`` (outer ring held at
``outer_fixed_angle_deg``, inner ring free: §IV, period T'').

The periods T, T', T'', T''' and Quet's integrals are in :mod:`.theory`.

Conventions of this module: ``vertical`` is ``PP'`` up (ω = 90° + γ, k = −n sin γ; Quet's
§IV T'' derivation takes ``oz`` down, k = n sin γ — the same periods); ``north_south`` points
north, ``east_west`` east, ``polar`` along the north part of Earth's axis (ω = 180°, k = −n;
Quet's §V takes the south part, ω = 0, k = n).
"""

import math

import numpy as np

from gyro_instrument.core.effect import CARRIER_INERTIA, DAMPING, GYROSCOPIC, RIGID_BODY, SPIN, Scales
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import plane_frame
from gyro_instrument.instruments.base import Column, DirectingModel, ExpectedSwing, Instrument, with_notes
from gyro_instrument.instruments.chain import HingeChain
from gyro_instrument.instruments.gimbal.torques import rigid_body_coefficients
# The chain and the integrators live in runs (GimbalRuns); ATOL is re-exported here, where it was defined.
from gyro_instrument.instruments.gimbal.runs import ATOL, GimbalRuns
from gyro_instrument.instruments.gimbal.theory import (free_mass_matrix, locked_swing_constant,
                                                       outer_fixed_swing_constant, quet_swing_durations_s,
                                                       spin_invariant, swing_duration_s, swing_inertias_kg_m2)
from gyro_instrument.instruments.observation import SwingRate

CONFIGURATIONS = ("free", "locked", "outer_fixed")
INTEGRATORS = ("auto", "compiled", "closed_form", "hinge_chain")

OUTER_AXES = ("vertical", "north_south", "east_west", "polar", "custom")

#: Default initial swing angle (0.1 rad, as for the directing-plane gyroscope), degrees.
DEFAULT_SWING_DEG = math.degrees(0.1)

#: Largest condition number of the (Jacobi-scaled) mass matrix accepted at release. Every step
#: solves M q̈ = f with LU (numpy.linalg.solve), whose relative error is up to cond · eps
#: (eps = 2.2e-16): at 1e12 that is 2e-4, fewer than 4 correct digits in the accelerations —
#: 7 orders above the default rtol (1e-11) and at the loosest the scene accepts (1e-3). At the
#: exact singularity (cond = inf) numpy raises LinAlgError. The scaling D^-1/2 M D^-1/2
#: (D = diag M) removes the units of the coordinates, which LU with pivoting does not mind
#: (a rotor far lighter than its rings is not degenerate); the massless-ring gimbal near the
#: lock has cond ≈ 4(μ + 1)/sin²θ (8e6 at θ = 1e-3 rad, which runs; 1e12 at θ ≈ 2.8e-6 rad).
MAX_MASS_MATRIX_CONDITION = 1.0e12

#: Smallest rotor μ = C/A accepted. The rotor's axial equation divides its torque by C; that
#: torque is zero analytically but carries round-off ~ eps · A · rate², so as C → 0 the axial
#: acceleration is round-off over C (μ = 1e-300 overflowed). Measured: 1e-15 still integrates
#: normally (locked and outer_fixed, 2 s); 1e-12 keeps three decades of margin.
MIN_INERTIA_RATIO = 1.0e-12


def outer_axis_direction_enu(outer_axis, outer_axis_enu, site) -> np.ndarray:
    """Unit vector along ``PP'`` (Quet's ``oz``) in ENU.

    Parameters
    ----------
    outer_axis : str
        ``vertical`` (up), ``north_south`` (north), ``east_west`` (east), ``polar`` (north part
        of Earth's axis) or ``custom``.
    outer_axis_enu : array_like or None
        The direction when ``custom``.
    site : Site

    Returns
    -------
    ndarray, shape (3,)
    """
    if outer_axis == "vertical":
        v = np.array([0.0, 0.0, 1.0])
    elif outer_axis == "north_south":
        v = np.array([0.0, 1.0, 0.0])
    elif outer_axis == "east_west":
        v = np.array([1.0, 0.0, 0.0])
    elif outer_axis == "polar":
        v = site.earth_axis_north_enu()
    else:
        v = np.asarray(outer_axis_enu, dtype=float)
    return v / np.linalg.norm(v)


def scaled_condition(M) -> float:
    """Condition number (2-norm) of D^-1/2 M D^-1/2, D = diag M; inf when singular."""
    d = np.sqrt(np.diag(M))
    if not np.all(d > 0.0):
        return math.inf
    with np.errstate(all="ignore"):
        cond = float(np.linalg.cond(M / np.outer(d, d)))
    return cond if math.isfinite(cond) else math.inf


class GimbalGyroscope(GimbalRuns, Instrument):
    """Rotor in two rings, the outer turning about an axis ``PP'`` fixed on the Earth.

    See the module docstring for axes, angle conventions and the four periods of
    Quet 1853 sec. 4 §IV.
    """

    type_name = "gimbal_gyroscope"
    summary = "rotor in two gimbal rings about an Earth-fixed axis PP' (Quet sec. 4 §III–V)"
    PARAMS = (
        Param("configuration", kind="str", default="locked", choices=CONFIGURATIONS,
              doc="free (both rings free), locked (rings held perpendicular, outer free: T, T', T''') "
                  "or outer_fixed (outer ring held, inner free: T'')"),
        Param("outer_axis", kind="str", default="vertical", choices=OUTER_AXES,
              doc="direction of PP': vertical (up), north_south (north), east_west (east), "
                  "polar (north part of Earth's axis) or custom"),
        Param("outer_axis_enu", kind="vec3", default=None, doc="PP' in ENU when outer_axis = custom"),
        Param("outer_fixed_angle_deg", default=0.0, low=-180.0, high=180.0,
              doc="outer_angle at which the outer ring is held (outer_fixed), degrees; 0 = NN' across "
                  "the plane of oz and ox (across the meridian for a vertical PP': Quet's T'')"),
        Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True,
              doc="μ = C/A of the rotor (≤ 2 for a rigid body of revolution)"),
        Param("transverse_inertia_kg_m2", default=1.0e-3, low=0.0, open_low=True,
              doc="A, the rotor's moment about a diameter, kg m^2"),
        Param("inner_ring_diametral_inertia_kg_m2", default=2.5e-4, low=0.0,
              doc="A1, inner ring's moment about its diameters NN' and oQ, kg m^2"),
        Param("inner_ring_axial_inertia_kg_m2", default=None, low=0.0,
              doc="C1, inner ring's moment about its figure axis oD, kg m^2 (default 2 A1: thin ring; "
                  "must be ≤ 2 A1)"),
        Param("outer_ring_diametral_inertia_kg_m2", default=5.0e-4, low=0.0,
              doc="A2, outer ring's moment about PP' (and NN'), kg m^2"),
        Param("outer_ring_axial_inertia_kg_m2", default=None, low=0.0,
              doc="C2, outer ring's moment about its figure axis, kg m^2 (default 2 A2: thin ring; "
                  "must be ≤ 2 A2)"),
        Param("spin_rate_rad_s", default=2 * math.pi * 100.0, low=-1.0e6, high=1.0e6,
              doc="initial relative spin ρ0 of the rotor about oQ, rad/s (positive: Earth's sense when "
                  "oQ is along ox)"),
        Param("initial_outer_angle_deg", default=None, low=-180.0, high=180.0,
              doc="initial outer_angle (rotor-axis azimuth from ox about PP'), degrees; default 5.73 "
                  "(0.1 rad) for locked and free; outer_fixed uses outer_fixed_angle_deg"),
        Param("initial_inner_angle_deg", default=None, low=-180.0, high=180.0,
              doc="initial inner_angle (θ − θ_ref), degrees; default 5.73 (0.1 rad) for outer_fixed, "
                  "0 for free; locked holds 0"),
        Param("initial_outer_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial ψ̇, degrees/s (must be 0 for outer_fixed)"),
        Param("initial_inner_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial θ̇, degrees/s (must be 0 for locked)"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
        Param("integrator", kind="str", default="auto", choices=INTEGRATORS,
              doc="compiled: the gimbal's equations unrolled as numba kernels through a compiled DOP853 with "
                  "dense output (core.dop853_jit; every configuration; the first run on a machine compiles, "
                  "later runs load numba's cache); closed_form: the same equations on Python floats (free rings: "
                  "Hairer's Fortran DOP853 from sample to sample; locked, outer_fixed: scipy's DOP853 with dense "
                  "output); both stream block by block; hinge_chain: the generic hinge chain through solve_ivp's "
                  "DOP853 (the reference; integrates the whole run before the first block); auto: compiled when "
                  "numba is enabled, the rings are free and every active hinge torque is linear in its rate, else "
                  "closed_form, unless "
                  "an active effect's rigid-body terms are not the Earth rate's first- and second-order terms "
                  "(then hinge_chain)"),
    )
    MECHANICS = frozenset({RIGID_BODY, DAMPING, SPIN, CARRIER_INERTIA})
    MEASURED_CHANNELS = ("outer_angle", "inner_angle")
    JOINTS = ("outer_ring", "inner_ring", "rotor")
    OBSERVATION = SwingRate        # RotorObservation with free rings (no directing line)
    SIMULATOR_NODE = "gyrocompass_sim"
    STREAMS = True
    COLUMNS = (
        Column("outer_angle", "rad", "ψ − 90°: azimuth of the rotor axis' projection from ox, about PP' "
                                     "(outer ring joint; equilibrium line 0 when locked)"),
        Column("inner_angle", "rad", "θ − θ_ref: inner ring about NN' from the reference pose (90° locked "
                                     "and free; the swing's equilibrium line for outer_fixed)"),
        Column("rotor_angle", "rad", "φ: rotor joint angle about oQ"),
        Column("outer_rate", "rad/s", "ψ̇"),
        Column("inner_rate", "rad/s", "θ̇"),
        Column("spin_rate", "rad/s", "ρ = φ̇ + ψ̇ cos θ: relative spin of the rotor about oQ"),
    )

    @classmethod
    def check_params(cls, prefix, p) -> None:
        """Refuse a missing custom axis, non-physical ring moments, a numerically massless rotor axis
        (inertia_ratio below :data:`MIN_INERTIA_RATIO`) and initial values for a held ring; raises
        SceneError."""
        if p["inertia_ratio"] < MIN_INERTIA_RATIO:
            raise SceneError(f"{prefix}.inertia_ratio", p["inertia_ratio"],
                             f"must be in [{MIN_INERTIA_RATIO:g}, 2]: a smaller axial moment C = μA is numerically "
                             f"zero (the rotor's axial acceleration, round-off of its torque divided by C, overflows)")
        if p["outer_axis"] == "custom" and p["outer_axis_enu"] is None:
            raise SceneError(f"{prefix}.outer_axis_enu", None, "is required when outer_axis = custom (3 numbers, ENU)")
        A1, C1 = p["inner_ring_diametral_inertia_kg_m2"], p["inner_ring_axial_inertia_kg_m2"]
        if C1 is not None and C1 > 2.0 * A1 * (1.0 + 1e-12):
            raise SceneError(f"{prefix}.inner_ring_axial_inertia_kg_m2", C1,
                             f"must be in [0, 2 A1] = [0, {2.0 * A1:g}] (triangle inequality of a rigid ring)")
        A2, C2 = p["outer_ring_diametral_inertia_kg_m2"], p["outer_ring_axial_inertia_kg_m2"]
        if C2 is not None and C2 > 2.0 * A2 * (1.0 + 1e-12):
            raise SceneError(f"{prefix}.outer_ring_axial_inertia_kg_m2", C2,
                             f"must be in [0, 2 A2] = [0, {2.0 * A2:g}] (triangle inequality of a rigid ring)")
        conf = p["configuration"]
        if conf == "locked":
            if p["initial_inner_angle_deg"] not in (None, 0.0):
                raise SceneError(f"{prefix}.initial_inner_angle_deg", p["initial_inner_angle_deg"],
                                 "must be unset or 0 when configuration = locked (inner ring held at θ = 90°)")
            if p["initial_inner_rate_deg_s"] != 0.0:
                raise SceneError(f"{prefix}.initial_inner_rate_deg_s", p["initial_inner_rate_deg_s"],
                                 "must be 0 when configuration = locked (inner ring held)")
        if conf == "outer_fixed":
            a0 = p["initial_outer_angle_deg"]
            if a0 is not None and a0 != p["outer_fixed_angle_deg"]:
                raise SceneError(f"{prefix}.initial_outer_angle_deg", a0,
                                 "must be unset or equal to outer_fixed_angle_deg when configuration = "
                                 "outer_fixed (the outer ring is held there)")
            if p["initial_outer_rate_deg_s"] != 0.0:
                raise SceneError(f"{prefix}.initial_outer_rate_deg_s", p["initial_outer_rate_deg_s"],
                                 "must be 0 when configuration = outer_fixed (outer ring held)")

    @classmethod
    def check_effects(cls, prefix, p, effects) -> None:
        """Refuse a free gimbal released at (or too near) gimbal lock with massless rings.

        Raises
        ------
        SceneError
            On ``initial_inner_angle_deg`` when the mass matrix at release (:func:`free_mass_matrix`
            with the ring moments as simulated: zero unless ``ring_inertia`` is listed) has a
            scaled condition number above :data:`MAX_MASS_MATRIX_CONDITION` (det M = a C u² is 0
            exactly when A1 = A2 = 0 and inner_angle = ±90°); the message names the ring
            parameters and the nearest accepted inner angle.
        """
        super().check_effects(prefix, p, effects)
        if p["configuration"] != "free":
            return                     # locked: diag(A + C1 + A2, C); outer_fixed: diag(A + A1, C)
        rings = bool(cls.named_with_term(effects, CARRIER_INERTIA))
        A = p["transverse_inertia_kg_m2"]
        C = p["inertia_ratio"] * A
        A1 = p["inner_ring_diametral_inertia_kg_m2"] if rings else 0.0
        C1 = (2.0 * A1 if p["inner_ring_axial_inertia_kg_m2"] is None else p["inner_ring_axial_inertia_kg_m2"]) \
            if rings else 0.0
        A2 = p["outer_ring_diametral_inertia_kg_m2"] if rings else 0.0
        inner = p["initial_inner_angle_deg"] or 0.0
        theta = math.radians(inner) + math.pi / 2
        cond = scaled_condition(free_mass_matrix(A, C, A1, C1, A2, theta))
        if cond <= MAX_MASS_MATRIX_CONDITION:
            return
        # the nearest accepted distance from the lock (cond falls monotonically with it)
        lo, hi = 0.0, math.pi / 2
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if scaled_condition(free_mass_matrix(A, C, A1, C1, A2, mid)) > MAX_MASS_MATRIX_CONDITION:
                lo = mid
            else:
                hi = mid
        why = ("ring_inertia is not listed for this instrument, so the rings are massless" if not rings else
               f"inner_ring_diametral_inertia_kg_m2 = {A1:g} and outer_ring_diametral_inertia_kg_m2 = {A2:g}")
        raise SceneError(f"{prefix}.initial_inner_angle_deg", inner,
                         f"puts the rotor axis along PP' (gimbal lock) in the free configuration while {why}: "
                         f"the mass matrix is singular there (scaled condition number {cond:.3g} > "
                         f"{MAX_MASS_MATRIX_CONDITION:g}); keep inner_angle at least {math.degrees(hi):.3g} deg "
                         f"away from +-90, or give the rings inertia (list ring_inertia with "
                         f"inner_ring_diametral_inertia_kg_m2 or outer_ring_diametral_inertia_kg_m2 > 0)")

    def __init__(self, name, site, params, effects) -> None:
        full = {prm.name: prm.default for prm in self.PARAMS}
        full.update(params)
        super().__init__(name, site, full, effects)
        self.check_params(name, self.params)
        self.check_effects(name, self.params, tuple(effects))
        self.pp_enu = outer_axis_direction_enu(self.p.outer_axis, self.p.outer_axis_enu, site)
        self.frame, self.sin_omega = plane_frame(self.pp_enu, site)
        # ω: angle between oz and the south part of Earth's axis (Quet sec. 1 eq. 17).
        self.cos_omega = -float(np.dot(site.earth_axis_north_enu(), self.pp_enu))
        n = site.earth_rate_rad_s
        self.k = n * self.cos_omega
        self.k_prime = n * self.sin_omega
        self.C = self.p.inertia_ratio * self.p.transverse_inertia_kg_m2
        # Ring moments as given (for predictions of both forms) ...
        self.C1_given = 2.0 * self.p.inner_ring_diametral_inertia_kg_m2 if self.p.inner_ring_axial_inertia_kg_m2 is None \
            else self.p.inner_ring_axial_inertia_kg_m2
        self.C2_given = 2.0 * self.p.outer_ring_diametral_inertia_kg_m2 if self.p.outer_ring_axial_inertia_kg_m2 is None \
            else self.p.outer_ring_axial_inertia_kg_m2
        # ... and as simulated: massless rings unless ``ring_inertia`` is listed.
        self.A1 = self.carrier_inertia(self.p.inner_ring_diametral_inertia_kg_m2)
        self.C1 = self.carrier_inertia(self.C1_given)
        self.A2 = self.carrier_inertia(self.p.outer_ring_diametral_inertia_kg_m2)
        self.C2 = self.carrier_inertia(self.C2_given)
        conf = self.p.configuration
        if conf == "outer_fixed":
            self.theta_ref = math.atan2(self.sin_omega * math.cos(self.p.outer_fixed_angle_rad), -self.cos_omega)
            self.outer0 = self.p.outer_fixed_angle_rad
            inner0 = DEFAULT_SWING_DEG if self.p.initial_inner_angle_deg is None else self.p.initial_inner_angle_deg
        else:
            self.theta_ref = math.pi / 2
            self.outer0 = math.radians(DEFAULT_SWING_DEG if self.p.initial_outer_angle_deg is None
                                       else self.p.initial_outer_angle_deg)
            inner0 = 0.0 if self.p.initial_inner_angle_deg is None else self.p.initial_inner_angle_deg
        self.inner0 = math.radians(inner0)
        # measured on the effects' own terms, for the effects declaring the forms the closed form holds
        self.rigid_body_coefficients = None if self.uncarried_effects("closed_form", self.effects) else \
            rigid_body_coefficients(self.effects.values(), self.context)
        if self.p.integrator == "closed_form" and self.rigid_body_coefficients is None:
            raise SceneError(f"{name}.integrator", "closed_form",
                             "needs rigid-body effect terms of first and second order in the Earth rate "
                             "(earth_rotation, centrifugal); use auto or hinge_chain with these effects")
        if self.p.integrator == "compiled" and not self.kernels_fit():
            raise SceneError(f"{name}.integrator", "compiled",
                             "needs rigid-body effect terms of first and second order in the Earth rate and hinge "
                             "torques linear in their rates (earth_rotation, centrifugal, pivot_damping, spin_decay); "
                             "use auto, closed_form or hinge_chain with these effects")

    def expected_swing(self) -> "ExpectedSwing | None":
        """Period 2 T of the configured swing (T' locked, T'' outer ring fixed; Quet sec. 4 §IV) and
        the release angle of the swinging ring; None when it does not swing (no directing torque)."""
        T = self.predictions()["swing_duration_small_s"]
        if not (math.isfinite(T) and T > 0):
            return None
        amp = self.outer0 if self.p.configuration != "outer_fixed" else self.inner0
        return ExpectedSwing(2.0 * T, abs(amp), "configuration, the inertias, spin_rate_rad_s and the site's latitude")

    def directing_model(self) -> DirectingModel | None:
        """What an estimator may know: K = (π/T0)² = gain · n ρ · s(γ) for the configured swing, or
        None for free rings (no single directing line).

        ``locked``: the rotor axis swings about PP' with inertia A + C1 + A2 (thick-ring form; Quet's
        A + 2A1 + A2 for thin rings), s = sin ω of PP' (T, T', T'''). ``outer_fixed``: the inner ring
        swings in the plane normal to NN' with inertia A + A1 (T'').
        """
        if self.p.configuration == "locked":
            normal = self.pp_enu
            gain = self.C / (self.p.transverse_inertia_kg_m2 + self.C1 + self.A2)
            label = {"vertical": "horizontal", "east_west": "meridian"}.get(self.p.outer_axis, self.p.outer_axis)
            chan = "outer_angle"
        elif self.p.configuration == "outer_fixed":
            psi = self.outer0 + math.pi / 2
            normal = self.frame @ np.array([math.cos(psi), math.sin(psi), 0.0])
            gain = self.C / (self.p.transverse_inertia_kg_m2 + self.A1)
            label = "meridian" if abs(normal[0]) > 1 - 1e-9 else "outer_fixed"
            chan = "inner_angle"
        else:
            return None
        return DirectingModel(gain=gain, normal_enu=tuple(float(v) for v in normal), label=label, angle_channel=chan,
                              spin_rate_rad_s=float(self.p.spin_rate_rad_s),
                              null_reason="the swing plane is perpendicular to Earth's axis here: no restoring torque")

    # ---------------------------------------------------------------- geometry helpers
    @property
    def psi0(self) -> float:
        """Initial ψ (Quet), rad."""
        return self.outer0 + math.pi / 2

    @property
    def theta0(self) -> float:
        """Initial θ (Quet), rad."""
        return self.inner0 + self.theta_ref

    def swing_plane_rate_rad_s(self) -> float:
        """n times the projection of Earth's axis on the plane of the inner swing (outer_fixed):
        m = n √(cos² ω + sin² ω cos² α); n for Quet's α = 0, whatever PP'."""
        return self.site.earth_rate_rad_s * math.hypot(self.cos_omega, self.sin_omega * math.cos(self.p.outer_fixed_angle_rad))

    # ---------------------------------------------------------------- predictions
    def predictions(self) -> dict:
        """Quet sec. 4 §IV periods in the printed thin-ring form and the thick-ring form.

        All durations are one swing (HALF the period), T = π/√K, in seconds, evaluated with the
        ring moments the simulation uses (zero when ``ring_inertia`` is absent) and the configured
        spin ρ0. Keys:

        * ``T_quet_s``, ``T_prime_quet_s``, ``T_second_quet_s``, ``T_third_quet_s``: T (this
          PP'), T' (PP' vertical), T'' (outer ring fixed across the meridian), T''' (PP'
          east–west), with Quet's A + 2A1 + A2 (T'': A + A1);
        * ``T_thick_s`` ... ``T_third_thick_s``: the same with the correct A + C1 + A2;
        * ``applies``: which of T, T', T'', T''' the configured case is (None when free; for
          outer_fixed with α ≠ 0 the generalised T'' with m = n √(cos²ω + sin²ω cos²α));
        * ``swing_duration_quet_s`` / ``swing_duration_small_s``: the configured case in
          Quet's printed form / the correct first-order form; ``quet_relative_error`` their
          ratio − 1; ``swing_duration_exact_s`` with the O(n²) terms; ``period_s`` = 2 T;
        * ``conserved_spin_rad_s``: eq. (13) at release; ``inner_reference_rad`` θ_ref;
        * ``nutation_half_period_s``: §V eq. (14), leading term, π √(a u0²) / (C ρ0 sin θ0),
          the fast gimbal nutation (free configuration).

        Without ``earth_rotation`` n = 0 in the model: no directing torque, every T is infinite
        (``null`` in JSON) and a ``notes`` entry says so.
        """
        rotating = self.has_term(GYROSCOPIC)
        out = self._predictions(rotating)
        T_site = None if rotating else self._predictions(True)["swing_duration_small_s"]
        with_it = f" (with it, the configured swing lasts {T_site:.6g} s)" \
            if T_site is not None and math.isfinite(T_site) else ""
        return with_notes(out, self.missing_term_note(
            GYROSCOPIC, "no directing torque C n ρ0 sin ω (sec. 4 §IV): T, T', T'', T''' are null" + with_it))

    def _predictions(self, rotating) -> dict:
        """The predictions with the site's Earth rate (``rotating``) or with n = 0."""
        f = 1.0 if rotating else 0.0
        n = self.site.earth_rate_rad_s * f
        k, k_prime = self.k * f, self.k_prime * f
        A, C, A1, C1, A2 = self.p.transverse_inertia_kg_m2, self.C, self.A1, self.C1, self.A2
        rho0 = self.p.spin_rate_rad_s
        cos_g = math.cos(self.site.latitude_rad)
        J_quet, J_thick, J_fixed = swing_inertias_kg_m2(A, A1, C1, A2)
        out = {"configuration": self.p.configuration, "sin_omega": self.sin_omega, "cos_omega": self.cos_omega,
               "k_rad_s": k, "k_prime_rad_s": k_prime,
               "inertia_locked_quet_kg_m2": J_quet, "inertia_locked_kg_m2": J_thick,
               "inertia_outer_fixed_kg_m2": J_fixed}
        out.update(quet_swing_durations_s(J_quet, J_thick, J_fixed, C, rho0, n, k_prime, cos_g))
        theta0, psi0 = self.theta0, self.psi0
        out["conserved_spin_rad_s"] = float(spin_invariant(rho0, theta0, psi0, k, k_prime))
        out["inner_reference_rad"] = self.theta_ref
        out["outer_reference_rad"] = math.pi / 2
        conf = self.p.configuration
        applies, Tq, Ts, Te = None, math.nan, math.nan, math.nan
        if conf == "locked":
            applies = {"vertical": "T'", "east_west": "T'''"}.get(self.p.outer_axis, "T")
            Tq, Ts = out["T_quet_s"], out["T_thick_s"]
            rho_eq = rho0 + k_prime * (math.cos(self.outer0) - 1.0)
            K = locked_swing_constant(A, C, C1, A2, self.C2, k_prime, rho_eq)
            Te = math.pi / math.sqrt(K) if K > 0 else math.inf
        elif conf == "outer_fixed":
            m = self.swing_plane_rate_rad_s() * f
            applies = "T''" if self.p.outer_fixed_angle_rad == 0.0 else "T'' (generalised)"
            Tq = Ts = swing_duration_s(J_fixed, C, m, rho0)
            rho_eq = rho0 + m * (math.cos(self.inner0) - 1.0)
            K = outer_fixed_swing_constant(A, C, A1, C1, m, rho_eq)
            Te = math.pi / math.sqrt(K) if K > 0 else math.inf
        out["applies"] = applies
        out["swing_duration_quet_s"] = Tq
        out["swing_duration_small_s"] = Ts
        out["swing_duration_exact_s"] = Te
        out["quet_relative_error"] = Tq / Ts - 1.0 if math.isfinite(Ts) and Ts > 0 else math.nan
        out["period_s"] = 2.0 * Ts
        s0 = math.sin(theta0)
        u02 = (A + C1 - A1) * s0 ** 2 + A1 + A2
        out["nutation_half_period_s"] = (math.pi * math.sqrt((A + A1) * u02) / abs(C * rho0 * s0)
                                         if rho0 != 0.0 and s0 != 0.0 else math.inf)
        return out

    def scales(self, duration_s) -> Scales:
        """Characteristic scales for ``Effect.relative_size``: swing and gyroscopic rates, ring ratio
        (those of the rotating Earth, whether or not ``earth_rotation`` is listed)."""
        pred = self._predictions(True)
        conf = self.p.configuration
        if conf == "outer_fixed":
            J = self.p.transverse_inertia_kg_m2 + self.A1
            ring_ratio = self.p.inner_ring_diametral_inertia_kg_m2 / self.p.transverse_inertia_kg_m2
            amp = abs(self.inner0)
        else:
            J = self.p.transverse_inertia_kg_m2 + self.C1 + self.A2
            ring_ratio = (self.C1_given + self.p.outer_ring_diametral_inertia_kg_m2) / self.p.transverse_inertia_kg_m2
            amp = abs(self.outer0)
        T0 = pred["swing_duration_small_s"]
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s,
                gyro_rate_rad_s=abs(self.C * self.p.spin_rate_rad_s / J) or None,
                restoring_rate_rad_s=math.pi / T0 if math.isfinite(T0) and T0 > 0 else 0.0,
                ring_inertia_ratio=ring_ratio, amplitude_rad=amp, duration_s=duration_s)
