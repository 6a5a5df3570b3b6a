"""MCAP in rosbag2's layout, written and read without rclpy.

Writer: profile ``ros2``; one schema per type (encoding ``ros2msg``, the concatenated definition of
:mod:`.definitions`); channels with message encoding ``cdr`` and metadata
``offered_qos_profiles`` (a YAML *list*, as rosbag2 jazzy writes it) and ``topic_type_hash``;
zstd-compressed chunks, indexed summary. Log time = receive time in sim time; the
publish time is written equal to it so files are deterministic. A metadata record
``gyro_instrument`` holds the scene (YAML), the seed and the command, for ``replay``.

The file on disk is a complete, indexed MCAP after every commit (see :class:`BagWriter`), so a
recorder killed with SIGKILL leaves a file every reader opens, up to its last commit.

Reader: ``read_messages`` yields (topic, type, log_time_ns, cdr bytes) in log-time order, every
chunk's CRC checked (:mod:`.bag_scan`): a damaged chunk is skipped, never read, and the intact
chunks after it are; a file truncated some other way (no footer) is read up to its last complete
record. The scan keeps where the intact messages are, not the messages: every reader here reads
them back from the file as it yields them, so memory does not grow with the bag (a few hundred
bytes per chunk for the scan's index, plus the chunks that overlap in log time). ``recover``
rewrites only intact records and records what was lost in the new file.
"""

import copy
import heapq
import json
import os
import struct
import time
from collections.abc import Iterator

from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.reader import make_reader
from mcap.records import MessageIndex
from mcap.writer import CompressionType, Writer

# the file under the writer (and its error) are mcap_file's, re-exported here
from gyro_instrument.recording.mcap_file import DiskFull, Sink, TailKeepingFile  # noqa: F401
from gyro_instrument.recording.bag_scan import DAMAGE_RECORD, STATUS_RECORD, scan_bag
from gyro_instrument.recording.definitions import concatenated_definition, type_hash

_INF = "    sec: 9223372036\n    nsec: 854775807\n"
#: a Message record's opcode, length, channel id, sequence, log time and publish time (MCAP spec, "Message")
_MESSAGE_HEAD = struct.Struct("<BQHIQQ").pack


class _MessageIndex(MessageIndex):
    """mcap's MessageIndex written with one pack (its own ``write`` packs each field apart)."""

    def write(self, stream) -> None:
        stream.start_record(Opcode.MESSAGE_INDEX)
        stream.write(struct.pack(f"<HI{2 * len(self.records)}Q", self.channel_id, 16 * len(self.records),
                                 *(v for row in self.records for v in row)))
        stream.finish_record()


def _add_messages(w, rows) -> None:
    """``Writer.add_message`` for each of ``rows`` ((log time, _, channel id, publish time, data,
    sequence), in order) into the chunk in progress, in one write: the same bytes, message index and
    statistics as one call per message, which cost 2/3 of the recorder's writing (issue 37 item 6;
    ``tests/test_mcap_io.py`` holds the two byte for byte). The chunk builder is mcap's own (its
    ``record_writer`` buffer, ``message_indices``); ``chunk_size`` is never reached (:class:`BagWriter`
    closes chunks itself)."""
    cb, stats = w._Writer__chunk_builder, w._Writer__statistics
    buf = cb.record_writer._buffer
    at = buf.tell()
    parts, counts, indices = [], stats.channel_message_counts, cb.message_indices
    for t, _, cid, pt, data, seq in rows:
        index = indices.get(cid)
        if not index:
            index = indices[cid] = _MessageIndex(channel_id=cid, records=[])
        index.records.append((t, at))
        head = _MESSAGE_HEAD(Opcode.MESSAGE, 22 + len(data), cid, seq, t, pt)
        parts += (head, data)
        at += len(head) + len(data)
        counts[cid] += 1
    buf.write(b"".join(parts))
    lo, hi = min(r[0] for r in rows), max(r[0] for r in rows)
    cb.message_start_time = lo if cb.num_messages == 0 else min(cb.message_start_time, lo)
    cb.message_end_time = max(cb.message_end_time, hi)
    cb.num_messages += len(rows)
    stats.message_start_time = lo if stats.message_count == 0 else min(stats.message_start_time, lo)
    stats.message_end_time = max(stats.message_end_time, hi)
    stats.message_count += len(rows)


