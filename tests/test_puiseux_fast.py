"""Puiseux's bodies with the fixed-step integrators (issue 27 item 1): ``axis_rk8`` (the exact
reduction of a body of revolution by its conserved spin) and ``rk8`` (the exact equations),
compiled: the same results as a tight DOP853 within the scene's tolerance, the invariants held over
long runs, the kernels equal to their plain Python, and ``auto``'s choice explained."""

import functools
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from gyro_instrument.bench.spin_puiseux import angle_error, energy_drift, reference, work_precision_rows
from gyro_instrument.core import jit
from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.scene import sample_times
from gyro_instrument.instruments.puiseux import fixed_step
from gyro_instrument.scenes import build_instruments, load_scene


def _body(scene_name, overrides=()):
    scene = load_scene(scene_name, list(overrides))
    (inst,) = build_instruments(scene).values()
    return inst, sample_times(scene)


@functools.cache
def _shipped_runs(scene_name):
    """The shipped scene's body, sample times, reference run and DOP853 run at the scene's rtol."""
    inst, t = _body(scene_name)
    return inst, t, reference(inst, t), inst.simulate(t, integrator="dop853")


@pytest.mark.parametrize("scene_name, integrator", [("puiseux_spheroid", "axis_rk8"), ("puiseux_spheroid", "rk8"),
                                                    ("puiseux_general", "rk8")])
def test_fixed_step_within_the_scene_tolerance_of_tight_dop853(scene_name, integrator):
    # The whole shipped run at the scene's sample rate and rtol (1e-10): every output angle within
    # rtol (rad) of DOP853 at rtol 1e-13 (atol 1e-15), and no farther than DOP853 at the scene's own
    # rtol is (measured: 1.5e-12 against 1.7e-9 rad for the spheroid, 7e-14 against 5e-11 for the
    # general body).
    inst, t, ref, dop = _shipped_runs(scene_name)
    fast = inst.simulate(t, integrator=integrator)
    err = angle_error(fast, ref)
    assert err <= inst.p.rtol, err
    assert err <= angle_error(dop, ref), (err, angle_error(dop, ref))
    for col in ("com_height", "contact_x", "contact_y", "contact_east", "contact_north"):     # metres
        assert np.max(np.abs(fast.columns[col] - ref.columns[col])) <= inst.p.rtol * 1.0, col
    assert np.max(np.abs(fast.columns["spin_rate"] - ref.columns["spin_rate"])) <= inst.p.rtol * abs(inst.r0) + 1e-12


def test_auto_picks_the_reduction_for_a_body_of_revolution_and_rk8_otherwise():
    sph, _ = _body("puiseux_spheroid")
    gen, _ = _body("puiseux_general")
    assert sph.chosen_integrator(20.0)[0] == "axis_rk8" and "body of revolution" in sph.chosen_integrator()[1]
    name, why = gen.chosen_integrator(30.0)
    assert name == "rk8" and "shape general" in why
    tri, _ = _body("puiseux_spheroid", ["instruments.spheroid.semi_axes_m=[0.1, 0.11, 0.2]"])
    assert tri.chosen_integrator()[0] == "rk8" and "alpha" in tri.chosen_integrator()[1]
    low, _ = _body("puiseux_spheroid", ["instruments.spheroid.initial_tilt_deg=120"])
    assert low.chosen_integrator()[0] == "rk8" and "below the horizontal" in low.chosen_integrator()[1]
    dop, _ = _body("puiseux_spheroid", ["instruments.spheroid.integrator=dop853"])
    name, why = dop.chosen_integrator()
    assert name == "dop853" and why == f"chosen in the scene (Hairer's DOP853 compiled, core.dop853_jit: {jit.status()})"


