"""Output files that are either complete or absent.

:func:`replaced_atomically` hands out a temporary name next to the target (``<path>.partial``)
and renames it onto the target only when the block finishes; on any exception, including
``KeyboardInterrupt``, the temporary file is removed and the target is left as it was (absent,
or the previous complete file).
"""

import contextlib
import os
from collections.abc import Iterator


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
