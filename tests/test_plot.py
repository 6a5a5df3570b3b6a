"""``gyro-instrument plot`` (issue 15 part 4): the standard views of a CSV, a Parquet table and a
bag drawn to PNG; existing PNGs are not written over; without matplotlib the command says how to
install it. (The time to plot a long record is a bench target: ``bench`` draws a day.)"""

import os
from pathlib import Path

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


def _check_pngs(out, views=("angles", "swing_azimuth", "bob_path", "residuals")):
    import matplotlib.image as mpimg
    assert sorted(p.name for p in out.iterdir()) == sorted(f"{v}.png" for v in views)
    for v in views:
        p = out / f"{v}.png"
        assert p.stat().st_size > 5000 and p.read_bytes()[:8] == PNG
        h, w, _ = mpimg.imread(p).shape
        assert h > 200 and w >= 1600          # readable on a slide (issue 26)


@pytest.mark.parametrize("source", ["csv", "csv with scene", "parquet", "bag"])
def test_plot_draws_every_view(tmp_path, capsys, tables, source):
    argv = {"csv": [str(tables / "q.csv")],
            "csv with scene": [str(tables / "q.csv"), "--scene", "quet_paris"],
            "parquet": [str(tables / "q.parquet")],
            "bag": [str(ROOT / "bags" / "quet_paris.mcap")]}[source]
    out = tmp_path / "views"
    assert core_main(["plot", *argv, "--out", str(out)]) == 0
    assert "wrote 4 views" in capsys.readouterr().out
    _check_pngs(out)


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
