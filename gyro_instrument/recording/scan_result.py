"""What :func:`~gyro_instrument.recording.bag_scan.scan_bag` finds in an MCAP file (:class:`BagScan`):
where its intact messages are (:class:`Container`: one per intact chunk, or per run of message
records outside chunks, with its byte range, message count and log-time range), every damaged
stretch with the log-time span it held (:class:`Damage`), the schemas, channels and metadata
records, and the metadata records in which ``recover`` keeps what a file lost and the recorder its
status.

The messages themselves are not kept: :meth:`BagScan.iter_keyed` reads them back from the file,
container by container, in log-time order, holding only the containers whose time ranges overlap
the message being yielded (the ``mcap`` reader's own ordering: a chunk is read when the earliest
message not yet yielded is not earlier than the chunk's first log time). So a scan's memory is a
few hundred bytes per container plus one chunk's messages, whatever the size of the bag.
"""

import heapq
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from io import BytesIO
from typing import NamedTuple

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import Chunk, Header, Message
from mcap.stream_reader import breakup_chunk

#: metadata record in which ``recover`` keeps the damage it found (spans as JSON) and the status
#: the original file had, so that a replay of the recovered file still reports the loss
DAMAGE_RECORD = "gyro_instrument_damage"
STATUS_RECORD = "gyro_instrument_status"


class Container(NamedTuple):
    """An intact stretch of a file's data section holding messages: a chunk whose CRC checked
    (``chunk`` True; ``length`` is its record's length field, the chunk's body being the bytes
    ``pos + 9 .. pos + 9 + length``), or a run of adjacent message records outside any chunk
    (``chunk`` False; the records fill ``pos .. pos + length``). ``count`` messages with log times
    ``t_min`` .. ``t_max`` (ns)."""

    t_min: int
    pos: int
    length: int
    chunk: bool
    count: int
    t_max: int


def _stream(data):
    return ReadDataStream(BytesIO(data))


def container_messages(fh, c) -> list:
    """The messages of container ``c`` read back from the open binary file ``fh``, as the scan
    ordered them: (log_time, pos, index, Message) with ``pos`` the chunk's offset and ``index`` the
    record's index in the chunk, or ``pos`` the message record's own offset and ``index`` 0.

    Raises
    ------
    mcap.exceptions.McapError
        The bytes changed since the scan (the chunk no longer passes its CRC).
    """
    fh.seek(c.pos + 9 if c.chunk else c.pos)
    body = fh.read(c.length)
    if c.chunk:
        records = breakup_chunk(Chunk.read(_stream(body)), validate_crc=True)
        return [(r.log_time, c.pos, i, r) for i, r in enumerate(records) if isinstance(r, Message)]
    out, p = [], 0
    while p < len(body):
        (length,) = struct.unpack_from("<Q", body, p + 1)
        if body[p] == Opcode.MESSAGE:
            msg = Message.read(_stream(body[p + 9:p + 9 + length]), length)
            out.append((msg.log_time, c.pos + p, 0, msg))
        p += 9 + length
    return out


def merge_containers(path, containers) -> Iterator:
    """Yield (log_time, pos, index, Message) of every message of ``containers`` (of the file
    ``path``) in (log_time, pos, index) order, reading a container only when the earliest message
    still to be yielded is not earlier than the container's first log time: memory holds the
    containers that overlap in time, never the file."""
    order = sorted(containers)            # by t_min, then offset
    heap, k = [], 0
    with open(path, "rb") as fh:
        while k < len(order) or heap:
            while k < len(order) and (not heap or order[k].t_min <= heap[0][0]):
                for item in container_messages(fh, order[k]):
                    heapq.heappush(heap, item)
                k += 1
            yield heapq.heappop(heap)


class _Messages:
    """``BagScan.messages``: a sized view that reads the messages back when iterated."""

    def __init__(self, scan):
        self._scan = scan

    def __len__(self):
        return self._scan.message_count

    def __iter__(self):
        return iter(self._scan.iter_keyed())


