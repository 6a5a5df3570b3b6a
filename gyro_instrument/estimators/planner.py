"""How long must I observe? The observation time a scene's instruments need for a target accuracy.

For every Earth-rate instrument of a scene the planner computes the Cramér–Rao bound of the
quantity its estimator measures, as a function of the observation time T (the scene's
``duration_s``, the same for every configuration), from the scene's own sensor model, and feeds the
bounds (at the scene's true values) into :func:`~gyro_instrument.estimators.latitude.solve_latitude`
with ``use_crlb=True`` to get the combined latitude and Earth-rate bounds. T for each target comes
from a bisection in log T. Sources and conventions:

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
  var(ω̂) = 24 σ² / (A² Δt² N (N² − 1)) and var(â) = 2σ²/N (physics_notes, 'Estimation'), is used
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
* **floor**: a noise-free run of the scene at the planned T (sensor noise, quantization, spin noise
  and dropouts 0) gives the estimator's bias, the way ``bench``'s systematic-floor study does; a
  target below |bias| is unreachable, and switching the scene's effects off one at a time in the
  noise-free run says which one sets the floor.
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.estimators.latitude import RateMeasurement, solve_latitude
from gyro_instrument.estimators.period import EstimationError, fit_oscillation

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
ARCSEC_RAD = math.pi / (180.0 * 3600.0)
DEG_H_RAD_S = math.pi / (180.0 * 3600.0)

#: Target names: quantity, the factor from the unit to SI (rad or rad/s).
TARGETS = {"latitude_arcsec": ("latitude", ARCSEC_RAD), "latitude_deg": ("latitude", math.pi / 180.0),
           "latitude_rad": ("latitude", 1.0), "earth_rate_rad_s": ("earth_rate", 1.0),
           "earth_rate_deg_h": ("earth_rate", DEG_H_RAD_S)}


def parse_targets(specs) -> list:
    """``["latitude_arcsec=1", "earth_rate_rad_s=1e-10"]`` -> list of (name, value in its unit, SI value).

    Raises
    ------
    SceneError
        On ``--target``: not NAME=VALUE, an unknown name (with the closest one), a value that is not
        a positive finite number, or no target at all.
    """
    from gyro_instrument.core.params import unknown_key_hint
    if not specs:
        raise SceneError("--target", None, f"is required (repeatable), e.g. --target latitude_arcsec=1; names: "
                                           f"{', '.join(TARGETS)}")
    out = []
    for spec in specs:
        name, sep, text = str(spec).partition("=")
        name = name.strip()
        if not sep:
            raise SceneError("--target", spec, f"must be NAME=VALUE, e.g. latitude_arcsec=1; names: {', '.join(TARGETS)}")
        if name not in TARGETS:
            raise SceneError("--target", spec, unknown_key_hint(name, TARGETS, "target"))
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise SceneError(f"--target {name}", text, "must be a positive finite number (the 1-sigma accuracy wanted)")
        out.append((name, value, value * TARGETS[name][1]))
    return out


@dataclass
class InstrumentModel:
    """What the planner knows of one Earth-rate instrument (angles rad, rates rad/s, times s).

    ``kind`` 'gyro': ``omega`` the swing's angular frequency (one full period 2π/ω = 2 T_swing),
    ``coef`` (a1, b1, a3, b3) the noise-free harmonic swing on t from 0, ``spin`` the rotor's
    spin; 'pendulum': ``omega`` its swing frequency and ``amplitude`` α."""

    name: str
    kind: str
    omega: float
    value: float
    geometry: tuple = (0.0, 0.0, 1.0)
    coef: tuple = (0.0, 0.0, 0.0, 0.0)
    amplitude: float = 0.0
    spin: float = 0.0
    label: str = ""

    @property
    def min_record_s(self) -> float:
        cycles = GYRO_MIN_CYCLES if self.kind == "gyro" else PENDULUM_MIN_PERIODS
        return cycles * 2.0 * math.pi / self.omega


def instrument_models(scene) -> tuple:
    """(models, skipped): :class:`InstrumentModel` per Earth-rate instrument of ``scene``, probed by
    a noise-free simulation of four periods (its amplitudes and frequency, as the fit sees them),
    and name -> reason for the instruments that give no Earth-rate measurement."""
    from gyro_instrument.scenes import build_instruments
    site = scene.site
    n = site.earth_rate_rad_s
    models, skipped = [], {}
    for name, inst in build_instruments(scene).items():
        if not inst.has("earth_rotation") and "earth_rotation" in inst.SUPPORTED_EFFECTS:
            skipped[name] = "earth_rotation is not simulated for it: it measures no Earth rate"
            continue
        if inst.IS_PENDULUM:
            pred = inst.predictions()
            alpha = math.sin(math.radians(inst.p.initial_deflection_deg))
            period = 4.0 * pred["quarter_period_s"] if "quarter_period_s" in pred else \
                2.0 * math.pi * math.sqrt(inst.pendulum_length_m() / site.gravity_m_s2)
            models.append(InstrumentModel(name, "pendulum", 2.0 * math.pi / period, n * math.sin(site.latitude_rad),
                                          amplitude=alpha, label="pendulum"))
            continue
        model = inst.directing_model()
        if model is None:
            skipped[name] = f"{inst.type_name} has no directing line: it gives no Earth-rate measurement"
            continue
        T0 = inst.predictions().get("swing_duration_small_s")
        if T0 is None or not math.isfinite(T0) or T0 <= 0:
            skipped[name] = f"no swing to time: {model.null_reason}"
            continue
        rate = scene.sample_rate_hz
        t = np.arange(0.0, 8.0 * T0 * 1.1, 1.0 / rate)
        y = inst.simulate(t).columns[model.angle_channel]
        try:
            fit = fit_oscillation(t, y, harmonics=(1, 3))
        except EstimationError as exc:
            skipped[name] = f"no oscillation in a noise-free probe: {exc}"
            continue
        w = fit.omega_rad_s
        X = np.column_stack([np.ones_like(t), np.cos(w * t), np.sin(w * t), np.cos(3 * w * t), np.sin(3 * w * t)])
        coef = np.linalg.lstsq(X, y, rcond=None)[0][1:]
        meas = RateMeasurement(name, "gyro", 0.0, 1.0, tuple(model.normal_enu))
        value = n * float(meas.shape(site.latitude_rad))
        models.append(InstrumentModel(name, "gyro", w, value, tuple(model.normal_enu), tuple(float(c) for c in coef),
                                      spin=model.spin_rate_rad_s, label=model.label))
    return models, skipped


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
    """1-σ Cramér–Rao bound on the measurement of ``m`` (rad/s: y = n s(γ) or k) over T s, and how."""
    keep = 1.0 - sensor.dropout_fraction
    sigma = sensor.sigma_rad
    if m.kind == "pendulum":
        n = samples(T, sensor.rate_hz) * keep
        if n < 3 or m.amplitude <= 0:
            return math.inf, "too few samples"
        span = (samples(T, sensor.rate_hz) - 1) / sensor.rate_hz
        from gyro_instrument.estimators.foucault import foucault_crlb_small_swing_rad_s
        return foucault_crlb_small_swing_rad_s(sigma, m.amplitude, m.omega, n, span), "Foucault rate bound"
    var_w, var_a, cov_wa, how = sine_fit_covariance(T, sensor.rate_hz, m.omega, m.coef, sigma, keep)
    if not math.isfinite(var_w):
        return math.inf, how
    amp = math.hypot(m.coef[0], m.coef[1])
    h = 1e-6 * max(amp, 1e-6)
    dlnF = (math.log(finite_amplitude_factor(amp + h)) - math.log(finite_amplitude_factor(max(amp - h, 0.0)))) / (2 * h)
    var_ln = var_w / m.omega ** 2 + dlnF ** 2 * var_a + 2.0 * dlnF * cov_wa / m.omega
    rel2 = 4.0 * max(var_ln, 0.0)
    if sensor.spin_noise_rad_s and m.spin:
        rel2 += (sensor.spin_noise_rad_s / m.spin) ** 2 / (samples(T, sensor.rate_hz) * keep)
    return abs(m.value) * math.sqrt(rel2), how


def counting_sigma(m, T) -> float:
    """σ of y from Quet's counting over T s: 2 T_swing / (√3 T) relative (:func:`.period.count_oscillations`)."""
    t_swing = math.pi / m.omega
    return abs(m.value) * 2.0 * t_swing / (math.sqrt(3.0) * T)


