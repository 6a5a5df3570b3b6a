"""Issue 37, the bag and node-control half: separate processes on real DDS, loopback only (conftest.py).

1. the player never dies of back-pressure: a subscriber that sleeps in its callback and one that is
   SIGSTOPped get every message (the player waits, logged), and its summary counts honestly;
2. parameters are idempotent: a set of the current value changes nothing; a real change restarts
   every simulator of the run together and the recorder starts one new file for all;
3. bags keep their QoS: the recorder writes the publishers' offered QoS (read back by rosbags), the
   player offers it back, so a TRANSIENT_LOCAL subscriber gets the latched estimate and heading;
4. a full disk is a failure, said so (metadata.yaml and the MCAP summary agree with the files, status
   ``incomplete`` with the reason, non-zero exit);
7. the recorder's ``~/pause``, ``~/resume``, ``~/split`` services; every node's ``/diagnostics``.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rclpy.node import Node

from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.mcap_io import BagWriter
from tests.test_ros_day import _tmpfs_available  # noqa: E402  (a small tmpfs in a mount namespace)

pytestmark = pytest.mark.ros
BIN = Path(sys.executable).parent

#: a subscriber process: argv name, sleep per message (s; negative: SIGSTOP itself at the first
#: message, as a debugger or Ctrl-Z would), history depth (0: KEEP_ALL), messages to wait for, longest
#: wait (s; and 3 s of spinning without a message once one came); prints "ready" once subscribed, then "<received> <distinct> <in order>" at the end
SUBSCRIBER = r'''
import os, signal, sys, time, rclpy
from rclpy.node import Node
from rclpy.qos import QoSProfile, HistoryPolicy, ReliabilityPolicy
from sensor_msgs.msg import JointState
name, sleep_s, depth, want = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
rclpy.init()
n = Node(name)
qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE) if depth \
    else QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
got = []
def cb(msg):
    got.append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
    if sleep_s > 0:
        time.sleep(sleep_s)
    elif sleep_s < 0 and len(got) == 1:
        os.kill(os.getpid(), signal.SIGSTOP)
n.create_subscription(JointState, "/pendulum/joint_states", cb, qos)
print("ready", flush=True)
t0 = time.monotonic()
idle = 0
while len(got) < want and time.monotonic() - t0 < float(sys.argv[5]) and idle < 60:
    k = len(got)
    rclpy.spin_once(n, timeout_sec=0.05)
    idle = idle + 1 if got and len(got) == k else 0
print(len(got), len(set(got)), got == sorted(got), flush=True)
'''


def start(exe, *ros_args):
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM="0", PYTHONUNBUFFERED="1")
    return subprocess.Popen([str(BIN / exe), "--ros-args", *ros_args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True, env=env)


def read_until(p, text, timeout):
    """Lines of ``p``'s output up to the first holding ``text`` (all of them if it exits first)."""
    import selectors
    sel = selectors.DefaultSelector()
    sel.register(p.stdout, selectors.EVENT_READ)
    lines, t0 = [], time.monotonic()
    while time.monotonic() - t0 < timeout:
        if sel.select(timeout=0.1):
            line = p.stdout.readline()
            if not line:
                break
            lines.append(line)
            if text in line:
                break
    return "".join(lines)


def stop(p, sig=signal.SIGINT, timeout=30):
    if p.poll() is None:
        p.send_signal(sig)
    out, _ = p.communicate(timeout=timeout)
    return out


def spin_until(node, cond, timeout):
    from rclpy.executors import SingleThreadedExecutor
    ex = SingleThreadedExecutor(context=node.context)
    ex.add_node(node)
    t0 = time.monotonic()
    try:
        while not cond():
            ex.spin_once(timeout_sec=0.05)
            if time.monotonic() - t0 > timeout:
                return False
        return True
    finally:
        ex.remove_node(node)


def joint_bag(path, n):
    """A bag of ``n`` JointStates on /pendulum/joint_states at 20 Hz (no clock: the player adds it)."""
    from rclpy.serialization import serialize_message
    from gyro_instrument.recording.qos import profile, profiles_yaml
    from gyro_instrument.ros import messages as m
    w = BagWriter(str(path))
    w.add_topic("/pendulum/joint_states", "sensor_msgs/msg/JointState", profiles_yaml([profile()]))
    for i in range(n):
        t = i * 50_000_000
        w.write("/pendulum/joint_states", EPOCH_NS + t,
                serialize_message(m.joint_state(t, ["pendulum/a"], [0.001 * i], [0.0], [0.0])))
    w.close()
    return str(path)


