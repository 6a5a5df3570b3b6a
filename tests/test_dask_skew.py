"""Issue 38: ``sweep --scheduler`` against a cluster it cannot run on. Workers without this package
gave every row "failed twice: RuntimeError: Error during deserialization" and exit 0; a scheduler of
another Dask version a 65-line TypeError traceback after 21.8 s despite ``--timeout 10``. Now the
client asks the cluster for its versions (``Client.get_versions``, gyro_instrument included) within
``--timeout`` and refuses in one line naming the package, the versions and the worker: exit 2,
nothing written (core/parallel.py ``check_cluster``). Loopback only."""

import os
import subprocess
import sys
import time

import pytest

from gyro_instrument.cli import main as core_main
from machine_env import cli

SWEEP = ["sweep", "quet_paris", "--vary", "site.latitude_deg=40:41:1", "--duration-s", "20", "--timeout", "20"]


@pytest.fixture
def scheduler_without_package(tmp_path):
    """A scheduler with one worker process whose Python cannot import gyro_instrument (a
    sitecustomize on its PYTHONPATH blocks it, as a machine without the package would)."""
    from dask.distributed import Client, LocalCluster
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text("import sys\nsys.modules['gyro_instrument'] = None\n")
    with LocalCluster(host="127.0.0.1", n_workers=0, dashboard_address=None, processes=True) as cluster:
        env = dict(os.environ, PYTHONPATH=str(hide), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", cluster.scheduler_address,
                                   "--no-nanny", "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard"],
                                  env=env, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            with Client(cluster.scheduler_address, set_as_default=False) as c:
                c.wait_for_workers(1, timeout=60)
            yield cluster.scheduler_address
        finally:
            worker.terminate()
            worker.wait(timeout=30)


def test_workers_without_the_package_are_refused_in_one_line(scheduler_without_package, tmp_path):
    # in a process of its own, bounded: before, the sweep's tasks killed that worker and the run waited
    # for workers forever
    out = tmp_path / "s.parquet"
    r = subprocess.run(cli(*SWEEP, "--out", out, "--scheduler", scheduler_without_package), capture_output=True,
                       text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    err = r.stderr.splitlines()                # the one line, nothing else
    # the worker's own ImportError (the sitecustomize's block), and 0.1.0: setup.py's version
    assert len(err) == 1 and "worker tcp://127.0.0.1:" in err[0] and (
        "cannot import gyro_instrument (ModuleNotFoundError: import of gyro_instrument halted; None in sys.modules): "
        "install it there (pip install gyro_instrument==0.1.0)") in err[0], err
    assert not out.exists() and not os.path.exists(f"{out}.partial")


@pytest.fixture(scope="module")
def scheduler():
    from dask.distributed import LocalCluster
    with LocalCluster(host="127.0.0.1", protocol="tcp", n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=None) as cluster:
        yield cluster.scheduler_address


def _skewed(package, version):
    """Client.get_versions as the real one, with this client's ``package`` reported as ``version``
    (the other side of a version skew, without a second Dask installed)."""
    from distributed import Client
    real = Client.get_versions

    def get_versions(self, *args, **kwargs):
        v = real(self, *args, **kwargs)
        v["client"]["packages"][package] = version
        return v
    return get_versions


@pytest.mark.parametrize("package", ["distributed", "gyro_instrument"])
def test_another_version_is_named_in_one_line(scheduler, tmp_path, capsys, monkeypatch, package):
    import distributed
    from distributed import Client
    if package == "distributed":
        monkeypatch.setattr(Client, "get_versions", _skewed(package, "2023.1.0"))
    else:             # this client's own version, as parallel.py reads it (the workers' comes from their probe)
        from gyro_instrument.core import parallel
        monkeypatch.setattr(parallel, "_own_version", lambda: "2023.1.0")
    out = tmp_path / "s.parquet"
    assert core_main([*SWEEP, "--out", str(out), "--scheduler", scheduler]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("gyro-instrument: error")]
    theirs = distributed.__version__ if package == "distributed" else "0.1.0"
    who = "the scheduler" if package == "distributed" else "worker tcp://"
    assert len(err) == 1 and f"{who}" in err[0] and f"runs {package} {theirs}, this client 2023.1.0" in err[0], err
    assert not out.exists()


def test_a_cluster_that_does_not_report_is_refused_within_the_timeout(scheduler, tmp_path, capsys, monkeypatch):
    # a request that never comes back (another Dask's handshake can hang): refused after --timeout
    from distributed import Client
    monkeypatch.setattr(Client, "get_versions", lambda self, *a, **k: time.sleep(60))
    assert core_main([*SWEEP[:-1], "1", "--out", str(tmp_path / "s.parquet"), "--scheduler", scheduler]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("gyro-instrument: error")]
    assert len(err) == 1 and "did not report its versions within 1 s (TimeoutError)" in err[0], err
