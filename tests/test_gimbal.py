"""Two-ring gimbal gyroscope (Quet 1853, sec. 4 §III–V) against the paper.

Site: Paris, γ = 48.85° (Quet's k = 1/18212 s⁻¹, sec. 2 §II, implies 48.847°; tests/test_site.py), sidereal
n. Rotor A = 1e-3 kg m², μ = 2, ρ0 = 2π·100 rad/s (unless stated); rings A1 = 2.5e-4,
A2 = 5e-4 kg m² (thin: C1 = 2A1, C2 = 2A2). Every "T" is ONE SWING, half the period
(π/√K; sec. 4 §IV "durée des oscillations", as sec. 4 §1 eq. (9); docs/physics.md, Sources).

Periods are measured by a least-squares sine fit over six swings of a 0.01° oscillation:
the fit itself is exact for a sinusoid, the finite-amplitude lengthening a²/16 = 1.9e-9
(pendulum law, sec. 4 §1 item 6) and the integrator error (rtol 1e-11) stay below 1e-8.
"""

import math

import numpy as np
import pytest
from scipy.optimize import curve_fit

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import validate_params
from gyro_instrument.core.site import Site
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments.gimbal import GimbalGyroscope, scaled_condition
from gyro_instrument.instruments.gimbal.kernels import KERNELS, compiled_kernel
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope

SITE = Site.from_degrees(48.85)
N = SITE.earth_rate_rad_s
EXACT = ("earth_rotation", "centrifugal", "ring_inertia")


def make(effects=EXACT, cls=GimbalGyroscope, **raw):
    """Validate parameters as a scene would and build the instrument."""
    p = validate_params("instruments.g", cls.PARAMS, raw)
    if hasattr(cls, "check_params"):
        cls.check_params("instruments.g", p)
    return cls("g", SITE, p, {e: EFFECTS[e]() for e in effects})


def fitted_swing(t, y, T_guess):
    """One-swing duration π/ω of a 4-parameter least-squares sine fit a sin ωt + b cos ωt + c."""
    s = np.max(np.abs(y))
    w0 = math.pi / T_guess
    X = np.column_stack([np.sin(w0 * t), np.cos(w0 * t), np.ones_like(t)])
    a0, b0, c0 = np.linalg.lstsq(X, y / s, rcond=None)[0]

    def f(t, a, b, w, c):
        return a * np.sin(w * t) + b * np.cos(w * t) + c

    p, _ = curve_fit(f, t, y / s, p0=[a0, b0, w0, c0], xtol=1e-14, ftol=1e-14)
    return math.pi / p[2]


def measure(g, swings=6, samples_per_swing=200):
    """Simulate ``swings`` swings and return (measured T, predictions)."""
    pr = g.predictions()
    T = pr["swing_duration_small_s"]
    t = np.linspace(0.0, swings * T, swings * samples_per_swing + 1)
    sim = g.simulate(t)
    key = "inner_angle" if g.p.configuration == "outer_fixed" else "outer_angle"
    y = sim.columns[key]
    # Small oscillations are about 0 in the documented column convention.
    assert abs(np.mean(y)) < 1e-3 * np.max(np.abs(y))
    return fitted_swing(sim.t, y, T), pr


# ------------------------------------------------------------------ sec. 4 §IV periods
@pytest.mark.parametrize("label, key, params", [
    # T' (PP' vertical, rings locked): π √((A + 2A1 + A2)/(C n ρ0 cos γ)).
    ("T'", "T_prime", dict(configuration="locked", outer_axis="vertical")),
    # T''' (PP' horizontal across the meridian, sin ω = 1): π √((A + 2A1 + A2)/(C n ρ0)).
    ("T'''", "T_third", dict(configuration="locked", outer_axis="east_west")),
    # T (general PP'): north–south horizontal, sin ω = sin γ.
    ("T", "T", dict(configuration="locked", outer_axis="north_south")),
    # T'' (PP' vertical, outer ring fixed across the meridian, inner free): π √((A + A1)/(C n ρ0)).
    ("T''", "T_second", dict(configuration="outer_fixed", outer_axis="vertical")),
])
def test_quet_periods_thin_rings(label, key, params):
    """Quet sec. 4 §IV T, T', T'', T''' (thin rings, C1 = 2A1) from simulated swings.

    Tolerance 1e-5 (the acceptance bound): the exact rigid-body motion (both ``earth_rotation``
    and ``centrifugal``) differs from Quet's first-order K by the O(n/(μρ0)) ≈ 1e-7 term he
    drops. Against the exact small-oscillation constant (Routhian, with that O(n²) term) the
    bound is 2e-8: a²/16 = 1.9e-9 plus fit and integrator error (~1e-9).
    """
    swing = "initial_inner_angle_deg" if params["configuration"] == "outer_fixed" else "initial_outer_angle_deg"
    g = make(**params, **{swing: 0.01})
    T_meas, pr = measure(g)
    assert pr["applies"] == label
    assert pr[f"{key}_quet_s"] == pytest.approx(pr["swing_duration_small_s"], rel=1e-15)  # thin: the forms agree
    assert T_meas == pytest.approx(pr[f"{key}_quet_s"], rel=1e-5)
    assert T_meas == pytest.approx(pr["swing_duration_exact_s"], rel=2e-8)
    # The dropped O(n²) term is really there and of the size n/(μρ0): the measurement sees it.
    drop = pr["swing_duration_exact_s"] / pr["swing_duration_small_s"] - 1.0
    assert 1e-8 < abs(drop) < 1e-6
    assert abs(T_meas / pr["swing_duration_small_s"] - 1.0 - drop) < 0.2 * abs(drop)


