"""Process pools for sweeps over seeds and sites (``concurrent.futures`` interface).

Workers are *spawned* with single-threaded BLAS: forked workers inherit OpenBLAS's thread pool,
and two workers × two busy-waiting BLAS threads on a 2-core machine ran 3× slower than one
process. Any executor with the same ``map``/``submit`` interface (for example a
``dask.distributed`` client's ``get_executor()``) can replace it for studies larger than one
machine: the sweep functions take an ``executor`` argument.

Ctrl-C: workers ignore SIGINT (a terminal sends it to the whole process group, and each worker
would print its own KeyboardInterrupt traceback); the parent gets the KeyboardInterrupt, and
``shutdown`` called while it propagates (the sweeps' ``finally``) terminates the workers instead
of waiting for their tasks.
"""

import multiprocessing
import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor

_BLAS_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class _InterruptiblePool(ProcessPoolExecutor):
    """``ProcessPoolExecutor`` whose ``shutdown`` during a KeyboardInterrupt stops the workers."""

    def shutdown(self, wait=True, *, cancel_futures=False):
        if isinstance(sys.exc_info()[1], KeyboardInterrupt):
            terminate = getattr(self, "terminate_workers", None)       # Python >= 3.14
            if terminate is not None:
                terminate()
                return
            for proc in list((getattr(self, "_processes", None) or {}).values()):
                proc.terminate()
            wait, cancel_futures = False, True
        super().shutdown(wait=wait, cancel_futures=cancel_futures)


def process_executor(max_workers=None) -> ProcessPoolExecutor:
    """A spawn-context ``ProcessPoolExecutor`` whose workers use one BLAS thread each and ignore
    SIGINT (the parent handles Ctrl-C and stops them)."""
    for var in _BLAS_VARS:
        os.environ.setdefault(var, "1")
    return _InterruptiblePool(max_workers=max_workers or os.cpu_count() or 1,
                              mp_context=multiprocessing.get_context("spawn"), initializer=_ignore_sigint)
