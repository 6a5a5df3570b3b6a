"""What there is to see, from the published samples (no rclpy): the pendulum's swing-plane azimuth
and the gyroscopes' rotor-axis directions in ENU (``site_enu``).

The bob's own azimuth flips by π every swing; the swing plane is the principal axis of the
deflection over the last period: with sums over a trailing window of ``e = x/l`` and ``n = y/l``,

    α = ½ atan2(2 Σ e n, Σ n² − Σ e²)

is the compass azimuth of the plane (0 north, clockwise seen from above), defined modulo π; it is
unwrapped so that the Foucault precession plots as a line (it starts in [0, π)).

What the markers show is computed here too (:class:`PendulumVisual`, :class:`AxisVisual`: the
geometry of one marker set in ``site_enu``); ``ros/messages.py`` only fills the messages.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from gyro_instrument.recording.topics import TRAIL



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


@dataclass(frozen=True)
class PendulumMarkers:
    """A pendulum's marker geometry in ``site_enu`` (m): the pivot, the bob, the bob's recent trail
    (k, 3), the swing-plane line's two ends (2, 3) and the bob's drawn size."""

    pivot: np.ndarray
    bob: np.ndarray
    trail: np.ndarray
    plane_ends: np.ndarray
    size_m: float


@dataclass(frozen=True)
class AxisMarkers:
    """A gyroscope's rotor axis drawn as an arrow of ``length_m`` from ``origin`` along ``axis``
    (unit vector), in ``site_enu``."""

    origin: np.ndarray
    axis: np.ndarray
    length_m: float


@dataclass
class PendulumVisual:
    """What a pendulum shows, block by block: the swing plane (continued over blocks,
    :class:`SwingPlaneStream`), the largest deflection so far (the plane line's half length), the
    bob trail's history.

    Parameters
    ----------
    origin : ndarray (3,)
        Where the instrument stands in ``site_enu``, m.
    length_m : float
        Pendulum length l, m.
    period_s : float
        The trailing window of the swing plane: one period 2π√(l/g), s (g the site's).
    n : int
        Samples of the run.
    t_last_s : float
        Time of its last sample, s.
    every : int
        Samples between two visual messages.
    """

    origin: np.ndarray
    length_m: float
    period_s: float
    n: int
    t_last_s: float
    every: int
    half: float = 1e-3
    trail: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    trail_start: int = 0
    plane: np.ndarray = None
    plane_rate: np.ndarray = None

    def __post_init__(self):
        self.plane_stream = SwingPlaneStream(self.period_s, self.n, self.t_last_s)

    def push(self, start, t_s, stream) -> None:
        """A new block (first sample ``start``, times ``t_s`` s) of the pendulum's ``JointStream``."""
        az, rate = self.plane_stream.push(t_s, stream.position[:, 0], stream.position[:, 1])
        self.plane, self.plane_rate = az, rate
        biggest = np.fmax.reduce(stream.position[:, 2]) if stream.position.shape[0] else np.nan
        if np.isfinite(biggest):
            self.half = max(self.half, float(biggest) * self.length_m)
        # trail: the last TRAIL visual periods before the block, then the block
        self.trail = np.concatenate([self.trail[-self.every * TRAIL:], stream.bob_enu_m])
        self.trail_start = start - (self.trail.shape[0] - stream.bob_enu_m.shape[0])

    def markers(self, i, j, stream) -> PendulumMarkers:
        """The markers at global sample ``i`` (row ``j`` of the current block's ``stream``)."""
        size = min(max(0.03 * self.length_m, 0.05), 2.0)
        a = self.trail_start
        trail = self.trail[max(i - self.every * TRAIL, 0) - a:i + 1 - a:self.every]
        pivot = self.origin + np.array([0.0, 0.0, self.length_m])
        bob = pivot + np.nan_to_num(stream.bob_enu_m[j])
        foot = np.array([pivot[0], pivot[1], bob[2]])
        az = float(self.plane[j])
        d = np.array([math.sin(az), math.cos(az), 0.0]) * self.half
        return PendulumMarkers(pivot, bob, pivot + np.nan_to_num(trail).reshape(-1, 3), np.array([foot - d, foot + d]),
                               size)

    def rows(self, local) -> tuple:
        """The swing-plane JointState columns (position, velocity, effort) at block rows ``local``."""
        return self.plane[local][:, None], self.plane_rate[local][:, None], np.zeros((local.size, 1))


@dataclass
class AxisVisual:
    """What a gyroscope shows: its rotor axis in ENU (unit vectors, ``Instrument.axis_direction_enu``
    of its published angles) per sample of the current block."""

    origin: np.ndarray
    inst: object
    axis: np.ndarray = None

    def push(self, start, t_s, stream) -> None:
        self.axis = self.inst.axis_direction_enu(stream.position)

    def markers(self, i, j, stream) -> AxisMarkers:
        return AxisMarkers(self.origin, np.nan_to_num(self.axis[j]), 1.0)

    def rows(self, local) -> tuple:
        """The Vector3Stamped column at block rows ``local``."""
        return (self.axis[local],)
