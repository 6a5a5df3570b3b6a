"""The sine fit's fast paths give the numbers of the textbook calls they replace: the polish is
MINPACK's lmder with least_squares(method="lm")'s settings (same iterates, same minimum), the FFT's
low-frequency cut is rfftfreq's, and the fitted swing of a known oscillation is within its standard
error of the truth."""

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from gyro_instrument.estimators.period import _bins_below, _OscillationModel, fit_oscillation


def _records():
    rng = np.random.default_rng(7)
    t = np.arange(0.0, 300.0, 0.05)
    rho = 1.0 + 0.1 * t / t[-1]
    warp = np.cumsum(np.sqrt(rho)) * 0.05
    yield t, 0.1 * np.cos(0.245 * t + 0.3) + rng.normal(0, 1e-4, t.size), None, (1, 3), False
    yield t, 0.5 * np.cos(1.1 * t) - 0.01 * np.cos(3.3 * t) + rng.normal(0, 1e-3, t.size), None, (1, 3, 5), False
    yield t, np.exp(-0.002 * t) * np.sin(0.7 * t) + rng.normal(0, 1e-3, t.size), None, (1,), True
    yield warp, rho ** -0.25 * np.cos(0.3 * warp) + rng.normal(0, 1e-3, t.size), rho ** -0.25, (1,), False


@pytest.mark.parametrize("case", range(4))
def test_polish_is_least_squares_lm(case):
    """model.polish (scipy.optimize.leastsq, Jacobian column-major, trig kept per ω) returns the
    parameters, residuals, cost and Jacobian of least_squares(method='lm', x_scale='jac',
    xtol=ftol=1e-15) from the same start, bit for bit: the same MINPACK iterates."""
    tau, y, env, harmonics, damping = list(_records())[case]
    tau = tau - tau.mean()
    model = _OscillationModel(tau, y, env, harmonics, damping)
    w0 = {0: 0.245, 1: 1.1, 2: 0.7, 3: 0.3}[case] * (1 + 2e-4)
    sol = model.polish(w0)
    X0 = model.design(w0)
    c0, *_ = np.linalg.lstsq(X0, y, rcond=None)
    q0 = [w0] + ([0.0] if damping else []) + list(c0)
    ref = least_squares(lambda q: model.values(q) - y, q0, jac=model.jac, method="lm", x_scale="jac",
                        xtol=1e-15, ftol=1e-15)
    assert sol.success and ref.success
    np.testing.assert_array_equal(sol.x, ref.x)
    np.testing.assert_array_equal(sol.fun, ref.fun)
    np.testing.assert_array_equal(sol.jac, ref.jac)
    assert sol.cost == ref.cost


def test_low_bins_cut_like_rfftfreq():
    """_bins_below(fmin, 1/(n dt), n//2+1) counts exactly the rfftfreq(n, dt) bins below fmin,
    including fmin on a bin, just below one, 0, negative, NaN and infinite."""
    rng = np.random.default_rng(3)
    for _ in range(3000):
        n = int(2 ** rng.integers(3, 16))
        dt = float(rng.choice([0.05, 0.01, 1 / 3, rng.uniform(1e-4, 2)]))
        f = np.fft.rfftfreq(n, dt)
        k = int(rng.integers(0, f.size))
        for fmin in (f[k], np.nextafter(f[k], 0.0), rng.uniform(0, 1.2 * f[-1]), 0.0, -1.0, math.inf, math.nan):
            assert _bins_below(float(fmin), 1.0 / (n * dt), f.size) == int(np.count_nonzero(f < fmin))


def test_repeated_fits_same_numbers_and_truth():
    """A record fitted twice gives identical results (the kept Hann window and unit waves are not
    altered by a fit), and the fitted ω of a 0.245 rad/s swing with its third harmonic lies within
    4 of its standard errors of the truth, with that error within 20 % of the Cramér–Rao bound."""
    rng = np.random.default_rng(0)
    t = np.arange(0, 600, 0.05)
    y = 0.1 * np.cos(0.245 * t) + 2e-3 * np.cos(3 * 0.245 * t) + rng.normal(0, 1e-4, t.size)
    a = fit_oscillation(t, y, harmonics=(1, 3))
    b = fit_oscillation(t, y, harmonics=(1, 3))
    assert vars(a) == vars(b)
    assert abs(a.omega_rad_s - 0.245) < 4 * a.omega_sigma_rad_s
    assert a.omega_sigma_rad_s == pytest.approx(a.crlb_omega_rad_s, rel=0.2)
