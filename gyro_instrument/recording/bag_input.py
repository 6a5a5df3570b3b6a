"""Reading rosbag2's directory layout: a bare ``.mcap``, a bag directory (``metadata.yaml`` plus one
or more ``.mcap`` files) or a split bag, read as one (:func:`bag_files`, :func:`scan_path`).

Every file is read through :func:`~gyro_instrument.recording.bag_scan.scan_bag`, so every CRC is
checked and every loss reported (with the file it is in). A directory without ``metadata.yaml``
(a recording killed before it was written, or a copy that lost it) is read from the ``.mcap``
files found in it, in split order (:func:`split_order`), with a note; so is a ``.mcap`` of the
directory that the ``metadata.yaml`` does not list. Writing is :mod:`.bag_layout`'s.
"""

import dataclasses
import heapq
import os
import re
from collections.abc import Iterator

import yaml

from gyro_instrument.core.errors import SceneError
from gyro_instrument.recording.bag_scan import STATUS_RECORD, BagScan, check_mcap, scan_bag

#: the file of a bag directory that lists its splits (rosbag2's)
METADATA = "metadata.yaml"


def split_order(names) -> list:
    """File names of one bag in split order: by the numeric index rosbag2 puts in them, compared as
    numbers (0, 1, ..., 10, 11, never lexically) — a trailing ``_<n>.mcap`` (``bag_0.mcap``, jazzy and
    earlier) or a leading ``<n>_`` (``0_bag_2025_12_17-10_00_00.mcap``, the index+name+timestamp names
    of later rosbag2) — whichever numbers the files apart; by name when neither does."""
    names = list(names)

    def lead(n):
        m = re.match(r"(\d+)_", os.path.basename(n))
        return int(m.group(1)) if m else None

    def trail(n):
        m = re.search(r"_(\d+)\.mcap$", n)
        return int(m.group(1)) if m else None
    for key in (lead, trail):
        ks = [key(n) for n in names]
        if None not in ks and len(set(ks)) == len(ks):
            return [n for _, n in sorted(zip(ks, names))]
    for key in (trail, lead):
        if any(key(n) is not None for n in names):
            return sorted(names, key=lambda n: (key(n) is None, key(n) or 0, n))
    return sorted(names)


def _listed_files(path, field, found, notes):
    """The files of the rosbag2 bag directory ``path`` as its ``metadata.yaml`` lists them, then any
    ``.mcap`` file it does not list (``found``, noted in ``notes``), in split order.

    Raises :class:`SceneError` (naming ``field``) for a metadata file that does not parse or is not
    a rosbag2 one, a storage other than mcap, rosbag2 compression, listed files that are missing,
    or no file at all.
    """
    meta_path = os.path.join(path, METADATA)
    try:
        with open(meta_path, encoding="utf-8") as fh:
            doc = yaml.safe_load(fh)
        info = doc["rosbag2_bagfile_information"]
        listed = [os.path.basename(str(p)) for p in info.get("relative_file_paths") or []]
        storage = info.get("storage_identifier", "mcap")
        if storage in ("", None) and listed and all(n.endswith(".mcap") for n in listed):
            storage = "mcap"      # empty (a reindexed Humble bag): the files say MCAP
        mode = str(info.get("compression_mode") or "").lower()
    except (OSError, yaml.YAMLError, TypeError, KeyError, AttributeError) as exc:
        raise SceneError(field, path, f"{METADATA} is not a rosbag2 metadata file "
                                      f"({exc.__class__.__name__})") from None
    if storage != "mcap":
        raise SceneError(field, path, f"{METADATA} names storage '{storage}'; only mcap is read "
                                      f"(convert with 'ros2 bag convert')")
    if mode not in ("", "none"):
        raise SceneError(field, path, f"{METADATA} says compression_mode '{mode}'; only uncompressed bag "
                                      f"files are read (MCAP chunk compression is fine)")
    missing = [n for n in listed if not os.path.isfile(os.path.join(path, n))]
    if missing:
        raise SceneError(field, path, f"{METADATA} names missing files: {', '.join(missing)}")
    extra = [n for n in found if n not in listed]
    if extra:
        notes.append(f"{', '.join(extra)} not listed in {METADATA} (a recording killed before it was "
                     f"rewritten?): read too")
    names = list(listed) + split_order(extra)
    if not names:
        raise SceneError(field, path, f"is a directory with no bag in it ({METADATA} lists no file and "
                                      f"there is no .mcap file)")
    return [os.path.join(path, n) for n in names]