def test_thick_ring_locked_inertia_is_A_plus_C1_plus_A2():
    """Thick inner ring (C1 = 3e-4 < 2A1 = 5e-4): the locked swing inertia is A + C1 + A2
    (eq. 11: u² = b sin²θ + γ at θ = 90°), not Quet's printed A + 2A1 + A2 (eq. 14).

    Printed form: J = 2.0e-3 vs true 1.8e-3 kg m², so Quet's T' is √(2.0/1.8) − 1 = +5.409 %
    too long. Measured to 1e-5 (acceptance bound) against the thick form and the stated
    discrepancy reproduced to 1e-5 absolute.
    """
    g = make(configuration="locked", outer_axis="vertical", initial_outer_angle_deg=0.01,
             inner_ring_axial_inertia_kg_m2=3.0e-4)
    T_meas, pr = measure(g)
    stated = math.sqrt((1e-3 + 2 * 2.5e-4 + 5e-4) / (1e-3 + 3e-4 + 5e-4)) - 1.0
    assert stated == pytest.approx(0.05409, abs=1e-5)
    assert pr["quet_relative_error"] == pytest.approx(stated, rel=1e-12)
    assert T_meas == pytest.approx(pr["T_prime_thick_s"], rel=1e-5)
    assert T_meas == pytest.approx(pr["swing_duration_exact_s"], rel=2e-8)
    assert pr["T_prime_quet_s"] / T_meas - 1.0 == pytest.approx(stated, abs=1e-5)


def test_thick_ring_outer_fixed_T_second_is_exact():
    """With the outer ring fixed the inertia about NN' is A + A1 for any ring: Quet's T'' is
    right for a thick ring too (same tolerances as above)."""
    g = make(configuration="outer_fixed", outer_axis="vertical", initial_inner_angle_deg=0.01,
             inner_ring_axial_inertia_kg_m2=3.0e-4)
    T_meas, pr = measure(g)
    assert pr["applies"] == "T''"
    assert T_meas == pytest.approx(pr["T_second_quet_s"], rel=1e-5)
    assert T_meas == pytest.approx(pr["swing_duration_exact_s"], rel=2e-8)


# ------------------------------------------------------------------ massless rings
def test_locked_without_ring_inertia_is_the_directing_plane_gyroscope():
    """Rings massless (``ring_inertia`` absent): the locked gimbal is the directing-plane
    gyroscope of the plane perpendicular to PP'; its swing is eq. (9) T = π/√(μ n ρ0 sin ω)
    of sec. 4 §1 (horizontal plane: sin ω = cos γ).

    Period to 1e-5 (the dropped O(n/μρ0) ≈ 1e-7 is inside), and the whole trajectory u(t)
    equal to the plane gyroscope's exact reduced model to 1e-9 rad on a 0.1 rad swing (both
    are the exact rigid-body motion; the difference is integrator error, ~1e-11).
    """
    g = make(effects=("earth_rotation", "centrifugal"), configuration="locked", outer_axis="vertical",
             initial_outer_angle_deg=0.01)
    pg = make(effects=("earth_rotation", "centrifugal", "finite_amplitude"), cls=PlaneGyroscope,
              plane="horizontal", initial_angle_deg=0.01)
    T_meas, pr = measure(g)
    T9 = pg.predictions()["swing_duration_small_s"]
    assert pr["sin_omega"] == pytest.approx(math.cos(SITE.latitude_rad), rel=1e-14)
    assert pr["swing_duration_small_s"] == pytest.approx(T9, rel=1e-14)
    assert T_meas == pytest.approx(T9, rel=1e-5)
    # Trajectory comparison at a large swing (0.1 rad, exact trigonometry on both sides).
    g = make(effects=("earth_rotation", "centrifugal"), configuration="locked", outer_axis="vertical")
    pg = make(effects=("earth_rotation", "centrifugal", "finite_amplitude"), cls=PlaneGyroscope,
              plane="horizontal")
    t = np.linspace(0.0, 3 * T9, 301)
    a, b = g.simulate(t), pg.simulate(t)
    assert np.max(np.abs(a.columns["outer_angle"] - b.columns["angle"])) < 1e-9
    assert np.max(np.abs(a.columns["spin_rate"] - b.columns["spin_rate"])) < 1e-9
    assert np.all(a.columns["inner_angle"] == 0.0)


