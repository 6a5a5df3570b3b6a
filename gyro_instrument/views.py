"""``gyro-instrument plot FILE``: the standard views of a run or a measurement, as PNG.

FILE is a CSV or Parquet table (msg_docs/csv.md) or a bag (an ``.mcap`` or a rosbag2 directory;
a bag recorded by another tool needs ``--scene``). Views, one PNG each in the output directory:

``angles.png``
    every measured angle over time (a gyroscope's swing angles, a pendulum's two-axis deflection),
    in degrees; a long record is drawn as its per-bin minimum-maximum band.
``swing_azimuth.png``
    each pendulum's swing-plane azimuth (compass, modulo 180°, from the deflection's principal
    axis over each swing period) with the line of Foucault's rate k = n sin γ (n and γ of the
    scene; without a scene, the fitted k and the latitude asin(k/n) it implies for the sidereal n).
``bob_path.png``
    each pendulum's bob seen from above (east, north; metres, or deflection x/l, y/l in rad when
    the length is unknown).
``residuals.png``
    fit residuals: a gyroscope's angle less its fitted oscillation (fundamental and third harmonic
    at the fitted frequency), a pendulum's swing-plane azimuth less the k line.

matplotlib is an optional extra (``pip install 'gyro_instrument[plot]'``); without it the command
exits 2 saying so.
"""

import math
import os

import numpy as np

from gyro_instrument.core.errors import SceneError

VIEWS = ("angles", "swing_azimuth", "bob_path", "residuals")
SIDEREAL_RATE_RAD_S = 7.2921150e-5
_BINS = 3000


def _pyplot():
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SceneError("plot", "matplotlib", "is not installed: pip install 'gyro_instrument[plot]' "
                                               "(or: pip install matplotlib)") from None
    return plt


# ----------------------------------------------------------------------------- input
def load_series(path, scene_arg=None, overrides=(), topics=(), field="FILE") -> tuple:
    """What to draw from a table or a bag.

    Returns
    -------
    series : dict
        instrument -> {``type``, ``t`` (s), ``angles`` {label: rad}, and for pendulums ``east``,
        ``north`` and ``path_unit`` (``m`` or ``rad``)}; ``type`` is None when unknown (a table read
        without a scene).
    scene : Scene or None
    notes : list of str

    Raises
    ------
    SceneError
        Unreadable input, a bag without a scene record and no ``--scene``, nothing to draw.
    """
    from gyro_instrument.scenes import load_scene
    scene = load_scene(scene_arg, list(overrides)) if scene_arg else None
    if not os.path.isdir(path) and not str(path).lower().endswith(".mcap"):
        series, notes = _table_series(path, field, scene), []
    else:
        series, scene, notes = _bag_series(path, scene, topics)
    if not series:
        raise SceneError(field, path, "holds no angle or pendulum channel to draw (columns as in msg_docs/csv.md)")
    return series, scene, notes


