"""Hard cases stay numerically stable (issue 6). Each case says why it is hard and asserts finite
results, invariants within a stated bound, agreement with the analytic prediction where one
exists, or a clear, documented refusal. Cases covered elsewhere are listed in the reliability
table of docs/reliability.md (179.9° and inverted launches: test_pendulum; free axis 1e-6 rad from Earth's
axis: test_free_gyroscope; gimbal near lock: test_gimbal)."""

import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.core.site import Site
from gyro_instrument.estimators.crossings import mean_interval, zero_crossings
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum, binet_ellipse
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope
from gyro_instrument.instruments.puiseux import PuiseuxBody, classify_stability, critical_spin_rad_s
from gyro_instrument.scenes import load_scene

EXACT = ("earth_rotation", "centrifugal", "finite_amplitude")


@pytest.mark.parametrize("lat", [90.0, -90.0, 89.99, -89.99, 0.01, -0.01, 0.0])
def test_singular_latitudes_simulate_and_estimate(capsys, lat):
    # Why hard: at ±90° the horizontal plane is perpendicular to Earth's axis (no torque, item 4)
    # and cos γ is 0; at ±89.99° the swing lasts ~790 s (Quet's sec. 4 §1 eq. (9), sin ω = cos γ);
    # near 0° cos γ is flat and the pendulum barely precesses. Every output is finite JSON (no
    # NaN/inf), the latitude is within 3σ of the truth or null with a reason, and the invariant (3) holds to 1e-12.
    scene = load_scene("quet_paris", [f"site.latitude_deg={lat}", "duration_s=300"])
    truth = simulate_truth(scene)
    for name, sim in truth[2].items():
        for col in sim.columns.values():
            assert np.all(np.isfinite(col)), name
    g = truth[1]["gyro_horizontal"]
    c = truth[2]["gyro_horizontal"].columns
    s = c["spin_rate"] + scene.site.earth_rate_rad_s * g.sin_omega * np.cos(c["angle"])
    assert np.ptp(s) / abs(s[0]) < 1e-12
    r = estimate_records(scene, truth[1], measure(scene, truth))
    json.dumps(r, allow_nan=False, default=float)
    if r["latitude_deg"] is None:
        assert r.get("reason")
    elif r["latitude_sigma_deg"] is None:
        # at a pole the 1-sigma region reaches the boundary: no local sigma, the intervals instead
        assert "not locally Gaussian" in r["latitude_sigma_reason"]
        lo3, hi3 = r["latitude_interval_3sigma_deg"]
        assert lo3 - 1e-12 <= lat <= hi3 + 1e-12
    else:
        assert abs(r["latitude_deg"] - lat) <= 3 * r["latitude_sigma_deg"] + 1e-12
    # the pendulum's precession sense decides the hemisphere wherever it precesses measurably
    if abs(lat) >= 1.0:
        assert r["hemisphere"] == ("north" if lat > 0 else "south")
    if abs(lat) == 90.0:
        assert r["instruments"]["gyro_horizontal"]["swing_duration_s"] is None
        assert "restoring torque" in r["instruments"]["gyro_horizontal"]["reason"]


def test_pendulum_amplitude_1e9_rad_follows_binet(build):
    # Why hard: the bob moves 7e-8 m on a 67 m rod; tolerances must scale with the motion, not the
    # rod. The linear model is exact here up to O(a²): Binet's ellipse to 1e-6 of the amplitude.
    site = Site.from_degrees(48.85)
    p = build(SphericalPendulum, site, ("earth_rotation", "finite_amplitude"), length_m=67.0,
              initial_deflection_deg=math.degrees(1e-9), rtol=1e-12)
    t = np.linspace(0.0, 600.0, 1201)
    s = p.simulate(t)
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, 67.0, site.gravity_m_s2, site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    amp = 67.0 * 1e-9
    assert np.max(np.hypot(s.columns["x_east"] - x, s.columns["y_north"] - y)) < 1e-6 * amp


