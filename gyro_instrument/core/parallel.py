"""Process pools for sweeps over seeds and sites (``concurrent.futures`` interface).

Workers are *spawned* with single-threaded BLAS: forked workers inherit OpenBLAS's thread pool,
and two workers × two busy-waiting BLAS threads on a 2-core machine ran 3× slower than one
process. Any executor with the same ``map``/``submit`` interface (for example a
``dask.distributed`` client's ``get_executor()``) can replace it for studies larger than one
machine: the sweep functions take an ``executor`` argument; :func:`dask_executor` connects to a
Dask scheduler and yields such an executor (``gyro-instrument bench --scheduler ADDRESS``).

Ctrl-C: workers ignore SIGINT (a terminal sends it to the whole process group, and each worker
would print its own KeyboardInterrupt traceback); the parent gets the KeyboardInterrupt, and
``shutdown`` called while it propagates (the sweeps' ``finally``) terminates the workers instead
of waiting for their tasks.
"""

import multiprocessing
import os
import signal
import sys
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

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


def _fresh(executor, own, workers):
    """A new pool for the retries when our own pool broke (a worker died: the pool is unusable)."""
    if own and getattr(executor, "_broken", False):
        executor.shutdown(wait=False)
        return process_executor(workers)
    return executor


def run_tasks(task, jobs, executor=None, on_done=None, on_retry=None, workers=None) -> list:
    """``task(job)`` for every job through ``executor`` (any ``concurrent.futures`` executor with
    ``submit``; default :func:`process_executor` of ``workers``, shut down after): the results in job
    order. A task
    that raises — a worker that died (BrokenProcessPool, Dask's KilledWorker) or anything else — is
    retried once (on a new pool when our own broke), then its result is ``{"error": "failed twice:
    …"}``; a task the executor refuses to take is ``{"error": "not run: …"}``. ``on_done(done,
    total)`` after each finished task, ``on_retry(index, reason)`` before a retry. The runner of
    ``gyro-instrument sweep`` (:mod:`gyro_instrument.bench.sweep`), of the bench's seeded studies and
    of ``plan --verify``."""
    from concurrent.futures import as_completed
    from concurrent.futures.process import BrokenProcessPool
    own = executor is None
    executor = executor or process_executor(workers)
    results, tries, pending = [None] * len(jobs), [0] * len(jobs), list(range(len(jobs)))
    done = 0
    try:
        while pending:
            executor = _fresh(executor, own, workers)
            futures, retry = {}, []
            for i in pending:
                try:
                    futures[executor.submit(task, jobs[i])] = i
                except (BrokenProcessPool, RuntimeError) as exc:
                    results[i] = {"error": f"not run: {type(exc).__name__}: {exc}"}
            for fut in as_completed(futures):
                i = futures[fut]
                try:
                    results[i] = fut.result()
                except Exception as exc:      # noqa: BLE001 - a dead worker: retried once, then in the result
                    tries[i] += 1
                    why = f"{type(exc).__name__}: {exc}".strip()
                    if tries[i] < 2:
                        retry.append(i)
                        if on_retry:
                            on_retry(i, why)
                        continue
                    results[i] = {"error": f"failed twice: {why}"}
                done += 1
                if on_done:
                    on_done(done, len(jobs))
            pending = sorted(retry)
    finally:
        if own:
            executor.shutdown()
    return results


@contextmanager
def dask_executor(address, timeout_s=10.0, need_workers=False, progress=None) -> Iterator:
    """A ``dask.distributed`` client's ``concurrent.futures`` executor on the scheduler at
    ``address`` (``tcp://host:8786``); the client is closed on exit. The cluster's workers need
    this package installed (the tasks are its picklable sweep functions). ``need_workers``: a
    scheduler without workers is waited for up to ``timeout_s`` (said through ``progress``), then
    refused.

    Raises
    ------
    SceneError
        Dask is not installed (the ``cluster`` extra), or no scheduler answers at ``address``
        within ``timeout_s``, or (``need_workers``) it has no worker after ``timeout_s``.
    """
    from gyro_instrument.core.errors import SceneError
    try:
        from dask.distributed import Client
    except ImportError:
        raise SceneError("--scheduler", address, "needs Dask: pip install 'gyro_instrument[cluster]' "
                                                 "(or: pip install 'dask[distributed]')") from None
    try:
        client = Client(address, timeout=f"{timeout_s}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SceneError("--scheduler", address, f"no Dask scheduler answered ({exc.__class__.__name__}): "
                                                 f"give tcp://HOST:PORT of a running scheduler") from None
    try:
        if need_workers:
            _wait_for_workers(client, address, timeout_s, progress)
        yield client.get_executor()
    finally:
        client.close()


def _wait_for_workers(client, address, timeout_s, progress) -> None:
    from gyro_instrument.core.errors import SceneError
    if client.scheduler_info().get("workers"):
        return
    if progress:
        progress(f"the Dask scheduler {address} has no workers: waiting up to {timeout_s:g} s (--timeout) for one")
    try:
        client.wait_for_workers(1, timeout=timeout_s)
    except (TimeoutError, OSError) as exc:
        raise SceneError("--scheduler", address, f"has no workers after {timeout_s:g} s "
                                                 f"({exc.__class__.__name__}): start some with "
                                                 f"'dask worker {address}'") from None
