"""Heading out (issue 24 item 5): the Imu fields of a north estimate and the $HEHDT sentences.

Independent references: scipy's ``Rotation`` (scalar-last quaternions, its own implementation) for
what a quaternion does to a vector; the definition of a compass azimuth (0 at north, clockwise:
the direction (sin A, cos A, 0) in ENU) for where the reference direction must point; pynmea2 (an
independent NMEA 0183 parser, test extra) for the sentences; a real UDP socket on 127.0.0.1.

Tolerances: the quaternion and rate are a few double-precision trigonometric operations and one
3×3 product, each within ~1 ulp (2.2e-16) relative, so 1e-12 (rad, or relative) leaves a margin of
thousands of ulp and is still ten orders below the smallest error of any wrong variant (≥ 1e-3 rad
on the test azimuths). A written heading is within half its last decimal of the value (rounding).
"""

import math
import socket

import numpy as np
import pynmea2
import pytest
from scipy.spatial.transform import Rotation

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.site import Site
from gyro_instrument.estimators.north.heading import (NOT_PROVIDED, UNMEASURED_TILT_VARIANCE_RAD2, ImuFields,
                                                earth_rate_body, earth_rate_body_covariance, imu_fields,
                                                orientation_xyzw, yaw_from_azimuth)
from gyro_instrument.recording.nmea import (NmeaUdpSender, format_heading, hehdt_sentence, nmea_checksum,
                                            parse_udp_target, resolve_udp_target)

#: the azimuths of the brief: the cardinal points, an oblique one, the southern half, just west of north
AZIMUTHS_DEG = (0.0, 90.0, 30.0, 200.0, 359.9)
#: see the module docstring
TIGHT = 1e-12
#: Paris (Foucault's pendulum, 48.846° N), Sydney (33.87° S), the equator, near the pole
LATITUDES_DEG = (48.846, -33.87, 0.0, 89.0)


# ----------------------------------------------------------------------------- the orientation
def misdirection_rad(q_xyzw, azimuth_rad: float) -> float:
    """Angle between where the quaternion sends the body's forward axis and the direction of
    azimuth A (ENU (sin A, cos A, 0)), plus how far it tips the body's up axis off ENU up."""
    rot = Rotation.from_quat(np.asarray(q_xyzw, dtype=float))  # scipy: scalar last, as the message
    forward = rot.apply([1.0, 0.0, 0.0])
    up = rot.apply([0.0, 0.0, 1.0])
    want = np.array([math.sin(azimuth_rad), math.cos(azimuth_rad), 0.0])
    miss = math.atan2(np.linalg.norm(np.cross(forward, want)), float(forward @ want))
    tilt = math.atan2(np.linalg.norm(np.cross(up, [0.0, 0.0, 1.0])), float(up[2]))
    return miss + tilt


def worst_misdirection_rad(quaternion_of) -> float:
    """The check over the test azimuths: the largest misdirection of ``quaternion_of(A)``."""
    return max(misdirection_rad(quaternion_of(math.radians(a)), math.radians(a)) for a in AZIMUTHS_DEG)


def _yaw_quat(yaw: float) -> tuple:
    """(x, y, z, w) of a rotation by ``yaw`` about ENU z, written out by hand."""
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


#: the classic heading mistakes, each built explicitly (azimuth rad -> quaternion x, y, z, w)
WRONG = {
    # NED yaw (= the compass azimuth, about the down axis) published as an ENU yaw
    "NED/ENU swap": lambda a: _yaw_quat(a),
    # the right rotation, scalar first, copied into x, y, z, w
    "(w,x,y,z) order": lambda a: (math.cos((math.pi / 2 - a) / 2), 0.0, 0.0, math.sin((math.pi / 2 - a) / 2)),
    # the clockwise azimuth negated into a counter-clockwise angle, the 90 deg from north to east forgotten
    "90 deg offset (yaw = -A)": lambda a: _yaw_quat(-a),
    "90 deg offset (yaw = pi - A)": lambda a: _yaw_quat(math.pi - a),
    # counter-clockwise and clockwise confused
    "sign flip (yaw = A - pi/2)": lambda a: _yaw_quat(a - math.pi / 2),
}


