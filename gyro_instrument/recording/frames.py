"""The frames a scene's messages name, their static transforms, and the two stamp parameters
(issue 37 item 5): no rclpy.

Every frame a message names hangs from ``site_enu`` (REP-103 ENU at the site, y true north) by a
static transform (:func:`scene_frames`): a pendulum's ``<pendulum>_pivot`` (ENU axes, origin at
the suspension point: 3 m apart along east in the scene's order, at height l, as the markers show
it) and a horizontal gyroscope's ``<gyro>_scale`` (x along the scale's zero, y left, z up: a yaw
ψ = π/2 − M, M the mount azimuth the scene declares, as a robot description declares a sensor's
mounting; the ``<gyro>/heading`` Imu is the *estimate* of the same rotation). A Puiseux body's
``<body>_body`` moves with the body: it has no static transform; nor has a marine gyrocompass's
``<compass>_body`` (the ship's), but its NED twin ``<compass>_body_ned`` hangs from it (a turn of π
about x: x forward, y starboard, z down) when the compass publishes its NED heading.

The nodes publish the transforms live as latched ``geometry_msgs/TransformStamped``; the recorder
writes them to the bag as one ``/tf_static`` ``tf2_msgs/msg/TFMessage`` encoded here
(:func:`tf_message_cdr`; tf2_msgs is not installed with the wheels, so its definition and type
hash are given in :mod:`.definitions`).

``frame_prefix`` (robot_state_publisher's convention) is put before every frame id
(:func:`check_frame_prefix`); ``stamp_epoch`` moves every stamp (:func:`parse_stamp_epoch`).
"""

import math
import re
import struct
from dataclasses import dataclass
from datetime import datetime, timezone

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.sim_stream import SPACING_M
from gyro_instrument.recording.topics import (SITE_FRAME, compass_frame, heading_frame, measures_azimuth,
                                              publications)

#: relative, as a namespaced robot's tf topics are (``/tf_static`` in the root namespace)
TF_STATIC = "tf_static"
TF_MESSAGE_TYPE = "tf2_msgs/msg/TFMessage"
TRANSFORM_TYPE = "geometry_msgs/msg/TransformStamped"
#: the relative topic on which every node publishes the static transforms of the frames it names
STATIC_TRANSFORMS = "static_transforms"
#: the latest stamp a builtin_interfaces/Time holds (int32 seconds)
_MAX_STAMP_NS = (2 ** 31 - 1) * 1_000_000_000
_PREFIX = re.compile(r"([A-Za-z0-9_]+/)*[A-Za-z0-9_]*")
WALL = "wall"


@dataclass(frozen=True)
class StaticTransform:
    """``child`` in ``parent``: translation (m) and rotation (x, y, z, w) of the child frame."""

    parent: str
    child: str
    translation_m: tuple
    rotation_xyzw: tuple


def check_frame_prefix(prefix, field="frame_prefix") -> str:
    """``prefix`` when a frame id may start with it: letters, digits, ``_`` and ``/`` between
    names, not starting with ``/`` (tf2 refuses a frame id starting with ``/``) and no ``//``;
    empty is no prefix. Raises SceneError naming ``field`` and the value otherwise."""
    prefix = "" if prefix is None else str(prefix)
    if not _PREFIX.fullmatch(prefix):
        raise SceneError(field, prefix, "letters, digits and '_', names separated by '/', not starting with '/' "
                                        "(a tf2 frame id's characters), e.g. 'ship1/'; '' for none")
    return prefix


def prefixed(prefix, frame) -> str:
    """``prefix + frame`` (an empty frame, no frame, stays empty)."""
    return f"{prefix}{frame}" if frame else ""