# ---- 1. the player never dies of back-pressure --------------------------------------------------

#: Fast DDS refuses a RELIABLE / KEEP_ALL write when 5000 samples of the writer's history are not
#: acknowledged (measured here: the 5001st publish to a SIGSTOPped subscriber raised "cannot publish
#: data"); 6000 messages fill it while one subscriber is stopped
N_BACKPRESSURE = 6000


def test_player_waits_when_a_write_is_refused_and_loses_nothing(tmp_path, ctx):
    # The short version (the DDS refusal itself, 5000 unacknowledged samples to a stopped subscriber,
    # is the slow test below): the player's publisher refuses 5 writes in a row mid-bag, as Fast DDS
    # does when a RELIABLE / KEEP_ALL subscriber's queue is full; the player logs the wait, tries
    # again at its next ticks, and a KEEP_ALL subscriber gets every message once, in order.
    from rclpy._rclpy_pybind11 import RCLError
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from sensor_msgs.msg import JointState
    from gyro_instrument.ros.nodes import RELIABLE_ALL, PlayerNode
    n = 300
    bag = joint_bag(tmp_path / "j.mcap", n)
    player = PlayerNode(context=ctx, parameter_overrides=[Parameter("bag", value=bag),
                                                          Parameter("real_time_factor", value=0.0)])
    sub = Node("taker", context=ctx)
    got = []
    sub.create_subscription(JointState, "/pendulum/joint_states",
                            lambda msg: got.append(msg.header.stamp.sec * 10 ** 9 + msg.header.stamp.nanosec),
                            RELIABLE_ALL)
    pub = player.pubs["pendulum/joint_states"]
    real, calls = pub.publish, [0]

    def refusing(data):
        calls[0] += 1
        if 100 < calls[0] <= 105:
            raise RCLError("Failed to publish: cannot publish data")
        return real(data)
    pub.publish = refusing
    logs = []
    player.get_logger().warning = lambda text, **kw: logs.append(text)
    player.get_logger().info = lambda text, **kw: logs.append(text)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(player)
    ex.add_node(sub)
    try:
        player.start()
        t0 = time.monotonic()
        while not (player.done and len(got) >= n) and time.monotonic() - t0 < 60:
            ex.spin_once(timeout_sec=0.01)
    finally:
        ex.shutdown()
        player.destroy_node()
        sub.destroy_node()
    assert player.done and calls[0] == n + 5, (calls, logs)
    assert got == [EPOCH_NS + i * 50_000_000 for i in range(n)], len(got)
    assert any(t.startswith("publishing /pendulum/joint_states waits") for t in logs), logs
    assert any(t.startswith("publishing /pendulum/joint_states resumed after") for t in logs), logs
    assert any(f"/taker on /pendulum/joint_states (RELIABLE VOLATILE) {n} of {n} sent while it was matched, " \
               f"all acknowledged" in t for t in logs), logs


@pytest.mark.slow
def test_player_waits_for_a_sleeping_and_a_stopped_subscriber(tmp_path):
    bag = joint_bag(tmp_path / "j.mcap", N_BACKPRESSURE)
    subs = {name: subprocess.Popen([sys.executable, "-c", SUBSCRIBER, name, sleep, depth, str(N_BACKPRESSURE), "60"],
                                   stdout=subprocess.PIPE, text=True, start_new_session=True)
            # 0.2 ms per message: the sleeping one takes ~1.2 s more than the player needs
            for name, sleep, depth in (("sleeper", "0.0002", "0"), ("stopped", "-1", "0"), ("depth10", "0", "10"))}
    for p in subs.values():
        assert p.stdout.readline().strip() == "ready"
    player = start("player", "-p", f"bag:={bag}", "-p", "real_time_factor:=0", "-p", "min_subscribers:=3")
    try:
        # the stopped one stops at its first message; 5000 later the player's writes are refused
        head = read_until(player, "waits", 60)
        assert "publishing /pendulum/joint_states waits" in head and player.poll() is None, head
        time.sleep(1.0)                                   # it keeps waiting (and stays up)
        subs["stopped"].send_signal(signal.SIGCONT)
        out, _ = player.communicate(timeout=60)
        out = head + out
    finally:
        subs["stopped"].send_signal(signal.SIGCONT)
        out = stop(player) if player.poll() is None else out
    got = {name: p.communicate(timeout=90)[0].split() for name, p in subs.items()}
    assert player.returncode == 0, out
    # every message, once, in order, to both KEEP_ALL subscribers
    assert got["sleeper"] == [str(N_BACKPRESSURE), str(N_BACKPRESSURE), "True"], (got, out)
    assert got["stopped"] == [str(N_BACKPRESSURE), str(N_BACKPRESSURE), "True"], (got, out)
    assert "publishing /pendulum/joint_states waits" in out and "resumed after" in out, out
    # honest counts: per subscriber, what was sent while it was matched; the KEEP_LAST one is told
    # apart (the publisher cannot know its depth: the summary says so)
    for name in subs:
        assert f"/{name} on /pendulum/joint_states (RELIABLE VOLATILE) {N_BACKPRESSURE} of {N_BACKPRESSURE} sent " \
               f"while it was matched, all acknowledged" in out, out
    assert "a KEEP_LAST one only those it took before its queue overflowed" in out


