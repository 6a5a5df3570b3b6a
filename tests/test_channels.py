"""Every reported channel of every instrument against an invariant or an independent formula.

A channel no test reads is a channel that can be wrong (issue 17: the compound pendulum's
``spin_rate`` broke Quet's eq. (55) by three orders of magnitude while the dynamics were right).
Each test below declares, with :func:`reads`, the instrument type and the channels it checks, and
fails unless it actually reads them from a simulation (:func:`simulate` records the reads);
:func:`test_every_declared_column_is_simulated_in_si_and_its_rates_are_derivatives` checks every
declared column of every registered type generically (simulated, finite, SI, rates the derivatives
of their angles), so a new column needs no edit here. Puiseux's body is covered by
tests/test_puiseux*.py (another module).

Derivatives of channels are taken with quintic interpolating splines on samples a few hundred
per period: their relative error is ~(ω Δt)⁵ / 720 (< 1e-12 here), far below every tolerance;
the first and last 5 % of a record, where the spline has one-sided support, are left out.
"""

import functools
import math

import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from gyro_instrument.core.site import Site
from gyro_instrument.instruments import REGISTRY
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.instruments.gimbal import GimbalGyroscope
from gyro_instrument.instruments.gimbal.theory import quet_energy, spin_invariant
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope

#: A southern site none of the older tests uses (the issue's audit site).
SOUTH = Site.from_degrees(-33.87)
NORTH = Site.from_degrees(48.85)
#: Covered elsewhere (tests/test_puiseux*.py), by agreement of issue 17.
ELSEWHERE = {"puiseux_body"}

DECLARED = {}          # type name -> set of columns some test declares it checks
_READ = set()          # (type name, column) read during the running test


class _Recording(dict):
    """Simulation columns that remember which were read (by the running test)."""

    def __init__(self, type_name, data):
        super().__init__(data)
        self.type_name = type_name

    def __getitem__(self, key):
        _READ.add((self.type_name, key))
        return super().__getitem__(key)


def simulate(inst, t, **options):
    """``inst.simulate(t)`` with its columns recording the reads."""
    sim = inst.simulate(np.asarray(t, dtype=float), **options)
    sim.columns = _Recording(inst.type_name, sim.columns)
    return sim


def reads(type_name, *columns):
    """Declare that the decorated test checks ``columns`` of ``type_name``; it fails if it does not
    read every one of them from a :func:`simulate` result."""
    def deco(f):
        DECLARED.setdefault(type_name, set()).update(columns)

        @functools.wraps(f)
        def wrapper(*args, **kwargs):
            _READ.clear()
            f(*args, **kwargs)
            unread = [c for c in columns if (type_name, c) not in _READ]
            assert not unread, f"{f.__name__} declares {type_name} channels it never read: {unread}"
        return wrapper
    return deco


def derivative(t, y, k=5):
    """Quintic-spline derivative of samples ``y`` at times ``t``."""
    return make_interp_spline(t, y, k=k).derivative()(t)


