"""ROS 2 suite with real rclpy and DDS (on loopback: see conftest.py), never skipped.

Wiring with DDS: message counts, the sim-time clock, recorder completeness at full speed, and
the estimate of the estimator node equal to the core's for the same samples; node logic without
DDS traffic: joint-state conversion and refused parameters.
"""

import json
import math

import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter

from gyro_instrument.cli import replay_bag, to_jsonable
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros import messages as m
from gyro_instrument.ros.nodes import EstimatorNode, SimulatorNode
from gyro_instrument.ros.suite import RunOptions, run_suite
from gyro_instrument.scenes import load_scene


@pytest.fixture(scope="module")
def live_run(tmp_path_factory):
    bag = str(tmp_path_factory.mktemp("bags") / "quet.mcap")
    result, stats = run_suite("quet_paris", ["seed=5"], 60.0, bag)
    return bag, to_jsonable(result), stats


def test_recorder_is_complete_at_full_speed(live_run):
    # Issue 4: at full speed the number of recorded messages per topic equals the number published
    # (RELIABLE / KEEP_ALL subscriptions, lock-step stepping).
    bag, result, stats = live_run
    n = stats["samples"]
    assert n == 60 * 20 + 1
    for inst in ("gyro_horizontal", "gyro_meridian", "pendulum"):
        assert stats["published"][inst] == n
        assert stats["recorded"][f"/{inst}/joint_states"] == n
    assert stats["recorded"]["/pendulum/bob_position"] == n
    assert stats["recorded"]["/clock"] == n
    assert stats["estimator_messages"] == 3 * n
    # published in batches (the last one partial): every topic recorded as often as published
    assert stats["batch"] > 1 and n % stats["batch"] != 0
    assert stats["published_topics"] == {t: stats["recorded"][t] for t in stats["published_topics"]}
    counts = {}
    for topic, *_ in read_messages(bag):
        counts[topic] = counts.get(topic, 0) + 1
    assert counts["/gyro_horizontal/joint_states"] == n and counts["/estimator/latitude_rad"] == 1


def test_live_bag_read_by_rosbags_message_by_message(live_run):
    # An independent reader (rosbags, its own CDR deserializer) decodes every message, and the joint
    # states to the samples the simulation measured (the same scene and seed through the core:
    # measure(), as the estimate test below) and to what the project's reader decodes (samples_from_bag):
    # JointState position[0] the gyroscope's angle, velocity[1] its spin rate; the pendulum's
    # position[0:2] its deflections east and north (msg_docs/topics.md). Same code, same seed, same
    # doubles: equal to the last bit.
    from pathlib import Path

    from rosbags.highlevel import AnyReader

    from gyro_instrument.recording.bag_samples import samples_from_bag
    bag = live_run[0]
    with AnyReader([Path(bag)]) as r:
        msgs = [(c.topic, t, r.deserialize(raw, c.msgtype)) for c, t, raw in r.messages()]
    assert len(msgs) == sum(1 for _ in read_messages(bag))
    scene = load_scene("quet_paris", ["seed=5", "duration_s=60.0"])
    rec = measure(scene, simulate_truth(scene))
    _, ours, _, _ = samples_from_bag(bag)
    columns = {"gyro_horizontal": [("position", 0, "angle"), ("velocity", 1, "spin_rate")],
               "gyro_meridian": [("position", 0, "angle"), ("velocity", 1, "spin_rate")],
               "pendulum": [("position", 0, "deflection_east"), ("position", 1, "deflection_north")]}
    for inst, cols in columns.items():
        js = [msg for tp, _, msg in msgs if tp == f"/{inst}/joint_states"]
        stamps = np.array([msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec for msg in js])
        np.testing.assert_array_equal(stamps, EPOCH_NS + np.round(rec[inst]["t"] * 1e9).astype(np.int64))
        np.testing.assert_array_equal(stamps - EPOCH_NS, ours[inst][0])       # ours: from the scene's start
        for field, k, channel in cols:
            theirs = np.array([getattr(msg, field)[k] for msg in js])
            np.testing.assert_array_equal(theirs, rec[inst][channel], err_msg=f"{inst} {channel}")
            np.testing.assert_array_equal(theirs, ours[inst][1 if field == "position" else 2][:, k])


