"""Tables as users have them (issue 22 item 2): ``estimate --data`` with ``--time-column``,
``--time-unit``, ``--angle-unit``, ``--column``, CSV byte-order marks, ``;`` and decimal commas,
Parquet timestamp/duration times, duplicated names, a time column that never increases, a gyroscope
without ``spin_rate``, and the sampling notes.

Every conversion is checked on physics: the table ``simulate`` writes for quet_gyroscopes (60 s,
20 Hz, noiseless: the truth) is rewritten the way a user's logger would have it, and the estimate
from the rewritten table is compared with the estimate from the original. ``simulate``'s times are
``round(i * 1e9 / f) / 1e9`` (core.scene.sample_times); a whole number of ms (or ns) divided by
10**3 (10**9) in one IEEE division is the double nearest the same exact time, so those conversions
give the same doubles and the estimate must be equal bit for bit, not merely close."""

import json
import subprocess
import sys

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.estimators.data_io import TIME_COLUMN, load_table, read_table, write_table

SCENE = "quet_gyroscopes"
GYROS = ("gyro_horizontal", "gyro_meridian")


@pytest.fixture(scope="module")
def original(tmp_path_factory):
    """The simulated table (columns as read back) and the estimate from it."""
    out = tmp_path_factory.mktemp("orig") / "run.csv"
    assert main(["simulate", SCENE, "--duration-s", "60", "--out", str(out), "--quiet"]) == 0
    cols = read_table(str(out))
    return cols, _estimate(out)


def _estimate(path, *flags):
    import io
    from contextlib import redirect_stdout
    buf = io.StringIO()
    with redirect_stdout(buf):
        rc = main(["estimate", "--data", str(path), "--scene", SCENE, "--duration-s", "60", "--json", *flags])
    assert rc == 0
    return json.loads(buf.getvalue())


def physics(r):
    """What the estimate measures: latitude, Earth rate and each gyroscope's swing duration."""
    out = {"latitude_deg": r["latitude_deg"], "earth_rate_rad_s": r["earth_rate_rad_s"]}
    for g in GYROS:
        out[f"{g}.swing_duration_s"] = r["instruments"][g]["swing_duration_s"]
        out[f"{g}.mean_spin_rad_s"] = r["instruments"][g]["mean_spin_rad_s"]
    return out


def _write_csv(path, header, columns, sep=",", decimal=".", bom=False):
    with open(path, "w", encoding="utf-8-sig" if bom else "utf-8", newline="") as fh:
        fh.write(sep.join(header) + "\n")
        for row in zip(*columns):
            fh.write(sep.join(v if isinstance(v, str) else repr(float(v)).replace(".", decimal) for v in row) + "\n")


def _channels(cols):
    return [c for c in cols if c != TIME_COLUMN]


@pytest.mark.parametrize("unit, per_s", [("ms", 1000), ("ns", 10 ** 9)])
def test_time_in_whole_ms_or_ns_gives_the_same_estimate_bit_for_bit(tmp_path, original, unit, per_s):
    cols, expected = original
    ticks = np.round(cols[TIME_COLUMN] * per_s).astype(np.int64)     # what a logger stamps
    path = tmp_path / f"{unit}.csv"
    _write_csv(path, ["stamp"] + _channels(cols), [[str(k) for k in ticks]] + [cols[c] for c in _channels(cols)])
    got = _estimate(path, "--time-column", "stamp", "--time-unit", unit)
    assert physics(got) == physics(expected)
    assert f"stamp in {unit}: converted to s" in got["data_notes"]
    assert "time from column stamp" in got["data_notes"]


def test_time_in_minutes(tmp_path, original):
    """Minutes are t/60 written in shortest repr, read back times 60: each time within 1 ulp of
    60 s (7e-15 s) of the original; a uniform relative error e of the time scale changes a swing
    duration by the same e, so the swing durations agree to 1e-13 relative and the Earth rate
    (n ~ 1/T^2) to 2e-13, far inside the fit's own precision (sigma_T / T ~ 3e-11). Asserted to
    1e-12 relative; measured: swing durations equal, latitude and Earth rate 1 ulp (2.2e-16)."""
    cols, expected = original
    path = tmp_path / "min.csv"
    _write_csv(path, ["time_min"] + _channels(cols), [cols[TIME_COLUMN] / 60] + [cols[c] for c in _channels(cols)])
    got = physics(_estimate(path, "--time-column", "time_min", "--time-unit", "min"))
    for k, v in physics(expected).items():
        assert got[k] == pytest.approx(v, rel=1e-12, abs=1e-12), k


