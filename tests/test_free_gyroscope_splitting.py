"""The free gyroscope's splitting integrator (issue 27 item 1): the exact torque-free flow of the
symmetric top composed with torque kicks (Celledoni, Fassò, Säfström & Zanna, SIAM J. Sci. Comput.
30(4), 2008), the mass-unbalance torque and spin_decay, the scene checks, and the heavy top's
invariants over a long run."""

import functools
import math

import numpy as np
import pytest

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.rigid_body_flow import COMPOSITIONS, splitting_run, stages
from gyro_instrument.core.scene import sample_times
from gyro_instrument.core.site import Site
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.scenes import build_instruments, load_scene

NUM = "instruments.free_gyro.model=numerical"


def _run(over, **kw):
    scene = load_scene("free_gyroscope", list(over))
    g = build_instruments(scene)["free_gyro"]
    return g, g.simulate(sample_times(scene), **kw)


def _axis_error(a, b):
    return float(np.max(np.linalg.norm(a.extra["axis_enu"] - b.extra["axis_enu"], axis=1)))


def test_compositions_are_consistent():
    # Σ weights = 1 (consistency), symmetric (even order); the merged kick fractions sum to 1 too
    for order, w in COMPOSITIONS.items():
        assert math.isclose(sum(w), 1.0, abs_tol=1e-15) and w == w[::-1]
        a, b = stages(order)
        assert math.isclose(sum(a), 1.0, abs_tol=1e-15) and b == w and len(a) == len(b) + 1
    # order conditions of the symmetric composition: Σ w³ = 0 (order 4), and Σ w⁵ = 0 too (order 6)
    assert abs(sum(x ** 3 for x in COMPOSITIONS[4])) < 1e-14
    assert abs(sum(x ** 3 for x in COMPOSITIONS[6])) < 1e-13 and abs(sum(x ** 5 for x in COMPOSITIONS[6])) < 1e-13
    with pytest.raises(ValueError, match="splitting order 3"):
        stages(3)


@pytest.mark.parametrize("lat,alt,az,mu,spin", [(48.8462, 0.0, 90.0, 1.0, 60.0), (-33.87, 40.0, 300.0, 0.5, 200.0),
                                                (10.0, -20.0, 10.0, 1.9, -35.0), (60.0, 60.0, 0.0, 2.0, 0.0)])
def test_torque_free_splitting_is_the_closed_form(build, lat, alt, az, mu, spin):
    # Without a torque the splitting is one exact step of the free flow per sample, started from the
    # previous sample's state: it must reproduce the closed form from release (analytic_state) to a
    # few ulps per step, here over 21 600 steps (6 h at 1 Hz, ~1e6 rad of spin).
    g = build(FreeGyroscope, Site.from_degrees(lat), {"earth_rotation": EFFECTS["earth_rotation"]()},
              initial_axis_altitude_deg=alt, initial_axis_azimuth_deg=az, inertia_ratio=mu, spin_rate_rad_s=spin)
    t = np.arange(0.0, 21600.0 + 0.5, 1.0)
    a = g.simulate(t)
    s = g.simulate(t, model="numerical")
    assert s.trajectory.meta["step_s"] == math.inf
    assert _axis_error(a, s) < 1e-12
    assert np.max(np.abs(a.columns["spin_rate"] - s.columns["spin_rate"])) < 1e-12 * max(1.0, abs(spin))


def test_compiled_loop_equals_the_python_loop():
    # the compiled kernel (numba, no fastmath) and the plain Python loop: the same arithmetic, equal to
    # round-off (math.sin/cos/exp of the two may differ by an ulp)
    g, _ = _run([NUM, "duration_s=1", "instruments.free_gyro.center_of_mass_offset_m=1e-4",
                 "effects.spin_decay={time_constant_s: 60}"])
    y0 = np.concatenate([g.q0, g.R0.T @ g.motion_constants()["omega0"]])
    times = np.linspace(0.0, 5.0, 51)
    for order in COMPOSITIONS:
        ya, yb = y0.copy(), y0.copy()
        a = splitting_run(ya, 0.0, times, 0.013, order, g.p.inertia_ratio, g.torque_array(), compiled=True)
        b = splitting_run(yb, 0.0, times, 0.013, order, g.p.inertia_ratio, g.torque_array(), compiled=False)
        assert np.max(np.abs(a - b)) < 1e-13 and np.array_equal(ya, a[:, -1]) and np.array_equal(yb, b[:, -1])


def test_kicks_are_the_right_hand_side_torques():
    # the kick over dt is the exact flow of the DOP853 path's torque terms with the attitude frozen:
    # Δω / dt → (ω̇1, ω̇2, ω̇3) of torque_rates as dt → 0 (here dt = 1e-7 s: O(dt) from the decay's exp)
    from gyro_instrument.core.rigid_body_flow import kick
    g, _ = _run([NUM, "duration_s=1", "instruments.free_gyro.center_of_mass_offset_m=-3e-4", "effects.spin_decay={time_constant_s: 30}"])
    f = g.torque_rates()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        y = np.concatenate([q, rng.normal(size=3) * 50.0])
        t, dt = float(rng.uniform(0, 1e4)), 1e-3
        y1 = y.copy()
        kick(y1, t, dt, g.torque_array())
        rates = f(t, tuple(q), y[6])
        assert np.allclose((y1[4:] - y[4:]) / dt, rates, rtol=1e-4, atol=1e-9)


