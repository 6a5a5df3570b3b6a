"""A single-axis rate gyroscope on a turntable (indexer or carousel): a north finder (issue 35 item 3).

The gyro's sensitive axis is horizontal; the turntable turns it about the vertical. Its heading
(azimuth, clockwise from true north) is h = M + φ: M the azimuth of the turntable's reference
(index 0), ``mount_azimuth_deg`` (what the estimate seeks, as a gyrotheodolite's scale zero), φ the
index angle read on the table's encoder, clockwise seen from above. The Earth rate in ENU is
n (0, cos γ, sin γ) and the axis (sin h, cos h, 0), so the rate about it is n cos γ cos h: a
horizontal axis sees only the horizontal component, the turntable's own turn (about the vertical)
not at all. The sensor reads (model of :mod:`.sensor`)::

    r = (1 + s) n cos γ cos(M + φ) + b0 + g(t) + w(t)

Schedules: ``positions`` equally spaced index angles φ_k = φ0 + k·360°/P held ``dwell_s`` each and
reached in ``slew_s`` (the table turns clockwise at constant rate; samples while it turns are read
but not used by the estimator), repeated over the run; or, with ``carousel_rate_deg_s`` ≠ 0, a
continuous turn φ = φ0 + ω t (a carousel: the Earth rate modulated at ω, above the bias
instability's corner). Two positions (φ0, φ0 + 180°) measure cos(M + φ0) only: M and its mirror
image −M − 2φ0 fit the data equally; a coarse prior (``mount_azimuth_prior_deg`` ±
``mount_azimuth_prior_tolerance_deg``, a magnetic compass's) picks one (estimators/north/rate_gyro.py).

Published as ``sensor_msgs/JointState`` (msg_docs/topics.md): joint ``table`` (position = the index
angle φ, rad; velocity = its centred difference) and joint ``sensitive_axis`` (velocity = the
measured rate about the sensitive axis, rad/s — the gyro's output; position = the integral of the
true rate, rad, wrapped, as a rotor joint's).
"""

import math
from collections.abc import Callable
from typing import ClassVar

import numpy as np

from gyro_instrument.core.effect import FRAME_RATE, Scales
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import Trajectory
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import Column, Instrument, Simulation, with_notes
from gyro_instrument.instruments.channels import ANGLE, Channel, RATE as RATE_MEANING
from gyro_instrument.instruments.observation import JointLayout, Observation
from gyro_instrument.instruments.rate_gyro.sensor import DEG_H, DEG_RT_H, GM_ALLAN_PEAK, GM_ALLAN_PEAK_TAU, GyroErrors

#: Measurement kind: the azimuth of a turntable's reference from the Earth rate a rate gyro reads at
#: several headings (the ``north`` block, estimators/north/rate_gyro.py).
RATE_AZIMUTH = "rate_azimuth"
#: the measured channels (record keys): the encoder's index angle (rad) and the gyro's rate (rad/s)
INDEX, RATE = "index", "rate"


def schedule(t_s, p) -> tuple:
    """(index φ in [0, 2π), settled flag 0/1) at times ``t_s`` (s) for the parameters ``p``.

    Indexed: position k = ⌊τ/(dwell + slew)⌋ of the cycle, τ = t mod P (dwell + slew); held for
    ``dwell_s``, then turned clockwise at constant rate to the next in ``slew_s``. Carousel:
    φ = φ0 + ω t, never settled."""
    t = np.asarray(t_s, dtype=float)
    phi0 = math.radians(p.first_index_deg)
    if p.carousel_rate_deg_s:
        return np.mod(phi0 + math.radians(p.carousel_rate_deg_s) * t, 2.0 * math.pi), np.zeros_like(t)
    step = 2.0 * math.pi / p.positions
    hold = p.dwell_s + p.slew_s
    k = np.floor(t / hold)
    u = t - k * hold
    moving = u >= p.dwell_s
    frac = np.where(moving, (u - p.dwell_s) / p.slew_s if p.slew_s > 0 else 0.0, 0.0)
    k_mod = np.mod(k, p.positions)
    return np.mod(phi0 + (k_mod + frac) * step, 2.0 * math.pi), (~moving).astype(float)


