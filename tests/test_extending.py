"""docs/extending.md, done (issue 23 item 5): two new instruments and a new effect, defined in this
module only, registered and unregistered by a fixture, each through ``describe``, ``simulate``,
``estimate``, the recorder node of a real ROS run (the in-process suite, ``gyro-instrument run
--bag``) and ``replay`` of the bag it wrote.

* :class:`PendulousGyrocompass`: a marine (Anschütz-type) gyrocompass kept near the meridian by
  pendulosity P (N m), not by a directing plane. Its directing law is not Quet's: the restoring
  constant is K = P n cos γ / H with H = C ρ, so T = 2π √(H / (P n cos γ)) (physics notes, "A
  pendulous (Schuler-tuned) gyrocompass"): K ∝ 1/ρ where Quet's K ∝ ρ. Its observation
  (:class:`PendulousSwing`, a :class:`SwingRate` subclass) owns that law, and the estimator,
  knowing n, recovers the latitude from the swing within 4 σ over seeds, σ at its Cramér–Rao bound.
* :class:`TorsionPendulum`: a disc on a torsion wire, no rotor, θ'' = −(κ/I) θ + Σ damping / I;
  it measures no Earth rate and the estimate says so.
* :class:`NormalGravity`: gravity's latitude variation (International Gravity Formula 1980) as a
  conservative ``point_mass`` term on the spherical pendulum, which keeps its parareal fast path
  and lengthens the swing by √(g / g(γ)).
"""

import json
import math

import numpy as np
import pytest
import yaml

from gyro_instrument import api, effects, instruments
from gyro_instrument.cli import main
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.effect import CONSERVATIVE, DAMPING, FRAME_RATE, POINT_MASS, SPIN, Effect, Scales, bound_hooks
from gyro_instrument.core.integrate import integrate
from gyro_instrument.core.params import Param
from gyro_instrument.core.site import normal_gravity_m_s2
from gyro_instrument.effects.finite_amplitude import finite_amplitude_factor
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.instruments.base import Column, DirectingModel, ExpectedSwing, Instrument, Simulation
from gyro_instrument.instruments.observation import Observation, SwingRate
from gyro_instrument.scenes import build_instruments, scene_from_data

# ---------------------------------------------------------------------------------------------- (c) effect
def igf1980_m_s2(latitude_rad) -> float:
    """International Gravity Formula 1980 (normal gravity of the GRS80 ellipsoid, series form):
    g(γ) = 9.780327 (1 + 0.0053024 sin² γ − 0.0000058 sin² 2γ) m/s² (H. Moritz, "Geodetic Reference
    System 1980", Bulletin Géodésique 54 (1980) 395–405; the series is within 1e-6 m/s² of the
    closed form, Somigliana's, that ``core.site.normal_gravity_m_s2`` evaluates for WGS-84)."""
    s = math.sin(latitude_rad)
    return 9.780327 * (1.0 + 0.0053024 * s * s - 0.0000058 * math.sin(2.0 * latitude_rad) ** 2)


class NormalGravity(Effect):
    """Gravity's latitude variation: the site's stated g replaced by the normal gravity g(γ) at its latitude.

    A scene that states a reference gravity (``site.gravity_m_s2``, e.g. standard gravity 9.80665
    m/s²) and lists this effect swings its pendulum in g(γ) = :func:`igf1980_m_s2`: the point-mass
    term adds −(g(γ) − g) along the vertical (a uniform field: the gradient of the potential
    (g(γ) − g) z, so ``conservative``). The swing period scales by √(g / g(γ)).
    """

    name = "normal_gravity"
    summary = "gravity's latitude variation: International Gravity Formula 1980 at the site's latitude"
    MECHANICS = frozenset({POINT_MASS})
    CAPABILITIES = frozenset({CONSERVATIVE})

    @staticmethod
    def delta_m_s2(ctx) -> float:
        """g(γ) − g: the normal gravity at ``ctx.site``'s latitude less the context's g, m/s²."""
        return igf1980_m_s2(ctx.site.latitude_rad) - ctx.gravity_m_s2

    def relative_size(self, ctx) -> tuple:
        return abs(math.sqrt(ctx.gravity_m_s2 / (ctx.gravity_m_s2 + self.delta_m_s2(ctx))) - 1.0), \
            "|sqrt(g / g(latitude)) - 1| (relative change of the swing period)"

    def point_mass_term(self, ctx):
        """(0, 0, −(g(γ) − g)), m/s², at every point (arrays of the states' shape when batched)."""
        dg = self.delta_m_s2(ctx)

        def extra_gravity(dx, dy, dz, vx, vy, vz):
            zero = 0.0 * dx
            return zero, zero, zero - dg
        return extra_gravity


