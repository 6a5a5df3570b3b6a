"""``gyro-instrument plot FILE``: the standard views of a run or a measurement (PNG, SVG or PDF).

FILE is a CSV or Parquet table (docs/formats/csv.md) or a bag (an ``.mcap`` or a rosbag2 directory;
a bag recorded by another tool needs ``--scene``). A table written by ``simulate`` carries its
scene (Parquet metadata, ``<name>.scene.yaml`` beside a CSV), used when ``--scene`` is absent.
Views, one file each in the output directory:

``angles``
    every measured angle over time in degrees (a gyroscope's swing angles, a pendulum's two-axis
    deflection), from the first to the last sample; more than 20000 samples are drawn as their
    min-max envelope over bins of at least 4 periods (no aliasing), gaps left empty. A pendulum
    whose length is unknown (no scene) is drawn as its bob's position in metres.
``swing_azimuth``
    each pendulum's swing-plane azimuth (compass degrees, one point per swing period) with the
    expected line anchored at the release at the scene pendulum's exact finite-amplitude rate
    (``apsidal_rate_from_rest_rad_s``), its rate in °/h, the full turn in hours and the latitude
    written on the plot; without a scene, the fitted line and the latitude it implies.
``bob_path``
    the rosette: each pendulum's bob seen from above (metres) over ``--window``, coloured by time,
    the start marked, an arrow for the sense and size of the swing plane's turn.
``residuals``
    a gyroscope's angle less its fitted oscillation; a swing azimuth less its line (a slope there
    is a rate difference, written beside it).

A CSV with a ``reading`` column is a surveyor's field book instead (``estimate --reversal-points``):
one view, ``field_book`` (:mod:`.field_book_view`): readings, turning points, the centre, north.

``--animate`` adds ``animation.gif`` (:mod:`.animate`). matplotlib is an optional extra (``pip
install 'gyro_instrument[plot]'``); without it the command exits 2 saying so.
"""

import os
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import check_dir_writable, shown
from gyro_instrument.views.backend import matplotlib_config_dir, pyplot  # noqa: F401
from gyro_instrument.views.measure import SIDEREAL_RATE_RAD_S, oscillation_residuals, swing_azimuth  # noqa: F401
from gyro_instrument.views.series import load_series, record_span  # noqa: F401

VIEWS = ("angles", "swing_azimuth", "bob_path", "residuals")
FORMATS = ("png", "svg", "pdf")
#: Default resolution: a 16 in wide figure is 1760 px.
DPI = 110


def draw_views(series, scene, out_dir, title="", fmt="png", dpi=DPI, window=None) -> list:
    """Write the views of :data:`VIEWS` that apply (swing azimuth and bob path need a pendulum) as
    ``<view>.<fmt>``; return their paths."""
    from gyro_instrument.views.figures import STYLE, angles_figure, azimuth_figure, residuals_figure, time_axis
    from gyro_instrument.views.measure import expected_line
    from gyro_instrument.views.rosette import rosette_figure
    plt = pyplot()
    os.makedirs(out_dir, exist_ok=True)
    written = []
    lo, hi = record_span(series)
    axis = time_axis(hi - lo if hi > lo else 0.0)
    pend = [n for n in series if "east" in series[n]]

    def save(fig, view):
        p = os.path.join(out_dir, f"{view}.{fmt}")
        fig.savefig(p, dpi=dpi)
        plt.close(fig)
        written.append(p)

    with plt.rc_context(STYLE):
        save(angles_figure(plt, series, axis, title), "angles")
        rows = []
        if pend:
            lines = {n: expected_line(scene, n) for n in pend}
            for n, line in lines.items():      # a measurement's line through its first swing (no release known)
                if line is not None:
                    line["anchor"] = "release" if series[n].get("simulated") else "first swing"
            fig, rows = azimuth_figure(plt, series, pend, lines, axis)
            save(fig, "swing_azimuth")
            save(rosette_figure(plt, series, pend, window, axis), "bob_path")
        rows += gyroscope_residual_rows(series)
        if rows:
            save(residuals_figure(plt, rows, axis), "residuals")
    return written