def parse_stamp_epoch(text, real_time_factor=None, field="stamp_epoch") -> "int | str":
    """The stamp of sim time 0 as ns since 1970 (UTC), from ``text``: '' the simulation epoch
    (``EPOCH_NS``, 2001-09-09T01:46:40Z); an ISO 8601 date-time (a naive one is UTC), within what a
    ``builtin_interfaces/Time`` holds; or ``wall``: returned as the string ``"wall"`` (the clock owner
    takes the wall clock when sim time starts), valid only at real-time factor 1 (give
    ``real_time_factor`` to check; None skips the check). Raises SceneError naming ``field``."""
    text = "" if text is None else str(text).strip()
    if text == "":
        return EPOCH_NS
    if text == WALL:
        if real_time_factor is not None and real_time_factor != 1.0:
            raise SceneError(field, text, f"'wall' only at real_time_factor 1 (here {real_time_factor:g}): sim "
                                          "time faster or slower than the wall clock cannot carry wall stamps")
        return WALL
    try:
        when = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        when = None
    if when is not None and when.tzinfo is None:
        when = when.replace(tzinfo=timezone.utc)
    ns = None if when is None else (int(when.timestamp()) * 1_000_000_000 + when.microsecond * 1000)
    if ns is None or not (0 <= ns <= _MAX_STAMP_NS):
        raise SceneError(field, text, "an ISO 8601 date-time (e.g. 2026-12-07T01:00:00Z; no zone: UTC) from 1970 "
                                      "to 2038-01-19, 'wall' (real_time_factor 1), or '' for the simulation epoch")
    return ns


def _yaw_xyzw(azimuth_rad) -> tuple:
    """Quaternion (x, y, z, w) of a levelled frame whose x has compass azimuth ``azimuth_rad``."""
    psi = math.pi / 2 - azimuth_rad
    return (0.0, 0.0, math.sin(psi / 2), math.cos(psi / 2))


def instrument_frames(insts, names=None, prefix="") -> list:
    """The static transforms of the frames the messages of instruments ``names`` (default all)
    name (module docstring). ``prefix`` before every frame id; ``insts`` is every instrument of the
    scene, in scene order (it places them)."""
    order = list(insts)
    out = []
    for name in order if names is None else [n for n in order if n in names]:
        inst = insts[name]
        x = SPACING_M * order.index(name)
        for p in publications(name, inst):
            if p.frame_id.endswith("_pivot"):
                out.append(StaticTransform(prefixed(prefix, SITE_FRAME), prefixed(prefix, p.frame_id),
                                           (x, 0.0, float(inst.observation().length_m)), (0.0, 0.0, 0.0, 1.0)))
        for p in publications(name, inst):
            if p.key == "heading_ned":     # a compass's NED twin of its moving body frame: π about x
                out.append(StaticTransform(prefixed(prefix, compass_frame(name)), prefixed(prefix, p.frame_id),
                                           (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)))
        if measures_azimuth(inst):
            mount = math.radians(getattr(inst.p, "mount_azimuth_deg", None) or 0.0)
            out.append(StaticTransform(prefixed(prefix, SITE_FRAME), prefixed(prefix, heading_frame(name)),
                                       (x, 0.0, 0.0), _yaw_xyzw(mount)))
    return out


class _Cdr:
    """Little-endian CDR (XCDR1), alignment relative to the byte after the encapsulation header."""

    def __init__(self):
        self.buf = bytearray(b"\x00\x01\x00\x00")

    def align(self, n):
        self.buf += bytes((-(len(self.buf) - 4)) % n)

    def u32(self, v):
        self.align(4)
        self.buf += struct.pack("<I", v)

    def string(self, s):
        b = s.encode() + b"\0"
        self.u32(len(b))
        self.buf += b

    def transform(self, tf, stamp_ns):
        self.align(4)
        self.buf += struct.pack("<iI", stamp_ns // 1_000_000_000, stamp_ns % 1_000_000_000)
        self.string(tf.parent)
        self.string(tf.child)
        self.align(8)
        self.buf += struct.pack("<7d", *tf.translation_m, *tf.rotation_xyzw)


def transform_stamped_cdr(tf, stamp_ns) -> bytes:
    """CDR bytes of one ``geometry_msgs/TransformStamped`` stamped ``stamp_ns`` (ns since 1970)."""
    w = _Cdr()
    w.transform(tf, int(stamp_ns))
    return bytes(w.buf)


def tf_message_cdr(tfs, stamp_ns) -> bytes:
    """CDR bytes of one ``tf2_msgs/msg/TFMessage`` holding ``tfs``, each stamped ``stamp_ns``."""
    w = _Cdr()
    w.u32(len(tfs))
    for tf in tfs:
        w.transform(tf, int(stamp_ns))
    return bytes(w.buf)
