"""The Cramér–Rao bound of a horizontal gyroscope's north reading as a function of the observation
time T, per north method, for ``plan --target azimuth_arcsec=...`` (issue 24 item 4, issue 33 item 3).

The rate bounds and the probes of the other measurement kinds are :mod:`.bounds`'s; this module
adds the probe and bound of :data:`~gyro_instrument.instruments.observation_azimuth.AZIMUTH`, which
its kind declares (:class:`.kinds.AzimuthKind`). Sources: the fit's σ is the
Cramér–Rao bound of the WHOLE joint problem the estimate solves (:func:`.north.exact.crlb`: the
swing equation in scale readings, rotor-on and rotor-off records, tape calibration included) at the
scene's true constants (:func:`exact_truth`); the reversal-point and transit methods of :mod:`.north`
run on the noise-free model record, tape-corrected by the estimate's own step
(:func:`.north.tape_corrected`, the exact relation N = c − atan(x (Z − c))).

The rotor-off swing: the scene simulates it simultaneously with the rotor-on swing over the same
span (its ``duration_s``), and so does the plan (``layout="simultaneous"``); in the field it is
swung before and after (``layout="before_after"``: half its record before the rotor-on swing, half
after, each a release of its own; the same joint fit's bound).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.estimators.bounds import (CLOSED_FORM_CYCLES, EXACT_SAMPLES, samples, shortest_time,
                                               sine_fit_covariance)


# ----------------------------------------------------------------------------- the azimuth (north)
#: The north methods the planner gives a time for (``north.methods`` of the estimate), fit last.
NORTH_METHODS = ("schuler_mean", "lavrov", "transit", "fit")
#: Longest model record (samples) the reversal-point and transit methods are run on; beyond it their
#: σ is extrapolated with σ ∝ T^-1/2 (a mean of ν ∝ T reversal points or transits of equal σ).
METHOD_SAMPLES = 400_000
#: What each method's σ law is (the plan's ``law``).
NORTH_LAWS = {
    "schuler_mean": "sigma_a sqrt(sum w^2), w = (1, 3, 4, ..., 4, 3, 1)/(4(nu - 2)) over the nu reversal points "
                    "of T; sigma_a = sigma sqrt(g'(X'X)^-1 g) of each point's local quartic (~ T^-1/2); with a tape "
                    "through the exact relation N = c - atan(x (Z - c))",
    "lavrov": "propagated from the reversal points' sigma_a through the damped-oscillation fit (~ T^-1/2)",
    "transit": "propagated from the transit times' sigma through x0 = A sin(pi dt/(2T)) (~ T^-1/2)",
    "fit": "Cramer-Rao bound of the whole joint problem, sqrt([I^-1]_NN), I = J'J/sigma^2 of the swing equation in "
           "scale readings (rotor-on and rotor-off records, tape calibration included) on the sample grid at the "
           "scene's truth (~ T^-1/2 for many swings)",
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
    #: the exact model (:func:`exact_truth`): the swing equation (t_ref = 0), its true parameters
    #: (:data:`.north.exact.GLOBAL`, clockwise reading) and each record's (reading, rate) at t = 0;
    #: None for a synthetic model (the centre's bound :func:`_centre_bound` then stands for the fit's)
    eq: object = None
    par: dict = field(default_factory=dict)
    initial: tuple = ()
    #: the estimator's check (``north.estimate._check_swing``): one full small-swing period, s
    check_period_s: float = 0.0
    rate_hz: float = 0.0
    rotor_off_name: str = ""

    def on_grid(self, T) -> float:
        """T rounded UP to the scene's sample grid (t_i = i/f): the record then spans ≥ T."""
        return math.ceil(T * self.rate_hz - 1e-9) / self.rate_hz if self.rate_hz else T

    @property
    def min_on_s(self) -> float:
        """Two full swings of the rotor-on record (the fit's start and the reversal-point methods need
        ≥ 3 complete reversal points whatever the phase at which the record starts; at least the
        estimator's check, one full small-swing period)."""
        return max(4.0 * math.pi / self.omega, self.check_period_s)

    @property
    def min_off_s(self) -> float:
        """Two full swings of the rotor-off swing (its fit, which starts the tape zero and period, needs
        ≥ 3 complete reversal points likewise); 0 without a tape."""
        return 4.0 * math.pi / self.off[0] if self.off else 0.0

    @property
    def min_record_s(self) -> float:
        """The shortest record the estimator's north block accepts (:attr:`min_on_s`, and with a tape
        :attr:`min_off_s`, the rotor-off swing simultaneous), rounded up to the sample grid so that
        the record's span passes the estimator's own check."""
        return self.on_grid(max(self.min_on_s, self.min_off_s))

    def record_limit(self) -> str:
        """What sets :attr:`min_record_s`, in words."""
        if self.min_off_s > self.min_on_s:
            return (f"the rotor-off swing {self.rotor_off_name}: two full swings of the torsion pendulum "
                    f"({self.min_off_s:.6g} s, period {2 * math.pi / self.off[0]:.6g} s) for the tape zero and period, "
                    f"observed over the same span as the rotor-on swing")
        return (f"two full swings of the rotor-on record ({self.min_on_s:.6g} s, period {2 * math.pi / self.omega:.6g} s: "
                f"the estimator's shortest record)")

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