# ------------------------------------------------------------------ invariants, free rings
def test_free_gimbal_invariants_13_and_12():
    """Free rings, large excursions (ρ0 = 2π·5 rad/s, released at 20°, −30° with 300°/s and
    200°/s so that θ, ψ sweep ~0.4 and ~1 rad in 1.5 s).

    * eq. (13) ρ − k cos θ + k' sin θ sin ψ (Quet's angles, here ψ = outer_angle + 90°,
      θ = inner_angle + 90°) is exact; the Earth-rate terms move ρ alone by ~1e-5 rad/s.
      Bound: the invariant's spread < 1e-3 of ρ's (observed 1.2e-5). Dropping or flipping
      an Earth-rate term makes the ratio ~1 or ~2.
    * eq. (12, first) a θ̇² + u²ψ̇² + Cρ² (≈ 2.04 J) is constant up to the dropped O(n²)
      centrifugal potential (≤ n²ΣI ≈ 4e-11 J); the spin energy Cρ² exchanges 1.2e-6 J with
      the swing through the Earth-rate terms. Bound: spread < 1e-3 of Cρ²'s spread (observed
      1.4e-5; the exact Jacobi integral T_rel − ½ΣΩᵀIΩ, 0.7e-5).
    * The chain's relative kinetic energy is Quet's sum of eqs. (7)–(9): 2 T_rel = (12) to 1e-13.
    """
    g = make(configuration="free", outer_axis="vertical", spin_rate_rad_s=2 * math.pi * 5,
             initial_outer_angle_deg=20.0, initial_inner_angle_deg=-30.0,
             initial_outer_rate_deg_s=300.0, initial_inner_rate_deg_s=200.0)
    t = np.linspace(0.0, 1.5, 601)
    sim = g.simulate(t)
    c = sim.columns
    assert np.ptp(c["outer_angle"]) > 0.5 and np.ptp(c["inner_angle"]) > 0.2
    inv = g.invariants(sim)
    rho_spread = np.ptp(c["spin_rate"])
    assert rho_spread > 3e-6  # the Earth-rate exchange is resolved
    assert np.ptp(inv["spin_13_rad_s"]) < 1e-3 * rho_spread
    spin_energy_spread = np.ptp(g.C * c["spin_rate"] ** 2)
    assert spin_energy_spread > 3e-7
    assert np.ptp(inv["energy_12_J"]) < 1e-3 * spin_energy_spread
    assert np.ptp(inv["jacobi_J"]) < 1e-3 * spin_energy_spread
    chain = sim.extra["chain"]
    for i in range(0, t.size, 60):
        qf = np.array([sim.extra["psi"][i], sim.extra["theta"][i], c["rotor_angle"][i]])
        qdf = np.array([c["outer_rate"][i], c["inner_rate"][i], sim.extra["rotor_joint_rate"][i]])
        assert 2 * chain.energy_relative(qf, qdf) == pytest.approx(inv["energy_12_J"][i], rel=1e-13)
    # Quet's conventions: (13) at release equals the prediction's value.
    assert inv["spin_13_rad_s"][0] == pytest.approx(g.predictions()["conserved_spin_rad_s"], rel=1e-15)


