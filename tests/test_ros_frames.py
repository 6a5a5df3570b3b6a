"""Frames, stamps and the gyrotheodolite's live heading for a navigation stack (issue 37 item 5),
over real DDS on loopback (tools/loopback).

One suite run of the gyrotheodolite scene (GAK1-like: one swing 240 s, a rotor-off tape swing of
796 s, 1 Hz) for 600 s with ``frame_prefix:=ship1/`` and ``stamp_epoch:=2026-12-07T01:00:00Z``; an
independent subscriber (its own context, TRANSIENT_LOCAL) reads the live static transforms. The bag
is read back with rosbags' own CDR (its Jazzy type store holds tf2_msgs/msg/TFMessage; the project
writes that type with its own codec).

References independent of the code under test: the scene's mount azimuth (359.75 deg) and swing
duration (240 s, its comment); datetime's reading of the epoch; the frame ids every message names
(read by rosbags); the REP-103 yaw of a compass azimuth (ψ = 90° − A) checked with scipy's Rotation.
"""

import math
import time
from datetime import datetime, timezone
from pathlib import Path

import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation

from gyro_instrument.core.errors import SceneError
from gyro_instrument.recording.frames import check_frame_prefix, parse_stamp_epoch
from gyro_instrument.ros.suite import RunOptions, run_suite
from test_ros_heading import spinning, wait_until

pytestmark = pytest.mark.ros

EPOCH_TEXT = "2026-12-07T01:00:00Z"
EPOCH_S = int(datetime(2026, 12, 7, 1, 0, 0, tzinfo=timezone.utc).timestamp())
PREFIX = "ship1/"
DURATION_S = 600.0
SWING_S = 240.0                  # gyrotheodolite.yaml: 8 min full period with the tape -> 240 s swing
MOUNT_DEG = 359.75               # gyrotheodolite.yaml: the scale's zero 0.25 deg west of north


