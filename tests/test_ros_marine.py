"""The ship's gyrocompass's node over real DDS and UDP (issue 39 item 5), on loopback (tools/loopback;
UDP to 127.0.0.1 only).

Two suite runs of the shipped ``marine_gyrocompass`` scene (a ship steaming north at 20 kn from 45° N):

- *sailing*: both compasses switched on 20° off north, 10 Hz for 1200 s, the Sperry's NED heading on
  and its ``$HEHDT`` sent to a UDP socket on 127.0.0.1: the Imu as robot_localization reads it (REP-103
  ENU yaw = 90° − heading, a normalised quaternion, the frame, Imu.msg's covariance conventions), the
  NED twin (yaw = heading), ≥ 10 Hz of headings and ≥ 1 Hz of statuses in sim time, the sentences
  parsed by pynmea2; an independent subscriber (its own context) hears the heading and the statuses.
- *settling*: the Sperry alone at 1 Hz for 7700 s, switched on near its settle point (−0.45° east of
  north: the damping error 1.43° and the speed error −1.88° at 45° N, 20 kn north, compass.py /
  the scene's comment): its state turns ``settled`` where ISO 22090-1 §3.10's criterion says so,
  recomputed here from the simulated error column (no code of the node).

References independent of the code under test: scipy's ``Rotation`` (where the quaternion sends the
body's forward axis), rclpy's own CDR decoder (``deserialize_message``) for every message read from
the bag, pynmea2 for the sentences, the simulated ``heading_error`` column (the instrument's, before
any measurement) and ISO 22090-1 §3.10–3.12's definitions (nippon.zaidan.info/seikabutsu/2000/00393/
contents/003.htm).
"""

import json
import math

import numpy as np
import pynmea2
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu, JointState

from gyro_instrument.estimators.pipeline import simulate_truth
from gyro_instrument.recording.bag_scan import scan_bag
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros.suite import RunOptions, run_suite
from gyro_instrument.scenes import load_scene
from test_ros_heading import NmeaListener, spinning, wait_until

pytestmark = pytest.mark.ros

SAILING = ["sample_rate_hz=10", "instruments.sperry.ned_heading=true", "seed=3"]
SAILING_S = 1200.0
SETTLING = ["sample_rate_hz=1", "instruments.anschutz=null", "instruments.sperry.initial_azimuth_deg=-0.45", "seed=4"]
SETTLING_S = 7700.0
EPOCH_S = 1e9                       # the simulation epoch (core.scene.EPOCH_NS)
#: ISO 22090-1 §3.10: three readings 30 min apart within a band of 0.7°
BAND_DEG, INTERVAL_S = 0.7, 1800.0
#: the scene's sensor noise (marine_gyrocompass.yaml: noise_rad 1e-4)
NOISE_RAD = 1e-4
KEYS = ("state", "settle_point_error_deg", "speed_correction", "latitude_setting_deg")


def stamp_s(msg) -> float:
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec - EPOCH_S


def forward_azimuth_deg(msg, ned=False) -> float:
    """Compass azimuth (deg, [0, 360)) of the body's forward axis in the world frame, by scipy
    (scalar-last, as the message): ENU (x east, y north) or NED (x north, y east)."""
    q = msg.orientation
    fwd = Rotation.from_quat([q.x, q.y, q.z, q.w]).apply([1.0, 0.0, 0.0])
    east, north = (fwd[1], fwd[0]) if ned else (fwd[0], fwd[1])
    return math.degrees(math.atan2(east, north)) % 360.0


def miss_deg(a, b) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def _listen(ctx, got):
    node = rclpy.create_node("marine_listener", context=ctx)
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE)
    node.create_subscription(Imu, "/sperry/heading", lambda m: got.setdefault("imu", []).append(m), qos)
    node.create_subscription(DiagnosticArray, "/diagnostics", lambda m: got.setdefault("diag", []).append(m), qos)
    return node


