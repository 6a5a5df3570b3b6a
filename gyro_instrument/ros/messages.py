"""Conversions between core arrays and ROS messages (REP-103: ENU, SI, radians)."""

import importlib
import math
import struct

import numpy as np

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Float64

from gyro_instrument.core.scene import EPOCH_NS
# the CDR codec is rclpy-free and shared with replay (gyro_instrument.recording.cdr); re-exported here
from gyro_instrument.recording.cdr import (CLOCK_LAYOUT, CdrLayout, cdr_stamp_ns, cdr_time_ns,  # noqa: F401
                                          joint_state_layout, point_stamped_layout)
from gyro_instrument.recording.topics import SITE_FRAME  # noqa: F401  (re-exported)
from gyro_instrument.recording.visual import AxisMarkers



def stamp(t_ns_from_release) -> Time:
    """builtin_interfaces/Time for ``EPOCH_NS + t``."""
    total = EPOCH_NS + int(t_ns_from_release)
    return Time(sec=total // 1_000_000_000, nanosec=total % 1_000_000_000)


def stamp_to_release_ns(st) -> int:
    """Inverse of :func:`stamp`."""
    return int(st.sec) * 1_000_000_000 + int(st.nanosec) - EPOCH_NS


def clock(t_ns) -> Clock:
    return Clock(clock=stamp(t_ns))


def joint_state(t_ns, names, position, velocity, effort, frame_id="") -> JointState:
    msg = JointState()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    msg.name = list(names)
    msg.position = [float(v) for v in position]
    msg.velocity = [float(v) for v in velocity]
    msg.effort = [float(v) for v in effort]
    return msg


def point_stamped(t_ns, xyz, frame_id) -> PointStamped:
    msg = PointStamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    msg.point.x, msg.point.y, msg.point.z = (float(v) for v in xyz)
    return msg


def float64(value) -> Float64:
    return Float64(data=float("nan") if value is None else float(value))


def earth_rate_vector(t_ns, earth_rate_rad_s, latitude_rad, frame_id=SITE_FRAME) -> Vector3Stamped:
    """The estimated Earth-rate vector in ENU, n (0, cos γ, sin γ) (REP-145)."""
    msg = Vector3Stamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    if earth_rate_rad_s is None or latitude_rad is None:
        msg.vector.x = msg.vector.y = msg.vector.z = float("nan")
    else:
        msg.vector.x = 0.0
        msg.vector.y = earth_rate_rad_s * math.cos(latitude_rad)
        msg.vector.z = earth_rate_rad_s * math.sin(latitude_rad)
    return msg


def imu(t_ns, frame_id, fields) -> Imu:
    """sensor_msgs/Imu from :class:`~gyro_instrument.estimators.north.heading.ImuFields` (copied field by
    field: quaternion x, y, z, w; covariances row-major)."""
    msg = Imu()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    q = msg.orientation
    q.x, q.y, q.z, q.w = (float(v) for v in fields.orientation_xyzw)
    msg.orientation_covariance = [float(v) for v in fields.orientation_covariance]
    w = msg.angular_velocity
    w.x, w.y, w.z = (float(v) for v in fields.angular_velocity_xyz_rad_s)
    msg.angular_velocity_covariance = [float(v) for v in fields.angular_velocity_covariance]
    a = msg.linear_acceleration
    a.x, a.y, a.z = (float(v) for v in fields.linear_acceleration_xyz_m_s2)
    msg.linear_acceleration_covariance = [float(v) for v in fields.linear_acceleration_covariance]
    return msg


def diagnostics(t_ns, name, level_ok, message, values, level=None, hardware_id="gyro_instrument") -> DiagnosticArray:
    """diagnostic_msgs/DiagnosticArray with one status; values: mapping -> KeyValue strings; ``level``
    (a ``DiagnosticStatus`` level byte) overrides ``level_ok`` (OK or WARN)."""
    if level is None:
        level = DiagnosticStatus.OK if level_ok else DiagnosticStatus.WARN
    st = DiagnosticStatus(level=level, name=name, message=message, hardware_id=hardware_id)
    st.values = [KeyValue(key=str(k), value=str(v)) for k, v in values.items()]
    arr = DiagnosticArray(status=[st])
    arr.header.stamp = stamp(t_ns)
    return arr


def marker_array_stamp_ns(data) -> int | None:
    """Stamp of a serialized visualization_msgs/MarkerArray: its first marker's header (after the
    encapsulation header and the uint32 sequence length); None when empty."""
    if len(data) < 16 or struct.unpack_from("<I" if data[1] == 1 else ">I", data, 4)[0] == 0:
        return None
    return cdr_time_ns(data, 8)


def _marker(t_ns, ns, mid, mtype, rgba, scale, points=(), position=(0.0, 0.0, 0.0), frame_id=SITE_FRAME):
    from visualization_msgs.msg import Marker
    from geometry_msgs.msg import Point
    from std_msgs.msg import ColorRGBA
    mk = Marker()
    mk.header.stamp = stamp(t_ns)
    mk.header.frame_id = frame_id
    mk.ns, mk.id, mk.type, mk.action = ns, int(mid), mtype, Marker.ADD
    mk.pose.orientation.w = 1.0
    mk.pose.position.x, mk.pose.position.y, mk.pose.position.z = (float(v) for v in position)
    mk.scale.x, mk.scale.y, mk.scale.z = (float(v) for v in scale)
    mk.color = ColorRGBA(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=float(rgba[3]))
    mk.points = [Point(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in points]
    mk.frame_locked = False
    return mk


def _set_points(mk, pts):
    """Set a marker's points, reusing its Point objects (cheaper than new ones)."""
    from geometry_msgs.msg import Point
    have = mk.points
    while len(have) < len(pts):
        have.append(Point())
    del have[len(pts):]
    for p, xyz in zip(have, pts):
        p.x, p.y, p.z = float(xyz[0]), float(xyz[1]), float(xyz[2])


def pendulum_markers(t_ns, name, geom, reuse=None, frame_id=SITE_FRAME) -> "MarkerArray":
    """visualization_msgs/MarkerArray of a pendulum (:class:`~gyro_instrument.recording.visual.PendulumMarkers`)
    in ``site_enu``: the bob (sphere), the wire, the bob's recent trail (a LINE_STRIP, left out while
    the trail has fewer than two points: a line strip of one point is invalid) and the swing plane
    (a line). ``reuse``: a MarkerArray this function returned before, updated in place."""
    from visualization_msgs.msg import Marker, MarkerArray
    size_m = geom.size_m
    arr = reuse or MarkerArray(markers=[
        _marker(t_ns, name, 0, Marker.SPHERE, (0.9, 0.6, 0.1, 1.0), (size_m,) * 3, frame_id=frame_id),
        _marker(t_ns, name, 1, Marker.LINE_LIST, (0.7, 0.7, 0.7, 1.0), (size_m / 10, 0, 0), frame_id=frame_id),
        _marker(t_ns, name, 3, Marker.LINE_LIST, (1.0, 0.2, 0.2, 1.0), (size_m / 5, 0, 0), frame_id=frame_id),
    ])
    trail = geom.trail
    strip = next((mk for mk in arr.markers if mk.id == 2), None)
    if trail.shape[0] >= 2 and strip is None:      # a line strip needs two points: left out until then
        strip = _marker(t_ns, name, 2, Marker.LINE_STRIP, (0.2, 0.6, 1.0, 0.8), (size_m / 10, 0, 0), frame_id=frame_id)
        arr.markers.insert(2, strip)
    elif trail.shape[0] < 2 and strip is not None:
        arr.markers.remove(strip)
        strip = None
    st = stamp(t_ns)
    for mk in arr.markers:
        mk.header.stamp = st
    bob = geom.bob
    pos = arr.markers[0].pose.position
    pos.x, pos.y, pos.z = float(bob[0]), float(bob[1]), float(bob[2])
    _set_points(arr.markers[1], [geom.pivot, bob])
    if strip is not None:
        _set_points(strip, trail)
    _set_points(arr.markers[-1], geom.plane_ends)
    return arr


def axis_markers(t_ns, name, geom, frame_id=SITE_FRAME) -> "MarkerArray":
    """visualization_msgs/MarkerArray of a gyroscope's rotor axis (an arrow,
    :class:`~gyro_instrument.recording.visual.AxisMarkers`) in ``site_enu``."""
    from visualization_msgs.msg import Marker, MarkerArray
    o, length_m = np.asarray(geom.origin, dtype=float), geom.length_m
    return MarkerArray(markers=[
        _marker(t_ns, name, 0, Marker.ARROW, (0.2, 0.8, 0.3, 1.0), (length_m / 20, length_m / 10, length_m / 6),
                [o, o + length_m * np.asarray(geom.axis, dtype=float)], frame_id=frame_id),
    ])


def marker_array(t_ns, name, geom, reuse=None, frame_id=SITE_FRAME) -> "MarkerArray":
    """The MarkerArray of a marker geometry of :mod:`gyro_instrument.recording.visual`."""
    if isinstance(geom, AxisMarkers):
        return axis_markers(t_ns, name, geom, frame_id)
    return pendulum_markers(t_ns, name, geom, reuse, frame_id)


def message_class(type_name) -> type:
    """Class of ``pkg/msg/Type``."""
    pkg, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.msg"), name)
