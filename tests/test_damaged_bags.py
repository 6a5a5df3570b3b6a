"""Commands that could destroy or hide data (issue 11): a damaged bag is read with every CRC
checked, a damaged chunk is left out and its log-time span reported; 'recover' never launders
damage and never writes over its input; no command writes over an existing output without
--overwrite, and what is not an MCAP is refused.

The bag is written without DDS (joint_streams -> CDR -> BagWriter, as the recorder lays it out);
expectations come from the undamaged file read by the ``mcap`` library itself."""

import json
import os
import shutil
import struct
import subprocess
import sys

import pytest

from gyro_instrument.cli import main as core_main
from gyro_instrument.core.scene import EPOCH_NS

DURATION_S = 120.0
FOOTER_AT = 8 + 29          # the footer record (29 bytes) sits before the closing magic


def write_bag(path, scene="quet_paris", duration_s=DURATION_S, chunk_size=32 * 1024):
    """A bag as the recorder writes it (scene metadata, /clock, one JointState topic per
    instrument), from the simulator's own arrays, without DDS."""
    from gyro_instrument.recording.joints import joint_streams
    from gyro_instrument.recording.mcap_io import BagWriter
    from gyro_instrument.ros import messages as m
    from gyro_instrument.recording.topics import CLOCK, joint_topic
    from gyro_instrument.scenes import load_scene
    sc = load_scene(scene, [f"duration_s={duration_s!r}"])
    t_ns, streams = joint_streams(sc)
    w = BagWriter(str(path), chunk_size=chunk_size, commit_period_s=1e9)
    w.add_metadata("gyro_instrument", {"scene_yaml": json.dumps(dict(sc.raw)), "scene": sc.name,
                                       "seed": sc.seed, "command": "test_damaged_bags"})
    w.add_topic(CLOCK, "rosgraph_msgs/msg/Clock")
    enc = {CLOCK: m.CLOCK_LAYOUT.encode(t_ns)}
    for name, s in streams.items():
        w.add_topic(joint_topic(name), "sensor_msgs/msg/JointState")
        enc[joint_topic(name)] = m.joint_state_layout(s.names).encode(t_ns, s.position, s.velocity, s.effort)
    for i, t in enumerate(t_ns):
        for topic, datas in enc.items():
            w.write(topic, EPOCH_NS + int(t), datas[i])
    w.close()


def chunk_indexes(path):
    from mcap.reader import make_reader
    with open(path, "rb") as fh:
        return sorted(make_reader(fh, validate_crcs=True).get_summary().chunk_indexes,
                      key=lambda ci: ci.chunk_start_offset)


def summary_start(path):
    data = open(path, "rb").read()
    return struct.unpack_from("<Q", data, len(data) - FOOTER_AT + 9)[0]


def chunk_message_keys(path, ci):
    """(channel id, sequence) of every message inside one chunk, read by mcap."""
    from mcap.data_stream import ReadDataStream
    from mcap.records import Chunk, Message
    from mcap.stream_reader import breakup_chunk
    with open(path, "rb") as fh:
        fh.seek(ci.chunk_start_offset + 9)
        chunk = Chunk.read(ReadDataStream(fh))
    return {(r.channel_id, r.sequence) for r in breakup_chunk(chunk, validate_crc=True) if isinstance(r, Message)}


def estimate_without(path, drop=frozenset()):
    """The estimate from the undamaged file read by the mcap library (CRCs checked, decoded by
    mcap_ros2), leaving out the messages ``drop`` = {(channel id, sequence)}: the expectation for
    a replay that uses exactly the intact data."""
    import numpy as np
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from gyro_instrument.cli import to_jsonable
    from gyro_instrument.estimators.pipeline import estimable, estimate_records
    from gyro_instrument.recording.joints import records_from_joints
    from gyro_instrument.scenes import build_instruments, scene_from_data
    data = {}
    with open(path, "rb") as fh:
        reader = make_reader(fh, validate_crcs=True, decoder_factories=[DecoderFactory()])
        meta = next(r for r in reader.iter_metadata() if r.name == "gyro_instrument").metadata
        for schema, channel, message, msg in reader.iter_decoded_messages(topics=None):
            if not channel.topic.endswith("/joint_states") or (channel.id, message.sequence) in drop:
                continue
            ts, ps, vs = data.setdefault(channel.topic.strip("/").split("/")[0], ([], [], []))
            ts.append(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec - EPOCH_NS)
            ps.append(list(msg.position))
            vs.append(list(msg.velocity))
    scene = scene_from_data(json.loads(meta["scene_yaml"]), source=str(path))
    insts = build_instruments(scene)
    samples = {n: (np.array(t, dtype=np.int64), np.array(p), np.array(v)) for n, (t, p, v) in data.items()
               if n in insts and estimable(insts[n])}
    return to_jsonable(estimate_records(scene, {n: insts[n] for n in samples}, records_from_joints(insts, samples)))


