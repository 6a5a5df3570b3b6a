"""Thin ROS 2 nodes over the core: parameters in, one core call, messages out.

* :class:`SimulatorNode` (``gyrocompass_sim``, ``pendulum_sim``, ``top_sim``): one core call
  (:func:`~gyro_instrument.recording.joints.joint_streams`: simulate, measure, lay out) then
  publishes the samples as ``sensor_msgs/JointState`` (and the bob position) and owns ``/clock``;
  messages are serialized with numpy (:class:`~gyro_instrument.ros.messages.CdrLayout`), many
  samples at a time, and published as CDR bytes.
* :class:`EstimatorNode`: collects joint samples (raw CDR, decoded in bulk) and calls the core
  estimator.
* :class:`RecorderNode`: raw CDR to MCAP in rosbag2's layout, RELIABLE / KEEP_ALL; an existing
  ``output`` file is refused unless the parameter ``overwrite`` is true (never the scene file).
* :class:`PlayerNode`: republishes a bag's intact messages (every chunk's CRC checked; what was
  lost is logged with its log-time span), driving ``/clock``.

Every node takes ``scene`` (name or path), ``overrides`` (``key.path=value`` strings) and
``duration_s``; a bad value is logged with the field, the value and the valid range, the change
is refused, and the node stays up.
"""

import json
import math
import os

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import ParameterUninitializedException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message

from gyro_instrument.cli import damage_line
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.pipeline import estimable, estimate_records
from gyro_instrument.recording.joints import joint_streams, records_from_joints
from gyro_instrument.recording.bag_layout import bag_format, check_bag_output, open_bag_writer, scan_path
from gyro_instrument.recording.mcap_io import qos_yaml, read_messages
from gyro_instrument.ros import messages as m
from gyro_instrument.ros.topics import CLOCK, ESTIMATOR_TOPICS, bob_topic, joint_topic, scene_topics
from gyro_instrument.scenes import build_instruments, load_scene

RELIABLE_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
RELIABLE_1000 = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE)


