"""North as the swing goes: a fit of the record so far from the first swing, and the Schuler mean
updated at each new reversal point, in bounded work.

A surveyor reading a gyrotheodolite writes each turning point down as it comes and has a north
reading from the third on (the Schuler mean of :func:`.north.schuler_mean`, Freiberger
Forschungshefte A 303 eq. 31b), better with each further point. :class:`NorthTracker` does the same
for a record that arrives sample by sample (the estimator node's joint states): it is given the
*tail* of the record — the last :meth:`NorthTracker.window_s` seconds, 1.75 full swings — finds the
reversal points there (:func:`.north.reversal_points`, each refined by its local quartic over
±T/8 of the period with the sensor's σ), and keeps those whose local window lies wholly inside the
tail and that come after the last one kept. The work per call is that of the tail, whatever the
length of the record; the caller calls it about four times per swing.

With a torsion tape the rotor-on centre c is pulled toward the tape zero Z; :func:`live_north`
then needs the rotor-off swing's tracker too: Z its Schuler mean (≥ 3 of its reversal points) and
D_B/D_K from the two mean reversal-point spacings (:func:`.north.tape_ratio`), N = c − atan(x (Z − c))
(:func:`.north.tape_corrected`). Until then there is no live north (a centre pulled by the tape is
not north). The full-record estimate (the fit, ``north`` block) replaces these at the end.

From the first swing on (issue 37: a heading a navigation stack can live on), :class:`SwingFit`
fits the record so far (at most :data:`FIT_SWINGS` swings of it) by the damped sine of the
full-record fit (:func:`.north.fit_record`'s model, u = c + e^(−δτ)(a cos ωτ + b sin ωτ)) with the
instrument's predicted frequency as a prior (ω ~ N(π/T, (:data:`OMEGA_PRIOR_REL` · π/T)²), δ ~ N(0,
(:data:`DAMPING_PRIOR_REL` · π/T)²): the maker's calibration, what a surveyor knows before the
first turning point), so a centre with the covariance of what is known so far exists after one
swing and its σ falls as the record grows. :func:`fit_north` tape-corrects it with the rotor-off
swing's fit by the relations the full-record estimate uses: the ratio from *undamped* frequencies
(:func:`.north.joint.tape_from_records`, ω_u² = ω_d² + δ²) and the exact N = c − atan(x (Z − c)).
:func:`live_north` (the Schuler mean of the reversal points) likewise takes undamped periods, the
damping from the decay of the reversal points' deviations.

Readings are clockwise, u = −angle (:mod:`.north`'s convention); the mount azimuth is (−N) mod 2π.
"""

import math

import numpy as np
from scipy.optimize import least_squares

from gyro_instrument.estimators import north
from gyro_instrument.estimators.north.fit import fit_jacobian, fit_model
from gyro_instrument.estimators.north.joint import SineSummary, tape_from_records

#: the tail of the record the tracker is given, in half periods (one swing each): 1.75 full swings
WINDOW_SWINGS = 3.5
#: the most of the record :class:`SwingFit` fits, in swings (bounded work per update)
FIT_SWINGS = 24
#: σ of the prior on the swing's angular frequency, relative to the predicted π/T: a calibration
#: known to 5 % (the tape, the finite amplitude and the damping shift the period far less)
OMEGA_PRIOR_REL = 0.05
#: σ of the prior on the amplitude decay rate δ (1/s), relative to π/T: broad (δ = 0.05 π/T halves
#: the amplitude in about 4.4 swings)
DAMPING_PRIOR_REL = 0.05


