"""Directing-plane gyroscope: Quet 1853 sec. 4 §1 (the gyrocompass), and its cone variant.

A body of revolution (moments A, C; μ = C/A) has its centre of mass fixed; its axis may turn
only in a plane fixed on the Earth (or on a cone of half-angle ε). Axes: ``oz`` the plane
normal, ``ox`` the projection of the north part of Earth's axis on the plane, ``oy = oz × ox``;
u is the angle of the rotor axis from ``ox``, counter-clockwise about ``oz``; ρ the relative
spin about the axis; ω the angle between the normal and Earth's axis.

Reduced model (``model: reduced``), exact for the rigid body when ``earth_rotation`` and
``centrifugal`` are both listed — the Lagrangian L = ½C(φ̇ + n sin ω cos u)² + ½A[(u̇ + r)² +
(n sin ω sin u)²] gives::

    u'' = −μ n sin ω ρ sin u − (μ − 1) n² sin² ω cos u sin u      (eq. 2 plus the dropped O(n²))
    d(ρ + n sin ω cos u) = 0                                       (eq. 3)

Quet's eq. (2) is the first term alone (``centrifugal`` absent). Small swings last
T = π / √(μ n ρ0 sin ω) (eq. 9: one swing, HALF the period); finite amplitude a multiplies
this by (2/π) K(sin(a/2)) (item 6: pendulum law). Hence n = π² / (μ ρ0 T² sin ω) (eq. 10;
item 8's printed π/(μρ0T²) is a misprint) and item 9: (T_m / T_h)² = cos γ.

Cone (``cone_half_angle_deg`` < 90): T = π √(sin ε / (μ n ρ0 sin ω)) (sec. 4 §1, end; the
printed second equation lacks a factor sin ε, the period is right). Integrated with the
generic :class:`~gyro_instrument.instruments.chain.HingeChain`; u is then the azimuth of
the axis about the cone axis, from the half-plane toward Earth's north axis.

Horizontal plane, as a gyrocompass (issue 24): the scale the measured ``angle`` is read on has its
zero at azimuth ``mount_azimuth_deg`` M (clockwise from true north) and reads like Quet's u,
counter-clockwise seen from above, so the reading is u + M (M wrapped to (−180°, 180°]; true north
reads +M; the clockwise reading of ``estimators/north.py`` is its negative, −angle = azimuth − M).
M = 0 (or M unstated, read as 0: the estimate still reports north, null with its reason when the
record cannot give it) reads u itself. A torsion tape (the ``torsion`` effects, e.g. ``tape_torsion``,
``tape_drift``) adds −(D_B/A)(u + M − Z(t)) to u'': the swing centre is pulled toward the tape zero Z,
to the equilibrium D_K sin(c − N) = D_B (Z − c) (:meth:`PlaneGyroscope.equilibrium_reading_rad`; near
north the linear c = (D_K N + D_B Z)/(D_K + D_B)) with D_K = C ρ0 n cos γ, and a rotor-off swing (the same gyroscope
with ``spin_rate_rad_s: 0``, named by ``rotor_off_instrument``) gives Z and D_B (D_K: Quet 1853
sec. 4 §1 eq. 9, sin ω = cos γ; the tape: this package's model, derived in ``estimators/north/fit.py``).
"""

import math
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import integrate, integration
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import plane_frame
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.core.effect import (CENTRIFUGAL_TORQUE, DAMPING, GYROSCOPIC, RESTORING_LAW, RIGID_BODY, SINE_LAW, SPIN,
                                         TORSION, VISCOUS_DAMPING, VISCOUS_SPIN, Scales)
from gyro_instrument.instruments.base import Column, DirectingModel, ExpectedSwing, Instrument, Simulation, run_span, with_notes
from gyro_instrument.instruments.chain import HingeChain, Link, axis_rotation
from gyro_instrument.instruments.observation_azimuth import HorizontalSwing


def plane_normal_enu(plane, normal_enu, site) -> np.ndarray:
    """Normal of the named directing plane in ENU.

    ``horizontal``: up (u counter-clockwise from north seen from above); ``meridian``: east;
    ``polar`` (normal along Earth's axis, Quet item 4: no restoring torque); ``custom``: given.
    """
    if plane == "horizontal":
        return np.array([0.0, 0.0, 1.0])
    if plane == "meridian":
        return np.array([1.0, 0.0, 0.0])
    if plane == "polar":
        return site.earth_axis_north_enu()
    return np.asarray(normal_enu, dtype=float)


