"""The pendulum's compiled fast path (issue 27 item 2): its kernels equal their plain Python functions,
the compiled run equals the numpy Newton-parareal run (GYRO_INSTRUMENT_JIT=0) to round-off, and the
bench's compiled reference integrates the same equations.

* :func:`~gyro_instrument.instruments.pendulum.fast_path.swing_grid` (serial RK8 over the swings) and
  :func:`~gyro_instrument.core.parareal.hermite_samples` (quintic Hermite output) compiled by numba
  against the same functions run by Python: the same operations in the same order without
  fastmath, so equal to the last bit; ``hermite_samples`` also equals numpy's
  :func:`~gyro_instrument.core.parareal.dense_output` bit for bit.
* The affine map of the point-mass terms the kernel integrates equals Coriolis −2 Ω × v and the
  centrifugal gradient −Ω × (Ω × δr) (Quet sec. 1 eqs. 16, 19); a non-affine term is refused
  (the numpy path then runs).
"""

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from gyro_instrument.core import dop853, jit
from gyro_instrument.core.effect import EffectContext
from gyro_instrument.core.parareal import dense_output, hermite_samples
from gyro_instrument.core.site import Site
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments.pendulum import SphericalPendulum
from gyro_instrument.instruments.pendulum.fast_path import linear_point_mass_map, swing_grid
from tests.conftest import make

PARIS = Site.from_degrees(48.8462)
FULL = ("earth_rotation", "finite_amplitude", "centrifugal")


def _pendulum(**params):
    return make(SphericalPendulum, PARIS, FULL, length_m=67.0, initial_deflection_deg=2.0, **params)


def test_swing_grid_compiled_equals_plain_python():
    assert jit.enabled(), jit.status()
    p = _pendulum(integrator="parareal")
    kernel, lin, consts = p.compiled_swings(2.3, 0.9, p.COMPILED_MIN_SWINGS)
    assert kernel is not swing_grid
    y0 = np.concatenate(p.initial_state())
    n, m, h = 3, 16, 16.4 / 16
    out = [(np.empty((n, m + 1, 6)), np.empty((n, m + 1, 6))) for _ in range(2)]
    kernel(y0, h, m, n, lin, consts, dop853.A, dop853.B, *out[0])
    swing_grid(y0, h, m, n, lin, consts, dop853.A, dop853.B, *out[1])
    np.testing.assert_array_equal(out[0][0], out[1][0])
    np.testing.assert_array_equal(out[0][1], out[1][1])
    # consecutive swings share their boundary point; derivatives are the right-hand side there
    np.testing.assert_array_equal(out[0][0][:-1, -1], out[0][0][1:, 0])
    rhs = p.rhs_exact()
    np.testing.assert_allclose(out[0][1][1, 5], rhs(0.0, out[0][0][1, 5]), rtol=1e-15, atol=1e-15 * 9.81)


def test_hermite_samples_equal_dense_output_bit_for_bit():
    from gyro_instrument.core.parareal import compiled_hermite_samples
    rng = np.random.default_rng(5)
    n, m, T = 7, 12, 3.7
    ys, fs = rng.standard_normal((n, m + 1, 6)), rng.standard_normal((n, m + 1, 6))
    grid = (np.ascontiguousarray(ys.transpose(1, 2, 0)), np.ascontiguousarray(fs.transpose(1, 2, 0)))
    # increasing times over the window, grid points and the window's ends included
    t = np.sort(np.concatenate([rng.uniform(0.0, n * T, 400), np.arange(n * m + 1) * (T / m)])) + 100.0
    want = dense_output(grid, T, (t - 100.0) - 0.0, 3)
    for kernel in (compiled_hermite_samples(), hermite_samples):
        out = np.empty((6, t.size))
        kernel(ys, fs, 3, T, t, 100.0, 0.0, out)
        np.testing.assert_array_equal(out, want)
    assert compiled_hermite_samples() is not hermite_samples
    # more samples than the kernel's block of 4096 (steps cut by a block boundary): still dense_output's doubles
    t = np.sort(rng.uniform(0.0, n * T, 9000)) + 100.0
    out = np.empty((6, t.size))
    compiled_hermite_samples()(ys, fs, 3, T, t, 100.0, 0.0, out)
    np.testing.assert_array_equal(out, dense_output(grid, T, (t - 100.0) - 0.0, 3))


