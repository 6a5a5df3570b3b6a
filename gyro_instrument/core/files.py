"""Output files: checked before any work, then either complete or absent.

:func:`check_output` / :func:`check_output_dir` refuse an output path before anything is simulated,
read or written (never an input, never an existing file without ``overwrite``).

:func:`replaced_atomically` hands out a temporary name next to the target (``<path>.partial``)
and renames it onto the target only when the block finishes; on any exception, including
``KeyboardInterrupt``, the temporary file is removed and the target is left as it was (absent,
or the previous complete file).
"""

import contextlib
import csv
import os
from collections.abc import Iterator

from gyro_instrument.core.errors import SceneError


@contextlib.contextmanager
def replaced_atomically(path) -> Iterator:
    """Yield ``<path>.partial``; on success rename it onto ``path`` (``os.replace``, atomic on
    POSIX within one directory), on any exception remove it and re-raise.

    Raises
    ------
    Whatever the block raises (after the cleanup), or OSError from the rename.
    """
    tmp = f"{path}.partial"
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def shown(path) -> str:
    """``path`` as text any writer takes (a file's contents, a plot title, a ROS message, MCAP
    metadata): a name of bytes that are not UTF-8 (``$'caf\\xe9.csv'``, held by Python as the
    surrogates of ``os.fsdecode``) shows them as ``\\xNN``; a UTF-8 name is returned as it is.
    Open files with the path itself, never with this text."""
    text = os.fsdecode(os.fspath(path))
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def is_utf8(path) -> bool:
    """True when ``path`` is text a library taking UTF-8 path strings accepts (pyarrow: a name of
    other bytes raised UnicodeEncodeError in its ``tobytes``)."""
    try:
        os.fsdecode(os.fspath(path)).encode("utf-8")
        return True
    except UnicodeEncodeError:
        return False


@contextlib.contextmanager
def opened_unless_utf8(path, mode="rb") -> Iterator:
    """Yield ``path`` itself when :func:`is_utf8`, else ``path`` opened in ``mode`` (closed after the
    block): what pyarrow's readers and writers take for a file name of any bytes."""
    if is_utf8(path):
        yield path
        return
    with open(path, mode) as fh:
        yield fh


def writable_dir(path) -> bool:
    """True when the directory ``path`` exists or can be made, and a file can be created in it (a
    read-only mount or a missing HOME says no; ``os.access`` alone says yes to root)."""
    import tempfile
    try:
        os.makedirs(path, exist_ok=True)
        tempfile.TemporaryFile(dir=path).close()
        return True
    except OSError:
        return False


def private_temp_dir(kind) -> str | None:
    """``<tmp>/gyro_instrument-<kind>-<uid>``: a directory of this user's in the temporary directory,
    kept between runs (a cache found again), used only when it is owned by the user and writable by
    no one else (what is cached there may be loaded as code: numba's index files are pickles), else a
    fresh ``mkdtemp``; None when no temporary directory is writable (``tempfile``'s candidates:
    TMPDIR, /tmp, /var/tmp, /usr/tmp, the working directory)."""
    import stat
    import tempfile
    uid = os.getuid() if hasattr(os, "getuid") else 0
    try:
        path = os.path.join(tempfile.gettempdir(), f"gyro_instrument-{kind}-{uid}")   # OSError: none usable
        os.makedirs(path, mode=0o700, exist_ok=True)
        st = os.lstat(path)
        if not (stat.S_ISDIR(st.st_mode) and st.st_uid == uid and not st.st_mode & 0o022):
            path = tempfile.mkdtemp(prefix=f"gyro_instrument-{kind}-")
        return path if writable_dir(path) else None
    except OSError:
        return None


def check_writable(path, field="--out") -> None:
    """Refuse an output path that cannot be written, before any simulation starts.

    Raises
    ------
    SceneError
        ``path`` is a directory, its directory is missing, or it is not writable.
    """
    directory = os.path.dirname(os.path.abspath(path)) or "."
    if os.path.isdir(path):
        raise SceneError(field, path, "is a directory; give a file path")
    if not os.path.isdir(directory):
        raise SceneError(field, path, f"directory {directory} does not exist")
    if not os.access(directory, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise SceneError(field, path, "is not writable")


def same_file(a, b) -> bool:
    """True when paths ``a`` and ``b`` name the same file (inode when both exist, else realpath)."""
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def check_output(path, field="--out", inputs=(), overwrite=False, also=()) -> None:
    """Refuse an output path before anything is simulated, read or written: it must be writable,
    never one of the command's ``inputs`` (compared by inode/realpath, whatever ``overwrite`` says),
    and not an existing file unless ``overwrite``. ``also``: other paths the command writes on the
    way (e.g. ``<out>.partial``), which must not be inputs either.

    Raises
    ------
    SceneError
        One line naming ``field``, the path and why.
    """
    check_writable(path, field)
    for inp in inputs:
        for p in (path, *also):
            if inp and same_file(p, inp):
                what = "is" if p == path else f"writes {p}, which is"
                raise SceneError(field, path, f"{what} the input {inp}; write elsewhere (--overwrite never "
                                              f"replaces an input)")
    if os.path.lexists(path) and not overwrite:
        raise SceneError(field, path, "exists; pass --overwrite to replace it, or give a new path")


def scene_inputs(scene_arg) -> tuple:
    """The files a scene argument reads (a YAML path; none for a shipped scene name)."""
    return (scene_arg,) if os.path.isfile(scene_arg) else ()


def check_dir_writable(path, field="--out") -> None:
    """Refuse an output directory that could not be written (it, or the nearest existing directory
    above it when it does not exist yet), before any work and without creating anything.

    Raises
    ------
    SceneError
        One line naming ``field``, the path and the directory that cannot be written.
    """
    probe = os.path.abspath(path)
    while not os.path.lexists(probe) and os.path.dirname(probe) != probe:
        probe = os.path.dirname(probe)
    if not os.path.isdir(probe):
        raise SceneError(field, path, f"{shown(probe)} is not a directory" if probe != os.path.abspath(path)
                         else "is a file; give a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        where = "" if probe == os.path.abspath(path) else f" (nor can it be created in {shown(probe)})"
        raise SceneError(field, path, f"is not writable{where}")


def check_output_dir(path, field="--out") -> None:
    """Create the output directory ``path`` (and its parents) or refuse it before any work.

    Raises
    ------
    SceneError
        When ``path`` is a file, cannot be created, or is not writable.
    """
    if os.path.exists(path) and not os.path.isdir(path):
        raise SceneError(field, path, "exists and is not a directory")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise SceneError(field, path, f"cannot be created as a directory ({exc.strerror})") from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise SceneError(field, path, "is not writable")


def write_csv(path, header, rows) -> None:
    """Write ``header`` then ``rows`` (iterables of cells) as CSV to ``path``, replacing it atomically
    (:func:`replaced_atomically`: a reader never sees half a file)."""
    with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        w.writerows(rows)
