"""The whole suite in one process (there is no ``ros2 launch`` on PyPI): simulators, estimator
and recorder as nodes of one context over DDS, stepped in lock-step so nothing is dropped.

The first simulator owns ``clock`` (``/clock``; ``<namespace>/clock`` with a namespace) and the
simulators step in the suite's loop, a batch of samples at a time, integrating a new block of
``window_s`` simulated seconds when a batch needs it (the recorder commits first): each simulator
publishes the batch (pre-serialized CDR; the RELIABLE / KEEP_ALL subscriptions queue it), then
:class:`LockStep` takes every message of the batch from the estimator's and the recorder's
subscriptions, waiting on a wait set for any not yet delivered, and runs their callbacks sample
by sample (sample i of every topic before sample i + 1), so the recorder writes the same ordered
stream as one sample at a time. Then the nodes' other subscriptions (the estimator's ``clock``)
are drained: its sim time reaches a sample's time only once that sample's data is delivered.
With ``real_time_factor`` > 0 the batches are at most 20 ms of wall time and paced to the wall
clock; 0 runs as fast as possible. The separate-node route (one process per node, as a launch
file starts them) is :mod:`gyro_instrument.ros.launch`.
"""

import json
import math
import resource
import signal
import threading
import time
from contextlib import ExitStack

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.parameter import Parameter
from rclpy.subscription import Subscription

from gyro_instrument.ros.nodes import RELIABLE_1000, EstimatorNode, RecorderNode, SimulatorNode
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import DEFAULT_WINDOW_S
from gyro_instrument.instruments import REGISTRY, simulator_kinds


#: samples per batch at full speed; at most the publishers' KEEP_LAST depth (1000), so a writer
#: never overwrites a sample before the subscriptions (KEEP_ALL) have it
BATCH = 100
MAX_BATCH = 1000


class DeliveryError(RuntimeError):
    """A message was not delivered in time (the suite never drops silently)."""


def _call(sub, taken):
    if sub._callback_type is Subscription.CallbackType.MessageOnly:
        sub.callback(taken[0])
    else:
        sub.callback(*taken)