def test_degrees_read_as_radians_and_only_the_angle_channels(tmp_path, original):
    """Angles in degrees (np.degrees, shortest repr) read with --angle-unit deg: each angle within
    2 ulp of the radian value (relative 4.4e-16); a swing duration is set by the zero crossings,
    which such a relative error of every sample cannot move by more than ~1e-16 of a period. Measured:
    swing durations equal, latitude and Earth rate 1 ulp (2.2e-16) apart; asserted to 1e-12 relative. spin_rate (rad/s) is not converted: were it, the
    mean spin would be 628 * pi / 180."""
    cols, expected = original
    path = tmp_path / "deg.csv"
    conv = {c: (np.degrees(cols[c]) if c.endswith(".angle") else cols[c]) for c in _channels(cols)}
    _write_csv(path, [TIME_COLUMN] + list(conv), [cols[TIME_COLUMN]] + list(conv.values()))
    got = _estimate(path, "--angle-unit", "deg")
    for k, v in physics(expected).items():
        assert physics(got)[k] == pytest.approx(v, rel=1e-12), k
    note = next(n for n in got["data_notes"] if n.startswith("angles in degrees"))
    assert "gyro_horizontal.angle" in note and "spin_rate" not in note and "angle_rate" not in note


def test_angle_unit_leaves_metres_and_rates_alone(tmp_path):
    path = tmp_path / "p.csv"
    path.write_text("time_s,pendulum.x_east,pendulum.deflection_east,g.spin_rate,g.outer_angle,g.inner_angle\n"
                    "0,1,180,100,90,45\n")
    from gyro_instrument.estimators.data_io import TableOptions
    cols, _ = load_table(str(path), options=TableOptions(angle_unit="deg"))
    assert cols["pendulum.x_east"][0] == 1 and cols["g.spin_rate"][0] == 100
    assert cols["pendulum.deflection_east"][0] == np.pi
    assert cols["g.outer_angle"][0] == np.pi / 2 and cols["g.inner_angle"][0] == np.pi / 4


def test_renamed_column_gives_the_same_estimate(tmp_path, original):
    cols, expected = original
    path = tmp_path / "renamed.csv"
    names = {c: ("Theta" if c == "gyro_horizontal.angle" else c) for c in cols}
    _write_csv(path, list(names.values()), [cols[c] for c in names])
    got = _estimate(path, "--column", "gyro_horizontal.angle=Theta")
    assert physics(got) == physics(expected)
    assert "columns read as channels: Theta as gyro_horizontal.angle" in got["data_notes"]


@pytest.mark.parametrize("sep, decimal, bom", [(",", ".", True), (";", ",", False), (";", ",", True),
                                               (";", ".", False), ("\t", ".", False)])
def test_bom_semicolon_decimal_comma_round_trip(tmp_path, original, sep, decimal, bom):
    """The same shortest-repr digits with a comma for the point read back to the same doubles:
    the estimate is equal bit for bit."""
    cols, expected = original
    path = tmp_path / "eu.csv"
    _write_csv(path, list(cols), list(cols.values()), sep=sep, decimal=decimal, bom=bom)
    if bom:
        assert path.read_bytes()[:3] == b"\xef\xbb\xbf"
    got = _estimate(path)
    assert physics(got) == physics(expected)
    if sep == ",":
        assert "data_notes" not in got
    else:
        assert any(n.startswith("CSV separated by") for n in got["data_notes"])