class NorthTracker:
    """Reversal points of a swing that arrives in pieces (module docstring).

    Parameters
    ----------
    swing_s : float
        The predicted duration of one swing (half a period, s): sizes the tail and the spacing test.
    noise_sigma_rad : float or None
        The sensor's white-noise σ (rad); None: pooled from the local fits' residuals.
    """

    def __init__(self, swing_s: float, noise_sigma_rad: float | None = None) -> None:
        self.swing_s = float(swing_s)
        self.noise_sigma_rad = noise_sigma_rad
        self.times, self.readings, self.sigmas = [], [], []

    def window_s(self) -> float:
        """Length of the tail :meth:`update` wants (s)."""
        return WINDOW_SWINGS * self.swing_s

    def update(self, t, u) -> int:
        """Take the reversal points complete in the tail (t s, u rad clockwise) after the last one
        kept; returns how many were added (0 when the tail holds none yet)."""
        t = np.asarray(t, dtype=float)
        if t.size < 16:
            return 0
        try:
            rp = north.reversal_points(t, u, self.noise_sigma_rad)
        except ValueError:                 # SceneError: no two reversal points in the tail yet
            return 0
        h = 0.25 * rp.half_period_s        # the local window: ±window_fraction × the period
        added = 0
        for tk, ak, sk in zip(rp.times_s, rp.readings_rad, rp.sigmas_rad):
            if tk - h < t[0] or tk + h > t[-1]:
                continue
            if self.times and tk <= self.times[-1] + 0.5 * self.swing_s:
                continue
            self.times.append(float(tk))
            self.readings.append(float(ak))
            self.sigmas.append(float(sk))
            added += 1
        return added

    def __len__(self) -> int:
        return len(self.times)

    def schuler(self) -> "north.NorthEstimate | None":
        """The Schuler mean of the points so far (None before the third)."""
        if len(self.readings) < 3:
            return None
        return north.schuler_mean(np.array(self.readings), np.array(self.sigmas))

    def half_period(self) -> tuple:
        """Mean spacing of the reversal points (s) and its σ (nan with fewer than 3)."""
        return north.half_period(np.array(self.times))

    def undamped_half_period(self) -> tuple:
        """The undamped half period π/ω_u (s) and its σ: ω_u² = ω_d² + δ² (:func:`.north.undamped_omega`)
        with ω_d = π/h from the spacing and δ from the decay of the deviations |a_i − c| about the
        Schuler mean (a log-linear fit, as the full-record fit's start, :func:`.north.fit._fit_start`)."""
        h, s_h = self.half_period()
        est = self.schuler()
        delta = 0.0
        if est is not None and len(self.readings) >= 3:
            dev = np.abs(np.array(self.readings) - est.centre_rad)
            if np.all(dev > 0):
                delta = max(float(-np.polyfit(np.array(self.times), np.log(dev), 1)[0]), 0.0)
        w, s_w = math.pi / h, (math.pi / h ** 2) * (s_h if math.isfinite(s_h) else 0.0)
        wu, s_wu = north.undamped_omega(w, delta, s_w, 0.0)
        return math.pi / wu, math.pi / wu ** 2 * s_wu


def live_north(on: NorthTracker, off: NorthTracker | None = None) -> "north.NorthEstimate | None":
    """The north reading now: the Schuler mean of ``on``'s reversal points, tape-corrected with the
    rotor-off tracker ``off`` when one is given (None until each has three reversal points)."""
    est = on.schuler()
    if est is None or off is None:
        return est
    zero = off.schuler()
    if zero is None:
        return None
    (h_on, s_on), (h_off, s_off) = on.undamped_half_period(), off.undamped_half_period()
    try:
        ratio, r_sig = north.tape_ratio(h_on, h_off, s_on if math.isfinite(s_on) else 0.0,
                                        s_off if math.isfinite(s_off) else 0.0)
    except ValueError:                     # the rotor-off swing not (yet) slower: no north
        return None
    return north.tape_corrected(est, zero.centre_rad, ratio, r_sig, zero.sigma_rad or 0.0)


