"""Bags recorded by other tools (``ros2 bag record``, rosbags, a lab's own recorder): the scene is
given on the command line (``replay BAG --scene SCENE [--set ...]``) and the instruments' topics
are found by the documented names and types (msg_docs/topics.md), or by the names given with
``--topic INSTRUMENT=/topic``.

For each instrument the estimator uses, the topic ``/<instrument>/joint_states`` (or the remapped
one) must be a ``sensor_msgs/msg/JointState`` whose joint names hold the instrument's measured
joints, as ``<instrument>/<joint>`` or as the bare ``<joint>`` (any ``prefix/<joint>`` is taken
too): a pendulum's ``deflection_east`` and ``deflection_north``; a directing gyroscope's swinging
joint (``axis``; the gimbal's ``outer_ring`` or ``inner_ring``) and ``rotor`` (its velocity is the
spin). Joints may come in any order and others may be present. Stamps are the messages' header
stamps (the log time when every header stamp is 0), in seconds from the first sample.

Every topic is accounted for in the result's ``topics``: ``matched`` (instrument -> topic),
``unmatched`` (instrument -> why: no such topic, a topic of another type, joints missing) and
``unused`` (topic -> type, the bag's other topics). Every file is read through the CRC-checking
scanner, so damage is reported exactly as for the package's own bags.
"""

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.topics import JOINT_STATE_TYPE, joint_topic

JOINT_STATE = JOINT_STATE_TYPE


def parse_topic_remaps(items, insts, field="--topic") -> dict:
    """``["pendulum=/lab/bob", ...]`` -> {instrument: topic}.

    Raises
    ------
    SceneError
        An item not of the form ``INSTRUMENT=/topic``, or an instrument the scene does not have.
    """
    out = {}
    for item in items or ():
        name, sep, topic = str(item).partition("=")
        name, topic = name.strip(), topic.strip()
        if not sep or not name or not topic.startswith("/"):
            raise SceneError(field, item, "must be INSTRUMENT=/topic, e.g. pendulum=/lab/pendulum/joint_states")
        key = name.strip("/").split("/")[0] if name.startswith("/") else name
        if key not in insts:
            raise SceneError(field, item, f"names no instrument of the scene; valid: {', '.join(insts)}")
        out[key] = topic
    return out


def _required_joints(inst):
    """The joints an instrument's record needs (None: not used by the estimator): its observation's."""
    return inst.observation().required_joints()


def _column_of(names, name, joint):
    """Index of ``joint`` among a message's joint names (``name/joint``, ``joint`` or ``*/joint``)."""
    for pref in (f"{name}/{joint}", joint):
        if pref in names:
            return names.index(pref)
    for i, n in enumerate(names):
        if n.endswith("/" + joint):
            return i
    return None


def foreign_samples(scan, insts, remaps=None) -> tuple:
    """Joint samples of the scene's instruments found by name and type in a scanned bag.

    Parameters
    ----------
    scan : BagScan
        From :func:`~gyro_instrument.recording.bag_layout.scan_path`.
    insts : dict
        instrument name -> instrument (``build_instruments``).
    remaps : dict, optional
        instrument name -> topic (``--topic``).

    Returns
    -------
    samples : dict
        instrument -> (t_ns from the first sample, position (m, k), velocity (m, k)) in
        joint layout order (``Instrument.JOINTS``) (NaN for joints not recorded).
    report : dict
        ``matched``, ``unmatched``, ``unused`` (see the module docstring).
    notes : list of str
    """
    by_topic = {}
    for ch in scan.channels.values():
        sc = scan.schemas.get(ch.schema_id)
        by_topic.setdefault(ch.topic, set()).add(sc.name if sc else "")
    report = {"matched": {}, "unmatched": {}, "unused": {}}
    wanted = _match_topics(insts, remaps or {}, by_topic, report)
    from gyro_instrument.recording.bag_samples import skipped_topics
    rows, undecodable, why = _read_rows(scan, wanted, report)
    notes = skipped_topics(scan) + why
    notes += [f"{undecodable} joint messages did not decode and were left out"] if undecodable else []
    samples = _arrays(wanted, rows, report, notes)
    used = set(report["matched"].values())
    report["unused"] = {tp: ", ".join(sorted(ty)) for tp, ty in sorted(by_topic.items()) if tp not in used}
    return samples, report, notes


def _match_topics(insts, remaps, by_topic, report):
    """topic -> (instrument name, instrument, required joints) for every instrument whose topic
    (``remaps`` or the documented ``/<name>/joint_states``) is in the bag as a JointState; the others
    go to ``report["unmatched"]`` with the reason."""
    wanted = {}
    for name, inst in insts.items():
        joints = _required_joints(inst)
        if joints is None:
            continue
        topic = remaps.get(name, "/" + joint_topic(name))
        types = by_topic.get(topic)
        if not types:
            report["unmatched"][name] = f"no topic {topic} in the bag" + ("" if name in remaps else
                                                                          f" (remap with --topic {name}=/other)")
        elif JOINT_STATE not in types:
            report["unmatched"][name] = f"topic {topic} has type {', '.join(sorted(types))}, expected {JOINT_STATE}"
        else:
            wanted[topic] = (name, inst, joints)
    return wanted


