"""``estimator``: :class:`EstimatorNode` collects joint samples (raw CDR, decoded in bulk, at most
4096 kept as bytes) into arrays of what it fits
(:class:`~gyro_instrument.recording.joint_buffer.JointBuffer`) and calls the core estimator; run
alone it publishes once every expected sample has arrived.

Live values (issues 24, 35, 37): each measurement kind that declares one (``LIVE``) gives a tracker
per instrument (``tracker(observation, scene, companions)``,
:class:`~gyro_instrument.instruments.measurement.LiveTracker`), which is given the tail of the
records it reads when due. A ``heading`` (the azimuth kind,
:class:`~gyro_instrument.estimators.kinds.NorthLive`: from the first swing on, the better of a
growing damped-sine fit with the predicted frequency as a prior and the Schuler mean of the
reversal points, :mod:`~gyro_instrument.estimators.north.live`) goes out as ``sensor_msgs/Imu`` on
``<instrument>/heading`` (:func:`~gyro_instrument.estimators.north.heading.imu_fields`, pre-serialized)
at :data:`~gyro_instrument.estimators.north.heading.HEADING_RATE_HZ` of sim time (every sample when the
instrument samples slower), stamped with the sample, and, with parameter ``nmea_udp``, as
``$HEHDT`` over UDP; the final estimate's block (the fit) replaces it. The work per joint message
is bounded: for the azimuth, a tail of 1.75 swings every quarter swing, at most ``FIT_SWINGS``
swings every half swing.
"""

import math
import time

import numpy as np

from rclpy.serialization import deserialize_message

