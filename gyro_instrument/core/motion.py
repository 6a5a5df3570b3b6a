"""A ship to carry an instrument: the scene's ``motion:`` block (issue 39 item 2).

Without a ``motion:`` block every instrument is on a fixed pier. With one, the instruments that
declare ``FEELS_MOTION`` (the marine gyrocompass) sail: the block gives the ship's speed and course,
their schedules, and its roll and pitch; the track (latitude along it) is dead reckoning on a sphere
of radius :data:`EARTH_RADIUS_M`. Layout::

    motion:
      speed_kn: 20                 # over ground, knots (1 kn = 1852 m / 3600 s)
      course_deg: 0                # true course, degrees clockwise from north (the ship's heading)
      max_turn_rate_deg_s: 20      # the declared limits every change must keep to
      max_acceleration_m_s2: 2.0
      schedule:                    # changes, in time order, each a ramp at a constant rate
        - {at_s: 3600, speed_kn: 0, acceleration_m_s2: 0.5}
        - {at_s: 7200, course_deg: 180, turn_rate_deg_s: 3}    # the short way (180: to starboard)
        - {at_s: 9000, turn_deg: -360, turn_rate_deg_s: 2}     # a signed turn (negative: to port)
      roll_amplitude_deg: 5        # roll and pitch: simple harmonic (the Scorsby table's motion)
      roll_period_s: 10
      pitch_amplitude_deg: 5       # equal to the roll, in phase: the intercardinal variant
      pitch_period_s: 10
      pitch_phase_deg: 0
      compass_height_m: 2          # height of the instrument above the roll and pitch axes

The ship's heading is its course (no leeway, no current). The instrument is gimballed: the ship's
roll and pitch reach it only as the horizontal acceleration of its point of support, h A ω² sin(ωt +
phase) for an amplitude A (rad), period 2π/ω and height h (the terms in h (dA/dt)², of second order in
A, and the vertical acceleration are left out). ISO 22090-1 §5.3.1 (Scorsby): period 6–15 s, up to 5°,
horizontal acceleration up to 0.22 m/s² (nippon.zaidan.info/seikabutsu/2000/00393/contents/005.htm).

Dead reckoning: dφ/dt = V cos C / R in closed form over each piece of the schedule (V and C linear in
time): ∫ (V0 + a s) cos(C0 + r s) ds = (V sin C − V0 sin C0)/r + a (cos C − cos C0)/r², or
cos C0 (V0 τ + a τ²/2) for r = 0. A track that reaches ±:data:`MAX_LATITUDE_DEG` is refused (at
the pole a course is undefined and the transport rate V sin C tan φ / R diverges).

Errors: :class:`~gyro_instrument.core.errors.SceneError` naming ``motion.<field>`` (with the schedule
entry's index), the value and the valid range.
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import Param, validate_params

#: Knot, m/s (1852 m per hour, exact).
KNOT_M_S = 1852.0 / 3600.0
#: Radius of the sphere the track is reckoned on, m: the IUGG mean Earth radius R1 (Moritz 2000,
#: Geodetic Reference System 1980, J. Geodesy 74:128): 6371008.8 m.
EARTH_RADIUS_M = 6371008.8
#: The track must stay within this latitude, degrees.
MAX_LATITUDE_DEG = 89.0
#: The name the ship's columns carry in a simulated table (``ship.course``, ``ship.latitude``...).
SHIP = "ship"

MOTION_PARAMS = (
    Param("speed_kn", default=0.0, low=0.0, high=100.0, doc="speed over ground at the start, knots"),
    Param("course_deg", default=0.0, low=-360.0, high=360.0,
          doc="true course (= heading) at the start, degrees clockwise from north"),
    Param("max_turn_rate_deg_s", default=20.0, low=0.0, high=90.0, open_low=True,
          doc="the declared largest rate of turn, deg/s (ISO 22090-1 §5.3.3: 20 deg/s); a turn beyond it is refused"),
    Param("max_acceleration_m_s2", default=2.0, low=0.0, high=20.0, open_low=True,
          doc="the declared largest horizontal acceleration, m/s^2 (ISO 22090-1 §5.3.3: 2.0); speed changes and "
              "the roll and pitch's acceleration at the instrument beyond it are refused"),
    Param("roll_amplitude_deg", default=0.0, low=0.0, high=45.0, doc="roll amplitude, degrees (Scorsby: up to 5)"),
    Param("roll_period_s", default=10.0, low=0.0, high=120.0, open_low=True, doc="roll period, s (Scorsby: 6-15)"),
    Param("pitch_amplitude_deg", default=0.0, low=0.0, high=45.0, doc="pitch amplitude, degrees"),
    Param("pitch_period_s", default=10.0, low=0.0, high=120.0, open_low=True, doc="pitch period, s"),
    Param("pitch_phase_deg", default=0.0, low=-360.0, high=360.0,
          doc="phase of the pitch after the roll, degrees (equal amplitudes and periods in phase: the intercardinal "
              "variant, a swing about an axis 45 deg off the fore-and-aft line)"),
    Param("compass_height_m", default=0.0, low=0.0, high=100.0,
          doc="height of the instrument's point of support above the roll and pitch axes, m"),
)

#: One entry of ``motion.schedule``.
CHANGE_PARAMS = (
    Param("at_s", low=0.0, doc="when the change starts, s from the start of the run"),
    Param("speed_kn", default=None, low=0.0, high=100.0, doc="the new speed, knots"),
    Param("acceleration_m_s2", default=None, low=0.0, open_low=True,
          doc="|dV/dt| of the speed change, m/s^2 (default: max_acceleration_m_s2)"),
    Param("course_deg", default=None, low=-360.0, high=360.0, doc="the new course, degrees (turning the short way)"),
    Param("turn_deg", default=None, low=-36000.0, high=36000.0,
          doc="a signed turn instead of course_deg, degrees (positive: to starboard, clockwise)"),
    Param("turn_rate_deg_s", default=None, low=0.0, open_low=True,
          doc="|dC/dt| of the turn, deg/s (default: max_turn_rate_deg_s)"),
)


@dataclass(frozen=True)
class Piece:
    """The ship between two breakpoints: speed V = v0 + a (t − t0), course C = c0 + r (t − t0),
    latitude φ0 at t0 (m/s, m/s², rad, rad/s, rad)."""

    t0: float
    t1: float
    v0: float
    a: float
    c0: float
    r: float
    lat0: float


@dataclass(frozen=True)
class Motion:
    """The validated ``motion:`` block: the schedule as pieces with constant rates, the roll and
    pitch. Times in s, angles in rad, speeds in m/s (the ``*_deg`` and ``*_kn`` of the block converted)."""

    pieces: tuple
    roll_amplitude_rad: float
    roll_rate_rad_s: float
    pitch_amplitude_rad: float
    pitch_rate_rad_s: float
    pitch_phase_rad: float
    compass_height_m: float
    raw: dict

    def breakpoints(self) -> tuple:
        """The start of every piece but the first: where the speed's or the course's rate jumps (s)."""
        return tuple(p.t0 for p in self.pieces[1:])

    def piece_at(self, t_s) -> Piece:
        """The piece holding time ``t_s`` (the last piece after the end of the schedule)."""
        for p in self.pieces:
            if t_s < p.t1:
                return p
        return self.pieces[-1]

    def sway_amplitudes_m_s2(self) -> tuple:
        """(forward, starboard) amplitudes of the acceleration the roll and pitch give the instrument, m/s²."""
        h = self.compass_height_m
        return h * self.pitch_amplitude_rad * self.pitch_rate_rad_s ** 2, h * self.roll_amplitude_rad * self.roll_rate_rad_s ** 2

    def track(self, t_s) -> dict:
        """The ship at times ``t_s`` (array, s): ``speed`` (m/s), ``course`` (rad, unwrapped), ``latitude``
        (rad), and the course's and speed's rates (rad/s, m/s²)."""
        t = np.asarray(t_s, dtype=float)
        out = {k: np.empty_like(t) for k in ("speed", "course", "latitude", "turn_rate", "acceleration")}
        for k, p in enumerate(self.pieces):
            last = k == len(self.pieces) - 1
            m = (t >= p.t0) & ((t < p.t1) | last) if k else (t < p.t1) | last
            tau = t[m] - p.t0
            out["speed"][m] = p.v0 + p.a * tau
            out["course"][m] = p.c0 + p.r * tau
            out["latitude"][m] = p.lat0 + _north_distance(p, tau) / EARTH_RADIUS_M
            out["turn_rate"][m] = p.r
            out["acceleration"][m] = p.a
        return out


def _north_distance(p, tau):
    """∫_0^τ V cos C ds over the piece ``p`` (m), closed form (module docstring)."""
    v, c = p.v0 + p.a * tau, p.c0 + p.r * tau
    if p.r == 0.0:
        return math.cos(p.c0) * (p.v0 * tau + 0.5 * p.a * tau * tau)
    return (v * np.sin(c) - p.v0 * math.sin(p.c0)) / p.r + p.a * (np.cos(c) - math.cos(p.c0)) / p.r ** 2


def parse_motion(raw, latitude_rad, duration_s) -> "Motion | None":
    """Validate a scene's ``motion:`` block (None: a fixed pier) into a :class:`Motion`.

    Parameters
    ----------
    raw : dict or None
        The block as read (``--set 'motion={...}'`` replaces it whole; ``motion=null`` removes it).
    latitude_rad : float
        The site's latitude: the ship's at the start, rad.
    duration_s : float
        The run's length: the track is checked over it, s.

    Raises
    ------
    SceneError
        On ``motion.<field>`` (``motion.schedule[i].<field>``): a value out of its range, a change
        beyond the declared turn rate or acceleration, two changes of the speed (or of the course)
        that overlap, a roll or pitch whose acceleration at the instrument exceeds
        ``max_acceleration_m_s2``, a track reaching ±:data:`MAX_LATITUDE_DEG`.
    """
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise SceneError("motion", raw, "must be a mapping (speed_kn, course_deg, schedule, roll_..., pitch_...) "
                                        "or null for a fixed pier")
    raw = dict(raw)
    schedule = raw.pop("schedule", None) or []
    p = validate_params("motion", MOTION_PARAMS, raw)
    if not isinstance(schedule, list):
        raise SceneError("motion.schedule", schedule, "must be a list of changes {at_s: ..., speed_kn | course_deg "
                                                      "| turn_deg: ...}")
    changes = [_change(i, c, p) for i, c in enumerate(schedule)]
    motion = Motion(_pieces(changes, p, latitude_rad), math.radians(p["roll_amplitude_deg"]),
                    2 * math.pi / p["roll_period_s"], math.radians(p["pitch_amplitude_deg"]),
                    2 * math.pi / p["pitch_period_s"], math.radians(p["pitch_phase_deg"]), p["compass_height_m"],
                    dict(p, schedule=schedule))
    for name, acc in zip(("pitch_amplitude_deg", "roll_amplitude_deg"), motion.sway_amplitudes_m_s2()):
        if acc > p["max_acceleration_m_s2"]:
            raise SceneError(f"motion.{name}", p[name], f"gives the instrument {acc:.3g} m/s^2 at compass_height_m = "
                                                        f"{p['compass_height_m']:g} m (h A w^2); must be at most "
                                                        f"max_acceleration_m_s2 = {p['max_acceleration_m_s2']:g}")
    _check_track(motion, duration_s)
    return motion


def _change(i, c, p) -> dict:
    """One schedule entry validated: {at_s, speed (m/s) | None, acceleration, dcourse (rad) | None, rate}."""
    field = f"motion.schedule[{i}]"
    if not isinstance(c, dict):
        raise SceneError(field, c, "must be a mapping {at_s: ..., speed_kn | course_deg | turn_deg: ...}")
    v = validate_params(field, CHANGE_PARAMS, c)
    if v["course_deg"] is not None and v["turn_deg"] is not None:
        raise SceneError(f"{field}.turn_deg", v["turn_deg"], "give course_deg or turn_deg, not both")
    if v["speed_kn"] is None and v["course_deg"] is None and v["turn_deg"] is None:
        raise SceneError(field, c, "changes nothing: give speed_kn, course_deg or turn_deg")
    for key, limit in (("acceleration_m_s2", "max_acceleration_m_s2"), ("turn_rate_deg_s", "max_turn_rate_deg_s")):
        if v[key] is None:
            v[key] = p[limit]
        elif v[key] > p[limit]:
            raise SceneError(f"{field}.{key}", v[key], f"is beyond the declared motion.{limit} = {p[limit]:g}; must "
                                                       f"be in (0, {p[limit]:g}]")
    return v


def _pieces(changes, p, lat0) -> tuple:
    """The schedule as pieces of constant rates (refusing overlapping changes of one quantity)."""
    events = []                                     # (start, end, 'speed' | 'course', rate)
    speed, course = p["speed_kn"] * KNOT_M_S, math.radians(p["course_deg"])
    busy = {"speed": (-1.0, 0.0), "course": (-1.0, 0.0)}
    for i, v in sorted(enumerate(changes), key=lambda iv: iv[1]["at_s"]):
        t = v["at_s"]
        for what, new in (("speed", v["speed_kn"]), ("course", v["course_deg"] if v["turn_deg"] is None else 0)):
            if new is None or (what == "course" and v["course_deg"] is None and v["turn_deg"] is None):
                continue
            if t < busy[what][1]:
                raise SceneError(f"motion.schedule[{i}].at_s", t, f"starts while the previous {what} change (from "
                                                                  f"{busy[what][0]:g} s) runs until {busy[what][1]:g} s;"
                                                                  f" must be >= {busy[what][1]:g}")
            if what == "speed":
                delta, rate = new * KNOT_M_S - speed, v["acceleration_m_s2"]
                speed += delta
            else:
                delta = (math.radians(v["turn_deg"]) if v["turn_deg"] is not None
                         else (math.radians(new) - course) % (2 * math.pi))
                delta = delta - 2 * math.pi if v["turn_deg"] is None and delta > math.pi else delta
                rate = math.radians(v["turn_rate_deg_s"])
                course += delta
            end = t + abs(delta) / rate
            busy[what] = (t, end)
            if delta:
                events.append((t, end, what, math.copysign(rate, delta)))
    return _split(events, p, lat0)


def _split(events, p, lat0) -> tuple:
    """Pieces between every start and end of the events, with the rates in force in each."""
    cuts = sorted({0.0} | {e[0] for e in events} | {e[1] for e in events})
    pieces, v, c, lat = [], p["speed_kn"] * KNOT_M_S, math.radians(p["course_deg"]), lat0
    for k, t0 in enumerate(cuts):
        t1 = cuts[k + 1] if k + 1 < len(cuts) else math.inf
        a = sum(e[3] for e in events if e[2] == "speed" and e[0] <= t0 < e[1])
        r = sum(e[3] for e in events if e[2] == "course" and e[0] <= t0 < e[1])
        piece = Piece(t0, t1, v, a, c, r, lat)
        pieces.append(piece)
        if math.isfinite(t1):
            tau = t1 - t0
            lat += _north_distance(piece, tau) / EARTH_RADIUS_M
            v, c = max(v + a * tau, 0.0), c + r * tau
    return tuple(pieces)


def _check_track(motion, duration_s) -> None:
    """Refuse a track that reaches ±MAX_LATITUDE_DEG within the run (checked every minute and at
    every breakpoint: a rhumb line's latitude is monotonic within a piece without a turn)."""
    t = np.union1d(np.arange(0.0, duration_s, 60.0), [duration_s, *[b for b in motion.breakpoints()
                                                                     if b <= duration_s]])
    lat = np.degrees(motion.track(t)["latitude"])
    bad = np.flatnonzero(np.abs(lat) >= MAX_LATITUDE_DEG)
    if bad.size:
        i = int(bad[0])
        raise SceneError("motion", {k: v for k, v in motion.raw.items() if k in ("speed_kn", "course_deg")},
                         f"takes the ship to latitude {lat[i]:.2f} deg at t = {t[i]:g} s (dead reckoning); the track "
                         f"must stay within +/-{MAX_LATITUDE_DEG:g} deg: shorten duration_s or change the course")


def check_sailing(motion, instruments, registry) -> None:
    """With a ``motion:`` block, refuse an instrument that cannot sail (its class does not declare
    ``FEELS_MOTION``: it would be simulated on a pier while the ship sails) and an instrument named
    ``ship`` (the ship's table columns are ``ship.<column>``). Raises SceneError."""
    if motion is None:
        return
    for name, spec in instruments.items():
        if name == SHIP:
            raise SceneError(f"instruments.{SHIP}", spec[0], "the name 'ship' is taken by the motion block's columns "
                                                             "(ship.course, ship.latitude); rename the instrument")
        if not getattr(registry[spec[0]], "FEELS_MOTION", False):
            sailing = sorted(t for t, c in registry.items() if getattr(c, "FEELS_MOTION", False))
            raise SceneError(f"instruments.{name}.type", spec[0], f"is simulated on a fixed pier and cannot sail with "
                                                                  f"the scene's motion block; instruments that sail: "
                                                                  f"{', '.join(sailing) or 'none'} (remove the block "
                                                                  f"with --set motion=null)")


#: The ship's table columns: name -> (unit, meaning).
SHIP_COLUMNS = {"course": ("rad", "the ship's true course = heading, wrapped to [0, 2 pi)"),
                "latitude": ("rad", "the ship's latitude by dead reckoning on the sphere"),
                "speed": ("m/s", "the ship's speed over ground")}


def ship_columns(motion, t_s) -> dict:
    """``ship.<column>`` -> array at times ``t_s`` (:data:`SHIP_COLUMNS`); {} for a fixed pier."""
    if motion is None:
        return {}
    tr = motion.track(t_s)
    return {f"{SHIP}.course": np.mod(tr["course"], 2 * math.pi), f"{SHIP}.latitude": tr["latitude"],
            f"{SHIP}.speed": tr["speed"]}