def combined(models, sigmas, hemisphere=None, latitude_rad=None) -> dict:
    """Combined 1-σ bounds from per-instrument σ: dict with latitude_rad, earth_rate_rad_s (None with
    ``*_reason`` when not determined), via ``solve_latitude(..., use_crlb=True)``."""
    # a noise-free sensor has a zero bound: keep its structure (what it can determine) with a vanishing σ
    sigmas = [s if s > 0 else 1e-20 * abs(m.value) for m, s in zip(models, sigmas)]
    meas = [RateMeasurement(m.name, m.kind, m.value, s, m.geometry, True, s)
            for m, s in zip(models, sigmas) if math.isfinite(s) and s > 0]
    if not meas:
        return {"latitude_rad": None, "earth_rate_rad_s": None,
                "latitude_reason": "no instrument can measure yet (record too short)",
                "earth_rate_reason": "no instrument can measure yet (record too short)"}
    sol = solve_latitude(meas, use_crlb=True, hemisphere=hemisphere)
    out = {"latitude_rad": sol.latitude_sigma_rad, "earth_rate_rad_s": sol.earth_rate_sigma_rad_s}
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

    def __init__(self, models, sensor, hemisphere=None):
        self.models, self.sensor, self.hemisphere = models, sensor, hemisphere

    def min_record_s(self) -> float:
        return max(m.min_record_s for m in self.models)

    def bounds(self, T, counting=False) -> tuple:
        """Combined bounds at T (dict, see :func:`combined`) and the per-instrument σ (name -> rad/s)."""
        models = [m for m in self.models if not counting or m.kind == "gyro"]
        sig = [counting_sigma(m, T) if counting else instrument_sigma(m, T, self.sensor)[0] for m in models]
        return combined(models, sig, self.hemisphere), dict(zip((m.name for m in models), sig))

    def sigma(self, quantity, T, counting=False) -> float | None:
        return self.bounds(T, counting)[0].get(f"{quantity}_rad" if quantity == "latitude" else "earth_rate_rad_s")

    def solve(self, quantity, target, counting=False) -> tuple:
        """Shortest T (s) with the bound ≤ ``target`` (SI), the estimator's minimum record included:
        (T or None, note). Bisection in log T to 1e-4 relative."""
        t_min = max(m.min_record_s for m in self.models if m.kind == "gyro") if counting else self.min_record_s()
        s0 = self.sigma(quantity, t_min, counting)
        if s0 is None:
            return None, self.bounds(t_min, counting)[0].get(f"{quantity}_reason", "not determined")
        if s0 <= target:
            return t_min, "the estimator's shortest record already meets the target"
        lo, hi = t_min, t_min
        while True:
            hi = min(hi * 4.0, MAX_OBSERVATION_S)
            s = self.sigma(quantity, hi, counting)
            if s is not None and s <= target:
                break
            if hi >= MAX_OBSERVATION_S:
                return None, f"not reached within {MAX_OBSERVATION_S:g} s ({MAX_OBSERVATION_S / YEAR_S:.0f} years)"
            lo = hi
        while hi / lo > 1.0 + 1e-4:
            mid = math.sqrt(lo * hi)
            s = self.sigma(quantity, mid, counting)
            if s is not None and s <= target:
                hi = mid
            else:
                lo = mid
        return hi, ""

    def slope(self, quantity, T, factor=2.0) -> float | None:
        """d ln σ / d ln T around T, the secant from T/factor to T·factor (−3/2 in the long-record
        regime; a secant, because the exact bound ripples with the phase at which the record ends)."""
        a, b = self.sigma(quantity, T / factor), self.sigma(quantity, T * factor)
        if not a or not b:
            return None
        return (math.log(b) - math.log(a)) / (2.0 * math.log(factor))


