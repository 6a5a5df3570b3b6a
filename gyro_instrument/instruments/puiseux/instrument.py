"""Puiseux's body as an instrument: parameters, predictions (:mod:`.theory`), the exact model
(:mod:`.dynamics`) integrated and sampled (``integrator``: :meth:`PuiseuxBody.integrator_choice`).

Earth rotation is ignored, as in the paper (``MECHANICS`` and so ``SUPPORTED_EFFECTS`` are
empty): the simulated model is the exact nonlinear rigid body on the frictionless plane, with no
small-angle or other approximation, so there is nothing to switch on or off.
"""

import math

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.effect import Scales
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import PairParam, Param
from gyro_instrument.instruments.base import Column, Instrument
from gyro_instrument.instruments.observation import RotorObservation
from gyro_instrument.instruments.puiseux.dynamics import contact_dynamics, contact_dynamics_general
from gyro_instrument.instruments.puiseux.general import (GeneralModes, general_modes, inertia_conjugacy,
                                                         linear_rotation, normal_frame)
from gyro_instrument.instruments.puiseux.runs import ContactRuns
from gyro_instrument.instruments.puiseux.surface import EllipsoidSurface, GeneralEllipsoidSurface
from gyro_instrument.instruments.puiseux.theory import (classify_coefficients, critical_spin_general_rad_s,
                                                        critical_spin_rad_s, curvature_coefficients,
                                                        ellipsoid_coefficients, homogeneous_inertia)

TWO_PI = 2.0 * math.pi
#: choices of the ``integrator`` parameter (:mod:`.fixed_step`)
INTEGRATORS = ("auto", "dop853", "axis_rk8", "rk8")
#: parameters that apply only to some shapes
GENERAL_ANGLES = ("axes_phi1_deg", "axes_theta1_deg", "axes_psi1_deg")
SHAPE_KEYS = {"semi_axes_m": ("ellipsoid",), "curvature_radii_m": ("curvature", "general"),
              "com_height_m": ("curvature", "general"), **{k: ("general",) for k in GENERAL_ANGLES}}


