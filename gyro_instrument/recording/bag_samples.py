"""Joint samples from a recorded bag, decoded without ROS: the fixed CDR layouts of
:mod:`gyro_instrument.recording.cdr` (the estimator node's), else ``mcap_ros2``'s dynamic decoder."""

import numpy as np

from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.bag_layout import scan_path
from gyro_instrument.recording.topics import JOINT_STATE_TYPE, instrument_of, is_joint_topic


class MessageDecoder:
    """Decode CDR messages with ``mcap_ros2``'s dynamic decoder, one decoder per schema (cached):
    ``decode(schema, channel, data)`` -> the message object. Raises what the decoder raises for
    bytes that do not decode."""

    def __init__(self):
        from mcap_ros2.decoder import DecoderFactory
        self._factory, self._decoders = DecoderFactory(), {}
        self.notes = []          # what was noticed about the schemas (an empty definition...)

    def __call__(self, schema, channel, data):
        dec = self._decoders.get(schema.id)
        if dec is None:
            dec = self._decoders[schema.id] = self._decoder(schema, channel)
        if isinstance(dec, Exception):
            raise dec
        return dec(data)

    def _decoder(self, schema, channel):
        """A decoder for the schema; a schema with an empty definition (a writer that stored none)
        is decoded with the installed definition of its type, noted; without one installed, the
        error names the missing definition as the cause."""
        import dataclasses
        from gyro_instrument.recording.definitions import concatenated_definition
        if not bytes(schema.data or b"").strip():
            try:
                text = concatenated_definition(schema.name)
            except (OSError, ValueError, KeyError, RuntimeError):
                why = ValueError(f"schema {schema.name} (topic {channel.topic}) has an empty message definition "
                                 f"and no definition of that type is installed: its messages cannot be decoded")
                self.notes.append(str(why))
                return why
            self.notes.append(f"schema {schema.name} (topic {channel.topic}) has an empty message definition (the "
                              f"writer stored none): decoded with the installed {schema.name} definition")
            schema = dataclasses.replace(schema, data=text.encode())
        try:
            return self._factory.decoder_for(channel.message_encoding, schema)
        except Exception as exc:  # a definition the decoder cannot parse: its messages are undecodable
            why = ValueError(f"schema {schema.name} (topic {channel.topic}): definition not usable "
                             f"({exc.__class__.__name__}: {exc})")
            self.notes.append(str(why))
            return why


def skipped_topics(scan, used_types=("sensor_msgs/msg/JointState",)) -> list:
    """One note per topic of the bag whose message type is not installed here (no definition under
    the share directories) and not one that is read: skipped, the rest used."""
    from gyro_instrument.recording.definitions import msg_text
    out = []
    for ch in sorted(scan.channels.values(), key=lambda c: c.topic):
        sc = scan.schemas.get(ch.schema_id)
        type_name = sc.name if sc else ""
        if type_name in used_types:
            continue
        try:
            if type_name.count("/") != 2:
                raise ValueError(type_name)
            msg_text(type_name)
            continue
        except (OSError, ValueError):
            out.append(f"topic {ch.topic} skipped: its type {type_name or '(none)'} is not installed here "
                       f"(unknown message type); the other topics are used")
    return out


def samples_from_bag(path, scan=None) -> tuple:
    """(metadata dict or None, {instrument: (t_ns, position, velocity)}, notes, damaged).

    ``path``: a bare ``.mcap`` or a rosbag2 bag directory, split or not
    (:func:`~gyro_instrument.recording.bag_layout.scan_path`). Reads every
    ``[/<namespace>]/<instrument>/joint_states`` message of every intact chunk (CRCs checked): a
    damaged chunk is skipped and the chunks after it are read; a file cut short is read up to its
    last complete record. Out-of-order or duplicated stamps are left for the estimator to sort out
    (it reports what it dropped).

    Returns
    -------
    meta : dict or None
        The ``gyro_instrument`` metadata record (the scene).
    samples : dict
    notes : list of str
        What the reader noticed (interrupted recording, damaged summary, ...).
    damaged : list of dict
        Each lost stretch: ``offset``, ``length`` (bytes), ``lost_from_s``, ``lost_to_s`` (seconds from
        the scene's start; None when unknown), ``span_from``, ``reason``; also the losses a previous
        ``recover`` recorded (``before_recovery``: true).

    Raises
    ------
    SceneError
        ``path`` is not an MCAP file nor a bag directory (see
        :func:`~gyro_instrument.recording.bag_layout.bag_files`).
    """
    scan = scan or scan_path(path)
    meta = scan.metadata_record("gyro_instrument")
    notes = list(scan.notes) + [f"before recovery: {n}" for n in scan.recorded_notes]
    notes += skipped_topics(scan)
    out, count, undecodable, why = joint_samples(scan, EPOCH_NS, with_notes=True)
    notes += why
    if undecodable:
        notes.append(f"{undecodable} joint messages did not decode and were left out")
    notes += status_notes(scan, count)
    return meta, out, notes, scan.damage_dicts(EPOCH_NS)