# ----------------------------------------------------------------------------- the plan
#: Default sensitivity factors: sensor noise ×0.1 and ×10, sample rate ×2 and ×0.5.
NOISE_FACTORS, RATE_FACTORS = (0.1, 10.0), (2.0, 0.5)


def _quantity_value(quantity, si, name):
    """SI value back in the unit of target ``name``."""
    return None if si is None else si / TARGETS[name][1]


#: The overrides that switch the sensor off (the same as ``bench.effect_cost.NOISE_FREE``, which the
#: systematic-floor study uses; the bench is a layer above and cannot be imported here).
NOISE_FREE = ("sensor.noise_rad=0", "sensor.quantization_rad=0", "sensor.spin_noise_rad_s=0",
              "sensor.dropout_fraction=0")


def noise_free_overrides() -> list:
    """The overrides that switch the sensor off (as ``bench``'s systematic-floor study does)."""
    return list(NOISE_FREE)


def plan(scene_arg, overrides=(), targets=(), noise_factors=NOISE_FACTORS, rate_factors=RATE_FACTORS, floor=True,
         progress=None) -> dict:
    """The plan for ``scene_arg`` (shipped name or YAML path) with ``overrides``: per target, the
    observation time per configuration, the bound's dependence on T, the systematic floor at that T,
    the sensitivity to the sensor's noise and rate, and Quet's counting for the same target.

    Parameters
    ----------
    scene_arg : str
    overrides : sequence of str
        ``--set`` strings.
    targets : sequence of (name, value, SI value)
        From :func:`parse_targets`.
    noise_factors, rate_factors : sequence of float
        Factors on the sensor's noise (σ and spin σ) and on the sample rate for the sensitivity rows.
    floor : bool
        Run the noise-free estimate at each planned T (one simulation per target, more when the floor
        exceeds the target: one per effect, to name it).

    Returns
    -------
    dict (JSON-ready but for non-finite floats: pass through ``cli.to_jsonable``)

    Raises
    ------
    SceneError
        Bad scene or overrides; a scene with no Earth-rate instrument; a factor that is not positive.
    """
    from gyro_instrument.scenes import load_scene
    for what, factors in (("--noise-factor", noise_factors), ("--rate-factor", rate_factors)):
        for f in factors:
            if not (isinstance(f, (int, float)) and math.isfinite(f) and f > 0):
                raise SceneError(what, f, "must be a positive finite number")
    scene = load_scene(scene_arg, list(overrides))
    models, skipped = instrument_models(scene)
    if not models:
        raise SceneError("scene", scene_arg, "has no instrument that measures an Earth rate (a gyroscope with a "
                                             "directing line or a pendulum, with earth_rotation): nothing to plan"
                         + (f" ({'; '.join(f'{k}: {v}' for k, v in skipped.items())})" if skipped else ""))
    sensor = SensorSpec.from_scene(scene)
    hemi = scene.estimator.get("hemisphere")
    planner = Planner(models, sensor, hemi)
    out = {"scene": scene.name, "source": scene.source, "overrides": list(overrides),
           "latitude_deg": scene.site.latitude_deg, "earth_rate_rad_s": scene.site.earth_rate_rad_s,
           "sensor": {"noise_rad": sensor.noise_rad, "quantization_rad": sensor.quantization_rad,
                      "effective_noise_rad": sensor.sigma_rad, "spin_noise_rad_s": sensor.spin_noise_rad_s,
                      "dropout_fraction": sensor.dropout_fraction, "sample_rate_hz": sensor.rate_hz},
           "instruments": {m.name: _model_dict(m) for m in models},
           "not_used": skipped, "min_record_s": planner.min_record_s(), "targets": []}
    for name, value, si in targets:
        if progress:
            progress(f"planning {name} = {value:g}")
        out["targets"].append(_plan_target(scene_arg, overrides, planner, name, value, si, noise_factors,
                                           rate_factors, floor))
    return out


