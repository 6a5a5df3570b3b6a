"""The azimuth measurement: a horizontal gyroscope's swing centre is the meridian (issue 24).

Quet 1853 sec. 4 §1 item 1: with its axis in a horizontal plane a spinning body rests only along
the meridian, so the centre of its swing, read on the instrument's scale, is true north and gives
the azimuth of the scale's zero (``mount_azimuth_deg``). :class:`HorizontalSwing` is the
observation of a horizontal plane gyroscope: its swing-rate measurement (:data:`SWING_RATE`, as
:class:`~.observation.SwingRate`) and beside it an :data:`AZIMUTH` measurement
(``ALSO_MEASURES``), which the estimator's engine for that kind turns into the ``north`` block
(``estimators/north_estimate.py``). :class:`TapeSwing` is the same gyroscope with the rotor stopped:
a torsion pendulum on its tape, no Earth-rate measurement, read by the rotor-on gyroscope's north
estimate for the tape zero and the tape's stiffness (``companions``).
"""

import math
from typing import ClassVar

from gyro_instrument.instruments.observation import RateEstimate, RotorObservation, SwingRate

#: Measurement kind: the azimuth of a scale's zero from a swing centre on the meridian.
AZIMUTH = "azimuth"
#: The key under which a rotor-on record carries its rotor-off companion's record.
ROTOR_OFF = "rotor_off"


def _on_scale(obs, out) -> dict:
    """``out`` with the swing angle read on the scale: u + M (``mount_reading_rad``)."""
    m = obs.instrument.mount_reading_rad
    if m:
        out["angle"] = out["angle"] + m
    return out


class TapeSwing(RotorObservation):
    """A suspended gyroscope with its rotor stopped: a torsion pendulum on its tape (no Earth rate),
    read on the same scale (u + M)."""

    def true_values(self, columns) -> dict:
        """The scale reading u + M (rad)."""
        return _on_scale(self, super().true_values(columns))

    def unmeasured_reason(self) -> str:
        return f"{self.name} swings with its rotor off: a torsion pendulum on its tape, read for the tape zero"


class HorizontalSwing(SwingRate):
    """A horizontal plane gyroscope: its swing rate, and its swing centre as an azimuth.

    The rate law is :class:`SwingRate`'s, less the tape's own restoring constant D_B/A when a torsion
    tape hangs it (K = (π/T0)² − D_B/A, D_B the scene's tape constant).
    """

    #: Measurement kinds beside ``MEASUREMENT`` the estimator runs the engines of: an azimuth, always
    #: (issue 24 item 1: every estimate with a horizontal gyroscope reports ``north``; the mount
    #: defaults to 0, the scale's zero on true north).
    ALSO_MEASURES: ClassVar[tuple] = (AZIMUTH,)

    @classmethod
    def of(cls, inst) -> "RotorObservation":
        """A :class:`HorizontalSwing` for a flat horizontal plane with the rotor on; :class:`TapeSwing`
        with the rotor stopped; :meth:`SwingRate.of` otherwise."""
        if getattr(inst, "is_cone", True) or inst.p.plane != "horizontal":
            return SwingRate.of(inst)
        if not inst.p.spin_rate_rad_s:
            return TapeSwing(inst)
        return cls(inst, inst.directing_model())

    def __init__(self, inst, model) -> None:
        super().__init__(inst, model)
        self.mount_reading_rad = inst.mount_reading_rad
        self.tape_constant_per_inertia = inst.tape[0] / inst.p.transverse_inertia_kg_m2
        #: True when the scene asks for north (states ``mount_azimuth_deg`` or hangs the gyroscope on a
        #: tape): an inadequate record is then refused (exit 2); otherwise ``north`` is null with its reason.
        self.north_asked = inst.p.mount_azimuth_deg is not None or self.has_tape()

    def true_values(self, columns) -> dict:
        """The scale reading u + M (rad): Quet's u offset by the mount (``mount_azimuth_deg``)."""
        return _on_scale(self, super().true_values(columns))

    def companions(self) -> dict:
        """{record key: instrument name} of the other records the azimuth engine reads: the rotor-off
        swing (``rotor_off_instrument``), when one is named."""
        name = self.instrument.p.rotor_off_instrument
        return {ROTOR_OFF: name} if name else {}

    def has_tape(self) -> bool:
        """True when a torsion tape hangs the gyroscope."""
        return bool(self.tape_constant_per_inertia)

    def centre_drifts(self) -> bool:
        """True when the swing's centre moves during the record (the tape zero drifts,
        ``tape_drift``): the full-record fit then fits a linear drift of the centre."""
        return self.instrument.has("tape_drift")

    def rate_from_swing(self, T0, rho_mean) -> tuple:
        """:meth:`SwingRate.rate_from_swing` with the tape's D_B/A taken out of K = (π/T0)²."""
        if not self.has_tape():
            return super().rate_from_swing(T0, rho_mean)
        k = (math.pi / T0) ** 2 - self.tape_constant_per_inertia
        return super().rate_from_swing(math.pi / math.sqrt(k) if k > 0 else math.inf, rho_mean)

    def measured_rate(self, T0, sig_T0, crlb_T0, rho_mean) -> "RateEstimate":
        """:meth:`SwingRate.measured_rate`; with a tape the relative σ and bound grow by K/(K − D_B/A)
        (the tape's part of K is known, the swing's σ falls on the gyroscope's part alone)."""
        r = super().measured_rate(T0, sig_T0, crlb_T0, rho_mean)
        if not self.has_tape():
            return r
        K = (math.pi / T0) ** 2
        f = K / (K - self.tape_constant_per_inertia) if K > self.tape_constant_per_inertia else math.inf
        return RateEstimate(r.value, r.sigma * f, r.crlb * f, r.extra)
