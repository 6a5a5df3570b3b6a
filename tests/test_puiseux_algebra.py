"""Puiseux's algebra for the general body (sec. III): the normal frame (eqs. 17-18), the modes as the
roots of his equation for omega, the lambda algebra and the vertical component of gravity along the
normal (sec. II). Split from tests/test_puiseux_general.py (the simulation side stays there).

Source: V. Puiseux, J. math. pures appl. (1) 17 (1852) 1-30, sec. II-III (read in a transcription of
the printed text); gyro_instrument/instruments/puiseux/general.py derives the
first-order theory in vector form.
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



# ------------------------------------------------------------------ Puiseux's algebra
def test_normal_frame_is_eq_17_and_obeys_eq_18():
    # eq. (17) gives a rotation; relations (18) (e.g. b1'c1'' - c1'b1'' = a1) are its cofactors.
    # Rounding only: 1e-15.
    for angles in ((20.0, 35.0, 50.0), (-130.0, 100.0, 75.0), (0.0, 0.0, 0.0)):
        P = normal_frame(*np.radians(angles))
        (a1, b1, c1), (a1p, b1p, c1p), (a1pp, b1pp, c1pp) = P
        np.testing.assert_allclose(P @ P.T, np.eye(3), atol=1e-15)
        assert np.linalg.det(P) == pytest.approx(1.0, abs=1e-15)
        for lhs, rhs in ((b1p * c1pp - c1p * b1pp, a1), (c1p * a1pp - a1p * c1pp, b1), (a1p * b1pp - b1p * a1pp, c1),
                         (c1 * b1pp - b1 * c1pp, a1p), (b1 * c1p - c1 * b1p, a1pp), (a1 * b1p - b1 * a1p, c1pp)):
            assert lhs == pytest.approx(rhs, abs=1e-15)
        # c1'' = cos θ1: GA makes the angle θ1 with Gz
        assert c1pp == pytest.approx(math.cos(math.radians(angles[1])), abs=1e-15)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.5, 2.0), st.floats(0.5, 2.0), st.floats(0.5, 2.0), st.floats(-180.0, 180.0),
       st.floats(0.0, 180.0), st.floats(-180.0, 180.0), st.floats(0.05, 0.9), st.floats(1.05, 3.0),
       st.floats(1.05, 3.0))
def test_modes_are_the_roots_of_puiseux_omega_equation(fa, fb, fc, phi1, theta1, psi1, gamma, kr, krp):
    # Sec. III, after eq. (25): AB ω² − [BC(ϖa1'² + ϖ'a1²) + AC(ϖb1'² + ϖ'b1²) + AB(ϖc1'² + ϖ'c1²)] ω
    # + Cϖϖ'(Aa1''² + Bb1''² + Cc1''²) = 0, with swing frequency √(Mgω/C). The generalised
    # eigenproblem of general.py is an independent route: equal to rounding (1e-9 relative).
    # Puiseux's proof that the roots are real: K = b² − 4ac = (lϖ − l'ϖ')² + 4(BCa1a1' + ACb1b1' +
    # ABc1c1')²ϖϖ' with l = BCa1'² + ACb1'² + ABc1'², l' = BCa1² + ACb1² + ABc1², m = ABC(Aa1''² + ...)
    # and ll' − m = (BCa1a1' + ...)² (1e-9 relative to the terms). The transcription prints
    # K = (l'ϖ + lϖ')² − 4mϖϖ', with l and l' exchanged against its own ω equation (b = lϖ + l'ϖ');
    # at θ1 = φ1 = ψ1 = 0 the printed form is off by (BCϖ − ACϖ')² − (BCϖ' − ACϖ)² ≠ 0.
    A, B, C = 0.02 * fa, 0.02 * fb, 0.02 * fc
    if A + B < C or B + C < A or A + C < B:
        return
    M, rho, rhop = 1.3, gamma * kr, gamma * krp
    P = normal_frame(*np.radians([phi1, theta1, psi1]))
    w, wp = rho - gamma, rhop - gamma
    a, b, c = puiseux_omega_quadratic(A, B, C, w, wp, P)
    modes = general_modes((A, B, C), M, G, rho, rhop, gamma, P)
    for om in modes.omega_m:
        assert abs(a * om * om - b * om + c) <= 1e-9 * (a * om * om + b * om + c)
    np.testing.assert_allclose(modes.frequencies_rad_s, np.sqrt(M * G * np.array(modes.omega_m) / C), rtol=1e-12)
    (a1, b1, c1), (a1p, b1p, c1p), _ = P
    l_ = B * C * a1p ** 2 + A * C * b1p ** 2 + A * B * c1p ** 2
    lp = B * C * a1 ** 2 + A * C * b1 ** 2 + A * B * c1 ** 2
    m = A * B * C * (A * P[2, 0] ** 2 + B * P[2, 1] ** 2 + C * P[2, 2] ** 2)
    assert l_ * lp - m == pytest.approx(inertia_conjugacy(A, B, C, P) ** 2, abs=1e-9 * l_ * lp)
    assert b == pytest.approx(l_ * w + lp * wp, rel=1e-12)
    K = (l_ * w - lp * wp) ** 2 + 4 * inertia_conjugacy(A, B, C, P) ** 2 * w * wp
    assert K == pytest.approx(b * b - 4 * a * c, abs=1e-9 * b * b)
    assert min(modes.omega_m) > 0.0                        # ϖ, ϖ' > 0: both roots positive (stable)
    # the zero root's mode is the turn about GA, and the swings are I-orthogonal to it
    V = modes.rotations
    np.testing.assert_allclose(V.T @ np.diag([A, B, C]) @ V, np.eye(3), atol=1e-9)


def puiseux_P_Q_R_S(A, B, C, w, wp, phi1, theta1, psi1):
    """Puiseux's D ... I and P, Q, R, S (sec. III, after eq. 22 and before eq. 24), transcribed."""
    (a1, b1, c1), (a1p, b1p, c1p), _ = normal_frame(phi1, theta1, psi1)
    sf, cf = math.sin(phi1), math.cos(phi1)
    D, E = w * a1p * cf - wp * a1 * sf, w * a1p * sf + wp * a1 * cf
    F, G_ = w * b1p * cf - wp * b1 * sf, w * b1p * sf + wp * b1 * cf
    H, I = w * c1p * cf - wp * c1 * sf, w * c1p * sf + wp * c1 * cf
    st, ct, sp, cp = math.sin(theta1), math.cos(theta1), math.sin(psi1), math.cos(psi1)
    return (C * D * ct - A * H * sp * st, C * E * ct - A * I * sp * st,
            B * H * cp * st - C * F * ct, B * I * cp * st - C * G_ * ct)


