"""Issue 38: ``describe`` says which path (compiled or not) a run takes under the environment it
sees, and a run takes that path. ``NUMBA_DISABLE_JIT=1`` used to leave ``describe`` saying
"compiled" while numba ran every kernel as interpreted Python (the same numbers in 60 s instead of
2.2 s); it now turns the compiled paths off like ``GYRO_INSTRUMENT_JIT=0`` (core/jit.py)."""

import json
import os
import subprocess

from machine_env import cli

#: the kernels line of describe, and whether the process then takes the compiled path (jit.enabled)
CHECK = ("import json, sys; from gyro_instrument import api; from gyro_instrument.core import jit; "
         "from gyro_instrument.scenes import load_scene; "
         "print(json.dumps([api.describe(load_scene('quet_paris'))['kernels'], jit.enabled()]))")


def test_describe_names_the_path_a_run_takes(tmp_path):
    fake = tmp_path / "no_numba" / "numba"      # a numba that cannot be imported (as a broken install)
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('numba hidden by the test')\n")
    base = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT", "GYRO_INSTRUMENT_JIT")}
    cases = {"default": {}, "GYRO_INSTRUMENT_JIT=0": {"GYRO_INSTRUMENT_JIT": "0"},
             "NUMBA_DISABLE_JIT=1": {"NUMBA_DISABLE_JIT": "1"},
             "missing": {"PYTHONPATH": os.pathsep.join([str(fake.parent), os.environ.get("PYTHONPATH", "")])}}
    procs = {name: subprocess.Popen(cli("describe", "quet_paris", "--json")[:1] + ["-c", CHECK], env=base | extra,
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for name, extra in cases.items()}
    got = {}
    for name, p in procs.items():
        out, err = p.communicate(timeout=120)
        assert p.returncode == 0 and not err.strip(), (name, err)
        got[name] = json.loads(out)
    kernels, enabled = got["default"]
    assert kernels.startswith("compiled, numba ") and kernels.endswith("(cached)") and enabled
    assert got["GYRO_INSTRUMENT_JIT=0"] == ["uncompiled: GYRO_INSTRUMENT_JIT=0", False]
    assert got["NUMBA_DISABLE_JIT=1"][0].startswith("uncompiled: NUMBA_DISABLE_JIT=1") and not got["NUMBA_DISABLE_JIT=1"][1]
    assert got["missing"][0].startswith("uncompiled: numba not importable (ImportError: numba hidden by the test")
    assert not got["missing"][1]


def test_describe_prints_the_kernels_line(monkeypatch, capsys):
    from gyro_instrument.cli import main as core_main
    from gyro_instrument.core import jit
    monkeypatch.setenv("GYRO_INSTRUMENT_JIT", "0")
    jit._numba.cache_clear()
    try:
        assert core_main(["describe", "quet_paris"]) == 0
    finally:
        monkeypatch.undo()
        jit._numba.cache_clear()          # this process's kernels as before the test
    assert "  kernels: uncompiled: GYRO_INSTRUMENT_JIT=0" in capsys.readouterr().out.splitlines()
