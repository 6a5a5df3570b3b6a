"""core.jit: the compiled kernel and the plain function agree; GYRO_INSTRUMENT_JIT=0 turns compilation off."""

import os
import subprocess
import sys

import numpy as np

from gyro_instrument.core import jit


def _horner(c, x):
    out = np.empty_like(x)
    for i in range(x.size):
        acc = 0.0
        for k in range(c.size):
            acc = acc * x[i] + c[k]
        out[i] = acc
    return out


def test_compiled_kernel_equals_the_plain_function():
    # CI installs numba (setup.py): the kernels must really compile there, not fall back silently.
    assert jit.enabled(), jit.status()
    c = np.array([1.5, -2.0, 0.25, 3.0])
    x = np.linspace(-2.0, 2.0, 101)
    k = jit.compiled(_horner)
    assert k is not _horner
    # Same operations in the same order without fastmath: equal to the last bit.
    np.testing.assert_array_equal(k(c, x), _horner(c, x))


def test_environment_turns_compilation_off():
    code = ("from gyro_instrument.core import jit; import sys; "
            "print(jit.enabled(), jit.status()); sys.exit('numba' in sys.modules)")
    env = dict(os.environ, GYRO_INSTRUMENT_JIT="0")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.split()[0] == "False" and "GYRO_INSTRUMENT_JIT=0" in out.stdout