def test_polar_axis_section_V():
    """PP' along Earth's axis, rings free, released at rest at θ0 = 60° (sec. 4 §V).

    * §V eq. (2, second): u²ψ̇ + Cρ cos θ − k(b − C) sin²θ is exact here (angular momentum
      about Earth's axis); bound 1e-12 of Cρ0 (integrator error).
    * §V eq. (14): θ swings between θ0 and θ' in T = π√(a u0²)/(C ρ0 sin θ0) (leading term;
      the dropped corrections are ~n/ρ0 ≈ 1e-7): to 1e-6 (observed 3e-8); the swing
      |θ0 − θ'| = 2n(b sin²θ0 + γ)/(C ρ0 sin θ0) from eq. (7) to 1e-6 (observed 2.6e-8).
    * §V: Ψ/T = n: the axis turns at n against the Earth's rotation (here oz is the north
      part of the axis, so ψ drifts at −n): to 1e-6 (observed 1.5e-8).
    """
    g = make(configuration="free", outer_axis="polar", initial_outer_angle_deg=0.0,
             initial_inner_angle_deg=-30.0)
    pr = g.predictions()
    assert pr["k_rad_s"] == pytest.approx(-N, rel=1e-15) and pr["k_prime_rad_s"] == 0.0
    Tn = pr["nutation_half_period_s"]
    t = np.linspace(0.0, 30 * Tn, 3001)
    sim = g.simulate(t)
    inv = g.invariants(sim)
    assert np.ptp(inv["axial_momentum_kg_m2_s"]) < 1e-12 * g.C * g.p.spin_rate_rad_s
    theta = sim.extra["theta"]
    s0 = math.sin(g.theta0)
    b, gam = g.p.transverse_inertia_kg_m2 + g.C1 - g.A1, g.A1 + g.A2
    assert np.ptp(theta) == pytest.approx(2 * N * (b * s0 ** 2 + gam) / (g.C * g.p.spin_rate_rad_s * s0), rel=1e-6)
    assert fitted_swing(t, theta - np.mean(theta), Tn) == pytest.approx(Tn, rel=1e-6)
    w = math.pi / Tn
    X = np.column_stack([np.ones_like(t), t, np.cos(w * t), np.sin(w * t)])
    drift = np.linalg.lstsq(X, sim.extra["psi"], rcond=None)[0][1]
    assert drift == pytest.approx(-N, rel=1e-6)


# ------------------------------------------------------------------ gimbal lock
def test_near_gimbal_lock_stays_finite_with_ring_inertia():
    """Rotor axis 1e-3 rad from PP' (vertical), rings free, released at rest.

    The mass matrix in (ψ, θ, φ) has det M = a C u² (from eq. 12, first) with u² ≥ A1 + A2:
    checked to 1e-12 against the chain and at least 5e5 times the massless-ring value
    a C A sin²θ0 (≈ 1e-9 kg m² for u²). Over 2 s the motion stays finite, (13) and the Jacobi
    integral hold to 1e-11 rad/s and 1e-11 J, and the rates obey the bound the two invariants
    give, u²ψ̇² + aθ̇² ≤ C(ρ0² − ρ²) + n²ΣI with |ρ − ρ0| ≤ 2n.
    """
    theta0 = 1e-3
    g = make(configuration="free", outer_axis="vertical", initial_outer_angle_deg=0.0,
             initial_inner_angle_deg=math.degrees(theta0) - 90.0)
    chain = g.build_chain()
    M = g.mass_matrix(chain, [g.psi0, g.theta0, 0.0])
    a, gam = g.p.transverse_inertia_kg_m2 + g.A1, g.A1 + g.A2
    u2 = (g.p.transverse_inertia_kg_m2 + g.C1 - g.A1) * math.sin(theta0) ** 2 + gam
    assert np.linalg.det(M) == pytest.approx(a * g.C * u2, rel=1e-12)
    assert u2 / (g.p.transverse_inertia_kg_m2 * math.sin(theta0) ** 2) > 5e5
    t = np.linspace(0.0, 2.0, 401)
    sim = g.simulate(t)
    c = sim.columns
    assert all(np.all(np.isfinite(v)) for v in c.values())
    assert sim.trajectory.nfev < 20000  # no stiffness from the coordinate singularity
    inv = g.invariants(sim)
    assert np.ptp(inv["spin_13_rad_s"]) < 1e-11
    assert np.ptp(inv["jacobi_J"]) < 1e-11
    sum_I = g.p.transverse_inertia_kg_m2 * 2 + g.C + g.A1 * 2 + g.C1 + g.A2 * 2 + g.C2
    rho0 = g.p.spin_rate_rad_s
    budget = 4 * N * g.C * (rho0 + N) + N ** 2 * sum_I
    assert np.max(gam * c["outer_rate"] ** 2) <= budget
    assert np.max(a * c["inner_rate"] ** 2) <= budget
    assert np.min(sim.extra["theta"]) > 0.0  # the axis does not pass through the lock


