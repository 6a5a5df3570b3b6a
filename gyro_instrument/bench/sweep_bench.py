"""Sweep throughput (issue 27, Bench): rows per second of ``gyro-instrument sweep``'s runner
(:func:`gyro_instrument.bench.sweep.run_sweep`, Parquet written) on the spawned process pool and
on a two-worker ``dask.distributed`` ``LocalCluster`` on loopback (host 127.0.0.1, worker
processes with one thread and one BLAS thread each), the same grid and seeds in one run.

Both executors have two workers. The pool spawns its processes at its first task, inside the wall
time, as ``gyro-instrument sweep`` does; the cluster is started before the clock (its start-up is
reported apart, ``startup_s``: a cluster is already running when a sweep is sent to it). The wall
time covers the grid check, every task — whose first on each worker imports the package — and the
Parquet write. Throughput = rows / wall time
(a sweep's rows are (grid point, seed) pairs; each point is one simulation and its seeds' estimates).
The rows of the two runs are compared field by field: the same seeds give the same estimates
wherever they run (``same_rows_as_process_pool``).
"""

import logging
import os
import tempfile
import time

from gyro_instrument.bench.sweep import run_sweep
from gyro_instrument.core.files import opened_unless_utf8
from gyro_instrument.core.parallel import dask_executor, process_executor

#: Workers of each executor (the pool's processes, the cluster's worker processes).
WORKERS = 2

#: (scene, overrides, --vary specs, seeds) of the full and the quick study.
GRIDS = {
    False: ("quet_paris", ["duration_s=300"], ["site.latitude_deg=-60:60:20"], 10),
    True: ("quet_gyroscopes", ["duration_s=60"], ["site.latitude_deg=30:60:30"], 3),
}


def _read_rows(path) -> list:
    import pyarrow.parquet as pq
    with opened_unless_utf8(path) as src:
        return pq.read_table(src).to_pylist()


def _row(scheduler, scene, overrides, specs, n_seeds, summary, startup_s, same) -> dict:
    return {"scheduler": scheduler, "scene": scene, "overrides": " ".join(overrides), "vary": " ".join(specs),
            "seeds": n_seeds, "points": summary["points"], "rows": summary["rows"], "errors": summary["errors"],
            "wall_s": summary["wall_s"], "rows_per_s": summary["rows_per_s"], "startup_s": startup_s,
            "same_rows_as_process_pool": same}


def sweep_throughput_rows(quick=False, progress=print) -> list[dict]:
    """Two rows (process pool, Dask LocalCluster), each a dict with ``scheduler``, ``scene``,
    ``overrides``, ``vary``, ``seeds``, ``points``, ``rows``, ``errors`` (points whose estimate was
    refused or whose task failed twice), ``wall_s`` (s), ``rows_per_s``, ``startup_s`` (executor
    start, s, not in ``wall_s``) and ``same_rows_as_process_pool`` (every row of the cluster's
    Parquet equal to the pool's: True for the pool's own row). The full study is quet_paris at
    seven latitudes −60°…60°, 10 seeds of 300 s (70 rows); ``quick``: quet_gyroscopes at two
    latitudes, 3 seeds of 60 s. Needs Dask (``dask[distributed]``) for the cluster row."""
    scene, overrides, specs, n_seeds = GRIDS[bool(quick)]
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")          # read by the cluster's worker processes at start
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        pool_out, dask_out = os.path.join(tmp, "pool.parquet"), os.path.join(tmp, "dask.parquet")
        progress(f"  sweep throughput: {scene} {' '.join(specs)} x {n_seeds} seeds on a {WORKERS}-process pool")
        t0 = time.perf_counter()
        with process_executor(WORKERS) as pool:
            startup = time.perf_counter() - t0
            s = run_sweep(scene, overrides, specs, n_seeds, pool_out, executor=pool)
        rows.append(_row(f"process pool ({WORKERS} spawned processes)", scene, overrides, specs, n_seeds, s,
                         startup, True))
        progress(f"  sweep throughput: the same on a {WORKERS}-worker Dask LocalCluster on 127.0.0.1")
        from dask.distributed import LocalCluster
        t0 = time.perf_counter()
        with LocalCluster(host="127.0.0.1", n_workers=WORKERS, threads_per_worker=1, processes=True,
                          dashboard_address=None, silence_logs=logging.ERROR) as cluster:
            with dask_executor(cluster.scheduler_address, need_workers=True) as ex:
                startup = time.perf_counter() - t0
                s = run_sweep(scene, overrides, specs, n_seeds, dask_out, executor=ex)
        same = _read_rows(dask_out) == _read_rows(pool_out)
        rows.append(_row(f"dask.distributed LocalCluster ({WORKERS} worker processes x 1 thread, 127.0.0.1)",
                         scene, overrides, specs, n_seeds, s, startup, same))
    for r in rows:
        progress(f"  {r['scheduler']}: {r['rows']} rows in {r['wall_s']:.2f} s = {r['rows_per_s']:.3g} rows/s")
    return rows