@pytest.mark.parametrize("kind", ["timestamp_ns_utc", "timestamp_us", "duration_ns", "duration_ms"])
def test_parquet_timestamp_and_duration_equal_the_float_table(tmp_path, original, kind):
    """Integer stamps converted exactly (integer subtraction of the first timestamp, then one
    division): the same doubles as the float table, so the same estimate bit for bit."""
    import pyarrow as pa
    import pyarrow.parquet as pq
    cols, expected = original
    typ, unit = kind.split("_")[0], kind.split("_")[1]
    per_s = {"ns": 10 ** 9, "us": 10 ** 6, "ms": 1000}[unit]
    ticks = np.round(cols[TIME_COLUMN] * per_s).astype(np.int64)
    if typ == "timestamp":
        ticks = ticks + 1_764_504_000 * per_s            # 2025-11-30 12:00 UTC: an absolute clock
        arrow_type = pa.timestamp(unit, tz="UTC" if kind.endswith("utc") else None)
    else:
        arrow_type = pa.duration(unit)
    table = pa.table({TIME_COLUMN: pa.array(ticks, arrow_type), **{c: cols[c] for c in _channels(cols)}})
    path = tmp_path / "t.parquet"
    pq.write_table(table, path)
    got = _estimate(path)
    assert physics(got) == physics(expected)
    assert got["observation_s"] == 60.0
    if typ == "timestamp":
        assert any("seconds from the earliest sample (2025-11-30 12:00:00" in n for n in got["data_notes"])


def test_gyroscope_without_spin_rate_takes_the_scene_spin(tmp_path, original):
    """The relative spin rho varies only through rho + n sin(omega) cos(u) = const (Quet), by at
    most n = 7.3e-5 rad/s of 628 rad/s: relative 1.2e-7. The Earth rate (eq. 10, n ~ 1/rho) moves by
    no more than that, and the latitude (item 9, cos(lat) from the ratio of the two gyroscopes' K/rho)
    by at most cot(lat) * 2.4e-7 rad = 1.2e-5 deg. Measured: 3e-10 relative and 5e-9 deg."""
    cols, expected = original
    path = tmp_path / "nospin.csv"
    keep = [c for c in cols if not c.endswith(".spin_rate")]
    write_table(str(path), cols[TIME_COLUMN], {c: cols[c] for c in keep if c != TIME_COLUMN})
    got = _estimate(path)
    nominal = 2 * np.pi * 100
    for g in GYROS:
        assert got["instruments"][g]["mean_spin_rad_s"] == pytest.approx(nominal, rel=1e-15)
        assert any(n.startswith(f"{g}: no {g}.spin_rate column: the scene's constant spin") for n in got["data_notes"])
    assert got["earth_rate_rad_s"] == pytest.approx(expected["earth_rate_rad_s"], rel=1.2e-7)
    assert got["latitude_deg"] == pytest.approx(expected["latitude_deg"], abs=1.2e-5)


def test_reversed_rows_are_sorted_and_noted(tmp_path, original):
    cols, expected = original
    path = tmp_path / "newest_first.csv"
    _write_csv(path, list(cols), [v[::-1] for v in cols.values()])
    got = _estimate(path)
    assert physics(got) == physics(expected)
    assert "rows in decreasing time order: sorted by time_s" in got["data_notes"]


def test_gaps_and_irregular_sampling_are_noted(tmp_path, original):
    """A 10 s hole (20 to 30 s) is one gap of 10 s at t = 20 s; dropping every third row makes the
    intervals alternate 0.05 and 0.1 s (irregular; the median of equally many 0.05 and 0.1 is 0.075).
    Both subsets still give each swing duration within 3 combined standard errors of the full
    table's (the fit's sigma_T, 4e-10 s here, from the model residual of the noiseless data). Measured:
    1.1e-10 s (0.27 sigma) with the gap, 1e-12 s irregular."""
    cols, expected = original
    t = cols[TIME_COLUMN]
    i = np.arange(t.size)
    for case, keep in {"gap": (t <= 20) | (t >= 30), "irregular": i % 3 != 2}.items():
        path = tmp_path / f"{case}.csv"
        write_table(str(path), t[keep], {c: cols[c][keep] for c in _channels(cols)})
        got = _estimate(path)
        notes = got["data_notes"]
        if case == "gap":
            assert notes == ["1 gap longer than 3x the median interval (0.05 s): 10 s at t = 20 s (from the first sample)"]
        else:
            assert notes == ["irregular sampling: intervals from 0.05 to 0.1 s (median 0.075 s; spread above 1% of "
                             "the median)"]
        for g in GYROS:
            a, b = got["instruments"][g], expected["instruments"][g]
            sigma = np.hypot(a["swing_duration_sigma_s"], b["swing_duration_sigma_s"])
            assert abs(a["swing_duration_s"] - b["swing_duration_s"]) < 3 * sigma, (case, g)


