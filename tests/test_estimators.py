"""Estimator: periods at the Cramér–Rao bound, Quet's items 8-9, the Foucault rate with its
ellipse correction, calibrated uncertainty, and null-with-reason at the singular latitudes.

Reference: the Cramér–Rao bound of a sinusoid's frequency, var(ω̂) ≥ 24σ²/(A²Δt²N(N²−1)) (Rife &
Boorstyn 1974, IEEE Trans. Inf. Theory 20(5) 591; estimators/period.py); through Quet 1853 sec. 4 §1
item 9 the quet_paris example (μ=2, ρ0=2π·100 rad/s, σ=1e-4 rad, A=0.1 rad, 20 Hz, 10 min) allows
≈0.14″ of latitude (this project's propagation, estimators/bounds.py).
"""

import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.estimators.foucault import estimate_foucault
from gyro_instrument.estimators.period import (EstimationError, count_oscillations, crlb_omega,
                                               fit_oscillation)
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.scenes import load_scene


def sine(t, A=0.1, w=0.5, phi=0.3):
    return A * np.cos(w * t + phi)


def test_fit_reaches_cramer_rao_bound_on_clean_sinusoids():
    # 300 noisy records: the empirical rms of ω̂ must sit at the bound (within 15 %, the sampling
    # spread of an rms from 300 draws is ~4 %) and the reported σ within 10 % of it.
    rng = np.random.default_rng(1)
    t = np.arange(0, 200, 0.05)
    errs, sig = [], []
    for _ in range(300):
        f = fit_oscillation(t, sine(t) + rng.normal(0, 1e-3, t.size))
        errs.append(f.omega_rad_s - 0.5)
        sig.append(f.omega_sigma_rad_s)
    bound = crlb_omega(1e-3, 0.1, 0.05, t.size)
    assert np.sqrt(np.mean(np.square(errs))) / bound == pytest.approx(1.0, abs=0.15)
    assert np.mean(sig) / bound == pytest.approx(1.0, abs=0.10)


def test_counting_is_orders_of_magnitude_worse_than_the_fit():
    # Quet's counting resolves one swing in N (~1e4 times worse than the fit: measured here, and in
    # the plan example of docs/cli.md, 1.73e4x).
    rng = np.random.default_rng(2)
    t = np.arange(0, 600, 0.05)
    y = sine(t, w=math.pi / 12.8) + rng.normal(0, 1e-4, t.size)
    f = fit_oscillation(t, y)
    c = count_oscillations(t, y)
    fit_err = abs(f.swing_duration_s - 12.8)
    count_err = abs(c.swing_duration_s - 12.8)
    assert fit_err < 5 * f.swing_duration_sigma_s
    assert count_err > 100 * fit_err
    assert c.swing_duration_sigma_s > 1000 * f.swing_duration_sigma_s


def test_fit_handles_nan_gaps_duplicates_and_quantization():
    # NaN samples, a 100 s gap, duplicated and shuffled stamps, 1e-4 rad quantization: the fitted
    # ω stays within 4 of its reported σ of the truth, and the notes say what was dropped.
    rng = np.random.default_rng(3)
    t = np.arange(0, 600, 0.05)
    y = np.round((sine(t) + rng.normal(0, 1e-4, t.size)) / 1e-4) * 1e-4
    y[rng.random(t.size) < 0.05] = np.nan
    keep = (t < 200) | (t > 300)
    t2, y2 = np.concatenate([t[keep], t[keep][:50]]), np.concatenate([y[keep], y[keep][:50]])
    perm = rng.permutation(t2.size)
    f = fit_oscillation(t2[perm], y2[perm])
    assert abs(f.omega_rad_s - 0.5) < 4 * f.omega_sigma_rad_s
    assert any("non-finite" in n for n in f.notes) and any("duplicated" in n for n in f.notes)


