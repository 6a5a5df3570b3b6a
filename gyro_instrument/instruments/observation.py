"""Observations: what an instrument measures, how it is laid out, and how a record becomes a measurement.

Every instrument returns one :class:`Observation` (``Instrument.observation()``); the rest of the
package (sensor draws, the estimator and the planner, the recorder's joint layout, foreign bags,
tables, the views, the bench) asks it and never asks whether the instrument is a pendulum or which
directing model it has. An observation declares

=============================  ====================================================================
``channels``                   the measured channels (:class:`Channel`: name, unit, meaning: angle,
                               rate or position); ``table_channels`` every channel a table may give
``layout``                     the ``sensor_msgs/JointState`` layout (:class:`JointLayout`), one
                               definition used to write rows (:meth:`Observation.joint_rows`) and to
                               read them back (:meth:`Observation.joint_record`)
``spin_channel``               the rotor's spin channel (rad/s), or None
``sensor_inputs``              the sensor draws: record key, true values, angle or rate
``sensor_draws``               the observation's own sensor (None: the scene's ``sensor`` draws)
``MEASUREMENT``,                the measurement kinds a record gives (names of registered kinds,
``ALSO_MEASURES``              :mod:`.measurement`): None (no Earth rate), :data:`SWING_RATE` (a swing
                               about a directing line: y = n s(γ)), :data:`PLANE_RATE` (a swing
                               plane's precession: k = n sin γ), an azimuth beside a swing; the
                               kind's engine, probe and bound do the fit, the observation supplies
                               its laws
``companions``                 {record key: instrument} of the other records its kinds read
``applicable_corrections``     which systematic corrections apply to its record
=============================  ====================================================================

and, for a swing (:class:`SwingRate`), its own restoring law (``amplitude_factor``), its spin
dependence (``spin_frequency``, ``spin_envelope``, ``PERIOD_EXPONENT``, ``SPIN_EXPONENT``), the rate
its swing duration gives (``rate_from_swing``) and the rate's σ and Cramér–Rao bound from the fit's
(``measured_rate``, ``rate_relative_variance``). A gyroscope whose directing torque obeys another law
(a pendulous, Schuler-tuned gyrocompass: K = P n cos γ / (C ρ), T = 2π √(H / (P n cos γ)), Quet's
law inverted in ρ) subclasses :class:`SwingRate` and overrides those members; nothing outside its
instrument changes.

Model: rosbags' typed ``StorageProtocol`` (one declared interface per backend, no type switches in
the reader).
"""

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gyro_instrument.core.effect import FRAME_RATE, RESTORING_LAW, SINE_LAW
from gyro_instrument.effects import REGISTRY, FiniteAmplitude, SpinDecay
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.instruments.channels import ANGLE, POSITION, RATE, Channel, JointLayout  # noqa: F401

#: Measurement kinds (the ``kind`` of the estimator's ``RateMeasurement``): a gyroscope's swing about
#: a directing line, y = K / (gain ρ) = n s(γ) (Quet 1853 sec. 4 §1 eq. 9); a pendulum's swing-plane
#: precession, k = n sin γ (sec. 2 §III).
SWING_RATE = "gyro"
PLANE_RATE = "pendulum"

#: The systematic corrections the estimator makes (``estimate_records(..., corrections=...)`` can leave
#: any out; ``gyro-instrument bench`` measures what each is worth): a swing reduced to small amplitude
#: through its amplitude law; a swing fitted in the spin-warped time of its measured spin history; the
#: Foucault rate less the finite-amplitude precession of the swing ellipse (sec. 2 §III).
AMPLITUDE_CORRECTION = FiniteAmplitude.name
SPIN_CORRECTION = SpinDecay.name
ELLIPSE_CORRECTION = "ellipse_precession"
CORRECTIONS = frozenset((AMPLITUDE_CORRECTION, SPIN_CORRECTION, ELLIPSE_CORRECTION))

#: The corrections that undo the finite-amplitude law. An instrument whose model can leave the
#: sine law out (it sums ``restoring_law`` terms) and does (no active effect gives it) is a small-angle model:
#: it swings in T0 at any amplitude and its apsides turn at exactly k, so correcting it would bias
#: the rate (by 2 x 6e-4 at 0.1 rad). Instruments without that choice (the gimbal, the compound
#: pendulum) always integrate the exact, nonlinear equations.
FINITE_AMPLITUDE_CORRECTIONS = frozenset((AMPLITUDE_CORRECTION, ELLIPSE_CORRECTION))

