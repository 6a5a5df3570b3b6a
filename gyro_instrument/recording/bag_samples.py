"""Joint samples from a recorded bag, decoded without ROS (``mcap_ros2``'s dynamic decoder)."""

import numpy as np
from gyro_instrument.recording.mcap_io import iter_records, read_metadata, recording_state


def samples_from_bag(path):
    """(metadata dict or None, {instrument: (t_ns, position, velocity)}, notes).

    Reads every ``/<instrument>/joint_states`` message; a damaged file is read up to its last
    complete record. Out-of-order or duplicated stamps are left for the estimator to sort out
    (it reports what it dropped).
    """
    from mcap_ros2.decoder import DecoderFactory
    from gyro_instrument.core.scene import EPOCH_NS
    meta = read_metadata(path)
    data, notes = {}, []
    factory = DecoderFactory()
    decoders = {}
    count = 0
    try:
        for schema, channel, message in iter_records(path):
            if schema is None or not channel.topic.endswith("/joint_states") \
                    or schema.name != "sensor_msgs/msg/JointState":
                continue
            dec = decoders.get(schema.id)
            if dec is None:
                dec = decoders[schema.id] = factory.decoder_for(channel.message_encoding, schema)
            msg = dec(message.data)
            name = channel.topic.strip("/").split("/")[0]
            ts, pos, vel = data.setdefault(name, ([], [], []))
            ts.append(int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec) - EPOCH_NS)
            pos.append(list(msg.position))
            vel.append(list(msg.velocity))
            count += 1
    except Exception as exc:  # damaged: keep what was read
        notes.append(f"bag read stopped after {count} joint messages: {exc.__class__.__name__}: {exc}")
    state = recording_state(path)
    if state == "no summary":
        notes.append(f"bag has no summary (recording interrupted): read {count} joint messages up to the last "
                     f"complete record")
    elif state == "recording":
        notes.append(f"recording interrupted (killed) after its last commit: the file is complete up to there; "
                     f"read {count} joint messages")
    elif state not in (None, "complete"):
        notes.append(f"recording {state}: read {count} joint messages")
    out = {n: (np.array(v[0], dtype=np.int64), np.array(v[1], dtype=float), np.array(v[2], dtype=float))
           for n, v in data.items()}
    return meta, out, notes

