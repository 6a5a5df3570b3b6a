"""MCAP in rosbag2's layout, checked with independent readers (rosbags, mcap + mcap_ros2)."""

import os

import pytest

from gyro_instrument.recording.definitions import SEPARATOR, concatenated_definition, msg_text, type_hash
from gyro_instrument.recording.mcap_io import BagWriter, qos_yaml, read_messages


def test_schema_text_is_rosbag2_concatenation():
    # rosbag2 jazzy get_full_text: root text, then depth-first over sorted dependencies, each once:
    # "\n" + 80 "=" + "\nMSG: " + name-as-written + "\n" + text. Written out by hand for
    # Vector3Stamped (fields std_msgs/Header, Vector3 -> 'geometry_msgs/Vector3' sorts first).
    expected = (msg_text("geometry_msgs/msg/Vector3Stamped")
                + "\n" + "=" * 80 + "\nMSG: geometry_msgs/Vector3\n" + msg_text("geometry_msgs/msg/Vector3")
                + "\n" + "=" * 80 + "\nMSG: std_msgs/Header\n" + msg_text("std_msgs/msg/Header")
                + "\n" + "=" * 80 + "\nMSG: builtin_interfaces/Time\n" + msg_text("builtin_interfaces/msg/Time"))
    assert concatenated_definition("geometry_msgs/msg/Vector3Stamped") == expected
    assert len(SEPARATOR) == 80
    js = concatenated_definition("sensor_msgs/msg/JointState")
    assert js.count("MSG: ") == 2 and "MSG: std_msgs/Header" in js and "MSG: builtin_interfaces/Time" in js
    assert type_hash("sensor_msgs/msg/JointState").startswith("RIHS01_")


def _write_demo(path, n=50):
    from rclpy.serialization import serialize_message
    from gyro_instrument.ros import messages as m
    w = BagWriter(str(path), chunk_size=4096)
    w.add_topic("/j/joint_states", "sensor_msgs/msg/JointState")
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    for i in range(n):
        t = i * 50_000_000
        w.write("/clock", m.EPOCH_NS + t, serialize_message(m.clock(t)))
        w.write("/j/joint_states", m.EPOCH_NS + t,
                serialize_message(m.joint_state(t, ["j/axis", "j/rotor"], [0.001 * i, 0.0], [1.0, 2.0], [0.0, 0.0])))
    return w


def test_independent_readers_read_every_message(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader
    path = tmp_path / "demo.mcap"
    w = _write_demo(path)
    w.add_metadata("gyro_instrument", {"scene": "demo"})
    w.close()
    with AnyReader([path]) as r:
        msgs = [(c.topic, r.deserialize(raw, c.msgtype)) for c, t, raw in r.messages()]
    assert len(msgs) == 100
    js = [x for tp, x in msgs if tp == "/j/joint_states"]
    assert js[7].position[0] == pytest.approx(0.007) and list(js[7].effort) == [0.0, 0.0]
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros2"
        for ch in summary.channels.values():
            assert ch.message_encoding == "cdr"
            assert ch.metadata["offered_qos_profiles"].startswith("- history:")
            assert ch.metadata["topic_type_hash"].startswith("RIHS01_")
        for sc in summary.schemas.values():
            assert sc.encoding == "ros2msg"
        decoded = list(reader.iter_decoded_messages())
    assert len(decoded) == 100


def test_qos_profile_is_a_yaml_list():
    import yaml
    prof = yaml.safe_load(qos_yaml())
    assert isinstance(prof, list) and prof[0]["reliability"] == 1 and prof[0]["history"] == 2


def test_truncated_file_is_read_up_to_the_last_complete_chunk(tmp_path):
    # A killed recorder leaves no summary: the reader falls back to streaming and returns a prefix.
    path = tmp_path / "cut.mcap"
    w = _write_demo(path, n=400)
    w._fh.flush()
    size = os.path.getsize(path)
    os.truncate(path, size - 1000)
    got = list(read_messages(str(path)))
    assert 0 < len(got) < 800
    times = [t for _, _, t, _ in got]
    assert times == sorted(times)


def test_file_on_disk_is_a_complete_mcap_after_every_commit(tmp_path):
    """BagWriter writes each chunk together with a provisional summary, footer and end magic (one
    pwrite), and the next commit writes over that end: a snapshot taken at any moment, as a SIGKILL
    would leave it, is a valid indexed MCAP that rosbags and mcap (CRCs checked) read in full."""
    import shutil
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    from rclpy.serialization import serialize_message
    from gyro_instrument.recording.mcap_io import recording_state
    from gyro_instrument.ros import messages as m
    path = tmp_path / "live.mcap"
    w = BagWriter(str(path), chunk_size=2048, commit_period_s=1e9)   # commits by size only
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    seen, snaps = [], []
    for i in range(600):
        w.write("/clock", m.EPOCH_NS + i * 50_000_000, serialize_message(m.clock(i * 50_000_000)))
        if i % 97 == 0:
            snap = tmp_path / f"snap{i}.mcap"
            shutil.copy(path, snap)
            snaps.append(snap)
    assert w.commits > 10
    for snap in snaps:
        with open(snap, "rb") as fh:
            reader = make_reader(fh, validate_crcs=True)
            n = reader.get_summary().statistics.message_count
            assert sum(1 for _ in reader.iter_messages()) == n
        with AnyReader([snap]) as r:
            assert sum(1 for _ in r.messages()) == n
        assert recording_state(str(snap)) == "recording"
        seen.append(n)
    assert seen == sorted(seen) and seen[-1] > 0
    # what was not committed is at most one chunk: 2048 bytes of ~60-byte records
    assert 582 - seen[-1] < 2048 // 40
    w.close()
    assert recording_state(str(path)) == "complete"
    with AnyReader([path]) as r:
        assert sum(1 for _ in r.messages()) == 600


def test_bulk_message_records_equal_mcap_own_add_message(tmp_path):
    """BagWriter adds a chunk's messages in one write (mcap_io._add_messages, issue 37 item 6): the
    file is byte for byte the one mcap's own Writer.add_message, called per message, writes (the same
    records, message indexes, chunk index and statistics); messages out of log-time order, several
    chunks, two channels, empty and odd-sized payloads, so offsets and time ranges are exercised."""
    from gyro_instrument.recording import mcap_io

    def own(w, rows):
        for t, _, cid, pt, data, seq in rows:
            w.add_message(channel_id=cid, log_time=t, publish_time=pt, data=data, sequence=seq)

    files = []
    for name, add in (("bulk.mcap", mcap_io._add_messages), ("own.mcap", own)):
        old = mcap_io._add_messages
        mcap_io._add_messages = add
        try:
            path = tmp_path / name
            w = BagWriter(str(path), chunk_size=300, commit_period_s=1e9)
            w.add_topic("/a", "std_msgs/msg/Float64")
            w.add_topic("/b", "std_msgs/msg/Float64")
            for i in range(40):
                w.write("/a" if i % 3 else "/b", 10_000 - 37 * i if i % 7 == 0 else 1000 + i, bytes(i % 5) * 7)
            w.close(state="complete")
        finally:
            mcap_io._add_messages = old
        files.append(path.read_bytes())
    assert files[0] == files[1]
    assert len(list(read_messages(str(tmp_path / "bulk.mcap")))) == 40
