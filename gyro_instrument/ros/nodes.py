"""Thin ROS 2 nodes over the core: parameters in, one core call, messages out.

* :class:`SimulatorNode` (``gyrocompass_sim``, ``pendulum_sim``, ``top_sim``): one core iterator
  (:func:`~gyro_instrument.recording.joints.joint_blocks`: integrate, measure, lay out one window of
  ``window_s`` simulated seconds at a time, over ``Instrument.stream``) whose blocks it publishes as
  it gets them, integrating the next only when the samples due go past the current one, as
  ``sensor_msgs/JointState`` (and the bob position); messages are
  serialized with numpy (:class:`~gyro_instrument.recording.cdr.CdrLayout`), many samples at a
  time, and published as CDR bytes. Run alone (:meth:`SimulatorNode.start`) it waits for the
  subscribers the scene expects (``wait_for``), then either owns ``clock`` (``publish_clock``) and
  paces it, or follows the owner's clock, publishing each sample when sim time reaches it.
* :class:`EstimatorNode`: collects joint samples (raw CDR, decoded in bulk, at most 4096 kept as
  bytes) into arrays of what it fits (:class:`JointBuffer`) and calls the core estimator; run alone
  it publishes once every expected sample has arrived.
* :class:`RecorderNode`: raw CDR to MCAP in rosbag2's layout, RELIABLE / KEEP_ALL, log time =
  sim time, written in log-time order; knows what the scene publishes and marks the file
  ``complete`` or ``incomplete`` with per-topic counts. An existing ``output`` file is refused
  unless the parameter ``overwrite`` is true (never the scene file).
* :class:`PlayerNode`: republishes a bag's intact messages (every chunk's CRC checked; what was
  lost is logged with its log-time span), driving ``clock``; waits for its subscribers, exits at
  the end (or loops).

Topic names are relative (``-r __ns:=/ship1`` moves them). Every parameter is declared with a
descriptor (:mod:`gyro_instrument.ros.params`); a bad value is logged with the field, the value
and the valid range, the change is refused, and the node stays up.
"""

import heapq
import json
import math
import os
import time

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock as RclClock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import deserialize_message, serialize_message

from gyro_instrument.cli import damage_line
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.adequacy import InadequateData
from gyro_instrument.core.memory import sample_count
from gyro_instrument.core.scene import DEFAULT_WINDOW_S
from gyro_instrument.estimators.pipeline import estimable, estimate_records
from gyro_instrument.recording.joints import joint_blocks, records_from_joints
from gyro_instrument.recording.bag_layout import bag_format, check_bag_output, open_bag_writer, scan_path
from gyro_instrument.recording.mcap_io import qos_yaml, read_messages
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.instruments import simulator_kinds
from gyro_instrument.ros.topics import (CLOCK, ESTIMATOR_TOPICS, TRAIL, axis_topic, resolve, visual_every,
                                        bob_topic, contact_point_topic, joint_topic, markers_topic, scene_topics,
                                        swing_plane_topic)
from gyro_instrument.recording.visual import SwingPlaneStream, axis_directions
from gyro_instrument.scenes import build_instruments, load_scene

RELIABLE_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
RELIABLE_1000 = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE)
#: the estimator's results: latched (the last estimate kept for subscribers that ask for
#: TRANSIENT_LOCAL; a VOLATILE subscriber, the recorder's, still matches and gets new ones)
LATCHED = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
#: publishers of a node run alone: a sample is kept until every matched subscriber has it, however
#: far ahead of a slow subscriber the publisher runs (real-time factor 0), so nothing is overwritten
PUBLISH_ALL = RELIABLE_ALL
#: timers that pace or wait run on the steady clock: never on sim time (a clock owner would wait for itself)
STEADY = RclClock(clock_type=ClockType.STEADY_TIME)
#: samples (or messages) a node run alone publishes per timer tick at real-time factor 0
FLOW_BATCH = 200
ACK_TIMEOUT = Duration(seconds=5)


def _acked(node, pubs):
    """Wait until every subscriber acknowledged what ``pubs`` published; warn once per topic if not."""
    for pub in pubs:
        if not pub.wait_for_all_acked(ACK_TIMEOUT):
            if pub.topic_name not in node._ack_warned:
                node._ack_warned.add(pub.topic_name)
                node.get_logger().warning(f"{pub.topic_name}: a subscriber did not acknowledge within 5 s "
                                          f"(slow or gone); publishing on")


