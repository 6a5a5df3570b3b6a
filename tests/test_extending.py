"""docs/extending.md, done (issue 12 part 5): a minimal extra effect and a minimal extra instrument,
defined here and registered, go through ``describe``, ``simulate``, ``estimate``, the recorder's
bag layout and ``replay`` without any other file of the package knowing them.

* ``EddyBrake``: a magnetic eddy-current brake on swinging hinges, torque −(J/τ) q̇ (amplitude
  e-folding in 2τ) — a ``damping`` term, so every instrument summing damping terms supports it.
* ``MinimalGyrocompass``: a horizontal gyrocompass of one joint (Quet sec. 4 §1 eq. 2 with a
  constant spin, the plane ``oz`` vertical): ü = −μ n cos γ ρ0 g(u) + Σ damping torques / A, with
  g the restoring law (sin u with ``finite_amplitude``, u otherwise) and n from the ``frame_rate``
  effects; its directing model is the plane gyroscope's (gain μ, normal up).
"""

import json
import math

import numpy as np
import pytest
import yaml

from gyro_instrument import effects, instruments
from gyro_instrument.cli import describe, main, replay_bag, simulate_scene
from gyro_instrument.core.effect import DAMPING, FRAME_RATE, RESTORING_LAW, Effect, Scales, bound_hooks
from gyro_instrument.core.integrate import integrate
from gyro_instrument.core.params import Param
from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.estimators.pipeline import estimable, estimate_records, simulate_truth
from gyro_instrument.instruments.base import Column, DirectingModel, Instrument, Simulation
from gyro_instrument.scenes import build_instruments, load_scene


class EddyBrake(Effect):
    """Eddy-current brake: torque −(J/τ) q̇ on every swinging hinge (amplitude e-folding in 2τ)."""

    name = "eddy_brake"
    summary = "magnetic eddy-current brake on the swinging hinges (time constant tau)"
    PARAMS = (Param("time_constant_s", default=600.0, low=0.0, open_low=True,
                    doc="tau: the brake torque is -(J/tau) times the hinge rate"),)
    MECHANICS = frozenset({DAMPING})

    def relative_size(self, ctx):
        return ctx.scales.duration_s / (2.0 * self.p.time_constant_s), "duration / (2 tau) (amplitude lost)"

    def damping_torque(self, ctx, inertia, rate):
        return -inertia * rate / self.p.time_constant_s


