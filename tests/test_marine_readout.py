"""The ship's gyrocompass's live state and heading fields, without ROS (issue 39 item 5):
``instruments/marine_gyrocompass/readout.py`` and ``recording/compass_stream.py``.

References: the closed form of damping in tilt (theory.py, ζ ω0 = (P_d/P_c)(P_c/H)/2, Christou 1983's
linear model); the simulated spiral of a compass damped in azimuth (its integrated equations, not the
linearisation); the estimator's single-message Imu fields (estimators/heading.py, tested against
scipy in test_heading.py); ISO 22090-1 §3.10–3.11 applied by hand to made-up records.
"""

import math

import numpy as np
import pytest
from scipy.signal import find_peaks

from gyro_instrument.estimators.north.heading import imu_fields
from gyro_instrument.instruments.marine_gyrocompass import theory as th
from gyro_instrument.instruments.marine_gyrocompass.readout import Readout, slowest_decay
from gyro_instrument.recording.compass_stream import imu_columns
from gyro_instrument.scenes import build_instruments, load_scene

PIER = ["motion=null", "duration_s=43200", "sample_rate_hz=0.1"]


def compass(name, over=()):
    return build_instruments(load_scene("marine_gyrocompass", PIER + list(over)))[name]


def test_decay_of_damping_in_tilt_is_the_closed_form():
    inst = compass("sperry")
    lam, zeta = slowest_decay(inst)
    k, om, lat = inst.control_per_s(), inst.site.earth_rate_rad_s, inst.site.latitude_rad
    # theory.py: s² + (P_d/H) s + (P_c/H + Ω cos φ) Ω cos φ = 0, Re s = −(P_d/P_c)(P_c/H)/2, |s| = ω0. The
    # closed form drops the element's swing (30 s: (30 s / 84 min)² ~ 3e-5) and linearises about zero tilt,
    # not the settled 0.11° (|s| moves by 1.4e-4, measured): 1e-4 on the rate, 1e-3 on ζ
    assert lam == pytest.approx(inst.p.damping_torque_ratio * k / 2, rel=1e-4)
    assert zeta == pytest.approx(th.damping_ratio_tilt(inst.p.damping_torque_ratio, k, om, lat), rel=1e-3)


def test_decay_of_damping_in_azimuth_is_the_simulated_spiral():
    inst = compass("anschutz")
    lam, _ = slowest_decay(inst)
    t = np.arange(0.0, 43200.0, 10.0)
    err = np.abs(inst.simulate(t).columns["heading_error"])
    peaks, _ = find_peaks(err)
    # the log of the spiral's peaks after the first (the switch-on transient of the oil and the tilt):
    # five peaks, two hours apart; 10 s samples place a peak to 1/200 of a swing: 1 % on the slope
    slope = np.polyfit(t[peaks][1:6], np.log(err[peaks][1:6]), 1)[0]
    assert -slope == pytest.approx(lam, rel=0.01)


def test_no_damping_no_decay():
    lam, _ = slowest_decay(compass("sperry", ["instruments.sperry.damping=none"]))
    assert lam < 1e-12


@pytest.mark.parametrize("heading_deg", [0.0, 45.0, 90.0, 179.9, 180.0, 270.0, 359.99, -10.0])
def test_imu_columns_are_the_estimators_fields(heading_deg):
    h, s = math.radians(heading_deg), math.radians(0.7)
    site = compass("sperry").site
    f = imu_fields(h, s, site)
    cols = imu_columns(np.array([h]), np.array([s]))
    for got, want in zip(cols, (f.orientation_xyzw, f.orientation_covariance, f.angular_velocity_xyz_rad_s,
                                f.angular_velocity_covariance, f.linear_acceleration_xyz_m_s2,
                                f.linear_acceleration_covariance)):
        assert got[0] == pytest.approx(want, abs=1e-15)
    # NED: yaw = heading about the down axis, w >= 0
    q = imu_columns(np.array([h]), np.array([s]), ned=True)[0][0]
    yaw = 2 * math.atan2(q[2], q[3])
    assert math.remainder(yaw - h, 2 * math.pi) == pytest.approx(0.0, abs=1e-12) and q[3] >= 0