# ---- 3. bags keep their QoS ------------------------------------------------------------------------

def _rosbags_qos(path):
    """{topic: [(reliability, durability, history, depth)]} as rosbags reads a bag's QoS (a bag
    directory: metadata.yaml; a bare .mcap: the channels' offered_qos_profiles)."""
    from rosbags.highlevel import AnyReader
    out = {}
    with AnyReader([Path(path)]) as reader:
        for c in reader.connections:
            out[c.topic] = [(q.reliability.name, q.durability.name, q.history.name, q.depth)
                            for q in c.ext.offered_qos_profiles]
    return out


#: a looping player's state: playing, or between two passes waiting for the acknowledgements
PLAYING = ("playing", "all played; waiting for every subscriber to acknowledge")


def test_bags_keep_their_qos_and_the_player_offers_the_latched_estimate_back(tmp_path, ctx):
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import Imu
    from std_msgs.msg import Float64
    from gyro_instrument.ros.suite import run_suite
    from gyro_instrument.recording.bag_layout import bag_files
    from gyro_instrument.recording.mcap_io import read_messages
    d = tmp_path / "q"
    run_suite("quet_paris", ["seed=5"], 60.0, f"{d}/")
    latched = [("RELIABLE", "TRANSIENT_LOCAL", "KEEP_LAST", 1)]       # the estimator's LATCHED profile
    samples = [("RELIABLE", "VOLATILE", "KEEP_LAST", 1000)]           # the suite's RELIABLE_1000
    for path in (d, d / "q_0.mcap"):           # metadata.yaml, and the file's channels
        qos = _rosbags_qos(path)
        assert qos["/estimator/latitude_rad"] == latched and qos["/gyro_horizontal/heading"] == latched, qos
        assert qos["/diagnostics"] == latched and qos["/pendulum/joint_states"] == samples, qos
        assert qos["/clock"] == samples, qos
    played = [(tp, data) for f in bag_files(str(d))[0] for tp, _, _, data in read_messages(f)]
    last = dict(played)
    # played back: a TRANSIENT_LOCAL subscriber that starts after the estimate was played gets it
    player = start("player", "-p", f"bag:={d}", "-p", "real_time_factor:=0", "-p", "min_subscribers:=0",
                   "-p", "loop:=true")
    try:
        head = read_until(player, "looping", 60)
        assert "looping" in head, head
        node = Node("late_navigator", context=ctx)
        tl = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                        durability=DurabilityPolicy.TRANSIENT_LOCAL)
        got = {}
        node.create_subscription(Float64, "/estimator/latitude_rad", lambda msg: got.setdefault("lat", msg), tl)
        node.create_subscription(Imu, "/gyro_horizontal/heading", lambda msg: got.setdefault("heading", msg), tl)
        # and the player's own state (its liveness status, beside the bag's /diagnostics)
        # (the latest: the one latched when the subscription matched may be from before the play)
        node.create_subscription(DiagnosticArray, "/diagnostics", lambda msg: [
            got.__setitem__("player", st) for st in msg.status if st.name == "gyro_instrument: /player"], tl)
        assert spin_until(node, lambda: len(got) == 3 and got["player"].message in PLAYING, 20), got
    finally:
        out = stop(player)
    from rclpy.serialization import deserialize_message
    assert got["lat"].data == deserialize_message(last["/estimator/latitude_rad"], Float64).data
    # the heading latched when the subscriber came: one of the bag's (the player loops, and a heading
    # is published at each reversal point as well as with the estimate: msg_docs/topics.md)
    headings = [deserialize_message(data, Imu) for tp, data in played if tp == "/gyro_horizontal/heading"]
    assert any(h.header.stamp == got["heading"].header.stamp and h.orientation == got["heading"].orientation
               for h in headings), got["heading"]
    assert "incompatible" not in out.lower(), out
    assert got["player"].hardware_id == "gyro_instrument/node", got["player"]


