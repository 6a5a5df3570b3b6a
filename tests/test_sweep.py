"""``gyro-instrument sweep`` (issue 27 item 4): a grid of any scene's values, one Parquet row per
(grid point, seed) through the process pool or a Dask cluster on loopback; bad ``--vary`` specs
exit 2 with one line; a worker killed during the run leaves no traceback."""

import os
import signal

import pytest

from gyro_instrument.bench.sweep import MAX_POINTS, parse_vary, run_sweep, sweep_point
from gyro_instrument.cli import main


def read(path):
    import pyarrow.parquet as pq
    return pq.read_table(path).to_pylist()


def test_two_latitudes_three_seeds_through_the_process_pool(tmp_path, capsys):
    out = tmp_path / "s.parquet"
    argv = ["sweep", "quet_gyroscopes", "--vary", "site.latitude_deg=30:60:30", "--seeds", "3",
            "--duration-s", "120", "--out", str(out)]
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert "2/2 points" in cap.err and "6 rows" in cap.out
    rows = read(out)
    assert len(rows) == 6
    assert [r["site.latitude_deg"] for r in rows] == [30, 30, 30, 60, 60, 60]
    assert [r["seed"] for r in rows] == [0, 1, 2] * 2
    for r in rows:
        assert r["error"] is None
        assert r["truth.latitude_deg"] == pytest.approx(r["site.latitude_deg"], abs=1e-9)
        assert abs(r["latitude_deg"] - r["truth.latitude_deg"]) < 5 * r["latitude_sigma_deg"]
        assert isinstance(r["checks"], str)              # a list: JSON text
    assert main(argv) == 2                               # an existing --out needs --overwrite
    assert "exists" in capsys.readouterr().err


