"""The Foucault estimator on records as sensors and loggers leave them (issue 22, found by trying it
as a user): samples lost at random, and clocks whose stamps are not exactly uniform (Unix-epoch
seconds, whole milliseconds at 15 Hz). The swept area is integrated chord by chord with each
interval's own deficit (foucault.areal_segments) and the noise from 6th divided differences on
the actual times (foucault.noise_from_differences): neither assumes a uniform grid."""

import math

import numpy as np
import pytest
from scipy.stats import chi2

from gyro_instrument.estimators.foucault import estimate_foucault, noise_from_differences
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.scenes import load_scene


@pytest.fixture(scope="module")
def pantheon():
    sc = load_scene("foucault_pantheon", ["duration_s=1800", "sensor.dropout_fraction=0.2"])
    return sc, simulate_truth(sc)


def test_lost_samples_leave_the_rate_calibrated(pantheon):
    # 20 % of the samples lost at random (the sensor model's dropouts): 20 seeds, rms(err/σ) within
    # χ²₂₀'s 0.05-99.95 % points; σ/bound per seed in [0.95, 1.1] (the bound counts the lost samples
    # as fewer samples). The symptom was errors of -17σ, +10σ, -18σ.
    sc, truth = pantheon
    k = sc.site.k_vertical_rad_s
    rows = []
    for seed in range(20):
        p = estimate_records(sc, truth[1], measure(sc, truth, seed))["instruments"]["pendulum"]
        rows.append((p["foucault_rate_rad_s"] - k, p["foucault_rate_sigma_rad_s"], p["crlb_foucault_rate_rad_s"]))
    err, sig, crlb = np.array(rows).T
    lo, hi = (math.sqrt(chi2.ppf(q, 20) / 20) for q in (5e-4, 1 - 5e-4))
    assert lo <= math.sqrt(np.mean((err / sig) ** 2)) <= hi
    assert np.all((sig / crlb >= 0.95) & (sig / crlb <= 1.1))


@pytest.mark.parametrize("clock", ["unix_epoch", "whole_ms_15hz"])
def test_a_clock_that_is_not_exactly_uniform_changes_nothing(clock):
    # the same swing and noise, stamped by a Unix-epoch clock (t + 1.7e9 s in a double: steps jitter
    # by its 2.4e-7 s resolution) or a whole-millisecond clock at 15 Hz (66/67 ms): the rate moves by
    # far less than its σ (timing errors of 0.5 ms move a sample by v δt <= 2e-6 rad against 1e-4
    # rad of noise) and the noise estimate stays the sensor's to its sampling spread (1/√(2N))
    sc = load_scene("foucault_pantheon", ["duration_s=1800", "sample_rate_hz=15"])
    t, insts, sims = truth = simulate_truth(sc)
    rec = measure(sc, truth, 3)["pendulum"]
    e, n = rec["deflection_east"], rec["deflection_north"]
    if clock == "unix_epoch":
        stamped = (t + 1.7e9) - 1.7e9
    else:
        stamped = np.round(t * 1000.0) / 1000.0
    assert not np.all(np.diff(stamped) == np.diff(stamped)[0])
    exact = estimate_foucault(t, e, n, noise_rad=1e-4)
    other = estimate_foucault(stamped, e, n, noise_rad=1e-4)
    assert abs(other.k_rad_s - exact.k_rad_s) < 0.1 * exact.k_sigma_rad_s
    assert other.k_sigma_rad_s == pytest.approx(exact.k_sigma_rad_s, rel=0.01)
    assert noise_from_differences(stamped, e, n) == pytest.approx(1e-4, rel=5 / math.sqrt(2 * 2 * t.size))
