"""Directing-plane gyroscope against Quet 1853 sec. 4 §1 (eqs. 1–10, items 6, 8, 9).

Reference values: eq. (9) T = π/√(μ n ρ0 sin ω) (one swing = half a period), the pendulum
finite-amplitude factor (2/π) K(sin(a/2)) (item 6), item 9 (T_m/T_h)² = cos γ, the exact
rigid-body equation derived in the module docstring (the term Quet drops has relative size
n/(μρ0)).
"""

import math

import numpy as np
import pytest

from gyro_instrument.core.site import Site
from gyro_instrument.estimators.crossings import local_maxima, mean_interval, zero_crossings
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope

EXACT = ("earth_rotation", "centrifugal", "finite_amplitude")
REDUCED = ("earth_rotation", "finite_amplitude")   # Quet's eqs. (1)-(3)


def measured_swing(g, n_swings=6, model=None):
    """One-swing duration from Hermite-refined zero crossings of u (error O((T/400)^4) ≈ 4e-11)."""
    T = g.predictions()["swing_duration_s"]
    t = np.linspace(0.0, (n_swings + 1) * T, 400 * (n_swings + 1) + 1)
    s = g.simulate(t, model=model)
    z = zero_crossings(t, s.columns["angle"], s.columns["angle_rate"])
    T_meas, _ = mean_interval(z)
    return T_meas, s


@pytest.mark.parametrize("lat_deg", [48.85, -33.9, 5.0])
@pytest.mark.parametrize("plane", ["horizontal", "meridian"])
def test_swing_duration_matches_eq9_times_finite_amplitude(build, lat_deg, plane):
    # Tolerance 1e-6: the exact model differs from eq. (9) only by O(n/(μρ0)) ≈ 6e-8 and the
    # zero-crossing measurement error is ~1e-10; a wrong factor (e.g. period vs half period, or
    # the a²/16 term ≈ 6e-4 at 0.1 rad) would miss by far more.
    g = build(PlaneGyroscope, Site.from_degrees(lat_deg), EXACT, plane=plane, initial_angle_deg=math.degrees(0.1))
    T_meas, _ = measured_swing(g)
    pred = g.predictions()
    sin_omega = math.cos(math.radians(lat_deg)) if plane == "horizontal" else 1.0
    T9 = math.pi / math.sqrt(2.0 * 7.2921150e-5 * 2 * math.pi * 100 * sin_omega)
    assert pred["swing_duration_small_s"] == pytest.approx(T9, rel=1e-12)
    assert T_meas == pytest.approx(T9 * finite_amplitude_factor(0.1), rel=1e-6)


def test_item9_ratio_of_squares_is_cos_latitude(build):
    # Item 9: (T_m/T_h)² = cos γ. Tolerance 1e-7: the O(n²) term shifts the ratio by
    # (μ−1) n (sin ω_h − sin ω_m)/(μ ρ0) ≈ −2e-8 (module docstring); measurement error ~1e-10.
    lat = 48.85
    site = Site.from_degrees(lat)
    Th, _ = measured_swing(build(PlaneGyroscope, site, EXACT, plane="horizontal"))
    Tm, _ = measured_swing(build(PlaneGyroscope, site, EXACT, plane="meridian"))
    assert (Tm / Th) ** 2 == pytest.approx(math.cos(math.radians(lat)), abs=1e-7)


def test_eq10_recovers_earth_rate_and_item8_misprint_does_not(build):
    # Eq. (10) n = π²/(μ ρ0 T² sin ω) with the small-amplitude T. Item 8 prints π/(μρ0T²),
    # which is off by a factor π (a misprint: docs/physics.md).
    g = build(PlaneGyroscope, Site.from_degrees(48.85), EXACT, plane="meridian", initial_angle_deg=0.01)
    T_meas, _ = measured_swing(g)
    T_small = T_meas / finite_amplitude_factor(math.radians(0.01))
    mu, rho0 = 2.0, 2 * math.pi * 100
    n_eq10 = math.pi ** 2 / (mu * rho0 * T_small ** 2)
    assert n_eq10 == pytest.approx(7.2921150e-5, rel=1e-6)
    n_item8 = math.pi / (mu * rho0 * T_small ** 2)
    assert abs(n_item8 / 7.2921150e-5 - 1) > 0.5


