"""``plot FILE --animate``: ``animation.gif``, seen from above and time-lapsed (a day in 20 s):
a pendulum's bob tracing its last swings and its turning swing plane, or a gyroscope's axis
swinging about the meridian, with a clock and the latitude."""

import math
import os

import numpy as np

from gyro_instrument.views.measure import latitude_words
from gyro_instrument.views.series import finite

#: Frames per second of the GIF and record seconds per frame: a day (86400 s) in 20 s.
FPS = 6
RECORD_S_PER_FRAME = 86400.0 / (20.0 * FPS)
MIN_FRAMES, MAX_FRAMES = 12, 120


def frame_times(t0, t1) -> np.ndarray:
    """The record times the frames show: one per :data:`RECORD_S_PER_FRAME` (a day in 20 s at
    :data:`FPS`), at least :data:`MIN_FRAMES` and at most :data:`MAX_FRAMES`, first to last sample."""
    n = int(min(MAX_FRAMES, max(MIN_FRAMES, math.ceil((t1 - t0) / RECORD_S_PER_FRAME) + 1)))
    return np.linspace(t0, t1, n)


def _clock(t_s):
    h, rem = divmod(int(round(t_s)), 3600)
    return f"{h:d} h {rem // 60:02d} min {rem % 60:02d} s after release"


def write_animation(series, scene, path) -> str:
    """Write the GIF of the first pendulum (else the first gyroscope) of ``series`` to ``path``
    (matplotlib's PillowWriter, :func:`frame_times`); return ``path``."""
    import matplotlib.pyplot as plt
    from matplotlib.animation import PillowWriter
    pend = [n for n in series if "east" in series[n]]
    name = pend[0] if pend else next(iter(series))
    s = series[name]
    lat = f"latitude {latitude_words(scene.site.latitude_deg)}" if scene is not None else "latitude unknown (no scene)"
    fig, ax = plt.subplots(figsize=(7.2, 7.2))
    draw = _pendulum_frames(ax, s) if pend else _gyroscope_frames(ax, s)
    t = np.asarray(s["t"], float)
    times = frame_times(float(np.nanmin(t)), float(np.nanmax(t)))
    ax.set_title(f"{name} seen from above, {lat}", fontsize=13)
    clock = ax.text(0.02, 0.02, "", transform=ax.transAxes, fontsize=13)
    writer = PillowWriter(fps=FPS)
    tmp = f"{path}.partial.gif"                 # Pillow picks the format from the extension
    try:
        with writer.saving(fig, tmp, dpi=80):
            for tf in times:
                draw(tf)
                clock.set_text(_clock(tf))
                writer.grab_frame()
        os.replace(tmp, path)
    finally:
        plt.close(fig)
        if os.path.exists(tmp):
            os.unlink(tmp)
    return path


def _pendulum_frames(ax, s):
    """Set up a pendulum's axes; return draw(t): its last ~2 swings and its swing plane at t."""
    t, e, n = finite(s["t"], s["east"], s["north"])
    r = float(np.max(np.hypot(e, n))) or 1.0
    unit = "m" if s["path_unit"] == "m" else "deflection, degrees"
    ax.set_xlim(-1.2 * r, 1.2 * r)
    ax.set_ylim(-1.2 * r, 1.2 * r)
    ax.set_aspect("equal")
    ax.set_xlabel(f"east ({unit})")
    ax.set_ylabel(f"north ({unit})")
    ax.text(0, 1.1 * r, "N", ha="center", fontsize=14)
    path, = ax.plot([], [], lw=1.0, color="C0")
    plane, = ax.plot([], [], lw=3, color="C3", label="swing plane")
    first, = ax.plot([], [], lw=1.5, ls="--", color="0.5", label="swing plane at the start")
    bob, = ax.plot([], [], "o", ms=10, color="k")
    ax.legend(loc="upper right", fontsize=11)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    span = max(20, int(40.0 / dt))          # ~40 s of path: a few swings of a long pendulum

    def axis_at(i):
        a, b = max(0, i - span), i + 1
        ee, nn = e[a:b], n[a:b]
        _, v = np.linalg.eigh(np.cov(np.vstack([ee, nn])) if b - a > 2 else np.eye(2))
        return v[:, -1] * 1.15 * r

    start = axis_at(min(span, e.size - 1))
    first.set_data([-start[0], start[0]], [-start[1], start[1]])

    def draw(tf):
        i = int(min(e.size - 1, np.searchsorted(t, tf)))
        path.set_data(e[max(0, i - span):i + 1], n[max(0, i - span):i + 1])
        ax_ = axis_at(i)
        plane.set_data([-ax_[0], ax_[0]], [-ax_[1], ax_[1]])
        bob.set_data([e[i]], [n[i]])
    return draw


def _gyroscope_frames(ax, s):
    """Set up a gyroscope's dial (north up); return draw(t): its axis (the first angle channel,
    degrees from the meridian) at t and its last ~30 s as a fading trail."""
    label, y, _ = s["channels"][0]
    t, y = finite(s["t"], y)
    ax.set_xlim(-1.25, 1.25)
    ax.set_ylim(-1.25, 1.25)
    ax.set_aspect("equal")
    ax.axis("off")
    from matplotlib.patches import Circle
    ax.add_patch(Circle((0, 0), 1.0, fill=False, lw=1, color="0.6"))
    ax.plot([0, 0], [-1.1, 1.1], ls="--", color="0.5", lw=1.2)
    ax.text(0, 1.12, "meridian (N)", ha="center", fontsize=13)
    needle, = ax.plot([], [], lw=4, color="C3", label=f"rotor axis ({label})")
    trail, = ax.plot([], [], lw=1, color="C0")
    ax.legend(loc="lower right", fontsize=11)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    span = max(10, int(30.0 / dt))

    def draw(tf):
        i = int(min(y.size - 1, np.searchsorted(t, tf)))
        a = np.radians(y[i])
        needle.set_data([math.sin(a), -math.sin(a)], [-math.cos(a), math.cos(a)])   # counter-clockwise angle
        seg = np.radians(y[max(0, i - span):i + 1])
        trail.set_data(-0.9 * np.sin(seg), 0.9 * np.cos(seg))
    return draw
