"""Ctrl-C (SIGINT) at several moments of a real ``gyro-instrument`` process: stderr is exactly
the one line ``gyro-instrument: interrupted``, the exit status is 130, and the ``--out`` file
either does not exist or is complete (no ``.partial`` is left behind).

The moments are found by watching the process, not by guessing delays: "during the imports"
is when numpy's extension module is mapped but scipy's integrators are not yet; "mid-run" is a
second after scipy's integrators are mapped, in a run that takes minutes.
"""

import os
import shutil
import signal
import subprocess
import sys
import time

import pytest

EXE = shutil.which("gyro-instrument", path=os.path.dirname(sys.executable)) or "gyro-instrument"
ONE_LINE = "gyro-instrument: interrupted\n"
#: The adaptive DOP853 keeps these runs minutes long (the default parareal fast path would finish a
#: 100 000 s run in seconds, before the moment to interrupt).
SLOW = ("--set", "instruments.pendulum.integrator=adaptive")


def mapped(pid, needle):
    try:
        with open(f"/proc/{pid}/maps") as fh:
            return needle in fh.read()
    except OSError:
        return False


def interrupt_when(cmd, ready, after_s=0.0, timeout=120, group=False):
    """Start ``cmd``, wait until ``ready(pid)``, sleep ``after_s``, send SIGINT (to the process
    group when ``group``, as a terminal's Ctrl-C does); return (returncode, stdout, stderr)."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=group)
    t0 = time.monotonic()
    while not ready(p.pid):
        assert p.poll() is None, f"finished before the moment to interrupt: {p.communicate()}"
        assert time.monotonic() - t0 < timeout, "never reached the moment to interrupt"
        time.sleep(0.002)
    time.sleep(after_s)
    assert p.poll() is None, "finished before the interrupt"
    if group:
        os.killpg(p.pid, signal.SIGINT)
    else:
        p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    return p.returncode, out, err


def importing(pid):
    """numpy's C core is loaded, scipy's integrators are not: the CLI is still importing."""
    return mapped(pid, "_multiarray_umath") and not mapped(pid, "scipy/integrate")


def imported(pid):
    return mapped(pid, "scipy/integrate")


def assert_interrupted(rc, err):
    assert rc == 130, (rc, err)
    assert err == ONE_LINE, err


@pytest.mark.parametrize("moment, ready, after_s", [
    ("during imports", importing, 0.0),
    ("mid-simulation", imported, 1.5),
])
def test_simulate_interrupted_one_line_130_no_output(tmp_path, moment, ready, after_s):
    out = tmp_path / "run.csv"
    rc, _, err = interrupt_when([EXE, "simulate", "foucault_pantheon", "--duration-s", "100000", *SLOW, "--quiet",
                                 "--out", str(out)], ready, after_s)
    assert_interrupted(rc, err)
    assert os.listdir(tmp_path) == []          # neither run.csv nor run.csv.partial


def test_simulate_interrupted_while_writing_leaves_no_partial(tmp_path):
    """Interrupt once the CSV is being written: the .partial goes, the output never appears."""
    out = tmp_path / "run.csv"
    part = tmp_path / "run.csv.partial"
    rc, _, err = interrupt_when([EXE, "simulate", "foucault_pantheon", "--duration-s", "20000", *SLOW, "--quiet",
                                 "--out", str(out)], lambda pid: part.exists() and part.stat().st_size > 1000,
                                timeout=300)
    assert_interrupted(rc, err)
    assert os.listdir(tmp_path) == []


def test_simulate_progress_lines_then_one_line(tmp_path):
    """Without --quiet the progress lines come first; the interrupt is still one line, the last."""
    rc, _, err = interrupt_when([EXE, "simulate", "foucault_pantheon", "--duration-s", "100000", *SLOW,
                                 "--out", str(tmp_path / "x.csv")], imported, 1.0)
    assert rc == 130 and "Traceback" not in err and err.endswith(ONE_LINE), err
    assert all(line.startswith("simulating ") for line in err.splitlines()[:-1]), err


@pytest.mark.parametrize("ready, after_s", [(importing, 0.0), (imported, 1.5)], ids=["imports", "mid-estimate"])
def test_estimate_interrupted(ready, after_s):
    rc, out, err = interrupt_when([EXE, "estimate", "foucault_pantheon", "--duration-s", "100000", *SLOW], ready, after_s)
    assert_interrupted(rc, err)
    assert out == ""


def test_python_dash_m_interrupted_during_imports():
    rc, _, err = interrupt_when([sys.executable, "-m", "gyro_instrument.cli", "estimate", "foucault_pantheon",
                                 "--duration-s", "100000"], importing)
    assert_interrupted(rc, err)


def test_terminal_ctrl_c_to_the_process_group_mid_simulation(tmp_path):
    """A terminal sends SIGINT to every process of the group: still one line."""
    rc, _, err = interrupt_when([EXE, "simulate", "foucault_pantheon", "--duration-s", "100000", *SLOW, "--quiet",
                                 "--out", str(tmp_path / "x.csv")], imported, 1.0, group=True)
    assert_interrupted(rc, err)
    assert os.listdir(tmp_path) == []


POOL_SCRIPT = """
import sys, time
from gyro_instrument.cli import guarded
from gyro_instrument.core.parallel import process_executor

def body():
    ex = process_executor(2)
    try:
        return sum(1 for _ in ex.map(time.sleep, [60, 60]))
    finally:
        ex.shutdown()

sys.exit(guarded(body, process=True))
"""


def children(pid):
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as fh:
            return fh.read().split()
    except OSError:
        return []


def test_ctrl_c_stops_a_process_pool_at_once():
    """bench's sweeps run in a spawn process pool: Ctrl-C (to the group) gives one line and 130
    within seconds — the workers ignore SIGINT and are terminated, not waited for (60 s tasks)."""
    t0 = time.monotonic()
    rc, _, err = interrupt_when([sys.executable, "-c", POOL_SCRIPT], lambda pid: len(children(pid)) >= 3,
                                after_s=2.0, group=True)
    assert_interrupted(rc, err)
    assert time.monotonic() - t0 < 40
