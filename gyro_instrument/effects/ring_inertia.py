"""Gimbal-ring inertia (Quet sec. 4 §III eqs. 8–9).

When listed, the inner ring (A1 about its diameters, C1 about its figure axis) and the outer
ring (A2 about the fixed axis PP', C2 about its figure axis) take part in the motion; when
absent the rings are massless and the rotor alone sets the periods. With the rings locked
perpendicular the swinging inertia is A + C1 + A2, which Quet writes A + 2A1 + A2 for thin
rings (C1 = 2A1) (sec. 4 §IV).
"""

import numpy as np

from gyro_instrument.core.effect import CARRIER_INERTIA, CONSERVATIVE, Effect


class RingInertia(Effect):
    """Include the inertia of the gimbal rings."""

    name = "ring_inertia"
    summary = "inertia of the gimbal rings (A1, C1, A2)"
    MECHANICS = frozenset({CARRIER_INERTIA})
    CAPABILITIES = frozenset({CONSERVATIVE})   # inertia: no work

    def relative_size(self, ctx) -> tuple:
        r = ctx.scales.get("ring_inertia_ratio", 0.0)       # the gimbal's scale: (C1 + A2)/A
        return r / 2.0, "(C1 + A2) / (2 A): relative change of the locked-ring period"

    def carrier_inertia(self, ctx, inertia) -> float | np.ndarray:
        """The ring's own moment, unchanged: the ring takes part in the motion (absent: massless)."""
        return inertia
