"""The error model of a single-axis rate gyroscope: turn-on bias, bias instability, angle random walk.

A rate gyro's output (rad/s) is the rate about its sensitive axis, times (1 + scale factor), plus
its bias and noise (IEEE Std 952-1997, the single-axis interferometric fiber optic gyro model; the
same terms for a MEMS gyro, Analog Devices "Gyroscope angle random walk" / "Gyroscope in-run bias
stability", https://ez.analog.com/mems/w/documents/4509 and /4510)::

    r_k = (1 + s) ω_k + b0 + g_k + w_k

- b0, the turn-on bias: one draw per run, N(0, σ_b0²) (a datasheet's bias repeatability);
- g_k, the bias instability: a first-order Gauss–Markov process (stationary AR(1) at the sample
  spacing Δ, g_{k+1} = ρ g_k + √(1 − ρ²) σ_g ε_k, ρ = exp(−Δ/τ_c)); its Allan deviation peaks at
  τ ≈ 1.89 τ_c with the value :data:`GM_ALLAN_PEAK` σ_g (computed below from the GM Allan variance,
  IEEE Std 952 annex C), so σ_g = B / GM_ALLAN_PEAK makes the peak equal the datasheet's bias
  instability B, quoted as the Allan deviation's minimum (Analog Devices' convention: "in-run bias
  stability is the lowest point of the Allan variance", ez.analog.com/docs/DOC-16082). A flicker
  floor is flat over decades of τ; one Gauss–Markov matches it at its peak only (stated, not hidden);
- w_k, the angle random walk: white rate noise; a sample averaging the rate over Δ has
  σ_w = N / √Δ, N the ARW in rad/√s (N[°/√h] · (π/180) / 60).

Covariance of the noise (what the estimator's least squares uses, exactly):
Cov(g_i + w_i, g_j + w_j) = σ_g² ρ^|i−j| + σ_w² δ_ij; b0 is a parameter, not noise.
"""

import math

import numpy as np

#: °/h -> rad/s
DEG_H = math.pi / 180.0 / 3600.0
#: °/√h -> rad/√s
DEG_RT_H = math.pi / 180.0 / 60.0


def gm_allan_variance(tau_s, sigma, tc_s) -> np.ndarray:
    """Allan variance of a stationary first-order Gauss–Markov process of standard deviation
    ``sigma`` and correlation time ``tc_s`` at cluster times ``tau_s`` (IEEE Std 952-1997 annex C,
    with q_c² = 2σ²/τ_c): σ_A² = (2σ² τ_c²/τ²)(τ/τ_c − 3/2 + 2e^(−τ/τ_c) − ½ e^(−2τ/τ_c))."""
    x = np.asarray(tau_s, dtype=float) / tc_s
    return 2.0 * sigma ** 2 / x ** 2 * (x - 1.5 + 2.0 * np.exp(-x) - 0.5 * np.exp(-2.0 * x))


def _allan_peak() -> tuple:
    x = np.linspace(0.5, 5.0, 45001)
    v = np.sqrt(gm_allan_variance(x, 1.0, 1.0))
    i = int(np.argmax(v))
    return float(v[i]), float(x[i])


#: (peak Allan deviation / σ_g, τ_peak / τ_c) of a Gauss–Markov process: (0.6175, 1.89)
GM_ALLAN_PEAK, GM_ALLAN_PEAK_TAU = _allan_peak()


class GyroErrors:
    """The seeded error draws of one rate gyro, block by block (equal to one draw of the whole run).

    Parameters
    ----------
    arw_rad_rt_s : float
        Angle random walk N, rad/√s.
    sigma_gm_rad_s : float
        σ_g of the Gauss–Markov bias instability, rad/s.
    tc_s : float
        Its correlation time τ_c, s.
    turn_on_rad_s : float
        σ of the turn-on bias b0, rad/s.
    dt_s : float
        Sample spacing Δ, s.
    rng : numpy.random.Generator
        Drawn in a fixed order: (b0, g_0) once, then per sample (w, ε) rows; blocks of any size
        concatenate to the one-shot draw bit for bit (``lfilter`` carries the AR(1) state).
    """

    def __init__(self, arw_rad_rt_s, sigma_gm_rad_s, tc_s, turn_on_rad_s, dt_s, rng) -> None:
        self.sigma_w = arw_rad_rt_s / math.sqrt(dt_s)
        self.sigma_g = sigma_gm_rad_s
        self.rho = math.exp(-dt_s / tc_s)
        self.turn_on = turn_on_rad_s
        self.rng = rng
        self.state = None            # lfilter's AR(1) state (the last g), after the first block
        self.b0 = None

    def draw(self, n) -> np.ndarray:
        """The next ``n`` samples of b0 + g_k + w_k (rad/s)."""
        if self.b0 is None:
            first = self.rng.standard_normal(2)
            self.b0 = self.turn_on * first[0]
            self.state = np.array([self.rho * self.sigma_g * first[1]])
        from scipy.signal import lfilter       # here, not at import: scipy.signal costs every command ~1 s
        e = self.rng.standard_normal((int(n), 2))
        drive = math.sqrt(1.0 - self.rho ** 2) * self.sigma_g * e[:, 1]
        g, self.state = lfilter([1.0], [1.0, -self.rho], drive, zi=self.state)
        return self.b0 + g + self.sigma_w * e[:, 0]


def block_sums(first_index, counts, rho) -> tuple:
    """Σ_{m,n ∈ I_i × I_j} ρ^|m−n| for runs of consecutive sample indices I_i = [p_i, p_i + n_i)
    (sorted, disjoint): the exact covariance of run sums of a unit AR(1) process.

    Within a run: n (1 + ρ)/(1 − ρ) − 2ρ(1 − ρⁿ)/(1 − ρ)²; between runs i < j:
    ρ^(p_j − q_i) (1 − ρ^n_i)(1 − ρ^n_j)/(1 − ρ)², q_i = p_i + n_i − 1 the last index of run i.
    Returns the (k, k) matrix (``rho`` in [0, 1); ρ = 0 gives diag(n))."""
    p = np.asarray(first_index, dtype=float)
    n = np.asarray(counts, dtype=float)
    if rho <= 0.0:
        return np.diag(n)
    om = 1.0 - rho
    geo = -np.expm1(n * math.log(rho)) / om                 # (1 − ρⁿ)/(1 − ρ), stable for ρ → 1
    q = p + n - 1.0
    gap = p[None, :] - q[:, None]                            # p_j − q_i
    cross = np.exp(np.maximum(gap, gap.T) * math.log(rho)) * geo[:, None] * geo[None, :]
    within = n * (1.0 + rho) / om - 2.0 * rho * geo / om
    cross[np.diag_indices_from(cross)] = within
    return cross