def _model_dict(m):
    d = {"kind": m.kind, "configuration": m.label, "measures": ("n sin(omega), rad/s" if m.kind == "gyro"
                                                              else "Foucault rate k = n sin(latitude), rad/s"),
         "true_value_rad_s": m.value, "period_s": 2 * math.pi / m.omega, "min_record_s": m.min_record_s}
    if m.kind == "gyro":
        d["swing_duration_s"] = math.pi / m.omega
        d["amplitude_rad"] = math.hypot(m.coef[0], m.coef[1])
    else:
        d["amplitude_rad"] = m.amplitude
    return d


def _plan_target(scene_arg, overrides, planner, name, value, si, noise_factors, rate_factors, floor):
    quantity = TARGETS[name][0]
    T, note = planner.solve(quantity, si)
    entry = {"target": name, "value": value, "quantity": quantity}
    if T is None:
        entry.update({"observation_s": None, "reason": note})
        return entry
    comb, per = planner.bounds(T)
    sig = comb["latitude_rad" if quantity == "latitude" else "earth_rate_rad_s"]
    entry.update({"observation_s": T, "samples_per_instrument": samples(T, planner.sensor.rate_hz),
                  "planned_sigma": _quantity_value(quantity, sig, name),
                  "instrument_sigma_rad_s": per, "note": note or None,
                  "limited_by": ("the estimator's shortest record" if note else "noise (Cramer-Rao bound)")})
    if comb.get("latitude_note") and quantity == "latitude":
        entry["latitude_note"] = comb["latitude_note"]
    entry["methods"] = {m.name: instrument_sigma(m, T, planner.sensor)[1] for m in planner.models}
    entry["dependence"] = _dependence(planner, quantity, name, T)
    entry["sensitivity"] = _sensitivity(planner, quantity, si, T, noise_factors, rate_factors)
    entry["counting"] = _counting(planner, quantity, si)
    if floor:
        entry["floor"] = systematic_floor(scene_arg, overrides, T, quantity, si, name)
    return entry


