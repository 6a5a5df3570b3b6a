"""``marine_gyrocompass``: :class:`CompassNode`, the ship's gyrocompass as a ROS user meets one (issue 39
item 5): one node per suite that simulates the scene's marine gyrocompasses and publishes, beside their
joint states, each one's heading as ``sensor_msgs/Imu`` on ``<compass>/heading`` at every sample (and in
NED on ``<compass>/heading_ned`` when the instrument's ``ned_heading`` is true), their state on
``diagnostics`` once per second of sim time (one ``DiagnosticStatus`` per compass, named after it:
``state`` settling/settled by ISO 22090-1 §3.10, ``settle_point_error_deg``, ``speed_correction``,
``latitude_setting_deg``, …) and, with ``nmea_udp``, the first compass's heading as ``$HEHDT`` over UDP.

It is a :class:`~gyro_instrument.ros.nodes.simulator.SimulatorNode` (the clock, waiting, restarts and
pacing are the simulators'); its messages come from the core's
:class:`~gyro_instrument.recording.compass_stream.CompassStream`, so the recorder and the lock-step
suite take them as they take every simulator topic.
"""

import math

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import DEFAULT_WINDOW_S
from gyro_instrument.instruments import simulator_kinds
from gyro_instrument.recording.compass_stream import CompassStream
from gyro_instrument.recording.nmea import NmeaUdpSender
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.simulator import SimulatorNode

#: the node's name (the instrument type's ``SIMULATOR_NODE``)
COMPASS_NODE = P.COMPASS_NODE


class CompassNode(SimulatorNode):
    """The ``marine_gyrocompass`` node (module docstring)."""

    SPECS = P.COMPASS

    def __init__(self, name=COMPASS_NODE, kinds=None, **kwargs):
        self.nmea = None
        super().__init__(name, simulator_kinds().get(name, ()) if kinds is None else kinds, **kwargs)

    def _new_stream(self) -> CompassStream:
        seed = self.get_parameter("seed").value
        stream = CompassStream(self.scene, self.insts, self.kinds, None if seed < 0 else seed,
                               float(self.value("window_s", DEFAULT_WINDOW_S)), self.clock_owner,
                               self.frame_prefix, self.get_namespace())
        stream.stamp_offset_ns = self.stamp_offset_ns
        return stream

    def prepare(self) -> None:
        super().prepare()
        rate = self.scene.sample_rate_hz
        if self.stream.chosen and rate < 10.0:
            self.get_logger().warning(
                f"sample_rate_hz = {rate:g}: the compasses' heading is published at every sample, {rate:g} Hz of "
                f"sim time, below the 10 Hz a navigation stack expects (IMO A.821(19): 10 readings a second); "
                f"set sample_rate_hz (e.g. --set sample_rate_hz=10)")
        target = str(self.value("nmea_udp", "") or "")
        if target and self.stream.chosen and self.nmea is None:
            try:
                self.nmea = NmeaUdpSender(target, field="nmea_udp")
                if self.nmea.note:
                    self.get_logger().info(f"nmea_udp: {self.nmea.note}")
            except SceneError as exc:
                self.get_logger().error(f"{exc}; no NMEA sentences are sent")

    def publish_steps(self, k) -> int:
        """:meth:`SimulatorNode.publish_steps`, then the ``$HEHDT`` sentences of those samples."""
        n = super().publish_steps(k)
        stream = self.stream
        if stream is not None and stream.nmea:
            due, stream.nmea = stream.nmea, []
            if self.nmea is not None:
                decimals = int(self.value("nmea_decimals", 1))
                for _, heading in due:
                    try:
                        self.nmea.send_heading(math.degrees(heading), decimals)
                    except OSError as exc:
                        self.get_logger().warning(f"nmea_udp: {exc}", throttle_duration_sec=10.0)
                        break
        return n

    def liveness(self) -> tuple:
        level, message, values = super().liveness()
        if self.stream is not None:
            for name, st in self.stream.statuses.items():
                values[f"{name}.state"] = st["state"]
        return level, message, values

    def teardown(self) -> None:
        super().teardown()
        if self.nmea is not None:
            self.nmea.close()
            self.nmea = None


def simulator_node(name, kinds, **kwargs) -> SimulatorNode:
    """The node simulating ``kinds`` under ``name``: a :class:`CompassNode` for the marine gyrocompass's,
    a :class:`SimulatorNode` otherwise."""
    if name == COMPASS_NODE:
        return CompassNode(name, kinds, **kwargs)
    return SimulatorNode(name, kinds, **kwargs)