def bag_files(path, field="bag") -> tuple:
    """The ``.mcap`` files of a bag, in order, and what was noticed on the way.

    Parameters
    ----------
    path : str
        A bare ``.mcap`` file, or a rosbag2 bag directory (``metadata.yaml`` + ``.mcap`` files).

    Returns
    -------
    files : list of str
    notes : list of str

    Raises
    ------
    SceneError
        Missing path; a directory with no bag in it; a ``metadata.yaml`` that does not parse, is
        not a rosbag2 one, names a storage other than mcap, uses rosbag2 file/message compression,
        or names files that are missing; a file that is not an MCAP.
    """
    if not os.path.exists(path):
        raise SceneError(field, path, "not found; expected an MCAP file or a rosbag2 bag directory")
    if not os.path.isdir(path):
        check_mcap(path, field)
        return [path], []
    found = split_order(n for n in os.listdir(path) if n.endswith(".mcap") and os.path.isfile(os.path.join(path, n)))
    meta_path = os.path.join(path, METADATA)
    notes = []
    if not os.path.exists(meta_path):
        if not found:
            raise SceneError(field, path, "is a directory with no bag in it (no metadata.yaml, no .mcap file); "
                                          "expected an MCAP file or a rosbag2 bag directory")
        notes.append(f"no {METADATA}: read the {len(found)} .mcap file(s) found, in the order of the split index "
                     f"in their names ({', '.join(found)})")
        files = [os.path.join(path, n) for n in found]
    else:
        files = _listed_files(path, field, found, notes)
    good = []
    for f in files:
        try:
            check_mcap(f, field)
            good.append(f)
        except SceneError as exc:
            # an empty or cut split (a full disk, a copy stopped early) is skipped; the rest is read
            notes.append(f"{os.path.basename(f)} skipped: {exc.valid}")
    if not good:
        raise SceneError(field, path, f"holds no readable MCAP file ({'; '.join(notes[-len(files):])})")
    return good, notes


def bag_inputs(path) -> tuple:
    """Every path a command reads for the bag ``path`` (the directory and its files), for the
    never-write-over-an-input checks; a missing or bad bag gives just ``path``."""
    try:
        files, _ = bag_files(path)
    except SceneError:
        return (path,)
    return (path, *files) if os.path.isdir(path) else (path,)


@dataclasses.dataclass
class BagSetScan(BagScan):
    """A bag directory read file by file (each one CRC-checked by ``scan_bag``) and merged:
    schemas and channels renumbered across files (``channel_maps``: per file, its channel id ->
    the merged one), messages in log-time order (ties: file order; read back file by file as
    they are iterated, see :meth:`iter_keyed`), the metadata records of every file (repeats
    dropped; status records of the last file), losses and notes of every file naming the file."""

    files: list = dataclasses.field(default_factory=list)
    file_scans: list = dataclasses.field(default_factory=list)
    channel_maps: list = dataclasses.field(default_factory=list)

    @property
    def message_count(self) -> int:
        return sum(s.message_count for s in self.file_scans)

    def iter_keyed(self) -> Iterator:
        """(log_time, (file index, container offset), index, Message) of every intact message of
        every file, channels renumbered, in log-time order (ties: file order); each file is read
        container by container (:meth:`BagScan.iter_keyed`)."""
        def one(k, scan, cmap):
            for t, pos, i, msg in scan.iter_keyed():
                if msg.channel_id in cmap:
                    msg = dataclasses.replace(msg, channel_id=cmap[msg.channel_id])
                yield t, (k, pos), i, msg
        return heapq.merge(*(one(k, s, cmap) for k, (s, cmap) in enumerate(zip(self.file_scans,
                                                                               self.channel_maps))))

    def damage_dicts(self, epoch_ns) -> list:
        out = []
        for f, s in zip(self.files, self.file_scans):
            out += [dict(d, file=os.path.basename(f)) for d in s.damage_dicts(epoch_ns)]
        return out


