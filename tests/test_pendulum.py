"""Foucault and compound pendulums against Quet 1853 sec. 2 and sec. 3 §VI.

References: eq. (42) and its exact elliptic form (the test uses the elliptic integral, not the
series, which is 59 % off at 179°); §II minimum deflection β = √(l/g) k sin θ0 cos(θ0/2); §III apsides'
rate k(1 − (3/8) θ0 sin θ0 cos(θ0/2)); Binet's turning ellipse for the linear model; eq. (57)
equivalent length λ = A/(Ml).
"""

import math

import numpy as np
import pytest
from scipy.special import ellipk

from gyro_instrument.core.site import Site
from gyro_instrument.estimators.crossings import local_maxima
from gyro_instrument.instruments.pendulum import (CompoundPendulum, SphericalPendulum, binet_ellipse,
                                                  quarter_period_s, quarter_period_series_s)

FULL = ("earth_rotation", "finite_amplitude")
PARIS = Site.from_degrees(48.8462)   # the Panthéon


def apsides(sim):
    """Times, azimuths (compass, folded modulo π onto a continuous line) and deflections at
    the maxima of the horizontal distance."""
    x, y = sim.columns["x_east"], sim.columns["y_north"]
    t = sim.t
    ta, rh2 = local_maxima(t, x * x + y * y)
    az = np.arctan2(np.interp(ta, t, x), np.interp(ta, t, y))
    az = np.unwrap(2.0 * az) / 2.0
    return ta, az, np.sqrt(rh2)


def test_apsides_turn_at_quet_rate_from_rest(build):
    # §III: released from rest at θ0 the apsides turn at k(1 − (3/8) θ0 sin θ0 cos(θ0/2)).
    # 67 m, θ0 = 2°, one hour, released east-west (the k' = n cos γ residual, ~2e-5 relative
    # for a north-south swing, is ~0 east-west: this project's estimate
    # of eq. (22)'s k' terms). Tolerance: 2 % of the correction term (4.6e-4 k), as the issue asks.
    p = build(SphericalPendulum, PARIS, FULL, length_m=67.0, initial_deflection_deg=2.0, initial_azimuth_deg=90.0,
              rtol=1e-12)
    t = np.arange(0.0, 3600.0, 0.02)
    ta, az, _ = apsides(p.simulate(t))
    slope = np.polyfit(ta, az, 1)[0]
    k = PARIS.k_vertical_rad_s
    th0 = math.radians(2.0)
    correction = 0.375 * th0 * math.sin(th0) * math.cos(th0 / 2)
    measured_correction = 1.0 - slope / k
    assert measured_correction == pytest.approx(correction, rel=0.02)


def test_precession_sense_and_rate_foucault(build):
    # Sec. 2: the plane turns with the Sun's apparent motion (compass azimuth increasing in the
    # north, decreasing in the south) at k = n sin γ: 11.326 °/h at Paris (computed from the sidereal n).
    assert math.degrees(PARIS.k_vertical_rad_s) * 3600 == pytest.approx(11.326, abs=1e-3)
    t = np.arange(0.0, 900.0, 0.05)
    for lat, sign in ((48.85, 1.0), (-33.9, -1.0)):
        p = build(SphericalPendulum, Site.from_degrees(lat), FULL, length_m=67.0, initial_deflection_deg=0.5)
        ta, az, _ = apsides(p.simulate(t))
        assert np.sign(np.polyfit(ta, az, 1)[0]) == sign


def test_minimum_deflection_from_rest_section2(build):
    # §II: β = √(l/g) k sin θ0 cos(θ0/2) (the printed 0.028 mm uses √(g/l) for √(l/g):
    # computed here; the right value for 67 m at 2° is 0.33 mm of bob travel). Measured as the
    # minimum of the deflection over a few swings; tolerance 2 %: β carries O(θ0²) corrections
    # of relative size ~1e-3 and the sampled minimum is refined by a parabola.
    p = build(SphericalPendulum, PARIS, FULL, length_m=67.0, initial_deflection_deg=2.0, rtol=1e-12)
    t = np.arange(0.0, 60.0, 0.01)
    s = p.simulate(t)
    pos, vel = s.extra["position_enu"], s.extra["velocity_enu"]
    # Near the bottom the path is straight to 1e-10 m over a sample (curvature radius a²/b ≈
    # 1.6e4 m), so the miss distance |r_h × v_h| / |v_h| at the sample nearest each passage is
    # the minimum horizontal distance; divided by l it is the minimum deflection.
    rh = np.hypot(pos[0], pos[1])
    near = np.nonzero((rh[1:-1] < rh[:-2]) & (rh[1:-1] <= rh[2:]))[0] + 1
    miss = np.abs(pos[0, near] * vel[1, near] - pos[1, near] * vel[0, near]) / np.hypot(vel[0, near], vel[1, near])
    beta = np.median(miss) / 67.0
    assert beta == pytest.approx(p.predictions()["min_deflection_from_rest_rad"], rel=0.02)


