"""The figures of ``plot``: angles over time, the swing plane's azimuth with its expected line, the
rosette (the bob seen from above), the residuals. Every figure is 16 in wide (1600 px and more at
the default dpi) with text of 12 pt and more: readable on a slide."""

import math
import textwrap

import numpy as np

from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S

from gyro_instrument.views.measure import (anchored, deg_per_h, dominant_period, latitude_words, sense_words,
                                           swing_azimuth)
from gyro_instrument.views.series import finite

#: Records up to this many samples are drawn as a line; longer ones as a min-max envelope.
LINE_SAMPLES = 20000
#: At most this many envelope bins; a bin spans at least :data:`PERIODS_PER_BIN` periods.
MAX_BINS = 1500
PERIODS_PER_BIN = 4
#: Width of every figure, inches; the text sizes (points).
WIDTH_IN = 16.0
STYLE = {"font.size": 13, "axes.titlesize": 14, "axes.labelsize": 13, "legend.fontsize": 12,
         "xtick.labelsize": 12, "ytick.labelsize": 12, "figure.titlesize": 15}
#: Minimum height of an azimuth axis, degrees: a drift of 0.01° is drawn at its true size.
MIN_AZIMUTH_SPAN_DEG = 2.0
#: Characters per line of a note beside a panel (12 pt: about 4.4 in of the figure's 16).
NOTE_CHARS_SIDE = 48


def time_axis(span_s) -> tuple:
    """(seconds per unit, axis label) for a record of ``span_s``: hours over 2 h, minutes over 10 min."""
    if span_s > 7200:
        return 3600.0, "time since release (h)"
    if span_s > 600:
        return 60.0, "time since release (min)"
    return 1.0, "time since release (s)"


def gap_breaks(t, y) -> tuple:
    """``t``, ``y`` with a NaN inserted in every gap (a step over 3x the median step): a line is
    drawn with a break there instead of bridging it."""
    if t.size < 3:
        return t, y
    dt = np.diff(t)
    gaps = np.flatnonzero(dt > 3.0 * np.median(dt)) + 1
    return np.insert(t, gaps, np.nan), np.insert(y, gaps, np.nan)