class RateGyroObservation(Observation):
    """What a rate gyro on a turntable measures: the index angle (exact encoder) and the rate (its
    own error model, :class:`~.sensor.GyroErrors`, not the scene's ``sensor``).

    No Earth-rate measurement for the latitude (``MEASUREMENT`` None: one horizontal axis reads
    (1 + s) n cos γ, scale factor and latitude inseparable); an azimuth beside it (``ALSO_MEASURES``:
    :data:`RATE_AZIMUTH`, the registered measurement kind of
    :class:`~gyro_instrument.estimators.rate_gyro_kind.RateAzimuthKind`: its engine, planner probe,
    bound, live tracker; its result the ``north`` block). Channels: ``index`` an angle (rad), ``rate``
    a measured rate (rad/s, the rotor slot of the joint layout: the ``sensitive_axis`` joint's velocity)."""

    ALSO_MEASURES: ClassVar[tuple] = (RATE_AZIMUTH,)

    @classmethod
    def layout_of(cls, inst_cls) -> JointLayout:
        """``table`` (the index angle), then ``sensitive_axis`` whose velocity is the measured rate."""
        return JointLayout(tuple(inst_cls.JOINTS), (INDEX,), (), RATE)

    @classmethod
    def channels_of(cls, inst_cls) -> tuple:
        """``index`` an angle (rad; ``estimate --data --angle-unit deg`` converts it), ``rate`` a rate (rad/s)."""
        return (Channel(INDEX, "rad", ANGLE), Channel(RATE, "rad/s", RATE_MEANING))

    def sensor_inputs(self, columns) -> list:
        """The index (read exactly: an encoder far finer than the estimate needs) and the rate."""
        return [(INDEX, columns[INDEX], "encoder"), (RATE, columns[RATE], "gyro")]

    def sensor_draws(self, sensor, rng) -> Callable | None:
        """The gyro's own error model (the scene's ``sensor`` block is not applied to it): a callable
        (key, values, kind) -> measured array, drawing from ``rng`` block after block."""
        inst, made = self.instrument, []

        def draw(key, values, kind):
            v = np.array(values, dtype=float)
            if kind != "gyro":
                return v
            if not made:            # at the first draw: the simulation before it has set the sample rate
                p = inst.p
                made.append(GyroErrors(p.arw_deg_rt_h * DEG_RT_H, p.bias_instability_deg_h * DEG_H / GM_ALLAN_PEAK,
                                       p.bias_correlation_time_s, p.turn_on_bias_deg_h * DEG_H,
                                       1.0 / inst.sample_rate_hz, rng))
            return v + made[0].draw(v.size)
        return draw

    def has_record(self, rec) -> bool:
        return INDEX in rec and RATE in rec

    def required_joints(self) -> tuple:
        return tuple(self.layout.names)

    def table_columns(self) -> tuple:
        return ((INDEX, RATE),)

    def unmeasured_reason(self) -> str | None:
        if not self.instrument.model_earth_rate():
            return "earth_rotation is not simulated for it: it measures no Earth rate"
        return None

    def noise_model(self, dt_s) -> dict:
        """The rate's noise as the estimator models it for samples ``dt_s`` apart (rad/s, s): white
        σ_w per sample, the Gauss–Markov σ_g and τ_c; the turn-on bias is a fitted parameter."""
        p, dt = self.instrument.p, float(dt_s)
        return {"sigma_white_rad_s": p.arw_deg_rt_h * DEG_RT_H / math.sqrt(dt),
                "sigma_gm_rad_s": p.bias_instability_deg_h * DEG_H / GM_ALLAN_PEAK,
                "correlation_time_s": p.bias_correlation_time_s, "dt_s": dt}


