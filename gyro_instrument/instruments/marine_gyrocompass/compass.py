"""The ship's gyrocompass: a pendulous, Schuler-tuned, damped north-seeking gyroscope (issue 39 item 1).

Instrument type ``marine_gyrocompass``. Its equations are those of :mod:`.dynamics` (the sensitive
element on a ship, :mod:`gyro_instrument.core.motion`; without a ``motion:`` block on a fixed pier), its
closed forms those of :mod:`.theory`. What it reads: the ship's heading ψ (its course) less the north
end's azimuth α (the card's north is where the axis points), plus the corrections a real compass makes
from its speed and latitude inputs (Raytheon Anschütz *Standard 22* operator manual,
easymanua.ls/raytheon-anschutz/standard-22-nx/manual?p=23; Northrop Grumman Sperry Marine *NAVIGAT X MK 1*
manual, manualshive.com/ru/manual/northrop-grumman/navigat-x-mk-1/1708755?page=79: a speed from
the log through a first-order filter of time constant 20 s by default; a latitude set by hand or
taken from the track, as from a GNSS input)::

    heading = ψ − α − e_f + δ_s(V_f, ψ_r, φ_set) + δ_d(φ_set)

δ_s = −asin(V_f cos G / (R Ω cos φ_set)) the speed error the equations settle to, computed from the
compass's own uncorrected reading G = ψ − α − e_f, as a compass knows no other heading
(:func:`.theory.speed_correction_rad`: exactly the settle point atan2(−V cos C, R Ω cos φ + V sin C)
of :func:`.theory.speed_error_rad` written in G), with ``speed_correction``; δ_d = asin((P_d/P_c) tan φ_set) the damping
(latitude) error, with damping in tilt (the Sperry latitude correction: ``latitude_setting_deg``). A
latitude set wrong by Δφ leaves both corrections' change with latitude as an error
(:meth:`MarineGyrocompass.predictions` reports it for the site).

e_f is the follow-up's lag (ISO 22090-1 §3.9: the output's delay behind the turning ship). The
element is free in azimuth; its follow-up (the phantom ring a servo keeps aligned with it, carrying
the card and the transmitter) is modelled as a first-order system of bandwidth ``follow_up_bandwidth_hz``
(ω_b = 2π f_b): de_f/dt = ψ' − ω_b e_f, solved exactly over the schedule's pieces of constant turn rate
(:func:`.theory.follow_up_lag_rad`): a steady turn at rate r lags by r/ω_b. The element's own rate
α' (≲ Ω, 7e-5 rad/s) is left out of it: a lag α'/ω_b below 1e-3° at any bandwidth over 0.01 Hz. The
5-Hz default is ASSUMED (no follow-up bandwidth was found in the public manuals searched; ISO 22090-1
§5.3.4 limits only the follow-up error).

Design figures: Schuler tuning 84.4 min at the design latitude (Chalmers, *The gyroscopic compass*,
ch. X: 40°; bitlit.ru/page/en/t-w-chalmers/the-gyroscopic-compass-a-non-mathematical-treatment/24);
Sperry's damping P_d/P_c = 1/40 ("Gyro Numerical Solved", scribd 598664583). The oil damping's lag and
ratio and the element's swing period are illustrative (no published figure was found: sources file).
"""

import math
from typing import ClassVar

import numpy as np

from gyro_instrument.core.effect import FRAME_RATE, Scales
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.motion import KNOT_M_S, Motion, Piece
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import Column, Instrument, Simulation, with_notes
from gyro_instrument.instruments.marine_gyrocompass import theory as th
from gyro_instrument.instruments.marine_gyrocompass.dynamics import Coefficients, integrate_pieces
from gyro_instrument.instruments.observation import Observation

#: ``latitude_setting_deg``'s word for "follow the ship's position".
TRACK = "track"


class LatitudeSetting(Param):
    """A latitude in degrees, [−89, 89], or the word ``track`` (the compass's latitude input follows the
    ship's dead-reckoned latitude, as from a GNSS input)."""

    def describe_range(self) -> str:
        return "must be a number of degrees in [-89, 89] or 'track'"

    def check(self, field, value) -> "float | str":
        if value == TRACK:
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not (-89.0 <= float(value) <= 89.0):
            raise SceneError(field, value, self.describe_range())
        return float(value)


