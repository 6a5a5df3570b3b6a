"""Compiled kernels: numba with its on-disk cache, imported only when a kernel is first used.

Every compiled kernel in the package is a plain Python function on floats and numpy arrays that
:func:`compiled` hands to ``numba.njit(cache=True)``; the same function runs uncompiled when
compilation is off, so the pure-Python path is always there and tests hold the two equal.

* numba is imported lazily (≈0.3 s): importing :mod:`gyro_instrument` or running a path that
  needs no kernel never pays for it.
* ``cache=True``: the machine code is written where numba puts it (``NUMBA_CACHE_DIR``, else
  beside the source in ``__pycache__``, else numba's user-wide cache under HOME); the first run on
  a machine compiles (seconds), later runs load it (tens of ms). When none of those is writable (a
  read-only install with a read-only HOME: numba would raise "no locator available") the cache
  goes to a private directory in the temporary directory (``gyro_instrument-numba-<uid>``, mode
  0700, exported as ``NUMBA_CACHE_DIR`` to child processes), with one note on stderr; when that
  cannot be written either, the kernels compile uncached in every process (also noted).
* ``GYRO_INSTRUMENT_JIT=0`` in the environment turns compilation off (the pure-Python path: slow
  but identical up to round-off); so do numba's own ``NUMBA_DISABLE_JIT=1`` (the callers then take
  their numpy paths rather than numba's Python-interpreted kernels) and a missing or broken numba.
  :func:`status` says which path runs and why (``describe`` prints it).
"""

import functools
import os
import sys
from collections.abc import Callable

from gyro_instrument.core.files import private_temp_dir

#: Environment variable that turns compilation off when set to ``0``.
JIT_ENV = "GYRO_INSTRUMENT_JIT"


@functools.cache
def _numba():
    """The numba module, or the reason it is not used (a string)."""
    if os.environ.get(JIT_ENV, "1").strip() == "0":
        return f"{JIT_ENV}=0"
    try:
        import numba  # noqa: PLC0415 - lazy on purpose (import cost)
    except Exception as exc:  # noqa: BLE001 - any import failure means "run uncompiled"
        return f"numba not importable ({type(exc).__name__}: {exc})"
    if getattr(numba.config, "DISABLE_JIT", False):
        return "NUMBA_DISABLE_JIT=1 (numba's compilation off: the numpy paths run)"
    return numba


def _probe(x):
    """A kernel never called: decorating it with ``cache=True`` asks numba where it would cache."""
    return x


def _cache_path(nb) -> str | None:
    """The directory numba would cache this package's kernels in, or None when it has none."""
    try:
        return getattr(getattr(nb.njit(cache=True)(_probe), "_cache", None), "_cache_path", "") or ""
    except RuntimeError:            # "cannot cache function ...: no locator available"
        return None


@functools.cache
def _cache() -> tuple[bool, str]:
    """(cached, how): numba's own cache location, else the private temporary one (exported as
    ``NUMBA_CACHE_DIR`` for child processes), else none; a fallback is noted once on stderr."""
    nb = _numba()
    if _cache_path(nb) is not None:
        return True, "cached"
    path = private_temp_dir("numba")
    if path is not None:
        nb.config.CACHE_DIR = path
        if _cache_path(nb) is not None:
            os.environ["NUMBA_CACHE_DIR"] = path
            how = f"cached in {path}: the install's and HOME's cache directories are not writable"
            print(f"gyro-instrument: note: compiled kernels {how}", file=sys.stderr)
            return True, how
        nb.config.CACHE_DIR = ""
    how = "not cached: no writable cache directory (install, HOME, temporary); every process compiles"
    print(f"gyro-instrument: note: compiled kernels {how}", file=sys.stderr)
    return False, how


def enabled() -> bool:
    """True when kernels are compiled (numba importable and not turned off by ``GYRO_INSTRUMENT_JIT=0``
    or ``NUMBA_DISABLE_JIT=1``)."""
    return not isinstance(_numba(), str)


def status() -> str:
    """One line for ``describe`` and the bench: ``numba X.Y (cached)`` (or where, or not cached) or
    why kernels run uncompiled."""
    nb = _numba()
    return f"numba {nb.__version__} ({_cache()[1]})" if not isinstance(nb, str) else f"uncompiled: {nb}"


def compiled(fn: Callable, **options) -> Callable:
    """``numba.njit(cache=True, **options)(fn)`` when :func:`enabled`, else ``fn`` itself.

    Call it where the kernel is first needed (and keep the result, e.g. with ``functools.cache``),
    not at import time, so the import of numba stays lazy. Without a writable cache directory the
    kernel is compiled uncached (see the module's notes).

    Parameters
    ----------
    fn : callable
        A function numba's nopython mode accepts (floats, ints, numpy arrays, other kernels
        returned by this function).
    **options
        Passed to ``numba.njit`` (``fastmath`` is never set here: results must match the
        uncompiled path to round-off).
    """
    nb = _numba()
    if isinstance(nb, str):
        return fn
    try:
        return nb.njit(cache=_cache()[0], **options)(fn)
    except RuntimeError:   # no locator for this kernel's file alone (a directory read-only where core/ is not)
        return nb.njit(**options)(fn)