def _read_rows(scan, wanted, report):
    """Decode the wanted topics' intact JointState records: ({name: (stamps, log times, positions,
    velocities)} as lists in joint layout order (``Instrument.JOINTS``), NaN for joints not recorded; the number of
    messages that did not decode; the decoder's notes about the schemas). A topic lacking a required joint goes to ``report["unmatched"]``."""
    from gyro_instrument.recording.bag_samples import MessageDecoder
    decode = MessageDecoder()
    rows = {name: ([], [], [], []) for name, _, _ in wanted.values()}     # stamps, log times, pos, vel
    columns, undecodable = {}, 0
    for schema, channel, message in scan.records(set(wanted)):
        if schema is None or schema.name != JOINT_STATE:
            continue
        name, inst, joints = wanted[channel.topic]
        if name in report["unmatched"]:
            continue
        try:
            msg = decode(schema, channel, message.data)
            names = list(msg.name)
            stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
            pos, vel = list(msg.position), list(msg.velocity)
        except Exception:  # an intact record holding a message that does not decode
            undecodable += 1
            continue
        key = tuple(names)
        if key not in columns:
            layout = inst.observation().layout.names
            cols = [_column_of(names, name, j) for j in layout]
            missing = [j for j in joints if cols[layout.index(j)] is None]
            if missing:
                report["unmatched"][name] = (f"topic {channel.topic} lacks the joints {', '.join(missing)} of a "
                                             f"{inst.type_name} (its joints: {', '.join(names) or 'none'})")
                continue
            columns[key] = cols
        cols = columns[key]
        ts, ls, ps, vs = rows[name]
        ts.append(stamp)
        ls.append(message.log_time)
        ps.append([pos[c] if c is not None and c < len(pos) else np.nan for c in cols])
        vs.append([vel[c] if c is not None and c < len(vel) else np.nan for c in cols])
    return rows, undecodable, list(decode.notes)


def _arrays(wanted, rows, report, notes):
    """The matched instruments' samples as arrays, sorted by stamp, times from the first sample of
    any instrument (log times when every stamp is 0); fewer than 3 messages is unmatched."""
    samples = {}
    for topic, (name, inst, _) in wanted.items():
        if name in report["unmatched"]:
            continue
        ts, ls, ps, vs = rows[name]
        if len(ts) < 3:
            report["unmatched"][name] = f"topic {topic} holds {len(ts)} intact messages; need at least 3"
            continue
        t = np.array(ts, dtype=np.int64)
        if not t.any():
            t = np.array(ls, dtype=np.int64)
            notes.append(f"{name}: every header stamp is 0: the log times are used")
        samples[name] = (t, np.array(ps, dtype=float), np.array(vs, dtype=float))
        report["matched"][name] = topic
    if samples:
        t0 = min(int(v[0].min()) for v in samples.values())
        if t0 != EPOCH_NS:
            notes.append(f"times from the first sample (stamp {t0 / 1e9:.9f} s)")
        for name, (t, p, v) in samples.items():
            order = np.argsort(t, kind="stable")
            if np.any(np.diff(order) < 0):
                notes.append(f"{name}: messages out of stamp order: sorted")
            samples[name] = (t[order] - t0, p[order], v[order])
    return samples


def replay_foreign(path, scene_arg=None, overrides=(), topic_remaps=()) -> dict:
    """``replay`` of a bag with the scene given (``--scene``) or taken from the bag's record, the
    instruments' topics found by name and type (:func:`foreign_samples`).

    Raises
    ------
    SceneError
        Not a bag; no scene (neither ``--scene`` nor a record); a bad ``--topic``; no instrument
        of the scene found in the bag (one line listing what was expected and why it did not match).
    """
    import json
    from gyro_instrument.core.jsonable import to_jsonable
    from gyro_instrument.estimators.pipeline import estimate_records
    from gyro_instrument.recording.bag_layout import scan_path
    from gyro_instrument.recording.joints import records_from_joints
    from gyro_instrument.scenes import build_instruments, load_scene, scene_from_data
    scan = scan_path(path)
    meta = scan.metadata_record("gyro_instrument")
    notes = list(scan.notes)
    if scene_arg is not None:
        scene = load_scene(scene_arg, list(overrides))
        if meta is not None and "scene_yaml" in meta:
            notes.append("the bag's own scene record was not used (--scene given)")
    elif meta is not None and "scene_yaml" in meta:
        scene = scene_from_data(json.loads(meta["scene_yaml"]), source=path)
        if overrides:
            raise SceneError("--set", overrides[0], "needs --scene (the bag's recorded scene is used as it is)")
    else:
        raise SceneError("bag", path, "has no gyro_instrument metadata record (scene): give the scene with "
                                      "--scene SCENE")
    if scan.state == "no summary" or scan.truncated:
        notes.append("bag has no summary (recording interrupted): read up to the last complete record")
    elif scan.state == "recording":
        notes.append("recording interrupted (killed) after its last commit: the file is complete up to there")
    insts = build_instruments(scene)
    remaps = parse_topic_remaps(topic_remaps, insts)
    samples, report, more = foreign_samples(scan, insts, remaps)
    notes += more
    if not samples:
        why = "; ".join(f"{n}: {r}" for n, r in report["unmatched"].items()) or "the scene has no instrument " \
                                                                               "the estimator uses"
        raise SceneError("bag", path, f"does not match the scene {scene.name}: {why}")
    for name, reason in report["unmatched"].items():
        notes.append(f"{name} not matched: {reason}")
    if report["unused"]:
        notes.append(f"topics not used: {', '.join(report['unused'])}")
    from gyro_instrument.recording.companions import check_companions
    check_companions(insts, samples, path, remaps)
    result = estimate_records(scene, {n: insts[n] for n in samples}, records_from_joints(insts, samples))
    spans = [float(v[0][-1] - v[0][0]) / 1e9 for v in samples.values()]
    result["observation_s"] = max(spans)
    result = to_jsonable(result)
    result["topics"] = report
    damaged = scan.damage_dicts(EPOCH_NS)
    if damaged:
        result["damaged"] = to_jsonable(damaged)
    if notes:
        result["replay_notes"] = notes
    return result