def test_exact_and_reduced_differ_by_order_n_over_mu_rho(build):
    # The exact equation (the module docstring's) adds −(μ−1) n² sin²ω cos u sin u to Quet's (2), so the
    # restoring constant grows by the factor 1 + (μ−1) n sin ω / (μ ρ0) and T shrinks by half of
    # that: ΔT/T = −(μ−1) n sin ω / (2 μ ρ0) = −2.9e-8 here. Use a slow spin (ρ0 = 0.05 rad/s,
    # n/(μρ0) ≈ 7e-4) so the difference stands far above the 1e-10 measurement error;
    # tolerance 3 % of the effect covers its own O((n/μρ0)²) and amplitude corrections.
    site = Site.from_degrees(48.85)
    kw = dict(plane="meridian", spin_rate_rad_s=0.05, initial_angle_deg=0.5)
    Te, _ = measured_swing(build(PlaneGyroscope, site, EXACT, **kw), n_swings=4)
    Tr, _ = measured_swing(build(PlaneGyroscope, site, REDUCED, **kw), n_swings=4)
    predicted = -(2.0 - 1.0) * 7.2921150e-5 / (2 * 2.0 * 0.05)
    assert (Te / Tr - 1.0) == pytest.approx(predicted, rel=0.03)


def test_generic_hinge_chain_reproduces_reduced_equation(build):
    # Two independent derivations: Kane's method on the hinge chain (instruments/chain.py) and
    # the closed-form Lagrangian equation must give the same motion; both are integrated at
    # rtol 1e-11, so the state agrees to ~1e-9 rad.
    g = build(PlaneGyroscope, Site.from_degrees(-33.9), EXACT, plane="horizontal", initial_angle_deg=30.0)
    t = np.linspace(0, 60, 601)
    a = g.simulate(t, model="reduced").columns
    b = g.simulate(t, model="chain").columns
    assert np.max(np.abs(a["angle"] - b["angle"])) < 1e-8
    assert np.max(np.abs(a["spin_rate"] - b["spin_rate"])) < 1e-8


@pytest.mark.parametrize("model", ["reduced", "chain"])
def test_invariants_spin_integral_and_energy(build, model):
    # Eq. (3)/(6): ρ + n sin ω cos u is conserved exactly; the Jacobi integral
    # ½u̇² − μ s p cos u − ½ p² sin² u (s the conserved spin, p = n sin ω) is conserved by the
    # exact equations. Bounds: 1e-9 relative — integration at rtol 1e-11 over ~20 swings; a
    # dropped or mis-signed term would break them at ~1e-4 (p sin u u̇ relative to ρ).
    site = Site.from_degrees(48.85)
    g = build(PlaneGyroscope, site, EXACT, plane="horizontal", initial_angle_deg=60.0, model=model)
    t = np.linspace(0, 250, 2501)
    c = g.simulate(t).columns
    p = site.earth_rate_rad_s * g.sin_omega
    s = c["spin_rate"] + p * np.cos(c["angle"])
    assert np.ptp(s) / abs(s[0]) < 1e-12
    E = 0.5 * c["angle_rate"] ** 2 - 2.0 * s[0] * p * np.cos(c["angle"]) - 0.5 * p ** 2 * np.sin(c["angle"]) ** 2
    assert np.ptp(E) / (2.0 * s[0] * p) < 1e-9


def test_reduced_energy_integral_eq1(build):
    # Eq. (1)/(5): u'² + μ ρ² is constant for Quet's reduced equations (2)-(3). Bound 1e-12
    # relative to μρ0² (integration at rtol 1e-11; the integral is quadratic in the state).
    g = build(PlaneGyroscope, Site.from_degrees(48.85), REDUCED, plane="meridian", initial_angle_deg=90.0)
    c = g.simulate(np.linspace(0, 100, 1001)).columns
    a = c["angle_rate"] ** 2 + 2.0 * c["spin_rate"] ** 2
    assert np.ptp(a) / a[0] < 1e-12


def test_stability_follows_spin_sense_items_1_2(build):
    # Items 1-2: stable about the north projection when the spin is in the Earth's sense
    # (ρ0 > 0 here), unstable otherwise: reversed spin makes the axis swing over to u = π.
    site = Site.from_degrees(48.85)
    t = np.linspace(0, 60, 601)
    stable = build(PlaneGyroscope, site, EXACT, initial_angle_deg=10.0).simulate(t).columns["angle"]
    unstable = build(PlaneGyroscope, site, EXACT, initial_angle_deg=10.0,
                     spin_rate_rad_s=-2 * math.pi * 100).simulate(t).columns["angle"]
    assert np.max(np.abs(stable)) <= math.radians(10.0) + 1e-9
    assert np.max(np.abs(unstable)) > math.radians(170.0)