def exact_truth(inst, off_inst=None) -> tuple:
    """The exact fit's model of ``inst`` at the scene's truth, t_ref = 0: (SwingEquation, par, initial).

    In the clockwise reading w = −angle (:mod:`.north.exact`): north N = −mount_reading_rad, the
    directing constant K = a ρ0 (:meth:`~gyro_instrument.instruments.plane_gyroscope.PlaneGyroscope.
    reduced_coefficients`: a = μ n sin ω), the tape k_B = D_B/A, its zero −Z0 drifting at −Ż, the
    damping rate; ``initial``: each record's (w0, v0) at t = 0, the rotor-off instrument's read on
    its own scale (its release u0 plus its mount reading).
    """
    from gyro_instrument.estimators.north.estimate import swing_equation
    c = inst.reduced_coefficients()
    par = {"north": -inst.mount_reading_rad, "directing": c["a"] * inst.p.spin_rate_rad_s, "tape": c["kb"],
           "zero": -c["zero"], "zero_rate": -c["zero_rate"], "damping": c["damping"]}
    initial = [(-(inst.p.initial_angle_rad + inst.mount_reading_rad), -inst.p.initial_rate_rad_s)]
    if off_inst is not None:
        initial.append((-(off_inst.p.initial_angle_rad + off_inst.mount_reading_rad), -off_inst.p.initial_rate_rad_s))
    return swing_equation(inst, 0.0), par, tuple(initial)


def azimuth_model(scene, obs) -> tuple:
    """The azimuth model of a horizontal gyroscope (and its rotor-off companion with a tape)."""
    from gyro_instrument.scenes import build_instruments
    inst = obs.instrument
    shape = _probe_swing(inst, scene.sample_rate_hz)
    if isinstance(shape, str):
        return None, f"{shape}: {obs.null_reason}"
    w, A, d, ph, c = shape
    model = AzimuthModel(obs.name, w, A, d, ph, c, drift=obs.centre_drifts(),
                         mount_azimuth_rad=math.radians(inst.p.mount_azimuth_deg or 0.0),   # unset: 0 (the estimate's convention)
                         check_period_s=2.0 * inst.predictions()["swing_duration_small_s"],
                         rate_hz=float(scene.sample_rate_hz))
    off_inst = None
    if obs.has_tape():
        other = obs.companions().get("rotor_off")
        insts = build_instruments(scene)
        if other not in insts:
            return None, "the tape torsion is on and no rotor-off swing is named (rotor_off_instrument)"
        off_inst = insts[other]
        off = _probe_swing(off_inst, scene.sample_rate_hz)
        if isinstance(off, str):
            return None, f"rotor-off swing {other}: {off}"
        model.tape_ratio, model.off, model.centre_minus_zero_rad = inst.tape_ratio(), off[:4], c - off[4]
        model.rotor_off_name = other
    model.eq, model.par, model.initial = exact_truth(inst, off_inst)
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
    """σ of the north reading from a centre's σ through the estimate's own tape step
    (:func:`.north.tape_corrected`: the exact relation N = c − atan(x (Z − c)), x = D_B/(D_K cos(c − N))),
    the tape zero's σ the rotor-off centre's bound and the ratio's from the two periods' bounds."""
    from gyro_instrument.estimators import north
    if not model.tape_ratio or not math.isfinite(sigma_c):
        return sigma_c
    x = model.tape_ratio
    if model.par:
        K, kb, N = model.par["directing"], model.par["tape"], model.par["north"]
        x = kb / (K * math.cos(model.centre - N))
    s_z = _centre_bound(model, T, sensor, off=True)
    s_r = _ratio_sigma(model, T, sensor)
    est = north.NorthEstimate("fit", model.centre, sigma_c, "", 0, "", ())
    return north.tape_corrected(est, model.centre - model.centre_minus_zero_rad, x, s_r, s_z).sigma_rad


