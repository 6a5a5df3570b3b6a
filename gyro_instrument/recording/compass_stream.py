"""The ship's gyrocompass's own messages, beside its joint states (issue 39 item 5; no rclpy): its
heading as ``sensor_msgs/Imu`` (ENU, and NED on request) at every sample, its state as a
``diagnostic_msgs/DiagnosticArray`` once per second of sim time, and the headings a ``$HEHDT``
sender takes. :class:`CompassStream` is the :class:`~gyro_instrument.recording.sim_stream.SimulatorStream`
of the ``marine_gyrocompass`` node: the joint states (and the clock) as every simulator publishes
them, then these, from the same block's readings through each compass's
:class:`~gyro_instrument.instruments.marine_gyrocompass.readout.Readout`.

Imu (REP-103, REP-145, sensor_msgs/Imu.msg's covariance conventions as
:mod:`gyro_instrument.estimators.north.heading` follows them): the header frame is the compass's body
frame ``<compass>_body`` (x forward along the ship's fore-and-aft line, y to port, z up; it moves
with the ship). ENU (``<compass>/heading``): yaw ψ = π/2 − H (H the compass's heading reading,
clockwise from true north), quaternion (0, 0, sin ψ/2, cos ψ/2) with ψ in (−π, π] (w ≥ 0). NED
(``<compass>/heading_ned``, frame ``<compass>_body_ned``: x forward, y starboard, z down, REP-103's
``_ned`` suffix): yaw = H, (0, 0, sin H/2, cos H/2), H in (−π, π]. Orientation covariance row-major
roll, pitch, yaw: yaw σ² (:meth:`Readout.sigma_rad`), roll and pitch
:data:`~gyro_instrument.estimators.north.heading.UNMEASURED_TILT_VARIANCE_RAD2` (not measured: element 0
= −1 would void the yaw too), off-diagonal 0. Angular velocity and linear acceleration are not
provided (zero, covariance element 0 = −1): a gyrocompass reads neither.
"""

import math
import struct

import numpy as np

from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.estimators.north.heading import NOT_PROVIDED, UNMEASURED_TILT_VARIANCE_RAD2
from gyro_instrument.instruments.marine_gyrocompass.readout import SETTLED, Readout
from gyro_instrument.recording.cdr import imu_layout
from gyro_instrument.recording.sim_stream import SimulatorStream
from gyro_instrument.recording.topics import DIAGNOSTICS, Publication, visual_every

#: a compass's heading publications (:func:`gyro_instrument.recording.topics.publications`)
HEADING_KEYS = ("heading", "heading_ned")
DIAGNOSTICS_TYPE = "diagnostic_msgs/msg/DiagnosticArray"
#: the ``hardware_id`` of a compass's status (the recorder keeps it: it is not a node's liveness)
HARDWARE_ID = "gyro_instrument/marine_gyrocompass"
#: diagnostic_msgs/DiagnosticStatus levels
OK, WARN = 0, 1
#: the most $HEHDT sentences per second of sim time (every sample of a slower compass)
NMEA_RATE_HZ = 10.0


def imu_columns(heading_rad, sigma_rad, ned=False) -> tuple:
    """The float64 columns of :func:`~gyro_instrument.recording.cdr.imu_layout` for headings
    ``heading_rad`` (rad, clockwise from true north) with standard errors ``sigma_rad`` (module
    docstring): orientation (n, 4), its covariance (n, 9), angular velocity (n, 3) and its
    covariance (n, 9), linear acceleration (n, 3) and its covariance (n, 9)."""
    h = np.asarray(heading_rad, dtype=float)
    yaw = h if ned else math.pi / 2 - h
    yaw = -np.remainder(-yaw + math.pi, 2 * math.pi) + math.pi          # (−π, π]
    n = h.size
    q = np.zeros((n, 4))
    q[:, 2], q[:, 3] = np.sin(yaw / 2), np.cos(yaw / 2)
    cov = np.zeros((n, 9))
    cov[:, 0] = cov[:, 4] = UNMEASURED_TILT_VARIANCE_RAD2
    cov[:, 8] = np.asarray(sigma_rad, dtype=float) ** 2
    absent = np.zeros((n, 9))
    absent[:, 0] = NOT_PROVIDED
    return q, cov, np.zeros((n, 3)), absent, np.zeros((n, 3)), absent.copy()


class _Writer:
    """Little-endian CDR (XCDR1): alignment relative to the byte after the encapsulation header."""

    def __init__(self) -> None:
        self.buf = bytearray(b"\x00\x01\x00\x00")

    def align(self, n) -> None:
        self.buf += bytes((-(len(self.buf) - 4)) % n)

    def u32(self, v) -> None:
        self.align(4)
        self.buf += struct.pack("<I", v)

    def string(self, s) -> None:
        b = s.encode() + b"\0"
        self.u32(len(b))
        self.buf += b


def diagnostic_array_cdr(stamp_ns, statuses) -> bytes:
    """CDR bytes of one ``diagnostic_msgs/DiagnosticArray`` stamped ``stamp_ns`` (ns since 1970), frame
    '', holding ``statuses``: (level, name, message, hardware_id, [(key, value)...]) each."""
    w = _Writer()
    w.buf += struct.pack("<iI", int(stamp_ns) // 1_000_000_000, int(stamp_ns) % 1_000_000_000)
    w.string("")
    w.u32(len(statuses))
    for level, name, message, hardware_id, values in statuses:
        w.buf += struct.pack("<B", level)
        for s in (name, message, hardware_id):
            w.string(s)
        w.u32(len(values))
        for k, v in values:
            w.string(k)
            w.string(v)
    return bytes(w.buf)


def _text(v, fmt=".6f") -> str:
    """A KeyValue's value: ``nan`` for None, a number with ``fmt``, a bool as true/false."""
    if v is None:
        return "nan"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float, np.floating)):
        return format(float(v), fmt)
    return str(v)


