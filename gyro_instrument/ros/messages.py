"""Conversions between core arrays and ROS messages (REP-103: ENU, SI, radians)."""

import importlib
import math
import struct

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

from gyro_instrument.core.scene import EPOCH_NS

#: frame of ENU vectors at the site (REP-105 'map'-like local frame)
SITE_FRAME = "site_enu"


def stamp(t_ns_from_release):
    """builtin_interfaces/Time for ``EPOCH_NS + t``."""
    total = EPOCH_NS + int(t_ns_from_release)
    return Time(sec=total // 1_000_000_000, nanosec=total % 1_000_000_000)


def stamp_to_release_ns(st):
    """Inverse of :func:`stamp`."""
    return int(st.sec) * 1_000_000_000 + int(st.nanosec) - EPOCH_NS


def clock(t_ns):
    return Clock(clock=stamp(t_ns))


def joint_state(t_ns, names, position, velocity, effort, frame_id=""):
    msg = JointState()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    msg.name = list(names)
    msg.position = [float(v) for v in position]
    msg.velocity = [float(v) for v in velocity]
    msg.effort = [float(v) for v in effort]
    return msg


def point_stamped(t_ns, xyz, frame_id):
    msg = PointStamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = frame_id
    msg.point.x, msg.point.y, msg.point.z = (float(v) for v in xyz)
    return msg


def float64(value):
    return Float64(data=float("nan") if value is None else float(value))


def earth_rate_vector(t_ns, earth_rate_rad_s, latitude_rad):
    """The estimated Earth-rate vector in ENU, n (0, cos γ, sin γ) (REP-145)."""
    msg = Vector3Stamped()
    msg.header.stamp = stamp(t_ns)
    msg.header.frame_id = SITE_FRAME
    if earth_rate_rad_s is None or latitude_rad is None:
        msg.vector.x = msg.vector.y = msg.vector.z = float("nan")
    else:
        msg.vector.x = 0.0
        msg.vector.y = earth_rate_rad_s * math.cos(latitude_rad)
        msg.vector.z = earth_rate_rad_s * math.sin(latitude_rad)
    return msg


def diagnostics(t_ns, name, level_ok, message, values):
    """diagnostic_msgs/DiagnosticArray with one status; values: mapping -> KeyValue strings."""
    st = DiagnosticStatus(level=DiagnosticStatus.OK if level_ok else DiagnosticStatus.WARN, name=name,
                          message=message, hardware_id="gyro_instrument")
    st.values = [KeyValue(key=str(k), value=str(v)) for k, v in values.items()]
    arr = DiagnosticArray(status=[st])
    arr.header.stamp = stamp(t_ns)
    return arr


def message_class(type_name):
    """Class of ``pkg/msg/Type``."""
    pkg, _, name = type_name.split("/")
    return getattr(importlib.import_module(f"{pkg}.msg"), name)


def cdr_stamp_ns(data):
    """Stamp of a CDR message whose first field is a Time (any Header-first type, or Clock):
    after the 4-byte encapsulation header, int32 sec and uint32 nanosec (little endian here)."""
    if len(data) < 12:
        return None
    little = data[1] == 1
    sec, nsec = struct.unpack("<iI" if little else ">iI", data[4:12])
    return sec * 1_000_000_000 + nsec
