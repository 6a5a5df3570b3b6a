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
import resource
import signal
import threading
import time
from dataclasses import dataclass

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

from gyro_instrument import api
from gyro_instrument.api import check_run_memory, check_window  # noqa: F401  (re-exported)
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import shown
from gyro_instrument.core.scene import DEFAULT_WINDOW_S, EPOCH_NS
from gyro_instrument.instruments import simulator_kinds
from gyro_instrument.recording.nmea import resolve_udp_target
from gyro_instrument.ros.lockstep import DeliveryError, LockStep  # noqa: F401  (re-exported)
from gyro_instrument.ros.dds_profile import use_package_profile
from gyro_instrument.ros.log_dir import ensure_log_dir
from gyro_instrument.ros.nodes import RELIABLE_1000, EstimatorNode, RecorderNode
from gyro_instrument.ros.nodes.compass import COMPASS_NODE, simulator_node


#: samples per batch at full speed; at most the publishers' KEEP_LAST depth (1000), so a writer
#: never overwrites a sample before the subscriptions (KEEP_ALL) have it
BATCH = 100
MAX_BATCH = 1000


#: a block integrated faster than this (s of wall time) is quick: the suite commits the bag before
#: the next integration only when its last commit is this old (see run_suite)
QUICK_S = 0.25
class BagWriteError(SceneError):
    """The bag could not be written (a full disk): :meth:`DiskFull.line` as the one line."""

    def __init__(self, line) -> None:
        ValueError.__init__(self, line)
        self.field, self.value, self.valid = "--bag", None, line


class NodeFailure(RuntimeError):
    """A node of the run failed (not the input): ``node`` and the reason, ``run``'s last line."""

    def __init__(self, node, reason) -> None:
        super().__init__(f"{node}: {reason}")
        self.node, self.reason = node, reason


def _params(scene, overrides, duration_s, **extra):
    ps = [Parameter("scene", value=scene), Parameter("duration_s", value=float(duration_s or 0.0))]
    if overrides:
        ps.append(Parameter("overrides", value=list(overrides)))
    ps += [Parameter(k, value=v) for k, v in extra.items()]
    return ps


@dataclass(frozen=True)
class RunOptions:
    """How :func:`run_suite` runs a scene (what it runs is its scene, overrides, duration and bag).

    ``gyro-instrument run`` builds one from its options (:func:`gyro_instrument.ros.cli`); a
    caller changes the defaults it needs: ``RunOptions(real_time_factor=1.0, window_s=100.0)``.

    Attributes
    ----------
    real_time_factor : float
        Simulated seconds per wall second; 0 runs as fast as possible.
    command : str
        The command line recorded in the bag's metadata.
    timeout_s : float
        Wall seconds a sample may take to be delivered (:class:`DeliveryError` after).
    progress : callable or None
        Called with one line of progress text now and then.
    batch : int or None
        Samples published per lock-step (default :data:`BATCH` at full speed, at most 20 ms of
        wall time when paced; capped at :data:`MAX_BATCH`).
    overwrite : bool
        Replace an existing file at the bag's path (never the scene file).
    bag_format : str or None
        ``mcap`` (one file) or ``rosbag2`` (a bag directory, split at ``max_bag_size`` bytes or
        ``max_bag_duration_s`` of log time; :mod:`gyro_instrument.recording.bag_layout`); default
        from the path (a trailing slash or splitting: rosbag2).
    max_bag_size : int
        Split size of a rosbag2 directory, bytes (0: no split by size).
    max_bag_duration_s : float
        Split duration of a rosbag2 directory, s of log time (0: no split by time).
    namespace : str
        Every node (and so every topic, ``clock`` included) in this namespace, so that suites in
        different namespaces run side by side.
    ros_args : sequence of str
        The arguments after ``--ros-args`` (remapping, log levels, ``-p`` for parameters the suite
        does not set itself), applied to every node.
    window_s : float
        Simulated seconds integrated per block (a positive finite number).
    nmea_udp : str
        HOST:PORT the estimator sends ``$HEHDT`` sentences to (its parameter ``nmea_udp``; checked
        and resolved before any node starts); '' sends none.
    """

    real_time_factor: float = 0.0
    command: str = ""
    timeout_s: float = 10.0
    progress: object = None
    batch: int | None = None
    overwrite: bool = False
    bag_format: str | None = None
    max_bag_size: int = 0
    max_bag_duration_s: float = 0.0
    namespace: str = ""
    ros_args: tuple = ()
    window_s: float = DEFAULT_WINDOW_S
    nmea_udp: str = ""


