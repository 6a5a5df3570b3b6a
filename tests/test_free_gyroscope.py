"""Free gyroscope against Quet 1853 sec. 4 §II (eqs. 1, 2, 7, 9, 16, 19, 22, 47, 48, 53).

Reference values: the mean westward rate V = n of the axis about Earth's axis (eq. 47), the
circular nutation of diameter 2 n sin θ0/(μ ρ0) and period 2π/h ≈ 2π/(μ ρ0) (eqs. 16, 19,
48; "ρ0 = 60: 2n/ρ0 = ½″"), the relative spin law ρ = ρ0 + n (cos θ − cos θ0) (eq. 7), and
the torque-free rigid body itself (|L|, kinetic energy and the rotating-frame Jacobi integral
T_rel − ½ Ωᵀ I Ω conserved). θ0 here is measured from the NORTH part of Earth's axis; Quet's
from the south part (his cos θ0 = −cos θ0 here, sin θ0 the same).
"""

import math

import numpy as np
import pytest

from gyro_instrument.core.quaternion import quat_to_matrix, rotate_about
from gyro_instrument.core.site import Site
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope

ROT = ("earth_rotation",)
PARIS = 48.85
N_SID = 7.2921150e-5
EPS_DEG = math.degrees(1e-6)     # 1e-6 rad, in degrees


def period_grid(g, t_min, per_period=64):
    """Samples from release to the first whole number of exact nutation periods ≥ t_min."""
    T = g.predictions()["nutation_period_exact_s"]
    m = math.ceil(t_min / T)
    return np.linspace(0.0, m * T, m * per_period + 1)


def slope(t, y):
    """Least-squares slope of y(t)."""
    return float(np.polyfit(t - t.mean(), y, 1)[0])


def upward_crossings(t, y):
    """Times where y crosses zero upward, by linear interpolation between samples."""
    i = np.nonzero((y[:-1] < 0.0) & (y[1:] >= 0.0))[0]
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


# ------------------------------------------------------------------ eq. (47): V = n


@pytest.mark.parametrize("lat_deg, alt, az, mu, spin", [
    (PARIS, 0.0, 90.0, 2.0, 60.0),       # axis horizontal, east: θ0 = 90°
    (PARIS, 20.0, 70.0, 1.0, 60.0),      # Quet's sphere (eqs. 20-48)
    (PARIS, 20.0, 70.0, 2.0, -60.0),     # item 3: the sense does not depend on the spin's
    (-33.9, -10.0, 200.0, 0.5, 600.0),   # southern site, prolate body
])
def test_mean_axis_rate_is_n_westward_analytic(build, lat_deg, alt, az, mu, spin):
    # Eq. (47): V = n, opposite to the Earth's rotation (hour angle grows). 1e-6 relative: over
    # ≥ 6 h the nutation wobble in hour angle, n/(μρ0) ≤ 2.4e-6 rad, is 1.5e-6 of the 1.6 rad
    # advance; ending on a whole number of exact nutation periods removes it (closed form:
    # exactly n), and the least-squares slope over 20 001 samples averages it to < 1e-7.
    g = build(FreeGyroscope, Site.from_degrees(lat_deg), ROT, initial_axis_altitude_deg=alt,
              initial_axis_azimuth_deg=az, inertia_ratio=mu, spin_rate_rad_s=spin)
    T = g.predictions()["nutation_period_exact_s"]
    t = np.linspace(0.0, math.ceil(6 * 3600.0 / T) * T, 20001)
    H = g.simulate(t).columns["hour_angle"]
    V_end = (H[-1] - H[0]) / t[-1]
    V_fit = slope(t, H)
    assert g.predictions()["mean_axis_rate_rad_s"] == N_SID
    assert V_end == pytest.approx(N_SID, rel=1e-6)
    assert V_fit == pytest.approx(N_SID, rel=1e-6)
    assert V_end > 0.0        # westward: opposite to the Earth's rotation (Quet's 3°)


