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


def swing_plane_azimuth(t_s, east, north, window_s):
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


def axis_directions(inst, stream):
    """Unit rotor-axis vectors in ENU (m, 3) of a gyroscope from its published angles, or None
    for an instrument whose axis is not shown (``Instrument.axis_direction_enu``)."""
    return inst.axis_direction_enu(stream.position) if inst.SHOWS_AXIS else None