class CompassObservation(Observation):
    """The compass's heading reading (rad), an angle channel, read beside the ship's track: the
    measurement kind ``compass`` (:mod:`gyro_instrument.estimators.compass_kind`: settle-point error,
    period and damping of the settling curve, heading error along the track). It gives no Earth-rate
    measurement; its block is the instrument's ``compass``."""

    ALSO_MEASURES = ("compass",)
    TRACK_KEYS = ("course", "latitude", "speed")

    def unmeasured_reason(self) -> str:
        return "a ship's gyrocompass gives its heading error (the compass block), not an Earth-rate measurement"

    def complete(self, rec) -> dict:
        """``rec`` with the ship's track at its times (``course`` rad, ``latitude`` rad, ``speed`` m/s) where
        it has none: the scene's ``motion:`` block (a pier: course 0 at the site, at rest), as a ship has its
        course and position from GNSS and its speed from the log."""
        if all(k in rec for k in self.TRACK_KEYS):
            return rec
        t = np.asarray(rec["t"], dtype=float)
        mo = self.instrument.motion
        if mo is None:
            tr = {"course": np.zeros_like(t), "latitude": np.full_like(t, self.instrument.site.latitude_rad),
                  "speed": np.zeros_like(t)}
        else:
            tr = mo.track(t)
        return rec | {k: tr[k] for k in self.TRACK_KEYS if k not in rec}

    def record_from_table(self, full, col, size, notes) -> dict:
        """The heading column (the track: the table's ``ship.*`` columns, added by the table reader, or the
        scene's, :meth:`complete`)."""
        return {c: col(c) for c in full}

    def table_columns(self) -> tuple:
        return (("heading",),)