# ---------------------------------------------------------------------------------------------- (a) compass
class PendulousSwing(SwingRate):
    """The pendulous gyrocompass's directing law: K = (P/H + n cos γ) n cos γ, H = C ρ, so with
    gain = P/C the swing gives y = n cos γ from y² + y gain/ρ − K = 0 (K = (π/T0)², T0 the small
    swing's duration, half the period T = 2π √(H/(P n cos γ)) to first order in n H/P).

    Spin law: ω = √K ∝ ρ^(−1/2) (Quet's ∝ ρ^(1/2)); the azimuth is the coordinate q of the
    oscillator H = ½ (P n cos γ / H) p² + ½ q² (p = −β/(n cos γ), β the tilt), whose action E/ω is
    kept, so its amplitude goes as √ω ∝ ρ^(−1/4) — Quet's exponent for another reason. Amplitude
    law: the azimuth obeys α'' = −K sin α (to O(β², n H/P)): the pendulum's, inherited.
    """

    SPIN_EXPONENT = 1.0          # y ≈ K ρ / gain at a given T0

    def rate_from_swing(self, T0, rho_mean) -> tuple:
        K = (math.pi / T0) ** 2
        b = self.gain / abs(rho_mean)
        y = 2.0 * K / (b + math.sqrt(b * b + 4.0 * K))
        return y, (K / b) / y - 1.0

    def spin_frequency(self, ratio) -> np.ndarray:
        return 1.0 / np.sqrt(ratio)

    def spin_envelope(self, ratio) -> np.ndarray:
        return ratio ** -0.25


