"""Issue 25, the recording half: a ROS user's bad day, on real DDS on loopback, separate processes.

1. a sample is logged at its own sim time: recorder and estimator first, simulators 4 s later,
   real-time factor 0, a default-QoS subscriber beside them (it stalls the publishers that wait for
   its acknowledgements): every JointState's log time equals its header stamp;
6. a clock that goes back (a runtime scene change on the clock owner) starts a new recording file;
7. a full disk: ``run`` closes the bag readable and exits 2 with one line; replay/recover skip an
   empty or cut split;
8. split limits below their floors refused; metadata.yaml not rewritten at every split;
9. a topic of an unknown message type: replay and plot skip it with a note;
10. foreign layouts: ``storage_identifier: ""``, split order by the numeric index, an empty schema;
11. no LINE_STRIP marker with fewer than two points.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from gyro_instrument.cli import replay_bag
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.bag_layout import (MIN_BAG_DURATION_S, MIN_BAG_SIZE, BagDirectoryWriter,
                                                  bag_files, split_order)
from gyro_instrument.recording.bag_scan import scan_bag
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros import messages as m
from gyro_instrument.ros.launch import _command, launch
from gyro_instrument.ros.suite import RunOptions, run_suite

pytestmark = pytest.mark.ros
BIN = Path(sys.executable).parent
GI = [sys.executable, "-m", "gyro_instrument.ros.cli"]

BYSTANDER = r'''
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from sensor_msgs.msg import JointState
from rosgraph_msgs.msg import Clock
rclpy.init()
n = Node("bystander")
got = {}
for tp in ("/pendulum/joint_states", "/gyro_horizontal/joint_states", "/gyro_meridian/joint_states"):
    n.create_subscription(JointState, tp, lambda msg, tp=tp: got.__setitem__(tp, got.get(tp, 0) + 1), 10)
n.create_subscription(Clock, "/clock", lambda msg: None, 10)
try:
    rclpy.spin(n)
except (KeyboardInterrupt, ExternalShutdownException):
    pass
print(got, flush=True)
'''


def status(bag):
    st = scan_bag(bag).metadata_record("gyro_instrument_status")
    return st["state"], json.loads(st.get("topics", "{}")), st


def moved_samples(bag):
    """{topic: count} of stamped messages whose log time is not their header stamp."""
    bad = {}
    for tp, ty, t, data in read_messages(bag):
        if ty in ("sensor_msgs/msg/JointState", "geometry_msgs/msg/PointStamped", "rosgraph_msgs/msg/Clock") \
                and m.cdr_stamp_ns(data) != t:
            bad[tp] = bad.get(tp, 0) + 1
    return bad


def _separate_run(tmp_path, k, seed=None):
    bag = str(tmp_path / f"r{k}.mcap")
    lis = subprocess.Popen([sys.executable, "-c", BYSTANDER], stdout=subprocess.PIPE, text=True,
                           start_new_session=True)
    try:
        res = launch("quet_paris", bag, overrides=[f"seed={seed}"] if seed is not None else (), duration_s=60.0,
                     delay_s=4.0, timeout_s=240, log_dir=str(tmp_path))
    finally:
        lis.send_signal(signal.SIGINT)
        lis.communicate(timeout=30)
    return bag, res


def _check_logged_at_stamp(bag, res):
    state, counts, st = status(bag)
    assert res["returncodes"]["recorder"] == 0, res["logs"]["recorder"]
    # the case: every JointState (and point, clock tick) logged at its own stamp
    assert moved_samples(bag) == {}, (st, res["logs"])
    if state == "complete":
        # every sample once; each estimator topic at least once (a gyroscope's heading also at each
        # reversal point: msg_docs/topics.md)
        assert all(k == n or (tp.endswith("/heading") and k > n) for tp, (k, n) in counts.items()), counts
    else:                                    # never 'complete' with samples missing
        assert state == "incomplete" and any(k < n for k, n in counts.values()), counts
    # read back in log-time order by an independent reader, whatever order they reached the file in
    from rosbags.highlevel import AnyReader
    with AnyReader([Path(bag)]) as reader:
        times = [t for _, t, _ in reader.messages()]
    assert times == sorted(times) and len(times) == sum(k for k, _ in counts.values())
    return int(st.get("late", 0))


def test_late_samples_are_logged_at_their_stamp(tmp_path):
    # One run here (~15 s; test_ros_nodes' separate-process run checks the same without the
    # bystander); 10 under slow. A stalled simulator's samples once landed at the last sample's
    # time in a file marked 'complete' (issue 25.1: 1 of 4 runs reproduced before the fix).
    bag, res = _separate_run(tmp_path, 0)
    _check_logged_at_stamp(bag, res)


@pytest.mark.slow
def test_late_samples_ten_runs(tmp_path):
    late = []
    for k in range(10):
        d = tmp_path / str(k)
        d.mkdir()
        bag, res = _separate_run(d, k, seed=k)
        late.append(_check_logged_at_stamp(bag, res))
    print("late per run", late)


# ---- 6. the clock goes back ----------------------------------------------------------------------

def _call_set(node_name, params, timeout=30):
    """ros2 param set, from a separate process."""
    code = r'''
import sys, json, rclpy
from rclpy.node import Node
from rcl_interfaces.srv import SetParameters
from rclpy.parameter import Parameter
rclpy.init()
n = Node("setter")
cli = n.create_client(SetParameters, sys.argv[1] + "/set_parameters")
assert cli.wait_for_service(timeout_sec=20)
req = SetParameters.Request()
req.parameters = [Parameter(k, value=v).to_parameter_msg() for k, v in json.loads(sys.argv[2]).items()]
fut = cli.call_async(req)
rclpy.spin_until_future_complete(n, fut, timeout_sec=20)
print([r.successful for r in fut.result().results])
'''
    return subprocess.run([sys.executable, "-c", code, node_name, json.dumps(params)], capture_output=True,
                          text=True, timeout=timeout)


@pytest.mark.parametrize("layout", ["mcap", pytest.param("rosbag2", marks=pytest.mark.slow)])
def test_clock_going_back_starts_a_new_recording(tmp_path, layout):
    # The clock owner runs paced at 4x real time; its seed is changed at runtime: it restarts at
    # t = 0. The recorder closes the first file (incomplete, 'restarted', naming the next) and
    # records the new run in q_run1.mcap (bag_run1/): no file holds stamps of two runs.
    out = str(tmp_path / ("q.mcap" if layout == "mcap" else "bag")) + ("/" if layout == "rosbag2" else "")
    rec = subprocess.Popen(_command("recorder") + ["--ros-args", "-p", "scene:=foucault_pantheon",
                            "-p", "duration_s:=8", "-p", f"output:={out}"],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    sim = subprocess.Popen(_command("pendulum_sim") + ["--ros-args", "-p", "scene:=foucault_pantheon",
                            "-p", "duration_s:=8", "-p", "publish_clock:=true", "-p", "real_time_factor:=4",
                            "-p", "wait_for:=['recorder']"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True, start_new_session=True)
    try:
        first = out.rstrip("/")
        t0 = time.monotonic()
        while time.monotonic() - t0 < 60:
            time.sleep(0.2)
            f = first if layout == "mcap" else os.path.join(first, "bag_0.mcap")
            if os.path.exists(f) and os.path.getsize(f) > 20000:
                break
        time.sleep(0.5)                 # about 2 s of sim time into the run
        r = _call_set("/pendulum_sim", {"seed": 9})
        assert "True" in r.stdout, r.stdout + r.stderr
        time.sleep(4.0)                 # the new run: 8 s of sim time at 4x
    finally:
        sim.send_signal(signal.SIGINT)
        sim_out = sim.communicate(timeout=30)[0]
        rec.send_signal(signal.SIGINT)
        rec_out = rec.communicate(timeout=30)[0]
    second = str(tmp_path / ("q_run1.mcap" if layout == "mcap" else "bag_run1"))
    assert "sim time went back" in rec_out and "recording continues in" in rec_out, rec_out
    assert os.path.exists(second), (rec_out, sim_out)
    runs = []
    for path in (first, second):
        msgs = [(tp, t, m.cdr_stamp_ns(d)) for tp, _, t, d in read_messages(path if layout == "mcap"
                                                                           else bag_files(path)[0][0])] \
            if layout == "mcap" else None
        if layout == "rosbag2":
            from gyro_instrument.recording.bag_layout import scan_path
            scan = scan_path(path)
            msgs = [(ch.topic, msg.log_time, m.cdr_stamp_ns(msg.data)) for _, ch, msg in scan.records()]
        runs.append(msgs)
        for tp in ("/clock", "/pendulum/joint_states"):
            stamps = [s for t, _, s in msgs if t == tp]
            assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps), (path, tp)
        assert all(t == s for tp, t, s in msgs if tp in ("/clock", "/pendulum/joint_states", "/pendulum/bob_position"))
    assert min(t for _, t, _ in runs[1]) == EPOCH_NS            # the new run starts again at t = 0
    assert max(t for _, t, _ in runs[0]) > EPOCH_NS + 1_000_000_000
    f0 = first if layout == "mcap" else os.path.join(first, "bag_0.mcap")
    st0 = scan_bag(f0).metadata_record("gyro_instrument_status")
    assert st0["state"] == "incomplete" and "continues_in" in st0["restarted"], st0
    assert json.loads(st0["restarted"])["continues_in"] == os.path.basename(second)


# ---- 7. a full disk --------------------------------------------------------------------------------

def _tmpfs_available():
    if os.geteuid() != 0 or shutil.which("unshare") is None:
        return False
    r = subprocess.run(["unshare", "-m", "sh", "-c", "d=$(mktemp -d) && mount -t tmpfs -o size=64k tmpfs $d "
                        "&& umount $d && rmdir $d"], capture_output=True)
    return r.returncode == 0


def _run_on_small_disk(tmp_path, size, args):
    """``gyro-instrument run ARGS`` in a private mount namespace with DIR a tmpfs of ``size``; the bag
    is copied out before the namespace ends. Returns (CompletedProcess, copy of DIR)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    keep = tmp_path / "kept"
    script = (f"mount -t tmpfs -o size={size} tmpfs {disk} && cd {os.getcwd()} && "
              f"{' '.join(GI)} {' '.join(args)}; rc=$?; cp -a {disk} {keep}; exit $rc")
    r = subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True, text=True, timeout=300)
    return r, keep


