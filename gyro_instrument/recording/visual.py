"""What there is to see, from the published samples (no rclpy): the pendulum's swing-plane azimuth
and the gyroscopes' rotor-axis directions in ENU (``site_enu``).

The bob's own azimuth flips by π every swing; the swing plane is the principal axis of the
deflection over the last period: with sums over a trailing window of ``e = x/l`` and ``n = y/l``,

    α = ½ atan2(2 Σ e n, Σ n² − Σ e²)

is the compass azimuth of the plane (0 north, clockwise seen from above), defined modulo π; it is
unwrapped so that the Foucault precession plots as a line (it starts in [0, π)).
"""

import math

import numpy as np

from gyro_instrument.core.site import plane_frame


def swing_plane_azimuth(t_s, east, north, window_s) -> tuple:
    """Compass azimuth of the swing plane (rad, unwrapped) and its mean rate over the last period
    (rad/s; the Foucault precession, positive clockwise seen from above) per sample.

    Parameters
    ----------
    t_s : ndarray (m,)
        Sample times, s.
    east, north : ndarray (m,)
        Measured deflection components (x/l, y/l); NaN (dropouts) count as nothing.
    window_s : float
        Trailing window, s (one pendulum period; the first samples use what there is).
    """
    e = np.nan_to_num(np.asarray(east, dtype=float))
    n = np.nan_to_num(np.asarray(north, dtype=float))
    m = e.size
    if m == 0:
        return np.zeros(0), np.zeros(0)
    dt = (t_s[-1] - t_s[0]) / (m - 1) if m > 1 else 1.0
    w = max(int(round(window_s / dt)), 1)

    def trailing(x):
        c = np.concatenate([[0.0], np.cumsum(x)])
        lo = np.maximum(np.arange(1, m + 1) - w, 0)
        return c[1:] - c[lo]
    see, snn, sen = trailing(e * e), trailing(n * n), trailing(e * n)
    twice = np.arctan2(2.0 * sen, snn - see)
    az = 0.5 * np.unwrap(twice)
    az += math.pi * -np.floor(az[0] / math.pi)          # starts in [0, π)
    lo = np.maximum(np.arange(m) - w, 0)
    span = t_s - t_s[lo]
    rate = np.divide(az - az[lo], span, out=np.zeros(m), where=span > 0)      # over the last period
    return az, rate


def axis_directions(inst, stream) -> np.ndarray | None:
    """Unit rotor-axis vectors in ENU (m, 3) of a gyroscope from its published angles, or None
    for an instrument whose axis is not shown (``Instrument.axis_direction_enu``)."""
    return inst.axis_direction_enu(stream.position) if inst.SHOWS_AXIS else None


class SwingPlaneStream:
    """:func:`swing_plane_azimuth` over a run that arrives block by block, bit for bit.

    The trailing sums are differences of running sums carried across blocks, the unwrapping's
    corrections a running sum too, the start in [0, π) fixed by the first sample; what is kept is
    the last window (``w`` samples) of running sums, azimuths and times: memory does not grow
    with the run.

    Parameters
    ----------
    window_s : float
        Trailing window, s (one pendulum period).
    n : int
        Samples of the whole run.
    t_last_s : float
        Time of its last sample, s (with the first at 0: the one-shot spacing (t[-1] - t[0])/(n - 1)).
    """

    def __init__(self, window_s, n, t_last_s):
        dt = t_last_s / (n - 1) if n > 1 else 1.0
        self.w = max(int(round(window_s / dt)), 1)
        self.sums = np.zeros((1, 3))       # running sums of e², n², e·n at the kept samples (0 first)
        self.az = np.zeros(0)              # kept azimuths and times (the last w)
        self.t = np.zeros(0)
        self.seen = 0                      # samples received
        self.twice_last = None             # the last raw 2α, for unwrapping
        self.correction = 0.0              # running sum of the unwrapping's corrections
        self.offset = None

    def push(self, t_s, east, north) -> tuple:
        """Azimuth (rad, unwrapped) and rate (rad/s) at the block's samples, as the one-shot gives them."""
        e = np.nan_to_num(np.asarray(east, dtype=float))
        n = np.nan_to_num(np.asarray(north, dtype=float))
        m = e.size
        if m == 0:
            return np.zeros(0), np.zeros(0)
        w, i0 = self.w, self.seen
        x = np.column_stack([e * e, n * n, e * n])
        c = np.vstack([self.sums[-1:], x]).cumsum(axis=0)     # sequential, carried: the one-shot's sums
        c_all = np.vstack([self.sums[:-1], c])                 # kept sums then this block's (global i0 - len + 1 ...)
        base = i0 - (self.sums.shape[0] - 1)                   # index in the one-shot's running sums of c_all[0]
        hi = np.arange(i0 + 1, i0 + m + 1)
        lo = np.maximum(hi - w, 0)
        tr = c_all[hi - base] - c_all[lo - base]
        twice = np.arctan2(2.0 * tr[:, 2], tr[:, 1] - tr[:, 0])
        az = 0.5 * self._unwrap(twice)
        if self.offset is None:
            self.offset = math.pi * -np.floor(az[0] / math.pi)
        az += self.offset
        az_all, t_all = np.concatenate([self.az, az]), np.concatenate([self.t, t_s])
        a_base = i0 - self.az.size
        k = np.arange(i0, i0 + m)
        lo = np.maximum(k - w, 0)
        span = t_all[k - a_base] - t_all[lo - a_base]
        rate = np.divide(az_all[k - a_base] - az_all[lo - a_base], span, out=np.zeros(m), where=span > 0)
        self.sums = c_all[-(w + 1):]
        self.az, self.t = az_all[-w:], t_all[-w:]
        self.seen += m
        return az, rate

    def _unwrap(self, p):
        """``numpy.unwrap`` continued from the previous block (numpy's formula, the running sum carried)."""
        prev = [] if self.twice_last is None else [self.twice_last]
        pp = np.concatenate([prev, p])
        dd = np.diff(pp)
        ddmod = np.mod(dd + np.pi, 2 * np.pi) - np.pi
        np.copyto(ddmod, np.pi, where=(ddmod == -np.pi) & (dd > 0))
        corr = ddmod - dd
        np.copyto(corr, 0, where=abs(dd) < np.pi)
        run = np.cumsum(np.concatenate([[self.correction], corr]))
        out = p.copy()
        if prev:
            out = p + run[1:]
        else:
            out[1:] = p[1:] + run[1:]
        self.twice_last, self.correction = p[-1], run[-1]
        return out