def _dependence(planner, quantity, name, T):
    """σ(T) on a log grid from a quarter of the shortest record to 4 × the plan, and the local slope."""
    t_min = planner.min_record_s()
    grid = sorted({*np.geomspace(t_min / 4.0, max(4.0 * T, 2 * t_min), 9).tolist(), T, t_min})
    rows = []
    for t in grid:
        s = planner.sigma(quantity, t)
        rows.append({"observation_s": t, "sigma": _quantity_value(quantity, s, name),
                     "regime": "short record (below the estimator's minimum)" if t < t_min * (1 - 1e-9)
                     else "fit"})
    return {"curve": rows, "slope_at_plan": planner.slope(quantity, T),
            "slope_short_record": planner.slope(quantity, t_min / 2.0, factor=1.25),
            "law": "sigma ~ T^-3/2 once two cycles are in the record (24 sigma^2 / (A^2 dt^2 N (N^2 - 1)))"}


def _sensitivity(planner, quantity, si, T, noise_factors, rate_factors):
    """T for the sensor's noise or rate changed by a factor, replanned; beside the T^-3/2 law
    T ∝ (σ²/f)^(1/3) (σ² T^-3 / f fixed)."""
    rows = []
    for what, factors in (("noise", noise_factors), ("rate", rate_factors)):
        for f in factors:
            sensor = planner.sensor.scaled(noise=f) if what == "noise" else planner.sensor.scaled(rate=f)
            p = Planner(planner.models, sensor, planner.hemisphere)
            T2, note = p.solve(quantity, si)
            law = T * (f ** 2) ** (1 / 3) if what == "noise" else T * (1.0 / f) ** (1 / 3)
            rows.append({"change": f"{what} x{f:g}", "factor": f, "observation_s": T2,
                         "law_observation_s": law, "note": note or None})
    return {"rows": rows, "law": "T ~ (sigma^2 / f)^(1/3) in the T^-3/2 regime"}


def _counting(planner, quantity, si):
    """Quet's counting for the same target: gyroscopes only (a period count); σ ∝ 1/T."""
    if not any(m.kind == "gyro" for m in planner.models):
        return {"observation_s": None, "reason": "no gyroscope: counting whole swings times a period, and the "
                                                 "Foucault rate is not a period"}
    T, note = planner.solve(quantity, si, counting=True)
    d = {"observation_s": T, "reason": note or None,
         "law": "sigma(T_swing) = T_swing / (N sqrt 3), N = T / T_swing swings: sigma ~ 1/T",
         "instruments": [m.name for m in planner.models if m.kind == "gyro"]}
    if any(m.kind == "pendulum" for m in planner.models):
        d["left_out"] = "the pendulum (its Foucault rate is not a period to count)"
    if T is not None:
        d["years"] = T / YEAR_S
        d["exceeds_a_year"] = T > YEAR_S
    return d


def _bias(result, quantity):
    """The noise-free estimate's error in SI (rad or rad/s), or None."""
    truth = result["truth"]
    if quantity == "latitude":
        lat = result.get("latitude_deg")
        if lat is None:
            return None
        ref = abs(truth["latitude_deg"]) if result.get("latitude_is_absolute") else truth["latitude_deg"]
        return math.radians(lat - ref)
    n = result.get("earth_rate_rad_s")
    return None if n is None else n - truth["earth_rate_rad_s"]


def noise_free_estimate(scene_arg, overrides, T) -> tuple:
    """The estimate of the scene with the sensor switched off, over T s per configuration."""
    from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
    from gyro_instrument.scenes import load_scene
    scene = load_scene(scene_arg, list(overrides) + [f"duration_s={T!r}"] + noise_free_overrides())
    truth = simulate_truth(scene)
    return scene, estimate_records(scene, truth[1], measure(scene, truth))