@pytest.mark.parametrize("fa, fb, fc, phi1, theta1, psi1, kr, krp", [
    (1.0, 1.5, 1.25, 20.0, 35.0, 50.0, 1.5, 2.5),        # BODY
    (1.0, 1.5, 1.25, 0.0, 5.0, 60.0, 2.0, 3.0),
    (0.6, 1.9, 1.4, -130.0, 70.0, 110.0, 1.3, 2.8),
    (1.7, 0.9, 1.1, 75.0, 20.0, -35.0, 2.9, 1.4),
    (1.2, 1.3, 0.7, 160.0, 55.0, 15.0, 2.2, 1.25),
])
def test_puiseux_lambda_algebra_gives_the_same_roots_planes_and_perpendicularity(fa, fb, fc, phi1, theta1, psi1,
                                                                                    kr, krp):
    # Puiseux's own route, transcribed: λ', λ'' roots of his quadratic (before Λ'), ω from eq. (25)
    # (both of its forms), the planes Π', Π'' from their printed equations, and
    # Λ' = Cϖϖ'(ϖ − ϖ')cos²θ1(Aa1''² + Bb1''² + Cc1''²)(BCa1a1' + ACb1b1' + ABc1c1'), against the
    # eigenproblem of general.py, for bodies away from the singular cases of his parametrisation
    # (ψ1 = 0 or 90° with φ1 = 0, ρ = ρ', cos θ1 = 0 make λ infinite or Λ' zero). Rounding: 1e-9
    # relative (1e-7 on the planes' angles). The transcription's
    # expansion of Λ' drops the term A(R cos ψ1 cos θ1 − S sin ψ1) from the bracket multiplying
    # (PR + QS); with it, Λ' equals the factorised form, without it not (7.4× off for the BODY).
    A, B, C = 0.02 * fa, 0.02 * fb, 0.02 * fc
    if A + B < C or B + C < A or A + C < B:
        return
    gamma = 0.2
    w, wp = gamma * (kr - 1), gamma * (krp - 1)
    f1, t1, p1 = np.radians([phi1, theta1, psi1])
    P, Q, R, S = puiseux_P_Q_R_S(A, B, C, w, wp, f1, t1, p1)
    st_, ct, sp, cp = math.sin(t1), math.cos(t1), math.sin(p1), math.cos(p1)
    qa = B * R * sp * ct + B * S * cp
    qb = B * P * sp * ct + B * Q * cp + A * R * cp * ct - A * S * sp
    qc = A * P * cp * ct - A * Q * sp
    lams = np.roots([qa, qb, qc])
    PF = normal_frame(f1, t1, p1)
    modes = general_modes((A, B, C), 1.0, G, gamma * kr, gamma * krp, gamma, PF)
    om1, om2 = modes.omega_m
    if abs(om2 - om1) < 1e-2 * om2 or np.iscomplexobj(lams):
        return
    omegas = [(P + l * R) / (A * sp - l * B * cp) for l in lams]
    omegas_b = [(Q + l * S) / ((A * cp + l * B * sp) * ct) for l in lams]
    np.testing.assert_allclose(sorted(omegas), modes.omega_m, rtol=1e-9)
    np.testing.assert_allclose(omegas_b, omegas, rtol=1e-9)
    for l, om in zip(lams, omegas):
        normal = np.array([Q * cp + P * sp * ct + l * (S * cp + R * sp * ct),
                           -(Q * sp - P * cp * ct + l * (S * sp - R * cp * ct)), -(P * st_ + l * R * st_)])
        assert abs(normal @ PF[2]) < 1e-9 * np.linalg.norm(normal)          # the plane holds GA
        trace = (math.atan2(normal @ PF[1], normal @ PF[0]) + 0.5 * math.pi) % math.pi
        k = int(np.argmin(np.abs(np.array(modes.omega_m) - om)))               # Π' goes with ω'
        d = (trace - modes.plane_angles_rad[k] + 0.5 * math.pi) % math.pi - 0.5 * math.pi
        assert abs(d) < 1e-7
    Lam = P * P + Q * Q + (P * R + Q * S) * lams.sum() + (R * R + S * S) * lams.prod()
    (_, _, _), (_, _, _), (a1pp, b1pp, c1pp) = PF
    factorised = (C * w * wp * (w - wp) * ct ** 2 * (A * a1pp ** 2 + B * b1pp ** 2 + C * c1pp ** 2)
                  * inertia_conjugacy(A, B, C, PF))
    scale = abs(qa) * (P * P + Q * Q + abs(P * R + Q * S) * abs(lams).sum() + (R * R + S * S) * abs(lams.prod()))
    assert abs(Lam * qa - factorised) < 1e-9 * scale