class PendulousGyrocompass(Instrument):
    """A pendulous gyrocompass: rotor of axial moment C spinning at ρ (H = C ρ) whose axis, of
    azimuth α (east of north) and tilt β (north end up), carries a pendulous mass (P = m g d, N m).

    Its motion is integrated from the gyroscopic (precession) equations: the axis a moves so that
    H ȧ = τ − H Ω × a, with τ = −P sin β (cos α, −sin α, 0) the pendulous torque; the rotor's
    transverse inertia is neglected (its nutation, at H/A, is far above the swing). In α, β::

        α' = n sin γ − (n cos γ cos α + P/H) tan β,    β' = n cos γ sin α,    C ρ' = Σ spin torques

    (n from the ``frame_rate`` effects; Arnold & Maunder, *Gyrodynamics*, 1961, ch. 13, small-angle
    form α'' = −(P n cos γ / H) α.)
    """

    type_name = "pendulous_gyrocompass"
    summary = "pendulous (Anschütz) gyrocompass: K = P n cos(latitude) / (C rho) (test of docs/extending.md)"
    PARAMS = (Param("pendulosity_n_m", default=20.0, low=0.0, open_low=True, doc="P = m g d, N m"),
              Param("axial_inertia_kg_m2", default=1.0e-4, low=0.0, open_low=True, doc="C, kg m^2"),
              Param("spin_rate_rad_s", default=100.0, low=-1.0e6, high=1.0e6,
                    doc="rho0, rad/s (H = C rho; negative: H toward the axis's south end, which then seeks north)"),
              Param("initial_azimuth_deg", default=5.0, low=-60.0, high=60.0,
                    doc="alpha0: the axis's azimuth east of north at release (level), degrees"))
    MECHANICS = frozenset({FRAME_RATE, SPIN})
    COLUMNS = (Column("azimuth", "rad", "alpha: the spin axis's azimuth, east of north"),
               Column("tilt", "rad", "beta: the spin axis's elevation (north end up)"),
               Column("spin_rate", "rad/s", "rho: the rotor's spin"))
    MEASURED_CHANNELS = ("azimuth",)
    JOINTS = ("azimuth", "rotor")
    OBSERVATION = PendulousSwing
    SIMULATOR_NODE = "gyrocompass_sim"

    @classmethod
    def check_params(cls, prefix, p) -> None:
        if p["spin_rate_rad_s"] == 0.0:
            raise SceneError(f"{prefix}.spin_rate_rad_s", 0.0, "must be nonzero: no angular momentum, no compass")

    def _H(self):
        """|H| = C |ρ|, N m s (either sense of spin: the end H points along seeks north)."""
        return self.p.axial_inertia_kg_m2 * abs(self.p.spin_rate_rad_s)

    def _K(self, n):
        """Restoring constant (rad/s)² at Earth rate n: (P/H + n cos γ) n cos γ."""
        nc = n * math.cos(self.site.latitude_rad)
        return (self.p.pendulosity_n_m / self._H() + nc) * nc

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, duration_s=duration_s,
                      restoring_rate_rad_s=math.sqrt(self._K(self.site.earth_rate_rad_s)),
                      gyro_rate_rad_s=self.p.pendulosity_n_m / self._H(),
                      amplitude_rad=abs(math.radians(self.p.initial_azimuth_deg)))

    def predictions(self) -> dict:
        """T = 2π √(H / (P n cos γ)) (the law) and the small swing's duration T0 = π/√K of the
        integrated equations (K with its n cos γ term); infinite without a frame rate."""
        n = self.model_earth_rate()
        nc = n * math.cos(self.site.latitude_rad)
        law = 2.0 * math.pi * math.sqrt(self._H() / (self.p.pendulosity_n_m * nc)) if nc > 0 else math.inf
        K = self._K(n)
        return {"period_law_s": law, "swing_duration_small_s": math.pi / math.sqrt(K) if K > 0 else math.inf}

    def expected_swing(self) -> ExpectedSwing | None:
        """Period 2 T0 F(α0) (the pendulum's amplitude factor) and amplitude α0; None without n."""
        T0 = self.predictions()["swing_duration_small_s"]
        a = abs(math.radians(self.p.initial_azimuth_deg))
        if not math.isfinite(T0):
            return None
        return ExpectedSwing(2.0 * T0 * finite_amplitude_factor(a), a, "pendulosity_n_m, C, rho and the latitude")

    def directing_model(self) -> DirectingModel:
        return DirectingModel(gain=self.p.pendulosity_n_m / self.p.axial_inertia_kg_m2, normal_enu=(0.0, 0.0, 1.0),
                              label="pendulous", angle_channel="azimuth", spin_rate_rad_s=self.p.spin_rate_rad_s,
                              null_reason="no directing torque at a pole (n cos(latitude) = 0)")

    def simulate(self, t, **options) -> Simulation:
        t = np.asarray(t, dtype=float)
        n = self.model_earth_rate()
        N, U = n * math.cos(self.site.latitude_rad), n * math.sin(self.site.latitude_rad)
        P, C = self.p.pendulosity_n_m, self.p.axial_inertia_kg_m2
        spin = bound_hooks(self.effects_of(SPIN), SPIN, self.context)

        def rhs(_, y):
            a, b, rho = y
            return np.array([U - (N * math.cos(a) + P / (C * rho)) * math.tan(b), N * math.sin(a),
                             sum(f(C, rho) for f in spin) / C])
        traj = integrate(rhs, [math.radians(self.p.initial_azimuth_deg), 0.0, self.p.spin_rate_rad_s], t,
                         rtol=1e-11, atol=1e-13)
        return Simulation(t, {"azimuth": traj.y[0], "tilt": traj.y[1], "spin_rate": traj.y[2]}, traj)


