"""rosbag2's bag directory both ways (issue 15 part 1): written by ``run --bag DIR/`` and the
recorder (split by size or duration), read back by rosbags' ``Rosbag2`` reader (an independent
implementation) message by message, and by ``replay``, ``recover`` and the player from a
directory, a split bag or a bare ``.mcap``; bad directories exit 2 with one line."""

import json
import os
import shutil
from pathlib import Path

import pytest
import yaml

from gyro_instrument.cli import main as core_main, replay_bag, to_jsonable
from gyro_instrument.recording.bag_layout import BagDirectoryWriter, bag_files, scan_path
from gyro_instrument.recording.mcap_io import read_messages


def _rosbags_messages(path):
    """(topic, log time, raw CDR) of every message, read by rosbags' rosbag2 reader."""
    from rosbags.rosbag2 import Reader
    with Reader(Path(path)) as r:
        return [(c.topic, t, bytes(raw)) for c, t, raw in r.messages()], r.message_count


def _ours(path):
    return [(topic, t, bytes(data)) for topic, _, t, data in read_messages(path, scan=scan_path(path))]


def _write_dir(path, n=1200, **kw):
    """A bag directory of /clock and one JointState topic at 20 Hz (n samples), as the recorder
    writes it (scene record first); returns the writer, closed."""
    from rclpy.serialization import serialize_message
    from gyro_instrument.ros import messages as m
    w = BagDirectoryWriter(str(path), chunk_size=4096, **kw)
    w.add_metadata("gyro_instrument", {"scene": "demo"})
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    w.add_topic("/j/joint_states", "sensor_msgs/msg/JointState")
    for i in range(n):
        t = i * 50_000_000
        w.write("/clock", m.EPOCH_NS + t, serialize_message(m.clock(t)))
        w.write("/j/joint_states", m.EPOCH_NS + t,
                serialize_message(m.joint_state(t, ["j/axis", "j/rotor"], [0.001 * i, 0.0], [1.0, 2.0], [0.0, 0.0])))
    return w


@pytest.mark.parametrize("split", [{}, {"max_bag_duration_s": 20.0}, {"max_bag_size": 20_000}],
                         ids=["one file", "by duration", "by size"])
