"""The live north's growing fit (issue 37 item 5, estimators/north/live.py) on synthetic swings.

A damped swing u(t) = c + A e^(−δt) cos(ωt) in white noise σ, the fit's prior frequency 1 % off
(the predicted swing duration is a calibration, not the truth). References: the generating c, ω,
δ (independent of the code); the undamped relation ω_u² = ω_d² + δ² (a damped oscillator,
derived in estimators/north/fit.py's undamped_omega). Tolerances: the centre within 4 σ of its own reported σ (a 4-σ
miss has probability 6e-5 per look); σ non-increasing to 5 % (a refit moves its linearisation
point) and below a tenth of the first after ten swings.
"""

import math

import numpy as np

from gyro_instrument.estimators.north.live import NorthTracker, SwingFit, fit_north


def _swing(c=0.01, a=0.02, swing_s=12.8, tau_s=3000.0, sigma=1e-4, rate_hz=20.0, duration_s=300.0, seed=3):
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    w = math.pi / swing_s
    rng = np.random.default_rng(seed)
    return t, c + a * np.exp(-t / tau_s) * np.cos(w * t) + rng.normal(0.0, sigma, t.size)


def test_the_fit_covers_the_centre_from_the_first_swing_and_sharpens():
    t, u = _swing()
    fit = SwingFit(12.8 * 1.01, 1e-4)              # the prediction 1 % long
    sig = []
    for k in range(64, t.size, 64):
        s = fit.update(t[:k], u[:k])
        if s is None:
            assert t[k - 1] < 12.8 * 1.01           # nothing before one (predicted) swing of data
            continue
        est = fit_north(s)
        sig.append(est.sigma_rad)
        assert abs(est.centre_rad - 0.01) < 4 * est.sigma_rad
    assert all(b <= a * 1.05 for a, b in zip(sig, sig[1:]))
    assert sig[-1] < sig[0] / 10
    assert abs(fit.summary.omega_rad_s - math.pi / 12.8) < 1e-4 * math.pi / 12.8    # the data, not the prior


def test_the_reversal_points_give_the_undamped_half_period():
    """δ from the decay of the deviations: π/√(ω_d² + δ²) (the tape ratio needs the stiffness)."""
    swing, tau = 12.8, 200.0                         # strong damping: ω_u exceeds ω_d by (δ/ω)²/2 = 2e-4 relative (2.7 ms of the swing)
    t, u = _swing(swing_s=swing, tau_s=tau, sigma=1e-6, duration_s=200.0)
    tr = NorthTracker(swing, 1e-6)
    for k in range(64, t.size, 64):
        tr.update(t[max(k - int(tr.window_s() * 20), 0):k], u[max(k - int(tr.window_s() * 20), 0):k])
    h_u, _ = tr.undamped_half_period()
    w_d = math.pi / swing
    # the damped turning points of c + A e^(-δt) cos(ω t) are spaced π/ω; the undamped π/√(ω² + δ²)
    # within a thousandth of the damping shift (+ 1 µs): the damped spacing itself would miss by 2.7 ms
    assert abs(h_u - math.pi / math.sqrt(w_d ** 2 + (1 / tau) ** 2)) < 1e-3 * (swing - h_u) + 1e-6
