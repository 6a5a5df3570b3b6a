"""The Cramér–Rao bounds of a scene's instruments as functions of the observation time T.

For every Earth-rate instrument of a scene the planner computes the Cramér–Rao bound of the
quantity its estimator measures, as a function of the observation time T (the scene's
``duration_s``, the same for every configuration), from the scene's own sensor model, and feeds the
bounds (at the scene's true values) into :func:`~gyro_instrument.estimators.latitude.solve_latitude`
with ``use_crlb=True`` to get the combined latitude and Earth-rate bounds (:class:`Planner`; the
planner, :mod:`.planner`, finds T for a target by bisection in log T). What is measured and which
laws convert it are the instrument's observation's (``MEASUREMENT``, the amplitude law, the period
and spin exponents of :class:`~gyro_instrument.instruments.observation.SwingRate`). Sources and
conventions:

* **gyroscopes** (directing plane, cone, locked or outer-fixed gimbal): the estimator fits
  offset, first and third harmonic and the frequency ω (:func:`.period.fit_oscillation`). The
  Fisher information of that model is computed exactly on the scene's sample grid t_i = i/f,
  i = 0..N−1 (N = ⌊T f⌋ + 1), with the column ∂y/∂ω = (t − t̄) ṡ(t)/ω (s the noise-free harmonic
  swing, amplitudes held at the mean time), noise variance σ² + q²/12 (quantization, when
  nonzero) and information × (1 − p) for a dropout fraction p. The measurement y = K/(gain ρ) =
  (π/T0)²/(gain ρ) has relative error 2 δ(ω F(a))/(ω F(a)) — the frequency and, because the
  estimator reduces the swing to small amplitude through F(a) = (2/π)K(sin(a/2)) with the fitted
  amplitude a, the amplitude too (its error falls only as T^-1/2, so it matters for long records)
  — plus the mean spin's δρ/ρ = σ_spin/(ρ √(N(1 − p))).
  Beyond :data:`EXACT_SAMPLES` samples the closed form for a pure sinusoid,
  var(ω̂) = 24 σ² / (A² Δt² N (N² − 1)) and var(â) = 2σ²/N (Rife & Boorstyn 1974, IEEE Trans. Inf.
  Theory 20(5) 591; :mod:`.period`), is used
  when the record holds at least :data:`CLOSED_FORM_CYCLES` cycles (the offset and the third
  harmonic then change the bound by < 1e-3 relative); with fewer cycles the exact sums are taken
  on a thinned grid (≥ 2000 points per cycle, information scaled by the stride).
* **pendulums**: the Foucault rate's bound of the estimator (:func:`.foucault.foucault_crlb_small_swing_rad_s`):
  the plane's rate, var(m̂) ≥ 24 σ² / (α² N T²), and the areal velocity the ellipse correction
  needs, var⟨H⟩ ≥ 2σ²α²ω²/N, through k = (m − (3/8)⟨H⟩)/(1 − (3/8)α²/2); α the swing amplitude
  (sin of the release deflection), σ on each deflection component.
* **short records**: the bounds are computed, not assumed, below two cycles too (there the
  amplitude and phase are not separated from ω and the bound grows faster than T^-3/2); the
  estimator itself needs two cycles of every gyroscope (``fit_oscillation``) and three periods of a
  pendulum (``estimate_foucault``), so a planned T is never shorter than that record.
* **counting** (Quet's literal method, :func:`.period.count_oscillations`): σ(T_swing) =
  T_swing / (N √3) with N = T / T_swing swings, so σ(y)/y = 2 T_swing / (√3 T) — it falls as
  T^-1 only; the pendulum's rate is not a period and is left out of the counting plan.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.estimators.foucault import foucault_crlb_small_swing_rad_s
from gyro_instrument.estimators.latitude import RateMeasurement, solve_latitude
from gyro_instrument.estimators.period import EstimationError, fit_oscillation
from gyro_instrument.instruments.measurement import declared_kinds, kind, load as load_kinds
from gyro_instrument.instruments.observation import SWING_RATE, SwingRate

#: Up to this many samples the Fisher information is summed exactly on the sample grid.
EXACT_SAMPLES = 200_000
#: Beyond :data:`EXACT_SAMPLES`, the closed form is used from this many cycles in the record.
CLOSED_FORM_CYCLES = 100.0
#: The estimator's shortest records: cycles of a gyroscope swing (``fit_oscillation``) and
#: periods of a pendulum (``estimate_foucault``).
GYRO_MIN_CYCLES, PENDULUM_MIN_PERIODS = 2.0, 3.0
#: Longest observation the planner searches (about 32 years), s.
MAX_OBSERVATION_S = 1.0e9
YEAR_S = 365.25 * 86400.0


@dataclass
class InstrumentModel:
    """What the planner knows of one Earth-rate instrument (angles rad, rates rad/s, times s).

    ``kind`` (the observation's ``MEASUREMENT``) 'gyro': ``omega`` the swing's angular frequency (one
    full period 2π/ω = 2 T_swing), ``coef`` (a1, b1, a3, b3) the noise-free harmonic swing on t from
    0, ``spin`` the rotor's spin; 'pendulum': ``omega`` its swing frequency and ``amplitude`` α.
    ``observation``: the instrument's, whose laws (amplitude law, spin and period exponents) the
    bound uses. ``axis``: ``geometry`` is a sensitive axis (:class:`~.latitude.RateMeasurement`).
    Another rate kind's model (its ``probe``) carries ``name``, ``kind``, ``value``, ``geometry``,
    ``axis`` and ``min_record_s`` too."""

    name: str
    kind: str
    omega: float
    value: float
    geometry: tuple = (0.0, 0.0, 1.0)
    coef: tuple = (0.0, 0.0, 0.0, 0.0)
    amplitude: float = 0.0
    spin: float = 0.0
    label: str = ""
    observation: object = field(default=None, repr=False, compare=False)
    axis: bool = False

    @property
    def min_record_s(self) -> float:
        cycles = GYRO_MIN_CYCLES if self.kind == SWING_RATE else PENDULUM_MIN_PERIODS
        return cycles * 2.0 * math.pi / self.omega


def instrument_models(scene, kinds=None) -> tuple:
    """(models, skipped): a model per measurement of ``kinds`` (default :func:`rate_kinds`: the
    Earth-rate instruments, :class:`InstrumentModel`) each instrument of ``scene`` declares
    (:func:`~gyro_instrument.instruments.measurement.declared_kinds`), from its kind's ``probe`` (for
    a swing a noise-free simulation of a few periods, its amplitudes and frequency as the fit sees
    them), and name -> reason for the instruments that give none."""
    kinds = rate_kinds() if kinds is None else tuple(kinds)
    from gyro_instrument.scenes import build_instruments
    models, skipped = [], {}
    for name, inst in build_instruments(scene).items():
        obs = inst.observation()
        reason = obs.unmeasured_reason()
        found = False
        for k in (k for k in declared_kinds(obs) if k in kinds) if reason is None else ():
            model, why = kind(k).probe(scene, obs)
            if model is not None:
                models.append(model)
                found = True
            else:
                reason = why
        if not found:
            skipped[name] = reason or f"measures none of {', '.join(kinds)}"
    return models, skipped


def plane_model(scene, obs) -> tuple:
    """A swing plane's model: its period and release amplitude α = sin θ0, k = n sin γ."""
    site = scene.site
    value = site.earth_rate_rad_s * math.sin(site.latitude_rad)
    return InstrumentModel(obs.name, obs.MEASUREMENT, 2.0 * math.pi / obs.swing_period_s(), value,
                           amplitude=obs.release_amplitude(), label="pendulum", observation=obs), None


