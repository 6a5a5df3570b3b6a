"""The ship's gyrocompass's measurement kind (issue 39 item 6): ``compass``, a registered kind.

:class:`CompassKind` is a :class:`~gyro_instrument.instruments.measurement.MeasurementKind` (the shipped
entry point ``compass`` of ``gyro_instrument.measurements``, setup.py, and in
:data:`~gyro_instrument.instruments.measurement.SHIPPED`). Its engine :func:`compass_block` reads a
compass's heading and the ship's track (course, latitude, speed: the record's, as a ship has them from GNSS
and the log; the observation adds the scene's track when the record has none) and gives the compass's
``compass`` block (:class:`.compass_entries.CompassBlock`): the settle-point error, the settling curve's
period and damping with σ (:mod:`.compass_fit`), and the heading error along the track beside the closed
forms' (:mod:`gyro_instrument.instruments.marine_gyrocompass.theory`). It gives no Earth-rate measurement
(``RATE`` False) and its blocks do not combine (each compass is its own: :meth:`CompassKind.combine` gives
None, no top-level block). Its planner bound is the settle point's σ_n/√N.
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.estimators import compass_fit as F
from gyro_instrument.estimators.adequacy import check_entry
from gyro_instrument.estimators.record import ABSENT
from gyro_instrument.estimators.compass_entries import (CompassBlock, CompassNull, SettlingCurve, SettlingCurveNull,
                                                        TrackError)
from gyro_instrument.instruments.marine_gyrocompass import theory as th
from gyro_instrument.instruments.measurement import MeasurementKind

#: The kind's name (the observation's ``ALSO_MEASURES``).
COMPASS = "compass"
#: Fewest readings the engine reads.
MIN_READINGS = 10
#: The track's source, stated in every block.
TRACK_NOTE = ("the ship's course, latitude and speed are the record's track (a table's ship.course, ship.latitude, "
              "ship.speed; else the scene's motion block, as from GNSS and the log), taken without error")


@dataclass(frozen=True)
class CompassModel:
    """The planner's model of one compass: the instrument, the scene's sample rate, one undamped period."""

    name: str
    kind: str
    instrument: object
    sample_rate_hz: float
    min_record_s: float


class CompassKind(MeasurementKind):
    """A ship's gyrocompass read against the ship's course: its settle point, period, damping, heading error."""

    name = COMPASS
    summary = "ship's gyrocompass: settle-point error, period and damping of the settling curve, heading error"
    RATE = False
    BLOCK = COMPASS
    UNIT = "rad"
    CLASSIC = None
    LIVE = None

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        return compass_block(obs, rec, checks, sensor), None

    def probe(self, scene, obs) -> tuple:
        inst = obs.instrument
        T0 = th.undamped_period_s(inst.control_per_s(), inst.model_earth_rate(), inst.site.latitude_rad)
        if not math.isfinite(T0):
            return None, "no Earth rate (earth_rotation off, or a pole): the compass seeks no north"
        return CompassModel(obs.name, self.name, inst, float(scene.sample_rate_hz), T0), None

    def bound(self, model, T, sensor) -> tuple:
        """σ of the settle point over T s of settled readings at the scene's rate (white noise)."""
        n = max(float(T) * model.sample_rate_hz, 1.0)
        return sensor.effective_sigma_rad() / math.sqrt(n), "sigma_n / sqrt(N) of T s of settled readings"

    def tracker(self, obs, scene, companions) -> None:
        return None

    def combine(self, blocks) -> None:
        """None: each compass's block is its own (no top-level block)."""
        return None


def _deg(x) -> "float | None":
    return None if x is None else math.degrees(x)


def predicted_error_rad(inst, course, lat, speed) -> np.ndarray:
    """The settled heading error the closed forms predict (rad): the compass's corrections
    (:meth:`~gyro_instrument.instruments.marine_gyrocompass.MarineGyrocompass.corrections_rad` at its own
    settings, read at the course) less the equations' settled offset of the north end, the speed error
    atan2(−V_N, R Ω cos φ + V_E) plus the damping error asin((P_d/P_c) tan φ) with damping in tilt."""
    Om = inst.model_earth_rate()
    alpha = th.speed_error_rad(speed * np.sin(course), speed * np.cos(course), Om, lat)
    if inst.p.damping == "tilt":
        alpha = alpha + np.arcsin(np.clip(inst.p.damping_torque_ratio * np.tan(lat), -1.0, 1.0))
    return inst.corrections_rad(course, lat, speed) - alpha


def _settle_sigma(sp, scatter_rad) -> float:
    """σ of the settled mean as an estimate of where the compass settles, rad: σ_n/√N, or the 20-min block
    means' scatter / √B when they wander beyond the noise (:func:`.compass_fit.block_wander`); when the
    settled stretch is under three blocks (no test possible), the settled readings' own scatter
    ``scatter_rad`` (one correlated stretch: no √N reduction)."""
    if sp.wander is None:
        return max(sp.sigma_rad, scatter_rad)
    if sp.wander[2] < F.WANDER_P:
        return max(sp.sigma_rad, sp.wander[3])
    return sp.sigma_rad


