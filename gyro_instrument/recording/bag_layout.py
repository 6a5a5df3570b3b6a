"""rosbag2's directory layout: a bag directory (``metadata.yaml`` plus one or more ``.mcap``
files), written with optional splitting and read like a bare ``.mcap``.

Writing (:class:`BagDirectoryWriter`): ``DIR/DIR_0.mcap``, ``DIR/DIR_1.mcap``, ... as rosbag2
names its splits, each file a :class:`~gyro_instrument.recording.mcap_io.BagWriter` (so each is a
complete, indexed MCAP after every commit); a new file starts when the current one reaches
``max_bag_size`` bytes or holds ``max_bag_duration`` of log time. Every file registers every topic
known so far and repeats the metadata records added before it (the scene), so each file can be
read alone. ``metadata.yaml`` (rosbag2 version 9, the fields ``rosbag2.Writer`` of rosbags and
rosbag2 jazzy write) is written atomically when the bag is opened, at each of the first
:data:`METADATA_EVERY_SPLIT` splits, then at every doubling of the file count, and at close (so
rewriting it costs O(files) over a run, never O(files²)); a recording killed between them still has a
``metadata.yaml`` naming its first files, and the reader takes the files it does not list too, with
a note. Split limits below :data:`MIN_BAG_SIZE` and :data:`MIN_BAG_DURATION_S` are refused. A full
disk leaves every file as its last commit made it (a split that could not be started is removed).

Reading (:func:`bag_files`, :func:`scan_path`: a bare ``.mcap``, a bag directory, or a split bag)
is :mod:`.bag_input`'s, re-exported here.
"""

import contextlib
import os
from typing import TYPE_CHECKING

import yaml

from gyro_instrument.core.errors import SceneError
# reading is bag_input's; its names are re-exported here, where the callers have always found them
from gyro_instrument.recording.bag_input import (METADATA, BagSetScan, bag_files, bag_inputs, scan_path,
                                                 split_order)

if TYPE_CHECKING:      # annotations only
    from gyro_instrument.recording.mcap_io import BagWriter

ROSBAG2_VERSION = 9
#: the smallest split limits accepted: below them a file would be mostly its repeated start (header,
#: scene record, schemas, channels) and summary (~60 kB for quet_paris), and a run would make
#: thousands of files (``--max-bag-size 1`` made 548 files for 5 s)
MIN_BAG_SIZE = 1 << 20
MIN_BAG_DURATION_S = 1.0
#: ``metadata.yaml`` is rewritten at every split while a bag has at most this many files, then at
#: every doubling of their count (and at close), so rewriting it costs O(files) over a run
METADATA_EVERY_SPLIT = 16
FORMATS = ("mcap", "rosbag2")

_HISTORY = {0: "system_default", 1: "keep_last", 2: "keep_all", 3: "unknown"}
_RELIABILITY = {0: "system_default", 1: "reliable", 2: "best_effort", 3: "unknown", 4: "best_available"}
_DURABILITY = {0: "system_default", 1: "transient_local", 2: "volatile", 3: "unknown", 4: "best_available"}
_LIVELINESS = {0: "system_default", 1: "automatic", 2: "manual_by_node", 3: "manual_by_topic", 4: "unknown",
               5: "best_available"}


# ----------------------------------------------------------------------------- output
def bag_format(path, fmt=None, max_bag_size=0, max_bag_duration_s=0.0, field="--bag-format") -> str:
    """The layout to record ``path`` in: ``rosbag2`` (a bag directory) when asked for, when the
    path ends with a slash or names an existing directory, or when splitting is asked for;
    ``mcap`` (one bare file) otherwise.

    Raises
    ------
    SceneError
        ``fmt`` is not a known layout, or splitting is asked for with ``fmt`` = ``mcap``.
    """
    if fmt not in (None, "", *FORMATS):
        raise SceneError(field, fmt, f"must be one of {', '.join(FORMATS)}")
    split = bool(max_bag_size) or bool(max_bag_duration_s)
    if fmt == "mcap" and split:
        raise SceneError(field, fmt, "splitting (--max-bag-size, --max-bag-duration) needs the rosbag2 layout")
    if fmt:
        return fmt
    if split or path.endswith(("/", os.sep)) or os.path.isdir(path):
        return "rosbag2"
    return "mcap"