def test_point_mass_map_is_coriolis_and_centrifugal():
    ctx = EffectContext.of_site(PARIS)
    om = PARIS.earth_rate_enu()
    terms = [EFFECTS[e]().point_mass_term(ctx) for e in ("earth_rotation", "centrifugal")]
    lin = linear_point_mass_map(terms, 2.3, 0.9)
    cross = np.array([[0.0, -om[2], om[1]], [om[2], 0.0, -om[0]], [-om[1], om[0], 0.0]])      # Ω ×
    np.testing.assert_allclose(lin[:, 3:6], -2.0 * cross, rtol=0, atol=1e-19)
    np.testing.assert_allclose(lin[:, :3], -cross @ cross, rtol=0, atol=1e-21)
    np.testing.assert_array_equal(lin[:, 6], 0.0)
    # a constant force is affine (its own column); a quadratic drag is not (numpy path instead)
    lin = linear_point_mass_map([lambda *u: (0.0, 0.0, -1e-6)], 2.3, 0.9)
    np.testing.assert_array_equal(lin[:, 6], [0.0, 0.0, -1e-6])
    assert linear_point_mass_map([lambda dx, dy, dz, vx, vy, vz: (-1e-3 * vx * abs(vx), 0.0, 0.0)], 2.3, 0.9) is None


def test_compiled_fast_path_equals_numpy_parareal(monkeypatch):
    # Both compute the sequential fine solution of the same RK8 grid (48 steps per swing): the
    # compiled path step after step, the numpy path by Newton-parareal converged to shooting_tol
    # = 1e-12 of the amplitude (2.34 m) at every swing start. Their difference is bounded by that
    # tolerance (2.3e-12 m) plus round-off: each step's sums are taken in different orders (BLAS
    # products against loops), ~ε |r| = 1.5e-14 m per step on the 67 m rod, accumulated over
    # 10 swings × 48 steps = 480 steps at most linearly: 7.1e-12 m; bound 1e-11 m (4e-12 of the
    # amplitude) on positions. Velocities: the tolerance times amplitude × ω0 (0.38 rad/s), 0.9e-12
    # m/s, plus 480 steps × ε g h (h = T/48 = 0.34 s: 7.4e-16 m/s each), 3.6e-13 m/s; bound 2e-12 m/s.
    monkeypatch.setattr(SphericalPendulum, "COMPILED_MIN_SWINGS", 1)
    t = np.arange(0.0, 10 * 16.4, 0.05)
    fast = _pendulum(integrator="parareal", shooting_tol=1e-12).simulate(t)
    monkeypatch.setattr(jit, "enabled", lambda: False)
    slow = _pendulum(integrator="parareal", shooting_tol=1e-12).simulate(t)
    assert "compiled, serial" in fast.trajectory.method and "parareal pass" in slow.trajectory.method
    assert np.max(np.abs(fast.extra["position_enu"] - slow.extra["position_enu"])) < 1e-11
    assert np.max(np.abs(fast.extra["velocity_enu"] - slow.extra["velocity_enu"])) < 2e-12
    assert abs(fast.columns["swing_azimuth"][-1] - slow.columns["swing_azimuth"][-1]) < 1e-11 / 2.34


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_fast_path_streams_bit_for_bit(monkeypatch, compiled):
    # compiled, and on numpy (GYRO_INSTRUMENT_JIT=0 or a short run): windows of 4 swings, blocks cut
    # elsewhere, concatenate to one simulate
    monkeypatch.setattr(SphericalPendulum, "COMPILED_MIN_SWINGS", 1)
    if not compiled:
        monkeypatch.setattr(jit, "enabled", lambda: False)
    monkeypatch.setattr(SphericalPendulum, "WINDOW_SWINGS", 4)
    p = _pendulum(integrator="parareal")
    t = np.arange(0.0, 150.0 + 1e-9, 0.05)
    one = p.simulate(t)
    parts = list(p.stream(np.array_split(t, 7), t_end=float(t[-1])))
    assert ("compiled, serial" if compiled else "parareal passes") + " in 3 windows" in one.trajectory.method
    for key in one.columns:
        np.testing.assert_array_equal(np.concatenate([s.columns[key] for s in parts]), one.columns[key])


def test_uncompiled_run_does_not_import_numba():
    code = ("import sys, numpy as np; from gyro_instrument.scenes import load_scene, build_instruments; "
            "p = build_instruments(load_scene('foucault_pantheon', ['duration_s=40']))['pendulum']; "
            "s = p.simulate(np.arange(0.0, 40.0, 0.05)); print(s.trajectory.method); sys.exit('numba' in sys.modules)")
    env = dict(os.environ, GYRO_INSTRUMENT_JIT="0")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "parareal pass" in out.stdout


def test_compiled_reference_integrates_the_same_equations():
    # The bench's reference writes Coriolis and the centrifugal gradient from Ω; the fast path's
    # kernel takes them from the effects' terms. On the same steps (10 swings × 48) their end
    # states agree to round-off: 480 steps × ε |r| (1.5e-14 m) = 7e-12 m, bound 1e-11 m.
    from gyro_instrument.bench.compiled_reference import compiled_rk8_reference, rk8_reference
    p = _pendulum(integrator="parareal")
    kernel, lin, consts = p.compiled_swings(2.3, 0.9, p.COMPILED_MIN_SWINGS)
    y0 = np.concatenate(p.initial_state())
    n, m, h = 10, 48, 16.4 / 48
    ys, fs = np.empty((n, m + 1, 6)), np.empty((n, m + 1, 6))
    kernel(y0, h, m, n, lin, consts, dop853.A, dop853.B, ys, fs)
    om = PARIS.earth_rate_enu()
    end = compiled_rk8_reference()(y0, h, n * m - 1, h, PARIS.gravity_m_s2, 67.0, om, dop853.A, dop853.B)
    assert np.max(np.abs(end[:3] - ys[-1, -1, :3])) < 1e-11
    short = [f(y0, h, 20, 0.5 * h, PARIS.gravity_m_s2, 67.0, om, dop853.A, dop853.B)
             for f in (compiled_rk8_reference(), rk8_reference)]
    np.testing.assert_array_equal(short[0], short[1])
    assert compiled_rk8_reference() is not rk8_reference
    assert math.isclose(float(np.linalg.norm(end[:3])), 67.0, rel_tol=1e-12)