@pytest.mark.parametrize("spec, words", [
    ("site.latitude_deg", ["--vary", "KEY=START:STOP:STEP"]),
    ("site.latitude_deg=0:10:0", ["STEP", "must be > 0"]),
    ("site.latitude_deg=0:10:-1", ["STEP", "must be > 0"]),
    ("site.latitude_deg=10:0:1", ["STOP", ">= START"]),
    ("site.latitude_deg=0:1:1e-5", ["100001", str(MAX_POINTS)]),
    ("site.latitude_deg=0:1", ["KEY=START:STOP:STEP"]),
    ("site.latitude_deg=a:1:1", ["START", "'a'"]),
    ("site.latitud_deg=0:10:10", ["latitud"]),
    ("site.latitude_deg=0:100:50", ["site.latitude_deg", "100", "[-90, 90]"]),
    ("seed=0:3:1", ["--seeds"]),
])
def test_bad_vary_specs_exit_2_with_one_line(tmp_path, capsys, spec, words):
    out = tmp_path / "bad.parquet"
    assert main(["sweep", "quet_gyroscopes", "--vary", spec, "--seeds", "2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("gyro-instrument: error:"), err
    assert all(w in err[0] for w in words), err
    assert not out.exists()


def test_grid_includes_stop_only_on_the_grid():
    assert parse_vary("a=0:1:0.1")[1][-1] == 1                # 10 steps of 0.1 land on 1 within 1e-9
    assert parse_vary("a=0:1:0.3")[1] == pytest.approx([0, 0.3, 0.6, 0.9])
    assert parse_vary("a=5:5:1")[1] == [5]
    assert parse_vary("a=-60:60:30")[1] == [-60, -30, 0, 30, 60]


def test_no_scheduler_and_no_workers_exit_2(tmp_path, capsys):
    assert main(["sweep", "quet_gyroscopes", "--vary", "site.latitude_deg=1:1:1", "--out", str(tmp_path / "x.parquet"),
                 "--scheduler", "tcp://127.0.0.1:9", "--timeout", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no Dask scheduler answered" in err[0]
    from dask.distributed import LocalCluster
    with LocalCluster(host="127.0.0.1", n_workers=0, processes=True, dashboard_address=None) as cluster:
        assert main(["sweep", "quet_gyroscopes", "--vary", "site.latitude_deg=1:1:1", "--out", str(tmp_path / "x.parquet"),
                     "--scheduler", cluster.scheduler_address, "--timeout", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "no workers" in err[0] and "has no workers after 1 s" in err[-1] and "Traceback" not in "".join(err)
    assert not (tmp_path / "x.parquet").exists()


def test_a_killed_dask_worker_is_retried(tmp_path, capsys):
    """The task kills its own worker process once (a marker file); the nanny restarts the worker and
    the point is run again (by Dask's rescheduling or by the sweep's one retry): its rows are there,
    estimated, once each, and the task started exactly twice (the killed run and the retry)."""
    from dask.distributed import LocalCluster

    from gyro_instrument.core.parallel import dask_executor
    marker = str(tmp_path / "killed")
    starts = str(tmp_path / "starts")

    def killer(job):
        with open(starts, "a") as fh:
            fh.write("start\n")
        if not os.path.exists(marker):
            open(marker, "w").close()
            os.kill(os.getpid(), signal.SIGKILL)
        return sweep_point(job)

    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    out = tmp_path / "k.parquet"
    with LocalCluster(host="127.0.0.1", n_workers=1, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        with dask_executor(cluster.scheduler_address, need_workers=True) as ex:
            r = run_sweep("quet_gyroscopes", ["duration_s=60"], ["site.latitude_deg=45:45:1"], 2, str(out),
                          executor=ex, progress=print, task=killer)
    assert os.path.exists(marker) and open(starts).read().split() == ["start", "start"]
    assert (r["rows"], r["errors"]) == (2, 0)
    rows = read(out)
    assert [(row["site.latitude_deg"], row["seed"], row["error"]) for row in rows] == [(45, 0, None), (45, 1, None)]
    for row in rows:
        # 60 s of quet_gyroscopes: the latitude within 5 of its reported sigma (as the pool's sweep above)
        assert abs(row["latitude_deg"] - 45) < 5 * row["latitude_sigma_deg"]
    assert "Traceback" not in capsys.readouterr().err


def test_a_failing_task_is_retried_once_then_reported():
    """The sweep's own retry (a process pool's BrokenProcessPool, Dask's KilledWorker): once, then
    the point's ``error``."""
    from concurrent.futures import ThreadPoolExecutor

    from gyro_instrument.bench.sweep import run_points
    calls = {}

    def flaky(job):
        calls[job] = calls.get(job, 0) + 1
        if job == "always" or calls[job] == 1:
            raise RuntimeError(f"worker died on {job}")
        return {"estimates": [job]}

    with ThreadPoolExecutor(2) as ex:
        res = run_points(["once", "always"], executor=ex, task=flaky)
    assert res[0] == {"estimates": ["once"]} and calls == {"once": 2, "always": 2}
    assert res[1]["error"] == "failed twice: RuntimeError: worker died on always"


def test_plan_verify_runs_on_the_sweeps_runner(monkeypatch):
    """``plan --verify`` (the bench's planner study) runs its seed chunks on the sweep's runner
    (core.parallel.run_tasks): a chunk whose worker dies once is run again and every seed counts; a
    chunk that fails twice ends the verification with one IntegrationError naming the reason (a dead
    worker was a BrokenProcessPool traceback before)."""
    from concurrent.futures import ThreadPoolExecutor

    from gyro_instrument.core.errors import IntegrationError
    from gyro_instrument.estimators import pipeline, planner
    real, calls = pipeline.seed_sweep, []

    def dies_once(job):
        calls.append(job[2][0])
        if job[2][0] == 0 and calls.count(0) == 1:
            raise RuntimeError("worker died")
        return real(job)

    monkeypatch.setattr(pipeline, "seed_sweep", dies_once)
    with ThreadPoolExecutor(2) as ex:
        out = planner.verify("quet_paris", [], 60.0, n_seeds=4, executor=ex, chunk=2)
    assert calls.count(0) == 2 and calls.count(2) == 1
    assert out["latitude"][1] + out["latitude"][2] == 4

    def gone(job):
        raise RuntimeError("worker gone")

    monkeypatch.setattr(pipeline, "seed_sweep", gone)
    with ThreadPoolExecutor(2) as ex, pytest.raises(IntegrationError, match="2 of 2 chunks of seeds failed twice"):
        planner.verify("quet_paris", [], 60.0, n_seeds=4, executor=ex, chunk=2)