def test_mean_axis_rate_over_a_sidereal_day_closes_the_circle(build):
    # Parallactic telescope: after one sidereal day the axis is back where it started relative
    # to the Earth, up to the nutation (diameter 2β ≈ 1.1e-6 rad here), and the unwrapped hour
    # angle has grown by 2π (to 1e-6 relative, as above).
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=70.0)
    day = 2 * math.pi / N_SID
    t = np.linspace(0.0, day, 4001)
    s = g.simulate(t)
    assert s.columns["hour_angle"][-1] - s.columns["hour_angle"][0] == pytest.approx(2 * math.pi, rel=1e-6)
    two_beta = g.predictions()["nutation_diameter_exact_rad"]
    assert np.linalg.norm(s.extra["axis_enu"][-1] - g.k0) <= two_beta * 1.0001
    assert np.ptp(s.columns["declination"]) <= two_beta * 1.0001


def test_mean_axis_rate_numerical_short(build):
    # The same from the numerical path over 4 s (~76 nutation periods): V = n to 1e-6. The
    # integration error in the axis is < 1e-14 rad (see the cross-check below), i.e. ~1e-10 of
    # the 2.9e-4 rad advance; ending on a whole number of nutation periods removes the wobble.
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=70.0, model="numerical", integrator="dop853")
    t = period_grid(g, 4.0, per_period=8)
    H = g.simulate(t).columns["hour_angle"]
    assert (H[-1] - H[0]) / t[-1] == pytest.approx(N_SID, rel=1e-6)


# ------------------------------------------------------------------ nutation (eqs. 16, 19, 48)


@pytest.mark.parametrize("alt, az, mu, spin", [
    (0.0, 90.0, 1.0, 60.0),      # Quet's example: θ0 = 90°, ρ0 = 60, μ = 1 -> 2n/ρ0 = 0.50″
    (20.0, 70.0, 2.0, 60.0),
    (-30.0, 200.0, 0.5, 100.0),
])
def test_nutation_diameter_and_period_from_numerical_samples(build, alt, az, mu, spin):
    # Diameter 2 n sin θ0/(μ ρ0) (eqs. 16, 19) to 5 %: the exact 2β differs by O(n/ρ0) ~ 1e-6
    # and the sampled peak-to-peak (64 samples a period) by at most 1 − cos(π/64) = 0.12 %.
    # The hour-angle wobble × cos δ0 has the same size (the nutation is circular, eq. 19).
    # Period 2π/(μ ρ0) to 1e-5: exact 2π A/|L| differs by n cos θ0/ρ0 ≤ 1.3e-6 and
    # interpolated crossings over ~20 periods err by < 1e-6.
    site = Site.from_degrees(PARIS)
    g = build(FreeGyroscope, site, ROT, initial_axis_altitude_deg=alt, initial_axis_azimuth_deg=az,
              inertia_ratio=mu, spin_rate_rad_s=spin, model="numerical", integrator="dop853")
    p = g.predictions()
    t = period_grid(g, 20 * p["nutation_period_s"], per_period=64)
    s = g.simulate(t)
    dec = s.columns["declination"]
    D_quet = 2 * N_SID * math.sin(g.theta0) / (mu * spin)
    assert p["nutation_diameter_rad"] == pytest.approx(D_quet, rel=1e-12)
    assert np.ptp(dec) == pytest.approx(D_quet, rel=0.05)
    wobble = (s.columns["hour_angle"] - s.columns["hour_angle"][0] - N_SID * t) * math.cos(dec[0])
    assert np.ptp(wobble) == pytest.approx(D_quet, rel=0.05)
    # Sign convention (Quet eq. 16 with θ from the south part): for ρ0 > 0 the axis first moves
    # toward the north part of Earth's axis: δ ranges over [δ0, δ0 + D].
    assert dec.min() >= dec[0] - 1e-14          # roundoff of atan2 on 0.5 rad: ~1e-15
    z = upward_crossings(t, dec - 0.5 * (dec.max() + dec.min()))
    T_meas = (z[-1] - z[0]) / (len(z) - 1)
    assert T_meas == pytest.approx(p["nutation_period_exact_s"], rel=1e-5)
    assert T_meas == pytest.approx(2 * math.pi / (mu * spin), rel=1e-5)
    if mu == 1.0:
        assert np.degrees(np.ptp(dec)) * 3600 == pytest.approx(0.50, abs=0.005)   # Quet: "½″"
    # Analytic path over the same horizon: the same axis to 1e-12 rad (integrator phase error
    # ~ rtol × μρ0 t ≈ 1e-9 rad on a circle of radius ≤ 1.2e-6 rad, plus roundoff ~1e-15) and
    # the same full attitude (spin phase included) to 1e-9 rad (rtol × ω t ≈ 1e-10 rad).
    a = g.simulate(t, model="analytic")
    assert np.max(np.linalg.norm(a.extra["axis_enu"] - s.extra["axis_enu"], axis=1)) < 1e-12
    assert np.max(np.abs(a.extra["attitude_enu"] - s.extra["attitude_enu"])) < 1e-9
    assert np.max(np.abs(a.columns["spin_rate"] - s.columns["spin_rate"])) < 1e-9


