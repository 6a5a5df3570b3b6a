"""``player``: :class:`PlayerNode` republishes a bag's intact messages (every chunk's CRC checked;
what was lost is logged with its log-time span) in log-time order, driving ``clock``; waits for its
subscribers, exits at the end (or loops).

Memory is bounded whatever the bag's size: the start-up scan
(:func:`~gyro_instrument.recording.bag_layout.scan_path`) keeps per-chunk offsets, times and counts,
not messages, and play streams (:func:`~gyro_instrument.recording.mcap_io.stream_messages`) an
intact file chunk by chunk through the MCAP reader and a damaged one container by container from
the scan's offsets, skipping the damaged chunks; what is held at once is the chunks that overlap
in log time (tests/test_player_memory.py measures it).
"""

import os
import time

from rclpy._rclpy_pybind11 import RCLError
from rclpy.duration import Duration
from rclpy.qos import DurabilityPolicy

from gyro_instrument import api
from gyro_instrument.core.errors import SceneError
from gyro_instrument.recording.bag_layout import scan_path
from gyro_instrument.recording.mcap_io import play_plan, stream_messages
from gyro_instrument.recording.qos import parse_profiles
from gyro_instrument.recording.topics import CLOCK, resolve
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.base import (ERROR, FLOW_BATCH, OK, PUBLISH_ALL, STEADY, WARN, SceneNode, qos_text,
                                            replay_qos)