#: The rotor's spin channel (rad/s) of the shipped rotor instruments.
SPIN_RATE = "spin_rate"


@dataclass(frozen=True)
class RateEstimate:
    """A rate from one record (rad/s): value, σ, Cramér–Rao bound and notes for the estimate JSON."""

    value: float
    sigma: float
    crlb: float
    extra: dict


class Observation:
    """What an instrument measures; the base: measured angles only, no rotor, no Earth rate.

    A torsion pendulum (no rotor) needs nothing more than this class. Subclasses set the class
    members and override the hooks; an instrument class names its observation class in
    ``Instrument.OBSERVATION``, and :meth:`of` builds the instance.
    """

    #: The measurement kind (:data:`SWING_RATE`, :data:`PLANE_RATE`) or None: no Earth rate.
    MEASUREMENT: ClassVar[str | None] = None
    #: Kinds measured beside ``MEASUREMENT`` from the same record (an azimuth:
    #: :class:`~.observation_azimuth.HorizontalSwing`); () for most observations.
    ALSO_MEASURES: ClassVar[tuple] = ()
    #: Joints after the measured ones, computed from them (see :class:`JointLayout`).
    DERIVED_JOINTS: ClassVar[tuple] = ()
    #: True when a last rotor joint carries the spin channel.
    HAS_ROTOR: ClassVar[bool] = False
    #: True when :meth:`bob_enu_m` gives a bob's position (published as ``<name>/bob``).
    SHOWS_BOB_POSITION: ClassVar[bool] = False

    #: The ship's track the estimator reads beside the measured channels (record keys; a table's
    #: ``ship.<key>`` columns, :mod:`gyro_instrument.core.motion`); () for an instrument on a pier.
    TRACK_KEYS: ClassVar[tuple] = ()

    @classmethod
    def layout_of(cls, inst_cls) -> JointLayout:
        """The joint layout of the instrument class ``inst_cls`` (raises ValueError when its ``JOINTS``
        do not fit the measured channels, the derived joints and the rotor)."""
        return JointLayout(tuple(inst_cls.JOINTS), tuple(inst_cls.MEASURED_CHANNELS), cls.DERIVED_JOINTS,
                           SPIN_RATE if cls.HAS_ROTOR else None)

    @classmethod
    def true_columns(cls, inst_cls) -> tuple:
        """The simulated columns the sensor reads (each must be one of ``inst_cls.COLUMNS``)."""
        return tuple(inst_cls.MEASURED_CHANNELS)

    @classmethod
    def of(cls, inst) -> "Observation":
        """The observation of the instrument ``inst``."""
        return cls(inst)

    def __init__(self, inst) -> None:
        self.instrument = inst
        self.name = inst.name
        self.type_name = inst.type_name
        self.layout = self.layout_of(type(inst))
        self.channels = self.channels_of(type(inst))

    @classmethod
    def channels_of(cls, inst_cls) -> tuple:
        """The measured channels (:class:`Channel`) of the instrument class ``inst_cls``: its angles,
        then the spin (a rate) when it has a rotor."""
        layout = cls.layout_of(inst_cls)
        spin = () if layout.rotor is None else (Channel(layout.rotor, "rad/s", RATE),)
        return tuple(Channel(c, "rad", ANGLE) for c in layout.measured) + spin

    @classmethod
    def table_channels(cls, inst_cls) -> tuple:
        """Every channel a table may give the record in (:class:`Channel`): the measured ones and those
        the observation reads beside them (a swing's ``angle``, a bob's positions)."""
        return cls.channels_of(inst_cls)

    # ------------------------------------------------------------------ sensor draws
    @property
    def spin_channel(self) -> str | None:
        """The spin channel (rad/s) the sensor reads, or None."""
        return self.layout.rotor

    def true_values(self, columns) -> dict:
        """True values of the measured angles from simulated ``columns``: name -> array (rad)."""
        return {c: columns[c] for c in self.layout.measured}

    def signal_angles(self, columns) -> dict:
        """The true angles whose motion carries the measurement (name -> array, rad): all measured
        angles by default."""
        return self.true_values(columns)

    def sensor_inputs(self, columns) -> list:
        """The sensor draws, in order: ``(record key, true values, 'angle' | 'rate')`` — the measured
        angles, then the spin when it is simulated."""
        out = [(k, v, "angle") for k, v in self.true_values(columns).items()]
        if self.spin_channel is not None and self.spin_channel in columns:
            out.append((self.spin_channel, columns[self.spin_channel], "rate"))
        return out

    def sensor_draws(self, sensor, rng) -> Callable | None:
        """The observation's own sensor, or None (the default): the scene's ``sensor`` (``SensorModel``)
        draws each channel of :meth:`sensor_inputs` as an angle or a rate.

        An instrument whose readings follow their own error model (a rate gyro's angle random walk,
        bias instability and turn-on bias, :class:`~.rate_gyro.RateGyroObservation`) returns a callable
        ``(record key, true values, kind of sensor_inputs) -> measured array`` drawing from ``rng``; it is
        called block after block in time order (``measure`` once, ``MeasureStream`` per block), and the
        blocks concatenate to the one-shot draw."""
        return None

    def complete(self, rec) -> dict:
        """``rec`` with what the estimator reads beside the measured channels (the default adds nothing)."""
        return rec

    def companions(self) -> dict:
        """{record key: instrument name} of the other records this one's engines read; {} by default."""
        return {}

    def reading_offsets(self) -> dict:
        """{channel: rad} the sensor reads on top of the simulated channel (a scale's zero); {} by default."""
        return {}

    def has_record(self, rec) -> bool:
        """True when ``rec`` holds what the estimator reads (the first measured channel)."""
        return bool(self.layout.measured) and self.layout.measured[0] in rec

    # ------------------------------------------------------------------ joint layout
    def derived_positions(self, rec) -> list:
        """Positions of :attr:`DERIVED_JOINTS` from a measured record (list of arrays, rad)."""
        return []

    def bob_enu_m(self, rec) -> np.ndarray | None:
        """The bob's position (m, 3) in ENU from the measured record, or None (no bob)."""
        return None

    def joint_rows(self, rec) -> tuple:
        """The writing half of :attr:`layout`: ``(rated, spin)`` — the positions whose velocity is their
        centred difference (measured, then derived; list of arrays) and the measured spin for the
        rotor's velocity (None without a rotor; zeros when no spin was measured)."""
        rated = [rec[c] for c in self.layout.measured] + self.derived_positions(rec)
        if self.layout.rotor is None:
            return rated, None
        return rated, rec.get(self.layout.rotor, np.zeros_like(rec["t"]))

    def joint_record(self, t_s, position, velocity) -> dict:
        """The estimator's record from joint arrays in :attr:`layout` order (``t`` in s)."""
        return self.complete({"t": t_s} | self.layout.record(position, velocity))

    def required_joints(self) -> tuple | None:
        """The joints a foreign bag must hold for the estimator (None: the estimator does not use it)."""
        return None

    # ------------------------------------------------------------------ tables
    def table_columns(self) -> tuple:
        """Alternative column sets (tuples of channel names) that give the record; () when unused."""
        return ()

    def record_from_table(self, full, col, size, notes) -> dict:
        """The record's channels from the table column set ``full`` (``col(channel)`` reads one column,
        ``size`` rows); notes what it assumed in ``notes``."""
        return {c: col(c) for c in full}

    def table_length_m(self) -> float | None:
        """The length (m) a table's position columns are divided by to give the measured angles, or
        None when the record is not read from positions."""
        return None

    # ------------------------------------------------------------------ estimation
    def rotating(self) -> bool:
        """True when the instrument simulates the Earth's rotation (a ``frame_rate`` term: its measurement observes n)."""
        return self.instrument.frame_rotates()

    def unmeasured_reason(self) -> str | None:
        """Why the instrument gives no Earth-rate measurement in this scene, or None when it does."""
        inst, turning = self.instrument, [n for n, c in REGISTRY.items() if FRAME_RATE in c.MECHANICS]
        turning = [n for n in turning if n in inst.SUPPORTED_EFFECTS]
        if not inst.frame_rotates() and turning:
            return f"{' or '.join(turning)} is not simulated for it: it measures no Earth rate"
        if self.MEASUREMENT is None:
            return f"{self.type_name} has no directing line: it gives no Earth-rate measurement"
        return None

    def small_angle_model(self) -> bool:
        """True when the instrument is simulated in its small-angle (linear) model (see
        :data:`FINITE_AMPLITUDE_CORRECTIONS`)."""
        return RESTORING_LAW in type(self.instrument).MECHANICS and not self.instrument.has_term(SINE_LAW)

    def applicable_corrections(self, corrections) -> frozenset:
        """The corrections of ``corrections`` that apply to this record (a small-angle model has no
        finite-amplitude law to undo)."""
        if self.small_angle_model():
            return frozenset(corrections) - FINITE_AMPLITUDE_CORRECTIONS
        return frozenset(corrections)

    def swing_amplitude(self, rec) -> float:
        """The record's swing amplitude, rad: half the 0.5–99.5 % range of :meth:`swing_signal`."""
        y = np.asarray(self.swing_signal(rec), dtype=float)
        y = y[np.isfinite(y)]
        return float(0.5 * (np.percentile(y, 99.5) - np.percentile(y, 0.5))) if y.size else math.nan

    def swing_signal(self, rec) -> np.ndarray:
        """The channel whose period is checked against the scene's prediction."""
        return rec[self.layout.measured[0]]


