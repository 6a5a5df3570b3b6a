"""Spin decay from bearing friction.

A viscous bearing torque −C ρ / τ on the rotor's relative spin ρ: the spin decays as e^(−t/τ),
and with it the gyroscopic restoring torque μ n ρ sin ω (Quet sec. 4 §1 eq. 9), so the swing
duration grows as ρ^(−1/2) and, adiabatically, the amplitude as ρ^(−1/4).
"""

from gyro_instrument.core.effect import SPIN, VISCOUS_SPIN, Effect
from gyro_instrument.core.params import Param


class SpinDecay(Effect):
    """Viscous bearing friction on the rotor."""

    name = "spin_decay"
    summary = "rotor spin decay from bearing friction (time constant tau)"
    MECHANICS = frozenset({SPIN})
    TERMS = frozenset({VISCOUS_SPIN})        # −C ρ / τ: τ from spin_decay_time_s
    PARAMS = (Param("time_constant_s", default=3600.0, low=0.0, open_low=True,
                    doc="e-folding time of the rotor's relative spin"),)

    def relative_size(self, ctx) -> tuple:
        return ctx.scales.duration_s / self.p.time_constant_s, "duration / tau (spin lost over the run)"

    def spin_torque_per_inertia(self, spin_rate_rad_s) -> float:
        """Angular deceleration −ρ/τ of the rotor (torque divided by C), rad/s²."""
        return -spin_rate_rad_s / self.p.time_constant_s

    def spin_decay_time_s(self, ctx, inertia) -> float:
        """τ, s: the bearing torque is −C ρ / τ whatever the rotor's moment C."""
        return self.p.time_constant_s

    def spin_torque(self, ctx, inertia, spin_rate) -> float:
        """Bearing torque −C ρ / τ (N m) on a rotor of axial moment C = ``inertia`` spinning at ρ =
        ``spin_rate`` relative to its carrier (C times :meth:`spin_torque_per_inertia`)."""
        return -inertia * spin_rate / self.p.time_constant_s