def trace(ax, t, y, scale, label, period=None) -> None:
    """Draw ``y`` over ``t`` from its first to its last finite sample: a line (gaps broken) for up
    to :data:`LINE_SAMPLES` samples, else its minimum-maximum envelope over bins of at least
    :data:`PERIODS_PER_BIN` periods (no aliasing), empty bins (gaps) left empty."""
    t, y = finite(t, y)
    if t.size == 0:
        return
    if t.size <= LINE_SAMPLES:
        tt, yy = gap_breaks(t, y)
        ax.plot(tt / scale, yy, lw=1.2, label=label)
        return
    span = t[-1] - t[0]
    width = max(span / MAX_BINS, PERIODS_PER_BIN * (period or 0.0))
    nb = max(1, int(span // width))
    edges = t[0] + span * np.arange(nb + 1) / nb
    edges[-1] = t[-1]
    start = np.searchsorted(t, edges[:-1], side="left")
    count = np.diff(np.append(start, t.size))
    lo, hi = np.full(nb, np.nan), np.full(nb, np.nan)
    full = count > 0
    lo[full] = np.minimum.reduceat(y, start[full])
    hi[full] = np.maximum.reduceat(y, start[full])
    per = f"{width / period:.0f} periods" if period else f"{width:.3g} s"
    ax.fill_between(edges / scale, np.append(lo, lo[-1]), np.append(hi, hi[-1]), step="post", lw=0.8,
                    alpha=0.55, label=f"{label} (min-max over bins of {per})")


def outside_legend(ax, *handles) -> None:
    """The axes' legend outside it, to the right of its top (never over the data)."""
    ax.legend(*handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)


def side_note(ax, text, width=NOTE_CHARS_SIDE, y=0.0, va="bottom", **kw) -> "object":
    """``text`` wrapped to ``width`` characters beside the axes, to the right of its plotting area
    (never over the data): bottom-aligned at ``y`` (axes fraction) by default."""
    wrapped = "\n".join(textwrap.fill(part, width) for part in str(text).split("\n"))
    return ax.text(1.01, y, wrapped, transform=ax.transAxes, va=va, ha="left", fontsize=12, **kw)


def angles_figure(plt, series, axis, title) -> "object":
    """The ``angles`` view: every measured angle (degrees) or position (m) over time, one panel per
    channel (two channels of one instrument on one axis hide each other when they swing alike: a
    pendulum swinging at 45°), from the record's first to its last sample; legends beside the panels."""
    scale, tlabel = axis
    panels = [(n, label, y, unit) for n, s in series.items() for label, y, unit in s["channels"]]
    fig, axes = plt.subplots(len(panels), 1, figsize=(WIDTH_IN, 3.0 * len(panels) + 1), squeeze=False,
                             sharex=True, layout="constrained")
    for i, (ax, (n, label, y, unit)) in enumerate(zip(axes[:, 0], panels)):
        s = series[n]
        t = np.asarray(s["t"], float)
        turn = is_azimuth(label)
        y = unwrapped_deg(y) if turn else np.asarray(y, float)
        trace(ax, t, y, scale, f"{label} (unwrapped)" if turn else label, _band_period(t, y))
        for artist in ax.lines[-1:] + ax.collections[-1:]:
            artist.set_color(f"C{i % 10}")
        ax.set_ylabel("azimuth (degrees, unwrapped)" if turn else "position (m)" if unit == "m"
                      else "angle (degrees)")
        ax.set_title(f"{n} ({(s['type'] or 'type unknown').replace('_', ' ')})"
                     + (": length unknown, bob position in metres" if unit == "m" else ""), fontsize=13)
        outside_legend(ax)
        _say_why_flat(ax, label, y)
    axes[-1, 0].set_xlabel(tlabel)
    fig.suptitle(f"angles over time {title}".strip())
    return fig


def _band_period(t, y) -> float | None:
    """The dominant period (an FFT) only where :func:`trace` draws a band, which needs it."""
    return dominant_period(t, y) if finite(np.asarray(t, float), np.asarray(y, float))[0].size > LINE_SAMPLES else None


def is_azimuth(label) -> bool:
    """A channel that measures a direction turning about the vertical (``*azimuth``): it wraps
    at ±180° and does not oscillate about a centre."""
    return "azimuth" in label


def unwrapped_deg(y_deg) -> np.ndarray:
    """Degrees unwrapped across ±180° jumps, NaN kept where they were."""
    y = np.asarray(y_deg, float).copy()
    ok = np.isfinite(y)
    y[ok] = np.degrees(np.unwrap(np.radians(y[ok])))
    return y


def _say_why_flat(ax, label, y):
    """A note beside a panel whose channel never moves (all zero or constant)."""
    if np.all(~np.isfinite(y)) or not np.nanmax(y) > np.nanmin(y):
        side_note(ax, f"constant (never moves): {label}", color="0.3")


def azimuth_figure(plt, series, pend, lines, axis) -> tuple:
    """The ``swing_azimuth`` view: each pendulum's swing-plane azimuth per swing (degrees, compass)
    with its expected line (``lines[name]``: :func:`~gyro_instrument.views.measure.expected_line`;
    anchored at the release for a simulation, ``anchor`` ``"release"``, the default, or at the first
    measured swing, ``"first swing"``, at a free pendulum's rate), the line fitted to the points, and
    the rates in °/h written beside the panel. Returns (figure, residual rows (name, label, t, deg,
    note, span))."""
    scale, tlabel = axis
    rows = []
    fig, axes = plt.subplots(len(pend), 1, figsize=(WIDTH_IN, 5.0 * len(pend) + 1), squeeze=False,
                             layout="constrained")
    for ax, n in zip(axes[:, 0], pend):
        s = series[n]
        t = np.asarray(s["t"], float)
        tc, az, period = swing_azimuth(t, np.asarray(s["east"], float), np.asarray(s["north"], float))
        ax.set_title(f"{n}: the swing plane's azimuth" + (f" (one point per swing period, {period:.3f} s)"
                                                            if period else ""))
        ax.set_xlabel(tlabel)
        ax.set_ylabel("azimuth (degrees from north, clockwise)")
        if tc.size < 2:
            ax.text(0.5, 0.5, "no swing to measure: the bob does not swing in this record (all-zero or "
                              "constant positions, or shorter than two periods)", ha="center", va="center",
                    transform=ax.transAxes, wrap=True)
            continue
        rows.append(_azimuth_panel(ax, n, t, tc, az, lines.get(n), scale))
    return fig, rows


def _expected(line, tc, az):
    """(rate, anchor time, anchor azimuth, label, words) of the expected line, or None without one."""
    if line is None:
        return None
    if line.get("anchor", "release") == "release":
        rate = line["rate_rad_s"]
        words = (f"expected: {deg_per_h(rate):+.3f} °/h, {sense_words(rate)}: a full turn in "
                 f"{line['full_turn_h']:.1f} h at latitude {latitude_words(line['latitude_deg'])}"
                 + (f", released at {math.degrees(line['release'][0]):.1f}° (exact finite-amplitude rate; "
                    f"n·sin(latitude) alone: {deg_per_h(line['k_rad_s']):+.3f} °/h)" if line["exact_amplitude"]
                    else " (n·sin(latitude))"))
        return rate, 0.0, line["release"][1], "expected, from the release", words
    rate = line["k_rad_s"]
    words = (f"expected for a free pendulum at {latitude_words(line['latitude_deg'])}: {deg_per_h(rate):+.3f} "
             f"°/h (n·sin(latitude); a swing's ellipse adds its own turn), {sense_words(rate)}, drawn through "
             f"the first measured swing")
    return rate, float(tc[0]), float(az[0]), "expected (free pendulum), through the first swing", words


def _azimuth_panel(ax, n, t, tc, az, line, scale):
    """One pendulum's azimuth panel: points, the expected line over the whole record (anchored as
    :func:`_expected` says), the fitted line, the rates beside the panel, autoscale at least
    :data:`MIN_AZIMUTH_SPAN_DEG` tall."""
    t = t[np.isfinite(t)]
    release = line is not None and line.get("anchor", "release") == "release"
    t_ends = np.array([min(0.0, t.min()) if release else t.min(), t.max()])
    exp = _expected(line, tc, az)
    if exp is not None:
        az = anchored(tc, az, exp[0], exp[1], exp[2])
    slope, icpt = (float(v) for v in np.polyfit(tc - tc[0], az, 1))
    fitted = np.degrees(icpt + slope * (t_ends - tc[0]))
    measured_words = f"measured (the line fitted to the points): {deg_per_h(slope):+.3f} °/h, {sense_words(slope)}"
    # every trace seen: the lines over the points (thin), the fitted line dashed over the expected one
    ax.plot(tc / scale, np.degrees(az), "o", ms=6 if tc.size < 60 else 3.5, color="C0", alpha=0.8, zorder=2,
            label="measured, one point per swing")
    if exp is not None:
        rate, t0, a0, label, words = exp
        yline = np.degrees(a0 + rate * (t_ends - t0))
        ax.plot(t_ends / scale, yline, "-", lw=2.2, color="C3", zorder=3, label=label)
        ax.plot(t_ends / scale, fitted, ls=(0, (4, 4)), lw=1.6, color="C2", zorder=4, label="fitted to the points")
        text = f"{words}\n{measured_words}"
    else:
        rate, t0, a0 = slope, float(tc[0]), icpt
        yline = fitted
        lat = math.degrees(math.asin(max(-1.0, min(1.0, rate / SIDEREAL_RATE_RAD_S))))
        ax.plot(t_ends / scale, yline, "-", lw=2.2, color="C3", zorder=3, label="fitted line (no scene)")
        text = (f"fitted: {deg_per_h(rate):+.3f} °/h, {sense_words(rate)} (no scene: no expected line); "
                f"the latitude it implies: {latitude_words(lat)} (rate = Earth's sidereal rate · sin(latitude))")
    lo = min(np.degrees(az).min(), yline.min(), fitted.min())
    hi = max(np.degrees(az).max(), yline.max(), fitted.max())
    pad = max(0.5 * (MIN_AZIMUTH_SPAN_DEG - (hi - lo)), 0.08 * (hi - lo))
    ax.set_ylim(lo - pad, hi + pad)
    outside_legend(ax)
    side_note(ax, text)
    resid = np.degrees(az - (a0 + rate * (tc - t0)))
    diff = deg_per_h(float(np.polyfit(tc, resid, 1)[0]) * math.pi / 180.0)
    about_fit = np.degrees(az - (icpt + slope * (tc - tc[0])))
    which = "expected" if exp is not None else "fitted"
    note = (f"a slope is a rate difference: measured − {which} = {diff:+.4f} °/h; rms about the fitted line "
            f"{float(np.sqrt(np.mean(about_fit ** 2))):.3g}°; a curve, a rate that changes; the ripple, the "
            f"ellipse's own turning within each swing")
    return n, f"swing-plane azimuth less the {which} line (degrees)", tc, resid, note, (t_ends[0], t_ends[1])


def residuals_figure(plt, rows, axis) -> "object":
    """The ``residuals`` view: one panel per (instrument, label, t, residual in degrees, note, span)
    row, with its rms in the title and what a trend in it means beside the panel."""
    scale, tlabel = axis
    fig, axes = plt.subplots(len(rows), 1, figsize=(WIDTH_IN, 3.8 * len(rows) + 1), squeeze=False,
                             layout="constrained")
    for ax, (n, label, tt, rr, note, span) in zip(axes[:, 0], rows):
        trace(ax, tt, rr, scale, label)
        if ax.lines and len(tt) < 500:             # a few points (one per swing): each one seen
            ax.lines[-1].set_marker("o")
            ax.lines[-1].set_markersize(4)
        ax.plot(np.array(span) / scale, [0.0, 0.0], "k-", lw=0.8, zorder=1)
        rms = float(np.sqrt(np.mean(rr ** 2))) if rr.size else float("nan")
        ax.set_title(f"{n}: {label}, rms {rms:.3g}°")
        ax.set_ylabel("degrees")
        side_note(ax, note, y=1.0, va="top", color="0.25")
        ax.set_xlabel(tlabel)
    return fig