def inner(a):
    """The samples away from the record's ends (the middle 90 %)."""
    m = a.shape[-1]
    return a[..., m // 20: m - m // 20]


# ----------------------------------------------------------------------------- Foucault pendulum

@reads("spherical_pendulum", "x_east", "y_north", "z_up", "deflection")
def test_spherical_pendulum_constraint_energy_and_deflection(build):
    # Quet sec. 2: the constraint (23) |r| = l and the energy integral (24) with the centrifugal
    # potential, −½|Ω × δr|² (Ω × δr: the exact model's centrifugal term about the rest point),
    # read from the position channels alone (velocity by spline). A 30° swing of 1 m (nonlinear).
    # Tolerances: the constraint is held by Baumgarte terms and rtol 1e-12 (1e-9 l); the energy by
    # the integrator (measured 3e-12 g l) and the spline derivative (< 1e-11): 1e-9 g l.
    # deflection = arccos(−z/l) (kinematics; 1e-7 rad: arccos near 0 loses half the digits of z).
    effects = ("earth_rotation", "centrifugal", "finite_amplitude")
    p = build(SphericalPendulum, SOUTH, effects, length_m=1.0, initial_deflection_deg=30.0,
              initial_azimuth_deg=45.0, transverse_speed_m_s=0.3, rtol=1e-12)
    t = np.arange(0.0, 12.0, 1.0 / 400.0)
    c = simulate(p, t).columns
    r = np.vstack([c["x_east"], c["y_north"], c["z_up"]])
    assert np.max(np.abs(np.linalg.norm(r, axis=0) - 1.0)) < 1e-9
    v = np.vstack([derivative(t, ri) for ri in r])
    dr = r - np.array([[0.0], [0.0], [-1.0]])
    g = SOUTH.gravity_m_s2
    E = 0.5 * np.sum(v * v, axis=0) + g * r[2] - 0.5 * np.sum(np.cross(SOUTH.earth_rate_enu(), dr.T) ** 2, axis=1)
    assert np.ptp(inner(E)) < 1e-9 * g
    assert np.max(np.abs(c["deflection"] - np.arccos(np.clip(-r[2], -1.0, 1.0)))) < 1e-7
    assert c["deflection"][0] == pytest.approx(math.radians(30.0), abs=1e-12)


@reads("spherical_pendulum", "x_east", "y_north")
def test_spherical_pendulum_follows_binet_at_small_amplitude(build):
    # Quet sec. 2 eq. (22) linearised: Binet's ellipse (binet_ellipse is the closed form). At 1e-6
    # rad the neglected terms are (amplitude)² ~ 1e-12 and the horizontal Earth rate's, k' θ ~ 1e-10
    # of the Coriolis force: positions agree to 1e-7 of the amplitude (integrator: rtol 1e-12).
    from gyro_instrument.instruments.pendulum import binet_ellipse
    p = build(SphericalPendulum, SOUTH, ("earth_rotation", "finite_amplitude"), length_m=10.0,
              initial_deflection_deg=math.degrees(1e-6), initial_azimuth_deg=30.0, rtol=1e-12)
    t = np.linspace(0.0, 120.0, 2401)
    c = simulate(p, t).columns
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, 10.0, SOUTH.gravity_m_s2, SOUTH.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    assert np.max(np.hypot(c["x_east"] - x, c["y_north"] - y)) < 1e-7 * 10.0 * 1e-6


@reads("spherical_pendulum", "azimuth", "deflection")
def test_spherical_pendulum_azimuth_keeps_the_area_integral(build):
    # Quet sec. 2 eq. (27), the area integral, in the model whose horizontal motion has only the
    # vertical Earth rate k (the linear model: ẍ = −ω0² x + 2k ẏ, ...): with ψ the compass azimuth
    # (clockwise from above) and ρ_h = l sin θ, d/dt(−ρ_h² ψ̇ + k ρ_h²) = 0 exactly. A fat ellipse
    # (transverse launch) keeps ψ smooth. Read from the azimuth and deflection channels alone;
    # tolerance 1e-9 of the area rate ρ_h² |ψ̇| (spline derivative < 1e-11, integrator 1e-12).
    l = 10.0
    p = build(SphericalPendulum, SOUTH, ("earth_rotation",), length_m=l, initial_deflection_deg=3.0,
              initial_azimuth_deg=-60.0, transverse_speed_m_s=0.2, rtol=1e-12)
    t = np.arange(0.0, 30.0, 1.0 / 200.0)
    c = simulate(p, t).columns
    rh2 = (l * np.sin(c["deflection"])) ** 2
    psid = derivative(t, c["azimuth"])
    h = -rh2 * psid + SOUTH.k_vertical_rad_s * rh2
    assert np.ptp(inner(h)) < 1e-9 * np.max(np.abs(rh2 * psid))
    # the azimuth is the compass azimuth of the bob: atan2(east, north)
    assert np.max(np.abs(np.angle(np.exp(1j * (c["azimuth"] - np.arctan2(c["x_east"], c["y_north"])))))) < 1e-12


@pytest.mark.parametrize("site", [SOUTH, NORTH], ids=["south", "north"])
@reads("spherical_pendulum", "swing_azimuth")
def test_spherical_pendulum_swing_plane_turns_at_k(build, site):
    # Quet sec. 2: the swing plane turns at k = n sin γ, clockwise seen from above in the north
    # (compass azimuth increasing), counter-clockwise in the south. Linear model released from rest:
    # in the frame turning at −k, Binet's ellipse is z' = a cos Ωt + i b sin Ωt with b = (k/Ω) a, and
    # the Earth-relative velocity there is ż' − ikz' = −(aΩ − kb) sin Ωt (along the major axis: the
    # transverse parts cancel since bΩ = ka). The Fradkin tensor ω0² r rᵀ + v vᵀ then has off-diagonal
    # ω0² a b cos Ωt sin Ωt over a diagonal ~ω0² a², so its major axis sits at ψ0 + k t (compass)
    # within (b/2a) |sin 2Ωt| ≤ |k|/(2ω0): tolerance 0.6 |k|/ω0.
    l = 10.0
    p = build(SphericalPendulum, site, ("earth_rotation",), length_m=l, initial_deflection_deg=2.0,
              initial_azimuth_deg=20.0, rtol=1e-12)
    t = np.linspace(0.0, 600.0, 12001)
    c = simulate(p, t).columns
    k = site.k_vertical_rad_s
    w0 = math.sqrt(site.gravity_m_s2 / l)
    resid = c["swing_azimuth"] - (math.radians(20.0) + k * t)
    resid = (resid + math.pi / 2) % math.pi - math.pi / 2
    assert np.max(np.abs(resid)) < 0.6 * abs(k) / w0
    assert abs(k) * 600.0 > 50 * abs(k) / w0         # the turn is far larger than the tolerance


# ----------------------------------------------------------------------------- compound pendulum

CP = dict(mass_kg=10.0, com_distance_m=1.0, transverse_inertia_kg_m2=10.0, axial_inertia_kg_m2=2e-4,
          initial_deflection_deg=5.0, initial_azimuth_deg=45.0, rtol=1e-12)


@pytest.mark.parametrize("rho0", [0.0, 30.0])
@reads("compound_pendulum", "spin_rate", "x_east", "y_north", "z_up")
def test_compound_pendulum_spin_obeys_eq55_and_vis_viva_eq51(build, rho0):
    # Quet sec. 3 §VI eq. (55): ρ + Ω·e is constant, e = (x, y, z)/l the figure axis (pivot to
    # centre of mass). The case (ρ0 = 0, C = 0.2 g m², launch azimuth 45°, −33.87°): Ω·e
    # swings by ~2 n sin θ0 = 1.3e-5 rad/s, so ρ must too, and the sum stays within 1e-10 rad/s
    # (atol 1e-13 on the spin hinge over ~1e3 steps; measured 2.5e-12). Eq. (51) (vis viva, exact
    # with the workless Coriolis terms): A|ė|² + Cρ² + 2 M g z constant, ė by spline; 1e-9 M g l.
    cp = build(CompoundPendulum, SOUTH, ("earth_rotation",), spin_rate_rad_s=rho0, **CP)
    t = np.arange(0.0, 15.0, 1.0 / 200.0)
    c = simulate(cp, t).columns
    e = np.vstack([c["x_east"], c["y_north"], c["z_up"]]) / CP["com_distance_m"]
    assert np.max(np.abs(np.linalg.norm(e, axis=0) - 1.0)) < 1e-12          # a rigid body
    om_e = SOUTH.earth_rate_enu() @ e
    inv = c["spin_rate"] + om_e
    assert np.ptp(inv) < 1e-10
    assert inv[0] == pytest.approx(cp.predictions()["absolute_spin_rad_s"], abs=1e-15)   # the stated constant
    assert c["spin_rate"][0] == pytest.approx(rho0, abs=1e-15)
    assert np.ptp(c["spin_rate"]) == pytest.approx(np.ptp(om_e), rel=1e-5)  # what eq. (55) allows, not more
    edot = np.vstack([derivative(t, ei) for ei in e])
    A, C, M, g = CP["transverse_inertia_kg_m2"], CP["axial_inertia_kg_m2"], CP["mass_kg"], SOUTH.gravity_m_s2
    E = A * np.sum(edot ** 2, axis=0) + C * c["spin_rate"] ** 2 + 2 * M * g * CP["com_distance_m"] * e[2]
    assert np.ptp(inner(E)) < 1e-9 * M * g * CP["com_distance_m"]


@reads("compound_pendulum", "deflection", "azimuth", "swing_azimuth")
def test_compound_pendulum_angles_are_a_simple_pendulum_of_length_lambda(build):
    # Quet sec. 3 §VI eq. (57): with μ = C/A small (2e-5) and ρ0 = 0 the motion is a simple pendulum
    # of length λ = A/(M l), whose swing plane turns at k (sec. 2) — slowed for a 5° release from
    # rest by the apsidal lag of sec. 2 §III, k(1 − (3/8) θ0 sin θ0 cos(θ0/2)). The Fradkin angle
    # oscillates about that by |k|/(2ω0) (see the spherical pendulum's test); the O(μ) gyroscopic
    # terms and Binet's minor axis (β ~ 1e-5 rad) move it by a few % of that: tolerance
    # 0.6|k|/ω0 + 1e-3 |k| t (measured: 7.0e-6 rad against |k|/(2ω0) = 6.5e-6 over 40 s).
    # deflection and azimuth are the centre of mass's θ and compass ψ (kinematics, 1e-12 rad).
    from gyro_instrument.instruments.pendulum import apsidal_rate_from_rest_rad_s
    cp = build(CompoundPendulum, SOUTH, ("earth_rotation", "finite_amplitude"), **CP)
    t = np.linspace(0.0, 40.0, 801)
    c = simulate(cp, t).columns
    x, y, z = c["x_east"], c["y_north"], c["z_up"]
    assert np.max(np.abs(c["deflection"] - np.arctan2(np.hypot(x, y), -z))) < 1e-12
    assert np.max(np.abs(np.angle(np.exp(1j * (c["azimuth"] - np.arctan2(x, y)))))) < 1e-12
    assert np.max(c["deflection"]) == pytest.approx(math.radians(5.0), rel=1e-9)
    k = SOUTH.k_vertical_rad_s
    w0 = math.sqrt(SOUTH.gravity_m_s2 / cp.equivalent_length_m)
    rate = apsidal_rate_from_rest_rad_s(k, math.radians(5.0))
    resid = c["swing_azimuth"] - (math.radians(45.0) + rate * t)
    resid = (resid + math.pi / 2) % math.pi - math.pi / 2
    assert np.all(np.abs(resid) < 0.6 * abs(k) / w0 + 1e-3 * abs(k) * t)
    assert c["swing_azimuth"][-1] < c["swing_azimuth"][0]        # south: counter-clockwise from above


# ----------------------------------------------------------------------------- directing plane

@pytest.mark.parametrize("model,cone", [("reduced", 90.0), ("chain", 90.0), ("chain", 60.0)])
@reads("plane_gyroscope", "angle", "angle_rate", "spin_rate")
def test_plane_gyroscope_integrals_eq1_eq3(build, model, cone):
    # Quet sec. 4 §1 eq. (3): ρ + Ω·e constant, e the rotor axis (plane: n sin ω cos u; cone of
    # half-angle ε: n sin ω sin ε cos u + n cos ω cos ε); eq. (1): A sin²ε u'² + C ρ² constant (the
    # vis viva; exact without the centrifugal term, the Coriolis terms do no work). Tolerances:
    # rtol 1e-12 over ~2 swings: 1e-12 of ρ0 for (3), 1e-10 of Cρ0² for (1).
    g = build(PlaneGyroscope, SOUTH, ("earth_rotation", "finite_amplitude"), model=model,
              cone_half_angle_deg=cone, initial_angle_deg=20.0, rtol=1e-12)
    T = g.predictions()["swing_duration_s"]
    t = np.linspace(0.0, 2.0 * T, 2001)
    c = simulate(g, t).columns
    eps = math.radians(cone)
    ox, oy, oz = g.frame.T
    n = SOUTH.earth_axis_north_enu() * SOUTH.earth_rate_rad_s
    axis = (math.sin(eps) * (np.cos(c["angle"])[:, None] * ox + np.sin(c["angle"])[:, None] * oy)
            + math.cos(eps) * oz)
    inv = c["spin_rate"] + axis @ n
    rho0 = g.p.spin_rate_rad_s
    assert np.ptp(inv) < 1e-12 * rho0
    E = g.p.transverse_inertia_kg_m2 * math.sin(eps) ** 2 * c["angle_rate"] ** 2 + g.C * c["spin_rate"] ** 2
    assert np.ptp(E) < 1e-10 * g.C * rho0 ** 2
    # angle_rate is du/dt (kinematics; spline, 1e-8 of the peak rate)
    ud = derivative(t, c["angle"])
    assert np.max(np.abs(inner(ud - c["angle_rate"]))) < 1e-8 * np.max(np.abs(c["angle_rate"]))


@reads("plane_gyroscope", "angle", "angle_rate")
def test_plane_gyroscope_small_swing_closed_form_eq9(build):
    # Quet sec. 4 §1 eq. (9): small swings u = u0 cos(π t/T), T = π/√(μ n ρ0 sin ω). The small-angle
    # model (no finite_amplitude) is linear in u but for ρ, which eq. (3) moves by n sin ω (1 − cos u0)
    # ~ 3e-9 rad/s at u0 = 0.01 rad: 5e-12 of ρ0, a phase error ~1e-10 over two swings. The
    # integrator's absolute tolerance (1e-13 rad per step, ~1e3 steps) allows 1e-10 rad = 1e-8 u0.
    u0 = 0.01
    g = build(PlaneGyroscope, SOUTH, ("earth_rotation",), initial_angle_deg=math.degrees(u0), rtol=1e-12)
    T = g.predictions()["swing_duration_small_s"]
    t = np.linspace(0.0, 2.0 * T, 801)
    c = simulate(g, t).columns
    w = math.pi / T
    assert np.max(np.abs(c["angle"] - u0 * np.cos(w * t))) < 1e-8 * u0
    assert np.max(np.abs(c["angle_rate"] + u0 * w * np.sin(w * t))) < 1e-8 * u0 * w


# ----------------------------------------------------------------------------- free gyroscope

def alt_az_to_equatorial(alt, az, lat):
    """Textbook spherical astronomy (compass azimuth A from north through east, altitude h):
    sin δ = sin φ sin h + cos φ cos h cos A; H = atan2(−sin A cos h, cos φ sin h − sin φ cos h cos A)."""
    sd = math.sin(lat) * np.sin(alt) + math.cos(lat) * np.cos(alt) * np.cos(az)
    H = np.arctan2(-np.sin(az) * np.cos(alt), math.cos(lat) * np.sin(alt) - math.sin(lat) * np.cos(alt) * np.cos(az))
    return np.arcsin(np.clip(sd, -1, 1)), H


@pytest.mark.parametrize("model,duration", [("analytic", 86400.0), ("numerical", 3.0)])
@reads("free_gyroscope", "axis_altitude", "axis_azimuth", "hour_angle", "declination", "spin_rate")
def test_free_gyroscope_channels(build, model, duration):
    # Quet sec. 4 §II: the absolute spin is constant, ρ + n cos θ = ρ0 + n cos θ0 (eqs. 1–2, 7;
    # θ from the north part of Earth's axis, cos θ = e·ê with e from altitude and azimuth); the axis
    # moves like a parallactic telescope: its hour angle grows at n (eq. 47) and its declination
    # stays within the nutation circle of diameter 2n sin θ0/(μρ0) (eqs. 16, 19) — allowed 1.1 × that
    # (the exact circle is larger by O(n/μρ0)). Hour angle and declination are the altitude and
    # azimuth converted by the textbook formulas (1e-9 rad: arcsin near ±90° loses digits).
    mu, rho0 = 2.0, 60.0
    f = build(FreeGyroscope, SOUTH, ("earth_rotation",), model=model, inertia_ratio=mu, spin_rate_rad_s=rho0,
              initial_axis_altitude_deg=25.0, initial_axis_azimuth_deg=120.0)
    t = np.linspace(0.0, duration, 4001)
    c = simulate(f, t).columns
    alt, az = c["axis_altitude"], c["axis_azimuth"]
    e = np.column_stack([np.cos(alt) * np.sin(az), np.cos(alt) * np.cos(az), np.sin(alt)])
    n = SOUTH.earth_rate_rad_s
    cos_t = e @ SOUTH.earth_axis_north_enu()
    assert np.ptp(c["spin_rate"] + n * cos_t) < 1e-13 * rho0
    dec, H = alt_az_to_equatorial(alt, az, SOUTH.latitude_rad)
    assert np.max(np.abs(c["declination"] - dec)) < 1e-9
    assert np.max(np.abs(np.angle(np.exp(1j * (c["hour_angle"] - H))))) < 1e-9
    sin_t0 = math.sin(f.theta0)
    diameter = 2 * n * sin_t0 / (mu * rho0)
    assert np.ptp(c["declination"]) < 1.1 * diameter
    drift = c["hour_angle"] - c["hour_angle"][0] - n * t
    assert np.max(np.abs(drift)) < 1.1 * diameter / math.cos(c["declination"][0])


# ----------------------------------------------------------------------------- gimbal

GIMBAL = dict(inertia_ratio=2.0, transverse_inertia_kg_m2=1e-3, inner_ring_diametral_inertia_kg_m2=2.5e-4,
              inner_ring_axial_inertia_kg_m2=3e-4, outer_ring_diametral_inertia_kg_m2=5e-4, rtol=1e-12)


def quet_angles(g, c):
    """Quet's θ, ψ from the published angles (module docstring of gimbal/instrument.py)."""
    return c["inner_angle"] + g.theta_ref, c["outer_angle"] + math.pi / 2


@reads("gimbal_gyroscope", "outer_angle", "inner_angle", "rotor_angle", "outer_rate", "inner_rate", "spin_rate")
def test_gimbal_free_integrals_eq12_eq13_and_rotor_kinematics(build):
    # Quet sec. 4 §III: eq. (13), ρ − k cos θ + k' sin θ sin ψ constant (1e-12 of ρ0: rtol 1e-12);
    # eq. (12, first), a θ̇² + u²ψ̇² + Cρ² constant — twice the relative kinetic energy, exact without
    # the centrifugal term (1e-10 of Cρ0²); the rotor joint turns at φ̇ = ρ − ψ̇ cos θ (sec. 4 eqs. 4, 6),
    # checked by integrating the rates (trapezoid, Δt = 0.5 ms: error Δt²/12 ∫|φ⃛| dt < 1e-7 rad for the
    # nutation's few-rad/s² swings; measured 1.3e-8; tolerance 1e-6 rad) and differentiating the
    # angles: outer_rate = dψ/dt,
    # inner_rate = dθ/dt (spline; 1e-7 of the peak rate). A slow rotor (20 rad/s) keeps the gimbal's
    # nutation (~Cρ/√(a u²)) resolvable at 2 kHz.
    g = build(GimbalGyroscope, SOUTH, ("earth_rotation", "ring_inertia"), configuration="free",
              outer_axis="north_south", spin_rate_rad_s=20.0, initial_outer_angle_deg=10.0,
              initial_inner_angle_deg=15.0, initial_outer_rate_deg_s=3.0, initial_inner_rate_deg_s=-2.0, **GIMBAL)
    t = np.arange(0.0, 2.5, 1.0 / 2000.0)
    c = simulate(g, t).columns
    theta, psi = quet_angles(g, c)
    inv = spin_invariant(c["spin_rate"], theta, psi, g.k, g.k_prime)
    assert np.ptp(inv) < 1e-12 * 20.0
    E = quet_energy(theta, c["inner_rate"], c["outer_rate"], c["spin_rate"], g.p.transverse_inertia_kg_m2, g.C, g.A1, g.C1, g.A2)
    assert np.ptp(E) < 1e-10 * g.C * 20.0 ** 2
    assert np.max(np.abs(inner(derivative(t, c["outer_angle"]) - c["outer_rate"]))) < 1e-7 * np.max(np.abs(c["outer_rate"]))
    assert np.max(np.abs(inner(derivative(t, c["inner_angle"]) - c["inner_rate"]))) < 1e-7 * np.max(np.abs(c["inner_rate"]))
    phid = c["spin_rate"] - c["outer_rate"] * np.cos(theta)
    from scipy.integrate import cumulative_trapezoid
    phi = c["rotor_angle"][0] + cumulative_trapezoid(phid, t, initial=0.0)
    assert np.max(np.abs(phi - c["rotor_angle"])) < 1e-6


@pytest.mark.parametrize("configuration", ["locked", "outer_fixed"])
@reads("gimbal_gyroscope", "outer_angle", "inner_angle", "spin_rate")
def test_gimbal_small_swings_closed_form_sec4_IV(build, configuration):
    # Quet sec. 4 §IV: locked rings swing about ox as u0 cos(π t/T), T = π√((A + C1 + A2)/(C n ρ0 sin ω))
    # (thick-ring inertia), the outer ring fixed lets the inner ring swing with T'' = π√((A + A1)/(C n ρ0))
    # (this PP' vertical at −33.87°). At u0 = 1e-4 rad the finite-amplitude period change u0²/16 is
    # 6e-10 and swing_duration_exact_s carries the O(n/ρ0) terms, so the closed form holds to the
    # integrator's error: an absolute 1e-13 rad per step (atol) over ~500 steps, 5e-7 of u0 at most
    # (measured 1.8e-7): tolerance 1e-6 u0. The held angle does not move and ρ obeys eq. (13).
    swing = math.degrees(1e-4)
    kw = ({"initial_outer_angle_deg": swing} if configuration == "locked" else {"initial_inner_angle_deg": swing})
    g = build(GimbalGyroscope, SOUTH, ("earth_rotation", "ring_inertia"), configuration=configuration, **kw, **GIMBAL)
    T = g.predictions()["swing_duration_exact_s"]
    t = np.linspace(0.0, 2.0 * T, 801)
    c = simulate(g, t).columns
    moving, held = ("outer_angle", "inner_angle") if configuration == "locked" else ("inner_angle", "outer_angle")
    assert np.max(np.abs(c[moving] - 1e-4 * np.cos(math.pi * t / T))) < 1e-6 * 1e-4
    assert np.ptp(c[held]) == 0.0
    theta, psi = quet_angles(g, c)
    assert np.ptp(spin_invariant(c["spin_rate"], theta, psi, g.k, g.k_prime)) < 1e-12 * g.p.spin_rate_rad_s


# ----------------------------------------------------------------------------- predictions: magnitudes

#: Prediction keys holding a magnitude (≥ 0 whatever the site's hemisphere or the spin's sense).
MAGNITUDE_WORDS = ("period", "duration", "deflection", "diameter", "length", "full_turn", "inertia", "departure",
                   "theta0", "sin_omega")


def magnitudes(pred):
    """(key, value) of the predictions whose name says they are magnitudes (a relative error is signed)."""
    return [(k, v) for k, v in pred.items() if any(w in k for w in MAGNITUDE_WORDS) and "error" not in k
            and isinstance(v, (int, float)) and not isinstance(v, bool)]


@pytest.mark.parametrize("site", [SOUTH, NORTH, Site.from_degrees(-89.0)], ids=["south", "north", "south_pole"])
@pytest.mark.parametrize("type_name", sorted(set(REGISTRY) - ELSEWHERE))
def test_predictions_report_magnitudes_unsigned(build, type_name, site):
    # Issue 17 item 4: a magnitude (a deflection, a period or duration, a diameter, a length, an
    # angle from an axis) is reported ≥ 0 at every site and for either sense of spin; a sense of
    # rotation is a separate entry (precession_sense) or the sign of a rate component (k, ρ). Every
    # instrument type (Puiseux's body: tests/test_puiseux*.py), at its defaults with the exact
    # model, at −33.87°, 48.85° and −89°, with the spin as given and reversed, and each gimbal
    # configuration.
    cls = REGISTRY[type_name]
    names = {p.name for p in cls.PARAMS}
    effects = tuple(e for e in ("earth_rotation", "centrifugal", "finite_amplitude") if e in cls.SUPPORTED_EFFECTS)
    variants = [{}]
    if "spin_rate_rad_s" in names:
        variants.append({"spin_rate_rad_s": -60.0})
    if "configuration" in names:
        variants += [{"configuration": c} for c in ("free", "locked", "outer_fixed")]
    for kw in variants:
        pred = build(cls, site, effects, **kw).predictions()
        found = magnitudes(pred)
        assert found, f"{type_name}: no magnitude to check in {sorted(pred)}"
        negative = [(k, v) for k, v in found if v < 0.0]
        assert not negative, f"{type_name} {kw} at {site.latitude_deg:g}°: magnitudes reported signed: {negative}"
        if cls.OBSERVATION.SHOWS_BOB_POSITION:
            k = site.k_vertical_rad_s
            assert pred["precession_sense"] == ("clockwise seen from above" if k > 0 else
                                                "counterclockwise seen from above")


# ----------------------------------------------------------------------------- every column, from its declaration

#: SI units a column may declare (angles in rad, rates in rad/s, lengths in m, "1" for a direction
#: cosine or other pure number): the architecture's "SI inside".
SI_UNITS = {"rad", "rad/s", "m", "1"}


def rate_pairs(cls):
    """(angle column, rate column) pairs read off the declarations: a ``<stem>_rate`` column in rad/s
    and a ``<stem>`` or ``<stem>_angle`` column in rad (``angle``/``angle_rate``,
    ``outer_angle``/``outer_rate``)."""
    units = {c.name: c.unit for c in cls.COLUMNS}
    pairs = []
    for name, unit in units.items():
        if name.endswith("_rate") and unit == "rad/s":
            stem = name[:-len("_rate")]
            pairs += [(a, name) for a in (stem, stem + "_angle") if units.get(a) == "rad"]
    return pairs


@pytest.mark.parametrize("type_name", sorted(set(REGISTRY) - ELSEWHERE))
def test_every_declared_column_is_simulated_in_si_and_its_rates_are_derivatives(build, type_name):
    # Generic over the instruments' declared COLUMNS, so a new instrument or column is checked without
    # an edit here: at its defaults with the exact model (4 s at 400 Hz, −33.87°), every declared
    # column is simulated, one finite sample per time, nothing undeclared; each unit is SI; and each
    # declared rate is the time derivative of its declared angle (quintic spline: relative error
    # ~(ωΔt)⁵/720 < 1e-12; the integrators' rtol ≤ 1e-10 — measured ≤ 7e-9 of the largest rate — so
    # 1e-6 of the largest rate, and 1e-12 rad/s when the rate is zero throughout). A rate in the
    # wrong unit, sign or scale, or a rate column fed from another state, fails.
    cls = REGISTRY[type_name]
    assert {c.unit for c in cls.COLUMNS} <= SI_UNITS, [(c.name, c.unit) for c in cls.COLUMNS]
    effects = tuple(e for e in ("earth_rotation", "centrifugal", "finite_amplitude") if e in cls.SUPPORTED_EFFECTS)
    t = np.arange(0.0, 4.0, 1.0 / 400.0)
    c = build(cls, SOUTH, effects).simulate(t).columns
    assert set(c) == {col.name for col in cls.COLUMNS}
    for col in cls.COLUMNS:
        v = np.asarray(c[col.name])
        assert v.shape == t.shape and np.all(np.isfinite(v)), col.name
        if col.unit == "1":
            assert np.all(np.abs(v) <= 1.0 + 1e-12), col.name
    for angle, rate in rate_pairs(cls):
        scale = max(np.max(np.abs(c[rate])), 1e-6)
        err = np.max(np.abs(inner(derivative(t, c[angle]) - c[rate])))
        assert err < 1e-6 * scale, (angle, rate, err, scale)


# ----------------------------------------------------------------------------- the meta-test

def test_every_channel_is_checked():
    # Issue 17: every reported channel of every instrument type is checked (puiseux's in
    # tests/test_puiseux*.py): by the generic test above, from its declaration, and where a physics
    # check reads it, by that check (issue 23: a new column needs no edit here, only an SI unit).
    missing = {name: sorted(c.name for c in cls.COLUMNS if c.unit not in SI_UNITS)
               for name, cls in REGISTRY.items() if name not in ELSEWHERE}
    missing = {k: v for k, v in missing.items() if v}
    assert not missing, f"channels the generic check cannot read (unit not SI): {missing}"
    # the rate rule finds the pairs it is meant for (so it can fail)
    assert rate_pairs(PlaneGyroscope) == [("angle", "angle_rate")]
    assert set(rate_pairs(GimbalGyroscope)) == {("outer_angle", "outer_rate"), ("inner_angle", "inner_rate")}
    stale = {name: sorted(cols - {c.name for c in REGISTRY[name].COLUMNS}) for name, cols in DECLARED.items()}
    assert not any(stale.values()), f"declared checks of channels that do not exist: {stale}"
