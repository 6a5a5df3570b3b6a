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
#: At least 20 frames (a short record is slowed down to them), at most 120.
MIN_FRAMES, MAX_FRAMES = 20, 120
#: The GIF's size: 12.8 x 7.2 in at 100 dpi, 1280 x 720 px (a 16:9 slide).
FIGSIZE_IN, GIF_DPI = (12.8, 7.2), 100


def frame_times(t0, t1) -> np.ndarray:
    """The record times the frames show: one per :data:`RECORD_S_PER_FRAME` (a day in 20 s at
    :data:`FPS`), at least :data:`MIN_FRAMES` (whatever the record's length) and at most
    :data:`MAX_FRAMES`, first to last sample."""
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
    fig = plt.figure(figsize=FIGSIZE_IN)
    ax = fig.add_axes((0.06, 0.08, 0.5, 0.84))     # square data area on the left, words on the right
    draw = _pendulum_frames(ax, s) if pend else _gyroscope_frames(ax, s)
    t = np.asarray(s["t"], float)
    times = frame_times(float(np.nanmin(t)), float(np.nanmax(t)))
    fig.text(0.62, 0.9, f"{name} seen from above\n{lat}", fontsize=15, va="top")
    clock = fig.text(0.62, 0.12, "", fontsize=14)
    writer = PillowWriter(fps=FPS)
    tmp = f"{path}.partial.gif"                 # Pillow picks the format from the extension
    try:
        with writer.saving(fig, tmp, dpi=GIF_DPI):
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
    """Set up a pendulum's axes (about the swing's centre); return draw(t): the path over about 40 s
    ending at t (the first 40 s for the first frames) and the swing plane fitted to that path (its
    principal axis), so the first frame shows the release's plane (an east-west release east-west)."""
    from gyro_instrument.views.rosette import swing_centre
    t, e, n = finite(s["t"], s["east"], s["north"])
    ce, cn = swing_centre(e, n) if e.size else (0.0, 0.0)
    e, n = e - ce, n - cn
    r = float(np.max(np.hypot(e, n))) if e.size else 1.0
    r = r or 1.0
    unit = "m" if s["path_unit"] == "m" else "deflection, degrees"
    ax.set_xlim(-1.2 * r, 1.2 * r)
    ax.set_ylim(-1.2 * r, 1.2 * r)
    ax.set_aspect("equal")
    ax.set_xlabel(f"east of the swing's centre ({unit})")
    ax.set_ylabel(f"north ({unit})")
    ax.text(0, 1.08 * r, "N", ha="center", fontsize=14)
    path, = ax.plot([], [], lw=1.0, color="C0")
    plane, = ax.plot([], [], lw=3, color="C3", label="swing plane")
    first, = ax.plot([], [], lw=1.5, ls="--", color="0.5", label="swing plane at the start")
    bob, = ax.plot([], [], "o", ms=10, color="k", label="bob")
    ax.legend(loc="upper left", bbox_to_anchor=(1.1, 0.7), fontsize=12, borderaxespad=0.0)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    span = max(20, int(40.0 / dt))          # ~40 s of path: a few swings of a long pendulum

    def window(i):
        b = min(e.size, max(i + 1, span + 1))           # the first frames look ahead: never fewer samples
        return max(0, b - span - 1), b

    def axis_at(i):
        a, b = window(i)
        v = plane_direction(e[a:b], n[a:b])
        return v * 1.15 * r

    start = axis_at(0)
    first.set_data([-start[0], start[0]], [-start[1], start[1]])

    def draw(tf):
        i = int(min(e.size - 1, np.searchsorted(t, tf)))
        a, b = window(i)
        path.set_data(e[a:b], n[a:b])
        ax_ = axis_at(i)
        plane.set_data([-ax_[0], ax_[0]], [-ax_[1], ax_[1]])
        bob.set_data([e[i]], [n[i]])
    return draw


def plane_direction(east, north) -> np.ndarray:
    """Unit vector (east, north) along the swing plane: the principal axis of the positions' covariance
    (east and north when there are fewer than 3 samples or no swing, never a made-up direction: NaN)."""
    if east.size < 3 or not (np.ptp(east) > 0 or np.ptp(north) > 0):
        return np.array([np.nan, np.nan])
    _, v = np.linalg.eigh(np.cov(np.vstack([east, north])))
    return v[:, -1]


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
    ax.legend(loc="upper left", bbox_to_anchor=(1.1, 0.7), fontsize=12, borderaxespad=0.0)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    span = max(10, int(30.0 / dt))

    def draw(tf):
        i = int(min(y.size - 1, np.searchsorted(t, tf)))
        a = np.radians(y[i])
        needle.set_data([math.sin(a), -math.sin(a)], [-math.cos(a), math.cos(a)])   # counter-clockwise angle
        seg = np.radians(y[max(0, i - span):i + 1])
        trail.set_data(-0.9 * np.sin(seg), 0.9 * np.cos(seg))
    return draw