@pytest.fixture(scope="module")
def sailing(tmp_path_factory):
    live = {}
    bag = str(tmp_path_factory.mktemp("marine") / "sailing.mcap")
    with spinning(lambda ctx: _listen(ctx, live)):
        with NmeaListener() as nmea:
            run_suite("marine_gyrocompass", SAILING, SAILING_S, bag, RunOptions(nmea_udp=nmea.address))
        wait_until(lambda: live.get("imu") and live.get("diag"))
    return _read(bag), nmea.sentences, live, bag


def _read(bag):
    """{topic: [decoded message]} of the bag, by rclpy's own decoder."""
    types = {"/sperry/heading": Imu, "/sperry/heading_ned": Imu, "/anschutz/heading": Imu,
             "/sperry/joint_states": JointState, "/anschutz/joint_states": JointState, "/diagnostics": DiagnosticArray}
    out = {tp: [] for tp in types}
    for topic, _, _, data in read_messages(bag, list(types)):
        out[topic].append(deserialize_message(data, types[topic]))
    return out


def compass_statuses(msgs, name):
    """(stamp s, {key: value}, status) of every status named ``name`` (the compass's) on /diagnostics."""
    out = []
    for arr in msgs:
        for st in arr.status:
            if st.name == name:
                out.append((stamp_s(arr), {kv.key: kv.value for kv in st.values}, st))
    return out


def test_the_imu_reads_as_robot_localization_expects(sailing):
    msgs = sailing[0]
    for name in ("sperry", "anschutz"):
        imu, joints = msgs[f"/{name}/heading"], msgs[f"/{name}/joint_states"]
        assert len(imu) == len(joints) == int(SAILING_S * 10) + 1
        for m, j in zip(imu, joints):
            assert m.header.frame_id == f"{name}_body" and m.header.stamp == j.header.stamp
            q = np.array([m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w])
            assert abs(np.linalg.norm(q) - 1.0) < 1e-12
            # REP-103: yaw = 90° − heading, the heading the compass reads (its joint state, in rad)
            assert miss_deg(forward_azimuth_deg(m), math.degrees(j.position[0])) < 1e-9
            cov = np.array(m.orientation_covariance).reshape(3, 3)
            assert np.array_equal(cov, cov.T) and np.all(np.diag(cov) > 0)
            # Imu.msg: element 0 = −1 for what is not provided (a gyrocompass reads no rate, no acceleration)
            assert m.angular_velocity_covariance[0] == -1.0 and m.linear_acceleration_covariance[0] == -1.0
        # the covariance is the compass's error estimate: the true error (the ship steams north, course 0;
        # the reading's error is its heading) stays within 2 σ (readout.py: within 1.3 σ on these compasses)
        sig = np.array([math.sqrt(m.orientation_covariance[8]) for m in imu])
        err = np.array([math.remainder(j.position[0], 2 * math.pi) for j in joints])
        assert np.all(np.abs(err) <= 2 * sig)
        assert sig[0] > math.radians(10) and sig[-1] < sig[0]           # large while settling from 20°


def test_the_ned_twin_reads_yaw_equal_to_heading(sailing):
    msgs = sailing[0]
    ned, enu = msgs["/sperry/heading_ned"], msgs["/sperry/heading"]
    assert len(ned) == len(enu) and "/anschutz/heading_ned" not in {tp for tp, *_ in read_messages(sailing[3])}
    for a, b in zip(ned, enu):
        assert a.header.frame_id == "sperry_body_ned" and a.header.stamp == b.header.stamp
        assert miss_deg(forward_azimuth_deg(a, ned=True), forward_azimuth_deg(b)) < 1e-9
        assert a.orientation_covariance[8] == b.orientation_covariance[8]


