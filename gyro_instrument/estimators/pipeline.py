"""From a scene to estimates: simulate the truth, measure through the sensor model, estimate.

``simulate_truth`` runs each instrument once; ``measure`` draws the sensor samples for one seed
(so 200 seeded runs cost one simulation); ``estimate_records`` turns measured records into the
``estimate`` JSON object: per-instrument periods (fit and Quet's counting), Quet's item 9 and
eq. (10), the Foucault rate with its ellipse correction, and the combined latitude and Earth
rate (profile likelihood, :mod:`.latitude`) with their Cramér–Rao bounds. Quantities that cannot
be estimated are ``None`` with a reason — never NaN, infinity or a crash.
"""

import math

import numpy as np

from gyro_instrument.core.scene import sample_times
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.estimators.adequacy import (InadequateData, check_before_fit, check_entry, check_fit,
                                                 check_period, detection_snr, hemisphere_entry, plane_fit_entry,
                                                 signal_entry)
from gyro_instrument.estimators.foucault import estimate_foucault
from gyro_instrument.estimators.latitude import (HEMISPHERE_UNDETERMINED, RateMeasurement, item9_cos_latitude,
                                                 solve_latitude)
from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, NoSignal, count_oscillations, fit_oscillation
from gyro_instrument.scenes import build_instruments, load_scene
from gyro_instrument.sensors import SensorModel, scene_rng


#: The systematic corrections the estimator makes; ``estimate_records(..., corrections=...)`` can
#: leave any of them out, which is how ``gyro-instrument bench`` measures what each one is worth:
#: ``finite_amplitude`` — a gyroscope's swing reduced to small amplitude through (2/π)K(sin(a/2))
#: (Quet's T is the small-swing limit); ``spin_decay`` — a gyroscope's fit in the spin-warped time
#: of its measured spin history (eq. (9): T ∝ ρ^-1/2); ``ellipse_precession`` — the Foucault rate
#: less the finite-amplitude precession of the swing ellipse (sec. 2 §III, from its areal velocity).
CORRECTIONS = frozenset(("finite_amplitude", "spin_decay", "ellipse_precession"))


def estimable(inst) -> bool:
    """True for instruments that measure an Earth rate: pendulums (``IS_PENDULUM``: k = n sin γ) and
    gyroscopes with a directing line (``directing_model()``: K = gain n ρ s(γ)). Free gyroscopes and
    Puiseux's body do not."""
    return inst.IS_PENDULUM or inst.directing_model() is not None


def simulate_truth(scene) -> tuple:
    """(t, instruments, sims): the noiseless simulation of every instrument."""
    t = sample_times(scene)
    insts = build_instruments(scene)
    return t, insts, {name: inst.simulate(t) for name, inst in insts.items()}


def measure(scene, truth, seed=None) -> dict:
    """Measured records for one seed: name -> {'t', channel arrays}."""
    t, insts, sims = truth
    sensor = SensorModel.from_scene(scene)
    seed = scene.seed if seed is None else seed
    records = {}
    for name, inst in insts.items():
        rng = scene_rng(seed, name)
        cols = sims[name].columns
        rec = {"t": t.copy()}
        for chan, angle in inst.measured_angles(cols).items():
            rec[chan] = sensor.measure_angle(angle, rng)
        if not inst.IS_PENDULUM:
            if "spin_rate" in cols:
                rec["spin_rate"] = sensor.measure_rate(cols["spin_rate"], rng)
            model = inst.directing_model()
            if model is not None:
                rec["angle"] = rec[model.angle_channel]
        records[name] = rec
    return records


#: normals drawn at a time when a stream is positioned past another channel's draws (8 MB)
_SKIP_CHUNK = 1 << 20


