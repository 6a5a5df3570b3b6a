"""``plot book.csv``: a field book drawn (issue 33 item 5).

A CSV whose header holds a ``reading`` column (:mod:`gyro_instrument.estimators.north.field_book`) is a
field book, not a table of samples. One view, ``field_book``: above, the turning points as read
(against their times, else their numbers) relative to the circle reading of north, joined in the
order observed, with the swing centre (the Schuler mean of the raw readings), north (the centre less
the tape's pull, when a tape is known), the tape's own turning points, the missed points and the
named outliers; below, the triple means a surveyor prints beside the readings, with the Schuler
mean's ±σ band.
"""

import math
import os
import re

import numpy as np

from gyro_instrument.core.angle_formats import format_angle
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import shown

VIEW = "field_book"


def is_field_book(path) -> bool:
    """True for a CSV whose first non-comment line names a ``reading`` or ``reading_<unit>`` column."""
    if os.path.isdir(path) or str(path).lower().endswith((".mcap", ".parquet", ".pq")):
        return False
    try:
        with open(path, encoding="utf-8-sig") as fh:
            for line in fh:
                if line.strip() and not line.lstrip().startswith("#"):
                    cells = [c.strip() for c in re.split(r"[,;\t]", line)]
                    return any(c == "reading" or c.startswith("reading_") for c in cells)
    except (OSError, UnicodeDecodeError):
        return False
    return False


def _x(sw, times):
    """(x of each reading, x of each missed point, label): times (min) when every reading has one."""
    t = sw.reading_times_s
    if times and t is not None and np.all(np.isfinite(t)):
        lookup = dict(zip(sw.time_index.tolist(), sw.time_values_s.tolist()))
        miss = [lookup.get(m["turning_point"] - sw.first_number, math.nan) / 60.0 for m in sw.missed]
        return t / 60.0, np.array(miss), "time (min)"
    return sw.index + sw.first_number, np.array([m["turning_point"] for m in sw.missed], float), "turning point"


def field_book_figure(plt, path, scene=None, title="") -> "object":
    """The figure (module docstring) of the book at ``path``; ``scene`` lends its latitude and tape."""
    from gyro_instrument.estimators.north.field_book import read_field_book
    from gyro_instrument.estimators.north.field_book_report import field_book_block
    book = read_field_book(path)
    n = field_book_block(path, scene=scene)
    nr = n["north_reading_deg"]
    ref = math.radians(nr)

    def arcmin(rad):
        return (np.asarray(rad) - ref) * 10800.0 / math.pi      # the readings are unwrapped about the first

    fig, (ax, bx) = plt.subplots(2, 1, figsize=(16.0, 9.0), height_ratios=[3, 2], sharex=False, layout="constrained")
    x, xm, label = _x(book.on, True)
    y = arcmin(book.on.readings_rad)
    cut = np.flatnonzero(np.diff(book.on.index) > 1) + 1          # no line across a missed turning point
    ax.plot(np.insert(np.asarray(x, float), cut, np.nan), np.insert(y, cut, np.nan), "-", lw=1.0, color="tab:blue")
    ax.plot(x, y, "o", ms=6, color="tab:blue", label="turning points (rotor on)")
    if book.off is not None:
        xo, _, lab_o = _x(book.off, label.startswith("time"))
        if lab_o == label:
            ax.plot(xo, arcmin(book.off.readings_rad), "-s", lw=0.8, ms=5, color="tab:gray",
                    label="tape turning points (rotor off)")
    c_raw = float(np.mean([t["mean_deg"] for t in n["methods"]["schuler_mean"]["triple_means"]]))
    if abs(c_raw - nr) * 3600 > 0.05:                               # the raw centre is not north: a tape
        ax.axhline((c_raw - nr) * 60.0, color="tab:orange", ls="--", lw=1.2, label="swing centre (Schuler mean)")
    ax.axhline(0.0, color="k", lw=1.4, label=f"north reads {format_angle(nr, 'dms')}")
    for xx in xm[np.isfinite(xm)]:
        ax.axvline(xx, color="tab:red", ls=":", lw=1.0)
    if xm.size:
        ax.plot([], [], color="tab:red", ls=":", label="missed turning point")
    pos = {int(k) + book.on.first_number: j for j, k in enumerate(book.on.index)}
    for o in n["outliers"]:
        j = pos[o["turning_point"]]
        ax.plot(x[j], arcmin(book.on.readings_rad[j]), "o", ms=16, mfc="none", mec="tab:red", mew=2)
        yj = float(arcmin(book.on.readings_rad[j]))
        up = yj > float(np.median(y))                # beyond the turning point, where the swing's lines are not
        ax.annotate(f"line {o['line']}: {o['sigmas']:+.1f} σ", (x[j], yj), xytext=(0, 16 if up else -16),
                    textcoords="offset points", color="tab:red", fontsize=12, ha="center",
                    va="bottom" if up else "top")
    if n["outliers"]:
        ax.plot([], [], "o", ms=12, mfc="none", mec="tab:red", mew=2, label="outlier (named, kept)")
    lo, hi = float(np.min(y)), float(np.max(y))
    ax.set_ylim(lo - 0.18 * (hi - lo), hi + 0.18 * (hi - lo))     # room for the outliers' labels
    ax.set_ylabel("reading − north (arcmin)")
    if label == "turning point":
        from matplotlib.ticker import MaxNLocator
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel(label)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.9)     # outside: never over data
    ax.set_title(f"field book {shown(os.path.basename(os.fsdecode(path)))}: mount azimuth {n['mount_azimuth_dms']} "
                 f"± {n['sigma_arcsec']:.3g}″ ({n['reduction'].split(':')[0].split(' (')[0]}) {title}")
    _means_axis(bx, book, n, x, nr, label)
    return fig


