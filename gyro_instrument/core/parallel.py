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
    import distributed
    try:
        client = _within(timeout_s, lambda: Client(address, timeout=f"{timeout_s}s", set_as_default=False))
    except (OSError, TimeoutError, ValueError) as exc:
        raise SceneError("--scheduler", address, f"no Dask scheduler answered ({exc.__class__.__name__}): "
                                                 f"give tcp://HOST:PORT of a running scheduler") from None
    except Exception as exc:   # noqa: BLE001 - another Dask's protocol fails in its own ways (TypeError, KeyError...)
        raise SceneError("--scheduler", address, f"answered but could not be talked to ({exc.__class__.__name__}): "
                                                 f"it may run another Dask version than this client's distributed "
                                                 f"{distributed.__version__}") from None
    try:
        if need_workers:
            _wait_for_workers(client, address, timeout_s, progress)
        check_cluster(client, address, timeout_s)
        yield client.get_executor()
    finally:
        client.close()


#: the packages whose versions must agree between this client, the scheduler and the workers (the
#: tasks and their results are pickled across; Dask's own check warns about the same list)
SAME_VERSIONS = ("python", "dask", "distributed", "cloudpickle", "msgpack")


def _within(timeout_s, call):
    """``call()`` in a helper thread, waited for at most ``timeout_s`` (TimeoutError after it; the
    thread is a daemon and is left behind): a scheduler of another Dask version can hang a handshake
    or a request well past the client's own timeout (21.8 s under --timeout 10 in issue 38)."""
    import concurrent.futures
    import threading
    box = concurrent.futures.Future()

    def run():
        try:
            box.set_result(call())
        except BaseException as exc:    # noqa: BLE001 - handed to the caller
            box.set_exception(exc)
    threading.Thread(target=run, name="dask-check", daemon=True).start()
    try:
        return box.result(timeout=timeout_s)
    except concurrent.futures.TimeoutError:
        raise TimeoutError(f"no answer within {timeout_s:g} s") from None


def check_cluster(client, address, timeout_s) -> None:
    """Refuse a cluster the sweeps cannot run on, in one line, within ``timeout_s``: versions of
    :data:`SAME_VERSIONS` that differ between this client and the scheduler or a worker (named with
    both versions), a worker where this package cannot be imported, or one with another version of
    it (the tasks would fail to deserialize there: "failed twice: RuntimeError: Error during
    deserialization" on every row, exit 0, before).

    Raises
    ------
    SceneError
        Naming ``--scheduler``, the address, the package, the versions and the worker.
    """
    from gyro_instrument.core.errors import SceneError
    try:
        v = _within(timeout_s, lambda: client.get_versions(check=False))
        probes = _within(timeout_s, lambda: client.run(_import_probe(), on_error="return"))
    except Exception as exc:  # noqa: BLE001 - another Dask's answer fails in its own ways
        raise SceneError("--scheduler", address, f"did not report its versions within {timeout_s:g} s "
                                                 f"({exc.__class__.__name__}): it may run another Dask version "
                                                 f"than this client's") from None
    mine = _packages(v["client"]) | {"gyro_instrument": _own_version()}
    for who, info in [("the scheduler", v["scheduler"])] + [(f"worker {w}", i) for w, i in v["workers"].items()]:
        theirs = _packages(info) | ({} if who == "the scheduler" else probe_result(probes.get(w_of(who))))
        for name in SAME_VERSIONS:
            if name in mine and name in theirs and _comparable(name, mine[name]) != _comparable(name, theirs[name]):
                raise SceneError("--scheduler", address, f"{who} runs {name} {theirs[name]}, this client "
                                                         f"{mine[name]}: use the same versions everywhere")
        if who == "the scheduler":
            continue
        if theirs.get("gyro_instrument") is None:
            raise SceneError("--scheduler", address, f"{who} cannot import gyro_instrument "
                                                     f"({theirs.get('import_error')}): install it there "
                                                     f"(pip install gyro_instrument=={mine['gyro_instrument']})")
        if theirs["gyro_instrument"] != mine.get("gyro_instrument"):
            raise SceneError("--scheduler", address, f"{who} runs gyro_instrument {theirs['gyro_instrument']}, this "
                                                     f"client {mine.get('gyro_instrument')}: install the same version")


#: the probe run on every worker (``Client.run``): defined from source in a module of its own so
#: that cloudpickle sends it by value: a worker without this package cannot unpickle a function of it
_PROBE_SOURCE = """
def probe():
    try:
        import gyro_instrument
    except Exception as exc:
        return {"import_error": type(exc).__name__ + ": " + str(exc)}
    from importlib import metadata
    try:
        return {"gyro_instrument": metadata.version("gyro_instrument")}
    except Exception:
        return {"gyro_instrument": getattr(gyro_instrument, "__version__", "unknown")}
"""


def _import_probe():
    """The worker-side probe: imports gyro_instrument, returns its version or the import error."""
    namespace = {"__name__": "gyro_instrument_worker_probe"}
    exec(compile(_PROBE_SOURCE, "<gyro_instrument worker probe>", "exec"), namespace)   # noqa: S102
    return namespace["probe"]


def _own_version() -> str:
    """This client's gyro_instrument version (the installed distribution's, as the probe reads it)."""
    from importlib import metadata
    try:
        return metadata.version("gyro_instrument")
    except metadata.PackageNotFoundError:
        return "unknown"


def probe_result(result) -> dict:
    """A worker's probe answer as ``{"gyro_instrument": version}`` or ``{"import_error": why}``
    (an exception the run returned instead, or no answer, is an import error too)."""
    if isinstance(result, dict):
        return result
    why = "no answer" if result is None else f"{type(result).__name__}: {result}"
    return {"import_error": why}


def w_of(who) -> str:
    """The worker address of a ``"worker ADDRESS"`` label."""
    return who.split(" ", 1)[1]


def _packages(info) -> dict:
    """{package: version} of one entry of ``Client.get_versions`` (host's python included)."""
    out = dict(info.get("packages", {}))
    python = info.get("host", {}).get("python") or out.get("python")
    if python:
        out["python"] = python
    return out


def _comparable(name, version) -> str:
    """The part of a version that must agree: Python's major.minor (pickles move between patch
    releases), every other package's whole version."""
    return ".".join(str(version).split(".")[:2]) if name == "python" else str(version)


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