@pytest.mark.parametrize("alt, az, mu", [(20.0, 70.0, 2.0), (0.0, 90.0, 1.0), (-30.0, 200.0, 0.5)])
def test_closed_form_matches_quet_first_order_eqs_16_19(build, alt, az, mu):
    # Eqs. (16), (19): cos θ_Q = cos θ0_Q − a (1 − cos ht), ψ − ψ0 = n t − (n/(μρ0)) sin ht,
    # a = n sin²θ0/(μ(ρ0 − 2n cos θ0_Q)), h² = μ²ρ0(ρ0 − 2n cos θ0_Q) (eq. 11), ψ = hour angle.
    # They drop terms of relative order n/(μρ0) ≤ 2.4e-6 of the nutation radius β ≤ 1.2e-6:
    # bound 5 (n/(μρ0)) β + 1e-14 rad (measured 6e-16 to 2.2e-12) over 100 s.
    site = Site.from_degrees(PARIS)
    g = build(FreeGyroscope, site, ROT, initial_axis_altitude_deg=alt, initial_axis_azimuth_deg=az,
              inertia_ratio=mu)
    rho0 = g.p.spin_rate_rad_s
    t = np.linspace(0.0, 100.0, 200001)
    s = g.simulate(t)
    cq = -math.cos(g.theta0)
    h = mu * math.sqrt(rho0 * (rho0 - 2 * N_SID * cq))
    a = N_SID * math.sin(g.theta0) ** 2 / (mu * (rho0 - 2 * N_SID * cq))
    dec_q = np.arcsin(-(cq - a + a * np.cos(h * t)))
    psi_q = N_SID * t - N_SID / (mu * rho0) * np.sin(h * t)
    bound = 5 * N_SID / (mu * rho0) * g.predictions()["nutation_diameter_rad"] / 2 + 1e-14
    assert np.max(np.abs(s.columns["declination"] - dec_q)) < bound
    H = s.columns["hour_angle"] - s.columns["hour_angle"][0]
    assert np.max(np.abs(H - psi_q)) * math.cos(s.columns["declination"][0]) < bound


# ------------------------------------------------------------------ near Earth's axis


@pytest.mark.parametrize("part", ["north", "south"])
@pytest.mark.parametrize("mu", [2.0, 1.0])
def test_axis_within_1e6_rad_of_earth_axis(build, part, mu):
    # Axis 1e-6 rad from the north (Quet: cos θ0_Q ≈ −1) or south part of Earth's axis. The
    # physics: the nutation cone (half-angle β = n sin θ0/(μρ0) ≈ 1e-12 rad) is far smaller
    # than the 1e-6 rad to the pole, so the axis stays fixed in inertial space up to 2β: relative
    # to the Earth it circles Earth's axis at n. Checks: every column finite; the axis equals
    # Rot(ê, −n t) k0 to 2β + 1e-15; the declination stays within 2β + 1e-15; the hour angle
    # grows at n to 1e-6 (ends on whole nutation periods; its precision is 1e-16/1e-6 = 1e-10
    # rad). Numerical path over 1 s: same axis as the closed form to 1e-13 rad.
    site = Site.from_degrees(PARIS)
    alt, az = (PARIS + EPS_DEG, 0.0) if part == "north" else (-(PARIS + EPS_DEG), 180.0)
    g = build(FreeGyroscope, site, ROT, initial_axis_altitude_deg=alt, initial_axis_azimuth_deg=az,
              inertia_ratio=mu)
    off = g.theta0 if part == "north" else math.pi - g.theta0
    assert off == pytest.approx(1e-6, rel=1e-6)
    two_beta = g.predictions()["nutation_diameter_exact_rad"]
    assert two_beta < 3e-12
    T = g.predictions()["nutation_period_exact_s"]
    t = np.linspace(0.0, math.ceil(6 * 3600.0 / T) * T, 4001)
    s = g.simulate(t)
    for name, col in s.columns.items():
        assert np.all(np.isfinite(col)), name
    fixed = rotate_about(g.k0, site.earth_axis_north_enu(), -N_SID * t)
    assert np.max(np.linalg.norm(s.extra["axis_enu"] - fixed, axis=1)) < two_beta + 1e-15
    assert np.ptp(s.columns["declination"]) < two_beta + 1e-15
    H = s.columns["hour_angle"]
    assert (H[-1] - H[0]) / t[-1] == pytest.approx(N_SID, rel=1e-6)
    tn = np.linspace(0.0, 1.0, 201)
    sn = g.simulate(tn, model="numerical", integrator="dop853")
    sa = g.simulate(tn, model="analytic")
    assert all(np.all(np.isfinite(c)) for c in sn.columns.values())
    assert np.max(np.linalg.norm(sn.extra["axis_enu"] - sa.extra["axis_enu"], axis=1)) < 1e-13