def gyroscope_residual_rows(series) -> list:
    """Residual rows (name, label, t, degrees, note, span) of every non-pendulum angle that an
    oscillation can be fitted to (not an azimuth: a turning direction has no centre to swing about)."""
    from gyro_instrument.views.figures import is_azimuth
    rows = []
    for n, s in series.items():
        if "east" in s:
            continue
        t = np.asarray(s["t"], float)
        for label, y, unit in s["channels"]:
            if is_azimuth(label):
                continue
            r = oscillation_residuals(t, np.radians(np.asarray(y, float)))
            if r is not None:
                rows.append((n, f"{label} less its fitted oscillation (degrees)", r[0], np.degrees(r[1]),
                             "what one oscillation (fundamental and third harmonic) does not describe: sensor "
                             "noise, damping, the period's change with amplitude, and other modes (a nutation, a "
                             "body on a plane's two frequencies)", (float(np.nanmin(t)), float(np.nanmax(t)))))
    return rows


@dataclass(frozen=True)
class PlotOptions:
    """How :func:`plot_file` reads and draws (``gyro-instrument plot``'s options).

    Attributes
    ----------
    scene : str or None
        The scene (a shipped name or a path) the input was made with (``--scene``); None: the one
        stored in the input, if any.
    overrides : sequence of str
        ``--set key.path=value`` texts applied to that scene.
    topics : sequence of str
        ``INSTRUMENT=/TOPIC`` pairs (``--topic``): a bag's topic for an instrument whose topic is
        not the one the scene gives it.
    overwrite : bool
        Replace views already in the output directory.
    fmt : str
        Image format, one of :data:`FORMATS`.
    dpi : float
        Resolution, dots per inch, in [20, 1200].
    window : tuple or None
        The time window drawn (:func:`gyro_instrument.views.rosette.parse_window`); None: all.
    animate : bool
        Also write ``animation.gif``.
    table : TableOptions or None
        How to read a table (:class:`~gyro_instrument.estimators.table_read.TableOptions`, the flags
        of ``estimate --data``).
    given : sequence of (flag, value)
        The table flags the user gave, refused for a bag or a field book.
    """

    scene: str | None = None
    overrides: tuple = ()
    topics: tuple = ()
    overwrite: bool = False
    fmt: str = "png"
    dpi: float = DPI
    window: object = None
    animate: bool = False
    table: object = None
    given: tuple = ()


def plot_file(path, out_dir, options=PlotOptions()) -> tuple:
    """Read ``path`` (table or bag), draw the views into ``out_dir`` (and ``animation.gif`` with
    ``options.animate``) as ``options`` (:class:`PlotOptions`) says; return (paths written, notes).

    Raises
    ------
    SceneError
        matplotlib missing; unreadable input; a bad ``fmt``, ``dpi`` or ``window``; a view's file
        already in ``out_dir`` without ``overwrite`` (nothing is written then); ``out_dir`` is a file;
        a table flag for a bag or a field book.
    """
    o = options
    fmt, dpi, overwrite, given = o.fmt, o.dpi, o.overwrite, o.given
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise SceneError("--out", out_dir, "is a file; give a directory for the views")
    check_dir_writable(out_dir)                      # before anything is read or drawn
    pyplot()
    if fmt not in FORMATS:
        raise SceneError("--format", fmt, f"must be one of {', '.join(FORMATS)}")
    if not (isinstance(dpi, (int, float)) and 20 <= dpi <= 1200):
        raise SceneError("--dpi", dpi, "must be a number in [20, 1200]")
    from gyro_instrument.views.field_book_view import is_field_book, plot_field_book
    bag = os.path.isdir(path) or str(path).lower().endswith(".mcap")
    if given and (bag or is_field_book(path)):
        raise SceneError(given[0][0], given[0][1], f"reads a table (CSV or Parquet); {path} is a "
                                                   f"{'bag' if bag else 'field book'}: leave the flag out")
    if is_field_book(path):                          # a surveyor's field book (views/field_book_view.py)
        from gyro_instrument.scenes import load_scene
        scene = load_scene(o.scene, list(o.overrides)) if o.scene else None
        return plot_field_book(path, out_dir, scene, fmt, dpi, overwrite), []
    names = [f"{v}.{fmt}" for v in VIEWS] + (["animation.gif"] if o.animate else [])
    if not overwrite:
        existing = [v for v in names if os.path.exists(os.path.join(out_dir, v))]
        if existing:
            raise SceneError("--out", out_dir, f"already holds {', '.join(existing)}; pass "
                                               f"--overwrite to replace them, or give a new directory")
    series, scene, notes = load_series(path, o.scene, o.overrides, o.topics, options=o.table)
    title = f"({shown(os.path.basename(os.fsdecode(path).rstrip('/')))})"
    written = draw_views(series, scene, out_dir, title, fmt, dpi, o.window)
    if o.animate:
        from gyro_instrument.views.animate import write_animation
        written.append(write_animation(series, scene, os.path.join(out_dir, "animation.gif")))
    return written, notes
