"""MCAP in rosbag2's layout, written and read without rclpy.

Writer: profile ``ros2``; one schema per type (encoding ``ros2msg``, the concatenated definition of
:mod:`.definitions`); channels with message encoding ``cdr`` and metadata
``offered_qos_profiles`` (a YAML *list*, as rosbag2 jazzy writes it) and ``topic_type_hash``;
zstd-compressed chunks, indexed summary on close. Log time = receive time in sim time; the
publish time is written equal to it so files are deterministic. A metadata record
``gyro_instrument`` holds the scene (YAML), the seed and the command, for ``replay``.

Reader: ``read_messages`` yields (topic, type, log_time_ns, cdr bytes) in log-time order;
A file cut short (SIGKILL) is read up to its last complete chunk.
"""

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer

from gyro_instrument.recording.definitions import concatenated_definition, type_hash

_INF = "    sec: 9223372036\n    nsec: 854775807\n"


def qos_yaml(reliable=True, keep_all=True, depth=0, transient_local=False):
    """rosbag2 (jazzy, metadata version 9) encoding of one offered QoS profile, as a YAML list."""
    return ("- history: {h}\n  depth: {d}\n  reliability: {r}\n  durability: {du}\n  deadline:\n{inf}"
            "  lifespan:\n{inf}  liveliness: 1\n  liveliness_lease_duration:\n{inf}"
            "  avoid_ros_namespace_conventions: false\n").format(
        h=2 if keep_all else 1, d=depth, r=1 if reliable else 2, du=1 if transient_local else 2,
        inf=_INF)


class BagWriter:
    """Write ROS 2 CDR messages to an MCAP file in rosbag2's layout.

    Parameters
    ----------
    path : str
        Output ``.mcap`` path; written to ``path + '.partial'`` is *not* used: chunks are flushed
        as they fill so a killed process leaves a readable prefix.
    chunk_size : int
        Bytes per chunk (smaller chunks lose less on SIGKILL).
    """

    def __init__(self, path, chunk_size=256 * 1024, compression="zstd"):
        self.path = path
        self._fh = open(path, "wb")
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
        self._w = Writer(self._fh, chunk_size=chunk_size, compression=comp)
        self._w.start(profile="ros2", library="gyro_instrument")
        self._schemas = {}
        self._channels = {}
        self.counts = {}
        self.closed = False
        self._since_flush = 0

    def add_topic(self, topic, type_name, qos=None):
        """Register a topic of type ``pkg/msg/Type`` (idempotent); returns the channel id."""
        if topic in self._channels:
            return self._channels[topic]
        if type_name not in self._schemas:
            self._schemas[type_name] = self._w.register_schema(
                name=type_name, encoding="ros2msg", data=concatenated_definition(type_name).encode())
        cid = self._w.register_channel(topic=topic, message_encoding="cdr", schema_id=self._schemas[type_name],
                                       metadata={"offered_qos_profiles": qos or qos_yaml(),
                                                 "topic_type_hash": type_hash(type_name)})
        self._channels[topic] = cid
        self.counts[topic] = 0
        return cid

    def write(self, topic, log_time_ns, data, publish_time_ns=None):
        """Append one CDR message on a registered topic."""
        cid = self._channels[topic]
        self._w.add_message(channel_id=cid, log_time=int(log_time_ns),
                            publish_time=int(log_time_ns if publish_time_ns is None else publish_time_ns),
                            data=bytes(data), sequence=self.counts[topic])
        self.counts[topic] += 1
        self._since_flush += 1
        if self._since_flush >= 256:      # completed chunks reach the disk: a SIGKILL loses little
            self._fh.flush()
            self._since_flush = 0

    def add_metadata(self, name, data):
        """A metadata record (str -> str mapping), written (and flushed) at once."""
        self._w.add_metadata(name, {str(k): str(v) for k, v in data.items()})
        self._fh.flush()

    def close(self):
        """Finish the file: summary, indexes, footer."""
        if not self.closed:
            self._w.finish()
            self._fh.close()
            self.closed = True


def iter_records(path, topics=None):
    """Yield (schema, channel, message) in log-time order from an indexed file, or in file order
    from one without a summary (a recorder killed mid-run): up to its last complete record."""
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader
    with open(path, "rb") as fh:
        try:
            reader = make_reader(fh)
            summary = reader.get_summary()
        except Exception:
            summary = None
        if summary is not None and summary.chunk_indexes:
            yield from reader.iter_messages(topics=topics, log_time_order=True)
            return
        fh.seek(0)
        schemas, channels = {}, {}
        try:
            for rec in StreamReader(fh, skip_magic=False).records:
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Message):
                    ch = channels.get(rec.channel_id)
                    if ch is not None and (topics is None or ch.topic in topics):
                        yield schemas.get(ch.schema_id), ch, rec
        except Exception:  # truncated tail: stop at the last complete record
            return


def read_messages(path, topics=None):
    """Yield (topic, type_name, log_time_ns, cdr_bytes); see :func:`iter_records`."""
    for schema, channel, message in iter_records(path, topics):
        yield channel.topic, schema.name if schema else "", message.log_time, message.data


def read_metadata(path, name="gyro_instrument"):
    """The named metadata record as a dict, or None (also from a file cut short)."""
    from mcap.records import Metadata
    from mcap.stream_reader import StreamReader
    with open(path, "rb") as fh:
        try:
            for rec in StreamReader(fh).records:
                if isinstance(rec, Metadata) and rec.name == name:
                    return dict(rec.metadata)
        except Exception:
            return None
    return None


def recover(damaged, out):
    """Rewrite a recording cut short (no summary/footer) into a complete, indexed MCAP holding every
    complete record of the original (schemas, channels with their metadata, messages, metadata).

    Returns the number of messages written.
    """
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    with open(damaged, "rb") as fh, open(out, "wb") as fo:
        w = Writer(fo, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="gyro_instrument recover")
        schema_ids, channel_ids, n = {}, {}, 0
        try:
            for rec in StreamReader(fh, skip_magic=False).records:
                if isinstance(rec, Schema):
                    schema_ids[rec.id] = w.register_schema(rec.name, rec.encoding, rec.data)
                elif isinstance(rec, Channel):
                    channel_ids[rec.id] = w.register_channel(rec.topic, rec.message_encoding,
                                                             schema_ids.get(rec.schema_id, 0), dict(rec.metadata))
                elif isinstance(rec, Message) and rec.channel_id in channel_ids:
                    w.add_message(channel_ids[rec.channel_id], rec.log_time, rec.data, rec.publish_time, rec.sequence)
                    n += 1
                elif isinstance(rec, Metadata):
                    w.add_metadata(rec.name, dict(rec.metadata))
        except Exception:
            pass  # truncated tail
        w.finish()
    return n
