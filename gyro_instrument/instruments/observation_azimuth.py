"""The azimuth measurement: a horizontal gyroscope's swing centre is the meridian (issue 24).

Quet 1853 sec. 4 §1 item 1: with its axis in a horizontal plane a spinning body rests only along
the meridian, so the centre of its swing, read on the instrument's scale, is true north and gives
the azimuth of the scale's zero (``mount_azimuth_deg``). :class:`HorizontalSwing` is the
observation of a horizontal plane gyroscope: its swing-rate measurement (:data:`SWING_RATE`, as
:class:`~.observation.SwingRate`) and beside it an :data:`AZIMUTH` measurement
(``ALSO_MEASURES``), which the estimator's engine for that kind turns into the ``north`` block
(``estimators/north/estimate.py``). :class:`TapeSwing` is the same gyroscope with the rotor stopped:
a torsion pendulum on its tape, no Earth-rate measurement, read by the rotor-on gyroscope's north
estimate for the tape zero and the tape's stiffness (``companions``).
"""

import math
from typing import ClassVar

import numpy as np

from gyro_instrument.instruments.observation import SPIN_RATE, RateEstimate, RotorObservation, SwingRate

#: Measurement kind: the azimuth of a scale's zero from a swing centre on the meridian.
AZIMUTH = "azimuth"
#: The key under which a rotor-on record carries its rotor-off companion's record.
ROTOR_OFF = "rotor_off"


def read_on_scale(obs, columns) -> dict:
    """``columns`` (channel -> array) as the sensor reads them: each channel of ``obs.reading_offsets()``
    plus its offset (a horizontal gyroscope's angle on its scale, u + M), the others as they are. What the
    sensor draws from (``true_values``) and what ``simulate`` writes into a table, the same doubles."""
    off = obs.reading_offsets()
    return {c: (v + off[c] if off.get(c) else v) for c, v in columns.items()}


def unwrapped_reading(angle, what, notes) -> np.ndarray:
    """A scale reading logged wrapped to (−π, π] (docs/formats/csv.md) unwrapped along the record (rad).

    The finite samples, in time order, are unwrapped where consecutive ones jump by more than π (a
    whole turn taken off: ``numpy.unwrap``). Only a record entirely inside [−π, π] with such a jump
    is touched: a column in degrees read as radians is left for the amplitude check to name. A line
    goes to ``notes`` when anything changed."""
    a = np.asarray(angle, dtype=float)
    ok = np.isfinite(a)
    v = a[ok]
    jumps = int(np.count_nonzero(np.abs(np.diff(v)) > math.pi)) if v.size > 1 else 0
    if not jumps or float(np.max(np.abs(v))) > math.pi:
        return a
    out = a.copy()
    out[ok] = np.unwrap(v)
    notes.append(f"{what}: read wrapped to (-180, 180] deg: unwrapped ({jumps} jump{'s' * (jumps > 1)} of a "
                 f"whole turn taken off)")
    return out


class _ScaleReading:
    """What the rotor-on and rotor-off swings share: the angle read on the scale, u + M
    (``mount_reading_rad``, the mount azimuth wrapped to (−π, π]), also from a table."""

    def reading_offsets(self) -> dict:
        """{``angle``: M} (rad): the scale's reading of true north."""
        return {"angle": self.instrument.mount_reading_rad}

    def true_values(self, columns) -> dict:
        """The scale reading u + M (rad): Quet's u offset by the mount (``mount_azimuth_deg``)."""
        return read_on_scale(self, super().true_values(columns))

    def record_from_table(self, full, col, size, notes) -> dict:
        """The record as the base reads it, the angle unwrapped when logged wrapped (:func:`unwrapped_reading`)."""
        rec = super().record_from_table(full, col, size, notes)
        rec["angle"] = unwrapped_reading(rec["angle"], f"{self.name}.angle", notes)
        return rec


class TapeSwing(_ScaleReading, RotorObservation):
    """A suspended gyroscope with its rotor stopped: a torsion pendulum on its tape (no Earth rate),
    read on the same scale (u + M). Not estimated itself: the rotor-on gyroscope's north reads its
    record (``companions``), so a table or a bag gives its angle like the gyroscope's."""

    def unmeasured_reason(self) -> str:
        return f"{self.name} swings with its rotor off: a torsion pendulum on its tape, read for the tape zero"

    def table_columns(self) -> tuple:
        """The angle (``spin_rate`` read too when the table has it)."""
        return (("angle",),)

    def record_from_table(self, full, col, size, notes) -> dict:
        """``angle`` (unwrapped when logged wrapped), and ``spin_rate`` when present (as live)."""
        rec = super().record_from_table(full, col, size, notes)
        spin = col(SPIN_RATE)
        if spin is not None:
            rec[SPIN_RATE] = spin
        return rec

    def required_joints(self) -> tuple:
        """The axis joint (the rotor's is read when present)."""
        return (self.layout.names[0],)