@dataclass
class Damage:
    """One damaged stretch of a file.

    ``offset``/``length`` in bytes (None for damage known only from a recorded damage record);
    ``lost_from_ns``/``lost_to_ns`` the log-time span it held (None: unknown at that end);
    ``span_from`` says where the span comes from: ``chunk index``, ``neighbouring messages`` or
    ``recorded by recover``.
    """

    offset: int
    length: int
    reason: str
    lost_from_ns: int = None
    lost_to_ns: int = None
    span_from: str = None
    chunk_offsets: tuple = ()

    def as_dict(self, epoch_ns) -> dict:
        """JSON form: times in seconds from ``epoch_ns`` (the scene's start)."""
        def s(ns):
            return None if ns is None else (ns - epoch_ns) / 1e9
        return {"offset": self.offset, "length": self.length, "lost_from_s": s(self.lost_from_ns),
                "lost_to_s": s(self.lost_to_ns), "span_from": self.span_from, "reason": self.reason}


@dataclass
class BagScan:
    """What :func:`scan_bag` found: where the intact messages are (``containers``), how many each
    channel has (``channel_stats``: channel id -> [count, key of its first message in log-time
    order, last log time]), the schemas, channels, metadata records, damage and notes. The
    messages are read back from the file on demand (:attr:`messages`, :meth:`records`)."""

    path: str
    size: int
    header: Header = None
    schemas: dict = field(default_factory=dict)
    channels: dict = field(default_factory=dict)
    containers: list = field(default_factory=list)
    channel_stats: dict = field(default_factory=dict)
    metadata: list = field(default_factory=list)
    damaged: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    summary_ok: bool = False
    data_end: bool = False
    truncated: bool = False
    recorded_damage: list = field(default_factory=list)
    recorded_notes: list = field(default_factory=list)
    recorded_status: str = None

    @property
    def message_count(self) -> int:
        """Intact messages, on known channels or not."""
        return sum(c.count for c in self.containers)

    @property
    def messages(self) -> _Messages:
        """Every intact message as (log_time, container offset, index, Message), in log-time order
        (ties: file order, as ``mcap``'s reader): ``len()`` is known, iterating reads the file."""
        return _Messages(self)

    def iter_keyed(self) -> Iterator:
        """Iterate :attr:`messages` (see :func:`merge_containers`)."""
        return merge_containers(self.path, self.containers)

    @property
    def state(self) -> str | None:
        """The recorder's last status (see :func:`~gyro_instrument.recording.mcap_io.recording_state`)."""
        if not self.data_end:
            return "no summary"
        state = None
        for rec in self.metadata:
            if rec.name == STATUS_RECORD:
                state = rec.metadata.get("state")
        return state

    def metadata_record(self, name) -> dict | None:
        """The first metadata record of that name as a dict, or None."""
        for rec in self.metadata:
            if rec.name == name:
                return dict(rec.metadata)
        return None

    def damage_dicts(self, epoch_ns) -> list:
        """Every loss, this file's own and what a previous ``recover`` recorded, as JSON dicts."""
        return [d.as_dict(epoch_ns) for d in self.damaged] + [dict(d) for d in self.recorded_damage]

    def channel_counts(self) -> list:
        """[(schema or None, channel, messages)] of every known channel holding intact messages, in
        the order of their first messages (log-time order): what :meth:`records` would yield,
        counted without reading it."""
        known = [(st[1], cid, st[0]) for cid, st in self.channel_stats.items() if cid in self.channels]
        out = []
        for _, cid, n in sorted(known):
            ch = self.channels[cid]
            out.append(((self.schemas.get(ch.schema_id) if ch.schema_id else None), ch, n))
        return out

    def records(self, topics=None) -> Iterator:
        """Yield (schema, channel, message) of every intact message with a known channel, read
        from the file in log-time order (see :attr:`messages`)."""
        for _, _, _, msg in self.messages:
            ch = self.channels.get(msg.channel_id)
            if ch is None or (topics is not None and ch.topic not in topics):
                continue
            yield (self.schemas.get(ch.schema_id) if ch.schema_id else None), ch, msg
