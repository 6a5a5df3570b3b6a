"""core.dop853_jit: the compiled DOP853 takes scipy's steps (as core.dop853's Python-float driver),
the compiled and plain drivers agree, blocks concatenate bit for bit, failures are named."""

import math

import numpy as np
import pytest

from gyro_instrument.core import dop853_jit, jit
from gyro_instrument.core.dop853 import ScalarDOP853
from gyro_instrument.core.errors import IntegrationError


def _pendulum(t, y, p, dy):
    """θ̈ = −ω² sin θ (ω² = p[0], rad/s²)."""
    dy[0] = y[1]
    dy[1] = -p[0] * math.sin(y[0])


def _blow_up(t, y, p, dy):
    """ẏ = y² (finite-time blow-up at t = 1/y0)."""
    dy[0] = y[0] * y[0]


def _kernel(fn):
    return jit.compiled(fn, signature_or_function=dop853_jit.rhs_signature()) if jit.enabled() else fn


T = np.linspace(0.0, 20.0, 401)


def test_compiled_driver_takes_the_python_float_drivers_steps():
    """Same tableau, initial step, error norm and step control as core.dop853.ScalarDOP853 (run with
    an end far away, so its last step is not cut): the same steps and rejections, and states equal
    to the last bit (both sum the stages in the same order; no fastmath)."""
    assert jit.enabled(), jit.status()
    run = dop853_jit.CompiledRun(_kernel(_pendulum), [4.0], [1.0, 0.0], 0.0, 1e-10, 1e-12)
    y = run.advance(T).y
    ref = ScalarDOP853(lambda t, a, b: (b, -4.0 * math.sin(a)), [1.0, 0.0], 0.0, 1e9, 1e-10, 1e-12).advance(T)
    assert run.meta["nsteps"] == ref.meta["nsteps"] and run.meta["nrejected"] == ref.meta["nrejected"]
    np.testing.assert_array_equal(y, ref.y)
    # and it solves the pendulum: the energy ½θ̇² − ω² cos θ to 1e-9 relative (rtol 1e-10)
    energy = 0.5 * y[1] ** 2 - 4.0 * np.cos(y[0])
    assert np.ptp(energy) < 1e-9 * abs(energy[0])


def test_compiled_equals_plain_and_blocks_concatenate():
    """The compiled driver and the plain Python one (``compiled=False``, the kernel uncompiled):
    bit for bit (the same operations in the same order). Blocks of any size: the one-shot run
    bit for bit (the steps never depend on the samples; the last step is kept across calls)."""
    kernel = _kernel(_pendulum)
    one = dop853_jit.CompiledRun(kernel, [4.0], [1.0, 0.0], 0.0, 1e-10, 1e-12).advance(T).y
    plain = dop853_jit.CompiledRun(_pendulum, [4.0], [1.0, 0.0], 0.0, 1e-10, 1e-12, compiled=False)
    assert "plain Python" in plain.meta["driver"]
    np.testing.assert_array_equal(plain.advance(T).y, one)
    run = dop853_jit.CompiledRun(kernel, [4.0], [1.0, 0.0], 0.0, 1e-10, 1e-12)
    parts = [run.advance(T[a:b]).y for a, b in ((0, 1), (1, 7), (7, 7), (7, 250), (250, 401))]
    np.testing.assert_array_equal(np.concatenate(parts, axis=1), one)
    assert run.nfev > 0


def test_failures_are_named():
    """A blow-up ends in a step below the spacing of floats (named); a non-finite start and a sample
    before the last step are refused."""
    kernel = _kernel(_blow_up)
    with pytest.raises(IntegrationError, match="step size"):
        dop853_jit.CompiledRun(kernel, [], [1.0], 0.0, 1e-10, 1e-12).advance(np.array([0.5, 2.0]))
    with pytest.raises(IntegrationError, match="not finite"):
        dop853_jit.CompiledRun(kernel, [], [math.nan], 0.0, 1e-10, 1e-12)
    run = dop853_jit.CompiledRun(_kernel(_pendulum), [4.0], [1.0, 0.0], 0.0, 1e-10, 1e-12)
    run.advance(np.array([0.0, 5.0]))
    with pytest.raises(IntegrationError, match="before the last step"):
        run.advance(np.array([1e-3]))
