"""Issue 38: file names whose bytes are not UTF-8 (``$'caf\\xe9.csv'``, a Latin-1 name on a Linux
disk) work in every command. Python holds such a name as the surrogates of ``os.fsdecode``; files
are opened with the name itself (pyarrow, which takes only UTF-8 path strings, gets the open
file), text that must be UTF-8 (a sidecar's comment, a plot's title, a ROS parameter, MCAP
metadata) shows the bytes as ``\\xNN`` (core/files.py ``shown``) and stdout/stderr write the bytes
as given (``errors="surrogateescape"``). Before: UnicodeEncodeError tracebacks in the sidecar (no
``.scene.yaml``), ``plot``, ``run --bag`` and after ``estimate --data``'s answer under a UTF-8 locale."""

import io
import json
import os
import subprocess
import sys

import pytest

from gyro_instrument.cli import main as core_main
from gyro_instrument.ros.cli import main as ros_main
from machine_env import cli

NAME = b"caf\xe9"                      # Latin-1 'café': 0xE9 alone is not UTF-8
#: the same bytes as Python's os.fsdecode holds them (a lone surrogate per undecodable byte)
NAME_STR = os.fsdecode(NAME)


def run(argv, cwd, env=None, timeout=120):
    out = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, timeout=timeout)
    assert b"Traceback" not in out.stderr and b"UnicodeEncodeError" not in out.stderr, out.stderr.decode(errors="replace")
    return out


@pytest.fixture
def streams():
    """stdout and stderr of in-process commands as the process's own are under a UTF-8 locale with
    surrogateescape (cli/commands.py ``names_as_given``): bytes in, bytes read back. Swapped in when
    first read inside the test (pytest puts its own capture back between a fixture and the test)."""
    made = {name: io.TextIOWrapper(io.BytesIO(), encoding="utf-8", errors="surrogateescape", write_through=True)
            for name in ("stdout", "stderr")}
    saved = {}

    def swap():
        for name, stream in made.items():
            saved[name] = getattr(sys, name)
            setattr(sys, name, stream)
        return lambda name: made[name].buffer.getvalue()
    yield swap
    for name, stream in saved.items():
        setattr(sys, name, stream)


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


def test_parquet_table_under_such_a_name(tmp_path, streams):
    read = streams()
    # in-process (the files and their reading are the point here; the streams are the tests above)
    out = str(tmp_path / (NAME_STR + ".parquet"))
    assert core_main(["simulate", "quet_paris", "--duration-s", "20", "--out", out, "--quiet"]) == 0
    assert core_main(["estimate", "--data", out, "--json"]) == 0
    # the scene came from the Parquet file's own metadata (read through the open file)
    assert b"from " + os.fsencode(out) + b"'s Parquet metadata" in read("stderr")
    assert os.fsencode(json.loads(read("stdout"))["data"]) == NAME + b".parquet"     # the file's name, as --json gives it


def test_plot_draws_a_table_into_a_directory_of_such_a_name(table, streams):
    read = streams()
    d, _ = table
    views = d / (NAME_STR + "_views")
    assert core_main(["plot", str(d / (NAME_STR + ".csv")), "--out", str(views)]) == 0
    assert sorted(os.listdir(os.fsencode(views))) == [b"angles.png", b"bob_path.png", b"swing_azimuth.png"]
    assert read("stdout").startswith(b"wrote 3 views") and NAME + b"_views/angles.png" in read("stdout")


def test_one_line_error_shows_the_bytes(tmp_path, streams):
    read = streams()
    missing = str(tmp_path / (NAME_STR + ".csv"))
    assert core_main(["estimate", "--data", missing, "--scene", "quet_paris"]) == 2
    lines = read("stderr").decode("ascii").splitlines()    # ASCII: the byte shown as \xe9
    assert len(lines) == 1 and lines[0].startswith(f"gyro-instrument: error: --data = '{tmp_path}/caf\\xe9.csv'"), lines


def test_run_bag_replay_and_recover(tmp_path, streams):
    read = streams()
    bag = str(tmp_path / (NAME_STR + ".mcap"))
    assert ros_main(["run", "quet_paris", "--duration-s", "3", "--bag", bag, "--quiet", "--json"]) == 0
    assert core_main(["replay", bag, "--json"]) == 0
    live, replayed = _two_json(read("stdout"))
    # the bag holds the run: replay reads the same 3 s per instrument and gives the live estimate
    assert replayed["observation_s"] == live["observation_s"] and replayed["methods"] == live["methods"]
    copy = str(tmp_path / (NAME_STR + "_copy.mcap"))
    n = len(read("stdout"))
    assert core_main(["recover", bag, "--out", copy]) == 0
    said = read("stdout")[n:]
    assert said.startswith(b"recovered ") and b" from " + os.fsencode(bag) + b" into " + os.fsencode(copy) in said
    from gyro_instrument.recording.mcap_io import read_messages
    assert len(list(read_messages(copy))) == int(said.split()[1])


def _two_json(data):
    """The two JSON documents printed one after the other (``json.dumps(indent=2)`` + newline each)."""
    text = data.decode("utf-8", "surrogateescape")
    first, end = json.JSONDecoder().raw_decode(text)
    second, _ = json.JSONDecoder().raw_decode(text[end:].lstrip())
    return first, second


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