#: The most samples a swing's noise-free probe simulates (8 MB a channel): a swing longer than
#: PROBE_MAX_SAMPLES / (8.8 f) s (a rotor all but stopped) gets no model, with the reason.
PROBE_MAX_SAMPLES = 1_000_000


def swing_model(scene, obs) -> tuple:
    """A swing's model from a noise-free simulation of four periods (amplitudes and frequency as the
    fit sees them); (None, reason) without a swing to time."""
    inst, site = obs.instrument, scene.site
    T0 = inst.predictions().get("swing_duration_small_s")
    if T0 is None or not math.isfinite(T0) or T0 <= 0:
        return None, f"no swing to time: {obs.null_reason}"
    rate = scene.sample_rate_hz
    n = math.ceil(8.0 * T0 * 1.1 * rate)
    if n > PROBE_MAX_SAMPLES:
        return None, (f"a swing of {T0:.6g} s: the noise-free probe of four periods would take {n:.3g} samples at "
                      f"{rate:g} Hz (more than {PROBE_MAX_SAMPLES:g}); no model to plan with")
    t = np.arange(0.0, 8.0 * T0 * 1.1, 1.0 / rate)
    y = inst.simulate(t).columns[obs.angle_channel]
    try:
        fit = fit_oscillation(t, y, harmonics=(1, 3))
    except EstimationError as exc:
        return None, f"no oscillation in a noise-free probe: {exc}"
    w = fit.omega_rad_s
    X = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t), np.cos(3 * w * t), np.sin(3 * w * t)])
    coef = np.linalg.lstsq(X, y, rcond=None)[0][1:]
    meas = RateMeasurement(obs.name, obs.MEASUREMENT, 0.0, 1.0, obs.normal_enu)
    value = site.earth_rate_rad_s * float(meas.shape(site.latitude_rad))
    return InstrumentModel(obs.name, obs.MEASUREMENT, w, value, obs.normal_enu, tuple(float(c) for c in coef),
                           spin=obs.model.spin_rate_rad_s, label=obs.label, observation=obs), None


