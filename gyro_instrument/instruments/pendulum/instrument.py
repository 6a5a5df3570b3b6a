"""Foucault (spherical) pendulum and compound pendulum on the rotating Earth.

Quet 1853 sec. 2. The bob, at r (ENU, from the suspension point; |r| = l), obeys eq. (21)
in vector form::

    r̈ = g + [−2 Ω × ṙ]_(earth_rotation) + [−Ω × (Ω × (r − r_rest))]_(centrifugal)
        + [drag]_(air_drag) − λ r

with g = (0, 0, −g) the plumb-line gravity at the rest point r_rest = (0, 0, −l) (it holds the
centrifugal part there, sec. 2 §I) and the tension λ r from the constraint (23), |r| = l:
λ = (ṙ·ṙ + r·F + 2a r·ṙ + b² C)/|r|², C = (|r|² − l²)/2, where the Baumgarte terms (a, b of the
order of √(g/l)) damp any numerical drift of the constraint and vanish on the exact solution.
Cartesian coordinates have no singularity, so any launch and any amplitude up to the inverted
position is allowed. Without ``finite_amplitude`` the linear (small-angle) model is
integrated: the horizontal motion ẍ = −(g/l) x + Coriolis ..., whose exact solution is Binet's
ellipse turning at −k (:func:`binet_ellipse`).

Predictions (sec. 2): the swing plane turns at k = n sin γ, clockwise seen from above in the
north (compass azimuth increasing); the quarter period (42) — exact form
:func:`quarter_period_s`; released from rest at θ0, the minimum deflection β = √(l/g) k sin θ0
cos(θ0/2) (§II) and the apsides turn at k (1 − (3/8) θ0 sin θ0 cos(θ0/2)) (§III), a series;
the exact rate (any amplitude) is :func:`apsidal_rate_exact_rad_s` (elliptic integral of the third kind).

The compound pendulum (sec. 3 §VI) is a body of revolution hung from a point of its axis, CM
at distance l, moments A (about the pivot, transverse) and C (axial): it moves like a simple
pendulum of length λ = A / (M l) when μ = C/A is small and ρ0 ≈ 0 (eq. 57).
"""

import math
from collections.abc import Iterator

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.angles import Unwrapper
from gyro_instrument.core.effect import (CORIOLIS, DAMPING, GYROSCOPIC, POINT_MASS, RIGID_BODY, RESTORING_LAW, SINE_LAW,
                                         SPIN, Scales)
from gyro_instrument.core.integrate import integration
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import (Column, ExpectedSwing, Instrument, Simulation, check_period_count,
                                              run_span, with_notes)
from gyro_instrument.instruments.chain import HingeChain, Link
from gyro_instrument.instruments.observation import PlanePrecession
# The theory (.theory) and the dynamics (.dynamics) live apart; their public names
# are re-exported here, where they were defined before.
from gyro_instrument.instruments.pendulum.columns import pendulum_columns
from gyro_instrument.instruments.pendulum.dynamics import SwingDynamics
from gyro_instrument.instruments.pendulum.theory import (apsidal_angle, apsidal_rate_exact_rad_s,
                                                         apsidal_rate_from_rest_exact_rad_s,
                                                         apsidal_rate_from_rest_rad_s, areal_constant_over_omega0,
                                                         binet_ellipse, min_deflection_for_areal_constant,
                                                         min_deflection_from_rest_rad,
                                                         min_deflection_with_horizontal_rate_rad, precession_sense,
                                                         quarter_period_s, quarter_period_series_s,
                                                         release_areal_constant_rad_s)

__all__ = ["CompoundPendulum", "PENDULUM_COLUMNS", "PENDULUM_JOINTS", "PENDULUM_MEASURED", "SWING_WINDOW_MIN_SAMPLES",
           "SphericalPendulum", "WINDOW_SAMPLING", "apsidal_angle", "apsidal_rate_exact_rad_s",
           "apsidal_rate_from_rest_exact_rad_s", "apsidal_rate_from_rest_rad_s", "areal_constant_over_omega0",
           "binet_ellipse", "min_deflection_for_areal_constant", "min_deflection_from_rest_rad",
           "min_deflection_with_horizontal_rate_rad", "pendulum_columns", "precession_sense", "quarter_period_s",
           "quarter_period_series_s", "relative_spin_rad_s", "release_areal_constant_rad_s"]