def test_describe_says_which_integrator_and_why(capsys):
    from gyro_instrument.cli import main
    assert main(["describe", "puiseux_spheroid", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    chosen = out["instruments"]["spheroid"]["integrator"]
    assert chosen["chosen"] == "axis_rk8" and "spin" in chosen["reason"]


def test_the_reduction_is_refused_for_a_body_not_of_revolution():
    with pytest.raises(SceneError) as exc:
        _body("puiseux_general", ["instruments.body.integrator=axis_rk8"])
    assert exc.value.field == "instruments.body.integrator" and "revolution" in str(exc.value)
    with pytest.raises(SceneError, match="moments A = 0.01 != B = 0.012"):
        _body("puiseux_spheroid", ["instruments.spheroid.homogeneous=false",
                                   "instruments.spheroid.inertia_kg_m2=[0.01, 0.012, 0.004]",
                                   "instruments.spheroid.integrator=axis_rk8"])


def _long_run(scene_name, duration_s, integrator, lv_rel):
    """The scene run for ``duration_s`` with ``auto`` (which must pick ``integrator``); its energy held to
    1e-11 and its vertical angular momentum about G to ``lv_rel``, relative (exact invariants)."""
    inst, t = _body(scene_name, [f"duration_s={duration_s}"])
    sim = inst.simulate(t)
    assert sim.trajectory.method == integrator
    assert energy_drift(sim) < 1e-11
    lv = sim.extra["angular_momentum_vertical_kg_m2_s"]
    assert np.max(np.abs(lv - lv[0])) < lv_rel * abs(lv[0])
    return inst, t, sim


def test_long_spheroid_run_keeps_energy_vertical_momentum_and_spin():
    # 200 s: ~800 nutation periods (C r / A = 25 rad/s) and the slow precession many times over.
    inst, t, sim = _long_run("puiseux_spheroid", 200, "axis_rk8", 1e-11)
    spin = sim.columns["spin_rate"]
    assert np.max(np.abs(spin - inst.r0)) < 1e-12 * abs(inst.r0)            # eq. 6: r constant
    assert np.max(np.abs(sim.extra["quaternion_norm"] - 1.0)) < 1e-14
    # the body stays up (1.03 r_crit): the tilt stays bounded, as in the shipped 20 s
    assert sim.columns["tilt"].max() < 0.1


def test_long_general_run_keeps_energy_and_vertical_momentum():
    # 600 s: about 1000 periods of the slower swing (0.94 s).
    inst, t, sim = _long_run("puiseux_general", 600, "rk8", 1e-10)
    # Puiseux's unbounded turn about the vertical at |alpha| (first order) keeps its rate
    alpha = inst.general_predictions()["turning_rate_rad_s"]
    rate = (sim.columns["turn_angle"][-1] - sim.columns["turn_angle"][0]) / (t[-1] - t[0])
    assert rate == pytest.approx(alpha, rel=1e-2)


def test_streamed_blocks_equal_one_run():
    inst, t = _body("puiseux_spheroid", ["duration_s=3"])
    whole = inst.simulate(t)
    parts = list(inst.stream(np.array_split(t, 7), t_end=float(t[-1])))
    np.testing.assert_array_equal(np.hstack([p.extra["state"] for p in parts]), whole.extra["state"])
    np.testing.assert_array_equal(np.concatenate([p.columns["turn_angle"] for p in parts]), whole.columns["turn_angle"])


def test_reduced_state_round_trip():
    # (q, w) -> (u, u', phi) -> (q, w) is the identity (up to the quaternion's sign).
    inst, _ = _body("puiseux_spheroid", ["instruments.spheroid.initial_tilt_deg=40",
                                         "instruments.spheroid.initial_tilt_rate_deg_s=30",
                                         "instruments.spheroid.initial_azimuth_rate_deg_s=-50"])
    y0 = inst.initial_state()
    x, r = fixed_step.axis_state(y0)
    back = fixed_step.body_states(x[:, None], r)[:, 0]
    sign = np.sign(back[0] * y0[0]) or 1.0
    np.testing.assert_allclose(sign * back[:4], y0[:4], atol=1e-15)
    np.testing.assert_allclose(back[4:], y0[4:], rtol=1e-14, atol=1e-14)


def test_swing_frame_twist_rate():
    # The minimal rotation taking e_z to u(t) turns about u at -e_z.(u x u')/(1 + u_z): the term the
    # reduction adds to the spin angle's rate (central difference of its rotation matrices).
    from gyro_instrument.core.quaternion import quat_to_matrix

    def u(t):
        v = np.array([0.3 * math.sin(t), 0.2 * math.cos(2 * t), 1.0 - 0.4 * t])
        return v / np.linalg.norm(v)

    def R(t):
        return quat_to_matrix(fixed_step._swing(u(t)[:, None]).T[0])
    t, h = 0.7, 1e-6
    W = (R(t + h) - R(t - h)) / (2 * h) @ R(t).T
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    ud = (u(t + h) - u(t - h)) / (2 * h)
    assert omega @ u(t) == pytest.approx(-np.cross(u(t), ud)[2] / (1.0 + u(t)[2]), rel=1e-8)


def test_compiled_kernels_equal_the_plain_functions():
    assert jit.enabled(), jit.status()
    k = fixed_step.fixed_step_kernels()
    inst, _ = _body("puiseux_spheroid", ["instruments.spheroid.initial_tilt_deg=20"])
    run = inst.integration_run(0.0, 1.0, 1e-10, 1e-12, "axis_rk8")
    for model, rhs, plain, x, p in ((k.AXIS, k.axis_rhs, k._axis_rhs, run.x, run.params),
                                    (k.BODY, k.body_rhs, k._body_rhs, *_body_args(inst))):
        a, b = np.empty(7), np.empty(7)
        rhs(x, p, a)
        plain(x, p, b)
        np.testing.assert_allclose(a, b, rtol=1e-15, atol=1e-15 * np.max(np.abs(b)))


def _body_args(inst):
    run = inst.integration_run(0.0, 1.0, 1e-10, 1e-12, "rk8")
    return run.x, run.params


def test_whole_runs_equal_without_compilation():
    # The same short runs with GYRO_INSTRUMENT_JIT=0 (every kernel plain Python) in a subprocess;
    # there integrator dop853 is scipy's DOP853 on the Python right-hand side, bit for bit the
    # compiled=False run here, and numba is never imported.
    code = ("import numpy as np, sys; from gyro_instrument.scenes import build_instruments, load_scene; "
            "from gyro_instrument.core.scene import sample_times; out = []\n"
            "for sc, i in (('puiseux_spheroid', 'axis_rk8'), ('puiseux_general', 'rk8'), ('puiseux_general', 'dop853')):\n"
            "    s = load_scene(sc, ['duration_s=0.2']); (b,) = build_instruments(s).values()\n"
            "    out.append(b.simulate(sample_times(s), integrator=i).extra['state'].tolist())\n"
            "import json; print(json.dumps(out)); sys.exit('numba' in sys.modules)")
    env = dict(os.environ, GYRO_INSTRUMENT_JIT="0")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    *plain, scipy = json.loads(res.stdout)
    inst, t = _body("puiseux_general", ["duration_s=0.2"])
    np.testing.assert_array_equal(inst.simulate(t, integrator="dop853", compiled=False).extra["state"], np.array(scipy))
    for (sc, integ), states in zip((("puiseux_spheroid", "axis_rk8"), ("puiseux_general", "rk8")), plain):
        inst, t = _body(sc, ["duration_s=0.2"])
        np.testing.assert_allclose(inst.simulate(t, integrator=integ).extra["state"], np.array(states),
                                   rtol=1e-13, atol=1e-14)


def test_work_precision_rows_quick():
    rows = work_precision_rows(quick=True, progress=lambda *_: None)
    keys = ("instrument", "integrator", "setting", "simulated_s", "cpu_s", "real_time_factor", "max_error_rad",
            "invariant", "invariant_drift")
    assert rows and all(tuple(r) == keys for r in rows)
    assert {r["integrator"] for r in rows} == {"dop853", "axis_rk8", "rk8"}
    assert all(r["max_error_rad"] < 1e-9 and r["invariant_drift"] < 1e-10 for r in rows)


@pytest.mark.parametrize("overrides", [
    # sec. II body of revolution: equal radii, G below the centre of curvature (c_z != 0), A = B
    ["instruments.spheroid.shape=curvature", "instruments.spheroid.semi_axes_m=null",
     "instruments.spheroid.homogeneous=false", "instruments.spheroid.curvature_radii_m=[0.3, 0.3]",
     "instruments.spheroid.com_height_m=0.2", "instruments.spheroid.inertia_kg_m2=[0.02, 0.02, 0.01]",
     "instruments.spheroid.spin_rate_turn_s=3", "instruments.spheroid.initial_tilt_deg=35",
     "instruments.spheroid.initial_tilt_rate_deg_s=40", "instruments.spheroid.initial_azimuth_rate_deg_s=-60"],
    # an oblate spheroid, far from the small tilts: the reduction's nonlinear terms
    ["instruments.spheroid.semi_axes_m=[0.2, 0.2, 0.1]", "instruments.spheroid.spin_rate_turn_s=-2",
     "instruments.spheroid.initial_tilt_deg=60", "instruments.spheroid.initial_tilt_rate_deg_s=-90"],
], ids=["curvature_revolution", "oblate_large_tilt"])
def test_reduction_matches_the_exact_equations_at_large_tilts(overrides):
    inst, t = _body("puiseux_spheroid", ["duration_s=4"] + overrides)
    assert inst.chosen_integrator()[0] == "axis_rk8"
    ref = reference(inst, t)
    fast = inst.simulate(t)
    assert angle_error(fast, ref) <= inst.p.rtol
    assert np.max(np.abs(fast.extra["normal_force_N"] - ref.extra["normal_force_N"])) <= 1e-9 * inst.p.mass_kg * 9.81
    assert energy_drift(fast) < 1e-12


def test_the_reduction_stops_before_its_upside_down_singularity():
    # Released at 169 degrees and tilting on at 200 deg/s, the reduced run stops with a message as the
    # tilt passes 170 degrees, rather than lose accuracy near 180 (the swing frame's twist rate grows
    # as 1/(1 + cos theta)).
    inst, t = _body("puiseux_spheroid", ["duration_s=3", "instruments.spheroid.spin_rate_turn_s=0",
                                         "instruments.spheroid.initial_tilt_deg=169",
                                         "instruments.spheroid.initial_tilt_rate_deg_s=200",
                                         "instruments.spheroid.integrator=axis_rk8"])
    with pytest.raises(IntegrationError, match="tilted past 170 deg.*rk8 or dop853"):
        inst.simulate(t)


# ---------------------------------------------------------------- integrator: dop853, compiled
@pytest.mark.parametrize("scene_name", ["puiseux_spheroid", "puiseux_general"])
def test_compiled_dop853_equals_scipy_dop853(scene_name):
    # The same method (Hairer's DOP853), tolerances and error control: the compiled run
    # (core.dop853_jit, steps with no end) and scipy's (steps bounded by the run's end, the arithmetic
    # in another order) differ by round-off amplified over the run, so within rtol x the scale of
    # each quantity: rtol (1 rad) for the output angles (measured over the shipped runs: 6.4e-13 rad
    # for the spheroid, 1.1e-12 for the general body), rtol x max|y_i| for each state component
    # (measured 6.9e-12 and 4.5e-12), rtol (1 m) for the lengths; the same steps (nfev within 1%:
    # 44174 against 44177, 12074 against 12074); energy held alike.
    inst, t, _, dop = _shipped_runs(scene_name)
    assert dop.trajectory.meta["driver"].startswith("DOP853 (core.dop853_jit, numba")
    sci = inst.simulate(t, integrator="dop853", compiled=False)
    assert "driver" not in sci.trajectory.meta          # scipy's Integration
    rtol = inst.p.rtol
    assert angle_error(dop, sci) <= rtol
    ys, yc = sci.extra["state"], dop.extra["state"]
    assert np.all(np.max(np.abs(yc - ys), axis=1) <= rtol * np.max(np.abs(ys), axis=1))
    for col in ("com_height", "contact_x", "contact_y", "contact_east", "contact_north"):     # metres
        assert np.max(np.abs(dop.columns[col] - sci.columns[col])) <= rtol * 1.0, col
    assert abs(dop.trajectory.nfev - sci.trajectory.nfev) <= 0.01 * sci.trajectory.nfev
    assert energy_drift(dop) < 1e-11 and energy_drift(sci) < 1e-11


def test_compiled_dop853_streamed_blocks_equal_one_run():
    inst, t = _body("puiseux_general", ["duration_s=3", "instruments.body.integrator=dop853"])
    whole = inst.simulate(t)
    assert whole.trajectory.meta["driver"].startswith("DOP853 (core.dop853_jit")
    parts = list(inst.stream(np.array_split(t, 7), t_end=float(t[-1])))
    np.testing.assert_array_equal(np.hstack([p.extra["state"] for p in parts]), whole.extra["state"])
    np.testing.assert_array_equal(np.concatenate([p.columns["turn_angle"] for p in parts]), whole.columns["turn_angle"])


def test_compiled_dop853_kernel_and_run_equal_the_plain_ones():
    k = fixed_step.fixed_step_kernels()
    kernel = fixed_step.dop853_kernel()
    assert kernel is not k._exact_rhs                   # numba's compiled kernel
    inst, t = _body("puiseux_general", ["duration_s=0.05"])
    y0, p = inst.initial_state(), np.asarray(inst.exact_params())
    for y in (y0, y0 + np.array([0.0, 0.01, -0.02, 0.03, 1.0, -2.0, 0.5])):
        a, b = np.empty(7), np.empty(7)
        kernel(0.3, y, p, a)
        k._exact_rhs(0.3, y, p, b)
        np.testing.assert_allclose(a, b, rtol=1e-15, atol=1e-15 * np.max(np.abs(b)))
    # the whole run: the compiled driver and kernel against both as plain Python (same steps)
    fast = fixed_step.compiled_dop853_run(y0, 0.0, p, 1e-10, 1e-12).advance(t)
    plain = fixed_step.compiled_dop853_run(y0, 0.0, p, 1e-10, 1e-12, compiled=False).advance(t)
    assert fast.nfev == plain.nfev
    np.testing.assert_allclose(fast.y, plain.y, rtol=1e-13, atol=1e-14)