def _merge(path, files, scans, notes):
    merged = BagSetScan(path=path, size=sum(s.size for s in scans), files=list(files), file_scans=list(scans))
    merged.header = next((s.header for s in scans if s.header is not None), None)
    schema_ids, channel_ids = {}, {}
    seen_meta = set()
    many = len(files) > 1
    for k, (f, s) in enumerate(zip(files, scans)):
        base = os.path.basename(f)
        smap, cmap = {}, {}
        for sid, sc in s.schemas.items():
            key = (sc.name, sc.encoding, bytes(sc.data))
            if key not in schema_ids:
                schema_ids[key] = len(schema_ids) + 1
                merged.schemas[schema_ids[key]] = dataclasses.replace(sc, id=schema_ids[key])
            smap[sid] = schema_ids[key]
        for cid, ch in s.channels.items():
            sid = smap.get(ch.schema_id, 0)
            key = (ch.topic, ch.message_encoding, sid, tuple(sorted(ch.metadata.items())))
            if key not in channel_ids:
                channel_ids[key] = len(channel_ids) + 1
                merged.channels[channel_ids[key]] = dataclasses.replace(ch, id=channel_ids[key], schema_id=sid)
            cmap[cid] = channel_ids[key]
        merged.channel_maps.append(cmap)
        for cid, (n, (t, pos, i), t_max) in s.channel_stats.items():
            st = merged.channel_stats.setdefault(cmap.get(cid, cid), [0, (t, (k, pos), i), t_max])
            st[0] += n
            st[1], st[2] = min(st[1], (t, (k, pos), i)), max(st[2], t_max)
        last = k == len(files) - 1
        for rec in s.metadata:
            if rec.name == STATUS_RECORD:
                if last:
                    merged.metadata.append(rec)
                continue
            key = (rec.name, tuple(sorted(rec.metadata.items())))
            if key not in seen_meta:
                seen_meta.add(key)
                merged.metadata.append(rec)
        merged.damaged += s.damaged
        merged.recorded_damage += s.recorded_damage
        merged.recorded_notes += [f"{base}: {n}" if many else n for n in s.recorded_notes]
        merged.notes += [f"{base}: {n}" if many else n for n in s.notes]
        if s.recorded_status is not None:
            merged.recorded_status = s.recorded_status
        if not last:
            if s.truncated:
                merged.notes.append(f"{base} (not the last file) was cut short: read up to its last complete record")
            elif s.state not in ("split", "complete", None):
                merged.notes.append(f"{base} (not the last file) has status '{s.state}'")
    merged.summary_ok = all(s.summary_ok for s in scans)
    merged.data_end = scans[-1].data_end
    merged.truncated = scans[-1].truncated
    merged.notes = list(notes) + merged.notes
    return merged


def scan_path(path, field="bag") -> "BagScan | BagSetScan":
    """:func:`~gyro_instrument.recording.bag_scan.scan_bag` for a bare ``.mcap``, or the merged
    :class:`BagSetScan` of a bag directory (every file CRC-checked); see :func:`bag_files` for
    what is accepted.

    Raises
    ------
    SceneError
        See :func:`bag_files`.
    """
    files, notes = bag_files(path, field)
    if not os.path.isdir(path):
        return scan_bag(files[0], field)
    return _merge(path, files, [scan_bag(f, field) for f in files], notes)