class HorizontalSwing(_ScaleReading, SwingRate):
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

    def companions(self) -> dict:
        """{record key: instrument name} of the other records the azimuth engine reads: with a tape, the
        rotor-off swing (``rotor_off_instrument``), when one is named."""
        name = self.instrument.p.rotor_off_instrument
        return {ROTOR_OFF: name} if name and self.has_tape() else {}

    def has_tape(self) -> bool:
        """True when a torsion tape hangs the gyroscope."""
        return bool(self.tape_constant_per_inertia)

    def centre_drifts(self) -> bool:
        """True when the swing's centre moves during the record (the tape zero drifts: the active
        ``torsion`` terms give it a rate, ``tape_drift``): the full-record fit then fits a linear drift
        of the centre."""
        return self.instrument.tape[2] != 0.0

    #: the swing centre's offset from the tape zero on the scale, Z − c (rad), from :meth:`rate_terms`
    centre_from_zero_rad = 0.0

    def rate_terms(self, rec) -> None:
        """With a tape, note Z − c: the tape zero at mid-record (the scene's Z0 + Ż t) less the swing's
        centre, (max + min)/2 of the scale reading over its 0.5–99.5 % range (an error δc there moves K
        by (k_B/K)² (Z − c) δc relative: 1e-6 for δc = 1e-4 rad on the shipped tape)."""
        if not self.has_tape():
            return
        t, a = np.asarray(rec["t"], dtype=float), np.asarray(rec["angle"], dtype=float)
        ok = np.isfinite(t) & np.isfinite(a)
        if ok.sum() < 2:
            return
        lo, hi = np.percentile(a[ok], [0.5, 99.5])
        c = self.instrument.reduced_coefficients()
        self.centre_from_zero_rad = float(c["zero"] + c["zero_rate"] * np.mean(t[ok]) - 0.5 * (lo + hi))

    #: the largest second-order period factor F − 1 (:meth:`amplitude_factor`) the rate law trusts: its
    #: neglected O(a⁴) term is ~(F − 1)², 1e-6 of the period here (a few 1e-5° of latitude)
    MAX_ANHARMONIC = 1e-3

    def rate_withheld(self, amplitude_rad) -> str | None:
        """Why the swing's period gives no rate (None when it does): with a tape, a swing so large about an
        equilibrium off north that the period's amplitude law (second order, :meth:`amplitude_factor`)
        no longer holds, nor the sine-and-third-harmonic fit (the swing is asymmetric)."""
        if not self.has_tape():
            return None
        F = float(self.amplitude_factor(amplitude_rad))
        if F - 1.0 <= self.MAX_ANHARMONIC:
            return None
        return (f"the swing ({math.degrees(amplitude_rad):.3g} deg) about a centre held "
                f"{math.degrees(self._offset_from_north()):.3g} deg from north by the tape is too anharmonic for the "
                f"period's amplitude law (factor {F:.6f} beyond 1 + {self.MAX_ANHARMONIC:g}): no Earth-rate measurement "
                "from it; north (the exact fit of the swing equation) is unaffected")

    def _directing_and_offset(self) -> tuple:
        """(K, sin(c − N)): the scene's directing constant per inertia (1/s²) and the equilibrium's offset
        from north, K sin(c − N) = k_B (Z − c) with Z − c from :meth:`rate_terms` (0 when K ≤ 0)."""
        K = self.instrument.reduced_coefficients()["a"] * self.instrument.p.spin_rate_rad_s
        sn = max(-1.0, min(1.0, self.tape_constant_per_inertia * self.centre_from_zero_rad / K)) if K > 0 else 0.0
        return K, sn

    def _offset_from_north(self) -> float:
        return math.asin(self._directing_and_offset()[1])

    def amplitude_factor(self, amplitude_rad) -> "float | np.ndarray":
        """T(a)/T0. Without a tape :meth:`SwingRate.amplitude_factor` (the sine law's elliptic factor). With
        one the restoring torque about the equilibrium c is K sin(ε + c − N) − K sin(c − N) + k_B ε, whose
        Taylor terms ω² ε + α ε² + β ε³ (α = −K sin(c − N)/2, β = −K cos(c − N)/6) shift the frequency by
        (3β/(8ω) − 5α²/(12ω³)) a² (Landau & Lifshitz, Mechanics §28): F = 1 + a² (K cos(c − N)/(16 ω²)
        + 5 K² sin²(c − N)/(48 ω⁴)), the sine law's 1 + a²/16 when k_B = 0 and c = N. K, k_B from the
        scene (a correction's coefficients), sin(c − N) = k_B (Z − c)/K with Z − c from :meth:`rate_terms`;
        the next term is O(a⁴) (4e-8 at a = 0.06 rad)."""
        if not self.has_tape():
            return super().amplitude_factor(amplitude_rad)
        K, sn = self._directing_and_offset()
        if not K > 0:
            return super().amplitude_factor(amplitude_rad)
        kb = self.tape_constant_per_inertia
        cs = math.sqrt(1.0 - sn * sn)
        w2 = K * cs + kb
        return 1.0 + np.square(amplitude_rad) * (K * cs / (16.0 * w2) + 5.0 * (K * sn) ** 2 / (48.0 * w2 * w2))

    def rate_from_swing(self, T0, rho_mean) -> tuple:
        """:meth:`SwingRate.rate_from_swing` with the tape taken out of K: linearised about the equilibrium
        c, ω² = (π/T0)² = K cos(c − N) + k_B, and there K sin(c − N) = k_B (Z − c) (the equilibrium of
        :meth:`.plane_gyroscope.instrument.PlaneGyroscope.equilibrium_reading_rad`), so
        K = √((ω² − k_B)² + k_B² (Z − c)²) (Z − c from :meth:`rate_terms`; the scale's
        zero far from north holds the centre degrees off the meridian, where ω² − k_B alone is
        K cos(c − N): 0.3 % low at a mount of 45°, 0.13° of latitude)."""
        if not self.has_tape():
            return super().rate_from_swing(T0, rho_mean)
        kb = self.tape_constant_per_inertia
        k = math.hypot((math.pi / T0) ** 2 - kb, kb * self.centre_from_zero_rad) if (math.pi / T0) ** 2 > kb else 0.0
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