def test_bob_at_rest_and_exactly_inverted_are_equilibria(build, capsys):
    # Why hard: the azimuth atan2(0, 0) is undefined (reported as 0, documented in csv.md). At rest
    # nothing moves. Exactly inverted is an unstable equilibrium (rate λ = √(g/l)): without the
    # centrifugal term it stays put (round-off 1e-16 grows ×1e3 in 20 s); with it, the gradient
    # 2l n² sin γ cos γ (southward: −Ω × (Ω × 2l ẑ)) forces it off as θ(t) = (n² sin 2γ / λ²)(cosh λt − 1)
    # (linearised) — 3.8e-5 rad after 20 s on 67 m at 48.85°, matched to 2 %.
    site = Site.from_degrees(48.85)
    t = np.linspace(0.0, 20.0, 201)
    c = build(SphericalPendulum, site, EXACT, length_m=67.0, initial_deflection_deg=0.0).simulate(t).columns
    assert all(np.all(np.isfinite(v)) for v in c.values()) and np.max(c["deflection"]) < 1e-12
    c = build(SphericalPendulum, site, ("earth_rotation", "finite_amplitude"), length_m=67.0,
              initial_deflection_deg=180.0).simulate(t).columns
    assert np.max(np.abs(c["deflection"] - math.pi)) < 1e-12
    c = build(SphericalPendulum, site, EXACT, length_m=67.0, initial_deflection_deg=180.0).simulate(t).columns
    lam = math.sqrt(site.gravity_m_s2 / 67.0)
    predicted = site.earth_rate_rad_s ** 2 * math.sin(2 * site.latitude_rad) / lam ** 2 * (math.cosh(lam * 20.0) - 1)
    assert math.pi - c["deflection"][-1] == pytest.approx(predicted, rel=0.02)
    assert np.cos(c["azimuth"][-1]) == pytest.approx(-1.0, abs=1e-6)     # pushed south, as derived
    # and the estimator says why it cannot get a Foucault rate from a bob at rest
    rc = main(["estimate", "foucault_pantheon", "--set", "instruments.pendulum.initial_deflection_deg=0",
               "--duration-s", "120", "--json"])
    r = json.loads(capsys.readouterr().out)
    assert rc == 0 and r["instruments"]["pendulum"]["foucault_rate_rad_s"] is None
    assert r["instruments"]["pendulum"]["reason"]


def test_gyroscope_spin_1e5_rad_s(build):
    # Why hard: stiff in the chain model (spin 1e5 rad/s), a 1 s swing; the reduced model does not
    # resolve the spin. Eq. (9) × finite-amplitude factor to 1e-6; spin integral to 1e-12.
    g = build(PlaneGyroscope, Site.from_degrees(48.85), EXACT, spin_rate_rad_s=1.0e5)
    T = g.predictions()["swing_duration_s"]
    t = np.linspace(0.0, 12 * T, 4801)
    c = g.simulate(t).columns
    Tm, _ = mean_interval(zero_crossings(t, c["angle"], c["angle_rate"]))
    assert Tm == pytest.approx(T, rel=1e-6)
    p = 7.2921150e-5 * g.sin_omega
    s = c["spin_rate"] + p * np.cos(c["angle"])
    assert np.ptp(s) / s[0] < 1e-12


