"""``recorder``: :class:`RecorderNode` writes raw CDR to MCAP in rosbag2's layout, RELIABLE /
KEEP_ALL, log time = sim time, in log-time order; it knows what the scene publishes and marks the
file ``complete`` or ``incomplete`` with per-topic counts. An existing ``output`` is refused unless
the parameter ``overwrite`` is true (never the scene file).
"""

import heapq
import json
import math
import os
import time

from rcl_interfaces.msg import SetParametersResult

from gyro_instrument import api
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import shown
from gyro_instrument.core.memory import sample_count
from gyro_instrument.recording.bag_layout import open_bag_writer, restart_path
from gyro_instrument.recording.frames import TF_MESSAGE_TYPE, TF_STATIC, instrument_frames, tf_message_cdr
from gyro_instrument.recording.mcap_io import DiskFull
from gyro_instrument.recording.qos import profile, profiles_yaml
from gyro_instrument.recording.topics import (DIAGNOSTICS, MARKER_TYPE, estimator_topics, scene_topics, sparse_topics,
                                              visual_every)
from gyro_instrument.ros import messages as m
from gyro_instrument.ros import params as P
from gyro_instrument.ros.nodes.base import (LATCHED, PUBLISH_ALL, RELIABLE_1000, RELIABLE_ALL, STEADY, SceneNode,
                                            qos_dict)
from gyro_instrument.ros.nodes.recorder_control import RecorderControl