PENDULUM_COLUMNS = (
    Column("deflection", "rad", "θ: angle of the bob from the downward vertical"),
    Column("azimuth", "rad", "ψ: compass azimuth of the bob's horizontal position (0 north, clockwise), unwrapped"),
    Column("swing_azimuth", "rad", "instantaneous swing-plane azimuth (compass, modulo π, unwrapped) from the "
                                   "Fradkin tensor ω0² r rᵀ + v vᵀ of the horizontal motion"),
    Column("x_east", "m", "bob east of the suspension point"),
    Column("y_north", "m", "bob north of the suspension point"),
    Column("z_up", "m", "bob height relative to the suspension point (negative below)"),
)


#: What a pendulum's sensor reads and publishes (``Instrument.MEASURED_CHANNELS``, ``JOINTS``).
PENDULUM_MEASURED = ("deflection_east", "deflection_north")
PENDULUM_JOINTS = PENDULUM_MEASURED + ("deflection", "azimuth")


#: Fewest samples in one swing period for the Foucault estimator's second moments of the deflections
#: over that period (estimators/foucault.py): fewer leave windows it cannot use.
SWING_WINDOW_MIN_SAMPLES = 8

#: What a pendulum's observation needs of the sampling (:class:`ExpectedSwing`'s last two fields).
WINDOW_SAMPLING = (float(SWING_WINDOW_MIN_SAMPLES),
                   "the swing plane is measured from second moments of the deflections over each swing "
                   "period, which needs that many samples in it")


def _not_conservative(effect_names) -> list:
    """The effects among ``effect_names`` (registered names) that do not declare ``conservative``, sorted."""
    from gyro_instrument.effects import REGISTRY
    return sorted(n for n in effect_names if not (n in REGISTRY and REGISTRY[n].is_conservative()))


