"""Pivot damping: viscous friction at a hinge.

A torque −2 J q̇ / τ on a hinge of swinging inertia J makes small oscillations decay as
e^(−t/τ) in amplitude. Applied to the swinging hinges of gyroscopes and compound pendulums.
"""

from gyro_instrument.core.effect import DAMPING, VISCOUS_DAMPING, Effect
from gyro_instrument.core.params import Param


class PivotDamping(Effect):
    """Viscous damping at the swinging hinges."""

    name = "pivot_damping"
    summary = "viscous friction at the swinging hinges (amplitude time constant tau)"
    MECHANICS = frozenset({DAMPING})
    TERMS = frozenset({VISCOUS_DAMPING})     # −(2/τ) J q̇: 2/τ from viscous_damping_rate_per_s
    PARAMS = (Param("time_constant_s", default=3600.0, low=0.0, open_low=True,
                    doc="e-folding time of the oscillation amplitude"),)

    def relative_size(self, ctx) -> tuple:
        return ctx.scales.duration_s / self.p.time_constant_s, "duration / tau (amplitude lost over the run)"

    def rate(self) -> float:
        """Damping rate 2/τ (per second) multiplying J q̇ in the hinge torque."""
        return 2.0 / self.p.time_constant_s

    def viscous_damping_rate_per_s(self, ctx, inertia) -> float:
        """d = 2/τ (1/s) of the torque −d J q̇, whatever the hinge's inertia J."""
        return self.rate()

    def damping_torque(self, ctx, inertia, rate) -> float:
        """−(2/τ) J q̇ (N m) on a hinge of swinging inertia J = ``inertia`` turning at q̇ = ``rate``."""
        return -self.rate() * inertia * rate