def _pushed(err_deg, t, over=()):
    """A Readout on a pier (true heading 0) fed readings = the made-up errors, in blocks of 997 samples."""
    r = Readout(compass("sperry", over))
    e = np.radians(err_deg)
    for k in range(0, t.size, 997):
        r.push(t[k:k + 997], np.mod(e[k:k + 997], 2 * math.pi))
    return r


def test_settled_by_three_readings_30_min_apart_within_0_7_deg():
    t = np.arange(0.0, 12000.0, 1.0)
    # a decaying error: |e(t) − e(t − 3600)| <= 0.7° first when 3 exp(−t/2000)(e^1.8 − 1) <= 0.7,
    # t = 2000 ln(3 (e^1.8 − 1)/0.7) = 6716.6 s (by hand); the readings at t − 30 min lie between
    err = 3.0 * np.exp(-t / 2000.0)
    r = _pushed(err, t)
    want = 2000.0 * math.log(3.0 * (math.exp(1.8) - 1.0) / 0.7)
    assert r.settled_s == pytest.approx(math.ceil(want), abs=1.0)
    assert r.status(r.settled_s - 1.0)["state"] == "settling" and r.status(r.settled_s)["state"] == "settled"
    # ISO 22090-1 §3.11: readings every 20 min after settling; their mean is the settle point's error
    st = r.status(11999.0)
    times = r.settled_s + 1200.0 * np.arange(1, st["settle_point_readings"] + 1)
    assert st["settle_point_readings"] == int((11999.0 - r.settled_s) // 1200.0)
    assert math.degrees(st["settle_point_error_rad"]) == pytest.approx(np.mean(3.0 * np.exp(-times / 2000.0)),
                                                                       rel=1e-9)


def test_never_settled_within_the_first_hour_nor_while_it_swings():
    t = np.arange(0.0, 10000.0, 1.0)
    assert _pushed(np.zeros(3599), t[:3599]).settled_s is None        # three readings need 60 min
    assert _pushed(np.zeros(t.size), t).settled_s == 3600.0
    # a swing of 2° amplitude and 50 min period: readings 30 min apart are 216° of phase apart, and the
    # least spread of three such readings over a whole period (a dense grid, by hand) exceeds 0.7°
    swing = 2.0 * np.sin(2 * math.pi * t / 3000.0)
    x = np.linspace(0.0, 2 * math.pi, 100001)
    rows = [2.0 * np.sin(x - k * 2 * math.pi * 1800.0 / 3000.0) for k in range(3)]
    assert np.min(np.max(rows, axis=0) - np.min(rows, axis=0)) > 0.7
    assert _pushed(swing, t).settled_s is None


def test_sigma_is_the_spiral_envelope_over_the_floor():
    t = np.arange(0.0, 43200.0, 10.0)
    r = _pushed(np.full(t.size, 20.0), t)
    lam, zeta = r.decay_per_s, r.zeta
    sig = r.sigma_rad(t, np.full(t.size, math.radians(45.0)))
    floor = math.radians(0.75) / math.sqrt(3.0) / math.cos(math.radians(45.0))
    env = math.radians(20.0) / math.sqrt(1 - zeta ** 2) * np.exp(-lam * t)
    assert np.allclose(sig, np.hypot(env, floor), rtol=1e-12)
    assert sig[-1] == pytest.approx(floor, rel=1e-6)                 # 12 h: the envelope is gone


def test_the_ned_frame_hangs_from_the_body_frame_turned_half_about_x():
    from scipy.spatial.transform import Rotation
    from gyro_instrument.recording.frames import instrument_frames
    insts = build_instruments(load_scene("marine_gyrocompass", ["instruments.sperry.ned_heading=true"]))
    tfs = {tf.child: tf for tf in instrument_frames(insts, None, "ship1/")}
    assert "ship1/anschutz_body_ned" not in tfs          # only on request
    tf = tfs["ship1/sperry_body_ned"]
    assert tf.parent == "ship1/sperry_body" and tf.translation_m == (0.0, 0.0, 0.0)
    # REP-103: the _ned twin of a forward-left-up frame is forward-right-down: its axes in the body frame
    axes = Rotation.from_quat(tf.rotation_xyzw).apply(np.eye(3))
    assert np.allclose(axes, [[1, 0, 0], [0, -1, 0], [0, 0, -1]], atol=1e-15)
