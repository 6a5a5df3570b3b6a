"""Issue 26, "pictures people can use": the views drawn over the whole record (awkward rates, NaN),
an envelope over bins of several periods, the swing plane's line anchored at the release at the
exact finite-amplitude rate, a southern release at 0° drawn from 0°, rates in °/h, no bare symbols,
a drift at its true size; tables carrying their scene; the animation's frames; text that leads with
the answer; no traceback on a closed pipe or an all-zero channel. Checked through matplotlib's
artist tree."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from gyro_instrument.cli import main as core_main
from gyro_instrument.estimators.data_io import write_table

ROOT = Path(__file__).resolve().parents[1]
SOUTH = """name: south_class
description: 10 m pendulum at -37.8 deg released at 20 deg toward north
site: {latitude_deg: -37.8}
duration_s: 900
sample_rate_hz: 20
seed: 3
effects: {earth_rotation: {}, centrifugal: {}, finite_amplitude: {}}
sensor: {noise_rad: 1.0e-4}
instruments:
  pendulum: {type: spherical_pendulum, length_m: 10.0, initial_deflection_deg: 20.0, initial_azimuth_deg: 0.0}
"""


def _figures(series, scene, window=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gyro_instrument.views import record_span
    from gyro_instrument.views.figures import angles_figure, azimuth_figure, time_axis
    from gyro_instrument.views.measure import expected_line
    from gyro_instrument.views.rosette import rosette_figure
    lo, hi = record_span(series)
    axis = time_axis(hi - lo)
    pend = [n for n in series if "east" in series[n]]
    figs = {"angles": angles_figure(plt, series, axis, "")}
    if pend:
        figs["swing_azimuth"], rows = azimuth_figure(plt, series, pend, {n: expected_line(scene, n) for n in pend}, axis)
        figs["bob_path"] = rosette_figure(plt, series, pend, window, axis)
    return figs, axis


def _x_extent(ax):
    xs = []
    for line in ax.get_lines():
        x = np.asarray(line.get_xdata(), float)
        xs.append(x[np.isfinite(x)])
    for coll in ax.collections:
        for path in coll.get_paths():
            xs.append(path.vertices[:, 0])
    x = np.concatenate(xs)
    return float(x.min()), float(x.max())


def _texts(fig):
    import matplotlib.text
    return [t.get_text() for t in fig.findobj(matplotlib.text.Text)]


@pytest.mark.parametrize("rate_hz,duration_s", [(14.0, 600.0), (14.0, 2000.0), (20.0, 3000.0)])
def test_angles_cover_the_whole_record_at_awkward_rates_with_nan(tmp_path, rate_hz, duration_s):
    from gyro_instrument.views import load_series
    t = np.arange(0.0, duration_s, 1.0 / rate_hz)
    y = 0.1 * np.cos(2 * math.pi * t / 7.3)
    y[np.random.default_rng(0).choice(t.size - 2, 15, replace=False) + 1] = np.nan
    path = tmp_path / "g.csv"
    write_table(str(path), t, {"gyro.angle": y})
    series, scene, _ = load_series(str(path))
    figs, (scale, _) = _figures(series, scene)
    ax = figs["angles"].axes[0]
    lo, hi = _x_extent(ax)
    assert lo == pytest.approx(t[0] / scale, abs=1e-12) and hi == pytest.approx(t[-1] / scale, rel=1e-12)
    assert ax.get_ylabel() == "angle (degrees)"
    if t.size > 20000:             # the envelope's bins span several periods: no false beating
        label = ax.get_legend().get_texts()[0].get_text()
        assert "min-max over bins of" in label and int(label.split("bins of ")[1].split()[0]) >= 4


def test_gaps_are_drawn_as_gaps(tmp_path):
    from gyro_instrument.views import load_series
    t = np.concatenate([np.arange(0, 100, 0.1), np.arange(200, 300, 0.1)])
    path = tmp_path / "g.csv"
    write_table(str(path), t, {"gyro.angle": np.sin(t)})
    series, scene, _ = load_series(str(path))
    figs, _ = _figures(series, scene)
    x = figs["angles"].axes[0].get_lines()[0].get_xdata()
    assert np.isnan(x).sum() == 1           # one break, at the gap


@pytest.fixture(scope="module")
def south(tmp_path_factory):
    d = tmp_path_factory.mktemp("south")
    (d / "south.yaml").write_text(SOUTH)
    assert core_main(["simulate", str(d / "south.yaml"), "--out", str(d / "s.parquet"), "--quiet"]) == 0
    assert core_main(["simulate", str(d / "south.yaml"), "--out", str(d / "s.csv"), "--quiet"]) == 0
    return d


def test_southern_release_is_anchored_at_zero_at_the_exact_rate(south):
    from gyro_instrument.views import load_series
    from gyro_instrument.scenes import build_instruments
    series, scene, notes = load_series(str(south / "s.parquet"))
    assert scene is not None and scene.name == "south_class" and "Parquet metadata" in notes[0]
    figs, (scale, _) = _figures(series, scene)
    ax = figs["swing_azimuth"].axes[0]
    points, line = ax.get_lines()[:2]
    x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    assert x[0] == 0.0 and y[0] == 0.0                      # anchored at the release: 0°, not 180°
    exact = build_instruments(scene)["pendulum"].predictions()["apsidal_rate_from_rest_rad_s"]
    assert (y[1] - y[0]) / ((x[1] - x[0]) * scale) == pytest.approx(math.degrees(exact), rel=1e-9)
    assert abs(np.asarray(points.get_ydata())[0]) < 1.0
    assert _x_extent(ax)[1] == pytest.approx(float(np.nanmax(series["pendulum"]["t"])) / scale)
    text = " ".join(_texts(figs["swing_azimuth"]))
    assert f"{math.degrees(exact) * 3600:+.3f} °/h" in text and "37.80° S" in text and "counter-clockwise" in text
    assert "γ" not in " ".join(t for f in figs.values() for t in _texts(f))
    assert figs["angles"].axes[0].get_ylabel() == "angle (degrees)"


def test_rosette_is_coloured_by_time_with_start_and_arrow(south):
    from matplotlib.collections import LineCollection
    from matplotlib.patches import FancyArrowPatch
    from gyro_instrument.views import load_series
    series, scene, _ = load_series(str(south / "s.csv"))
    figs, _ = _figures(series, scene, window=(100.0, 800.0))
    ax = figs["bob_path"].axes[0]
    lc = [c for c in ax.collections if isinstance(c, LineCollection)][0]
    times = lc.get_array()
    assert times.min() >= 100.0 / 60 - 1e-9 and times.max() <= 800.0 / 60 + 1e-9   # the window, in minutes
    assert any(isinstance(p, FancyArrowPatch) for p in ax.patches)
    assert any("start" in t.get_text() for t in ax.get_legend().get_texts())
    assert ax.get_xlabel() == "east (m)" and ax.get_ylabel() == "north (m)"


def test_equator_drift_is_drawn_at_its_true_size(tmp_path):
    from gyro_instrument.views import load_series
    yaml_ = tmp_path / "eq.yaml"
    yaml_.write_text(SOUTH.replace("-37.8", "0.0").replace("20.0, initial", "2.0, initial")
                     .replace("duration_s: 900", "duration_s: 300"))
    assert core_main(["simulate", str(yaml_), "--out", str(tmp_path / "e.parquet"), "--quiet"]) == 0
    series, scene, _ = load_series(str(tmp_path / "e.parquet"))
    figs, _ = _figures(series, scene)
    lo, hi = figs["swing_azimuth"].axes[0].get_ylim()
    assert hi - lo >= 2.0


def test_table_without_scene_is_drawn_in_metres_with_a_note(tmp_path, capsys, south):
    import pyarrow.parquet as pq
    table = pq.read_table(south / "s.parquet").replace_schema_metadata(None)
    pq.write_table(table, tmp_path / "bare.parquet")
    from gyro_instrument.views import load_series
    series, scene, notes = load_series(str(tmp_path / "bare.parquet"))
    assert scene is None and "metres" in notes[0]
    assert [u for _, _, u in series["pendulum"]["channels"]] == ["m", "m"]
    figs, _ = _figures(series, scene)
    assert figs["angles"].axes[0].get_ylabel() == "position (m)"
    assert core_main(["estimate", "--data", str(tmp_path / "bare.parquet")]) == 2
    assert "give the scene" in capsys.readouterr().err


def test_all_zero_pendulum_draws_what_it_can(tmp_path, capsys):
    t = np.arange(0.0, 200.0, 0.05)
    z = np.zeros_like(t)
    write_table(str(tmp_path / "z.csv"), t, {"pendulum.x_east": z, "pendulum.y_north": z,
                                             "gyro.angle": np.full_like(t, 0.3)})
    assert core_main(["plot", str(tmp_path / "z.csv"), "--out", str(tmp_path / "v")]) == 0
    assert sorted(p.name for p in (tmp_path / "v").iterdir()) == ["angles.png", "bob_path.png", "swing_azimuth.png"]
    assert "Traceback" not in capsys.readouterr().err


def test_tables_carry_their_scene_and_the_sidecar_obeys_overwrite(south, tmp_path, capsys):
    import pyarrow.parquet as pq
    meta = pq.read_schema(south / "s.parquet").metadata
    assert {b"gyro_instrument.scene_yaml", b"gyro_instrument.scene_seed", b"gyro_instrument.units",
            b"gyro_instrument.version"} <= set(meta)
    assert (south / "s.scene.yaml").read_text().count("south_class") == 1
    (tmp_path / "south.yaml").write_text(SOUTH.replace("duration_s: 900", "duration_s: 10"))
    (tmp_path / "r.scene.yaml").write_text("x")
    assert core_main(["simulate", str(tmp_path / "south.yaml"), "--out", str(tmp_path / "r.csv"), "--quiet"]) == 2
    assert "r.scene.yaml" in capsys.readouterr().err and not (tmp_path / "r.csv").exists()
    assert core_main(["estimate", "--data", str(south / "s.csv")]) == 0
    out, err = capsys.readouterr()
    assert "using the scene 'south_class'" in err and out.startswith("latitude 37.")


def test_animation_frame_count(south, tmp_path):
    from PIL import Image
    from gyro_instrument.views.animate import frame_times
    assert core_main(["plot", str(south / "s.parquet"), "--out", str(tmp_path / "a"), "--animate",
                      "--format", "svg"]) == 0
    assert (tmp_path / "a" / "angles.svg").exists()
    with Image.open(tmp_path / "a" / "animation.gif") as im:
        # issue 34 item 5: at least 20 frames for any record length, sized for a slide (>= 1200 px)
        assert im.n_frames == len(frame_times(0.0, 900.0 - 0.05)) == 20
        assert im.size[0] >= 1200
    assert len(frame_times(0.0, 86400.0)) == 120               # a day in 20 s at 6 frames/s
    assert len(frame_times(0.0, 60.0)) == 20


def test_describe_leads_with_the_answer_and_wraps(capsys):
    assert core_main(["describe", "foucault_pantheon"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "latitude 48.8462° N" in lines[2] and "°/h" in " ".join(lines[3:5]) and "full turn in" in lines[3]
    assert max(len(x) for x in lines) <= 120


def test_closed_pipe_is_quiet():
    cmd = f"{sys.executable} -m gyro_instrument.cli describe quet_paris | head -2"
    r = subprocess.run(["bash", "-c", cmd + "; echo ${PIPESTATUS[0]} >&2"], capture_output=True, text=True,
                       cwd=ROOT)
    assert len(r.stdout.splitlines()) == 2 and "Traceback" not in r.stderr and "BrokenPipe" not in r.stderr
    assert r.stderr.strip().splitlines()[-1] in ("0", "141")


from realdata import HEIGVD_OPTIONS, HEIGVD_SCENE, REALDATA  # noqa: E402


def _data_boxes_clear_of(fig, ax):
    """True when no plotted point of ``ax`` lies inside its legend's or its texts' boxes (pixels)."""
    fig.canvas.draw()
    boxes = [a.get_window_extent() for a in [ax.get_legend()] + list(ax.texts) if a is not None]
    for line in ax.get_lines():
        xy = ax.transData.transform(np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float))
        xy = xy[np.isfinite(xy).all(axis=1)]
        for b in boxes:
            if np.any((xy[:, 0] > b.x0) & (xy[:, 0] < b.x1) & (xy[:, 1] > b.y0) & (xy[:, 1] < b.y1)):
                return False
    return True


def test_heigvd_plot_with_the_documented_options(tmp_path, capsys):
    # item 4/5: plot reads the published track (no header, mm, date-time text) with estimate's flags
    (tmp_path / "h.yaml").write_text(HEIGVD_SCENE)
    data = str(REALDATA / "heigvd_periode_06_22_09_27.csv")
    out = tmp_path / "v"
    assert core_main(["plot", data, "--scene", str(tmp_path / "h.yaml"), "--out", str(out), "--animate"]
                     + HEIGVD_OPTIONS) == 0
    assert "date-time text" in capsys.readouterr().err
    assert {"angles.png", "swing_azimuth.png", "bob_path.png", "residuals.png", "animation.gif"} <= \
        {p.name for p in out.iterdir()}
    # without the flags the headerless file is refused in one line saying what to pass
    assert core_main(["plot", data, "--out", str(tmp_path / "w")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--no-header --names" in err[0]


def test_measured_expected_line_goes_through_the_first_swing_and_nothing_covers_the_data(tmp_path):
    # item 5: with a --scene (a measurement, no release known) the expected line passes through the
    # first measured swing's azimuth (the HEIG-VD record starts 89° from the scene's release); every
    # legend and caption box is clear of every plotted point
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gyro_instrument.estimators.table_read import TableOptions
    from gyro_instrument.estimators.table_camera import CameraOptions
    from gyro_instrument.views import load_series, record_span
    from gyro_instrument.views.figures import angles_figure, azimuth_figure, residuals_figure, time_axis
    from gyro_instrument.views.measure import expected_line, swing_azimuth
    from gyro_instrument.views.rosette import rosette_figure
    (tmp_path / "h.yaml").write_text(HEIGVD_SCENE)
    opts = TableOptions(names=tuple(HEIGVD_OPTIONS[2].split(",")), camera=CameraOptions(metres_per_pixel=0.001))
    series, scene, _ = load_series(str(REALDATA / "heigvd_periode_06_22_09_27.csv"), str(tmp_path / "h.yaml"),
                                   options=opts)
    assert series["pendulum"]["simulated"] is False
    line = expected_line(scene, "pendulum")
    line["anchor"] = "first swing"
    lo, hi = record_span(series)
    axis = time_axis(hi - lo)
    fig, rows = azimuth_figure(plt, series, ["pendulum"], {"pendulum": line}, axis)
    ax = fig.axes[0]
    s = series["pendulum"]
    tc, az, _ = swing_azimuth(s["t"], s["east"], s["north"])
    expected = ax.get_lines()[1]
    x, y = np.asarray(expected.get_xdata()), np.asarray(expected.get_ydata())
    # the line at the first swing's time is the first swing's azimuth (to rounding: 1e-9°)
    at_first = y[0] + (y[1] - y[0]) * (tc[0] / axis[0] - x[0]) / (x[1] - x[0])
    assert at_first == pytest.approx(math.degrees(az[0]), abs=1e-9)
    # its slope is a free pendulum's n sin(latitude) at the scene's site
    assert (y[1] - y[0]) / ((x[1] - x[0]) * axis[0]) == pytest.approx(math.degrees(line["k_rad_s"]), rel=1e-9)
    assert _data_boxes_clear_of(fig, ax)
    figs = [angles_figure(plt, series, axis, ""), residuals_figure(plt, rows, axis),
            rosette_figure(plt, series, ["pendulum"], None, axis)]
    for f in figs:
        for a in f.axes:
            if a.get_lines():
                assert _data_boxes_clear_of(f, a)
    # the residual about the anchored line starts at zero (not 89°, the "rms 54.6°")
    assert abs(rows[0][3][0]) < 1e-9
    plt.close("all")


def test_first_animation_frame_shows_the_release_plane(south, tmp_path):
    # item 5: the first frame's swing plane lies along the release azimuth (the scene: 0°, north-
    # south; and an east-west release east-west), not the identity's north-south whatever the release
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from gyro_instrument.views import load_series
    from gyro_instrument.views.animate import _pendulum_frames
    (tmp_path / "ew.yaml").write_text(SOUTH.replace("initial_azimuth_deg: 0.0", "initial_azimuth_deg: 90.0")
                                      .replace("duration_s: 900", "duration_s: 120"))
    assert core_main(["simulate", str(tmp_path / "ew.yaml"), "--out", str(tmp_path / "ew.parquet"), "--quiet"]) == 0
    for path, release_deg in ((south / "s.parquet", 0.0), (tmp_path / "ew.parquet", 90.0)):
        series, _, _ = load_series(str(path))
        fig, ax = plt.subplots()
        draw = _pendulum_frames(ax, series["pendulum"])
        draw(float(np.nanmin(series["pendulum"]["t"])))
        plane = next(ln for ln in ax.get_lines() if ln.get_label() == "swing plane")
        xs, ys = plane.get_xdata(), plane.get_ydata()
        az = math.degrees(math.atan2(xs[1] - xs[0], ys[1] - ys[0])) % 180.0
        # within 1° of the release (the plane turns ~0.2° in the first 40 s at 37.8° S)
        assert min(abs(az - release_deg), 180.0 - abs(az - release_deg)) < 1.0
        plt.close(fig)
