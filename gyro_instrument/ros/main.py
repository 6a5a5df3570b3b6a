"""Entry points of the nodes (``ros2 run gyro_instrument <node>``), Jazzy ``main()`` pattern, each
with ``--help`` (parameters with their descriptors, topics, an example) before ``--ros-args``."""

import signal
import sys

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from rclpy._rclpy_pybind11 import RCLError

from gyro_instrument.instruments import REGISTRY, simulator_kinds
from gyro_instrument.recording.topics import (CLOCK, CLOCK_TYPE, ESTIMATOR_TOPICS, IMU_TYPE, VISUAL_PERIOD_S, heading_frame,
                                              heading_topic, publications)
from gyro_instrument.ros import params as P
from gyro_instrument.ros.dds_profile import use_package_profile
from gyro_instrument.ros.log_dir import ensure_log_dir

#: the nodes that are not simulators (a simulator's help is derived from the instruments it hosts)
_SUMMARIES = {
    "estimator": "Estimates latitude and Earth rate from the instruments' joint states.",
    "recorder": "Records the scene's topics to MCAP (rosbag2 layout, sim-time log times, completeness status).",
    "player": "Plays an MCAP bag back to DDS, driving clock; exits at the end (or loops).",
}
_TOPICS = {
    "estimator": ["subscribes <instrument>/joint_states, clock"] + [f"{t} ({ty})" for t, ty in ESTIMATOR_TOPICS.items()]
                 + [f"{heading_topic('<gyro>')} ({IMU_TYPE}, {heading_frame('<gyro>')}): a horizontal gyroscope's heading, "
                    f"from the first swing at 10 Hz of sim time (every sample when slower) and with the estimate",
                    "static_transforms (geometry_msgs/msg/TransformStamped, latched): the frames it names"],
    "recorder": ["subscribes every topic of the scene (or the parameter topics)",
                 "services ~/pause, ~/resume, ~/split (std_srvs/srv/Trigger)",
                 "writes tf_static (tf2_msgs/msg/TFMessage) to the bag: the scene's static frames"],
    "player": ["the bag's topics (relative names, each offered the QoS the bag recorded), clock"],
}
#: what a simulator node publishes beyond its instruments' publications
_MORE = {P.COMPASS_NODE: [
    "diagnostics (diagnostic_msgs/msg/DiagnosticArray), once per second of sim time: one status per compass, "
    "named after it, keys state (settling / settled: ISO 22090-1 3.10), settle_point_error_deg, speed_correction, "
    "latitude_setting_deg, ...",
    "with nmea_udp: $HEHDT over UDP, the first compass's heading at 10 Hz of sim time"]}
#: every node run alone publishes its state on /diagnostics (msg_docs/topics.md, "Services and liveness")
LIVENESS_LINE = "diagnostics (diagnostic_msgs/msg/DiagnosticArray): this node's state every 0.5 s"
_EXAMPLES = {
    "estimator": "estimator --ros-args -p scene:=quet_paris",
    "recorder": "recorder --ros-args -p scene:=quet_paris -p output:=out.mcap -p stop_when_complete:=true",
    "player": "player --ros-args -p bag:=bags/quet_paris.mcap -p real_time_factor:=0",
}


def simulator_topics(kinds) -> list:
    """``--help`` lines of the topics a simulator hosting ``kinds`` publishes (from each type's
    :func:`~gyro_instrument.recording.topics.publications`), then the clock."""
    lines = []
    for kind in kinds:
        for p in publications("<instrument>", REGISTRY[kind]):
            frame = f", {p.frame_id}" if p.frame_id else ""
            rate = f"once per {VISUAL_PERIOD_S:g} s of sim time" if p.sparse else "per sample"
            line = f"{p.topic} ({p.type_name}{frame}), {rate}"
            if line not in lines:
                lines.append(line)
    return lines + [f"{CLOCK} ({CLOCK_TYPE}): published with publish_clock:=true, else subscribed (followed)",
                    "service ~/restart (std_srvs/srv/Trigger): restart the run from t = 0, every simulator together",
                    "static_transforms (geometry_msgs/msg/TransformStamped, latched): the frames its messages name"]