def rate_kinds() -> tuple:
    """The registered kinds whose bounds combine into a latitude and an Earth rate (``RATE``)."""
    return tuple(k for k, v in load_kinds().items() if v.RATE)


def measured_kinds(obs) -> tuple:
    """Every measurement kind an observation declares: its ``MEASUREMENT`` and ``ALSO_MEASURES``."""
    return declared_kinds(obs)


@dataclass(frozen=True)
class SensorSpec:
    """The sensor as the bound sees it: σ (rad), q (rad), spin σ (rad/s), dropout p, rate f (Hz)."""

    noise_rad: float
    quantization_rad: float
    spin_noise_rad_s: float
    dropout_fraction: float
    rate_hz: float

    @classmethod
    def from_scene(cls, scene) -> "SensorSpec":
        s = dict(scene.sensor)
        return cls(s.get("noise_rad", 1e-4), s.get("quantization_rad", 0.0), s.get("spin_noise_rad_s", 0.0),
                   s.get("dropout_fraction", 0.0), scene.sample_rate_hz)

    @property
    def sigma_rad(self) -> float:
        """√(σ² + q²/12): quantization as extra white noise (period.py's module docstring)."""
        return math.sqrt(self.noise_rad ** 2 + self.quantization_rad ** 2 / 12.0)

    def scaled(self, noise=1.0, rate=1.0) -> "SensorSpec":
        return SensorSpec(self.noise_rad * noise, self.quantization_rad, self.spin_noise_rad_s * noise,
                          self.dropout_fraction, self.rate_hz * rate)


def samples(T, rate_hz) -> int:
    """N = ⌊T f⌋ + 1, the scene's sample grid (:func:`gyro_instrument.core.scene.sample_times`)."""
    return int(math.floor(T * rate_hz + 1e-9)) + 1


def sine_fit_covariance(T, rate_hz, omega, coef, sigma, keep=1.0) -> tuple:
    """Inverse Fisher information of ``fit_oscillation``'s model (offset, first and third harmonic, ω)
    for the swing ``coef`` = (a1, b1, a3, b3) on t_i = i/f over T, white noise σ, a fraction
    ``keep`` of the samples kept. Returns (var ω̂ (rad²/s²), var â1 (rad²), cov(ω̂, â1), method);
    infinite variances when the record has fewer than 7 samples."""
    n = samples(T, rate_hz)
    dt = 1.0 / rate_hz
    a1, b1, a3, b3 = coef
    amp = math.hypot(a1, b1)
    if sigma <= 0:
        return 0.0, 0.0, 0.0, "noise-free sensor"
    if n < 7 or amp <= 0:
        return math.inf, math.inf, 0.0, "too few samples"
    span = (n - 1) * dt
    cycles = omega * span / (2.0 * math.pi)
    if n > EXACT_SAMPLES and cycles >= CLOSED_FORM_CYCLES:
        var_w = 24.0 * sigma ** 2 / (keep * amp ** 2 * dt ** 2 * n * (n * n - 1.0))
        return var_w, 2.0 * sigma ** 2 / (keep * n), 0.0, "closed form (pure sinusoid)"
    stride = max(1, math.ceil(n / EXACT_SAMPLES))
    t = np.arange(0, n, stride) * dt
    tau = t - (n - 1) * dt / 2.0
    c1, s1, c3, s3 = np.cos(omega * t), np.sin(omega * t), np.cos(3 * omega * t), np.sin(3 * omega * t)
    sdot = omega * (-a1 * s1 + b1 * c1) + 3 * omega * (-a3 * s3 + b3 * c3)
    # (cos hωt, sin hωt) span the same space as the fit's (cos hωτ, sin hωτ), τ = t − t̄; the ω column
    # holds the amplitudes at t̄ fixed, as the fit does: ∂y/∂ω = τ ṡ(t)/ω
    X = np.column_stack([tau * sdot / omega, np.ones_like(t), c1, s1, c3, s3])
    scale = np.linalg.norm(X, axis=0)
    scale[scale == 0] = 1.0
    Xs = X / scale
    info = (Xs.T @ Xs) * stride * keep / sigma ** 2
    try:
        cov = np.linalg.inv(info) / np.outer(scale, scale)
    except np.linalg.LinAlgError:
        return math.inf, math.inf, 0.0, "singular"
    # â1 = |first harmonic|: gradient (a1, b1)/A in the (cos ωt, sin ωt) columns
    g = np.array([0.0, 0.0, a1 / amp, b1 / amp, 0.0, 0.0])
    var_a = float(g @ cov @ g)
    cov_wa = float(cov[0] @ g)
    method = "exact Fisher" + (f" (grid thinned by {stride})" if stride > 1 else "")
    return float(cov[0, 0]), var_a, cov_wa, method