@pytest.mark.skipif(not _tmpfs_available(), reason="needs root and unshare -m to mount a small tmpfs")
def test_disk_full_during_split_recording(tmp_path):
    # A real full file system (a 3 MiB tmpfs): a split recording of 600 s (~6 MB) fills it.
    r, kept = _run_on_small_disk(tmp_path, "3m", ["run", "quet_paris", "--duration-s", "600", "--bag",
                                                  f"{tmp_path}/disk/bag/", "--max-bag-size", str(MIN_BAG_SIZE),
                                                  "--quiet"])
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "No space left on device" in lines[0] and "bytes free" in lines[0] \
        and "needs" in lines[0] and "Traceback" not in r.stderr, r.stderr
    bag = str(kept / "bag")
    files, notes = bag_files(bag)
    assert len(files) >= 2
    from gyro_instrument.recording.bag_layout import scan_path
    scan = scan_path(bag)
    assert scan.damaged == [] and len(scan.messages) > 1000
    per_file = []
    for f in files:                        # every file opens in an independent reader
        from rosbags.highlevel import AnyReader
        with AnyReader([Path(f)]) as reader:
            per_file.append(sum(1 for _ in reader.messages()))
    assert all(k > 0 for k in per_file), per_file
    # the replay says the recording was cut, and how much it read: the span of the joint stamps the
    # splits hold (the shortest over the instruments, as replay.read_span_s), short of the 600 s asked
    joints = {}
    for f in files:
        for tp, _, t, _ in read_messages(f):
            if tp.endswith("/joint_states"):
                joints.setdefault(tp, []).append(t)
    span_s = min((max(t) - min(t)) / 1e9 for t in joints.values())
    check_disk_full_bag(bag)
    res = replay_bag(bag)
    assert "observation_read_s" in res and "recording_cut" in res, sorted(res)
    assert res["observation_read_s"] == pytest.approx(span_s, abs=1e-9) and 0 < span_s < 600, (res["observation_read_s"], span_s)
    # recover uses it all: every message of every split, once (the count the independent reader found)
    fixed = str(tmp_path / "fixed.mcap")
    rr = subprocess.run(GI + ["recover", bag, "--out", fixed], capture_output=True, text=True, timeout=120)
    assert rr.returncode == 0, rr.stderr
    assert rr.stdout.startswith(f"recovered {sum(per_file)} messages from "), (rr.stdout, per_file)
    assert len(list(read_messages(fixed))) == sum(per_file)