def test_axis_exactly_on_earth_axis_is_finite_and_fixed(build):
    # θ0 = 0: L ∥ k0 ∥ ê, the axis never moves (β = 0). Declination stays π/2 and the axis at
    # k0 to roundoff (bounds 1e-14: a few ulps of the rotations); the hour angle is undefined
    # there (atan2 of two roundoff-sized numbers) but must still be finite.
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=PARIS,
              initial_axis_azimuth_deg=0.0)
    t = np.linspace(0.0, 86400.0, 1001)
    for model in ("analytic", "numerical"):
        tt = t if model == "analytic" else t[:11] / 8640.0     # numerical: 1 s
        s = g.simulate(tt, model=model, integrator="dop853")
        assert all(np.all(np.isfinite(c)) for c in s.columns.values())
        assert np.max(np.abs(s.columns["declination"] - math.pi / 2)) < 1e-14
        assert np.max(np.linalg.norm(s.extra["axis_enu"] - g.k0, axis=1)) < 1e-14


def test_quet_condition_eq53_holds_near_north_axis():
    # Eq. (53) needs cos θ0_Q − 2μρ0 n sin²θ0/h² ≥ −1 and Quet warns it fails with the axis
    # "presque parallèle à la partie nord". With ρ0 ≫ n it holds however near: 1 + cos θ0_Q =
    # 2 cos²(θ0_Q/2) ≈ ε²/2 while the subtracted term ≈ 2 n ε²/(μρ0). Margin ratio ≥ 0.99.
    mu, rho0 = 2.0, 60.0
    for eps in (1e-9, 1e-6, 1e-3, 0.1):
        th = math.pi - eps
        h2 = mu * mu * rho0 * (rho0 - 2 * N_SID * math.cos(th))
        sub = 2 * mu * rho0 * N_SID * math.sin(th) ** 2 / h2
        assert 2 * math.cos(th / 2) ** 2 - sub > 0.99 * 2 * math.cos(th / 2) ** 2


# ------------------------------------------------------------------ zero spin (item 1°)


@pytest.mark.parametrize("case, alt, az, mu", [
    ("sphere", 20.0, 70.0, 1.0),                 # μ = 1: every axis is principal
    ("along_axis", PARIS, 0.0, 2.0),             # k0 = ê: Ω along the figure axis
    ("across_axis", PARIS - 90.0, 0.0, 2.0),     # k0 ⊥ ê: Ω along a transverse principal axis
])
def test_zero_spin_stays_in_relative_equilibrium_when_omega_is_principal(build, case, alt, az, mu):
    # Item 1°: released at rest relative to the Earth with ρ0 = 0 it stays at rest. Exact when Ω
    # is a principal axis (then L = IΩ ∥ Ω and the co-rotation is a steady Euler motion): the
    # axis stays fixed relative to the Earth to 1e-12 rad over a day (roundoff of the two
    # rotations by nt ≤ 2π: ~1e-15) and over 1 h numerically, and the relative spin stays 0.
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=alt,
              initial_axis_azimuth_deg=az, inertia_ratio=mu, spin_rate_rad_s=0.0)
    assert g.predictions()["relative_equilibrium_exact"]
    for model, T in (("analytic", 86400.0), ("numerical", 3600.0)):
        t = np.linspace(0.0, T, 241)
        s = g.simulate(t, model=model, integrator="dop853")
        assert np.max(np.linalg.norm(s.extra["axis_enu"] - g.k0, axis=1)) < 1e-12
        assert np.max(np.abs(s.columns["spin_rate"])) < 1e-15