def test_heading_at_10_hz_and_state_at_1_hz_of_sim_time(sailing):
    msgs, _, live, bag = sailing
    stamps = np.array([stamp_s(m) for m in msgs["/sperry/heading"]])
    assert np.all(np.abs(np.diff(stamps) - 0.1) < 1e-6)                       # 10 Hz of sim time
    for name in ("sperry", "anschutz"):
        st = compass_statuses(msgs["/diagnostics"], name)
        t = np.array([s[0] for s in st])
        assert t[0] == 0.0 and np.all(np.abs(np.diff(t) - 1.0) < 1e-6) and len(t) == int(SAILING_S) + 1
        for _, values, status in st:
            assert set(KEYS) <= set(values) and status.hardware_id == "gyro_instrument/marine_gyrocompass"
            # 20 min from 20° off: ISO 22090-1 §3.10 needs an hour of readings at least
            assert values["state"] == "settling" and status.level == DiagnosticStatus.WARN and values["settle_point_error_deg"] == "nan"
            assert values["speed_correction"] == "true"
        # the latitude input follows the track (latitude_setting_deg: track): 20 kn north for t s
        lat = [float(v["latitude_setting_deg"]) for _, v, _ in st]
        assert lat[0] == pytest.approx(45.0, abs=1e-9) and lat[-1] > lat[0]
    # heard by an independent subscriber over DDS, decoded by rclpy
    assert live["imu"][0].header.frame_id == "sperry_body"
    assert any(st.name == "sperry" for arr in live["diag"] for st in arr.status)
    state = scan_bag(bag).metadata_record("gyro_instrument_status")["state"]
    assert state == "complete"


def test_hehdt_sentences_match_the_heading(sailing):
    msgs, sentences = sailing[0], sailing[1]
    headings = [math.degrees(j.position[0]) % 360.0 for j in msgs["/sperry/joint_states"]]
    # one sentence per sample at 10 Hz (UDP may drop a datagram on a loaded machine: most arrive)
    assert 0.9 * len(headings) <= len(sentences) <= len(headings)
    k = 0
    for text in sentences:
        msg = pynmea2.parse(text.strip(), check=True)
        assert msg.sentence_type == "HDT" and msg.talker == "HE" and msg.hdg_true == "T"
        value = float(msg.heading)
        # in order: the next heading that rounds to it (1 decimal: within 0.05° + rounding)
        while k < len(headings) and miss_deg(value, headings[k]) > 0.05 + 1e-9:
            k += 1
        assert k < len(headings), text
        k += 1


@pytest.fixture(scope="module")
def settling(tmp_path_factory):
    bag = str(tmp_path_factory.mktemp("marine") / "settling.mcap")
    run_suite("marine_gyrocompass", SETTLING, SETTLING_S, bag)
    scene = load_scene("marine_gyrocompass", SETTLING + [f"duration_s={SETTLING_S}"])
    t, _, sims = simulate_truth(scene)
    return _read(bag), np.asarray(t), np.degrees(sims["sperry"].columns["heading_error"])


def _first_settled(t, err_deg, band_deg):
    """ISO 22090-1 §3.10 on a record sampled evenly (30 min a whole number of samples): the first t with
    e(t), e(t − 30 min), e(t − 60 min) within a band."""
    k = int(round(INTERVAL_S / (t[1] - t[0])))
    rows = np.vstack([err_deg[2 * k:], err_deg[k:-k], err_deg[:-2 * k]])
    ok = np.flatnonzero(rows.max(axis=0) - rows.min(axis=0) <= band_deg)
    return t[2 * k + ok[0]] if ok.size else None


