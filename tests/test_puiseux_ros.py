"""The contact point of Puiseux's body on ROS: ``<body>/contact_point`` (geometry_msgs/PointStamped
in the body frame ``<body>_body``, per sample), published by top_sim because the instrument class
declares ``SHOWS_CONTACT_POINT``; real rclpy and DDS on loopback (conftest.py), received by the
recorder node and read back by an independent reader (rosbags)."""

from pathlib import Path

import numpy as np

from gyro_instrument.estimators.pipeline import simulate_truth
from gyro_instrument.ros.suite import run_suite
from gyro_instrument.recording.topics import scene_topics
from gyro_instrument.scenes import build_instruments, load_scene


def test_contact_point_topic_is_declared_by_the_class():
    scene = load_scene("puiseux_spheroid")
    topics = scene_topics(build_instruments(scene))
    assert topics["spheroid/contact_point"] == "geometry_msgs/msg/PointStamped"
    quet = scene_topics(build_instruments(load_scene("quet_paris")))
    assert not any(t.endswith("/contact_point") for t in quet)       # only where the class says so


def test_contact_point_received_over_dds_equals_the_simulated_point(tmp_path):
    # 2 s at 200 Hz: 401 samples, every one delivered (RELIABLE / KEEP_ALL, lock-step) and recorded.
    bag = tmp_path / "spheroid.mcap"
    _, stats = run_suite("puiseux_spheroid", [], 2.0, str(bag))
    n = stats["samples"]
    assert n == 401
    assert stats["published_topics"]["/spheroid/contact_point"] == n == stats["recorded"]["/spheroid/contact_point"]
    from rosbags.highlevel import AnyReader
    with AnyReader([Path(bag)]) as r:
        conns = [c for c in r.connections if c.topic == "/spheroid/contact_point"]
        msgs = [r.deserialize(raw, c.msgtype) for c, _, raw in r.messages(connections=conns)]
    assert len(msgs) == n and {m_.header.frame_id for m_ in msgs} == {"spheroid_body"}
    got = np.array([[m_.point.x, m_.point.y, m_.point.z] for m_ in msgs])
    # float64 on the wire: the published points are the simulated columns, bit for bit
    _, _, sims = simulate_truth(load_scene("puiseux_spheroid", ["duration_s=2"]))
    c = sims["spheroid"].columns
    np.testing.assert_array_equal(got, np.column_stack([c["contact_x"], c["contact_y"], c["contact_z"]]))
    # and they are on the spheroid's surface (semi-axes 0.1, 0.1, 0.2 m): rounding, 1e-12
    assert np.max(np.abs((got[:, 0] ** 2 + got[:, 1] ** 2) / 0.01 + got[:, 2] ** 2 / 0.04 - 1.0)) < 1e-12
    # near the lowest vertex A = (0, 0, -0.2): the tilt stays below 0.05 rad, so |AH| < ρ·0.05 = 2.5 mm
    # (ρ = α²/γ = 0.05 m; sec. I: x = −α² a''/γ)
    assert np.max(np.hypot(got[:, 0], got[:, 1])) < 0.05 * 0.05