class SwingFit:
    """The damped-sine fit of a swing record as it grows, with the predicted frequency as a prior
    (module docstring).

    Parameters
    ----------
    swing_s : float
        The predicted duration of one swing (half a period, s): the prior ω = π/swing_s.
    noise_sigma_rad : float or None
        The sensor's white-noise σ (rad); None: the residual rms of the fit.
    """

    def __init__(self, swing_s: float, noise_sigma_rad: float | None = None) -> None:
        self.swing_s = float(swing_s)
        self.omega0 = math.pi / self.swing_s
        self.prior_sigma = np.array([OMEGA_PRIOR_REL, DAMPING_PRIOR_REL]) * self.omega0
        self.noise_sigma_rad = noise_sigma_rad
        self.nonlinear = None       # (ω, δ) of the last fit: the next one starts there
        self.summary = None         # the last fit (SineSummary)

    def window_s(self) -> float:
        """Length of the record's tail :meth:`update` fits (s)."""
        return FIT_SWINGS * self.swing_s

    def update(self, t, u, min_span_s=None) -> "SineSummary | None":
        """Fit the record (t s, u rad clockwise) when it spans at least ``min_span_s`` (default one
        swing); returns the new :class:`~.north.joint.SineSummary` (centre variance in
        ``centre_cov[0]``), or None (too short, or the fit failed: the last one is kept)."""
        t, u = np.asarray(t, dtype=float), np.asarray(u, dtype=float)
        span = self.swing_s if min_span_s is None else float(min_span_s)
        if t.size < 8 or t[-1] - t[0] + (t[1] - t[0]) < span:      # the span the samples cover
            return None
        tau = t - t[0]
        w, d = self.nonlinear if self.nonlinear is not None else (self.omega0, 0.0)
        e = np.exp(-d * tau)
        lin, *_ = np.linalg.lstsq(np.column_stack([np.ones_like(tau), e * np.cos(w * tau), e * np.sin(w * tau)]),
                                  u, rcond=None)
        p0 = np.array([*lin, w, d])
        sig = self.noise_sigma_rad or max(float(np.std(u - fit_model(tau, p0, True, False))), 1e-12)
        prior = np.array([self.omega0, 0.0])
        rows = np.zeros((2, 5))
        rows[0, 3], rows[1, 4] = 1.0 / self.prior_sigma[0], 1.0 / self.prior_sigma[1]

        def res(p):
            return np.concatenate([(fit_model(tau, p, True, False) - u) / sig, (p[3:] - prior) / self.prior_sigma])

        def jac(p):
            return np.vstack([fit_jacobian(tau, p, True, False) / sig, rows])
        try:
            sol = least_squares(res, p0, jac=jac, method="lm", xtol=1e-12, max_nfev=60)
            cov = np.linalg.inv(sol.jac.T @ sol.jac)
        except (np.linalg.LinAlgError, ValueError):
            return None
        x = sol.x
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(np.diag(cov))) and x[3] > 0):
            return None
        self.nonlinear = (float(x[3]), float(x[4]))
        u0 = fit_model(np.array([0.0]), x, True, False)[0]
        rate0 = float(-x[4] * x[1] + x[3] * x[2])
        self.summary = SineSummary(float(x[0]), 0.0, float(x[3]), float(x[4]), math.sqrt(cov[3, 3]),
                                   math.sqrt(cov[4, 4]), float(t[0]), float(u0), rate0, (float(cov[0, 0]), 0.0, 0.0))
        return self.summary


def fit_north(on: "SineSummary | None", off: "SineSummary | None" = None,
              tape: bool = False) -> "north.NorthEstimate | None":
    """The north reading from :class:`SwingFit` summaries: the rotor-on centre, tape-corrected with
    the rotor-off swing's fit when ``tape`` (the ratio from undamped frequencies and the exact
    relation, :func:`.north.joint.tape_from_records`, :func:`.north.tape_corrected`); None while a
    needed fit is missing or the rotor-off swing is not (yet) the slower."""
    if on is None:
        return None
    est = north.NorthEstimate("live fit", on.centre_rad, math.sqrt(on.centre_cov[0]),
                              "the growing record's damped-sine fit with the predicted frequency as a prior",
                              0, "one swing of the record")
    if not tape:
        return est
    if off is None:
        return None
    try:
        cal = tape_from_records(on, off, off.t_ref_s)
        if not (cal["ratio"] > 0 and math.isfinite(cal["ratio"])):
            return None
        return north.tape_corrected(est, cal["zero_rad"], cal["ratio"], cal["ratio_sigma"], cal["zero_sigma_rad"])
    except (ValueError, ZeroDivisionError):
        return None