# ---- 4. a full disk is a failure, said so ------------------------------------------------------------

@pytest.mark.skipif(not _tmpfs_available(), reason="needs root and unshare -m to mount a small tmpfs")
def test_a_recorder_node_on_a_full_disk_fails_and_says_so(tmp_path):
    # The recorder node alone in a private mount namespace whose output directory is a 256 KiB tmpfs;
    # 150 s of foucault_pantheon (~0.6 MB) fill it. The bag directory is copied out before the
    # namespace ends.
    from tests.test_ros_day import check_disk_full_bag
    disk, kept = tmp_path / "disk", tmp_path / "kept"
    disk.mkdir()
    common = ["-p", "scene:=foucault_pantheon", "-p", "duration_s:=150.0"]
    rec_cmd = " ".join([str(BIN / "recorder"), "--ros-args", *common, "-p", f"output:={disk}/bag/",
                        "-p", "stop_when_complete:=true"])
    env = dict(os.environ, RCUTILS_LOGGING_BUFFERED_STREAM="0")
    rec = subprocess.Popen(["unshare", "-m", "sh", "-c", f"mount -t tmpfs -o size=256k tmpfs {disk} && {rec_cmd}; "
                            f"rc=$?; cp -a {disk} {kept}; exit $rc"], stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, start_new_session=True, env=env)
    sim = start("pendulum_sim", *common, "-p", "publish_clock:=true", "-p", "real_time_factor:=0.0",
                "-p", "wait_for:=['recorder']")
    try:
        out, _ = rec.communicate(timeout=120)
    finally:
        sim_out = stop(sim)
        if rec.poll() is None:
            rec.kill()
    assert rec.returncode == 1, out                     # a failure, not a normal end
    assert "No space left on device" in out and "needs" in out, out
    check_disk_full_bag(str(kept / "bag"))
    assert "Traceback" not in out + sim_out, out + sim_out


# ---- 2 and 7. parameters idempotent, a real change restarts the run together; controls, liveness --------

def call(node, srv_type, name, request, timeout=20):
    cli = node.create_client(srv_type, name)
    assert spin_until(node, cli.service_is_ready, timeout), f"{name} not available"
    fut = cli.call_async(request)
    assert spin_until(node, fut.done, timeout), f"{name} did not answer"
    node.destroy_client(cli)
    return fut.result()


