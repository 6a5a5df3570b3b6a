"""The Cramér–Rao bound of a horizontal gyroscope's oscillation centre (north) as a function of the
observation time T, per north method, for ``plan --target azimuth_arcsec=...`` (issue 24 item 4).

The rate bounds and the probes of the other measurement kinds are :mod:`.bounds`'s; this module
adds the probe of :data:`~gyro_instrument.instruments.observation_azimuth.AZIMUTH` to
:data:`.bounds.PROBES` when imported (:mod:`.planner` imports it). Sources: the centre's bound
:func:`.north.crlb_centre` (:func:`.north.crlb_centre_long` for long undamped records), the
reversal-point and transit methods of :mod:`.north` run on the noise-free model record, and the
torsion tape's correction N = c + (D_B/D_K)(c − Z) (physics_notes, 'North finding').
"""

import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.estimators.bounds import (CLOSED_FORM_CYCLES, EXACT_SAMPLES, PROBES, samples, shortest_time,
                                               sine_fit_covariance)
from gyro_instrument.instruments.observation_azimuth import AZIMUTH


# ----------------------------------------------------------------------------- the azimuth (north)
#: The north methods the planner gives a time for (``north.methods`` of the estimate), fit last.
NORTH_METHODS = ("schuler_mean", "lavrov", "transit", "fit")
#: Longest model record (samples) the reversal-point and transit methods are run on; beyond it their
#: σ is extrapolated with σ ∝ T^-1/2 (a mean of ν ∝ T reversal points or transits of equal σ).
METHOD_SAMPLES = 400_000
#: What each method's σ law is (the plan's ``law``).
NORTH_LAWS = {
    "schuler_mean": "sigma_a sqrt(sum w^2), w = (1, 3, 4, ..., 4, 3, 1)/(4(nu - 2)) over the nu reversal points "
                    "of T; sigma_a = sigma sqrt(g'(X'X)^-1 g) of each point's local quartic (~ T^-1/2)",
    "lavrov": "propagated from the reversal points' sigma_a through the damped-oscillation fit (~ T^-1/2)",
    "transit": "propagated from the transit times' sigma through x0 = A sin(pi dt/(2T)) (~ T^-1/2)",
    "fit": "Cramer-Rao bound of the centre, sqrt([I^-1]_cc), I = J'J/sigma^2 on the sample grid "
           "(-> sigma/sqrt(N), ~ T^-1/2, for many cycles)",
}


@dataclass
class AzimuthModel:
    """What the planner knows of one horizontal gyroscope's swing for north (rad, rad/s, s).

    The clockwise reading u(t) = c + A e^(−δt) cos(ωt + φ) (:func:`.north.damped_swing`), from a
    noise-free probe; ``drift``: the estimator fits a drift of the centre (``tape_drift``).
    With a torsion tape: ``tape_ratio`` r = D_B/D_K, the rotor-off swing (``off``: ω, A, δ, φ of the
    torsion pendulum) whose centre gives the tape zero Z, and ``centre_minus_zero_rad`` c − Z, so that
    σ_N² = (1 + r)² σ_c² + r² σ_Z² + (c − Z)² σ_r² (:func:`.north.tape_corrected`).
    ``mount_azimuth_rad``: the scene's true mount azimuth (what the floor and ``--verify`` compare to)."""

    name: str
    omega: float
    amplitude: float
    damping: float = 0.0
    phase: float = 0.0
    centre: float = 0.0
    drift: bool = False
    tape_ratio: float = 0.0
    off: tuple | None = None
    centre_minus_zero_rad: float = 0.0
    mount_azimuth_rad: float = 0.0
    kind: str = "azimuth"

    @property
    def min_record_s(self) -> float:
        """One full swing; with a tape two full swings of the rotor-off swing (its fit, which gives the
        tape zero and period, starts from ≥ 3 complete reversal points, whatever the phase at which
        the record starts): the shortest record the estimator's north block accepts."""
        return max(2.0 * math.pi / self.omega, 4.0 * math.pi / self.off[0] if self.off else 0.0)

    def record(self, T, rate_hz, off=False) -> tuple:
        """(t, u): the noise-free model record on the scene's sample grid over T s (rotor-off with ``off``)."""
        from gyro_instrument.estimators.north import damped_swing
        t = np.arange(samples(T, rate_hz)) / rate_hz
        w, A, d, ph = self.off if off else (self.omega, self.amplitude, self.damping, self.phase)
        return t, damped_swing(t, 0.0 if off else self.centre, A, w, d, ph)


