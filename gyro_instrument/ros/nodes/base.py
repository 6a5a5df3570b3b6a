"""What every node shares: the QoS profiles, the steady clock, and :class:`SceneNode` (parameters
declared from a table with descriptors and checked on every change, the scene, one clock owner
per namespace)."""

import threading
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock as RclClock, ClockType
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from gyro_instrument import api
from gyro_instrument.core.errors import SceneError
from gyro_instrument.recording.qos import profile, replay_offer
from gyro_instrument.recording.topics import DIAGNOSTICS, resolve
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.scenes import build_instruments

RELIABLE_ALL = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
RELIABLE_1000 = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE)
#: a clock follower's subscription (a following simulator, the estimator): RELIABLE / KEEP_ALL, every
#: tick queued until taken (the drain takes a whole queue at once and the follower publishes once up
#: to the last). KEEP_LAST 1 was used until 2026-12: with Fast DDS 2.14 such a reader stopped
#: receiving mid-run (never past a batch's last tick) in about 1 of 5 launches at real-time factor 0,
#: on shared memory and on UDP alike, and the run never ended (issue 37 item 6, docs/ros.md)
FOLLOW_CLOCK = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE)
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
#: seconds the subscriptions of an :class:`AnyOf` node (the recorder) must stay unchanged before a
#: simulator or the player counts it ready (:meth:`SceneNode._named_nodes_ready`)
ANY_OF_SETTLE_S = 0.3
ACK_TIMEOUT = Duration(seconds=5)


def qos_dict(qos) -> dict:
    """An rclpy ``QoSProfile`` as :func:`gyro_instrument.recording.qos.profile` (what a bag records)."""
    history = {HistoryPolicy.KEEP_LAST: "keep_last", HistoryPolicy.KEEP_ALL: "keep_all"}.get(qos.history, "unknown")
    return profile(history=history, depth=qos.depth if history == "keep_last" else 0,
                   reliability={ReliabilityPolicy.RELIABLE: "reliable", ReliabilityPolicy.BEST_EFFORT: "best_effort"}
                   .get(qos.reliability, "unknown"),
                   durability={DurabilityPolicy.TRANSIENT_LOCAL: "transient_local",
                               DurabilityPolicy.VOLATILE: "volatile"}.get(qos.durability, "unknown"))


def qos_text(qos) -> str:
    """A QoS profile in a log line: ``RELIABLE KEEP_LAST 10 VOLATILE`` (``RELIABLE VOLATILE`` for an
    endpoint seen in the graph: its history is not discovered)."""
    d = qos_dict(qos)
    hist = f"KEEP_LAST {d['depth']} " if d["history"] == "keep_last" else "KEEP_ALL " if d["history"] == "keep_all" \
        else ""          # a discovered endpoint's history is not known (DDS does not send it)
    return f"{d['reliability'].upper()} {hist}{d['durability'].upper()}"


def replay_qos(profiles) -> QoSProfile:
    """The QoS the player offers for a topic recorded with ``profiles`` (:func:`replay_offer`: the
    recorded reliability and durability): a TRANSIENT_LOCAL topic KEEP_LAST with the recorded depth
    (what a late subscriber gets; the player waits for each message's acknowledgement before the
    next, so a reliable subscriber loses none), any other KEEP_ALL (flow control: a slow RELIABLE
    subscriber makes the player wait, never drop)."""
    offer = replay_offer(profiles)
    rel = ReliabilityPolicy.RELIABLE if offer["reliability"] == "reliable" else ReliabilityPolicy.BEST_EFFORT
    if offer["durability"] == "transient_local":
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=offer["depth"], reliability=rel,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
    return QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=rel, durability=DurabilityPolicy.VOLATILE)


#: a node's liveness status on /diagnostics: published every this many s of wall time
DIAG_PERIOD_S = 0.5
#: the ``hardware_id`` of the liveness statuses (the recorder does not record them: they describe the
#: live nodes, and a played bag would bring back nodes that are not running)
LIVENESS_ID = "gyro_instrument/node"
OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def list_or(value) -> object:
    """An array parameter's value as a list (rclpy may hold an ``array.array``), others as they are."""
    return list(value) if isinstance(value, (list, tuple)) or hasattr(value, "tolist") else value