def instrument_sigma(m, T, sensor) -> tuple:
    """1-σ Cramér–Rao bound on the measurement of ``m`` over T s, and how: its kind's ``bound``."""
    return kind(m.kind).bound(m, T, sensor)


def plane_sigma(m, T, sensor) -> tuple:
    """1-σ Cramér–Rao bound of a swing plane's rate k (rad/s) over T s, and how."""
    keep = 1.0 - sensor.dropout_fraction
    n = samples(T, sensor.rate_hz) * keep
    if n < 3 or m.amplitude <= 0:
        return math.inf, "too few samples"
    span = (samples(T, sensor.rate_hz) - 1) / sensor.rate_hz
    return foucault_crlb_small_swing_rad_s(sensor.sigma_rad, m.amplitude, m.omega, n, span), "Foucault rate bound"


def swing_sigma(m, T, sensor) -> tuple:
    """1-σ Cramér–Rao bound of a swing's rate y = n s(γ) (rad/s) over T s, and how."""
    keep = 1.0 - sensor.dropout_fraction
    sigma = sensor.sigma_rad
    var_w, var_a, cov_wa, how = sine_fit_covariance(T, sensor.rate_hz, m.omega, m.coef, sigma, keep)
    if not math.isfinite(var_w):
        return math.inf, how
    obs = m.observation
    amplitude_factor = finite_amplitude_factor if obs is None else obs.amplitude_factor
    amp = math.hypot(m.coef[0], m.coef[1])
    h = 1e-6 * max(amp, 1e-6)
    dlnF = (math.log(amplitude_factor(amp + h)) - math.log(amplitude_factor(max(amp - h, 0.0)))) / (2 * h)
    var_ln = var_w / m.omega ** 2 + dlnF ** 2 * var_a + 2.0 * dlnF * cov_wa / m.omega
    var_spin = 0.0
    if sensor.spin_noise_rad_s and m.spin:
        var_spin = (sensor.spin_noise_rad_s / m.spin) ** 2 / (samples(T, sensor.rate_hz) * keep)
    rel2 = (obs or SwingRate).rate_relative_variance(var_ln, var_spin)
    return abs(m.value) * math.sqrt(rel2), how


def counting_sigma(m, T) -> float:
    """σ of y from Quet's counting over T s: 2 T_swing / (√3 T) relative (:func:`.period.count_oscillations`)."""
    t_swing = math.pi / m.omega
    return abs(m.value) * 2.0 * t_swing / (math.sqrt(3.0) * T)