# ---------------------------------------------------------------------------------------------- (b) torsion
class TorsionPendulum(Instrument):
    """A disc of moment I on a torsion wire of constant κ: θ'' = −(κ/I) θ + Σ damping torques / I
    (Hooke's law in the twist: no finite-amplitude law, no rotor, no Earth rate)."""

    type_name = "torsion_pendulum"
    summary = "disc on a torsion wire, no rotor (test of docs/extending.md)"
    PARAMS = (Param("moment_of_inertia_kg_m2", default=2.0e-3, low=0.0, open_low=True, doc="I, kg m^2"),
              Param("torsion_constant_n_m_rad", default=5.0e-3, low=0.0, open_low=True, doc="kappa, N m/rad"),
              Param("initial_twist_deg", default=10.0, low=-180.0, high=180.0, doc="theta0, degrees"))
    MECHANICS = frozenset({DAMPING})
    COLUMNS = (Column("twist", "rad", "theta: the disc's twist from rest"),
               Column("twist_rate", "rad/s", "dtheta/dt"))
    MEASURED_CHANNELS = ("twist",)
    JOINTS = ("disc",)
    OBSERVATION = Observation
    SIMULATOR_NODE = "pendulum_sim"

    def _w0(self):
        return math.sqrt(self.p.torsion_constant_n_m_rad / self.p.moment_of_inertia_kg_m2)

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, duration_s=duration_s,
                      restoring_rate_rad_s=self._w0(), amplitude_rad=abs(math.radians(self.p.initial_twist_deg)))

    def predictions(self) -> dict:
        """T = 2π √(I/κ)."""
        return {"period_s": 2.0 * math.pi / self._w0()}

    def simulate(self, t, **options) -> Simulation:
        t = np.asarray(t, dtype=float)
        w0sq, inertia = self._w0() ** 2, self.p.moment_of_inertia_kg_m2
        damping = bound_hooks(self.effects_of(DAMPING), DAMPING, self.context)

        def rhs(_, y):
            th, thd = y
            return np.array([thd, -w0sq * th + sum(f(inertia, thd) for f in damping) / inertia])
        traj = integrate(rhs, [math.radians(self.p.initial_twist_deg), 0.0], t, rtol=1e-11, atol=1e-13)
        return Simulation(t, {"twist": traj.y[0], "twist_rate": traj.y[1]}, traj)


# ---------------------------------------------------------------------------------------------- scenes
LATITUDE_DEG = 48.8462

#: The pendulous compass alone. C = 1e-4 kg m², ρ = 100 rad/s (H = 0.01 N m s) and P = 20 N m make
#: H/P = 5e-4 s: T = 2π √(H/(P n cos γ)) = 20.3 s at Paris, so 200 s hold ten periods (a real
#: Schuler-tuned compass has 84.4 min). n H/P = 2.4e-8: its second-order term is below the σ.
COMPASS = {"name": "pendulous", "description": "a fast pendulous gyrocompass", "site": {"latitude_deg": LATITUDE_DEG},
           "duration_s": 200.0, "sample_rate_hz": 10.0, "seed": 1, "effects": {"earth_rotation": {}},
           "sensor": {"noise_rad": 1.0e-4}, "instruments": {"compass": {"type": "pendulous_gyrocompass"}}}

#: All three through one ROS run: the compass, the torsion pendulum (braked by pivot damping), and a
#: 1 m Foucault pendulum in standard gravity 9.80665 m/s² (CGPM 1901) with normal_gravity: g(γ) instead.
SUITE = {"name": "extending", "description": "a pendulous gyrocompass, a torsion pendulum, a Foucault pendulum",
         "site": {"latitude_deg": LATITUDE_DEG, "gravity_m_s2": 9.80665}, "duration_s": 60.0,
         "sample_rate_hz": 20.0, "seed": 3, "sensor": {"noise_rad": 1.0e-4}, "estimator": {"earth_rate": "known"},
         "effects": {"earth_rotation": {}, "finite_amplitude": {}, "normal_gravity": {},
                     "pivot_damping": {"time_constant_s": 600.0}},
         "instruments": {"compass": {"type": "pendulous_gyrocompass"},
                         "torsion": {"type": "torsion_pendulum"},
                         "pendulum": {"type": "spherical_pendulum", "length_m": 1.0, "initial_deflection_deg": 5.0}}}


@pytest.fixture(scope="module")
def registered():
    """Register the three classes (docs/extending.md, 'register'), unregister afterwards so the rest
    of the suite (generated docs, parametrised tests) sees the shipped registries only."""
    effects.register(NormalGravity)
    instruments.register(PendulousGyrocompass)
    instruments.register(TorsionPendulum)
    try:
        yield
    finally:
        instruments.unregister(TorsionPendulum.type_name)
        instruments.unregister(PendulousGyrocompass.type_name)
        effects.unregister(NormalGravity.name)


