"""Process pools for sweeps over seeds and sites (``concurrent.futures`` interface).

Workers are *spawned* with single-threaded BLAS: forked workers inherit OpenBLAS's thread pool,
and two workers × two busy-waiting BLAS threads on a 2-core machine ran 3× slower than one
process. Any executor with the same ``map``/``submit`` interface (for example a
``dask.distributed`` client's ``get_executor()``) can replace it for studies larger than one
machine: the sweep functions take an ``executor`` argument.
"""

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor

_BLAS_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def process_executor(max_workers=None):
    """A spawn-context ``ProcessPoolExecutor`` whose workers use one BLAS thread each."""
    for var in _BLAS_VARS:
        os.environ.setdefault(var, "1")
    return ProcessPoolExecutor(max_workers=max_workers or os.cpu_count() or 1,
                               mp_context=multiprocessing.get_context("spawn"))