def combined(models, sigmas, hemisphere=None, latitude_rad=None, known=None) -> dict:
    """Combined 1-σ bounds from per-instrument σ: dict with latitude_rad, earth_rate_rad_s (None with
    ``*_reason`` when not determined), via ``solve_latitude(..., use_crlb=True)``. ``known``: the
    keyword arguments ``earth_rate``, ``n_known``, ``n_source`` of :func:`solve_latitude`, as
    ``estimate`` passes them (a pendulum alone: the latitude with n known)."""
    # a noise-free sensor has a zero bound: keep its structure (what it can determine) with a vanishing σ
    sigmas = [s if s > 0 else 1e-20 * abs(m.value) for m, s in zip(models, sigmas)]
    meas = [RateMeasurement(m.name, m.kind, m.value, s, m.geometry, True, s, axis=m.axis)
            for m, s in zip(models, sigmas) if math.isfinite(s) and s > 0]
    if not meas:
        return {"latitude_rad": None, "earth_rate_rad_s": None,
                "latitude_reason": "no instrument can measure yet (record too short)",
                "earth_rate_reason": "no instrument can measure yet (record too short)"}
    sol = solve_latitude(meas, use_crlb=True, hemisphere=hemisphere, **(known or {}))
    out = {"latitude_rad": sol.latitude_sigma_rad, "earth_rate_rad_s": sol.earth_rate_sigma_rad_s}
    if sol.earth_rate_known:
        out["earth_rate_reason"] = f"the Earth rate is not estimated: {sol.earth_rate_basis}"
    if sol.latitude_rad is None:
        out["latitude_reason"] = sol.reason
        if sol.earth_rate_sigma_rad_s is None:
            out["earth_rate_reason"] = sol.reason
    elif sol.latitude_sigma_rad is None:
        # near a pole or the equator: no local Gaussian σ; the 1-σ interval's half-width stands in
        out["latitude_rad"] = 0.5 * (sol.latitude_hi_rad - sol.latitude_lo_rad)
        out["latitude_note"] = f"{sol.sigma_reason}: the 1-sigma interval's half-width is planned instead"
    return out


class Planner:
    """The bounds of one scene's instruments as functions of the observation time T (s)."""

    def __init__(self, models, sensor, hemisphere=None, known=None):
        self.models, self.sensor, self.hemisphere = models, sensor, hemisphere
        #: how ``estimate`` treats the Earth rate (:func:`combined`'s ``known``)
        self.known = known

    def min_record_s(self) -> float:
        return max(m.min_record_s for m in self.models)

    def bounds(self, T, counting=False) -> tuple:
        """Combined bounds at T (dict, see :func:`combined`) and the per-instrument σ (name -> rad/s)."""
        models = [m for m in self.models if not counting or kind(m.kind).CLASSIC == "gyro"]
        sig = [counting_sigma(m, T) if counting else instrument_sigma(m, T, self.sensor)[0] for m in models]
        return combined(models, sig, self.hemisphere, known=self.known), dict(zip((m.name for m in models), sig))

    def sigma(self, quantity, T, counting=False) -> float | None:
        return self.bounds(T, counting)[0].get(f"{quantity}_rad" if quantity == "latitude" else "earth_rate_rad_s")

    def solve(self, quantity, target, counting=False) -> tuple:
        """Shortest T (s) with the bound ≤ ``target`` (SI), the estimator's minimum record included:
        (T or None, note). Bisection in log T to 1e-4 relative."""
        t_min = max(m.min_record_s for m in self.models if kind(m.kind).CLASSIC == "gyro") if counting else self.min_record_s()
        s0 = self.sigma(quantity, t_min, counting)
        if s0 is None:
            return None, self.bounds(t_min, counting)[0].get(f"{quantity}_reason", "not determined")
        if s0 <= target:
            return t_min, "the estimator's shortest record already meets the target"
        return shortest_time(lambda T: self.sigma(quantity, T, counting), t_min, target, 4.0, 1e-4)

    def slope(self, quantity, T, factor=2.0) -> float | None:
        """d ln σ / d ln T around T, the secant from T/factor to T·factor (−3/2 in the long-record
        regime; a secant, because the exact bound ripples with the phase at which the record ends)."""
        a, b = self.sigma(quantity, T / factor), self.sigma(quantity, T * factor)
        if not a or not b:
            return None
        return (math.log(b) - math.log(a)) / (2.0 * math.log(factor))


def shortest_time(sigma_of, t_min, target, grow, rel) -> tuple:
    """Shortest T > ``t_min`` with ``sigma_of(T)`` (None: not determined) ≤ ``target``, σ(t_min) being
    above it: T × ``grow`` until met (at most :data:`MAX_OBSERVATION_S`), then bisection in log T to
    ``rel``. Returns (T or None, note)."""
    def met(T):
        s = sigma_of(T)
        return s is not None and s <= target
    lo = hi = t_min
    while True:
        hi = min(hi * grow, MAX_OBSERVATION_S)
        if met(hi):
            break
        if hi >= MAX_OBSERVATION_S:
            return None, f"not reached within {MAX_OBSERVATION_S:g} s ({MAX_OBSERVATION_S / YEAR_S:.0f} years)"
        lo = hi
    while hi / lo > 1.0 + rel:
        mid = math.sqrt(lo * hi)
        if met(mid):
            hi = mid
        else:
            lo = mid
    return hi, ""