# ------------------------------------------------------------------ effects
def test_pivot_damping_and_spin_decay():
    """``pivot_damping`` (τ = 100 s): −(2/τ) J ψ̇ with J = A + C1 + A2 makes the locked swing
    decay as e^(−t/τ): fitted decay rate 1/τ to 1e-4 (the damped-oscillator law is exact for
    the linear swing; a²-terms are 1e-9). ``spin_decay`` (τ = 50 s): ρ = ρ0 e^(−t/τ) to 1e-8
    relative (the Earth's share of dρ, eq. 14 third, is k' Δ sin ψ ~ 1e-7 rad/s on 628)."""
    g = make(effects=EXACT + ("pivot_damping",), configuration="locked", initial_outer_angle_deg=0.01)
    g.effects["pivot_damping"] = EFFECTS["pivot_damping"](time_constant_s=100.0)
    T = g.predictions()["swing_duration_small_s"]
    t = np.linspace(0.0, 6 * T, 1201)
    y = g.simulate(t).columns["outer_angle"]
    s = np.max(np.abs(y))

    def f(t, a, b, w, lam):
        return np.exp(-lam * t) * (a * np.sin(w * t) + b * np.cos(w * t))

    p, _ = curve_fit(f, t, y / s, p0=[0.0, 1.0, math.pi / T, 0.01], xtol=1e-14, ftol=1e-14)
    assert p[3] == pytest.approx(1.0 / 100.0, rel=1e-4)
    g = make(effects=EXACT + ("spin_decay",), configuration="locked", initial_outer_angle_deg=0.01)
    g.effects["spin_decay"] = EFFECTS["spin_decay"](time_constant_s=50.0)
    t = np.linspace(0.0, 20.0, 21)
    rho = g.simulate(t).columns["spin_rate"]
    np.testing.assert_allclose(rho, g.p.spin_rate_rad_s * np.exp(-t / 50.0), rtol=1e-8)


# ------------------------------------------------------------------ geometry and parameters
def test_geometry_and_reference_lines():
    """Quet's axes and the column conventions in ENU (REP-103).

    PP' vertical: ox = north, Earth rate (k', 0, −k) = (n cos γ, 0, −n sin γ) with oz up.
    outer_angle = 0, rings locked: rotor axis north (the equilibrium line of §IV).
    outer_fixed at 0, inner_angle = 0: rotor axis along the north part of Earth's axis
    (Quet's u = 0 of T''), θ_ref = 180° − ω. Exact to rounding (1e-14).
    """
    g = make(configuration="locked", outer_axis="vertical", initial_outer_angle_deg=0.0)
    np.testing.assert_allclose(g.frame[:, 0], [0.0, 1.0, 0.0], atol=1e-15)
    assert g.k_prime == pytest.approx(N * math.cos(SITE.latitude_rad), rel=1e-14)
    assert g.k == pytest.approx(-N * math.sin(SITE.latitude_rad), rel=1e-14)
    chain = g.build_chain()
    np.testing.assert_allclose(chain.axis_in_enu(g.initial_state(chain)[:chain.nf], 2, [0, 0, 1]),
                               [0.0, 1.0, 0.0], atol=1e-14)
    g = make(configuration="outer_fixed", outer_axis="vertical", initial_inner_angle_deg=0.0)
    chain = g.build_chain()
    np.testing.assert_allclose(chain.axis_in_enu(g.initial_state(chain)[:chain.nf], 2, [0, 0, 1]),
                               SITE.earth_axis_north_enu(), atol=1e-14)
    assert g.theta_ref == pytest.approx(math.pi - math.acos(g.cos_omega), rel=1e-14)
    # T'' does not depend on PP' when the outer ring is held at 0: the swing plane holds ox and oz.
    assert make(configuration="outer_fixed", outer_axis="east_west").predictions()["swing_duration_small_s"] \
        == pytest.approx(g.predictions()["T_second_quet_s"], rel=1e-14)