@pytest.mark.parametrize("lat, az_deg, amp_deg, length_m", [
    (48.8462, 0.0, 2.0, 67.0),      # the Pantheon's pendulum released toward north: β 2.1 % too large
    (-33.87, 0.0, 2.0, 67.0),       # the southern site: β 3.4 % too small
    (-33.87, 135.0, 5.0, 10.0),     # a release with both components, larger amplitude
])
def test_minimum_deflection_with_the_horizontal_earth_rate(build, lat, az_deg, amp_deg, length_m):
    # Issue 17 item 5, what sec. 2 §II could not include: its β keeps only the vertical Earth rate.
    # The horizontal rate n cos γ acts on the bob's vertical velocity and changes the area integral
    # (27) by −n cos γ l² cos ψ0 (θ0 − sin θ0 cos θ0) per descent (min_deflection_with_horizontal_rate_rad),
    # so a release with a north–south component passes the vertical at a different distance. The
    # prediction states the value and Quet's relative error for the configuration; the simulation
    # must reproduce both. The minimum is sampled every 1e-6 s around the first three passages
    # (the deflection there is √(β² + (θ0 ω0 t)²): sampling error < 1e-9 β). Tolerance 2e-5 of β:
    # the derivation is first order in β/θ0 (1e-4) and n/ω0 (2e-4) for the path (their product
    # with the 2–6 % effect is ~1e-5); measured ~1e-6. Quet's β would fail it by the 2–6 % stated.
    from gyro_instrument.instruments.pendulum import min_deflection_from_rest_rad
    site = Site.from_degrees(lat)
    p = build(SphericalPendulum, site, FULL, length_m=length_m, initial_deflection_deg=amp_deg,
              initial_azimuth_deg=az_deg, rtol=1e-12)
    pred = p.predictions()
    th0 = math.radians(amp_deg)
    beta_quet = abs(min_deflection_from_rest_rad(length_m, site.gravity_m_s2, site.k_vertical_rad_s, th0))
    assert pred["min_deflection_from_rest_rad"] == pytest.approx(beta_quet, rel=1e-15)
    exact = pred["min_deflection_from_rest_exact_rad"]
    Tq = pred["quarter_period_s"]
    windows = [np.linspace(j * Tq - 0.01, j * Tq + 0.01, 20001) for j in (1, 3, 5)]
    dfl = p.simulate(np.concatenate([[0.0], *windows])).columns["deflection"][1:].reshape(3, -1)
    minima = dfl.min(axis=1)
    assert np.all(np.argmin(dfl, axis=1) > 0) and np.all(np.argmin(dfl, axis=1) < dfl.shape[1] - 1)
    assert np.max(np.abs(minima / exact - 1.0)) < 2e-5
    stated = pred["min_deflection_quet_relative_error"]
    assert 0.02 < abs(stated) < 0.07                                       # the 2–6 % the paper misses
    assert np.max(np.abs((beta_quet / minima - 1.0) - stated)) < 2e-5
    assert "%" in pred["beyond_the_paper"] and "sec. 2 §II" in pred["beyond_the_paper"]


def test_east_west_release_keeps_quets_beta(build):
    # Issue 17 item 5: for an east–west release cos ψ0 = 0 and the horizontal Earth rate does not
    # change β (the Pantheon's configuration): the stated relative error is 0 to round-off.
    p = build(SphericalPendulum, Site.from_degrees(-33.87), FULL, length_m=67.0, initial_deflection_deg=2.0,
              initial_azimuth_deg=90.0)
    pred = p.predictions()
    assert abs(pred["min_deflection_quet_relative_error"]) < 1e-12
    assert "equal to it" in pred["beyond_the_paper"]


@pytest.mark.parametrize("lat, sense", [(-33.87, "counterclockwise seen from above"),
                                         (48.8462, "clockwise seen from above"),
                                         (0.0, "none")])