def qos_yaml(reliable=True, keep_all=True, depth=0, transient_local=False) -> str:
    """rosbag2 (jazzy, metadata version 9) encoding of one offered QoS profile, as a YAML list."""
    return ("- history: {h}\n  depth: {d}\n  reliability: {r}\n  durability: {du}\n  deadline:\n{inf}"
            "  lifespan:\n{inf}  liveliness: 1\n  liveliness_lease_duration:\n{inf}"
            "  avoid_ros_namespace_conventions: false\n").format(
        h=2 if keep_all else 1, d=depth, r=1 if reliable else 2, du=1 if transient_local else 2,
        inf=_INF)



class BagWriter:
    """Write ROS 2 CDR messages to an MCAP file in rosbag2's layout, valid on disk at every commit.

    Chunks are closed by the writer itself (every ``chunk_size`` bytes of messages, or every
    ``commit_period_s`` of wall time, whichever comes first). Each commit writes the chunk and
    then a provisional summary, footer and end magic, with a metadata record
    ``gyro_instrument_status`` = ``{"state": "recording"}``; :meth:`close` writes the final one
    with ``state`` = ``complete`` (or the state given). So a killed recorder (SIGKILL, power cut of
    the process) leaves an indexed MCAP that any reader (``mcap``, ``rosbags``, ``ros2 bag``)
    opens, holding every message up to the last commit, and :func:`recording_state` tells that it
    was cut short.

    Parameters
    ----------
    path : str
        Output ``.mcap`` path.
    chunk_size : int
        Bytes of messages per chunk.
    commit_period_s : float
        Longest wall time between commits: at most this much recording is lost on SIGKILL.
    """

    def __init__(self, path, chunk_size=256 * 1024, compression="zstd", commit_period_s=0.5) -> None:
        self.path = path
        self.failed = None
        self._fh = TailKeepingFile(path)
        comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[compression]
        # chunks are closed here (flush), never by mcap's own size test
        self._w = Writer(self._fh, chunk_size=1 << 62, compression=comp, enable_data_crcs=True)
        self._w.start(profile="ros2", library="gyro_instrument")
        self._schemas = {}
        self._channels = {}
        self.counts = {}
        self.closed = False
        self.chunk_size = int(chunk_size)
        self.commit_period_s = float(commit_period_s)
        self._bytes = 0
        self._chunk = []       # messages of the chunk in progress, added to the MCAP writer in log-time order
        self._last_commit = time.monotonic()
        self.commits = 0
        self._last = None      # (writer snapshot, data end, counts) at the last commit that reached the disk
        self._commit()

    def add_topic(self, topic, type_name, qos=None) -> int:
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

    def write(self, topic, log_time_ns, data, publish_time_ns=None) -> None:
        """Append one CDR message on a registered topic (nothing once closed)."""
        if self.closed:
            return
        cid = self._channels[topic]
        data = bytes(data)
        t = int(log_time_ns)
        self._chunk.append((t, len(self._chunk), cid, int(t if publish_time_ns is None else publish_time_ns),
                            data, self.counts[topic]))
        self.counts[topic] += 1
        self._bytes += len(data) + 31          # message record overhead
        if self._bytes >= self.chunk_size or time.monotonic() - self._last_commit >= self.commit_period_s:
            self.commit()

    def pending(self) -> bool:
        """True when messages were written since the last commit (a SIGKILL now would lose them)."""
        return self._bytes > 0

    def since_commit_s(self) -> float:
        """Wall time since the last commit, s (a bound on the age of what a SIGKILL would lose)."""
        return time.monotonic() - self._last_commit

    def add_metadata(self, name, data) -> None:
        """A metadata record (str -> str mapping), committed to disk at once (nothing once closed)."""
        if self.closed:
            return
        self._add_chunk()
        self._w.add_metadata(name, {str(k): str(v) for k, v in data.items()})
        self.commit()

    def commit(self) -> None:
        """Close the chunk in progress and make the file on disk a complete MCAP holding it.

        The chunk's messages are added in log-time order (a message that arrived late is written
        at its own log time; the chunk index records each chunk's time range, so readers that read
        in log-time order merge overlapping chunks)."""
        if self.closed:
            return
        self._add_chunk()
        self._w.flush()
        self._commit()

    def _add_chunk(self):
        if self._chunk:
            self._chunk.sort()
            _add_messages(self._w, self._chunk)
            self._chunk = []

    def _commit(self):
        self._write_out(self._provisional_end())
        self._last = self._next_last          # what the file on disk holds now
        self._bytes = 0
        self._last_commit = time.monotonic()
        self.commits += 1

    def _snapshot(self):
        """A copy of the MCAP writer as it is now (right after a flush: no chunk open) that the real
        one's later records do not reach: every list and mapping ``add_metadata``/``finish`` read or
        change is copied, the chunk builder dropped."""
        w = copy.copy(self._w)
        stats = copy.copy(self._w._Writer__statistics)
        stats.channel_message_counts = dict(stats.channel_message_counts)
        w._Writer__statistics = stats
        for name in ("summary_offsets", "metadata_indexes", "chunk_indices", "attachment_indexes"):
            setattr(w, f"_Writer__{name}", list(getattr(self._w, f"_Writer__{name}")))
        for name in ("schemas", "channels"):
            setattr(w, f"_Writer__{name}", dict(getattr(self._w, f"_Writer__{name}")))
        w._Writer__chunk_builder = None
        w._Writer__record_builder = RecordBuilder()
        w._Writer__should_close = False
        return w

    @staticmethod
    def _end_of(w, at, status) -> bytes:
        """What ``finish`` on the snapshot ``w`` writes at file offset ``at``, after ``status``."""
        sink = Sink(at)
        w._Writer__stream = sink
        w.add_metadata(STATUS_RECORD, status)
        w.finish()
        return bytes(sink.buf)

    def _provisional_end(self):
        """What ``Writer.finish`` would write now (status record ``recording``, data end, summary,
        footer, magic), computed on a copy of the writer so the real one carries on. The status is
        padded (``reserve``) so that the disk-full status that may replace it later
        (:meth:`_failed_end`) fits in the bytes it has on disk."""
        self._next_last = (self._snapshot(), self._fh.tell(), dict(self.counts))
        return self._end_of(self._snapshot(), self._fh.tell(),
                            {"state": "recording", "messages": str(sum(self.counts.values())),
                             "reserve": " " * self.RESERVE})

    #: spaces in the provisional status record: room for the disk-full status's reason
    RESERVE = 320

    def _failed_end(self, exc) -> bytes:
        """The file's end as the last commit left it, with the status ``incomplete`` and the reason
        (the disk full) instead of ``recording``: no longer than that commit's end."""
        w, at, counts = self._last
        reason = f"disk full: {exc.cause.strerror or 'write failed'} (errno {exc.errno}); the messages after the " \
                 f"last commit are lost"
        return self._end_of(w, at, {"state": "incomplete", "messages": str(sum(counts.values())),
                                    "reason": reason[:self.RESERVE]})

    def committed(self) -> tuple:
        """(per-topic message counts, first and last log time ns or None) of what the file held at its
        last commit (what it holds after a full disk)."""
        w, _, counts = self._last
        st = w._Writer__statistics
        if not st.message_count:
            return counts, None, None
        return counts, st.message_start_time, st.message_end_time

    def close(self, state="complete", **fields) -> None:
        """Finish the file: final status record (``state``, ``messages`` and any ``fields``, e.g. the
        per-topic counts of an ``incomplete`` recording), summary, indexes, footer."""
        if not self.closed:
            status = {"state": state, "messages": str(sum(self.counts.values()))}
            status.update({str(k): str(v) for k, v in fields.items()})
            self._add_chunk()
            self._w.add_metadata(STATUS_RECORD, status)
            self._w.finish()
            self._write_out(b"")
            self._fh.close()
            self.closed = True

    def _write_out(self, tail):
        """Commit to disk; on a full disk the file is left as the last commit made it (see
        :meth:`TailKeepingFile.commit`), this writer is closed (``failed``) and DiskFull raised."""
        try:
            self._fh.commit(tail)
        except DiskFull as exc:
            self.failed = exc
            self.closed = True
            try:                   # the status says why the file ends here, where it fits
                if self._last is not None:
                    self.counts = dict(self._last[2])
                    self._fh.rewrite_tail(self._failed_end(exc))
            except OSError:
                pass               # the last commit's end stays: status 'recording'
            self._fh.close()
            raise


