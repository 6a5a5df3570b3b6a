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


def angles_figure(plt, series, axis, title) -> "object":
    """The ``angles`` view: every measured angle (degrees) or position (m) over time, one panel per
    instrument, from the record's first to its last sample."""
    scale, tlabel = axis
    names = list(series)
    fig, axes = plt.subplots(len(names), 1, figsize=(WIDTH_IN, 3.6 * len(names) + 1), squeeze=False)
    for ax, n in zip(axes[:, 0], names):
        s = series[n]
        units = sorted({u for _, _, u in s["channels"]})
        swings = [(lab, v) for lab, v, _ in s["channels"] if not is_azimuth(lab)]
        turns = [(lab, v) for lab, v, _ in s["channels"] if is_azimuth(lab)]
        for label, y in swings:
            trace(ax, np.asarray(s["t"], float), np.asarray(y, float), scale, label, _band_period(s["t"], y))
        handles = ax.get_legend_handles_labels()
        if turns:      # turning azimuths on their own axis, continuous (not a ±180° sawtooth)
            tw = ax.twinx() if swings else ax
            for i, (label, y) in enumerate(turns):
                y = unwrapped_deg(y)
                n_lines, n_fills = len(tw.lines), len(tw.collections)
                trace(tw, np.asarray(s["t"], float), y, scale, f"{label} (unwrapped, right axis, dashed)" if swings
                      else f"{label} (unwrapped)", _band_period(s["t"], y))
                colour = f"C{len(swings) + i}"      # a twin axis restarts the colour cycle
                for ln in tw.lines[n_lines:]:
                    ln.set_color(colour)
                    ln.set_linestyle("--" if swings else "-")
                for band in tw.collections[n_fills:]:
                    band.set_facecolor(colour)
            tw.set_ylabel("azimuth (degrees, unwrapped)")
            if swings:
                more = tw.get_legend_handles_labels()
                handles = (handles[0] + more[0], handles[1] + more[1])
        what = "position (m)" if units == ["m"] else "angle (degrees)"
        ax.set_ylabel(what if swings or not turns else "azimuth (degrees, unwrapped)")
        ax.set_title(f"{n} ({(s['type'] or 'type unknown').replace('_', ' ')})"
                     + (": length unknown, bob position in metres" if units == ["m"] else ""))
        ax.legend(*handles, loc="upper right")
        _say_why_flat(ax, s)
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


def _say_why_flat(ax, s):
    """A note on a panel whose channels never move (all zero or constant)."""
    flat = [lab for lab, v, _ in s["channels"] if np.all(~np.isfinite(v)) or not np.nanmax(v) > np.nanmin(v)]
    if flat:
        ax.text(0.01, 0.04, "constant (never moves): " + ", ".join(flat), transform=ax.transAxes, fontsize=12,
                color="0.3")


def azimuth_figure(plt, series, pend, lines, axis) -> tuple:
    """The ``swing_azimuth`` view: each pendulum's swing-plane azimuth per swing (degrees, compass)
    with its expected line anchored at the release (``lines[name]``: :func:`~gyro_instrument.views.
    measure.expected_line`, or a fitted line without a scene) and the rates in °/h written on the
    plot. Returns (figure, residual rows (name, label, t, deg, note))."""
    scale, tlabel = axis
    rows = []
    fig, axes = plt.subplots(len(pend), 1, figsize=(WIDTH_IN, 5.0 * len(pend) + 1), squeeze=False)
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
        row = _azimuth_panel(ax, n, t, tc, az, lines.get(n), scale)
        rows.append(row)
    fig.tight_layout()
    return fig, rows