@pytest.mark.parametrize("effects", [FULL, ("earth_rotation",)])
def test_predictions_report_magnitudes_and_the_sense_apart(build, lat, sense, effects):
    # Issue 17 item 4: `describe foucault_pantheon --set site.latitude_deg=-33.87` printed
    # min_deflection_from_rest_rad = −3.709e-06, a magnitude signed with k. β, the periods and the
    # turn time are magnitudes (≥ 0) at every site; the rates stay signed about the upward vertical
    # (positive clockwise from above: k = n sin γ, sec. 2) and precession_sense says it in words.
    site = Site.from_degrees(lat)
    p = build(SphericalPendulum, site, effects, length_m=67.0, initial_deflection_deg=2.0)
    pred = p.predictions()
    k = site.k_vertical_rad_s
    assert pred["precession_sense"] == sense
    assert pred["foucault_rate_rad_s"] == k and pred["apsidal_rate_from_rest_rad_s"] * k >= 0.0
    beta_abs = math.sqrt(67.0 / site.gravity_m_s2) * abs(k) * math.sin(math.radians(2.0)) * math.cos(math.radians(1.0))
    assert pred["min_deflection_from_rest_rad"] >= 0.0
    assert pred["min_deflection_from_rest_rad"] == pytest.approx(beta_abs, rel=1e-5 if effects == FULL else 2e-3,
                                                                abs=1e-300)   # linear model: asin(sin θ0 |k|/Ω)
    assert pred["full_turn_h"] > 0.0 and pred["quarter_period_s"] > 0.0
    cp = build(CompoundPendulum, site, effects)
    assert cp.predictions()["precession_sense"] == sense


def test_describe_at_a_southern_site_prints_beta_unsigned(capsys):
    # Issue 17 item 4, the reported command: β positive, the sense in words.
    import json
    from gyro_instrument.cli import main
    assert main(["describe", "foucault_pantheon", "--set", "site.latitude_deg=-33.87", "--json"]) == 0
    pred = json.loads(capsys.readouterr().out)["instruments"]["pendulum"]["predictions"]
    assert pred["min_deflection_from_rest_rad"] == pytest.approx(3.7085847769e-06, rel=1e-9)  # |−3.709e-06|
    assert pred["precession_sense"] == "counterclockwise seen from above"
    assert pred["foucault_rate_rad_s"] < 0.0


@pytest.mark.parametrize("amp_deg", [1.0, 30.0, 90.0, 150.0, 170.0])
def test_quarter_period_matches_elliptic_form_eq42(build, amp_deg):
    # Eq. (42), exact form: the time from maximum to minimum deflection is
    # √(l/g) K(sin²(α/2)) for a plane swing. Measured as half the interval between successive
    # apsides, with n = 0 effects off so the swing is exactly planar. Tolerance 1e-6: apsides
    # are refined by a parabola on 1e-3 s samples; the series form is checked to be far off at
    # large amplitude (59 % at 179°, computed from K(sin²(α/2))).
    site = Site.from_degrees(48.85)
    l = 10.0
    p = build(SphericalPendulum, site, ("finite_amplitude",), length_m=l, initial_deflection_deg=amp_deg, rtol=1e-12)
    Tq = quarter_period_s(l, site.gravity_m_s2, math.radians(amp_deg))
    assert Tq == pytest.approx(math.sqrt(l / site.gravity_m_s2) * ellipk(math.sin(math.radians(amp_deg) / 2) ** 2),
                               rel=1e-12)
    t = np.arange(0.0, 8.5 * Tq, 1e-3)
    s = p.simulate(t)
    ta, _ = local_maxima(t, -s.columns["z_up"])
    interval = np.polyfit(np.arange(ta.size), ta, 1)[0]    # apsides every half period = 2 Tq
    assert interval / 2.0 == pytest.approx(Tq, rel=1e-6)
    if amp_deg >= 150:
        assert abs(quarter_period_series_s(l, site.gravity_m_s2, math.radians(amp_deg)) / Tq - 1) > 0.1


def test_spherical_quarter_period_with_minor_axis(build):
    # Exact spherical form (α, β ≠ 0): launch from 40° with a transverse speed, measure the
    # time between a maximum and the next minimum of the deflection. Tolerance 1e-5 (the
    # extrema are located by a parabola on 1e-3 s samples).
    site = Site.from_degrees(0.0)
    p = build(SphericalPendulum, site, ("finite_amplitude",), length_m=2.0, initial_deflection_deg=40.0,
              transverse_speed_m_s=1.0, rtol=1e-12)
    t = np.arange(0.0, 20.0, 1e-3)
    d = p.simulate(t).columns["deflection"]
    tmax, dmax = local_maxima(t, d)
    tmin, dmin = local_maxima(t, -d)
    alpha, beta = dmax.mean(), -dmin.mean()
    Tq = quarter_period_s(2.0, site.gravity_m_s2, alpha, beta)
    assert np.mean(np.diff(tmax)) / 2 == pytest.approx(Tq, rel=1e-5)