def check_disk_full_bag(bag):
    """A bag directory a full disk stopped: metadata.yaml says what the files hold (per file, per
    topic, as rosbags reads them), its last file's status is 'incomplete' with the reason."""
    from rosbags.highlevel import AnyReader
    info = yaml.safe_load(open(os.path.join(bag, "metadata.yaml")))["rosbag2_bagfile_information"]
    per_topic, total = {}, 0
    for f in info["files"]:
        with AnyReader([Path(bag) / f["path"]]) as reader:
            n = 0
            for conn, _, _ in reader.messages():
                per_topic[conn.topic] = per_topic.get(conn.topic, 0) + 1
                n += 1
        assert n == f["message_count"], (f, n)
        total += n
    assert info["message_count"] == total
    assert {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]
            if t["message_count"]} == per_topic
    with AnyReader([Path(bag)]) as reader:             # rosbags's own reading of the directory
        assert reader.message_count == total == sum(1 for _ in reader.messages())
    st = scan_bag(os.path.join(bag, info["files"][-1]["path"])).metadata_record("gyro_instrument_status")
    assert st["state"] == "incomplete" and st["reason"].startswith("disk full: No space left on device"), st
    assert int(st["messages"]) == info["files"][-1]["message_count"], st


def test_disk_full_injected_at_the_writer_leaves_a_readable_file(tmp_path, monkeypatch):
    # Variant (no root needed): ENOSPC injected at the commit's write, in a one-file recording run
    # in-process: run_suite raises the one-line error, the file is its last commit (indexed, CRCs).
    import errno
    from gyro_instrument.recording import mcap_io
    from gyro_instrument.ros.suite import BagWriteError
    real = os.pwrite
    budget = {"bytes": 400_000}

    def pwrite(fd, data, at):
        if at + len(data) > budget["bytes"]:
            k = max(budget["bytes"] - at, 0)
            if k:
                real(fd, bytes(data[:k]), at)
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd, data, at)
    monkeypatch.setattr(mcap_io.os, "pwrite", pwrite)
    bag = str(tmp_path / "full.mcap")
    with pytest.raises(BagWriteError) as exc:
        run_suite("quet_paris", [], 120.0, bag)
    line = str(exc.value)
    assert "needs" in line and "bytes free" in line and "\n" not in line
    monkeypatch.setattr(mcap_io.os, "pwrite", real)
    scan = scan_bag(bag)
    assert scan.damaged == [] and scan.summary_ok and len(scan.messages) > 1000
    assert scan.state == "incomplete"       # with the reason: the disk full (the status record fits where it was)
    from rosbags.highlevel import AnyReader
    with AnyReader([Path(bag)]) as reader:
        assert sum(1 for _ in reader.messages()) == len(scan.messages)