def test_gyroscope_spin_of_the_order_of_n(build):
    # Why hard: ρ0 ≈ n, so Quet's reduced equation (dropping n/(μρ0) ≈ 0.4) is wrong and only the
    # exact one holds (Quet: 'particularités curieuses' when ρ0 is small). Exact small-swing
    # constant K = p (μ ρ_eq + (μ − 1) p) with ρ_eq = b − p the spin at u = 0: the period matches
    # π/√K to 1e-6, and the Jacobi integral holds to 1e-9.
    site = Site.from_degrees(48.85)
    rho0 = 1.0e-4
    g = build(PlaneGyroscope, site, EXACT, spin_rate_rad_s=rho0, initial_angle_deg=0.05, plane="meridian")
    p = site.earth_rate_rad_s
    b = rho0 + p * math.cos(math.radians(0.05))
    K = p * (2.0 * (b - p) + p)
    T = math.pi / math.sqrt(K)
    t = np.linspace(0.0, 4.5 * T, 9001)
    c = g.simulate(t).columns
    Tm, _ = mean_interval(zero_crossings(t, c["angle"], c["angle_rate"]))
    assert Tm == pytest.approx(T, rel=1e-6)
    E = 0.5 * c["angle_rate"] ** 2 - 2.0 * b * p * np.cos(c["angle"]) - 0.5 * p ** 2 * np.sin(c["angle"]) ** 2
    assert np.ptp(E) < 1e-9 * abs(2.0 * b * p)


def test_48_hour_runs(build):
    # Why hard: long horizons accumulate error. Free gyroscope, 48 h (two sidereal days, closed
    # form): the hour angle grows by 2 n t to 1e-9 rad and the axis comes back within its nutation
    # diameter. Plane gyroscope, 48 h at a slow spin (2π rad/s: 1350 swings): the spin integral
    # (3) holds to 1e-11 and the Jacobi integral to 1e-7 — no secular drift.
    site = Site.from_degrees(48.85)
    fg = build(FreeGyroscope, site, ("earth_rotation",), spin_rate_rad_s=60.0)
    t = np.concatenate([np.arange(0.0, 48 * 3600.0 + 1, 600.0), [2 * 86164.0989]])   # unwrap needs dense samples
    c = fg.simulate(t[:-1]).columns
    assert c["hour_angle"][-1] - c["hour_angle"][0] == pytest.approx(site.earth_rate_rad_s * 48 * 3600.0, abs=1e-6)
    two_days = fg.simulate(np.array([0.0, t[-1]])).columns
    assert abs(two_days["axis_altitude"][1] - two_days["axis_altitude"][0]) < \
        2 * fg.predictions()["nutation_diameter_rad"] + 1e-12
    g = build(PlaneGyroscope, site, EXACT, spin_rate_rad_s=2 * math.pi, rtol=1e-10)
    t = np.linspace(0.0, 48 * 3600.0, 1729)
    c = g.simulate(t).columns
    p = site.earth_rate_rad_s * g.sin_omega
    s = c["spin_rate"] + p * np.cos(c["angle"])
    assert np.ptp(s) / s[0] < 1e-11
    E = 0.5 * c["angle_rate"] ** 2 - 2.0 * s[0] * p * np.cos(c["angle"]) - 0.5 * p ** 2 * np.sin(c["angle"]) ** 2
    assert np.ptp(E) < 1e-7 * (2.0 * s[0] * p)