def joint_samples(scan, epoch_ns, with_notes=False) -> tuple:
    """Every ``[/<namespace>]/<instrument>/joint_states`` JointState of the intact records of ``scan``:
    ({instrument: (t_ns from ``epoch_ns``, position (m, j), velocity (m, j))}, messages read,
    messages that did not decode).

    A channel whose first message has the fixed layout this package publishes
    (:func:`~gyro_instrument.recording.cdr.joint_state_layout`: the estimator node's decoder) is
    decoded with it, many messages at once; any other message through ``mcap_ros2``'s dynamic
    decoder. Both read the same float64 bytes."""
    from gyro_instrument.recording.cdr import joint_state_layout
    decode = MessageDecoder()
    layouts = {}                 # channel id -> CdrLayout, or None: decode message by message
    rows = {}                    # instrument -> list of (layout, bytes) or (None, (stamp, pos, vel))
    count = undecodable = 0
    for schema, channel, message in scan.records():
        if schema is None or not is_joint_topic(channel.topic) or schema.name != JOINT_STATE_TYPE:
            continue
        data = message.data
        lay = layouts.get(channel.id)
        if lay is not None and lay.matches(data):
            entry = (lay, data)
        else:
            try:
                msg = decode(schema, channel, data)
                stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec) - epoch_ns
                pos, vel = list(msg.position), list(msg.velocity)
            except Exception:  # an intact record holding a message that does not decode
                undecodable += 1
                continue
            if channel.id not in layouts:
                try:
                    lay = joint_state_layout(tuple(msg.name), msg.header.frame_id)
                except ValueError:      # no joints
                    lay = None
                layouts[channel.id] = lay if lay is not None and lay.matches(data) and epoch_ns == EPOCH_NS \
                    else None
            entry = (None, (stamp, pos, vel))
        rows.setdefault(instrument_of(channel.topic), []).append(entry)
        count += 1
    out = {name: _arrays(entries) for name, entries in rows.items()}
    if with_notes:
        return out, count, undecodable, list(decode.notes)
    return out, count, undecodable


def _arrays(entries):
    """(t_ns int64, position, velocity) from :func:`joint_samples`' entries, in their order; runs of
    fixed-layout messages are decoded together (:meth:`~gyro_instrument.recording.cdr.CdrLayout.decode`)."""
    ts, ps, vs = [], [], []
    k = 0
    while k < len(entries):
        lay, item = entries[k]
        if lay is None:
            ts.append(item[0])
            ps.append(item[1])
            vs.append(item[2])
            k += 1
            continue
        z = k
        while z < len(entries) and entries[z][0] is lay:
            z += 1
        t, (pos, vel, _) = lay.decode([d for _, d in entries[k:z]])
        ts.extend(t.tolist())
        ps.extend(pos.tolist())
        vs.extend(vel.tolist())
        k = z
    return np.array(ts, dtype=np.int64), np.array(ps, dtype=float), np.array(vs, dtype=float)


def status_notes(scan, count) -> list:
    """What the recording's status record says about how complete it is (list of str), ``count``
    being the joint messages read."""
    notes = []
    state = scan.state
    if state == "no summary":
        notes.append(f"bag has no summary (recording interrupted): read {count} joint messages up to the last "
                     f"complete record")
    elif state == "recording":
        notes.append(f"recording interrupted (killed) after its last commit: the file is complete up to there; "
                     f"read {count} joint messages")
    elif state == "split":
        notes.append(f"this file is one part of a split bag (status split): read {count} joint messages; "
                     f"replay the bag directory for all of it")
    elif state not in (None, "complete"):
        notes.append(f"recording {state}: read {count} joint messages")
    if scan.recorded_status not in (None, "complete", state):
        notes.append(f"before recovery the recording's status was '{scan.recorded_status}'")
    return notes