def test_the_closed_form_refuses_a_torque():
    for over, field in ((["instruments.free_gyro.center_of_mass_offset_m=1e-6"], "center_of_mass_offset_m"),
                        (["effects.spin_decay={time_constant_s: 600}"], "spin_decay"),
                        (["instruments.free_gyro.integrator=dop853"], "integrator"),
                        ([NUM, "instruments.free_gyro.splitting_order=3"], "splitting_order")):
        with pytest.raises(SceneError, match=field):
            load_scene("free_gyroscope", over)
    g, _ = _run([NUM, "duration_s=1", "effects.spin_decay={time_constant_s: 600}"])
    chosen, why = g.chosen_integrator()
    assert chosen == "splitting" and "order 6" in why and "nutation" in why
    g, _ = _run([NUM, "duration_s=1"])
    assert g.chosen_integrator() == ("splitting", g.chosen_integrator()[1]) and "one exact step per sample" in \
        g.chosen_integrator()[1]


#: Torqued configurations, each against DOP853 at rtol 1e-13 (atol 1e-14) over 10 s at 1 Hz.
TORQUED = {"unbalance": ["instruments.free_gyro.center_of_mass_offset_m=1e-4"],
           "spin_decay": ["effects.spin_decay={time_constant_s: 600}"],
           "unbalance + spin_decay": ["instruments.free_gyro.center_of_mass_offset_m=-2e-5",
                                      "effects.spin_decay={time_constant_s: 600}"],
           "unbalance, axis 40 deg up, mu 1.6": ["instruments.free_gyro.center_of_mass_offset_m=1e-5",
                                                 "instruments.free_gyro.initial_axis_altitude_deg=40",
                                                 "instruments.free_gyro.inertia_ratio=1.6"]}


@functools.cache
def _reference(case):
    """DOP853 at rtol 1e-13 (the tightest that runs) and the torque-free run, for one TORQUED case."""
    over = [NUM, "duration_s=10"] + TORQUED[case]
    ref = _run(over + ["instruments.free_gyro.integrator=dop853", "instruments.free_gyro.rtol=1e-13"])[1]
    free = _run([NUM, "duration_s=10"] + [o for o in TORQUED[case] if "offset" not in o and "spin_decay" not in o])[1]
    return ref, free


@pytest.mark.parametrize("case", sorted(TORQUED))
@pytest.mark.parametrize("rtol", [1e-8, 1e-11])
def test_torqued_splitting_within_tolerance_of_tight_dop853(case, rtol):
    # the step law (FreeGyroscope.splitting_step) aims at an axis error ≈ rtol rad: within 10 rtol
    # (the law's constants were fitted on the unbalance case; spin_decay alone errs far less)
    ref, free = _reference(case)
    g, s = _run([NUM, "duration_s=10", f"instruments.free_gyro.rtol={rtol}"] + TORQUED[case])
    assert g.chosen_integrator()[0] == "splitting" and s.trajectory.method == "splitting"
    assert _axis_error(ref, s) < 10.0 * rtol
    spin = ref.columns["spin_rate"]
    assert np.max(np.abs(spin - s.columns["spin_rate"])) < 10.0 * rtol * abs(spin[0])
    # the torques act: the axis or the spin leaves the torque-free motion by far more than that
    assert _axis_error(free, ref) > 1e-6 or np.max(np.abs(free.columns["spin_rate"] - spin)) > 1e-3 * abs(spin[0])


@pytest.mark.parametrize("order", [2, 4, 6])
def test_error_law_order_p_in_the_step(order):
    # halving the step divides the axis error by ≈ 2^p while λh ≲ 1 (λ = 60 rad/s): measured ratio
    # within a factor 1.6 of 2^p
    over = [NUM, "duration_s=5", "instruments.free_gyro.center_of_mass_offset_m=1e-4"]
    _, ref = _run(over + ["instruments.free_gyro.integrator=dop853", "instruments.free_gyro.rtol=1e-13"])
    split = over + [f"instruments.free_gyro.splitting_order={order}"]
    h = {2: 0.004, 4: 0.01, 6: 0.02}[order]
    e1 = _axis_error(ref, _run(split, step_s=h)[1])
    e2 = _axis_error(ref, _run(split, step_s=h / 2)[1])
    assert 1e-12 < e2 and 2 ** order / 1.6 < e1 / e2 < 2 ** order * 1.6