def test_compound_pendulum_spinning_past_its_cardan_singularity(build):
    # Why hard: the compound pendulum is integrated on a Cardan pair (east hinge, then north hinge),
    # singular with the figure axis horizontal east–west. Released at the 80° limit toward the east
    # with a fast spin (ρ0 = 30 rad/s, μ = C/A = 0.5: C ρ0² / (4 A M g l) = 1.15, a fast top hanging),
    # it precesses about the vertical (~0.65 rad/s) and passes 10° from the singularity on each
    # side, with a 15 rad/s nutation, at −33.87° with every exact term (centrifugal included). Quet
    # sec. 3 §VI eq. (55), ρ + Ω·e constant (the centrifugal torque has no component along the figure
    # axis of a body of revolution), holds to 1e-10 of ρ0 (rtol 1e-12 over ~1e4 steps), and the
    # Jacobi integral ½A|ė|² + ½Cρ² + M g l e_z − ½ Ωᵀ I Ω (eq. 51 with the centrifugal potential;
    # ė by quintic spline, error < 1e-10) to 1e-9 of M g l; the axis goes around (azimuth turns > π
    # in 6 s). Measured: (55) to 2.7e-12 rad/s, the Jacobi integral to 1.2e-10 M g l.
    from scipy.interpolate import make_interp_spline
    site = Site.from_degrees(-33.87)
    A, C, M, lc, rho0 = 10.0, 5.0, 10.0, 1.0, 30.0
    cp = build(CompoundPendulum, site, EXACT, mass_kg=M, com_distance_m=lc, transverse_inertia_kg_m2=A,
               axial_inertia_kg_m2=C, spin_rate_rad_s=rho0, initial_deflection_deg=80.0, initial_azimuth_deg=90.0,
               rtol=1e-12)
    t = np.arange(0.0, 6.0, 1.0 / 400.0)
    c = cp.simulate(t).columns
    for col in c.values():
        assert np.all(np.isfinite(col))
    e = np.vstack([c["x_east"], c["y_north"], c["z_up"]]) / lc
    om = site.earth_rate_enu()
    oe = om @ e
    assert np.ptp(c["spin_rate"] + oe) < 1e-10 * rho0
    edot = np.vstack([make_interp_spline(t, ei, k=5).derivative()(t) for ei in e])
    g = site.gravity_m_s2
    E = (0.5 * A * np.sum(edot ** 2, axis=0) + 0.5 * C * c["spin_rate"] ** 2 + M * g * lc * e[2]
         - 0.5 * (A * (om @ om) + (C - A) * oe ** 2))
    m = t.size // 20
    assert np.ptp(E[m:-m]) < 1e-9 * M * g * lc
    assert np.ptp(c["azimuth"]) > math.pi
    assert np.max(c["deflection"]) < math.radians(89.0)


@pytest.mark.parametrize("factor", [1 - 1e-3, 1 + 1e-3])
def test_puiseux_spheroid_at_critical_spin(build, factor):
    # Why hard: at r_crit the small-tilt frequencies merge and the stability margin vanishes, so
    # linear theory bounds nothing. The classifier flips exactly across r_crit; the simulation stays
    # finite and never tilts past the first turning point allowed by the invariants (vertical
    # angular momentum and energy; released with no precession):
    #   (C r)² (cos θ0 − cos θ)² / (2 A sin² θ) = M g (h(θ0) − h(θ)),  h = √(α² sin²θ + γ² cos²θ),
    # to 1e-4 (sampling at 10 ms), with the energy conserved to 1e-8.
    from scipy.optimize import brentq
    g = 9.8088
    al, ga, M = 0.1, 0.2, 1.0
    rc = critical_spin_rad_s(al, al, ga, g)
    A = M * (al ** 2 + ga ** 2) / 5
    C = M * (al ** 2 + al ** 2) / 5
    r = factor * rc
    v = classify_stability(A, A, C, M, g, r, al, al, ga)
    assert v.verdict == ("stable" if factor > 1 else "unstable")
    th0 = 0.01
    h = lambda th: math.sqrt(al ** 2 * math.sin(th) ** 2 + ga ** 2 * math.cos(th) ** 2)  # noqa: E731
    f = lambda th: (C * r) ** 2 * (math.cos(th0) - math.cos(th)) ** 2 / (2 * A * math.sin(th) ** 2) \
        - M * g * (h(th0) - h(th))  # noqa: E731
    grid = np.linspace(th0 * 1.0001, math.pi / 2, 20000)
    vals = np.array([f(x) for x in grid])
    i = int(np.argmax(vals < 0))                      # just above θ0 the potential term wins (f < 0)
    j = i + int(np.argmax(vals[i:] >= 0))             # the turning point: f back to 0
    turning = brentq(f, grid[j - 1], grid[j])
    site = Site(math.radians(48.85), gravity_m_s2=g)
    body = build(PuiseuxBody, site, (), shape="ellipsoid", semi_axes_m=[al, al, ga], mass_kg=M,
                 spin_rate_rad_s=r, initial_tilt_deg=math.degrees(th0))
    s = body.simulate(np.linspace(0.0, 20.0, 2001))
    tilt = s.columns["tilt"]
    assert np.all(np.isfinite(tilt))
    assert np.max(tilt) <= turning * (1 + 1e-4)
    energy = s.extra["energy_J"]
    assert np.ptp(energy) < 1e-8 * max(abs(energy[0]), 1.0)