class MeasureStream:
    """:func:`measure` block by block for one instrument: the same draws, in bounded memory.

    ``measure`` draws, per instrument from ``scene_rng(seed, name)``, every sample of one channel
    before the next (noise normals, then the dropout uniforms, channel after channel, then the
    spin). Here each of those draws gets its own copy of the generator, positioned once at the
    start where ``measure`` would begin it: uniforms by ``PCG64.advance`` (one 64-bit word each),
    normals by drawing and discarding them (the ziggurat's word count varies) in chunks of
    :data:`_SKIP_CHUNK`. Blocks then draw from their channel's copy in order, so the concatenated
    blocks equal ``measure`` bit for bit (``Generator`` keeps no cached value between calls).

    Parameters
    ----------
    scene : Scene
    inst : Instrument
    n : int
        Samples of the whole run (``core.memory.sample_count``).
    seed : int, optional
        The scene's seed by default.

    Costs ``n`` discarded normals per noisy draw that is not the last one, before the first block
    (38 ns each measured on this machine: 0.13 s for 48 h at 20 Hz, but 33 s for a day at 10 kHz —
    the price of equality with ``measure`` bit for bit).
    """

    def __init__(self, scene, inst, n, seed=None):
        self.inst = inst
        self.n = int(n)
        self.sensor = SensorModel.from_scene(scene)
        self.rng = scene_rng(scene.seed if seed is None else seed, inst.name)
        self.gens = None

    def _plan(self, columns):
        """The draws ``measure`` makes, in its order: (channel, 'normal' | 'uniform')."""
        s, plan = self.sensor, []
        spin = [] if self.inst.IS_PENDULUM or "spin_rate" not in columns else ["spin_rate"]
        for chan in list(self.inst.MEASURED_CHANNELS) + spin:
            noisy = s.noise_rad if chan != "spin_rate" else s.spin_noise_rad_s
            if noisy:
                plan.append((chan, "normal"))
            if s.dropout_fraction:
                plan.append((chan, "uniform"))
        return plan

    def _position(self, columns):
        bg = self.rng.bit_generator
        self.gens = {}
        for chan, kind in self._plan(columns):
            copy = type(bg)()
            copy.state = bg.state
            self.gens[(chan, kind)] = np.random.Generator(copy)
            if kind == "uniform":
                bg.advance(self.n)
            else:
                for i in range(0, self.n, _SKIP_CHUNK):
                    self.rng.standard_normal(min(_SKIP_CHUNK, self.n - i))

    def _apply(self, chan, values, angle):
        s = self.sensor
        y = np.array(values, dtype=float)
        g = self.gens.get((chan, "normal"))
        if g is not None:
            y = y + g.normal(0.0, s.noise_rad if angle else s.spin_noise_rad_s, y.shape)
        if angle and s.quantization_rad:
            y = np.round(y / s.quantization_rad) * s.quantization_rad
        g = self.gens.get((chan, "uniform"))
        if g is not None:
            y[g.random(y.shape) < s.dropout_fraction] = np.nan
        return y

    def block(self, t, columns) -> dict:
        """The measured record of one block (as one instrument's entry of :func:`measure`)."""
        if self.gens is None:
            self._position(columns)
        rec = {"t": np.array(t, dtype=float)}
        for chan, angle in self.inst.measured_angles(columns).items():
            rec[chan] = self._apply(chan, angle, True)
        if not self.inst.IS_PENDULUM:
            if "spin_rate" in columns:
                rec["spin_rate"] = self._apply("spin_rate", columns["spin_rate"], False)
            model = self.inst.directing_model()
            if model is not None:
                rec["angle"] = rec[model.angle_channel]
        return rec


def _spin_warp(t, spin, spin_ok, rho_mean):
    """Time warp and adiabatic envelope from the measured spin history, or Nones when the spin did not
    change measurably.

    The spin is smoothed by a quadratic in log|ρ| (exact for the viscous bearing's e^(-t/τ), and for
    any slow law over a run shorter than its time scale: a quadratic in ρ itself is 0.5 % off over
    one τ); τ = ∫ √(ρ/ρ̄) dt and the envelope (ρ/ρ̄)^(−1/4).

    Returns
    -------
    tuple
        (warp, envelope, ratio ρ/ρ̄, note) — all None when no correction applies.
    """
    sgn = 1.0 if rho_mean >= 0 else -1.0
    same_sign = spin[spin_ok] * sgn > 0
    if same_sign.all():
        coef = np.polyfit(t[spin_ok], np.log(spin[spin_ok] * sgn), 2)
        smooth = sgn * np.exp(np.polyval(coef, t))
    else:
        coef = np.polyfit(t[spin_ok], spin[spin_ok], 2)
        smooth = np.polyval(coef, t)
    change = abs(smooth[-1] - smooth[0])
    noise = np.std(spin[spin_ok] - smooth[spin_ok])
    if change > max(10 * noise / math.sqrt(spin_ok.sum()), 1e-9 * abs(rho_mean)) and change > 1e-6 * abs(rho_mean):
        ratio = np.clip(smooth / rho_mean, 1e-6, None)
        warp = np.concatenate([[0.0], np.cumsum(0.5 * (np.sqrt(ratio[1:]) + np.sqrt(ratio[:-1])) * np.diff(t))])
        env = ratio ** -0.25
        return warp, env, ratio, f"spin changed by {change / abs(rho_mean):.3g} relative: fitted in spin-warped time"
    return None, None, None, None