def drain(node, limit=20000) -> int:
    """Take the messages waiting on ``node``'s raw subscriptions and run their callbacks, topic by
    topic, without the executor: one wait of the executor then serves a whole queue, not one
    message (rclpy's executor rebuilds its wait set per callback, the separate-node route's ceiling,
    issue 37 item 6). Each topic's messages keep their order. Then the node's ``after_drain()``, if
    it has one (a follower publishes once up to the last clock tick taken). Returns how many were
    taken (at most ``limit`` per subscription, so that one long queue starves no other)."""
    from rclpy.exceptions import InvalidHandle
    n = 0
    for sub in [s for s in node.subscriptions if s.raw]:
        for _ in range(limit):
            try:
                with sub.handle:
                    taken = sub.handle.take_message(sub.msg_type, True)
            except InvalidHandle:           # destroyed by an earlier callback (a restart)
                break
            if taken is None:
                break
            sub.callback(taken[0])
            n += 1
    hook = getattr(node, "after_drain", None)
    if hook is not None:
        hook()
    return n


def acked(node, pubs) -> None:
    """Wait until every subscriber acknowledged what ``pubs`` published; warn once per topic if not."""
    for pub in pubs:
        if not pub.wait_for_all_acked(ACK_TIMEOUT):
            if pub.topic_name not in node._ack_warned:
                node._ack_warned.add(pub.topic_name)
                node.get_logger().warning(f"{pub.topic_name}: a subscriber did not acknowledge within 5 s "
                                          f"(slow or gone); publishing on")