def _write(tmp_path, scene, name):
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(scene))
    return str(path)


@pytest.fixture()
def suite_file(registered, tmp_path):
    return _write(tmp_path, SUITE, "extending")


def test_registration(registered):
    assert NormalGravity.name in instruments.REGISTRY["spherical_pendulum"].SUPPORTED_EFFECTS
    # the shipped effects of their kinds are supported (others registered beside them may be too)
    assert {"earth_rotation", "spin_decay"} <= PendulousGyrocompass.SUPPORTED_EFFECTS
    assert "pivot_damping" in TorsionPendulum.SUPPORTED_EFFECTS
    for cls in (PendulousGyrocompass, TorsionPendulum):
        assert all(effects.REGISTRY[n].MECHANICS & cls.MECHANICS for n in cls.SUPPORTED_EFFECTS)
    assert instruments.Observation.layout_of(TorsionPendulum).rotor is None
    kinds = instruments.simulator_kinds()
    assert TorsionPendulum.type_name in kinds["pendulum_sim"]
    assert PendulousGyrocompass.type_name in kinds["gyrocompass_sim"]
    # the 1980 series against WGS-84's closed form (core/site.py): its rounded coefficients (9.780327
    # against 9.7803253359 at the equator) put it 1.3e-6 to 2.1e-6 m/s² above, 0.2 mGal at most
    for lat in np.linspace(0.0, 90.0, 19):
        lat = math.radians(lat)
        assert igf1980_m_s2(lat) - normal_gravity_m_s2(lat) == pytest.approx(1.7e-6, abs=5e-7)


def test_describe(suite_file):
    d = api.describe(api.load_scene(suite_file))
    ins = d["instruments"]
    assert ins["pendulum"]["integrator"]["chosen"] == "parareal"
    g, g_lat = 9.80665, igf1980_m_s2(math.radians(LATITUDE_DEG))
    e = ins["pendulum"]["effects"]["normal_gravity"]
    assert e["active"] and e["relative_size"] == pytest.approx(abs(math.sqrt(g / g_lat) - 1.0), rel=1e-12)
    assert ins["compass"]["predictions"]["period_law_s"] == pytest.approx(20.3, abs=0.1)
    assert ins["torsion"]["columns"] == ["torsion.twist [rad]", "torsion.twist_rate [rad/s]"]
    assert ins["torsion"]["predictions"]["period_s"] == pytest.approx(2 * math.pi * math.sqrt(2e-3 / 5e-3))


def _crossing_period(t, x):
    """Full period (s) from the zero crossings of ``x`` (linear interpolation), half a period apart."""
    i = np.nonzero(np.diff(np.sign(x)))[0]
    tc = t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])
    return 2.0 * (tc[-1] - tc[0]) / (tc.size - 1)


def test_the_compass_swings_at_its_own_law(registered):
    """The integrated motion swings in T = 2π √(H/(P n cos γ)) times the pendulum's amplitude factor
    (to n H/P = 2.4e-8), and twice the spin lengthens it by √2 (K ∝ 1/ρ; Quet's law would shorten it)."""
    t = np.linspace(0.0, 200.0, 20001)
    periods = []
    for spin in (100.0, 200.0):
        data = json.loads(json.dumps(COMPASS))
        data["instruments"]["compass"]["spin_rate_rad_s"] = spin
        inst = build_instruments(scene_from_data(data))["compass"]
        periods.append(_crossing_period(t, inst.simulate(t).columns["azimuth"]))
        law = inst.predictions()["period_law_s"] * finite_amplitude_factor(math.radians(5.0))
        assert periods[-1] == pytest.approx(law, rel=2e-6)
    assert periods[1] / periods[0] == pytest.approx(math.sqrt(2.0), rel=2e-6)
    # the spin reversed: H points along the axis's south end, the same swing about south (magnitudes unsigned)
    data["instruments"]["compass"]["spin_rate_rad_s"] = -200.0
    assert build_instruments(scene_from_data(data))["compass"].predictions() == inst.predictions()


