"""Measured data (issue 15 part 3): ``estimate --data FILE --scene SCENE`` from CSV and Parquet.

The round trip is checked against ``estimate`` itself: with the sensor's noise switched off,
``estimate`` measures exactly the simulated truth, which is what ``simulate --out`` writes, so
``estimate --data`` of that file must print the same object (bar the ``data`` key naming the file)."""

import csv
import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main as core_main

NOISELESS = ["--set", "sensor.noise_rad=0", "--duration-s", "120"]


def _json(capsys, argv):
    assert core_main(argv) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def expected():
    """``estimate quet_paris`` with the noise off: the same samples simulate writes."""
    import io
    from contextlib import redirect_stdout
    buf = io.StringIO()
    with redirect_stdout(buf):
        assert core_main(["estimate", "quet_paris", *NOISELESS, "--json"]) == 0
    return json.loads(buf.getvalue())


@pytest.mark.parametrize("suffix", ["csv", "parquet"])
def test_simulate_then_estimate_data_gives_the_estimate(tmp_path, capsys, expected, suffix):
    out = tmp_path / f"run.{suffix}"
    assert core_main(["simulate", "quet_paris", *NOISELESS, "--out", str(out), "--quiet"]) == 0
    if suffix == "parquet":
        import pyarrow.parquet as pq
        assert pq.read_table(out).column_names[0] == "time_s"
    got = _json(capsys, ["estimate", "--data", str(out), "--scene", "quet_paris", "--set", "sensor.noise_rad=0",
                         "--json"])
    assert got.pop("data") == out.name
    assert "data_notes" not in got                  # nothing dropped, re-ordered or unknown
    assert json.dumps(got, sort_keys=True) == json.dumps(expected, sort_keys=True)
    assert got["latitude_deg"] == pytest.approx(48.8462, abs=1e-6)


def _pendulum_truth(duration_s=900.0):
    from gyro_instrument.cli import simulate_scene
    from gyro_instrument.scenes import load_scene
    scene = load_scene("foucault_pantheon", [f"duration_s={duration_s}"])
    t, cols, _ = simulate_scene(scene)
    return scene, t, cols["pendulum.x_east"] / 67.0, cols["pendulum.y_north"] / 67.0


def test_hand_made_csv_with_a_gap_nan_and_disorder_estimates_with_notes(tmp_path, capsys):
    """A two-axis deflection log as an instrument would write it: wall-clock times (not from 0),
    a 2-minute gap, a few NaN and empty cells, rows out of order, noise, and a column the scene does
    not know. It estimates k = n sin(latitude) within 3 sigma and says what it did."""
    scene, t, e, n = _pendulum_truth()
    rng = np.random.default_rng(7)
    e = e + rng.normal(0, 1e-4, e.size)
    n = n + rng.normal(0, 1e-4, n.size)
    keep = ~((t > 300) & (t < 420))                      # the gap
    rows = [[repr(float(1.7e9 + ti)), repr(float(ei)), repr(float(ni)), "21.5"] for ti, ei, ni in zip(t[keep], e[keep], n[keep])]
    for i in (50, 51, 900, 4000):
        rows[i][1] = "nan"
    rows[1200][2] = ""
    rows[10], rows[11] = rows[11], rows[10]            # out of order
    rows[3000], rows[2990] = rows[2990], rows[3000]
    path = tmp_path / "lab.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["time_s", "pendulum.deflection_east", "pendulum.deflection_north", "room.temperature_c"])
        w.writerows(rows)
    r = _json(capsys, ["estimate", "--data", str(path), "--scene", "foucault_pantheon", "--json"])
    notes = " | ".join(r["data_notes"])
    assert "pendulum: 5 missing or NaN values left out" in notes
    assert "sorted by time_s" in notes and "times taken from the first sample" in notes
    assert "room.temperature_c" in notes
    k_true = scene.site.earth_rate_rad_s * math.sin(math.radians(48.8462))
    p = r["instruments"]["pendulum"]
    assert abs(p["foucault_rate_rad_s"] - k_true) < 3 * p["foucault_rate_sigma_rad_s"] + 2e-7, p
    assert r["observation_s"] == pytest.approx(t[-1], abs=1e-6)
    # the text output prints the notes
    assert core_main(["estimate", "--data", str(path), "--scene", "foucault_pantheon"]) == 0
    assert "note: pendulum: 5 missing or NaN values left out" in capsys.readouterr().out


@pytest.mark.parametrize("case", ["no time column", "wrong instrument type", "columns missing", "not a number",
                                  "no matching instrument", "not parquet", "missing file"])
def test_bad_data_exits_2_with_one_line(tmp_path, capsys, case):
    path = tmp_path / "d.csv"
    header, row = ["time_s", "pendulum.x_east", "pendulum.y_north"], ["0", "0.1", "0.2"]
    expect = {"no time column": "has no time column 'time_s'",
              "wrong instrument type": "does not match the scene's gyro_horizontal (plane_gyroscope)",
              "columns missing": "needs pendulum.x_east, pendulum.y_north or pendulum.deflection_east",
              "not a number": "line 2, column pendulum.x_east: 'abc' is not a number",
              "no matching instrument": "no instrument's columns found",
              "not parquet": "cannot be read as Parquet",
              "missing file": "file not found"}[case]
    if case == "no time column":
        header[0] = "t"
    elif case == "wrong instrument type":
        header[1:] = ["gyro_horizontal.x_east", "gyro_horizontal.y_north"]
    elif case == "columns missing":
        header, row = header[:2], row[:2]
    elif case == "not a number":
        row[1] = "abc"
    elif case == "no matching instrument":
        header[1:] = ["other.x_east", "other.y_north"]
    elif case == "not parquet":
        path = tmp_path / "d.parquet"
    if case != "missing file":
        path.write_text(",".join(header) + "\n" + ",".join(row) + "\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    assert core_main(["estimate", "--data", str(path), "--scene", "quet_paris"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expect in err[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
