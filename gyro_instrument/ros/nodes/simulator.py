"""``gyrocompass_sim``, ``pendulum_sim``, ``top_sim``: :class:`SimulatorNode`.

One core object (:class:`~gyro_instrument.recording.sim_stream.SimulatorStream`: integrate, measure
and lay out one window of ``window_s`` simulated seconds at a time, encode every publication's
messages in publishing order) whose batches the node publishes as CDR bytes, integrating the next
block only when the samples due go past the current one. Run alone (:meth:`SimulatorNode.start`)
it waits for the subscribers the scene expects (``wait_for``), then either owns ``clock``
(``publish_clock``) and paces it, or follows the owner's clock, publishing each sample when sim
time reaches it.
"""

import time

from rclpy._rclpy_pybind11 import RCLError
from rclpy.serialization import serialize_message

from gyro_instrument.core.scene import DEFAULT_WINDOW_S
from gyro_instrument.estimators.pipeline import estimator_instruments
from gyro_instrument.instruments import simulator_kinds
from gyro_instrument.recording.frames import instrument_frames
from gyro_instrument.recording.sim_stream import SimulatorStream
from gyro_instrument.recording.topics import CLOCK
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.base import FLOW_BATCH, LATEST_CLOCK, PUBLISH_ALL, RELIABLE_ALL, STEADY, SceneNode, acked


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
        self.stream = None          # the core: SimulatorStream
        self.pubs = {}              # (instrument, publication key) -> publisher
        self.clock_pub = None
        self.clock_sub = None
        self.timer = None
        self.offsets = {}           # topic -> sample offsets of the last batch's sparse messages
        self._marker_msgs = {}      # instrument -> its last MarkerArray (updated in place)
        self.state = "idle"
        if self.load():
            self.prepare()

    def prepare(self) -> None:
        """Create the core stream and the publishers its publications declare: nothing is integrated
        until the first publish, and then one window of ``window_s`` simulated seconds at a time."""
        seed = self.get_parameter("seed").value
        self.frames_and_epoch()
        self.stream = SimulatorStream(self.scene, self.insts, self.kinds, None if seed < 0 else seed,
                                      float(self.value("window_s", DEFAULT_WINDOW_S)), self.clock_owner,
                                      self.frame_prefix)
        self.stream.stamp_offset_ns = self.stamp_offset_ns
        if not self.stream.chosen:
            self.get_logger().warning(f"scene {self.scene.name} has no instrument of kinds {', '.join(self.kinds)}")
        self.clock_pub = self.create_publisher(m.Clock, CLOCK, self.pub_qos) if self.clock_owner else None
        for name, pubs in self.stream.pubs.items():
            for p in pubs:
                self.pubs[(name, p.key)] = self.create_publisher(m.message_class(p.type_name), p.topic, self.pub_qos)
        self.publish_static_transforms(instrument_frames(self.insts, self.stream.chosen, self.frame_prefix))

    def set_stamp_offset(self, offset_ns) -> None:
        """Shift every stamp from now on by ``offset_ns`` (``stamp_epoch``: a ``wall`` epoch once known)."""
        self.stamp_offset_ns = int(offset_ns)
        if self.stream is not None:
            self.stream.stamp_offset_ns = self.stamp_offset_ns
            self.publish_static_transforms(instrument_frames(self.insts, self.stream.chosen, self.frame_prefix))

    @property
    def chosen(self) -> dict:
        """The instruments this node publishes (name -> Instrument)."""
        return self.stream.chosen if self.stream is not None else {}

    @property
    def samples(self) -> int:
        """Samples of the whole run (0 when the scene has no instrument of this node's kinds)."""
        return self.stream.samples if self.stream is not None else 0

    @property
    def index(self) -> int:
        """Samples published so far."""
        return self.stream.index if self.stream is not None else 0

    @property
    def blocks_pulled(self) -> int:
        """Blocks integrated so far."""
        return self.stream.blocks_pulled if self.stream is not None else 0

    def block_ready(self, k) -> bool:
        """True when the next ``k`` samples (or the rest of the run) are already integrated: a
        :meth:`publish_steps` of ``k`` integrates nothing (the suite commits the bag before it does)."""
        return self.stream is None or self.stream.block_ready(k)

    def teardown(self) -> None:
        if self.timer is not None:
            self.destroy_timer(self.timer)
        self.timer = None
        for attr in ("clock_sub", "_clock_watch"):
            if getattr(self, attr, None) is not None:
                self.destroy_subscription(getattr(self, attr))
                setattr(self, attr, None)
        for pub in self.publishers():
            self.destroy_publisher(pub)
        self.drop_static_transforms()
        self.pubs, self.clock_pub, self.stream, self._marker_msgs = {}, None, None, {}
        self._clock_t = None

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

    def publishers(self) -> list:
        """This node's publishers, the clock first."""
        return ([self.clock_pub] if self.clock_pub is not None else []) + list(self.pubs.values())

    def topics(self) -> list:
        """Topics this node publishes (fully qualified)."""
        return [pub.topic_name for pub in self.publishers()]

    def sample_index(self, t_ns) -> int:
        """How many samples have a stamp <= ``t_ns`` (ns from release)."""
        return self.stream.sample_index(t_ns)

    def publish_steps(self, k) -> int:
        """Publish samples ``index`` .. ``index + k - 1`` (fewer at the end): topic by topic, the
        clock first, each topic's messages in sample order (each topic is its own ordered stream);
        return how many samples were published (0 when none remain). Blocks are integrated by the
        core, when the samples asked for go past the current one."""
        if self.stream is None:
            return 0
        batch = self.stream.batch(k)
        self.offsets = {self.pubs[key].topic_name: offs for key, offs in batch.offsets.items()}
        for key, datas in batch.messages:
            pub = self.clock_pub if key == "clock" else self.pubs[key]
            if key in batch.stamps:          # marker geometry: into messages
                datas = [serialize_message(self._marker_array(key[0], t, g)) for t, g in zip(batch.stamps[key], datas)]
            with pub.handle:
                publish = pub.handle.publish_raw
                for data in datas:
                    try:
                        publish(data)
                    except RCLError:
                        if not self.standalone or not self.context.ok():
                            raise
                        self._publish_waiting(publish, data, pub.topic_name)
        return batch.count

    def _publish_waiting(self, publish, data, topic) -> None:
        """Publish ``data``, whose write was just refused: while a RELIABLE / KEEP_ALL subscriber is not
        taking messages (a recorder paused or starved of CPU: the writer's history fills, and Fast DDS
        refuses the write after its blocking time, "cannot publish data") wait and try again, nothing
        dropped and nothing reordered, with a WARN when the wait starts, every 10 s while it lasts and
        an INFO when it ends. A stop asked meanwhile (SIGINT / SIGTERM: :attr:`stop_asked`) ends the
        wait by raising KeyboardInterrupt; a context shut down re-raises the error. Only for a node
        run alone: in ``run``'s lock-step suite the subscribers are served by the same thread."""
        t0 = last = time.monotonic()
        self.get_logger().warn(f"publishing {topic} waits: a RELIABLE / KEEP_ALL subscriber is not "
                               f"taking messages (its queue is full); nothing is dropped")
        while True:
            if self.stop_asked():
                raise KeyboardInterrupt
            time.sleep(0.01)
            try:
                publish(data)
                break
            except RCLError:
                if not self.context.ok():
                    raise
                now = time.monotonic()
                if now - last >= 10.0:
                    last = now
                    self.get_logger().warn(f"publishing {topic} has waited {now - t0:.0f} s for a subscriber")
        self.get_logger().info(f"publishing {topic} resumed after {time.monotonic() - t0:.1f} s")

    def _marker_array(self, name, t_ns, geom):
        msg = m.marker_array(t_ns, name, geom, self._marker_msgs.get(name), self.frame_prefix + m.SITE_FRAME)
        self._marker_msgs[name] = msg
        return msg

    def publish_step(self) -> bool:
        """Publish sample ``index`` (clock first); return False when none remain."""
        return self.publish_steps(1) > 0

    # ---- run alone (ros2 run): wait for subscribers, then own or follow the clock -----------------

    def expected_subscribers(self) -> dict:
        """{node name: [topics it must subscribe to]} from ``wait_for`` and the scene: the recorder
        every topic, the estimator the joint states it reads (``estimator_instruments``), another name any of
        this node's topics; the clock owner also waits for the scene's other simulators (they
        subscribe to clock once their own subscribers are matched)."""
        mine = self.topics()
        out = {}
        for name in self.value("wait_for", []):
            if name == "recorder":
                out[name] = mine
            elif name == "estimator":
                topics = [self.pubs[(n, "joints")].topic_name for n in estimator_instruments(self.insts)
                          if (n, "joints") in self.pubs]
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
        if self.clock_pub is not None and self.stamp_offset_ns is None:
            self._wall_epoch()
        self.get_logger().info("sim time starts" if self.clock_pub is not None else "following the clock")
        if self.clock_owner:
            self._rtf = None
            self.timer = self.create_timer(0.002, self._run, clock=STEADY)
        else:
            self.clock_sub = self.create_subscription(m.Clock, CLOCK, self._on_clock, LATEST_CLOCK, raw=True)

    def _wall_epoch(self):
        """The clock owner with ``stamp_epoch`` = wall: sim time 0 is now (real-time factor 1; at any
        other factor the simulation epoch, logged)."""
        rtf = float(self.value("real_time_factor", 1.0))
        if rtf != 1.0:
            self.get_logger().error(f"stamp_epoch = 'wall' is invalid: only at real_time_factor 1 (here {rtf:g}); "
                                    f"the simulation epoch used")
            self.set_stamp_offset(0)
            return
        self.set_stamp_offset(time.time_ns() - m.EPOCH_NS)
        self.get_logger().info(f"stamp_epoch = wall: sim time 0 is stamped "
                               f"{(m.EPOCH_NS + self.stamp_offset_ns) / 1e9:.9f} s")

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
        """Follower: note the owner's clock; :meth:`after_drain` publishes every sample up to it
        (once per queue of ticks taken, not once per tick)."""
        st = m.cdr_stamp_ns(data)
        if self.stamp_offset_ns is None:
            self.set_stamp_offset(self.learn_epoch(st))
        self._clock_t = st - m.EPOCH_NS - self.stamp_offset_ns

    def after_drain(self) -> None:
        """Follower: publish every sample up to the last clock tick taken."""
        t = getattr(self, "_clock_t", None)
        if t is None or self.state != "running" or self.stream is None:
            return
        k = self.sample_index(t) - self.index
        if k > 0:
            self.publish_steps(k)
            if self.index >= self.samples:
                self._finish()

    def _finish(self):
        if self.timer is not None:
            self.timer.cancel()                  # destroyed on restart or with the node
        self.state = "done"
        self.get_logger().info(f"published {self.samples} samples of {', '.join(self.chosen)}")
        acked(self, self.publishers())
