"""Air drag on a pendulum bob: linear (Stokes) and quadratic (Newton) terms.

Quet mentions the pendulum in air as a separate memoir (end of sec. 4); here the drag
acceleration is −(2/τ) v − c_q |v| v, so small linear-drag swings decay as e^(−t/τ).
"""

from collections.abc import Callable

import numpy as np

from gyro_instrument.core.effect import POINT_MASS, Effect
from gyro_instrument.core.params import Param


class AirDrag(Effect):
    """Drag on a point bob."""

    name = "air_drag"
    summary = "air drag on the bob: linear (time constant tau) plus quadratic"
    MECHANICS = frozenset({POINT_MASS})
    CAPABILITIES = frozenset()           # dissipative: velocity-dependent work
    PARAMS = (Param("time_constant_s", default=7200.0, low=0.0, open_low=True,
                    doc="e-folding time of the amplitude under linear drag"),
              Param("quadratic_per_m", default=0.0, low=0.0,
                    doc="quadratic drag coefficient c_q (acceleration = c_q |v|^2), 1/m"))

    def relative_size(self, ctx) -> tuple:
        return ctx.scales.duration_s / self.p.time_constant_s, "duration / tau (amplitude lost over the run)"

    def acceleration(self, v) -> np.ndarray:
        """Drag acceleration −(2/τ) v − c_q |v| v (m/s²) for a velocity ``v`` (3,) relative to the air."""
        return -(2.0 / self.p.time_constant_s) * v - self.p.quadratic_per_m * np.linalg.norm(v) * v

    def point_mass_term(self, ctx) -> Callable:
        """:meth:`acceleration` of the velocity relative to the Earth (still air); one state at a time."""
        acceleration = self.acceleration

        def drag(dx, dy, dz, vx, vy, vz):
            return acceleration(np.array([vx, vy, vz]))
        return drag