def test_fit_with_damping_and_spin_warp():
    # Damped record: the damped model recovers ω within 4σ; the undamped fit's residual is larger.
    rng = np.random.default_rng(4)
    t = np.arange(0, 600, 0.05)
    y = np.exp(-t / 300) * sine(t) + rng.normal(0, 1e-4, t.size)
    f = fit_oscillation(t, y, damping=True)
    assert abs(f.omega_rad_s - 0.5) < 4 * f.omega_sigma_rad_s
    assert f.damping_per_s == pytest.approx(1 / 300, rel=0.02)
    # Spin decaying 10 % over the record: frequency ∝ √ρ; the warp τ = ∫√(ρ/ρ̄)dt makes it a
    # sinusoid of ω at ρ̄ (checked within 4σ).
    rho = 1.0 - 0.1 * t / 600
    rbar = rho.mean()
    w0 = 0.5
    phase = np.concatenate([[0], np.cumsum(0.5 * (np.sqrt(rho[1:] / rbar) + np.sqrt(rho[:-1] / rbar)) * np.diff(t))])
    y = 0.1 * (rho / rbar) ** -0.25 * np.cos(w0 * phase) + rng.normal(0, 1e-4, t.size)
    f = fit_oscillation(t, y, warp=phase, envelope=(rho / rbar) ** -0.25)
    assert abs(f.omega_rad_s - w0) < 4 * f.omega_sigma_rad_s
    naive = fit_oscillation(t, y)
    assert abs(naive.omega_rad_s - w0) > 10 * f.omega_sigma_rad_s


def test_too_short_or_flat_record_is_refused_clearly():
    t = np.arange(0, 10, 0.05)
    with pytest.raises(EstimationError, match="cycles"):
        fit_oscillation(t, sine(t, w=0.5))
    with pytest.raises(EstimationError, match="too few"):
        fit_oscillation(t[:3], sine(t[:3]))


# Seeds per latitude: 200 at Paris and at -33.9 (the issue-3 acceptance: an rms from 200 draws has a
# relative sampling spread of 1/sqrt(400) = 5 %, so the 1.3 bound is 6 spreads); 60 at 5, 70 and 85 deg in
# the default run (spread 1/sqrt(120) = 9 %: the same 1.3 bound is still 3.3 spreads; measured
# 2026-11-30: rms/sigma = 0.969, 1.038, 0.975 with 60 seeds against 1.000, 1.002, 1.021 with 200), the
# 200-seed runs there in `pytest -m slow` (the whole suite must stay under 15 min on 2 cores).
def _calibration(lat, seeds, *marks):
    """One case, its seed sweep declared (submitted to the session's pool when collection ends)."""
    sweep = pytest.mark.seed_sweep("quet_paris", [f"site.latitude_deg={lat}"], seeds)
    return pytest.param(lat, seeds, marks=(sweep, *marks), id=f"{lat}-{seeds}" + ("-slow" if marks else ""))


CALIBRATION_CASES = [_calibration(lat, n) for lat, n in ((48.8462, 200), (-33.9, 200), (5.0, 60), (70.0, 60),
                                                         (85.0, 60))] + [
    _calibration(lat, 200, pytest.mark.slow) for lat in (5.0, 70.0, 85.0)]


@pytest.mark.parametrize("lat,seeds", CALIBRATION_CASES)
def test_latitude_uncertainty_is_calibrated_over_seeds(sweep_seeds, lat, seeds):
    # Issue 3 acceptance: default run within 3σ; σ within 1.5× the Cramér–Rao bound; over the
    # seeded runs the rms error within 1.3× the reported σ (see CALIBRATION_CASES for the sampling
    # spread), for the latitude and the Earth rate. The seeds run on the session's process pool.
    results = sweep_seeds("quet_paris", [f"site.latitude_deg={lat}"], seeds)
    rows = np.array([(r["latitude_deg"] - lat, r["latitude_sigma_deg"], r["crlb"]["latitude_deg"],
                      r["earth_rate_rad_s"] - r["truth"]["earth_rate_rad_s"], r["earth_rate_sigma_rad_s"])
                     for r in results])
    seeds = [*range(0, seeds, 2), *range(1, seeds, 2)]        # sweep_seeds' order
    err, sig, crlb, nerr, nsig = rows.T
    d = seeds.index(load_scene("quet_paris").seed)
    assert abs(err[d]) < 3 * sig[d]          # the scene's default seed
    assert np.all(sig < 1.5 * crlb)
    assert np.sqrt(np.mean(err ** 2)) < 1.3 * np.mean(sig)
    assert np.sqrt(np.mean(nerr ** 2)) < 1.3 * np.mean(nsig)
    assert abs(np.mean(err)) < 3 * np.mean(sig) / math.sqrt(len(err))   # no bias beyond 3 standard errors


def run_json(capsys, *overrides):
    args = ["estimate", "quet_paris", "--json"]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 0
    return json.loads(capsys.readouterr().out)