def _fit_swing(t, y, warp, env, ratio, corrections):
    """The sine fit (fundamental and third harmonic) of a gyroscope's swing, refitted once in a
    time also warped by the finite-amplitude law when the spin changed; raises EstimationError.

    Returns
    -------
    tuple
        (fit, warp actually used).
    """
    fit = fit_oscillation(t, y, harmonics=(1, 3), warp=warp, envelope=env)
    if warp is not None and "finite_amplitude" in corrections:
        # the swing lengthens as its amplitude grows (a ∝ ρ^-1/4): the instantaneous rate is
        # ω_small(ρ(t)) / F(a(t)), so warp by F(a_ref)/F(a(t)) too and refit once
        a_t = abs(fit.amplitude) * env
        rate = np.sqrt(ratio) * finite_amplitude_factor(abs(fit.amplitude)) / finite_amplitude_factor(a_t)
        warp = np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(t))])
        fit = fit_oscillation(t, y, omega_guess=fit.omega_rad_s, harmonics=(1, 3), warp=warp, envelope=env)
    return fit, warp


def _with_damping(t, y, fit, warp, env, notes):
    """The fit refitted with an exponential envelope when that lowers the residual significantly."""
    try:
        dfit = fit_oscillation(t, y, omega_guess=fit.omega_rad_s, harmonics=(1, 3), damping=True, warp=warp,
                               envelope=env)
        if fit.residual_rms ** 2 - dfit.residual_rms ** 2 > 10.0 * fit.residual_rms ** 2 / fit.n_samples:
            notes.append(f"damping fitted: {dfit.damping_per_s:.3g} 1/s")
            return dfit
    except EstimationError:
        pass
    return fit


def _counting(t, y, F):
    """Quet's counting baseline for the estimate JSON (its swing reduced to small amplitude by F)."""
    try:
        c = count_oscillations(t, y)
        return {"swing_duration_s": c.swing_duration_s, "swing_duration_sigma_s": c.swing_duration_sigma_s,
                "swings": c.swings, "small_amplitude_swing_duration_s": c.swing_duration_s / F}
    except EstimationError as exc:
        return {"swing_duration_s": None, "reason": str(exc)}


def _gyro_measurement(inst, model, T0, sig_T0, crlb_T0, rho_mean, out):
    """The rate measurement y = K / (gain ρ̄) = n s(γ) (eq. 9, K = (π/T0)²), with the O(n²) centrifugal
    term of the exact equation removed when the model has one (recorded in ``out``)."""
    K = (math.pi / T0) ** 2
    y_val = K / (model.gain * rho_mean)
    c2 = model.second_order
    if c2:
        # invert y = y0 (1 + c2 y0/ρ) for y0 = n s(γ): the O(n²) centrifugal term of the exact equation
        y_val = 2.0 * y_val / (1.0 + math.sqrt(1.0 + 4.0 * c2 * y_val / rho_mean))
        out["second_order_correction"] = K / (model.gain * rho_mean) / y_val - 1.0
    rel = 2 * sig_T0 / T0
    return RateMeasurement(inst.name, "gyro", y_val, y_val * rel, tuple(model.normal_enu),
                           True, y_val * 2 * crlb_T0 / T0)