def test_gz_along_the_normal_is_section_II():
    # θ1 = 0: Gz is the normal, and the general body is sec. II's with δ = −(φ1 + ψ1) (Aξ is at
    # −(φ1 + ψ1) from Gx by eq. 17). At r = 0 the frequencies are the roots of sec. II's
    # AB ω⁴ − (AF + BE) ω² + EF − G² = 0: rounding (1e-12).
    I, M, rho, rhop, gamma = (0.02, 0.03, 0.025), 1.0, 0.3, 0.5, 0.2
    for phi1, psi1 in ((10.0, 20.0), (-50.0, 5.0)):
        modes = general_modes(I, M, G, rho, rhop, gamma, normal_frame(math.radians(phi1), 0.0, math.radians(psi1)))
        v = classify_stability_curvature(*I, M, G, 0.0, rho, rhop, gamma, -math.radians(phi1 + psi1))
        np.testing.assert_allclose(modes.frequencies_rad_s, v.frequencies_rad_s, rtol=1e-12)
    # and the simulated motions coincide: the general body turned by δ about the vertical is the
    # curvature body tilted toward the azimuth turned by δ (compass, clockwise). Both integrate the
    # same exact equations with different arithmetic: 1e-8 of the amplitude (rtol 1e-10).
    delta = 25.0
    t = np.linspace(0.0, 3.0, 601)
    gen = make(shape="general", inertia_kg_m2=list(I), curvature_radii_m=[rho, rhop], com_height_m=gamma,
               axes_phi1_deg=-delta, axes_theta1_deg=0.0, axes_psi1_deg=0.0, initial_tilt_deg=0.06,
               initial_tilt_azimuth_deg=40.0, spin_rate_rad_s=0.3, rtol=1e-10).simulate(t)
    cur = make(shape="curvature", inertia_kg_m2=list(I), curvature_radii_m=[rho, rhop], com_height_m=gamma,
               curvature_angle_deg=delta, initial_tilt_deg=0.06, initial_tilt_azimuth_deg=40.0 - delta,
               spin_rate_rad_s=0.3, rtol=1e-10).simulate(t)
    amp = math.radians(0.06)
    for col in ("tilt", "vertical_body_x", "vertical_body_y", "turn_angle"):
        assert np.max(np.abs(gen.columns[col] - cur.columns[col])) < 1e-8 * amp, col
    for col in ("contact_x", "contact_y", "contact_z"):
        assert np.max(np.abs(gen.columns[col] - cur.columns[col])) < 1e-8 * amp * rhop, col
