"""The observation protocol (gyro_instrument/instruments/observation.py): one joint layout written and
read back, registration checked against the observation's layout (a torsion pendulum without a rotor
registers), and a directing law that is the observation's, not the estimator's."""

import math

import numpy as np
import pytest

from gyro_instrument import instruments
from gyro_instrument.core.params import Param
from gyro_instrument.instruments.base import Column, DirectingModel, Instrument
from gyro_instrument.instruments.observation import Observation, SwingRate
from gyro_instrument.scenes import build_instruments, load_scene


class TorsionPendulum(Instrument):
    """A disc on a torsion wire: one twist angle, no rotor (its joints are its measured channel only)."""

    type_name = "torsion_pendulum_test"
    summary = "disc on a torsion wire (test)"
    PARAMS = (Param("period_s", default=10.0, low=0.0, open_low=True, doc="T"),)
    COLUMNS = (Column("twist", "rad", "twist angle"),)
    MEASURED_CHANNELS = ("twist",)
    JOINTS = ("disc",)
    OBSERVATION = Observation
    SIMULATOR_NODE = "gyrocompass_sim"


def test_a_torsion_pendulum_without_a_rotor_registers():
    instruments.register(TorsionPendulum)
    try:
        assert Observation.layout_of(TorsionPendulum).rotor is None
    finally:
        instruments.unregister(TorsionPendulum.type_name)


def test_register_checks_the_observations_layout():
    bad = type("BadJoints", (TorsionPendulum,), {"type_name": "bad_joints_test", "JOINTS": ("disc", "rotor")})
    with pytest.raises(ValueError, match="JOINTS"):
        instruments.register(bad)
    bad = type("BadColumns", (TorsionPendulum,), {"type_name": "bad_columns_test", "MEASURED_CHANNELS": ("tilt",),
                                                  "JOINTS": ("tilt",)})
    with pytest.raises(ValueError, match="columns"):
        instruments.register(bad)
    assert "bad_joints_test" not in instruments.REGISTRY and "bad_columns_test" not in instruments.REGISTRY


@pytest.mark.parametrize("scene", ["quet_gyroscopes", "foucault_pantheon", "gimbal_paris", "free_gyroscope", "puiseux_spheroid"])
def test_rows_written_are_read_back(scene):
    # one definition: what joint_rows lays out, joint_record reads back (measured channels, spin)
    for inst in build_instruments(load_scene(scene, ["duration_s=5"])).values():
        obs = inst.observation()
        t = np.linspace(0.0, 1.0, 7)
        rec = {"t": t} | {c: 0.01 * (j + 1) * np.sin(t) for j, c in enumerate(obs.layout.measured)}
        if obs.spin_channel:
            rec[obs.spin_channel] = np.full(t.size, 600.0)
        rated, spin = obs.joint_rows(rec)
        pos = np.column_stack(rated + ([np.zeros_like(t)] if spin is not None else []))
        vel = np.column_stack([np.gradient(c, t) for c in rated] + ([spin] if spin is not None else []))
        assert pos.shape[1] == len(obs.layout.names) == len(inst.JOINTS)
        back = obs.joint_record(t, pos, vel)
        for c in obs.layout.measured + ((obs.spin_channel,) if obs.spin_channel else ()):
            assert np.array_equal(back[c], rec[c]), (scene, c)


class _Pendulous(SwingRate):
    """A pendulous gyrocompass's law: K = P n cos γ / (C ρ), so y = K ρ / gain with gain = P/C."""

    SPIN_EXPONENT = 1.0

    def rate_from_swing(self, T0, rho_mean):
        return (math.pi / T0) ** 2 * rho_mean / self.gain, None

    def spin_frequency(self, ratio):
        return 1.0 / np.sqrt(ratio)


def test_the_directing_law_is_the_observations():
    # T = 2π √(H/(P n cos γ)), H = C ρ: the swing duration T0 = T/2 gives back n cos γ through the
    # subclass's law; Quet's law (K ∝ ρ) would give a rate off by the factor ρ²/gain² instead.
    inst = build_instruments(load_scene("quet_gyroscopes", ["duration_s=5"]))["gyro_horizontal"]
    C, P, rho, n, lat = 0.01, 2.0e-3, 2 * math.pi * 400, 7.292115e-5, math.radians(48.8462)
    model = DirectingModel(gain=P / C, normal_enu=(0.0, 0.0, 1.0), label="horizontal", angle_channel="angle",
                           null_reason="")
    T0 = math.pi * math.sqrt(C * rho / (P * n * math.cos(lat)))
    y, _ = _Pendulous(inst, model).rate_from_swing(T0, rho)
    assert y == pytest.approx(n * math.cos(lat), rel=1e-12)
    r = _Pendulous(inst, model).measured_rate(T0, 1e-3 * T0, 1e-3 * T0, rho)
    assert r.sigma == pytest.approx(2e-3 * y, rel=1e-12)
    assert SwingRate(inst, model).rate_from_swing(T0, rho)[0] != pytest.approx(y, rel=1e-3)