class SphericalPendulum(SwingDynamics, Instrument):
    """Foucault pendulum: a point bob on a massless rod, Cartesian rotating-frame model."""

    type_name = "spherical_pendulum"
    summary = "Foucault pendulum, point bob, any launch and amplitude (Quet sec. 2)"
    PARAMS = (
        Param("length_m", default=67.0, low=0.0, high=1.0e4, open_low=True, doc="rod length l, m"),
        Param("initial_deflection_deg", default=2.0, low=0.0, high=180.0,
              doc="θ0 from the downward vertical (180 is the inverted bob: simulated, no swing to describe)"),
        Param("initial_azimuth_deg", default=90.0, low=-360.0, high=360.0,
              doc="compass azimuth of the release point (0 north, 90 east)"),
        Param("radial_speed_m_s", default=0.0, low=-1.0e3, high=1.0e3, doc="launch speed away from the vertical"),
        Param("transverse_speed_m_s", default=0.0, low=-1.0e3, high=1.0e3,
              doc="launch speed perpendicular to the release plane (u0 of sec. 2 §IV), positive clockwise "
                  "seen from above (toward increasing azimuth)"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance (adaptive)"),
        Param("integrator", kind="str", default="auto", choices=("auto", "adaptive", "parareal"),
              doc="auto: parareal whenever the model allows it (finite_amplitude listed, every effect conservative "
                  "as earth_rotation, centrifugal and finite_amplitude are, a release from rest at up to 10 degrees whose "
                  "amplitude is "
                  "above the round-off floor), "
                  "else adaptive ('describe' says which and why); adaptive: DOP853 swing after swing; parareal: "
                  "the fast path for long runs of the full model, a fixed-step RK8 over every swing period: "
                  "compiled (numba) swing after swing for runs of 2048 swings or more, else every swing period "
                  "of a window at once (batched over periods on numpy, Newton-parareal from Quet's comparison "
                  "pendulum)"),
        Param("segment_steps", kind="int", default=48, low=8, high=100000,
              doc="parareal: RK8 steps per swing period"),
        Param("shooting_tol", default=1e-9, low=1e-14, high=1e-3,
              doc="parareal: largest change of a swing's start state (relative to the amplitude) accepted"),
    )
    MECHANICS = frozenset({POINT_MASS, RESTORING_LAW})
    #: Both models sum every ``point_mass`` term through its hook (:meth:`~.dynamics.SwingDynamics.rhs_exact`,
    #: ``rhs_linear``); the exact (Cartesian) model is exact in the angle, the sine law, and is taken
    #: when an effect gives a restoring law (:meth:`model_taken`), the small-angle model otherwise.
    MODELS = {"exact": frozenset({POINT_MASS, SINE_LAW}), "linear": frozenset({POINT_MASS})}
    COLUMNS = PENDULUM_COLUMNS
    MEASURED_CHANNELS = PENDULUM_MEASURED
    JOINTS = PENDULUM_JOINTS
    OBSERVATION = PlanePrecession
    SIMULATOR_NODE = "pendulum_sim"

    @classmethod
    def model_taken(cls, params, effects) -> str:
        """``exact`` when an active effect has a ``restoring_law`` term (the sine law), else ``linear``."""
        return "exact" if any(RESTORING_LAW in e.MECHANICS for e in effects.values()) else "linear"

    @classmethod
    def check_effects(cls, prefix, p, effects) -> None:
        from gyro_instrument.core.errors import SceneError
        super().check_effects(prefix, p, effects)
        if p["integrator"] == "parareal":
            if not cls.named_with_term(effects, RESTORING_LAW):
                raise SceneError(f"{prefix}.integrator", "parareal", "needs the effect finite_amplitude (the "
                                 "full model); the linear model has Binet's closed form")
            dissipative = _not_conservative(effects)
            if dissipative:
                raise SceneError(f"{prefix}.integrator", "parareal", f"needs a conservative motion: leave out "
                                 f"{', '.join(dissipative)} or use integrator: adaptive")
            if p["initial_deflection_deg"] >= 90.0 or p["initial_deflection_deg"] <= 0.0 \
                    or p["radial_speed_m_s"] != 0.0 or p["transverse_speed_m_s"] != 0.0:
                raise SceneError(f"{prefix}.integrator", "parareal", "needs a release from rest at a deflection "
                                 "in (0, 90) degrees (its period and precession come from that release)")

    #: The parareal fast path needs of the active effects (chosen by ``integrator: auto``, required by
    #: an explicit ``parareal``): a ``restoring_law`` effect (the full Cartesian model, whose right-hand
    #: side :meth:`rhs_exact` sums every active ``point_mass`` term, batched over swings as the hook's
    #: contract says) and every effect ``conservative`` (:data:`~gyro_instrument.core.effect.CONSERVATIVE`:
    #: its Newton iteration starts from the comparison pendulum, a conservative swing, and its period is
    #: that of the first swing). Any effect declaring it keeps the fast path; none is named here.
    #: Largest release deflection (deg) at which ``integrator: auto`` takes parareal at its default
    #: grid: against DOP853 at rtol 1e-12 (5 m, 20 min, full model) the largest position difference
    #: over the amplitude was 3.2e-10, 2.2e-10, 3.2e-10 at 2°, 5°, 10°, under the shooting tolerance
    #: 1e-9, then 1.3e-9 at 20°, 4.7e-9 at 30° and 6.1e-7 at 60° (48 RK8 steps per swing no longer
    #: resolve the large swing's harmonics): beyond 10° auto keeps the adaptive DOP853.
    PARAREAL_AUTO_MAX_DEG = 10.0

    def chosen_integrator(self, duration_s=None) -> tuple:
        """(integrator, reason): ``adaptive`` or ``parareal`` as the scene asks, or for ``auto`` the fast
        path parareal when the full model and a release from rest allow it (the conditions
        :meth:`check_effects` enforces for an explicit parareal: a restoring law and every active effect
        conservative), else adaptive with the reason."""
        if self.p.integrator != "auto":
            return self.p.integrator, "chosen in the scene"
        if self.restoring_law() is None:
            return "adaptive", "auto: the linear (small-angle) model has no parareal path (finite_amplitude not listed)"
        other = _not_conservative(self.effects)
        if other:
            return "adaptive", f"auto: parareal is for a conservative swing; {', '.join(other)} listed"
        if not (0.0 < self.p.initial_deflection_deg < 90.0) or self.p.radial_speed_m_s or self.p.transverse_speed_m_s:
            return "adaptive", "auto: parareal needs a release from rest between 0 and 90 degrees"
        # The bob's height (~l) carries round-off eps·l: relative to the swing amplitude l sin θ0 that is
        # eps / sin θ0, and Newton cannot move the swing starts by less (at θ0 = 1e-9 rad it stalled at
        # 1e-7 > shooting_tol 1e-9). Auto asks for a floor 100 times below the tolerance.
        floor = np.finfo(float).eps / math.sin(self.p.initial_deflection_rad)
        if 100.0 * floor > self.p.shooting_tol:
            return "adaptive", (f"auto: at a release of {self.p.initial_deflection_deg:.3g} deg the round-off of the "
                                f"bob's height is {floor:.1e} of the amplitude, too close to parareal's shooting "
                                f"tolerance {self.p.shooting_tol:g}")
        if self.p.initial_deflection_deg > self.PARAREAL_AUTO_MAX_DEG:
            return "adaptive", (f"auto: a release at {self.p.initial_deflection_deg:g} deg is beyond the "
                                f"{self.PARAREAL_AUTO_MAX_DEG:g} deg where parareal's {self.p.segment_steps}-step grid "
                                f"is validated to its shooting tolerance")
        return "parareal", ("auto: the full conservative model released from rest, the fast path (a fixed-step RK8 "
                            "over every swing: compiled for runs of 2048 swings or more, else all swings of a window "
                            "at once on numpy; DOP853 with integrator: adaptive)")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)

    def pendulum_length_m(self) -> float:
        """The rod length l, m."""
        return self.p.length_m

    def expected_swing(self) -> "ExpectedSwing":
        """Four exact quarter periods of a plane swing (sec. 2 eq. 42 without its series:
        :func:`quarter_period_s`) and the release deflection θ0 (the Earth's k changes neither
        by more than (k/ω0)², below 1e-8 for any pendulum)."""
        return ExpectedSwing(4.0 * quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, 0.0), abs(self.p.initial_deflection_rad),
                             "length_m, initial_deflection_deg and the site's gravity", *WINDOW_SAMPLING)

    def initial_state(self) -> tuple:
        """Bob position and velocity (ENU) at release; velocity relative to the Earth."""
        st, ct = math.sin(self.p.initial_deflection_rad), math.cos(self.p.initial_deflection_rad)
        sp, cp = math.sin(self.p.initial_azimuth_rad), math.cos(self.p.initial_azimuth_rad)
        r = self.p.length_m * np.array([st * sp, st * cp, -ct])
        e_rad = np.array([ct * sp, ct * cp, st])        # ∂r/∂θ / l
        e_az = np.array([cp, -sp, 0.0])                 # ∂r/∂ψ direction (clockwise from above)
        if st == 0.0:
            e_az = np.array([cp, -sp, 0.0])
        v = self.p.radial_speed_m_s * e_rad + self.p.transverse_speed_m_s * e_az
        return r, v

    def predictions(self) -> dict:
        """Sec. 2 for the model as simulated: k = n sin γ (0 without ``earth_rotation``); with
        ``finite_amplitude`` the exact quarter period (42), β of §II and the exact apse-line rate
        ``apsidal_rate_from_rest_rad_s`` at release (:func:`apsidal_rate_from_rest_exact_rad_s`: the
        elliptic-integral apsidal angle of the spherical pendulum, the horizontal rate's share of the
        area constant included), beside Quet's series ``apsidal_rate_quet_series_rad_s`` of §III,
        k(1 − (3/8) θ0 sin θ0 cos(θ0/2)) (the paper's value; equal to k in the linear model); without it the linear model's Binet ellipse (quarter period π/(2Ω), Ω = √(g/l + k²),
        β = asin(sin θ0 · |k|/Ω), apsides turning at k). ``quarter_period_series_s`` is Quet's
        series (42) in every case.

        Rates (``foucault_rate_*``, ``apsidal_rate_*``) are signed components about the upward
        vertical, positive clockwise seen from above (k > 0 in the north); ``precession_sense`` says
        it in words. Magnitudes (β, periods, ``full_turn_h``) are ≥ 0 at every site.

        Beyond the paper (``finite_amplitude`` and ``earth_rotation``, release from rest):
        ``min_deflection_from_rest_exact_rad`` adds the horizontal Earth rate's term that §II's β
        drops (:func:`min_deflection_with_horizontal_rate_rad`), ``min_deflection_quet_relative_error``
        is β/that − 1 (0 for an east–west release), and ``beyond_the_paper`` (str) says so in words.
        """
        if self.p.initial_deflection_deg >= 180.0:
            raise SceneError(f"instruments.{self.name}.initial_deflection_deg", self.p.initial_deflection_deg,
                             "[0, 180) for the predictions of sec. 2: the inverted bob is an unstable equilibrium "
                             "with no swing (it can be simulated: it tips under the centrifugal gradient)")
        k_site = self.site.k_vertical_rad_s
        rotating = self.has_term(CORIOLIS)
        k = k_site if rotating else 0.0
        if self.has_term(SINE_LAW):
            beta = abs(min_deflection_from_rest_rad(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad))
            quarter = quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta)
            k_h = self.site.earth_rate_enu()[1] if rotating else 0.0
            apsidal = apsidal_rate_from_rest_exact_rad_s(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad, k_h, self.p.initial_azimuth_rad)
            series = apsidal_rate_from_rest_rad_s(k, self.p.initial_deflection_rad)
        else:
            W = math.sqrt(self.context.gravity_m_s2 / self.p.length_m + k * k)
            beta = math.asin(min(1.0, math.sin(self.p.initial_deflection_rad) * abs(k) / W))
            quarter = 0.5 * math.pi / W
            apsidal = series = k
        out = {"foucault_rate_rad_s": k,
               "foucault_rate_deg_h": math.degrees(k) * 3600.0,
               "precession_sense": precession_sense(k),
               "full_turn_h": (2 * math.pi / abs(k) / 3600.0) if k else math.inf,
               "quarter_period_s": quarter,
               "quarter_period_series_s": quarter_period_series_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta),
               "min_deflection_from_rest_rad": beta,
               "apsidal_rate_from_rest_rad_s": apsidal,
               "apsidal_rate_quet_series_rad_s": series}
        if self.has_term(SINE_LAW) and rotating and 0.0 < self.p.initial_deflection_rad < math.pi:
            out.update(self._horizontal_rate_beta(beta))
        return with_notes(out, self.missing_term_note(
            CORIOLIS, f"the swing plane keeps its azimuth (k = 0; with it k = n sin γ = {k_site:.6g} rad/s "
                              f"= {math.degrees(k_site) * 3600.0:.4g} deg/h)"),
            self.missing_term_note(
            SINE_LAW, "small-angle (linear) model: Binet's ellipse, quarter period π/(2√(g/l + k²)), "
                                "apsides turning at k"))

    def _horizontal_rate_beta(self, beta) -> dict:
        """What sec. 2 §II could not include: the horizontal Earth rate's share of the minimum
        deflection (:func:`min_deflection_with_horizontal_rate_rad`), for this release."""
        k_h = self.site.earth_rate_enu()[1]
        exact = min_deflection_with_horizontal_rate_rad(self.p.length_m, self.context.gravity_m_s2, self.site.k_vertical_rad_s, k_h,
                                                        self.p.initial_deflection_rad, self.p.initial_azimuth_rad)
        err = beta / exact - 1.0 if exact > 0.0 else math.inf
        north = min_deflection_with_horizontal_rate_rad(self.p.length_m, self.context.gravity_m_s2, self.site.k_vertical_rad_s, k_h,
                                                        self.p.initial_deflection_rad, 0.0)
        err_north = beta / north - 1.0 if north > 0.0 else math.inf
        from_rest = self.p.radial_speed_m_s == 0.0 and self.p.transverse_speed_m_s == 0.0
        def off(e):
            return "equal to it" if abs(e) < 1e-12 else f"{100.0 * abs(e):.3g} % {'above' if e > 0 else 'below'} it"
        text = (f"sec. 2 §II's minimum deflection β = √(l/g) k sin θ0 cos(θ0/2) keeps only the vertical Earth "
                f"rate; the horizontal rate n cos γ = {k_h:.6g} rad/s acting on the bob's vertical velocity changes "
                f"the area integral by −n cos γ l² cos ψ0 (θ0 − sin θ0 cos θ0): for this release (azimuth "
                f"{math.degrees(self.p.initial_azimuth_rad):g}°) the minimum deflection is {exact:.6g} rad and β = {beta:.6g} rad "
                f"is {off(err)} (for a release toward north here: {off(err_north)})"
                + ("" if from_rest else "; both are for a release from rest, not this launch"))
        return {"min_deflection_from_rest_exact_rad": exact, "min_deflection_quet_relative_error": err,
                "beyond_the_paper": text}

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=None,
                restoring_rate_rad_s=math.sqrt(self.context.gravity_m_s2 / self.p.length_m), amplitude_rad=self.p.initial_deflection_rad,
                duration_s=duration_s)

    STREAMS = True