def systematic_floor(scene_arg, overrides, T, quantity, si, name) -> dict:
    """The estimator's noise-free bias at T against the target; when it exceeds the target, the bias
    with each of the scene's effects (but ``earth_rotation``) switched off names the one that sets it."""
    try:
        scene, r = noise_free_estimate(scene_arg, overrides, T)
    except SceneError as exc:
        return {"bias": None, "reason": f"noise-free run at {T:.6g} s not possible: {exc}"}
    b = _bias(r, quantity)
    d = {"bias": _quantity_value(quantity, b, name), "observation_s": T}
    if b is None:
        d["reason"] = r.get("reason") or "the noise-free estimate is null"
        return d
    d["reachable"] = abs(b) <= si
    if abs(b) > si:
        culprits = []
        for eff in scene.effects:
            if eff == "earth_rotation":
                continue
            try:
                _, r2 = noise_free_estimate(scene_arg, list(overrides) + [f"effects.{eff}=null"], T)
                b2 = _bias(r2, quantity)
            except SceneError:
                continue
            culprits.append({"effect": eff, "bias_without": _quantity_value(quantity, b2, name)})
        d["effects"] = culprits
        best = [c for c in culprits if c["bias_without"] is not None]
        if best:
            top = min(best, key=lambda c: abs(c["bias_without"]))
            if abs(top["bias_without"]) < abs(d["bias"]):
                d["set_by"] = top["effect"]
    return d


# ----------------------------------------------------------------------------- verification
def _errors(results, quantity):
    errs = [_bias(r, quantity) for r in results]
    return [e for e in errs if e is not None], sum(e is None for e in errs)


def verify(scene_arg, overrides, T, n_seeds=100, executor=None, progress=None, chunk=None) -> dict:
    """Seeded Monte Carlo at observation time T: ``n_seeds`` sensor draws of one simulation per
    chunk (:func:`~gyro_instrument.estimators.pipeline.seed_sweep` through ``executor``, by default
    :func:`~gyro_instrument.core.parallel.process_executor`); ``progress(done, total)`` after each
    chunk. Returns {quantity: (rms error in SI, number of seeds used, number null)}."""
    from gyro_instrument.core.parallel import process_executor
    from gyro_instrument.estimators.pipeline import seed_sweep
    over = list(overrides) + [f"duration_s={T!r}"]
    chunk = chunk or max(1, math.ceil(n_seeds / 8))
    jobs = [(scene_arg, over, list(range(i, min(i + chunk, n_seeds)))) for i in range(0, n_seeds, chunk)]
    own = executor is None
    executor = executor or process_executor(min(len(jobs), 2))
    results = []
    try:
        for res in executor.map(seed_sweep, jobs):
            results.extend(res)
            if progress:
                progress(len(results), n_seeds)
    finally:
        if own:
            executor.shutdown()
    out = {}
    for quantity in ("latitude", "earth_rate"):
        errs, null = _errors(results, quantity)
        rms = float(np.sqrt(np.mean(np.square(errs)))) if errs else None
        out[quantity] = (rms, len(errs), null)
    return out


def verify_plan(result, n_seeds=100, executor=None, progress=None) -> dict:
    """Add ``verify`` to each planned target of ``result`` (from :func:`plan`): the achieved rms over
    ``n_seeds`` at the planned T next to the target and the planned σ (ratio achieved / target)."""
    for entry in result["targets"]:
        T = entry.get("observation_s")
        if T is None:
            continue
        name = entry["target"]
        if progress:
            progress(f"verify {name}: {n_seeds} seeds at {T:.6g} s per configuration")
        rep = (lambda d, n: progress(f"  {d}/{n} seeds")) if progress else None
        got = verify(result["source"], result["overrides"], T, n_seeds, executor, rep)
        rms, used, null = got[entry["quantity"]]
        v = _quantity_value(entry["quantity"], rms, name)
        entry["verify"] = {"seeds": n_seeds, "used": used, "null": null, "achieved_rms": v,
                           "target": entry["value"], "planned_sigma": entry["planned_sigma"],
                           "achieved_over_target": None if v is None else v / entry["value"],
                           "achieved_over_planned": None if v is None else v / entry["planned_sigma"]}
    return result