def _azimuth_panel(ax, n, t, tc, az, line, scale):
    """One pendulum's azimuth panel: points, the anchored (or fitted) line over the whole record,
    the rates written, autoscale at least :data:`MIN_AZIMUTH_SPAN_DEG` tall."""
    t = t[np.isfinite(t)]
    t_ends = np.array([min(0.0, t.min()) if line else t.min(), t.max()])
    measured = float(np.polyfit(tc, az, 1)[0])
    if line is not None:
        rate, t0, a0 = line["rate_rad_s"], 0.0, line["release"][1]
        az = anchored(tc, az, rate, t0, a0)
        text = (f"expected: {deg_per_h(rate):+.3f} °/h, {sense_words(rate)}: a full turn in "
                f"{line['full_turn_h']:.1f} h\nat latitude {latitude_words(line['latitude_deg'])}"
                + (f", released at {math.degrees(line['release'][0]):.1f}° (exact finite-amplitude rate; "
                   f"n·sin(latitude) alone: {deg_per_h(line['k_rad_s']):+.3f} °/h)" if line["exact_amplitude"]
                   else " (n·sin(latitude))")
                + f"\nmeasured (slope of the points): {deg_per_h(measured):+.3f} °/h")
        label = "expected, from the release"
    else:
        rate = measured
        t0, a0 = float(tc[0]), float(np.mean(az - rate * (tc - tc[0])))
        lat = math.degrees(math.asin(max(-1.0, min(1.0, rate / SIDEREAL_RATE_RAD_S))))
        text = (f"fitted: {deg_per_h(rate):+.3f} °/h, {sense_words(rate)} (no scene: no expected line)\n"
                f"the latitude it implies: {latitude_words(lat)} (rate = Earth's sidereal rate · sin(latitude))")
        label = "fitted line (no scene)"
    yline = np.degrees(a0 + rate * (t_ends - t0))
    ax.plot(tc / scale, np.degrees(az), ".", ms=5, label="measured, one point per swing")
    ax.plot(t_ends / scale, yline, "-", lw=2, color="C3", label=label)
    ax.text(0.01, 0.97, text, transform=ax.transAxes, va="top", fontsize=12,
            bbox={"boxstyle": "round", "fc": "white", "alpha": 0.85})
    lo = min(np.degrees(az).min(), yline.min())
    hi = max(np.degrees(az).max(), yline.max())
    pad = max(0.5 * (MIN_AZIMUTH_SPAN_DEG - (hi - lo)), 0.08 * (hi - lo))
    ax.set_ylim(lo - pad, hi + pad + 0.45 * (hi - lo + 2 * pad))     # room for the text above the data
    ax.legend(loc="upper right")
    resid = np.degrees(az - (a0 + rate * (tc - t0)))
    slope = deg_per_h(float(np.polyfit(tc, resid, 1)[0]) * math.pi / 180.0)
    note = (f"a slope is a rate difference: measured − {'expected' if line else 'fitted'} = {slope:+.4f} °/h; "
            f"a curve, a rate that changes (the expected line is the rate at release); the ripple, the "
            f"ellipse's own turning within each swing")
    return n, "swing-plane azimuth less the " + ("expected" if line else "fitted") + " line (degrees)", tc, resid, \
        note, (t_ends[0], t_ends[1])



#: Characters per line of a note inside a panel of the figure's width at 12 pt.
NOTE_CHARS = 140


def residuals_figure(plt, rows, axis) -> "object":
    """The ``residuals`` view: one panel per (instrument, label, t, residual in degrees, note, span)
    row, with its rms and what a trend in it means."""
    scale, tlabel = axis
    fig, axes = plt.subplots(len(rows), 1, figsize=(WIDTH_IN, 3.8 * len(rows) + 1), squeeze=False)
    for ax, (n, label, tt, rr, note, span) in zip(axes[:, 0], rows):
        trace(ax, tt, rr, scale, label)
        ax.plot(np.array(span) / scale, [0.0, 0.0], "k-", lw=0.8)
        rms = float(np.sqrt(np.mean(rr ** 2))) if rr.size else float("nan")
        ax.set_title(f"{n}: {label}, rms {rms:.3g}°")
        ax.set_ylabel("degrees")
        # wrapped to the panel's width (a line running past the figure made tight_layout shrink the panel)
        ax.text(0.01, 0.04, textwrap.fill(note, NOTE_CHARS), transform=ax.transAxes, fontsize=12, color="0.25",
                bbox={"boxstyle": "round", "fc": "white", "alpha": 0.8, "ec": "none"})
        ax.set_xlabel(tlabel)
    fig.tight_layout()
    return fig