class LockStep:
    """Delivery of published batches to subscriptions, without the executor's per-callback cost.

    Parameters
    ----------
    context : rclpy.Context
    counted : list of (topic, Subscription)
        Subscriptions that receive exactly one message per published sample of their topic.
    others : list of Subscription
        Subscriptions drained after each batch (whatever arrived), e.g. the nodes' ``/clock``.
    """

    def __init__(self, context, counted, others=()):
        self.context = context
        self.counted = list(counted)
        self.others = list(others)

    def deliver(self, published, timeout_s, describe=lambda: "") -> None:
        """Take ``published[topic]`` messages from every counted subscription of that topic, run
        the callbacks sample-major (message i of each subscription in order, then i + 1), then
        drain the other subscriptions. ``published[topic]`` is a count (one message per sample
        of the batch) or a list of the sample offsets in the batch its messages belong to (the
        markers, every few samples). Raises :class:`DeliveryError` after ``timeout_s`` without
        a complete batch."""
        offsets = [published.get(topic, 0) for topic, _ in self.counted]
        want = [len(o) if isinstance(o, list) else o for o in offsets]
        got = self._collect(want, timeout_s, describe)
        self._run_sample_major(self._calls(got), offsets)
        self.drain()

    def _collect(self, want, timeout_s, describe):
        """Take ``want[j]`` messages from counted subscription j, waiting on a wait set for any not
        yet delivered.

        Returns the list (one per counted subscription) of the taken tuples, in arrival order.
        Raises :class:`DeliveryError` (naming ``describe()`` and the short topics) when a
        subscription still lacks messages ``timeout_s`` after the first incomplete pass.
        """
        got = [[] for _ in self.counted]
        deadline = None
        while True:
            missing = []
            for (_, sub), q, n in zip(self.counted, got, want):
                if len(q) < n:
                    with sub.handle:
                        take, msg_type, raw = sub.handle.take_message, sub.msg_type, sub.raw
                        while len(q) < n:
                            taken = take(msg_type, raw)
                            if taken is None:
                                break
                            q.append(taken)
                    if len(q) < n:
                        missing.append(sub)
            if not missing:
                return got
            now = time.monotonic()
            if deadline is None:
                deadline = now + timeout_s
            elif now > deadline:
                short = ", ".join(f"{topic} {len(q)}/{n}" for (topic, _), q, n in zip(self.counted, got, want)
                                  if len(q) < n)
                raise DeliveryError(f"{describe()}: not delivered in {timeout_s} s: {short}")
            self._wait(missing, 0.01)

    def _calls(self, got):
        """Turn the taken messages into ``(callback, arguments)`` pairs, one list per counted
        subscription: MessageOnly callbacks get the message alone, the others the whole taken
        tuple (message and message info)."""
        calls = []
        for (_, sub), q in zip(self.counted, got):
            if sub._callback_type is Subscription.CallbackType.MessageOnly:
                calls.append([(sub.callback, (taken[0],)) for taken in q])
            else:
                calls.append([(sub.callback, taken) for taken in q])
        return calls

    @staticmethod
    def _run_sample_major(calls, offsets):
        """Run the calls sample-major: call i of every per-sample (dense) subscription in order,
        then the sparse subscriptions' (markers') calls at sample offset i, then i + 1. Dense
        subscriptions with different numbers of calls run row by row up to the longest."""
        dense = [c for c, o in zip(calls, offsets) if not isinstance(o, list)]
        sparse_at = {}                               # sample offset -> calls of sparse topics (markers)
        for c, o in zip(calls, offsets):
            if isinstance(o, list):
                for off, call in zip(o, c):
                    sparse_at.setdefault(off, []).append(call)
        if len({len(c) for c in dense}) <= 1:        # every per-sample topic published the same samples
            if not sparse_at:
                for row in zip(*dense):
                    for cb, args in row:
                        cb(*args)
            else:
                for i, row in enumerate(zip(*dense)):
                    for cb, args in row:
                        cb(*args)
                    for cb, args in sparse_at.get(i, ()):
                        cb(*args)
        else:
            for i in range(max(len(c) for c in dense)):
                for c in dense:
                    if i < len(c):
                        cb, args = c[i]
                        cb(*args)
                for cb, args in sparse_at.get(i, ()):
                    cb(*args)

    def drain(self) -> None:
        """Run the callbacks of whatever the other subscriptions hold."""
        for sub in self.others:
            with sub.handle:
                while True:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                    if taken is None:
                        break
                    _call(sub, taken)

    def _wait(self, subs, timeout_s):
        with ExitStack() as stack:
            stack.enter_context(self.context.handle)
            for sub in subs:
                stack.enter_context(sub.handle)
            ws = _rclpy.WaitSet(len(subs), 0, 0, 0, 0, 0, self.context.handle)
            ws.clear_entities()
            for sub in subs:
                ws.add_subscription(sub.handle)
            ws.wait(int(timeout_s * 1e9))


#: a block integrated faster than this (s of wall time) is quick: the suite commits the bag before
#: the next integration only when its last commit is this old (see run_suite)
QUICK_S = 0.25
#: accepted ``window_s`` (simulated seconds per integrated block), as the simulators' parameter
MIN_WINDOW_S, MAX_WINDOW_S = 1.0e-3, 1.0e6


class BagWriteError(SceneError):
    """The bag could not be written (a full disk): :meth:`DiskFull.line` as the one line."""

    def __init__(self, line) -> None:
        ValueError.__init__(self, line)
        self.field, self.value, self.valid = "--bag", None, line


def check_window(window_s, field="--window-s") -> None:
    """Refuse a window that cannot work: not a number, not finite, or outside [:data:`MIN_WINDOW_S`,
    :data:`MAX_WINDOW_S`] (below a millisecond every block is one sample and the run crawls).

    Raises
    ------
    SceneError
        Naming ``field``, the value and the valid range.
    """
    ok = isinstance(window_s, (int, float)) and not isinstance(window_s, bool) and math.isfinite(window_s)
    if not (ok and MIN_WINDOW_S <= window_s <= MAX_WINDOW_S):
        raise SceneError(field, window_s, f"must be a number of simulated seconds in [{MIN_WINDOW_S:g}, "
                                          f"{MAX_WINDOW_S:g}]")