def _swing_shape(t, u):
    """(ω, A, δ, φ, c) of a noise-free swing record, as :func:`.north.fit_record` starts: ω from the
    reversal-point spacing, δ from the decay of their deviations, then the linear terms."""
    from gyro_instrument.estimators import north
    rp = north.reversal_points(t, u, 1e-12)
    w = math.pi / rp.half_period_s
    c0 = north.schuler_mean(rp.readings_rad).centre_rad if rp.readings_rad.size >= 3 else float(np.mean(u))
    dev = np.abs(rp.readings_rad - c0)
    d = max(float(-np.polyfit(rp.times_s, np.log(dev), 1)[0]), 0.0) if dev.size >= 3 else 0.0
    E = np.exp(-d * t)
    (c, a, b), *_ = np.linalg.lstsq(np.column_stack([np.ones_like(t), E * np.cos(w * t), E * np.sin(w * t)]), u,
                                    rcond=None)
    return w, math.hypot(a, b), d, math.atan2(-b, a), float(c)


def _probe_swing(inst, rate_hz):
    """The shape (:func:`_swing_shape`) of a noise-free simulation of four full swings of ``inst``
    (clockwise reading: −angle), or a reason string."""
    T0 = inst.predictions().get("swing_duration_small_s")
    if T0 is None or not math.isfinite(T0) or T0 <= 0:
        return "no swing to time"
    t = np.arange(0.0, 8.0 * T0 * 1.1, 1.0 / rate_hz)
    try:
        return _swing_shape(t, -np.asarray(inst.simulate(t).columns["angle"], dtype=float))
    except ValueError as exc:                  # SceneError: no reversal points in the probe
        return f"no swing in a noise-free probe: {exc}"


def _azimuth_model(scene, obs):
    """The azimuth model of a horizontal gyroscope (and its rotor-off companion with a tape)."""
    from gyro_instrument.scenes import build_instruments
    inst = obs.instrument
    shape = _probe_swing(inst, scene.sample_rate_hz)
    if isinstance(shape, str):
        return None, f"{shape}: {obs.null_reason}"
    w, A, d, ph, c = shape
    model = AzimuthModel(obs.name, w, A, d, ph, c, drift=obs.centre_drifts(),
                         mount_azimuth_rad=float(inst.p.mount_azimuth_rad))
    if obs.has_tape():
        other = obs.companions().get("rotor_off")
        insts = build_instruments(scene)
        if other not in insts:
            return None, "the tape torsion is on and no rotor-off swing is named (rotor_off_instrument)"
        off = _probe_swing(insts[other], scene.sample_rate_hz)
        if isinstance(off, str):
            return None, f"rotor-off swing {other}: {off}"
        model.tape_ratio, model.off, model.centre_minus_zero_rad = inst.tape_ratio(), off[:4], c - off[4]
    return model, None


def _centre_bound(model, T, sensor, off=False) -> float:
    """Cramér–Rao bound on the centre of the model record over T (rad): :func:`.north.crlb_centre`
    on the sample grid (thinned to :data:`EXACT_SAMPLES`, the information scaled by the stride), or
    :func:`.north.crlb_centre_long` for an undamped record of :data:`CLOSED_FORM_CYCLES` cycles."""
    from gyro_instrument.estimators import north
    n = samples(T, sensor.rate_hz)
    keep = 1.0 - sensor.dropout_fraction
    sigma = sensor.sigma_rad
    w, A, d, ph = model.off if off else (model.omega, model.amplitude, model.damping, model.phase)
    if sigma <= 0:
        return 0.0
    if n < 8:
        return math.inf
    span = (n - 1) / sensor.rate_hz
    if n > EXACT_SAMPLES and d == 0 and not model.drift and w * span / (2 * math.pi) >= CLOSED_FORM_CYCLES:
        return north.crlb_centre_long(sigma, n * keep)
    stride = max(1, math.ceil(n / EXACT_SAMPLES))
    t = np.arange(0, n, stride) / sensor.rate_hz
    t_ref = 0.5 * span
    amp, phase = A * math.exp(-d * t_ref), ph + w * t_ref      # the fit's amplitude and phase at t_ref
    try:
        b = north.crlb_centre(t, amp, w, sigma, d, phase, fit_damping=True, drift=model.drift and not off, t_ref_s=t_ref)
    except np.linalg.LinAlgError:
        return math.inf
    return b / math.sqrt(stride * keep)