def set_params(node, target, **values):
    from rcl_interfaces.msg import Parameter as ParamMsg
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter
    req = SetParameters.Request(parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
    assert all(isinstance(p, ParamMsg) for p in req.parameters)
    return [r.successful for r in call(node, SetParameters, f"/{target}/set_parameters", req).results]


def test_a_service_call_while_not_recording_is_refused_and_logged(ctx):
    # Bad input: the recorder has no output (refused at start-up): ~/pause and ~/split answer
    # success = false with the reason, and the node keeps running.
    from std_srvs.srv import Trigger
    from gyro_instrument.ros.nodes import RecorderNode
    rec = RecorderNode(context=ctx)
    client = Node("operator", context=ctx)
    from rclpy.executors import SingleThreadedExecutor
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(rec)
    ex.add_node(client)
    try:
        for name in ("pause", "split", "resume"):
            cli = client.create_client(Trigger, f"/recorder/{name}")
            fut = cli.call_async(Trigger.Request())
            t0 = time.monotonic()
            while not fut.done() and time.monotonic() - t0 < 20:
                ex.spin_once(timeout_sec=0.05)
            res = fut.result()
            assert res.success is False and res.message.startswith(f"{name} refused: not recording"), res
        assert rec.context.ok() and rec.liveness()[1].startswith("not recording")
    finally:
        ex.shutdown()
        rec.destroy_node()
        client.destroy_node()


def test_parameters_are_idempotent_a_change_restarts_the_run_together_and_the_recorder_is_controlled(
        tmp_path, ctx):
    from diagnostic_msgs.msg import DiagnosticArray
    from rosgraph_msgs.msg import Clock
    from std_srvs.srv import Trigger
    from gyro_instrument.recording.bag_layout import bag_files
    from gyro_instrument.recording.bag_scan import scan_bag
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.ros.launch import write_params
    from gyro_instrument.ros.nodes import RELIABLE_ALL
    from rclpy.qos import DurabilityPolicy, QoSProfile
    # TRANSIENT_LOCAL: each node's state when this subscription matches it (its first, "waiting")
    LATCHED_1000 = QoSProfile(depth=1000, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    bag = tmp_path / "bag"
    params = tmp_path / "params.yaml"
    # quet_paris, 60 s at real-time factor 10: two simulators (gyrocompass_sim owns the clock)
    write_params(str(params), "quet_paris", f"{bag}/", duration_s=60.0, real_time_factor=10.0,
                 sims=["gyrocompass_sim", "pendulum_sim"])
    node = Node("operator", context=ctx)
    ticks, diag = [], []
    node.create_subscription(Clock, "/clock", lambda msg: ticks.append(msg.clock.sec * 10 ** 9 + msg.clock.nanosec),
                             RELIABLE_ALL)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda msg: diag.extend(
        (time.monotonic(), st.name.split("/")[-1], st.level, st.message) for st in msg.status
        if st.hardware_id == "gyro_instrument/node"), LATCHED_1000)
    procs = {n: start(n, "--params-file", str(params)) for n in ("recorder", "estimator", "pendulum_sim",
                                                                   "gyrocompass_sim")}
    try:
        assert spin_until(node, lambda: ticks and ticks[-1] > EPOCH_NS + 10 * 10 ** 9, 60), "run 1 did not start"
        # the current values (a `ros2 param load` of an unchanged dump): nothing restarts; an unknown
        # name is refused, logged with its value, and the node keeps running
        assert set_params(node, "gyrocompass_sim", seed=-1) == [True]
        assert set_params(node, "pendulum_sim", scene="quet_paris", duration_s=60.0, latitude_deg=48.0) == \
            [True, True, False]
        # a real change on a follower: the owner restarts the run and every simulator with it
        assert set_params(node, "pendulum_sim", seed=7) == [True]
        n_before = len(ticks)
        assert spin_until(node, lambda: any(b < a for a, b in zip(ticks[n_before - 1:], ticks[n_before:])), 30)
        assert spin_until(node, lambda: EPOCH_NS + 20 * 10 ** 9 < ticks[-1] < EPOCH_NS + 50 * 10 ** 9, 30)
        assert call(node, Trigger, "/recorder/pause", Trigger.Request()).success
        spin_until(node, lambda: False, 1.0)               # ~10 s of sim time not recorded
        assert call(node, Trigger, "/recorder/resume", Trigger.Request()).success
        res = call(node, Trigger, "/recorder/split", Trigger.Request())
        assert res.success and res.message.startswith("recording continues in bag_run1_1.mcap"), res
        # the run ends: the estimate of run 2 (the recorder, paused, does not complete: stopped below)
        assert spin_until(node, lambda: any(d[1] == "estimator" and d[3] == "settled: estimate published"
                                            and d[0] > time.monotonic() - 1 for d in diag[-20:]), 60)
    finally:
        outs = {n: stop(p) for n, p in procs.items()}
    assert all(p.returncode == 0 for p in procs.values()), outs
    # idempotent: the unchanged values restarted nothing and split nothing: run 1 and run 2 only
    assert "parameters set to the values they had: seed; nothing changes" in outs["gyrocompass_sim"]
    assert "latitude_deg" in outs["pendulum_sim"] and "48.0" in outs["pendulum_sim"]
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith("bag")) == ["bag", "bag_run1"]
    # run 1: one file, closed when the clock went back; run 2: both simulators from t = 0, split in two
    st0 = scan_bag(str(bag / "bag_0.mcap")).metadata_record("gyro_instrument_status")
    assert st0["state"] == "incomplete" and json.loads(st0["restarted"])["continues_in"] == "bag_run1", st0
    files, _ = bag_files(str(tmp_path / "bag_run1"))
    assert [os.path.basename(f) for f in files] == ["bag_run1_0.mcap", "bag_run1_1.mcap"]
    first = {}
    for f in files:
        for tp, _, t, _ in read_messages(f):
            first.setdefault(tp, t)
    assert first["/pendulum/joint_states"] == first["/gyro_horizontal/joint_states"] == first["/clock"] == EPOCH_NS
    st1 = scan_bag(files[-1]).metadata_record("gyro_instrument_status")
    assert int(st1["not_recorded_paused"]) > 0, st1
    # liveness: every node at >= 1 Hz (0.5 s period; the gap bound is loose for a loaded machine)
    for name in ("gyrocompass_sim", "pendulum_sim", "estimator", "recorder"):
        t = [d[0] for d in diag if d[1] == name]
        assert len(t) >= (t[-1] - t[0]) and max(b - a for a, b in zip(t, t[1:])) < 2.0, (name, len(t))
    said = {(d[1], d[3].split(":")[0]) for d in diag}
    # (each node's first state, "waiting for subscribers", is latched depth 1: this subscription sees it
    # only when it matches before the wait ends, which discovery on a loaded machine does not promise)
    for want in [("gyrocompass_sim", "publishing"),
                 ("pendulum_sim", "publishing"), ("recorder", "recording"),
                 ("recorder", "paused (~/resume to record again)"), ("estimator", "collecting samples"),
                 ("estimator", "settled")]:
        assert want in said, (want, sorted(said))