@pytest.mark.parametrize("raw, field, text", [
    (dict(outer_axis="custom"), "outer_axis_enu", "is required when outer_axis = custom"),
    (dict(inner_ring_diametral_inertia_kg_m2=1e-4, inner_ring_axial_inertia_kg_m2=3e-4),
     "inner_ring_axial_inertia_kg_m2", "must be in [0, 2 A1] = [0, 0.0002]"),
    (dict(outer_ring_axial_inertia_kg_m2=2e-3), "outer_ring_axial_inertia_kg_m2", "[0, 2 A2] = [0, 0.001]"),
    (dict(configuration="locked", initial_inner_angle_deg=3.0), "initial_inner_angle_deg", "inner ring held"),
    (dict(configuration="outer_fixed", initial_outer_rate_deg_s=1.0), "initial_outer_rate_deg_s", "outer ring held"),
    (dict(configuration="stuck"), "configuration", "must be one of free, locked, outer_fixed"),
])
def test_parameter_errors(raw, field, text):
    """Errors name the field and quote the value and the valid range."""
    with pytest.raises(SceneError) as err:
        make(**raw)
    assert err.value.field == f"instruments.g.{field}"
    assert text in str(err.value)


# ------------------------------------------------------------------ the closed form (issue 13 item 5)
def random_states(g, chain, rng, count=30):
    """``count`` random states y (angles in ±3 rad, rates in ±5 rad/s, the rotor's ×100), each with
    the chain's right-hand side there and the bound 1000 eps κ max(S, |q̈|) of
    :func:`test_closed_form_is_the_chain` (S = v (v + n) ΣI / min(A, C), κ the scaled condition
    number of M)."""
    inertia = g.p.transverse_inertia_kg_m2 + g.C + g.A1 + g.C1 + g.A2 + g.C2
    for _ in range(count):
        q = rng.uniform(-3.0, 3.0, chain.nf)
        v = rng.uniform(-5.0, 5.0, chain.nf)
        v[-1] *= 100.0                         # the rotor spins fast
        y = np.concatenate([q, v])
        ref = chain.rhs(0.0, y)
        scale = max(np.max(np.abs(v)) * (np.max(np.abs(v)) + N) * inertia / min(g.p.transverse_inertia_kg_m2, g.C),
                    np.max(np.abs(ref[chain.nf:])))
        yield y, ref, 1000 * np.finfo(float).eps * scaled_condition(g.mass_matrix(chain, q)) * scale


@pytest.mark.parametrize("effects", [EXACT, ("earth_rotation", "ring_inertia", "pivot_damping", "spin_decay"),
                                     ("centrifugal",), ()], ids=lambda e: "+".join(e) or "none")
def test_closed_form_is_the_chain(effects):
    """:func:`closed_form_rhs` (Kane's equations unrolled, M solved in closed form) equals the
    generic chain's right-hand side at random states, every configuration, three PP' directions.

    Bound: 1000 eps κ max(S, |q̈|), S = v (v + n) ΣI / min(A, C) the force scale (v the largest
    rate: every acceleration is a sum of inertia × rate × rate over an inertia), κ the scaled
    condition number of M (:func:`scaled_condition`): both sides round sums of ~30 such terms and
    solve M q̈ = f, whose forward error is ~κ eps (κ ≲ 10 with ring inertia, up to ~1e5 for massless
    rings near the lock, where q̈ grows as 1/sin²θ); observed 0.74 eps κ max(S, |q̈|) at worst
    (5e-13 of the scale without κ). A wrong sign or a missing term is O(1e-3..1) of S.

    The numba kernels of ``integrator: compiled`` (:func:`~.kernels.free_kernel`,
    :func:`~.kernels.held_kernel`) are held to the same bound, and compiled to the plain Python
    function bit for bit (the same operations in the same order, no fastmath).
    """
    rng = np.random.default_rng(13)
    for conf in ("free", "locked", "outer_fixed"):
        for axis in ("vertical", "north_south", "polar"):
            g = make(effects, configuration=conf, outer_axis=axis, inner_ring_axial_inertia_kg_m2=3.0e-4,
                     integrator="closed_form")
            if "pivot_damping" in effects:
                g.effects["pivot_damping"] = EFFECTS["pivot_damping"](time_constant_s=100.0)
            chain = g.build_chain()
            f, _ = g.closed_form(chain)
            name, p = g.kernel_params(chain)
            kernel = compiled_kernel(name)
            assert kernel is not KERNELS[name]
            for y, ref, bound in random_states(g, chain, rng):
                assert np.max(np.abs(np.array(f(0.0, *y)) - ref)) < bound, (conf, axis)
                got, plain = np.empty_like(y), np.empty_like(y)
                kernel(0.0, y, p, got)
                KERNELS[name](0.0, y, p, plain)
                np.testing.assert_array_equal(got, plain)
                assert np.max(np.abs(got - ref)) < bound, (conf, axis)


