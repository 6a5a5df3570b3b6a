"""CDR bytes of the fixed-layout messages this package publishes and reads, without ROS.

A :class:`CdrLayout` is a message type whose strings and sequence lengths are fixed (a JointState
with given joint names, a PointStamped with a given frame, a Clock): only the stamp and some float64
fields vary, so many messages encode and decode at once with numpy. The simulators publish
pre-serialized messages with it, the estimator node reads its joint states with it, and replay
(:mod:`gyro_instrument.recording.bag_samples`) decodes recorded joint states with the same layouts,
falling back to ``mcap_ros2``'s dynamic decoder for a message of another layout. Little-endian CDR
(XCDR1) as rclpy's Fast-CDR serializer writes it (OMG DDS-XTypes 1.3, sec. 7.4.3; checked byte for
byte in ``tests/test_ros.py``).
"""

import struct

import numpy as np

from gyro_instrument.core.scene import EPOCH_NS


_STAMP_LE, _STAMP_BE = struct.Struct("<iI").unpack_from, struct.Struct(">iI").unpack_from


def cdr_time_ns(data, offset) -> int:
    """A builtin_interfaces/Time (int32 sec, uint32 nanosec) at byte ``offset`` of a CDR message,
    in the message's byte order (encapsulation header byte 1: 1 little endian), as int ns."""
    sec, nsec = (_STAMP_LE if data[1] == 1 else _STAMP_BE)(data, offset)
    return sec * 1_000_000_000 + nsec


def cdr_stamp_ns(data) -> int | None:
    """Stamp of a CDR message whose first field is a Time (any Header-first type, or Clock):
    after the 4-byte encapsulation header, int32 sec and uint32 nanosec; None when too short."""
    if len(data) < 12:
        return None
    return cdr_time_ns(data, 4)

_STAMP_SET = struct.Struct("<II").pack


def restamped(data, t_ns_from_release) -> bytes:
    """``data`` (little-endian CDR bytes whose first field is a Time: a :meth:`CdrLayout.encode`
    message) with the stamp ``EPOCH_NS + t`` instead of its own: byte for byte what ``encode`` writes
    for that stamp (seconds floored, wrapped to 32 bits as its int32 cast), without numpy (~1 µs)."""
    sec, nsec = divmod(EPOCH_NS + int(t_ns_from_release), 1_000_000_000)
    return data[:4] + _STAMP_SET(sec & 0xFFFFFFFF, nsec) + data[12:]