def help_text(name) -> str:
    """``--help`` of node ``name``: a simulator's summary, topics and example follow from the
    instrument types it hosts (``SIMULATOR_NODE``), so a new simulator node needs no table here."""
    kinds = simulator_kinds().get(name)
    if kinds is not None:
        summary = f"Simulates the scene's instruments of types {', '.join(kinds)} and publishes what they show."
        return P.help_text(name, summary, P.NODE_SPECS[name], simulator_topics(kinds) + _MORE.get(name, [])
                           + [LIVENESS_LINE],
                           f"{name} --ros-args -p scene:=SCENE -p publish_clock:=true -p real_time_factor:=0")
    return P.help_text(name, _SUMMARIES[name], P.NODE_SPECS[name], _TOPICS[name] + [LIVENESS_LINE], _EXAMPLES[name])


def _wants_help(name, args):
    argv = list(sys.argv[1:] if args is None else args[1:])
    if "--ros-args" in argv:
        argv = argv[:argv.index("--ros-args")]
    if "-h" in argv or "--help" in argv:
        print(help_text(name))
        return True
    return False


class _Stop:
    """SIGINT / SIGTERM ask the spin loop to stop; the context stays valid until the node's last
    words (the recorder's status, a final log line) are out and the node is destroyed, so no log
    message goes to a dead ``/rosout`` publisher ("publisher's context is invalid")."""

    def __init__(self):
        self.asked = False
        self.previous = {}

    def install(self):
        for sig in (signal.SIGINT, signal.SIGTERM):
            self.previous[sig] = signal.signal(sig, self._handler)

    def _handler(self, signum, frame):
        if self.asked:              # a second Ctrl-C: the default behaviour
            raise KeyboardInterrupt
        self.asked = True

    def restore(self):
        for sig, handler in self.previous.items():
            signal.signal(sig, handler)


_STOP = _Stop()


def _spin(node, on_exit=None):
    """Spin until SIGINT/SIGTERM (or an external shutdown) or until the node says it is ``done``;
    then the node's exit work, the node destroyed, and only then the context shut down."""
    from gyro_instrument.ros.nodes.base import drain
    ex = SingleThreadedExecutor(context=node.context)
    ex.add_node(node)
    try:
        while node.context.ok() and not _STOP.asked and not getattr(node, "done", False):
            try:
                ex.spin_once(timeout_sec=0.1)
                drain(node)
            except RCLError:
                if node.context.ok():
                    raise
                break                      # SIGINT/SIGTERM shut the context down mid-wait
        if getattr(node, "done", False) and node.context.ok():
            # done (the recorder: every expected message recorded): what already arrived on the other
            # topics (live headings published before the final estimate) is taken before the exit
            for _ in range(100):
                if not drain(node):
                    break
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        try:
            if on_exit:
                on_exit()
        finally:
            ex.remove_node(node)
            ex.shutdown()
            node.destroy_node()
            rclpy.try_shutdown()
            _STOP.restore()


def _run(name, make, args=None, on_exit=None):
    if _wants_help(name, args):
        return 0
    extra = ensure_log_dir()           # a read-only or unset HOME: a writable log directory first
    use_package_profile()              # the package's Fast DDS timing, unless the user chose a profile
    if extra:
        args = list(sys.argv if args is None else args) + extra
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    _STOP.install()
    node = make()
    node.stop_asked = lambda: _STOP.asked
    node.start()
    _spin(node, on_exit=(lambda: on_exit(node)) if on_exit else None)
    return getattr(node, "exit_status", 0)


def _simulator(name, args=None):
    from gyro_instrument.ros.nodes.compass import simulator_node
    return _run(name, lambda: simulator_node(name, simulator_kinds().get(name, ())), args)


def gyrocompass_sim(args=None) -> int:
    return _simulator("gyrocompass_sim", args)


def pendulum_sim(args=None) -> int:
    return _simulator("pendulum_sim", args)


def top_sim(args=None) -> int:
    return _simulator("top_sim", args)


def marine_gyrocompass(args=None) -> int:
    return _simulator("marine_gyrocompass", args)


def estimator(args=None) -> int:
    from gyro_instrument.ros.nodes import EstimatorNode
    return _run("estimator", EstimatorNode, args)


def recorder(args=None) -> int:
    from gyro_instrument.ros.nodes import RecorderNode
    # SIGINT (or stop_when_complete) finishes a complete, indexed MCAP with its status
    return _run("recorder", RecorderNode, args, on_exit=lambda node: node.close())


def player(args=None) -> int:
    from gyro_instrument.ros.nodes import PlayerNode
    return _run("player", PlayerNode, args)


if __name__ == "__main__":
    sys.exit(estimator())