class MinimalGyrocompass(Instrument):
    """Horizontal gyrocompass, one joint, constant spin (Quet sec. 4 §1 eq. 2)."""

    type_name = "minimal_gyrocompass"
    summary = "one-joint horizontal gyrocompass with constant spin (test of docs/extending.md)"
    PARAMS = (Param("inertia_ratio", default=2.0, low=0.0, high=2.0, open_low=True, doc="mu = C/A"),
              Param("transverse_inertia_kg_m2", default=1.0e-3, low=0.0, open_low=True, doc="A, kg m^2"),
              Param("spin_rate_rad_s", default=2 * math.pi * 100.0, low=0.0, open_low=True, doc="rho0, rad/s"),
              Param("initial_angle_deg", default=5.0, low=-90.0, high=90.0, doc="u0, degrees"))
    MECHANICS = frozenset({FRAME_RATE, DAMPING, RESTORING_LAW})
    COLUMNS = (Column("angle", "rad", "u: axis angle from north, counter-clockwise seen from above"),
               Column("angle_rate", "rad/s", "du/dt"),
               Column("spin_rate", "rad/s", "rho: the rotor's (constant) spin"))
    MEASURED_CHANNELS = ("angle",)
    JOINTS = ("axis", "rotor")
    SIMULATOR_NODE = "gyrocompass_sim"

    def _K(self):
        return self.p.inertia_ratio * self.model_earth_rate() * math.cos(self.site.latitude_rad) * self.p.spin_rate_rad_s

    def scales(self, duration_s):
        K = self.p.inertia_ratio * self.site.earth_rate_rad_s * math.cos(self.site.latitude_rad) * self.p.spin_rate_rad_s
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, gyro_rate_rad_s=self.p.inertia_ratio
                      * self.p.spin_rate_rad_s, restoring_rate_rad_s=math.sqrt(K),
                      amplitude_rad=math.radians(abs(self.p.initial_angle_deg)), duration_s=duration_s)

    def predictions(self):
        K = self._K()
        return {"swing_duration_small_s": math.pi / math.sqrt(K) if K > 0 else math.inf}

    def directing_model(self):
        return DirectingModel(gain=self.p.inertia_ratio, normal_enu=(0.0, 0.0, 1.0), label="horizontal",
                              angle_channel="angle", null_reason="no restoring torque at a pole")

    def simulate(self, t, **options):
        t = np.asarray(t, dtype=float)
        K, A = self._K(), self.p.transverse_inertia_kg_m2
        law = self.restoring_law() or (lambda u: u)
        damping = bound_hooks(self.effects_of(DAMPING), DAMPING, self.context)

        def rhs(_, y):
            u, ud = y
            return np.array([ud, -K * law(u) + sum(f(A, ud) for f in damping) / A])
        traj = integrate(rhs, [math.radians(self.p.initial_angle_deg), 0.0], t, rtol=1e-11, atol=1e-13)
        return Simulation(t, {"angle": traj.y[0], "angle_rate": traj.y[1],
                              "spin_rate": np.full(t.size, self.p.spin_rate_rad_s)}, traj)


SCENE = {"name": "extending", "description": "a minimal gyrocompass and a meridian plane gyroscope, braked",
         "site": {"latitude_deg": 48.8462}, "duration_s": 120.0, "sample_rate_hz": 20.0, "seed": 4,
         "effects": {"earth_rotation": {}, "finite_amplitude": {}, "eddy_brake": {"time_constant_s": 600.0}},
         "sensor": {"noise_rad": 1.0e-5},
         "instruments": {"compass": {"type": "minimal_gyrocompass"},
                         "meridian": {"type": "plane_gyroscope", "plane": "meridian", "inertia_ratio": 2.0,
                                      "spin_rate_rad_s": 628.3185307179586, "initial_angle_deg": 5.0}}}


@pytest.fixture(scope="module")
def registered():
    """Register the two classes (docs/extending.md step 'register'), unregister afterwards so the
    rest of the suite (generated docs, parametrised tests) sees the shipped registries only."""
    effects.register(EddyBrake)
    instruments.register(MinimalGyrocompass)
    try:
        yield
    finally:
        instruments.unregister(MinimalGyrocompass.type_name)
        effects.unregister(EddyBrake.name)


@pytest.fixture()
def scene_file(registered, tmp_path):
    path = tmp_path / "extending.yaml"
    path.write_text(yaml.safe_dump(SCENE))
    return str(path)


def test_registration_declares_support_from_the_kinds(registered):
    assert "eddy_brake" in instruments.REGISTRY["plane_gyroscope"].SUPPORTED_EFFECTS      # sums damping
    assert "eddy_brake" in instruments.REGISTRY["gimbal_gyroscope"].SUPPORTED_EFFECTS
    assert "eddy_brake" not in instruments.REGISTRY["spherical_pendulum"].SUPPORTED_EFFECTS
    assert MinimalGyrocompass.SUPPORTED_EFFECTS == {"earth_rotation", "pivot_damping", "finite_amplitude",
                                                   "eddy_brake"}
    assert "minimal_gyrocompass" in instruments.simulator_kinds()["gyrocompass_sim"]
    with pytest.raises(ValueError, match="already registered"):
        effects.register(EddyBrake)


