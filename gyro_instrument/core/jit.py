"""Compiled kernels: numba with its on-disk cache, imported only when a kernel is first used.

Every compiled kernel in the package is a plain Python function on floats and numpy arrays that
:func:`compiled` hands to ``numba.njit(cache=True)``; the same function runs uncompiled when
compilation is off, so the pure-Python path is always there and tests hold the two equal.

* numba is imported lazily (≈0.3 s): importing :mod:`gyro_instrument` or running a path that
  needs no kernel never pays for it.
* ``cache=True``: the machine code is written beside the source (``__pycache__``), or to numba's
  user-wide cache when the package directory is read-only (an installed package); the first run
  on a machine compiles (seconds), later runs load it (tens of ms).
* ``GYRO_INSTRUMENT_JIT=0`` in the environment turns compilation off (the pure-Python path: slow
  but identical up to round-off); so does a missing or broken numba, which is then reported by
  :func:`status`.
"""

import functools
import os
from collections.abc import Callable

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
    return numba


def enabled() -> bool:
    """True when kernels are compiled (numba importable and not turned off by ``GYRO_INSTRUMENT_JIT=0``)."""
    return not isinstance(_numba(), str)


def status() -> str:
    """One line for ``describe`` and the bench: ``numba X.Y (cached)`` or why kernels run uncompiled."""
    nb = _numba()
    return f"numba {nb.__version__} (cached)" if not isinstance(nb, str) else f"uncompiled: {nb}"


def compiled(fn: Callable, **options) -> Callable:
    """``numba.njit(cache=True, **options)(fn)`` when :func:`enabled`, else ``fn`` itself.

    Call it where the kernel is first needed (and keep the result, e.g. with ``functools.cache``),
    not at import time, so the import of numba stays lazy.

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
    return nb.njit(cache=True, **options)(fn)