class CompassStream(SimulatorStream):
    """:class:`SimulatorStream` of the ``marine_gyrocompass`` node (module docstring).

    Extra parameter ``namespace`` (the node's): a status is named ``<namespace>/<compass>``
    (``sperry`` in the root namespace). Attribute ``nmea`` collects (stamp ns, heading rad) of the
    first compass, at most :data:`NMEA_RATE_HZ` per second of sim time, for the node to send.
    """

    def __init__(self, scene, insts, kinds, seed, window_s, clock, frame_prefix="", namespace="") -> None:
        super().__init__(scene, insts, kinds, seed, window_s, clock, frame_prefix)
        self.readouts = {name: Readout(inst) for name, inst in self.chosen.items()}
        self.base_pubs = {name: [p for p in ps if p.key not in HEADING_KEYS] for name, ps in self.pubs.items()}
        self.imu = {(name, p.key): imu_layout(frame_prefix + p.frame_id)
                    for name, ps in self.pubs.items() for p in ps if p.key in HEADING_KEYS}
        self.status_key = None
        if self.chosen:
            first = next(iter(self.chosen))
            self.status_key = (first, "status")
            self.pubs[first] = self.pubs[first] + [Publication("status", DIAGNOSTICS, DIAGNOSTICS_TYPE, sparse=True)]
        self.names = {name: f"{namespace.strip('/')}/{name}".lstrip("/") for name in self.chosen}
        self.nmea = []
        self.nmea_every = max(int(round(scene.sample_rate_hz / NMEA_RATE_HZ)), 1)
        self.statuses = {}

    def _segment(self, a, z, i0, out) -> None:
        """The simulators' messages of samples a .. z − 1 (:meth:`SimulatorStream._segment`), then each
        compass's heading(s), the status once per second of sim time, the NMEA headings."""
        full, self.pubs = self.pubs, self.base_pubs
        try:
            super()._segment(a, z, i0, out)
        finally:
            self.pubs = full
        b = self.block
        ja, jz = a - b.start, z - b.start
        off = int(self.stamp_offset_ns or 0)
        t_ns = b.t_ns[ja:jz]
        marks = np.arange(-(-a // self.every) * self.every, z, self.every)
        statuses = {int(i): [] for i in marks}
        for k, name in enumerate(self.chosen):
            heading = b.streams[name].position[ja:jz, 0]
            got = self.readouts[name].push(t_ns / 1e9, heading)
            for key in HEADING_KEYS:
                if (name, key) in self.imu:
                    cols = imu_columns(heading, got["sigma"], ned=key == "heading_ned")
                    out.messages.setdefault((name, key), []).extend(self.imu[(name, key)].encode(t_ns + off, *cols))
            for i in marks:
                j = int(i) - a
                statuses[int(i)].append(self._status(name, float(t_ns[j]) / 1e9, heading[j], got["sigma"][j],
                                                     got["latitude"][j]))
            if k == 0:
                due = np.arange(-(-a // self.nmea_every) * self.nmea_every, z, self.nmea_every) - a
                self.nmea.extend(zip((t_ns[due] + off).tolist(), heading[due].tolist()))
        if self.status_key is not None and marks.size:
            out.offsets.setdefault(self.status_key, []).extend((marks - i0).tolist())
            out.messages.setdefault(self.status_key, []).extend(
                diagnostic_array_cdr(int(b.t_ns[int(i) - b.start]) + off + EPOCH_NS, statuses[int(i)])
                for i in marks)

    def _status(self, name, t_s, heading_rad, sigma_rad, latitude_rad) -> tuple:
        """One compass's ``DiagnosticStatus`` fields at ``t_s`` (level OK settled, WARN settling)."""
        inst, st = self.chosen[name], self.readouts[name].status(t_s)
        p = inst.p
        settled = st["state"] == SETTLED
        sp = st["settle_point_error_rad"]
        msg = (f"settled at {st['settling_time_s']:.0f} s (ISO 22090-1 3.10: three readings 30 min apart within "
               f"0.7 deg)" if settled else "settling: ISO 22090-1 3.10 not met yet (three readings 30 min apart "
                                           "within 0.7 deg)")
        values = [("state", st["state"]),
                  ("settle_point_error_deg", _text(None if sp is None else math.degrees(sp))),
                  ("speed_correction", _text(bool(p.speed_correction))),
                  ("latitude_setting_deg", _text(math.degrees(latitude_rad))),
                  ("latitude_input", "track" if p.latitude_setting_deg == "track" else "manual"),
                  ("heading_deg", _text(math.degrees(heading_rad) % 360.0)),
                  ("heading_sigma_deg", _text(math.degrees(sigma_rad))),
                  ("settling_time_s", _text(st["settling_time_s"], ".3f")),
                  ("settle_point_readings", str(st["settle_point_readings"])),
                  ("damping", p.damping)]
        self.statuses[name] = dict(values)
        return (OK if settled else WARN, self.names[name], msg, HARDWARE_ID, values)
