"""A minimal streaming instrument for the ROS streaming tests (tests/test_ros_streaming.py,
tests/test_interrupted.py), importable by a child process too.

``AnalyticCompass``: a horizontal gyrocompass at small amplitude with constant spin (Quet 1853 sec. 4
§1 eq. 2 linearised, the plane ``oz`` vertical): ü = −K u with K = μ n cos γ ρ0, so
u(t) = u0 cos(√K t) exactly at any t. It streams (``STREAMS`` True): each block is the closed form at
the block's times, so a block costs nothing and the state carried across blocks is t itself. Two
test knobs: ``block_cost_s`` (wall time spent per block, as a slow integrator would) and the class
list ``EVENTS``, where ``stream`` appends ``("integrate", i, n_blocks_so_far)`` before it computes
block i and calls ``ON_BLOCK`` (a test's probe) first.
"""

import math
import time

import numpy as np

from gyro_instrument import instruments
from gyro_instrument.core.effect import FRAME_RATE, Scales
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import Column, DirectingModel, Instrument, Simulation


class AnalyticCompass(Instrument):
    """Horizontal gyrocompass, small amplitude, constant spin: u = u0 cos(√K t) (Quet sec. 4 §1 eq. 2)."""

    type_name = "analytic_compass"
    summary = "closed-form small-amplitude horizontal gyrocompass that streams (test instrument)"
    PARAMS = (Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True, doc="mu = C/A"),
              Param("spin_rate_rad_s", default=2 * math.pi * 100.0, low=0.0, open_low=True, doc="rho0, rad/s"),
              Param("initial_angle_deg", default=1.0, low=-10.0, high=10.0, doc="u0, degrees"),
              Param("block_cost_s", default=0.0, low=0.0, high=60.0, doc="wall time spent per block (test knob)"))
    MECHANICS = frozenset({FRAME_RATE})
    COLUMNS = (Column("angle", "rad", "u: axis angle from north"),
               Column("angle_rate", "rad/s", "du/dt"),
               Column("spin_rate", "rad/s", "rho: the rotor's constant spin"))
    MEASURED_CHANNELS = ("angle",)
    JOINTS = ("axis", "rotor")
    SIMULATOR_NODE = "gyrocompass_sim"
    STREAMS = True
    EVENTS = []
    ON_BLOCK = None

    def _omega(self):
        K = self.p.inertia_ratio * self.model_earth_rate() * math.cos(self.site.latitude_rad) * self.p.spin_rate_rad_s
        return math.sqrt(max(K, 0.0))

    def scales(self, duration_s):
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, restoring_rate_rad_s=self._omega(),
                      amplitude_rad=math.radians(abs(self.p.initial_angle_deg)), duration_s=duration_s)

    def predictions(self):
        w = self._omega()
        return {"swing_duration_small_s": math.pi / w if w > 0 else math.inf}

    def directing_model(self):
        return DirectingModel(gain=self.p.inertia_ratio, normal_enu=(0.0, 0.0, 1.0), label="horizontal",
                              angle_channel="angle", null_reason="no restoring torque at a pole")

    def simulate(self, t, **options):
        t = np.asarray(t, dtype=float)
        w, u0 = self._omega(), math.radians(self.p.initial_angle_deg)
        return Simulation(t, {"angle": u0 * np.cos(w * t), "angle_rate": -u0 * w * np.sin(w * t),
                              "spin_rate": np.full(t.size, self.p.spin_rate_rad_s)}, None)

    def stream(self, blocks, **options):
        for i, b in enumerate(blocks):
            if AnalyticCompass.ON_BLOCK is not None:
                AnalyticCompass.ON_BLOCK(i)
            AnalyticCompass.EVENTS.append(("integrate", i))
            if self.p.block_cost_s:
                time.sleep(self.p.block_cost_s)
            yield self.simulate(b, **options)


def register():
    """Register :class:`AnalyticCompass` (idempotent); returns the class."""
    if AnalyticCompass.type_name not in instruments.REGISTRY:
        instruments.register(AnalyticCompass)
    return AnalyticCompass


def scene(duration_s=60.0, block_cost_s=0.0, rate_hz=20.0):
    """A scene dict with one analytic compass at Paris (the Panthéon's latitude)."""
    return {"name": "streaming", "description": "one closed-form gyrocompass that streams",
            "site": {"latitude_deg": 48.8462}, "duration_s": float(duration_s), "sample_rate_hz": float(rate_hz),
            "seed": 3, "effects": {"earth_rotation": {}}, "sensor": {"noise_rad": 1.0e-5},
            "instruments": {"compass": {"type": "analytic_compass", "block_cost_s": float(block_cost_s)}}}