class AnyOf(tuple):
    """Topics of which a waited-for node must subscribe to at least one (:meth:`SceneNode._named_nodes_ready`)."""

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
        #: True once the process was asked to stop (SIGINT / SIGTERM; set by the entry point): a
        #: node waiting inside a callback gives up the wait
        self.stop_asked = lambda: False
        self._ack_warned = set()
        self._restart = False
        self.add_pre_set_parameters_callback(P.pre_set_checker(self, self.specs))
        self.add_on_set_parameters_callback(self._check_params)
        self.add_post_set_parameters_callback(self._after_set)

    def frames_and_epoch(self, owner=False) -> None:
        """Read ``frame_prefix`` and ``stamp_epoch`` (issue 37) into :attr:`frame_prefix` and
        :attr:`stamp_offset_ns` (the shift of every stamp from the simulation epoch; None while a
        ``wall`` epoch is not known yet: the clock owner takes it when sim time starts, another node
        from the first stamp it receives, :meth:`learn_epoch`). A bad value is logged with the
        reason and the default kept; the node runs on."""
        from gyro_instrument.recording.frames import WALL, check_frame_prefix, parse_stamp_epoch
        self.frame_prefix, self.stamp_offset_ns = "", 0
        try:
            self.frame_prefix = check_frame_prefix(self.value("frame_prefix", ""))
        except SceneError as exc:
            self.get_logger().error(f"{exc}; no prefix used")
        try:
            rtf = float(self.value("real_time_factor", 1.0)) if owner else None
            epoch = parse_stamp_epoch(self.value("stamp_epoch", ""), rtf)
            self.stamp_offset_ns = None if epoch == WALL else epoch - m.EPOCH_NS
        except SceneError as exc:
            self.get_logger().error(f"{exc}; the simulation epoch used")

    def learn_epoch(self, stamp_ns) -> int:
        """With ``stamp_epoch`` = wall on a node that does not own the clock: the first stamp
        received (sim time 0 of the run: the first clock tick or a topic's first sample) fixes the
        shift. Returns :attr:`stamp_offset_ns`."""
        if self.stamp_offset_ns is None:
            self.stamp_offset_ns = int(stamp_ns) - m.EPOCH_NS
            self.get_logger().info(f"stamp_epoch = wall: sim time 0 is stamped {int(stamp_ns) / 1e9:.9f} s "
                                   f"(the first stamp received)")
        return self.stamp_offset_ns

    def publish_static_transforms(self, tfs) -> None:
        """Publish ``tfs`` (:class:`~gyro_instrument.recording.frames.StaticTransform`) once, latched,
        on the relative topic ``static_transforms``: ``geometry_msgs/TransformStamped``, RELIABLE,
        TRANSIENT_LOCAL, KEEP_LAST with a depth of the frame count (a late subscriber gets them all),
        stamped at sim time 0; then watch the graph for another namespace publishing the same frames
        (:meth:`_check_frame_clash`). Nothing while a ``wall`` epoch is not known (called again)."""
        from gyro_instrument.recording.frames import STATIC_TRANSFORMS, transform_stamped_cdr
        if not tfs or self.stamp_offset_ns is None or getattr(self, "_tf_pub", None) is not None:
            return
        qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=len(tfs), reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._tf_pub = self.create_publisher(m.message_class("geometry_msgs/msg/TransformStamped"),
                                             STATIC_TRANSFORMS, qos)
        for tf in tfs:
            self._tf_pub.publish(transform_stamped_cdr(tf, m.EPOCH_NS + self.stamp_offset_ns))
        self._tf_children = {tf.child for tf in tfs}
        self._tf_watched, self._tf_warned = {}, set()
        self._tf_timer = self.create_timer(1.0, self._check_frame_clash, clock=STEADY)

    def drop_static_transforms(self) -> None:
        """Undo :meth:`publish_static_transforms` (a restart)."""
        for sub in getattr(self, "_tf_watched", {}).values():
            self.destroy_subscription(sub)
        if getattr(self, "_tf_timer", None) is not None:
            self.destroy_timer(self._tf_timer)
        if getattr(self, "_tf_pub", None) is not None:
            self.destroy_publisher(self._tf_pub)
        self._tf_pub, self._tf_timer, self._tf_watched = None, None, {}

    def _check_frame_clash(self) -> None:
        """Subscribe (latched, raw) to every ``static_transforms`` topic of another namespace; a
        transform there whose child frame is one of this node's is warned about once, naming that
        topic: two suites with the same frame names (set ``frame_prefix``)."""
        from gyro_instrument.recording.frames import STATIC_TRANSFORMS
        mine = self._tf_pub.topic_name
        for topic, _ in self.get_topic_names_and_types():
            if topic == mine or topic in self._tf_watched or not topic.endswith("/" + STATIC_TRANSFORMS):
                continue
            qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
            self._tf_watched[topic] = self.create_subscription(
                m.message_class("geometry_msgs/msg/TransformStamped"), topic,
                lambda msg, tp=topic: self._on_foreign_transform(tp, msg), qos)

    def _on_foreign_transform(self, topic, msg) -> None:
        child = msg.child_frame_id
        if child in self._tf_children and (topic, child) not in self._tf_warned:
            self._tf_warned.add((topic, child))
            ns = topic[: -len("/static_transforms")] or "/"
            self.get_logger().warning(
                f"frame {child!r} is also published on {topic} (another suite in namespace {ns} names the same "
                f"frames; frame_prefix = {self.frame_prefix!r}): tf2 cannot tell them apart; give each suite its "
                f"own frame_prefix (e.g. frame_prefix:=ship1/)")

    def value(self, name, default=None) -> object:
        """A parameter's value (``default`` if it is not declared)."""
        if not self.has_parameter(name):
            return default
        v = self.get_parameter(name).value
        return default if v is None else v

    # ---- liveness on /diagnostics ------------------------------------------------------------------

    def start_diagnostics(self) -> None:
        """Publish this node's state on ``diagnostics`` every :data:`DIAG_PERIOD_S` of wall time (a
        node run alone; latched, so an aggregator started later gets every node's last state), from a
        thread of its own: the state keeps coming while a callback integrates a block or waits for a
        slow subscriber."""
        self._diag_pub = self.create_publisher(DiagnosticArray, DIAGNOSTICS, LATCHED)
        self._diag_stop = threading.Event()

        def loop():
            while True:
                try:
                    self.publish_diagnostics()
                except Exception:        # the context shut down under it (the node is going), or a
                    if not self.context.ok():    # state read while the node's thread changed it:
                        return                   # the next period says it
                if self._diag_stop.wait(DIAG_PERIOD_S):
                    return
        self._diag_thread = threading.Thread(target=loop, name=f"{self.get_name()}_diagnostics", daemon=True)
        self._diag_thread.start()

    def destroy_node(self) -> None:
        stop = getattr(self, "_diag_stop", None)
        if stop is not None:
            stop.set()
            self._diag_thread.join(timeout=2.0)
        return super().destroy_node()

    def liveness(self) -> tuple:
        """(level, message, {key: value}) of this node now; subclasses say more."""
        return OK, getattr(self, "state", "idle"), {}

    def sim_time_ns(self) -> int:
        """This node's sim time (ns from the release, the epoch's t = 0) for the liveness stamp."""
        return 0

    def publish_diagnostics(self) -> None:
        pub = getattr(self, "_diag_pub", None)
        if pub is None or not self.context.ok():
            return
        level, message, values = self.liveness()
        name = f"gyro_instrument: {resolve(self.get_namespace(), self.get_name())}"
        pub.publish(m.diagnostics(self.sim_time_ns(), name, True, message,
                                  {k: v for k, v in values.items() if v is not None}, level=level,
                                  hardware_id=LIVENESS_ID))

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
        return vals["scene"], list(vals["overrides"] or []), (float(vals["duration_s"] or 0.0) or None)

    def unchanged(self, param) -> bool:
        """True when ``param`` (already converted by the pre-set check) holds the value the node has:
        setting it changes nothing (``ros2 param set`` of the current value, ``ros2 param load`` of an
        unchanged dump)."""
        if not self.has_parameter(param.name) or param.name in self.refused:
            return False                 # a start-up value refused: any value set now is a correction
        old = self.get_parameter(param.name)
        return old.type_ == param.type_ and list_or(old.value) == list_or(param.value)

    def _check_params(self, params):
        # what this set really changes (the post-set callback acts on these only)
        self._changing = {p.name for p in params if not self.unchanged(p)}
        params = [p for p in params if p.name in self._changing]
        for p in params:
            if p.name == "use_sim_time" and p.value is True and self.clock_owner:
                reason = ("use_sim_time = true is invalid on the clock owner: it publishes clock and would wait "
                          "for itself")
                self.get_logger().error(f"parameter refused: {reason}")
                return SetParametersResult(successful=False, reason=reason)
        if not any(p.name in P.SCENE_NAMES for p in params):
            return SetParametersResult(successful=True)
        try:
            api.load_scene(*self._scene_args(params))
        except SceneError as exc:
            self.get_logger().error(f"parameter refused: {exc}")
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _after_set(self, params):
        for p in params:
            self.refused.pop(p.name, None)
        changed = [p for p in params if p.name in getattr(self, "_changing", ())]
        if changed:
            self.get_logger().info("parameters changed: " + ", ".join(f"{p.name} = {p.value!r}" for p in changed))
        same = [p.name for p in params if p.name not in getattr(self, "_changing", ())]
        if same:
            self.get_logger().info(f"parameters set to the values they had: {', '.join(same)}; nothing changes")
        if any(p.name in self.RESTART_ON for p in changed):
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
            self.scene = api.load_scene(*self._scene_args())
            self.insts = build_instruments(self.scene)
            return True
        except SceneError as exc:
            self.get_logger().error(f"{exc}")
            self.scene, self.insts = None, {}
            return False

    def _named_nodes_ready(self, expected):
        """expected: {node name: [resolved topics it must subscribe to]} -> names still missing. An
        :class:`AnyOf` of topics is met by a subscription to any one of them (a recorder of a subset of
        this node's topics) once the set of them this node sees has not changed for
        :data:`ANY_OF_SETTLE_S` (the graph shows a recorder's subscriptions one by one as it creates
        them: seen after its first, a simulator started and its later topics missed every sample, 1 in
        10 runs of two namespaced suites); the others are then waited for as unmatched ones."""
        ns = self.get_namespace()
        missing = []
        settled = getattr(self, "_any_of_seen", None)
        if settled is None:
            settled = self._any_of_seen = {}
        now = time.monotonic()
        for node_name, topics in expected.items():
            there = [any(i.node_name == node_name and i.node_namespace == ns
                         for i in self.get_subscriptions_info_by_topic(topic)) for topic in topics]
            if isinstance(topics, AnyOf):
                seen = frozenset(t for t, ok in zip(topics, there) if ok)
                if settled.get(node_name, (None,))[0] != seen:
                    settled[node_name] = (seen, now)
                if not seen or now - settled[node_name][1] < ANY_OF_SETTLE_S:
                    missing.append(node_name)
            elif not all(there):
                missing.append(node_name)
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
        self._watch_t0 = self._watch_matched = None

        def tick(_data):
            self._foreign_ticks += 1
        self._clock_watch = self.create_subscription(m.Clock, topic, tick, RELIABLE_ALL, raw=True)

    def clock_watch_settled(self) -> bool:
        """True once the clock watch can tell whether another owner ticks: it has matched every other
        publisher of the clock the graph shows and has listened :data:`ANY_OF_SETTLE_S` since (or it
        has waited ``wait_timeout_s`` + 2 s for that). A node started while an owner already ticks
        decided before its watch was matched, saw no tick and, named first, started a second clock
        (1 of ~10 CI runs)."""
        watch = getattr(self, "_clock_watch", None)
        if watch is None:
            return True
        me = resolve(self.get_namespace(), self.get_name())
        others = {resolve(i.node_namespace, i.node_name) for i in self.get_publishers_info_by_topic(watch.topic_name)}
        others.discard(me)
        now = time.monotonic()
        if getattr(self, "_watch_t0", None) is None:
            self._watch_t0 = now
        if now - self._watch_t0 > float(self.value("wait_timeout_s", 0.0)) + 2.0:
            return True
        if others and watch.get_publisher_count() < len(others):
            self._watch_matched = None
            return False
        if self._foreign_ticks or not others:
            return True
        if getattr(self, "_watch_matched", None) is None:
            self._watch_matched = now
        return now - self._watch_matched >= ANY_OF_SETTLE_S

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