class RotorObservation(Observation):
    """Measured angles and a rotor whose spin is measured; no Earth rate (a free gyroscope, Puiseux's
    body, a gimbal with free rings)."""

    HAS_ROTOR = True


class SwingRate(RotorObservation):
    """A gyroscope swinging about a directing line: Quet's law K = gain · n ρ · s(γ) (1 + c2 n s/ρ).

    Small swings last T0 = π/√K (Quet 1853 sec. 4 §1 eq. 9; sec. 4 §IV for the gimbal). The members
    below are the law's; a gyroscope with another directing law overrides them.

    Attributes
    ----------
    model : DirectingModel
        gain, swing-plane normal (ENU), configuration label, angle channel, null reason, c2, ρ0.
    """

    MEASUREMENT = SWING_RATE
    #: y ∝ T0^PERIOD_EXPONENT at a given spin (y = (π/T0)² / (gain ρ))
    PERIOD_EXPONENT: ClassVar[float] = -2.0
    #: y ∝ ρ^SPIN_EXPONENT at a given T0 (Quet: K ∝ ρ, so y = K/(gain ρ) ∝ 1/ρ)
    SPIN_EXPONENT: ClassVar[float] = -1.0

    @classmethod
    def of(cls, inst) -> Observation:
        """The swing of ``inst`` from its :meth:`~.base.Instrument.directing_model`, or a
        :class:`RotorObservation` when it has none in this configuration (free rings)."""
        model = inst.directing_model()
        return cls(inst, model) if model is not None else RotorObservation(inst)

    def __init__(self, inst, model) -> None:
        super().__init__(inst)
        self.model = model
        self.angle_channel = model.angle_channel
        self.gain = model.gain
        self.normal_enu = tuple(model.normal_enu)
        self.label = model.label
        self.null_reason = model.null_reason

    def signal_angles(self, columns) -> dict:
        """The swinging angle only."""
        return {self.angle_channel: columns[self.angle_channel]}

    def complete(self, rec) -> dict:
        """Adds ``angle``: the swinging channel."""
        if self.angle_channel in rec:
            rec["angle"] = rec[self.angle_channel]
        return rec

    def has_record(self, rec) -> bool:
        """True when ``rec`` holds the swinging angle."""
        return "angle" in rec

    def required_joints(self) -> tuple:
        """The swinging channel's joint and the rotor."""
        return (self.layout.names[self.layout.measured.index(self.angle_channel)], self.layout.names[-1])

    @classmethod
    def table_channels(cls, inst_cls) -> tuple:
        """The measured channels, ``angle`` (the swinging one) and ``spin_rate``."""
        return super().table_channels(inst_cls) + (Channel("angle", "rad", ANGLE), Channel(SPIN_RATE, "rad/s", RATE))

    def table_columns(self) -> tuple:
        """The swing angle, with the spin unless the scene states a constant one."""
        if self.model.spin_rate_rad_s:        # spin_rate optional: the scene's constant spin without it
            return ((self.angle_channel,),)
        return ((self.angle_channel, SPIN_RATE),)

    def record_from_table(self, full, col, size, notes) -> dict:
        """The angle channels present, the spin (the scene's constant without a column), ``angle``."""
        rec = {}
        for chan in self.layout.measured:
            value = col(chan)
            if value is not None:
                rec[chan] = value
        spin = col(SPIN_RATE)
        if spin is None:
            rho = self.model.spin_rate_rad_s
            spin = np.full(size, rho)
            notes.append(f"{self.name}: no {self.name}.{SPIN_RATE} column: the scene's constant spin "
                         f"{rho!r} rad/s used (spin_rate_rad_s)")
        rec[SPIN_RATE] = spin
        rec["angle"] = rec[full[0]]
        return rec

    def swing_signal(self, rec) -> np.ndarray:
        """The swinging angle (rad)."""
        return rec["angle"]

    # ------------------------------------------------------------------ the directing law
    def amplitude_factor(self, amplitude_rad) -> float | np.ndarray:
        """F(a) = T(a)/T0 of the restoring law −K sin u: (2/π) K(sin(a/2)) (sec. 2 eq. 42 exact form)."""
        return finite_amplitude_factor(amplitude_rad)

    def spin_frequency(self, ratio) -> np.ndarray:
        """ω(ρ)/ω(ρ̄) for the spin ratio ρ/ρ̄: √(ρ/ρ̄) (ω = √K, K ∝ ρ; the warp τ = ∫ of it dt)."""
        return np.sqrt(ratio)

    def spin_envelope(self, ratio) -> np.ndarray:
        """The adiabatic amplitude ratio a(ρ)/a(ρ̄): (ρ/ρ̄)^(−1/4) (action E/ω kept, K ∝ ρ)."""
        return ratio ** -0.25

    def rate_withheld(self, amplitude_rad) -> str | None:
        """Why a swing of this amplitude gives no rate (None: it does; after :meth:`rate_terms`)."""

    def rate_terms(self, rec) -> None:
        """Note what the rate law needs from the record beyond its period (a tape's centre offset)."""

    def rate_from_swing(self, T0, rho_mean) -> tuple:
        """(y, second-order correction or None): y = K/(gain ρ̄) = n s(γ), K = (π/T0)², with the O(n²)
        centrifugal term of the exact equation removed when the model has one (y = y0 (1 + c2 y0/ρ))."""
        K = (math.pi / T0) ** 2
        y_val = K / (self.gain * rho_mean)
        c2 = self.model.second_order
        if not c2:
            return y_val, None
        y0 = 2.0 * y_val / (1.0 + math.sqrt(1.0 + 4.0 * c2 * y_val / rho_mean))
        return y0, K / (self.gain * rho_mean) / y0 - 1.0

    def measured_rate(self, T0, sig_T0, crlb_T0, rho_mean) -> RateEstimate:
        """The rate, its σ and its Cramér–Rao bound from the small-amplitude swing duration T0 (s), its
        σ and bound (s), and the mean spin (rad/s): relative σ = |PERIOD_EXPONENT| σ_T0/T0."""
        y_val, c2_corr = self.rate_from_swing(T0, rho_mean)
        k = abs(self.PERIOD_EXPONENT)
        extra = {} if c2_corr is None else {"second_order_correction": c2_corr}
        return RateEstimate(y_val, y_val * (k * sig_T0 / T0), y_val * k * crlb_T0 / T0, extra)

    def rate_relative_variance(self, var_ln_frequency, var_ln_spin) -> float:
        """(σ_y / y)² from var ln(1/T0) (the fit's, amplitude law included) and var ln ρ̄ (the spin
        sensor's): PERIOD_EXPONENT² · var + SPIN_EXPONENT² · var."""
        return self.PERIOD_EXPONENT ** 2 * max(var_ln_frequency, 0.0) + self.SPIN_EXPONENT ** 2 * var_ln_spin