class SceneNode(Node):
    """Parameters declared from a table with descriptors, checked on every change; the scene."""

    SPECS = P.SCENE
    #: a change of these reloads the scene and restarts the run (simulators, estimator)
    RESTART_ON = P.SCENE_NAMES

    def __init__(self, name, specs=None, **kwargs):
        super().__init__(name, **kwargs)
        self.specs = specs or self.SPECS
        self.refused = P.declare_all(self, self.specs)
        self.scene = None
        self.insts = {}
        self.clock_owner = False
        self.standalone = False
        self._ack_warned = set()
        self._restart = False
        self.add_pre_set_parameters_callback(P.pre_set_checker(self, self.specs))
        self.add_on_set_parameters_callback(self._check_params)
        self.add_post_set_parameters_callback(self._after_set)

    def value(self, name, default=None) -> object:
        """A parameter's value (``default`` if it is not declared)."""
        if not self.has_parameter(name):
            return default
        v = self.get_parameter(name).value
        return default if v is None else v

    def refuse_sim_time_if_owner(self) -> None:
        """A clock owner started with ``use_sim_time:=true`` would wait for its own clock: refused."""
        if self.clock_owner and self.value("use_sim_time", False):
            self.get_logger().error("use_sim_time = true is invalid on the clock owner (it publishes clock and "
                                    "would wait for itself): use_sim_time set back to false")
            self.set_parameters([Parameter("use_sim_time", value=False)])

    def _scene_args(self, changes=None):
        vals = {p: self.value(p) for p in P.SCENE_NAMES}
        for p in changes or ():
            if p.name in vals:
                vals[p.name] = p.value
        overrides = list(vals["overrides"] or [])
        if vals["duration_s"]:
            overrides.append(f"duration_s={float(vals['duration_s'])!r}")
        return vals["scene"], overrides

    def _check_params(self, params):
        for p in params:
            if p.name == "use_sim_time" and p.value is True and self.clock_owner:
                reason = ("use_sim_time = true is invalid on the clock owner: it publishes clock and would wait "
                          "for itself")
                self.get_logger().error(f"parameter refused: {reason}")
                return SetParametersResult(successful=False, reason=reason)
        if not any(p.name in P.SCENE_NAMES for p in params):
            return SetParametersResult(successful=True)
        try:
            load_scene(*self._scene_args(params))
        except SceneError as exc:
            self.get_logger().error(f"parameter refused: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _after_set(self, params):
        for p in params:
            self.refused.pop(p.name, None)
        if any(p.name in self.RESTART_ON for p in params):
            self._restart = True
            if not self.standalone:
                self.restart()

    def restart(self) -> None:
        """Reload the scene after a parameter change (subclasses tear down and start again)."""
        self._restart = False

    def load(self) -> bool:
        """Load the scene from the parameters; on bad input log it and return False (stay up)."""
        bad = [n for n in self.refused if n in P.SCENE_NAMES or n == "seed"]
        if bad:
            self.get_logger().error(f"not running: {', '.join(bad)} refused at start-up; set a valid value "
                                    f"(ros2 param set) to start")
            self.scene, self.insts = None, {}
            return False
        try:
            self.scene = load_scene(*self._scene_args())
            self.insts = build_instruments(self.scene)
            return True
        except SceneError as exc:
            self.get_logger().error(f"{exc}")
            self.scene, self.insts = None, {}
            return False

    def _named_nodes_ready(self, expected):
        """expected: {node name: [resolved topics it must subscribe to]} -> names still missing."""
        ns = self.get_namespace()
        missing = []
        for node_name, topics in expected.items():
            for topic in topics:
                infos = self.get_subscriptions_info_by_topic(topic)
                if not any(i.node_name == node_name and i.node_namespace == ns for i in infos):
                    missing.append(node_name)
                    break
        return missing

    def _unmatched(self, pubs):
        """Topics with a subscription the graph knows of that a publisher has not matched yet."""
        return [pub.topic_name for pub in pubs
                if pub.get_subscription_count() < len(self.get_subscriptions_info_by_topic(pub.topic_name))]

    # ---- one clock per namespace -------------------------------------------------------------------

    def clock_remap_note(self, topic) -> str:
        """What sim-time consumers need when this node's clock is not ``/clock``: rclpy's time source
        subscribes to the absolute ``/clock`` whatever the node's namespace."""
        if topic == "/clock":
            return ""
        return (f"; a use_sim_time node reads this clock only when started with -r /clock:={topic} (rclpy's time "
                f"source listens on the absolute /clock)")

    def watch_clock(self, topic) -> None:
        """Before owning ``topic``: count the ticks another node publishes on it (:meth:`other_clock_owner`)."""
        self._foreign_ticks = 0

        def tick(_data):
            self._foreign_ticks += 1
        self._clock_watch = self.create_subscription(m.Clock, topic, tick, RELIABLE_ALL, raw=True)

    def other_clock_owner(self, topic) -> str | None:
        """Why this node must not publish ``topic`` (None when it may): another node publishes it and
        either ticks were seen from it while this node waited, or it is named before this one (two
        owners started together: the first name keeps the clock). Stops the watch."""
        watch = getattr(self, "_clock_watch", None)
        if watch is not None:
            self.destroy_subscription(watch)
            self._clock_watch = None
        me = resolve(self.get_namespace(), self.get_name())
        others = sorted({resolve(i.node_namespace, i.node_name) for i in self.get_publishers_info_by_topic(topic)}
                        - {me})
        if not others:
            return None
        ticks = getattr(self, "_foreign_ticks", 0)
        if ticks or others[0] < me:
            seen = f"{ticks} ticks seen from it" if ticks else f"it was named first ({others[0]} < {me})"
            return (f"another node already publishes {topic}: {', '.join(others)} ({seen}); one clock owner per "
                    f"namespace, so this node does not publish it (no duplicate or backwards ticks)")
        return None


class SimulatorNode(SceneNode):
    """Publishes the scene's instruments of the given kinds; owns ``clock`` when ``publish_clock``."""

    SPECS = P.SIMULATOR
    RESTART_ON = P.SCENE_NAMES + ("seed",)

    def __init__(self, name, kinds, pub_qos=PUBLISH_ALL, **kwargs):
        super().__init__(name, **kwargs)
        self.kinds = tuple(kinds)
        self.pub_qos = pub_qos
        self.clock_owner = bool(self.value("publish_clock", False))
        self.refuse_sim_time_if_owner()
        self.index = 0
        self.n_total = 0
        self.chosen = {}
        self.blocks = self.block = None
        self.blocks_pulled = 0
        self.streams = {}
        self.pubs = {}
        self.layouts = {}
        self.clock_pub = None
        self.clock_sub = None
        self.timer = None
        self.visual = {}
        self.offsets = {}
        self.state = "idle"
        self._ctl = None
        if self.load():
            self.prepare()

    def prepare(self) -> None:
        """Create the publishers and the block iterator (:func:`joint_blocks`): nothing is integrated
        until the first publish, and then one window of ``window_s`` simulated seconds at a time."""
        seed = self.get_parameter("seed").value
        self.chosen = {n: inst for n, inst in self.insts.items() if inst.type_name in self.kinds}
        if not self.chosen:
            self.get_logger().warning(f"scene {self.scene.name} has no instrument of kinds {', '.join(self.kinds)}")
        self.n_total = sample_count(self.scene) if self.chosen else 0
        self.step_ns = 1e9 / self.scene.sample_rate_hz
        self.blocks = joint_blocks(self.scene, self.kinds, None if seed < 0 else seed,
                                   float(self.value("window_s", DEFAULT_WINDOW_S)), self.insts) if self.chosen else None
        self.block = None
        self.blocks_pulled = 0
        for name, inst in self.chosen.items():
            names = tuple(f"{name}/{j}" for j in inst.JOINTS)
            self.pubs[name] = self.create_publisher(m.JointState, joint_topic(name), self.pub_qos)
            self.layouts[name] = m.joint_state_layout(names)
            if inst.IS_PENDULUM:
                self.pubs[name + "/bob"] = self.create_publisher(m.PointStamped, bob_topic(name), self.pub_qos)
                self.layouts[name + "/bob"] = m.point_stamped_layout(f"{name}_pivot")
            if inst.SHOWS_CONTACT_POINT:
                self.pubs[name + "/contact"] = self.create_publisher(m.PointStamped, contact_point_topic(name),
                                                                     self.pub_qos)
                self.layouts[name + "/contact"] = m.point_stamped_layout(f"{name}_body")
        self.streams = {name: None for name in self.chosen}
        self._prepare_visuals()
        self.clock_pub = self.create_publisher(m.Clock, CLOCK, self.pub_qos) if self.clock_owner else None
        self.index = 0

    def _prepare_visuals(self):
        """What there is to see, once per second of sim time: the swing-plane azimuth
        (pendulums), the rotor-axis direction (plane and free gyroscopes), and markers in
        ``site_enu``; instruments stand 3 m apart along east in the scene's order. Computed block by
        block (:meth:`_visual_block`)."""
        self.visual = {}
        self.visual_every = visual_every(self.scene.sample_rate_hz)
        order = list(self.insts)
        n, t_last = self.n_total, round((self.n_total - 1) * self.step_ns) / 1e9 if self.n_total else 0.0
        for name, inst in self.chosen.items():
            v = {"origin": np.array([3.0 * order.index(name), 0.0, 0.0])}
            if inst.IS_PENDULUM:
                l = inst.pendulum_length_m()
                v.update(plane_stream=SwingPlaneStream(2 * math.pi * math.sqrt(l / 9.80665), n, t_last), length=l,
                         half=1e-3, trail=np.zeros((0, 3)))
                self.pubs[name + "/plane"] = self.create_publisher(m.JointState, swing_plane_topic(name), self.pub_qos)
                self.layouts[name + "/plane"] = m.joint_state_layout((f"{name}/swing_plane_azimuth",))
            if inst.SHOWS_AXIS:
                v["axis"] = None
                self.pubs[name + "/axis"] = self.create_publisher(m.Vector3Stamped, axis_topic(name), self.pub_qos)
                self.layouts[name + "/axis"] = m.point_stamped_layout(m.SITE_FRAME)
            if len(v) > 1:
                self.pubs[name + "/markers"] = self.create_publisher(m.message_class(
                    "visualization_msgs/msg/MarkerArray"), markers_topic(name), self.pub_qos)
                self.visual[name] = v

    def _visual_block(self, block):
        """The visuals of a new block: swing plane (continued), the largest deflection so far (the
        plane line's half length), the bob trail's history, the rotor axes."""
        t_s = block.t_ns / 1e9
        keep = self.visual_every * TRAIL
        for name, v in self.visual.items():
            s = block.streams[name]
            if "plane_stream" in v:
                az, rate = v["plane_stream"].push(t_s, s.position[:, 0], s.position[:, 1])
                v["plane"], v["plane_rate"] = az[:, None], rate[:, None]
                biggest = np.fmax.reduce(s.position[:, 2]) if s.position.shape[0] else np.nan
                if np.isfinite(biggest):
                    v["half"] = max(v["half"], float(biggest) * v["length"])
                # trail: the last TRAIL visual periods before the block, then the block
                v["trail"] = np.concatenate([v["trail"][-keep:], s.bob_enu_m])
                v["trail_start"] = block.start - (v["trail"].shape[0] - s.bob_enu_m.shape[0])
            if "axis" in v:
                v["axis"] = axis_directions(self.insts[name], s)

    def _next_block(self):
        """The next :class:`JointBlock` (integrating it), or None at the end of the run."""
        block = next(self.blocks, None) if self.blocks is not None else None
        if block is not None:
            self.blocks_pulled += 1
            self.streams = block.streams
            self._visual_block(block)
        self.block = block
        return block

    def block_ready(self, k) -> bool:
        """True when the next ``k`` samples (or the rest of the run) are already integrated: a
        :meth:`publish_steps` of ``k`` integrates nothing (the suite commits the bag before it does)."""
        b = self.block
        end = 0 if b is None else b.start + b.t_ns.size
        return self.index >= self.samples or min(self.index + k, self.samples) <= end

    def _markers(self, name, i, tm):
        """Markers of global sample ``i`` (stamp ``tm``) of the current block."""
        v, s, j = self.visual[name], self.block.streams[name], i - self.block.start
        if "axis" in v:
            return m.axis_markers(tm, name, v["origin"], np.nan_to_num(v["axis"][j]), 1.0)
        l = v["length"]
        size = min(max(0.03 * l, 0.05), 2.0)
        a = v["trail_start"]
        trail = v["trail"][max(i - self.visual_every * TRAIL, 0) - a:i + 1 - a:self.visual_every]
        v["msg"] = m.pendulum_markers(tm, name, v["origin"] + np.array([0.0, 0.0, l]), np.nan_to_num(s.bob_enu_m[j]),
                                      np.nan_to_num(trail), float(v["plane"][j, 0]), v["half"], size, v.get("msg"))
        return v["msg"]

    def teardown(self) -> None:
        for t in (self.timer,):
            if t is not None:
                self.destroy_timer(t)
        self.timer = None
        for attr in ("clock_sub", "_clock_watch"):
            if getattr(self, attr, None) is not None:
                self.destroy_subscription(getattr(self, attr))
                setattr(self, attr, None)
        for pub in list(self.pubs.values()) + ([self.clock_pub] if self.clock_pub is not None else []):
            self.destroy_publisher(pub)
        self.pubs, self.layouts, self.streams, self.clock_pub, self.visual = {}, {}, {}, None, {}
        self.blocks, self.block, self.chosen, self.n_total = None, None, {}, 0
        self.index = 0

    def restart(self) -> None:
        """A scene (or seed) change: stop, reload, and run again from t = 0."""
        super().restart()
        self.teardown()
        if self.load():
            self.prepare()
            self.get_logger().info(f"scene {self.scene.name}: restarting the run from t = 0")
            if self.standalone:
                self._wait_begin()
        else:
            self.state = "idle"

    @property
    def samples(self) -> int:
        """Samples of the whole run (0 when the scene has no instrument of this node's kinds)."""
        return self.n_total

    def messages_per_step(self) -> int:
        return sum(1 + inst.IS_PENDULUM + inst.SHOWS_CONTACT_POINT for inst in self.chosen.values())

    def publishers(self) -> list:
        """This node's publishers, the clock first."""
        return ([self.clock_pub] if self.clock_pub is not None else []) + list(self.pubs.values())

    def topics(self) -> list:
        """Topics this node publishes (fully qualified), each once per sample."""
        return [pub.topic_name for pub in self.publishers()]

    def sample_index(self, t_ns) -> int:
        """How many samples have a stamp <= ``t_ns`` (ns from release): stamps are round(i · 1e9 / f)."""
        i = int(math.floor(t_ns / self.step_ns)) + 2
        while i > 0 and round((i - 1) * self.step_ns) > t_ns:
            i -= 1
        return min(i, self.samples)

    def publish_steps(self, k) -> int:
        """Publish samples ``index`` .. ``index + k - 1`` (fewer at the end): topic by topic, the
        clock first, each topic's messages in sample order (each topic is its own ordered stream);
        return how many samples were published (0 when none remain). Blocks are integrated here,
        when the samples asked for go past the current one."""
        i0 = self.index
        i1 = min(i0 + max(int(k), 0), self.samples)
        if i1 <= i0:
            return 0
        batches = {}
        self.offsets = {}
        while self.index < i1:
            b = self.block
            if b is None or self.index >= b.start + b.t_ns.size:
                if self._next_block() is None:
                    break
                continue
            self._segment(self.index, min(i1, b.start + b.t_ns.size), i0, batches)
        for pub, datas in batches.values():
            with pub.handle:
                publish = pub.handle.publish_raw
                for data in datas:
                    publish(data)
        return self.index - i0

    def _segment(self, a, z, i0, batches):
        """Encode samples a .. z - 1 (all in the current block) into ``batches`` {key: (publisher, [bytes])}."""
        b = self.block
        ja, jz = a - b.start, z - b.start
        t = b.t_ns[ja:jz]

        def add(key, pub, datas):
            batches.setdefault(key, (pub, []))[1].extend(datas)
        if self.clock_pub is not None:
            add("clock", self.clock_pub, m.CLOCK_LAYOUT.encode(t))
        for name, s in b.streams.items():
            add(name, self.pubs[name], self.layouts[name].encode(t, s.position[ja:jz], s.velocity[ja:jz],
                                                                 s.effort[ja:jz]))
            if s.bob_enu_m is not None:
                add(name + "/bob", self.pubs[name + "/bob"], self.layouts[name + "/bob"].encode(t, s.bob_enu_m[ja:jz]))
            if name + "/contact" in self.pubs:
                add(name + "/contact", self.pubs[name + "/contact"], self.layouts[name + "/contact"].encode(
                    t, s.extra["contact_point_m"][ja:jz]))
            v = self.visual.get(name)
            if v is None:
                continue
            # once per VISUAL_PERIOD_S of sim time: cheap beside the samples themselves
            every = self.visual_every
            marks = np.arange(-(-a // every) * every, z, every)
            local = marks - b.start
            tm = b.t_ns[local]
            if "plane" in v:
                add(name + "/plane", self.pubs[name + "/plane"], self.layouts[name + "/plane"].encode(
                    tm, v["plane"][local], v["plane_rate"][local], np.zeros((marks.size, 1))))
            if "axis" in v:
                add(name + "/axis", self.pubs[name + "/axis"], self.layouts[name + "/axis"].encode(tm, v["axis"][local]))
            add(name + "/markers", self.pubs[name + "/markers"],
                [serialize_message(self._markers(name, int(i), int(ti))) for i, ti in zip(marks, tm)])
            for key in ("/plane", "/axis", "/markers"):
                if name + key in self.pubs:
                    self.offsets.setdefault(self.pubs[name + key].topic_name, []).extend((marks - i0).tolist())
        self.index = z

    def publish_step(self) -> bool:
        """Publish sample ``index`` (clock first); return False when none remain."""
        return self.publish_steps(1) > 0

    # ---- run alone (ros2 run): wait for subscribers, then own or follow the clock -----------------

    def expected_subscribers(self) -> dict:
        """{node name: [topics it must subscribe to]} from ``wait_for`` and the scene: the recorder
        every topic, the estimator the joint states of estimable instruments, another name any of
        this node's topics; the clock owner also waits for the scene's other simulators (they
        subscribe to clock once their own subscribers are matched)."""
        mine = self.topics()
        out = {}
        for name in self.value("wait_for", []):
            if name == "recorder":
                out[name] = mine
            elif name == "estimator":
                topics = [self.pubs[n].topic_name for n, inst in self.insts.items()
                          if n in self.pubs and estimable(inst)]
                if topics:
                    out[name] = topics
            elif mine:
                out[name] = mine[:1]
        if self.clock_owner and self.clock_pub is not None:
            types = {inst.type_name for inst in self.insts.values()}
            for sim, kinds in simulator_kinds().items():
                if sim != self.get_name() and types & set(kinds):
                    out[sim] = [self.clock_pub.topic_name]
        return out

    def start(self) -> None:
        """Run alone: log what is published, wait for the expected subscribers (at most
        ``wait_timeout_s``), then publish (owner: paced by ``real_time_factor``; follower: as the
        owner's clock reaches each sample)."""
        self.standalone = True
        self._ctl = self.create_timer(0.05, self._control, clock=STEADY)
        if self.samples:
            self._wait_begin()

    def startup_line(self) -> str:
        pubs = ", ".join(f"{pub.topic_name} ({pub.msg_type.__module__.split('.')[0]}/msg/{pub.msg_type.__name__})"
                         for pub in self.publishers())
        clock = ("owns the clock (publish_clock = true): publishes " + self.clock_pub.topic_name
                 + self.clock_remap_note(self.clock_pub.topic_name)
                 if self.clock_pub is not None else "follows the clock another node publishes (publish_clock = false)")
        return (f"scene {self.scene.name}: {self.samples} samples at {self.scene.sample_rate_hz:g} Hz; publishes "
                f"{pubs}; {clock}")

    def _wait_begin(self):
        self.get_logger().info(self.startup_line())
        self.state = "waiting"
        self._wait_t0 = time.monotonic()
        if self.clock_pub is not None:
            self.watch_clock(self.clock_pub.topic_name)
        exp = self.expected_subscribers()
        if exp:
            self.get_logger().info(f"waiting up to {self.value('wait_timeout_s'):g} s for {', '.join(exp)} "
                                   f"(parameter wait_for) before sim time starts")

    def _control(self):
        if self._restart:
            self.restart()
        if self.state != "waiting":
            return
        missing = self._named_nodes_ready(self.expected_subscribers())
        unmatched = self._unmatched(self.publishers())
        if missing or unmatched:
            if time.monotonic() - self._wait_t0 < self.value("wait_timeout_s"):
                return
            self.get_logger().warning(f"wait_timeout_s = {self.value('wait_timeout_s'):g} s passed without "
                                      f"{', '.join(missing + unmatched)}: starting anyway (those may miss samples)")
        self._begin()

    def _begin(self):
        if self.clock_pub is not None:
            reason = self.other_clock_owner(self.clock_pub.topic_name)
            if reason is not None:
                self.get_logger().error(f"publish_clock refused: {reason}; not running (stop the other owner, "
                                        f"or start this node with publish_clock:=false to follow it)")
                self.destroy_publisher(self.clock_pub)      # not counted as an owner by the next one
                self.clock_pub = None
                self.state = "refused"
                return
        self.state = "running"
        if self.clock_owner:
            self._rtf = None
            self.timer = self.create_timer(0.002, self._run, clock=STEADY)
        else:
            self.clock_sub = self.create_subscription(m.Clock, CLOCK, self._on_clock, RELIABLE_ALL, raw=True)

    def _run(self):
        """Owner: publish what is due (paced) or the next flow-controlled batch (real_time_factor 0)."""
        rtf = float(self.value("real_time_factor", 1.0))
        if rtf <= 0:
            k = FLOW_BATCH
        else:
            now = time.monotonic()
            if rtf != self._rtf:
                self._rtf, self._w0, self._i0 = rtf, now, self.index
            dt = 1.0 / self.scene.sample_rate_hz
            k = min(self._i0 + int((now - self._w0) * rtf / dt) + 1, self.samples) - self.index
        if k > 0:
            self.publish_steps(min(k, FLOW_BATCH))
        if self.index >= self.samples:
            self._finish()

    def _on_clock(self, data):
        """Follower: publish every sample up to the owner's clock."""
        t = m.cdr_stamp_ns(data) - m.EPOCH_NS
        k = self.sample_index(t) - self.index
        if k > 0 and self.state == "running":
            self.publish_steps(k)
            if self.index >= self.samples:
                self._finish()

    def _finish(self):
        if self.timer is not None:
            self.timer.cancel()                  # destroyed on restart or with the node
        self.state = "done"
        self.get_logger().info(f"published {self.samples} samples of {', '.join(self.chosen)}")
        _acked(self, self.publishers())


class JointBuffer:
    """The joint samples one instrument's topic delivered, in arrival order, kept as the estimator
    needs them: the stamp, the measured channels' positions (the first ``keep`` joints) and the last
    joint's velocity (a gyroscope's measured spin) — 8 (2 + ``keep``) bytes per sample, in arrays
    that grow by doubling (what grows with the run: the samples the estimator fits, nothing else).
    Serialized messages of the expected layout are kept as bytes, at most :attr:`DECODE_EVERY`,
    and decoded together; any other accepted message (decoded by rclpy) is appended after them.
    Both give the same float64 values bit for bit, so the estimate does not depend on which path
    a message took."""

    def __init__(self, layout, keep=None):
        self.layout = layout
        k = layout.fields[0][1]
        self.keep = k if keep is None else int(keep)
        self._raw = []
        self._t = np.zeros(0, dtype=np.int64)
        self._pos = np.zeros((0, self.keep))
        self._vel = np.zeros((0, 1))
        self._n = 0                # rows of the arrays in use
        self.count = 0

    def __len__(self):
        return self.count

    #: serialized messages kept before they are decoded into arrays (at most this many bytes objects)
    DECODE_EVERY = 4096

    def add_raw(self, data) -> None:
        """A serialized message that ``layout.matches``."""
        self._raw.append(data)
        self.count += 1
        if len(self._raw) >= self.DECODE_EVERY:
            self._flush()

    def add(self, t_ns, position, velocity) -> None:
        self._flush()
        self._append(np.array([t_ns], dtype=np.int64), np.array([position], dtype=np.float64),
                     np.array([velocity], dtype=np.float64))
        self.count += 1

    def _append(self, t, pos, vel):
        m_ = t.size
        need = self._n + m_
        if need > self._t.size:
            cap = max(need, 2 * self._t.size, 1024)
            for name in ("_t", "_pos", "_vel"):
                old = getattr(self, name)
                new = np.empty((cap,) + old.shape[1:], dtype=old.dtype)
                new[:self._n] = old[:self._n]
                setattr(self, name, new)
        self._t[self._n:need] = t
        self._pos[self._n:need] = pos[:, :self.keep]
        self._vel[self._n:need] = vel[:, -1:]
        self._n = need

    def _flush(self):
        if self._raw:
            t, (pos, vel, _) = self.layout.decode(self._raw)
            self._raw = []
            self._append(t, pos, vel)

    def arrays(self) -> tuple:
        """(t_ns (m,), position (m, keep), velocity (m, 1): the last joint's) of everything received;
        views of the buffer, valid until the next sample arrives."""
        self._flush()
        n = self._n
        return self._t[:n], self._pos[:n], self._vel[:n]

    def split_run(self) -> tuple:
        """(the samples before the last place the stamps go back, those after it: a new run's that
        arrived before its first clock tick) as two buffers; all before when they never go back."""
        t, pos, vel = self.arrays()
        back = np.flatnonzero(t[1:] < t[:-1])
        k = int(back[-1]) + 1 if back.size else t.size
        parts = []
        for a, z in ((0, k), (k, t.size)):
            out = JointBuffer(self.layout, keep=self.keep)
            if z > a:
                out._append(t[a:z].copy(), pos[a:z].copy(), vel[a:z].copy())
                out.count = z - a
            parts.append(out)
        return tuple(parts)

    def nbytes(self) -> int:
        """Bytes held (the arrays' capacity and the serialized messages not yet decoded)."""
        return self._t.nbytes + self._pos.nbytes + self._vel.nbytes + sum(len(d) for d in self._raw)

    def last_stamp(self) -> int | None:
        if self._raw:
            return m.cdr_stamp_ns(self._raw[-1]) - m.EPOCH_NS
        return int(self._t[self._n - 1]) if self._n else None


class EstimatorNode(SceneNode):
    """Subscribes to the instruments' joint states and publishes latitude and Earth rate."""

    SPECS = P.ESTIMATOR

    def __init__(self, name="estimator", **kwargs):
        super().__init__(name, **kwargs)
        self.buffers = {}
        self.subs = {}
        self.rejected = {}
        self.wrong_types = {}
        self.result = None
        self.refusal = None     # the InadequateData of a refused estimate (estimators/adequacy.py)
        self.pubs = {}
        self.timers_ = []
        self.clock_sub = None
        self.last_clock_ns = None
        self.expected = 0
        self.final = False
        self._clock_done_at = None
        self._last_input = None
        self.runs = 0
        if self.load():
            self.prepare()

    def prepare(self) -> None:
        self.expected = sample_count(self.scene)
        self.last_stamp_ns = round((self.expected - 1) * (1e9 / self.scene.sample_rate_hz))
        for name, inst in self.insts.items():
            if estimable(inst):
                # records_from_joints reads the measured channels and the last joint's velocity
                self.buffers[name] = JointBuffer(m.joint_state_layout(
                    tuple(f"{name}/{j}" for j in inst.JOINTS)), keep=len(inst.MEASURED_CHANNELS))
                sub = self.create_subscription(
                    m.JointState, joint_topic(name), lambda data, n=name: self._on_joint_raw(n, data),
                    RELIABLE_ALL, raw=True)
                self.subs[sub.topic_name] = sub
        # sim time from the clock: the stamp of an estimate that used no sample
        self.clock_sub = self.create_subscription(m.Clock, CLOCK, self._on_clock, RELIABLE_ALL, raw=True)
        for topic, type_name in ESTIMATOR_TOPICS.items():
            self.pubs[topic] = self.create_publisher(m.message_class(type_name), topic, LATCHED)
        period = float(self.get_parameter("publish_period_s").value)
        if period > 0:
            self.timers_.append(self.create_timer(period, self.finalize, clock=STEADY))

    def teardown(self) -> None:
        for t in self.timers_:
            self.destroy_timer(t)
        for sub in list(self.subs.values()) + ([self.clock_sub] if self.clock_sub is not None else []):
            self.destroy_subscription(sub)
        for pub in self.pubs.values():
            self.destroy_publisher(pub)
        self.buffers, self.subs, self.pubs, self.timers_, self.clock_sub = {}, {}, {}, [], None
        self.rejected, self.result, self.final, self.last_clock_ns, self._clock_done_at = {}, None, False, None, None
        self._last_input = None

    def new_run(self, why) -> None:
        """The run restarted (the clock went back: a scene change or restart of the clock owner):
        an estimate not yet published for the run so far is published first (WARN), then the
        samples are dropped and a new estimate starts (with the new run's samples that came before
        its first clock tick)."""
        split = {name: buf.split_run() for name, buf in self.buffers.items()}
        self.buffers = {name: old for name, (old, _) in split.items()}
        if not self.final and self.received():
            self._final(f"{why}; the run so far ended early")
        self.runs += 1
        self.get_logger().info(f"{why}: run {self.runs + 1} begins, a new estimate starts")
        self.buffers = {name: new for name, (_, new) in split.items()}
        self.rejected, self.result, self.refusal, self.final, self._clock_done_at = {}, None, None, False, None

    def restart(self) -> None:
        super().restart()
        self.teardown()
        if self.load():
            self.prepare()
            self.get_logger().info(f"scene {self.scene.name}: estimator restarted, waiting for samples")
            if self.standalone:
                self.get_logger().info(self.startup_line())

    def start(self) -> None:
        """Run alone: publish once every expected sample has arrived, or with what there is (WARN)
        ``input_timeout_s`` of wall time after the clock reached the last sample or after the input
        (joint samples and clock) went silent; a new run (the clock going back) starts a new estimate."""
        self.standalone = True
        self.create_timer(0.5, self._control, clock=STEADY)
        if self.scene is not None:
            self.get_logger().info(self.startup_line())

    def startup_line(self) -> str:
        subs = ", ".join(self.subs) or "no joint states (nothing estimable in this scene)"
        pubs = ", ".join(pub.topic_name for pub in self.pubs.values())
        return (f"scene {self.scene.name}: expects {self.expected} samples on {subs}; publishes {pubs} "
                f"(TRANSIENT_LOCAL, depth 1: a late subscriber asking for TRANSIENT_LOCAL gets the last estimate) "
                f"once they have arrived, or from what it has when the input is silent for input_timeout_s = "
                f"{self.value('input_timeout_s'):g} s")

    def _control(self):
        if self._restart:
            self.restart()
        if self.final or self.scene is None:
            return
        timeout = float(self.value("input_timeout_s", 5.0))
        now = time.monotonic()
        if self._clock_done_at is not None and now - max(self._clock_done_at, self._last_input or 0.0) > timeout:
            # samples still arriving (a slow subscriber's queue) keep it waiting
            self._final(f"the clock reached the end and no sample came for {timeout:g} s (input_timeout_s)")
        elif self._last_input is not None and now - self._last_input > timeout:
            self._final(f"no joint sample or clock tick for {now - self._last_input:.1f} s (input_timeout_s = "
                        f"{timeout:g})")

    def _final(self, short=None):
        """Estimate and publish; ``short``: why the estimate comes before every expected sample (a
        WARN, and the diagnostic status WARN with that reason)."""
        self.final = True
        if short is not None:
            have = {n: len(b) for n, b in self.buffers.items()}
            short = f"{short}: estimate from the samples received {have} of {self.expected} each"
            self.get_logger().warning(short)
        r = self.finalize(short)
        if r is not None:
            self.get_logger().info(f"estimate published: latitude {r.get('latitude_deg')} deg, Earth rate "
                                   f"{r.get('earth_rate_rad_s')} rad/s ({r.get('method') or r.get('reason', '')})")

    def _check_complete(self):
        if self.standalone and not self.final and all(len(b) >= self.expected for b in self.buffers.values()):
            if self.buffers or self._clock_done_at is not None:
                self._final()

    def _on_clock(self, data):
        t = m.cdr_stamp_ns(data) - m.EPOCH_NS
        self._last_input = time.monotonic()
        if self.standalone and self.last_clock_ns is not None and t < self.last_clock_ns and self.scene is not None:
            self.new_run(f"the clock went back from {self.last_clock_ns / 1e9:g} s to {t / 1e9:g} s")
        self.last_clock_ns = t
        if self.standalone and self._clock_done_at is None and self.expected and self.scene is not None \
                and self.last_clock_ns >= self.last_stamp_ns:
            self._clock_done_at = time.monotonic()
            self._check_complete()

    def received(self) -> int:
        return sum(len(b) for b in self.buffers.values())

    def check_topic_types(self) -> dict:
        """Topics the estimator listens to that the graph offers with another type (DDS never
        matches them, so nothing arrives): {topic: [types]}; logged once and put in diagnostics."""
        wrong = {}
        for topic, types in self.get_topic_names_and_types():
            if topic in self.subs:
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
        self._last_input = time.monotonic()
        if buf.layout.matches(data):
            buf.add_raw(data)
            if self.standalone and len(buf) >= self.expected:
                self._check_complete()
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
        if self.standalone and len(self.buffers[name]) >= self.expected:
            self._check_complete()

    def estimate(self) -> dict | None:
        """Core call on everything received so far (None if nothing usable)."""
        if self.scene is None:
            return None
        samples = {n: b.arrays() for n, b in self.buffers.items() if len(b) >= 3}
        recs = records_from_joints(self.insts, samples)
        return estimate_records(self.scene, {n: self.insts[n] for n in samples}, recs)

    def stamp_ns(self) -> int:
        """Stamp of an estimate: the last sample it used, else the last clock tick (sim time), else 0."""
        t = max((b.last_stamp() for b in self.buffers.values() if len(b)), default=None)
        if t is None:
            t = self.last_clock_ns
        return 0 if t is None else max(int(t), 0)

    def finalize(self, short=None) -> dict | None:
        """Estimate and publish; returns the result dict. ``short``: why the input is incomplete (the
        diagnostic status is then WARN with that text before the method)."""
        try:
            self.result = self.estimate()
        except InadequateData as exc:  # the data fail an adequacy check: said on /diagnostics, no number
            self.refusal = exc
            self.get_logger().error(str(exc))
            self.pubs["diagnostics"].publish(m.diagnostics(
                self.stamp_ns(), "gyro_instrument/estimator", False, str(exc),
                {"refused_by_check": exc.field, "rejected_messages": self.rejected}))
            return None
        except Exception as exc:  # the estimator must never take the node down
            self.get_logger().error(f"estimation failed: {exc.__class__.__name__}: {exc}")
            return None
        if self.result is None:
            return None
        r = self.result
        t = self.stamp_ns()
        lat = None if r.get("latitude_deg") is None else math.radians(r["latitude_deg"])
        sig = None if r.get("latitude_sigma_deg") is None else math.radians(r["latitude_sigma_deg"])
        self.pubs["estimator/earth_rate_enu"].publish(m.earth_rate_vector(t, r.get("earth_rate_rad_s"), lat))
        text = r.get("method") or r.get("reason", "")
        self.pubs["diagnostics"].publish(m.diagnostics(
            t, "gyro_instrument/estimator", r.get("method") is not None and short is None,
            text if short is None else f"{short}; {text}",
            {"latitude_deg": r.get("latitude_deg"), "latitude_sigma_deg": r.get("latitude_sigma_deg"),
             "earth_rate_rad_s": r.get("earth_rate_rad_s"), "carried_by": r.get("carried_by"),
             "rejected_messages": self.rejected, "wrong_topic_types": self.check_topic_types()}))
        self.pubs["estimator/latitude_rad"].publish(m.float64(lat))
        self.pubs["estimator/latitude_sigma_rad"].publish(m.float64(sig))
        self.pubs["estimator/earth_rate_rad_s"].publish(m.float64(r.get("earth_rate_rad_s")))
        self.pubs["estimator/earth_rate_sigma_rad_s"].publish(m.float64(r.get("earth_rate_sigma_rad_s")))
        return r


class RecorderNode(SceneNode):
    """Records the scene's topics (raw CDR) to MCAP with sim-time log times, in log-time order, and
    marks the file ``complete`` or ``incomplete`` (per-topic counts against what the scene publishes).

    Parameters
    ----------
    reorder : bool
        True (alone): messages of different topics, arriving interleaved from separate processes,
        are held until every sample topic has reached their stamp and written in stamp order. False
        (the lock-step suite, which delivers sample by sample): written as they arrive.
    """

    SPECS = P.RECORDER
    RESTART_ON = ()
    #: parameters that may be corrected until the recording starts (then they are fixed)
    RETRY_ON = P.RECORDING_FIXED_NAMES
    #: wall time (s) without any message after which held messages are written although a sample
    #: topic lags, when no publisher of that topic is left (its messages then written at their own
    #: stamps, out of file order: MCAP indexes each chunk's time range)
    HOLD_S = 2.0
    #: ... and the longest hold while a lagging topic still has a publisher (a stalled simulator, or
    #: one that has published all it will): holding only keeps the file's order sorted — a message
    #: arriving later is still logged at its own stamp — so a few seconds suffice
    HOLD_MAX_S = 6.0
    #: messages held at most before they are written anyway (memory bound)
    HOLD_MAX_MESSAGES = 500_000

    def __init__(self, name="recorder", reorder=True, **kwargs):
        super().__init__(name, **kwargs)
        self.writer = None
        self.counts = {}
        self.expected = {}
        self.subs = {}
        self.last_ns = 0
        self.max_ns = 0
        self.reorder = bool(reorder)
        self._held = []
        self._seq = 0
        self._last_in = {}
        self._last_arrival = time.monotonic()
        self.late = 0
        self.done = False
        self.failed = None           # the DiskFull that stopped the recording
        self.runs = []               # [(path, state)] of recordings closed because the clock went back
        self._topic_last = {}        # topic -> last stamp seen (a stamp going back: the run restarted)
        self._topic_run = {}         # topic -> run index its messages belong to
        self.run_index = 0
        self._old = {}               # run index -> (writer, counts) of a run closed by a restart
        if self.load():
            self.prepare()

    def _check_params(self, params):
        if self.writer is not None and any(p.name in self.RETRY_ON for p in params):
            names = ", ".join(p.name for p in params if p.name in self.RETRY_ON)
            reason = f"{names} cannot change while recording to {self.writer.path}: a recording has one scene and " \
                     "one file (stop the recorder and start it again)"
            self.get_logger().error(f"parameter refused: {reason}")
            return SetParametersResult(successful=False, reason=reason)
        return super()._check_params(params)

    def _after_set(self, params):
        super()._after_set(params)
        if self.writer is None and any(p.name in self.RETRY_ON for p in params):
            # a value refused at start-up, corrected: start recording now
            if self.load():
                self.prepare()
            if self.writer is not None:
                self.get_logger().info(f"parameters corrected: recording to {self.writer.path}")

    def prepare(self) -> None:
        out = self.get_parameter("output").value
        if not out:
            self.get_logger().error("output = '' is invalid: give an .mcap path to record to")
            return
        fmt = self._output_format(out)
        if fmt is None:
            return
        types = scene_topics(self.insts)
        wanted = self._wanted_topics(types)
        self._out, self._fmt = out, fmt
        self.writer = open_bag_writer(out, fmt, self.value("max_bag_size", 0), self.value("max_bag_duration", 0.0),
                                      overwrite=bool(self.value("overwrite", False)))
        # the scene first, so that a recording cut short still says what it holds (replay needs it)
        self.writer.add_metadata("gyro_instrument", self._scene_record())
        self._record_topics(wanted, types)
        if self.reorder:
            self.create_timer(0.5, self._control, clock=STEADY)

    def _scene_record(self):
        return {"scene_yaml": json.dumps(dict(self.scene.raw)), "scene": self.scene.name, "seed": self.scene.seed,
                "command": self.value("command", "recorder node")}

    def _output_format(self, out):
        """Check the ``output`` path for the bag layout the parameters give (``format``,
        ``max_bag_size``, ``max_bag_duration``) and return that layout (``mcap`` or ``rosbag2``), or
        None after logging why the path is invalid: a bad layout, a missing or unwritable directory,
        a directory given for a file, the scene file itself, or an existing file without
        ``overwrite``."""
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
            return None
        if fmt != "rosbag2":       # a bag directory was checked above (bag_layout.check_bag_output)
            directory = os.path.dirname(os.path.abspath(out)) or "."
            if not os.path.isdir(directory) or not os.access(directory, os.W_OK):
                self.get_logger().error(f"output = {out!r} is invalid: directory {directory} is missing or not writable")
                return None
            if os.path.isdir(out):
                self.get_logger().error(f"output = {out!r} is invalid: is a directory; give an .mcap file path")
                return None
            scene_file = self.value("scene", "")
            if os.path.isfile(scene_file) and os.path.exists(out) and os.path.samefile(out, scene_file):
                self.get_logger().error(f"output = {out!r} is invalid: is the scene file this node reads; record "
                                        f"elsewhere (overwrite never replaces an input)")
                return None
            if os.path.lexists(out) and not self.value("overwrite", False):
                self.get_logger().error(f"output = {out!r} is invalid: the file exists and parameter overwrite is "
                                        f"false; set overwrite:=true to replace it, or give a new path")
                return None
        return fmt

    def _wanted_topics(self, types):
        """The scene topics to record, relative names in the order of parameter ``topics`` (every
        topic of the scene, ``types``, when empty); a name that resolves to no topic of the scene
        is logged as an error and skipped."""
        resolved = {self.resolve_topic_name(tp): tp for tp in types}
        wanted = []
        for topic in self.value("topics", []) or list(types):
            rel = resolved.get(self.resolve_topic_name(topic))
            if rel is None:
                self.get_logger().error(f"topics: {topic!r} is not a topic of this scene; valid: {', '.join(types)}")
                continue
            wanted.append(rel)
        return wanted

    def _record_topics(self, wanted, types):
        """Add each wanted topic to the bag writer and subscribe to it (raw, RELIABLE / KEEP_ALL),
        classifying it (stamped, marker, per-sample) for the ordering and completeness checks and
        noting the count of messages the scene publishes on it (``expected``)."""
        n = sample_count(self.scene)
        n_markers = len(range(0, n, visual_every(self.scene.sample_rate_hz)))
        self.stamped = set()
        self.marker_topics = set()
        self.sample_topics = set()
        self.rank = {}
        self._topic_types = {}
        for topic in wanted:
            name = self.resolve_topic_name(topic)         # namespace and remapping applied
            self.writer.add_topic(name, types[topic], qos_yaml(reliable=True, keep_all=False, depth=1000))
            self._topic_types[name] = types[topic]
            self.counts[name] = 0
            self.rank[name] = list(types).index(topic)      # ties in stamp: clock first, then scene order
            if types[topic] == "visualization_msgs/msg/MarkerArray":
                self.marker_topics.add(name)
            elif types[topic] != "std_msgs/msg/Float64":
                self.stamped.add(name)
            if not (topic.startswith("estimator/") or topic == "diagnostics"):
                self.sample_topics.add(name)
            # what the scene publishes: every sample on clock and the instruments' topics, and at
            # least one estimate on each estimator topic
            sparse = topic.endswith(("/markers", "/swing_plane", "/axis_direction"))
            self.expected[name] = (n_markers if sparse else n) if name in self.sample_topics else 1
            self.subs[name] = self.create_subscription(m.message_class(types[topic]), topic,
                                                       lambda data, tp=name: self._on_raw(tp, data),
                                                       RELIABLE_ALL, raw=True)

    def start(self) -> None:
        self.standalone = True
        if self.writer is not None:
            self.get_logger().info(
                f"recording {', '.join(self.subs)} to {self.writer.path}; expects "
                f"{max(self.expected.values(), default=0)} samples per sample topic and one estimate")

    def received(self) -> int:
        return sum(self.counts.values())

    def _on_raw(self, topic, data):
        # Header-first types and Clock carry their sim time; Float64 takes the latest sim time
        # received (never wall time), so one bag has one time base.
        if self.writer is None or self.writer.closed:
            return
        st = m.cdr_stamp_ns(data) if topic in self.stamped else \
            m.marker_array_stamp_ns(data) if topic in self.marker_topics else None
        if st is not None and topic in self.sample_topics:
            # each publisher sends its topic in stamp order: a stamp going back means its run
            # restarted (a scene change on the clock owner restarts sim time at 0)
            last = self._topic_last.get(topic)
            self._topic_last[topic] = st
            run = self._topic_run.get(topic, self.run_index)
            if last is not None and st < last:
                run += 1
            self._topic_run[topic] = run
            if run > self.run_index:
                self._new_run(topic, last, st)
            elif run < self.run_index:      # the rest of a run closed by a restart: into its own file
                self._write_old(run, topic, st, data)
                return
        if st is None:
            st = self.max_ns
        self.counts[topic] += 1
        if st > self.max_ns:
            self.max_ns = st
        if not self.reorder:
            self._write(topic, st, data)
            return
        self._last_arrival = time.monotonic()
        if topic in self.sample_topics:
            self._last_in[topic] = st
        heapq.heappush(self._held, (st, self.rank[topic], self._seq, topic, data))
        self._seq += 1
        if self._seq % 64 == 0 or topic not in self.sample_topics:
            self._flush(self._watermark())

    def _write(self, topic, st, data):
        if self.writer.closed:           # stopped by a full disk
            return
        if st < self.last_ns:            # arrived after later stamps were written: still logged at its stamp
            self.late += 1
        self.last_ns = max(self.last_ns, st)
        try:
            self.writer.write(topic, st, data)
        except OSError as exc:
            self._disk_full(exc)

    def _disk_full(self, exc):
        """A write failed (ENOSPC...): the bag stays as its last commit made it (readable); the
        recorder stops recording, logs one line and keeps the error for ``run`` to report."""
        from gyro_instrument.recording.mcap_io import DiskFull
        if not isinstance(exc, DiskFull):
            raise exc
        self.failed = exc
        self._held = []
        if self.standalone:          # in 'run' the one line is the command's error
            self.get_logger().error(exc.line("output"))
        try:
            self.writer.close(state="disk full")
        except OSError:
            pass
        self.done = True

    def _new_run(self, topic, last, st):
        """The stamps of ``topic`` went back (``last`` -> ``st``): close this recording (everything
        held written first) and record the new run to a new file (:func:`restart_path`); messages of
        the old run that still arrive go to the old file, kept open until close."""
        from gyro_instrument.recording.bag_layout import restart_path
        self._flush(math.inf)
        old_path = self.writer.path
        self.run_index += 1
        new_out = restart_path(self._out, self.run_index)
        self.get_logger().warning(
            f"{topic}: sim time went back from {(last - m.EPOCH_NS) / 1e9:.9g} s to {(st - m.EPOCH_NS) / 1e9:.9g} s "
            f"(the clock owner restarted its run): {old_path} closed, recording continues in {new_out}")
        self._old[self.run_index - 1] = (self.writer, self.counts, new_out)
        self.counts = {tp: 0 for tp in self.counts}
        self._last_in, self.last_ns, self.max_ns, self.late = {}, 0, 0, 0
        self.done = False
        self.writer = open_bag_writer(new_out, self._fmt, self.value("max_bag_size", 0),
                                      self.value("max_bag_duration", 0.0))
        rec = self._scene_record()
        rec["continues"] = os.path.basename(old_path.rstrip("/"))
        self.writer.add_metadata("gyro_instrument", rec)
        for name in self.counts:
            self.writer.add_topic(name, self._topic_types[name], qos_yaml(reliable=True, keep_all=False, depth=1000))

    def _write_old(self, run, topic, st, data):
        writer, counts, _ = self._old[run]
        counts[topic] = counts.get(topic, 0) + 1
        if not writer.closed:
            try:
                writer.write(topic, st, data)
            except OSError as exc:
                self._disk_full(exc)

    def _close_old(self):
        for run, (writer, counts, new_out) in sorted(self._old.items()):
            if writer.closed:
                continue
            topics = {tp: [counts[tp], n] for tp, n in self.expected.items()}
            state = "incomplete" if any(counts[tp] < n for tp, n in self.expected.items()) else "complete"
            try:
                writer.close(state=state, topics=json.dumps(topics), restarted=json.dumps(
                    {"continues_in": os.path.basename(new_out.rstrip("/")),
                     "reason": "sim time went back: the clock owner restarted its run"}))
            except OSError:
                pass
            self.runs.append((writer.path, state))

    def _watermark(self):
        """Stamps up to here are complete on every sample topic still publishing."""
        open_topics = [tp for tp in self.sample_topics if self.counts[tp] < self.expected[tp]]
        if any(tp not in self._last_in for tp in open_topics):
            return None
        return min((self._last_in[tp] for tp in open_topics), default=math.inf)

    def _flush(self, upto):
        held = self._held
        if upto is None:
            return
        while held and held[0][0] <= upto:
            st, _, _, topic, data = heapq.heappop(held)
            self._write(topic, st, data)

    def commit(self, older_than_s=0.0) -> None:
        """Put on disk what was written and not yet committed (MCAP chunk and provisional summary,
        no fsync) when the last commit is at least ``older_than_s`` old: the suite calls it before it
        integrates a block or sleeps, the node's timer every 0.5 s, so a SIGKILL loses at most the
        messages of the last second of wall time. (A commit rewrites the summary, ~13 µs per chunk
        so far: the suite skips it before quick integrations when the last commit is recent.)"""
        if self.writer is not None and not self.writer.closed and self.writer.pending() \
                and self.writer.since_commit_s() >= older_than_s:
            try:
                self.writer.commit()
            except OSError as exc:
                self._disk_full(exc)

    def _control(self):
        if self._held:
            quiet = time.monotonic() - self._last_arrival
            lagging = [tp for tp in self.sample_topics if self.counts[tp] < self.expected[tp]]
            alive = any(self.count_publishers(tp) for tp in lagging)
            if (quiet > self.HOLD_S and not alive) or quiet > self.HOLD_MAX_S \
                    or len(self._held) > self.HOLD_MAX_MESSAGES:
                self._flush(math.inf)    # a topic stopped: write what is held (late ones: at their stamps)
        self.commit()
        if self.value("stop_when_complete", False) and self.writer is not None and not self.done \
                and self.missing() == {}:
            self.get_logger().info(f"every expected message recorded ({self.received()}): finishing {self.writer.path}")
            self.done = True

    def missing(self) -> dict:
        """{topic: (recorded, expected)} of every topic short of what the scene publishes."""
        return {tp: (self.counts[tp], n) for tp, n in self.expected.items() if self.counts[tp] < n}

    def close(self, metadata=None, name="gyro_instrument", state=None) -> None:
        """Write an optional metadata record and finish the file (summary, indexes, footer) with
        the status record: ``state`` if given (``interrupted`` when a run is cut short), else
        ``complete`` when every topic holds what the scene publishes, ``incomplete`` otherwise;
        with the per-topic counts (``topics``: {topic: [recorded, expected]}) and ``late`` (messages
        that arrived after later stamps were written and carry that later log time)."""
        self._close_old()
        if self.writer is not None and not self.writer.closed:
            self._flush(math.inf)
            if self.writer.closed:       # the disk filled while writing what was held
                return
            if metadata:
                try:
                    self.writer.add_metadata(name, metadata)
                except OSError as exc:
                    self._disk_full(exc)
                    return
            missing = self.missing()
            if state is None:
                state = "incomplete" if missing else "complete"
                if missing:
                    self.get_logger().warning("recording incomplete: " + ", ".join(
                        f"{tp} {k} of {n}" for tp, (k, n) in missing.items()))
            topics = {tp: [self.counts[tp], n] for tp, n in self.expected.items()}
            fields = {"topics": json.dumps(topics), "late": self.late}
            if self.run_index:
                fields["restart"] = json.dumps({"run": self.run_index, "continues": os.path.basename(
                    self._old[self.run_index - 1][0].path.rstrip("/"))})
            try:
                self.writer.close(state=state, **fields)
            except OSError as exc:
                self._disk_full(exc)


class PlayerNode(SceneNode):
    """Republishes a bag on its topics (relative names), driving ``clock`` from the log times; waits
    for its subscribers (topic by topic), counts what reached a subscriber, exits at the end
    (``done``) or loops."""

    SPECS = P.PLAYER
    RESTART_ON = ()
    #: the subscriptions the graph shows on the bag's topics must be unchanged (and all matched) for
    #: this long (wall time, s) before playing: a subscriber's topics are discovered one by one
    SETTLE_S = 0.5

    def __init__(self, name="player", **kwargs):
        super().__init__(name, **kwargs)
        self.clock_owner = True
        self.refuse_sim_time_if_owner()
        self.pubs = {}
        self.pub_qos = PUBLISH_ALL
        self.queue = []
        self.index = 0
        self.damaged = []
        self.skipped = {}
        self.done = False
        self.state = "idle"
        self.has_clock = False
        self.timer = None
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
        classes = {}
        queue = []
        for tp, ty, t, data in read_messages(bag, scan=scan):
            topic = tp.lstrip("/")
            if topic not in classes:
                classes[topic] = self._message_class(bag, tp, ty)
            if classes[topic] is None:
                self.skipped[tp] = self.skipped.get(tp, 0) + 1
            else:
                queue.append((topic, ty, t, data))
        self.queue = queue
        for tp, n in self.skipped.items():
            self.get_logger().warning(f"bag {bag}: {tp}: {n} messages not played (type not installed)")
        clock_topics = {tp for tp, *_ in self.queue if tp.split("/")[-1] == CLOCK}
        self.has_clock = bool(clock_topics)
        for topic, type_name, _, _ in self.queue:
            if topic not in self.pubs:
                self.pubs[topic] = self.create_publisher(classes[topic], topic, self.pub_qos)
        if not self.has_clock:
            self.pubs[CLOCK] = self.create_publisher(m.Clock, CLOCK, self.pub_qos)
            clock_topics = {CLOCK}
        self.clock_topics = sorted(self.pubs[tp].topic_name for tp in clock_topics)
        self._last_clock = None
        self.sent = {tp: [0, 0, 0] for tp in self.pubs}     # sent, sent to >= 1 subscriber, deliveries
        self._first_sent = set()
        self._wait_topics = []
        self._hold_topic = self._hold_t0 = None

    def _message_class(self, bag, topic, type_name):
        """The message class of ``type_name``, or None (logged) when its package is not installed or
        has no such type: that topic is skipped, the rest played."""
        try:
            return m.message_class(type_name)
        except (ImportError, AttributeError, ValueError) as exc:
            self.get_logger().warning(f"bag {bag}: {topic} has type {type_name!r}, which is not installed here "
                                      f"({exc.__class__.__name__}): that topic is skipped, the others are played")
            return None

    def load(self) -> bool:
        return False

    def publish_next(self, counts=None) -> bool:
        """Publish the next message (and a clock tick when the bag has none); False when done.
        ``counts`` {topic: matched subscribers} is what :attr:`sent` counts as delivered."""
        if self.index >= len(self.queue):
            return False
        topic, _, log_ns, data = self.queue[self.index]
        if not self.has_clock and log_ns != self._last_clock:
            self._send(CLOCK, m.CLOCK_LAYOUT.encode([log_ns - m.EPOCH_NS])[0], counts)
            self._last_clock = log_ns
        self._send(topic, data, counts)
        self.index += 1
        return True

    def _send(self, topic, data, counts):
        pub = self.pubs[topic]
        n = counts[topic] if counts is not None else pub.get_subscription_count()
        pub.publish(data)
        c = self.sent[topic]
        c[0] += 1
        c[1] += n > 0
        c[2] += n
        self._first_sent.add(topic)

    def start(self) -> None:
        """Wait for the subscribers (``wait_topics``, ``wait_for``, ``min_subscribers``; every
        subscription the graph shows matched and unchanged for :attr:`SETTLE_S`; at most
        ``wait_timeout_s``), then play."""
        self.standalone = True
        if not self.queue:
            self.done = True
            return
        wt = self._wait_topics = self.wait_topics()
        self.get_logger().info(
            f"publishes {len(self.queue)} messages on {', '.join(p.topic_name for p in self.pubs.values())}"
            f"{self.clock_remap_note(self.clock_topics[0])}; waiting up to {self.value('wait_timeout_s'):g} s for "
            f"{self.value('min_subscribers')} subscriber(s) on topics other than the clock"
            + (f", a subscriber on each of {', '.join(wt)} (wait_topics)" if wt else "")
            + (f" and {', '.join(self.value('wait_for'))}" if self.value("wait_for") else "")
            + f", and every subscription seen matched for {self.SETTLE_S:g} s")
        self.state = "waiting"
        self._wait_t0 = time.monotonic()
        self._graph, self._graph_t = None, time.monotonic()
        for tp in self.clock_topics:
            self.watch_clock(tp)
        self.timer = self.create_timer(0.002, self._tick, clock=STEADY)

    def wait_topics(self) -> list:
        """Resolved names of the topics that must each have a matched subscription before playing."""
        want = list(self.value("wait_topics", []) or [])
        by_name = {p.topic_name: p.topic_name for p in self.pubs.values()}
        if "*" in want:
            return sorted(by_name)
        out = []
        for tp in want:
            name = self.resolve_topic_name(tp)
            if name not in by_name:
                self.get_logger().warning(f"wait_topics: {tp!r} is not a topic of the bag; not waited for")
                continue
            out.append(name)
        return out

    def _ready(self):
        pubs = list(self.pubs.values())
        topics = [p.topic_name for p in pubs]
        missing = self._named_nodes_ready({n: topics for n in self.value("wait_for", [])})
        # named nodes subscribe to any of the bag's topics
        missing = [n for n in missing if not any(
            i.node_name == n and i.node_namespace == self.get_namespace()
            for t in topics for i in self.get_subscriptions_info_by_topic(t))]
        # every sim-time node subscribes to the clock: only the other topics count as subscribers
        few = sum(p.get_subscription_count() for p in pubs
                  if p.topic_name not in self.clock_topics) < self.value("min_subscribers", 1)
        alone = [p.topic_name for p in pubs if p.topic_name in self._wait_topics and p.get_subscription_count() == 0]
        # subscriptions are discovered topic by topic: wait until what the graph shows stops changing
        graph = tuple(len(self.get_subscriptions_info_by_topic(t)) for t in topics)
        now = time.monotonic()
        if graph != self._graph:
            self._graph, self._graph_t = graph, now
        settling = ["the graph to settle"] if now - self._graph_t < self.SETTLE_S else []
        return missing + (["min_subscribers"] if few else []) + alone + self._unmatched(pubs) + settling

    def _tick(self):
        if self.state == "waiting":
            missing = self._ready()
            if missing:
                if time.monotonic() - self._wait_t0 < self.value("wait_timeout_s"):
                    return
                self.get_logger().warning(f"wait_timeout_s passed without {', '.join(missing)}: playing anyway")
            for tp in self.clock_topics:
                reason = self.other_clock_owner(tp)
                if reason is not None:
                    self.get_logger().error(f"not playing: {reason}")
                    self.timer.cancel()
                    self.state = "refused"
                    self.done = True
                    return
            self.state = "playing"
            self._rtf = None
            self._hold_t0 = None
        if self.state != "playing":
            return
        counts = {tp: p.get_subscription_count() for tp, p in self.pubs.items()}
        if self._held(counts):
            return
        rtf = float(self.value("real_time_factor", 1.0))
        if rtf <= 0:
            for _ in range(FLOW_BATCH):
                if self._first_of_topic() or not self.publish_next(counts):
                    break
        else:
            now = time.monotonic()
            if rtf != self._rtf:
                self._rtf, self._w0, self._t0 = rtf, now, self.queue[min(self.index, len(self.queue) - 1)][2]
            k = 0
            while k < FLOW_BATCH and self.index < len(self.queue) and \
                    (self.queue[self.index][2] - self._t0) <= (now - self._w0) * rtf * 1e9:
                if self._first_of_topic():
                    break
                self.publish_next(counts)
                k += 1
        if self.index >= len(self.queue):
            _acked(self, self.pubs.values())
            line = self.summary()
            if self.value("loop", False):
                self.get_logger().info(f"{line}; looping")
                self.index, self._rtf, self._last_clock = 0, None, None
            else:
                self.get_logger().info(f"{line}; exiting")
                self.timer.cancel()
                self.state = "done"
                self.done = True

    def _first_of_topic(self) -> bool:
        """True (stop the batch) when the next message is its topic's first and the graph shows a
        subscription on that topic not matched yet: it is held (:meth:`_held`)."""
        if self.index >= len(self.queue):
            return False
        topic = self.queue[self.index][0]
        if topic in self._first_sent or not self._unmatched([self.pubs[topic]]):
            return False
        self._hold_topic = topic
        return True

    def _held(self, counts) -> bool:
        """A topic's first message waits (at most ``wait_timeout_s``) for a subscription the graph
        shows on it to match; paced play then resumes from that message."""
        topic = getattr(self, "_hold_topic", None)
        if topic is None:
            return False
        if self._unmatched([self.pubs[topic]]):
            if self._hold_t0 is None:
                self._hold_t0 = time.monotonic()
            if time.monotonic() - self._hold_t0 < self.value("wait_timeout_s"):
                return True
            self.get_logger().warning(f"{self.pubs[topic].topic_name}: a subscription seen in the graph did not match "
                                      f"within wait_timeout_s; playing on")
            self._first_sent.add(topic)
        self._hold_topic, self._hold_t0, self._rtf = None, None, None      # paced play re-anchors here
        counts[topic] = self.pubs[topic].get_subscription_count()
        return False

    def summary(self) -> str:
        """What was played and what reached a subscriber (matched when the message was sent)."""
        sent = sum(c[0] for c in self.sent.values())
        to_one = sum(c[1] for c in self.sent.values())
        deliveries = sum(c[2] for c in self.sent.values())
        short = [f"{self.pubs[tp].topic_name} {c[1]} of {c[0]}" for tp, c in self.sent.items() if c[1] < c[0]]
        line = (f"played {len(self.queue)} messages ({sent} published with the clock ticks added); {to_one} reached "
                f"at least one matched subscriber, {deliveries} deliveries in all")
        if short:
            line += "; sent with no subscriber matched: " + ", ".join(short)
        if self.skipped:
            line += "; skipped (type not installed): " + ", ".join(f"{tp} {n}" for tp, n in self.skipped.items())
        return line
