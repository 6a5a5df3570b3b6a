"""What :func:`~gyro_instrument.recording.bag_scan.scan_bag` finds in an MCAP file: every intact
record (:class:`BagScan`) and every damaged stretch with the log-time span it held (:class:`Damage`),
and the metadata records in which ``recover`` keeps what a file lost and the recorder its status.
"""

from collections.abc import Iterator
from dataclasses import dataclass, field

from mcap.records import Header

#: metadata record in which ``recover`` keeps the damage it found (spans as JSON) and the status
#: the original file had, so that a replay of the recovered file still reports the loss
DAMAGE_RECORD = "gyro_instrument_damage"
STATUS_RECORD = "gyro_instrument_status"



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
    """What :func:`scan_bag` found. ``messages`` holds (log_time, container offset, index, Message)
    of every intact message, in log-time order (ties: file order, as ``mcap``'s reader)."""

    path: str
    size: int
    header: Header = None
    schemas: dict = field(default_factory=dict)
    channels: dict = field(default_factory=dict)
    messages: list = field(default_factory=list)
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

    def records(self, topics=None) -> Iterator:
        """Yield (schema, channel, message) of every intact message with a known channel."""
        for _, _, _, msg in self.messages:
            ch = self.channels.get(msg.channel_id)
            if ch is None or (topics is not None and ch.topic not in topics):
                continue
            yield (self.schemas.get(ch.schema_id) if ch.schema_id else None), ch, msg