@pytest.mark.parametrize("azimuth_deg", AZIMUTHS_DEG)
def test_the_quaternion_points_the_forward_axis_along_the_azimuth(azimuth_deg):
    a = math.radians(azimuth_deg)
    fields = imu_fields(a, 1e-5, Site.from_degrees(48.846))
    assert misdirection_rad(fields.orientation_xyzw, a) < TIGHT
    assert fields.orientation_xyzw == orientation_xyzw(a)
    assert abs(np.linalg.norm(fields.orientation_xyzw) - 1.0) < TIGHT
    # REP-103 yaw, independently: the forward axis's angle from east, counter-clockwise
    yaw = Rotation.from_quat(fields.orientation_xyzw).as_euler("ZYX")[0]
    assert abs(math.remainder(yaw - (math.pi / 2 - a), 2 * math.pi)) < TIGHT
    assert abs(math.remainder(yaw_from_azimuth(a) - yaw, 2 * math.pi)) < TIGHT


def test_north_and_east_explicitly():
    """Azimuth 0: forward = +y (north), yaw +90 deg; azimuth 90: forward = +x (east), identity."""
    north = Rotation.from_quat(orientation_xyzw(0.0)).apply([1.0, 0.0, 0.0])
    assert np.allclose(north, [0.0, 1.0, 0.0], atol=TIGHT, rtol=0)
    assert np.allclose(orientation_xyzw(math.pi / 2), (0.0, 0.0, 0.0, 1.0), atol=TIGHT, rtol=0)


@pytest.mark.parametrize("name", sorted(WRONG))
def test_each_classic_heading_mistake_fails_the_check(name):
    worst = worst_misdirection_rad(WRONG[name])
    assert worst > 1e-3, f"{name}: the check would pass it (worst {worst:.3g} rad)"


def test_the_check_passes_the_module():
    assert worst_misdirection_rad(orientation_xyzw) < TIGHT


# ----------------------------------------------------------------------------- the Earth rate
@pytest.mark.parametrize("latitude_deg", LATITUDES_DEG)
@pytest.mark.parametrize("azimuth_deg", AZIMUTHS_DEG)
def test_angular_velocity_is_the_earth_rate_in_the_body_frame(latitude_deg, azimuth_deg):
    """REP-145: a gyro at rest reads the Earth rate n (0, cos γ, sin γ) (ENU) in its own frame:
    the inverse of the body→ENU rotation (scipy) applied to it; its norm is n."""
    site = Site.from_degrees(latitude_deg)
    a = math.radians(azimuth_deg)
    fields = imu_fields(a, 1e-5, site, rate_measured=True)
    n = site.earth_rate_rad_s
    want = Rotation.from_quat(fields.orientation_xyzw).inv().apply(site.earth_rate_enu())
    assert np.allclose(fields.angular_velocity_xyz_rad_s, want, atol=TIGHT * n, rtol=0)
    assert abs(np.linalg.norm(fields.angular_velocity_xyz_rad_s) - n) < TIGHT * n
    # the up axis reads k = n sin γ whatever the heading (Quet sec. 2 §I), negative south of the equator
    assert abs(fields.angular_velocity_xyz_rad_s[2] - site.k_vertical_rad_s) < TIGHT * n


@pytest.mark.parametrize("latitude_deg", LATITUDES_DEG)
def test_pointing_north_and_east_read_the_horizontal_rate_on_the_forward_and_left_axes(latitude_deg):
    """Derivation: pointing north the body axes are (north, west, up) and Earth's rate has a north
    component k' = n cos γ, no west component and an up component k = n sin γ, so ω_b = (k', 0, k);
    pointing east the axes are (east, north, up), so ω_b = (0, k', k)."""
    site = Site.from_degrees(latitude_deg)
    k, k_h, n = site.k_vertical_rad_s, site.k_horizontal_rad_s, site.earth_rate_rad_s
    assert np.allclose(earth_rate_body(0.0, site), [k_h, 0.0, k], atol=TIGHT * n, rtol=0)
    assert np.allclose(earth_rate_body(math.pi / 2, site), [0.0, k_h, k], atol=TIGHT * n, rtol=0)
    assert np.allclose(earth_rate_body(math.pi, site), [-k_h, 0.0, k], atol=TIGHT * n, rtol=0)