#: how long a latched topic's publish waits for the previous message's acknowledgement before the
#: tick gives up (and tries again at the next one)
LATCH_ACK_WAIT = Duration(seconds=0.05)


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
        self.total = 0              # messages to play (intact, of an installed type)
        self.index = 0              # messages played in this pass
        self._plan, self._it, self._next = [], iter(()), None
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
            self.get_logger().warning(f"bag {bag}: damaged: {api.damage_line(d)}; those messages are not published")
        for note in scan.notes:
            self.get_logger().warning(f"bag {bag}: {note}")
        classes = self._classes(bag, scan)
        offers = self._offers(scan)
        self._plan = play_plan(bag, scan)       # offsets only: every file is read as it is played
        del scan
        self._restart_stream()
        for tp, n in self.skipped.items():
            self.get_logger().warning(f"bag {bag}: {tp}: {n} messages not played (type not installed)")
        self.latched = set()        # topics offered TRANSIENT_LOCAL (as recorded)
        for topic, cls in classes.items():
            if cls is not None:
                qos = replay_qos(offers.get(topic, []))
                if qos.durability == DurabilityPolicy.TRANSIENT_LOCAL:
                    self.latched.add(topic)
                self.pubs[topic] = self.create_publisher(cls, topic, qos)
        clock_topics = {tp for tp in self.pubs if tp.split("/")[-1] == CLOCK}
        self.has_clock = bool(clock_topics)
        if not self.has_clock:
            self.pubs[CLOCK] = self.create_publisher(m.Clock, CLOCK, self.pub_qos)
            clock_topics = {CLOCK}
        self.clock_topics = sorted(self.pubs[tp].topic_name for tp in clock_topics)
        self._last_clock = None
        self.sent = {tp: [0, 0, 0] for tp in self.pubs}     # sent, sent to >= 1 subscriber, deliveries
        self.per_sub = {}           # (topic, node, QoS text) -> messages sent while it was matched
        self._graph_cache = {}      # topic -> (matched count, [(node, QoS text)]) of its subscriptions
        self.blocked = None         # (topic, since) while a write is refused (a subscriber's queue is full)
        self._unacked = set()       # topics a subscriber had not acknowledged when the player finished
        self._blocked_log = 0.0
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

    def _classes(self, bag, scan):
        """{relative topic: message class or None (type not installed)} in the order the topics
        first appear; counts :attr:`total` and the messages :attr:`skipped` from the scan's
        per-channel counts (nothing is read)."""
        classes = {}
        for schema, channel, n in scan.channel_counts():
            tp = channel.topic
            topic = tp.lstrip("/")
            if topic not in classes:
                classes[topic] = self._message_class(bag, tp, schema.name if schema else "")
            if classes[topic] is None:
                self.skipped[tp] = self.skipped.get(tp, 0) + n
            else:
                self.total += n
        return classes

    @staticmethod
    def _offers(scan) -> dict:
        """{relative topic: [recorded QoS profiles]} of every channel of the bag (rosbag2's
        ``offered_qos_profiles``: one profile per publisher the recorder saw)."""
        out = {}
        for _, channel, _ in scan.channel_counts():
            profiles = parse_profiles((channel.metadata or {}).get("offered_qos_profiles", ""))
            out.setdefault(channel.topic.lstrip("/"), []).extend(profiles)
        return out

    def _restart_stream(self):
        """Play from the bag's first message (the start, or a loop)."""
        self.index, self._next = 0, None
        self._it = ((tp.lstrip("/"), ty, t, data) for tp, ty, t, data in stream_messages(self._plan)
                    if tp.lstrip("/") in self.pubs)

    def peek(self) -> tuple | None:
        """The next message to play, (topic, type, log time ns, CDR bytes), or None at the end."""
        if self._next is None:
            self._next = next(self._it, None)
        return self._next

    def publish_next(self, counts=None) -> bool | None:
        """Publish the next message (and a clock tick when the bag has none); False when done, None
        when a subscriber's full queue refused the write (the message stays next: nothing is dropped,
        :meth:`_send`). ``counts`` {topic: matched subscribers} is what :attr:`sent` counts."""
        item = self.peek()
        if item is None:
            return False
        topic, _, log_ns, data = item
        if not self.has_clock and log_ns != self._last_clock:
            if not self._send(CLOCK, m.CLOCK_LAYOUT.encode([log_ns - m.EPOCH_NS])[0], counts):
                return None
            self._last_clock = log_ns
        if not self._send(topic, data, counts):
            return None
        self._next = None
        self.index += 1
        return True

    def _send(self, topic, data, counts) -> bool:
        """Publish ``data`` on ``topic``; False (logged when the wait starts, every 10 s and when it
        ends) when the write is refused: a RELIABLE / KEEP_ALL subscriber is not taking messages and
        the writer's history is full (Fast DDS refuses after its blocking time, "cannot publish
        data"), or a latched (KEEP_LAST) topic's previous message is not acknowledged yet (it would
        be overwritten). The caller tries again at its next tick, as the simulators wait."""
        pub = self.pubs[topic]
        if topic in self.latched and not pub.wait_for_all_acked(LATCH_ACK_WAIT):
            return self._refused(pub)
        try:
            pub.publish(data)
        except RCLError:
            if not self.context.ok():
                raise
            return self._refused(pub)
        if self.blocked is not None:
            self.get_logger().info(f"publishing {self.blocked[0]} resumed after "
                                   f"{time.monotonic() - self.blocked[1]:.1f} s")
            self.blocked = None
        n = counts[topic] if counts is not None else pub.get_subscription_count()
        c = self.sent[topic]
        c[0] += 1
        c[1] += n > 0
        c[2] += n
        for key in self._subscribers(topic, n):
            self.per_sub[key] = self.per_sub.get(key, 0) + 1
        self._first_sent.add(topic)
        return True

    def _refused(self, pub) -> bool:
        now = time.monotonic()
        if self.blocked is None:
            self.blocked = (pub.topic_name, now)
            self._blocked_log = now
            self.get_logger().warning(f"publishing {pub.topic_name} waits: a RELIABLE subscriber is not taking "
                                      f"messages (its queue is full); nothing is dropped")
        elif now - self._blocked_log >= 10.0:
            self._blocked_log = now
            self.get_logger().warning(f"publishing {self.blocked[0]} has waited {now - self.blocked[1]:.0f} s "
                                      f"for a subscriber")
        return False

    def _subscribers(self, topic, matched) -> list:
        """Keys (topic, node, QoS) of the subscriptions matched on ``topic`` (the graph's, re-read
        when the matched count changes); none when the graph shows fewer than are matched."""
        cached = self._graph_cache.get(topic)
        if cached is None or cached[0] != matched:
            infos = self.get_subscriptions_info_by_topic(self.pubs[topic].topic_name)
            keys = [(self.pubs[topic].topic_name, resolve(i.node_namespace, i.node_name), qos_text(i.qos_profile))
                    for i in infos] if len(infos) == matched else []
            cached = self._graph_cache[topic] = (matched, keys)
        return cached[1]

    def start(self) -> None:
        """Wait for the subscribers (``wait_topics``, ``wait_for``, ``min_subscribers``; every
        subscription the graph shows matched and unchanged for :attr:`SETTLE_S`; at most
        ``wait_timeout_s``), then play."""
        self.standalone = True
        if not self.total:
            self.done = True
            return
        wt = self._wait_topics = self.wait_topics()
        self.get_logger().info(
            f"publishes {self.total} messages on {', '.join(p.topic_name for p in self.pubs.values())}"
            f"{self.clock_remap_note(self.clock_topics[0])}; waiting up to {self.value('wait_timeout_s'):g} s for "
            f"{self.value('min_subscribers')} subscriber(s) on topics other than the clock"
            + (f", a subscriber on each of {', '.join(wt)} (wait_topics)" if wt else "")
            + (f" and {', '.join(self.value('wait_for'))}" if self.value("wait_for") else "")
            + f", and every subscription seen matched for {self.SETTLE_S:g} s")
        self.state = "waiting"
        self._missing = []
        self.start_diagnostics()
        self._wait_t0 = time.monotonic()
        self._graph, self._graph_t = None, time.monotonic()
        for tp in self.clock_topics:
            self.watch_clock(tp)
        self.timer = self.create_timer(0.002, self._tick, clock=STEADY)

    def liveness(self) -> tuple:
        """The state on /diagnostics: waiting for subscribers, playing, waiting for a subscriber to take
        messages, waiting for acknowledgements, done, refused, or not playing (a bad bag)."""
        values = {"played": self.index, "messages": self.total, "sim_time_s": self.sim_time_ns() / 1e9}
        if self.state == "idle":
            return ERROR, "not playing: the bag is missing or unreadable (see the log)", values
        if self.state == "waiting":
            return OK, "waiting for subscribers: " + (", ".join(self._missing) or "the graph"), values
        if self.state == "refused":
            return ERROR, "not playing: another node publishes the clock", values
        if self.blocked is not None:
            return WARN, f"waiting for a subscriber to take messages on {self.blocked[0]} (nothing dropped)", values
        if self.state == "draining":
            return OK, "all played; waiting for every subscriber to acknowledge", values
        return OK, self.state, values

    def sim_time_ns(self) -> int:
        return max(self._last_clock - m.EPOCH_NS, 0) if getattr(self, "_last_clock", None) else 0

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
            missing = self._missing = self._ready()
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
        if self.state == "draining":
            self._drain()
            return
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
                nxt = self.peek()
                self._rtf, self._w0, self._t0 = rtf, now, (nxt[2] if nxt is not None else 0)
            k = 0
            while k < FLOW_BATCH and self.peek() is not None and \
                    (self.peek()[2] - self._t0) <= (now - self._w0) * rtf * 1e9:
                if self._first_of_topic() or not self.publish_next(counts):
                    break
                k += 1
        if self.peek() is None:
            self.state = "draining"
            self._drain_t0 = self._drain_log = time.monotonic()
            self._waited, self._unacked = set(), set()

    def _drain(self):
        """After the last message: wait until every subscriber acknowledged everything (a slow
        RELIABLE subscriber still gets the rest: exiting would drop the writer's history), at most
        ``wait_timeout_s`` (a subscriber that never takes, stopped or stuck, must not keep the player
        forever: warned, and the summary says "not all acknowledged"), logged every 10 s; a subscriber
        that leaves stops counting. Then the summary, and exit or loop."""
        waiting = [p for p in self.pubs.values() if p.get_subscription_count() and not p.wait_for_all_acked(
            LATCH_ACK_WAIT)]
        now = time.monotonic()
        self._waited |= {p.topic_name for p in waiting}
        if waiting and now - self._drain_t0 >= self.value("wait_timeout_s"):
            self.get_logger().warning(f"wait_timeout_s passed without every acknowledgement on "
                                      f"{', '.join(p.topic_name for p in waiting)}: finishing anyway")
            self._unacked = {p.topic_name for p in waiting}
        elif waiting:
            if now - self._drain_log >= 10.0:
                self._drain_log = now
                self.get_logger().warning(f"all played; waiting {now - self._drain_t0:.0f} s for the subscribers of "
                                          f"{', '.join(p.topic_name for p in waiting)} to acknowledge")
            return
        # a subscriber that left while the player waited for it: not every message acknowledged
        self._unacked |= {p.topic_name for p in self.pubs.values() if p.topic_name in self._waited
                          and not p.get_subscription_count()}
        line = self.summary()
        if self.value("loop", False):
            self.get_logger().info(f"{line}; looping")
            self._restart_stream()
            self._rtf, self._last_clock = None, None
            self.state = "playing"
        else:
            self.get_logger().info(f"{line}; exiting")
            self.timer.cancel()
            self.state = "done"
            self.done = True

    def _first_of_topic(self) -> bool:
        """True (stop the batch) when the next message is its topic's first and the graph shows a
        subscription on that topic not matched yet: it is held (:meth:`_held`)."""
        item = self.peek()
        if item is None:
            return False
        topic = item[0]
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
        """What was played, and per subscriber what it could have received: the messages sent while
        it was matched; all of them reached a RELIABLE / KEEP_ALL subscriber (the player waits for
        it), a KEEP_LAST or best-effort one keeps only what it takes in time (its own queue drops
        the rest, which no publisher can see)."""
        sent = sum(c[0] for c in self.sent.values())
        to_one = sum(c[1] for c in self.sent.values())
        short = [f"{self.pubs[tp].topic_name} {c[1]} of {c[0]}" for tp, c in self.sent.items() if c[1] < c[0]]
        line = (f"played {self.total} messages ({sent} published with the clock ticks added); {to_one} sent while "
                f"at least one subscriber was matched")
        subs = []
        for (topic, node, qos), k in sorted(self.per_sub.items()):
            total = next(c[0] for tp, c in self.sent.items() if self.pubs[tp].topic_name == topic)
            if not qos.startswith("RELIABLE"):
                fate = "best effort: not acknowledged, some may be lost"
            else:
                fate = "not all acknowledged" if topic in self._unacked else "all acknowledged"
            subs.append(f"{node} on {topic} ({qos}) {k} of {total} sent while it was matched, {fate}")
        if subs:
            line += ("; per subscriber (a KEEP_ALL subscriber received every message acknowledged; a KEEP_LAST "
                     "one only those it took before its queue overflowed, which a publisher cannot see): "
                     + ", ".join(subs))
        if short:
            line += "; sent with no subscriber matched: " + ", ".join(short)
        if self.skipped:
            line += "; skipped (type not installed): " + ", ".join(f"{tp} {n}" for tp, n in self.skipped.items())
        return line
