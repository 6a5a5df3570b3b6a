"""The runs of the marine gyrocompass's type test (``gyro-instrument typetest``, :mod:`.typetest`): each
test method of ISO 22090-1 §6.2–6.9 on one emulated compass at one latitude, as figures.

Every run is the compass's own equations (:mod:`gyro_instrument.instruments.marine_gyrocompass`) on a
pier or a ship built for the test (a ``motion:`` block, :mod:`gyro_instrument.core.motion`); a run that
follows another starts from its final state (``simulate(..., initial_state=...)``). Readings are the
compass's heading (corrections and follow-up included) every :data:`STEP_S`, noise-free (the emulator
is deterministic: what it reads is its error).

Definitions (ISO 22090-1, nippon.zaidan.info/seikabutsu/2000/00393/contents/003.htm): settled (§3.10) =
three readings taken 30 min apart within a 0.7° band, the settling time being switch-on to the third of
the first such three (any three: the readings slide on the 1-min grid); settle point heading (§3.11) =
the mean of ten readings at 20-min intervals after settling; settle point error (§3.12) = it less the
true heading; error (§3.13) = a reading less the settle point heading.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.core.motion import KNOT_M_S, parse_motion
from gyro_instrument.core.site import Site
from gyro_instrument.instruments.marine_gyrocompass.iso import (  # noqa: F401  (the definitions, re-exported)
    SETTLE_BAND_DEG, SETTLE_INTERVAL_S, SP_INTERVAL_S, SP_READINGS, STEP_S, settle_point, settle_time_s)

#: A pier run-up lasts this long at most (a settle later than the 6-h limit is still timed, to report it).
MAX_RUN_UP_S = 12 * 3600.0
#: §5.2, §5.3.1: settled within 6 h.
SETTLE_LIMIT_S = 6 * 3600.0
#: §6.5's Scorsby motions (roll 5° at 15 s, pitch 5° at 6 s) and §5.3.1's largest horizontal acceleration,
#: 0.22 m/s², which sets the compass's height above the table's axes (h A ω² of the 6-s pitch).
SCORSBY_SETTLE = {"roll_amplitude_deg": 5.0, "roll_period_s": 15.0, "pitch_amplitude_deg": 5.0, "pitch_period_s": 6.0}
SCORSBY_ACCEL_M_S2 = 0.22
#: §6.6: roll 20° at 6 s, pitch 10° at 10 s (yaw 5° at 15 s: not run, see the docs) for 25 min.
SCORSBY_TEST = {"roll_amplitude_deg": 20.0, "roll_period_s": 6.0, "pitch_amplitude_deg": 10.0, "pitch_period_s": 10.0}
SCORSBY_TEST_S = 25 * 60.0
#: §5.3.3: 20 kn, horizontal acceleration at most 2.0 m/s², turns up to 20°/s.
SPEED_KN, MAX_ACCEL_M_S2, MAX_TURN_DEG_S = 20.0, 2.0, 20.0
#: When the ship's speed changes (s from the start of a sea run) and how long a transient is watched.
CHANGE_AT_S, WATCH_S = 600.0, 2 * 3600.0
#: §5.3.4: the follow-up's rates of turn, deg/s.
FOLLOW_UP_RATES_DEG_S = (10.0, 20.0)


@dataclass
class Run:
    """A run's readings: times (s), heading error (deg, unwrapped), azimuth and tilt (deg), the final state."""

    t: np.ndarray
    error_deg: np.ndarray
    azimuth_deg: np.ndarray
    tilt_deg: np.ndarray
    final: tuple
    extra: dict = field(default_factory=dict)


def compass_at(scene, name, lat_deg, motion=None, duration_s=0.0) -> "Instrument":
    """The scene's instrument ``name`` at latitude ``lat_deg`` on a pier (``motion`` None) or on the ship of
    the ``motion:`` mapping ``motion`` (checked over ``duration_s``); the site's Earth rate and gravity
    (the scene's, or WGS-84 normal gravity at the latitude when the scene gives none) are kept."""
    from gyro_instrument.instruments import REGISTRY
    itype, params, effect_names = scene.instruments[name]
    gravity = (scene.raw.get("site") or {}).get("gravity_m_s2")
    site = Site(math.radians(lat_deg), scene.site.earth_rate_rad_s, gravity, True)
    gc = REGISTRY[itype](name, site, params, {e: scene.effects[e] for e in effect_names})
    gc.motion = None if motion is None else parse_motion(motion, site.latitude_rad, duration_s)
    return gc


