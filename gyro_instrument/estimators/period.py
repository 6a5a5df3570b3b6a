"""Period and frequency estimation from samples.

``fit_oscillation`` is a least-squares sine fit by variable projection: for a trial angular
frequency ω the amplitudes enter linearly and are solved in closed form, so only ω is searched
(bracketed around an FFT peak, refined by Brent's method), then the full covariance comes from
the Jacobian of all parameters. On clean sinusoids in white noise it reaches the Cramér–Rao bound
var(ω̂) ≥ 24 σ² / (A² Δt² N (N² − 1)) (Rife & Boorstyn 1974, single-tone estimation). Extensions for real records:

* NaN samples and gaps are dropped (uneven sampling is fine for least squares);
* ``damping=True`` adds an exponential envelope e^(−λt) (fitted by ``least_squares``);
* ``warp``: a known time warp τ(t) and envelope — used with the measured spin history of a
  decaying rotor, τ = ∫ √(ρ/ρ̄) dt and envelope (ρ/ρ̄)^(−1/4) (adiabatic invariant), so the fitted ω
  is the one at the mean spin ρ̄;
* ``harmonics`` adds odd harmonics for finite-amplitude (anharmonic) swings;
* quantization acts as extra white noise q²/12 and is absorbed by the residual variance.

``count_oscillations`` is Quet's literal method — count the swings in a fixed time — kept as the
historical baseline: its error is one swing in N (≈ 10⁴ times worse than the fit).
"""

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import OptimizeResult, leastsq, minimize_scalar



@dataclass
class OscillationFit:
    """Result of :func:`fit_oscillation`.

    Attributes
    ----------
    omega_rad_s, omega_sigma_rad_s : float
        Angular frequency of the fundamental and its standard error.
    swing_duration_s, swing_duration_sigma_s : float
        Quet's T = π/ω (one swing, half a period) and its standard error.
    amplitude : float
        Peak amplitude of the fitted oscillation at the reference time (signal units).
    residual_rms : float
        RMS of the residuals (estimate of the noise σ).
    crlb_omega_rad_s : float
        Cramér–Rao bound on σ(ω) for this record and the fitted noise.
    n_samples : int
    damping_per_s : float
    method : str
    """

    omega_rad_s: float
    omega_sigma_rad_s: float
    amplitude: float
    residual_rms: float
    crlb_omega_rad_s: float
    n_samples: int
    observation_s: float
    damping_per_s: float = 0.0
    method: str = "sine_fit"
    notes: list = field(default_factory=list)

    @property
    def swing_duration_s(self) -> float:
        return math.pi / self.omega_rad_s

    @property
    def swing_duration_sigma_s(self) -> float:
        return math.pi * self.omega_sigma_rad_s / self.omega_rad_s ** 2

    @property
    def crlb_swing_duration_s(self) -> float:
        return math.pi * self.crlb_omega_rad_s / self.omega_rad_s ** 2


#: Detection threshold: an oscillation counts when A² N / (4 σ²) exceeds this (the periodogram
#: peak of pure noise is ~ln N ≈ 10 for N ~ 1e4).
DETECTION_SNR = 100.0


class EstimationError(ValueError):
    """The record cannot give the requested quantity (too short, no oscillation, ...)."""


class NoSignal(EstimationError):
    """No oscillation detected above the noise (the ``signal`` check's ``no_signal``)."""


def crlb_omega(sigma, amplitude, dt, n) -> float:
    """Cramér–Rao bound on σ(ω̂) for a sinusoid of amplitude A in white noise σ, N samples Δt apart:
    √(24 σ² / (A² Δt² N (N² − 1)))."""
    if n < 3 or amplitude <= 0:
        return math.inf
    return math.sqrt(24.0 * sigma ** 2 / (amplitude ** 2 * dt ** 2 * n * (n * n - 1.0)))


@functools.lru_cache(maxsize=8)
def _hanning(n):
    """``np.hanning(n)``, kept read-only for the next record of the same length."""
    w = np.hanning(n)
    w.setflags(write=False)
    return w


@functools.lru_cache(maxsize=8)
def _unit_waves(harmonics):
    """cos hφ and sin hφ on 4097 phases φ over one cycle, for each harmonic (read-only)."""
    phase = np.linspace(0.0, 2 * math.pi, 4097)
    out = tuple((np.cos(h * phase), np.sin(h * phase)) for h in harmonics)
    for c, s_ in out:
        c.setflags(write=False)
        s_.setflags(write=False)
    return out