class PuiseuxBody(ContactRuns, Instrument):
    """Heavy body spun on a smooth horizontal plane (Puiseux 1852): exact rigid-body model.

    World frame ENU (x east, y north, z up); the azimuths are compass azimuths (0 north,
    clockwise seen from above), as in :func:`~gyro_instrument.core.site.compass_azimuth_from_enu`.
    Initially the body is upright with its axes along ENU, then turned by ``initial_tilt_deg``
    about the horizontal line perpendicular to ``initial_tilt_azimuth_deg`` so that the axis Gz
    leans toward that azimuth; it spins at r about Gz (positive counter-clockwise seen from
    above when upright), and the axis moves at the given tilt and azimuth rates. Earth rotation
    and friction are ignored (the paper's hypotheses); nothing is approximated.

    ``shape: general`` (sec. III) is a body of any form whose line GA (centre of mass to the
    contact point at rest) is not a principal axis: at rest its normal frame A-xi, A-eta, A-zeta
    lies along ENU and its principal axes at Puiseux's angles (φ1, θ1, ψ1) from it (eq. 17);
    the line GA plays the axis above (tilt, azimuth, spin about it). Its theory is
    :mod:`.general`; its surface the osculating ellipsoid at A in any orientation
    (:class:`~gyro_instrument.instruments.puiseux.surface.GeneralEllipsoidSurface`).

    Raises
    ------
    SceneError
        From :meth:`check_params`: a shape's missing or foreign fields, two spins, an inertia
        that is not a rigid body's; for the general body also GA at or above a centre of
        curvature (γ ≥ min(ρ, ρ'): no stable equilibrium, outside sec. III).
    """

    type_name = "puiseux_body"
    summary = "heavy body spun on a smooth horizontal plane (Puiseux 1852), exact rigid-body model"
    PARAMS = (
        Param("shape", kind="str", default="ellipsoid", choices=("ellipsoid", "curvature", "general"),
              doc="ellipsoid with G at its centre (sec. I); any body whose principal axis Gz is normal "
                  "at the contact point, by its curvature radii there (sec. II); or any body at all, "
                  "GA oblique to the principal axes, slightly displaced with small velocities (sec. III)"),
        Param("semi_axes_m", kind="vec3", default=None,
              doc="ellipsoid semi-axes alpha, beta, gamma along body x, y, z (z starts vertical), m"),
        Param("homogeneous", kind="bool", default=True,
              doc="ellipsoid: moments from mass and semi-axes, A = M(beta^2+gamma^2)/5 etc.; "
                  "false: give inertia_kg_m2"),
        Param("inertia_kg_m2", kind="vec3", default=None,
              doc="principal moments A, B, C about body x, y, z through G, kg m^2"),
        Param("mass_kg", default=1.0, low=0.0, open_low=True, doc="mass M, kg"),
        PairParam("curvature_radii_m", kind="pair", default=None,
                  doc="curvature, general: principal radii rho, rho' of the surface at the contact "
                      "point A (curvature: rho in the body x direction when curvature_angle_deg = 0; "
                      "general: rho along A-xi, rho' along A-eta), m"),
        Param("com_height_m", default=None, low=0.0, open_low=True,
              doc="curvature, general: distance gamma = GA from the centre of mass to the contact point "
                  "at rest, m (general: below both radii, Puiseux's stable equilibrium)"),
        Param("axes_theta1_deg", default=None, low=0.0, high=180.0,
              doc="general: Puiseux's theta1 (sec. III, eq. 17), the angle between the principal axis Gz "
                  "and the normal A-zeta (along AG), degrees"),
        Param("axes_phi1_deg", default=None, low=-360.0, high=360.0,
              doc="general: Puiseux's phi1, the angle from A-xi (the principal section of radius rho) to "
                  "the line of nodes of the planes A-xi-eta and Gxy, degrees"),
        Param("axes_psi1_deg", default=None, low=-360.0, high=360.0,
              doc="general: Puiseux's psi1, the angle from the principal axis Gx to that line of nodes, "
                  "degrees"),
        Param("curvature_angle_deg", default=0.0, low=-90.0, high=90.0,
              doc="curvature: angle delta from body x to the principal direction of rho, degrees"),
        Param("spin_rate_rad_s", default=None, low=-1.0e5, high=1.0e5,
              doc="initial spin r about the body axis Gz (general: about the line GA), rad/s "
                  "(give this or spin_rate_turn_s)"),
        Param("spin_rate_turn_s", default=None, low=-1.0e4, high=1.0e4,
              doc="initial spin r about the body axis Gz (general: about the line GA), turns/s "
                  "(give this or spin_rate_rad_s)"),
        Param("initial_tilt_deg", default=0.0, low=0.0, high=180.0, open_high=True,
              doc="initial angle theta0 between the body axis Gz (general: the line GA) and the upward "
                  "vertical, degrees"),
        Param("initial_tilt_azimuth_deg", default=0.0, low=-360.0, high=360.0,
              doc="compass azimuth toward which the axis leans, degrees (0 north, 90 east)"),
        Param("initial_tilt_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial d(theta)/dt, degrees/s"),
        Param("initial_azimuth_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial rate of the axis' compass azimuth (clockwise from above), degrees/s"),
        Param("rtol", default=1e-10, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
        Param("integrator", kind="str", default="auto", choices=INTEGRATORS,
              doc="auto: axis_rk8 for a body of revolution released with its axis above the horizontal, else rk8; dop853: adaptive DOP853 on the exact "
                  "equations (the reference), compiled (core.dop853_jit, the equations a numba kernel) when numba is "
                  "on, else scipy's DOP853 on the Python right-hand side (GYRO_INSTRUMENT_JIT=0); axis_rk8: compiled fixed-step RK8 on the exact reduction of a "
                  "body of revolution by its conserved spin (steps set by the nutation, not the spin); rk8: "
                  "compiled fixed-step RK8 on the exact equations (any body)"),
    )
    MECHANICS = frozenset()
    MEASURED_CHANNELS = ("tilt", "tilt_azimuth")
    SHOWS_CONTACT_POINT = True
    JOINTS = ("tilt", "tilt_azimuth", "spin")
    OBSERVATION = RotorObservation
    SIMULATOR_NODE = "top_sim"
    COLUMNS = (
        Column("tilt", "rad", "theta: angle between the body axis Gz and the upward vertical"),
        Column("tilt_azimuth", "rad", "compass azimuth of the axis' horizontal projection (0 north, clockwise)"),
        Column("spin_rate", "rad/s", "r: body angular velocity about Gz"),
        Column("com_height", "m", "height of the centre of mass above the plane, h(n)"),
        Column("vertical_body_x", "1", "a'' = theta sin psi: body-x component of the upward vertical (eq. 16)"),
        Column("vertical_body_y", "1", "b'' = theta cos psi: body-y component of the upward vertical (eq. 16)"),
        Column("contact_x", "m", "contact point in the principal axes Gx, Gy, Gz from G: x (sec. I: x = -alpha^2 a''/gamma "
                                 "at small tilts; its path about A shows stations and retrogradations)"),
        Column("contact_y", "m", "contact point in principal axes: y"),
        Column("contact_z", "m", "contact point in principal axes: z (-gamma at rest for ellipsoid and curvature)"),
        Column("contact_east", "m", "contact point on the plane, east of the vertical through G (G moves only "
                                    "vertically, eqs. 1-2)"),
        Column("contact_north", "m", "contact point on the plane, north of the vertical through G"),
        Column("turn_angle", "rad", "turn of the body about the vertical since release, counter-clockwise seen from "
                                    "above, unwrapped (swing-twist; sec. III: alpha t + beta + periodic terms)"),
    )

    @classmethod
    def check_params(cls, prefix, p) -> None:
        """Cross-field checks: the shape's required fields, one spin, a physical inertia."""
        if p["spin_rate_rad_s"] is not None and p["spin_rate_turn_s"] is not None:
            raise SceneError(f"{prefix}.spin_rate_turn_s", p["spin_rate_turn_s"],
                             "give either spin_rate_rad_s or spin_rate_turn_s, not both")
        for key, shapes in SHAPE_KEYS.items():
            if p["shape"] not in shapes and p[key] is not None:
                raise SceneError(f"{prefix}.{key}", p[key], f"applies only to shape = {' or '.join(shapes)}")
        if p["shape"] == "ellipsoid":
            if p["homogeneous"] and p["inertia_kg_m2"] is not None:
                raise SceneError(f"{prefix}.inertia_kg_m2", list(p["inertia_kg_m2"]),
                                 "is computed from mass and semi-axes when homogeneous = true; "
                                 "set homogeneous: false to give it")
            if p["semi_axes_m"] is None:
                raise SceneError(f"{prefix}.semi_axes_m", None,
                                 "is required when shape = ellipsoid (3 numbers > 0, m)")
            if min(p["semi_axes_m"]) <= 0.0:
                raise SceneError(f"{prefix}.semi_axes_m", list(p["semi_axes_m"]),
                                 "must be 3 numbers > 0, m")
            if not p["homogeneous"] and p["inertia_kg_m2"] is None:
                raise SceneError(f"{prefix}.inertia_kg_m2", None,
                                 "is required when homogeneous = false (A, B, C > 0, kg m^2)")
        else:
            required = [("curvature_radii_m", "2 numbers > 0, m"), ("com_height_m", "a number > 0, m"),
                        ("inertia_kg_m2", "A, B, C > 0, kg m^2")]
            if p["shape"] == "general":
                required += [(k, "degrees") for k in GENERAL_ANGLES]
            for key, what in required:
                if p[key] is None:
                    raise SceneError(f"{prefix}.{key}", None, f"is required when shape = {p['shape']} ({what})")
            if p["shape"] == "general":
                cls._check_general(prefix, p)
        I = p["inertia_kg_m2"]
        if I is not None and (p["shape"] != "ellipsoid" or not p["homogeneous"]):
            A, B, C = I
            if min(I) <= 0.0 or A + B < C or B + C < A or A + C < B:
                raise SceneError(f"{prefix}.inertia_kg_m2", list(I),
                                 "must be 3 numbers > 0 obeying the triangle inequalities "
                                 "(A + B >= C, B + C >= A, C + A >= B) of a rigid body")

        if p["integrator"] == "axis_rk8" and cls.not_of_revolution(p):
            raise SceneError(f"{prefix}.integrator", "axis_rk8",
                             f"needs a body of revolution about Gz ({cls.not_of_revolution(p)}); use rk8 or dop853")

    @staticmethod
    def not_of_revolution(p) -> "str | None":
        """Why the body of parameters ``p`` is not one of revolution about Gz (A = B and a surface of
        revolution: α = β, or ρ = ρ'), or None when it is (``integrator: axis_rk8`` then applies)."""
        if p["shape"] == "general":
            return "shape general: GA is not a principal axis"
        if p["shape"] == "ellipsoid":
            a, b, _ = p["semi_axes_m"]
            if a != b:
                return f"semi-axes alpha = {a:g} m != beta = {b:g} m"
            if p["homogeneous"]:
                return None
        else:
            rho, rho_p = p["curvature_radii_m"]
            if rho != rho_p:
                return f"curvature radii rho = {rho:g} m != rho' = {rho_p:g} m"
        A, B, _ = p["inertia_kg_m2"]
        return None if A == B else f"moments A = {A:g} != B = {B:g} kg m^2"

    def integrator_choice(self) -> tuple:
        """(integrator, reason): what ``integrator`` (``auto`` by default) runs and why: the reduction
        ``axis_rk8`` for a body of revolution released with its axis above the horizontal, else
        ``rk8`` (:mod:`.fixed_step`), unless the scene names one (``dop853``: the reason says whether it
        runs compiled, :mod:`gyro_instrument.core.dop853_jit`, or as scipy's, numba off)."""
        if self.p.integrator == "dop853":
            how = (f"Hairer's DOP853 compiled, core.dop853_jit: {jit.status()}" if jit.enabled() else
                   f"scipy's DOP853 on the Python right-hand side, {jit.status()}")
            return "dop853", f"chosen in the scene ({how})"
        if self.p.integrator != "auto":
            return self.p.integrator, "chosen in the scene"
        why_not = self.not_of_revolution(self.params)
        why_not = why_not and f"not a body of revolution ({why_not})"
        if why_not is None and self.p.initial_tilt_rad > 0.5 * math.pi:
            why_not = "released with the axis below the horizontal, toward the reduction's singular upside-down pose"
        if why_not is None:
            return "axis_rk8", ("auto: a body of revolution, so its spin r is conserved (eq. 6) and the exact "
                                "reduction to the figure axis leaves the nutation, not the spin, to set the step")
        return "rk8", f"auto: {why_not}, so the exact equations, compiled, fixed step"

    def chosen_integrator(self, duration_s=None) -> tuple:
        """:meth:`integrator_choice` (for ``describe``; the choice does not depend on ``duration_s``)."""
        return self.integrator_choice()

    @classmethod
    def _check_general(cls, prefix, p) -> None:
        """Sec. III: GA below both radii (else no stable equilibrium: refused); no sec. II angle."""
        if p["curvature_angle_deg"] != 0.0:
            raise SceneError(f"{prefix}.curvature_angle_deg", p["curvature_angle_deg"],
                             "applies only to shape = curvature (shape = general: the principal sections "
                             "are A-xi, A-eta and axes_phi1_deg, axes_theta1_deg, axes_psi1_deg place the "
                             "principal axes); leave it 0")
        rho = min(p["curvature_radii_m"])
        if not p["com_height_m"] < rho:
            raise SceneError(f"{prefix}.com_height_m", p["com_height_m"],
                             f"must be < {rho:g} m, the smaller curvature radius: Puiseux sec. III treats a "
                             f"stable equilibrium, the centre of mass below both centres of curvature "
                             f"(at or above one of them the body falls or has a zero-frequency swing)")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        if self.p.shape == "ellipsoid":
            self.alpha, self.beta, self.gamma = self.p.semi_axes_m
            self.rho = self.alpha ** 2 / self.gamma
            self.rho_prime = self.beta ** 2 / self.gamma
            self.delta = 0.0
            self.surface = EllipsoidSurface(self.p.semi_axes_m)
            self.inertia = (homogeneous_inertia(self.p.mass_kg, self.p.semi_axes_m) if self.p.homogeneous
                            else tuple(self.p.inertia_kg_m2))
        elif self.p.shape == "curvature":
            self.rho, self.rho_prime = self.p.curvature_radii_m
            self.gamma = float(self.p.com_height_m)
            self.delta = math.radians(self.p.curvature_angle_deg)
            self.surface = EllipsoidSurface.osculating(self.rho, self.rho_prime, self.gamma, self.delta)
            self.inertia = tuple(self.p.inertia_kg_m2)
        else:
            self.rho, self.rho_prime = self.p.curvature_radii_m
            self.gamma = float(self.p.com_height_m)
            self.delta = None
            self.P = normal_frame(*(math.radians(getattr(self.p, k)) for k in GENERAL_ANGLES))
            self.surface = GeneralEllipsoidSurface.osculating(self.rho, self.rho_prime, self.gamma, self.P)
            self.inertia = tuple(self.p.inertia_kg_m2)
        self.general = self.p.shape == "general"
        self.dynamics = contact_dynamics_general if self.general else contact_dynamics
        #: the body line GA (upward at rest) in body axes
        self.u_body = self.P[2] if self.general else np.array([0.0, 0.0, 1.0])
        if self.p.spin_rate_rad_s is not None:
            self.r0 = float(self.p.spin_rate_rad_s)
        elif self.p.spin_rate_turn_s is not None:
            self.r0 = TWO_PI * float(self.p.spin_rate_turn_s)
        else:
            self.r0 = 0.0

    # ---------------------------------------------------------------- predictions
    def coefficients(self, r=None) -> tuple:
        """D, E, F, G of eq. (14) at spin ``r`` (rad/s; default the initial spin).

        Raises
        ------
        ValueError
            For the general body: eq. (14) needs a principal axis normal at A (sec. I-II); sec.
            III has :meth:`modes` instead.
        """
        if self.general:
            raise ValueError("eq. (14)'s D, E, F, G need a principal axis normal at the contact point "
                             "(shape ellipsoid or curvature); the general body (sec. III) has modes()")
        A, B, C = self.inertia
        r = self.r0 if r is None else r
        if self.p.shape == "ellipsoid":
            return (*ellipsoid_coefficients(A, B, C, self.p.mass_kg, self.context.gravity_m_s2, r, self.alpha, self.beta, self.gamma), 0.0)
        return curvature_coefficients(A, B, C, self.p.mass_kg, self.context.gravity_m_s2, r, self.rho, self.rho_prime, self.gamma,
                                      self.delta)

    def predictions(self) -> dict:
        """Small-tilt theory for this body and spin (Puiseux 1852, eqs. 14-16, sec. I-II).

        Returns
        -------
        dict
            ``omega_sq_rad2_s2`` (the two roots of eq. 15), ``frequencies_rad_s`` (their square
            roots when stable: angular frequencies of a'', b'' in body axes), ``periods_s``,
            ``verdict`` (three inequalities), ``inequalities``, ``coefficients`` (D, E, F, G),
            ``stable_at_rest`` (γ < ρ and γ < ρ'), ``critical_spin_rad_s`` and
            ``critical_spin_turn_s`` (from the inequalities' polynomials in r²),
            ``critical_spin_closed_form_rad_s`` (homogeneous ellipsoid only), the curvature radii
            and the initial invariants (energy, vertical angular momentum about G). The general
            body (sec. III) has its own: :meth:`general_predictions`.
        """
        if self.general:
            return self.general_predictions()
        A, B, C = self.inertia
        D, E, F, G = self.coefficients()
        v = classify_coefficients(A, B, D, E, F, G)
        rcrit = critical_spin_general_rad_s(A, B, C, self.p.mass_kg, self.context.gravity_m_s2, self.rho, self.rho_prime, self.gamma,
                                            self.delta)
        out = {
            "omega_sq_rad2_s2": v.omega_sq,
            "frequencies_rad_s": v.frequencies_rad_s,
            "periods_s": tuple(TWO_PI / f if f > 0 else math.inf for f in v.frequencies_rad_s),
            "verdict": v.verdict,
            "inequalities": v.inequalities,
            "coefficients": {"D": D, "E": E, "F": F, "G": G},
            "stable_at_rest": self.gamma < self.rho and self.gamma < self.rho_prime,
            "critical_spin_rad_s": rcrit,
            "critical_spin_turn_s": rcrit / TWO_PI,
            "rho_m": self.rho,
            "rho_prime_m": self.rho_prime,
            "spin_rate_rad_s": self.r0,
        }
        if self.p.shape == "ellipsoid" and self.p.homogeneous:
            rc = critical_spin_rad_s(self.alpha, self.beta, self.gamma, self.context.gravity_m_s2)
            out["critical_spin_closed_form_rad_s"] = rc
            out["critical_spin_closed_form_turn_s"] = rc / TWO_PI
        y0 = self.initial_state()
        diag = self.diagnostics(y0[:, None])
        out["energy_J"] = float(diag["energy_J"][0])
        out["angular_momentum_vertical_kg_m2_s"] = float(diag["angular_momentum_vertical_kg_m2_s"][0])
        return out

    def contact_point_body(self, columns) -> np.ndarray:
        """The ``contact_x``, ``contact_y``, ``contact_z`` columns side by side, shape (m, 3), m:
        the contact point in the principal axes Gx, Gy, Gz from G (frame ``<name>_body``)."""
        return np.column_stack([columns["contact_x"], columns["contact_y"], columns["contact_z"]])

    # ---------------------------------------------------------------- sec. III
    def modes(self) -> "GeneralModes":
        """:class:`~gyro_instrument.instruments.puiseux.general.GeneralModes` of the general body."""
        return general_modes(self.inertia, self.p.mass_kg, self.context.gravity_m_s2, self.rho, self.rho_prime, self.gamma, self.P)

    def linear_initial_conditions(self) -> tuple:
        """φ(0), φ̇(0): rotation vector from the rest orientation and body rate, body axes (general body).

        The initial tilt is the rotation by θ0 about the horizontal (−cos az, sin az, 0) (ENU), i.e.
        Pᵀ θ0 (−cos az, sin az, 0) in body axes; the rate is the exact initial body rate (first order
        in the small velocities, φ̇ = w).
        """
        tilt = self.p.initial_tilt_rad * np.array([-math.cos(self.p.initial_tilt_azimuth_rad), math.sin(self.p.initial_tilt_azimuth_rad), 0.0])
        return self.P.T @ tilt, self.initial_state()[4:]

    def linear_prediction(self, t, modes=None) -> dict:
        """First-order motion of the general body at times ``t`` (Puiseux 1852, sec. III).

        Returns
        -------
        dict of ndarray
            ``phi`` (3, m) rotation vector in body axes; ``tilt_vector`` ε = u × φ (3, m), so the
            vertical is n = u + ε; ``tilt`` |ε| (rad); ``turn`` u·φ (rad: αt + β + periodic);
            ``contact_xi``, ``contact_eta`` (m: −ρ ε_ξ, −ρ' ε_η, the contact point about A in the
            tangent plane); ``contact_body`` (3, m: −γu + ξ ξ̂ + η η̂); ``contact_east``,
            ``contact_north`` (m: −ϖ ε_ξ, −ϖ' ε_η on the plane, first order in the turn too).
        """
        modes = modes or self.modes()
        phi = linear_rotation(modes, t, *self.linear_initial_conditions())
        xi, eta, u = self.P
        eps = np.cross(u, phi.T).T
        ex, ee = xi @ eps, eta @ eps
        cx, ce = -self.rho * ex, -self.rho_prime * ee
        return {"phi": phi, "tilt_vector": eps, "tilt": np.linalg.norm(eps, axis=0), "turn": u @ phi,
                "contact_xi": cx, "contact_eta": ce,
                "contact_body": -self.gamma * u[:, None] + np.outer(xi, cx) + np.outer(eta, ce),
                "contact_east": -(self.rho - self.gamma) * ex, "contact_north": -(self.rho_prime - self.gamma) * ee}

    def general_predictions(self) -> dict:
        """Puiseux 1852, sec. III, for this body and its initial state.

        Returns
        -------
        dict
            ``puiseux_omega_m`` (ω', ω'', roots of his equation after eq. 25), ``frequencies_rad_s``
            (√(Mgω/C)), ``swing_durations_s`` (π√(C/(Mgω)): one swing of the vertical projections of
            the points of Π', Π''), ``periods_s`` (twice those), ``plane_angles_rad`` (traces of Π',
            Π'' on the tangent plane from A-xi toward A-eta, in [0, π)), ``angle_between_planes_rad``,
            ``planes_perpendicular`` and ``perpendicularity`` (Puiseux's two factors ρ − ρ' and
            BC a1a1' + AC b1b1' + AB c1c1'; perpendicular iff one vanishes), ``turning_rate_rad_s``
            (|α|, α = L_v/(A a1''² + B b1''² + C c1''²), the unbounded turn about the vertical) with
            ``turning_sense``, ``inertia_about_normal_kg_m2``, ``max_tilt_rad`` and
            ``contact_path_max_distance_m`` (first-order bounds: the modes' amplitudes added, reached
            when their phases meet), the initial invariants, ``verdict`` ("stable": unstable bodies
            are refused) and ``notes`` when the velocities are not small.
        """
        modes = self.modes()
        A, B, C = self.inertia
        conj = inertia_conjugacy(A, B, C, self.P)
        scale = abs(B * C) + abs(A * C) + abs(A * B)
        perpendicular = abs(self.rho - self.rho_prime) <= 1e-12 * max(self.rho, self.rho_prime) \
            or abs(conj) <= 1e-12 * scale
        y0 = self.initial_state()
        diag = self.diagnostics(y0[:, None])
        lv = float(diag["angular_momentum_vertical_kg_m2_s"][0])
        alpha = lv / modes.inertia_about_normal_kg_m2
        phi0, phidot0 = self.linear_initial_conditions()
        Vinv = np.linalg.inv(modes.rotations)
        q0, qd0 = Vinv @ phi0, Vinv @ phidot0
        u = self.P[2]
        tilt_amp, path = 0.0, 0.0
        for k, om in zip((1, 2), modes.frequencies_rad_s):
            amp = math.hypot(q0[k], qd0[k] / om) if om > 0.0 else math.inf
            eps = np.cross(u, modes.rotations[:, k])
            tilt_amp += amp * float(np.linalg.norm(eps))
            path += amp * math.hypot(self.rho * (self.P[0] @ eps), self.rho_prime * (self.P[1] @ eps))
        notes = []
        f1, f2 = modes.frequencies_rad_s
        if abs(f2 - f1) <= 1e-9 * f2:
            out_planes = None
            notes.append("double root (omega' = omega''): every plane through GA swings with the same duration, "
                         "so Puiseux's two planes are not defined (e.g. equal radii and equal moments)")
        else:
            out_planes = modes.plane_angles_rad
        out = {
            "section": "III",
            "verdict": "stable",
            "stable_at_rest": True,
            "puiseux_omega_m": modes.omega_m,
            "frequencies_rad_s": modes.frequencies_rad_s,
            "swing_durations_s": modes.swing_durations_s,
            "periods_s": tuple(2.0 * d for d in modes.swing_durations_s),
            "plane_angles_rad": out_planes,
            "angle_between_planes_rad": modes.angle_between_planes_rad if out_planes else None,
            "planes_perpendicular": bool(perpendicular),
            "perpendicularity": {"rho_minus_rho_prime_m": self.rho - self.rho_prime,
                                 "inertia_conjugacy_kg2_m4": conj},
            "inertia_about_normal_kg_m2": modes.inertia_about_normal_kg_m2,
            "turning_rate_rad_s": abs(alpha),
            "turning_sense": ("none" if alpha == 0.0 else
                              "counter-clockwise seen from above" if alpha > 0 else "clockwise seen from above"),
            "max_tilt_rad": tilt_amp,
            "contact_path_max_distance_m": path,
            "rho_m": self.rho,
            "rho_prime_m": self.rho_prime,
            "spin_rate_rad_s": self.r0,
            "energy_J": float(diag["energy_J"][0]),
            "angular_momentum_vertical_kg_m2_s": lv,
        }
        slow = modes.frequencies_rad_s[0]
        fast = float(np.linalg.norm(y0[4:])) / slow if slow > 0.0 else math.inf
        if fast > 0.1 or tilt_amp > 0.1:
            notes += [f"not a small motion (|w0|/slower swing frequency = {fast:.3g}, tilt up to "
                      f"{tilt_amp:.3g} rad): Puiseux sec. III assumes small displacements and velocities; "
                      f"the simulation is exact, these predictions are first order"]
        if notes:
            out["notes"] = notes
        return out

    def scales(self, duration_s) -> Scales:
        """Characteristic scales: spin, small-tilt restoring rate at rest, amplitude, duration."""
        A, B, _ = self.inertia
        w0 = math.sqrt(self.p.mass_kg * self.context.gravity_m_s2 * min(abs(self.rho - self.gamma), abs(self.rho_prime - self.gamma))
                       / max(A, B))
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=abs(self.r0) or None,
                restoring_rate_rad_s=w0, amplitude_rad=self.p.initial_tilt_rad, duration_s=duration_s)

    STREAMS = True


