"""A real cluster engine (issue 15 part 5): the sweeps' executor seam with ``dask.distributed``
(a LocalCluster of 2 worker processes on loopback, dashboard off) gives rows identical to the
spawned process pool. ``gyro-instrument bench --quick --scheduler ADDRESS`` running its sweeps on such a
cluster is tested in test_bench.py (its module fixture runs the whole quick bench that way); here a
scheduler that does not answer."""

import json
import os

import pytest

from gyro_instrument.cli import main as core_main
from gyro_instrument.core.parallel import dask_executor
from gyro_instrument.estimators.pipeline import seed_sweep

JOBS = [("quet_paris", ("duration_s=120",), (1, 2, 3)),
        ("quet_paris", ("duration_s=120", "site.latitude_deg=-33.87"), (4, 5))]


@pytest.fixture(scope="module")
def scheduler():
    from dask.distributed import LocalCluster
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")          # one BLAS thread per worker process, as the process pool
    with LocalCluster(host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        yield cluster.scheduler_address


def test_dask_rows_equal_the_process_pool_rows(scheduler, pool):
    # pool: the session's spawned process pool of two workers (conftest.py; idle this early in the run),
    # not a second one spawned here
    from gyro_instrument.bench.studies import site_sweep
    local = list(pool.map(seed_sweep, JOBS))
    local_sites = site_sweep((-33.9, 48.8462), 2, minutes=1.0, executor=pool)
    with dask_executor(scheduler) as ex:
        remote = list(ex.map(seed_sweep, JOBS))
        remote_sites = site_sweep((-33.9, 48.8462), 2, minutes=1.0, executor=ex)
    assert [len(r) for r in remote] == [3, 2]
    assert json.dumps(remote, sort_keys=True, default=str) == json.dumps(local, sort_keys=True, default=str)
    assert remote_sites == local_sites


def test_bench_scheduler_that_does_not_answer_exits_2(capsys, tmp_path):
    assert core_main(["bench", "--quick", "--out", str(tmp_path / "b"), "--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no Dask scheduler answered" in err[0]
    assert not (tmp_path / "b").exists()


def _prefixes(address):
    from dask.distributed import Client
    with Client(address, set_as_default=False) as client:
        return set(client.run_on_scheduler(lambda dask_scheduler: list(dask_scheduler.task_prefixes)))


def test_bench_scene_scheduler_runs_its_studies_on_the_cluster(scheduler, tmp_path):
    # `bench --scene S --scheduler ADDRESS` once ran both studies on a local process pool and left the
    # cluster idle: the observation-time study's seeds and systematic floors and the planner's seeds
    # now reach the scheduler (by their task functions' names), and the files are written
    before = _prefixes(scheduler)
    assert "systematic_floor_rows" not in before
    out = tmp_path / "scene_bench"
    assert core_main(["bench", "--quick", "--scene", "quet_paris", "--out", str(out), "--scheduler", scheduler]) == 0
    assert {"seed_sweep", "systematic_floor_rows"} <= _prefixes(scheduler)
    for name in ("observation_time.csv", "systematic_floors.csv", "planner.csv", "summary.md"):
        assert (out / name).exists(), name
