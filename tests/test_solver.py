"""Issue 36: every integration driver implements core.solver.Solver (scipy's OdeSolver shape).

Each driver runs the pendulum θ̈ = −ω² sin θ (ω² = 4 s⁻², θ0 = 1 rad at rest; its energy
E = θ̇²/2 − ω² cos θ is exact) and must: step forward (``t_old`` < ``t``), give a dense output that
meets the step's ends, count evaluations, keep time, say its status, and resume block by block to
the one-shot run bit for bit.
"""

import math

import numpy as np
import pytest

from gyro_instrument.core import dop853_jit, jit
from gyro_instrument.core.dop853 import ScalarDOP853
from gyro_instrument.core.dop853_fortran import FortranRun
from gyro_instrument.core.integrate import Integration
from gyro_instrument.core.solver import FINISHED, RUNNING, Solver

W2 = 4.0
Y0 = [1.0, 0.0]
T = np.linspace(0.0, 6.0, 121)


def _scalar(t, a, b):
    return b, -W2 * math.sin(a)


def _array(t, y):
    return np.array(_scalar(t, *y))


def _kernel(t, y, p, dy):
    dy[0] = y[1]
    dy[1] = -p[0] * math.sin(y[0])


def _compiled_kernel():
    if not jit.enabled():
        return _kernel
    return jit.compiled(_kernel, signature_or_function=dop853_jit.rhs_signature())


DRIVERS = {
    "Integration (scipy OdeSolver)": lambda: Integration(_array, Y0, 0.0, 10.0, rtol=1e-10, atol=1e-12),
    "Integration, no end": lambda: Integration(_array, Y0, 0.0, math.inf, rtol=1e-10, atol=1e-12),
    "ScalarDOP853": lambda: ScalarDOP853(_scalar, Y0, 0.0, 10.0, rtol=1e-10, atol=1e-12),
    "CompiledRun": lambda: dop853_jit.CompiledRun(_compiled_kernel(), [W2], Y0, 0.0, 1e-10, 1e-12),
    "FortranRun": lambda: FortranRun(_scalar, Y0, 0.0, 1e-10, 1e-12),
}


def _energy(y):
    return 0.5 * y[1] ** 2 - W2 * np.cos(y[0])


@pytest.mark.parametrize("name", list(DRIVERS))
def test_step_dense_output_counts_and_status(name):
    run = DRIVERS[name]()
    assert isinstance(run, Solver)
    assert run.status == RUNNING and run.t_old is None
    before = run.nfev
    for _ in range(3):
        run.step()
    assert run.t_old < run.t and run.nfev > before
    sol = run.dense_output()
    ends = sol(np.array([run.t_old, run.t]))
    mid = sol(np.array([0.5 * (run.t_old + run.t)]))[:, 0]
    # the interpolant meets the step's end: the driver's own state there (to 1e-12 rad: rounding of
    # the interpolant's sums of terms of order 1)
    end = np.asarray(run.y, dtype=float)
    np.testing.assert_allclose(ends[:, 1], end, rtol=0, atol=1e-12)
    # and stays on the motion: the energy at the step's middle is E0 = −ω² cos 1 to 1e-6 (the
    # Hermite interpolant's error, (h⁴/384) |y⁗| with h ≲ 0.1 s: ≈ 1e-7; DOP853's 7th order: ≈ 1e-12)
    assert abs(_energy(mid) + W2 * math.cos(1.0)) < 1e-6
    assert run.wall_time_s >= 0.0 and run.cpu_time_s >= 0.0


@pytest.mark.parametrize("name", list(DRIVERS))
def test_blocks_resume_to_the_one_shot_run(name):
    one = DRIVERS[name]().advance(T)
    run = DRIVERS[name]()
    parts = [run.advance(T[a:b]) for a, b in ((0, 1), (1, 40), (40, 41), (41, 121))]
    np.testing.assert_array_equal(np.concatenate([p.y for p in parts], axis=1), one.y)
    assert parts[-1].nfev == run.nfev >= one.nfev > 0
    # the states solve the pendulum: energy constant to 1e-8 relative (rtol 1e-10, 6 s)
    assert np.ptp(_energy(one.y)) < 1e-8 * abs(_energy(one.y)[0])


def test_a_bounded_run_finishes():
    run = ScalarDOP853(_scalar, Y0, 0.0, 0.5, rtol=1e-10, atol=1e-12)
    run.advance(np.array([0.5]))
    assert run.status == FINISHED
    with pytest.raises(Exception, match="finished"):
        run.step()


def _instrument(scene_name, overrides, name):
    from gyro_instrument.scenes import build_instruments, load_scene
    return build_instruments(load_scene(scene_name, overrides))[name]


def _splitting_run():
    from gyro_instrument.core.rigid_body_flow import SplittingRun
    g = _instrument("free_gyroscope", ["instruments.free_gyro.model=numerical"], "free_gyro")
    y0 = np.concatenate([g.q0, g.R0.T @ g.motion_constants()["omega0"]])
    return SplittingRun(y0, 0.0, g.splitting_step(), g.p.splitting_order, g.p.inertia_ratio, g.torque_array())


def _fixed_step_run():
    body = _instrument("puiseux_spheroid", [], "spheroid")
    return body.integration_run(0.0, 1.0, body.p.rtol, 1e-12, "rk8")


def _swing_run():
    from gyro_instrument.instruments.pendulum.fast_path import SwingRun
    p = _instrument("foucault_pantheon", ["duration_s=200"], "pendulum")
    p.WINDOW_SWINGS = 4                  # windows of 4 swings (~66 s): a step is one window
    r0, v0 = p.initial_state()
    return SwingRun(p, 0.0, 200.0, r0, v0, p.p.length_m * math.sin(p.p.initial_deflection_rad))


ALL = dict(DRIVERS, SplittingRun=_splitting_run, FixedStepRun=_fixed_step_run, SwingRun=_swing_run)


@pytest.mark.parametrize("name", list(ALL))
def test_the_dense_output_is_what_advance_reads_there(name):
    """After a step, the dense output at the step's end is the state ``advance`` gives there, bit for
    bit (the same interpolant, or the same composition or substep, on the same doubles), and the run
    goes on from it. The fast path's windows meet at a grid point, where ``advance`` reads the next
    window's start (equal to the last one's interpolant at its end to rounding): it is asked inside
    the window."""
    run = ALL[name]()
    assert isinstance(run, Solver)
    run.step()
    run.step()
    at = np.array([run.t if name != "SwingRun" else run.t_old + 0.6 * (run.t - run.t_old)])
    dense = run.dense_output()(at)
    np.testing.assert_array_equal(dense, run.advance(at).y)
    later = run.advance(np.array([run.t + 0.25, run.t + 0.5]))
    assert later.y.shape[1] == 2 and np.all(np.isfinite(later.y))