def test_describe_shows_the_effect_active_with_its_size(scene_file):
    d = describe(load_scene(scene_file))
    for name in ("compass", "meridian"):
        e = d["instruments"][name]["effects"]["eddy_brake"]
        assert e["active"] is True and e["relative_size"] == pytest.approx(0.1)
    assert d["instruments"]["compass"]["columns"] == ["compass.angle [rad]", "compass.angle_rate [rad/s]",
                                                      "compass.spin_rate [rad/s]"]


def test_the_new_effect_changes_what_it_says_on_both_instruments(scene_file):
    """Leaving the brake out changes each instrument's angle by at least 1/5 of describe's size
    relative to the swing's range (the bound of tests/test_effect_sizes.py); the plane gyroscope
    integrates its hinge chain since its hand-derived path does not know the brake."""
    with_ = load_scene(scene_file)
    without = load_scene(scene_file, ["effects.eddy_brake=null"])
    _, cols_with, sims = simulate_scene(with_)
    _, cols_without, _ = simulate_scene(without)
    assert sims["meridian"].extra["model"] == "chain"
    for name in ("compass", "meridian"):
        a, b = cols_with[f"{name}.angle"], cols_without[f"{name}.angle"]
        assert np.max(np.abs(a - b)) / np.ptp(a) >= 0.2 * 0.1


def test_simulate_and_estimate_through_the_cli(scene_file, tmp_path, capsys):
    out = tmp_path / "sim.csv"
    assert main(["simulate", scene_file, "--out", str(out), "--quiet"]) == 0
    assert "compass.angle" in out.read_text().splitlines()[0]
    assert main(["estimate", scene_file, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["instruments"]["compass"]["type"] == "minimal_gyrocompass"
    # Quet's item 9 from the new horizontal compass and the shipped meridian gyroscope: the brake and
    # the finite amplitude are corrected by the fit (damped sine, (2/pi) K(sin(a/2))); |latitude| to 0.05 deg
    assert r["methods"]["item9"]["latitude_deg"] == pytest.approx(48.8462, abs=0.05)


def test_recorded_and_replayed(scene_file, tmp_path):
    """The recorder's layout (the joints each class declares, JointState over CDR in MCAP, the scene
    as metadata), then ``replay``: the same estimate as the live joint streams give."""
    from rclpy.serialization import serialize_message
    from gyro_instrument.recording.joints import joint_streams, records_from_joints
    from gyro_instrument.recording.mcap_io import BagWriter, qos_yaml
    from gyro_instrument.ros import messages as m
    from gyro_instrument.recording.topics import joint_topic, scene_topics
    scene = load_scene(scene_file)
    insts = build_instruments(scene)
    t_ns, streams = joint_streams(scene, truth=simulate_truth(scene))
    assert streams["compass"].names == ("compass/axis", "compass/rotor")
    path = tmp_path / "extending.mcap"
    w = BagWriter(str(path))
    w.add_metadata("gyro_instrument", {"scene_yaml": json.dumps(dict(scene.raw)), "scene": scene.name,
                                       "seed": scene.seed, "command": "tests/test_extending.py"})
    for topic, type_name in scene_topics(insts).items():
        w.add_topic(topic, type_name, qos_yaml(reliable=True, keep_all=False, depth=1000))
    for i, tn in enumerate(t_ns):
        for name, s in streams.items():
            w.write(joint_topic(name), EPOCH_NS + int(tn), serialize_message(
                m.joint_state(int(tn), s.names, s.position[i], s.velocity[i], s.effort[i])))
    w.close()
    live = estimate_records(scene, {n: insts[n] for n in streams if estimable(insts[n])},
                            records_from_joints(insts, {n: (t_ns, s.position, s.velocity)
                                                        for n, s in streams.items()}))
    replayed = replay_bag(str(path))
    assert replayed["latitude_deg"] is not None
    for key in ("latitude_deg", "latitude_sigma_deg", "earth_rate_rad_s"):
        assert replayed[key] == live[key]
    assert replayed["instruments"]["compass"]["swing_duration_s"] == live["instruments"]["compass"]["swing_duration_s"]