@pytest.mark.parametrize("integrator", ["closed_form", "compiled"])
def test_closed_form_free_gimbal_equals_the_chain_run(integrator):
    """The free gimbal with large excursions (the invariants test's release): closed form
    (Fortran DOP853, sample to sample; or the compiled kernel through the compiled DOP853 with
    dense output, ~same step count) against the chain (solve_ivp DOP853), both at rtol 1e-11,
    over 0.5 s. Each has a global error ~1e-11 rad on these O(1) rad excursions (rtol 1e-11 per
    step; ~100 steps for the chain, ~430 for the closed form stopping at the 201 samples, whose
    errors add); bound 1e-9 rad on the angles and 1e-9 relative on the rates (observed 1.8e-11 rad
    and 9e-11). Swapping the integrators changes nothing that is not integration error."""
    params = dict(configuration="free", outer_axis="vertical", spin_rate_rad_s=2 * math.pi * 5,
                  initial_outer_angle_deg=20.0, initial_inner_angle_deg=-30.0,
                  initial_outer_rate_deg_s=300.0, initial_inner_rate_deg_s=200.0)
    t = np.linspace(0.0, 0.5, 201)
    fast = make(**params, integrator=integrator).simulate(t)
    ref = make(**params, integrator="hinge_chain").simulate(t)
    assert fast.trajectory.meta["integrator"] == integrator
    assert ref.trajectory.meta["integrator"] == "hinge_chain"
    for k in ("outer_angle", "inner_angle", "rotor_angle"):
        assert np.max(np.abs(fast.columns[k] - ref.columns[k])) < 1e-9, k
    for k in ("outer_rate", "inner_rate", "spin_rate"):
        assert np.max(np.abs(fast.columns[k] - ref.columns[k])) < 1e-9 * np.max(np.abs(ref.columns[k])), k


def test_unknown_rigid_body_term_falls_back_to_the_chain():
    """An effect whose rigid-body torque is not c_l L + c_q Ω × IΩ (here cubic in Ω) is never
    dropped by the closed form: ``auto`` runs the chain, an explicit ``closed_form`` is refused
    by name."""
    from gyro_instrument.core.effect import RIGID_BODY, Effect
    from gyro_instrument.instruments.gimbal.torques import rigid_body_coefficients

    class Cubic(Effect):
        name = "cubic"
        MECHANICS = frozenset({RIGID_BODY})

        def rigid_body_torque(self, ctx, inertia, w_rel, omega_b):
            return np.dot(omega_b, omega_b) * np.cross(omega_b, inertia @ omega_b)

    assert rigid_body_coefficients([EFFECTS["earth_rotation"](), EFFECTS["centrifugal"]()]) == (1.0, 1.0)
    assert rigid_body_coefficients([Cubic()]) is None
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, {"configuration": "free"})
    g = GimbalGyroscope("g", SITE, p, {"earth_rotation": EFFECTS["earth_rotation"](), "cubic": Cubic()})
    assert g.integrator_choice()[0] == "hinge_chain"
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, {"configuration": "free", "integrator": "closed_form"})
    with pytest.raises(SceneError) as err:
        GimbalGyroscope("g", SITE, p, {"cubic": Cubic()})
    assert err.value.field == "g.integrator"