def simulate(gc, t, state=None) -> Run:
    """``gc`` read at ``t`` (from ``state`` at ``t[0]``, else switched on), as a :class:`Run`."""
    if state is not None:
        state = tuple(state[:5]) + (gc.pieces()[0].lat0, float(state[6]))
    sim = gc.simulate(np.asarray(t, float), initial_state=state)
    c = sim.columns
    return Run(sim.t, np.degrees(np.unwrap(c["heading_error"])), np.degrees(c["azimuth"]), np.degrees(c["tilt"]),
               tuple(float(v) for v in sim.trajectory.y[:, -1]),
               {"follow_up_deg": np.degrees(c["follow_up_lag"])})


def grid(t0, t1, step=STEP_S) -> np.ndarray:
    """Times from ``t0`` to ``t1`` (included) every ``step`` s."""
    return t0 + step * np.arange(int(round((t1 - t0) / step)) + 1)


def run_up(scene, name, lat_deg, azimuth_deg=None) -> dict:
    """A pier run-up (§6.2, §6.3): switched on (at ``azimuth_deg`` instead of the compass's own initial
    azimuth when given), read every minute for :data:`MAX_RUN_UP_S` plus the ten settle readings.
    Returns {run, settle_s (None: not settled within the run), settle_point (mean, rms) or None}."""
    gc = compass_at(scene, name, lat_deg)
    state = None
    if azimuth_deg is not None:
        state = (math.radians(azimuth_deg),) + tuple(gc.initial_state()[1:])
    run = simulate(gc, grid(0.0, MAX_RUN_UP_S + SP_READINGS * SP_INTERVAL_S), state)
    ts = settle_time_s(run.t, run.error_deg)
    return {"run": run, "settle_s": ts, "settle_point": None if ts is None else settle_point(run.t, run.error_deg, ts)}


def scorsby_height_m() -> float:
    """The compass's height above the Scorsby table's axes that gives §6.5's 6-s, 5° pitch the largest
    horizontal acceleration §5.3.1 allows, 0.22 m/s² (h A ω²): 2.30 m."""
    w = 2 * math.pi / SCORSBY_SETTLE["pitch_period_s"]
    return SCORSBY_ACCEL_M_S2 / (math.radians(SCORSBY_SETTLE["pitch_amplitude_deg"]) * w * w)


def scorsby_settling(scene, name, lat_deg) -> "float | None":
    """§6.5: switched on while the table rolls and pitches (:data:`SCORSBY_SETTLE`), read every minute in
    motion, integrated an hour at a time until settled or 6 h: the settling time, s (None: not within 6 h)."""
    motion = dict(SCORSBY_SETTLE, compass_height_m=scorsby_height_m())
    gc = compass_at(scene, name, lat_deg, motion, SETTLE_LIMIT_S)
    ts, es, state, t0 = [], [], None, 0.0
    while t0 < SETTLE_LIMIT_S:
        t = grid(t0, min(t0 + 3600.0, SETTLE_LIMIT_S))
        run = simulate(gc, t, state)
        keep = slice(1, None) if ts else slice(None)
        ts.append(run.t[keep])
        es.append(run.error_deg[keep])
        state, t0 = run.final, float(t[-1])
        found = settle_time_s(np.concatenate(ts), np.concatenate(es))
        if found is not None:
            return found
    return None


def dynamic_error(scene, name, lat_deg, settled) -> float:
    """§6.6: from the settled state on a pier, the table rolls and pitches (:data:`SCORSBY_TEST`, roll axis
    north–south: heading 0) for 25 min: the largest |error| (§3.13: the reading less the settle point
    heading, here the settled reading at the start), deg, read every 0.5 s."""
    motion = dict(SCORSBY_TEST, compass_height_m=scorsby_height_m(), max_acceleration_m_s2=MAX_ACCEL_M_S2)
    gc = compass_at(scene, name, lat_deg, motion, SCORSBY_TEST_S)
    run = simulate(gc, grid(0.0, SCORSBY_TEST_S, 0.5), settled)
    return float(np.max(np.abs(run.error_deg - run.error_deg[0])))


