"""Puiseux's general body (sec. III) and the contact-point path (sec. I and III).

Source: V. Puiseux, J. math. pures appl. (1) 17 (1852) 1-30, sec. III (pp. 22-30) and the end of
sec. I (the contact point, "stations et rétrogradations"), read in a transcription of the printed
text. The module docstring of gyro_instrument/instruments/puiseux/general.py derives the first-order
theory in vector form; here it is held to Puiseux's printed equations and to the exact simulation.

Small-amplitude tolerances. The simulation is the exact nonlinear body (DOP853, rtol 1e-10). At
tilt amplitude θ0 the first-order theory errs by O(θ0²) in the frequencies (nonlinear frequency
shift: θ0 = 1e-3 gives ~1e-6 relative) and by O(θ0) relative in the displacements and directions
(second-order terms divided by first-order ones: ~1e-3); each bound below is a few times that,
with the measured value in the comment.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.quaternion import quat_to_matrix
from gyro_instrument.instruments.puiseux import classify_stability_curvature
from gyro_instrument.instruments.puiseux.general import (general_modes, inertia_conjugacy, normal_frame,
                                                         puiseux_omega_quadratic)
from test_puiseux import G, fit_two_frequencies, make

THETA0 = 1e-3          # rad: the small displacement of every simulated case here
# An oblique body: principal moments 0.02, 0.03, 0.025 kg m², curvature radii 0.3 m (along A-xi)
# and 0.5 m (A-eta), G at 0.2 m from A, principal axes at Puiseux's (phi1, theta1, psi1) =
# (20°, 35°, 50°) from the normal frame: GA is not a principal axis, rho != rho', and the planes
# are not perpendicular (BC a1a1' + AC b1b1' + AB c1c1' = 6.8e-5 kg² m⁴).
BODY = dict(shape="general", inertia_kg_m2=[0.02, 0.03, 0.025], mass_kg=1.0, curvature_radii_m=[0.3, 0.5],
            com_height_m=0.2, axes_phi1_deg=20.0, axes_theta1_deg=35.0, axes_psi1_deg=50.0)


def general(**over):
    spec = dict(BODY, initial_tilt_deg=math.degrees(THETA0), initial_tilt_azimuth_deg=30.0, rtol=1e-10)
    spec.update(over)
    return make(**spec)


def fit_at(t, x, freqs):
    """Least-squares fit of x(t) (time on the last axis) by a constant and cos/sin at the given
    frequencies (rad/s); returns the amplitudes (c_k, s_k) per frequency, shape (len(freqs), 2, ...)."""
    x = np.asarray(x, dtype=float)
    X = np.column_stack([np.ones_like(t)] + [f(w * t) for w in freqs for f in (np.cos, np.sin)])
    coef, *_ = np.linalg.lstsq(X, x.reshape(-1, x.shape[-1]).T, rcond=None)
    return coef[1:].reshape(len(freqs), 2, *x.shape[:-1])


def body_heights(sim, body, points):
    """Exact heights above the plane of body points (body axes from G, shape (k, 3)) along a run:
    z_G + e_z·R x, from the state and the com_height column (an independent reader)."""
    R = quat_to_matrix(sim.extra["state"][:4].T)
    return sim.columns["com_height"][:, None] + np.einsum("mj,kj->mk", R[:, 2, :], points)


@pytest.fixture(scope="module")
def oblique():
    body = general()
    t = np.linspace(0.0, 40.0, 8001)
    return body, t, body.simulate(t)


# ------------------------------------------------------------------ simulation: durations, planes
def test_both_swing_durations(oblique):
    # Sec. III: two swings of durations π√(C/(Mgω')) and π√(C/(Mgω'')). The fitted frequencies of
    # the vertical in body axes (a'', b'') over 40 s (> 40 swings of the slow mode) hold them to
    # the O(θ0²) = 1e-6 nonlinear shift (measured 2.4e-7 and 6.4e-7): bound 1e-5.
    body, t, sim = oblique
    pred = body.predictions()
    assert pred["verdict"] == "stable" and pred["section"] == "III"
    C, M = body.inertia[2], body.p.mass_kg
    durations = [math.pi * math.sqrt(C / (M * G * om)) for om in pred["puiseux_omega_m"]]
    np.testing.assert_allclose(pred["swing_durations_s"], durations, rtol=1e-14)
    freqs, _, misfit = fit_two_frequencies(t, sim.columns["vertical_body_x"], sim.columns["vertical_body_y"])
    np.testing.assert_allclose(math.pi / freqs, durations, rtol=1e-5)
    assert misfit < 1e-4       # two sinusoids explain the motion: residue O(θ0) at most; measured 5.7e-7
    # the tilt of GA stays small: Puiseux's "ce qui reste très-petit" (first-order bound, +1 %;
    # reached when the phases meet: 0.76 of it in 40 s)
    assert np.max(sim.columns["tilt"]) <= 1.01 * pred["max_tilt_rad"]


def test_vertical_projections_of_the_two_planes_swing_like_simple_pendulums(oblique):
    # Sec. III: the points of Π' rise and fall with the duration π√(C/(Mgω')) only, those of Π''
    # with π√(C/(Mgω'')) only, with amplitudes proportional to their distance from GA. Heights of
    # body points read from the exact state; at first order a point on Π' has no Ω'' component;
    # second-order terms (O(θ0) relative) sit at other frequencies (2Ω, Ω' ± Ω'') and leak into
    # the fit only by non-orthogonality over the window: bound θ0 = 1e-3, measured ≤ 3.1e-6.
    # A point on neither plane carries both (ratio > 0.1): the check is not vacuous.
    body, t, sim = oblique
    pred = body.predictions()
    xi, eta, u = body.P
    freqs = pred["frequencies_rad_s"]
    # unit directions in the body along the traces of Π', Π'' and between them
    dirs = [math.cos(a) * xi + math.sin(a) * eta for a in pred["plane_angles_rad"]]
    mid = 0.5 * (pred["plane_angles_rad"][0] + pred["plane_angles_rad"][1])
    points = np.array([0.1 * dirs[0], 0.2 * dirs[0] + 0.05 * u, 0.1 * dirs[1],
                       0.1 * (math.cos(mid) * xi + math.sin(mid) * eta)])
    Z = body_heights(sim, body, points)
    amp = np.linalg.norm(fit_at(t, Z.T, freqs), axis=1)          # (2 frequencies, 4 points)
    assert amp[1, 0] < 1e-3 * amp[0, 0] and amp[1, 1] < 1e-3 * amp[0, 1]     # Π': Ω' only
    assert amp[0, 2] < 1e-3 * amp[1, 2]                                       # Π'': Ω'' only
    assert min(amp[:, 3]) > 0.1 * max(amp[:, 3])                              # elsewhere: both
    # amplitudes proportional to the distance from GA (the second point is twice as far): O(θ0),
    # measured 1.2e-6
    assert amp[0, 1] == pytest.approx(2.0 * amp[0, 0], rel=1e-3)
    # the planes measured from the motion: the Ω'' part of the tilt vector is along e'', and Π' ⊥ e''
    eps = np.array([sim.columns["vertical_body_x"], sim.columns["vertical_body_y"],
                    np.sqrt(1.0 - sim.columns["vertical_body_x"] ** 2 - sim.columns["vertical_body_y"] ** 2)])
    coef = fit_at(t, eps, freqs)                                  # (2, 2, 3)
    measured = []
    for k in (1, 0):
        c, s = coef[k]
        e = c if np.linalg.norm(c) > np.linalg.norm(s) else s
        measured.append(math.atan2(e @ eta, e @ xi) + 0.5 * math.pi)
    for m_, p_ in zip(measured, pred["plane_angles_rad"]):
        d = (m_ - p_ + 0.5 * math.pi) % math.pi - 0.5 * math.pi
        assert abs(d) < 1e-3                                       # O(θ0) = 1e-3 rad; measured 1.6e-7
    assert pred["planes_perpendicular"] is False
    assert abs(pred["angle_between_planes_rad"] - 0.5 * math.pi) > 0.1   # 1.430 rad here


def _measured_angle_between_planes(body, duration=30.0):
    t = np.linspace(0.0, duration, int(duration * 200) + 1)
    sim = body.simulate(t)
    pred = body.predictions()
    nx, ny = sim.columns["vertical_body_x"], sim.columns["vertical_body_y"]
    n = np.array([nx, ny, np.sqrt(1.0 - nx * nx - ny * ny)])       # n_z > 0: cos θ1 > 0 here
    coef = fit_at(t, n, pred["frequencies_rad_s"])                  # n = u + ε: the swings are ε's
    dirs = []
    for k in (0, 1):
        c, s = coef[k]
        e = c if np.linalg.norm(c) > np.linalg.norm(s) else s
        dirs.append(e / np.linalg.norm(e))
    return math.acos(min(abs(dirs[0] @ dirs[1]), 1.0)), pred


def test_perpendicularity_condition():
    # Sec. III, last page: Π' ⊥ Π'' iff Λ' = 0, i.e. ρ = ρ' or BC a1a1' + AC b1b1' + AB c1c1' = 0
    # (the tilt directions e', e'' are perpendicular exactly when the planes are). Three bodies:
    # (1) equal radii, oblique axes; (2) unequal radii, φ1 solved so that Puiseux's inertia factor
    # vanishes (nothing symmetric about it); (3) the same body with φ1 moved 20° (not perpendicular).
    # Measured from the simulation: the angle between the tilt directions of the two swings
    # (first-order fit: O(θ0) = 1e-3 rad; measured 1.7e-4, 3.4e-7, 1.4e-6), bound 3e-3 rad.
    I = (0.02, 0.03, 0.025)
    theta1, psi1 = math.radians(35.0), math.radians(50.0)
    conj = lambda phi1: inertia_conjugacy(*I, normal_frame(phi1, theta1, psi1))
    phi_perp = brentq(conj, 0.0, math.pi / 2 - 1e-9) if conj(0.0) * conj(math.pi / 2 - 1e-9) < 0 else \
        brentq(conj, math.pi / 2 + 1e-9, math.pi)
    cases = [(dict(curvature_radii_m=[0.4, 0.4]), True),
             (dict(axes_phi1_deg=math.degrees(phi_perp)), True),
             (dict(axes_phi1_deg=math.degrees(phi_perp) + 20.0), False)]
    for over, perp in cases:
        body = general(initial_tilt_azimuth_deg=-70.0, **over)
        angle, pred = _measured_angle_between_planes(body)
        assert pred["planes_perpendicular"] is perp
        assert abs(angle - pred["angle_between_planes_rad"]) < 3e-3
        if perp:
            assert abs(angle - 0.5 * math.pi) < 3e-3
        else:
            assert abs(angle - 0.5 * math.pi) > 0.05
    assert abs(conj(phi_perp)) < 1e-12 * (I[0] * I[1] + I[1] * I[2] + I[0] * I[2])


# ------------------------------------------------------------------ the slow turning
def test_body_turns_about_the_vertical_without_bound():
    # Sec. III: φ = αt + β + k' sin(...) + k'' sin(...): with small initial velocities the body
    # turns about the vertical at a constant mean rate, without bound. α = L_v/(Aa1''² + Bb1''² +
    # Cc1''²), L_v = n·Iw exactly conserved. A spin of 0.02 Ω' about GA: corrections are the
    # centrifugal relative equilibrium, O((α/Ω')²) = 4e-4 relative, and the O(θ0²Ω') = 1e-5 rad/s
    # geometric drift of the swings (1e-4 of α): bound 2e-3 relative (measured 9.6e-6; the turn
    # reaches 8.0 rad in 60 s).
    body0 = general()
    r0 = 0.02 * body0.predictions()["frequencies_rad_s"][0]
    body = general(spin_rate_rad_s=r0)
    pred = body.predictions()
    alpha = pred["turning_rate_rad_s"]
    assert pred["turning_sense"] == "counter-clockwise seen from above"
    assert alpha == pytest.approx(abs(pred["angular_momentum_vertical_kg_m2_s"]) / pred["inertia_about_normal_kg_m2"],
                                  rel=1e-14)
    # a magnitude, unsigned; the sense is reported apart (issue 17 item 4)
    back = general(spin_rate_rad_s=-r0).predictions()
    assert back["turning_rate_rad_s"] == pytest.approx(alpha, rel=1e-14)      # w0 = r0 U: L_v odd in r0
    assert back["turning_sense"] == "clockwise seen from above"
    t = np.linspace(0.0, 60.0, 12001)
    sim = body.simulate(t)
    X = np.column_stack([t, np.ones_like(t)] + [f(w * t) for w in pred["frequencies_rad_s"] for f in (np.cos, np.sin)])
    slope = np.linalg.lstsq(X, sim.columns["turn_angle"], rcond=None)[0][0]
    assert slope == pytest.approx(alpha, rel=2e-3)
    assert sim.columns["turn_angle"][-1] > 2 * math.pi            # more than a whole turn: no bound
    # the spin_rate channel (u·w) averages to the same rate (measured 1.4e-5)
    assert np.mean(sim.columns["spin_rate"]) == pytest.approx(alpha, rel=2e-3)
    # An independent reader: the azimuth of the horizontal projection of the body line A-xi
    # (counter-clockwise from east), unwrapped, has the same mean rate (it differs by periodic O(θ0)).
    R = quat_to_matrix(sim.extra["state"][:4].T)
    line = R @ body.P[0]
    az = np.unwrap(np.arctan2(line[:, 1], line[:, 0]))
    assert np.linalg.lstsq(X, az, rcond=None)[0][0] == pytest.approx(alpha, rel=2e-3)
    # L_v exact invariant (1e-8 relative at rtol 1e-10)
    lv = sim.extra["angular_momentum_vertical_kg_m2_s"]
    assert np.ptp(lv) < 1e-8 * abs(lv[0])
    # Released without vertical momentum the turn stays bounded: α = 0, only the periodic terms
    # k', k'' (first order: within θ0) and the O(θ0²) drift (measured 1.5e-6 rad over 40 s from the
    # first-order turn; bound 1e-5 rad).
    t0 = t[:8001]
    turn0 = body0.simulate(t0).columns["turn_angle"]
    assert body0.predictions()["turning_rate_rad_s"] == 0.0
    assert np.max(np.abs(turn0)) < THETA0
    assert np.max(np.abs(turn0 - body0.linear_prediction(t0)["turn"])) < 1e-5


# ------------------------------------------------------------------ the contact point
def test_contact_columns_are_the_contact_point(oblique):
    # Exact, any amplitude: the contact point is on the plane, R x_P has height −h (h = the
    # com_height column); its surface normal is the downward vertical; at rest it is A = −γ u.
    # Rounding: 1e-12 m.
    body, t, sim = oblique
    c = sim.columns
    xp = np.array([c["contact_x"], c["contact_y"], c["contact_z"]])
    R = quat_to_matrix(sim.extra["state"][:4].T)
    world = np.einsum("mij,jm->im", R, xp)
    assert np.max(np.abs(world[2] + c["com_height"])) < 1e-12
    np.testing.assert_array_equal(world[0], c["contact_east"])
    np.testing.assert_array_equal(world[1], c["contact_north"])
    surf = body.surface
    normal = np.linalg.solve(surf.S, xp - surf.c[:, None])         # ∝ outward normal of the ellipsoid
    n = R[:, 2, :].T                                                # upward vertical in body axes
    cosang = np.sum(normal * n, axis=0) / np.linalg.norm(normal, axis=0)
    assert np.max(cosang + 1.0) < 1e-12
    rest = make(**dict(BODY, rtol=1e-10)).simulate(np.array([0.0, 1.0]))
    A_point = -0.2 * body.P[2]
    np.testing.assert_allclose([rest.columns[k][-1] for k in ("contact_x", "contact_y", "contact_z")], A_point,
                               atol=1e-12)


def test_contact_path_follows_the_small_oscillation_theory(oblique):
    # Sec. III eq. (21) in vector form: about A the contact point is at ξ = −ρ ε_ξ, η = −ρ' ε_η;
    # on the plane at −ϖ ε_ξ, −ϖ' ε_η from G's vertical. The whole path against the first-order
    # motion from the initial state: O(θ0) relative (measured 4.9e-4 in the body, 3.1e-4 on the
    # plane), bound 3e-3 of its extent.
    body, t, sim = oblique
    c = sim.columns
    lin = body.linear_prediction(t)
    xp = np.array([c["contact_x"], c["contact_y"], c["contact_z"]])
    extent = np.max(np.hypot(lin["contact_xi"], lin["contact_eta"]))
    assert np.max(np.abs(xp - lin["contact_body"])) < 3e-3 * extent
    plane = np.max(np.hypot(lin["contact_east"], lin["contact_north"]))
    assert np.max(np.abs(c["contact_east"] - lin["contact_east"])) < 3e-3 * plane
    assert np.max(np.abs(c["contact_north"] - lin["contact_north"])) < 3e-3 * plane
    # the predicted bound of |AH| holds (first order, +1 %)
    xi_s = (xp.T + 0.2 * body.P[2]) @ body.P[0]
    eta_s = (xp.T + 0.2 * body.P[2]) @ body.P[1]
    assert np.max(np.hypot(xi_s, eta_s)) <= 1.01 * body.predictions()["contact_path_max_distance_m"]


def _stations(t, xi, eta):
    """Times where the radius vector AH stops turning (ξη̇ − ηξ̇ changes sign), by linear
    interpolation of the areal velocity, with the slope there."""
    w = xi * np.gradient(eta, t) - eta * np.gradient(xi, t)
    i = np.nonzero(np.sign(w[1:]) != np.sign(w[:-1]))[0]
    ts = t[i] - w[i] * (t[i + 1] - t[i]) / (w[i + 1] - w[i])
    return ts, (w[i + 1] - w[i]) / (t[i + 1] - t[i]), w


def test_stations_and_retrogradations_of_the_contact_point(oblique):
    # Sec. I end: "le mouvement du point de contact, vu du sommet A par un observateur qui croirait
    # le corps immobile, offrira des stations et des rétrogradations". Here for the oblique body
    # (sec. III): the radius vector AH turns one way, stops, turns back. Station times and places
    # from the simulated path against those of the first-order path: a station moves by
    # ~θ0/Ω' ≈ 1.5e-4 s (the O(θ0) error of the areal velocity over its slope; measured 1.1e-4 s
    # over 47 stations); bound 2e-3 s, and
    # its place by O(θ0) of the path's extent, bound 1e-2. Only well-defined stations are compared
    # (slope above a tenth of the typical |areal velocity| Ω', so a graze is not counted).
    body, t, sim = oblique
    c = sim.columns
    xp = np.array([c["contact_x"], c["contact_y"], c["contact_z"]]).T + 0.2 * body.P[2]
    xi_s, eta_s = xp @ body.P[0], xp @ body.P[1]
    lin = body.linear_prediction(t)
    ts_s, _, w_s = _stations(t, xi_s, eta_s)
    ts_p, slope_p, w_p = _stations(t, lin["contact_xi"], lin["contact_eta"])
    assert np.max(w_s) > 0 > np.min(w_s)                 # both senses: retrogradations happen
    clear = np.abs(slope_p) > 0.1 * np.mean(np.abs(w_p)) * body.predictions()["frequencies_rad_s"][0]
    assert clear.sum() >= 20                               # many stations in 40 s
    extent = np.max(np.hypot(lin["contact_xi"], lin["contact_eta"]))
    for tp in ts_p[clear]:
        j = np.argmin(np.abs(ts_s - tp))
        assert abs(ts_s[j] - tp) < 2e-3
        pos_s = np.array([np.interp(ts_s[j], t, xi_s), np.interp(ts_s[j], t, eta_s)])
        pos_p = np.array([np.interp(tp, t, lin["contact_xi"]), np.interp(tp, t, lin["contact_eta"])])
        assert np.linalg.norm(pos_s - pos_p) < 1e-2 * extent


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("over, field, text", [
    (dict(com_height_m=0.3), "com_height_m", "must be < 0.3 m"),          # γ = ρ: marginal
    (dict(com_height_m=0.45), "com_height_m", "centre of mass below both centres of curvature"),
    (dict(axes_theta1_deg=None), "axes_theta1_deg", "required when shape = general"),
    (dict(axes_theta1_deg=190.0), "axes_theta1_deg", "[0, 180]"),
    (dict(curvature_angle_deg=10.0), "curvature_angle_deg", "applies only to shape = curvature"),
    (dict(semi_axes_m=[0.1, 0.1, 0.2]), "semi_axes_m", "applies only to shape = ellipsoid"),
    (dict(inertia_kg_m2=[0.01, 0.01, 0.03]), "inertia_kg_m2", "triangle"),
    (dict(inertia_kg_m2=None), "inertia_kg_m2", "required when shape = general"),
])
def test_bad_general_bodies_are_refused_by_name(over, field, text):
    spec = dict(BODY)
    spec.update(over)
    spec = {k: v for k, v in spec.items() if v is not None}
    with pytest.raises(SceneError) as err:
        make(**spec)
    assert err.value.field == f"instruments.body.{field}"
    assert text in str(err.value)


def test_general_angles_apply_only_to_the_general_body():
    with pytest.raises(SceneError) as err:
        make(shape="curvature", curvature_radii_m=[0.3, 0.5], com_height_m=0.2, inertia_kg_m2=[0.02, 0.03, 0.025],
             axes_theta1_deg=10.0)
    assert err.value.field == "instruments.body.axes_theta1_deg" and "only to shape = general" in str(err.value)


# ------------------------------------------------------------------ sec. I: the ellipsoid's contact point
def section_I_path(body, t):
    """Puiseux sec. I, eqs. (15)-(16) and the four equations for h', h'', ε', ε'' from the initial
    a'', b'', p, q (after eq. 16), then the contact point x = −(α²/γ) a'', y = −(β²/γ) b''."""
    A, B, _ = body.inertia
    D, E, F, _ = body.coefficients()
    P3 = A * F + B * E + D * D
    disc = math.sqrt(P3 * P3 - 4 * A * B * E * F)
    om = [math.sqrt((P3 - disc) / (2 * A * B)), math.sqrt((P3 + disc) / (2 * A * B))]
    lam = [D * w / (A * w * w - E) for w in om]                    # λ = k/h
    y0 = body.initial_state()
    a0, b0, _ = body.diagnostics(y0[:, None])["n"][:, 0]
    p0, q0, r = y0[4:]
    # unknowns h' sin ε', h' cos ε', h'' sin ε'', h'' cos ε''
    M = np.array([[1, 0, 1, 0], [0, lam[0], 0, lam[1]], [0, om[0], 0, om[1]],
                  [om[0] * lam[0], 0, om[1] * lam[1], 0]])
    X1, Y1, X2, Y2 = np.linalg.solve(M, [a0, b0, r * b0 - q0, r * a0 - p0])
    a = X1 * np.cos(om[0] * t) + Y1 * np.sin(om[0] * t) + X2 * np.cos(om[1] * t) + Y2 * np.sin(om[1] * t)
    b = (lam[0] * (Y1 * np.cos(om[0] * t) - X1 * np.sin(om[0] * t))
         + lam[1] * (Y2 * np.cos(om[1] * t) - X2 * np.sin(om[1] * t)))
    alpha, beta, gamma = body.p.semi_axes_m
    return -alpha * alpha / gamma * a, -beta * beta / gamma * b


@pytest.mark.parametrize("spin, retrograde", [(5.0, True), (12.0, False)])
def test_ellipsoid_contact_point_stations_and_retrogradations(spin, retrograde):
    # Sec. I end: x = −(α²/γ)[h' sin(ω't + ε') + h'' sin(ω''t + ε'')], y = −(β²/γ)[λ'h' cos(...) + ...];
    # "le rayon vecteur AH pourra donc ne pas tourner toujours dans le même sens": stations and
    # retrogradations as in the planets' motion. The oblate homogeneous ellipsoid (0.12, 0.10,
    # 0.05 m) on its short axis, released from θ0 = 1e-3 rad: at 5 rad/s the radius vector stops
    # and turns back (11 stations in 10 s by the formulas), at 12 rad/s it never does (its areal
    # velocity stays between −8.4e-7 and −4.0e-8 m²/s: 5 % margin, far above the O(θ0) error).
    # Path against the formulas: O(θ0) relative (measured 7.6e-4 / 9.3e-4), bound 5e-3 of its
    # extent; station times: ~θ0/ω' = 4e-5 s (measured 7.3e-5 s), bound 1e-3 s.
    body = make(semi_axes_m=[0.12, 0.10, 0.05], mass_kg=1.0, spin_rate_rad_s=spin,
                initial_tilt_deg=math.degrees(THETA0), initial_tilt_azimuth_deg=30.0, rtol=1e-10)
    t = np.linspace(0.0, 10.0, 4001)
    sim = body.simulate(t)
    x, y = sim.columns["contact_x"], sim.columns["contact_y"]
    xp, yp = section_I_path(body, t)
    extent = np.max(np.hypot(xp, yp))
    assert np.max(np.hypot(x - xp, y - yp)) < 5e-3 * extent
    ts_s, _, w_s = _stations(t, x, y)
    ts_p, slope_p, w_p = _stations(t, xp, yp)
    assert bool(np.max(w_s) > 0 > np.min(w_s)) is retrograde
    assert bool(np.max(w_p) > 0 > np.min(w_p)) is retrograde
    if retrograde:
        assert len(ts_p) >= 10 and len(ts_s) == len(ts_p)
        np.testing.assert_allclose(ts_s, ts_p, atol=1e-3)
    # turn_angle: Puiseux sec. I, φ = rt − ψ + const, so the twist about the vertical φ + ψ is rt to
    # first order; the rest is second order in the tilt, at most θ0² r t (measured 1.6e-5 and
    # 2.7e-5 rad after 50 and 120 rad of turn).
    assert np.max(np.abs(sim.columns["turn_angle"] - spin * t)) < THETA0 ** 2 * spin * t[-1]
    # exact: the contact point is on the ellipsoid, below G by the com_height column (1e-12 m)
    a, b, c = body.p.semi_axes_m
    z = sim.columns["contact_z"]
    assert np.max(np.abs(x * x / a ** 2 + y * y / b ** 2 + z * z / c ** 2 - 1.0)) < 1e-12
    R = quat_to_matrix(sim.extra["state"][:4].T)
    assert np.max(np.abs(np.einsum("mj,jm->m", R[:, 2, :], np.array([x, y, z])) + sim.columns["com_height"])) < 1e-12


# ------------------------------------------------------------------ the other channels of the general body
def test_axis_azimuth_and_spin_channels_follow_the_first_order_motion(oblique):
    # tilt_azimuth: compass azimuth of the line GA; at first order GA is along e_z + Φ × e_z in ENU,
    # Φ = P φ the rotation vector in the rest frame (= ENU). The horizontal projection
    # tilt·(sin az, cos az) against (Φ_y, −Φ_x): O(θ0) relative (measured 3.2e-4), bound 3e-3 of θ0.
    # spin_rate (the rate about GA, u·w) against the first-order d(u·φ)/dt: they differ by
    # ½ u·(φ × φ̇) and the second-order motion, O(θ0² Ω'') ≈ 1e-5 rad/s (measured 6.9e-6): bound
    # 3 θ0² Ω''. (Its mean, the turning rate, is held to 2e-3 in the slow-turning test.)
    body, t, sim = oblique
    c = sim.columns
    lin = body.linear_prediction(t)
    Phi = body.P @ lin["phi"]
    horiz = c["tilt"] * np.array([np.sin(c["tilt_azimuth"]), np.cos(c["tilt_azimuth"])])
    assert np.max(np.hypot(horiz[0] - Phi[1], horiz[1] + Phi[0])) < 3e-3 * THETA0
    rate = np.gradient(lin["turn"], t)          # central differences: (Ω dt)²/6 ~ 4e-4 of the rate
    bound = 3 * THETA0 ** 2 * body.predictions()["frequencies_rad_s"][1]
    assert np.max(np.abs(c["spin_rate"] - rate)[2:-2]) < bound


def test_shipped_scene_holds_what_its_comment_says():
    # gyro_instrument/scenes/puiseux_general.yaml prints 0.472 s, 0.303 s, 0.126 rad/s
    # counter-clockwise, planes not perpendicular: the 3 printed digits (the scene's site gravity).
    from gyro_instrument.scenes import build_instruments, load_scene
    (body,) = build_instruments(load_scene("puiseux_general")).values()
    p = body.predictions()
    assert [round(d, 3) for d in p["swing_durations_s"]] == [0.472, 0.303]
    assert round(p["turning_rate_rad_s"], 3) == 0.126 and p["turning_sense"] == "counter-clockwise seen from above"
    assert p["planes_perpendicular"] is False and p["verdict"] == "stable"
    assert p["max_tilt_rad"] < 0.01 and "notes" not in p        # a small motion: Puiseux's hypotheses


def test_double_root_leaves_the_planes_undefined():
    # Equal moments and equal radii (a weighted ball): Puiseux's ω equation has a double root,
    # Mg ω/C = Mg(ρ − γ)/A for both swings (K = 0: l = l', ϖ = ϖ', BC a1a1' + ... = A²ξ̂·η̂ = 0),
    # so every plane through GA swings alike; the body is valid (not refused) and describe says so.
    body = make(shape="general", inertia_kg_m2=[0.02, 0.02, 0.02], curvature_radii_m=[0.4, 0.4], com_height_m=0.1,
                axes_phi1_deg=10.0, axes_theta1_deg=30.0, axes_psi1_deg=5.0, initial_tilt_deg=0.05)
    p = body.predictions()
    np.testing.assert_allclose(p["frequencies_rad_s"], [math.sqrt(1.0 * G * 0.3 / 0.02)] * 2, rtol=1e-12)
    assert p["plane_angles_rad"] is None and p["angle_between_planes_rad"] is None
    assert p["planes_perpendicular"] is True                       # Puiseux's factors: ρ = ρ'
    assert any("double root" in n for n in p["notes"])


def test_magnitudes_are_unsigned_with_the_sense_apart():
    # Issue 17 item 4 for Puiseux's body: magnitudes (critical spin, frequencies, periods, swing
    # durations, turning rate, tilt and path bounds) are reported unsigned whatever the sense of the
    # spin; the sense is its own entry (turning_sense) or the signed parameter echo spin_rate_rad_s.
    for r in (-80.0, 80.0):
        p = make(semi_axes_m=[0.10, 0.11, 0.20], spin_rate_rad_s=r, initial_tilt_deg=0.01).predictions()
        assert p["critical_spin_rad_s"] > 0 and p["critical_spin_closed_form_rad_s"] > 0
        assert min(p["frequencies_rad_s"]) > 0 and min(p["periods_s"]) > 0
        assert p["spin_rate_rad_s"] == r
    for r in (-0.1, 0.1):
        p = general(spin_rate_rad_s=r).predictions()
        for key in ("swing_durations_s", "periods_s", "frequencies_rad_s", "puiseux_omega_m"):
            assert min(p[key]) > 0, key
        for key in ("turning_rate_rad_s", "max_tilt_rad", "contact_path_max_distance_m", "angle_between_planes_rad"):
            assert p[key] > 0, key
        assert p["turning_sense"] == ("clockwise seen from above" if r < 0 else "counter-clockwise seen from above")