def fft_guess(t, y, min_cycles=1.0) -> float:
    """Angular frequency of the strongest FFT peak (zero-padded, resampled if uneven)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    dt = float(np.median(np.diff(t)))
    grid = np.arange(t[0], t[-1], dt)
    yi = np.interp(grid, t, y - np.mean(y))
    n = 1 << int(math.ceil(math.log2(max(len(grid), 8)) + 3))
    spec = np.abs(np.fft.rfft(yi * _hanning(len(yi)), n))
    fmin = min_cycles / (t[-1] - t[0])
    spec[:_bins_below(fmin, 1.0 / (n * dt), len(spec))] = 0.0
    if not np.any(spec > 0):
        raise EstimationError("no oscillation found in the record")
    k = int(np.argmax(spec))
    if 0 < k < len(spec) - 1:  # parabolic refinement on the log spectrum
        a, b, c = np.log(spec[k - 1:k + 2] + 1e-300)
        k = k + 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) != 0 else k
    return 2.0 * math.pi * k / (n * dt)


def _bins_below(fmin, df, size):
    """Number of FFT bins k (of ``size``) with frequency k·df below ``fmin`` (Hz), the frequencies
    being ``np.fft.rfftfreq``'s k·df (so the same bins as masking ``rfftfreq(n, dt) < fmin``)."""
    if not fmin > 0.0:                       # NaN or ≤ 0: no bin lies below
        return 0
    if fmin > (size - 1) * df:               # every bin (also fmin = inf)
        return size
    k = int(fmin / df)
    while k < size and k * df < fmin:
        k += 1
    while k > 0 and (k - 1) * df >= fmin:
        k -= 1
    return k


