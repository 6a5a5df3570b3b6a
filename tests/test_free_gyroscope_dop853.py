"""The free gyroscope's ``integrator: dop853`` on the compiled DOP853 (issue 27 item 1): the compiled
right-hand side (core.rigid_body_flow.rhs_kernel) is rhs_scalar's arithmetic, compiled and plain agree,
the compiled run takes the Python-float driver's steps, and it streams bit for bit."""

import math

import numpy as np
import pytest

from gyro_instrument.core import jit
from gyro_instrument.core.rigid_body_flow import compiled_rhs_kernel, rhs_kernel, rhs_params
from gyro_instrument.core.scene import sample_times
from gyro_instrument.scenes import build_instruments, load_scene

NUM = ["instruments.free_gyro.model=numerical", "instruments.free_gyro.integrator=dop853"]

#: Torque-free, mass unbalance, unbalance + spin_decay (μ = 1.6, axis 40° up), spin_decay alone.
CASES = {"free": [],
         "unbalance": ["instruments.free_gyro.center_of_mass_offset_m=1e-4"],
         "unbalance + spin_decay": ["instruments.free_gyro.center_of_mass_offset_m=-2e-5",
                                    "instruments.free_gyro.initial_axis_altitude_deg=40",
                                    "instruments.free_gyro.inertia_ratio=1.6", "effects.spin_decay={time_constant_s: 600}"],
         "spin_decay": ["effects.spin_decay={time_constant_s: 60}"]}


def _gyro(over, duration_s=20):
    scene = load_scene("free_gyroscope", [f"duration_s={duration_s}"] + NUM + list(over))
    return build_instruments(scene)["free_gyro"], sample_times(scene)


def _params(g):
    decay = g.effect("spin_decay")
    return rhs_params(g.p.inertia_ratio, g.baumgarte_rate(), decay.p.time_constant_s if decay is not None else 0.0,
                      g.torque_array())


@pytest.mark.parametrize("case", sorted(CASES))
def test_kernel_is_rhs_scalar_and_compiled_equals_plain(case):
    # the kernel repeats rhs_scalar's terms in its order: the same doubles (no tolerance); the compiled
    # kernel (numba, no fastmath) the same arithmetic: equal to round-off (libm's and LLVM's sin/cos
    # may differ by an ulp: 4 ulp of the largest term)
    g, _ = _gyro(CASES[case])
    f, p = g.rhs_scalar(), _params(g)
    fc = compiled_rhs_kernel()
    rng = np.random.default_rng(11)
    for _ in range(50):
        y = np.concatenate([rng.normal(size=4), rng.normal(size=3) * 60.0])
        t = float(rng.uniform(0.0, 1e5))
        plain, comp = np.empty(7), np.empty(7)
        rhs_kernel(t, y, p, plain)
        fc(t, y, p, comp)
        assert np.array_equal(plain, np.array(f(t, *(float(v) for v in y))))
        assert np.max(np.abs(comp - plain)) <= 4.0 * np.spacing(np.max(np.abs(y)) ** 2)


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("rtol", [1e-8, 1e-12])
def test_compiled_dop853_takes_the_python_drivers_steps(case, rtol):
    # the same method, step control and dense output: the same accepted steps, so every
    # sample but the last agrees to round-off (here: to 1e3 ulp of the state's scale). The Python-float
    # driver ends its last step on the last sample, the compiled one steps on with no end: that sample
    # comes from two steps of different length, each with error norm < 1, i.e. each component's local
    # error ≤ √7 (atol + rtol |y|) (RMS over the 7 components): within twice that
    g, t = _gyro(CASES[case])
    a = g.simulate(t, rtol=rtol)
    b = g.simulate(t, rtol=rtol, compiled=False)
    assert b.trajectory.method == "DOP853"
    if jit.enabled():
        assert a.trajectory.method == "DOP853 (compiled)" and "compiled" in g.chosen_integrator()[1]
    assert a.trajectory.meta["nsteps"] == b.trajectory.meta["nsteps"]
    # the last step's length differs (clipped or not), so may its rejections (measured: one at most)
    assert abs(a.trajectory.meta["nrejected"] - b.trajectory.meta["nrejected"]) <= 1
    ya, yb = a.trajectory.y, b.trajectory.y
    scale = np.max(np.abs(yb), axis=1)
    assert np.all(np.abs(ya[:, :-1] - yb[:, :-1]) <= 1e3 * np.spacing(scale)[:, None])
    bound = 2.0 * math.sqrt(7.0) * (g.DOP853_ATOL + rtol * scale)
    assert np.all(np.abs(ya[:, -1] - yb[:, -1]) <= bound)


@pytest.mark.parametrize("case", ["free", "unbalance + spin_decay"])
def test_compiled_dop853_streams_bit_for_bit(case):
    # the compiled run keeps its last step across blocks and never steps by the samples
    g, t = _gyro(CASES[case], duration_s=30)
    whole = g.simulate(t)
    blocks = list(g.stream([t[:1], t[1:7], t[7:20], t[20:]]))
    assert np.array_equal(np.hstack([b.trajectory.y for b in blocks]), whole.trajectory.y)
    for col in ("axis_azimuth", "hour_angle", "spin_rate"):
        assert np.array_equal(np.concatenate([b.columns[col] for b in blocks]), whole.columns[col])