def test_bag_directory_is_read_by_rosbags_message_by_message(tmp_path, split):
    from mcap.reader import make_reader
    d = tmp_path / "run1"
    w = _write_dir(d, **split)
    w.close()
    meta = yaml.safe_load((d / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap" and meta["ros_distro"] == "jazzy"
    names = meta["relative_file_paths"]
    assert names == [f"run1_{i}.mcap" for i in range(len(names))] == [f["path"] for f in meta["files"]]
    assert sorted(os.listdir(d)) == sorted(names + ["metadata.yaml"])
    if split.get("max_bag_duration_s"):
        assert len(names) == 3 and [f["message_count"] for f in meta["files"]] == [800, 800, 800]
        assert all(f["duration"]["nanoseconds"] < 20e9 for f in meta["files"])
    elif split:
        assert len(names) > 2
        # a file ends past the limit by at most one chunk (4096 bytes here) and its summary and
        # closing metadata (the rosbag2 record repeats metadata.yaml): rosbag2 overshoots the same way
        assert all(os.path.getsize(d / n) < 20_000 + 4096 + 8192 for n in names)
    else:
        assert len(names) == 1
    assert meta["message_count"] == sum(f["message_count"] for f in meta["files"]) == 2400
    assert {t["topic_metadata"]["name"]: t["message_count"] for t in meta["topics_with_message_count"]} == \
        {"/clock": 1200, "/j/joint_states": 1200}
    prof = meta["topics_with_message_count"][0]["topic_metadata"]["offered_qos_profiles"][0]
    assert prof["history"] == "keep_all" and prof["reliability"] == "reliable"     # v9: names, a list
    # every split file is a complete, indexed MCAP (CRCs validated) with the scene record
    for n in names:
        with open(d / n, "rb") as fh:
            reader = make_reader(fh, validate_crcs=True)
            assert sum(1 for _ in reader.iter_messages()) == reader.get_summary().statistics.message_count
            assert "gyro_instrument" in {m.name for m in reader.iter_metadata()}
    theirs, count = _rosbags_messages(d)
    assert count == 2400
    assert theirs == _ours(d) and len(theirs) == 2400
    assert [t for _, t, _ in theirs] == sorted(t for _, t, _ in theirs)
    scan = scan_path(str(d))
    assert scan.state == "complete" and not scan.notes and not scan.damage_dicts(0)


def test_a_recording_killed_between_splits_is_still_read(tmp_path):
    """metadata.yaml is rewritten when the bag opens, at every split and at close: a copy taken
    mid-recording (as SIGKILL leaves it) names every file; each file is complete up to its last
    commit; rosbags and replay read it, and replay says it was interrupted."""
    d = tmp_path / "live"
    w = _write_dir(d, n=1000, max_bag_duration_s=20.0)
    w.commit()
    snap = tmp_path / "snap"
    shutil.copytree(d, snap)                        # the recorder is still writing file _2
    w.close()
    theirs, _ = _rosbags_messages(snap)
    assert len(theirs) == 2000 and theirs == _ours(snap)
    scan = scan_path(str(snap))
    assert scan.state == "recording"
    # metadata.yaml lost (or never written): the .mcap files found are read, with a note
    os.unlink(snap / "metadata.yaml")
    files, notes = bag_files(str(snap))
    assert [os.path.basename(f) for f in files] == ["live_0.mcap", "live_1.mcap", "live_2.mcap"]
    assert "no metadata.yaml" in notes[0]
    assert _ours(snap) == theirs


def test_a_file_not_listed_in_metadata_is_read_with_a_note(tmp_path):
    d = tmp_path / "b"
    _write_dir(d, n=1000, max_bag_duration_s=20.0).close()
    meta_path = d / "metadata.yaml"
    doc = yaml.safe_load(meta_path.read_text())
    doc["rosbag2_bagfile_information"]["relative_file_paths"] = ["b_0.mcap", "b_1.mcap"]
    meta_path.write_text(yaml.safe_dump(doc))
    files, notes = bag_files(str(d))
    assert [os.path.basename(f) for f in files] == ["b_0.mcap", "b_1.mcap", "b_2.mcap"]
    assert "b_2.mcap not listed in metadata.yaml" in notes[0]


@pytest.mark.parametrize("case", ["empty directory", "missing file", "not rosbag2 yaml", "sqlite3"])
def test_bad_bag_directories_exit_2_with_one_line(tmp_path, capsys, case):
    d = tmp_path / "bag"
    if case == "empty directory":
        d.mkdir()
        (d / "notes.txt").write_text("no bag here")
        expect = "no bag in it"
    else:
        _write_dir(d, n=1000, max_bag_duration_s=20.0).close()
        doc = yaml.safe_load((d / "metadata.yaml").read_text())
        info = doc["rosbag2_bagfile_information"]
        if case == "missing file":
            os.unlink(d / "bag_1.mcap")
            expect = "metadata.yaml names missing files: bag_1.mcap"
        elif case == "not rosbag2 yaml":
            doc = {"something": "else"}
            expect = "not a rosbag2 metadata file"
        else:
            info["storage_identifier"] = "sqlite3"
            expect = "only mcap is read"
        (d / "metadata.yaml").write_text(yaml.safe_dump(doc))
    before = sorted(os.listdir(d))
    out = tmp_path / "fixed.mcap"
    for argv in (["replay", str(d)], ["recover", str(d), "--out", str(out)]):
        assert core_main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"bag = '{d}'" in err[0] and expect in err[0], err
    assert not out.exists() and sorted(os.listdir(d)) == before


def test_recover_a_split_bag_into_one_mcap(tmp_path, capsys):
    d = tmp_path / "s"
    _write_dir(d, n=1000, max_bag_duration_s=20.0).close()
    out = tmp_path / "one.mcap"
    assert core_main(["recover", str(d), "--out", str(out)]) == 0
    assert "recovered 2000 messages" in capsys.readouterr().out
    assert _ours(out) == _ours(d)
    # never over an input: a file of the bag is refused as --out
    assert core_main(["recover", str(d), "--out", str(d / "s_0.mcap"), "--overwrite"]) == 2
    assert "is the input" in capsys.readouterr().err


def test_a_damaged_split_file_is_reported_with_its_name(tmp_path):
    from gyro_instrument.recording.bag_scan import scan_bag
    d = tmp_path / "dmg"
    _write_dir(d, n=1000, max_bag_duration_s=20.0).close()
    f = d / "dmg_1.mcap"
    s = scan_bag(str(f))
    first_chunk = min(p for _, p, _, _ in s.messages)
    data = bytearray(f.read_bytes())
    data[first_chunk + 60] ^= 0xFF                  # a byte inside the first chunk's compressed records
    f.write_bytes(bytes(data))
    scan = scan_path(str(d))
    dmg = scan.damage_dicts(0)
    assert len(dmg) == 1 and dmg[0]["file"] == "dmg_1.mcap"
    assert len(_ours(d)) < 2000


def test_run_records_a_split_rosbag2_directory_that_replays_to_the_live_estimate(tmp_path, capsys):
    """gyro-instrument run --bag DIR/ --max-bag-duration 20 (real DDS, loopback): three files, read
    by rosbags message by message; replay of the directory, of the directory's recovered .mcap and
    the player all give what the live run gave."""
    import rclpy
    from rclpy.parameter import Parameter
    from gyro_instrument.ros.cli import main as ros_main
    from gyro_instrument.ros.nodes import PlayerNode
    d = tmp_path / "quet"
    argv = ["run", "quet_paris", "--set", "seed=5", "--duration-s", "60", "--bag", f"{d}/",
            "--max-bag-duration", "20", "--json", "--quiet"]
    assert ros_main(argv) == 0
    live = json.loads(capsys.readouterr().out)
    names = yaml.safe_load((d / "metadata.yaml").read_text())["rosbag2_bagfile_information"]["relative_file_paths"]
    assert names == ["quet_0.mcap", "quet_1.mcap", "quet_2.mcap", "quet_3.mcap"]   # 0-20-40-60 s: t = 60 s opens _3
    theirs, _ = _rosbags_messages(d)
    assert theirs == _ours(d)
    assert json.dumps(replay_bag(str(d)), sort_keys=True) == json.dumps(live, sort_keys=True)
    # refused without --overwrite; with it the bag files are replaced
    assert ros_main(argv) == 2
    assert "exists" in capsys.readouterr().err
    (d / "keep.txt").write_text("not a bag file")
    assert ros_main(argv + ["--overwrite"]) == 2
    assert "not written over" in capsys.readouterr().err and (d / "keep.txt").exists()
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=[])
    try:
        node = PlayerNode(context=ctx, parameter_overrides=[Parameter("bag", value=str(d))])
        # every message but /tf_static, which the player skips where tf2_msgs is not installed (the wheels)
        assert node.total == len([m for m in theirs if m[0] != "/tf_static"]) and not node.damaged
        node.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
    # a split file alone is still a bag (the scene is repeated in every file) and says it is a part
    part = replay_bag(str(d / "quet_1.mcap"))
    assert any("one part of a split bag" in n for n in part["replay_notes"])
    assert to_jsonable(part)["scene"] == "quet_paris"


#: run in a private mount namespace whose DIR is a 96 KiB tmpfs: a bag directory opened with one
#: topic (its first metadata.yaml is one page), then 14 more topics, then messages until the disk
#: is full; PAYLOAD varies where in a page the disk runs out
_FILL_SMALL_DISK = r'''
import sys
from gyro_instrument.recording.bag_layout import BagDirectoryWriter
from gyro_instrument.recording.mcap_io import DiskFull
disk, payload = sys.argv[1], int(sys.argv[2])
w = BagDirectoryWriter(disk + "/bag", chunk_size=2048)
w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
for k in range(14):
    w.add_topic(f"/instrument_{k:02d}/a_long_enough_topic_name/joint_states", "sensor_msgs/msg/JointState")
i = 0
try:
    while True:
        w.write(f"/instrument_{i % 14:02d}/a_long_enough_topic_name/joint_states", 10**18 + i * 10**7,
                bytes(payload))
        i += 1
        if i % 7 == 0:
            w.commit()
except DiskFull as exc:
    print("full", i, exc.needed)
'''


@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("unshare") is None, reason="needs root and unshare -m")
@pytest.mark.parametrize("payload", [1, 97, 333, 1000, 2500])
def test_a_full_disk_leaves_a_metadata_yaml_that_lists_what_the_files_hold(tmp_path, payload):
    # The failure seen in CI: metadata.yaml rewritten in place on a full disk after it had grown past
    # its first page (topics added since) was cut at the page, without 'files'. The room kept after it
    # (fallocate, KEEP_SIZE) makes the rewrite need no new space. Payloads 1 to 2500 bytes move the
    # point where the disk runs out across a page (4 KiB) and across chunks (2 KiB).
    import subprocess
    import sys
    disk, kept = tmp_path / "disk", tmp_path / "kept"
    disk.mkdir()
    r = subprocess.run(["unshare", "-m", "sh", "-c", f"mount -t tmpfs -o size=96k tmpfs {disk} && "
                        f"{sys.executable} -c '{_FILL_SMALL_DISK}' {disk} {payload}; rc=$?; cp -a {disk} {kept}; "
                        "exit $rc"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith("full "), r.stdout + r.stderr
    bag = kept / "bag"
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert len(info["topics_with_message_count"]) == 15, info
    listed = sum(f["message_count"] for f in info["files"])
    got, count = _rosbags_messages(bag)                 # rosbags reads what metadata.yaml lists
    assert listed == info["message_count"] == count == len(got) > 0, (listed, info["message_count"], count)
