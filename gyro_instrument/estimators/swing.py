"""A swing about a directing line, fitted: from a record to a rate y = n s(γ) with its σ and bound.

The fit is the estimator's (:func:`~.period.fit_oscillation`: fundamental and third harmonic, in a
spin-warped time when the spin changed, with damping when it lowers the residual); every law is the
observation's (:class:`~gyro_instrument.instruments.observation.SwingRate`): the amplitude law F(a)
that reduces the swing to small amplitude, the spin law that warps the time and scales the envelope,
and the directing law that turns the small-amplitude swing duration T0 and the mean spin ρ̄ into the
rate (Quet 1853 sec. 4 §1 eq. 9: K = (π/T0)² = gain n ρ s(γ)) with its σ and Cramér–Rao bound.
"""

import math

import numpy as np

from gyro_instrument.estimators.adequacy import check_fit, check_period, detection_snr, signal_entry
from gyro_instrument.estimators.entries import Counting, CountingNull, SwingEntry, SwingNull
from gyro_instrument.estimators.latitude import RateMeasurement
from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, count_oscillations, fit_oscillation
from gyro_instrument.estimators.record import ABSENT
from gyro_instrument.instruments.observation import AMPLITUDE_CORRECTION, CORRECTIONS, SPIN_CORRECTION