#: bytes per sample of the final estimate's work arrays, per instrument, with a margin of 1.5: 437
#: measured (peak RSS of estimate_records on 172 800 samples of one horizontal gyrocompass, +72 MB)
FIT_BYTES_PER_SAMPLE = 660


def check_run_memory(scene) -> None:
    """Refuse a run that cannot fit in memory, before any node starts. Instruments that stream hold
    one block; one that does not (``STREAMS`` False) holds the run (``core.memory.check_memory``'s
    estimate). The estimator keeps 8 (2 + k) bytes per sample of each instrument (k its measured
    channels) in arrays that double (2x), and its final fits take :data:`FIT_BYTES_PER_SAMPLE` more."""
    from gyro_instrument.core.memory import available_bytes, check_memory, sample_count
    types = [spec[0] for spec in scene.instruments.values()]
    if not all(REGISTRY[t].STREAMS for t in types):
        check_memory(scene)
        return
    n = sample_count(scene)
    need = n * sum(2 * 8 * (2 + len(REGISTRY[t].MEASURED_CHANNELS)) + FIT_BYTES_PER_SAMPLE for t in types)
    available = available_bytes()
    if available is not None and need > available:
        raise SceneError("duration_s", scene.duration_s,
                         f"the estimator would keep ~{need / 1e9:.3g} GB for {n} samples at {scene.sample_rate_hz:g} "
                         f"Hz; {available / 1e9:.3g} GB available: lower duration_s or sample_rate_hz")


def _params(scene, overrides, duration_s, **extra):
    ps = [Parameter("scene", value=scene), Parameter("duration_s", value=float(duration_s or 0.0))]
    if overrides:
        ps.append(Parameter("overrides", value=list(overrides)))
    ps += [Parameter(k, value=v) for k, v in extra.items()]
    return ps