def test_latitude_from_the_period_over_seeds(registered):
    """The compass's observation owns K ∝ 1/ρ: with n known the estimator's latitude is within 4 σ
    of the truth for every seed, σ is its Cramér–Rao bound (to 5 %), and the seeds' spread is σ.
    (300 seeds: mean pull −0.03, spread 1.02 σ; σ = 2.0e-4°.)"""
    scene = scene_from_data(COMPASS)
    truth = simulate_truth(scene)
    lat, sig = [], []
    for seed in range(12):
        r = estimate_records(scene, truth[1], measure(scene, truth, seed))
        assert r["earth_rate_known"] is True and r["carried_by"] == {"compass": 1.0}
        assert r["latitude_sigma_deg"] == pytest.approx(r["crlb"]["latitude_deg"], rel=0.05)
        lat.append(r["latitude_deg"])
        sig.append(r["latitude_sigma_deg"])
    lat, sig = np.array(lat), np.array(sig)
    assert np.all(np.abs(lat - LATITUDE_DEG) < 4.0 * sig)
    assert 0.5 < np.std(lat, ddof=1) / np.mean(sig) < 1.6         # 12 draws: the ratio's 2.5-97.5 % range


def _pendulum_only(*effect_names):
    data = json.loads(json.dumps(SUITE))
    data["instruments"] = {"pendulum": SUITE["instruments"]["pendulum"]}
    data["effects"] = {k: SUITE["effects"].get(k, {}) for k in effect_names}
    return scene_from_data(data)


def test_normal_gravity_keeps_the_fast_path_and_lengthens_the_swing(registered):
    """A conservative point-mass term keeps the pendulum on parareal (its capability, not its name,
    decides; a dissipative one does not) and changes the swing period by √(g / g(γ)) − 1 = −1.4e-4."""
    base = ("earth_rotation", "finite_amplitude")
    t = np.arange(0.0, 30.0, 0.01)
    period = {}
    for names in (base, base + ("normal_gravity",)):
        inst = build_instruments(_pendulum_only(*names))["pendulum"]
        assert inst.chosen_integrator(30.0)[0] == "parareal"
        sim = inst.simulate(t)
        period[names[-1]] = (sim.extra["period_s"], _crossing_period(t, sim.columns["x_east"]))
    g, g_lat = 9.80665, igf1980_m_s2(math.radians(LATITUDE_DEG))
    ratio = math.sqrt(g / g_lat)
    assert period["normal_gravity"][0] / period["finite_amplitude"][0] == pytest.approx(ratio, rel=1e-10)
    assert period["normal_gravity"][1] / period["finite_amplitude"][1] == pytest.approx(ratio, rel=1e-8)
    dissipative = build_instruments(_pendulum_only(*base, "normal_gravity", "air_drag"))["pendulum"]
    assert dissipative.chosen_integrator(30.0) == ("adaptive", "auto: parareal is for a conservative swing; "
                                                               "air_drag listed")