class MarineGyrocompass(Instrument):
    """A ship's gyrocompass (module docstring): heading from a pendulous, damped gyroscope on a ship."""

    type_name = "marine_gyrocompass"
    summary = ("ship's gyrocompass: pendulous (or ballistic) Schuler-tuned gyroscope, damped in tilt (Sperry) or "
               "azimuth (Anschutz), on the scene's ship; heading with speed and latitude corrections")
    PARAMS = (
        Param("control", kind="str", default="pendulous", choices=("pendulous", "ballistic"),
              doc="control torque: a bottom-heavy element, or a top-heavy liquid ballistic with the rotor spinning "
                  "the other way (the same equations for the north end: instantaneous liquid flow)"),
        Param("damping", kind="str", default="tilt", choices=("tilt", "azimuth", "none"),
              doc="damping in tilt (Sperry: a latitude error sin d = (P_d/P_c) tan lat), in azimuth (Anschutz: "
                  "a lagging oil ballistic, no error) or none"),
        Param("design_latitude_deg", default=40.0, low=0.0, high=80.0,
              doc="latitude where the compass is Schuler-tuned (84.4 min; ballistic deflection dead-beat)"),
        Param("pendulosity_factor", default=1.0, low=0.0, high=100.0, open_low=True,
              doc="P_c over its Schuler-tuned value at the design latitude (1: tuned)"),
        Param("damping_torque_ratio", default=0.025, low=0.0, high=1.0,
              doc="P_d/P_c of damping in tilt (Sperry: 1/40)"),
        Param("oil_torque_ratio", default=1.6, low=0.0, high=100.0,
              doc="k_o: the oil ballistic's torque over the control torque (damping in azimuth)"),
        Param("oil_lag_s", default=300.0, low=0.0, high=1.0e4, open_low=True,
              doc="the oil's flow time constant, s (damping in azimuth)"),
        Param("element_swing_period_s", default=30.0, low=0.0, high=1000.0, open_low=True,
              doc="period of the element's pendulum swing about its spin axis, s (illustrative)"),
        Param("element_swing_damping_ratio", default=0.5, low=0.0, high=10.0,
              doc="damping ratio of that swing (the supporting liquid)"),
        Param("initial_azimuth_deg", default=20.0, low=-180.0, high=180.0,
              doc="the north end's azimuth at switch-on, degrees east of true north (the initial heading error, "
                  "opposite sign)"),
        Param("initial_tilt_deg", default=0.0, low=-30.0, high=30.0, doc="the north end's tilt at switch-on, degrees"),
        LatitudeSetting("latitude_setting_deg", kind="latitude", default=TRACK,
                        doc="the compass's latitude input, degrees, or 'track' (the ship's position)"),
        Param("speed_correction", kind="bool", default=True,
              doc="correct the speed error from the speed log and the latitude input"),
        Param("speed_filter_s", default=20.0, low=0.0, high=1000.0,
              doc="time constant of the speed log's filter, s (NAVIGAT X MK 1: 20 s; 0: none)"),
        Param("follow_up_bandwidth_hz", default=5.0, low=0.0, high=1000.0, open_low=True,
              doc="bandwidth of the first-order follow-up carrying the card, Hz (a steady turn at rate r lags by "
                  "r / (2 pi f)); 5 Hz ASSUMED, no published figure"),
        Param("ned_heading", kind="bool", default=False,
              doc="ROS: also publish the heading in NED on <name>/heading_ned (frame <name>_body_ned); "
                  "simulate ignores it"),
    )
    MECHANICS = frozenset({FRAME_RATE})
    COLUMNS = (
        Column("heading", "rad", "the compass's heading reading (corrections applied), wrapped to [0, 2 pi)"),
        Column("heading_error", "rad", "heading - the ship's true heading, wrapped to [-pi, pi)"),
        Column("azimuth", "rad", "alpha: the north end's azimuth east of true north (true, not read)"),
        Column("tilt", "rad", "theta: the north end's tilt above the horizontal"),
        Column("element_roll", "rad", "beta: the element's pendulum swing about its spin axis"),
        Column("correction", "rad", "the speed and latitude corrections the compass adds"),
        Column("follow_up_lag", "rad", "the follow-up's lag behind the ship's heading (first order)"),
    )
    MEASURED_CHANNELS = ("heading",)
    JOINTS = ("heading",)
    OBSERVATION = CompassObservation
    #: Its own node (issue 39 item 5): the joint states, its heading as ``sensor_msgs/Imu`` and its state
    #: on /diagnostics (:mod:`gyro_instrument.ros.nodes.compass`).
    SIMULATOR_NODE = "marine_gyrocompass"
    #: It publishes its heading (:func:`gyro_instrument.recording.topics.publications`).
    SHOWS_HEADING: ClassVar[bool] = True
    #: It sails with the scene's ``motion:`` block (:func:`gyro_instrument.core.motion.check_sailing`).
    FEELS_MOTION: ClassVar[bool] = True
    #: The ship (:class:`~gyro_instrument.core.motion.Motion`), set by ``build_instruments``; None: a pier.
    motion: "Motion | None" = None

    # ------------------------------------------------------------------ constants
    def control_per_s(self) -> float:
        """P_c/H, 1/s (:func:`.theory.control_ratio_per_s` with the site's g and the design Earth rate)."""
        return th.control_ratio_per_s(self.context.gravity_m_s2, self.site.earth_rate_rad_s,
                                      math.radians(self.p.design_latitude_deg), self.p.pendulosity_factor)

    def coefficients(self) -> Coefficients:
        """The right-hand side's constants (:class:`.dynamics.Coefficients`)."""
        p, mo = self.p, self.motion
        kd = p.damping_torque_ratio if p.damping == "tilt" else 0.0
        ko = p.oil_torque_ratio if p.damping == "azimuth" else 0.0
        sway = {}
        if mo is not None:
            fwd, stbd = mo.sway_amplitudes_m_s2()
            sway = dict(fwd_m_s2=fwd, fwd_rate=mo.pitch_rate_rad_s, fwd_phase=mo.pitch_phase_rad, stbd_m_s2=stbd,
                        stbd_rate=mo.roll_rate_rad_s)
        return Coefficients(self.model_earth_rate(), self.context.gravity_m_s2, self.control_per_s(), kd, ko,
                            p.oil_lag_s, 2 * math.pi / p.element_swing_period_s, p.element_swing_damping_ratio,
                            p.speed_filter_s, **sway)

    def pieces(self) -> tuple:
        """The ship's schedule as pieces (a pier: one piece at rest at the site)."""
        if self.motion is None:
            return (Piece(0.0, math.inf, 0.0, 0.0, 0.0, 0.0, self.site.latitude_rad),)
        return self.motion.pieces

    def initial_state(self) -> tuple:
        p0 = self.pieces()[0]
        return (math.radians(self.p.initial_azimuth_deg), math.radians(self.p.initial_tilt_deg), 0.0, 0.0, 0.0,
                p0.lat0, p0.v0)

    # ------------------------------------------------------------------ protocol
    def scales(self, duration_s) -> Scales:
        """The Earth-rate torque is its directing torque itself (``gyro_rate_rad_s`` = P_c/H); the swing
        is the undamped compass period at the site."""
        w0 = 2 * math.pi / th.undamped_period_s(self.control_per_s(), self.site.earth_rate_rad_s,
                                                self.site.latitude_rad)
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, duration_s=duration_s, restoring_rate_rad_s=w0,
                      gyro_rate_rad_s=self.control_per_s(), amplitude_rad=abs(math.radians(self.p.initial_azimuth_deg)))

    def predictions(self) -> dict:
        """The period, settled tilt and settle points the closed forms give at the site (a pier) and,
        for a ship at its start speed and course, the speed error (:mod:`.theory`)."""
        p, lat, Om = self.p, self.site.latitude_rad, self.site.earth_rate_rad_s
        k, g = self.control_per_s(), self.context.gravity_m_s2
        out = {"schuler_period_s": th.schuler_period_s(g),
               "undamped_period_s": th.undamped_period_s(k, Om, lat),
               "undamped_period_design_latitude_s": th.undamped_period_s(k, Om, math.radians(p.design_latitude_deg)),
               "settled_tilt_rad": th.settled_tilt_rad(k, Om, lat),
               "damping_error_rad": th.damping_error_rad(p.damping_torque_ratio, lat) if p.damping == "tilt" else 0.0}
        if p.damping == "tilt":
            out["damping_ratio"] = th.damping_ratio_tilt(p.damping_torque_ratio, k, Om, lat)
        if self.motion is not None:
            p0 = self.motion.pieces[0]
            out["speed_error_rad"] = float(th.speed_error_rad(p0.v0 * math.sin(p0.c0), p0.v0 * math.cos(p0.c0), Om, lat))
            out["start_speed_kn"] = p0.v0 / KNOT_M_S
        if p.latitude_setting_deg != TRACK:         # the reading's error from the setting, at the start
            lat_set = math.radians(p.latitude_setting_deg)
            err = 0.0
            if p.damping == "tilt":
                err += th.damping_error_rad(p.damping_torque_ratio, lat) - th.damping_error_rad(p.damping_torque_ratio,
                                                                                                lat_set)
            if self.motion is not None and p.speed_correction:
                vE, vN = p0.v0 * math.sin(p0.c0), p0.v0 * math.cos(p0.c0)
                err += float(th.speed_error_rad(vE, vN, Om, lat) - th.speed_error_rad(vE, vN, Om, lat_set))
            out["latitude_setting_error_rad"] = -err
        return with_notes(out, self.missing_term_note(FRAME_RATE, "the gyroscope feels no Earth rate: it seeks no north"))

    def corrections_rad(self, reading_raw, latitude, log_speed) -> np.ndarray:
        """The compass's corrections (module docstring) at the samples, rad."""
        p, Om = self.p, self.site.earth_rate_rad_s
        lat = latitude if p.latitude_setting_deg == TRACK else np.full_like(latitude, math.radians(p.latitude_setting_deg))
        corr = np.zeros_like(latitude)
        if p.speed_correction:
            corr = corr + th.speed_correction_rad(reading_raw, log_speed, Om, lat)   # from its own reading
        if p.damping == "tilt":
            corr = corr + np.arcsin(np.clip(p.damping_torque_ratio * np.tan(lat), -1.0, 1.0))
        return corr

    def simulate(self, t, **options) -> Simulation:
        """Integrate the element on the ship (:func:`.dynamics.integrate_pieces`) and read the heading.
        Option ``initial_state``: the 7-component state (:data:`.dynamics.STATE`) at ``t[0]`` instead of
        the switch-on state (a run continued from another, as the type test does)."""
        t = np.asarray(t, dtype=float)
        y0 = options.get("initial_state")
        traj = integrate_pieces(self.coefficients(), self.motion, self.pieces(),
                                self.initial_state() if y0 is None else tuple(y0), t, rtol=options.get("rtol", 1e-9))
        al, tilt, beta, _, _, lat, vf = traj.y
        course = self.motion.track(t)["course"] if self.motion is not None else np.zeros_like(t)
        lag = th.follow_up_lag_rad(self.pieces(), t, 2 * math.pi * self.p.follow_up_bandwidth_hz)
        raw = course - al - lag
        corr = self.corrections_rad(raw, lat, vf)
        heading = np.mod(raw + corr, 2 * math.pi)
        err = np.mod(heading - course + math.pi, 2 * math.pi) - math.pi
        return Simulation(t, {"heading": heading, "heading_error": err, "azimuth": al, "tilt": tilt,
                              "element_roll": beta, "correction": corr, "follow_up_lag": lag}, traj)
