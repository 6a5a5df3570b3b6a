"""``gyro-instrument plot`` (issue 15 part 4): the standard views of a CSV, a Parquet table and a
bag drawn to PNG; existing PNGs are not written over; without matplotlib the command says how to
install it. (The time to plot a long record is a bench target: ``bench`` draws a day.)"""

import os
from pathlib import Path

import numpy as np
import pytest

from gyro_instrument.cli import main as core_main

ROOT = Path(__file__).resolve().parents[1]
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    d = tmp_path_factory.mktemp("tables")
    for suffix in ("csv", "parquet"):
        assert core_main(["simulate", "quet_paris", "--duration-s", "120", "--out", str(d / f"q.{suffix}"),
                          "--quiet"]) == 0
    return d


@pytest.fixture
def drawn(monkeypatch):
    """{view file name: [(panel title, [(label, x, y) of each line])]}: what each figure held when saved."""
    from matplotlib.figure import Figure
    views, save = {}, Figure.savefig

    def savefig(fig, path, *args, **kwargs):
        views[os.path.basename(str(path))] = [
            (ax.get_title(), [(ln.get_label(), np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float))
                              for ln in ax.lines]) for ax in fig.axes]
        return save(fig, path, *args, **kwargs)
    monkeypatch.setattr(Figure, "savefig", savefig)
    return views


def _check_pngs(out, views=("angles", "swing_azimuth", "bob_path", "residuals")):
    import matplotlib.image as mpimg
    assert sorted(p.name for p in out.iterdir()) == sorted(f"{v}.png" for v in views)
    for v in views:
        p = out / f"{v}.png"
        assert p.read_bytes()[:8] == PNG
        img = mpimg.imread(p)
        h, w, _ = img.shape
        assert h > 200 and w >= 1600          # readable on a slide (issue 26)
        # something drawn, not a blank page: between 1 % and 60 % of the pixels are not white (the
        # views of the 120 s table measured 4-8 %), and the lines' colours are there: pixels well away
        # from grey (measured 0.4-2.6 %; axes, ticks and text alone are grey)
        rgb = img[:, :, :3]
        ink = np.any(rgb < 0.95, axis=2).mean()
        colour = (rgb.max(axis=2) - rgb.min(axis=2) > 0.3).mean()
        assert 0.01 < ink < 0.6 and colour > 1e-3, (v, ink, colour)


def _panel(drawn, view, title_start, label):
    """(x, y) of the one line whose label starts with ``label`` in the panel whose title starts with
    ``title_start``."""
    (x, y), = [(x, y) for title, lines in drawn[view] if title.startswith(title_start)
               for lab, x, y in lines if lab.startswith(label)]
    return x, y


def _check_values(drawn, t_s, angle_rad, east_rad, length_m=67.0):
    """The angles view draws the record's values: the horizontal gyroscope's angle in degrees over
    time in seconds (a 120 s record: seconds, no binning under 20000 samples), the pendulum's east
    deflection as degrees of x/length; the swing azimuth's measured points lie on the line expected
    from the release (the Foucault rate n sin(latitude), 11.3 deg/h at Paris) to 1e-3 deg."""
    x, y = _panel(drawn, "angles.png", "gyro_horizontal", "angle")
    np.testing.assert_allclose(x, t_s, rtol=0, atol=1e-9)
    np.testing.assert_allclose(y, np.degrees(angle_rad), rtol=0, atol=1e-12)
    x, y = _panel(drawn, "angles.png", "pendulum", "deflection east (x/length)")
    np.testing.assert_allclose(y, np.degrees(east_rad), rtol=0, atol=1e-12)
    tp, az = _panel(drawn, "swing_azimuth.png", "pendulum", "measured, one point per swing")
    # the line from the release (a simulated table), or through the first swing (--scene: a measurement)
    tl, line = _panel(drawn, "swing_azimuth.png", "pendulum", "expected")
    rate_deg_s = np.degrees(7.292115e-5 * np.sin(np.radians(48.8462)))
    assert (line[1] - line[0]) / (tl[1] - tl[0]) == pytest.approx(rate_deg_s, rel=1e-3)
    assert len(tp) >= 6 and np.max(np.abs(az - np.interp(tp, tl, line))) < 1e-3


def _table(path):
    import csv
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    col = lambda k: np.array([float(r[k]) for r in rows])  # noqa: E731
    return col("time_s"), col("gyro_horizontal.angle"), col("pendulum.x_east") / 67.0


@pytest.mark.parametrize("source", ["csv", "csv with scene", "parquet", "bag"])
def test_plot_draws_every_view(tmp_path, capsys, tables, source, drawn):
    argv = {"csv": [str(tables / "q.csv")],
            "csv with scene": [str(tables / "q.csv"), "--scene", "quet_paris"],
            "parquet": [str(tables / "q.parquet")],
            "bag": [str(ROOT / "bags" / "quet_paris.mcap")]}[source]
    out = tmp_path / "views"
    assert core_main(["plot", *argv, "--out", str(out)]) == 0
    assert "wrote 4 views" in capsys.readouterr().out
    _check_pngs(out)
    if source == "bag":     # the recorded (noisy) samples, as the project's reader decodes them
        from gyro_instrument.recording.bag_samples import samples_from_bag
        _, samples, _, _ = samples_from_bag(argv[0])
        t_ns, pos, _ = samples["gyro_horizontal"]
        x, y = _panel(drawn, "angles.png", "gyro_horizontal", "angle")
        np.testing.assert_allclose(y, np.degrees(pos[:, 0]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(x, t_ns / 1e9, rtol=0, atol=1e-9)     # 600 s: drawn in seconds
    else:                   # the simulated table (noise-free): the file's own columns
        _check_values(drawn, *_table(tables / "q.csv"))


def test_default_output_directory_and_no_overwrite(tmp_path, capsys, tables, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert core_main(["plot", str(tables / "q.csv")]) == 0
    out = tmp_path / "q_plots"
    _check_pngs(out)
    before = (out / "angles.png").read_bytes()
    capsys.readouterr()      # the first run's note (the scene taken from q.scene.yaml)
    assert core_main(["plot", str(tables / "q.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already holds angles.png" in err[0] and "--overwrite" in err[0]
    assert (out / "angles.png").read_bytes() == before
    assert core_main(["plot", str(tables / "q.csv"), "--overwrite"]) == 0


def test_without_matplotlib_the_command_says_how_to_install_it(tmp_path, capsys, tables, monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert core_main(["plot", str(tables / "q.csv"), "--out", str(tmp_path / "v")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pip install 'gyro_instrument[plot]'" in err[0]
    assert not (tmp_path / "v").exists()


def test_plot_bad_input_exits_2(tmp_path, capsys):
    bad = tmp_path / "x.csv"
    bad.write_text("t,a\n0,1\n")
    assert core_main(["plot", str(bad), "--out", str(tmp_path / "v")]) == 2
    assert "has no time column" in capsys.readouterr().err
    assert not (tmp_path / "v").exists()