def recording_state(path, scan=None) -> str | None:
    """The recorder's last status: ``complete``, ``recording`` (cut short after its last commit),
    ``no summary`` (an unindexed prefix, e.g. from an older writer), or None (no status record:
    a file written by another tool or before status records).

    Raises
    ------
    SceneError
        ``path`` is not an MCAP file (see :func:`~gyro_instrument.recording.bag_scan.check_mcap`).
    """
    return (scan or scan_bag(path)).state


def iter_records(path, topics=None, scan=None) -> Iterator:
    """Yield (schema, channel, message) of every intact message in log-time order (ties in file
    order), every chunk's CRC checked: a damaged chunk is skipped and the intact chunks after it are
    read (:func:`~gyro_instrument.recording.bag_scan.scan_bag` says what was lost); a file cut
    short is read up to its last complete record.

    Raises
    ------
    SceneError
        ``path`` is not an MCAP file.
    """
    yield from (scan or scan_bag(path)).records(topics)


def read_messages(path, topics=None, scan=None) -> Iterator:
    """Yield (topic, type_name, log_time_ns, cdr_bytes); see :func:`iter_records`."""
    for schema, channel, message in iter_records(path, topics, scan):
        yield channel.topic, schema.name if schema else "", message.log_time, message.data


def play_plan(path, scan) -> list:
    """How :func:`stream_messages` reads each file of a bag: [(file, None)] for a file found intact
    (summary read, no damage, no note: read chunk by chunk by the MCAP reader, in log-time order) or
    [(file, its scan)] for one that is not (its intact chunks and records read back from the
    offsets the scan kept, skipping the damaged ones, in log-time order)."""
    files = getattr(scan, "files", None) or [path]
    scans = getattr(scan, "file_scans", None) or [scan]
    return [(f, None if (s.summary_ok and s.data_end and not s.damaged and not s.truncated and not s.notes) else s)
            for f, s in zip(files, scans)]


