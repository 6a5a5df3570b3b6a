"""Puiseux's body as an instrument: parameters, predictions (:mod:`.theory`), the exact model
(:mod:`.dynamics`) integrated and sampled.

Earth rotation is ignored, as in the paper (``MECHANICS`` and so ``SUPPORTED_EFFECTS`` are
empty): the simulated model is the exact nonlinear rigid body on the frictionless plane, with no
small-angle or other approximation, so there is nothing to switch on or off.
"""

import math
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import integration
from gyro_instrument.core.params import PairParam, Param
from gyro_instrument.core.quaternion import rotation_matrix
from gyro_instrument.core.site import compass_azimuth_from_enu
from gyro_instrument.instruments.base import Column, Instrument, Simulation, run_span
from gyro_instrument.instruments.puiseux.dynamics import contact_dynamics
from gyro_instrument.instruments.puiseux.surface import EllipsoidSurface
from gyro_instrument.instruments.puiseux.theory import (classify_coefficients, critical_spin_general_rad_s,
                                                        critical_spin_rad_s, curvature_coefficients,
                                                        ellipsoid_coefficients, homogeneous_inertia)

TWO_PI = 2.0 * math.pi


class PuiseuxBody(Instrument):
    """Heavy body spun on a smooth horizontal plane (Puiseux 1852): exact rigid-body model.

    World frame ENU (x east, y north, z up); the azimuths are compass azimuths (0 north,
    clockwise seen from above), as in :func:`~gyro_instrument.core.site.compass_azimuth_from_enu`.
    Initially the body is upright with its axes along ENU, then turned by ``initial_tilt_deg``
    about the horizontal line perpendicular to ``initial_tilt_azimuth_deg`` so that the axis Gz
    leans toward that azimuth; it spins at r about Gz (positive counter-clockwise seen from
    above when upright), and the axis moves at the given tilt and azimuth rates. Earth rotation
    and friction are ignored (the paper's hypotheses); nothing is approximated.
    """

    type_name = "puiseux_body"
    summary = "heavy body spun on a smooth horizontal plane (Puiseux 1852), exact rigid-body model"
    PARAMS = (
        Param("shape", kind="str", default="ellipsoid", choices=("ellipsoid", "curvature"),
              doc="ellipsoid with G at its centre (sec. I) or any body by its curvature radii at "
                  "the contact point (sec. II)"),
        Param("semi_axes_m", kind="vec3", default=None,
              doc="ellipsoid semi-axes alpha, beta, gamma along body x, y, z (z starts vertical), m"),
        Param("homogeneous", kind="bool", default=True,
              doc="ellipsoid: moments from mass and semi-axes, A = M(beta^2+gamma^2)/5 etc.; "
                  "false: give inertia_kg_m2"),
        Param("inertia_kg_m2", kind="vec3", default=None,
              doc="principal moments A, B, C about body x, y, z through G, kg m^2"),
        Param("mass_kg", default=1.0, low=0.0, open_low=True, doc="mass M, kg"),
        PairParam("curvature_radii_m", kind="pair", default=None,
                  doc="curvature: principal radii rho, rho' of the surface at the contact point "
                      "(rho in the body x direction when curvature_angle_deg = 0), m"),
        Param("com_height_m", default=None, low=0.0, open_low=True,
              doc="curvature: height gamma = GA of the centre of mass above the contact point at rest, m"),
        Param("curvature_angle_deg", default=0.0, low=-90.0, high=90.0,
              doc="curvature: angle delta from body x to the principal direction of rho, degrees"),
        Param("spin_rate_rad_s", default=None, low=-1.0e5, high=1.0e5,
              doc="initial spin r about the body axis Gz, rad/s (give this or spin_rate_turn_s)"),
        Param("spin_rate_turn_s", default=None, low=-1.0e4, high=1.0e4,
              doc="initial spin r about the body axis Gz, turns/s (give this or spin_rate_rad_s)"),
        Param("initial_tilt_deg", default=0.0, low=0.0, high=180.0, open_high=True,
              doc="initial angle theta0 between the body axis Gz and the upward vertical, degrees"),
        Param("initial_tilt_azimuth_deg", default=0.0, low=-360.0, high=360.0,
              doc="compass azimuth toward which the axis leans, degrees (0 north, 90 east)"),
        Param("initial_tilt_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial d(theta)/dt, degrees/s"),
        Param("initial_azimuth_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6,
              doc="initial rate of the axis' compass azimuth (clockwise from above), degrees/s"),
        Param("rtol", default=1e-10, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
    )
    MECHANICS = frozenset()
    MEASURED_CHANNELS = ("tilt", "tilt_azimuth")
    JOINTS = ("tilt", "tilt_azimuth", "spin")
    SIMULATOR_NODE = "top_sim"
    COLUMNS = (
        Column("tilt", "rad", "theta: angle between the body axis Gz and the upward vertical"),
        Column("tilt_azimuth", "rad", "compass azimuth of the axis' horizontal projection (0 north, clockwise)"),
        Column("spin_rate", "rad/s", "r: body angular velocity about Gz"),
        Column("com_height", "m", "height of the centre of mass above the plane, h(n)"),
        Column("vertical_body_x", "1", "a'' = theta sin psi: body-x component of the upward vertical (eq. 16)"),
        Column("vertical_body_y", "1", "b'' = theta cos psi: body-y component of the upward vertical (eq. 16)"),
    )

    @classmethod
    def check_params(cls, prefix, p) -> None:
        """Cross-field checks: the shape's required fields, one spin, a physical inertia."""
        if p["spin_rate_rad_s"] is not None and p["spin_rate_turn_s"] is not None:
            raise SceneError(f"{prefix}.spin_rate_turn_s", p["spin_rate_turn_s"],
                             "give either spin_rate_rad_s or spin_rate_turn_s, not both")
        own = {"ellipsoid": ("semi_axes_m",), "curvature": ("curvature_radii_m", "com_height_m")}
        for other, keys in own.items():
            if other != p["shape"]:
                for key in keys:
                    if p[key] is not None:
                        raise SceneError(f"{prefix}.{key}", p[key], f"applies only to shape = {other}")
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
            for key, what in (("curvature_radii_m", "2 numbers > 0, m"), ("com_height_m", "a number > 0, m"),
                              ("inertia_kg_m2", "A, B, C > 0, kg m^2")):
                if p[key] is None:
                    raise SceneError(f"{prefix}.{key}", None, f"is required when shape = curvature ({what})")
        I = p["inertia_kg_m2"]
        if I is not None and (p["shape"] == "curvature" or not p["homogeneous"]):
            A, B, C = I
            if min(I) <= 0.0 or A + B < C or B + C < A or A + C < B:
                raise SceneError(f"{prefix}.inertia_kg_m2", list(I),
                                 "must be 3 numbers > 0 obeying the triangle inequalities "
                                 "(A + B >= C, B + C >= A, C + A >= B) of a rigid body")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        self.g = float(site.gravity_m_s2)
        self.M = float(self.mass_kg)
        if self.shape == "ellipsoid":
            self.alpha, self.beta, self.gamma = self.semi_axes_m
            self.rho = self.alpha ** 2 / self.gamma
            self.rho_prime = self.beta ** 2 / self.gamma
            self.delta = 0.0
            self.surface = EllipsoidSurface(self.semi_axes_m)
            self.inertia = (homogeneous_inertia(self.M, self.semi_axes_m) if self.homogeneous
                            else tuple(self.inertia_kg_m2))
        else:
            self.rho, self.rho_prime = self.curvature_radii_m
            self.gamma = float(self.com_height_m)
            self.delta = math.radians(self.curvature_angle_deg)
            self.surface = EllipsoidSurface.osculating(self.rho, self.rho_prime, self.gamma, self.delta)
            self.inertia = tuple(self.inertia_kg_m2)
        if self.spin_rate_rad_s is not None:
            self.r0 = float(self.spin_rate_rad_s)
        elif self.spin_rate_turn_s is not None:
            self.r0 = TWO_PI * float(self.spin_rate_turn_s)
        else:
            self.r0 = 0.0
        self.theta0 = math.radians(self.initial_tilt_deg)
        self.azimuth0 = math.radians(self.initial_tilt_azimuth_deg)
        self.thetadot0 = math.radians(self.initial_tilt_rate_deg_s)
        self.azimuthdot0 = math.radians(self.initial_azimuth_rate_deg_s)

    # ---------------------------------------------------------------- predictions
    def coefficients(self, r=None) -> tuple:
        """D, E, F, G of eq. (14) at spin ``r`` (rad/s; default the initial spin)."""
        A, B, C = self.inertia
        r = self.r0 if r is None else r
        if self.shape == "ellipsoid":
            return (*ellipsoid_coefficients(A, B, C, self.M, self.g, r, self.alpha, self.beta, self.gamma), 0.0)
        return curvature_coefficients(A, B, C, self.M, self.g, r, self.rho, self.rho_prime, self.gamma,
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
            and the initial invariants (energy, vertical angular momentum about G).
        """
        A, B, C = self.inertia
        D, E, F, G = self.coefficients()
        v = classify_coefficients(A, B, D, E, F, G)
        rcrit = critical_spin_general_rad_s(A, B, C, self.M, self.g, self.rho, self.rho_prime, self.gamma,
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
        if self.shape == "ellipsoid" and self.homogeneous:
            rc = critical_spin_rad_s(self.alpha, self.beta, self.gamma, self.g)
            out["critical_spin_closed_form_rad_s"] = rc
            out["critical_spin_closed_form_turn_s"] = rc / TWO_PI
        y0 = self.initial_state()
        diag = self.diagnostics(y0[:, None])
        out["energy_J"] = float(diag["energy_J"][0])
        out["angular_momentum_vertical_kg_m2_s"] = float(diag["angular_momentum_vertical_kg_m2_s"][0])
        return out

    def scales(self, duration_s) -> dict:
        """Characteristic scales: spin, small-tilt restoring rate at rest, amplitude, duration."""
        A, B, _ = self.inertia
        w0 = math.sqrt(self.M * self.g * min(abs(self.rho - self.gamma), abs(self.rho_prime - self.gamma))
                       / max(A, B))
        return {"earth_rate_rad_s": self.site.earth_rate_rad_s, "gyro_rate_rad_s": abs(self.r0) or None,
                "restoring_rate_rad_s": w0, "amplitude_rad": self.theta0, "duration_s": duration_s}

    # ---------------------------------------------------------------- model
    def initial_state(self) -> np.ndarray:
        """State [q_w, q_x, q_y, q_z, w_x, w_y, w_z] at t = 0 (quaternion body -> ENU, w in body axes)."""
        th, az = self.theta0, self.azimuth0
        # axis u in ENU, leaning toward compass azimuth az: (sin az, cos az) horizontally
        e_th = np.array([math.cos(th) * math.sin(az), math.cos(th) * math.cos(az), -math.sin(th)])
        e_az = np.array([math.cos(az), -math.sin(az), 0.0])  # direction of increasing compass azimuth
        u = np.array([math.sin(th) * math.sin(az), math.sin(th) * math.cos(az), math.cos(th)])
        udot = self.thetadot0 * e_th + self.azimuthdot0 * math.sin(th) * e_az
        w_world = self.r0 * u + np.cross(u, udot)
        # rotation by th about e_z x u / |...| = (-cos az, sin az, 0) (horizontal, perpendicular to az)
        axis = np.array([-math.cos(az), math.sin(az), 0.0])
        q = np.concatenate([[math.cos(th / 2)], math.sin(th / 2) * axis])
        R = rotation_matrix(q)
        return np.concatenate([q, R.T @ w_world])

    def rhs(self) -> Callable:
        """Right-hand side f(t, y) of the exact model (:mod:`.dynamics`)."""
        surf, inertia, M, g = self.surface, self.inertia, self.M, self.g
        sqrt = math.sqrt

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
        _, _, N, h, zdot, n = contact_dynamics(y, self.surface, self.inertia, self.M, self.g, np.sqrt)
        q = y[:4]
        qn2 = np.sum(q * q, axis=0)
        qw, qx, qy, qz = q
        axis = np.array([2.0 * (qx * qz + qw * qy), 2.0 * (qy * qz - qw * qx), qw * qw - qx * qx - qy * qy + qz * qz]) / qn2
        A, B, C = self.inertia
        w = y[4:]
        rot = 0.5 * (A * w[0] ** 2 + B * w[1] ** 2 + C * w[2] ** 2)
        energy = 0.5 * self.M * zdot ** 2 + rot + self.M * self.g * h
        lz = n[0] * A * w[0] + n[1] * B * w[1] + n[2] * C * w[2]
        return {"n": np.array(n), "axis_enu": axis, "com_height_m": h, "com_velocity_m_s": zdot,
                "normal_force_N": N, "energy_J": energy, "angular_momentum_vertical_kg_m2_s": lz,
                "quaternion_norm": np.sqrt(qn2)}

    STREAMS = True

    def simulate(self, t, rtol=None, atol=1e-12, **options) -> Simulation:
        """Integrate the exact model (DOP853) and sample at times ``t`` (s, from t[0]): one block of
        :meth:`stream`.

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
        """Block by block (:meth:`Instrument.stream`): one DOP853 step sequence bounded by the run's
        end, carried across blocks (the blocks concatenate to :meth:`simulate` bit for bit);
        ``extra["min_normal_force_N"]`` is the block's minimum."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        run = integration(self.rhs(), self.initial_state(), t0, t_end, method="DOP853",
                          rtol=self.rtol if rtol is None else rtol, atol=atol)
        for t in blocks:
            traj = run.advance(t)
            d = self.diagnostics(traj.y)
            n, axis = d["n"], d["axis_enu"]
            tilt = np.arctan2(np.hypot(n[0], n[1]), n[2])
            columns = {"tilt": tilt,
                       "tilt_azimuth": compass_azimuth_from_enu(axis[0], axis[1]),
                       "spin_rate": traj.y[6].copy(),
                       "com_height": d["com_height_m"],
                       "vertical_body_x": n[0], "vertical_body_y": n[1]}
            extra = {k: d[k] for k in ("energy_J", "angular_momentum_vertical_kg_m2_s", "quaternion_norm",
                                       "normal_force_N", "com_velocity_m_s")}
            extra["min_normal_force_N"] = float(np.min(d["normal_force_N"]))
            extra["state"] = traj.y
            yield Simulation(t, columns, traj, extra=extra)