def test_player_republishes_a_bag_to_an_estimator(live_run, ctx):
    # DDS wiring of the player: it drives /clock and republishes every joint message; an estimator
    # node fed only by it reproduces the live estimate exactly.
    from rclpy.executors import SingleThreadedExecutor
    from gyro_instrument.ros.nodes import PlayerNode
    bag, result, stats = live_run
    player = PlayerNode(context=ctx, parameter_overrides=[Parameter("bag", value=bag),
                                                          Parameter("real_time_factor", value=0.0)])
    est = EstimatorNode(context=ctx, parameter_overrides=[
        Parameter("scene", value="quet_paris"), Parameter("overrides", value=["seed=5"]),
        Parameter("duration_s", value=60.0)])
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(player)
    ex.add_node(est)
    import time
    t0 = time.monotonic()
    while any(p.get_subscription_count() < 1 for tp, p in player.pubs.items() if tp.endswith("joint_states")):
        ex.spin_once(timeout_sec=0.01)
        assert time.monotonic() - t0 < 10
    n_joint, sent = 3 * stats["samples"], 0
    while player.peek() is not None:
        sent += player.peek()[0].endswith("/joint_states")
        player.publish_next()
        while est.received() < sent:            # lock-step, as the suite does
            ex.spin_once(timeout_sec=0.001)
            assert time.monotonic() - t0 < 60
    assert sent == n_joint and est.received() == n_joint
    assert json.dumps(to_jsonable(est.finalize()), sort_keys=True) == json.dumps(result, sort_keys=True)
    player.destroy_node()
    est.destroy_node()


def test_batched_run_records_every_message_in_sample_order(tmp_path):
    # Batches of 7 samples (61 samples: the last batch has 5) and one sample at a time give the
    # same recording and the same estimate: every topic recorded as often as published, the file
    # in sample order (clock first, then the instruments), the estimator's Float64 topics stamped
    # at the last sample (the recorder's sim-time clock never runs ahead of the delivered data).
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader
    runs = {}
    for batch in (7, 1):
        bag = str(tmp_path / f"b{batch}.mcap")
        result, stats = run_suite("quet_paris", ["seed=5"], 3.0, bag, RunOptions(batch=batch))
        assert stats["batch"] == batch and stats["samples"] == 61
        visual = {"/gyro_horizontal/axis_direction", "/gyro_horizontal/markers", "/gyro_meridian/axis_direction",
                  "/gyro_meridian/markers", "/pendulum/swing_plane", "/pendulum/markers"}
        assert set(stats["published_topics"]) == {"/clock", "/gyro_horizontal/joint_states",
                                                  "/gyro_meridian/joint_states", "/pendulum/joint_states",
                                                  "/pendulum/bob_position"} | visual
        for topic, n in stats["published_topics"].items():
            # per sample, or once per second of sim time (samples 0, 20, 40, 60) for what there is to see
            assert n == (4 if topic in visual else 61) and stats["recorded"][topic] == n
        assert stats["estimator_messages"] == 3 * 61
        channels, order = {}, []
        with open(bag, "rb") as fh:                      # file order, not log-time order
            for rec in StreamReader(fh).records:
                if isinstance(rec, Channel):
                    channels[rec.id] = rec.topic
                elif isinstance(rec, Message):
                    order.append((channels[rec.channel_id], rec.log_time, rec.data))
        times = [t for _, t, _ in order]
        assert times == sorted(times) and times[0] == EPOCH_NS
        seen = [(tp, t) for tp, t, _ in order if tp in visual]
        assert seen == sorted(seen, key=lambda x: x[1]) and {t for _, t in seen} == {
            EPOCH_NS + k * 1_000_000_000 for k in range(4)}
        assert order[0][:2] == ("/tf_static", EPOCH_NS)       # the static frames first, at sim time 0 (issue 37)
        order = [r for r in order if r[0] not in visual and r[0] != "/tf_static"]
        per_sample = ["/clock", "/gyro_horizontal/joint_states", "/gyro_meridian/joint_states",
                      "/pendulum/joint_states", "/pendulum/bob_position"]
        assert [tp for tp, _, _ in order[:5 * 61]] == per_sample * 61
        times = [t for _, t, _ in order]
        assert times == sorted(times) and times[0] == EPOCH_NS
        last = EPOCH_NS + 3_000_000_000
        assert [t for tp, t, _ in order[5 * 61:] if tp.startswith("/estimator/")] == [last] * 5
        runs[batch] = (json.dumps(to_jsonable(result), sort_keys=True), [(tp, t, d) for tp, t, d in order[:5 * 61]],
                       json.dumps(replay_bag(bag), sort_keys=True))
    assert runs[7] == runs[1]
    assert runs[7][2] == runs[7][0]