def test_replay_and_recover_skip_an_empty_or_cut_split(tmp_path):
    bag = str(tmp_path / "b")
    run_suite("foucault_pantheon", [], 30.0, bag + "/", RunOptions(max_bag_duration_s=10.0))
    files, _ = bag_files(bag)
    assert len(files) == 4                      # 0-10, 10-20, 20-30 s and the sample at 30 s
    with open(os.path.join(bag, "b_4.mcap"), "wb"):
        pass                                    # the 0-byte split a full disk leaves
    with open(files[1], "r+b") as fh:           # a split cut inside its first bytes
        fh.truncate(5)
    meta = yaml.safe_load(open(os.path.join(bag, "metadata.yaml")))
    meta["rosbag2_bagfile_information"]["relative_file_paths"].append("b_4.mcap")
    yaml.safe_dump(meta, open(os.path.join(bag, "metadata.yaml"), "w"))
    res = replay_bag(bag)
    notes = " ".join(res.get("replay_notes", []))
    assert "b_4.mcap skipped: is empty" in notes and "b_1.mcap skipped" in notes, notes
    # the intact splits' messages, counted by an independent reader: recover writes each of them once
    from rosbags.highlevel import AnyReader
    intact = []
    for f in (files[0], files[2], files[3]):
        with AnyReader([Path(f)]) as reader:
            intact.append(sum(1 for _ in reader.messages()))
    assert all(k > 0 for k in intact), intact
    out = str(tmp_path / "fixed.mcap")
    r = subprocess.run(GI + ["recover", bag, "--out", out], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"recovered {sum(intact)} messages from "), (r.stdout, intact)
    got = list(read_messages(out))
    assert len(got) == sum(intact)
    # and they are the intact splits' own messages (0-10 s, 20-30 s): their log times, nothing of 10-20 s
    want = sorted((tp, t, bytes(d)) for f in (files[0], files[2], files[3]) for tp, _, t, d in read_messages(f))
    assert sorted((tp, t, bytes(d)) for tp, _, t, d in got) == want