def test_linear_model_is_binet_turning_ellipse(build):
    # Without finite_amplitude and centrifugal, and with the horizontal Earth-rate component
    # acting only on vertical velocity (zero in the linear model), the motion is exactly Binet's
    # ellipse turning at −k (closed form in binet_ellipse). Tolerance 1e-9 of the amplitude.
    p = build(SphericalPendulum, PARIS, ("earth_rotation",), length_m=67.0, initial_deflection_deg=1.0,
              transverse_speed_m_s=0.01, rtol=1e-12)
    t = np.linspace(0.0, 1200.0, 2001)
    s = p.simulate(t)
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, 67.0, PARIS.gravity_m_s2, PARIS.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    amp = 67.0 * math.sin(math.radians(1.0))
    assert np.max(np.hypot(s.columns["x_east"] - x, s.columns["y_north"] - y)) < 1e-9 * amp * 10


def test_small_amplitude_exact_model_follows_binet(build):
    # At 1e-3 rad the full nonlinear model follows Binet's ellipse up to O(a²) effects:
    # period shift a²/16 ≈ 6e-8 over ~36 periods (phase 1.4e-5 rad) plus k' terms of order
    # n cos γ ... ; tolerance 1e-4 of the amplitude.
    p = build(SphericalPendulum, PARIS, FULL, length_m=67.0, initial_deflection_deg=math.degrees(1e-3))
    t = np.linspace(0.0, 600.0, 3001)
    s = p.simulate(t)
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, 67.0, PARIS.gravity_m_s2, PARIS.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    amp = 67.0 * 1e-3
    assert np.max(np.hypot(s.columns["x_east"] - x, s.columns["y_north"] - y)) < 1e-4 * amp


def test_invariants_constraint_and_energy(build):
    # Constraint (23) |r| = l held by the Baumgarte-stabilised tension to 1e-9 l; energy (24)
    # ½v² + g z is conserved (the Coriolis force does no work) to 1e-9 of g l over 20 minutes
    # at 60° amplitude. Regressions (e.g. a wrong tension) break these by orders of magnitude.
    p = build(SphericalPendulum, PARIS, FULL + ("centrifugal",), length_m=5.0, initial_deflection_deg=60.0,
              rtol=1e-12)
    s = p.simulate(np.linspace(0.0, 1200.0, 24001))
    pos, vel = s.extra["position_enu"], s.extra["velocity_enu"]
    assert np.max(np.abs(np.linalg.norm(pos, axis=0) - 5.0)) < 1e-9 * 5.0
    g = PARIS.gravity_m_s2
    # with the centrifugal gradient the conserved energy gains −½|Ω × (r − r_rest)|²
    om = PARIS.earth_rate_enu()
    dr = pos - np.array([[0.0], [0.0], [-5.0]])
    cf = 0.5 * np.sum(np.cross(om, dr.T) ** 2, axis=1)
    E = 0.5 * np.sum(vel ** 2, axis=0) + g * pos[2] - cf
    assert np.ptp(E) < 1e-9 * g * 5.0


def test_near_inverted_launch_is_regular(build):
    # Any amplitude up to near-inverted. Without Earth rotation a 179.9° release returns to
    # 179.9° after one period 4 Tq, Tq = √(l/g) K(sin²(89.95°)) (tolerance 1e-5 degree: the
    # apex is flat, so a timing error δt shows as ½ (g/l) sin(0.1°) δt²). With Earth rotation
    # the path near the unstable top is very sensitive, so there only the constraint (23) and
    # the energy (24) are asserted (Coriolis does no work): both to 1e-8.
    Tq = quarter_period_s(1.0, PARIS.gravity_m_s2, math.radians(179.9))
    t = np.linspace(0.0, 4 * Tq, 40001)
    p = build(SphericalPendulum, PARIS, ("finite_amplitude",), length_m=1.0, initial_deflection_deg=179.9,
              rtol=1e-13)
    s = p.simulate(t)
    assert math.degrees(s.columns["deflection"][-1]) == pytest.approx(179.9, abs=1e-5)
    p = build(SphericalPendulum, PARIS, FULL, length_m=1.0, initial_deflection_deg=179.9, rtol=1e-12)
    s = p.simulate(t)
    pos, vel = s.extra["position_enu"], s.extra["velocity_enu"]
    assert np.max(np.abs(np.linalg.norm(pos, axis=0) - 1.0)) < 1e-8
    E = 0.5 * np.sum(vel ** 2, axis=0) + PARIS.gravity_m_s2 * pos[2]
    assert np.ptp(E) < 1e-8 * PARIS.gravity_m_s2