def _gyro_estimate(inst, rec, corrections=CORRECTIONS, checks=None, sensor=None):
    """Fit one gyroscope record: swing duration, small-amplitude conversion, counting baseline.

    ``checks`` (list) receives the ``signal``, ``period`` and ``fit`` checks (:mod:`.adequacy`, with
    ``sensor`` the scene's :class:`SensorModel`); raises :class:`.adequacy.InadequateData`."""
    checks = [] if checks is None else checks
    t, y = rec["t"], rec["angle"]
    out = {"type": inst.type_name}
    model = inst.directing_model()
    out["configuration"] = model.label
    spin = rec["spin_rate"]
    spin_ok = np.isfinite(spin)
    if not spin_ok.any():
        return out | {"swing_duration_s": None, "reason": "no valid spin samples"}
    rho_mean = float(np.mean(spin[spin_ok]))
    out["mean_spin_rad_s"] = rho_mean
    warp = env = ratio = None
    notes = []
    if spin_ok.sum() > 10 and "spin_decay" in corrections:
        warp, env, ratio, note = _spin_warp(t, spin, spin_ok, rho_mean)
        if note:
            notes.append(note)
    try:
        fit, warp = _fit_swing(t, y, warp, env, ratio, corrections)
    except EstimationError as exc:
        return out | {"swing_duration_s": None, "reason": f"no oscillation measured: {exc}; {model.null_reason}"}
    snr = detection_snr(fit.amplitude, fit.n_samples, fit.residual_rms)
    checks.append(signal_entry(inst.name, snr, DETECTION_SNR))
    if snr < DETECTION_SNR:
        return out | {"swing_duration_s": None,
                      "reason": f"no oscillation detected (SNR {snr:.3g} < {DETECTION_SNR:g}); {model.null_reason}"}
    entry = check_period(inst.name, inst, 2.0 * math.pi / fit.omega_rad_s)
    if entry:
        checks.append(entry)
    fit = _with_damping(t, y, fit, warp, env, notes)
    if sensor is not None:
        checks.append(check_fit(inst.name, fit.residual_rms, fit.n_samples - (2 + 2 * 2 + bool(fit.damping_per_s)),
                                sensor))
    a = fit.amplitude
    if fit.damping_per_s:
        tau = (t - np.mean(t))
        a = a * math.sqrt(float(np.mean(np.exp(-2 * fit.damping_per_s * tau))))
    F = finite_amplitude_factor(a) if "finite_amplitude" in corrections else 1.0
    T = fit.swing_duration_s
    T0 = T / F
    sig_T0 = fit.swing_duration_sigma_s / F
    crlb_T0 = math.pi * fit.crlb_omega_rad_s / fit.omega_rad_s ** 2 / F
    out.update({"swing_duration_s": T, "swing_duration_sigma_s": fit.swing_duration_sigma_s,
                "small_amplitude_swing_duration_s": T0, "small_amplitude_swing_duration_sigma_s": sig_T0,
                "crlb_swing_duration_s": crlb_T0 * F, "amplitude_rad": a, "finite_amplitude_factor": F,
                "period_s": 2 * T, "noise_rad": fit.residual_rms, "fit_method": fit.method,
                "samples": fit.n_samples, "notes": notes + fit.notes})
    out["counting"] = _counting(t, y, F)
    out["_measurement"] = _gyro_measurement(inst, model, T0, sig_T0, crlb_T0, rho_mean, out)
    return out


