"""Issue 38, any machine: a read-only install with a read-only HOME (containers, shared installs).

numba caches compiled kernels beside their source or under HOME; with both read-only it raised
``RuntimeError: cannot cache function 'swing_grid': no locator available`` (numba#5566, #4032).
The kernels now cache in a private temporary directory (one note), or compile uncached (one note)
when that is read-only too, and ``describe`` says which path a run takes (core/jit.py)."""

import json
import os

import pytest

from machine_env import ROOT, cli, install_dirs, needs_mount_ns, run_readonly

#: a kernel in a file of its own, so that the test can make its directory read-only
KERNEL = "def horner(c, x):\n    acc = 0.0\n    for k in range(c.size):\n        acc = acc * x + c[k]\n    return acc\n"
PROBE = ("import sys; sys.path.insert(0, sys.argv[1]); import numpy as np, tiny_kernel as t; "
         "from gyro_instrument.core import jit; k = jit.compiled(t.horner); "
         "print(k(np.array([1.5, -2.0, 0.25]), 2.0), jit.status())")


def _env(tmp):
    tmp.mkdir(exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "NUMBA_DISABLE_JIT",
                                                            "GYRO_INSTRUMENT_JIT")}
    return env | {"TMPDIR": str(tmp)}


def _one_note(stderr):
    lines = [ln for ln in stderr.splitlines() if ln.strip()]
    assert "Traceback" not in stderr and len(lines) == 1 and lines[0].startswith("gyro-instrument: note: "), stderr
    return lines[0]


@needs_mount_ns
def test_kernel_caches_in_a_private_temporary_directory(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    (src / "tiny_kernel.py").write_text(KERNEL)
    env = _env(tmp_path / "tmp")
    argv = [os.sys.executable, "-c", PROBE, src]
    first = run_readonly(argv, install_dirs() + [src], env, text=True)
    assert first.returncode == 0, first.stderr
    # 1.5*4 - 2*2 + 0.25 = 2.25 exactly in binary floating point (Horner: (1.5*2 - 2)*2 + 0.25)
    assert first.stdout.split()[0] == "2.25"
    private = tmp_path / "tmp" / f"gyro_instrument-numba-{os.getuid()}"
    note = _one_note(first.stderr)
    assert str(private) in note and "not writable" in note
    # numba's index and machine code of the kernel are there (src/ stayed read-only), private to this user
    assert any(private.rglob("tiny_kernel.horner-*.nbi")) and any(private.rglob("tiny_kernel.horner-*.nbc"))
    assert not list(src.glob("__pycache__/*.nb*"))
    assert oct(private.stat().st_mode & 0o777) == oct(0o700)
    assert f"cached in {private}" in first.stdout


@needs_mount_ns
def test_kernel_compiles_uncached_when_the_temporary_directory_is_read_only_too(tmp_path):
    src = tmp_path / "src"
    src.mkdir()
    (src / "tiny_kernel.py").write_text(KERNEL)
    env = _env(tmp_path / "tmp")
    # every directory Python's tempfile would pick (TMPDIR, /tmp, /var/tmp, /usr/tmp, the working directory)
    temps = [tmp_path / "tmp"] + [d for d in ("/tmp", "/var/tmp", "/usr/tmp") if os.path.isdir(d)]
    out = run_readonly([os.sys.executable, "-c", PROBE, src], install_dirs() + [src] + temps, env, text=True, cwd=src)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[0] == "2.25"
    assert "not cached" in _one_note(out.stderr) and "not cached" in out.stdout


def _main_commands(tmp_path, env):
    """simulate and estimate of quet_paris on a read-only install and HOME: exit 0, no
    traceback, the table and its scene written, the estimate read back from them."""
    out = tmp_path / "out"
    out.mkdir()
    ro = install_dirs()
    s = run_readonly(cli("simulate", "quet_paris", "--duration-s", "60", "--out", out / "q.csv", "--quiet"), ro, env,
                     text=True)
    assert s.returncode == 0 and "Traceback" not in s.stderr, s.stderr
    assert (out / "q.csv").is_file() and (out / "q.scene.yaml").is_file()
    e = run_readonly(cli("estimate", "--data", out / "q.csv", "--json"), ro, env, text=True)
    assert e.returncode == 0 and "Traceback" not in e.stderr, e.stderr
    # the scene quet_paris read back from the sidecar: the site's latitude (48.8462 deg, scenes/quet_paris.yaml)
    assert json.loads(e.stdout)["truth"]["latitude_deg"] == 48.8462


@needs_mount_ns
def test_main_commands_run_on_a_read_only_install_and_home(tmp_path):
    # describe under the same read-only install says where a compiled run caches (quet_paris's estimate
    # compiles north's exact fit: 20 s of numba on a cold cache, so the commands run it uncompiled
    # here and the compiled read-only run is the slow test below; the fallback itself is the tiny kernel's)
    env = _env(tmp_path / "tmp")
    d = run_readonly(cli("describe", "quet_paris", "--json"), install_dirs(), env, text=True)
    kernels = json.loads(d.stdout)["kernels"]
    assert kernels.startswith("compiled, numba ") and "cached in" in kernels and "not writable" in kernels
    assert d.returncode == 0 and "Traceback" not in d.stderr, d.stderr
    _main_commands(tmp_path, env | {"GYRO_INSTRUMENT_JIT": "0"})


@pytest.mark.slow
@needs_mount_ns
def test_main_commands_compiled_on_a_read_only_install_and_home(tmp_path):
    env = _env(tmp_path / "tmp")
    _main_commands(tmp_path, env)
    assert any((tmp_path / "tmp" / f"gyro_instrument-numba-{os.getuid()}").rglob("*.nbc"))   # kernels cached there
