"""σ of a rate from the record's own scatter when its residuals are not white.

A line fitted through one value per swing (a swing plane's azimuth ψ_i at the window centres t_i)
has the white-noise σ of the sensor's noise (the Cramér–Rao bound of the record) only when the
values scatter about the line as that noise says. Real pendulums (a drive, an anisotropic support,
air) move the plane slowly: the residuals are then correlated from swing to swing and the rate
itself differs between the first and the second half of the record. Three tests decide
(:func:`line_with_record_sigma`):

* χ²/dof of the residuals against the white σ beyond 1 + 5 √(2/dof) (the adequacy band);
* the lag-1 autocorrelation r1 of the residuals beyond :data:`AUTOCORR_Z` / √n (white residuals:
  r1 ≈ N(−1/n, 1/n), Box & Jenkins, *Time Series Analysis*, 1976, §6.2.1, Bartlett's formula);
* the two halves' rates differing by more than :data:`HALVES_Z` σ (each half's σ the larger of its
  white σ, √8 times the whole record's for a line, and its own residual scatter).

If every test passes the white σ stands (simulated white noise stays at the Cramér–Rao bound). If
one fails, σ comes from the record's own scatter: the largest of (a) the residuals' scatter about
the line (ordinary least squares), (b) the Newey–West heteroskedasticity- and autocorrelation-
consistent (HAC) standard error of the slope (W. K. Newey and K. D. West, "A simple, positive
semi-definite, heteroskedasticity and autocorrelation consistent covariance matrix", Econometrica
55 (1987) 703–708; Bartlett weights 1 − j/(L + 1), L = ⌊4 (n/100)^(2/9)⌋ lags, Newey and West,
Rev. Econ. Stud. 61 (1994) 631–653) and (c) swing-to-swing blocks: the line through the means of
blocks of 2, 4, 8 ... consecutive swings (at least :data:`MIN_BLOCKS` blocks), whose scatter grows
with the block until the blocks are uncorrelated (the blocking method of H. Flyvbjerg and H. G.
Petersen, "Error estimates on averages of correlated data", J. Chem. Phys. 91 (1989) 461–466,
applied to the slope); its largest value is taken. The basis is stated (``sigma_basis``).
"""

import math
from dataclasses import dataclass

import numpy as np

#: Residuals' lag-1 autocorrelation above AUTOCORR_Z/√n: correlated from swing to swing (3.5 σ of
#: white residuals' r1, a false alarm once in ~4000 records).
AUTOCORR_Z = 3.5

#: The halves' rates differ by more than this many σ: they disagree (as the site check's 4 σ).
HALVES_Z = 4.0

#: Fewest values for the autocorrelation and halves tests (3 per half for a line with a dof).
MIN_FOR_TESTS = 6

#: Fewest blocks a blocked line's scatter is taken from (6 degrees of freedom).
MIN_BLOCKS = 8

WHITE = "white"
RECORD = "record scatter"


@dataclass
class LineSigma:
    """A rate (slope) with its σ and how σ was decided.

    ``sigma_basis`` is :data:`WHITE` (the white-noise σ given) or :data:`RECORD`; ``reasons`` names
    the failed tests; ``halves`` = (rate of the first half, its σ, of the second, its σ, z) or None.
    """

    rate: float
    sigma: float
    sigma_basis: str
    white_sigma: float
    ols_sigma: float
    hac_sigma: float
    block_sigma: float
    chi2_per_dof: float
    dof: int
    autocorrelation: float
    halves: tuple | None
    reasons: list
    hac_lags: int = 0

    def basis_text(self) -> str:
        """``sigma_basis`` in words, for the estimate's notes and JSON."""
        if self.sigma_basis == WHITE:
            return "white noise: the record's noise through the Cramer-Rao bound (residuals white)"
        return (f"record scatter ({'; '.join(self.reasons)}): the largest of the residuals' scatter (OLS), "
                f"Newey-West HAC ({self.hac_lags} lags, Bartlett) and swing-to-swing blocks")