def check_split_limits(max_bag_size=0, max_bag_duration_s=0.0, size_field="--max-bag-size",
                       duration_field="--max-bag-duration") -> None:
    """Refuse split limits below their floors (:data:`MIN_BAG_SIZE` bytes, :data:`MIN_BAG_DURATION_S`
    s); 0 means no limit.

    Raises
    ------
    SceneError
        One line naming the field, the value and the valid range.
    """
    import math
    size = float(max_bag_size or 0)
    if size and (not math.isfinite(size) or not size.is_integer() or size < MIN_BAG_SIZE):
        raise SceneError(size_field, max_bag_size, f"must be 0 (no limit) or a whole number of bytes >= "
                                                   f"{MIN_BAG_SIZE} (the floor: 1 MiB)")
    dur = float(max_bag_duration_s or 0.0)
    if dur != 0.0 and not (math.isfinite(dur) and dur >= MIN_BAG_DURATION_S):
        raise SceneError(duration_field, max_bag_duration_s, f"must be 0 (no limit) or a duration in s >= "
                                                            f"{MIN_BAG_DURATION_S:g} (the floor) and finite")


def restart_path(path, k) -> str:
    """The ``k``-th (1, 2, ...) file or bag directory of a recording whose clock went back: ``q.mcap``
    -> ``q_run1.mcap``, ``bag/`` -> ``bag_run1/``; the next free name (nothing is written over)."""
    d = path.rstrip("/" + os.sep) or path
    stem, ext = os.path.splitext(d) if d.endswith(".mcap") else (d, "")
    while True:
        out = f"{stem}_run{k}{ext}"
        if not os.path.lexists(out):
            return out + (os.sep if d != path else "")
        k += 1


def _bag_dir_contents_ok(path):
    """True when a directory holds only what a bag directory holds (metadata.yaml, .mcap files)."""
    return all(n == METADATA or n.endswith((".mcap", ".yaml.partial")) for n in os.listdir(path))