def test_a_runs_last_line_names_the_node_and_the_reason(monkeypatch, capsys):
    # An estimate that fails in the core (not the input): `run` used to end with "the scene could
    # not be loaded by the nodes"; its last line now names the estimator and the error.
    from gyro_instrument.ros.cli import main as ros_main
    from gyro_instrument.ros.nodes import EstimatorNode

    def fails(self):
        raise RuntimeError("the fit's work array could not be allocated")
    monkeypatch.setattr(EstimatorNode, "estimate", fails)
    assert ros_main(["run", "foucault_pantheon", "--duration-s", "5", "--quiet"]) == 3
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("gyro-instrument: estimator: estimation failed: RuntimeError: the fit's work array could not "
                       "be allocated"), err


@pytest.mark.slow
@pytest.mark.parametrize("k", range(5))
def test_a_restarted_run_completes_its_new_file_and_the_recorder_finishes(tmp_path, ctx, k):
    # Item 2 repeated, without the services: a real change on the clock owner mid-run (`ros2 param set
    # /gyrocompass_sim seed 9`); the recorder closes run 1 and records run 2 to one new file, which is
    # complete (every sample of every topic, from both simulators), and finishes by itself.
    from rosgraph_msgs.msg import Clock
    from gyro_instrument.recording.bag_scan import scan_bag
    from gyro_instrument.ros.launch import write_params
    from gyro_instrument.ros.nodes import RELIABLE_ALL
    bag, params = tmp_path / "r.mcap", tmp_path / "params.yaml"
    write_params(str(params), "quet_paris", str(bag), duration_s=60.0, real_time_factor=10.0,
                 sims=["gyrocompass_sim", "pendulum_sim"])
    node = Node("operator", context=ctx)
    ticks = []
    node.create_subscription(Clock, "/clock", lambda msg: ticks.append(msg.clock.sec * 10 ** 9 + msg.clock.nanosec),
                             RELIABLE_ALL)
    procs = {n: start(n, "--params-file", str(params)) for n in ("recorder", "estimator", "pendulum_sim",
                                                                   "gyrocompass_sim")}
    try:
        assert spin_until(node, lambda: ticks and ticks[-1] > EPOCH_NS + 10 * 10 ** 9, 60), "run 1 did not start"
        assert set_params(node, "gyrocompass_sim", seed=9) == [True]
        procs["recorder"].wait(timeout=120)                 # stop_when_complete: run 2 complete
    finally:
        outs = {n: stop(p) for n, p in procs.items()}
    assert procs["recorder"].returncode == 0, outs["recorder"]
    st0 = scan_bag(str(bag)).metadata_record("gyro_instrument_status")
    st1 = scan_bag(str(tmp_path / "r_run1.mcap")).metadata_record("gyro_instrument_status")
    assert st0["state"] == "incomplete" and st1["state"] == "complete", (st0, st1, outs["recorder"])
    assert not (tmp_path / "r_run2.mcap").exists()
