"""Heading out over real DDS and UDP (issue 24 item 5, issue 37 item 5), on loopback (tools/loopback;
UDP to 127.0.0.1 only).

One suite run of quet_paris's horizontal gyroscope alone (one swing 12.8 s, σ = 1e-4 rad at 20 Hz),
its scale zero at 211.3° (the southern half: the yaw wraps), for 120 s: about nine reversal points.
The suite's recorder (its subscription matched before sim time starts) holds every ``sensor_msgs/Imu``
the estimator published on ``/gyro_horizontal/heading``: from the first swing on at 10 Hz of sim time
(issue 37: a heading a navigation stack can live on), then the final estimate; an independent
subscriber (its own rclpy context, TRANSIENT_LOCAL: it may match the estimator after its first
messages under load) gets at least the last; a UDP socket on 127.0.0.1, read while the suite runs,
gets the ``$HEHDT`` sentences, parsed by pynmea2.

References, each independent of the code under test: scipy's ``Rotation`` (where the quaternion
sends the body's forward axis; a compass azimuth is the ENU direction (sin A, cos A, 0)); the scene's
mount azimuth; Imu.msg's covariance conventions. Tolerances: the headings are within 4 σ of the truth
(σ the message's own, from its covariance: a 4-σ miss of a Gaussian has probability 6e-5); a written
heading within half its last decimal plus 4 σ of the value.
"""

import contextlib
import math
import socket
import threading
import time

import pynmea2
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu

from gyro_instrument.core.errors import SceneError
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros.suite import RunOptions, run_suite

pytestmark = pytest.mark.ros

MOUNT_DEG = 211.3
SCENE = ["instruments.gyro_meridian=null", "instruments.pendulum=null",
         f"instruments.gyro_horizontal.mount_azimuth_deg={MOUNT_DEG}", "seed=11"]
DURATION_S = 120.0
LATITUDE_DEG = 48.8462           # quet_paris


def azimuth_of(msg) -> float:
    """Compass azimuth (deg, [0, 360)) of the body's forward axis, by scipy (scalar-last, as the message)."""
    q = msg.orientation
    fwd = Rotation.from_quat([q.x, q.y, q.z, q.w]).apply([1.0, 0.0, 0.0])
    return math.degrees(math.atan2(fwd[0], fwd[1])) % 360.0


def miss_deg(a, b) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


@pytest.fixture(scope="module")
def heading_run(tmp_path_factory):
    got = []
    qos = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

    def listener(ctx):
        node = rclpy.create_node("heading_listener", context=ctx)
        node.create_subscription(Imu, "/gyro_horizontal/heading", got.append, qos)
        return node
    bag = str(tmp_path_factory.mktemp("heading") / "h.mcap")
    with spinning(listener):
        with NmeaListener() as nmea:
            result, stats = run_suite("quet_paris", SCENE, DURATION_S, bag, RunOptions(nmea_udp=nmea.address))
        wait_until(lambda: got)
        time.sleep(0.2)
    sentences = nmea.sentences
    recorded = [deserialize_message(data, Imu) for topic, _, _, data in read_messages(bag)
                if topic == "/gyro_horizontal/heading"]
    return result, stats, recorded, sentences, bag, list(got)


@contextlib.contextmanager
def spinning(make_node):
    """A listener beside a suite run: an rclpy context of its own, the node ``make_node(ctx)`` spun in a
    thread while the body runs; stopped, destroyed and shut down after (yields the node)."""
    ctx = rclpy.Context()
    rclpy.init(context=ctx)
    node = make_node(ctx)
    ex = SingleThreadedExecutor(context=ctx)
    ex.add_node(node)
    stop = threading.Event()
    spinner = threading.Thread(target=lambda: [ex.spin_once(timeout_sec=0.01) for _ in iter(stop.is_set, True)])
    spinner.start()
    try:
        yield node
    finally:
        stop.set()
        spinner.join()
        node.destroy_node()
        rclpy.shutdown(context=ctx)


def wait_until(condition, timeout_s=10.0) -> bool:
    """Poll ``condition()`` every 50 ms until true or ``timeout_s`` passed (the listener's thread fills it
    after the run returns: its last messages are still in flight); returns whether it came true."""
    t0 = time.monotonic()
    while not condition():
        if time.monotonic() - t0 >= timeout_s:
            return False
        time.sleep(0.05)
    return True


class NmeaListener:
    """A UDP socket on loopback and a thread collecting its sentences while a suite runs (the suite sends
    10 sentences a second of sim time, faster than real time: read as they come, with a 4 MB buffer, or
    they overflow it): ``with NmeaListener() as nmea: run_suite(..., RunOptions(nmea_udp=nmea.address))``,
    then ``nmea.sentences`` (str, in arrival order)."""

    def __enter__(self) -> "NmeaListener":
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        self.udp.bind(("127.0.0.1", 0))
        self.udp.settimeout(0.2)
        self.address = f"127.0.0.1:{self.udp.getsockname()[1]}"
        self.sentences, self._done = [], threading.Event()
        self._reader = threading.Thread(target=self._read)
        self._reader.start()
        return self

    def _read(self) -> None:
        while True:
            try:
                self.sentences.append(self.udp.recv(4096).decode("ascii"))
            except socket.timeout:
                if self._done.is_set():
                    return

    def __exit__(self, *exc) -> None:
        self._done.set()
        self._reader.join()
        self.udp.close()