class PlanePrecession(Observation):
    """A bob's swing plane turning at k = n sin γ (Foucault; Quet sec. 2 §III): the measured channels
    are the deflections x/l, y/l (east, north) of a bob on a rod of length l; the joints add the
    deflection hypot(x, y)/l and the compass azimuth atan2(east, north); the spin is not measured."""

    MEASUREMENT = PLANE_RATE
    DERIVED_JOINTS = ("deflection", "azimuth")
    SHOWS_BOB_POSITION = True
    #: The bob's simulated position columns (m).
    POSITION_COLUMNS: ClassVar[tuple] = ("x_east", "y_north")

    @classmethod
    def true_columns(cls, inst_cls) -> tuple:
        return cls.POSITION_COLUMNS

    def __init__(self, inst) -> None:
        super().__init__(inst)
        self.length_m = float(inst.pendulum_length_m())

    def true_values(self, columns) -> dict:
        """x_east / l and y_north / l (rad)."""
        east, north = self.layout.measured
        return {east: columns["x_east"] / self.length_m, north: columns["y_north"] / self.length_m}

    def derived_positions(self, rec) -> list:
        e, n = (rec[c] for c in self.layout.measured)
        return [np.hypot(e, n), np.arctan2(e, n)]

    def bob_enu_m(self, rec) -> np.ndarray:
        """(x, y, −√(l² − x² − y²)) from the measured deflections, m."""
        l = self.length_m
        x, y = (l * rec[c] for c in self.layout.measured)
        return np.column_stack([x, y, -np.sqrt(np.maximum(l * l - x * x - y * y, 0.0))])

    def required_joints(self) -> tuple:
        return self.layout.names[:len(self.layout.measured)]

    @classmethod
    def table_channels(cls, inst_cls) -> tuple:
        """The deflections (rad) and the bob's positions (m)."""
        return super().table_channels(inst_cls) + tuple(Channel(c, "m", POSITION) for c in cls.POSITION_COLUMNS)

    def table_columns(self) -> tuple:
        """Positions (m) or deflections (rad)."""
        return (self.POSITION_COLUMNS, tuple(self.layout.measured))

    def record_from_table(self, full, col, size, notes) -> dict:
        """Deflections, from positions divided by the length when the table holds positions."""
        east, north = self.layout.measured
        if full == self.POSITION_COLUMNS:
            return {east: col("x_east") / self.length_m, north: col("y_north") / self.length_m}
        return {east: col(east), north: col(north)}

    def table_length_m(self) -> float:
        """l: ``x_east`` / l and ``y_north`` / l are the deflections."""
        return self.length_m

    def swing_amplitude(self, rec) -> float:
        """The 99.5 % deflection hypot(x, y)/l, rad."""
        r = np.hypot(*(rec[c] for c in self.layout.measured))
        r = r[np.isfinite(r)]
        return float(np.percentile(r, 99.5)) if r.size else math.nan

    def swing_signal(self, rec) -> np.ndarray:
        """The deflection with the larger variance."""
        e, n = (rec[c] for c in self.layout.measured)
        return n if np.nanvar(n) > np.nanvar(e) else e

    def release(self) -> tuple | None:
        """(θ0, ψ0): the release deflection and compass azimuth (rad), or None when not stated."""
        p = self.instrument.params
        if "initial_deflection_deg" not in p or "initial_azimuth_deg" not in p:
            return None
        return math.radians(p["initial_deflection_deg"]), math.radians(p["initial_azimuth_deg"])

    def release_amplitude(self) -> float:
        """α = sin θ0 of the release (the planner's swing amplitude)."""
        return math.sin(math.radians(self.instrument.params["initial_deflection_deg"]))

    def swing_period_s(self) -> float:
        """The full swing period (s): four quarter periods of the predictions, else 2π √(l/g)."""
        pred = self.instrument.predictions()
        if "quarter_period_s" in pred:
            return 4.0 * pred["quarter_period_s"]
        return 2.0 * math.pi * math.sqrt(self.length_m / self.instrument.site.gravity_m_s2)

    def models_finite_amplitude(self) -> bool:
        """True when the finite-amplitude law is simulated (the apse line turns at the exact rate)."""
        return self.instrument.has_term(SINE_LAW)