def _ratio_sigma(model, T, sensor) -> float:
    """σ of D_B/D_K from the two fitted periods' bounds (:func:`.north.tape_ratio`), each period's
    relative σ that of ω: the closed form of :func:`sine_fit_covariance`."""
    from gyro_instrument.estimators import north
    out = []
    for w, A in ((model.omega, model.amplitude), (model.off[0], model.off[1])):
        var_w = sine_fit_covariance(T, sensor.rate_hz, w, (A, 0.0, 0.0, 0.0), sensor.sigma_rad,
                                    1.0 - sensor.dropout_fraction)[0]
        out.append((2 * math.pi / w, 2 * math.pi * math.sqrt(var_w) / w ** 2 if math.isfinite(var_w) else math.inf))
    (t_on, s_on), (t_off, s_off) = out
    if not (math.isfinite(s_on) and math.isfinite(s_off)):
        return math.inf
    return north.tape_ratio(t_on, t_off, s_on, s_off)[1]


def tape_combined(model, sigma_c, T, sensor) -> float:
    """σ of the north reading from a centre's σ with the tape's terms (:class:`AzimuthModel`)."""
    if not model.tape_ratio or not math.isfinite(sigma_c):
        return sigma_c
    r = model.tape_ratio
    s_z = _centre_bound(model, T, sensor, off=True)
    s_r = _ratio_sigma(model, T, sensor)
    return math.sqrt(((1 + r) * sigma_c) ** 2 + (r * s_z) ** 2 + (model.centre_minus_zero_rad * s_r) ** 2)


def _method_sigmas(model, T, sensor) -> dict:
    """The reversal-point and transit methods' own σ on the noise-free model record over T (rad; inf
    where the method refuses the record): what the estimator reports for them at this T, its σ law
    (:data:`NORTH_LAWS`) evaluated exactly, turning-point count and phase included."""
    from gyro_instrument.estimators import north
    t, u = model.record(T, sensor.rate_hz)
    sigma = max(sensor.sigma_rad, 1e-300) / math.sqrt(1.0 - sensor.dropout_fraction)
    out = dict.fromkeys(NORTH_METHODS[:3], math.inf)
    try:
        rp = north.reversal_points(t, u, sigma)
    except ValueError:
        return out
    runs = {"schuler_mean": lambda: north.schuler_mean(rp.readings_rad, rp.sigmas_rad),
            "lavrov": lambda: north.lavrov(rp.readings_rad, rp.sigmas_rad),
            "transit": lambda: north.transit_method(t, u, model.centre, sigma)}
    for name, run in runs.items():
        try:
            s = run().sigma_rad
        except (ValueError, np.linalg.LinAlgError):
            continue
        out[name] = math.inf if s is None else s
    return out


def azimuth_sigmas(model, T, sensor) -> dict:
    """{method: σ of the north reading (rad) over T s} for :data:`NORTH_METHODS`: the fit at the
    Cramér–Rao bound (:func:`_centre_bound`), the others by their σ laws (:func:`_method_sigmas`;
    beyond :data:`METHOD_SAMPLES` extrapolated ∝ T^-1/2), each with the tape's terms
    (:func:`tape_combined`); inf below one full swing."""
    if T < model.min_record_s * (1 - 1e-9):
        return dict.fromkeys(NORTH_METHODS, math.inf)
    cap = (METHOD_SAMPLES - 1) / sensor.rate_hz
    if T > cap:
        out = {k: v * math.sqrt(cap / T) for k, v in _method_sigmas(model, cap, sensor).items()}
    else:
        out = _method_sigmas(model, T, sensor)
    out["fit"] = _centre_bound(model, T, sensor)
    return {k: tape_combined(model, v, T, sensor) for k, v in out.items()}


def solve_azimuth(model, sensor, target_rad, method="fit") -> tuple:
    """Shortest T (s) whose σ (:func:`azimuth_sigmas`) of ``method`` is ≤ ``target_rad``, from one full
    swing up: (T or None, note). Exponential search, then bisection in log T to 1e-3 relative (the
    reversal-point methods' σ falls in steps, one per reversal point: the first T of the step)."""
    def sig(T):
        return azimuth_sigmas(model, T, sensor)[method] if method != "fit" else tape_combined(
            model, _centre_bound(model, T, sensor), T, sensor)
    if sig(model.min_record_s) <= target_rad:
        return model.min_record_s, "one full swing (the shortest record) already meets the target"
    return shortest_time(sig, model.min_record_s, target_rad, 2.0, 1e-3)


PROBES[AZIMUTH] = _azimuth_model