def _file_messages(k, path, scan):
    if scan is not None:
        for i, (tp, ty, t, data) in enumerate(read_messages(path, scan=scan)):
            yield t, k, i, tp, ty, data
        return
    with open(path, "rb") as fh:
        for i, (schema, channel, message) in enumerate(make_reader(fh).iter_messages(log_time_order=True)):
            yield message.log_time, k, i, channel.topic, schema.name if schema else "", message.data


def stream_messages(plan) -> Iterator:
    """Yield (topic, type_name, log_time_ns, cdr_bytes) of every intact message of a bag in log-time
    order (ties: file order), as :func:`read_messages` does, reading the files of ``plan``
    (:func:`play_plan`) as they are needed: memory holds the chunks being read (those overlapping
    in log time), not the bag."""
    for t, _, _, tp, ty, data in heapq.merge(*(_file_messages(k, f, s) for k, (f, s) in enumerate(plan))):
        yield tp, ty, t, data


def damage_record(scan, epoch_ns) -> dict:
    """The ``gyro_instrument_damage`` metadata a recovered file carries: every lost span (this
    file's and any a previous recovery recorded) as JSON, the notes, and the status the original had."""
    notes = list(scan.recorded_notes) + list(scan.notes)
    if scan.truncated:
        notes.append("the original was cut short (no summary): whatever followed its last complete record is lost")
    return {"damaged": json.dumps(scan.damage_dicts(epoch_ns)), "notes": json.dumps(notes),
            "status": str(scan.recorded_status or scan.state), "source": os.path.basename(scan.path)}