@pytest.fixture(scope="module")
def gyro_run(tmp_path_factory):
    from geometry_msgs.msg import TransformStamped
    live = []
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

    def listener(ctx):
        node = rclpy.create_node("frames_listener", context=ctx)
        node.create_subscription(TransformStamped, "/static_transforms", live.append, qos)
        return node
    bag = str(tmp_path_factory.mktemp("frames") / "g.mcap")
    with spinning(listener):
        result, stats = run_suite("gyrotheodolite", [], DURATION_S, bag, RunOptions(
            ros_args=["-p", f"frame_prefix:={PREFIX}", "-p", f"stamp_epoch:={EPOCH_TEXT}"]))
        wait_until(lambda: live)
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    msgs = []
    with AnyReader([Path(bag)], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        for conn, log_ns, raw in reader.messages():
            msgs.append((conn.topic, log_ns, reader.deserialize(raw, conn.msgtype)))
    return result, msgs, list(live)


def _stamp_s(h):
    return h.stamp.sec + 1e-9 * h.stamp.nanosec


def _azimuth_deg(q):
    fwd = Rotation.from_quat([q.x, q.y, q.z, q.w]).apply([1.0, 0.0, 0.0])
    return math.degrees(math.atan2(fwd[0], fwd[1])) % 360.0


def test_gyrotheodolite_heading_from_the_first_swing_at_every_sample(gyro_run):
    """At 1 Hz (the instrument samples slower than 10 Hz: every sample) from one swing on, tape
    corrected, within 4 σ of the mount azimuth, σ shrinking; the rate not provided."""
    _, msgs, _ = gyro_run
    imu = [m for tp, _, m in msgs if tp == "/gak1/heading"][:-1]          # the last is the final estimate
    t = [_stamp_s(m.header) - EPOCH_S for m in imu]
    assert t[0] <= SWING_S + 1.0 + 1e-6         # one swing of data (the rotor-off fit may come a sample later)
    assert all(abs((b - a) - 1.0) < 1e-6 for a, b in zip(t, t[1:]))       # every sample: 1 Hz of sim time
    assert t[-1] >= DURATION_S - 1 - 1e-6
    sig = [math.sqrt(m.orientation_covariance[8]) for m in imu]
    assert all(b <= a * 1.05 for a, b in zip(sig, sig[1:]))               # what is known so far: shrinking
    assert sig[-1] < sig[0] / 5
    for m, s in zip(imu, sig):
        miss = abs((_azimuth_deg(m.orientation) - MOUNT_DEG + 180.0) % 360.0 - 180.0)
        assert miss < 4 * math.degrees(s)
        assert m.angular_velocity_covariance[0] == -1.0                   # Imu.msg: not provided
        assert m.header.frame_id == PREFIX + "gak1_scale"


def test_frame_prefix_everywhere_and_a_transform_for_every_frame(gyro_run):
    _, msgs, live = gyro_run
    named = set()
    for tp, _, m in msgs:
        h = getattr(m, "header", None)
        if h is not None and h.frame_id:
            named.add(h.frame_id)
        for mk in getattr(m, "markers", []):
            named.add(mk.header.frame_id)
    assert named and all(f.startswith(PREFIX) for f in named)
    tf = [m for tp, _, m in msgs if tp == "/tf_static"]
    assert len(tf) == 1
    children = {t.child_frame_id: t for t in tf[0].transforms}
    roots = {t.header.frame_id for t in tf[0].transforms}
    assert roots == {PREFIX + "site_enu"}
    assert named <= set(children) | roots                                 # every frame a message names
    scale = children[PREFIX + "gak1_scale"].transform.rotation
    assert _azimuth_deg(scale) == pytest.approx(MOUNT_DEG, abs=1e-9)      # the mounting the scene declares
    # live: the same transforms, latched, to an independent late subscriber
    assert {t.child_frame_id for t in live} == set(children)
    for t in live:
        assert t.header.frame_id == PREFIX + "site_enu"


def test_stamp_epoch_shifts_every_stamp(gyro_run):
    result, msgs, _ = gyro_run
    clock = [m for tp, _, m in msgs if tp == "/clock"]
    assert (clock[0].clock.sec, clock[0].clock.nanosec) == (EPOCH_S, 0)   # sim time 0 at the epoch
    assert clock[-1].clock.sec == EPOCH_S + DURATION_S
    tf = [(log, m) for tp, log, m in msgs if tp == "/tf_static"][0]
    assert tf[0] == EPOCH_S * 10 ** 9 and tf[1].transforms[0].header.stamp.sec == EPOCH_S
    for tp, log, m in msgs:
        h = getattr(m, "header", None)
        if h is not None and h.stamp.sec:
            assert EPOCH_S <= h.stamp.sec <= EPOCH_S + DURATION_S
    # the estimate is unchanged by where the stamps start: the mount azimuth found
    north = result["north"]
    assert abs((north["mount_azimuth_deg"] - MOUNT_DEG + 180) % 360 - 180) < 4 * north["sigma_arcsec"] / 3600


# ----------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("prefix", ["", "ship1/", "fleet/ship_2/", "a"])
def test_valid_frame_prefixes(prefix):
    assert check_frame_prefix(prefix) == prefix


@pytest.mark.parametrize("prefix", ["/ship1/", "ship 1/", "ship1//", "schiff-1/", "ä/"])
def test_a_frame_prefix_a_frame_id_may_not_hold_is_refused_naming_it(prefix):
    with pytest.raises(SceneError, match="frame_prefix") as err:
        check_frame_prefix(prefix)
    assert repr(prefix) in str(err.value)


def test_stamp_epoch_values():
    assert parse_stamp_epoch("") == 10 ** 18                             # the simulation epoch
    assert parse_stamp_epoch(EPOCH_TEXT) == EPOCH_S * 10 ** 9
    assert parse_stamp_epoch("2026-12-07T01:00:00") == EPOCH_S * 10 ** 9  # no zone: UTC
    assert parse_stamp_epoch("2026-12-07T02:00:00+01:00") == EPOCH_S * 10 ** 9
    assert parse_stamp_epoch("wall", 1.0) == "wall"
    for bad in ("yesterday", "2026-13-01", "1969-12-31T00:00:00Z", "2040-01-01"):
        with pytest.raises(SceneError, match="stamp_epoch") as err:
            parse_stamp_epoch(bad)
        assert repr(bad) in str(err.value)
    with pytest.raises(SceneError, match="real_time_factor 1"):
        parse_stamp_epoch("wall", 0.0)


def test_bad_frame_prefix_and_stamp_epoch_are_logged_and_the_node_runs(capfd):
    from gyro_instrument.ros.nodes import EstimatorNode
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=[])
    try:
        node = EstimatorNode(context=ctx, parameter_overrides=[
            Parameter("scene", value="quet_paris"), Parameter("duration_s", value=20.0),
            Parameter("frame_prefix", value="ship 1/"), Parameter("stamp_epoch", value="yesterday")])
        assert node.scene is not None and node.subs                       # running: it listens
        assert node.frame_prefix == "" and node.stamp_offset_ns == 0      # the defaults kept
        node.destroy_node()
        log = capfd.readouterr().err
        assert "frame_prefix = 'ship 1/' is invalid" in log and "stamp_epoch = 'yesterday' is invalid" in log
    finally:
        rclpy.shutdown(context=ctx)