def _means_axis(bx, book, n, x, nr, label) -> None:
    """The triple means (arcsec from north) at their middle turning point, and the Schuler mean's ±σ."""
    tri = n["methods"]["schuler_mean"]["triple_means"]
    pos = {int(k) + book.on.first_number: j for j, k in enumerate(book.on.index)}
    xm = [x[pos[t["turning_points"][1]]] for t in tri]
    ym = [((t["mean_deg"] - nr + 180.0) % 360.0 - 180.0) * 3600.0 for t in tri]
    raw = float(np.mean(ym)) if ym else 0.0                         # the raw Schuler mean: their mean
    bx.plot(xm, ym, "D", ms=7, color="tab:green", label="triple means (a_k + 2a_k+1 + a_k+2)/4")
    sig = n["methods"]["schuler_mean"]["sigma_arcsec"] or 0.0
    bx.axhspan(raw - sig, raw + sig, color="tab:green", alpha=0.15, label=f"Schuler mean ± σ ({sig:.3g}″)")
    bx.set_title("the triple means of the raw readings" + (" (the tape's pull is removed from the centre, "
                                                           "not from these)" if n["tape"] is not None else ""))
    bx.set_ylabel("mean − north (arcsec)")
    bx.set_xlabel("middle turning point" if label == "turning point" else f"{label} of the middle turning point")
    if label == "turning point":
        from matplotlib.ticker import MaxNLocator
        bx.xaxis.set_major_locator(MaxNLocator(integer=True))
    bx.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.9)


def plot_field_book(path, out_dir, scene=None, fmt="png", dpi=110, overwrite=False) -> list:
    """Write ``field_book.<fmt>`` in ``out_dir``; return [its path].

    Raises
    ------
    SceneError
        The book's bad input; the file already there without ``overwrite``.
    """
    from gyro_instrument.views.backend import pyplot
    from gyro_instrument.views.figures import STYLE
    plt = pyplot()
    out = os.path.join(out_dir, f"{VIEW}.{fmt}")
    if os.path.exists(out) and not overwrite:
        raise SceneError("--out", out_dir, f"already holds {VIEW}.{fmt}; pass --overwrite or give a new directory")
    os.makedirs(out_dir, exist_ok=True)
    with plt.rc_context(STYLE):
        fig = field_book_figure(plt, path, scene)
        fig.savefig(out, dpi=dpi)
        plt.close(fig)
    return [out]