ESTIMATE_KEYS = ("latitude_deg", "latitude_sigma_deg", "earth_rate_rad_s", "earth_rate_sigma_rad_s", "methods",
                 "instruments", "method")


def same_estimate(a, b):
    return all(json.dumps(a.get(k), sort_keys=True) == json.dumps(b.get(k), sort_keys=True) for k in ESTIMATE_KEYS)


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """The undamaged bag, its chunk index, and the estimates the damage cases expect."""
    d = tmp_path_factory.mktemp("damaged")
    path = d / "good.mcap"
    write_bag(path)
    idx = chunk_indexes(path)
    assert len(idx) > 10
    k = len(idx) // 2                        # a chunk in the middle: its schemas were in chunk 0
    full = estimate_without(path)
    without_k = estimate_without(path, chunk_message_keys(path, idx[k]))
    assert full["latitude_deg"] is not None and without_k["latitude_deg"] is not None
    assert without_k["latitude_deg"] != full["latitude_deg"]      # the chunk matters to the estimate
    return {"path": path, "dir": d, "idx": idx, "k": k, "full": full, "without_k": without_k}


def damaged_copy(bag, name, offsets):
    data = bytearray(bag["path"].read_bytes())
    for off in offsets:
        data[off] ^= 0x10
    out = bag["dir"] / f"{name}.mcap"
    out.write_bytes(bytes(data))
    return out