def relative_spin_rad_s(qb, qda, qds) -> np.ndarray:
    """Quet's ρ (sec. 3 §VI): the body's spin about its figure axis relative to the Earth, rad/s.

    The figure axis e points from the pivot to the centre of mass; the spin is right-handed
    about e (the ``spin_rate_rad_s`` parameter is ρ0). The body's angular velocity relative to
    the Earth is the east hinge's rate q̇a along east, the north hinge's q̇b along the hinge's
    north axis (perpendicular to e) and the spin hinge's q̇s along e; in the body's axes east is
    (cos qb, 0, sin qb) and e = (0, 0, −1), so ρ = q̇s − q̇a sin qb.

    Eq. (53), d(ρ − K cos θ + K' sin θ sin ψ) = 0, integrated in (55): ρ + Ω·e is constant (the
    body's absolute spin; no torque acts about the figure axis of a body of revolution).

    Parameters
    ----------
    qb, qda, qds : ndarray (m,)
        North-hinge angle (rad), east-hinge rate and spin-hinge rate (rad/s) of the chain.

    Returns
    -------
    ndarray (m,)
        ρ, rad/s.
    """
    return qds - qda * np.sin(qb)


class CompoundPendulum(Instrument):
    """Compound pendulum (Quet sec. 3 §VI): a body of revolution hung from a point of its axis.

    Integrated with the generic :class:`HingeChain`: two massless Cardan hinges (about east,
    then about the new north) carry the body, which spins about its own axis. The Cardan pair
    is singular only with the axis horizontal along east–west, so deflections stay below 90°.
    """

    type_name = "compound_pendulum"
    summary = "body of revolution hung from a point of its axis (Quet sec. 3 §VI)"
    PARAMS = (
        Param("mass_kg", default=10.0, low=0.0, open_low=True, doc="M"),
        Param("com_distance_m", default=1.0, low=0.0, open_low=True, doc="l: pivot to centre of mass"),
        Param("transverse_inertia_kg_m2", default=10.0, low=0.0, open_low=True,
              doc="A: moment about a transverse axis through the pivot (≥ M l²)"),
        Param("axial_inertia_kg_m2", default=0.01, low=0.0, open_low=True, doc="C: moment about the figure axis"),
        Param("spin_rate_rad_s", default=0.0, low=-1.0e5, high=1.0e5, doc="initial relative spin ρ0"),
        Param("initial_deflection_deg", default=5.0, low=0.0, high=80.0, open_low=False,
              doc="θ0 (below 90°: Cardan hinges)"),
        Param("initial_azimuth_deg", default=90.0, low=-360.0, high=360.0, doc="compass azimuth of the release"),
        Param("rtol", default=1e-11, low=1e-14, high=1e-3, doc="integrator relative tolerance"),
    )
    MECHANICS = frozenset({RIGID_BODY, DAMPING, SPIN})
    COLUMNS = PENDULUM_COLUMNS + (Column("spin_rate", "rad/s", "ρ: spin about the figure axis (pivot to centre of "
                                                             "mass, right-handed) relative to the Earth; ρ + Ω·e "
                                                             "is constant (sec. 3 §VI eq. 55)"),)
    MEASURED_CHANNELS = PENDULUM_MEASURED
    JOINTS = PENDULUM_JOINTS
    OBSERVATION = PlanePrecession
    SIMULATOR_NODE = "pendulum_sim"

    @classmethod
    def check_params(cls, prefix, p) -> None:
        from gyro_instrument.core.errors import SceneError
        ml = p["mass_kg"] * p["com_distance_m"]
        if not (ml > 0.0 and math.isfinite(p["transverse_inertia_kg_m2"] / ml)):
            raise SceneError(f"{prefix}.com_distance_m", p["com_distance_m"],
                             f"with mass_kg = {p['mass_kg']:g} gives M l = {ml:g}: the equivalent length A/(M l) is "
                             f"not a finite number")
        ml2 = p["mass_kg"] * p["com_distance_m"] ** 2
        if p["transverse_inertia_kg_m2"] < ml2 * (1 - 1e-12):
            raise SceneError(f"{prefix}.transverse_inertia_kg_m2", p["transverse_inertia_kg_m2"],
                             f"must be >= M l^2 = {ml2:g} (parallel-axis theorem)")

    def __init__(self, name, site, params, effects) -> None:
        super().__init__(name, site, params, effects)
        self.equivalent_length_m = self.p.transverse_inertia_kg_m2 / (self.p.mass_kg * self.p.com_distance_m)

    def pendulum_length_m(self) -> float:
        """The pivot–centre-of-mass distance l, m (the deflections are those of the centre of mass)."""
        return self.p.com_distance_m

    def expected_swing(self) -> "ExpectedSwing":
        """Four quarter periods of the simple pendulum of the equivalent length λ (sec. 3 §VI eq. 57)
        and the release deflection θ0."""
        return ExpectedSwing(4.0 * quarter_period_s(self.equivalent_length_m, self.site.gravity_m_s2, self.p.initial_deflection_rad, 0.0),
                             abs(self.p.initial_deflection_rad), "the body's inertia, mass, centre of mass and initial deflection",
                             *WINDOW_SAMPLING)

    def predictions(self) -> dict:
        """Sec. 3 §VI: equivalent length λ = A/(M l) (eq. 57), k = n sin γ (0 without
        ``earth_rotation``; signed, positive clockwise seen from above, as ``precession_sense``
        says in words), the quarter period of the simple pendulum of length λ, and
        ``absolute_spin_rad_s`` = ρ0 + Ω·e0, the constant of eq. (55) (ρ + Ω·e, e the figure axis
        from the pivot to the centre of mass, Ω the Earth rate as simulated), rad/s."""
        k_site = self.site.k_vertical_rad_s
        k = k_site if self.has_term(GYROSCOPIC) else 0.0
        lam = self.equivalent_length_m
        g = self.site.gravity_m_s2
        e0 = np.array([math.sin(self.p.initial_deflection_rad) * math.sin(self.p.initial_azimuth_rad), math.sin(self.p.initial_deflection_rad) * math.cos(self.p.initial_azimuth_rad),
                       -math.cos(self.p.initial_deflection_rad)])
        om = self.site.earth_rate_enu() if self.has_term(GYROSCOPIC) else np.zeros(3)
        out = {"equivalent_length_m": lam, "foucault_rate_rad_s": k, "precession_sense": precession_sense(k),
               "quarter_period_s": quarter_period_s(lam, g, self.p.initial_deflection_rad, 0.0),
               "absolute_spin_rad_s": self.p.spin_rate_rad_s + float(om @ e0)}
        return with_notes(out, self.missing_term_note(
            GYROSCOPIC, f"the swing plane keeps its azimuth (k = 0; with it k = n sin γ = {k_site:.6g} rad/s)"))

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=None,
                restoring_rate_rad_s=math.sqrt(self.site.gravity_m_s2 / self.equivalent_length_m),
                amplitude_rad=self.p.initial_deflection_rad, duration_s=duration_s)

    def build_chain(self) -> HingeChain:
        A, C = self.p.transverse_inertia_kg_m2, self.p.axial_inertia_kg_m2
        links = [Link("cardan_east", np.array([1.0, 0.0, 0.0]), np.zeros((3, 3))),
                 Link("cardan_north", np.array([0.0, 1.0, 0.0]), np.zeros((3, 3))),
                 Link("body", np.array([0.0, 0.0, -1.0]), np.diag([A, A, C]),
                      mass_kg=self.p.mass_kg, com_m=np.array([0.0, 0.0, -self.p.com_distance_m]), spin_inertia=C)]
        links[0].swing_inertia = links[1].swing_inertia = A
        return HingeChain(links, np.eye(3), self.site.earth_rate_enu(),
                          np.array([0.0, 0.0, -self.context.gravity_m_s2]), self.effects.values(), self.context)

    STREAMS = True

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """Integrate the hinge chain block by block (:meth:`Instrument.stream`): one DOP853 step
        sequence bounded by the run's end, carried across blocks, so the blocks concatenate to
        :meth:`simulate` bit for bit. Raises SceneError (``transverse_inertia_kg_m2``) for a run of
        more swings than can be integrated."""
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        check_period_count(f"instruments.{self.name}.transverse_inertia_kg_m2", self.p.transverse_inertia_kg_m2,
                           2.0 * math.pi * math.sqrt(self.equivalent_length_m / self.site.gravity_m_s2), t_end - t0)
        chain = self.build_chain()
        d = np.array([math.sin(self.p.initial_deflection_rad) * math.sin(self.p.initial_azimuth_rad), math.sin(self.p.initial_deflection_rad) * math.cos(self.p.initial_azimuth_rad),
                      -math.cos(self.p.initial_deflection_rad)])
        # Body axis (0,0,-1) after Rx(a) Ry(b) is (−sin b, cos b sin a, −cos b cos a).
        b = math.asin(-d[0])
        a = math.atan2(d[1], -d[2])
        run = integration(chain.rhs, [a, b, 0.0, 0.0, 0.0, self.p.spin_rate_rad_s], t0, t_end, rtol=self.p.rtol,
                          atol=1e-13)
        unwrappers = (Unwrapper(), Unwrapper())
        for t in blocks:
            traj = run.advance(t)
            qa, qb, qs, qda, qdb, qds = traj.y
            lc = self.p.com_distance_m
            pos = lc * np.vstack([-np.sin(qb), np.cos(qb) * np.sin(qa), -np.cos(qb) * np.cos(qa)])
            # velocity of the CM by differentiating the expression
            vel = lc * np.vstack([-np.cos(qb) * qdb,
                                  -np.sin(qb) * qdb * np.sin(qa) + np.cos(qb) * np.cos(qa) * qda,
                                  np.sin(qb) * qdb * np.cos(qa) + np.cos(qb) * np.sin(qa) * qda])
            cols = pendulum_columns(pos, vel, self.site.gravity_m_s2 / self.equivalent_length_m, unwrappers)
            cols["spin_rate"] = relative_spin_rad_s(qb, qda, qds)
            yield Simulation(t, cols, traj, extra={"chain": chain})