def stamp_s(msg) -> float:
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


def test_heading_converges_on_the_mount_azimuth(heading_run):
    result, stats, msgs = heading_run[:3]
    truth = MOUNT_DEG
    for msg in msgs:
        sigma_deg = math.degrees(math.sqrt(msg.orientation_covariance[8]))
        assert miss_deg(azimuth_of(msg), truth) < 4 * sigma_deg
        assert msg.header.frame_id == "gyro_horizontal_scale"
    live = [math.sqrt(m.orientation_covariance[8]) for m in msgs[:-1]]
    # the covariance of what is known so far: it shrinks as the record grows (a refit's σ may exceed
    # the last by the change of its linearisation point, a few per cent at most), by far over the run
    assert all(b <= a * 1.05 for a, b in zip(live, live[1:]))
    assert live[-1] < live[0] / 10
    # the last message is the final estimate's north block (the fit): its azimuth and σ
    final, block = msgs[-1], result["north"]
    assert azimuth_of(final) == pytest.approx(block["mount_azimuth_deg"], abs=1e-9)
    assert math.sqrt(final.orientation_covariance[8]) == pytest.approx(math.radians(block["sigma_arcsec"] / 3600),
                                                                        rel=1e-9)


def test_heading_from_the_first_swing_at_10_hz_of_sim_time(heading_run):
    """issue 37: from the first swing (12.8 s, the instrument's predicted swing duration; a fit is
    tried every half swing, so the first heading comes at one to one and a half swings) at 10 Hz
    of the node's clock (sim time, the stamps): every 2nd sample of the 20 Hz record."""
    msgs = heading_run[2][:-1]
    epoch_s = 1e9                                          # the simulation epoch (core.scene.EPOCH_NS)
    assert stamp_s(msgs[0]) - epoch_s <= 1.5 * 12.8 + 0.05
    gaps = [round(stamp_s(b) - stamp_s(a), 6) for a, b in zip(msgs, msgs[1:])]
    assert max(gaps) <= 0.1 + 1e-6 and min(gaps) >= 0.1 - 1e-6
    assert stamp_s(msgs[-1]) - epoch_s >= DURATION_S - 0.1 - 1e-6


def test_imu_fields_follow_rep_103_145_and_imu_msg(heading_run):
    msgs = heading_run[2]
    for msg in msgs:
        w = msg.angular_velocity
        assert msg.angular_velocity_covariance[0] == -1.0                      # not provided: not measured
        assert (w.x, w.y, w.z) == (0.0, 0.0, 0.0)
        assert msg.linear_acceleration_covariance[0] == -1.0                   # not provided
        assert msg.orientation_covariance[0] > 0 and msg.orientation_covariance[8] > 0
        assert msg.header.stamp.sec > 1_000_000_000                             # sim time from the epoch


def test_nmea_hehdt_sentences_parse_and_match_the_imu(heading_run):
    _, _, msgs, sentences = heading_run[:4]
    assert len(sentences) == len(msgs)            # one datagram per heading published
    for text, msg in zip(sentences, msgs):
        assert text.endswith("\r\n")
        s = pynmea2.parse(text.strip(), check=True)
        assert s.sentence_type == "HDT" and s.talker == "HE" and s.hdg_true == "T"
        sigma_deg = math.degrees(math.sqrt(msg.orientation_covariance[8]))
        assert miss_deg(float(s.heading), azimuth_of(msg)) <= 0.0005 + 1e-9
        assert miss_deg(float(s.heading), MOUNT_DEG) < 4 * sigma_deg + 0.0005


def test_an_independent_subscriber_gets_the_same_messages(heading_run):
    _, stats, msgs, _, _, listened = heading_run
    assert len(msgs) == stats["recorded"]["/gyro_horizontal/heading"]
    # what the independent subscriber got is the tail of what was published, the final estimate last
    assert 1 <= len(listened) <= len(msgs)
    tail = msgs[len(msgs) - len(listened):]
    for a, b in zip(listened, tail):
        assert (a.header.stamp.sec, a.header.stamp.nanosec) == (b.header.stamp.sec, b.header.stamp.nanosec)
        assert list(a.orientation_covariance) == list(b.orientation_covariance)
        assert (a.orientation.z, a.orientation.w) == (b.orientation.z, b.orientation.w)


def test_a_bad_nmea_target_is_refused_before_any_node_starts():
    with pytest.raises(SceneError, match="--nmea-udp"):
        run_suite("quet_paris", SCENE, 10.0, options=RunOptions(nmea_udp="127.0.0.1:70000"))