def test_cdr_layouts_are_what_rclpy_serializes():
    # The simulators publish numpy-built CDR; rclpy decodes it to the same message, and rclpy's
    # own bytes equal it outside the alignment padding (which Fast-CDR leaves unset).
    from rclpy.serialization import deserialize_message, serialize_message

    def masked(layout, data):
        data = bytearray(data)
        for lo, hi in layout.padding:
            data[lo:hi] = bytes(hi - lo)
        return bytes(data)
    rng = np.random.default_rng(1)
    t = np.array([0, 1, 999_999_999, 50_000_000_123, 10 ** 15])
    for k in (1, 2, 3, 4):
        for frame in ("", "a", "abcd", "pendulum_pivot"):
            names = [f"inst/j{'x' * j}" for j in range(k)]
            layout = m.joint_state_layout(names, frame)
            pos, vel, eff = rng.normal(size=(3, 5, k))
            pos[1, 0], vel[2, -1] = np.nan, -0.0
            enc = layout.encode(t, pos, vel, eff)
            for i in range(5):
                msg = m.joint_state(int(t[i]), names, pos[i], vel[i], eff[i], frame_id=frame)
                ref = serialize_message(msg)
                assert enc[i] == masked(layout, ref) and layout.matches(ref) and layout.matches(enc[i])
                back = deserialize_message(enc[i], m.JointState)
                assert m.stamp_to_release_ns(back.header.stamp) == t[i] and list(back.name) == names
                assert back.header.frame_id == frame
                assert np.array_equal(back.position, pos[i], equal_nan=True) and list(back.effort) == list(eff[i])
            t2, (p2, v2, e2) = layout.decode(enc)
            assert np.array_equal(t2, t) and np.array_equal(p2, pos, equal_nan=True)
            assert np.array_equal(v2, vel) and np.array_equal(e2, eff)
            assert np.signbit(v2[2, -1])                                # bit for bit, -0.0 included
            other = serialize_message(m.joint_state(0, names[:-1] + ["inst/y"], pos[0], vel[0], eff[0], frame))
            assert not layout.matches(other)
            assert not layout.matches(serialize_message(m.joint_state(0, names, pos[0, :-1], vel[0], eff[0], frame))
                                      if k > 1 else other)
    layout = m.point_stamped_layout("pendulum_pivot")
    xyz = rng.normal(size=(5, 3))
    for i, data in enumerate(layout.encode(t, xyz)):
        assert data == masked(layout, serialize_message(m.point_stamped(int(t[i]), xyz[i], "pendulum_pivot")))
    for i, data in enumerate(m.CLOCK_LAYOUT.encode(t)):
        assert data == serialize_message(m.clock(int(t[i])))
        assert m.cdr_stamp_ns(data) == EPOCH_NS + t[i]


def test_sim_clock_starts_at_epoch_and_is_monotonic(live_run):
    bag = live_run[0]
    ticks = [m.cdr_stamp_ns(data) for topic, _, _, data in read_messages(bag, ["/clock"])]
    assert ticks[0] == EPOCH_NS                       # non-zero epoch: time 0 means "no time yet"
    assert np.all(np.diff(ticks) == 50_000_000)       # 20 Hz, strictly increasing


def test_node_estimate_equals_core_and_replay_equals_live(live_run):
    # The estimator node's published estimate equals the core's on the same samples, and
    # 'replay' of the bag reproduces the live estimate to the last digit.
    bag, result, _ = live_run
    scene = load_scene("quet_paris", ["seed=5", "duration_s=60.0"])
    truth = simulate_truth(scene)
    core = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
    assert json.dumps(core, sort_keys=True) == json.dumps(result, sort_keys=True)
    assert json.dumps(replay_bag(bag), sort_keys=True) == json.dumps(result, sort_keys=True)
    # and the estimate is physics: within 3 σ of the truth
    assert abs(result["latitude_deg"] - 48.8462) < 3 * result["latitude_sigma_deg"]