def test_hinge_terms_linear_or_called():
    """The free closed form multiplies hinge torques that are linear in the rate by their measured
    coefficient (:func:`linear_hinge_coefficient`: pivot damping −(2/τ) J q̇, bearing −C ρ/τ) and
    calls any other term. Both routes equal the chain's right-hand side (the same bound as
    :func:`test_closed_form_is_the_chain`, 1000 eps κ S; a dropped or doubled term is O(J q̇/τ) ≈ 1e-3 S
    here): a quadratic pivot drag is not linear (None) and is called as is."""
    from gyro_instrument.core.effect import DAMPING, SPIN, Effect, EffectContext, bound_hooks
    from gyro_instrument.instruments.gimbal.torques import linear_hinge_coefficient

    class QuadraticDrag(Effect):
        name = "quadratic_drag"
        MECHANICS = frozenset({DAMPING})

        def damping_torque(self, ctx, inertia, rate):
            return -0.05 * inertia * rate * abs(rate)

    damping = EFFECTS["pivot_damping"](time_constant_s=100.0)
    decay = EFFECTS["spin_decay"](time_constant_s=50.0)
    ctx = EffectContext.of_site(SITE)
    (damp,), (spin,) = bound_hooks([damping], DAMPING, ctx), bound_hooks([decay], SPIN, ctx)
    assert linear_hinge_coefficient([damp], 2.0) == damping.damping_torque(ctx, 2.0, 1.0)
    assert linear_hinge_coefficient([spin], 3.0) == decay.spin_torque(ctx, 3.0, 1.0)
    assert linear_hinge_coefficient([], 3.0) == 0.0
    assert linear_hinge_coefficient(bound_hooks([QuadraticDrag()], DAMPING, ctx), 2.0) is None
    rng = np.random.default_rng(17)
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, {"configuration": "free", "integrator": "closed_form"})
    for extra in ({"pivot_damping": damping, "spin_decay": decay},
                  {"pivot_damping": damping, "spin_decay": decay, "quadratic_drag": QuadraticDrag()}):
        effects = {k: EFFECTS[k]() for k in EXACT}
        effects.update(extra)
        g = GimbalGyroscope("g", SITE, p, effects)
        chain = g.build_chain()
        f, _ = g.closed_form(chain)
        for y, ref, bound in random_states(g, chain, rng, count=20):
            assert np.max(np.abs(np.array(f(0.0, *y)) - ref)) < bound, sorted(extra)


@pytest.mark.parametrize("integrator", ["closed_form", "compiled"])
@pytest.mark.parametrize("configuration", ["locked", "outer_fixed", "free"])
def test_stream_equals_simulate_bit_for_bit(configuration, integrator):
    """Streaming (issue 13 item 1): the closed form's runs never let the blocks steer the steps (the
    free gimbal's reaches each sample by one Fortran DOP853 call from the previous sample; the
    locked and outer-fixed swings' steps with no end and keeps a step's dense output across
    blocks), so blocks of any size concatenate to the one-shot run exactly (bound 0, not
    round-off), and each block comes with
    the run's cumulative RHS count. (The counts themselves are not compared with the one-shot run:
    scipy's DOP853 spent 36 fewer evaluations on the second sample of the first run in a process,
    with identical states.) The compiled driver steps with no end and keeps its last step, as the
    dense-output run does, for every configuration."""
    from gyro_instrument.core.scene import sample_blocks, sample_times
    from gyro_instrument.scenes import build_instruments, load_scene
    over = ["instruments.gimbal_locked.configuration=free"] if configuration == "free" else []
    over += [f"instruments.{name}.integrator={integrator}" for name in ("gimbal_locked", "gimbal_outer_fixed")]
    duration = 1.5 if configuration == "free" else 30.0      # ~3 nutations per sample / ~2 swings
    scene = load_scene("gimbal_paris", [f"duration_s={duration}", "sample_rate_hz=50"] + over)
    g = build_instruments(scene)["gimbal_outer_fixed" if configuration == "outer_fixed" else "gimbal_locked"]
    assert g.p.configuration == configuration
    assert g.STREAMS and g.integrator_choice()[0] == integrator
    one = g.simulate(sample_times(scene))
    for window_s in (0.07, 1.0):
        parts = list(g.stream(sample_blocks(scene, window_s)))
        assert len(parts) > 1
        for k, v in one.columns.items():
            assert np.array_equal(np.concatenate([p.columns[k] for p in parts]), v), (window_s, k)
        counts = [p.trajectory.nfev for p in parts]
        assert counts == sorted(counts) and counts[-1] > counts[0]       # the run's count so far


def test_two_free_gimbals_streamed_together_equal_each_alone():
    """A node streams a scene's instruments side by side: two free gimbals' runs interleaved block by
    block (each its own Fortran DOP853 state) equal each one-shot run bit for bit (bound 0)."""
    from gyro_instrument.core.scene import sample_blocks, sample_times
    from gyro_instrument.scenes import build_instruments, load_scene
    scene = load_scene("gimbal_paris", ["duration_s=1", "instruments.gimbal_locked.configuration=free",
                                        "instruments.gimbal_outer_fixed.configuration=free"])
    pair = list(build_instruments(scene).values())
    alone = [g.simulate(sample_times(scene)) for g in pair]
    together = list(zip(*(g.stream(sample_blocks(scene, 0.1)) for g in pair)))
    for i, one in enumerate(alone):
        for k, v in one.columns.items():
            assert np.array_equal(np.concatenate([blocks[i].columns[k] for blocks in together]), v), (i, k)