from gyro_instrument.core.memory import sample_count
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.adequacy import InadequateData
from gyro_instrument.estimators.north.heading import HEADING_RATE_HZ, imu_fields
from gyro_instrument.estimators.pipeline import estimate_records, estimated_instruments, estimator_instruments
from gyro_instrument.instruments.measurement import declared_kinds, kind
from gyro_instrument.recording.cdr import imu_layout, restamped
from gyro_instrument.recording.frames import instrument_frames
from gyro_instrument.recording.joint_buffer import JointBuffer
from gyro_instrument.recording.joints import records_from_joints
from gyro_instrument.recording.nmea import NmeaUdpSender
from gyro_instrument.recording.topics import (CLOCK, DIAGNOSTICS, estimator_topics, heading_frame, heading_topic,
                                              joint_names, joint_topic, live_kinds)
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.base import ERROR, LATCHED, FOLLOW_CLOCK, OK, RELIABLE_ALL, STEADY, WARN, SceneNode


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
        self.failure = None     # why the last estimate failed (an error in the core), for run's last line
        self.pubs = {}
        self.timers_ = []
        self.clock_sub = None
        self.last_clock_ns = None
        self.expected = 0
        self.final = False
        self._clock_done_at = None
        self._last_input = None
        self.runs = 0
        self.sent = {}          # messages published per (resolved) topic
        self.trackers = {}      # instrument -> its kind's LiveTracker (a horizontal gyroscope's north)
        self.feeds = {}         # instrument whose record a tracker reads -> the instruments of those trackers
        self._due = {}          # (tracker's instrument, record's) -> samples at which it is next given the tail
        self.live = {}          # tracker's instrument -> its last live value ((azimuth rad, σ rad) for a heading)
        self._heading_t = {}    # tracker's instrument -> stamp (ns) of its last heading published
        self._imu_cols = {}     # tracker's instrument -> (value, its Imu encoded at stamp 0)
        self.nmea = None
        if self.load():
            self.prepare()

    def _buffered(self) -> set:
        """The instruments whose joint states the estimator keeps: the estimable ones and the records
        they read beside their own (``companions()``: a gyroscope's rotor-off swing)."""
        return set(estimator_instruments(self.insts))

    def prepare(self) -> None:
        self.frames_and_epoch()
        self.expected = sample_count(self.scene)
        self.last_stamp_ns = round((self.expected - 1) * (1e9 / self.scene.sample_rate_hz))
        buffered = self._buffered()
        for name, inst in self.insts.items():
            if name in buffered:
                # records_from_joints reads the measured channels and the last joint's velocity
                self.buffers[name] = JointBuffer(m.joint_state_layout(
                    joint_names(name, inst)), keep=len(inst.MEASURED_CHANNELS))
                sub = self.create_subscription(
                    m.JointState, joint_topic(name), lambda data, n=name: self._on_joint_raw(n, data),
                    RELIABLE_ALL, raw=True)
                self.subs[sub.topic_name] = sub
        # sim time from the clock: the stamp of an estimate that used no sample
        self.clock_sub = self.create_subscription(m.Clock, CLOCK, self._on_clock, FOLLOW_CLOCK, raw=True)
        for topic, type_name in estimator_topics(self.insts).items():
            self.pubs[topic] = self.create_publisher(m.message_class(type_name), topic, LATCHED)
        self._prepare_heading()
        period = float(self.get_parameter("publish_period_s").value)
        if period > 0:
            self.timers_.append(self.create_timer(period, self.finalize, clock=STEADY))

    def _warm(self, buffered) -> None:
        """Each measurement kind of the kept instruments loads what its estimate pays for on first use
        (``MeasurementKind.warm``: numba and the compiled kernels of the exact north fit) when the node
        is run alone, in a thread of its own: it overlaps discovery and the stream, the node spins at
        once (a cold numba cache compiles for many seconds: the simulators' ``wait_timeout_s`` must not
        pass meanwhile), and :meth:`estimate` waits for it. The estimate
        then follows the last sample without 1-2 s of imports (issue 37 item 6)."""
        import threading
        found = [kind(k) for k in sorted({k for n in buffered for k in declared_kinds(self.insts[n].observation())})]

        def warm():
            for k in found:
                if k is not None:
                    try:
                        k.warm()
                    except Exception as exc:      # the estimate pays for it then, and says what fails
                        self.get_logger().warning(f"{k.name}: warm-up failed ({exc.__class__.__name__}: {exc})")
        self._warming = threading.Thread(target=warm, name="estimator_warm", daemon=True)
        self._warming.start()

    def _prepare_heading(self) -> None:
        """A live tracker per instrument whose kind publishes live (``LIVE``), and the NMEA sender."""
        for name, inst in self.insts.items():
            if name not in self.buffers:
                continue
            obs = inst.observation()
            companions = {key: other for key, other in obs.companions().items() if other in self.buffers}
            for k in live_kinds(inst):
                tr = k.tracker(obs, self.scene, companions)
                if tr is not None:
                    self.trackers[name] = tr
                    break
        for owner, tr in self.trackers.items():
            for read in tr.reads:
                self.feeds.setdefault(read, []).append(owner)
                self._due[(owner, read)] = self._every(tr, read)
        self.heading_period_ns = round(1e9 * max(1.0 / HEADING_RATE_HZ, 1.0 / self.scene.sample_rate_hz)) - 1
        self.imu_layouts = {name: imu_layout(self.frame_prefix + heading_frame(name)) for name in self.trackers}
        self.publish_static_transforms(instrument_frames(self.insts, self.imu_layouts, self.frame_prefix))
        target = str(self.value("nmea_udp", "") or "")
        if target and self.trackers:
            try:
                self.nmea = NmeaUdpSender(target, field="nmea_udp")
                if self.nmea.note and self.standalone:     # in 'run' the command said it once
                    self.get_logger().info(f"nmea_udp: {self.nmea.note}")
            except SceneError as exc:
                self.get_logger().error(f"{exc}; no NMEA sentences are sent")

    def _every(self, tracker, name) -> int:
        """Samples between two looks at ``name``'s tail (at least 1)."""
        return max(int(tracker.every_s_of(name) * self.scene.sample_rate_hz), 1)

    def _track(self, name) -> None:
        """Give the trackers reading ``name`` its tail when due (stamps shifted back to sim time from
        release, ``stamp_epoch``); keep the live value of a tracker that has a new one; publish the
        heading of ``name``'s own tracker when :attr:`heading_period_ns` of sim time has passed."""
        buf = self.buffers[name]
        for owner in self.feeds[name]:
            tr = self.trackers[owner]
            if len(buf) >= self._due[(owner, name)]:
                self._due[(owner, name)] = len(buf) + self._every(tr, name)
                t_ns, pos, vel = buf.arrays()
                window_s = tr.window_s_of(name)          # inf: the whole record so far
                k = max(int(t_ns.size - window_s * self.scene.sample_rate_hz) - 1, 0) if math.isfinite(window_s) else 0
                off = self.stamp_offset_ns or 0
                rec = records_from_joints({name: self.insts[name]}, {name: (t_ns[k:] - off, pos[k:], vel[k:])})[name]
                value = tr.update(name, rec)
                if value is not None:
                    self.live[owner] = value
            if owner == name and self.live.get(owner) is not None:
                t = buf.last_stamp()
                if t - self._heading_t.get(owner, -10 ** 18) >= self.heading_period_ns:
                    self._heading_t[owner] = t
                    self._publish_heading(owner, t, *self.live[owner])

    def _publish_heading(self, name, t_ns, azimuth_rad, sigma_rad) -> None:
        """One ``sensor_msgs/Imu`` on ``<name>/heading`` (pre-serialized once per live value; only the
        stamp changes between two, :func:`~gyro_instrument.recording.cdr.restamped`) and a ``$HEHDT`` for the first gyroscope."""
        key = (name, azimuth_rad, sigma_rad)
        if self._imu_cols.get(name, (None,))[0] != key:
            f = imu_fields(azimuth_rad, sigma_rad, self.scene.site)
            cols = [np.array([v]) for v in (
                f.orientation_xyzw, f.orientation_covariance, f.angular_velocity_xyz_rad_s,
                f.angular_velocity_covariance, f.linear_acceleration_xyz_m_s2, f.linear_acceleration_covariance)]
            self._imu_cols[name] = (key, self.imu_layouts[name].encode([0], *cols)[0])
        data = restamped(self._imu_cols[name][1], t_ns)
        self._send(heading_topic(name), data)
        if self.nmea is not None and azimuth_rad is not None and name == next(iter(self.trackers)):
            try:
                self.nmea.send_heading(math.degrees(azimuth_rad), int(self.value("nmea_decimals", 3)))
            except OSError as exc:
                self.get_logger().warning(f"nmea_udp: {exc}", throttle_duration_sec=10.0)

    def _send(self, topic, msg) -> None:
        """Publish on one of the estimator's topics, counted (:attr:`sent`, by resolved name)."""
        pub = self.pubs[topic]
        pub.publish(msg)
        self.sent[pub.topic_name] = self.sent.get(pub.topic_name, 0) + 1

    def _final_headings(self, r, t) -> None:
        """The final estimate's live values per tracker: from the instrument's entry (the azimuth: its
        ``north`` block, the fit), or not provided (Imu.msg: covariance element 0 = −1) when it has none."""
        for name, tr in self.trackers.items():
            value = tr.final(r.get("instruments", {}).get(name)) or (None, None)
            self._publish_heading(name, t, *value)

    def teardown(self) -> None:
        for t in self.timers_:
            self.destroy_timer(t)
        for sub in list(self.subs.values()) + ([self.clock_sub] if self.clock_sub is not None else []):
            self.destroy_subscription(sub)
        for pub in self.pubs.values():
            self.destroy_publisher(pub)
        self.drop_static_transforms()
        self.buffers, self.subs, self.pubs, self.timers_, self.clock_sub = {}, {}, {}, [], None
        self.rejected, self.result, self.final, self.last_clock_ns, self._clock_done_at = {}, None, False, None, None
        self._last_input = None
        self.trackers, self.feeds, self._due = {}, {}, {}
        self.live, self._heading_t = {}, {}
        if self.nmea is not None:
            self.nmea.close()
            self.nmea = None

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
        self.failure = None
        self.trackers = {name: tr.restarted() for name, tr in self.trackers.items()}
        for (owner, read) in self._due:
            self._due[(owner, read)] = len(self.buffers[read]) + self._every(self.trackers[owner], read)
        self.live, self._heading_t = {}, {}

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
        if self.scene is not None:
            self._warm(self._buffered())
        self.create_timer(0.5, self._control, clock=STEADY)
        self.start_diagnostics()
        if self.scene is not None:
            self.get_logger().info(self.startup_line())

    def liveness(self) -> tuple:
        """The state on /diagnostics (beside the estimate's own status)."""
        values = {"samples": self.received(), "expected_per_instrument": self.expected, "runs": self.runs}
        if self.scene is None:
            return ERROR, "not running: the scene did not load or a start-up value was refused (see the log)", values
        if self.failure is not None:
            return ERROR, f"settled: {self.failure}", values
        if self.refusal is not None:
            return WARN, f"settled: estimate refused: {self.refusal}", values
        if self.final:
            return OK, "settled: estimate published", values
        if self._last_input is None:
            return OK, "waiting for input (joint states and clock)", values
        return OK, "collecting samples", values

    def sim_time_ns(self) -> int:
        return max(self.last_clock_ns or 0, 0)

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
                self.get_logger().info(f"every expected sample received ({self.received()}): estimating")
                self._final()

    def _on_clock(self, data):
        st = m.cdr_stamp_ns(data)
        t = st - m.EPOCH_NS - (self.stamp_offset_ns if self.stamp_offset_ns is not None else self._learn(st))
        self._last_input = time.monotonic()
        if self.standalone and self.last_clock_ns is not None and t < self.last_clock_ns and self.scene is not None:
            self.new_run(f"the clock went back from {self.last_clock_ns / 1e9:g} s to {t / 1e9:g} s")
        self.last_clock_ns = t
        if self.standalone and self._clock_done_at is None and self.expected and self.scene is not None \
                and self.last_clock_ns >= self.last_stamp_ns:
            self._clock_done_at = time.monotonic()
            self._check_complete()

    def _learn(self, stamp_ns) -> int:
        """``stamp_epoch`` = wall: the first stamp received (sim time 0) fixes the shift; the static
        transforms go out then."""
        off = self.learn_epoch(stamp_ns)
        self.publish_static_transforms(instrument_frames(self.insts, self.imu_layouts, self.frame_prefix))
        return off

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
        if self.stamp_offset_ns is None:
            self._learn(m.cdr_stamp_ns(data))
        if buf.layout.matches(data):
            buf.add_raw(data)
            if name in self.feeds:
                self._track(name)
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
        expected = tuple(n.split("/")[-1] for n in joint_names(name, self.insts[name]))
        names = tuple(n.split("/")[-1] for n in msg.name)
        if names != expected or len(msg.position) != len(expected) or len(msg.velocity) != len(expected):
            self._reject(name, f"joints {list(names)} do not match {list(expected)}")
            return
        self.buffers[name].add(m.stamp_to_release_ns(msg.header.stamp), list(msg.position), list(msg.velocity))
        if name in self.feeds:
            self._track(name)
        if self.standalone and len(self.buffers[name]) >= self.expected:
            self._check_complete()

    def estimate(self) -> dict | None:
        """Core call on everything received so far (None if nothing usable)."""
        if self.scene is None:
            return None
        if getattr(self, "_warming", None) is not None:
            self._warming.join()
        off = self.stamp_offset_ns or 0                  # stamps -> sim time from release (stamp_epoch)
        samples = {n: (lambda t, p, v: (t - off, p, v))(*b.arrays()) for n, b in self.buffers.items() if len(b) >= 3}
        recs = records_from_joints(self.insts, samples)
        return estimate_records(self.scene, estimated_instruments(self.insts, samples), recs)

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
            self._send(DIAGNOSTICS, m.diagnostics(
                self.stamp_ns(), "gyro_instrument/estimator", False, str(exc),
                {"refused_by_check": exc.field, "rejected_messages": self.rejected}))
            return None
        except Exception as exc:  # the estimator must never take the node down
            self.failure = f"estimation failed: {exc.__class__.__name__}: {exc}"
            self.get_logger().error(self.failure)
            return None
        if self.result is None:
            return None
        r = self.result
        t = self.stamp_ns()
        lat = None if r.get("latitude_deg") is None else math.radians(r["latitude_deg"])
        sig = None if r.get("latitude_sigma_deg") is None else math.radians(r["latitude_sigma_deg"])
        self._send("estimator/earth_rate_enu", m.earth_rate_vector(t, r.get("earth_rate_rad_s"), lat,
                                                                   self.frame_prefix + m.SITE_FRAME))
        text = r.get("method") or r.get("reason", "")
        self._send(DIAGNOSTICS, m.diagnostics(
            t, "gyro_instrument/estimator", r.get("method") is not None and short is None,
            text if short is None else f"{short}; {text}",
            {"latitude_deg": r.get("latitude_deg"), "latitude_sigma_deg": r.get("latitude_sigma_deg"),
             "earth_rate_rad_s": r.get("earth_rate_rad_s"), "carried_by": r.get("carried_by"),
             "rejected_messages": self.rejected, "wrong_topic_types": self.check_topic_types()}))
        self._send("estimator/latitude_rad", m.float64(lat))
        self._send("estimator/latitude_sigma_rad", m.float64(sig))
        self._send("estimator/earth_rate_rad_s", m.float64(r.get("earth_rate_rad_s")))
        self._send("estimator/earth_rate_sigma_rad_s", m.float64(r.get("earth_rate_sigma_rad_s")))
        self._final_headings(r, t)
        return r