def test_heavy_top_invariants_over_ten_thousand_nutations():
    # n = 0 (no earth_rotation) and a mass unbalance: the Lagrange top. Energy E = T + m g d k·up, the
    # vertical angular momentum L·up and ω3 are conserved; over 1000 s (~9 600 nutation periods of
    # 2π/60 s, 16 rad of precession) E stays within 1e-9 m g d (measured 6e-11), L·up within 1e-12 |L|
    # (1e-13) and ω3 exactly (the kicks are across the axis)
    g, s = _run(["effects=null", "duration_s=1000", "sample_rate_hz=10", NUM,
                 "instruments.free_gyro.center_of_mass_offset_m=1e-4", "instruments.free_gyro.rtol=1e-10"])
    mgd = g.p.rotor_mass_kg * g.site.gravity_m_s2 * g.p.center_of_mass_offset_m
    E = s.extra["kinetic_energy_j"] + mgd * s.extra["axis_inertial"][:, 2]
    L = s.extra["angular_momentum"]
    assert np.ptp(s.columns["axis_azimuth"]) > 10.0                 # it precesses (≈ 16 rad)
    assert np.ptp(E) < 1e-9 * mgd
    assert np.ptp(L[:, 2]) < 1e-12 * np.linalg.norm(L[0])
    assert np.ptp(s.columns["spin_rate"]) == 0.0


def test_torque_free_invariants_to_round_off_over_a_day():
    # torque-free (earth_rotation on): |L| and the energy in the inertial frame are constants of the
    # exact flow: 86 400 steps keep them to round-off
    g, s = _run(["duration_s=86400", NUM])
    L = np.linalg.norm(s.extra["angular_momentum"], axis=1)
    E = s.extra["kinetic_energy_j"]
    assert np.ptp(L) / L[0] < 1e-13 and np.ptp(E) / E[0] < 1e-13
    assert np.max(np.abs(s.extra["quaternion_norm"] - 1.0)) < 1e-14


def test_work_precision_rows_quick():
    # bench spin_free: the keys the lead wires into bench, every integrator row within its rtol's
    # reach (splitting: ≤ 10 rtol, the step law; DOP853: ≤ 1e3 rtol), the heavy top's energy kept
    # as well as the angles (relative to m g d)
    from gyro_instrument.bench.spin_free import KEYS, work_precision_rows
    rows = work_precision_rows(quick=True, progress=lambda s: None)
    assert rows and all(tuple(r) == KEYS for r in rows)
    assert {r["integrator"] for r in rows} == {"splitting", "dop853"}
    for r in rows:
        rtol = float(r["setting"].split("rtol ")[1].split(",")[0])
        assert r["max_error_rad"] < (10.0 if r["integrator"] == "splitting" else 1e3) * rtol, r
        assert r["invariant_drift"] < (10.0 if r["integrator"] == "splitting" else 1e3) * rtol, r
        assert r["simulated_s"] == 5.0 and r["cpu_s"] > 0.0


def test_streamed_blocks_are_the_simulation_bit_for_bit():
    # the splitting's state and time carry across blocks: the same steps, the same doubles
    scene = load_scene("free_gyroscope", ["duration_s=30", NUM, "instruments.free_gyro.center_of_mass_offset_m=1e-5",
                                          "effects.spin_decay={}"])
    g = build_instruments(scene)["free_gyro"]
    t = sample_times(scene)
    whole = g.simulate(t)
    blocks = list(g.stream([t[:7], t[7:20], t[20:]]))
    assert np.array_equal(np.hstack([b.trajectory.y for b in blocks]), whole.trajectory.y)
    assert np.array_equal(np.concatenate([b.columns["axis_azimuth"] for b in blocks]), whole.columns["axis_azimuth"])


def test_unbalance_drift_is_the_gyroscopic_precession():
    # n = 0, axis horizontal, d = 0.1 mm: the axis precesses about the vertical at m g d / (C ω3)
    # (steady precession, exact for a horizontal axis; released from rest it adds a nutation of
    # relative size (Ω/λ)² ~ 1e-7 to the mean rate), counterclockwise seen from above for d > 0,
    # ω3 > 0 (torque m g d up × k): the compass azimuth decreases. Over 600 s (≈ 10 rad) the mean rate
    # agrees to 1e-5 relative
    g, s = _run(["effects=null", "duration_s=600", NUM, "instruments.free_gyro.center_of_mass_offset_m=1e-4",
                 "instruments.free_gyro.rtol=1e-10"])
    rate = g.predictions()["unbalance_precession_rate_rad_s"]
    C = g.p.inertia_ratio * g.p.transverse_inertia_kg_m2
    assert rate == pytest.approx(g.p.rotor_mass_kg * g.site.gravity_m_s2 * 1e-4 / (C * 60.0), rel=1e-14)
    az = s.columns["axis_azimuth"]
    slope = np.polyfit(s.t, az, 1)[0]
    assert slope == pytest.approx(-rate, rel=1e-5)
    assert "unbalance_precession_rate_rad_s" not in _run(["duration_s=1"])[0].predictions()


def test_forcing_the_closed_form_under_a_torque_is_refused():
    g, _ = _run([NUM, "duration_s=1", "instruments.free_gyro.center_of_mass_offset_m=1e-6"])
    with pytest.raises(SceneError, match="model"):
        g.simulate(np.linspace(0.0, 1.0, 3), model="analytic")