def test_the_rate_in_the_wrong_frame_direction_fails():
    """Applying the body→ENU rotation instead of its inverse (a frame-direction mistake) is caught
    by the same reference at an oblique azimuth."""
    site, a = Site.from_degrees(48.846), math.radians(30.0)
    wrong = Rotation.from_quat(orientation_xyzw(a)).apply(site.earth_rate_enu())
    assert np.linalg.norm(wrong - earth_rate_body(a, site)) > 0.1 * site.earth_rate_rad_s


# ----------------------------------------------------------------------------- covariances (Imu.msg)
def test_covariances_follow_the_imu_message_convention():
    site, sigma = Site.from_degrees(48.846), 2.6 / 206264.806  # 2.6 arcsec (the DMT Gyromat 5000 figure)
    f = imu_fields(math.radians(30.0), sigma, site)
    cov = np.reshape(f.orientation_covariance, (3, 3))
    assert cov[2, 2] == sigma ** 2                                    # yaw: the estimate's variance
    assert cov[0, 0] == cov[1, 1] == UNMEASURED_TILT_VARIANCE_RAD2    # roll, pitch: set to 0, not measured
    assert cov[0, 0] != NOT_PROVIDED                                  # element 0 = -1 would void the yaw
    assert not np.any(cov - np.diag(np.diag(cov)))
    assert f.linear_acceleration_covariance == (NOT_PROVIDED,) + (0.0,) * 8
    assert f.linear_acceleration_xyz_m_s2 == (0.0, 0.0, 0.0)
    levelled = imu_fields(math.radians(30.0), sigma, site, level_sigma_rad=1e-4)
    assert levelled.orientation_covariance[0] == levelled.orientation_covariance[4] == (1e-4) ** 2
    assert levelled.orientation_covariance[8] == sigma ** 2


def test_the_rate_is_not_provided_unless_measured():
    """Imu.msg: element 0 of a covariance = -1 means "no estimate of this data element"; the
    gyrocompass measures no rate (issue 37: robot_localization would fuse a variance-0 rate)."""
    site = Site.from_degrees(48.846)
    for sigma in (1e-5, None):
        f = imu_fields(math.radians(30.0), sigma, site)
        assert f.angular_velocity_covariance == (NOT_PROVIDED,) + (0.0,) * 8
        assert f.angular_velocity_xyz_rad_s == (0.0, 0.0, 0.0)


def test_unknown_sigma_and_no_estimate():
    site = Site.from_degrees(-33.87)
    f = imu_fields(1.0, None, site, rate_measured=True)               # value without σ: covariance unknown
    assert f.orientation_covariance == (0.0,) * 9 and f.angular_velocity_covariance == (0.0,) * 9
    g = imu_fields(None, None, site)                                  # no estimate: not provided
    assert g.orientation_covariance[0] == NOT_PROVIDED and g.angular_velocity_covariance[0] == NOT_PROVIDED
    assert g.linear_acceleration_covariance[0] == NOT_PROVIDED
    assert g.orientation_xyzw == (0.0, 0.0, 0.0, 1.0)