def run_suite(scene, overrides=(), duration_s=None, bag=None, real_time_factor=0.0, command="",
              timeout_s=10.0, progress=None, batch=None, overwrite=False, bag_format=None, max_bag_size=0,
              max_bag_duration_s=0.0, namespace="", ros_args=(), window_s=DEFAULT_WINDOW_S) -> tuple:
    """Run the scene's nodes; return (estimate dict, stats dict).

    The simulators integrate one window of ``window_s`` simulated seconds at a time
    (:func:`~gyro_instrument.recording.joints.joint_blocks` over ``Instrument.stream``) and publish
    it before integrating the next, so the first message leaves after one window's integration
    whatever the duration; before an integration (and before a paced sleep) the recorder commits
    what it wrote (:meth:`RecorderNode.commit`; after a quick block, < :data:`QUICK_S`, only once its
    last commit is that old), so a SIGKILL loses at most the last second of wall time. Memory: one
    block per simulator (plus what an instrument that does not stream yet holds,
    ``Instrument.STREAMS`` False), the estimator's kept samples (:class:`JointBuffer`, 8 (2 + k) bytes
    per sample) and the bag writer's chunk index (one entry per chunk); then the estimate's work
    arrays over every kept sample (the fits; ~440 bytes per sample for one gyroscope). The stats
    give the process's peak RSS before the estimate (``peak_rss_streaming_mb``) and at the end
    (``peak_rss_mb``), in MB.

    ``namespace``: every node (and so every topic, ``clock`` included) in this namespace, so that
    suites in different namespaces run side by side. ``ros_args``: the arguments after
    ``--ros-args`` (remapping, log levels, ``-p`` for parameters the suite does not set itself),
    applied to every node.

    ``batch``: samples published per lock-step (default :data:`BATCH` at full speed, at most 20 ms
    of wall time when paced; capped at :data:`MAX_BATCH`). ``bag``: record to this path; an
    existing file there is replaced only with ``overwrite`` (never when it is the scene file).
    ``bag_format``: ``mcap`` (one file) or ``rosbag2`` (a bag directory, split at ``max_bag_size``
    bytes or ``max_bag_duration_s`` of log time; see :mod:`gyro_instrument.recording.bag_layout`);
    default from the path (a trailing slash or splitting: rosbag2).

    Raises
    ------
    SceneError
        Bad scene values, a ``bag`` path that exists without ``overwrite`` or is the scene file, a
        ``window_s`` that is not a positive finite number, or a run too large for the memory available
        (checked before any node starts).
    DeliveryError
        A sample was not delivered within ``timeout_s``.
    """
    from gyro_instrument.scenes import load_scene
    t_start = time.perf_counter()
    overrides = list(overrides)
    overrides_all = overrides + ([f"duration_s={float(duration_s)!r}"] if duration_s else [])
    scene_obj = load_scene(scene, overrides_all)          # refuse bad input before any node starts
    if bag:
        bag_format = _check_bag(scene, bag, bag_format, overwrite, max_bag_size, max_bag_duration_s)
    check_window(window_s)
    check_run_memory(scene_obj)                           # and a run that cannot fit in memory
    context = rclpy.Context()
    stop, handlers = _install_stop_handlers()
    args = ["gyro-instrument"] + (["--ros-args", *ros_args] if ros_args else [])
    rclpy.init(context=context, args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    ns = {"namespace": namespace} if namespace else {}
    nodes = []
    try:
        sims = _make_simulators(scene, scene_obj, overrides, duration_s, context, ns, window_s)
        est = EstimatorNode(context=context, **ns, parameter_overrides=_params(scene, overrides, duration_s))
        rec = RecorderNode(context=context, reorder=False, **ns, parameter_overrides=_params(
            scene, overrides, duration_s, output=bag, overwrite=bool(overwrite), command=command,
            format=bag_format or "", max_bag_size=int(max_bag_size or 0),
            max_bag_duration=float(max_bag_duration_s or 0.0))) if bag else None
        nodes = sims + [est] + ([rec] if rec else [])
        ex = SingleThreadedExecutor(context=context)
        for n in nodes:
            ex.add_node(n)
        sim_pubs, lockstep, need = _wire(context, sims, est, rec)
        _wait_for_discovery(ex, sim_pubs, need, timeout_s, stop)
        n_samples = max((s.samples for s in sims), default=0)
        dt = 1.0 / scene_obj.sample_rate_hz
        if batch is None:
            batch = BATCH if real_time_factor <= 0 else int(0.02 * real_time_factor / dt)
        batch = max(1, min(int(batch), MAX_BATCH))
        published, first_message_s, wall = _stream(
            sims, rec, ex, lockstep, sim_pubs, n_samples, dt, batch, real_time_factor, timeout_s, progress,
            stop, t_start)
        if rec is not None and rec.failed is not None:
            # the disk filled: the bag is left readable up to its last commit; one line, exit 2
            rec.close(state="disk full")
            raise BagWriteError(rec.failed.line("--bag"))
        # the process's peak so far: the streaming part of the run, before the estimate's work arrays
        peak_streaming_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        result = _finalize(est, rec, ex, timeout_s)
        stats = _stats(sims, est, rec, n_samples, dt, wall, published, batch, first_message_s, window_s,
                       peak_streaming_mb)
        return result, stats
    finally:
        for n in nodes:
            if isinstance(n, RecorderNode):
                n.close(state="interrupted")   # only still open if the run did not finish
            n.destroy_node()
        rclpy.shutdown(context=context)
        for sig, h in handlers.items():
            signal.signal(sig, h)


def _check_bag(scene, bag, bag_format, overwrite, max_bag_size, max_bag_duration_s):
    """Resolve the bag layout (``mcap`` or ``rosbag2``) of the output path ``bag`` and refuse an
    output that exists without ``overwrite`` or is one of the scene's input files; return the
    layout. Raises :class:`SceneError` as
    :func:`~gyro_instrument.recording.bag_layout.check_bag_output` does."""
    from gyro_instrument.cli import scene_inputs
    from gyro_instrument.recording.bag_layout import bag_format as layout_of, check_bag_output
    bag_format = layout_of(bag, bag_format, max_bag_size, max_bag_duration_s)
    check_bag_output(bag, bag_format, "bag", scene_inputs(scene), overwrite, max_bag_size, max_bag_duration_s)
    return bag_format


def _install_stop_handlers():
    """Route SIGINT and SIGTERM to a flag read between samples, so the interrupt never lands
    inside a write (the recorder then finishes the file with status 'interrupted'). Only in the
    main thread (signals cannot be set elsewhere). Returns ``(stop, handlers)``: the list a
    signal appends its number to, and the previous handlers to restore, by signal."""
    stop = []
    handlers = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            handlers[sig] = signal.signal(sig, lambda signum, frame: stop.append(signum))
    return stop, handlers


def _make_simulators(scene, scene_obj, overrides, duration_s, context, ns, window_s):
    """Create one :class:`SimulatorNode` per simulator kind the scene's instruments need (in
    :func:`~gyro_instrument.instruments.simulator_kinds` order), publishing on RELIABLE depth-1000
    topics and stepped by the suite (``real_time_factor`` 0); the first one publishes the clock.
    Returns the list of nodes."""
    sims = []
    owner = True
    types = {spec[0] for spec in scene_obj.instruments.values()}
    for name, kinds in simulator_kinds().items():
        if types & set(kinds):
            sims.append(SimulatorNode(name, kinds, context=context, pub_qos=RELIABLE_1000, **ns,
                                      parameter_overrides=_params(
                scene, overrides, duration_s, real_time_factor=0.0, publish_clock=owner,
                window_s=float(window_s))))
            owner = False
    return sims


def _wire(context, sims, est, rec):
    """Pair the simulators' publishers with the estimator's and recorder's subscriptions: the
    subscriptions that get one message per sample of a simulator topic are counted by the
    :class:`LockStep`, the others (e.g. ``clock``) drained after each batch. Returns
    ``(sim_pubs, lockstep, need)``: publisher by topic, the lock-step, and the number of counted
    subscriptions per topic (the matches discovery waits for)."""
    sim_pubs = {}
    for s in sims:
        sim_pubs.update(zip(s.topics(), s.publishers()))
    counted = [(topic, sub) for n in (est, rec) if n is not None for topic, sub in n.subs.items()
               if topic in sim_pubs]
    counted_ids = {id(sub) for _, sub in counted}
    others = [sub for n in (est, rec) if n is not None for sub in n.subscriptions if id(sub) not in counted_ids]
    lockstep = LockStep(context, counted, others)
    need = {}
    for topic, _ in counted:
        need[topic] = need.get(topic, 0) + 1
    return sim_pubs, lockstep, need


def _wait_for_discovery(ex, sim_pubs, need, timeout_s, stop):
    """Spin ``ex`` until every simulator publisher is matched by its ``need[topic]`` subscribers.
    Raises :class:`KeyboardInterrupt` when a stop signal arrived, :class:`DeliveryError` after
    ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    def matched():
        return all(sim_pubs[topic].get_subscription_count() >= k for topic, k in need.items())
    while not matched():
        if stop:
            raise KeyboardInterrupt
        ex.spin_once(timeout_sec=0.01)
        if time.monotonic() > deadline:
            raise DeliveryError("subscribers did not match the simulators' publishers in time")


def _stream(sims, rec, ex, lockstep, sim_pubs, n_samples, dt, batch, real_time_factor, timeout_s, progress,
            stop, t_start):
    """The suite's loop: publish ``batch`` samples of every simulator and deliver them in
    lock-step until ``n_samples``, committing the bag before an integration, spinning the executor
    for its other work every 0.1 s, pacing to ``real_time_factor`` (> 0) and reporting progress
    every twentieth of the run. Returns ``(published, first_message_s, wall)``: messages per topic,
    seconds from ``t_start`` to the first message, and the loop's wall time. Raises
    :class:`KeyboardInterrupt` when a stop signal arrived."""
    published = {topic: 0 for topic in sim_pubs}
    every = max(n_samples // 20, 1)
    w0 = time.perf_counter()
    t_spin = w0
    first_message_s = None
    last_block_s = None
    i = 0
    while i < n_samples:
        if stop:
            raise KeyboardInterrupt
        if rec is not None and rec.failed is not None:
            break
        integrating = not all(s.block_ready(batch) for s in sims)
        if rec is not None and integrating:
            # on disk before the next integration: always after a slow one (it may be as slow);
            # after quick ones only once the last commit is QUICK_S old (a commit costs more as
            # the file grows), so what a SIGKILL loses stays under QUICK_S + one quick block
            rec.commit(0.0 if last_block_s is None or last_block_s >= QUICK_S else QUICK_S)
        step = {}
        t_batch = time.perf_counter()
        for s in sims:
            k = s.publish_steps(batch)
            if first_message_s is None and k:
                first_message_s = time.perf_counter() - t_start
            for topic in s.topics():
                # per-sample topics: k messages; markers: at these offsets in the batch
                step[topic] = s.offsets.get(topic, k)
                published[topic] += len(step[topic]) if isinstance(step[topic], list) else k
        if integrating:
            last_block_s = time.perf_counter() - t_batch
        lockstep.deliver(step, timeout_s, lambda: f"samples {i}..{i + batch - 1}")
        i_next = i + batch
        now = time.perf_counter()
        if now - t_spin > 0.1:    # parameter services, timers: the executor's other work
            ex.spin_once(timeout_sec=0)
            t_spin = now
        if real_time_factor > 0:
            lag = min(i_next, n_samples) * dt / real_time_factor - (time.perf_counter() - w0)
            if lag > 0:
                if rec is not None and lag > 0.1:
                    rec.commit()
                time.sleep(lag)
        if progress and (i_next - 1) // every > (i - 1) // every:
            progress(f"sample {min(i_next, n_samples)}/{n_samples}")
        i = i_next
    return published, first_message_s, time.perf_counter() - w0


def _finalize(est, rec, ex, timeout_s):
    """Compute the estimate (:meth:`EstimatorNode.finalize`); with a recorder, wait (up to
    ``timeout_s``) for the estimator's result messages to reach it, then close the bag with the
    estimate in its metadata. Returns the estimate (None when there is none)."""
    base = rec.received() if rec else 0
    result = est.finalize()
    if rec:
        # the estimate's messages, or the refusal's one /diagnostics status
        want = base + (len([t for t in rec.counts if t not in rec.sample_topics]) if result is not None
                       else int(est.refusal is not None))
        t_wait = time.monotonic() + timeout_s
        while rec.received() < want and time.monotonic() < t_wait:
            ex.spin_once(timeout_sec=0.001)
        meta = {"estimate_json": json.dumps(result, default=str) if result else ""}
        if est.refusal is not None:
            meta["refused"] = str(est.refusal)
        rec.close(meta, name="gyro_instrument_estimate")
    if est.refusal is not None:     # the data failed an adequacy check: exit 2 with its one line
        raise est.refusal
    return result


def _stats(sims, est, rec, n_samples, dt, wall, published, batch, first_message_s, window_s, peak_streaming_mb):
    """The run's statistics dict (samples, wall time, achieved real-time factor, messages received,
    recorded and published, batch, first-message latency, blocks integrated per simulator, the
    estimator's kept bytes, and the peak RSS during streaming and now, in MB)."""
    return {"samples": n_samples, "wall_s": wall,
            "real_time_factor_achieved": (n_samples * dt / wall) if wall > 0 else None,
            "estimator_messages": est.received(), "recorded": dict(rec.counts) if rec else {},
            "published": {name: s.samples for s in sims for name in s.chosen},
            "published_topics": published, "batch": batch, "first_message_s": first_message_s,
            "blocks": {s.get_name(): s.blocks_pulled for s in sims}, "window_s": float(window_s),
            "estimator_bytes": sum(b.nbytes() for b in est.buffers.values()),
            "peak_rss_streaming_mb": peak_streaming_mb,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