def test_compiled_reference_rows():
    # The bench rows (quick: one hour, the fast path compiled although shorter than its minimum
    # run): both end errors against DOP853 at rtol 1e-13 within the work-precision study's 1e-6 rad
    # target with room (RK8 at 48 steps per swing: ~1e-13 over an hour), CPU measured, ratio formed.
    from gyro_instrument.bench.compiled_reference import compiled_reference_rows
    ref, fast = compiled_reference_rows(quick=True, progress=lambda line: None)
    keys = {"case", "method", "simulated_s", "cpu_s", "cpu_system_s", "cpu_ratio", "goal", "met", "end_error_rad",
            "numba"}
    assert set(ref) == keys and set(fast) == keys
    assert "compiled, serial" in fast["method"] and ref["numba"] == jit.status()
    assert ref["end_error_rad"] < 1e-11 and fast["end_error_rad"] < 1e-11
    assert ref["cpu_s"] > 0 and fast["cpu_ratio"] == pytest.approx(fast["cpu_s"] / ref["cpu_s"])


def _columns_input(rng, size):
    # positions and velocities of a 67 m bob swinging through the vertical and round it (azimuth wraps
    # at ±π both ways), a Fradkin tensor whose angle crosses ±π too, and a bob exactly below the pivot
    ang = np.cumsum(rng.uniform(-2.5, 2.5, size))
    rad = 2.3 * rng.uniform(0.0, 1.0, size)
    pos = np.vstack([rad * np.sin(ang), rad * np.cos(ang), -np.sqrt(67.0 ** 2 - rad ** 2)])
    vel = rng.standard_normal((3, size)) * 0.9
    pos[:2, 5] = 0.0
    return pos, vel


def test_column_kernels_compiled_equal_plain_python_and_numpy():
    # angle_arguments and unwrap_in_place: the same operations in the same order as
    # pendulum_columns' numpy (hypot is the C library's in both), so the compiled kernels, their plain
    # Python functions and numpy give the same doubles, blocks and chunks cut anywhere
    from gyro_instrument.core.angles import Unwrapper
    from gyro_instrument.instruments.pendulum import columns as pd
    rng = np.random.default_rng(27)
    pos, vel = _columns_input(rng, 5000)
    w0sq = PARIS.gravity_m_s2 / 67.0
    compiled = pd.compiled_column_kernels()
    assert compiled[0] is not pd.angle_arguments and compiled[1] is not pd.unwrap_in_place
    args = [np.empty((4, 300)) for _ in range(2)]
    for kernel, out in zip((compiled[0], pd.angle_arguments), args):
        kernel(pos[:, :300], vel[:, :300], w0sq, out)
    np.testing.assert_array_equal(args[0], args[1])
    angles = [np.arctan2(args[0][2], args[0][3]) for _ in range(2)]
    states = [np.array([1.0, 3.0, -2.0]) for _ in range(2)]
    for kernel, angle, state in zip((compiled[1], pd.unwrap_in_place), angles, states):
        kernel(angle, state, 0.5)
    np.testing.assert_array_equal(angles[0], angles[1])
    np.testing.assert_array_equal(states[0], states[1])
    want = pd.pendulum_columns(pos, vel, w0sq)
    assert np.ptp(want["azimuth"]) > 20.0 and np.ptp(want["swing_azimuth"]) > 5.0     # many wraps unwrapped
    got = pd.compiled_pendulum_columns(pos, vel, w0sq, chunk=777)
    for key in want:
        np.testing.assert_array_equal(got[key], want[key])
    ua, ub = (Unwrapper(), Unwrapper()), (Unwrapper(), Unwrapper())
    for a, b in ((0, 1), (1, 1200), (1200, 1201), (1201, 5000)):
        one = pd.pendulum_columns(pos[:, a:b], vel[:, a:b], w0sq, ua)
        two = pd.compiled_pendulum_columns(pos[:, a:b], vel[:, a:b], w0sq, ub, chunk=500)
        for key in one:
            np.testing.assert_array_equal(two[key], one[key])
            np.testing.assert_array_equal(two[key], want[key][a:b])
        assert [(u.prev, u.turns) for u in ua] == [(u.prev, u.turns) for u in ub]