def swing_duration_small_s(mu, earth_rate, spin, sin_omega, sin_eps=1.0) -> float:
    """One-swing duration of small oscillations, T = π √(sin ε / (μ n ρ0 sin ω)) (eq. 9 and
    the cone variant); ``inf`` when there is no restoring torque (items 1–4)."""
    k = mu * earth_rate * spin * sin_omega
    if k <= 0.0:
        return math.inf
    return math.pi * math.sqrt(sin_eps / k)


class PlaneGyroscope(Instrument):
    """Gyroscope whose axis turns in a directing plane (or on a cone) fixed on the Earth."""

    type_name = "plane_gyroscope"
    summary = "rotor axis held in a directing plane or cone (Quet sec. 4 §1)"
    PARAMS = (
        Param("plane", kind="str", default="horizontal", choices=("horizontal", "meridian", "polar", "custom"),
              doc="directing plane: horizontal, meridian, polar (normal along Earth's axis) or custom"),
        Param("normal_enu", kind="vec3", default=None, doc="plane normal in ENU when plane = custom"),
        Param("cone_half_angle_deg", default=90.0, low=0.0, high=90.0, open_low=True,
              doc="half-angle ε of the directing cone about the normal; 90 = plane"),
        Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True,
              doc="μ = C/A, axial over transverse moment (≤ 2 for a rigid body of revolution)"),
        Param("transverse_inertia_kg_m2", default=1.0e-3, low=0.0, open_low=True, doc="A, kg m^2"),
        Param("spin_rate_rad_s", default=2 * math.pi * 100.0, low=-1.0e6, high=1.0e6,
              doc="initial relative spin ρ0 about the axis, rad/s (positive: Earth's sense when u = 0)"),
        Param("initial_angle_deg", default=math.degrees(0.1), low=-180.0, high=180.0,
              doc="initial angle u0 of the axis from the equilibrium line, degrees"),
        Param("initial_rate_deg_s", default=0.0, low=-1.0e6, high=1.0e6, doc="initial u̇0, degrees/s"),
        Param("model", kind="str", default="reduced", choices=("reduced", "chain"),
              doc="reduced 1-DOF equation or the generic hinge chain (cone, or an effect whose terms the reduced "
                  "equation does not carry: always chain)"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
        Param("integrator", kind="str", default="auto", choices=("auto", "scalar", "vector"),
              doc="DOP853 driver of the reduced model: scalar (Python floats, ~5x faster on its 3 components), "
                  "vector (scipy's solve_ivp on arrays; the same steps, equal to rounding), auto: scalar; the "
                  "hinge chain (model: chain, a cone) always runs vector"),
        Param("mount_azimuth_deg", default=None, low=0.0, high=360.0, open_high=True,
              doc="horizontal plane: azimuth (clockwise from true north) of the scale's zero; the measured "
                  "angle reads u + this (wrapped to (-180, 180] degrees), so true north reads +this, and the "
                  "estimate reports it (north). Unstated (null): reads as 0 and every other result is as before "
                  "issue 24; north is then null with its reason when the record cannot give it (shorter than "
                  "one swing, no directing torque, a fit refused) where a stated mount is refused (exit 2)"),
        Param("rotor_off_instrument", kind="str", default="",
              doc="with tape_torsion: the scene's instrument that is this gyroscope swung with the rotor off "
                  "(spin_rate_rad_s: 0), whose swing gives the tape zero and D_B"),
    )
    MECHANICS = frozenset({RIGID_BODY, DAMPING, SPIN, RESTORING_LAW, TORSION})
    MEASURED_CHANNELS = ("angle",)
    JOINTS = ("axis", "rotor")
    OBSERVATION = HorizontalSwing
    SHOWS_AXIS = True
    SIMULATOR_NODE = "gyrocompass_sim"
    COLUMNS = (Column("angle", "rad", "u: axis angle from the north projection, counter-clockwise about the "
                      "normal; a horizontal plane's table, bag and sensor read it on the scale, u + mount_azimuth_deg"),
               Column("angle_rate", "rad/s", "du/dt"),
               Column("spin_rate", "rad/s", "ρ: relative spin of the rotor about its axis"))

    @classmethod
    def check_params(cls, prefix, p) -> None:
        if p["plane"] == "custom" and p["normal_enu"] is None:
            raise SceneError(f"{prefix}.normal_enu", None, "is required when plane = custom (3 numbers, ENU)")
        if p["mount_azimuth_deg"] is not None and (p["plane"] != "horizontal" or p["cone_half_angle_deg"] < 90.0):
            raise SceneError(f"{prefix}.mount_azimuth_deg", p["mount_azimuth_deg"],
                             "must be left out unless plane = horizontal (a flat plane: the scale's zero is an azimuth)")

    #: The models and the term kinds each carries (:data:`~gyro_instrument.core.effect.TERM_KINDS`): the
    #: reduced equation (:meth:`reduced_rhs_scalar`) is derived by hand for these forms; the hinge chain
    #: (:meth:`build_chain`) sums every ``rigid_body``, ``damping``, ``spin`` and ``torsion`` term through
    #: the hooks and is exact in the angle (the sine law).
    MODELS = {"reduced": frozenset({GYROSCOPIC, CENTRIFUGAL_TORQUE, SINE_LAW, VISCOUS_DAMPING, VISCOUS_SPIN, TORSION}),
              "chain": frozenset({RIGID_BODY, DAMPING, SPIN, TORSION, SINE_LAW})}

    @classmethod
    def model_taken(cls, params, effects) -> str:
        """``chain`` on a cone, when the scene asks for it, or when an active effect has a term the reduced
        equation does not carry (:data:`MODELS`); else ``reduced``."""
        if params["cone_half_angle_deg"] < 90.0 or cls.uncarried_effects("reduced", effects):
            return "chain"
        return params["model"]

    @classmethod
    def check_effects(cls, prefix, params, effect_names) -> None:
        """Every effect carried by the model taken (:meth:`~.base.Instrument.check_carried`); a tape (the
        ``torsion`` effects) hangs a horizontal gyroscope only (a tape's drift alone has no stiffness to
        act through: it changes nothing)."""
        super().check_effects(prefix, params, effect_names)
        tape = sorted(cls.named_with_term(effect_names, TORSION))
        if tape and (params["plane"] != "horizontal" or params["cone_half_angle_deg"] < 90.0):
            raise SceneError(f"{prefix}.effects", tape, "a torsion tape hangs a horizontal gyroscope: "
                             "needs plane = horizontal and no cone")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        self.normal = plane_normal_enu(self.p.plane, self.p.normal_enu, site)
        self.frame, self.sin_omega = plane_frame(self.normal, site)
        self.is_cone = self.p.cone_half_angle_deg < 90.0
        self.C = self.p.inertia_ratio * self.p.transverse_inertia_kg_m2
        #: the scale's reading of true north, rad: M wrapped to (−π, π] (module docstring)
        mount = math.radians(self.p.mount_azimuth_deg or 0.0)
        self.mount_reading_rad = math.pi - (math.pi - mount) % (2.0 * math.pi)
        self.tape = self._tape()
        self._check_tape()

    def _tape(self) -> tuple:
        """(D_B N m/rad, Z0 rad, Ż rad/s): the sums of the active ``torsion`` effects' terms."""
        terms = [e.torsion_term(self.context) for e in self.effects_of(TORSION)]
        return tuple(float(sum(x)) for x in zip(*terms)) if terms else (0.0, 0.0, 0.0)

    def directing_constant_n_m(self) -> float:
        """D_K = C ρ0 n sin ω, the directing torque per radian at the site (N m/rad; 0 without
        ``earth_rotation``): Quet's μ n ρ0 sin ω (eq. 9) times A."""
        return self.C * self.p.spin_rate_rad_s * self.model_earth_rate() * self.sin_omega

    def _check_tape(self) -> None:
        """Refuse a tape that cancels, reverses or outweighs the directing torque (the rotor on)."""
        D_B = self.tape[0]
        if not D_B or not self.p.spin_rate_rad_s:
            return
        D_K = self.directing_constant_n_m()
        if self.frame_rotates() and D_B >= D_K:
            per_cos = self.C * self.p.spin_rate_rad_s * self.site.earth_rate_rad_s
            lim = math.degrees(math.acos(D_B / per_cos)) if 0 < D_B < per_cos else None
            where = f"; for this tape |site.latitude_deg| < {lim:.4g}" if lim is not None else ""
            raise SceneError(self._stiffness_field(), D_B,
                             f"must be < D_K = C rho0 n cos(latitude) = {D_K:.6g} N m/rad of {self.name} at latitude "
                             f"{self.site.latitude_deg:g} deg: a tape at least as stiff cancels or reverses the directing "
                             f"torque's hold on the swing centre (D_K sin(c - N) = D_B (Z - c)){where}")

    def _stiffness_field(self) -> str:
        """``effects.<effect>.<parameter>`` of the tape's stiffness (the first ``torsion`` effect with one)."""
        for e in (e for e in self.effects_of(TORSION) if e.torsion_term(self.context)[0]):
            held = [p.name for p in e.PARAMS if e.params.get(p.name) == e.torsion_term(self.context)[0]]
            return f"effects.{e.name}" + (f".{held[0]}" if held else "")
        return "effects"

    def tape_ratio(self) -> float:
        """D_B/D_K of the scene (nan without rotor or directing torque)."""
        D_K = self.directing_constant_n_m()
        return self.tape[0] / D_K if D_K else math.nan

    # ---------------------------------------------------------------- predictions
    def _swing_duration_small_s(self, n):
        """Eq. (9) (or the cone form) at Earth rate ``n``; with a torsion tape π/√(K + D_B/A)."""
        if self.tape[0]:
            k = self.p.inertia_ratio * n * self.p.spin_rate_rad_s * self.sin_omega + self.tape[0] / self.p.transverse_inertia_kg_m2
            return math.pi / math.sqrt(k) if k > 0 else math.inf
        return swing_duration_small_s(self.p.inertia_ratio, n, self.p.spin_rate_rad_s, self.sin_omega,
                                      math.sin(self.p.cone_half_angle_rad) if self.is_cone else 1.0)

    def equilibrium_reading_rad(self, t_s=0.0) -> float:
        """The swing's equilibrium c on the scale at time ``t_s`` (rad, the counter-clockwise reading
        u + M of the measured ``angle``), exact for the reduced model (:meth:`reduced_rhs_scalar`):
        (a ρ + b cos u) s(u) + k_B (u + M − Z0 − Ż t) = 0, u = c − M, by Newton from north (u = 0).
        Without a tape c = M, true north's reading. With the rotor off: the tape zero (a torsion
        pendulum). The north estimate's :func:`~gyro_instrument.estimators.north.joint.equilibrium`
        solves the same equation, in the clockwise reading (derived in ``north.fit.tape_north``)."""
        c = self.reduced_coefficients()
        K, b, kb = c["a"] * self.p.spin_rate_rad_s * math.exp(-c["decay"] * t_s), c["b"], c["kb"]
        M = self.mount_reading_rad
        if not kb:
            return M
        zero = c["zero"] + c["zero_rate"] * t_s - M          # the tape zero's u
        sine = c["sine_law"]
        u = 0.0 if K > 0 else zero
        for _ in range(100):
            s, ds = (math.sin(u), math.cos(u)) if sine else (u, 1.0)
            f = (K + b * math.cos(u)) * s + kb * (u - zero)
            step = f / ((K + b * math.cos(u)) * ds - b * math.sin(u) * s + kb)
            u -= step
            if abs(step) < 1e-15:
                break
        return M + u

    def tape_predictions(self) -> dict:
        """With a torsion tape: D_B/D_K, the rotor-off swing duration π√(A/D_B) (s) and the swing centre's
        offset from north c − N on the scale at the start (rad, counter-clockwise reading), the exact
        equilibrium (:meth:`equilibrium_reading_rad`; the linear law (D_B/(D_K + D_B))(Z − N) errs by
        tens of arcseconds once the scale's zero is degrees from north)."""
        D_B = self.tape[0]
        D_K = self.directing_constant_n_m()
        return {"tape_ratio": D_B / D_K if D_K else None,
                "rotor_off_swing_duration_s": math.pi * math.sqrt(self.p.transverse_inertia_kg_m2 / D_B),
                "centre_offset_rad": self.equilibrium_reading_rad() - self.mount_reading_rad}

    def _north_predictions(self) -> dict:
        """A horizontal gyroscope asked for north (a stated mount or a tape): the scale readings (ccw,
        the measured ``angle``'s, degrees) of true north and of the swing's centre at the start; with
        the rotor off, the torsion pendulum on its tape (no directing torque)."""
        if self.p.plane != "horizontal" or self.is_cone or (self.p.mount_azimuth_deg is None and not self.tape[0]):
            return {}
        c = self.reduced_coefficients()
        arcsec_h = 3600.0 * 648000.0 / math.pi
        if not self.p.spin_rate_rad_s:
            if not self.tape[0]:
                return {}
            kb, d = c["kb"], c["damping"]
            damped = kb - 0.25 * d * d
            return {"torsion_period_s": 2.0 * math.pi / math.sqrt(kb),
                    "torsion_period_damped_s": 2.0 * math.pi / math.sqrt(damped) if damped > 0 else math.inf,
                    "tape_zero_reading_deg": math.degrees(c["zero"]), "tape_zero_rate_arcsec_h": c["zero_rate"] * arcsec_h,
                    "damping_per_s": d}
        out = {"north_reading_deg": math.degrees(self.mount_reading_rad),
               "mount_azimuth_deg": float(self.p.mount_azimuth_deg or 0.0)}
        if self.frame_rotates():
            centre = self.equilibrium_reading_rad()
            out.update({"centre_reading_deg": math.degrees(centre),
                        "centre_from_north_arcsec": (centre - self.mount_reading_rad) * 648000.0 / math.pi})
        if self.tape[0]:
            out.update({"tape_zero_reading_deg": math.degrees(c["zero"]), "tape_zero_rate_arcsec_h": c["zero_rate"] * arcsec_h})
        return out

    def predictions(self) -> dict:
        """Eq. (9) (or the cone form), the finite-amplitude factor and eq. (10)'s ingredients, for
        the model as simulated: without ``earth_rotation`` n = 0, there is no directing torque
        μ n ρ0 sin ω and the durations are infinite (``null`` in JSON); without
        ``finite_amplitude`` the small-angle model swings in T0 at any amplitude. A horizontal
        gyroscope asked for north adds :meth:`_north_predictions`; with its rotor off (a torsion
        pendulum on its tape) its swing is the tape's alone and the gyroscope's words (sin ω, the
        conserved spin, the tape ratio) are left out."""
        n = self.model_earth_rate()
        T0 = self._swing_duration_small_s(n)
        factor = finite_amplitude_factor(self.p.initial_angle_rad) if self.has_term(SINE_LAW) else 1.0
        north = self._north_predictions()
        out = {"swing_duration_small_s": T0,
               "swing_duration_s": T0 * factor if math.isfinite(T0) else math.inf,
               "period_s": 2.0 * T0}
        if "torsion_period_s" in north:       # a torsion pendulum: linear tape, its period at any amplitude
            return north | {"swing_duration_small_s": T0, "swing_duration_s": T0}
        out = north | {"sin_omega": self.sin_omega} | out | {
            "conserved_spin_rad_s": self.p.spin_rate_rad_s + n * self.sin_omega * math.cos(self.p.initial_angle_rad)}
        if self.tape[0]:
            out.update(self.tape_predictions())
        T_site = self._swing_duration_small_s(self.site.earth_rate_rad_s)
        rest = " (only the O(n²) centrifugal term acts)" if self.has_term(CENTRIFUGAL_TORQUE) else ""
        return with_notes(out, self.missing_term_note(
            GYROSCOPIC, f"no directing torque μ n ρ0 sin ω (eq. 9): the axis stays where it is released{rest}, "
                        f"swing durations null (with it T0 = {T_site:.6g} s)"),
            self.missing_term_note(
            SINE_LAW, "small-angle model: swing_duration_s = swing_duration_small_s at any amplitude"))

    def axis_direction_enu(self, position) -> "np.ndarray":
        """Rotor axis in ENU, (m, 3): cos u · ox + sin u · oy in the plane's frame (``core.site.plane_frame``),
        u the ``axis`` joint (rad)."""
        import numpy as np
        from gyro_instrument.core.site import plane_frame
        R, _ = plane_frame(self.normal, self.site)
        u = np.asarray(position)[:, 0] - self.mount_reading_rad
        return np.cos(u)[:, None] * R[:, 0] + np.sin(u)[:, None] * R[:, 1]

    def expected_swing(self) -> "ExpectedSwing | None":
        """Period 2 T0 of eq. (9) at the scene's spin and latitude (times the finite-amplitude factor
        when simulated) and amplitude u0; None without a directing torque."""
        T = self.predictions()["swing_duration_s"]
        if not (math.isfinite(T) and T > 0):
            return None
        return ExpectedSwing(2.0 * T, abs(self.p.initial_angle_rad), "inertia_ratio, spin_rate_rad_s, plane and the site's latitude")

    def directing_model(self) -> DirectingModel | None:
        """What an estimator may know of this instrument: K = (π/T0)² = gain · n ρ · sin ω(γ), with
        gain = μ (μ / sin ε on a cone) and sin ω from the plane normal (ENU) and the latitude."""
        gain = self.p.inertia_ratio / (math.sin(self.p.cone_half_angle_rad) if self.is_cone else 1.0)
        # The exact equation adds (μ − 1) n² sin² ω to K (module docstring): K/(μρ) = y0 (1 + c2 y0 / ρ)
        # with y0 = n sin ω and c2 = (μ − 1)/μ. Derived for the plane only (ε = 90°).
        c2 = 0.0 if self.is_cone else (self.p.inertia_ratio - 1.0) / self.p.inertia_ratio
        return DirectingModel(gain=gain, second_order=c2, normal_enu=tuple(float(v) for v in self.normal),
                              label=self.p.plane, angle_channel="angle", spin_rate_rad_s=float(self.p.spin_rate_rad_s),
                              null_reason="a directing plane perpendicular to Earth's axis (horizontal at a pole) "
                                          "has no restoring torque (Quet sec. 4 §1 item 4)")

    def scales(self, duration_s) -> Scales:
        """The common scales, and this instrument's own: ``torsion_share`` (D_B/(D_K + D_B) of a tape) and
        ``swing_inertia_kg_m2`` (the swinging hinge's inertia A, kg m²)."""
        n = self.site.earth_rate_rad_s
        T0 = self._swing_duration_small_s(n)           # the scales of the rotating Earth (effect sizes)
        return Scales(earth_rate_rad_s=n, gyro_rate_rad_s=abs(self.p.inertia_ratio * self.p.spin_rate_rad_s) or None,
                restoring_rate_rad_s=math.pi / T0 if math.isfinite(T0) else 0.0,
                amplitude_rad=abs(self.p.initial_angle_rad), duration_s=duration_s,
                torsion_share=self._torsion_share(), swing_inertia_kg_m2=self.p.transverse_inertia_kg_m2)

    def _torsion_share(self) -> float:
        """D_B / (D_K + D_B) (0 without a tape; 1 with the rotor off)."""
        total = self.directing_constant_n_m() + self.tape[0]
        return self.tape[0] / total if self.tape[0] and total > 0 else 0.0

    # ---------------------------------------------------------------- models
    def reduced_rhs_scalar(self) -> Callable:
        """Right-hand side of the reduced model on floats, ``f(t, u, u̇, ρ) -> (u̇, ü, ρ̇)``; only
        listed effects::

            ü = −μ p ρ s − (μ − 1) p² cos u · s − d u̇     (eq. 2; O(n²) term: ``centrifugal``)
                − (D_B/A)(u + M − Z0 − Ż t)                  (a torsion tape: ``tape_torsion``, ``tape_drift``)
            ρ̇ = p sin u · u̇ − ρ / τ_s                       (eq. 3; spin decay: ``spin_decay``)

        with p = n sin ω, s = sin u (``finite_amplitude``; u for Quet's small-swing form) and d the
        ``pivot_damping`` rate. Absent effects enter as zero coefficients."""
        c = self.reduced_coefficients()
        a, pr, b, damp, kb, zr, decay = (c[k] for k in ("a", "pr", "b", "damping", "kb", "zero_rate", "decay"))
        zb = c["zero"] - self.mount_reading_rad
        sin, cos = math.sin, math.cos

        if kb:
            law = sin if c["sine_law"] else (lambda x: x)

            def rhs(t, u, ud, rho):
                su = law(u)
                return (ud, -(a * rho + b * cos(u)) * su - kb * (u - zb - zr * t) - damp * ud,
                        pr * sin(u) * ud - decay * rho)
        elif c["sine_law"]:                          # the sine law (finite_amplitude): sin u
            def rhs(t, u, ud, rho):
                su = sin(u)
                return ud, -(a * rho + b * cos(u)) * su - damp * ud, pr * su * ud - decay * rho
        else:
            def rhs(t, u, ud, rho):
                return ud, -(a * rho + b * cos(u)) * u - damp * ud, pr * sin(u) * ud - decay * rho
        return rhs

    def reduced_coefficients(self) -> dict:
        """The constants of the reduced model (:meth:`reduced_rhs_scalar`), absent effects as zeros:
        ``a`` = μ n sin ω (eq. 2; times ρ the directing constant per inertia, 1/s²), ``pr`` = n sin ω
        (eq. 3), ``b`` = (μ − 1) n² sin² ω (the O(n²) term, 1/s²), ``damping`` (1/s), ``kb`` = D_B/A
        (1/s²), ``zero`` Z0 and ``zero_rate`` Ż (the tape zero on the scale, rad, rad/s), ``decay``
        (1/s, the spin's) and ``sine_law`` (``finite_amplitude``: sin u, else u). The north estimate's
        exact fit (:mod:`gyro_instrument.estimators.north.exact`) fits the same equation."""
        p = self.site.earth_rate_rad_s * self.sin_omega
        mu = self.p.inertia_ratio
        rot = self.has_term(GYROSCOPIC)
        tau_s = self.spin_decay_time_s(self.C) or 0.0
        return {"a": mu * p if rot else 0.0, "pr": p if rot else 0.0,
                "b": (mu - 1.0) * p * p if self.has_term(CENTRIFUGAL_TORQUE) else 0.0,
                "damping": self.viscous_damping_rate_per_s(self.p.transverse_inertia_kg_m2),
                "kb": self.tape[0] / self.p.transverse_inertia_kg_m2, "zero": self.tape[1], "zero_rate": self.tape[2],
                "decay": 1.0 / tau_s if tau_s else 0.0, "sine_law": self.has_term(SINE_LAW)}

    def reduced_rhs(self) -> Callable:
        """Right-hand side of the reduced model for y = [u, u̇, ρ] (array form of
        :meth:`reduced_rhs_scalar`, eqs. 2–3); only listed effects."""
        f = self.reduced_rhs_scalar()

        def rhs(t, y):
            u, ud, rho = y
            return np.array(f(t, u, ud, rho))
        return rhs

    def build_chain(self) -> HingeChain:
        """The same instrument as a hinge chain: swing hinge about the normal (massless frame),
        an optional fixed tilt to the cone, then the rotor's spin hinge."""
        # the frame's hinge reads u + M on a horizontal plane's scale: a torsion tape acts on it there
        flat = self.p.plane == "horizontal" and not self.is_cone
        links = [Link("frame", np.array([0.0, 0.0, 1.0]), np.zeros((3, 3)),
                      scale_offset_rad=self.mount_reading_rad if flat else None)]
        # Rotor axis along body x; tilt about y by (π/2 − ε) puts it at ε from the normal.
        tilt = axis_rotation([0.0, 1.0, 0.0], -(math.pi / 2 - self.p.cone_half_angle_rad)) if self.is_cone else np.eye(3)
        links[0].swing_inertia = self.p.transverse_inertia_kg_m2 * (math.sin(self.p.cone_half_angle_rad) ** 2 if self.is_cone else 1.0)
        links.append(Link("rotor", np.array([1.0, 0.0, 0.0]), np.diag([self.C, self.p.transverse_inertia_kg_m2, self.p.transverse_inertia_kg_m2]),
                          pre_rotation=tilt, spin_inertia=self.C))
        g = np.array([0.0, 0.0, -self.site.gravity_m_s2])
        return HingeChain(links, self.frame, self.site.earth_rate_enu(), g, self.effects.values(), self.context)

    STREAMS = True

    def chosen_integrator(self, duration_s=None) -> tuple:
        """(driver, reason): the DOP853 driver a run uses (``integrator``; auto: the scalar driver for
        the reduced model, scipy's for the hinge chain)."""
        if self._model() == "chain":
            outside = self.uncarried_effects("reduced", self.effects)
            why = "a cone" if self.is_cone else (
                "; ".join(f"{n}: its terms {', '.join(k)} are outside the reduced equation" for n, k in outside.items())
                if outside else "model: chain")
            return "vector", f"the hinge chain ({why}) runs scipy's DOP853 on arrays"
        if self.p.integrator != "auto":
            return self.p.integrator, "chosen in the scene"
        return "scalar", "auto: the reduced model's 3 components on Python floats, the fast path (same steps as vector)"

    def _model(self, model=None):
        taken = self.taken_model()
        return "chain" if taken == "chain" and (self.is_cone or self.uncarried_effects("reduced", self.effects)) else (model or taken)

    def simulate(self, t, model=None, **options) -> Simulation:
        """Integrate from rest relative to the Earth at u0 (with u̇0) and spin ρ0: the reduced model
        (scalar DOP853) or the hinge chain — always the chain on a cone or with an active effect the
        reduced equation does not carry (:data:`MODELS`; ``extra["model"]`` says which ran). One block of
        :meth:`stream`; sample times that are not increasing go to the generic driver, which refuses
        them with ``solve_ivp``'s ValueError."""
        t = np.asarray(t, dtype=float)
        if t.ndim == 1 and t.size and np.all(np.diff(t) >= 0.0):
            return super().simulate(t, model=model, **options)
        if self._model(model) == "reduced":
            traj = integrate(self.reduced_rhs(), [self.p.initial_angle_rad, self.p.initial_rate_rad_s, self.p.spin_rate_rad_s], t, rtol=self.p.rtol,
                             atol=1e-13)
            u, ud, rho = traj.y
            return Simulation(t, {"angle": u, "angle_rate": ud, "spin_rate": rho}, traj, extra={"model": "reduced"})
        return super().simulate(t, model=model, **options)

    def stream(self, blocks, model=None, **options) -> Iterator[Simulation]:
        """Integrate block by block (:meth:`Instrument.stream`): the reduced model on the resumable
        scalar DOP853 (:class:`~gyro_instrument.core.dop853.ScalarDOP853`; scipy's with ``integrator:
        vector``) or the hinge chain on
        scipy's DOP853 (:class:`~gyro_instrument.core.integrate.Integration`), the step sequence
        carried across blocks, so the blocks concatenate to :meth:`simulate` bit for bit."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        model = self._model(model)
        if model == "reduced":
            y0 = [self.p.initial_angle_rad, self.p.initial_rate_rad_s, self.p.spin_rate_rad_s]
            if self.p.integrator == "vector":
                run = integration(self.reduced_rhs(), y0, t0, t_end, rtol=self.p.rtol, atol=1e-13)
            else:
                run = integration(self.reduced_rhs_scalar(), y0, t0, t_end, method="DOP853-scalar", rtol=self.p.rtol,
                                  atol=1e-13)
            for t in blocks:
                traj = run.advance(t)
                u, ud, rho = traj.y
                yield Simulation(t, {"angle": u, "angle_rate": ud, "spin_rate": rho}, traj, extra={"model": model})
            return
        chain = self.build_chain()
        # ρ = φ̇ + u̇ cos ε (the frame's rate has a component cos ε along a cone axis).
        cos_eps = math.cos(self.p.cone_half_angle_rad) if self.is_cone else 0.0
        phid0 = self.p.spin_rate_rad_s - self.p.initial_rate_rad_s * cos_eps
        run = integration(chain.rhs, [self.p.initial_angle_rad, 0.0, self.p.initial_rate_rad_s, phid0], t0, t_end, rtol=self.p.rtol, atol=1e-13)
        for t in blocks:
            traj = run.advance(t)
            u, phi, ud, phid = traj.y
            rho = phid + ud * cos_eps
            yield Simulation(t, {"angle": u, "angle_rate": ud, "spin_rate": rho}, traj,
                             extra={"rotor_angle": phi, "chain": chain, "model": model})
