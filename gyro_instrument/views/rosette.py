"""The rosette: a pendulum's bob seen from above over a window, coloured by time, with its start
marked and an arrow for the sense in which the swing plane turns."""

import math

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.views.measure import deg_per_h, dominant_period, sense_words, swing_azimuth
from gyro_instrument.views.series import finite

#: At most this many swings drawn (evenly spread over the window), so the petals stay apart.
MAX_SWINGS = 60


def parse_window(text) -> tuple | None:
    """``--window START:END`` (seconds since release; either side may be empty) as (start, end).

    Raises
    ------
    SceneError
        Not ``START:END`` with numbers, or END <= START.
    """
    if text is None:
        return None
    parts = str(text).split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        lo = float(parts[0]) if parts[0].strip() else -math.inf
        hi = float(parts[1]) if parts[1].strip() else math.inf
    except ValueError:
        raise SceneError("--window", text, "must be START:END in seconds since release, e.g. 0:3600 "
                                           "(either side may be empty)") from None
    if not hi > lo:
        raise SceneError("--window", text, "must have END > START")
    return lo, hi


def _spread_swings(t, period):
    """Mask keeping whole swings, at most :data:`MAX_SWINGS` of them spread evenly over ``t``."""
    if not period:
        return np.ones(t.size, bool)
    index = np.floor((t - t[0]) / period).astype(np.int64)
    every = max(1, int(math.ceil((index[-1] + 1) / MAX_SWINGS)))
    return index % every == 0


def rosette_figure(plt, series, pend, window, axis) -> "object":
    """The ``rosette`` view (file ``bob_path``): each pendulum's bob seen from above over ``window``
    (s; the whole record when None), coloured by time, the start marked, an arrow for the swing
    plane's turn over the window and its size written."""
    from matplotlib.collections import LineCollection
    scale, tlabel = axis
    fig, axes = plt.subplots(1, len(pend), figsize=(16.0, 9.0 if len(pend) == 1 else 16.0 / len(pend) + 2.5),
                             squeeze=False, layout="constrained")
    for ax, n in zip(axes[0, :], pend):
        s = series[n]
        t, e, nn = finite(s["t"], s["east"], s["north"])
        if window is not None:
            keep = (t >= window[0]) & (t <= window[1])
            t, e, nn = t[keep], e[keep], nn[keep]
        unit = s["path_unit"]
        ax.set_xlabel(f"east ({'m' if unit == 'm' else 'deflection, degrees'})")
        ax.set_ylabel(f"north ({'m' if unit == 'm' else 'deflection, degrees'})")
        ax.set_aspect("equal", adjustable="datalim")
        if t.size < 2 or not (np.ptp(e) > 0 or np.ptp(nn) > 0):
            ax.set_title(f"{n}: bob seen from above")
            ax.text(0.5, 0.5, "nothing to draw: " + ("no sample in the window" if t.size < 2 else
                                                     "the bob does not move (all-zero or constant positions)"),
                    ha="center", va="center", transform=ax.transAxes)
            continue
        centre = swing_centre(e, nn)
        e, nn = e - centre[0], nn - centre[1]      # about the swing's centre (an origin anywhere)
        period = dominant_period(t, e if np.var(e) >= np.var(nn) else nn)
        m = _spread_swings(t, period)
        pts = np.column_stack([e, nn])
        seg = np.stack([pts[:-1], pts[1:]], axis=1)[m[:-1] & m[1:]]
        tm = t[:-1][m[:-1] & m[1:]] / scale
        lc = LineCollection(seg, array=tm, cmap="viridis", linewidths=1.0)
        ax.add_collection(lc)
        ax.autoscale_view()
        fig.colorbar(lc, ax=ax, label=tlabel, shrink=0.6, location="bottom")
        ax.plot(e[0], nn[0], "o", ms=12, color="C3", label=f"start ({t[0] / scale:.4g} {tlabel.split('(')[-1]}")
        off = float(np.hypot(*centre))
        title = (f"{n}: the bob seen from above, {(t[-1] - t[0]) / scale:.3g} {tlabel.split('(')[-1][:-1]}"
                 + (f" ({min(MAX_SWINGS, int((t[-1] - t[0]) / period))} swings shown, evenly spread)"
                    if period and (t[-1] - t[0]) / period > MAX_SWINGS else "")
                 + (f"\nabout the swing's centre, ({centre[0]:.4g}, {centre[1]:.4g}) {unit} from the track's origin"
                    if off > 0.01 * float(np.max(np.hypot(e, nn))) else ""))
        words = _turn_arrow(ax, t, e, nn)
        ax.set_title(title + (f"\n{words}" if words else ""))
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
        ax.grid(alpha=0.3)
    return fig


def swing_centre(east, north) -> tuple:
    """The swing's centre (east, north): the midpoint of the 0.5 % and 99.5 % points of each
    coordinate (a swing spends as long on either side; robust to a few wild points)."""
    return tuple(0.5 * float(np.percentile(v, 0.5) + np.percentile(v, 99.5)) for v in (east, north))


def _turn_arrow(ax, t, e, nn):
    """An arc arrow from the swing plane's azimuth at the window's start to its end; returns the turn
    in words (or that it is too small to see; None without two swings) for the title."""
    from matplotlib.patches import FancyArrowPatch
    tc, az, _ = swing_azimuth(t, e, nn)
    if tc.size < 2:
        return
    turned = float(az[-1] - az[0])
    rate = float(np.polyfit(tc, az, 1)[0])
    r = 1.12 * float(np.max(np.hypot(e, nn)))
    words = (f"the swing plane turned {abs(math.degrees(turned)):.2f}° {sense_words(turned)}\n"
             f"in {(tc[-1] - tc[0]) / 3600.0:.3g} h ({deg_per_h(rate):+.2f} °/h)")
    if abs(math.degrees(turned)) < 1.0:
        return words.replace("\n", " ") + ": too little to see here"
    # from the end of the plane nearer the top toward where it turned to (compass: east = sin, north = cos)
    a0 = float(az[0]) % math.pi
    a0 = a0 if math.cos(a0) >= 0 else a0 - math.pi
    a1 = a0 + math.copysign(min(max(abs(turned), math.radians(25.0)), math.radians(90.0)), turned)  # the sense
    p0, p1 = (r * math.sin(a0), r * math.cos(a0)), (r * math.sin(a1), r * math.cos(a1))
    arc = 0.35 * (1 if turned > 0 else -1) * min(1.0, abs(turned))
    ax.add_patch(FancyArrowPatch(p0, p1, connectionstyle=f"arc3,rad={-arc}", arrowstyle="-|>",
                                 mutation_scale=28, lw=3, color="C3"))
    ax.update_datalim([(-r, -r), (r, r)])
    ax.autoscale_view()
    return words.replace("\n", " ")