def _write_parquet_dup(path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    pq.write_table(pa.Table.from_arrays([pa.array([0.0, 0.05]), pa.array([0.1, 0.1]), pa.array([0.1, 0.2])],
                                        names=[TIME_COLUMN, "gyro_horizontal.angle", "gyro_horizontal.angle"]), path)


def _write_parquet_text(path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    pq.write_table(pa.table({TIME_COLUMN: [0.0, 0.05], "gyro_horizontal.angle": ["0.1", "0.2"]}), path)


def _write_parquet_timestamp(path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    pq.write_table(pa.table({TIME_COLUMN: pa.array([0, 50], pa.timestamp("ms")),
                             "gyro_horizontal.angle": [0.1, 0.2]}), path)


BAD = {
    "duplicate csv": ("d.csv", "time_s,gyro_horizontal.angle,gyro_horizontal.angle\n0,0.1,0.1\n0.05,0.1,0.2\n", [],
                      "column gyro_horizontal.angle appears twice (columns 2 and 3)"),
    "duplicate parquet": ("d.parquet", _write_parquet_dup, [],
                          "column gyro_horizontal.angle appears twice (columns 2 and 3)"),
    "constant time": ("c.csv", "time_s,gyro_horizontal.angle\n5,0.1\n5,0.2\n5,0.3\n", [],
                      "column time_s never increases: its 3 finite times are all 5.0"),
    "one row": ("o.csv", "time_s,gyro_horizontal.angle\n5,0.1\n", [], "column time_s never increases"),
    "text parquet": ("s.parquet", _write_parquet_text, [], "column gyro_horizontal.angle is string, not a number"),
    "ambiguous separator": ("a.csv", "time_s;gyro_horizontal.angle,x\n0;1\n", [],
                            "holds both ',' and ';': cannot tell the separator; pass --separator"),
    "decimal comma with commas": ("e.csv", "time_s,gyro_horizontal.angle\n0,0.1\n1,\"0,2\"\n", [],
                                  "line 3, column gyro_horizontal.angle: '0,2' is not a number"),
    "column without =": ("r.csv", "time_s,Theta\n0,1\n1,2\n", ["--column", "Theta"], "--column = 'Theta'"),
    "column source missing": ("r.csv", "time_s,Theta\n0,1\n1,2\n", ["--column", "gyro_horizontal.angle=Phi"],
                              "the table has no column 'Phi'"),
    "column name taken": ("r.csv", "time_s,Theta,gyro_horizontal.angle\n0,1,1\n1,2,2\n",
                          ["--column", "gyro_horizontal.angle=Theta"],
                          "the table already has a column gyro_horizontal.angle"),
    "time unit on a timestamp": ("t.parquet", _write_parquet_timestamp, ["--time-unit", "ms"],
                                 "--time-unit = 'ms' is invalid: does not apply: column time_s is stored as "
                                 "timestamp[ms]"),
    "time column missing": ("m.csv", "t,gyro_horizontal.angle\n0,1\n1,2\n", ["--time-column", "stamp"],
                            "has no time column 'stamp'"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_tables_exit_2_with_one_line(tmp_path, capsys, case):
    name, content, flags, expect = BAD[case]
    path = tmp_path / name
    if callable(content):
        content(path)
    else:
        path.write_text(content)
    assert main(["estimate", "--data", str(path), "--scene", SCENE, *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gyro-instrument: error: ") and expect in err[0], err


def test_table_flags_need_data(capsys):
    assert main(["estimate", SCENE, "--angle-unit", "deg"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--angle-unit = 'deg' is invalid: reads a table: give --data FILE" in err[0]


def test_constant_time_in_a_real_process_has_no_traceback(tmp_path):
    """Before: numpy.linalg.LinAlgError deep in the fit."""
    path = tmp_path / "c.csv"
    path.write_text("time_s,gyro_horizontal.angle,gyro_horizontal.spin_rate\n" + "7,0.1,628\n" * 50)
    r = subprocess.run([sys.executable, "-m", "gyro_instrument.cli", "estimate", "--data", str(path), "--scene",
                        SCENE], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "column time_s never increases" in lines[0]