def test_estimate_topics_are_typed_and_plottable(live_run):
    bag = live_run[0]
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    with open(bag, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        got = {ch.topic: msg for _, ch, _, msg in reader.iter_decoded_messages(
            topics=["/estimator/latitude_rad", "/estimator/earth_rate_enu", "/diagnostics"])}
    lat = got["/estimator/latitude_rad"].data
    assert math.degrees(lat) == pytest.approx(48.8462, abs=0.01)
    v = got["/estimator/earth_rate_enu"].vector
    assert math.hypot(v.y, v.z) == pytest.approx(7.2921150e-5, rel=1e-4) and v.x == 0.0
    assert got["/diagnostics"].status[0].name == "gyro_instrument/estimator"


def test_joint_state_conversion_fills_every_array():
    # Fast-CDR pads an empty float64[]; independent readers reject it: position, velocity and
    # effort are always filled.
    msg = m.joint_state(1_500_000_000, ["a", "b"], [0.1, 0.2], [1.0, 2.0], [0.0, 0.0])
    assert len(msg.position) == len(msg.velocity) == len(msg.effort) == 2
    assert m.stamp_to_release_ns(msg.header.stamp) == 1_500_000_000


def test_estimator_node_logic_without_dds_traffic(ctx):
    # Messages handed to the callback directly (no publishing): the node's estimate equals the
    # core's on the same samples; a message with the wrong joint layout is counted and ignored.
    from gyro_instrument.recording.joints import joint_streams
    params = [Parameter("scene", value="quet_paris"), Parameter("duration_s", value=40.0)]
    node = EstimatorNode(context=ctx, parameter_overrides=params)
    scene = load_scene("quet_paris", ["duration_s=40.0"])
    truth = simulate_truth(scene)
    t_ns, streams = joint_streams(scene, truth=truth)
    for name, s in streams.items():
        for i in range(len(t_ns)):
            node._on_joint(name, m.joint_state(int(t_ns[i]), s.names, s.position[i], s.velocity[i], s.effort[i]))
    node._on_joint("pendulum", m.joint_state(0, ["x"], [0.0], [0.0], [0.0]))
    assert node.rejected == {"pendulum": 1}
    est = to_jsonable(node.finalize())
    core = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
    assert json.dumps(est, sort_keys=True) == json.dumps(core, sort_keys=True)
    node.destroy_node()


def test_lockstep_waits_for_late_messages_and_never_drops_silently(ctx):
    # A message published later (another thread) is waited for on a wait set; a batch that never
    # completes is a DeliveryError naming the topic and the count, not a silent loss.
    import threading
    import time
    from rclpy.node import Node
    from gyro_instrument.ros.nodes import RELIABLE_1000, RELIABLE_ALL
    from gyro_instrument.ros.suite import DeliveryError, LockStep
    node = Node("lockstep_test", context=ctx)
    pub = node.create_publisher(m.Clock, "/lockstep_test", RELIABLE_1000)
    got = []
    sub = node.create_subscription(m.Clock, "/lockstep_test", got.append, RELIABLE_ALL, raw=True)
    step = LockStep(ctx, [("/lockstep_test", sub)])
    t0 = time.monotonic()
    while pub.get_subscription_count() < 1:
        time.sleep(0.01)
        assert time.monotonic() - t0 < 10
    data = m.CLOCK_LAYOUT.encode([0, 1, 2, 3])
    pub.publish(data[0])
    later = threading.Timer(0.2, pub.publish, args=(data[1],))
    later.start()
    step.deliver({"/lockstep_test": 2}, timeout_s=10.0)
    later.join()
    assert got == data[:2]
    pub.publish(data[2])
    with pytest.raises(DeliveryError, match="/lockstep_test 1/2"):
        step.deliver({"/lockstep_test": 2}, timeout_s=0.2)
    assert got == data[:2]                           # an incomplete batch runs no callback
    node.destroy_node()


def test_estimator_raw_path_equals_message_path(ctx):
    # Serialized joint states of the simulators' layout are kept as bytes and decoded in bulk;
    # others (here: another joint-name prefix, rclpy's serializer) are decoded one by one. Mixed
    # in one stream, the arrival order and the values are kept: the estimate equals the core's.
    from rclpy.serialization import serialize_message
    from gyro_instrument.recording.joints import joint_streams
    params = [Parameter("scene", value="quet_paris"), Parameter("duration_s", value=40.0)]
    node = EstimatorNode(context=ctx, parameter_overrides=params)
    scene = load_scene("quet_paris", ["duration_s=40.0"])
    truth = simulate_truth(scene)
    t_ns, streams = joint_streams(scene, truth=truth)
    for name, s in streams.items():
        node.buffers[name].DECODE_EVERY = 50           # bytes decoded into arrays along the way too
        raw = m.joint_state_layout(s.names).encode(t_ns, s.position, s.velocity, s.effort)
        other = [f"elsewhere/{n.split('/')[-1]}" for n in s.names]
        for i in range(len(t_ns)):
            if i % 7 == 3:
                node._on_joint_raw(name, serialize_message(m.joint_state(
                    int(t_ns[i]), other, s.position[i], s.velocity[i], s.effort[i])))
            else:
                node._on_joint_raw(name, raw[i])
        assert len(node.buffers[name]) == len(t_ns) and node.buffers[name].last_stamp() == t_ns[-1]
        # kept: what the estimator reads (the measured channels' positions, the last joint's velocity)
        got_t, got_p, got_v = node.buffers[name].arrays()
        k = len(node.insts[name].MEASURED_CHANNELS)
        assert np.array_equal(got_t, t_ns) and np.array_equal(got_p, s.position[:, :k], equal_nan=True)
        assert np.array_equal(got_v, s.velocity[:, -1:], equal_nan=True)
    node._on_joint_raw("pendulum", serialize_message(m.joint_state(0, ["x"], [0.0], [0.0], [0.0])))
    node._on_joint_raw("pendulum", b"\x00\x01\x00\x00 not cdr")
    assert node.rejected == {"pendulum": 2} and len(node.buffers["pendulum"]) == len(t_ns)
    est = to_jsonable(node.finalize())
    core = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
    assert json.dumps(est, sort_keys=True) == json.dumps(core, sort_keys=True)
    node.destroy_node()


def test_bad_parameters_are_refused_and_the_node_stays_up(ctx):
    node = SimulatorNode("gyrocompass_sim", ("plane_gyroscope",), context=ctx,
                         parameter_overrides=[Parameter("scene", value="quet_paris"),
                                              Parameter("duration_s", value=2.0)])
    assert node.samples == 41
    res = node.set_parameters([Parameter("overrides", value=["site.latitude_deg=123"])])[0]
    assert not res.successful and "site.latitude_deg = 123" in res.reason and "[-90, 90]" in res.reason
    res = node.set_parameters([Parameter("scene", value="no_such_scene")])[0]
    assert not res.successful and "shipped scenes" in res.reason
    assert node.publish_step()                       # still up and working
    assert node.publish_steps(100) == 40 and node.publish_steps(100) == 0 and not node.publish_step()
    node.destroy_node()
    bad = SimulatorNode("gyrocompass_sim", ("plane_gyroscope",), context=ctx,
                        parameter_overrides=[Parameter("overrides", value=["instruments.gyro_meridian.inertia_ratio=-1"])])
    assert bad.scene is None and bad.samples == 0 and not bad.publish_step()
    bad.destroy_node()


def test_the_live_estimator_refuses_an_aliased_record_as_the_cli_does(tmp_path):
    # Issue 22: one adequacy mechanism for every estimate. quet_paris sampled at 0.07 Hz holds
    # 25.6 s x 0.07 = 1.79 samples per period of its horizontal gyroscope (< 2.5): the estimator node
    # publishes no number, says the refusal on /diagnostics (recorded), and run_suite raises it (exit 2)
    from gyro_instrument.estimators.adequacy import InadequateData
    bag = str(tmp_path / "alias.mcap")
    with pytest.raises(InadequateData) as exc:
        run_suite("quet_paris", ["sample_rate_hz=0.07"], 300.0, bag)
    assert exc.value.field == "gyro_horizontal.sampling"
    diag = [data for topic, _, _, data in read_messages(bag) if topic == "/diagnostics"]
    assert len(diag) == 1 and b"sampling check of gyro_horizontal" in bytes(diag[0])
    with pytest.raises(InadequateData):        # and a replay of the bag says the same
        replay_bag(bag)
