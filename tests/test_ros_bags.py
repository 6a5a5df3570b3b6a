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


def test_bags_keep_their_qos_and_the_player_offers_the_latched_estimate_back(tmp_path, ctx):
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
    last = {tp: data for f in bag_files(str(d))[0] for tp, _, _, data in read_messages(f)}
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
        assert spin_until(node, lambda: len(got) == 2, 20), got
    finally:
        out = stop(player)
    from rclpy.serialization import deserialize_message
    assert got["lat"].data == deserialize_message(last["/estimator/latitude_rad"], Float64).data
    assert got["heading"].orientation == deserialize_message(last["/gyro_horizontal/heading"], Imu).orientation
    assert "incompatible" not in out.lower(), out
