"""North as the swing goes: the Schuler mean updated at each new reversal point, in bounded work.

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

Readings are clockwise, u = −angle (:mod:`.north`'s convention); the mount azimuth is (−N) mod 2π.
"""

import math

import numpy as np

from gyro_instrument.estimators import north

#: the tail of the record the tracker is given, in half periods (one swing each): 1.75 full swings
WINDOW_SWINGS = 3.5


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


def live_north(on: NorthTracker, off: NorthTracker | None = None) -> "north.NorthEstimate | None":
    """The north reading now: the Schuler mean of ``on``'s reversal points, tape-corrected with the
    rotor-off tracker ``off`` when one is given (None until each has three reversal points)."""
    est = on.schuler()
    if est is None or off is None:
        return est
    zero = off.schuler()
    if zero is None:
        return None
    (h_on, s_on), (h_off, s_off) = on.half_period(), off.half_period()
    try:
        ratio, r_sig = north.tape_ratio(h_on, h_off, s_on if math.isfinite(s_on) else 0.0,
                                        s_off if math.isfinite(s_off) else 0.0)
    except ValueError:                     # the rotor-off swing not (yet) slower: no north
        return None
    return north.tape_corrected(est, zero.centre_rad, ratio, r_sig, zero.sigma_rad or 0.0)
