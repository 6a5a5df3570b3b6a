"""Output files: checked before any work, then either complete or absent.

:func:`check_output` / :func:`check_output_dir` refuse an output path before anything is simulated,
read or written (never an input, never an existing file without ``overwrite``).

:func:`replaced_atomically` hands out a temporary name next to the target (``<path>.partial``)
and renames it onto the target only when the block finishes; on any exception, including
``KeyboardInterrupt``, the temporary file is removed and the target is left as it was (absent,
or the previous complete file).
"""

import contextlib
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