class RecorderNode(RecorderControl, SceneNode):
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

    def __init__(self, name="recorder", reorder=True, output_path=None, **kwargs):
        #: the bag path itself when given by ``run`` (a file name of any bytes); the ``output`` parameter,
        #: a ROS string (UTF-8), then only shows it (:func:`~gyro_instrument.core.files.shown`)
        self.output_path = output_path
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
        self._tf_static_pending = False   # /tf_static not written yet (a wall stamp_epoch not known yet)
        self.runs = []               # [(path, state)] of recordings closed because the clock went back
        self._topic_last = {}        # topic -> last stamp seen (a stamp going back: the run restarted)
        self._topic_run = {}         # topic -> run index its messages belong to
        self.run_index = 0
        self._old = {}               # run index -> (writer, counts) of a run closed by a restart
        self._offered = {}           # topic -> offered_qos_profiles text recorded for it
        self._diagnostics = self.resolve_topic_name(DIAGNOSTICS)
        self.init_control()
        if self.load():
            self.prepare()

    def _check_params(self, params):
        changing = [p for p in params if p.name in self.RETRY_ON and not self.unchanged(p)]
        if self.writer is not None and changing:
            names = ", ".join(p.name for p in changing)
            reason = f"{names} cannot change while recording to {self.writer.path}: a recording has one scene and " \
                     "one file (stop the recorder and start it again)"
            self.get_logger().error(f"parameter refused: {reason}")
            return SetParametersResult(successful=False, reason=reason)
        return super()._check_params(params)

    def _after_set(self, params):
        super()._after_set(params)
        if self.writer is None and any(p.name in self.RETRY_ON and p.name in self._changing for p in params):
            # a value refused at start-up, corrected: start recording now
            if self.load():
                self.prepare()
            if self.writer is not None:
                self.get_logger().info(f"parameters corrected: recording to {self.writer.path}")

    def prepare(self) -> None:
        out = self.get_parameter("output").value
        if self.output_path is not None and out == shown(self.output_path):
            out = self.output_path
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
        self.frames_and_epoch()
        self._tf_static_pending = True
        self._write_tf_static()
        if self.reorder:
            self.create_timer(0.5, self._control, clock=STEADY)

    def _scene_record(self):
        return {"scene_yaml": json.dumps(dict(self.scene.raw)), "scene": self.scene.name, "seed": self.scene.seed,
                "command": self.value("command", "recorder node")}

    def _output_format(self, out):
        """Check the ``output`` path for the bag layout the parameters give (``format``,
        ``max_bag_size``, ``max_bag_duration``) and return that layout (``mcap`` or ``rosbag2``), or
        None after logging why the path is invalid (:func:`gyro_instrument.api.check_bag`: a bad
        layout, a missing or unwritable directory, a directory given for a file, the scene file
        itself, or an existing output without ``overwrite``)."""
        try:
            return api.check_bag(self.value("scene", ""), out, self.value("format", "") or None,
                                 self.value("overwrite", False), self.value("max_bag_size", 0),
                                 self.value("max_bag_duration", 0.0), field="output", format_field="format")
        except SceneError as exc:
            self.get_logger().error(str(exc).replace("--overwrite", "overwrite:=true"))
            return None

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
        sparse = sparse_topics(self.insts)
        estimates = estimator_topics(self.insts)
        self.stamped = set()
        self.marker_topics = set()
        self.sample_topics = set()
        self.rank = {}
        self._topic_types = {}
        self._known_qos = {}
        classes = {topic: m.message_class(types[topic]) for topic in wanted}   # imports first, then the
        for topic in wanted:                                                   # subscriptions close together
            name = self.resolve_topic_name(topic)         # namespace and remapping applied
            self._topic_types[name] = types[topic]
            # what this package's publisher of the topic offers (history and depth are not discovered)
            self._known_qos[name] = qos_dict(LATCHED if topic in estimates else
                                             PUBLISH_ALL if self.reorder else RELIABLE_1000)
            self.counts[name] = 0
            self.rank[name] = list(types).index(topic)      # ties in stamp: clock first, then scene order
            if types[topic] == MARKER_TYPE:
                self.marker_topics.add(name)
            elif types[topic] != "std_msgs/msg/Float64":
                self.stamped.add(name)
            if topic not in estimates:
                self.sample_topics.add(name)
            # what the scene publishes: every sample on clock and the instruments' topics, and at
            # least one estimate on each estimator topic
            self.expected[name] = (n_markers if topic in sparse else n) if name in self.sample_topics else 1
            self.subs[name] = self.create_subscription(classes[topic], topic,
                                                       lambda data, tp=name: self._on_raw(tp, data),
                                                       RELIABLE_ALL, raw=True)

    def _write_tf_static(self, first_stamp_ns=None) -> None:
        """``/tf_static``: one ``tf2_msgs/msg/TFMessage`` (the project's CDR codec, the type is not
        installed) with the static transform of every frame the scene's messages name, stamped and
        logged at sim time 0 (issue 37); with ``stamp_epoch`` = wall once the first stamp is known."""
        if not getattr(self, "_tf_static_pending", False):
            return
        if self.stamp_offset_ns is None:
            if first_stamp_ns is None:
                return
            self.learn_epoch(first_stamp_ns)
        self._tf_static_pending = False
        tfs = instrument_frames(self.insts, None, self.frame_prefix)
        if tfs:
            topic = self.resolve_topic_name(TF_STATIC)       # /tf_static; /<ns>/tf_static in a namespace
            t0 = m.EPOCH_NS + self.stamp_offset_ns
            self._topic_types[topic] = TF_MESSAGE_TYPE
            # offered as a latched tf_static (no publisher in the graph: the recorder writes it)
            self._offered[topic] = profiles_yaml([profile("keep_last", 1, "reliable", "transient_local")])
            self.counts[topic], self.expected[topic] = 1, 1       # in the status counts as the file holds it
            self._write(topic, t0, tf_message_cdr(tfs, t0))

    def start(self) -> None:
        self.standalone = True
        self.start_diagnostics()
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
        if topic == self._diagnostics and self.is_liveness(data):
            return
        st = m.cdr_stamp_ns(data) if topic in self.stamped else \
            m.marker_array_stamp_ns(data) if topic in self.marker_topics else None
        if self._tf_static_pending and st is not None:
            self._write_tf_static(st)
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
        if self.paused:
            self.not_recorded += 1
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

    def _offered_qos(self, topic) -> str:
        """``offered_qos_profiles`` of ``topic`` as rosbag2 records them: one profile per publisher the
        graph shows (reliability and durability as discovered; history and depth, which DDS does not
        discover, from what this package's publisher of the topic offers), or that publisher's
        profile when the graph shows none."""
        known = self._known_qos[topic]
        profiles = []
        for info in self.get_publishers_info_by_topic(topic):
            q = qos_dict(info.qos_profile)
            if q["history"] == "unknown":
                q["history"], q["depth"] = known["history"], known["depth"]
            profiles.append(q)
        return profiles_yaml(profiles or [known])

    def _ensure_topic(self, topic) -> None:
        """Register ``topic`` in the current file before its first message, with the publishers'
        offered QoS (the first file's, seen then, in the files that follow)."""
        if topic not in self.writer.counts:
            if topic not in self._offered:
                self._offered[topic] = self._offered_qos(topic)
            self.writer.add_topic(topic, self._topic_types[topic], self._offered[topic])

    def _write(self, topic, st, data):
        if self.writer.closed:           # stopped by a full disk
            return
        self._ensure_topic(topic)
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
        for name in self._offered:          # the QoS seen in the first run's file
            self._ensure_topic(name)
        self._tf_static_pending = True      # the new file starts with the static frames too
        self._write_tf_static()

    def _write_old(self, run, topic, st, data):
        writer, counts, _ = self._old[run]
        counts[topic] = counts.get(topic, 0) + 1
        if not writer.closed:
            try:
                if topic not in writer.counts:
                    writer.add_topic(topic, self._topic_types[topic], self._offered.get(topic)
                                     or self._offered_qos(topic))
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
            try:
                for topic in self.counts:    # a topic with no message is listed too
                    self._ensure_topic(topic)
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
            if self.not_recorded:
                fields["not_recorded_paused"] = self.not_recorded
            if self.run_index:
                fields["restart"] = json.dumps({"run": self.run_index, "continues": os.path.basename(
                    self._old[self.run_index - 1][0].path.rstrip("/"))})
            try:
                self.writer.close(state=state, **fields)
            except OSError as exc:
                self._disk_full(exc)
