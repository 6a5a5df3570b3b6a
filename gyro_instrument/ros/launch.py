"""The separate-node route: every node of a scene in its own process, started the way a launch file
(or a user with ``ros2 run``) starts them, configured by one params file.

:func:`write_params` writes that file (one section per node); :func:`launch` starts the recorder
(``stop_when_complete``) and the estimator, then the simulators (the first one owns ``clock``),
waits for the recorder to finish the bag and stops the others with SIGINT. Nothing here steps the
nodes: they find each other over DDS, the simulators wait for their subscribers, the followers
follow the owner's clock, the recorder orders what arrives — so the bag checks the same
guarantees as the lock-step suite (:mod:`gyro_instrument.ros.suite`). Run it on loopback
(``tools/loopback``).
"""

import os
import signal
import subprocess
import sys
import time

import yaml

from gyro_instrument.instruments import simulator_kinds


def simulators_of(scene_obj) -> list:
    """Names of the simulator nodes the scene needs, in :func:`~gyro_instrument.instruments.simulator_kinds` order."""
    types = {spec[0] for spec in scene_obj.instruments.values()}
    return [name for name, kinds in simulator_kinds().items() if types & set(kinds)]


def write_params(path, scene, bag, overrides=(), duration_s=0.0, real_time_factor=0.0, sims=(),
                 overwrite=False, any_namespace=False) -> dict:
    """A ROS 2 params file (``--params-file``) for every node of the scene; the first simulator in
    ``sims`` owns the clock; ``any_namespace``: sections keyed ``/**/<node>`` (they apply whatever
    ``__ns`` the nodes get). Returns the dict written."""
    def common(**more):
        out = {"scene": scene, "duration_s": float(duration_s or 0.0)}
        if overrides:
            out["overrides"] = list(overrides)
        out.update(more)
        return out
    doc = {"recorder": {"ros__parameters": common(output=bag, stop_when_complete=True, overwrite=bool(overwrite))},
           "estimator": {"ros__parameters": common()}}
    for i, name in enumerate(sims):
        doc[name] = {"ros__parameters": common(real_time_factor=float(real_time_factor),
                                             publish_clock=(i == 0),
                                             wait_for=["estimator", "recorder"])}
    if any_namespace:
        doc = {f"/**/{name}": v for name, v in doc.items()}
    with open(path, "w", encoding="utf-8") as fh:
        yaml.safe_dump(doc, fh, sort_keys=False, default_flow_style=None)
    return doc


def _command(node):
    return [sys.executable, "-c", f"import sys; from gyro_instrument.ros.main import {node}; sys.exit({node}())"]


def launch(scene, bag, overrides=(), duration_s=0.0, real_time_factor=0.0, namespace="", timeout_s=300.0,
           log_dir=None, overwrite=False, extra_ros_args=(), delay_s=0.0) -> dict:
    """Start the scene's nodes as separate processes and wait until the recorder finished ``bag``.

    Returns
    -------
    dict
        ``returncodes`` {node: exit status}, ``logs`` {node: text}, ``params`` (the params file).

    Raises
    ------
    TimeoutError
        The recorder did not finish within ``timeout_s`` (every process is stopped first).
    """
    from gyro_instrument.scenes import load_scene
    scene_obj = load_scene(scene, list(overrides) + ([f"duration_s={float(duration_s)!r}"] if duration_s else []))
    sims = simulators_of(scene_obj)
    log_dir = log_dir or os.path.dirname(os.path.abspath(bag))
    params = os.path.join(log_dir, "params.yaml")
    write_params(params, scene, bag, overrides, duration_s, real_time_factor, sims, overwrite, bool(namespace))
    ros = ["--ros-args", "--params-file", params] + (["-r", f"__ns:={namespace}"] if namespace else []) \
        + list(extra_ros_args)
    procs, logs = {}, {}
    order = ["recorder", "estimator"] + sims[1:] + sims[:1]   # the clock owner last
    try:
        for node in order:
            if node == order[2] and delay_s:
                time.sleep(delay_s)             # simulators started later than the recorder
            logs[node] = open(os.path.join(log_dir, f"{node}.log"), "w+", encoding="utf-8")
            procs[node] = subprocess.Popen(_command(node) + ros, stdout=logs[node], stderr=subprocess.STDOUT,
                                           start_new_session=True)
        try:
            procs["recorder"].wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise TimeoutError(f"the recorder did not finish {bag} within {timeout_s} s") from None
    finally:
        for node, p in procs.items():
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        for node, p in procs.items():
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    out = {"returncodes": {n: p.returncode for n, p in procs.items()}, "logs": {}, "params": params}
    for node, fh in logs.items():
        fh.seek(0)
        out["logs"][node] = fh.read()
        fh.close()
    return out


