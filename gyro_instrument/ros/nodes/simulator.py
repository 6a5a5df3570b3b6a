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
from std_srvs.srv import Trigger

from gyro_instrument.core.scene import DEFAULT_WINDOW_S
from gyro_instrument.estimators.pipeline import estimator_instruments
from gyro_instrument.instruments import simulator_kinds
from gyro_instrument.recording.frames import instrument_frames
from gyro_instrument.recording.sim_stream import SimulatorStream
from gyro_instrument.recording.topics import CLOCK, resolve
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.base import (AnyOf, ERROR, FLOW_BATCH, FOLLOW_CLOCK, OK, PUBLISH_ALL, RELIABLE_ALL, STEADY,
                                            WARN, SceneNode, acked)


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
        self._clock_t = None        # the last clock tick a follower saw (ns from the epoch)
        self._integrating = False   # inside a block's integration (liveness)
        self._blocked_on = None     # topic a refused write waits on (liveness)
        self._missing = []          # what the wait before sim time still misses (liveness)
        self._restart_clients = {}
        if self.load():
            self.prepare()

    def _new_stream(self) -> SimulatorStream:
        """The core stream with this node's parameters, frame prefix and stamp shift
        (:meth:`frames_and_epoch` read them; a rewind keeps them)."""
        seed = self.get_parameter("seed").value
        stream = SimulatorStream(self.scene, self.insts, self.kinds, None if seed < 0 else seed,
                                 float(self.value("window_s", DEFAULT_WINDOW_S)), self.clock_owner,
                                 self.frame_prefix)
        stream.stamp_offset_ns = self.stamp_offset_ns
        return stream

    def prepare(self) -> None:
        """Create the core stream and the publishers its publications declare: nothing is integrated
        until the first publish, and then one window of ``window_s`` simulated seconds at a time."""
        self.frames_and_epoch()
        self.stream = self._new_stream()
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

    def rewind(self) -> bool:
        """Start the run again from t = 0 with the parameters as they are now, keeping the publishers
        (so every subscriber stays matched and nothing published is lost): True when the reloaded
        scene publishes the same topics with the same types; False (nothing changed) otherwise, or when
        the scene does not load (logged)."""
        old = {key: (pub.topic_name, pub.msg_type) for key, pub in self.pubs.items()}
        if not self.load():
            return False
        stream = self._new_stream()
        new = {(name, p.key): (self.resolve_topic_name(p.topic), m.message_class(p.type_name))
               for name, pubs in stream.pubs.items() for p in pubs}
        if new != old:
            return False
        self.stream, self._marker_msgs, self._clock_t = stream, {}, None
        return True

    def _restart_run(self) -> None:
        """A real change of ``scene``, ``overrides``, ``duration_s`` or ``seed`` on a node run alone:
        the whole run starts again together. The clock owner rewinds (its clock goes back to the epoch;
        the followers rewind when they see it, :meth:`_on_clock`; the recorder starts one new file and
        the estimator a new estimate); a follower asks the owner to restart (service ``restart``) and
        rewinds with its new values when the clock goes back. Alone (no owner seen), or when the topics
        change, the node tears down and starts again (:meth:`restart`)."""
        self._restart = False
        if self.clock_owner:
            if self.state in ("running", "done") and self.rewind():
                self.get_logger().info(f"scene {self.scene.name}: restarting the run from t = 0 (the clock goes "
                                       f"back to the epoch; the followers restart with it)")
                self.state, self._rtf = "running", None
                self.timer.reset()
                return
        elif self.state in ("running", "done"):
            owner = self.clock_owner_name()
            if owner is not None:
                self.get_logger().info(f"asking the clock owner {owner} to restart the run: this node restarts with "
                                       f"its new values when the clock goes back")
                self._ask_restart(owner)
                return
        self.restart()

    def clock_owner_name(self) -> str | None:
        """The fully qualified name of the node publishing this node's clock, or None."""
        topic = self.resolve_topic_name(CLOCK)
        me = resolve(self.get_namespace(), self.get_name())
        owners = sorted({resolve(i.node_namespace, i.node_name) for i in self.get_publishers_info_by_topic(topic)}
                        - {me})
        return owners[0] if owners else None

    def _ask_restart(self, owner) -> None:
        cli = self._restart_clients.get(owner)
        if cli is None:
            cli = self._restart_clients[owner] = self.create_client(Trigger, f"{owner}/restart")
        if not cli.service_is_ready():
            self.get_logger().warning(f"{owner}/restart is not available: restarting this node alone")
            self.restart()
            return
        cli.call_async(Trigger.Request()).add_done_callback(
            lambda fut: self.get_logger().info(f"{owner}: {fut.result().message}") if fut.result() else None)

    def _on_restart_request(self, request, response):
        """Service ``restart`` (std_srvs/Trigger): the clock owner restarts the run from t = 0 with its
        current parameters (every follower with it); a follower passes the request to the owner."""
        if self.state not in ("running", "done"):
            response.success = False
            response.message = f"not restarted: {self.get_name()} is {self.state} (no run to restart)"
            self.get_logger().error(f"restart refused: {response.message}")
        elif self.clock_owner:
            self._restart = True
            response.success, response.message = True, "restarting the run from t = 0"
        else:
            owner = self.clock_owner_name()
            if owner is None:
                self._restart = True
                response.success, response.message = True, "no clock owner seen: restarting this node alone"
            else:
                self._ask_restart(owner)
                response.success, response.message = True, f"asked the clock owner {owner} to restart the run"
        return response

    def liveness(self) -> tuple:
        """The state on /diagnostics: waiting for subscribers, integrating, publishing, waiting for a
        subscriber to take messages, done (settled), refused or idle (not running, with why)."""
        n = self.samples
        values = {"samples_published": self.index, "samples": n, "sim_time_s": self.sim_time_ns() / 1e9,
                  "owns_clock": self.clock_owner}
        if self.state == "idle":
            return (ERROR if self.scene is None else OK), ("not running: the scene did not load or a start-up "
                                                          "value was refused (see the log)" if self.scene is None
                                                          else "idle"), values
        if self.state == "waiting":
            return OK, "waiting for subscribers: " + (", ".join(self._missing) or "the graph"), values
        if self.state == "refused":
            return ERROR, "not running: publish_clock refused (another node publishes the clock)", values
        if self.state == "done":
            return OK, f"settled: published all {n} samples", values
        if self._blocked_on:
            return WARN, f"waiting for a subscriber to take messages on {self._blocked_on} (nothing dropped)", values
        return OK, ("integrating" if self._integrating else "publishing"), values

    def sim_time_ns(self) -> int:
        return int(self.stream.index * self.stream.step_ns) if self.stream is not None else 0

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
        self._integrating = not self.stream.block_ready(k)
        batch = self.stream.batch(k)
        self._integrating = False
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
        self._blocked_on = topic
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
        self._blocked_on = None
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
        any of them (then the publishers' unmatched subscriptions are waited for), the estimator the joint states it reads (``estimator_instruments``), another name any of
        this node's topics; the clock owner also waits for the scene's other simulators (they
        subscribe to clock once their own subscribers are matched)."""
        mine = self.topics()
        out = {}
        for name in self.value("wait_for", []):
            if name == "recorder":                   # it may record a subset of them (its topics parameter)
                out[name] = AnyOf(mine)
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
        self._restart_srv = self.create_service(Trigger, "~/restart", self._on_restart_request)
        if self.samples:
            self._wait_begin()
        self.start_diagnostics()

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
            self._restart_run()
        if self.state != "waiting":
            return
        missing = self._named_nodes_ready(self.expected_subscribers())
        unmatched = self._unmatched(self.publishers())
        self._missing = missing + unmatched
        if missing or unmatched:
            if time.monotonic() - self._wait_t0 < self.value("wait_timeout_s"):
                return
            self.get_logger().warning(f"wait_timeout_s = {self.value('wait_timeout_s'):g} s passed without "
                                      f"{', '.join(missing + unmatched)}: starting anyway (those may miss samples)")
        if self.clock_pub is not None and not self.clock_watch_settled():
            return
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
            self.clock_sub = self.create_subscription(m.Clock, CLOCK, self._on_clock, FOLLOW_CLOCK, raw=True)

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
        """Follower: note the owner's clock (:meth:`after_drain` publishes every sample up to it, once
        per queue of ticks taken, not once per tick); when the clock goes back (the owner restarted its
        run) rewind first, with this node's current parameters."""
        st = m.cdr_stamp_ns(data)
        if self.stamp_offset_ns is None:
            self.set_stamp_offset(self.learn_epoch(st))
        t = st - m.EPOCH_NS - self.stamp_offset_ns
        if self._clock_t is not None and t < self._clock_t:
            if self.rewind():
                self.state = "running"
                self.get_logger().info(f"the clock went back to {t / 1e9:g} s: restarting the run from t = 0")
            else:
                self._clock_t = None
                self.restart()
                return
        self._clock_t = t

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