def test_json_has_the_documented_fields(capsys):
    r = run_json(capsys)
    for key in ("latitude_deg", "latitude_sigma_deg", "earth_rate_rad_s", "earth_rate_sigma_rad_s", "method",
                "observation_s", "truth", "crlb", "instruments", "methods"):
        assert key in r
    assert set(r["truth"]) == {"latitude_deg", "earth_rate_rad_s"}
    assert set(r["crlb"]) == {"latitude_deg", "earth_rate_rad_s"}
    assert r["instruments"]["gyro_horizontal"]["swing_duration_s"] > 0
    assert abs(r["latitude_deg"] - 48.8462) < 3 * r["latitude_sigma_deg"]
    # Quet's counting side by side, and far worse than the fit (>= 100 σ away here)
    cnt = r["methods"]["item9_counting"]["latitude_deg"]
    assert abs(cnt - 48.8462) > 100 * r["latitude_sigma_deg"]


@pytest.mark.parametrize("lat", [90.0, -90.0])
def test_pole_horizontal_gyro_is_null_with_reason_pendulum_gives_latitude(capsys, lat):
    # Quet item 4: at a pole the horizontal plane is perpendicular to Earth's axis — no torque.
    r = run_json(capsys, f"site.latitude_deg={lat}")
    h = r["instruments"]["gyro_horizontal"]
    assert h["swing_duration_s"] is None and "restoring torque" in h["reason"]
    assert r["methods"]["item9"]["latitude_deg"] is None and r["methods"]["item9"]["reason"]
    # sin γ is flat at the pole: the 1-sigma region reaches it, so no local sigma but both intervals
    assert r["latitude_deg"] is not None and r["latitude_sigma_deg"] is None
    assert "reaches a pole" in r["latitude_sigma_reason"]
    lo3, hi3 = r["latitude_interval_3sigma_deg"]
    assert lo3 <= lat <= hi3
    assert r["carried_by"]["pendulum"] > 0.5 or r["carried_by"].get("gyro_horizontal", 0) == 0
    json.dumps(r, allow_nan=False)


def test_equator_pendulum_earth_rate_null_gyroscopes_give_latitude(capsys):
    # At the equator the pendulum does not precess: n = k / sin γ is undetermined (null + reason);
    # the latitude is still given, within 3σ of 0.
    r = run_json(capsys, "site.latitude_deg=0")
    f = r["methods"]["foucault"]
    assert f["earth_rate_rad_s"] is None and "does not precess" in f["reason_earth_rate"]
    assert abs(r["latitude_deg"]) <= 3 * r["latitude_sigma_deg"]
    assert r["earth_rate_rad_s"] == pytest.approx(7.2921150e-5, abs=3 * r["earth_rate_sigma_rad_s"])
    json.dumps(r, allow_nan=False)


def test_unequal_amplitudes_and_spins_corrected_uncorrected_biased(capsys):
    # 0.1 rad horizontal, 0.05 rad meridian, spins 100 and 80 turn/s: the corrected item 9 is
    # unbiased within 1σ (averaged over 8 seeds: the mean of 8 has σ/√8); the uncorrected
    # (T_m/T_h)² is off by the amplitude term ≈ (a_m² − a_h²)/8 and the spin ratio 0.8.
    over = ["instruments.gyro_meridian.initial_angle_deg=2.8647889756541161",
            "instruments.gyro_meridian.spin_rate_rad_s=502.6548245743669"]
    scene = load_scene("quet_paris", over)
    truth = simulate_truth(scene)
    errs, sigs, unc = [], [], []
    for seed in range(8):
        r = estimate_records(scene, truth[1], measure(scene, truth, seed))
        errs.append(r["methods"]["item9"]["latitude_deg"] - 48.8462)
        sigs.append(r["methods"]["item9"]["latitude_sigma_deg"])
        unc.append(r["methods"]["item9"]["uncorrected_cos_latitude"])
    assert abs(np.mean(errs)) < np.mean(sigs) / math.sqrt(8) * 3
    assert abs(np.mean(errs)) < np.mean(sigs)
    c_true = math.cos(math.radians(48.8462))
    expected_unc = c_true / 0.8 * (1 + (0.05 ** 2 - 0.1 ** 2) / 8)
    assert np.mean(unc) == pytest.approx(expected_unc, rel=2e-4)
    assert abs(math.degrees(math.acos(min(np.mean(unc), 1.0))) - 48.8462) > 100 * np.mean(sigs) \
        or np.mean(unc) > 1