def check_bag_output(path, fmt, field="--bag", inputs=(), overwrite=False, max_bag_size=0,
                     max_bag_duration_s=0.0) -> None:
    """Refuse a recording destination before anything runs (see ``cli.check_output`` for a file).

    A rosbag2 destination is a directory that must not exist, unless ``overwrite`` and it holds
    nothing but a bag (``metadata.yaml`` and ``.mcap`` files): any other directory is never
    written over. Its parent must exist and be writable, and no input may lie inside it.

    Raises
    ------
    SceneError
        One line naming ``field``, the path and why.
    """
    from gyro_instrument.core.files import check_output, same_file
    check_split_limits(max_bag_size, max_bag_duration_s)
    if fmt != "rosbag2":
        return check_output(path, field, inputs, overwrite)
    d = path.rstrip("/" + os.sep) or path
    parent = os.path.dirname(os.path.abspath(d)) or "."
    if not os.path.isdir(parent):
        raise SceneError(field, path, f"directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise SceneError(field, path, f"directory {parent} is not writable")
    for inp in inputs:
        if inp and (same_file(inp, d) or os.path.realpath(inp).startswith(os.path.realpath(d) + os.sep)):
            raise SceneError(field, path, f"holds the input {inp}; record elsewhere (--overwrite never replaces "
                                          f"an input)")
    if os.path.lexists(d):
        if not os.path.isdir(d):
            raise SceneError(field, path, "exists and is not a directory; a rosbag2 bag is a directory")
        if not overwrite:
            raise SceneError(field, path, "exists; pass --overwrite to replace it, or give a new path")
        if not _bag_dir_contents_ok(d):
            raise SceneError(field, path, "holds files that are not a bag's (only metadata.yaml and .mcap files "
                                          "are replaced): not written over")


def open_bag_writer(path, fmt="mcap", max_bag_size=0, max_bag_duration_s=0.0, overwrite=False,
                    **kwargs) -> "BagWriter | BagDirectoryWriter":
    """A :class:`~gyro_instrument.recording.mcap_io.BagWriter` (``mcap``) or a
    :class:`BagDirectoryWriter` (``rosbag2``); the caller checked the path
    (:func:`check_bag_output`)."""
    from gyro_instrument.recording.mcap_io import BagWriter
    if fmt == "rosbag2":
        return BagDirectoryWriter(path, max_bag_size=max_bag_size, max_bag_duration_s=max_bag_duration_s,
                                  overwrite=overwrite, **kwargs)
    return BagWriter(path, **kwargs)


def _qos_v9(qos_text):
    """A channel's ``offered_qos_profiles`` (YAML text, numeric enums) as metadata.yaml version 9
    writes it: a list of mappings with the policies by name."""
    out = []
    for p in yaml.safe_load(qos_text or "[]") or []:
        q = dict(p)
        for key, names in (("history", _HISTORY), ("reliability", _RELIABILITY), ("durability", _DURABILITY),
                           ("liveliness", _LIVELINESS)):
            if isinstance(q.get(key), int):
                q[key] = names.get(q[key], "unknown")
        out.append(q)
    return out


class BagDirectoryWriter:
    """Record to a rosbag2 bag directory (see the module docstring); the interface of
    :class:`~gyro_instrument.recording.mcap_io.BagWriter` (``add_topic``, ``write``,
    ``add_metadata``, ``commit``, ``close``, ``counts``, ``closed``).

    Parameters
    ----------
    path : str
        The bag directory (created; must not exist unless ``overwrite``).
    max_bag_size : int
        Start a new file before a message when the current one holds this many bytes (committed
        bytes plus the uncompressed messages of the chunk in progress); 0: no limit. A file ends
        past the limit by at most its last chunk and its summary and closing metadata records.
    max_bag_duration_s : float
        Start a new file before a message whose log time is this many seconds or more after the
        current file's first message; 0: no limit.
    overwrite : bool
        Replace the bag files (metadata.yaml, .mcap) of an existing directory.
    **writer_kwargs
        Passed to each file's ``BagWriter`` (``chunk_size``, ``commit_period_s``...).
    """

    def __init__(self, path, max_bag_size=0, max_bag_duration_s=0.0, overwrite=False, **writer_kwargs):
        self.path = path.rstrip("/" + os.sep) or path
        self.name = os.path.basename(os.path.abspath(self.path))
        self.max_bag_size = int(max_bag_size or 0)
        self.max_bag_duration_ns = int(round(float(max_bag_duration_s or 0.0) * 1e9))
        self._kwargs = writer_kwargs
        if os.path.isdir(self.path):
            if not overwrite:
                raise SceneError("bag", path, "exists; pass overwrite to replace it")
            for n in os.listdir(self.path):
                if n == METADATA or n.endswith((".mcap", ".yaml.partial")):
                    os.unlink(os.path.join(self.path, n))
        else:
            os.mkdir(self.path)
        self._topics = {}             # topic -> (type, qos text)
        self._closed_counts = {}      # topic -> messages in the files closed so far
        self._carried = []            # metadata records repeated in every new file
        self.counts = {}
        self.files = []               # per file: dict(path, start, end, count)
        self.closed = False
        self.commits = 0
        self._cur = None
        self._open_next()

    # -------------------------------------------------------------- files
    def _open_next(self):
        from gyro_instrument.recording.mcap_io import BagWriter, DiskFull
        name = f"{self.name}_{len(self.files)}.mcap"
        full = os.path.join(self.path, name)
        try:
            self._cur = BagWriter(full, **self._kwargs)
            for rec_name, data in self._carried:
                self._cur.add_metadata(rec_name, data)
            for topic, (type_name, qos) in self._topics.items():
                self._cur.add_topic(topic, type_name, qos)
        except DiskFull:
            # a split that could not even hold its start holds nothing: removed, so the bag
            # directory is the files before it, each closed (status 'split')
            if os.path.exists(full):
                os.unlink(full)
            self.closed = True
            raise
        self.files.append({"path": name, "start": None, "end": None, "count": 0})
        n = len(self.files)
        if n <= METADATA_EVERY_SPLIT or n & (n - 1) == 0:
            self.write_metadata()

    def _close_current(self, state, **fields):
        with self._on_full_disk():
            self._cur.add_metadata("rosbag2", {"serialized_metadata": yaml.safe_dump(self.bag_information(),
                                                                                     sort_keys=False),
                                               "ros_distro": "jazzy"})
            self.commits += self._cur.commits
            self._cur.close(state=state, **fields)
        for topic, n in self._cur.counts.items():
            self._closed_counts[topic] = self._closed_counts.get(topic, 0) + n

    @contextlib.contextmanager
    def _on_full_disk(self):
        """A full disk while writing the current file: it holds what its last commit put there (its
        status ``incomplete`` with the reason); the counts and times of ``metadata.yaml`` are made
        those of the files as they are, and it is written (in place if need be); DiskFull raised."""
        from gyro_instrument.recording.mcap_io import DiskFull
        try:
            yield
        except DiskFull:
            counts, start, end = self._cur.committed()
            f = self.files[-1]
            f["count"], f["start"], f["end"] = sum(counts.values()), start, end
            self.counts = {tp: self._closed_counts.get(tp, 0) + counts.get(tp, 0) for tp in self.counts}
            self.closed = True
            try:
                self.write_metadata(in_place=True)
            except OSError:
                pass
            raise

    def split(self) -> None:
        """Close the current file (status ``split``) and continue in the next one."""
        self._close_current("split")
        try:
            self._open_next()
        except OSError:
            self.write_metadata(in_place=True)     # the files as they are (the one not started removed)
            raise

    # -------------------------------------------------------------- BagWriter interface
    def add_topic(self, topic, type_name, qos=None) -> int:
        """Register a topic in the current file and every later one."""
        from gyro_instrument.recording.mcap_io import qos_yaml
        qos = qos or qos_yaml()
        new = topic not in self._topics
        self._topics.setdefault(topic, (type_name, qos))
        self.counts.setdefault(topic, 0)
        if new:
            self._keep_metadata_room()
        return self._cur.add_topic(topic, type_name, qos)

    def write(self, topic, log_time_ns, data, publish_time_ns=None) -> None:
        """Append one message, starting a new file first when a limit is reached."""
        f = self.files[-1]
        if f["count"] and ((self.max_bag_size and self._cur._fh.tell() + self._cur._bytes >= self.max_bag_size)
                           or (self.max_bag_duration_ns
                               and int(log_time_ns) - f["start"] >= self.max_bag_duration_ns)):
            self.split()
            f = self.files[-1]
        with self._on_full_disk():
            self._cur.write(topic, log_time_ns, data, publish_time_ns)
        t = int(log_time_ns)
        f["start"] = t if f["start"] is None else min(f["start"], t)
        f["end"] = t if f["end"] is None else max(f["end"], t)
        f["count"] += 1
        self.counts[topic] += 1

    def add_metadata(self, name, data) -> None:
        """A metadata record in the current file; records added before the first message (the
        scene) are repeated at the start of every later file."""
        if not any(f["count"] for f in self.files):
            self._carried.append((name, data))
        with self._on_full_disk():
            self._cur.add_metadata(name, data)

    def pending(self) -> bool:
        """True when the current file holds messages written since its last commit."""
        return self._cur.pending()

    def since_commit_s(self) -> float:
        """Wall time since the current file's last commit, s."""
        return self._cur.since_commit_s()

    def commit(self) -> None:
        with self._on_full_disk():
            self._cur.commit()

    def close(self, state="complete", **fields) -> None:
        """Finish the last file with status ``state`` (and the recorder's ``fields``: per-topic counts,
        late messages; see :meth:`BagWriter.close`) and write the final ``metadata.yaml``."""
        if self.closed:
            return
        self.closed = True
        from gyro_instrument.recording.mcap_io import DiskFull
        err = None
        try:
            self._close_current(state, **fields)
        except DiskFull as exc:       # the file is left as its last commit made it: still listed
            err = exc
        try:
            self.write_metadata()
        except OSError:
            if err is None:
                raise
        if err is not None:
            raise err

    @property
    def failed(self) -> "OSError | None":
        """The DiskFull that stopped the current file, or None."""
        return getattr(self._cur, "failed", None)

    # -------------------------------------------------------------- metadata.yaml
    def bag_information(self) -> dict:
        """The ``rosbag2_bagfile_information`` mapping (version 9) for the files so far."""
        starts = [f["start"] for f in self.files if f["start"] is not None]
        ends = [f["end"] for f in self.files if f["end"] is not None]
        start = min(starts) if starts else 0
        return {
            "version": ROSBAG2_VERSION,
            "storage_identifier": "mcap",
            "duration": {"nanoseconds": (max(ends) - start) if ends else 0},
            "starting_time": {"nanoseconds_since_epoch": start},
            "message_count": sum(f["count"] for f in self.files),
            "topics_with_message_count": [
                {"topic_metadata": {"name": topic, "type": type_name, "serialization_format": "cdr",
                                    "offered_qos_profiles": _qos_v9(qos),
                                    "type_description_hash": _type_hash(type_name)},
                 "message_count": self.counts.get(topic, 0)}
                for topic, (type_name, qos) in self._topics.items()],
            "compression_format": "",
            "compression_mode": "",
            "relative_file_paths": [f["path"] for f in self.files],
            "files": [{"path": f["path"],
                       "starting_time": {"nanoseconds_since_epoch": f["start"] or 0},
                       "duration": {"nanoseconds": (f["end"] - f["start"]) if f["count"] else 0},
                       "message_count": f["count"]} for f in self.files],
            "custom_data": None,
            "ros_distro": "jazzy",
        }

    def write_metadata(self, in_place=False) -> None:
        """Write ``metadata.yaml`` atomically (temporary file, then rename), with room kept for the
        next rewrite (:func:`reserve_space`); on a full disk the previous one stays (the temporary
        file is removed) unless ``in_place``: then it is rewritten over its own bytes and the room
        kept after them, so that it says what the files hold. When even that room is too small
        (a file system without ``fallocate``) the previous one is left whole rather than cut."""
        target = os.path.join(self.path, METADATA)
        tmp = target + ".partial"
        text = yaml.safe_dump({"rosbag2_bagfile_information": self.bag_information()},
                              sort_keys=False).encode("utf-8")
        try:
            with open(tmp, "wb") as fh:
                fh.write(text)
                fh.flush()
                reserve_space(fh.fileno(), _metadata_room(len(text)))
            os.replace(tmp, target)
        except OSError:
            if os.path.exists(tmp):
                os.unlink(tmp)
            if not in_place:
                raise
            fd = os.open(target, os.O_WRONLY)
            try:
                if len(text) > os.fstat(fd).st_blocks * 512:
                    raise OSError(28, "metadata.yaml has no room kept for its rewrite")
                view, at = memoryview(text), 0
                while view:
                    k = os.pwrite(fd, view, at)
                    view, at = view[k:], at + k
                os.ftruncate(fd, at)
            finally:
                os.close(fd)

    def _keep_metadata_room(self) -> None:
        """Make the room kept after ``metadata.yaml`` cover the text it would have now (called
        when a topic is added: the text grows most then)."""
        target = os.path.join(self.path, METADATA)
        try:
            text = yaml.safe_dump({"rosbag2_bagfile_information": self.bag_information()}, sort_keys=False)
            fd = os.open(target, os.O_WRONLY)
        except OSError:
            return
        try:
            reserve_space(fd, _metadata_room(len(text.encode("utf-8"))))
        finally:
            os.close(fd)


def _metadata_room(n_bytes) -> int:
    """Bytes kept for ``metadata.yaml``: twice its text (the file list at most doubles between two
    rewrites, :data:`METADATA_EVERY_SPLIT`) and 16 KiB for topics and longer counts."""
    return 2 * int(n_bytes) + (16 << 10)


def reserve_space(fd, n_bytes) -> bool:
    """Allocate the first ``n_bytes`` of the file ``fd`` without changing its size (Linux
    ``fallocate(2)`` with ``FALLOC_FL_KEEP_SIZE``), so that a later rewrite of up to that many bytes
    over it needs no new space. False, and nothing done, where the call is missing or refused
    (another OS, a file system without it, a disk already full)."""
    global _fallocate
    if _fallocate is None:
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            f = libc.fallocate
            f.argtypes = (ctypes.c_int, ctypes.c_int, ctypes.c_longlong, ctypes.c_longlong)
            f.restype = ctypes.c_int
            _fallocate = f
        except (OSError, AttributeError):
            _fallocate = False
    if not _fallocate:
        return False
    return _fallocate(int(fd), _FALLOC_FL_KEEP_SIZE, 0, int(n_bytes)) == 0


_FALLOC_FL_KEEP_SIZE = 1
_fallocate = None

def _type_hash(type_name):
    from gyro_instrument.recording.definitions import type_hash
    try:
        return type_hash(type_name)
    except (KeyError, FileNotFoundError):
        return ""


__all__ = ["FORMATS", "METADATA", "MIN_BAG_DURATION_S", "MIN_BAG_SIZE", "BagDirectoryWriter", "BagSetScan", "reserve_space",
           "bag_files", "bag_format", "bag_inputs", "check_bag_output", "check_split_limits", "open_bag_writer",
           "restart_path", "scan_path", "split_order"]