def _table_series(path, field, scene):
    """:func:`load_series` for a CSV or Parquet table (instrument types from ``scene`` when given)."""
    from gyro_instrument.estimators.data_io import TIME_COLUMN, read_table
    from gyro_instrument.instruments import REGISTRY
    from gyro_instrument.scenes import build_instruments
    series = {}
    cols = read_table(path, field)
    t = cols[TIME_COLUMN]
    insts = build_instruments(scene) if scene else {}
    names = list(dict.fromkeys(c.split(".", 1)[0] for c in cols if "." in c))
    angle_names = {c for cls in REGISTRY.values() if not cls.IS_PENDULUM for c in cls.MEASURED_CHANNELS} \
        | {"deflection"}
    for name in names:
        ch = {c.split(".", 1)[1]: cols[c] for c in cols if c.startswith(f"{name}.")}
        inst = insts.get(name)
        typ = inst.type_name if inst else None
        s = {"type": typ, "t": t, "angles": {}}
        if {"x_east", "y_north"} <= set(ch) or {"deflection_east", "deflection_north"} <= set(ch):
            s["type"] = typ or "pendulum"
            if {"x_east", "y_north"} <= set(ch):
                s["east"], s["north"], s["path_unit"] = ch["x_east"], ch["y_north"], "m"
                l = inst.pendulum_length_m() if inst is not None and inst.IS_PENDULUM else None
                if l:
                    s["angles"] = {"deflection east (x/l)": ch["x_east"] / l,
                                   "deflection north (y/l)": ch["y_north"] / l}
                else:
                    s["angles"] = {"x east / 1 m": ch["x_east"], "y north / 1 m": ch["y_north"]}
            else:
                s["east"], s["north"] = ch["deflection_east"], ch["deflection_north"]
                l = inst.pendulum_length_m() if inst is not None and inst.IS_PENDULUM else None
                if l:
                    s["east"], s["north"], s["path_unit"] = s["east"] * l, s["north"] * l, "m"
                else:
                    s["path_unit"] = "rad"
                s["angles"] = {"deflection east": ch["deflection_east"], "deflection north": ch["deflection_north"]}
        else:
            s["angles"] = {c: v for c, v in ch.items() if c in angle_names}
        if s["angles"]:
            series[name] = s
    return series


def _bag_series(path, scene, topics):
    """:func:`load_series` for a bag: its own scene record, or ``scene`` and ``topics`` for a
    foreign bag. Returns (series, scene, notes)."""
    from gyro_instrument.scenes import build_instruments
    notes, series = [], {}
    from gyro_instrument.recording.bag_layout import scan_path
    from gyro_instrument.recording.joints import records_from_joints
    scan = scan_path(path)
    if scene is None and not topics:
        import json
        from gyro_instrument.recording.bag_samples import samples_from_bag
        from gyro_instrument.scenes import scene_from_data
        meta, samples, more, _ = samples_from_bag(path, scan)
        if meta is None or "scene_yaml" not in meta:
            raise SceneError("bag", path, "has no gyro_instrument metadata record (scene): give the scene "
                                          "with --scene SCENE")
        scene = scene_from_data(json.loads(meta["scene_yaml"]), source=path)
        insts = build_instruments(scene)
        samples = {n: v for n, v in samples.items() if n in insts and len(v[0]) >= 3}
    else:
        from gyro_instrument.recording.foreign import foreign_samples, parse_topic_remaps
        if scene is None:
            raise SceneError("--topic", topics[0], "needs --scene")
        insts = build_instruments(scene)
        samples, report, more = foreign_samples(scan, insts, parse_topic_remaps(topics, insts))
        more += [f"{n} not matched: {r}" for n, r in report["unmatched"].items()]
    notes += more
    records = records_from_joints(insts, samples)
    for name, rec in records.items():
        inst = insts[name]
        s = {"type": inst.type_name, "t": rec["t"], "angles": {}}
        if inst.IS_PENDULUM:
            l = inst.pendulum_length_m()
            s["angles"] = {"deflection east": rec["deflection_east"], "deflection north": rec["deflection_north"]}
            s["east"], s["north"], s["path_unit"] = rec["deflection_east"] * l, rec["deflection_north"] * l, "m"
        else:
            s["angles"] = {c: rec[c] for c in inst.MEASURED_CHANNELS if c in rec}
        series[name] = s
    return series, scene, notes


# ----------------------------------------------------------------------------- computations
def _finite(*arrays):
    ok = np.ones(len(arrays[0]), bool)
    for a in arrays:
        ok &= np.isfinite(a)
    order = np.argsort(arrays[0][ok], kind="stable")
    return [np.asarray(a, dtype=float)[ok][order] for a in arrays]