def _curve(inst, t, e, lat, sigma) -> "SettlingCurve | SettlingCurveNull":
    """The settling curve's record (:func:`.compass_fit.fit_curve`, the theory beside it)."""
    Om, lat_m = inst.model_earth_rate(), float(np.mean(lat))
    T0 = th.undamped_period_s(inst.control_per_s(), Om, lat_m)
    f = F.fit_curve(t, e, T0, sigma)
    if f.reason is not None:
        return SettlingCurveNull(period_s=None, damping_ratio=None, reason=f.reason)
    v, s = f.values, f.sigmas
    zeta = (th.damping_ratio_tilt(inst.p.damping_torque_ratio, inst.control_per_s(), Om, lat_m)
            if inst.p.damping == "tilt" and math.isfinite(T0) else None)
    return SettlingCurve(model=f.model, period_s=v["period_s"], period_sigma_s=s["period_s"],
                         undamped_period_s=v["undamped_period_s"], undamped_period_sigma_s=s["undamped_period_s"],
                         damping_ratio=v["damping_ratio"], damping_ratio_sigma=s["damping_ratio"],
                         log_decrement=v["log_decrement"], log_decrement_sigma=s["log_decrement"],
                         swing_ratio=v["swing_ratio"], swing_ratio_sigma=s["swing_ratio"],
                         settle_point_error_deg=math.degrees(v["settle_point_rad"]),
                         settle_point_error_sigma_deg=math.degrees(s["settle_point_rad"]),
                         amplitude_deg=math.degrees(v["amplitude_rad"]),
                         amplitude_sigma_deg=math.degrees(s["amplitude_rad"]),
                         residual_rms_deg=math.degrees(f.residual_rms_rad), sigma_basis=f.sigma_basis,
                         samples=f.samples, theory_undamped_period_s=T0 if math.isfinite(T0) else None,
                         theory_damping_ratio=zeta)


def compass_block(obs, rec, checks, sensor) -> "CompassBlock | CompassNull":
    """The ``compass`` block of one compass's record (module docstring); appends its checks."""
    inst, name = obs.instrument, obs.name
    t = np.asarray(rec["t"], dtype=float)
    cols = [np.asarray(rec[k], dtype=float) for k in ("heading", "course", "latitude", "speed")]
    ok = np.isfinite(t) & np.logical_and.reduce([np.isfinite(c) for c in cols])
    if int(ok.sum()) < MIN_READINGS:
        return CompassNull(settle_point_error_deg=None, reason=f"{int(ok.sum())} readings with a course: at least "
                                                                 f"{MIN_READINGS} are needed")
    if not inst.model_earth_rate():
        return CompassNull(settle_point_error_deg=None,
                           reason="earth_rotation is not simulated for it: the compass seeks no north")
    t, (heading, course, lat, speed) = t[ok], [c[ok] for c in cols]
    t = t - t[0]
    e = F.wrap_rad(heading - course)
    sigma = sensor.effective_sigma_rad()
    sp = F.settle_point(t, e, sigma)
    curve = _curve(inst, t, e, lat, sigma)
    track = None
    if sp.settled_at_s is not None:
        m = t >= sp.settled_at_s
        pred = float(np.mean(predicted_error_rad(inst, course[m], lat[m], speed[m])))
        track = TrackError(rms_deg=math.degrees(math.sqrt(float(np.mean(e[m] ** 2)))),
                           max_abs_deg=math.degrees(float(np.max(np.abs(e[m])))), predicted_mean_deg=math.degrees(pred),
                           measured_minus_predicted_deg=math.degrees(sp.mean_rad - pred),
                           measured_minus_predicted_sigma_deg=math.degrees(_settle_sigma(sp, float(np.std(e[m])))))
        checks.append(check_entry(name, "settling", "passed", f"settled at {sp.settled_at_s:.0f} s (ISO 22090-1 "
                                                               "§3.10)", value=sp.settled_at_s))
    else:
        checks.append(check_entry(name, "settling", "flagged", sp.reason))
    if sp.settled_at_s is not None and sp.wander is None:
        checks.append(check_entry(name, "stationary", "flagged", "settled readings span under three 20-min blocks: "
                                  "not tested; measured - predicted takes their scatter as its sigma"))
    if sp.wander is not None:
        blocks, stat, p, _ = sp.wander
        checks.append(check_entry(
            name, "stationary", "passed" if p >= F.WANDER_P else "flagged",
            f"settled readings' {blocks} block means of {F.iso.SP_INTERVAL_S / 60:g} min against the noise: chi2 "
            f"{stat:.3g} on {blocks - 1} degrees of freedom, p = {p:.2g}"
            + ("" if p >= F.WANDER_P else " (the compass still wanders: measured - predicted takes its sigma from "
                                          "the block means)"), value=stat, expected=float(blocks - 1)))
    if isinstance(curve, SettlingCurve):
        status = "passed" if curve.sigma_basis == "sensor noise" else "flagged"
        checks.append(check_entry(name, "fit", status, f"settling curve ({curve.model}): residual rms "
                                                       f"{curve.residual_rms_deg:.3g} deg against the sensor's "
                                                       f"{math.degrees(sigma):.3g} deg", value=curve.residual_rms_deg,
                                  expected=math.degrees(sigma)))
    return CompassBlock(settled_at_s=sp.settled_at_s, settle_point_error_deg=_deg(sp.mean_rad),
                        settle_point_error_sigma_deg=_deg(sp.sigma_rad), settle_point_samples=sp.samples,
                        iso_settle_point_error_deg=_deg(sp.iso_mean_rad), iso_settle_point_rms_deg=_deg(sp.iso_rms_rad),
                        reading_noise_deg=math.degrees(sp.noise_rad),
                        reason=ABSENT if sp.reason is None else sp.reason, settling_curve=curve,
                        track=ABSENT if track is None else track, notes=[TRACK_NOTE])