class RateGyro(Instrument):
    """A single-axis rate gyroscope, sensitive axis horizontal, on an indexing turntable or carousel."""

    type_name = "rate_gyro"
    summary = "single-axis rate gyro (MEMS/FOG) on a turntable: north from the Earth rate at several headings"
    PARAMS = (
        Param("mount_azimuth_deg", default=0.0, low=-360.0, high=360.0,
              doc="M: azimuth (clockwise from true north) of the turntable's reference, index 0, degrees"),
        Param("positions", kind="int", default=4, low=1, high=3600,
              doc="P: index positions per sequence, equally spaced (2: h, h+180; 4: every 90 deg)"),
        Param("first_index_deg", default=0.0, low=-360.0, high=360.0, doc="phi0: the first index angle, degrees"),
        Param("dwell_s", default=60.0, low=0.0, open_low=True, doc="time held at each position, s"),
        Param("slew_s", default=5.0, low=0.0, doc="time to turn to the next position (not used by the estimator), s"),
        Param("carousel_rate_deg_s", default=0.0, low=-360.0, high=360.0,
              doc="omega: continuous turn of the table, deg/s (0: indexed positions)"),
        Param("arw_deg_rt_h", default=0.09, low=0.0, doc="angle random walk N, deg/sqrt(h) (white rate noise)"),
        Param("bias_instability_deg_h", default=0.8, low=0.0,
              doc="bias instability B, deg/h: the Allan deviation's minimum (a Gauss-Markov process peaking there)"),
        Param("bias_correlation_time_s", default=100.0, low=0.0, open_low=True,
              doc="tau_c of the Gauss-Markov bias, s (its Allan deviation peaks at 1.89 tau_c)"),
        Param("turn_on_bias_deg_h", default=10.0, low=0.0, doc="sigma of the turn-on bias b0 (drawn per run), deg/h"),
        Param("scale_factor_ppm", default=0.0, low=-1.0e5, high=1.0e5, doc="s: scale factor error, ppm"),
        Param("mount_azimuth_prior_deg", default=0.0, low=-360.0, high=360.0,
              doc="coarse prior on M (a magnetic compass), degrees: picks the sign with two positions"),
        Param("mount_azimuth_prior_tolerance_deg", default=180.0, low=0.0, high=180.0,
              doc="+/- tolerance of that prior, degrees (180: no prior)"),
    )
    MECHANICS = frozenset({FRAME_RATE})
    COLUMNS = (Column(INDEX, "rad", "phi: the turntable's index angle, clockwise from its reference, in [0, 2 pi)"),
               Column(RATE, "rad/s", "the true rate about the sensitive axis, (1 + s) n cos(lat) cos(M + phi) "
                                     "(no bias, no noise)"),
               Column("settled", "1", "1 while the table holds a position, 0 while it turns"))
    MEASURED_CHANNELS = (INDEX,)
    JOINTS = ("table", "sensitive_axis")
    OBSERVATION = RateGyroObservation
    SIMULATOR_NODE = "gyrocompass_sim"
    #: the rate the gyro is read at (Hz; its white noise per sample is N/√Δ): the scene's
    #: sample_rate_hz, set by :meth:`simulate` from its sample times (the draws follow a simulation)
    sample_rate_hz: float = 1.0

    @classmethod
    def check_params(cls, prefix, params) -> None:
        """Raises SceneError: a carousel turning so slowly that the run would not hold one turn is left
        to the estimator (it says what is undetermined); a schedule with no dwell is refused here."""
        if not params.get("carousel_rate_deg_s") and params.get("positions", 4) > 1 and params.get("dwell_s", 60.0) <= 0:
            raise SceneError(f"{prefix}.dwell_s", params.get("dwell_s"), "must be > 0 for indexed positions")

    def horizontal_rate_rad_s(self) -> float:
        """n cos γ as simulated (rad/s): 0 without ``earth_rotation``."""
        return self.model_earth_rate() * math.cos(math.radians(self.site.latitude_deg))

    def amplitude_rad_s(self) -> float:
        """A = (1 + s) n cos γ, rad/s."""
        return (1.0 + 1e-6 * self.p.scale_factor_ppm) * self.horizontal_rate_rad_s()

    def scales(self, duration_s) -> Scales:
        """The Earth rate is the measured signal itself: its own scale ``sensed_rate_rad_s`` = n cos γ (the
        rate about the horizontal sensitive axis at its largest, rad/s), so ``earth_rotation`` reports a
        relative size of 1 in the rate gyro's words."""
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, duration_s=duration_s,
                      sensed_rate_rad_s=abs(self.horizontal_rate_rad_s()) or None)

    def predictions(self) -> dict:
        """The rate amplitude, the rate at each position, the sequence's length and the noise figures."""
        p, A = self.p, self.amplitude_rad_s()
        out = {"horizontal_earth_rate_rad_s": abs(self.horizontal_rate_rad_s()), "rate_amplitude_rad_s": abs(A),
               "bias_instability_gm_sigma_rad_s": p.bias_instability_deg_h * DEG_H / GM_ALLAN_PEAK,
               "bias_instability_allan_peak_s": GM_ALLAN_PEAK_TAU * p.bias_correlation_time_s,
               "arw_rad_rt_s": p.arw_deg_rt_h * DEG_RT_H}
        if p.carousel_rate_deg_s:
            out["carousel_period_s"] = 360.0 / abs(p.carousel_rate_deg_s)
        else:
            M = math.radians(p.mount_azimuth_deg)
            phis = [math.radians(p.first_index_deg) + 2 * math.pi * k / p.positions for k in range(p.positions)]
            out["sequence_duration_s"] = p.positions * (p.dwell_s + p.slew_s)
            out["position_rates_rad_s"] = [A * math.cos(M + f) for f in phis[:16]]
        return with_notes(out, self.missing_term_note(FRAME_RATE, "the gyro reads no Earth rate: no north"))

    def simulate(self, t, **options) -> Simulation:
        """The true index, rate and settled flag at ``t`` (closed form: no integration)."""
        t = np.asarray(t, dtype=float)
        if t.size > 1:
            self.sample_rate_hz = 1.0 / float(np.median(np.diff(t)))
        phi, settled = schedule(t, self.p)
        rate = self.amplitude_rad_s() * np.cos(math.radians(self.p.mount_azimuth_deg) + phi)
        traj = Trajectory(t=t, y=np.vstack([phi, rate]), nfev=0, wall_time_s=0.0, cpu_time_s=0.0, method="closed form")
        return Simulation(t, {INDEX: phi, RATE: rate, "settled": settled}, traj)