def test_zero_spin_general_axis_leaves_relative_equilibrium(build):
    # Physics, not Quet's 1°: for μ ≠ 1 and an axis neither along nor across Earth's axis,
    # L = IΩ is not parallel to Ω, so the co-rotation is not a torque-free motion; in Earth axes
    # the centrifugal torque (C − A) n² sin θ0 cos θ0 (dropped by Quet's eq. 2, see below)
    # turns the axis: δ(t) − δ0 = ½ (μ − 1) n² sin θ0 cos θ0 t² + O((nt)²) relative.
    # At t = 600 s (nt = 0.044) to 2e-3 relative (measured −1.6e-4); after 1 h ≈ 0.83°.
    # Numerical and analytic paths agree to 1e-12 rad over the hour (measured 8e-14).
    mu = 2.0
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=0.0, inertia_ratio=mu, spin_rate_rad_s=0.0)
    p = g.predictions()
    assert not p["relative_equilibrium_exact"]
    t = np.linspace(0.0, 3600.0, 61)
    sa = g.simulate(t)
    sn = g.simulate(t, model="numerical", integrator="dop853")
    dec = sa.columns["declination"] - sa.columns["declination"][0]
    th = g.theta0
    acc = (mu - 1) * N_SID ** 2 * math.sin(th) * math.cos(th)
    assert dec[10] == pytest.approx(0.5 * acc * 600.0 ** 2, rel=2e-3)
    assert math.degrees(dec[-1]) == pytest.approx(0.83, abs=0.01)
    # d²(cos θ)/dt² = cos δ0 · δ̈ at release (δ̇ = 0): the closed-form prediction.
    assert p["initial_cos_theta_acceleration_rad_s2"] == pytest.approx(acc * math.sin(th), rel=1e-12)
    assert np.max(np.linalg.norm(sa.extra["axis_enu"] - sn.extra["axis_enu"], axis=1)) < 1e-12


@pytest.mark.parametrize("lat, alt, az, mu, spin", [
    (-33.87, -10.0, 180.0, 1.5, 60.0),     # southern site, axis below the horizon, a spinning configuration
    (PARIS, 20.0, 0.0, 2.0, 0.0),          # the 0.83° case of the test above
    (PARIS, 0.0, 90.0, 2.0, 60.0),         # east: across Earth's axis, Quet exact (departure 0)
    (-33.87, 40.0, 300.0, 0.5, 0.0),       # μ < 1: the departure has the other sense, same law
])
def test_stated_zero_spin_departure_matches_the_simulated_one(build, lat, alt, az, mu, spin):
    # Issue 17 item 5: sec. 4 §II item 1 says a zero-spin body stays in relative equilibrium; the
    # prediction states, for the configuration's axis, μ and site, how far a zero-spin release
    # actually leaves its place in the first hour (zero_spin_departure_1h_rad, from the closed form).
    # An independent path must reproduce it: the quaternion integration (model: numerical, rtol
    # 1e-12) of the zero-spin body, 1 h — agreement to 1e-10 rad (the two paths agree to 8e-14 over
    # the hour in the test above). The leading-order law ½|μ − 1| n² sin θ0 |cos θ0| t² is within
    # (n t)² ≈ 7 % of it.
    site = Site.from_degrees(lat)
    kw = dict(initial_axis_altitude_deg=alt, initial_axis_azimuth_deg=az, inertia_ratio=mu)
    g = build(FreeGyroscope, site, ROT, spin_rate_rad_s=spin, **kw)
    pred = g.predictions()
    zero = build(FreeGyroscope, site, ROT, spin_rate_rad_s=0.0, model="numerical", integrator="dop853", **kw)
    s = zero.simulate(np.linspace(0.0, 3600.0, 61))
    a = s.extra["axis_enu"]
    simulated = math.atan2(np.linalg.norm(np.cross(a[0], a[-1])), a[0] @ a[-1])
    assert pred["zero_spin_departure_1h_rad"] >= 0.0
    assert simulated == pytest.approx(pred["zero_spin_departure_1h_rad"], abs=1e-10)
    if pred["relative_equilibrium_exact"]:
        assert simulated < 1e-12 and "stays put" in pred["beyond_the_paper"]
    else:
        assert simulated > 1e-4                      # 0.04–0.8° here: far beyond what Quet allows (0)
        assert pred["zero_spin_departure_1h_leading_rad"] == pytest.approx(simulated, rel=(N_SID * 3600) ** 2)
        assert f"{math.degrees(simulated):.4g}°" in pred["beyond_the_paper"]