def test_polar_plane_has_no_restoring_torque_item4(build):
    # Item 4: a plane perpendicular to Earth's axis gives no directing torque; the axis keeps
    # its initial angle (released at rest) and eq. (9) gives an infinite duration.
    g = build(PlaneGyroscope, Site.from_degrees(48.85), EXACT, plane="polar", initial_angle_deg=40.0)
    c = g.simulate(np.linspace(0, 100, 11)).columns
    assert math.isinf(g.predictions()["swing_duration_small_s"])
    assert np.max(np.abs(c["angle"] - math.radians(40.0))) < 1e-12


def test_cone_variant_period(build):
    # Sec. 4 §1 (end): T = π √(sin ε / (μ n ρ0 sin ω)), the cone's half-angle ε about the
    # normal. Tolerance 1e-6 as for the plane; amplitude 0.01 rad so the finite-amplitude
    # correction (~6e-6, not derived for the cone) stays below it.
    g = build(PlaneGyroscope, Site.from_degrees(48.85), EXACT, plane="horizontal", cone_half_angle_deg=50.0,
              initial_angle_deg=math.degrees(0.002))
    T_meas, _ = measured_swing(g, n_swings=4)
    T_pred = math.pi * math.sqrt(math.sin(math.radians(50.0)) /
                                 (2.0 * 7.2921150e-5 * 2 * math.pi * 100 * math.cos(math.radians(48.85))))
    assert T_meas == pytest.approx(T_pred, rel=1e-6)


def test_spin_decay_and_pivot_damping(build):
    # Spin decay: ρ̇ = −ρ/τ (+ the O(n) exchange of eq. 3): after τ the spin is ρ0/e to 1e-6.
    # Pivot damping: the peak envelope decays at 1/τ_d within 1 % (peaks refined by a parabola).
    site = Site.from_degrees(48.85)
    g = build(PlaneGyroscope, site, EXACT + (("spin_decay", {"time_constant_s": 100.0}),))
    c = g.simulate(np.array([0.0, 100.0])).columns
    assert c["spin_rate"][-1] / c["spin_rate"][0] == pytest.approx(math.exp(-1.0), rel=1e-6)
    g = build(PlaneGyroscope, site, EXACT + (("pivot_damping", {"time_constant_s": 100.0}),),
              initial_angle_deg=1.0)
    t = np.linspace(0, 130, 13001)
    u = g.simulate(t).columns["angle"]
    tp, up = local_maxima(t, u)
    rate = -np.polyfit(tp, np.log(up), 1)[0]
    assert rate == pytest.approx(1.0 / 100.0, rel=0.01)


@pytest.mark.parametrize("effects", [EXACT, REDUCED, ("earth_rotation",),
                                     EXACT + (("spin_decay", {"time_constant_s": 50.0}),
                                              ("pivot_damping", {"time_constant_s": 30.0}))])
def test_scalar_dop853_driver_matches_generic_driver(build, effects):
    # The reduced model runs on a float DOP853 driver (speed); it must be the same method as
    # core.integrate's solve_ivp DOP853: same steps (nfev), same samples to rounding (1e-12 of
    # the scale, far below the ~1e-10 integration error at rtol 1e-11), for every effect set.
    from gyro_instrument.core.integrate import integrate
    g = build(PlaneGyroscope, Site.from_degrees(48.85), effects, plane="meridian", initial_angle_deg=40.0)
    t = np.linspace(0.0, 120.0, 2401)
    s = g.simulate(t)
    ref = integrate(g.reduced_rhs(), [g.p.initial_angle_rad, g.p.initial_rate_rad_s, g.p.spin_rate_rad_s], t, rtol=g.p.rtol, atol=1e-13)
    assert s.trajectory.nfev == ref.nfev
    assert np.max(np.abs(s.trajectory.y[:2] - ref.y[:2])) < 1e-12
    assert np.max(np.abs(s.trajectory.y[2] - ref.y[2])) < 1e-12 * abs(ref.y[2, 0])
    one = g.simulate(np.array([5.0])).columns
    assert one["angle"][0] == g.p.initial_angle_rad and one["spin_rate"][0] == g.p.spin_rate_rad_s
