"""Shared fixtures: effects and instruments built the way scenes build them.

Network safety: every test process that may start rclpy stays on loopback. Discovery is limited
to LOCALHOST, and when run as root the whole session re-executes inside a loopback-only network
namespace (``unshare -n``), so Fast DDS cannot reach any other address whoever starts pytest.
"""

import os
import shutil
import sys

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
os.environ.setdefault("AMENT_PREFIX_PATH", sys.prefix)
# child processes (the node executables, gyro-instrument) import the package from this checkout,
# not from wherever the venv's editable install points (a git worktree tests its own code)
_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
os.environ["PYTHONPATH"] = os.pathsep.join([_ROOT] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)
                                                     if p and p != _ROOT])
import pytest


def pytest_configure(config):
    """As root, re-run the whole session inside a loopback-only network namespace."""
    if (os.geteuid() == 0 and not os.environ.get("GYRO_IN_NETNS") and shutil.which("unshare")
            and shutil.which("ip") and not os.environ.get("GYRO_NO_NETNS")):
        capman = config.pluginmanager.getplugin("capturemanager")
        if capman is not None:
            capman.stop_global_capturing()
        os.environ["GYRO_IN_NETNS"] = "1"
        sys.stdout.flush()
        sys.stderr.flush()
        os.execvp("unshare", ["unshare", "-n", "sh", "-c", 'ip link set lo up && exec "$@"', "sh",
                              sys.executable, "-m", "pytest", *config.invocation_params.args])

from gyro_instrument.core.params import validate_params
from gyro_instrument.effects import REGISTRY as EFFECTS


def make(cls, site, effects=(), **params):
    """Build an instrument of class ``cls`` at ``site`` with the named effects (default params)."""
    eff = {}
    for e in effects:
        if isinstance(e, tuple):
            eff[e[0]] = EFFECTS[e[0]](**e[1])
        else:
            eff[e] = EFFECTS[e]()
    return cls("test", site, validate_params("instruments.test", cls.PARAMS, params), eff)


@pytest.fixture
def build():
    return make


@pytest.fixture
def ctx():
    """A private rclpy context for one test (the ROS tests' nodes in this process), shut down after."""
    import rclpy
    context = rclpy.Context()
    rclpy.init(context=context, args=[])
    yield context
    rclpy.shutdown(context=context)


@pytest.fixture(scope="session")
def pool():
    """One spawned process pool (two workers, the CI machine's cores) for every seeded sweep of the
    session. Spawning a pool costs seconds (each worker imports numpy, scipy and the package), and
    the seeded studies used to spawn one per test; a task's result does not depend on the pool or
    worker it runs in (each task simulates its own truth, each seed's noise comes from its own
    generator, ``sensors.scene_rng``), so sharing it changes no number."""
    from gyro_instrument.core.parallel import process_executor
    ex = process_executor(2)
    yield ex
    ex.shutdown()


@pytest.fixture(scope="session")
def sweep_seeds(pool):
    """``sweep_seeds(scene, overrides, n)``: the estimate dicts of seeds 0..n-1 of one scene, through
    :func:`gyro_instrument.estimators.pipeline.seed_sweep` on :func:`pool` in two chunks (even seeds,
    then odd: one simulation of the truth per chunk), in the order 0, 2, 4, ..., 1, 3, 5, ..."""
    from gyro_instrument.estimators.pipeline import seed_sweep

    def run(scene, overrides, seeds):
        chunks = [(scene, list(overrides), range(i, seeds, 2)) for i in range(2)]
        return [r for part in pool.map(seed_sweep, chunks) for r in part]
    return run