def _log_time(text, marker) -> float | None:
    """The ROS log time (s) of the first line of ``text`` holding ``marker``."""
    import re
    for line in text.splitlines():
        if marker in line:
            found = re.search(r"\[(\d+\.\d+)\]", line)
            return float(found.group(1)) if found else None
    return None


def timed_launch(scene="quet_paris", duration_s=600.0) -> dict:
    """The separate-node route at real-time factor 0 with recording, timed (issue 37 item 6): the
    wall time from the clock owner's first tick ("sim time starts" in its log) to the recorder's
    "every expected message recorded" (the estimate's own computation included), to the estimator's
    "every expected sample received" (``samples_s``: the streaming alone, as ``run``'s own figure
    leaves the estimate out); the messages per second in the bag, and the DDS deliveries per second
    (a clock tick goes to the recorder, the estimator and each following simulator, a joint state
    to the recorder and the estimator); the launch's whole
    wall time (interpreters, imports and discovery too), the messages in the bag and its status.
    Run on loopback (``tools/loopback``)."""
    import tempfile
    from gyro_instrument.recording.mcap_io import read_messages, recording_state
    with tempfile.TemporaryDirectory() as tmp:
        bag = os.path.join(tmp, "route.mcap")
        t0 = time.monotonic()
        res = launch(scene, bag, duration_s=duration_s, real_time_factor=0.0, timeout_s=600, log_dir=tmp)
        wall = time.monotonic() - t0
        logs = res["logs"]
        # the owner's own line ("]: sim time starts"), not a follower's "... before sim time starts"
        owner = next((n for n, text in logs.items() if "]: sim time starts" in text), None)
        start = _log_time(logs[owner], "]: sim time starts") if owner else None
        end = _log_time(logs.get("recorder", ""), "every expected message recorded")
        samples = _log_time(logs.get("estimator", ""), "every expected sample received")
        counts = {}
        for topic, _, _, _ in read_messages(bag):
            counts[topic] = counts.get(topic, 0) + 1
        messages = sum(counts.values())
        state = recording_state(bag)
    # DDS deliveries: every recorded message reached the recorder; the clock also each follower
    # simulator and the estimator, a joint state also the estimator
    sims = [n for n in res["returncodes"] if n not in ("recorder", "estimator")]
    deliveries = sum(n * (1 + (len(sims) if topic.endswith("/clock") else 1 if topic.endswith("/joint_states") else 0))
                     for topic, n in counts.items())
    streaming = (end - start) if start is not None and end is not None else None
    to_samples = (samples - start) if start is not None and samples is not None else None
    return {"scene": scene, "simulated_s": float(duration_s), "streaming_s": streaming,
            "samples_s": to_samples,
            "samples_real_time_factor": (duration_s / to_samples) if to_samples else None,
            "real_time_factor": (duration_s / streaming) if streaming else None, "launch_wall_s": wall,
            "messages": messages, "messages_per_s": (messages / streaming) if streaming else None,
            "deliveries_per_s": (deliveries / streaming) if streaming else None,
            "state": state, "returncodes": res["returncodes"]}


if __name__ == "__main__":          # python -m gyro_instrument.ros.launch [SCENE [DURATION_S]]: one JSON line
    import json
    print(json.dumps(timed_launch(sys.argv[1] if len(sys.argv) > 1 else "quet_paris",
                                  float(sys.argv[2]) if len(sys.argv) > 2 else 600.0)))