def _write_intact(fo, scan, lossy, epoch_ns) -> int:
    """Write to the open binary file ``fo`` a complete, indexed (ZSTD chunks, data CRCs) MCAP of
    what ``scan`` found intact: its schemas and channels, its messages (read back as they are
    written) and its metadata, the old damage record replaced by a fresh :func:`damage_record` when
    ``lossy``; returns the number of messages written."""
    w = Writer(fo, compression=CompressionType.ZSTD, enable_data_crcs=True)
    w.start(profile=scan.header.profile if scan.header else "ros2", library="gyro_instrument recover")
    schema_ids, channel_ids = {}, {}
    for sid in sorted(scan.schemas):
        s = scan.schemas[sid]
        schema_ids[sid] = w.register_schema(s.name, s.encoding, s.data)
    for cid in sorted(scan.channels):
        c = scan.channels[cid]
        channel_ids[cid] = w.register_channel(c.topic, c.message_encoding, schema_ids.get(c.schema_id, 0),
                                              dict(c.metadata))
    for rec in scan.metadata:
        if rec.name != DAMAGE_RECORD:       # merged into the new one below
            w.add_metadata(rec.name, dict(rec.metadata))
    n = 0
    for _, channel, m in scan.records():
        w.add_message(channel_ids[m.channel_id], m.log_time, m.data, m.publish_time, m.sequence)
        n += 1
    if lossy:
        w.add_metadata(DAMAGE_RECORD, damage_record(scan, epoch_ns))
    w.finish()
    return n


def recover(damaged, out, scan=None, epoch_ns=None) -> tuple:
    """Rewrite a recording that is cut short (no summary/footer) or damaged (chunks failing their
    CRC, a broken summary) into a complete, indexed MCAP holding only what is intact: the schemas
    and channels, every message of every chunk whose CRC checks, and the metadata. Damaged bytes
    are never copied, so no fresh CRC vouches for them.

    When anything was lost (a damaged stretch, a cut-short tail, or damage an earlier recovery
    recorded) the new file carries a metadata record ``gyro_instrument_damage`` with the lost
    log-time spans, the notes and the status the original had, so a replay of the recovered file
    still reports the loss.

    The file is written to a temporary name beside ``out`` and renamed over it at the end.

    Parameters
    ----------
    damaged, out : str
        Input and output paths (the caller checks that they are different files).
    scan : BagScan, optional
        The input already scanned.
    epoch_ns : int, optional
        Time origin for the recorded spans (default: the scene epoch ``EPOCH_NS``).

    Returns
    -------
    (int, BagScan)
        The number of messages written and what the scan found.

    Raises
    ------
    SceneError
        The input is not an MCAP, or holds no intact message (nothing is written then).
    """
    import tempfile
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.core.scene import EPOCH_NS
    epoch_ns = EPOCH_NS if epoch_ns is None else epoch_ns
    scan = scan or scan_bag(damaged)
    if not any(n for _, _, n in scan.channel_counts()):
        lost = f"; {len(scan.damaged)} damaged stretches" if scan.damaged else ""
        raise SceneError("bag", damaged, f"holds no intact message{lost}: nothing recovered, nothing written")
    lossy = bool(scan.damaged or scan.truncated or scan.notes or any(r.name == DAMAGE_RECORD for r in scan.metadata))
    directory = os.path.dirname(os.path.abspath(out))
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{os.path.basename(out)}.", suffix=".partial")
    try:
        with os.fdopen(fd, "wb") as fo:
            n = _write_intact(fo, scan, lossy, epoch_ns)
        os.chmod(tmp, 0o644)
        os.replace(tmp, out)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return n, scan
