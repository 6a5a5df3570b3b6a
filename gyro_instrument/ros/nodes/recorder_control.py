"""The recorder's controls and liveness (:class:`RecorderControl`, mixed into
:class:`~gyro_instrument.ros.nodes.recorder.RecorderNode`): the services ``~/pause``, ``~/resume`` and
``~/split`` (``std_srvs/srv/Trigger``, as rosbag2's recorder offers pause, resume and split), and the
state it publishes on ``/diagnostics``."""

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.serialization import deserialize_message
from std_srvs.srv import Trigger

from gyro_instrument.ros import messages as m
from gyro_instrument.ros.nodes.base import ERROR, LIVENESS_ID, OK, WARN


class RecorderControl:
    """Pause, resume, split; the recorder's liveness. Needs the recorder's ``writer``, ``done``,
    ``failed``, ``counts``, ``max_ns`` and ``_flush``."""

    def init_control(self) -> None:
        self.paused = False
        self.not_recorded = 0           # messages received while paused (not written)
        self.splits = 0                 # files started by ~/split
        self._srvs = [self.create_service(Trigger, f"~/{name}", getattr(self, f"_srv_{name}"))
                      for name in ("pause", "resume", "split")]

    def recording_state(self) -> str | None:
        """None while recording (paused or not); else why nothing is recorded."""
        if self.failed is not None:
            return "stopped by a full disk"
        if self.writer is None:
            return "not recording: output or scene refused at start-up (see the log; set a valid value)"
        if self.writer.closed or self.done:
            return f"not recording: {self.writer.path} is finished"
        return None

    def _refuse(self, name, response, why):
        response.success, response.message = False, f"{name} refused: {why}"
        self.get_logger().error(response.message)
        return response

    def _srv_pause(self, request, response):
        """``~/pause``: received messages are not written until ``~/resume`` (counted, and named in
        the file's status: a paused recording is ``incomplete``)."""
        why = self.recording_state()
        if why is not None:
            return self._refuse("pause", response, why)
        if not self.paused:
            self.paused = True
            self.get_logger().info(f"paused: {self.writer.path} gets nothing until ~/resume")
        response.success, response.message = True, "paused"
        return response

    def _srv_resume(self, request, response):
        why = self.recording_state()
        if why is not None:
            return self._refuse("resume", response, why)
        if self.paused:
            self.paused = False
            self.get_logger().info(f"resumed: recording to {self.writer.path} ({self.not_recorded} messages not "
                                   f"recorded while paused)")
        response.success, response.message = True, "recording"
        return response

    def _srv_split(self, request, response):
        """``~/split``: the bag directory's current file is closed (status ``split``) and the
        recording continues in the next (rosbag2 layout only: a bare .mcap is one file)."""
        why = self.recording_state()
        if why is not None:
            return self._refuse("split", response, why)
        if not hasattr(self.writer, "split"):
            return self._refuse("split", response, f"output = {self.writer.path!r} is one .mcap file; a split needs "
                                                   f"the rosbag2 layout (format: rosbag2, or an output ending in '/')")
        try:
            self.writer.split()
        except OSError as exc:
            self._disk_full(exc)
            return self._refuse("split", response, str(exc))
        self.splits += 1
        name = self.writer.files[-1]["path"]
        self.get_logger().info(f"split: recording continues in {name}")
        response.success, response.message = True, f"recording continues in {name}"
        return response

    @property
    def exit_status(self) -> int:
        """The process's exit status: 1 when a full disk stopped the recording, else 0."""
        return 1 if self.failed is not None else 0

    @staticmethod
    def is_liveness(data) -> bool:
        """True for a node's liveness status on /diagnostics (not recorded: it describes the live
        nodes, and a played bag would bring back nodes that are not running)."""
        try:
            arr = deserialize_message(data, DiagnosticArray)
        except Exception:
            return False
        return bool(arr.status) and all(st.hardware_id == LIVENESS_ID for st in arr.status)

    def liveness(self) -> tuple:
        values = {"messages": sum(self.counts.values()), "not_recorded_paused": self.not_recorded,
                  "output": self.writer.path if self.writer is not None else None}
        if self.failed is not None:
            return ERROR, f"disk full: {self.failed.line('output')}", values
        if self.writer is None:
            return ERROR, "not recording: output or scene refused at start-up (see the log)", values
        if self.writer.closed or self.done:
            return OK, f"finished {self.writer.path}", values
        if self.paused:
            return WARN, "paused (~/resume to record again)", values
        return OK, "recording" if values["messages"] else "recording: waiting for the first message", values

    def sim_time_ns(self) -> int:
        return max(self.max_ns - m.EPOCH_NS, 0) if self.max_ns else 0