def swing_azimuth(t, east, north) -> tuple:
    """Swing-plane azimuth per swing period: (window centre times s, compass azimuth rad, unwrapped
    modulo π, period s); the principal axis of the deflection over each period (as the Foucault
    estimator measures it). Empty arrays when there is no swing."""
    from gyro_instrument.estimators.period import fft_guess
    t, e, n = _finite(t, east, north)
    if t.size < 20:
        return np.array([]), np.array([]), None
    main = e if np.var(e) >= np.var(n) else n
    head = min(t.size, 20000)
    omega = fft_guess(t[:head], main[:head] - np.mean(main[:head]))
    if not omega or not math.isfinite(omega) or omega <= 0:
        return np.array([]), np.array([]), None
    period = 2 * math.pi / omega
    n_win = int((t[-1] - t[0]) // period)
    if n_win < 1:
        return np.array([]), np.array([]), period
    idx = np.searchsorted(t, t[0] + period * np.arange(n_win + 1))
    a, b = idx[:-1], idx[1:]
    good = (b - a) >= 8
    cnt = np.maximum((b - a).astype(float), 1.0)
    end = int(b[-1])                      # segments a[i]:a[i+1], the last one a[-1]:b[-1]
    e, n = e[:end], n[:end]
    see = np.add.reduceat(e * e, a) / cnt
    snn = np.add.reduceat(n * n, a) / cnt
    sen = np.add.reduceat(e * n, a) / cnt
    psi = 0.5 * np.arctan2(2 * sen, snn - see)
    tc = 0.5 * (t[a] + t[np.maximum(b - 1, a)])
    psi, tc = psi[good], tc[good]
    az = np.unwrap(2 * psi) / 2
    if az.size:
        az = az - math.pi * math.floor(az[0] / math.pi)      # first value in [0, π): compass, mod 180°
    return tc, az, period


def oscillation_residuals(t, y) -> tuple | None:
    """(t, residual) of a gyroscope angle less its fitted oscillation (fundamental and third
    harmonic at the frequency :func:`~gyro_instrument.estimators.period.fit_oscillation` finds,
    plus a constant); None when no oscillation can be fitted."""
    from gyro_instrument.estimators.period import EstimationError, fit_oscillation
    t, y = _finite(t, y)
    try:
        fit = fit_oscillation(t, y, harmonics=(1, 3))
    except EstimationError:
        return None
    tau = t - np.mean(t)
    w = fit.omega_rad_s
    X = np.column_stack([np.ones_like(tau), np.cos(w * tau), np.sin(w * tau), np.cos(3 * w * tau),
                         np.sin(3 * w * tau)])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    return t, y - X @ coef


# ----------------------------------------------------------------------------- drawing
def _time_axis(t):
    span = float(np.nanmax(t) - np.nanmin(t)) if len(t) else 0.0
    return (3600.0, "time (h)") if span > 7200 else (1.0, "time (s)")


def _band(ax, t, y, scale, label):
    """A line for short records, the per-bin min-max band for long ones (fast, alias-free)."""
    t, y = _finite(t, y)
    if t.size == 0:
        return
    if t.size <= 2 * _BINS:
        ax.plot(t / scale, y, lw=0.6, label=label)
        return
    k = t.size // _BINS
    m = k * _BINS
    tb = t[:m].reshape(_BINS, k).mean(axis=1)
    yb = y[:m].reshape(_BINS, k)
    ax.fill_between(tb / scale, yb.min(axis=1), yb.max(axis=1), lw=0, alpha=0.5, label=f"{label} (min-max per bin)")


def _k_line(scene):
    if scene is None:
        return None
    lat = math.radians(scene.site.latitude_deg)
    return scene.site.earth_rate_rad_s * math.sin(lat), scene.site.latitude_deg, scene.site.earth_rate_rad_s


def draw_views(series, scene, out_dir, title="") -> list:
    """Write the PNGs of :data:`VIEWS` that apply (swing azimuth and bob path need a pendulum);
    return their paths."""
    plt = _pyplot()
    os.makedirs(out_dir, exist_ok=True)
    written = []
    names = list(series)
    pend = [n for n in names if "east" in series[n]]
    all_t = np.concatenate([np.asarray(series[n]["t"], float) for n in names])
    axis = _time_axis(all_t[np.isfinite(all_t)])

    def save(fig, view):
        fig.tight_layout()
        p = os.path.join(out_dir, f"{view}.png")
        fig.savefig(p, dpi=100)
        plt.close(fig)
        written.append(p)

    save(_angles_figure(plt, series, names, axis, title), "angles")
    residual_rows = []
    if pend:
        fig, residual_rows = _swing_azimuth_figure(plt, series, pend, scene, axis)
        save(fig, "swing_azimuth")
        save(_bob_path_figure(plt, series, pend), "bob_path")
    for n in names:
        if "east" in series[n]:
            continue
        s = series[n]
        for label, y in s["angles"].items():
            r = oscillation_residuals(np.asarray(s["t"], float), np.asarray(y, float))
            if r is not None:
                residual_rows.append((n, f"{label} less the fitted oscillation (deg)", r[0], np.degrees(r[1])))
    if residual_rows:
        save(_residuals_figure(plt, residual_rows, axis), "residuals")
    return written


def _angles_figure(plt, series, names, axis, title):
    """The ``angles`` view: every measured angle over time, one panel per instrument (deg)."""
    scale, tlabel = axis
    fig, axes = plt.subplots(len(names), 1, figsize=(9, 2.6 * len(names)), squeeze=False)
    for ax, n in zip(axes[:, 0], names):
        s = series[n]
        for label, y in s["angles"].items():
            _band(ax, np.asarray(s["t"], float), np.degrees(np.asarray(y, float)), scale, label)
        ax.set_title(f"{n} ({s['type'] or 'type unknown'})", fontsize=9)
        ax.set_ylabel("deg")
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel(tlabel)
    fig.suptitle(f"angles over time {title}".strip(), fontsize=10)
    return fig


def _apse_rate(scene, name):
    """The scene pendulum ``name``'s predicted apse-line rate, rad/s (``apsidal_rate_from_rest_rad_s``
    of its predictions: the exact elliptic-integral rate, :func:`~gyro_instrument.instruments.pendulum.
    apsidal_rate_from_rest_exact_rad_s`, the one ``describe`` prints and the estimator inverts), or
    None without a scene or such a pendulum."""
    if scene is None:
        return None
    try:
        from gyro_instrument.scenes import build_instruments
        inst = build_instruments(scene).get(name)
        rate = inst.predictions().get("apsidal_rate_from_rest_rad_s") if inst is not None else None
    except Exception:                   # noqa: BLE001 - a scene that does not build draws the k line
        return None
    return float(rate) if rate is not None else None


def _swing_azimuth_figure(plt, series, pend, scene, axis):
    """The ``swing_azimuth`` view: the swing plane's azimuth per swing with the line of the scene
    pendulum's exact apse-line rate (:func:`_apse_rate`; k = n sin γ for a scene without that
    pendulum, or fitted without a scene); returns (figure, residual rows of the azimuth less the line)."""
    scale, tlabel = axis
    residual_rows = []
    k_info = _k_line(scene)
    fig, axes = plt.subplots(len(pend), 1, figsize=(9, 3.2 * len(pend)), squeeze=False)
    for ax, n in zip(axes[:, 0], pend):
        s = series[n]
        tc, az, period = swing_azimuth(np.asarray(s["t"], float), np.asarray(s["east"], float),
                                       np.asarray(s["north"], float))
        if tc.size < 2:
            ax.text(0.5, 0.5, "no swing measured", ha="center", transform=ax.transAxes)
            continue
        rate = _apse_rate(scene, n)
        if rate is not None:
            k, lat = rate, k_info[1]
            label = (f"apse line {k:.4e} rad/s (exact, k = n sin γ = {k_info[0]:.4e} rad/s at γ = {lat:.4f}°, "
                     f"with the ellipse precession)")
        elif k_info is not None:
            k, lat, nrate = k_info
            label = f"k = n sin γ = {k:.4e} rad/s (γ = {lat:.4f}°)"
        else:
            k = float(np.polyfit(tc, az, 1)[0])
            x = max(-1.0, min(1.0, k / SIDEREAL_RATE_RAD_S))
            label = f"fitted k = {k:.4e} rad/s (γ = asin(k/n) = {math.degrees(math.asin(x)):.3f}°, sidereal n)"
        az0 = float(np.mean(az - k * tc))
        ax.plot(tc / scale, np.degrees(az), ".", ms=2, label="swing-plane azimuth (per swing)")
        ax.plot(tc / scale, np.degrees(az0 + k * tc), "-", lw=1, label=label)
        ax.set_ylabel("compass azimuth (deg, unwrapped)")
        ax.set_title(f"{n}: swing plane, period {period:.4f} s", fontsize=9)
        ax.legend(fontsize=7, loc="best")
        residual_rows.append((n, "azimuth less the k line (deg)", tc, np.degrees(az - az0 - k * tc)))
    axes[-1, 0].set_xlabel(tlabel)
    return fig, residual_rows


def _bob_path_figure(plt, series, pend):
    """The ``bob_path`` view: each pendulum's bob seen from above (at most ~60000 points drawn)."""
    fig, axes = plt.subplots(1, len(pend), figsize=(4.5 * len(pend), 4.5), squeeze=False)
    for ax, n in zip(axes[0, :], pend):
        s = series[n]
        e, nn = _finite(np.asarray(s["east"], float), np.asarray(s["north"], float))
        step = max(1, e.size // 60000)
        ax.plot(e[::step], nn[::step], lw=0.2)
        ax.set_aspect("equal", adjustable="datalim")
        unit = s["path_unit"]
        ax.set_xlabel(f"east ({unit})")
        ax.set_ylabel(f"north ({unit})")
        ax.set_title(f"{n}: bob seen from above", fontsize=9)
    return fig


def _residuals_figure(plt, residual_rows, axis):
    """The ``residuals`` view: one panel per (instrument, label, t, residual in deg) row, with its rms."""
    scale, tlabel = axis
    fig, axes = plt.subplots(len(residual_rows), 1, figsize=(9, 2.4 * len(residual_rows)), squeeze=False)
    for ax, (n, label, tt, rr) in zip(axes[:, 0], residual_rows):
        _band(ax, tt, rr, scale, label)
        rms = float(np.sqrt(np.mean(rr ** 2))) if rr.size else float("nan")
        ax.set_title(f"{n}: {label}, rms {rms:.3g}", fontsize=9)
        ax.set_ylabel("deg")
    axes[-1, 0].set_xlabel(tlabel)
    return fig


def plot_file(path, out_dir, scene_arg=None, overrides=(), topics=(), overwrite=False) -> tuple:
    """Read ``path`` (table or bag), draw the views into ``out_dir``; return (PNG paths, notes).

    Raises
    ------
    SceneError
        matplotlib missing; unreadable input; a PNG of a view already in ``out_dir`` without
        ``overwrite`` (nothing is written then); ``out_dir`` is a file.
    """
    _pyplot()
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise SceneError("--out", out_dir, "is a file; give a directory for the PNGs")
    if not overwrite:
        existing = [v for v in VIEWS if os.path.exists(os.path.join(out_dir, f"{v}.png"))]
        if existing:
            raise SceneError("--out", out_dir, f"already holds {', '.join(v + '.png' for v in existing)}; pass "
                                               f"--overwrite to replace them, or give a new directory")
    series, scene, notes = load_series(path, scene_arg, overrides, topics)
    return draw_views(series, scene, out_dir, title=f"({os.path.basename(str(path).rstrip('/'))})"), notes