def run_suite(scene, overrides=(), duration_s=None, bag=None, options=RunOptions()) -> tuple:
    """Run the scene's nodes; return (estimate dict, stats dict).

    ``scene`` (a shipped name or a path), its ``overrides`` (``--set`` texts) and ``duration_s``
    (None: the scene's) say what runs; ``bag`` (None: no recording) where it is recorded;
    ``options`` (:class:`RunOptions`) how.

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

    Raises
    ------
    SceneError
        Bad scene values, a ``bag`` path that exists without ``overwrite`` or is the scene file, a
        ``window_s`` that is not a positive finite number, or a run too large for the memory available
        (checked before any node starts).
    DeliveryError
        A sample was not delivered within ``timeout_s``.
    """
    t_start = time.perf_counter()
    opts, overrides, bag_format, batch = options, list(overrides), options.bag_format, options.batch
    scene_obj = api.load_scene(scene, overrides, duration_s or None)    # refuse bad input before any node starts
    if bag:
        bag_format = api.check_bag(scene, bag, bag_format, opts.overwrite, opts.max_bag_size, opts.max_bag_duration_s,
                                   field="bag")
    check_window(opts.window_s)
    if opts.nmea_udp:
        resolve_udp_target(opts.nmea_udp)                 # exit 2 naming --nmea-udp before any node starts
    check_run_memory(scene_obj)                           # and a run that cannot fit in memory
    context = rclpy.Context()
    stop, handlers = _install_stop_handlers()
    args = ["gyro-instrument"] + (["--ros-args", *opts.ros_args] if opts.ros_args else []) + ensure_log_dir()
    use_package_profile()                                 # before rclpy.init: Fast DDS reads it once per process
    rclpy.init(context=context, args=args, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    ns = {"namespace": opts.namespace} if opts.namespace else {}
    nodes = []
    try:
        sims = _make_simulators(scene, scene_obj, overrides, duration_s, context, ns, opts.window_s, opts.nmea_udp)
        _wall_epoch(sims, opts.real_time_factor)
        est = EstimatorNode(context=context, **ns, parameter_overrides=_params(
            scene, overrides, duration_s, **({"nmea_udp": str(opts.nmea_udp)} if opts.nmea_udp else {})))
        rec = RecorderNode(context=context, reorder=False, output_path=bag, **ns, parameter_overrides=_params(
            scene, overrides, duration_s, output=shown(bag), overwrite=bool(opts.overwrite),
            command=shown(opts.command),
            format=bag_format or "", max_bag_size=int(opts.max_bag_size or 0),
            max_bag_duration=float(opts.max_bag_duration_s or 0.0))) if bag else None
        nodes = sims + [est] + ([rec] if rec else [])
        ex = SingleThreadedExecutor(context=context)
        for n in nodes:
            ex.add_node(n)
        sim_pubs, lockstep, need = _wire(context, sims, est, rec)
        _wait_for_discovery(ex, sim_pubs, need, opts.timeout_s, stop)
        n_samples = max((s.samples for s in sims), default=0)
        dt = 1.0 / scene_obj.sample_rate_hz
        if batch is None:
            batch = BATCH if opts.real_time_factor <= 0 else int(0.02 * opts.real_time_factor / dt)
        batch = max(1, min(int(batch), MAX_BATCH))
        published, first_message_s, wall = _stream(
            sims, rec, ex, lockstep, sim_pubs, n_samples, dt, batch, opts.real_time_factor, opts.timeout_s,
            opts.progress, stop, t_start)
        if rec is not None and rec.failed is not None:
            # the disk filled: the bag is left readable up to its last commit; one line, exit 2
            rec.close(state="disk full")
            raise BagWriteError("recorder: " + rec.failed.line("--bag"))
        # the process's peak so far: the streaming part of the run, before the estimate's work arrays
        peak_streaming_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        result = _finalize(est, rec, ex, opts.timeout_s)
        stats = _stats(sims, est, rec, n_samples, dt, wall, published, batch, first_message_s, opts.window_s,
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


def _wall_epoch(sims, real_time_factor) -> None:
    """``stamp_epoch`` = wall (issue 37): sim time 0 is now, for every simulator of the suite (the
    estimator and the recorder take it from the first stamp); at a real-time factor other than 1
    the simulation epoch, with the error logged."""
    if not sims or sims[0].scene is None or sims[0].stamp_offset_ns is not None:
        return
    if real_time_factor != 1.0:
        sims[0].get_logger().error(f"stamp_epoch = 'wall' is invalid: only at real-time factor 1 (here "
                                   f"{real_time_factor:g}); the simulation epoch used")
        off = 0
    else:
        off = time.time_ns() - EPOCH_NS
    for s in sims:
        s.set_stamp_offset(off)


def _make_simulators(scene, scene_obj, overrides, duration_s, context, ns, window_s, nmea_udp=""):
    """Create one :class:`~gyro_instrument.ros.nodes.SimulatorNode` (the marine gyrocompass's
    :class:`~gyro_instrument.ros.nodes.compass.CompassNode`, with ``nmea_udp``) per simulator kind the scene's instruments need (in
    :func:`~gyro_instrument.instruments.simulator_kinds` order), publishing on RELIABLE depth-1000
    topics and stepped by the suite (``real_time_factor`` 0); the first one publishes the clock.
    Returns the list of nodes."""
    sims = []
    owner = True
    types = {spec[0] for spec in scene_obj.instruments.values()}
    for name, kinds in simulator_kinds().items():
        if types & set(kinds):
            more = {"nmea_udp": nmea_udp} if nmea_udp and name == COMPASS_NODE else {}
            sims.append(simulator_node(name, kinds, context=context, pub_qos=RELIABLE_1000, **ns,
                                       parameter_overrides=_params(
                scene, overrides, duration_s, real_time_factor=0.0, publish_clock=owner,
                window_s=float(window_s), **more)))
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
    # what the recorder and the estimator had before: /diagnostics also carries a marine compass's statuses
    base = dict(rec.counts) if rec else {}
    sent0 = dict(est.sent)
    result = est.finalize()
    if rec:
        # every message the estimator published on a recorded topic (the estimate's, the headings at
        # the reversal points, or the refusal's one /diagnostics status)
        def delivered():
            return all(rec.counts[t] >= n and rec.counts[t] - base.get(t, 0) >= n - sent0.get(t, 0)
                       for t, n in est.sent.items() if t in rec.counts)
        t_wait = time.monotonic() + timeout_s
        while not delivered() and time.monotonic() < t_wait:
            ex.spin_once(timeout_sec=0.001)
        meta = {"estimate_json": json.dumps(result, default=str) if result else ""}
        if est.refusal is not None:
            meta["refused"] = str(est.refusal)
        rec.close(meta, name="gyro_instrument_estimate")
    if est.refusal is not None:     # the data failed an adequacy check: exit 2 with its one line
        raise est.refusal
    if result is None:
        if est.scene is None:
            raise NodeFailure("estimator", "the scene could not be loaded (see the log above)")
        raise NodeFailure("estimator", est.failure or f"no estimate from the samples received "
                                                      f"({est.received()} joint samples)")
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