class SceneNode(Node):
    """Common scene parameters and their validation."""

    def __init__(self, name, **kwargs):
        super().__init__(name, **kwargs)
        self._declare("scene", "quet_paris")
        self._declare("overrides", Parameter.Type.STRING_ARRAY)
        self._declare("duration_s", 0.0)
        self.scene = None
        self.insts = {}
        self.add_on_set_parameters_callback(self._check_params)

    def _declare(self, name, default):
        if not self.has_parameter(name):
            self.declare_parameter(name, default)

    def value(self, name, default=None):
        """A parameter's value; ``default`` for a declared-but-unset one (string arrays)."""
        try:
            v = self.get_parameter(name).value
        except ParameterUninitializedException:
            return default
        return default if v is None else v

    def _scene_args(self, changes=None):
        vals = {p: self.value(p) for p in ("scene", "overrides", "duration_s")}
        for p in changes or ():
            vals[p.name] = p.value
        overrides = list(vals["overrides"] or [])
        if vals["duration_s"]:
            overrides.append(f"duration_s={float(vals['duration_s'])!r}")
        return vals["scene"], overrides

    def _check_params(self, params):
        if not any(p.name in ("scene", "overrides", "duration_s") for p in params):
            return SetParametersResult(successful=True)
        try:
            load_scene(*self._scene_args(params))
        except SceneError as exc:
            self.get_logger().error(f"parameter refused: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def load(self):
        """Load the scene from the parameters; on bad input log it and return False (stay up)."""
        try:
            self.scene = load_scene(*self._scene_args())
            self.insts = build_instruments(self.scene)
            return True
        except SceneError as exc:
            self.get_logger().error(f"{exc}")
            self.scene, self.insts = None, {}
            return False


class SimulatorNode(SceneNode):
    """Publishes the scene's instruments of the given kinds; owns ``/clock``."""

    def __init__(self, name, kinds, **kwargs):
        super().__init__(name, **kwargs)
        self.kinds = tuple(kinds)
        self._declare("real_time_factor", 1.0)
        self._declare("publish_clock", True)
        self._declare("seed", -1)
        self.index = 0
        self.t_ns = np.zeros(0, dtype=np.int64)
        self.streams = {}
        self.pubs = {}
        self.layouts = {}
        self.clock_pub = None
        self.timer = None
        if self.load():
            self.prepare()

    def prepare(self):
        """One core call: simulate, measure and lay out; then create the publishers."""
        seed = self.get_parameter("seed").value
        self.t_ns, self.streams = joint_streams(self.scene, self.kinds, None if seed < 0 else seed)
        if not self.streams:
            self.get_logger().warning(f"scene {self.scene.name} has no instrument of kinds {', '.join(self.kinds)}")
        for name, s in self.streams.items():
            self.pubs[name] = self.create_publisher(m.JointState, joint_topic(name), RELIABLE_1000)
            self.layouts[name] = m.joint_state_layout(s.names)
            if s.bob_enu_m is not None:
                self.pubs[name + "/bob"] = self.create_publisher(m.PointStamped, bob_topic(name), RELIABLE_1000)
                self.layouts[name + "/bob"] = m.point_stamped_layout(f"{name}_pivot")
        self.clock_pub = (self.create_publisher(m.Clock, CLOCK, RELIABLE_1000)
                          if self.get_parameter("publish_clock").value else None)
        self.index = 0

    @property
    def samples(self):
        return int(self.t_ns.size) if self.streams else 0

    def messages_per_step(self):
        return sum(2 if s.bob_enu_m is not None else 1 for s in self.streams.values())

    def topics(self):
        """Topics this node publishes, each once per sample."""
        out = [CLOCK] if self.clock_pub is not None else []
        for name, s in self.streams.items():
            out.append(joint_topic(name))
            if s.bob_enu_m is not None:
                out.append(bob_topic(name))
        return out

    def publish_steps(self, k):
        """Publish samples ``index`` .. ``index + k - 1`` (fewer at the end): topic by topic, the
        clock first, each topic's messages in sample order (each topic is its own ordered stream);
        return how many samples were published (0 when none remain)."""
        i0, i1 = self.index, min(self.index + max(int(k), 0), self.samples)
        if i1 <= i0:
            return 0
        t = self.t_ns[i0:i1]
        batches = []
        if self.clock_pub is not None:
            batches.append((self.clock_pub, m.CLOCK_LAYOUT.encode(t)))
        for name, s in self.streams.items():
            batches.append((self.pubs[name], self.layouts[name].encode(
                t, s.position[i0:i1], s.velocity[i0:i1], s.effort[i0:i1])))
            if s.bob_enu_m is not None:
                batches.append((self.pubs[name + "/bob"], self.layouts[name + "/bob"].encode(t, s.bob_enu_m[i0:i1])))
        for pub, datas in batches:
            with pub.handle:
                publish = pub.handle.publish_raw
                for data in datas:
                    publish(data)
        self.index = i1
        return i1 - i0

    def publish_step(self):
        """Publish sample ``index`` (clock first); return False when none remain."""
        return self.publish_steps(1) > 0

    def start(self):
        """Standalone pacing: a wall timer at dt / real_time_factor (0: as fast as possible)."""
        if not self.samples:
            return
        rtf = float(self.get_parameter("real_time_factor").value)
        dt = 1.0 / self.scene.sample_rate_hz
        self.timer = self.create_timer(dt / rtf if rtf > 0 else 0.0, self._tick)

    def _tick(self):
        if not self.publish_step():
            self.timer.cancel()
            self.get_logger().info(f"published {self.samples} samples of {', '.join(self.streams)}")


class JointBuffer:
    """The joint samples one instrument's topic delivered, in arrival order: serialized messages
    of the expected layout are kept as bytes and decoded together when the arrays are needed; any
    other accepted message (decoded by rclpy) is appended after them. Both give the same float64
    values bit for bit, so the estimate does not depend on which path a message took."""

    def __init__(self, layout):
        self.layout = layout
        self._raw = []
        self._chunks = []          # [(t_ns int64 (m,), position (m, k), velocity (m, k))]
        self.count = 0

    def __len__(self):
        return self.count

    #: serialized messages kept before they are decoded into arrays (a quarter of the memory)
    DECODE_EVERY = 4096

    def add_raw(self, data):
        """A serialized message that ``layout.matches``."""
        self._raw.append(data)
        self.count += 1
        if len(self._raw) >= self.DECODE_EVERY:
            self._flush()

    def add(self, t_ns, position, velocity):
        self._flush()
        self._chunks.append((np.array([t_ns], dtype=np.int64), np.array([position], dtype=np.float64),
                             np.array([velocity], dtype=np.float64)))
        self.count += 1

    def _flush(self):
        if self._raw:
            t, (pos, vel, _) = self.layout.decode(self._raw)
            self._chunks.append((t, pos, vel))
            self._raw = []

    def arrays(self):
        """(t_ns, position, velocity) of everything received."""
        self._flush()
        if len(self._chunks) > 1:
            self._chunks = [tuple(np.concatenate(parts) for parts in zip(*self._chunks))]
        if not self._chunks:
            k = self.layout.fields[0][1]
            return np.zeros(0, dtype=np.int64), np.zeros((0, k)), np.zeros((0, k))
        return self._chunks[0]

    def last_stamp(self):
        if self._raw:
            return m.cdr_stamp_ns(self._raw[-1]) - m.EPOCH_NS
        return int(self._chunks[-1][0][-1]) if self._chunks else None


class EstimatorNode(SceneNode):
    """Subscribes to the instruments' joint states and publishes latitude and Earth rate."""

    def __init__(self, name="estimator", **kwargs):
        super().__init__(name, **kwargs)
        self._declare("publish_period_s", 0.0)
        self.buffers = {}
        self.subs = {}
        self.rejected = {}
        self.wrong_types = {}
        self.result = None
        self.pubs = {}
        if self.load():
            self.prepare()

    def prepare(self):
        for name, inst in self.insts.items():
            if estimable(inst):
                self.buffers[name] = JointBuffer(m.joint_state_layout(
                    tuple(f"{name}/{j}" for j in inst.JOINTS)))
                self.subs[joint_topic(name)] = self.create_subscription(
                    m.JointState, joint_topic(name), lambda data, n=name: self._on_joint_raw(n, data),
                    RELIABLE_ALL, raw=True)
        for topic, type_name in ESTIMATOR_TOPICS.items():
            self.pubs[topic] = self.create_publisher(m.message_class(type_name), topic, RELIABLE_1000)
        period = float(self.get_parameter("publish_period_s").value)
        if period > 0:
            self.create_timer(period, self.finalize)

    def received(self):
        return sum(len(b) for b in self.buffers.values())

    def check_topic_types(self):
        """Topics the estimator listens to that the graph offers with another type (DDS never
        matches them, so nothing arrives): {topic: [types]}; logged once and put in diagnostics."""
        wrong = {}
        for topic, types in self.get_topic_names_and_types():
            name = topic.strip("/").split("/")[0]
            if name in self.buffers and topic == joint_topic(name):
                others = [t for t in types if t != "sensor_msgs/msg/JointState"]
                if others:
                    wrong[topic] = others
        for topic, types in wrong.items():
            if topic not in self.wrong_types:
                self.get_logger().warning(f"{topic} is published as {', '.join(types)}; the estimator expects "
                                          f"sensor_msgs/msg/JointState and receives nothing of that type")
        self.wrong_types.update(wrong)
        return wrong

    def _reject(self, name, why):
        self.rejected[name] = self.rejected.get(name, 0) + 1
        if self.rejected[name] == 1:
            self.get_logger().warning(f"{joint_topic(name)}: {why}; message ignored")

    def _on_joint_raw(self, name, data):
        """A serialized JointState: kept as bytes when it has the layout the simulators publish
        (the common case, no Python message object), otherwise decoded and checked as any other."""
        buf = self.buffers[name]
        if buf.layout.matches(data):
            buf.add_raw(data)
            return
        try:
            msg = deserialize_message(data, m.JointState)
        except Exception as exc:
            self._reject(name, f"undecodable message ({exc.__class__.__name__})")
            return
        self._on_joint(name, msg)

    def _on_joint(self, name, msg):
        expected = self.insts[name].JOINTS
        names = tuple(n.split("/")[-1] for n in msg.name)
        if names != expected or len(msg.position) != len(expected) or len(msg.velocity) != len(expected):
            self._reject(name, f"joints {list(names)} do not match {list(expected)}")
            return
        self.buffers[name].add(m.stamp_to_release_ns(msg.header.stamp), list(msg.position), list(msg.velocity))

    def estimate(self):
        """Core call on everything received so far (None if nothing usable)."""
        if self.scene is None:
            return None
        samples = {n: b.arrays() for n, b in self.buffers.items() if len(b) >= 3}
        recs = records_from_joints(self.insts, samples)
        return estimate_records(self.scene, {n: self.insts[n] for n in samples}, recs)

    def finalize(self):
        """Estimate and publish; returns the result dict."""
        try:
            self.result = self.estimate()
        except Exception as exc:  # the estimator must never take the node down
            self.get_logger().error(f"estimation failed: {exc.__class__.__name__}: {exc}")
            return None
        if self.result is None:
            return None
        r = self.result
        t = max((b.last_stamp() for b in self.buffers.values() if len(b)), default=0)
        lat = None if r.get("latitude_deg") is None else math.radians(r["latitude_deg"])
        sig = None if r.get("latitude_sigma_deg") is None else math.radians(r["latitude_sigma_deg"])
        self.pubs["/estimator/earth_rate_enu"].publish(m.earth_rate_vector(t, r.get("earth_rate_rad_s"), lat))
        self.pubs["/diagnostics"].publish(m.diagnostics(
            t, "gyro_instrument/estimator", r.get("method") is not None,
            r.get("method") or r.get("reason", ""),
            {"latitude_deg": r.get("latitude_deg"), "latitude_sigma_deg": r.get("latitude_sigma_deg"),
             "earth_rate_rad_s": r.get("earth_rate_rad_s"), "carried_by": r.get("carried_by"),
             "rejected_messages": self.rejected, "wrong_topic_types": self.check_topic_types()}))
        self.pubs["/estimator/latitude_rad"].publish(m.float64(lat))
        self.pubs["/estimator/latitude_sigma_rad"].publish(m.float64(sig))
        self.pubs["/estimator/earth_rate_rad_s"].publish(m.float64(r.get("earth_rate_rad_s")))
        self.pubs["/estimator/earth_rate_sigma_rad_s"].publish(m.float64(r.get("earth_rate_sigma_rad_s")))
        return r


class RecorderNode(SceneNode):
    """Records topics (raw CDR) to MCAP; log time = the message stamp (sim time) when it has one."""

    def __init__(self, name="recorder", **kwargs):
        super().__init__(name, **kwargs)
        self._declare("output", "")
        self._declare("overwrite", False)
        self._declare("topics", Parameter.Type.STRING_ARRAY)
        self._declare("command", "recorder node")
        self._declare("format", "")
        self._declare("max_bag_size", 0)
        self._declare("max_bag_duration", 0.0)
        self.writer = None
        self.counts = {}
        self.subs = {}
        self.last_ns = 0
        if self.load():
            self.prepare()

    def prepare(self):
        out = self.get_parameter("output").value
        if not out:
            self.get_logger().error("output = '' is invalid: give an .mcap path to record to")
            return
        try:
            fmt = bag_format(out, self.value("format", "") or None, self.value("max_bag_size", 0),
                             self.value("max_bag_duration", 0.0), field="format")
            if fmt == "rosbag2":
                scene_file = self.value("scene", "")
                check_bag_output(out, fmt, "output", (scene_file,) if os.path.isfile(scene_file) else (),
                                 self.value("overwrite", False), self.value("max_bag_size", 0),
                                 self.value("max_bag_duration", 0.0))
        except SceneError as exc:
            self.get_logger().error(str(exc))
            return
        if fmt != "rosbag2":       # a bag directory was checked above (bag_layout.check_bag_output)
            directory = os.path.dirname(os.path.abspath(out)) or "."
            if not os.path.isdir(directory) or not os.access(directory, os.W_OK):
                self.get_logger().error(f"output = {out!r} is invalid: directory {directory} is missing or not writable")
                return
            if os.path.isdir(out):
                self.get_logger().error(f"output = {out!r} is invalid: is a directory; give an .mcap file path")
                return
            scene_file = self.value("scene", "")
            if os.path.isfile(scene_file) and os.path.exists(out) and os.path.samefile(out, scene_file):
                self.get_logger().error(f"output = {out!r} is invalid: is the scene file this node reads; record "
                                        f"elsewhere (overwrite never replaces an input)")
                return
            if os.path.lexists(out) and not self.value("overwrite", False):
                self.get_logger().error(f"output = {out!r} is invalid: the file exists and parameter overwrite is "
                                        f"false; set overwrite:=true to replace it, or give a new path")
                return
        types = scene_topics(self.insts)
        wanted = self.value("topics", []) or list(types)
        self.writer = open_bag_writer(out, fmt, self.value("max_bag_size", 0), self.value("max_bag_duration", 0.0),
                                      overwrite=bool(self.value("overwrite", False)))
        # the scene first, so that a recording cut short still says what it holds (replay needs it)
        self.writer.add_metadata("gyro_instrument", {"scene_yaml": json.dumps(dict(self.scene.raw)),
                                                     "scene": self.scene.name, "seed": self.scene.seed,
                                                     "command": self.value("command", "recorder node")})
        self.stamped = {tp for tp, ty in types.items() if ty != "std_msgs/msg/Float64"}
        for topic in wanted:
            if topic not in types:
                self.get_logger().error(f"topics: {topic!r} is not a topic of this scene; valid: {', '.join(types)}")
                continue
            self.writer.add_topic(topic, types[topic], qos_yaml(reliable=True, keep_all=False, depth=1000))
            self.counts[topic] = 0
            self.subs[topic] = self.create_subscription(m.message_class(types[topic]), topic,
                                                        lambda data, tp=topic: self._on_raw(tp, data),
                                                        RELIABLE_ALL, raw=True)

    def received(self):
        return sum(self.counts.values())

    def _on_raw(self, topic, data):
        # Header-first types and Clock carry their sim time; Float64 takes the clock (never earlier
        # than the last stamp, so the file stays deterministic and ordered in lock-step).
        st = m.cdr_stamp_ns(data) if topic in self.stamped else None
        if st is None:
            st = max(self.last_ns, self.get_clock().now().nanoseconds)
        self.last_ns = max(self.last_ns, st)
        self.writer.write(topic, st, data)
        self.counts[topic] += 1

    def close(self, metadata=None, name="gyro_instrument", state="complete"):
        """Write an optional metadata record and finish the file (summary, indexes, footer) with
        the status record ``state`` (``complete``, or ``interrupted`` when a run is cut short)."""
        if self.writer is not None and not self.writer.closed:
            if metadata:
                self.writer.add_metadata(name, metadata)
            self.writer.close(state=state)


class PlayerNode(Node):
    """Republishes a bag on its topics, driving ``/clock`` from the log times."""

    def __init__(self, name="player", **kwargs):
        super().__init__(name, **kwargs)
        self.declare_parameter("bag", "")
        self.declare_parameter("real_time_factor", 1.0)
        self.pubs = {}
        self.queue = []
        self.index = 0
        self.damaged = []
        bag = self.get_parameter("bag").value
        if not bag or not os.path.exists(bag):
            self.get_logger().error(f"bag = {bag!r} is invalid: give an existing .mcap file or rosbag2 bag directory")
            return
        try:
            scan = scan_path(bag)
        except SceneError as exc:
            self.get_logger().error(str(exc))
            return
        self.damaged = scan.damage_dicts(m.EPOCH_NS)
        for d in self.damaged:
            self.get_logger().warning(f"bag {bag}: damaged: {damage_line(d)}; those messages are not published")
        for note in scan.notes:
            self.get_logger().warning(f"bag {bag}: {note}")
        self.queue = list(read_messages(bag, scan=scan))
        self.has_clock = any(tp == CLOCK for tp, *_ in self.queue)
        for topic, type_name, _, _ in self.queue:
            if topic not in self.pubs:
                self.pubs[topic] = self.create_publisher(m.message_class(type_name), topic, RELIABLE_1000)
        if not self.has_clock:
            self.pubs[CLOCK] = self.create_publisher(m.Clock, CLOCK, RELIABLE_1000)

    def publish_next(self):
        """Publish the next message (and a clock tick when the bag has none); False when done."""
        if self.index >= len(self.queue):
            return False
        topic, _, log_ns, data = self.queue[self.index]
        if not self.has_clock:
            from builtin_interfaces.msg import Time
            self.pubs[CLOCK].publish(m.Clock(clock=Time(sec=log_ns // 10 ** 9, nanosec=log_ns % 10 ** 9)))
        self.pubs[topic].publish(data)
        self.index += 1
        return True

    def start(self):
        rtf = float(self.get_parameter("real_time_factor").value)
        self.t_wall0 = None

        def tick():
            if self.index >= len(self.queue):
                self.timer.cancel()
                return
            if rtf > 0:
                now = self.get_clock().now().nanoseconds
                if self.t_wall0 is None:
                    self.t_wall0, self.t_log0 = now, self.queue[0][2]
                while self.index < len(self.queue) and \
                        (self.queue[self.index][2] - self.t_log0) <= (now - self.t_wall0) * rtf:
                    self.publish_next()
            else:
                self.publish_next()
        self.timer = self.create_timer(0.001 if rtf > 0 else 0.0, tick)