def spin_warp(obs, t, spin, spin_ok, rho_mean) -> tuple:
    """Time warp and adiabatic envelope from the measured spin history, or Nones when the spin did not
    change measurably.

    The spin is smoothed by a quadratic in log|ρ| (exact for the viscous bearing's e^(-t/τ), and for
    any slow law over a run shorter than its time scale: a quadratic in ρ itself is 0.5 % off over
    one τ); τ = ∫ ω(ρ)/ω(ρ̄) dt and the envelope a(ρ)/a(ρ̄), both the observation's spin law
    (:meth:`~gyro_instrument.instruments.observation.SwingRate.spin_frequency`, ``spin_envelope``;
    Quet's √(ρ/ρ̄) and (ρ/ρ̄)^(−1/4)).

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
        freq = obs.spin_frequency(ratio)
        warp = np.concatenate([[0.0], np.cumsum(0.5 * (freq[1:] + freq[:-1]) * np.diff(t))])
        env = obs.spin_envelope(ratio)
        return warp, env, ratio, f"spin changed by {change / abs(rho_mean):.3g} relative: fitted in spin-warped time"
    return None, None, None, None


def _fit_swing(obs, t, y, warp, env, ratio, corrections):
    """The sine fit (fundamental and third harmonic) of a gyroscope's swing, refitted once in a
    time also warped by the observation's amplitude law when the spin changed; raises EstimationError.

    Returns
    -------
    tuple
        (fit, warp actually used).
    """
    fit = fit_oscillation(t, y, harmonics=(1, 3), warp=warp, envelope=env)
    if warp is not None and AMPLITUDE_CORRECTION in corrections:
        # the swing lengthens as its amplitude grows (a ∝ ρ^-1/4 for Quet's law): the instantaneous
        # rate is ω_small(ρ(t)) / F(a(t)), so warp by F(a_ref)/F(a(t)) too and refit once
        a_t = abs(fit.amplitude) * env
        rate = obs.spin_frequency(ratio) * obs.amplitude_factor(abs(fit.amplitude)) / obs.amplitude_factor(a_t)
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
        return Counting(swing_duration_s=c.swing_duration_s, swing_duration_sigma_s=c.swing_duration_sigma_s,
                        swings=c.swings, small_amplitude_swing_duration_s=c.swing_duration_s / F)
    except EstimationError as exc:
        return CountingNull(swing_duration_s=None, reason=str(exc))


def swing_estimate(obs, rec, corrections=CORRECTIONS, checks=None, sensor=None) -> tuple:
    """Fit one swing record: swing duration, small-amplitude conversion, counting baseline, and the
    rate the observation's law gives (:meth:`~gyro_instrument.instruments.observation.SwingRate.measured_rate`).

    ``checks`` (list) receives the ``signal``, ``period`` and ``fit`` checks (:mod:`.adequacy`, with
    ``sensor`` the scene's :class:`SensorModel`); raises :class:`.adequacy.InadequateData`.

    Returns
    -------
    (SwingEntry or SwingNull, RateMeasurement or None)
        The instrument's entry of the estimate and its rate measurement (None when no swing is measured).
    """
    checks = [] if checks is None else checks
    inst = obs.instrument
    t, y = rec["t"], rec["angle"]
    out = {"type": obs.type_name, "configuration": obs.label}
    null = lambda why: (SwingNull(**out, swing_duration_s=None, reason=why), None)  # noqa: E731
    spin = rec[obs.spin_channel]
    spin_ok = np.isfinite(spin)
    if not spin_ok.any():
        return null("no valid spin samples")
    rho_mean = float(np.mean(spin[spin_ok]))
    out["mean_spin_rad_s"] = rho_mean
    warp = env = ratio = None
    notes = []
    if spin_ok.sum() > 10 and SPIN_CORRECTION in corrections:
        warp, env, ratio, note = spin_warp(obs, t, spin, spin_ok, rho_mean)
        if note:
            notes.append(note)
    try:
        fit, warp = _fit_swing(obs, t, y, warp, env, ratio, corrections)
    except EstimationError as exc:
        return null(f"no oscillation measured: {exc}; {obs.null_reason}")
    obs.rate_terms(rec)
    why = obs.rate_withheld(fit.amplitude)
    if why:
        return null(why)
    snr = detection_snr(fit.amplitude, fit.n_samples, fit.residual_rms)
    checks.append(signal_entry(obs.name, snr, DETECTION_SNR))
    if snr < DETECTION_SNR:
        return null(f"no oscillation detected (SNR {snr:.3g} < {DETECTION_SNR:g}); {obs.null_reason}")
    entry = check_period(obs.name, inst, 2.0 * math.pi / fit.omega_rad_s)
    if entry:
        checks.append(entry)
    fit = _with_damping(t, y, fit, warp, env, notes)
    if sensor is not None:
        checks.append(check_fit(obs.name, fit.residual_rms, fit.n_samples - (2 + 2 * 2 + bool(fit.damping_per_s)),
                                sensor))
    return _swing_result(obs, out, fit, rec, notes, rho_mean, corrections)


def _swing_result(obs, out, fit, rec, notes, rho_mean, corrections):
    """The swing's entry (durations, amplitude law, counting) and its rate measurement."""
    t, y = rec["t"], rec["angle"]
    a = fit.amplitude
    if fit.damping_per_s:
        tau = (t - np.mean(t))
        a = a * math.sqrt(float(np.mean(np.exp(-2 * fit.damping_per_s * tau))))
    F = obs.amplitude_factor(a) if AMPLITUDE_CORRECTION in corrections else 1.0
    T = fit.swing_duration_s
    # viscous damping (ü + 2δu̇ + ω_u² u = 0) swings at ω_d = √(ω_u² − δ²): the restoring constant is
    # ω_u² = ω_d² + δ² (δ²/ω² = 5e-5 on the gyrotheodolite: 0.0026° of latitude, 1.8σ, uncorrected)
    undamped = math.sqrt(1.0 + (fit.damping_per_s / fit.omega_rad_s) ** 2) if fit.damping_per_s else 1.0
    T0 = T / F / undamped
    sig_T0 = fit.swing_duration_sigma_s / F
    crlb_T0 = math.pi * fit.crlb_omega_rad_s / fit.omega_rad_s ** 2 / F
    out.update({"swing_duration_s": T, "swing_duration_sigma_s": fit.swing_duration_sigma_s,
                "small_amplitude_swing_duration_s": T0, "small_amplitude_swing_duration_sigma_s": sig_T0,
                "crlb_swing_duration_s": crlb_T0 * F, "amplitude_rad": a, "finite_amplitude_factor": F,
                "period_s": 2 * T, "noise_rad": fit.residual_rms, "fit_method": fit.method,
                "samples": fit.n_samples, "notes": notes + fit.notes})
    out["counting"] = _counting(t, y, F)
    r = obs.measured_rate(T0, sig_T0, crlb_T0, rho_mean)
    extra = dict(r.extra)
    second = extra.pop("second_order_correction", ABSENT)
    entry = SwingEntry(**out, second_order_correction=second, extra=extra or ABSENT)
    return entry, RateMeasurement(obs.name, obs.MEASUREMENT, r.value, r.sigma, obs.normal_enu, True, r.crlb)
