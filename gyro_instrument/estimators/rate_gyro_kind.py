"""The rate gyro's measurement kind in one place, ready for the kinds mechanism (issue 35 items 1, 3).

:class:`RateAzimuthKind` has the members a measurement kind declares on the ``kinds`` branch
(``instruments/measurement.py``: ``MeasurementKind`` — name, summary, RATE, BLOCK, UNIT, CLASSIC,
LIVE, TARGET, estimate, probe, bound, tracker, combine, plan), each delegating to this package's
rate-gyro modules. Today nothing imports it: the estimator, the planner and the estimator node reach
those modules through the marked ``KINDS-REWIRE`` touch points. When the kinds land, re-wiring is
``class RateAzimuthKind(RateAzimuthKind, MeasurementKind)`` (or the base swapped here) and an entry
point ``rate_azimuth = gyro_instrument.estimators.rate_gyro_kind:RateAzimuthKind`` in the group
``gyro_instrument.measurements``; then the touch points go.

:class:`RateNorthLive` is its live tracker (the kinds branch's ``LiveTracker`` protocol, duck-typed):
the estimator node gives it the record so far once per sequence of positions (a carousel: every ten
turns) and it publishes the least-squares north of what has arrived; the final estimate's block
replaces it.
"""

import math
from dataclasses import dataclass

from gyro_instrument.estimators import rate_gyro_north as R
from gyro_instrument.instruments.rate_gyro import RATE_AZIMUTH


@dataclass(frozen=True)
class RateGyroModel:
    """The planner's model of one rate gyro: the instrument and the scene's sample rate."""

    name: str
    kind: str
    instrument: object
    sample_rate_hz: float
    min_record_s: float


class RateNorthLive:
    """Live north of a rate gyro from the record so far (module docstring)."""

    def __init__(self, obs) -> None:
        self.obs = obs
        self.reads = (obs.name,)
        p = obs.instrument.p
        self.every_s = (10 * 360.0 / abs(p.carousel_rate_deg_s) if p.carousel_rate_deg_s
                        else p.positions * (p.dwell_s + p.slew_s))

    def every_s_of(self, name) -> float:
        return self.every_s

    def window_s_of(self, name) -> float:
        """The whole record (the fit is over every held sample; at most a few thousand bins)."""
        return math.inf

    def update(self, name, rec) -> tuple | None:
        """(mount azimuth rad, σ rad) of the record so far, or None (too few headings, or two positions
        whose mirror image the prior does not exclude)."""
        try:
            f = R.fit_record(self.obs, rec)
        except (ValueError, ArithmeticError):
            return None
        if "reason" in f or not f.get("resolved", True):
            return None
        return f["mount_rad"] % (2.0 * math.pi), f["sigma_rad"]

    def final(self, entry) -> tuple:
        block = (entry or {}).get("north") or {}
        deg, sig = block.get("mount_azimuth_deg"), block.get("sigma_arcsec")
        return (None if deg is None else math.radians(deg),
                None if sig is None or deg is None else math.radians(sig / 3600.0))

    def restarted(self) -> "RateNorthLive":
        return RateNorthLive(self.obs)


class RateAzimuthKind:
    """The azimuth of a turntable's reference from a rate gyro's readings at several headings."""

    name = RATE_AZIMUTH
    summary = "azimuth of a rate gyro turntable's reference from the Earth rate read at several headings"
    RATE = False
    BLOCK = "north"
    UNIT = "rad"
    CLASSIC = None
    LIVE = "heading"
    TARGET = "azimuth"

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        return R.north_entry(obs, rec, corrections, checks, sensor)

    def probe(self, scene, obs) -> tuple:
        inst = obs.instrument
        if not inst.horizontal_rate_rad_s():
            return None, "no Earth rate about a horizontal axis (earth_rotation off, or a pole)"
        p = inst.p
        first = 360.0 / abs(p.carousel_rate_deg_s) if p.carousel_rate_deg_s else p.positions * (p.dwell_s + p.slew_s)
        return RateGyroModel(obs.name, self.name, inst, float(scene.sample_rate_hz), first), None

    def bound(self, model, T, sensor) -> tuple:
        from gyro_instrument.estimators.rate_gyro_plan import sigma_mount_rad
        inst = model.instrument
        return (sigma_mount_rad(inst, inst.p, T, model.sample_rate_hz),
                "J = H^T C^-1 H of the schedule's bin means (white ARW + Gauss-Markov bias instability)")

    def tracker(self, obs, scene, companions) -> RateNorthLive:
        return RateNorthLive(obs)

    def combine(self, blocks) -> dict | None:
        from gyro_instrument.estimators.north_estimate import best_block
        return best_block(blocks)

    def plan_entry(self, model) -> dict:
        return {"kind": self.name, "measures": self.summary, "min_record_s": model.min_record_s,
                "mount_azimuth_deg": model.instrument.p.mount_azimuth_deg % 360.0}

    def plan(self, scene_arg, overrides, models, skipped, sensor, name, value, si, floor=True) -> dict:
        from gyro_instrument.estimators.rate_gyro_plan import plan_target
        from gyro_instrument.scenes import load_scene
        scene = load_scene(scene_arg, list(overrides))
        return plan_target(scene, {m.name: m.instrument for m in models}, name, value, si, si / value)