def test_state_turns_settled_where_iso_22090_says(settling):
    msgs, t, err = settling
    st = compass_statuses(msgs["/diagnostics"], "sperry")
    first = next(s for s in st if s[1]["state"] == "settled")
    t_node = first[0]
    # the node reads noisy readings (σ 1e-4 rad): its crossing lies between the noise-free record's
    # crossings of a band narrowed and widened by 4 σ of the difference of two readings (√2 σ)
    m = math.degrees(4 * math.sqrt(2) * NOISE_RAD)
    assert _first_settled(t, err, BAND_DEG + m) <= t_node <= _first_settled(t, err, BAND_DEG - m)
    assert 3600.0 < t_node < SETTLING_S - 1200.0
    assert float(first[1]["settling_time_s"]) == pytest.approx(t_node)
    for ts, values, status in st:
        assert values["state"] == ("settled" if ts >= t_node else "settling")
        assert status.level == (DiagnosticStatus.OK if ts >= t_node else DiagnosticStatus.WARN)
    # ISO 22090-1 §3.11–3.12: readings every 20 min after settling, their mean less the true heading
    after = [(ts, v) for ts, v, _ in st if ts >= t_node + 1200.0]
    n = int((SETTLING_S - t_node) // 1200.0)
    want = np.mean([np.interp(t_node + 1200.0 * (j + 1), t, err) for j in range(n)])
    assert after[-1][1]["settle_point_readings"] == str(n)
    # the node's readings carry the noise (the mean of n: 4 σ/√n, σ 1e-4 rad) beside the interpolation
    assert float(after[-1][1]["settle_point_error_deg"]) == pytest.approx(want, abs=math.degrees(4 * NOISE_RAD))
    assert all(v["settle_point_error_deg"] == "nan" for ts, v, _ in st if ts < t_node + 1200.0)


def test_the_shipped_compasses_settle_within_six_hours(tmp_path):
    """The shipped scene (6 h, switched on 20° off north at 20 kn; read every 10 s: 0.1 Hz): both compasses
    settle within ISO 22090-1 §5.2's 6 h (issue 39), where §3.10 recomputed on the simulated error
    says (10 s samples: the readings 30 min apart are samples; the same noise margin as above)."""
    bag = str(tmp_path / "shipped.mcap")
    run_suite("marine_gyrocompass", ["sample_rate_hz=0.1"], None, bag)
    msgs = _read(bag)["/diagnostics"]
    t, _, sims = simulate_truth(load_scene("marine_gyrocompass", ["sample_rate_hz=0.1"]))
    m = math.degrees(4 * math.sqrt(2) * NOISE_RAD)
    for name in ("sperry", "anschutz"):
        err = np.degrees(sims[name].columns["heading_error"])
        st = compass_statuses(msgs, name)
        t_node = next(ts for ts, v, _ in st if v["state"] == "settled")
        assert _first_settled(np.asarray(t), err, BAND_DEG + m) <= t_node <= _first_settled(np.asarray(t), err,
                                                                                            BAND_DEG - m)
        assert t_node < 6 * 3600.0 and st[-1][1]["state"] == "settled"


def late_in_file(bag):
    """Topics of the messages written after a later log time, in file order (mcap's own reader)."""
    from mcap.records import Channel, Message
    from mcap.stream_reader import StreamReader
    channels, out, last = {}, [], -1
    with open(bag, "rb") as fh:
        for rec in StreamReader(fh).records:
            if isinstance(rec, Channel):
                channels[rec.id] = rec.topic
            elif isinstance(rec, Message):
                if rec.log_time < last:
                    out.append(channels[rec.channel_id])
                last = max(last, rec.log_time)
    return out


def test_the_separate_node_route_records_the_compass(tmp_path):
    """``python -m gyro_instrument.ros.launch``'s route: the marine_gyrocompass node started as its own
    process beside the recorder and the estimator; the bag complete with the compass's topics."""
    from gyro_instrument.ros.launch import launch
    bag = str(tmp_path / "route.mcap")
    res = launch("marine_gyrocompass", bag, overrides=["sample_rate_hz=10", "instruments.sperry.ned_heading=true"],
                 duration_s=60.0, timeout_s=120, log_dir=str(tmp_path))
    assert res["returncodes"] == {"recorder": 0, "estimator": 0, "marine_gyrocompass": 0}, res["logs"]
    status = scan_bag(bag).metadata_record("gyro_instrument_status")
    counts = json.loads(status["topics"])
    assert status["state"] == "complete"
    # /diagnostics is not one of the recorder's sample topics (it holds those until every one reached a
    # stamp): a status that arrives after later samples were written is logged at its own stamp and
    # counted late (msg_docs/topics.md); the headings are sample topics, held for order: never late
    assert set(late_in_file(bag)) <= {"/diagnostics"}
    for topic in ("/sperry/heading", "/sperry/heading_ned", "/anschutz/heading"):
        assert counts[topic] == [601, 601]
    # one status a second of sim time from the compass node, one from the estimator's estimate
    assert counts["/diagnostics"][0] == 61 + 1