def test_a_second_suite_with_the_same_frames_is_warned_about(capfd):
    """Two estimators of quet_paris (its gyroscope's scale frame) in /ship1 and /ship2, no prefix:
    each sees the other's latched transforms and warns, naming the other namespace's topic."""
    from gyro_instrument.ros.nodes import EstimatorNode
    ctx = rclpy.Context()
    rclpy.init(context=ctx, args=[])
    params = [Parameter("scene", value="quet_paris"), Parameter("duration_s", value=20.0)]
    nodes = []
    try:
        nodes = [EstimatorNode(context=ctx, namespace=ns, parameter_overrides=params) for ns in ("/ship1", "/ship2")]
        ex = SingleThreadedExecutor(context=ctx)
        for n in nodes:
            ex.add_node(n)
        t0 = time.monotonic()
        while time.monotonic() - t0 < 15 and not all(n._tf_warned for n in nodes):
            ex.spin_once(timeout_sec=0.05)
        assert ("/ship2/static_transforms", "gyro_horizontal_scale") in nodes[0]._tf_warned
        assert ("/ship1/static_transforms", "gyro_horizontal_scale") in nodes[1]._tf_warned
        log = capfd.readouterr().err
        assert "also published on /ship2/static_transforms" in log and "namespace /ship2" in log
    finally:
        for n in nodes:
            n.destroy_node()
        rclpy.shutdown(context=ctx)


def test_the_tf_message_type_hash_follows_rep_2011():
    """The embedded TFMessage hash is computed by the method that reproduces the installed
    TransformStamped hash (its own .json)."""
    import json
    from gyro_instrument.recording.definitions import _find, rihs01, type_hash
    with open(_find("geometry_msgs", "TransformStamped", "json"), encoding="utf-8") as fh:
        d = json.load(fh)
    assert rihs01(d["type_description_msg"]) == type_hash("geometry_msgs/msg/TransformStamped")
    assert type_hash("tf2_msgs/msg/TFMessage").startswith("RIHS01_")


def test_wall_stamp_epoch_at_real_time_factor_1(tmp_path):
    """``stamp_epoch:=wall`` at real-time factor 1: sim time 0 is stamped with the wall clock when
    the run starts (between the wall times before and after the run), and every stamp follows it:
    the recorder's /tf_static and the estimator's heading take it from the first stamp they get."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore
    bag = str(tmp_path / "w.mcap")
    before = time.time()
    run_suite("quet_paris", ["instruments.gyro_meridian=null", "instruments.pendulum=null"], 2.0, bag,
              RunOptions(real_time_factor=1.0, ros_args=["-p", "stamp_epoch:=wall"]))
    after = time.time()
    with AnyReader([Path(bag)], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        got = [(c.topic, log, reader.deserialize(raw, c.msgtype)) for c, log, raw in reader.messages()]
    clock0 = [m for tp, _, m in got if tp == "/clock"][0].clock
    t0 = clock0.sec + 1e-9 * clock0.nanosec
    assert before <= t0 <= after
    tf = [(log, m) for tp, log, m in got if tp == "/tf_static"][0]
    assert tf[0] == clock0.sec * 10 ** 9 + clock0.nanosec
    joints = [m for tp, _, m in got if tp == "/gyro_horizontal/joint_states"]
    assert _stamp_s(joints[-1].header) - t0 == pytest.approx(2.0, abs=1e-6)


def test_separate_nodes_share_a_wall_epoch_and_the_prefix(tmp_path):
    """The route ROS users take (one process per node, one params file): the clock owner takes the
    wall clock when sim time starts; the other simulator, the estimator and the recorder take it
    from the first stamp they receive, so every topic starts at the same stamp; frames prefixed."""
    from gyro_instrument.recording.cdr import cdr_stamp_ns
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.ros.launch import launch
    bag = str(tmp_path / "s.mcap")
    before = time.time()
    res = launch("quet_paris", bag, duration_s=3.0, real_time_factor=1.0, timeout_s=120,
                 extra_ros_args=["-p", "stamp_epoch:=wall", "-p", f"frame_prefix:={PREFIX}"])
    after = time.time()
    assert res["returncodes"]["recorder"] == 0, res["logs"]
    first = {}
    for topic, _, log, data in read_messages(bag):
        first.setdefault(topic, (log, data))
    t0 = first["/clock"][0]
    assert before <= t0 / 1e9 <= after
    for topic in ("/gyro_horizontal/joint_states", "/pendulum/bob_position", "/tf_static"):
        assert first[topic][0] == t0, topic                  # pendulum_sim followed the owner's epoch
    assert f"{PREFIX}pendulum_pivot".encode() in first["/pendulum/bob_position"][1]
    assert cdr_stamp_ns(first["/pendulum/bob_position"][1]) == t0
    for node in ("estimator", "recorder", "pendulum_sim"):
        assert "stamp_epoch = wall: sim time 0 is stamped" in res["logs"][node]
