"""Reading an MCAP file that may be damaged, without ever hiding the damage.

:func:`scan_bag` reads a file record by record (the ``mcap`` library's record classes and its
``breakup_chunk``, which checks a chunk's ``uncompressed_crc``), and:

* refuses a file that is not an MCAP (empty, a directory, wrong magic) with a
  :class:`~gyro_instrument.core.errors.SceneError`;
* checks every chunk's CRC (and the data-section and summary CRCs when the writer set them);
* SKIPS a damaged chunk and keeps reading the intact chunks after it: it continues after the
  damaged record when its length is consistent (with the summary's chunk index when the summary is
  intact, else with the framing of the next record), otherwise it resynchronizes at the next
  record the summary indexes, or, when the summary is gone or damaged, by scanning forward for the
  next chunk whose CRC checks (or a metadata / data-end record that frames correctly);
* reports which log-time span each damaged stretch held: the chunk index's
  ``message_start_time``/``message_end_time`` when the summary is intact, otherwise the open
  interval between the last intact message before it and the first intact message after it;
* reads the damage a previous ``recover`` wrote into the file (metadata record
  ``gyro_instrument_damage``), so a recovered file still says what it lost.

It keeps where the intact messages are (one
:class:`~gyro_instrument.recording.scan_result.Container` per intact chunk or run of message
records, and per channel its count), not the messages: readers read them back from those
offsets in log-time order, so neither the scan nor a reader holds the bag in memory.

A file cut short (no footer: a recorder killed without its provisional end, a copy taken
mid-write) is read up to its last complete record and flagged ``truncated``; that is the
"interrupted" case, reported as a note rather than as damage.
"""

import json
import mmap
import os
import struct
import zlib
from io import BytesIO

from mcap.data_stream import ReadDataStream
from mcap.opcode import Opcode
from mcap.records import (Channel, Chunk, ChunkIndex, DataEnd, Footer, Header, Message, Metadata,
                          MetadataIndex, Schema, Statistics)
from mcap.stream_reader import CRCValidationError, breakup_chunk

from gyro_instrument.core.errors import SceneError
# the scan's result types live in scan_result; re-exported here, where the callers have found them
from gyro_instrument.recording.scan_result import DAMAGE_RECORD, STATUS_RECORD, BagScan, Container, Damage

MAGIC = b"\x89MCAP0\r\n"
_KNOWN = {int(op) for op in Opcode}
_FOOTER_LEN = 1 + 8 + 20          # opcode, length, summary_start, summary_offset_start, summary_crc
#: a run of message records outside chunks becomes a new container after this many records or
#: bytes, so that reading one back holds no more than a chunk's worth
RUN_RECORDS = 1024
RUN_BYTES = 1 << 20


def check_mcap(path, field="bag") -> None:
    """Refuse what is not an MCAP file before anything is read or written.

    Raises
    ------
    SceneError
        ``path`` is missing, a directory, empty, unreadable or does not start with the MCAP magic.
    """
    if not os.path.exists(path):
        raise SceneError(field, path, "file not found; expected an MCAP file")
    if os.path.isdir(path):
        raise SceneError(field, path, "is a directory; expected an MCAP file")
    try:
        with open(path, "rb") as fh:
            head = fh.read(len(MAGIC))
    except OSError as exc:
        raise SceneError(field, path, f"cannot be read ({exc.strerror}); expected an MCAP file") from None
    if not head:
        raise SceneError(field, path, "is empty; expected an MCAP file")
    if head != MAGIC:
        raise SceneError(field, path, f"is not an MCAP file: expected the magic {MAGIC.hex(' ')} at byte 0, "
                                      f"found {head.hex(' ')}")


def _crc32(buf, start, end, block=1 << 18) -> int:
    """CRC-32 of ``buf[start:end]`` computed block by block: never a copy of the whole range."""
    crc = 0
    for a in range(start, end, block):
        crc = zlib.crc32(buf[a:min(a + block, end)], crc)
    return crc


def _stream(data):
    return ReadDataStream(BytesIO(data))