def estimate_records(scene, insts, records, corrections=CORRECTIONS) -> dict:
    """The ``estimate`` JSON object (see module docstring) from measured records.

    ``corrections`` — the subset of :data:`CORRECTIONS` to apply (all by default); a study of
    what a correction is worth passes fewer.

    Raises
    ------
    gyro_instrument.estimators.adequacy.InadequateData
        The data fail a check no estimate can survive (estimators/adequacy.py): one line naming
        the check, and, in a scene of several instruments, how to leave the failing one out.
    """
    unknown = set(corrections) - CORRECTIONS
    if unknown:
        raise ValueError(f"unknown corrections {sorted(unknown)}; known: {sorted(CORRECTIONS)}")
    site = scene.site
    result = {"scene": scene.name, "seed": scene.seed, "observation_s": float(scene.duration_s),
              "truth": {"latitude_deg": site.latitude_deg, "earth_rate_rad_s": site.earth_rate_rad_s},
              "instruments": {}, "methods": {}}
    meas, gyros, pend, checks = [], {}, None, []
    sensor = SensorModel.from_scene(scene)
    for name, inst in insts.items():
        try:
            est, m = _instrument_estimate(name, inst, records[name], corrections, checks, sensor)
        except InadequateData as exc:
            if len(insts) > 1:
                exc.add_hint(f"or leave {name} out: --set instruments.{name}=null")
            raise
        result["instruments"][name] = est
        if m is not None:
            meas.append(m)
            if m.kind == "pendulum":
                pend = (inst, est, m)
            else:
                gyros[name] = (inst, est, m)
    if meas:
        result.update(_combined(meas, scene.estimator.get("hemisphere"), *known_earth_rate(scene, meas),
                                earth_rate=scene.estimator.get("earth_rate")))
    else:
        result.update(_null_combined("no Earth-rate measurement: needs a gyroscope with a directing line "
                                     "(plane, cone, gimbal) or a pendulum with a measured oscillation"))
    _classic_methods(result, gyros, pend, scene.estimator.get("earth_rate"))
    entry = hemisphere_entry(result.get("hemisphere"), result.get("hemisphere_basis", ""), site.latitude_deg)
    result["checks"] = checks + ([entry] if entry else [])
    return result


#: The corrections that undo the finite-amplitude law. An instrument whose model can leave the
#: ``finite_amplitude`` effect out (it is in its SUPPORTED_EFFECTS) and does is a small-angle model:
#: it swings in T0 at any amplitude and its apsides turn at exactly k, so correcting it would bias
#: the rate (by 2 x 6e-4 at 0.1 rad). Instruments without that choice (the gimbal, the compound
#: pendulum) always integrate the exact, nonlinear equations.
FINITE_AMPLITUDE_CORRECTIONS = frozenset(("finite_amplitude", "ellipse_precession"))


def small_angle_model(inst) -> bool:
    """True when the instrument is simulated in its small-angle (linear) model (see
    :data:`FINITE_AMPLITUDE_CORRECTIONS`)."""
    return "finite_amplitude" in type(inst).SUPPORTED_EFFECTS and not inst.has("finite_amplitude")


def _instrument_estimate(name, inst, rec, corrections, checks, sensor):
    """(the instrument's entry of the estimate, its RateMeasurement or None); appends its checks."""
    if small_angle_model(inst):
        corrections = frozenset(corrections) - FINITE_AMPLITUDE_CORRECTIONS
    if ("angle" in rec and inst.directing_model() is not None) or "deflection_east" in rec:
        checks += check_before_fit(name, inst, rec)
    if "angle" in rec and inst.directing_model() is not None:
        est = _gyro_estimate(inst, rec, corrections, checks, sensor)
        return est, est.pop("_measurement", None)
    if "deflection_east" in rec:
        return _pendulum_estimate(name, inst, rec, corrections, checks, sensor)
    return {"type": inst.type_name, "reason": "not used by the estimator (no Earth-rate measurement from this "
                                              "instrument)"}, None


def _pendulum_estimate(name, inst, rec, corrections, checks, sensor):
    """The Foucault rate of one pendulum record (estimators/foucault.py) and its checks."""
    try:
        f = estimate_foucault(rec["t"], rec["deflection_east"], rec["deflection_north"],
                              correct_ellipse="ellipse_precession" in corrections,
                              noise_rad=sensor.effective_sigma_rad())
    except EstimationError as exc:
        if isinstance(exc, NoSignal):
            checks.append(check_entry(name, "signal", "no_signal", str(exc), expected=DETECTION_SNR))
        return {"type": inst.type_name, "foucault_rate_rad_s": None, "reason": str(exc)}, None
    est = {"type": inst.type_name, "foucault_rate_rad_s": f.k_rad_s,
           "foucault_rate_sigma_rad_s": f.k_sigma_rad_s, "crlb_foucault_rate_rad_s": f.crlb_k_rad_s,
           "measured_plane_rate_rad_s": f.measured_rate_rad_s,
           "ellipse_correction_rad_s": f.airy_correction_rad_s, "amplitude_rad": f.amplitude_rad,
           "minor_axis_rad": f.minor_axis_rad, "period_s": f.period_s, "windows": f.windows,
           "notes": f.notes}
    checks.append(check_entry(name, "signal", "passed", f"swing detected (A^2 N / (4 sigma^2) >= {DETECTION_SNR:g}; "
                                                       "estimators/foucault.py)", expected=DETECTION_SNR))
    entry = check_period(name, inst, f.period_s)
    if entry:
        checks.append(entry)
    checks.append(plane_fit_entry(name, f.plane_chi2_per_dof, f.plane_dof, f.noise_rad))
    # a noise-free record's bound is 0; the combination weights it as exact (1/σ² finite)
    return est, RateMeasurement(name, "pendulum", f.k_rad_s, f.k_sigma_rad_s, crlb_sigma=max(f.crlb_k_rad_s, 1e-150))