def offsets_for(bag, case):
    ci = bag["idx"][bag["k"]]
    crc_at = ci.chunk_start_offset + 9 + 8 + 8 + 8                  # start, end, uncompressed_size
    data_at = crc_at + 4 + 4 + len(ci.compression) + 8              # crc, compression string, data length
    return {"header magic": [3],
            "chunk data": [data_at + ci.compressed_size // 2],
            "chunk crc": [crc_at + 1],
            "chunk length": [ci.chunk_start_offset + 1 + 2],
            "summary": [summary_start(bag["path"]) + 40],
            "summary and chunk data": [summary_start(bag["path"]) + 40, data_at + ci.compressed_size // 2],
            }[case]


def replay_json(path, capsys):
    code = core_main(["replay", str(path), "--json"])
    out, err = capsys.readouterr()
    return code, (json.loads(out) if code == 0 else None), err


def test_header_magic_damage_is_refused_in_one_line_without_traceback(bag):
    path = damaged_copy(bag, "magic", offsets_for(bag, "header magic"))
    for args in (["replay", str(path)], ["recover", str(path), "--out", str(bag["dir"] / "magic_fixed.mcap")]):
        r = subprocess.run([sys.executable, "-m", "gyro_instrument.cli", *args], capture_output=True, text=True)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and "Traceback" not in r.stderr and len(lines) == 1, r.stderr
        assert lines[0].startswith("gyro-instrument: error: bag = ") and str(path) in lines[0]
        assert "not an MCAP file" in lines[0] and "magic" in lines[0]
    assert not (bag["dir"] / "magic_fixed.mcap").exists()


@pytest.mark.parametrize("case", ["chunk data", "chunk crc", "chunk length"])
def test_damaged_chunk_is_skipped_and_its_span_reported(bag, case, capsys):
    path = damaged_copy(bag, case.replace(" ", "_"), offsets_for(bag, case))
    ci = bag["idx"][bag["k"]]
    code, result, err = replay_json(path, capsys)
    assert code == 0 and "Traceback" not in err
    # the estimate uses only intact data: the undamaged file without that chunk's messages
    assert same_estimate(result, bag["without_k"])
    assert not same_estimate(result, bag["full"])
    [d] = result["damaged"]
    assert d["offset"] == ci.chunk_start_offset and d["span_from"] == "chunk index"
    assert d["lost_from_s"] == (ci.message_start_time - EPOCH_NS) / 1e9
    assert d["lost_to_s"] == (ci.message_end_time - EPOCH_NS) / 1e9
    assert "chunk" in d["reason"] or "framing" in d["reason"]
    json.dumps(result, allow_nan=False)
    # the text output says it too, one line per lost span
    assert core_main(["replay", str(path)]) == 0
    text = capsys.readouterr().out
    lines = [ln for ln in text.splitlines() if ln.strip().startswith("damaged:")]
    assert len(lines) == 1 and f"at byte {ci.chunk_start_offset}" in lines[0]
    assert f"lost {d['lost_from_s']:g}" in lines[0] and f"to {d['lost_to_s']:g}" in lines[0]


def test_damaged_summary_is_ignored_and_nothing_is_lost(bag, capsys):
    path = damaged_copy(bag, "summary", offsets_for(bag, "summary"))
    import zlib
    data = path.read_bytes()                       # the footer's summary CRC (spec) no longer matches
    footer = len(data) - FOOTER_AT
    assert zlib.crc32(data[summary_start(path):footer + 25]) != struct.unpack_from("<I", data, footer + 25)[0]
    code, result, err = replay_json(path, capsys)
    assert code == 0 and "damaged" not in result
    assert same_estimate(result, bag["full"])
    assert any("summary" in n and "CRC" in n for n in result["replay_notes"])


def test_damaged_chunk_without_a_summary_span_from_the_neighbouring_messages(bag, capsys):
    # the summary is damaged too: the chunk is found by scanning, the span is between the last
    # intact message before it (end of the previous chunk) and the first after (start of the next)
    path = damaged_copy(bag, "summary_chunk", offsets_for(bag, "summary and chunk data"))
    idx, k = bag["idx"], bag["k"]
    code, result, err = replay_json(path, capsys)
    assert code == 0 and same_estimate(result, bag["without_k"])
    [d] = result["damaged"]
    assert d["offset"] == idx[k].chunk_start_offset and d["span_from"] == "neighbouring messages"
    assert d["lost_from_s"] == (idx[k - 1].message_end_time - EPOCH_NS) / 1e9
    assert d["lost_to_s"] == (idx[k + 1].message_start_time - EPOCH_NS) / 1e9


def test_recover_copies_only_intact_chunks_and_the_loss_survives_in_the_new_file(bag, capsys):
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    path = damaged_copy(bag, "to_recover", offsets_for(bag, "chunk data"))
    fixed = bag["dir"] / "recovered.mcap"
    assert core_main(["recover", str(path), "--out", str(fixed)]) == 0
    out = capsys.readouterr().out
    ci = bag["idx"][bag["k"]]
    assert f"chunk at byte {ci.chunk_start_offset} failed its CRC" in out or "chunk undecodable" in out
    # independent readers, CRCs checked, read every message of the recovered file
    with open(fixed, "rb") as fh:
        reader = make_reader(fh, validate_crcs=True)
        n = reader.get_summary().statistics.message_count
        assert sum(1 for _ in reader.iter_messages()) == n
        damage = [r for r in reader.iter_metadata() if r.name == "gyro_instrument_damage"]
    with AnyReader([fixed]) as r:
        assert sum(1 for _ in r.messages()) == n
    with open(bag["path"], "rb") as fh:
        total = make_reader(fh).get_summary().statistics.message_count
    assert n == total - len(chunk_message_keys(bag["path"], ci))      # exactly the damaged chunk is missing
    assert len(damage) == 1 and damage[0].metadata["status"] == "complete"
    # a later replay of the recovered file still says what was lost, with the same span
    code, result, err = replay_json(fixed, capsys)
    assert code == 0 and same_estimate(result, bag["without_k"])
    [d] = result["damaged"]
    assert d["before_recovery"] and d["lost_from_s"] == (ci.message_start_time - EPOCH_NS) / 1e9
    assert d["lost_to_s"] == (ci.message_end_time - EPOCH_NS) / 1e9
    # and recovering the recovered file keeps the record (damage is never laundered)
    again = bag["dir"] / "recovered_again.mcap"
    assert core_main(["recover", str(fixed), "--out", str(again)]) == 0
    capsys.readouterr()
    assert replay_json(again, capsys)[1]["damaged"] == result["damaged"]


def test_recover_never_writes_over_its_input(bag, capsys, tmp_path):
    x = tmp_path / "x.mcap"
    shutil.copy(bag["path"], x)
    before = x.read_bytes()
    link = tmp_path / "link.mcap"
    os.symlink(x, link)
    for out in (str(x), str(tmp_path / "." / "x.mcap"), str(link)):
        for extra in ([], ["--overwrite"]):
            assert core_main(["recover", str(x), "--out", out, *extra]) == 2
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and err[0].startswith("gyro-instrument: error: --out = ") and "input" in err[0]
    assert x.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.mcap", "x.mcap"]   # no partial file left


def test_recover_refuses_an_existing_output_unless_overwrite(bag, capsys, tmp_path):
    out = tmp_path / "out.mcap"
    out.write_bytes(b"keep me")
    assert core_main(["recover", str(bag["path"]), "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err and out.read_bytes() == b"keep me"
    assert core_main(["recover", str(bag["path"]), "--out", str(out), "--overwrite"]) == 0
    assert out.read_bytes()[:8] == b"\x89MCAP0\r\n"


@pytest.mark.parametrize("content", [b"time_s,a\n0,1\n", b"", None], ids=["csv", "empty", "directory"])
def test_recover_refuses_what_is_not_an_mcap_and_writes_nothing(content, capsys, tmp_path):
    src = tmp_path / "notes.csv"
    if content is None:
        src.mkdir()
    else:
        src.write_bytes(content)
    y = tmp_path / "y.mcap"
    assert core_main(["recover", str(src), "--out", str(y)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"bag = '{src}'" in err[0] and "MCAP" in err[0]
    assert not y.exists()
    assert core_main(["replay", str(src)]) == 2


def test_recover_that_finds_no_message_exits_2_and_writes_nothing(capsys, tmp_path):
    from gyro_instrument.recording.mcap_io import BagWriter
    src = tmp_path / "empty_run.mcap"
    w = BagWriter(str(src))
    w.add_metadata("gyro_instrument", {"scene": "none"})
    w.close()                                              # a valid MCAP holding no message
    y = tmp_path / "y.mcap"
    assert core_main(["recover", str(src), "--out", str(y)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no intact message" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty_run.mcap"]


def test_simulate_refuses_an_existing_output_and_its_scene_file(tmp_path, capsys):
    out = tmp_path / "q.csv"
    out.write_text("precious\n")
    args = ["simulate", "quet_paris", "--duration-s", "2", "--quiet", "--out", str(out)]
    assert core_main(args) == 2
    assert "--overwrite" in capsys.readouterr().err and out.read_text() == "precious\n"
    assert core_main(args + ["--overwrite"]) == 0 and out.read_text().startswith("time_s,")
    scene = tmp_path / "s.yaml"
    from gyro_instrument.scenes import load_scene
    import yaml
    scene.write_text(yaml.safe_dump(dict(load_scene("quet_paris", []).raw)))
    text = scene.read_text()
    assert core_main(["simulate", str(scene), "--overwrite", "--quiet", "--out", str(scene)]) == 2
    assert "input" in capsys.readouterr().err and scene.read_text() == text


def test_run_bag_refuses_an_existing_file_before_anything_runs(tmp_path, capsys, monkeypatch):
    from gyro_instrument.ros import cli as ros_cli
    from gyro_instrument.ros import suite
    bag = tmp_path / "existing.mcap"
    bag.write_bytes(b"an earlier recording")
    calls = []
    real = suite.run_suite
    monkeypatch.setattr(suite, "run_suite", lambda *a, **k: calls.append(1) or real(*a, **k))
    args = ["run", "quet_paris", "--duration-s", "2", "--quiet", "--json", "--bag", str(bag)]
    assert ros_cli.main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gyro-instrument: error: --bag = ") and "--overwrite" in err[0]
    assert calls == [] and bag.read_bytes() == b"an earlier recording"
    assert ros_cli.main(args + ["--overwrite"]) == 0
    capsys.readouterr()
    assert calls == [1] and bag.read_bytes()[:8] == b"\x89MCAP0\r\n"
    from gyro_instrument.recording.mcap_io import recording_state
    assert recording_state(str(bag)) == "complete"
    # run_suite itself (the API the tests and the bench use) refuses too
    from gyro_instrument.core.errors import SceneError
    with pytest.raises(SceneError, match="exists"):
        real("quet_paris", (), 2.0, str(bag))


def test_recorder_node_refuses_an_existing_output_unless_overwrite(tmp_path, capfd):
    import rclpy
    from rclpy.parameter import Parameter
    from gyro_instrument.ros.nodes import RecorderNode
    out = tmp_path / "rec.mcap"
    out.write_bytes(b"an earlier recording")
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=[])
    try:
        params = [Parameter("scene", value="quet_paris"), Parameter("duration_s", value=2.0),
                  Parameter("output", value=str(out))]
        node = RecorderNode(context=ctx, parameter_overrides=params)
        assert node.writer is None and not node.subs
        node.close()
        node.destroy_node()
        assert out.read_bytes() == b"an earlier recording"
        log = capfd.readouterr().err
        assert "overwrite" in log and str(out) in log
        node = RecorderNode(context=ctx, parameter_overrides=params + [Parameter("overwrite", value=True)])
        assert node.writer is not None
        node.close()
        node.destroy_node()
        assert out.read_bytes()[:8] == b"\x89MCAP0\r\n"
    finally:
        rclpy.shutdown(context=ctx)


def test_player_publishes_only_intact_messages_and_logs_the_loss(bag):
    import rclpy
    from rclpy.parameter import Parameter
    from gyro_instrument.ros.nodes import PlayerNode
    path = damaged_copy(bag, "player", offsets_for(bag, "chunk crc"))
    ci = bag["idx"][bag["k"]]
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=[])
    try:
        node = PlayerNode(context=ctx, parameter_overrides=[Parameter("bag", value=str(path))])
        good = PlayerNode(context=ctx, parameter_overrides=[Parameter("bag", value=str(bag["path"]))])
        assert good.total - node.total == len(chunk_message_keys(bag["path"], ci))
        assert [d["offset"] for d in node.damaged] == [ci.chunk_start_offset] and not good.damaged
        node.destroy_node()
        good.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