def test_simulate_and_estimate_through_the_cli(suite_file, tmp_path, capsys):
    out = tmp_path / "sim.csv"
    assert main(["simulate", suite_file, "--out", str(out), "--quiet"]) == 0
    header = out.read_text().splitlines()[0]
    for column in ("compass.azimuth", "compass.spin_rate", "torsion.twist", "pendulum.x_east"):
        assert column in header
    capsys.readouterr()
    assert main(["estimate", suite_file, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["instruments"]["compass"]["type"] == PendulousGyrocompass.type_name
    assert r["carried_by"]["compass"] > 0.999
    assert r["latitude_deg"] == pytest.approx(LATITUDE_DEG, abs=4.0 * r["latitude_sigma_deg"])
    assert "no Earth-rate measurement" in r["instruments"]["torsion"]["reason"]


def _torsion_only():
    data = json.loads(json.dumps(SUITE))
    data["instruments"] = {"torsion": SUITE["instruments"]["torsion"]}
    data["effects"] = {"pivot_damping": SUITE["effects"]["pivot_damping"]}
    return data


def test_the_torsion_pendulum_alone_says_it_measures_no_earth_rate(registered, tmp_path, capsys):
    data = _torsion_only()
    path = _write(tmp_path, data, "torsion")
    assert main(["estimate", path, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["latitude_deg"] is None and r["earth_rate_rad_s"] is None
    assert "no Earth-rate measurement" in r["reason"]
    # braked by pivot_damping (torque -(2/tau) I dθ/dt): θ = θ0 e^(-t/tau) (cos ωd t + sin(ωd t)/(ωd tau)),
    # ωd = √(κ/I − 1/tau²), the damped oscillator's closed form
    t = np.linspace(0.0, 60.0, 601)
    th = build_instruments(scene_from_data(data))["torsion"].simulate(t).columns["twist"]
    tau, wd = 600.0, math.sqrt(5e-3 / 2e-3 - 1.0 / 600.0 ** 2)
    exact = math.radians(10.0) * np.exp(-t / tau) * (np.cos(wd * t) + np.sin(wd * t) / (wd * tau))
    assert np.max(np.abs(th - exact)) < 1e-9


@pytest.mark.ros      # starts the ROS suite (rclpy and DDS, on loopback)
def test_recorder_node_and_replay(suite_file, tmp_path, capsys):
    """``gyro-instrument run SCENE --bag`` (the suite in this process, so the node classes see the
    registered types): the recorder node writes every instrument's joints, and ``replay`` of the bag
    gives the live estimate."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.ros.cli import main as run_main
    bag = str(tmp_path / "extending.mcap")
    capsys.readouterr()
    assert run_main(["run", suite_file, "--bag", bag, "--json", "--quiet"]) == 0
    live = json.loads(capsys.readouterr().out)
    topics = {}
    for topic, _, _, _ in read_messages(bag):
        topics[topic] = topics.get(topic, 0) + 1
    names = ("compass", "torsion", "pendulum")
    for name in names:
        assert topics[f"/{name}/joint_states"] == 1201
    first = {topic: data for topic, _, _, data in read_messages(bag, [f"/{n}/joint_states" for n in names])}
    assert {t: tuple(deserialize_message(d, JointState).name) for t, d in first.items()} == {
        "/compass/joint_states": ("compass/azimuth", "compass/rotor"), "/torsion/joint_states": ("torsion/disc",),
        "/pendulum/joint_states": tuple(f"pendulum/{j}" for j in instruments.REGISTRY["spherical_pendulum"].JOINTS)}
    replayed = api.replay_bag(bag)
    assert live["earth_rate_known"] is True and live["carried_by"]["compass"] > 0.999
    assert live["latitude_deg"] == pytest.approx(LATITUDE_DEG, abs=4.0 * live["latitude_sigma_deg"])
    for key in ("latitude_deg", "latitude_sigma_deg", "earth_rate_rad_s", "crlb"):
        assert replayed[key] == live[key]
    assert replayed["instruments"]["compass"] == live["instruments"]["compass"]
    assert replayed["instruments"]["pendulum"] == live["instruments"]["pendulum"]


@pytest.mark.ros      # starts the ROS suite (rclpy and DDS, on loopback)
def test_a_torsion_pendulum_run_records_and_replays_without_an_earth_rate(registered, tmp_path, capsys):
    """A scene of the torsion pendulum alone through the recorder node and ``replay``: its twist is
    recorded, and both estimates say there is no Earth-rate measurement (latitude null, no failure)."""
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import JointState
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.ros.cli import main as run_main
    path = _write(tmp_path, _torsion_only(), "torsion")
    bag = str(tmp_path / "torsion.mcap")
    capsys.readouterr()
    assert run_main(["run", path, "--bag", bag, "--json", "--quiet"]) == 0
    live = json.loads(capsys.readouterr().out)
    twist = [deserialize_message(d, JointState).position[0]
             for _, _, _, d in read_messages(bag, ["/torsion/joint_states"])]
    assert len(twist) == 1201 and twist[0] == pytest.approx(math.radians(10.0), abs=5e-4)     # 1e-4 rad noise
    replayed = api.replay_bag(bag)
    for r in (live, replayed):
        assert r["latitude_deg"] is None and r["earth_rate_rad_s"] is None
        assert r["reason"].startswith("no Earth-rate measurement")
