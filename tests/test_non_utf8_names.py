"""Issue 38: file names whose bytes are not UTF-8 (``$'caf\\xe9.csv'``, a Latin-1 name on a Linux
disk) work in every command. Python holds such a name as the surrogates of ``os.fsdecode``; files
are opened with the name itself (pyarrow, which takes only UTF-8 path strings, gets the open
file), text that must be UTF-8 (a sidecar's comment, a plot's title, a ROS parameter, MCAP
metadata) shows the bytes as ``\\xNN`` (core/files.py ``shown``) and stdout/stderr write the bytes
as given (``errors="surrogateescape"``). Before: UnicodeEncodeError tracebacks in the sidecar (no
``.scene.yaml``), ``plot``, ``run --bag`` and after ``estimate --data``'s answer under a UTF-8 locale."""

import json
import os
import subprocess

import pytest

from machine_env import cli, ros_cli

NAME = b"caf\xe9"                      # Latin-1 'café': 0xE9 alone is not UTF-8
#: the same bytes as Python's os.fsdecode holds them (a lone surrogate per undecodable byte)
NAME_STR = os.fsdecode(NAME)


def run(argv, cwd, env=None, timeout=120):
    out = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, timeout=timeout)
    assert b"Traceback" not in out.stderr and b"UnicodeEncodeError" not in out.stderr, out.stderr.decode(errors="replace")
    return out


def locale_env(lang):
    env = {k: v for k, v in os.environ.items() if not k.startswith("LC_") and k not in ("LANG", "PYTHONIOENCODING",
                                                                                        "PYTHONUTF8")}
    return env | {"LANG": lang}


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    """quet_paris 30 s simulated to caf\\xe9.csv (and its scene beside it)."""
    d = tmp_path_factory.mktemp("names")
    out = run(cli("simulate", "quet_paris", "--duration-s", "30", "--out", NAME_STR + ".csv"), d)
    assert out.returncode == 0, out.stderr
    return d, out


def test_simulate_writes_table_and_scene_under_the_name_given(table):
    d, out = table
    assert sorted(os.listdir(os.fsencode(d))) == [NAME + b".csv", NAME + b".scene.yaml"]
    # stderr names the file with its own bytes (surrogateescape), not an escape of them
    assert b"wrote " + NAME + b".csv: 601 rows" in out.stderr     # 30 s at 20 Hz and t = 0: 601 rows
    side = (d / (NAME_STR + ".scene.yaml")).read_bytes().decode("utf-8")   # strict: valid UTF-8 text
    assert side.startswith("# the scene gyro-instrument simulate ran for caf\\xe9.csv (seed")


@pytest.mark.parametrize("lang", ["en_US.UTF-8", "C"])
def test_estimate_reads_the_table_and_its_scene_in_any_locale(table, lang):
    # the text answer names the file (it printed the answer, then died on this line under a UTF-8 locale);
    # GYRO_INSTRUMENT_JIT=0 spares loading numba: file names do not depend on the kernels
    d, _ = table
    env = locale_env(lang) | {"GYRO_INSTRUMENT_JIT": "0"}
    out = run(cli("estimate", "--data", NAME_STR + ".csv"), d, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(b"north: ") and b"\ndata " + NAME + b".csv read with scene quet_paris" in out.stdout
    assert b"using the scene 'quet_paris' from " + NAME + b".scene.yaml" in out.stderr
    if lang == "C":
        return
    result = json.loads(run(cli("estimate", "--data", NAME_STR + ".csv", "--json"), d, env=env).stdout)
    # the path round-trips: JSON carries the surrogate, os.fsencode gives the bytes back
    assert os.fsencode(result["data"]) == NAME + b".csv"
    assert result["scene"] == "quet_paris" and result["truth"]["latitude_deg"] == 48.8462   # scenes/quet_paris.yaml


def test_parquet_table_under_such_a_name(tmp_path):
    out = run(cli("simulate", "quet_paris", "--duration-s", "20", "--out", NAME_STR + ".parquet", "--quiet"), tmp_path)
    assert out.returncode == 0, out.stderr
    est = run(cli("estimate", "--data", NAME_STR + ".parquet", "--json"), tmp_path)
    assert est.returncode == 0, est.stderr
    # the scene came from the Parquet file's own metadata (read through the open file)
    assert b"from " + NAME + b".parquet's Parquet metadata" in est.stderr
    assert json.loads(est.stdout)["observation_s"] > 0


def test_plot_draws_a_table_into_a_directory_of_such_a_name(table):
    d, _ = table
    out = run(cli("plot", NAME_STR + ".csv", "--out", NAME_STR + "_views"), d)
    assert out.returncode == 0, out.stderr
    assert sorted(os.listdir(os.fsencode(d / (NAME_STR + "_views")))) == [b"angles.png", b"bob_path.png",
                                                                           b"swing_azimuth.png"]
    assert out.stdout.startswith(b"wrote 3 views") and NAME + b"_views/angles.png" in out.stdout


def test_one_line_error_shows_the_bytes(tmp_path):
    out = run(cli("estimate", "--data", NAME_STR + ".csv", "--scene", "quet_paris"), tmp_path)
    assert out.returncode == 2
    lines = out.stderr.decode("ascii").splitlines()      # the error line is ASCII: the byte shown as \xe9
    assert len(lines) == 1 and lines[0].startswith("gyro-instrument: error: --data = 'caf\\xe9.csv'"), lines


def test_run_bag_replay_and_recover(tmp_path):
    bag = NAME_STR + ".mcap"
    out = run(ros_cli("run", "quet_paris", "--duration-s", "3", "--bag", bag, "--quiet", "--json"), tmp_path)
    assert out.returncode == 0, out.stderr
    live = json.loads(out.stdout)
    rep = run(cli("replay", bag, "--json"), tmp_path)
    assert rep.returncode == 0, rep.stderr
    replayed = json.loads(rep.stdout)
    # the bag holds the run: replay reads the same 3 s per instrument and gives the live estimate
    assert replayed["observation_s"] == live["observation_s"] and replayed["methods"] == live["methods"]
    rec = run(cli("recover", bag, "--out", NAME_STR + "_copy.mcap"), tmp_path)
    assert rec.returncode == 0, rec.stderr
    assert rec.stdout.startswith(b"recovered ") and b" from " + NAME + b".mcap into " + NAME + b"_copy.mcap" in rec.stdout
    from gyro_instrument.recording.mcap_io import read_messages
    assert len(list(read_messages(str(tmp_path / (NAME_STR + "_copy.mcap"))))) == int(rec.stdout.split()[1])


def test_a_sidecar_that_cannot_be_written_leaves_no_table(tmp_path, monkeypatch):
    # the report's half state: the table written, then the sidecar failed (no .scene.yaml, so the table
    # could no longer be estimated alone). The sidecar is now written before the table is renamed in.
    from gyro_instrument.cli import simulate
    from gyro_instrument.scenes import load_scene

    def fail(*args, **kwargs):
        raise UnicodeEncodeError("utf-8", "\udce9", 0, 1, "surrogates not allowed")
    monkeypatch.setattr(simulate, "write_scene_sidecar", fail)
    with pytest.raises(UnicodeEncodeError):
        simulate.simulate_to_file(load_scene("quet_paris", ["duration_s=5.0"]), str(tmp_path / "q.csv"))
    assert list(tmp_path.iterdir()) == []          # neither the table nor its .partial