def known_earth_rate(scene, meas) -> tuple:
    """(n, source): the Earth rate the estimator may take as known — the scene's
    ``site.earth_rate_rad_s`` (IERS conventional 7.292115e-5 rad/s by default) — or (None, "") when
    no measured instrument simulates ``earth_rotation`` (a non-rotating Earth has no known n)."""
    from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S
    names = {m.name for m in meas}
    rotating = any("earth_rotation" in scene.instruments[n][2] for n in names if n in scene.instruments)
    if not rotating:
        return None, ""
    n = scene.site.earth_rate_rad_s
    source = ("the IERS conventional value, the scene's site.earth_rate_rad_s" if n == SIDEREAL_RATE_RAD_S
              else "the scene's site.earth_rate_rad_s")
    return n, source


def _combined(meas, hemisphere=None, n_known=None, n_source="", earth_rate=None):
    """The combined latitude and Earth rate (profile likelihood) with their Cramér–Rao bounds from
    the same mode, and what the instruments cannot determine (hemisphere, separability); Earth's
    rate held at ``n_known`` where they cannot separate it from the latitude (or where
    ``earth_rate`` = 'known'), said in ``earth_rate_basis``."""
    how = {"earth_rate": earth_rate, "n_known": n_known, "n_source": n_source}
    sol = solve_latitude(meas, hemisphere=hemisphere, **how)
    deg = lambda x: None if x is None else math.degrees(x)  # noqa: E731
    out = {"earth_rate_rad_s": sol.earth_rate_rad_s, "earth_rate_sigma_rad_s": sol.earth_rate_sigma_rad_s,
           "earth_rate_known": sol.earth_rate_known, "earth_rate_basis": sol.earth_rate_basis,
           "hemisphere": sol.hemisphere, "hemisphere_basis": sol.hemisphere_basis}
    if sol.latitude_rad is None:
        out.update({"latitude_deg": None, "latitude_sigma_deg": None, "reason": sol.reason,
                    "crlb": {"latitude_deg": None, "earth_rate_rad_s": sol.earth_rate_sigma_rad_s},
                    "method": (f"weighted mean over {len(meas)} measurement(s) independent of the latitude"
                               if sol.earth_rate_rad_s is not None else None)})
        return out
    crlb = solve_latitude(meas, use_crlb=True, domain=sol.domain, **how)
    out.update({"latitude_deg": math.degrees(sol.latitude_rad), "latitude_sigma_deg": deg(sol.latitude_sigma_rad),
                "latitude_interval_deg": [math.degrees(sol.latitude_lo_rad), math.degrees(sol.latitude_hi_rad)],
                "latitude_interval_3sigma_deg": [math.degrees(v) for v in sol.interval_3sigma_rad],
                "latitude_is_absolute": sol.latitude_is_absolute,
                "crlb": {"latitude_deg": deg(crlb.latitude_sigma_rad), "earth_rate_rad_s": crlb.earth_rate_sigma_rad_s},
                "carried_by": sol.carried_by, "chi2": sol.chi2, "dof": sol.dof})
    if sol.sigma_reason:
        out["latitude_sigma_reason"] = sol.sigma_reason
    if sol.other_modes:
        out["other_latitudes_deg"] = [{"latitude_deg": math.degrees(g), "delta_chi2": d} for g, d in sol.other_modes]
    if sol.dropped:
        out["left_out_of_latitude"] = sol.dropped
    lead = max(sol.carried_by, key=sol.carried_by.get)
    kinds = "+".join(sorted({("pendulum" if m.kind == "pendulum" else "gyroscope") for m in meas}))
    out["method"] = (f"{'least squares over the latitude with n known' if sol.earth_rate_known else 'profile least squares'}"
                     f" over {kinds} ({len(meas)} measurement{'s' if len(meas) > 1 else ''}); "
                     f"latitude carried by {lead} ({100 * sol.carried_by[lead]:.1f} % of the information)")
    return out