def _clean_record(t, y, warp, envelope):
    """Drop non-finite samples (of any of the arrays), sort by time, drop duplicated time stamps.

    Returns
    -------
    tuple
        (t, y, warp, envelope, notes): the cleaned arrays (``warp``/``envelope`` None when not
        given) and one note per kind of change.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    if warp is not None:
        warp = np.asarray(warp, dtype=float)
        ok &= np.isfinite(warp)
    if envelope is not None:
        envelope = np.asarray(envelope, dtype=float)
        ok &= np.isfinite(envelope)
    notes = []
    if ok.sum() < len(ok):
        notes.append(f"{int(len(ok) - ok.sum())} non-finite samples dropped")
    t, y = t[ok], y[ok]
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(order) < 0):
        notes.append("samples re-ordered by time")
    t, y = t[order], y[order]
    if warp is not None:
        warp = warp[ok][order]
    if envelope is not None:
        envelope = envelope[ok][order]
    if t.size > 1:
        keep = np.concatenate([[True], np.diff(t) > 0])
        if not keep.all():
            notes.append(f"{int((~keep).sum())} duplicated time stamps dropped")
            t, y = t[keep], y[keep]
            warp = warp[keep] if warp is not None else None
            envelope = envelope[keep] if envelope is not None else None
    return t, y, warp, envelope, notes


class _OscillationModel:
    """The model fitted by :func:`fit_oscillation` on (warped) times ``tau``: a constant plus, for
    each harmonic h, env·e^(−λτ)(a_h cos hωτ + b_h sin hωτ); parameters (ω, [λ], C, a_h, b_h, ...).

    The cosines and sines of hωτ are kept for the last ω asked (:meth:`_trig`): MINPACK evaluates the
    residuals and the Jacobian at the same point, and the polish starts at the ω of the design matrix,
    so each ω costs its trigonometric functions once (same numbers, computed once).
    """

    def __init__(self, tau, y, env, harmonics, damping):
        """``env``: the known amplitude envelope sampled like ``tau``, or None for none (unit)."""
        self.tau, self.y, self.env = tau, y, env
        self.harmonics, self.damping = harmonics, damping
        self.base = 3 if damping else 2          # index of a_1 in the parameters
        self._omega, self._cs = None, None

    def _trig(self, omega):
        """[(cos hωτ, sin hωτ) for h in harmonics] at ω (rad/s), computed once per ω."""
        if omega != self._omega:
            tau = self.tau
            self._cs = [(np.cos(h * omega * tau), np.sin(h * omega * tau)) for h in self.harmonics]
            self._omega = omega
        return self._cs

    def _scaled(self, e, x):
        """e·x, with e None standing for a unit envelope (1·x is x exactly)."""
        return x if e is None else e * x

    def design(self, omega):
        """Design matrix of the linear parameters (C, a_h, b_h, ...) at ω: columns 1, env·cos hωτ,
        env·sin hωτ."""
        cols = [np.ones_like(self.tau)]
        for c, s_ in self._trig(omega):
            cols += [self._scaled(self.env, c), self._scaled(self.env, s_)]
        return np.column_stack(cols)

    def rss(self, omega):
        """Residual sum of squares at ω with the linear parameters solved (variable projection)."""
        X = self.design(omega)
        coef, *_ = np.linalg.lstsq(X, self.y, rcond=None)
        r = self.y - X @ coef
        return float(r @ r)

    def _envelope(self, params):
        """env·e^(−λτ) with damping, else env (None: unit envelope)."""
        if not self.damping:
            return self.env
        d = np.exp(-params[1] * self.tau)
        return d if self.env is None else self.env * d

    def values(self, params):
        """The model at every sample."""
        e = self._envelope(params)
        out = np.full_like(self.tau, params[2 if self.damping else 1])
        base = self.base
        for i, (c, s_) in enumerate(self._trig(params[0])):
            a, b = params[base + 2 * i], params[base + 2 * i + 1]
            out += self._scaled(e, a * c + b * s_)
        return out

    def jac_rows(self, params, out=None) -> np.ndarray:
        """Transpose of the analytic Jacobian (rows: ω, [λ], C, a_h, b_h ...; columns: samples),
        written into ``out`` if given."""
        tau = self.tau
        e = self._envelope(params)
        base = self.base
        out = np.empty((base + 2 * len(self.harmonics), tau.size)) if out is None else out
        out[0] = 0.0
        osc = np.zeros_like(tau) if self.damping else None
        for i, (h, (c, s_)) in enumerate(zip(self.harmonics, self._trig(params[0]))):
            a, b = params[base + 2 * i], params[base + 2 * i + 1]
            out[0] += (h * tau if e is None else e * h * tau) * (-a * s_ + b * c)
            if self.damping:
                osc += e * (a * c + b * s_)
            out[base + 2 * i] = self._scaled(e, c)
            out[base + 2 * i + 1] = self._scaled(e, s_)
        if self.damping:
            np.multiply(-tau, osc, out=out[1])
        out[base - 1] = 1.0
        return out

    def jac(self, params):
        """Analytic Jacobian of the model (rows: samples; columns: ω, [λ], C, a_h, b_h ...)."""
        return np.column_stack(list(self.jac_rows(params)))

    def polish(self, omega0):
        """Levenberg–Marquardt on all parameters (analytic Jacobian) from ω0, amplitudes solved.

        MINPACK's ``lmder`` (Moré 1978) through :func:`scipy.optimize.leastsq` with the settings
        of ``least_squares(method="lm", x_scale="jac", xtol=ftol=1e-15)``: gtol 1e-8, at most
        100 evaluations per parameter, step bound factor 100, scaling from the Jacobian's column
        norms — the same iterates, with the Jacobian handed over column-major (no copies).
        Returns an ``OptimizeResult`` with ``x``, ``fun`` (residuals), ``jac``, ``cost`` (½ Σ r²),
        ``success`` and ``status`` (MINPACK's info, 1–4 converged).
        """
        X0 = self.design(omega0)
        c0, *_ = np.linalg.lstsq(X0, self.y, rcond=None)
        q0 = np.array([omega0] + ([0.0] if self.damping else []) + list(c0), dtype=float)
        # full_output: MINPACK's info 0 and 5–8 come back in ``ier`` (no warning, no exception)
        x, _, info, _, ier = leastsq(lambda q: self.values(q) - self.y, q0, Dfun=self.jac_rows, full_output=True,
                                     col_deriv=True, ftol=1e-15, xtol=1e-15, gtol=1e-8, maxfev=100 * q0.size,
                                     factor=100)
        f = info["fvec"]
        return OptimizeResult(x=x, fun=f, jac=self.jac(x), cost=0.5 * float(np.dot(f, f)),
                              success=1 <= ier <= 4, status=ier, nfev=info["nfev"])


def _search(model, omega_guess, bin_w):
    """The least-squares solution (``scipy.optimize.OptimizeResult``) near the FFT guess.

    Fast path: the zero-padded, parabola-refined FFT peak is within a small fraction of a bin
    (``bin_w`` = 2π / span), inside the basin of the least-squares minimum; accept when the solution
    stays within half a bin. Fallback: bracket ±1.5 bins on a 9-point grid, Brent to 1e-3 of a bin,
    then polish; keep the better of the two.
    """
    sol = model.polish(omega_guess)
    if not (sol.success and abs(sol.x[0] - omega_guess) < 0.5 * bin_w):
        lo, hi = max(omega_guess - 1.5 * bin_w, 0.1 * omega_guess), omega_guess + 1.5 * bin_w
        grid = np.linspace(lo, hi, 9)
        best = grid[int(np.argmin([model.rss(w) for w in grid]))]
        step = grid[1] - grid[0]
        res = minimize_scalar(model.rss, bounds=(best - step, best + step), method="bounded",
                              options={"xatol": 1e-3 * step})
        sol2 = model.polish(float(res.x))
        if not sol.success or 2 * sol2.cost <= 2 * sol.cost:
            sol = sol2
    return sol


def _fit_result(sol, model, n_samples, span, warped, notes):
    """:class:`OscillationFit` from the least-squares solution: standard error of ω from the
    Jacobian, peak amplitude of the fitted waveform, Cramér–Rao bound for the fitted noise."""
    p = sol.x
    omega = float(p[0])
    lam = float(p[1]) if model.damping else 0.0
    r = sol.fun
    dof = max(n_samples - len(p), 1)
    s2 = float(r @ r) / dof
    J = sol.jac
    try:
        cov = np.linalg.inv(J.T @ J) * s2
        sig_omega = float(math.sqrt(max(cov[0, 0], 0.0)))
    except np.linalg.LinAlgError:
        sig_omega = math.inf
    base = model.base
    amp = float(math.hypot(p[base], p[base + 1]))
    # Peak amplitude from the fitted waveform itself: harmonics may be in antiphase (a pendulum-law
    # swing has A3 < 0 relative to the peak: a = A1 − |A3| + ...), so their sizes do not simply add.
    wave = sum(p[base + 2 * i] * c + p[base + 2 * i + 1] * s_
               for i, (c, s_) in enumerate(_unit_waves(tuple(model.harmonics))))
    amp_peak = float(0.5 * (np.max(wave) - np.min(wave)))
    dt = span / max(n_samples - 1, 1)
    crlb = crlb_omega(math.sqrt(s2), amp, dt, n_samples)
    method = "sine_fit" + ("+damping" if model.damping else "") + ("+warp" if warped else "") + \
             ("+harmonics" if len(model.harmonics) > 1 else "")
    return OscillationFit(omega, sig_omega, amp_peak, math.sqrt(s2), crlb, int(n_samples), span, lam, method, notes)


def fit_oscillation(t, y, omega_guess=None, harmonics=(1,), damping=False, warp=None, envelope=None,
                    t_ref=None) -> OscillationFit:
    """Least-squares fit of an oscillation; see the module docstring.

    Parameters
    ----------
    t, y : array_like
        Sample times (s) and values; non-finite samples are ignored.
    omega_guess : float, optional
        Starting angular frequency (rad/s); default from the FFT peak.
    harmonics : tuple of int
        Harmonic numbers of the model (1 = fundamental; (1, 3) for anharmonic swings).
    damping : bool
        Fit an exponential envelope e^(−λ (t − t_ref)).
    warp, envelope : array_like, optional
        Warped time τ(t) (s) and a known amplitude envelope, sampled like ``t``.

    Returns
    -------
    OscillationFit

    Raises
    ------
    EstimationError
        If fewer than two cycles or too few samples remain.
    """
    t, y, warp, envelope, notes = _clean_record(t, y, warp, envelope)
    p_lin = 1 + 2 * len(harmonics)
    if t.size < p_lin + 4:
        raise EstimationError(f"too few valid samples ({t.size}) to fit an oscillation")
    t_ref = float(np.mean(t)) if t_ref is None else t_ref
    tau = (warp - np.mean(warp)) if warp is not None else (t - t_ref)
    span = float(t[-1] - t[0])
    if omega_guess is None:
        omega_guess = fft_guess(tau + t_ref, y)
    if omega_guess * span / (2 * math.pi) < 2.0:
        raise EstimationError(f"record holds {omega_guess * span / (2 * math.pi):.2f} cycles; need at least 2")
    model = _OscillationModel(tau, y, envelope, harmonics, damping)
    sol = _search(model, omega_guess, 2 * math.pi / span)
    return _fit_result(sol, model, t.size, span, warp is not None, notes)


@dataclass
class CountResult:
    """Quet's counting method: N swings counted in a fixed observation time."""

    swing_duration_s: float
    swing_duration_sigma_s: float
    swings: int
    observation_s: float
    method: str = "counting"


def count_oscillations(t, y) -> CountResult:
    """Quet's literal method: count whole swings (passages through equilibrium) in the record.

    T = T_obs / N with N the number of zero crossings of the (mean-removed) signal; an observer
    can be out by up to one swing, so σ(T) = T / (N √3) (uniform ±1 swing... half-swing
    resolution at each end). Historical baseline only.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok] - np.median(y[ok])
    if t.size < 3:
        raise EstimationError("too few valid samples to count oscillations")
    s = np.sign(y)
    s[s == 0] = 1
    n = int(np.count_nonzero(s[1:] != s[:-1]))
    span = float(t[-1] - t[0])
    if n < 2:
        raise EstimationError("fewer than two swings in the record: nothing to count")
    T = span / n
    return CountResult(T, T / (n * math.sqrt(3.0)), n, span)
