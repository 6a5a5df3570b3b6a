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
_WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
if _WORKER.startswith("gw"):
    # each pytest-xdist worker (and every node it starts) in a DDS domain of its own (0-101 are valid
    # with Fast DDS' default ports): their graphs, /clock and /diagnostics never meet
    os.environ["ROS_DOMAIN_ID"] = str((int(os.environ["ROS_DOMAIN_ID"]) + 1 + int(_WORKER[2:])) % 101)
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

# Property tests draw the same examples on every run and every machine (a failure is reproduced by
# re-running, never lost to a random draw; no example database is written into the checkout). A
# search with fresh random draws: HYPOTHESIS_PROFILE=explore.
try:
    from hypothesis import settings as _hsettings
    _hsettings.register_profile("derandomized", derandomize=True, database=None, print_blob=True)
    _hsettings.register_profile("explore", derandomize=False)
    _hsettings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "derandomized"))
except ImportError:                    # the test extra not installed: the property tests fail on import
    pass


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


# ----------------------------------------------------------------------------- seeded sweeps
# The seeded calibrations (hundreds of sensor seeds of one simulated truth each) are CPU work on a
# process pool. One pool serves the whole session (spawning one costs seconds of imports). The sweeps
# tests declare with ``@pytest.mark.seed_sweep(scene, overrides, n)`` are all submitted to it, in test
# order, when the first such test starts: they then run on the cores the serial session leaves idle
# while the tests between them run, and each test collects its own. (Not earlier: the tests before it
# include wall-clock targets — the bench's plot, the ROS suite — that must not share the cores.) A
# sweep's numbers do not depend on when or where it runs (each task simulates its own truth; each
# seed's noise comes from its own generator, ``sensors.scene_rng``).
_POOL = []
_DECLARED = []         # (scene, overrides, n) of every declared sweep of the session, in test order
_PREFETCHED = {}       # (scene, overrides, n) -> [future of each chunk]
_FILE_SWEEPS = {}      # test file -> the sweeps its tests declare


def _pool():
    if not _POOL:
        from gyro_instrument.core.parallel import process_executor
        _POOL.append(process_executor(2))
    return _POOL[0]


def _chunks(scene, overrides, seeds):
    """Two tasks per sweep (even seeds, odd seeds: one simulation of the truth each)."""
    return [(scene, list(overrides), range(i, seeds, 2)) for i in range(2)]


def _submit(scene, overrides, seeds):
    from gyro_instrument.estimators.pipeline import seed_sweep
    return [_pool().submit(seed_sweep, c) for c in _chunks(scene, overrides, seeds)]


def _key(mark):
    return mark.args[0], tuple(mark.args[1]), mark.args[2]


def pytest_collection_finish(session):
    """Note every declared seed sweep of the selected tests, in test order (and per file)."""
    for item in session.items:
        for mark in item.iter_markers("seed_sweep"):
            _FILE_SWEEPS.setdefault(item.path, []).append(_key(mark))
            if _key(mark) not in _DECLARED:
                _DECLARED.append(_key(mark))


def pytest_runtest_setup(item):
    """At the first test that declares a sweep, submit every declared sweep of the session — under
    pytest-xdist (``--dist loadfile``: a worker runs whole files) those of the test's own file, as each
    worker collects every file but runs only some."""
    if _DECLARED and item.get_closest_marker("seed_sweep") is not None:
        keys = list(_DECLARED)
        if _WORKER:
            keys = [k for k in keys if k in _FILE_SWEEPS.get(item.path, ())]
        for key in keys:
            _PREFETCHED.setdefault(key, _submit(*key))
            _DECLARED.remove(key)


def pytest_sessionfinish(session):
    if _POOL:
        _POOL.pop().shutdown(wait=True, cancel_futures=True)


@pytest.fixture(scope="session")
def pool():
    """The session's spawned process pool (two workers, the CI machine's cores)."""
    return _pool()


@pytest.fixture(scope="session")
def sweep_seeds():
    """``sweep_seeds(scene, overrides, n)``: the estimate dicts of seeds 0..n-1 of one scene, through
    :func:`gyro_instrument.estimators.pipeline.seed_sweep` on the session's pool in two chunks (even
    seeds, then odd), in the order 0, 2, 4, ..., 1, 3, 5, ...; a sweep the test declared with
    ``@pytest.mark.seed_sweep(scene, overrides, n)`` was submitted when the first declaring test
    started."""
    def run(scene, overrides, seeds):
        futures = _PREFETCHED.pop((scene, tuple(overrides), seeds), None) or _submit(scene, overrides, seeds)
        return [r for fut in futures for r in fut.result()]
    return run