def _framed(buf, pos, limit):
    """A plausible record header at ``pos``: a known opcode and a length inside ``limit``."""
    if pos == limit:
        return True
    if pos + 9 > limit or buf[pos] not in _KNOWN:
        return False
    (length,) = struct.unpack_from("<Q", buf, pos + 1)
    return pos + 9 + length <= limit


class _Scanner:
    def __init__(self, buf, scan):
        self.buf = buf
        self.scan = scan
        self.size = len(buf)
        self.footer = None
        self.summary_start = None
        self.chunk_index = {}        # chunk_start_offset -> (chunk_length, message start, end time) (intact summary)
        self.index_offsets = []      # record offsets the intact summary points at
        self.summary_schemas = {}
        self.summary_channels = {}
        self.raw_damage = []         # (offset, end or None, reason, "span" | "record")
        self.no_crc = 0
        self.run = None              # [t_min, pos, end, count, t_max] of the run of message records being read

    # ------------------------------------------------------------------ summary
    def read_summary(self):
        buf, size = self.buf, self.size
        fpos = size - len(MAGIC) - _FOOTER_LEN
        if fpos < len(MAGIC) or buf[size - len(MAGIC):] != MAGIC or buf[fpos] != Opcode.FOOTER:
            return
        try:
            footer = Footer.read(_stream(buf[fpos + 9:fpos + _FOOTER_LEN]))
        except Exception:
            return
        self.footer = footer
        start = footer.summary_start
        if start == 0:
            return
        if not len(MAGIC) < start <= fpos:
            self.scan.notes.append(f"footer points at a summary outside the file (byte {start}): summary ignored, "
                                   f"the data section was read record by record")
            return
        if footer.summary_crc != 0:
            crc = _crc32(buf, start, fpos + 25)
            if crc != footer.summary_crc:
                self.scan.notes.append(f"summary section (bytes {start}-{fpos + _FOOTER_LEN}) failed its CRC: "
                                       f"ignored; the data section was read record by record")
                return
        chunk_index, offsets, schemas, channels = {}, [], {}, {}
        pos = start
        try:
            while pos < fpos:
                op = buf[pos]
                (length,) = struct.unpack_from("<Q", buf, pos + 1)
                end = pos + 9 + length
                if end > fpos:
                    raise ValueError("summary record runs past the footer")
                body = buf[pos + 9:end]
                if op == Opcode.CHUNK_INDEX:
                    ci = ChunkIndex.read(_stream(body))
                    chunk_index[ci.chunk_start_offset] = (ci.chunk_length, ci.message_start_time,
                                                          ci.message_end_time)
                    offsets.append(ci.chunk_start_offset)
                elif op == Opcode.METADATA_INDEX:
                    offsets.append(MetadataIndex.read(_stream(body)).offset)
                elif op == Opcode.SCHEMA:
                    s = Schema.read(_stream(body))
                    schemas[s.id] = s
                elif op == Opcode.CHANNEL:
                    c = Channel.read(_stream(body))
                    channels[c.id] = c
                elif op == Opcode.STATISTICS:
                    Statistics.read(_stream(body))
                pos = end
        except Exception as exc:
            self.scan.notes.append(f"summary section unreadable ({exc.__class__.__name__}): ignored; the data "
                                   f"section was read record by record")
            return
        self.summary_start = start
        self.chunk_index = chunk_index
        self.index_offsets = sorted(o for o in offsets if len(MAGIC) <= o < start)
        self.summary_schemas, self.summary_channels = schemas, channels
        self.scan.summary_ok = True

    # ------------------------------------------------------------------ data section
    def _chunk(self, pos, length):
        """(records, consumed) of an intact chunk; raises on damage."""
        st = _stream(self.buf[pos + 9:pos + 9 + length])
        chunk = Chunk.read(st)
        if chunk.uncompressed_crc == 0:
            self.no_crc += 1
        return breakup_chunk(chunk, validate_crc=True), st.count

    def _valid_chunk_at(self, p, limit):
        if p + 9 > limit:
            return False
        (length,) = struct.unpack_from("<Q", self.buf, p + 1)
        if p + 9 + length > limit or length < 40:
            return False
        try:
            st = _stream(self.buf[p + 9:p + 9 + length])
            chunk = Chunk.read(st)
            if chunk.uncompressed_crc == 0 or st.count != length:
                return False
            breakup_chunk(chunk, validate_crc=True)
            return True
        except Exception:
            return False

    def _valid_record_at(self, p, limit):
        op = self.buf[p]
        if op == Opcode.CHUNK:
            return self._valid_chunk_at(p, limit)
        if not _framed(self.buf, p, limit):
            return False
        (length,) = struct.unpack_from("<Q", self.buf, p + 1)
        end = p + 9 + length
        try:
            if op == Opcode.METADATA:
                st = _stream(self.buf[p + 9:end])
                Metadata.read(st)
                return st.count == length and _framed(self.buf, end, limit)
            if op == Opcode.DATA_END:
                return length == 4 and (end == limit or (end < limit and self.buf[end] in
                                                         (Opcode.FOOTER, Opcode.SCHEMA, Opcode.CHANNEL,
                                                          Opcode.STATISTICS, Opcode.CHUNK_INDEX,
                                                          Opcode.METADATA_INDEX, Opcode.SUMMARY_OFFSET)))
        except Exception:
            return False
        return False

    def resync(self, after, limit):
        """The offset of the next trustworthy record after byte ``after`` (None: none before ``limit``)."""
        if self.scan.summary_ok:
            nxt = [o for o in self.index_offsets if o > after]
            if nxt:
                return nxt[0]
            data_end = self.summary_start - 13
            return data_end if data_end > after and self.buf[data_end] == Opcode.DATA_END else None
        buf = self.buf
        nxt = {op: buf.find(bytes([op]), after + 1, limit) for op in (Opcode.CHUNK, Opcode.METADATA,
                                                                        Opcode.DATA_END)}
        while True:
            hits = [h for h in nxt.values() if h >= 0]
            if not hits:
                return None
            p = min(hits)
            if self._valid_record_at(p, limit):
                return p
            op = buf[p]
            nxt[op] = buf.find(bytes([op]), p + 1, limit)

    def _record_ok_at_end(self, pos, length, limit):
        """Continue after a damaged record at ``pos`` only when its length is corroborated."""
        ci = self.chunk_index.get(pos)
        if ci is not None:
            return ci[0] == 9 + length
        return _framed(self.buf, pos + 9 + length, limit) and pos + 9 + length < limit

    def read_data(self) -> None:
        """Walk the data section record by record into ``self.scan`` (schemas, channels, message containers,
        metadata), resynchronising after framing damage and noting every lost span in ``raw_damage``;
        stops at the data-end record, the footer, or the end of a file cut short (``truncated``)."""
        buf, scan = self.buf, self.scan
        limit = self.size
        if self.scan.summary_ok:
            limit = self.summary_start
        elif self.footer is not None:
            limit = self.size - len(MAGIC) - _FOOTER_LEN
        pos = len(MAGIC)
        while pos < limit:
            if pos + 9 > limit or buf[pos] not in _KNOWN or \
                    pos + 9 + struct.unpack_from("<Q", buf, pos + 1)[0] > limit:
                nxt = self.resync(pos, limit)
                if nxt is None:
                    if self.footer is None:
                        scan.truncated = True          # a file cut short: read up to here
                    else:
                        self.raw_damage.append((pos, None, "unreadable records (framing lost) up to the end "
                                                           "of the data section", "span"))
                    return
                self.raw_damage.append((pos, nxt, "unreadable records (framing lost)", "span"))
                pos = nxt
                continue
            op = buf[pos]
            (length,) = struct.unpack_from("<Q", buf, pos + 1)
            end = pos + 9 + length
            if op == Opcode.CHUNK:
                pos = self._read_chunk(pos, length, end, limit)
                if pos is None:
                    return
                continue
            if op == Opcode.DATA_END:
                self._data_end(pos, buf[pos + 9:end])
                return
            if op == Opcode.FOOTER:
                return
            self._read_record(op, pos, buf[pos + 9:end], length, end)
            pos = end
        scan.truncated = scan.truncated or (self.footer is None and not scan.data_end)

    def _read_chunk(self, pos, length, end, limit):
        """Read the chunk record at ``pos`` (CRC checked) into the scan; returns where the next record
        starts, or None when a damaged chunk's length cannot be trusted and no record follows."""
        scan = self.scan
        try:
            records, consumed = self._chunk(pos, length)
        except Exception as exc:
            reason = ("chunk CRC mismatch" if isinstance(exc, CRCValidationError)
                      else f"chunk undecodable ({exc.__class__.__name__})")
            if self._record_ok_at_end(pos, length, limit):
                self.raw_damage.append((pos, end, reason, "span"))
                return end
            nxt = self.resync(pos, limit)
            self.raw_damage.append((pos, nxt, reason + "; record length untrustworthy", "span"))
            return nxt
        count, t_min, t_max = 0, None, None
        for i, rec in enumerate(records):
            if isinstance(rec, Schema):
                scan.schemas[rec.id] = rec
            elif isinstance(rec, Channel):
                scan.channels[rec.id] = rec
            elif isinstance(rec, Message):
                t = rec.log_time
                self._count(rec.channel_id, (t, pos, i))
                count += 1
                t_min = t if t_min is None or t < t_min else t_min
                t_max = t if t_max is None or t > t_max else t_max
        if count:
            scan.containers.append(Container(t_min, pos, length, True, count, t_max))
        if consumed != length and not _framed(self.buf, end, limit):
            end = pos + 9 + consumed       # a flipped length on an intact chunk
        return end

    def _data_end(self, pos, body):
        """The data-end record: check the data section's CRC when it carries one."""
        scan = self.scan
        try:
            de = DataEnd.read(_stream(body))
            if de.data_section_crc and _crc32(self.buf, 0, pos) != de.data_section_crc:
                scan.notes.append("data section failed its CRC (data-end record)"
                                  + ("" if self.raw_damage else ": the damage is outside every chunk's "
                                     "contents (record headers, metadata or indexes); every chunk checked"))
        except Exception:
            pass
        scan.data_end = True

    def _read_record(self, op, pos, body, length, end):
        """A record outside chunks (header, schema, channel, message, metadata; others skipped); an
        unreadable one is noted in ``raw_damage``."""
        scan = self.scan
        try:
            st = _stream(body)
            if op == Opcode.HEADER:
                scan.header = Header.read(st)
            elif op == Opcode.SCHEMA:
                s = Schema.read(st)
                scan.schemas[s.id] = s
            elif op == Opcode.CHANNEL:
                c = Channel.read(st)
                scan.channels[c.id] = c
            elif op == Opcode.MESSAGE:
                self._loose_message(Message.read(st, length), pos, end)
            elif op == Opcode.METADATA:
                scan.metadata.append(Metadata.read(st))
        except Exception as exc:
            self.raw_damage.append((pos, end, f"{Opcode(op).name.lower()} record unreadable "
                                              f"({exc.__class__.__name__})", "record"))

    def _count(self, cid, key):
        """Count a message of channel ``cid`` whose (log_time, pos, index) is ``key``."""
        st = self.scan.channel_stats.get(cid)
        if st is None:
            self.scan.channel_stats[cid] = [1, key, key[0]]
            return
        st[0] += 1
        st[1] = min(st[1], key)
        st[2] = max(st[2], key[0])

    def _loose_message(self, msg, pos, end):
        """A message record outside chunks (bytes ``pos`` .. ``end``): counted into the run of
        adjacent message records it continues, or a new run."""
        t = msg.log_time
        self._count(msg.channel_id, (t, pos, 0))
        run = self.run
        if run is not None and run[2] == pos and run[3] < RUN_RECORDS and end - run[1] <= RUN_BYTES:
            run[0], run[2], run[3], run[4] = min(run[0], t), end, run[3] + 1, max(run[4], t)
            return
        self._end_run()
        self.run = [t, pos, end, 1, t]

    def _end_run(self):
        if self.run is not None:
            t_min, pos, end, count, t_max = self.run
            self.scan.containers.append(Container(t_min, pos, end - pos, False, count, t_max))
            self.run = None

    # ------------------------------------------------------------------ spans
    def spans(self):
        scan = self.scan
        for offset, end, reason, kind in self.raw_damage:
            d = Damage(offset=offset, length=None if end is None else end - offset, reason=reason)
            scan.damaged.append(d)
            if kind != "span":         # a metadata or schema record: no messages in it
                continue
            hi = self.size if end is None else end
            idx = [(o, ci) for o, ci in self.chunk_index.items() if offset <= o < hi]
            if self.scan.summary_ok and idx:
                d.lost_from_ns = min(ci[1] for _, ci in idx)
                d.lost_to_ns = max(ci[2] for _, ci in idx)
                d.span_from = "chunk index"
                d.chunk_offsets = tuple(sorted(o for o, _ in idx))
            elif self.scan.summary_ok and not d.reason.startswith("chunk"):
                d.reason += "; the summary's index puts no chunk in it"    # message indexes only
            else:
                # a container lies wholly before or after a damaged stretch (runs end at anything unread)
                before = [c.t_max for c in scan.containers if c.pos < offset]
                after = [c.t_min for c in scan.containers if c.pos >= hi]
                d.lost_from_ns = max(before) if before else None
                d.lost_to_ns = min(after) if after else None
                d.span_from = "neighbouring messages"

    def finish(self):
        scan = self.scan
        for sid, s in self.summary_schemas.items():
            scan.schemas.setdefault(sid, s)
        for cid, c in self.summary_channels.items():
            scan.channels.setdefault(cid, c)
        self._end_run()
        self.spans()
        orphans = [st for cid, st in scan.channel_stats.items() if cid not in scan.channels]
        if orphans:
            scan.damaged.append(Damage(offset=None, length=None, lost_from_ns=min(st[1][0] for st in orphans),
                                       lost_to_ns=max(st[2] for st in orphans), span_from="neighbouring messages",
                                       reason=f"{sum(st[0] for st in orphans)} intact messages on channels "
                                              f"defined only in a damaged record"))
        if self.no_crc:
            scan.notes.append(f"{self.no_crc} chunks carry no CRC (written without one): their contents could "
                              f"not be checked")
        for rec in scan.metadata:
            if rec.name == DAMAGE_RECORD:
                try:
                    scan.recorded_damage += [dict(d, span_from=d.get("span_from") or "recorded by recover",
                                                  before_recovery=True)
                                             for d in json.loads(rec.metadata.get("damaged", "[]"))]
                    scan.recorded_notes += list(json.loads(rec.metadata.get("notes", "[]")))
                except (ValueError, TypeError, AttributeError):
                    scan.notes.append(f"a {DAMAGE_RECORD} record is unreadable: data was lost before a recovery, "
                                      f"span unknown")
                scan.recorded_status = rec.metadata.get("status", scan.recorded_status)


def scan_bag(path, field="bag") -> "BagScan":
    """Read every intact record of an MCAP file, checking every CRC; see the module docstring.

    The result keeps where the intact messages are, not the messages (see
    :class:`~gyro_instrument.recording.scan_result.BagScan`): its memory grows with the number of
    chunks (one :class:`~gyro_instrument.recording.scan_result.Container` each), while scanning
    holds one chunk at a time.

    Parameters
    ----------
    path : str
        The ``.mcap`` file.
    field : str
        Name used in the error for a file that is not an MCAP (``bag``, ``--out`` ...).

    Returns
    -------
    BagScan

    Raises
    ------
    SceneError
        The file is missing, a directory, empty or not an MCAP (no magic at byte 0).
    """
    check_mcap(path, field)
    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        buf = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
    try:
        scan = BagScan(path=path, size=size)
        sc = _Scanner(buf, scan)
        sc.read_summary()
        sc.read_data()
        sc.finish()
    finally:
        # drop every view of the map before closing it (records hold bytes copies, never views)
        sc = None
        buf.close()
    return scan


__all__ = ["DAMAGE_RECORD", "MAGIC", "STATUS_RECORD", "BagScan", "Damage", "check_mcap", "scan_bag"]