@pytest.mark.parametrize("latitude_deg", LATITUDES_DEG)
def test_rate_covariance_is_the_propagated_azimuth_variance(latitude_deg):
    """Σ = σ_A² j jᵀ with j = ∂ω_b/∂A by central differences (step 1e-6 rad: truncation ~h²/6
    ~ 2e-13, rounding ~ eps/h ~ 2e-10 relative; tolerance 1e-7 of the largest entry); likewise for
    σ_γ and σ_n. Its trace is σ_A² (n cos γ)²: the horizontal rate turns with the heading."""
    site, a, sigma, h = Site.from_degrees(latitude_deg), math.radians(200.0), 1e-4, 1e-6
    j = (earth_rate_body(a + h, site) - earth_rate_body(a - h, site)) / (2 * h)
    cov = np.reshape(imu_fields(a, sigma, site, rate_measured=True).angular_velocity_covariance, (3, 3))
    scale = site.earth_rate_rad_s ** 2 * sigma ** 2
    assert np.allclose(cov, sigma ** 2 * np.outer(j, j), atol=1e-7 * scale, rtol=0)
    assert abs(np.trace(cov) - sigma ** 2 * site.k_horizontal_rad_s ** 2) < 1e-12 * scale
    s_lat, s_n = 1e-5, 1e-9
    up = Site(site.latitude_rad + h, site.earth_rate_rad_s)
    dn = Site(site.latitude_rad - h, site.earth_rate_rad_s) if latitude_deg < 89.9 else site
    j_lat = (earth_rate_body(a, up) - earth_rate_body(a, dn)) / ((up.latitude_rad - dn.latitude_rad))
    j_n = earth_rate_body(a, site) / site.earth_rate_rad_s
    full = earth_rate_body_covariance(a, sigma, site, s_lat, s_n)
    want = sigma ** 2 * np.outer(j, j) + s_lat ** 2 * np.outer(j_lat, j_lat) + s_n ** 2 * np.outer(j_n, j_n)
    assert np.allclose(full, want, atol=1e-7 * np.abs(want).max(), rtol=0)


def test_fields_are_plain_tuples_that_a_ros_message_takes():
    from sensor_msgs.msg import Imu
    f = imu_fields(math.radians(123.4), 1e-5, Site.from_degrees(48.846), level_sigma_rad=1e-4)
    for value, size in ((f.orientation_xyzw, 4), (f.orientation_covariance, 9), (f.angular_velocity_xyz_rad_s, 3),
                        (f.angular_velocity_covariance, 9), (f.linear_acceleration_xyz_m_s2, 3),
                        (f.linear_acceleration_covariance, 9)):
        assert isinstance(value, tuple) and len(value) == size and all(type(v) is float for v in value)
    msg = Imu()
    msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = f.orientation_xyzw
    msg.orientation_covariance = f.orientation_covariance
    msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = f.angular_velocity_xyz_rad_s
    msg.angular_velocity_covariance = f.angular_velocity_covariance
    msg.linear_acceleration_covariance = f.linear_acceleration_covariance
    assert msg.orientation_covariance[8] == (1e-5) ** 2
    with pytest.raises(AttributeError):
        f.orientation_xyzw = (0.0, 0.0, 0.0, 1.0)
    assert isinstance(f, ImuFields)


@pytest.mark.parametrize("kwargs, field", [
    ({"azimuth_rad": math.nan, "sigma_rad": 1e-5}, "north.azimuth_rad"),
    ({"azimuth_rad": 1.0, "sigma_rad": 0.0}, "north.sigma_rad"),
    ({"azimuth_rad": 1.0, "sigma_rad": -1e-5}, "north.sigma_rad"),
    ({"azimuth_rad": 1.0, "sigma_rad": math.inf}, "north.sigma_rad"),
    ({"azimuth_rad": 1.0, "sigma_rad": 1e-5, "level_sigma_rad": -1.0}, "imu.level_sigma_rad"),
    ({"azimuth_rad": 1.0, "sigma_rad": 1e-5, "latitude_sigma_rad": math.nan}, "site.latitude_sigma_rad"),
])
def test_bad_input_names_field_and_value(kwargs, field):
    with pytest.raises(SceneError) as err:
        imu_fields(site=Site.from_degrees(10.0), **kwargs)
    assert err.value.field == field and field in str(err.value)


# ----------------------------------------------------------------------------- NMEA 0183 $HEHDT
HEADINGS_DEG = (0.0, 0.04, 4.0, 45.0, 123.4, 200.0, 274.07, 359.9, 359.94, 359.96, -30.0, 725.5)