def toward_equator_deg(lat_deg) -> float:
    """The course that keeps a sea run inside the track's ±89° (south in the north, north elsewhere)."""
    return 180.0 if lat_deg > 0 else 0.0


def sea_run(scene, name, lat_deg, settled, speed_kn, turn_rate_deg_s) -> dict:
    """§6.9 and §5.3.3 on a ship, from the pier-settled state: at :data:`CHANGE_AT_S` the speed goes from
    0 to ``speed_kn`` at 2.0 m/s² on a north–south course (the speed change that moves the settle point
    most); after 6 h ten readings 20 min apart give the steady error; then a 180° turn at ``turn_rate_deg_s``
    is watched for 2 h. Returns {speed_change (max |error − error before|, deg, over the 6 h), steady (mean
    error of the ten readings, deg), course_change (max |error − error before the turn|, deg), run}."""
    turn_at = 6 * 3600.0 + (SP_READINGS + 1) * SP_INTERVAL_S
    course = toward_equator_deg(lat_deg)
    motion = {"speed_kn": 0.0, "course_deg": course, "max_acceleration_m_s2": MAX_ACCEL_M_S2,
              "max_turn_rate_deg_s": MAX_TURN_DEG_S,
              "schedule": [{"at_s": CHANGE_AT_S, "speed_kn": speed_kn, "acceleration_m_s2": MAX_ACCEL_M_S2},
                           {"at_s": turn_at, "turn_deg": 180.0, "turn_rate_deg_s": turn_rate_deg_s}]}
    end = turn_at + WATCH_S
    gc = compass_at(scene, name, lat_deg, motion, end)
    t = np.union1d(grid(0.0, end), grid(turn_at, turn_at + 600.0, 0.1))
    run = simulate(gc, t, settled)
    e = run.error_deg
    before = e[np.searchsorted(t, CHANGE_AT_S) - 1]
    sp = settle_point(t[t <= turn_at], e[t <= turn_at], 6 * 3600.0)
    i_turn = np.searchsorted(t, turn_at)
    change = (t >= CHANGE_AT_S) & (t < 6 * 3600.0)
    return {"speed_change": float(np.max(np.abs(e[change] - before))), "steady": sp[0],
            "course_change": float(np.max(np.abs(e[i_turn:] - e[i_turn - 1]))), "run": run}


def turn_speed_kn(rate_deg_s) -> float:
    """The speed at which a turn at ``rate_deg_s`` reaches §5.3.3's 2.0 m/s² (V r), at most 20 kn."""
    return min(SPEED_KN, MAX_ACCEL_M_S2 / math.radians(rate_deg_s) / KNOT_M_S)


def turn_rate_deg_s(speed_kn) -> float:
    """The rate of turn at which ``speed_kn`` reaches 2.0 m/s² (V r), at most 20°/s."""
    return min(MAX_TURN_DEG_S, math.degrees(MAX_ACCEL_M_S2 / (speed_kn * KNOT_M_S)))


def follow_up(scene, name, lat_deg, settled) -> dict:
    """§5.3.4: from the settled state on a pier (no speed: the element feels no turn), full turns at
    10°/s and 20°/s: rate -> the largest |output − the sensed heading| (§3.9: the delay between the value
    sensed, the element's heading on the ship with the corrections, and the output), deg, read every 0.02 s:
    the follow-up's lag (:func:`~gyro_instrument.instruments.marine_gyrocompass.theory.follow_up_lag_rad`;
    for a first-order follow-up it grows with the rate, so the largest over 'up to 10°/s' is at 10°/s).
    An element that has not settled still drifts; measured against what it senses, its drift is not
    counted as follow-up error."""
    out = {}
    for rate in FOLLOW_UP_RATES_DEG_S:
        span = 360.0 / rate
        motion = {"speed_kn": 0.0, "max_turn_rate_deg_s": MAX_TURN_DEG_S,
                  "schedule": [{"at_s": 1.0, "turn_deg": 360.0, "turn_rate_deg_s": rate}]}
        gc = compass_at(scene, name, lat_deg, motion, span + 10.0)
        run = simulate(gc, grid(0.0, span + 10.0, 0.02), settled)
        out[rate] = float(np.max(np.abs(run.extra["follow_up_deg"])))     # the output less the sensed heading
    return out
