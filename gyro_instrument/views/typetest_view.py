"""The pictures of ``gyro-instrument typetest --out DIR`` (:mod:`gyro_instrument.bench.typetest`): per
compass, the settling curve of the first pier run-up at every latitude (heading error against time,
the 0.7° band of ISO 22090-1 §3.10 about the settled reading, each settling time marked) and the
spiral (tilt against azimuth: the north end's damped spiral onto its settle point)."""

import os

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import check_dir_writable


def picture_names(compass) -> tuple:
    """The file names of one compass's pictures."""
    return f"settling_{compass}.png", f"spiral_{compass}.png"


def check_pictures(out_dir, overwrite=False) -> None:
    """Refuse ``--out`` before anything runs: a file, an unwritable place, or (without ``overwrite``) a
    directory that already holds pictures of a type test; matplotlib missing.

    Raises
    ------
    SceneError
        Naming ``--out`` (or ``plot`` for matplotlib).
    """
    from gyro_instrument.views import pyplot
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise SceneError("--out", out_dir, "is a file; give a directory for the pictures")
    check_dir_writable(out_dir)
    pyplot()
    if not overwrite and os.path.isdir(out_dir):
        old = sorted(f for f in os.listdir(out_dir) if f.startswith(("settling_", "spiral_")) and f.endswith(".png"))
        if old:
            raise SceneError("--out", out_dir, f"already holds {', '.join(old)}; pass --overwrite to replace them, "
                                               f"or give a new directory")


def draw_typetest(curves, out_dir, dpi=110) -> list:
    """Draw the pictures of every compass in ``curves`` ({(compass, latitude): curve}, as
    :func:`gyro_instrument.bench.typetest.run_typetest` returns them) into ``out_dir``; their paths."""
    from gyro_instrument.views import pyplot
    from gyro_instrument.views.figures import STYLE
    plt = pyplot()
    os.makedirs(out_dir, exist_ok=True)
    written = []
    for compass in dict.fromkeys(c for c, _ in curves):
        mine = sorted(((lat, cv) for (c, lat), cv in curves.items() if c == compass), key=lambda x: x[0])
        with plt.rc_context(STYLE):
            for fig, name in zip((_settling(plt, compass, mine), _spiral(plt, compass, mine)), picture_names(compass)):
                path = os.path.join(out_dir, name)
                fig.savefig(path, dpi=dpi)
                plt.close(fig)
                written.append(path)
    return written


def _settling(plt, compass, mine):
    """Two panels: the whole run-up, and the last degrees about the settle point with the 0.7° band."""
    fig, (top, low) = plt.subplots(2, 1, figsize=(16, 10), constrained_layout=True, sharex=True,
                                   gridspec_kw={"height_ratios": (1, 1.3)})
    for lat, cv in mine:
        t_h, e = np.asarray(cv["t_s"]) / 3600.0, np.asarray(cv["error_deg"])
        line, = top.plot(t_h, e, lw=1.4, label=f"{lat:g} deg")
        ts = cv["settle_s"]
        low.plot(t_h, e, lw=1.4, color=line.get_color())
        if ts is not None:
            when = ts - np.array([3600.0, 1800.0, 0.0])
            three = np.interp(when, cv["t_s"], e)
            mid = 0.5 * (three.max() + three.min())
            top.plot([ts / 3600.0], [three[-1]], "o", color=line.get_color(), ms=8)
            low.plot(when / 3600.0, three, "o", color=line.get_color(), ms=7)
            low.fill_between([when[0] / 3600.0, ts / 3600.0], mid - 0.35, mid + 0.35, color=line.get_color(),
                             alpha=0.15, lw=0)
    for ax in (top, low):
        ax.axvline(6.0, color="k", ls="--", lw=1, label="6 h: ISO 22090-1 5.2" if ax is top else None)
        ax.grid(alpha=0.3)
    low.set_ylim(-2.0, 2.0)
    top.set_ylabel("heading error (deg)")
    low.set_ylabel("heading error (deg), +/-2 deg")
    low.set_xlabel("time since switch-on (h)")
    fig.suptitle(f"{compass}: settling on a pier from the initial heading error; dot: settled (ISO 22090-1 3.10: the "
                 f"third of three readings 30 min apart\nwithin a 0.7 deg band; below: the three readings and a 0.7-deg band holding them); "
                 f"the run goes on 200 min past 12 h for the ten settle-point readings")
    top.legend(title="latitude", loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return fig


def _spiral(plt, compass, mine):
    fig, ax = plt.subplots(figsize=(16, 9), constrained_layout=True)
    for lat, cv in mine:
        az, tilt = np.asarray(cv["azimuth_deg"]), np.asarray(cv["tilt_deg"]) * 60.0
        line, = ax.plot(az, tilt, lw=1.2, label=f"{lat:g} deg")
        ax.plot(az[:1], tilt[:1], ">", color=line.get_color(), ms=9)
        ax.plot(az[-1:], tilt[-1:], "o", color=line.get_color(), ms=7)
    ax.set_xlabel("north end's azimuth, east of true north (deg)")
    ax.set_ylabel("north end's tilt, up (arcmin)")
    ax.set_title(f"{compass}: the damped spiral onto the settle point (triangle: switch-on, dot: end of the run-up)")
    ax.grid(alpha=0.3)
    ax.legend(title="latitude", loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return fig
