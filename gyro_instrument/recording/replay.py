"""Replay: the estimate from a recorded bag, without DDS (``gyro-instrument replay``, the player).

:func:`replay_bag` reads the bag's scene record and JointState messages (every chunk's CRC
checked) and runs the same estimator as a live ``run``; :func:`damage_line` is the one-line text
of a damaged stretch used by the CLI and the nodes.
"""

import json

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.jsonable import to_jsonable
from gyro_instrument.recording.companions import check_companions


def _span_s(v, end):
    if v is None:
        return end
    txt = f"{v:.3f}".rstrip("0")
    return f"{txt}0 s" if txt.endswith(".") else f"{txt} s"


def damage_line(d) -> str:
    """One line for a lost stretch of a bag (a ``damaged`` entry of the replay JSON)."""
    reason = d.get("reason") or "damaged"
    where = f" at byte {d['offset']}" if d.get("offset") is not None else ""
    what = (f"chunk{where} failed its CRC" if reason.startswith("chunk CRC mismatch")
            else f"{reason}{where}")
    if d.get("file"):
        what = f"{d['file']}: {what}"
    if d.get("before_recovery"):
        what = f"before recovery: {what}"
    if d.get("lost_from_s") is None and d.get("lost_to_s") is None and d.get("span_from") is None:
        return f"{what}: no message in it"
    span = f"lost {_span_s(d.get('lost_from_s'), 'the start')} to {_span_s(d.get('lost_to_s'), 'the end')}"
    if d.get("span_from") == "neighbouring messages":
        span += " (between the intact messages around it)"
    return f"{what}: {span}"


def replay_bag(path, scene=None, overrides=(), topics=()) -> dict:
    """Estimate from a recorded bag (no DDS): the scene from the bag's metadata, the samples from its
    JointState messages decoded without ROS. Every chunk's CRC is checked; a damaged chunk is left
    out and listed under ``damaged`` with the log-time span it held (seconds from the scene's start).
    ``path``: an ``.mcap`` or a rosbag2 bag directory. With ``scene`` (and its ``overrides``) or
    ``topics`` remaps, a bag recorded by another tool: see
    :func:`gyro_instrument.recording.foreign.replay_foreign`.

    For a cut recording it adds ``observation_read_s`` (the span of joint stamps decoded, the shortest
    over the instruments), ``recording_cut`` (why it falls short of the scene's ``duration_s``);
    ``replay_notes`` says what the reader noticed.

    Raises
    ------
    SceneError
        ``path`` is missing or not a bag, or holds no scene metadata record and no ``scene`` is given.
    """
    if scene is not None or topics or overrides:
        from gyro_instrument.recording.foreign import replay_foreign
        return replay_foreign(path, scene, list(overrides), list(topics))
    from gyro_instrument.estimators.pipeline import estimate_records, estimated_instruments, estimator_instruments
    from gyro_instrument.recording.bag_samples import samples_from_bag
    from gyro_instrument.recording.joints import records_from_joints
    from gyro_instrument.scenes import build_instruments, scene_from_data
    meta, samples, notes, damaged = samples_from_bag(path)
    read_s = read_span_s(samples)
    if meta is None or "scene_yaml" not in meta:
        lost = " (damaged stretches: it may have been lost)" if damaged else ""
        raise SceneError("bag", path, "has no gyro_instrument metadata record (scene); record it with "
                                      f"'gyro-instrument run --bag' or the recorder node, or give the scene with "
                                      f"--scene SCENE{lost}")
    scene = scene_from_data(json.loads(meta["scene_yaml"]), source=path)
    insts = build_instruments(scene)
    # the records a live run's estimator keeps (estimable instruments and their companions: a rotor-off
    # swing), in the scene's instrument order, whatever order the bag's topics first appear in
    samples = {n: samples[n] for n in estimator_instruments(insts) if n in samples and len(samples[n][0]) >= 3}
    check_companions(insts, samples, path)
    result = estimate_records(scene, estimated_instruments(insts, samples), records_from_joints(insts, samples))
    result = to_jsonable(result)
    if damaged:
        result["damaged"] = to_jsonable(damaged)
    if read_s < scene.duration_s - 0.5 / scene.sample_rate_hz:
        result["observation_read_s"] = read_s
        result["recording_cut"] = "; ".join(notes) or "the joint samples stop before the scene's duration_s"
    if notes:
        result["replay_notes"] = notes
    return result


def read_span_s(samples) -> float:
    """Shortest span of joint stamps actually decoded from a bag, over its instruments, s (0 when
    none): the observation a replay really had (``samples`` as from ``samples_from_bag``)."""
    spans = [(int(t[-1]) - int(t[0])) / 1e9 for t, _, _ in samples.values() if len(t)]
    return min(spans) if spans else 0.0
