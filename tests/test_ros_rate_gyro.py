"""The rate gyro through a real ROS run (issue 35 item 3), on loopback (tools/loopback).

One suite run of ``rate_gyro_two_position`` for 300 s (two sequences of its two positions at 20 Hz):
the recorder's bag holds the joint states (``<gyro>/sensitive_axis`` velocity = the measured rate,
rad/s) and one ``sensor_msgs/Imu`` on ``/mems/heading`` (the final estimate's north; no live tracker).
References: ``estimate`` of the same scene and seed in the same process (the draws are the same
doubles: equal to the last bit), scipy's ``Rotation`` for the heading's yaw (a compass azimuth is the
ENU direction (sin A, cos A, 0)).
"""

import math

import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu, JointState

from gyro_instrument.estimators.measure import measure, simulate_truth
from gyro_instrument.estimators.pipeline import estimate_records
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.recording.replay import replay_bag
from gyro_instrument.ros.suite import run_suite
from gyro_instrument.scenes import load_scene

pytestmark = pytest.mark.ros

SCENE, DURATION_S = "rate_gyro_two_position", 300.0


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    bag = str(tmp_path_factory.mktemp("rate_gyro") / "r.mcap")
    result, _ = run_suite(SCENE, [], DURATION_S, bag)
    scene = load_scene(SCENE, [f"duration_s={DURATION_S!r}"])
    truth = simulate_truth(scene)
    return result, bag, estimate_records(scene, truth[1], measure(scene, truth)), truth


def test_run_replay_and_estimate_agree(run):
    result, bag, est, _ = run
    rep = replay_bag(bag)
    for r in (result, rep):
        assert r["north"]["instrument"] == "mems"
        assert r["north"]["mount_azimuth_deg"] == est["north"]["mount_azimuth_deg"]
        assert r["north"]["sigma_arcsec"] == est["north"]["sigma_arcsec"]


def test_the_measured_rate_is_the_sensitive_axis_joint_velocity(run):
    _, bag, _, truth = run
    msgs = [deserialize_message(d, JointState) for topic, _, _, d in read_messages(bag) if topic == "/mems/joint_states"]
    assert [n for n in msgs[0].name] == ["mems/table", "mems/sensitive_axis"]
    rate = np.array([m.velocity[1] for m in msgs])
    index = np.array([m.position[0] for m in msgs])
    cols = truth[2]["mems"].columns
    assert np.array_equal(index, cols["index"])                          # the encoder is read exactly
    # the measured rate scatters about the true one by the gyro's noise: white ARW/sqrt(dt) = 0.09 deg/sqrt(h)
    # / sqrt(0.05 s) = 1.171e-4 rad/s per sample (the Gauss-Markov's 6.3e-6 adds 0.15 %); over 6001
    # samples the std's own scatter is 0.9 %: 5 % is > 5 of it
    resid = rate - cols["rate"]
    assert abs(np.std(resid) / 1.1708e-4 - 1.0) < 0.05


def _azimuth_deg(imu) -> float:
    """The mount azimuth an Imu's orientation carries (its body x axis, clockwise from north in ENU)."""
    q = imu.orientation
    fwd = Rotation.from_quat([q.x, q.y, q.z, q.w]).apply([1.0, 0.0, 0.0])
    return math.degrees(math.atan2(fwd[0], fwd[1])) % 360.0


def test_heading_imu_live_then_the_final_north(run):
    """The kind's live tracker (RateNorthLive) publishes on /mems/heading once per sequence of positions
    (2 x (140 + 10) s = 300 s: once, at the record's 6000th sample), then the final estimate's block."""
    result, bag, _, truth = run
    imus = [deserialize_message(d, Imu) for topic, _, _, d in read_messages(bag) if topic == "/mems/heading"]
    assert len(imus) == 2
    live, final = imus
    assert _azimuth_deg(final) == pytest.approx(result["north"]["mount_azimuth_deg"], abs=1e-9)
    assert math.sqrt(final.orientation_covariance[8]) == pytest.approx(
        math.radians(result["north"]["sigma_arcsec"] / 3600.0), rel=1e-9)
    # the live value: the fit of all but the last sample, so the final's to well within its sigma (one
    # sample of 6001 moves it by ~1/6000 of sigma); 0.1 sigma is far above that, far below a wrong fit
    sigma_deg = result["north"]["sigma_arcsec"] / 3600.0
    d = (_azimuth_deg(live) - _azimuth_deg(final) + 180.0) % 360.0 - 180.0
    assert abs(d) < 0.1 * sigma_deg
    stamp = lambda m: m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec         # noqa: E731
    assert stamp(live) <= stamp(final)