def test_relative_vis_viva_eq2_is_exact_only_for_a_sphere(build):
    # Quet's eq. (2), first line: the relative vis viva A(θ'² + sin²θ ψ'² + μρ²) is constant.
    # In axes turning at constant Ω the conserved quantity is the Jacobi integral
    # T_rel − ½ ΩᵀIΩ; ΩᵀIΩ = A n² (1 + (μ − 1) cos²θ) varies with θ unless μ = 1. Zero spin,
    # μ = 2, 1 h: T_rel grows from 0 by (μ−1)A n² Δ(cos²θ)/2 = 3.2e-14 J (to 1e-6 relative:
    # integration error ~1e-12) while the Jacobi integral holds to 1e-25 J (2e-14 of
    # ½ΩᵀIΩ = 4.7e-12 J; measured 5.7e-27 J) on the Python-float DOP853, whose last step ends on the
    # last sample. The compiled DOP853 steps with no end (8 steps over the hour) and reads the last
    # samples from the dense output of a longer last step: the integral within rtol of ½ΩᵀIΩ there
    # (measured 1.6e-25 J, 3e-14 relative).
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=0.0, inertia_ratio=2.0, spin_rate_rad_s=0.0)
    t = np.linspace(0.0, 3600.0, 61)
    for compiled in (False, True):
        s = g.simulate(t, model="numerical", integrator="dop853", compiled=compiled)
        R = quat_to_matrix(s.trajectory.y[:4].T)
        wb = s.trajectory.y[4:].T
        om_b = np.einsum("mji,j->mi", R, N_SID * g.e_axis)
        inertia = np.array([g.p.transverse_inertia_kg_m2, g.p.transverse_inertia_kg_m2, g.C])
        t_rel = 0.5 * np.sum(inertia * (wb - om_b) ** 2, axis=1)
        t0 = 0.5 * np.sum(inertia * om_b ** 2, axis=1)
        cos_th = s.extra["axis_inertial"] @ g.e_axis
        assert t_rel[-1] - t_rel[0] == pytest.approx(0.5 * g.p.transverse_inertia_kg_m2 * N_SID ** 2 * (cos_th[-1] ** 2 - cos_th[0] ** 2),
                                                     rel=1e-6)
        assert t_rel[-1] - t_rel[0] > 1e-14
        assert np.ptp(t_rel - t0) < (g.p.rtol * np.max(np.abs(t0)) if compiled else 1e-25)


# ------------------------------------------------------------------ invariants


def test_numerical_invariants_and_relative_spin_eq7(build):
    # Torque-free body: |L| (inertial) and the kinetic energy are constant; |q| = 1. Over 5 s
    # (~95 nutation periods, rtol 1e-12): |L| and energy to 1e-12 relative, |q| to 1e-12
    # (Baumgarte term; measured ~1e-15, 0, 1e-13). Relative spin: eq. (7) ρ = ρ0 + n (cos θ_Q −
    # cos θ0_Q) = ρ0 + n (sin δ0 − sin δ) to 1e-13 rad/s (a 1e-10 rad/s effect here).
    g = build(FreeGyroscope, Site.from_degrees(PARIS), ROT, initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=70.0, model="numerical", integrator="dop853")
    t = np.linspace(0.0, 5.0, 2001)
    s = g.simulate(t)
    L = np.linalg.norm(s.extra["angular_momentum"], axis=1)
    E = s.extra["kinetic_energy_j"]
    assert np.ptp(L) / L[0] < 1e-12
    assert np.ptp(E) / E[0] < 1e-12
    assert np.max(np.abs(s.extra["quaternion_norm"] - 1.0)) < 1e-12
    assert s.trajectory.nfev > 0
    dec = s.columns["declination"]
    rho7 = g.p.spin_rate_rad_s + N_SID * (np.sin(dec[0]) - np.sin(dec))
    assert np.max(np.abs(s.columns["spin_rate"] - rho7)) < 1e-13
    assert np.ptp(s.columns["spin_rate"]) > 1e-11          # the eq. (7) variation is resolved
    # The closed form's constants: absolute spin ρ0 + n cos θ0 and |L| = A |Λ|.
    k = s.extra["motion_constants"]
    assert L[0] == pytest.approx(g.p.transverse_inertia_kg_m2 * k["lam"], rel=1e-14)
    assert g.predictions()["absolute_spin_rad_s"] == pytest.approx(g.p.spin_rate_rad_s + N_SID * math.cos(g.theta0), rel=1e-15)