def test_damaged_records_are_reported_not_fatal():
    # Issue 6 §4: NaN samples, a gap, out-of-order and duplicated stamps, and a too-short record.
    # The estimator says what it dropped and still estimates what it can; the too-short gyroscope is
    # null with a reason while the others carry on.
    scene = load_scene("quet_paris", ["duration_s=300"])
    truth = simulate_truth(scene)
    rec = measure(scene, truth)
    rng = np.random.default_rng(0)
    g = rec["gyro_horizontal"]
    g["angle"][rng.random(g["angle"].size) < 0.05] = np.nan
    keep = (g["t"] < 100) | (g["t"] > 150)
    perm = rng.permutation(int(keep.sum()))
    for k in ("t", "angle", "spin_rate"):
        g[k] = np.concatenate([g[k][keep][perm], g[k][keep][:20]])
    g.pop("angle_channel", None)
    m = rec["gyro_meridian"]
    for k in ("t", "angle", "spin_rate"):
        m[k] = m[k][:60]                       # 3 s: a fraction of a swing
    r = estimate_records(scene, truth[1], rec)
    json.dumps(r, allow_nan=False, default=float)
    notes = " ".join(r["instruments"]["gyro_horizontal"]["notes"])
    assert "non-finite" in notes and "duplicated" in notes and "re-ordered" in notes
    assert r["instruments"]["gyro_horizontal"]["swing_duration_s"] > 0
    assert r["instruments"]["gyro_meridian"]["swing_duration_s"] is None
    assert r["instruments"]["gyro_meridian"]["reason"]
    # the horizontal gyroscope and the pendulum still give the latitude: quet_paris's, within 5 of its
    # reported sigma (a Gaussian draw beyond 5 sigma: 6e-7), from the records that are left
    assert abs(r["latitude_deg"] - 48.8462) < 5 * r["latitude_sigma_deg"], (r["latitude_deg"], r["latitude_sigma_deg"])
    # ... and only they carry it (the meridian gyroscope's 3 s are out; measured weights 1 - 1.5e-8, 1.5e-8)
    assert set(r["carried_by"]) == {"gyro_horizontal", "pendulum"}, r["carried_by"]


def test_wrong_message_type_on_a_topic_is_reported():
    # A Float64 published on a JointState topic: DDS never matches it; the estimator node finds it
    # in the graph, logs it and reports it in its diagnostics instead of waiting silently.
    import time
    import rclpy
    from rclpy.parameter import Parameter
    from std_msgs.msg import Float64
    from gyro_instrument.ros.nodes import EstimatorNode
    ctx, ctx2 = rclpy.Context(), rclpy.Context()     # the rogue is another participant, as in the field
    rclpy.init(context=ctx, args=[])
    rclpy.init(context=ctx2, args=[])
    try:
        est = EstimatorNode(context=ctx, parameter_overrides=[Parameter("scene", value="quet_paris")])
        rogue = rclpy.create_node("rogue", context=ctx2)
        rogue.create_publisher(Float64, "/gyro_horizontal/joint_states", 10)
        t0 = time.monotonic()
        while not est.check_topic_types() and time.monotonic() - t0 < 10:
            time.sleep(0.05)
        assert est.wrong_types == {"/gyro_horizontal/joint_states": ["std_msgs/msg/Float64"]}
        assert est.received() == 0
        rogue.destroy_node()
        est.destroy_node()
    finally:
        rclpy.shutdown(context=ctx)
        rclpy.shutdown(context=ctx2)