# ---- 8. split limits -----------------------------------------------------------------------------

@pytest.mark.parametrize("flag,value,floor", [("--max-bag-size", "1", str(MIN_BAG_SIZE)),
                                              ("--max-bag-size", str(MIN_BAG_SIZE - 1), str(MIN_BAG_SIZE)),
                                              ("--max-bag-duration", "0.5", "1"),
                                              ("--max-bag-duration", "nan", "1")])
def test_split_limits_below_the_floor_are_refused(tmp_path, flag, value, floor):
    out = tmp_path / "bag"
    r = subprocess.run(GI + ["run", "quet_paris", "--duration-s", "5", "--bag", f"{out}/", flag, value],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert flag in r.stderr and floor in r.stderr and "Traceback" not in r.stderr
    assert not out.exists()                    # nothing written


def test_metadata_is_not_rewritten_at_every_split(tmp_path, monkeypatch):
    writes = []
    real = BagDirectoryWriter.write_metadata
    monkeypatch.setattr(BagDirectoryWriter, "write_metadata", lambda self: (writes.append(len(self.files)),
                                                                             real(self))[1])
    w = BagDirectoryWriter(str(tmp_path / "b"), max_bag_duration_s=MIN_BAG_DURATION_S)
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    for i in range(100):                         # 100 files
        w.write("/clock", EPOCH_NS + i * 1_000_000_000, m.CLOCK_LAYOUT.encode([i * 1_000_000_000])[0])
    w.close()
    assert len(w.files) == 100
    assert writes == list(range(1, 17)) + [32, 64, 100], writes     # each split to 16 files, doublings, close
    files, notes = bag_files(str(tmp_path / "b"))
    assert len(files) == 100 and notes == []            # the final metadata.yaml lists every file
    assert sum(1 for _ in read_messages(files[-1])) == 1


# ---- 9. unknown message types; 10. foreign layouts ---------------------------------------------------

def _rewrite(src, dst, empty_joint=False, unknown=False):
    from mcap.writer import Writer
    scan = scan_bag(src)
    with open(dst, "wb") as fo:
        w = Writer(fo)
        w.start(profile="ros2", library="test")
        sids, cids = {}, {}
        for sid, s in scan.schemas.items():
            data = b"" if (empty_joint and s.name == "sensor_msgs/msg/JointState") else s.data
            sids[sid] = w.register_schema(s.name, s.encoding, data)
        for cid, c in scan.channels.items():
            cids[cid] = w.register_channel(c.topic, c.message_encoding, sids.get(c.schema_id, 0), dict(c.metadata))
        if unknown:
            us = w.register_schema("acme_msgs/msg/Widget", "ros2msg", b"float64 spin\nstring label\n")
            uc = w.register_channel("/acme/widget", "cdr", us, {})
        for rec in scan.metadata:
            w.add_metadata(rec.name, dict(rec.metadata))
        for i, (_, _, _, msg) in enumerate(scan.messages):
            w.add_message(cids[msg.channel_id], msg.log_time, msg.data, msg.publish_time, msg.sequence)
            if unknown and i % 7 == 0:
                w.add_message(uc, msg.log_time, b"\x00\x01\x00\x00" + b"\x00" * 8 + b"\x02\x00\x00\x00a\x00",
                              msg.log_time)
        w.finish()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    d = tmp_path_factory.mktemp("rec")
    bag = str(d / "q.mcap")
    result, _ = run_suite("quet_paris", ["seed=3"], 60.0, bag)
    return bag, replay_bag(bag)


def test_unknown_type_topic_skipped_by_replay_and_plot(tmp_path, recorded):
    bag, base = recorded
    unk = str(tmp_path / "unk.mcap")
    _rewrite(bag, unk, unknown=True)
    res = replay_bag(unk)
    notes = res.get("replay_notes", [])
    assert any("/acme/widget skipped" in n and "acme_msgs/msg/Widget" in n for n in notes), notes
    assert res["latitude_deg"] == base["latitude_deg"]
    pytest.importorskip("matplotlib")
    r = subprocess.run(GI + ["plot", unk, "--out", str(tmp_path / "png")], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and "/acme/widget skipped" in r.stderr + r.stdout, r.stderr
    assert any(p.suffix == ".png" for p in (tmp_path / "png").iterdir())


def test_unknown_type_in_a_bag_directory_of_a_foreign_recorder(tmp_path, recorded):
    # Variant: the bag directory of another tool (no scene record) with a topic of an unknown type.
    bag, base = recorded
    d = tmp_path / "lab"
    d.mkdir()
    _rewrite(bag, str(d / "lab_0.mcap"), unknown=True)
    r = subprocess.run(GI + ["replay", str(d), "--scene", "quet_paris", "--json"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert any("/acme/widget skipped" in n for n in out.get("replay_notes", []) + out.get("notes", [])), out


def test_empty_joint_state_definition_named_as_the_cause(tmp_path, recorded):
    bag, base = recorded
    empty = str(tmp_path / "empty.mcap")
    _rewrite(bag, empty, empty_joint=True)
    res = replay_bag(empty)
    notes = " ".join(res.get("replay_notes", []))
    assert "empty message definition" in notes, notes
    assert res["latitude_deg"] == base["latitude_deg"]       # decoded with the installed definition
    # without an installed definition: the cause named, not "0 intact messages"
    from gyro_instrument.recording import bag_samples, definitions
    scan = scan_bag(empty)
    real = definitions.concatenated_definition
    try:
        definitions.concatenated_definition = lambda name: (_ for _ in ()).throw(FileNotFoundError(name))
        _, _, undecodable, why = bag_samples.joint_samples(scan, EPOCH_NS, with_notes=True)
    finally:
        definitions.concatenated_definition = real
    assert undecodable > 0 and any("empty message definition" in w and "no definition" in w for w in why), why


def test_storage_identifier_empty_and_numeric_split_order(tmp_path):
    bag = str(tmp_path / "h")
    run_suite("foucault_pantheon", [], 24.0, bag + "/", RunOptions(max_bag_duration_s=2.0))
    files, _ = bag_files(bag)
    assert len(files) == 13                     # 2 s each and the sample at 24 s
    meta_path = os.path.join(bag, "metadata.yaml")
    meta = yaml.safe_load(open(meta_path))
    meta["rosbag2_bagfile_information"]["storage_identifier"] = ""        # a Humble reindex
    yaml.safe_dump(meta, open(meta_path, "w"))
    base = replay_bag(bag)
    assert base["instruments"]
    # Kilted-style names (index first), no metadata.yaml: read in numeric order 0, 1, ..., 10, 11
    os.unlink(meta_path)
    for i, f in enumerate(files):
        os.rename(f, os.path.join(bag, f"{i}_h_2025_12_17-10_00_{i:02d}.mcap"))
    order, notes = bag_files(bag)
    assert [int(os.path.basename(f).split("_")[0]) for f in order] == list(range(13)), order
    assert "order of the split index" in notes[0]
    again = replay_bag(bag)
    assert again["latitude_deg"] == base["latitude_deg"]
    # jazzy names without metadata.yaml: numeric too
    assert split_order([f"b_{i}.mcap" for i in (10, 1, 0, 11, 2)]) == [f"b_{i}.mcap" for i in (0, 1, 2, 10, 11)]


# ---- 11. valid markers -----------------------------------------------------------------------------

def test_no_line_strip_with_fewer_than_two_points(recorded):
    from rclpy.serialization import deserialize_message
    from visualization_msgs.msg import Marker, MarkerArray
    bag, _ = recorded
    n = strips = 0
    for tp, _, _, data in read_messages(bag, ["/pendulum/markers"]):
        arr = deserialize_message(data, MarkerArray)
        n += 1
        for mk in arr.markers:
            if mk.type == Marker.LINE_STRIP:
                strips += 1
                assert len(mk.points) >= 2
    assert n == 61 and strips == 60           # the first one (one trail point) has no trail marker


def test_a_paused_recorder_makes_the_simulator_wait_and_lose_nothing(tmp_path):
    """A recorder that stops taking messages for 3 s (SIGSTOP: a process starved of CPU or paused in
    a debugger) while a simulator publishes as fast as it can: the RELIABLE / KEEP_ALL writer's
    history fills and Fast DDS refuses the write ("cannot publish data"), which ended the simulator
    with an RCLError traceback (seen trying separate nodes beside a busy bench). Now the simulator
    waits, says so, resumes, and every sample is recorded (600 s at 20 Hz: 12 001 per topic)."""
    bag = str(tmp_path / "paused.mcap")
    rec = subprocess.Popen([str(BIN / "recorder"), "--ros-args", "-p", "scene:=foucault_pantheon",
                            "-p", "duration_s:=600.0", "-p", f"output:={bag}", "-p", "stop_when_complete:=true",
                            "-p", "topics:=['clock', 'pendulum/joint_states']"],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # the simulator starts once the recorder says it records (its subscriptions exist) and waits for it
    # in the graph (wait_for: a recorder of a subset of its topics counts once it subscribes to one; its
    # process may see the recorder's subscriptions a second after its start — all 12 001 samples were
    # published before that on a loaded machine, with wait_for:=[])
    head = []
    for line in rec.stdout:
        head.append(line)
        if "recording " in line:
            break
    sim = subprocess.Popen([str(BIN / "pendulum_sim"), "--ros-args", "-p", "scene:=foucault_pantheon",
                            "-p", "duration_s:=600.0", "-p", "publish_clock:=true", "-p", "real_time_factor:=0.0",
                            "-p", "wait_for:=['recorder']", "-p", "wait_timeout_s:=60"],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        t0 = time.monotonic()
        while not (os.path.exists(bag) and os.path.getsize(bag) > 100_000):
            assert time.monotonic() - t0 < 60 and sim.poll() is None, "the run never started"
            time.sleep(0.02)
        rec.send_signal(signal.SIGSTOP)
        time.sleep(3.0)
        rec.send_signal(signal.SIGCONT)
        rec_out, _ = rec.communicate(timeout=120)       # stop_when_complete: it exits when all is in
        rec_out = "".join(head) + rec_out
        sim.send_signal(signal.SIGINT)                    # a simulator stays up once done, as a node does
        sim_out, _ = sim.communicate(timeout=60)
    finally:
        for p in (sim, rec):
            if p.poll() is None:
                p.send_signal(signal.SIGCONT)
                p.kill()
                p.wait()
    assert sim.returncode == 0 and "Traceback" not in sim_out, sim_out
    assert "starting anyway" not in sim_out, sim_out     # the subset recorder was counted as there
    assert "waits: a RELIABLE / KEEP_ALL subscriber is not taking messages" in sim_out, sim_out
    assert "resumed after" in sim_out, sim_out
    state, counts, _ = status(bag)
    assert state == "complete", (counts, rec_out)
    assert counts["/clock"][0] == counts["/pendulum/joint_states"][0] == 12001, counts
