"""The file under :class:`~gyro_instrument.recording.mcap_io.BagWriter`: records buffered and written
in one ``pwrite`` with a provisional end after them, so the file on disk is a complete MCAP after
every commit (:class:`TailKeepingFile`); :class:`DiskFull`, the error a full disk raises."""

import os


class TailKeepingFile:
    """The writer's output stream: data records are buffered and reach the file in one ``pwrite``
    together with a provisional end (summary, footer, magic) placed after them. The next commit
    writes over that provisional end from its first byte, so the file on disk is a complete MCAP
    after every commit, and a SIGKILL loses only what was not yet committed."""

    def __init__(self, path):
        self.path = path
        self._fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self._pos = 0              # end of the committed data section
        self._pending = bytearray()
        self._end = 0              # end of what is on disk
        self._tail = b""           # the provisional end on disk now

    def write(self, data) -> int:
        self._pending += data
        return len(data)

    def tell(self) -> int:
        return self._pos + len(self._pending)

    def flush(self) -> None:
        pass

    def commit(self, tail=b"") -> None:
        """Write the pending records and then ``tail`` (not part of the data: overwritten next time).

        When the write fails (ENOSPC: the disk is full, EDQUOT, EFBIG...) the file is put back as
        the last commit left it (the extension cut off, the previous provisional end written back
        into the space it already had), so it stays a complete, indexed MCAP; the error is raised
        as :class:`DiskFull` with the bytes needed and free."""
        buf = memoryview(bytes(self._pending) + tail)
        need = len(buf)
        at = self._pos
        try:
            while buf:             # one syscall in practice; loop for short writes
                k = os.pwrite(self._fd, buf, at)
                buf, at = buf[k:], at + k
        except OSError as exc:
            self._restore()
            raise DiskFull(self.path, need, exc) from None
        self._tail = bytes(tail)
        self._pos += len(self._pending)
        self._pending.clear()
        if at < self._end:         # never happens with a growing summary; keep the file exact anyway
            os.ftruncate(self._fd, at)
        self._end = at

    def _restore(self):
        try:
            os.ftruncate(self._fd, self._end)
            tail, at = memoryview(self._tail), self._pos
            while tail:
                k = os.pwrite(self._fd, tail, at)
                tail, at = tail[k:], at + k
        except OSError:
            pass                   # nothing better to do: the reader reads up to the last complete record

    def rewrite_tail(self, tail) -> None:
        """Replace the provisional end on disk by ``tail`` (no longer than it: the space it takes is
        already the file's), the file cut after it."""
        if len(tail) > len(self._tail):
            raise OSError(28, "the new end is longer than the space the old one has")
        view, at = memoryview(tail), self._pos
        while view:
            k = os.pwrite(self._fd, view, at)
            view, at = view[k:], at + k
        os.ftruncate(self._fd, at)
        self._tail, self._end = bytes(tail), at

    def close(self) -> None:
        os.close(self._fd)


class DiskFull(OSError):
    """A bag write failed for lack of space; the file is left as its last commit made it.
    ``needed``: bytes the failed write needed; ``free``: bytes free on that file system then."""

    def __init__(self, path, needed, cause):
        super().__init__(cause.errno, cause.strerror)
        self.path, self.needed, self.cause = path, int(needed), cause
        try:
            st = os.statvfs(os.path.dirname(os.path.abspath(path)) or ".")
            self.free = st.f_bavail * st.f_frsize
        except OSError:
            self.free = None

    def line(self, field="--bag") -> str:
        free = "unknown" if self.free is None else f"{self.free}"
        return (f"{field} {self.path}: {self.cause.strerror or 'write failed'} (errno {self.errno}): the next write "
                f"needs {self.needed} bytes, {free} bytes free; the bag is closed readable up to its last commit")


class Sink:
    """A byte sink that reports file offsets from ``start`` (for the provisional end)."""

    def __init__(self, start):
        self.start, self.buf = start, bytearray()

    def write(self, data) -> int:
        self.buf += data
        return len(data)

    def tell(self) -> int:
        return self.start + len(self.buf)

    def flush(self) -> None:
        pass
