"""Tape torsion: the torsion tape a gyrotheodolite's gyroscope hangs from.

A suspended gyroscope (Wild GAK1, Fennel KT1) hangs on a thin metal tape that keeps its axis
horizontal; twisting the tape by the swing angle gives a restoring torque −D_B (u − Z) toward the
tape's torque-free reading Z (the *tape zero*, on the instrument's scale). With the directing
torque D_K = C ρ0 n cos γ (Quet 1853 sec. 4 §1 eq. 8, times A) the swing is about
c = (D_K N + D_B Z)/(D_K + D_B) near north N (N = c + (D_B/D_K)(c − Z)); exactly, D_K sin(c − N) = D_B (Z − c)
(the two torques, −D_K sin(u − N) and −D_B (u − Z), balance at u = c); with the rotor stopped the
gyroscope swings on the tape alone, a torsion pendulum of angular frequency √(D_B / J). Contributes
to the ``torsion`` mechanics of a swinging hinge.
"""

from gyro_instrument.core.effect import TORSION, Effect
from gyro_instrument.core.params import Param


class TapeTorsion(Effect):
    """The torsion tape: stiffness D_B and zero Z (on the instrument's scale)."""

    name = "tape_torsion"
    summary = "torsion tape of a suspended gyroscope: torque -D_B (u - Z) toward the tape zero Z"
    MECHANICS = frozenset({TORSION})
    PARAMS = (Param("torsion_constant_n_m_rad", default=1.0e-6, low=0.0, open_low=True,
                    doc="D_B, the tape's torsion constant, N m/rad (> 0)"),
              Param("zero_deg", default=0.0, low=-180.0, high=180.0,
                    doc="Z, the tape's torque-free reading on the instrument's scale (the tape zero), degrees"))

    def relative_size(self, ctx) -> tuple:
        return 0.5 * ctx.scales.get("torsion_share", 0.0), "D_B / (2 (D_K + D_B)): the relative change of the swing frequency"

    def torsion_term(self, ctx) -> tuple:
        """(D_B, Z, 0): stiffness (N m/rad), tape zero (rad, scale reading), no drift."""
        return self.p.torsion_constant_n_m_rad, self.p.zero_rad, 0.0