def _null_combined(reason):
    return {"latitude_deg": None, "latitude_sigma_deg": None, "earth_rate_rad_s": None,
            "earth_rate_sigma_rad_s": None, "crlb": {"latitude_deg": None, "earth_rate_rad_s": None},
            "hemisphere": HEMISPHERE_UNDETERMINED, "method": None, "reason": reason}


def _classic_methods(result, gyros, pend, earth_rate=None):
    """Quet's item 9 and eq. (10), and the pendulum-only results, side by side (the pendulum's
    asin(k/n) with the nominal n only where ``earth_rate`` (``estimator.earth_rate``) allows a known n)."""
    methods = result["methods"]
    hor = [g for g in gyros.values() if g[0].directing_model().label == "horizontal"]
    mer = [g for g in gyros.values() if g[0].directing_model().label == "meridian"]
    if hor and mer:
        _item9(result, hor[0], mer[0], pend)
    elif hor or mer:
        methods["item9"] = {"latitude_deg": None, "reason": "item 9 needs both a horizontal and a meridian "
                            "configuration with a measured oscillation"}
    if mer:
        im, em, mm = mer[0]
        model = im.directing_model()
        n = mm.value
        methods["item8_eq10"] = {"earth_rate_rad_s": n, "earth_rate_sigma_rad_s": mm.sigma,
                                 "formula": "n = pi^2 / (mu rho0 T_m^2) (eq. 10; item 8's printed pi/(mu rho0 T^2) is a misprint)",
                                 "gain": model.gain}
    if pend is not None and pend[1].get("foucault_rate_rad_s") is not None:
        methods["foucault"] = _foucault_method(result, pend, earth_rate)


def _item9(result, hor, mer, pend):
    """Quet's item 9, cos γ = (T_m/T_h)² ρ_m/ρ_h, from the first horizontal and meridian gyroscopes
    (``methods["item9"]``, and ``methods["item9_counting"]`` from the counted swings)."""
    methods = result["methods"]
    (ih, eh, mh), (im, em, mm) = hor, mer
    # cos γ = y_h / y_m with y = K/(gain ρ): Quet's (T_m/T_h)² ρ_m/ρ_h, with the finite-amplitude
    # and (gimbal) ring-inertia corrections carried by T0 and the gains.
    c = mh.value / mm.value
    rel = math.hypot(mh.sigma / mh.value, mm.sigma / mm.value)
    entry = {"cos_latitude": c, "cos_latitude_sigma": c * rel}
    if c + c * rel >= 1.0 and c <= 1.0 + 3 * c * rel:
        entry.update({"latitude_deg": None,
                      "reason": f"cos(latitude) = {c:.9f} is within 1 sigma ({c * rel:.2g}) of 1: near the "
                                "equator item 9 cannot resolve the latitude (cos is flat, "
                                "d(latitude) = d(cos)/sin(latitude) diverges)"
                                + ("; the pendulum carries the latitude" if pend is not None else "")})
    elif 0.0 < c <= 1.0:
        lat = math.degrees(math.acos(c))
        # cos is even: the sign comes from the combination's hemisphere (measured by a pendulum, or
        # the user's estimator.hemisphere); otherwise item 9 reports |latitude|
        hemi = result.get("hemisphere")
        sign = {"north": 1.0, "south": -1.0}.get(hemi, 1.0)
        entry["hemisphere"] = hemi if hemi in ("north", "south") else HEMISPHERE_UNDETERMINED
        entry["latitude_is_absolute"] = hemi not in ("north", "south")
        s = math.sqrt(max(1 - c * c, 0.0))
        lo = math.degrees(math.acos(min(c + c * rel, 1.0)))
        hi = math.degrees(math.acos(max(c - c * rel, 0.0)))
        entry.update({"latitude_deg": sign * lat, "latitude_sigma_deg": 0.5 * (hi - lo),
                      "linear_sigma_deg": (math.degrees(c * rel / s) if s > 0 else None)})
    else:
        entry.update({"latitude_deg": None, "reason": f"(T_m/T_h)^2 rho_m/rho_h = {c:.9g} is outside (0, 1]"})
    # uncorrected (printed T at unequal amplitudes, no spin ratio) for comparison
    entry["uncorrected_cos_latitude"] = (em["swing_duration_s"] / eh["swing_duration_s"]) ** 2
    ch, cm = eh.get("counting", {}), em.get("counting", {})
    if ch.get("swing_duration_s") and cm.get("swing_duration_s"):
        gain_ratio = im.directing_model().gain / ih.directing_model().gain
        cc = item9_cos_latitude(cm["small_amplitude_swing_duration_s"], ch["small_amplitude_swing_duration_s"],
                                em["mean_spin_rad_s"], eh["mean_spin_rad_s"]) * gain_ratio
        methods["item9_counting"] = {"cos_latitude": cc,
                                     "latitude_deg": math.degrees(math.acos(cc)) if 0 < cc <= 1 else None,
                                     "swings": [ch["swings"], cm["swings"]]}
    methods["item9"] = entry