def _circular_diff_deg(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


@pytest.mark.parametrize("decimals", (0, 1, 2, 6))
def test_pynmea2_reads_the_heading_back_with_a_valid_checksum(decimals):
    for h in HEADINGS_DEG:
        s = hehdt_sentence(h, decimals)
        msg = pynmea2.parse(s, check=True)                            # check=True: a checksum must be there and match
        assert (msg.talker, msg.sentence_type, msg.hdg_true) == ("HE", "HDT", "T"), s
        got = float(msg.heading)
        assert 0.0 <= got < 360.0, s
        assert _circular_diff_deg(got, h) <= 0.5 * 10.0 ** -decimals + 1e-9, s
        assert len(msg.data[0].partition(".")[2]) == decimals, s
    with pytest.raises(pynmea2.ChecksumError):                        # the parser does check
        pynmea2.parse(hehdt_sentence(123.4)[:-2] + "00", check=True)


def test_published_sentences_and_edges():
    """Sample sentences quoted in public NMEA parser test data (gpsd's Saab R4 log: 4.0)."""
    assert hehdt_sentence(4.0) == "$HEHDT,4.0,T*2B"
    assert hehdt_sentence(45.0) == "$HEHDT,45.0,T*1E"
    assert nmea_checksum("HEHDT,4.0,T") == "2B"
    assert format_heading(359.96) == "0.0" and format_heading(-1e-20, 3) == "0.000"
    assert hehdt_sentence(123.4) == "$HEHDT,123.4,T*2B"
    for bad in (math.nan, math.inf, "north"):
        with pytest.raises(SceneError, match="nmea.heading_deg"):
            hehdt_sentence(bad)
    for bad in (-1, 7, 1.0, True):
        with pytest.raises(SceneError, match="nmea.decimals"):
            hehdt_sentence(10.0, bad)


def test_sentences_over_udp_on_loopback_parse():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx:
        rx.bind(("127.0.0.1", 0))
        rx.settimeout(2.0)
        port = rx.getsockname()[1]
        with NmeaUdpSender(f"127.0.0.1:{port}") as tx:
            sent = [tx.send_heading(h, 2) for h in HEADINGS_DEG]
        got = [rx.recv(256).decode("ascii") for _ in sent]
    assert all(g.endswith("\r\n") for g in got)
    assert [g[:-2] for g in got] == sent
    for g, h in zip(got, HEADINGS_DEG):
        assert _circular_diff_deg(float(pynmea2.parse(g.strip(), check=True).heading), h) <= 0.005 + 1e-9


@pytest.mark.parametrize("target, why", [
    ("127.0.0.1", ""), ("127.0.0.1:0", "outside [1, 65535]"), ("127.0.0.1:65536", "outside [1, 65535]"),
    ("127.0.0.1:-5", "not an integer"), ("127.0.0.1:ten", "not an integer"), ("127.0.0.1:1_0", "not an integer"),
    (":10110", ""), ("::1:10110", "brackets"), ("", ""), (None, ""),
])
def test_bad_targets_name_the_option_the_value_and_the_form(target, why):
    with pytest.raises(SceneError) as err:
        parse_udp_target(target)
    text = str(err.value)
    assert text.startswith(f"--nmea-udp = {target!r}") and "HOST:PORT" in text and "[1, 65535]" in text
    assert why in text


def test_an_unresolvable_host_is_named(monkeypatch):
    """Resolution failure, without asking any resolver: getaddrinfo replaced by one that fails."""
    def fail(*args, **kwargs):
        raise socket.gaierror(socket.EAI_NONAME, "Name or service not known")
    monkeypatch.setattr(socket, "getaddrinfo", fail)
    with pytest.raises(SceneError, match=r"nmea_udp = 'nowhere:10110'.*HOST 'nowhere' does not resolve"):
        NmeaUdpSender("nowhere:10110", field="nmea_udp")


def test_targets_that_parse():
    assert parse_udp_target("127.0.0.1:10110") == ("127.0.0.1", 10110)
    assert parse_udp_target("[::1]:1") == ("::1", 1)
    assert parse_udp_target("localhost:65535") == ("localhost", 65535)
    assert resolve_udp_target("127.0.0.1:10110")[1] == ("127.0.0.1", 10110)


def test_the_sender_refuses_what_is_not_one_sentence():
    with NmeaUdpSender("127.0.0.1:9") as tx:
        for bad in ("HEHDT,1.0,T*00", "$HEHDT,1.0,T*2F\r\n$HEHDT,2.0,T*2C", "$" + "x" * 90, "$HEHDT,é,T"):
            with pytest.raises(SceneError, match="nmea.sentence"):
                tx.send(bad)
