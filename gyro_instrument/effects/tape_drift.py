"""Tape-zero drift: the torque-free reading of a torsion tape creeping with time.

A suspension tape relaxes and follows temperature, so its zero Z moves during an observation:
Z(t) = Z0 + Ż t (linear over an observation of an hour; the observers of Williams & Belling 1967,
Tijdschrift voor Kadaster en Landmeetkunde p. 275, read the tape's torque-free position before and
after the rotor-on swing for this reason). The swing centre follows it scaled by D_B/(D_K + D_B),
so the centre drifts. Contributes to the ``torsion`` mechanics: stiffness 0, zero 0, rate Ż; it
acts only with ``tape_torsion`` (which gives the stiffness).
"""

import math

from gyro_instrument.core.effect import TORSION, Effect
from gyro_instrument.core.params import Param

_ARCSEC = math.pi / 648000.0


class TapeDrift(Effect):
    """A linear drift Ż of the tape zero."""

    name = "tape_drift"
    summary = "linear drift of the torsion tape's zero (arcsec per hour)"
    MECHANICS = frozenset({TORSION})
    PARAMS = (Param("rate_arcsec_h", default=10.0, low=-3600.0, high=3600.0,
                    doc="Ż, the drift of the tape zero, arcseconds per hour"),)

    def zero_rate_rad_s(self) -> float:
        """Ż in rad/s."""
        return self.p.rate_arcsec_h * _ARCSEC / 3600.0

    def relative_size(self, ctx) -> tuple:
        s = ctx.scales
        if not (s.duration_s and s.amplitude_rad):
            return 0.0, "no run or no swing"
        return (s.get("torsion_share", 0.0) * abs(self.zero_rate_rad_s()) * s.duration_s / (2.0 * s.amplitude_rad),
                "D_B/(D_K + D_B) · Ż · duration / (2 amplitude): the centre's move against the swing's range")

    def torsion_term(self, ctx) -> tuple:
        """(0, 0, Ż): no stiffness of its own, the zero's rate (rad/s)."""
        return 0.0, 0.0, self.zero_rate_rad_s()