def _grid(T, rate_hz, start=0.0) -> np.ndarray:
    """The scene's sample times over T s from ``start`` (:func:`.bounds.samples`)."""
    return start + np.arange(samples(T, rate_hz)) / rate_hz


def _off_records(model, T, off_s, layout, rate_hz) -> list:
    """The rotor-off records' times: ``simultaneous`` from t = 0 over ``off_s`` (default T, as the
    scene simulates it), or ``before_after``: half of ``off_s`` ending where the rotor-on record
    starts and half from where it ends (each a release of its own)."""
    off_s = T if off_s is None else off_s
    if layout == "simultaneous":
        return [_grid(off_s, rate_hz)]
    half = 0.5 * off_s
    before = _grid(half, rate_hz)
    return [before - before[-1] - 1.0 / rate_hz, _grid(half, rate_hz, T + 1.0 / rate_hz)]


def fit_bound(model, T, sensor, off_s=None, layout="simultaneous") -> float:
    """Cramér–Rao bound on the north reading of the exact joint fit (rad) over a rotor-on record of T
    s and the rotor-off record(s) (:func:`_off_records`): :func:`.north.exact.crlb` at the scene's
    truth (:func:`exact_truth`) on the sample grid (thinned to :data:`EXACT_SAMPLES` samples in all,
    the information scaled by the stride), the dropouts' information (1 − p) taken out. A synthetic
    model without the swing equation: the centre's bound (:func:`_centre_bound`). inf when the
    records cannot determine the parameters."""
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.estimators.north import exact
    if model.eq is None:
        return _centre_bound(model, T, sensor)
    sigma, rate = sensor.sigma_rad, sensor.rate_hz
    if sigma <= 0:
        return 0.0
    records, kinds = [_grid(T, rate)], ["on"]
    initial = [model.initial[0]]
    if model.eq.tape:
        offs = _off_records(model, T, off_s, layout, rate)
        records += offs
        kinds += ["off"] * len(offs)
        initial += [model.initial[1]] * len(offs)
    stride = max(1, math.ceil(sum(r.size for r in records) / EXACT_SAMPLES))
    records = [r[::stride] for r in records]
    if min(r.size for r in records) < 8:
        return math.inf
    try:
        b = exact.crlb(model.eq, model.par, records, kinds, initial, sigma)
    except (np.linalg.LinAlgError, SceneError, ValueError):
        return math.inf
    return b / math.sqrt(stride * (1.0 - sensor.dropout_fraction)) if math.isfinite(b) else math.inf


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
    Cramér–Rao bound of the whole joint problem (:func:`fit_bound`), the others by their σ laws
    (:func:`_method_sigmas`; beyond :data:`METHOD_SAMPLES` extrapolated ∝ T^-1/2) with the tape's step
    (:func:`tape_combined`); inf below the shortest record (:attr:`AzimuthModel.min_record_s`)."""
    if T < model.min_record_s * (1 - 1e-9):
        return dict.fromkeys(NORTH_METHODS, math.inf)
    cap = (METHOD_SAMPLES - 1) / sensor.rate_hz
    if T > cap:
        out = {k: v * math.sqrt(cap / T) for k, v in _method_sigmas(model, cap, sensor).items()}
    else:
        out = _method_sigmas(model, T, sensor)
    out = {k: tape_combined(model, v, T, sensor) for k, v in out.items()}
    out["fit"] = fit_bound(model, T, sensor)
    return out


def solve_azimuth(model, sensor, target_rad, method="fit") -> tuple:
    """Shortest T (s) whose σ (:func:`azimuth_sigmas`) of ``method`` is ≤ ``target_rad``, from the
    shortest record up: (T or None, note). Exponential search, then bisection in log T to 1e-3
    relative (the reversal-point methods' σ falls in steps, one per reversal point: the first T of the
    step); T rounded up to the sample grid, so that the record's span passes the estimator's check."""
    def sig(T):
        return fit_bound(model, T, sensor) if method == "fit" else azimuth_sigmas(model, T, sensor)[method]
    t_min = model.min_record_s
    if sig(t_min) <= target_rad:
        return t_min, f"the shortest record already meets the target: {model.record_limit()}"
    T, note = shortest_time(sig, t_min, target_rad, 2.0, 1e-3)
    return (None, note) if T is None else (model.on_grid(T), note)


def rotor_off_plan(m, sensor, T, unit) -> dict:
    """The rotor-off swing's part in an azimuth plan at rotor-on time T (σ in the target's unit, ``unit``
    rad): what is assumed (simultaneous over the same span, as the scene simulates it), its shortest
    record and whether that sets T, the fit's σ for other rotor-off record lengths, and the field's
    before-and-after layout (:func:`fit_bound`)."""
    def fin(x):
        return x / unit if math.isfinite(x) else None
    spans = sorted({m.on_grid(x) for x in (m.min_off_s, 0.5 * T, T, 2.0 * T, 4.0 * T) if x >= m.min_off_s * (1 - 1e-9)})
    return {"instrument": m.rotor_off_name, "period_s": 2 * math.pi / m.off[0], "min_record_s": m.on_grid(m.min_off_s),
            "sets_the_time": bool(m.min_off_s > m.min_on_s and T <= m.min_record_s * (1 + 1e-9)),
            "assumed": "observed simultaneously over the same span as the rotor-on swing, as the scene simulates it "
                       "(duration_s for both); the estimator reads that one record",
            "curve": [{"rotor_off_s": x, "sigma": fin(fit_bound(m, T, sensor, off_s=x))} for x in spans],
            "before_after": {"rotor_off_s": T, "field_time_s": 2.0 * T,
                             "sigma": fin(fit_bound(m, T, sensor, off_s=T, layout="before_after")),
                             "layout": "the field's: half the rotor-off record before the rotor-on swing and half "
                                       "after, each a release of its own; the same joint fit's bound (the estimate "
                                       "here reads one simultaneous record)"}}


def azimuth_entry(m) -> dict:
    """The plan's entry of a horizontal gyroscope's azimuth model (``plan --json``, ``north_instruments``)."""
    d = {"kind": m.kind, "measures": "mount azimuth: the swing centre on the scale is true north",
         "period_s": 2 * math.pi / m.omega, "amplitude_rad": m.amplitude, "damping_per_s": m.damping,
         "min_record_s": m.min_record_s, "mount_azimuth_deg": math.degrees(m.mount_azimuth_rad),
         "drift_fitted": m.drift}
    if m.tape_ratio:
        d.update({"tape_ratio_db_dk": m.tape_ratio, "rotor_off_period_s": 2 * math.pi / m.off[0],
                  "rotor_off_instrument": m.rotor_off_name, "rotor_off_min_record_s": m.min_off_s})
    return d
