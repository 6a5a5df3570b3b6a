"""The rate gyro's measurement kind (issue 35 items 1, 3): ``rate_azimuth``, a registered kind.

:class:`RateAzimuthKind` is a :class:`~gyro_instrument.instruments.measurement.MeasurementKind`
(the shipped entry point ``rate_azimuth`` of ``gyro_instrument.measurements``, setup.py, and in
:data:`~gyro_instrument.instruments.measurement.SHIPPED`): its engine is
:func:`.north.rate_gyro.north_entry` (the ``north`` block by GLS), its planner probe and Fisher
information :mod:`.north.rate_gyro_plan` (``plan --target azimuth_*``: time per position, number of
positions), its live tracker :class:`RateNorthLive`. The estimator, the planner, the estimator node,
the recorder and ``replay`` reach it through the kind only, as any other kind.

:class:`RateNorthLive` is its live tracker (:class:`~gyro_instrument.instruments.measurement.LiveTracker`):
the estimator node gives it the record so far once per sequence of positions (a carousel: every ten
turns) and publishes the least-squares north of what has arrived on ``<name>/heading``; the final
estimate's block replaces it.
"""

import math
from dataclasses import dataclass

from gyro_instrument.estimators.north import rate_gyro as R
from gyro_instrument.instruments.measurement import LiveTracker, MeasurementKind
from gyro_instrument.instruments.rate_gyro import RATE_AZIMUTH


@dataclass(frozen=True)
class RateGyroModel:
    """The planner's model of one rate gyro: the instrument and the scene's sample rate."""

    name: str
    kind: str
    instrument: object
    sample_rate_hz: float
    min_record_s: float


class RateNorthLive(LiveTracker):
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


class RateAzimuthKind(MeasurementKind):
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
        from gyro_instrument.estimators.north.rate_gyro_plan import sigma_mount_rad
        inst = model.instrument
        return (sigma_mount_rad(inst, inst.p, T, model.sample_rate_hz),
                "J = H^T C^-1 H of the schedule's bin means (white ARW + Gauss-Markov bias instability)")

    def tracker(self, obs, scene, companions) -> RateNorthLive:
        return RateNorthLive(obs)

    def combine(self, blocks) -> dict | None:
        from gyro_instrument.estimators.north.estimate import best_block
        return best_block(blocks)

    def plan_entry(self, model) -> dict:
        return {"kind": self.name, "measures": self.summary, "min_record_s": model.min_record_s,
                "mount_azimuth_deg": model.instrument.p.mount_azimuth_deg % 360.0}

    def plan(self, scene_arg, overrides, models, skipped, sensor, name, value, si, floor=True) -> dict:
        from gyro_instrument.estimators.north.rate_gyro_plan import plan_target
        from gyro_instrument.scenes import load_scene
        scene = load_scene(scene_arg, list(overrides))
        return plan_target(scene, {m.name: m.instrument for m in models}, name, value, si, si / value)

    def plan_lines(self, entry) -> list:
        """The plan text of its target (:func:`.north.rate_gyro_plan.plan_lines`)."""
        from gyro_instrument.estimators.north.rate_gyro_plan import plan_lines
        return plan_lines(entry)

    def bench(self, out_dir, quick, write, progress, reference_rows) -> list:
        """North in the same time beside the gyrotheodolite (:func:`.north.rate_gyro_study.bench`)."""
        from gyro_instrument.estimators.north.rate_gyro_study import bench
        return bench(out_dir, quick, write, progress, reference_rows)