class CdrLayout:
    """The CDR bytes of a message type whose strings and sequence lengths are fixed, so that only
    the stamp (bytes 4–12: int32 sec, uint32 nanosec) and some float64 fields vary: a template
    and the offsets of those fields. Encodes and decodes many messages at once with numpy: byte
    for byte what rclpy's serializer writes (little-endian CDR), except that the alignment padding
    is zero here where Fast-CDR leaves it unset (``tests/test_ros.py``).

    Used by the simulators to publish pre-serialized messages and by the estimator to read its
    joint states without building message objects; a message that does not match the layout
    (other names, lengths or encoding) is handled by deserializing it.
    """

    def __init__(self, template, fields, padding=()):
        self.template = bytes(template)
        self.size = len(self.template)
        self.fields = [(int(off), int(k)) for off, k in fields]   # (byte offset, number of float64)
        # alignment padding: written as zeros, ignored when matching (Fast-CDR leaves it unset)
        self.padding = [(int(lo), int(hi)) for lo, hi in padding]
        varying = [(4, 12)] + [(off, off + 8 * k) for off, k in self.fields] + self.padding
        fixed, at = [], 0
        for lo, hi in sorted(varying):
            if lo > at:
                fixed.append((at, lo))
            at = max(at, hi)
        if at < self.size:
            fixed.append((at, self.size))
        self._fixed = [(lo, hi, self.template[lo:hi]) for lo, hi in fixed]
        self._row = np.frombuffer(self.template, dtype=np.uint8)

    def matches(self, data) -> bool:
        """True if ``data`` has this layout (same length and the same bytes outside the stamp, the
        float64 fields and the alignment padding)."""
        if len(data) != self.size:
            return False
        for lo, hi, want in self._fixed:
            if data[lo:hi] != want:
                return False
        return True

    def encode(self, t_ns_from_release, *columns) -> list:
        """One serialized message (bytes) per stamp; ``columns[j]`` is an (n, k_j) array (or (n,)
        for k_j = 1) for field j."""
        t = EPOCH_NS + np.asarray(t_ns_from_release, dtype=np.int64)
        n = t.size
        rows = np.empty((n, self.size), dtype=np.uint8)
        rows[:] = self._row
        rows[:, 4:8] = (t // 1_000_000_000).astype("<i4").view(np.uint8).reshape(n, 4)
        rows[:, 8:12] = (t % 1_000_000_000).astype("<u4").view(np.uint8).reshape(n, 4)
        for (off, k), col in zip(self.fields, columns):
            col = np.ascontiguousarray(col, dtype="<f8").reshape(n, k)
            rows[:, off:off + 8 * k] = col.view(np.uint8).reshape(n, 8 * k)
        buf, size = rows.tobytes(), self.size
        return [buf[i:i + size] for i in range(0, n * size, size)]

    def decode(self, datas) -> tuple:
        """Inverse of :meth:`encode` for messages that :meth:`matches`: (t_ns from release as int64,
        [float64 array (n, k) per field])."""
        n = len(datas)
        rows = np.frombuffer(b"".join(datas), dtype=np.uint8).reshape(n, self.size)
        sec = rows[:, 4:8].copy().view("<i4").reshape(n).astype(np.int64)
        nsec = rows[:, 8:12].copy().view("<u4").reshape(n).astype(np.int64)
        t = sec * 1_000_000_000 + nsec - EPOCH_NS
        cols = [rows[:, off:off + 8 * k].copy().view("<f8").reshape(n, k).astype(np.float64, copy=False)
                for off, k in self.fields]
        return t, cols


class _CdrTemplate:
    """Little-endian CDR (XCDR1) writer for templates: alignment is relative to the byte after the
    4-byte encapsulation header."""

    def __init__(self):
        self.buf = bytearray(b"\x00\x01\x00\x00")
        self.padding = []
        self.stamp()

    def align(self, n):
        pad = (-(len(self.buf) - 4)) % n
        if pad:
            self.padding.append((len(self.buf), len(self.buf) + pad))
            self.buf += bytes(pad)

    def layout(self, fields):
        return CdrLayout(self.buf, fields, self.padding)

    def stamp(self):
        self.align(4)
        self.buf += bytes(8)

    def string(self, s):
        b = s.encode() + b"\0"
        self.u32(len(b))
        self.buf += b

    def u32(self, v):
        self.align(4)
        self.buf += struct.pack("<I", v)

    def doubles(self, k, sequence):
        """float64[k] (fixed array) or float64[] with k elements; returns the offset of the values."""
        if sequence:
            self.u32(k)
        self.align(8)
        off = len(self.buf)
        self.buf += bytes(8 * k)
        return off


def joint_state_layout(names, frame_id="") -> CdrLayout:
    """:class:`CdrLayout` of sensor_msgs/JointState with these joint names; fields position,
    velocity, effort (each ``len(names)`` values, never empty: see :func:`joint_state`)."""
    if not names:
        raise ValueError("a JointState layout needs at least one joint")
    w = _CdrTemplate()
    w.string(frame_id)
    w.u32(len(names))
    for n in names:
        w.string(n)
    return w.layout([(w.doubles(len(names), True), len(names)) for _ in range(3)])


def point_stamped_layout(frame_id) -> CdrLayout:
    """:class:`CdrLayout` of geometry_msgs/PointStamped: one field (x, y, z)."""
    w = _CdrTemplate()
    w.string(frame_id)
    return w.layout([(w.doubles(3, False), 3)])


def imu_layout(frame_id) -> CdrLayout:
    """:class:`CdrLayout` of sensor_msgs/Imu: fields orientation (x, y, z, w), its covariance (9),
    angular velocity (3), its covariance (9), linear acceleration (3), its covariance (9); the
    covariances are fixed arrays (no length prefix)."""
    w = _CdrTemplate()
    w.string(frame_id)
    return w.layout([(w.doubles(k, False), k) for k in (4, 9, 3, 9, 3, 9)])


#: :class:`CdrLayout` of rosgraph_msgs/Clock (the stamp only)
CLOCK_LAYOUT = _CdrTemplate().layout([])