def _foucault_method(result, pend, earth_rate=None):
    """The pendulum alone: latitude from k / n (n from eq. (10) when a meridian gyroscope gave it,
    else the nominal sidereal rate) and n = k / sin(latitude from item 9)."""
    methods = result["methods"]
    k, sk = pend[1]["foucault_rate_rad_s"], pend[1]["foucault_rate_sigma_rad_s"]
    entry = {"foucault_rate_rad_s": k, "foucault_rate_sigma_rad_s": sk}
    n_ref = methods.get("item8_eq10", {}).get("earth_rate_rad_s")
    if n_ref is None and earth_rate == "estimate":
        entry.update({"latitude_deg": None, "reason": "asin(k / n) needs n: no meridian gyroscope measures it, and "
                                                      "estimator.earth_rate: estimate forbids taking it as known"})
        n_ref = math.nan
    elif n_ref is None:
        n_ref = result["truth"]["earth_rate_rad_s"]
        entry["note"] = "latitude from k / n with the nominal sidereal n (no meridian gyroscope)"
    x = k / n_ref
    if not math.isfinite(x):
        pass
    elif abs(x) <= 1.0 + 3 * sk / n_ref:
        xc = max(min(x, 1.0), -1.0)
        lo = math.degrees(math.asin(max(xc - sk / n_ref, -1.0)))
        hi = math.degrees(math.asin(min(xc + sk / n_ref, 1.0)))
        entry.update({"latitude_deg": math.degrees(math.asin(xc)), "latitude_sigma_deg": 0.5 * (hi - lo)})
    else:
        entry.update({"latitude_deg": None, "reason": f"k/n = {x:.6g} exceeds 1 by more than 3 sigma"})
    lat9 = methods.get("item9", {}).get("latitude_deg")
    if abs(k) < 3 * sk:
        entry["earth_rate_rad_s"] = None
        entry["reason_earth_rate"] = ("the pendulum does not precess measurably here (|k| < 3 sigma_k, as at "
                                      "the equator): n = k / sin(latitude) is undetermined")
    elif lat9 is None:
        entry["earth_rate_rad_s"] = None
        entry["reason_earth_rate"] = "n = k / sin(latitude) needs the latitude from item 9, which is null here"
    else:
        s = math.sin(math.radians(lat9))
        entry["earth_rate_rad_s"] = k / s
        entry["earth_rate_sigma_rad_s"] = sk / abs(s)
        entry["earth_rate_formula"] = "n = k / sin(latitude from item 9): needs no inertia ratio"
    return entry


def seed_sweep(job) -> list:
    """Estimates of one scene over many sensor seeds, simulating the truth once.

    ``job`` = (scene name or path, overrides, seeds) — one picklable argument, so a sweep can be
    ``executor.map``-ed over any ``concurrent.futures`` executor. Returns the estimate dicts.
    """
    name, overrides, seeds = job
    scene = load_scene(name, list(overrides))
    truth = simulate_truth(scene)
    return [estimate_records(scene, truth[1], measure(scene, truth, s)) for s in seeds]