def test_without_earth_rotation_the_axis_stays_put(build):
    # n = 0 in the model: L ∥ k0, the axis never moves (1e-15 rad over a day); spin constant.
    g = build(FreeGyroscope, Site.from_degrees(PARIS), (), initial_axis_altitude_deg=20.0,
              initial_axis_azimuth_deg=70.0)
    t = np.linspace(0.0, 86400.0, 1001)
    s = g.simulate(t)
    assert np.max(np.linalg.norm(s.extra["axis_enu"] - g.k0, axis=1)) < 1e-15
    assert np.ptp(s.columns["hour_angle"]) < 1e-14
    assert np.ptp(s.columns["spin_rate"]) == 0.0
    assert s.columns["spin_rate"][0] == pytest.approx(g.p.spin_rate_rad_s, rel=1e-15)
    assert g.predictions()["nutation_diameter_rad"] == 0.0


def test_initial_columns_and_scales(build):
    # Columns at release for two directions (to 1e-15 rad, roundoff): the equator's meridian
    # point (altitude 90° − γ, due south) has hour angle 0 and declination 0; the west point of
    # the horizon has hour angle +π/2 (6 h, westward positive) and compass azimuth −π/2 (270°).
    site = Site.from_degrees(PARIS)
    g = build(FreeGyroscope, site, ROT, initial_axis_altitude_deg=90.0 - PARIS, initial_axis_azimuth_deg=180.0)
    s = g.simulate(np.array([0.0, 1.0]))
    assert s.columns["axis_altitude"][0] == pytest.approx(math.radians(90.0 - PARIS), abs=1e-15)
    assert abs(s.columns["hour_angle"][0]) < 1e-15 and abs(s.columns["declination"][0]) < 1e-15
    g = build(FreeGyroscope, site, ROT, initial_axis_altitude_deg=0.0, initial_axis_azimuth_deg=270.0)
    s = g.simulate(np.array([0.0, 1.0]))
    assert s.columns["hour_angle"][0] == pytest.approx(math.pi / 2, abs=1e-15)     # west: +6 h
    assert s.columns["axis_azimuth"][0] == pytest.approx(-math.pi / 2, abs=1e-15)
    sc = g.scales(3600.0)
    assert set(sc) >= {"earth_rate_rad_s", "gyro_rate_rad_s", "restoring_rate_rad_s", "amplitude_rad", "duration_s"}
    assert sc.gyro_rate_rad_s == pytest.approx(2.0 * 60.0)


def test_scalar_right_hand_side_is_the_array_one_term_for_term():
    # the numerical model integrates rhs_scalar (Python floats, the scalar DOP853 driver, for speed);
    # it must be rhs() exactly: the same terms in the same order give the same doubles (no tolerance)
    import numpy as np
    from gyro_instrument.scenes import build_instruments, load_scene
    for over in ([], ["instruments.free_gyro.inertia_ratio=1.7"]):
        inst = build_instruments(load_scene("free_gyroscope", ["instruments.free_gyro.model=numerical"] + over))[
            "free_gyro"]
        f, g = inst.rhs(), inst.rhs_scalar()
        rng = np.random.default_rng(7)
        for _ in range(50):
            y = rng.normal(size=7)
            assert np.array_equal(f(0.0, y), np.array(g(0.0, *(float(v) for v in y))))
