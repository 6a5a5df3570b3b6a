"""The whole suite in one process (there is no ``ros2 launch`` on PyPI): simulators, estimator
and recorder on one ``SingleThreadedExecutor``, stepped in lock-step so nothing is dropped.

The simulators own ``/clock`` and step in the suite's loop: after each sample the executor spins
until the estimator and the recorder hold every message of that sample. With
``real_time_factor`` > 0 the loop is paced to the wall clock; 0 runs as fast as possible.
"""

import json
import signal
import threading
import time

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.parameter import Parameter

from gyro_instrument.ros.nodes import EstimatorNode, RecorderNode, SimulatorNode
from gyro_instrument.ros.topics import SIMULATOR_KINDS


class DeliveryError(RuntimeError):
    """A message was not delivered in time (the suite never drops silently)."""


def _params(scene, overrides, duration_s, **extra):
    ps = [Parameter("scene", value=scene), Parameter("duration_s", value=float(duration_s or 0.0))]
    if overrides:
        ps.append(Parameter("overrides", value=list(overrides)))
    ps += [Parameter(k, value=v) for k, v in extra.items()]
    return ps


def run_suite(scene, overrides=(), duration_s=None, bag=None, real_time_factor=0.0, command="",
              timeout_s=10.0, progress=None):
    """Run the scene's nodes; return (estimate dict, stats dict).

    Raises
    ------
    SceneError
        Bad scene values (checked before any node starts).
    DeliveryError
        A sample was not delivered within ``timeout_s``.
    """
    from gyro_instrument.scenes import load_scene
    overrides = list(overrides)
    overrides_all = overrides + ([f"duration_s={float(duration_s)!r}"] if duration_s else [])
    scene_obj = load_scene(scene, overrides_all)          # refuse bad input before any node starts
    context = rclpy.Context()
    # SIGINT/SIGTERM set a flag read between samples, so the interrupt never lands inside a write
    # (the recorder then finishes the file with status 'interrupted')
    stop = []
    handlers = {}
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            handlers[sig] = signal.signal(sig, lambda signum, frame: stop.append(signum))
    rclpy.init(context=context, args=[], signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
    nodes = []
    try:
        sims = []
        owner = True
        types = {spec[0] for spec in scene_obj.instruments.values()}
        for name, kinds in SIMULATOR_KINDS.items():
            if types & set(kinds):
                sims.append(SimulatorNode(name, kinds, context=context, parameter_overrides=_params(
                    scene, overrides, duration_s, real_time_factor=0.0, publish_clock=owner)))
                owner = False
        est = EstimatorNode(context=context, parameter_overrides=_params(
            scene, overrides, duration_s, use_sim_time=True))
        rec = RecorderNode(context=context, parameter_overrides=_params(
            scene, overrides, duration_s, output=bag, use_sim_time=True, command=command)) if bag else None
        nodes = sims + [est] + ([rec] if rec else [])
        ex = SingleThreadedExecutor(context=context)
        for n in nodes:
            ex.add_node(n)
        # wait for discovery: every publisher matched by its subscribers
        deadline = time.monotonic() + timeout_s
        def matched():
            for s in sims:
                for name, pub in s.pubs.items():
                    need = (1 if name in est.buffers else 0) + (1 if rec else 0)
                    if pub.get_subscription_count() < need:
                        return False
            return True
        while not matched():
            if stop:
                raise KeyboardInterrupt
            ex.spin_once(timeout_sec=0.01)
            if time.monotonic() > deadline:
                raise DeliveryError("subscribers did not match the simulators' publishers in time")
        n_samples = max((s.samples for s in sims), default=0)
        per_step_est = sum(1 for s in sims for name in s.streams if name in est.buffers)
        per_step_rec = sum(s.messages_per_step() + (1 if s.clock_pub else 0) for s in sims) if rec else 0
        dt = 1.0 / scene_obj.sample_rate_hz
        w0 = time.perf_counter()
        for i in range(n_samples):
            if stop:
                raise KeyboardInterrupt
            for s in sims:
                s.publish_step()
            want_e, want_r = per_step_est * (i + 1), per_step_rec * (i + 1)
            t_wait = time.monotonic() + timeout_s
            while est.received() < want_e or (rec and rec.received() < want_r):
                ex.spin_once(timeout_sec=0.001)
                if time.monotonic() > t_wait:
                    raise DeliveryError(f"sample {i}: estimator has {est.received()}/{want_e}, recorder "
                                        f"{rec.received() if rec else 0}/{want_r} messages")
            if real_time_factor > 0:
                lag = (i + 1) * dt / real_time_factor - (time.perf_counter() - w0)
                if lag > 0:
                    time.sleep(lag)
            if progress and i % max(n_samples // 20, 1) == 0:
                progress(f"sample {i}/{n_samples}")
        wall = time.perf_counter() - w0
        base = rec.received() if rec else 0
        result = est.finalize()
        if rec:
            want = base + (len([t for t in rec.counts if t.startswith("/estimator") or t == "/diagnostics"])
                           if result is not None else 0)
            t_wait = time.monotonic() + timeout_s
            while rec.received() < want and time.monotonic() < t_wait:
                ex.spin_once(timeout_sec=0.001)
            rec.close({"estimate_json": json.dumps(result, default=str) if result else ""}, name="gyro_instrument_estimate")
        stats = {"samples": n_samples, "wall_s": wall,
                 "real_time_factor_achieved": (n_samples * dt / wall) if wall > 0 else None,
                 "estimator_messages": est.received(), "recorded": dict(rec.counts) if rec else {},
                 "published": {name: s.samples for s in sims for name in s.streams}}
        return result, stats
    finally:
        for n in nodes:
            if isinstance(n, RecorderNode):
                n.close(state="interrupted")   # only still open if the run did not finish
            n.destroy_node()
        rclpy.shutdown(context=context)
        for sig, h in handlers.items():
            signal.signal(sig, h)