def test_compound_pendulum_equivalent_length_eq57(build):
    # Eq. (57): with μ = C/A small and ρ0 = 0 the compound pendulum is a simple pendulum of
    # length λ = A/(Ml). Quarter periods agree to 1e-6 (the O(μ) and O(n) couplings are ~1e-5
    # of the precession, not of the period); the swing plane turns at k within 2 %.
    A, M, lc = 30.0, 10.0, 1.5      # λ = 2 m
    site = Site.from_degrees(48.85)
    cp = build(CompoundPendulum, site, ("earth_rotation",), transverse_inertia_kg_m2=A, mass_kg=M,
               com_distance_m=lc, axial_inertia_kg_m2=1e-3, initial_deflection_deg=5.0, rtol=1e-12)
    lam = cp.predictions()["equivalent_length_m"]
    assert lam == pytest.approx(2.0)
    Tq = quarter_period_s(lam, site.gravity_m_s2, math.radians(5.0))
    t = np.arange(0.0, 40 * Tq, 2e-3)
    s = cp.simulate(t)
    ta, _ = local_maxima(t, -s.columns["z_up"])
    assert np.polyfit(np.arange(ta.size), ta, 1)[0] / 2 == pytest.approx(Tq, rel=1e-6)


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_parareal_fast_path_is_the_full_model(build, monkeypatch, compiled):
    # The fast path (integrator: parareal) integrates every swing: compiled, one after the other
    # (the sequential fine solution), or on numpy (GYRO_INSTRUMENT_JIT=0) all at once from
    # Newton-converged swing starts; it drops no term, so over 2 h of the Pantheon pendulum (440
    # swings, the full model with the centrifugal gradient) it must agree with the adaptive DOP853
    # at rtol 1e-12: swing azimuth at the end within 1e-9 rad (the adaptive run's own error is
    # ~1e-11) and positions within 1e-9 l everywhere. The dense output (quintic Hermite between RK8
    # grid points) must keep the constraint (23) to 1e-9 l and the energy (24) to 1e-9 g l.
    from gyro_instrument.core import jit
    monkeypatch.setattr(SphericalPendulum, "COMPILED_MIN_SWINGS", 1)     # compiled from the first swing
    if not compiled:
        monkeypatch.setattr(jit, "enabled", lambda: False)
    effects = FULL + ("centrifugal",)
    t = np.arange(0.0, 7200.0 + 1e-9, 0.05)
    fast = build(SphericalPendulum, PARIS, effects, length_m=67.0, initial_deflection_deg=2.0,
                 integrator="parareal").simulate(t)
    ref = build(SphericalPendulum, PARIS, effects, length_m=67.0, initial_deflection_deg=2.0,
                rtol=1e-12, integrator="adaptive").simulate(t)
    info = fast.extra["parareal"]
    assert fast.extra["segments"] >= 438
    assert ("compiled, serial" in fast.trajectory.method) == compiled
    if not compiled:
        # Newton: each update is about the square of the previous (quadratic convergence)
        ch = info["changes"]
        assert ch[-1] <= 1e-9 and all(b < 10 * a * a + 1e-12 for a, b in zip(ch, ch[1:]))
    dpos = np.max(np.abs(fast.extra["position_enu"] - ref.extra["position_enu"]))
    assert dpos < 1e-9 * 67.0
    assert abs(fast.columns["swing_azimuth"][-1] - ref.columns["swing_azimuth"][-1]) < 1e-9
    pos, vel = fast.extra["position_enu"], fast.extra["velocity_enu"]
    assert np.max(np.abs(np.linalg.norm(pos, axis=0) - 67.0)) < 1e-9 * 67.0
    g = PARIS.gravity_m_s2
    om = PARIS.earth_rate_enu()
    dr = pos - np.array([[0.0], [0.0], [-67.0]])
    E = 0.5 * np.sum(vel ** 2, axis=0) + g * pos[2] - 0.5 * np.sum(np.cross(om, dr.T) ** 2, axis=1)
    assert np.ptp(E) < 1e-9 * g * 67.0


def test_parareal_needs_the_full_conservative_model():
    # The fast path's period and first guess come from a release from rest of the full model:
    # other set-ups are refused at load time with the field, value and reason.
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.scenes import load_scene
    with pytest.raises(SceneError, match="instruments.pendulum.integrator.*finite_amplitude"):
        load_scene("foucault_pantheon", ["effects={earth_rotation: {}}", "instruments.pendulum.integrator=parareal"])
    with pytest.raises(SceneError, match="release from rest"):
        load_scene("foucault_pantheon", ["instruments.pendulum.integrator=parareal",
                                         "instruments.pendulum.transverse_speed_m_s=0.01"])