def slope(t, y) -> tuple:
    """(slope, intercept at mean t, residuals, centred t) of the least-squares line. Sums by numpy's
    pairwise reduction, not BLAS's dot: the same doubles under every BLAS kernel (the shipped bags'
    estimates are compared across OPENBLAS_CORETYPE choices; the pendulum's rest-point drift fed
    through the ellipse correction moved k by 2e-12 relative between kernels with ``@``)."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    x = t - t.mean()
    sxx = float(np.sum(x * x))
    b = float(np.sum(x * (y - y.mean())) / sxx) if sxx > 0 else 0.0
    a = float(y.mean())
    return b, a, y - a - b * x, x


def newey_west_slope_sigma(x, u, lags) -> float:
    """Newey–West HAC standard error of a line's slope (Newey and West 1987; Bartlett weights):
    var = Σ_j w_j Σ_t x_t u_t x_(t−j) u_(t−j) (j = −L..L) / (Σ x²)², x centred times, u residuals."""
    xu = x * u
    s = float(xu @ xu)
    for j in range(1, lags + 1):
        s += 2.0 * (1.0 - j / (lags + 1.0)) * float(xu[j:] @ xu[:-j])
    sxx = float(x @ x)
    return math.sqrt(max(s, 0.0)) / sxx if sxx > 0 else math.inf


def newey_west_mean_sigma(u, lags) -> float:
    """Newey–West HAC standard error of a mean of correlated values (same weights)."""
    u = np.asarray(u, float) - np.mean(u)
    n = u.size
    s = float(u @ u)
    for j in range(1, lags + 1):
        s += 2.0 * (1.0 - j / (lags + 1.0)) * float(u[j:] @ u[:-j])
    return math.sqrt(max(s, 0.0)) / n if n else math.inf


def nw_lags(n) -> int:
    """Newey and West (1994)'s rule of thumb ⌊4 (n/100)^(2/9)⌋, at least 1."""
    return max(1, int(4.0 * (n / 100.0) ** (2.0 / 9.0)))


def blocked_slope_sigma(t, y) -> float:
    """The largest OLS slope σ over lines through block means of 1, 2, 4 ... consecutive values with
    at least :data:`MIN_BLOCKS` blocks (Flyvbjerg and Petersen 1989's blocking, on the slope)."""
    n, size, best = len(t), 1, 0.0
    while n // size >= MIN_BLOCKS:
        m = n // size
        tb = np.asarray(t[:m * size]).reshape(m, size).mean(axis=1)
        yb = np.asarray(y[:m * size]).reshape(m, size).mean(axis=1)
        _, _, u, x = slope(tb, yb)
        sxx = float(x @ x)
        if sxx > 0:
            best = max(best, math.sqrt(float(u @ u) / (m - 2) / sxx))
        size *= 2
    return best


def line_with_record_sigma(t, y, white_sigma) -> LineSigma:
    """The least-squares rate of ``y`` over ``t`` (one value per swing) with σ as the module says.

    ``white_sigma``: the slope's σ the sensor's white noise gives (0 for a noise-free record).
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    n = t.size
    b, _, u, x = slope(t, y)
    dof = max(n - 2, 1)
    sxx = float(x @ x)
    ols = math.sqrt(float(u @ u) / dof / sxx) if sxx > 0 else math.inf
    chi2 = (ols / white_sigma) ** 2 if white_sigma > 0 else math.inf
    reasons = []
    if not chi2 <= 1.0 + 5.0 * math.sqrt(2.0 / dof):
        reasons.append(f"chi2/dof {chi2:.3g} over {dof}")
    uu = float(u @ u)
    r1 = float(u[1:] @ u[:-1]) / uu if uu > 0 and n > 1 else 0.0
    halves = None
    lags = nw_lags(n)
    hac = newey_west_slope_sigma(x, u, lags) if n > 2 else math.inf
    block = blocked_slope_sigma(t, y)
    if n >= MIN_FOR_TESTS:
        if r1 > AUTOCORR_Z / math.sqrt(n):
            reasons.append(f"swing-to-swing autocorrelation {r1:.2f} > {AUTOCORR_Z / math.sqrt(n):.2f}")
        h = n // 2
        parts = []
        for a, c in ((0, h), (h, n)):
            bh, _, uh, xh = slope(t[a:c], y[a:c])
            sh = float(xh @ xh)
            own = math.sqrt(float(uh @ uh) / max(c - a - 2, 1) / sh) if sh > 0 else math.inf
            parts.append((bh, max(white_sigma * math.sqrt(8.0), own)))
        (b1, s1), (b2, s2) = parts
        s12 = math.hypot(s1, s2)
        z = (b2 - b1) / s12 if s12 > 0 else (0.0 if b2 == b1 else math.inf)
        halves = (b1, s1, b2, s2, z)
        if not abs(z) <= HALVES_Z:
            reasons.append(f"halves differ by {abs(z):.3g} sigma")
    if not reasons:
        return LineSigma(b, white_sigma, WHITE, white_sigma, ols, hac, block, chi2, dof, r1, halves, reasons, lags)
    sigma = max(white_sigma, ols, hac if math.isfinite(hac) else 0.0, block)
    return LineSigma(b, sigma, RECORD, white_sigma, ols, hac, block, chi2, dof, r1, halves, reasons, lags)