def test_spin_decay_over_one_time_constant_is_followed():
    # quet_paris with bearing friction τ = 1 h over a whole hour (the spin falls to 1/e), noise-free.
    # Eq. (9): T ∝ ρ^(-1/2), and adiabatically a ∝ ρ^(-1/4), so the swing lengthens through both ρ
    # and (2/π)K(sin(a/2)). The estimator fits in the time warped by the measured spin (smoothed in
    # log ρ) and the amplitude-dependent rate: the gyroscope pair's bias must stay near the
    # Cramér–Rao bound of the noisy hour (2.7e-6°, 2.4e-12 rad/s; bench observation_time.csv).
    # Measured: 2.3e-6° and 6.2e-12 rad/s (the adiabatic approximation's own error, ε = 1/(τω) ≈ 1e-3);
    # bounds 4e-6° and 2e-11 rad/s. Without the correction eq. (10) is off by ~6e-6 rad/s.
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    from gyro_instrument.estimators.pipeline import CORRECTIONS
    scene = load_scene("quet_paris", ["duration_s=3600", "effects.spin_decay.time_constant_s=3600"] + list(NOISE_FREE))
    truth = simulate_truth(scene)
    rec = measure(scene, truth)
    r = estimate_records(scene, truth[1], rec)
    assert abs(r["methods"]["item9"]["latitude_deg"] - 48.8462) < 4e-6
    assert abs(r["methods"]["item8_eq10"]["earth_rate_rad_s"] - 7.292115e-5) < 2e-11
    assert any("spin-warped" in n for n in r["instruments"]["gyro_meridian"]["notes"])
    raw = estimate_records(scene, truth[1], rec, corrections=CORRECTIONS - {"spin_decay"})
    assert abs(raw["methods"]["item8_eq10"]["earth_rate_rad_s"] - 7.292115e-5) > 1e-6
    with pytest.raises(ValueError, match="unknown corrections"):
        estimate_records(scene, truth[1], rec, corrections={"air_drag"})


def test_foucault_launch_ellipse_corrected_within_2_sigma():
    # A launch with a transverse speed opens a wide ellipse whose Airy precession
    # (3/8)ω0 a b / l² is ~6 % of k here; the corrected k agrees with n sin γ within 2σ, the
    # uncorrected swing-plane rate does not (> 10σ off).
    scene = load_scene("foucault_pantheon", ["instruments.pendulum.transverse_speed_m_s=0.05", "duration_s=1800"])
    truth = simulate_truth(scene)
    rec = measure(scene, truth, 3)["pendulum"]
    f = estimate_foucault(rec["t"], rec["deflection_east"], rec["deflection_north"])
    k = scene.site.k_vertical_rad_s
    assert abs(f.k_rad_s - k) < 2 * f.k_sigma_rad_s
    assert abs(f.measured_rate_rad_s - k) > 10 * f.k_sigma_rad_s


def test_foucault_release_from_rest_removes_quet_lag():
    # Released from rest, the swing plane lags by (3/8) θ0 sin θ0 cos(θ0/2) (sec. 2 §III); the
    # correction computed from the data alone removes it: 1 h, noise 1e-6 rad so the 4.6e-4
    # lag stands at many σ.
    scene = load_scene("foucault_pantheon", ["sensor.noise_rad=1e-6"])
    truth = simulate_truth(scene)
    rec = measure(scene, truth, 1)["pendulum"]
    f = estimate_foucault(rec["t"], rec["deflection_east"], rec["deflection_north"])
    k = scene.site.k_vertical_rad_s
    lag = 0.375 * math.radians(2) * math.sin(math.radians(2)) * math.cos(math.radians(1))
    assert f.measured_rate_rad_s / k - 1 == pytest.approx(-lag, rel=0.05)
    assert abs(f.k_rad_s / k - 1) < 0.05 * lag


def test_gimbal_pair_t_prime_t_second_gives_latitude_with_ring_correction(capsys):
    # Quet sec. 4 §IV: "the values of T', T'' can serve to determine n and γ". With the thick
    # inner ring (C1 = 1.2 A1) the estimator's gains C/(A + C1 + A2) and C/(A + A1) recover γ and n
    # within 3σ; Quet's thin-ring A + 2A1 + A2 would be off by 5 % in T'² (not used).
    assert main(["estimate", "gimbal_paris", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert abs(r["latitude_deg"] - 48.8462) < 3 * r["latitude_sigma_deg"]
    assert abs(r["earth_rate_rad_s"] - 7.2921150e-5) < 3 * r["earth_rate_sigma_rad_s"]
    assert r["latitude_sigma_deg"] < 1.5 * r["crlb"]["latitude_deg"]
