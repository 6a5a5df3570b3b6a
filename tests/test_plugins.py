"""Plug-ins, the Python way (issue 35 item 2): a package of its own, built here in a temporary
directory (a ``*.dist-info/entry_points.txt`` and its modules on ``PYTHONPATH``; nothing is installed,
no file of gyro_instrument is edited), adds an instrument, an effect and a measurement kind through
the entry-point groups ``gyro_instrument.instruments``, ``gyro_instrument.effects`` and
``gyro_instrument.measurements``; ``describe``, ``simulate``, ``estimate``, ``plan``, ``run --bag``
and ``replay`` of a scene using them run as separate processes, as a user runs them
(docs/extending.md tells this test for a person).

The package, ``gyro_rig_demo``:

* the instrument ``rate_integrating_gyro``: a single-axis rate-integrating gyroscope on a fixed mount,
  its input axis vertical; its gimbal angle integrates the rate about that axis, θ(t) = θ0 + Ω_up t,
  Ω_up = Σ frame rates · sin γ (the Earth's rotation seen along the local vertical, Quet 1853 sec. 2
  §III: the same component as the Foucault rate). It sums the ``frame_rate`` terms of its effects.
* the effect ``length_of_day``: a day longer than the sidereal one by ΔLOD (IERS Bulletin A: 1–3 ms
  in recent decades) turns the Earth-fixed frame at n (1 − ΔLOD n / 2π); a ``frame_rate`` term.
* the measurement kind ``vertical_rate``: the least-squares slope of θ(t), k = n sin γ, σ² = σ_θ² /
  Σ(t − t̄)² — for a straight line in white noise also the Cramér–Rao bound (the linear model's Fisher
  information is exact) — and the planner's bound σ_k(T) = σ_θ √12 / (Δt √(N (N² − 1))), N = ⌊T f⌋ + 1.
"""

import json
import math
import os
import subprocess
import sys
import textwrap

import pytest
import yaml

LATITUDE_DEG = 48.8462
EARTH_RATE = 7.292115e-5                       # IERS conventional n, rad/s (the scenes' default)
NOISE_RAD = 1.0e-6

ENTRY_POINTS = """\
[gyro_instrument.instruments]
rate_integrating_gyro = gyro_rig_demo.instrument:RateIntegratingGyro

[gyro_instrument.effects]
length_of_day = gyro_rig_demo.effect:LengthOfDay

[gyro_instrument.measurements]
vertical_rate = gyro_rig_demo.kind:VerticalRate
"""

INSTRUMENT = '''
"""A rate-integrating gyroscope, input axis vertical: theta(t) = theta0 + (sum of frame rates) sin(latitude) t."""
import math

import numpy as np

from gyro_instrument.core.effect import FRAME_RATE, Scales, bound_hooks
from gyro_instrument.core.params import Param
from gyro_instrument.core.trajectory import Trajectory
from gyro_instrument.instruments.base import Column, Instrument, Simulation
from gyro_instrument.instruments.observation import Observation


class RateIntegration(Observation):
    """The gimbal angle (rad) integrating the rate about the vertical: the kind vertical_rate."""

    MEASUREMENT = "vertical_rate"


class RateIntegratingGyro(Instrument):
    """Single-axis rate-integrating gyroscope on a fixed mount, input axis along the local vertical."""

    type_name = "rate_integrating_gyro"
    summary = "rate-integrating gyroscope, input axis vertical (plug-in gyro_rig_demo)"
    PARAMS = (Param("initial_angle_deg", default=0.0, low=-180.0, high=180.0, doc="theta0, degrees"),)
    MECHANICS = frozenset({FRAME_RATE})
    COLUMNS = (Column("angle", "rad", "theta: the gimbal angle"), Column("angle_rate", "rad/s", "dtheta/dt"))
    MEASURED_CHANNELS = ("angle",)
    JOINTS = ("gimbal",)
    OBSERVATION = RateIntegration
    SIMULATOR_NODE = "gyrocompass_sim"

    def vertical_rate_rad_s(self) -> float:
        """Omega_up = (sum of the frame rates) sin(latitude), rad/s."""
        n = sum(f() for f in bound_hooks(self.effects_of(FRAME_RATE), FRAME_RATE, self.context))
        return n * math.sin(self.site.latitude_rad)

    def scales(self, duration_s) -> Scales:
        return Scales(earth_rate_rad_s=self.site.earth_rate_rad_s, duration_s=duration_s)

    def predictions(self) -> dict:
        return {"vertical_rate_rad_s": self.vertical_rate_rad_s()}

    def simulate(self, t, **options) -> Simulation:
        t = np.asarray(t, dtype=float)
        w = self.vertical_rate_rad_s()
        angle = math.radians(self.p.initial_angle_deg) + w * t
        rate = np.full_like(t, w)
        return Simulation(t, {"angle": angle, "angle_rate": rate},
                          Trajectory(t, np.vstack([angle, rate]), 0, 0.0, 0.0, "closed form"))
'''

EFFECT = '''
"""The length of day: the Earth-fixed frame turns at n (1 - dLOD n / 2 pi)."""
import math

from gyro_instrument.core.effect import CONSERVATIVE, FRAME_RATE, Effect
from gyro_instrument.core.params import Param


class LengthOfDay(Effect):
    """A day longer than the sidereal day 2 pi / n by dLOD (IERS Bulletin A, 1-3 ms): frame rate -n^2 dLOD / 2 pi."""

    name = "length_of_day"
    summary = "the day's excess length: the Earth turns at n (1 - dLOD n / 2 pi)"
    PARAMS = (Param("excess_s", default=2.0e-3, low=-0.01, high=0.01, doc="dLOD, s"),)
    MECHANICS = frozenset({FRAME_RATE})
    CAPABILITIES = frozenset({CONSERVATIVE})

    def relative_size(self, ctx) -> tuple:
        n = ctx.site.earth_rate_rad_s
        return abs(self.p.excess_s) * n / (2.0 * math.pi), "|dLOD| n / (2 pi) (relative change of the Earth rate)"

    def frame_rate_rad_s(self, ctx) -> float:
        n = ctx.site.earth_rate_rad_s
        return -n * n * self.p.excess_s / (2.0 * math.pi)
'''

KIND = '''
"""The measurement kind vertical_rate: the slope of an integrated angle."""
import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.estimators.latitude import RateMeasurement
from gyro_instrument.instruments.measurement import MeasurementKind

UP = (0.0, 0.0, 1.0)


@dataclass
class VerticalRateModel:
    """What the planner knows: the rate k = n sin(latitude) (rad/s) along the vertical axis."""

    name: str
    kind: str
    value: float
    min_record_s: float
    geometry: tuple = UP
    axis: bool = True


class VerticalRate(MeasurementKind):
    """k = n sin(latitude) from the least-squares slope of the gimbal angle."""

    name = "vertical_rate"
    summary = "rate about the vertical, n sin(latitude), rad/s, from the integrated angle"
    RATE = True
    UNIT = "rad/s"

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        t, a = np.asarray(rec["t"], dtype=float), np.asarray(rec[obs.layout.measured[0]], dtype=float)
        ok = np.isfinite(t) & np.isfinite(a)
        t, a = t[ok], a[ok]
        if t.size < 3:
            return {"type": obs.type_name, "vertical_rate_rad_s": None, "reason": "fewer than 3 samples"}, None
        tc = t - t.mean()
        sxx = float(tc @ tc)
        k = float(tc @ (a - a.mean()) / sxx)
        noise = sensor.effective_sigma_rad() if sensor is not None else 0.0
        resid = a - a.mean() - k * tc
        sigma_theta = noise if noise > 0 else float(np.sqrt(resid @ resid / (t.size - 2)))
        sigma = max(sigma_theta / math.sqrt(sxx), 1e-150)
        entry = {"type": obs.type_name, "vertical_rate_rad_s": k, "vertical_rate_sigma_rad_s": sigma,
                 "crlb_vertical_rate_rad_s": sigma, "samples": int(t.size)}
        return entry, RateMeasurement(obs.name, self.name, k, sigma, UP, True, sigma, axis=True)

    def probe(self, scene, obs) -> tuple:
        k = obs.instrument.vertical_rate_rad_s()
        return VerticalRateModel(obs.name, self.name, k, 2.0 / scene.sample_rate_hz), None

    def bound(self, model, T, sensor) -> tuple:
        n = math.floor(T * sensor.rate_hz + 1e-9) + 1
        keep = 1.0 - sensor.dropout_fraction
        if n < 3:
            return math.inf, "too few samples"
        dt = 1.0 / sensor.rate_hz
        return sensor.sigma_rad * math.sqrt(12.0 / keep) / (dt * math.sqrt(n * (n * n - 1.0))), "straight-line slope"

    def tracker(self, obs, scene, companions):
        return None
'''


def scene(duration_s=60.0, **extra) -> dict:
    """The plug-in's scene: the gyroscope alone at Paris, the Earth's rotation and the day's length."""
    out = {"name": "rig_demo", "description": "a rate-integrating gyroscope from the plug-in gyro_rig_demo",
           "site": {"latitude_deg": LATITUDE_DEG}, "duration_s": duration_s, "sample_rate_hz": 10.0, "seed": 2,
           "sensor": {"noise_rad": NOISE_RAD}, "estimator": {"earth_rate": "known"},
           "effects": {"earth_rotation": {}, "length_of_day": {"excess_s": 2.0e-3}},
           "instruments": {"rig": {"type": "rate_integrating_gyro"}}}
    out.update(extra)
    return out


def write_package(root, entry_points=ENTRY_POINTS, modules=None) -> str:
    """The package ``gyro_rig_demo`` under ``root`` with its dist-info; returns ``root``."""
    pkg = root / "gyro_rig_demo"
    pkg.mkdir(parents=True, exist_ok=True)
    (pkg / "__init__.py").write_text('"""gyro_rig_demo: a plug-in of gyro_instrument (tests/test_plugins.py)."""\n')
    for name, src in (modules or {"instrument": INSTRUMENT, "effect": EFFECT, "kind": KIND}).items():
        (pkg / f"{name}.py").write_text(textwrap.dedent(src))
    info = root / "gyro_rig_demo-0.1.dist-info"
    info.mkdir(exist_ok=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: gyro-rig-demo\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(entry_points)
    return str(root)


def cli(args, path, module="gyro_instrument.cli") -> subprocess.CompletedProcess:
    """``python -m <module> ARGS`` with the plug-in directory ``path`` on PYTHONPATH."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (path, env.get("PYTHONPATH")) if p)
    return subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True, env=env,
                          timeout=600)


@pytest.fixture(scope="module")
def plugin(tmp_path_factory):
    root = tmp_path_factory.mktemp("plugin")
    path = write_package(root)
    scene_file = root / "rig_demo.yaml"
    scene_file.write_text(yaml.safe_dump(scene()))
    return path, str(scene_file)


def test_the_groups_list_the_shipped_ones_and_the_plugins():
    """The installed package's metadata lists every shipped instrument, effect and kind in its group."""
    from importlib.metadata import entry_points
    from gyro_instrument import effects, instruments
    from gyro_instrument.core.plugins import GROUPS
    from gyro_instrument.instruments import measurement
    listed = {k: {e.load() for e in entry_points(group=g) if e.value.startswith("gyro_instrument.")}
              for k, g in GROUPS.items()}
    assert listed["instruments"] == set(instruments.SHIPPED)
    assert listed["effects"] == set(effects.SHIPPED)
    assert listed["measurements"] == {type(measurement.kind(k)) for k in ("gyro", "pendulum", "azimuth",
                                                                          "rate_azimuth", "compass")}
    assert set(GROUPS.values()) == {"gyro_instrument.instruments", "gyro_instrument.effects",
                                    "gyro_instrument.measurements"}


def test_describe_and_simulate(plugin, tmp_path):
    path, scene_file = plugin
    r = cli(["describe", scene_file, "--json"], path)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)["instruments"]["rig"]
    assert d["type"] == "rate_integrating_gyro"
    # |dLOD| n / 2 pi = 2e-3 * 7.292115e-5 / 2 pi = 2.32e-8 (the effect's own formula)
    assert d["effects"]["length_of_day"]["relative_size"] == pytest.approx(2e-3 * EARTH_RATE / (2 * math.pi), rel=1e-12)
    out = tmp_path / "rig.csv"
    r = cli(["simulate", scene_file, "--out", str(out), "--quiet"], path)
    assert r.returncode == 0, r.stderr
    rows = out.read_text().splitlines()
    header = rows[0].split(",")
    last = dict(zip(header, map(float, rows[-1].split(","))))
    # theta(60 s) = n (1 - dLOD n / 2 pi) sin(latitude) 60 s: the frame rates of both effects summed
    n_eff = EARTH_RATE * (1.0 - 2e-3 * EARTH_RATE / (2 * math.pi))
    assert last["rig.angle"] == pytest.approx(n_eff * math.sin(math.radians(LATITUDE_DEG)) * 60.0, rel=1e-12)


def test_estimate_gives_the_latitude_at_its_bound(plugin):
    path, scene_file = plugin
    r = cli(["estimate", scene_file, "--json"], path)
    assert r.returncode == 0, r.stderr
    e = json.loads(r.stdout)
    entry = e["instruments"]["rig"]
    k_true = EARTH_RATE * (1.0 - 2e-3 * EARTH_RATE / (2 * math.pi)) * math.sin(math.radians(LATITUDE_DEG))
    # one draw: within 4 sigma of the simulated rate; sigma is the straight line's bound,
    # sigma_theta sqrt(12) / (dt sqrt(N (N^2 - 1))), N = 601 samples at 10 Hz
    sigma = NOISE_RAD * math.sqrt(12.0) / (0.1 * math.sqrt(601 * (601 ** 2 - 1)))
    assert entry["vertical_rate_sigma_rad_s"] == pytest.approx(sigma, rel=1e-9)
    assert abs(entry["vertical_rate_rad_s"] - k_true) < 4 * sigma
    # the latitude with n known: asin(k / n), its sigma = sigma_k / (n cos(latitude)); the day's
    # length (2.3e-8 relative) is far below it
    assert e["latitude_deg"] == pytest.approx(LATITUDE_DEG, abs=4 * e["latitude_sigma_deg"])
    assert e["latitude_sigma_deg"] == pytest.approx(
        math.degrees(sigma / (EARTH_RATE * math.cos(math.radians(LATITUDE_DEG)))), rel=1e-3)


def test_plan_solves_the_bound_for_a_target(plugin):
    path, scene_file = plugin
    r = cli(["plan", scene_file, "--target", "latitude_arcsec=1", "--json"], path)
    assert r.returncode == 0, r.stderr
    p = json.loads(r.stdout)
    t = p["targets"][0]
    T = t["observation_s"]
    # at T the bound meets 1" and 0.5 % less does not: sigma_k(T) / (n cos(latitude)), the latitude's
    # bound along the vertical axis (d(n sin g)/dg = n cos g; bisection in log T to 1e-4, 10 Hz grid)
    def sig_lat_arcsec(T):
        n = 1 + math.floor(T * 10.0 + 1e-9)
        sig_k = NOISE_RAD * math.sqrt(12.0) / (0.1 * math.sqrt(n * (n * n - 1.0)))
        return math.degrees(sig_k / (EARTH_RATE * math.cos(math.radians(LATITUDE_DEG)))) * 3600.0
    assert sig_lat_arcsec(T) <= 1.0 < sig_lat_arcsec(0.995 * T)
    assert t["planned_sigma"] == pytest.approx(sig_lat_arcsec(T), rel=1e-3)
    assert p["instruments"]["rig"]["kind"] == "vertical_rate"


@pytest.mark.ros      # starts the ROS suite (rclpy and DDS, on loopback) in a child process
def test_run_and_replay(plugin, tmp_path):
    path, scene_file = plugin
    bag = str(tmp_path / "rig.mcap")
    r = cli(["run", scene_file, "--bag", bag, "--json", "--quiet"], path, module="gyro_instrument.ros.cli")
    assert r.returncode == 0, r.stderr
    live = json.loads(r.stdout)
    r = cli(["replay", bag, "--json"], path, module="gyro_instrument.ros.cli")
    assert r.returncode == 0, r.stderr
    replayed = json.loads(r.stdout)
    r = cli(["estimate", scene_file, "--json"], path)
    estimated = json.loads(r.stdout)
    for key in ("latitude_deg", "latitude_sigma_deg", "instruments"):
        assert live[key] == replayed[key] == estimated[key], key


# ----------------------------------------------------------------------------- bad plug-ins
BAD_KIND = KIND.replace("    def tracker(self, obs, scene, companions):\n        return None\n", "")
BAD_EFFECT = EFFECT.replace("frozenset({FRAME_RATE})", 'frozenset({"frame_rates"})')
TAKEN = """\
[gyro_instrument.effects]
air_drag = gyro_rig_demo.effect:LengthOfDay
"""
TAKEN_EFFECT = EFFECT.replace('name = "length_of_day"', 'name = "air_drag"')


@pytest.mark.parametrize("case", ["incomplete_kind", "malformed_effect", "name_taken"])
def test_a_bad_plugin_gets_one_line_and_the_shipped_registry_is_unchanged(case, tmp_path):
    if case == "incomplete_kind":
        path = write_package(tmp_path, modules={"instrument": INSTRUMENT, "effect": EFFECT, "kind": BAD_KIND})
        expect = ["vertical_rate", "incomplete: missing tracker", "rate_integrating_gyro"]
    elif case == "malformed_effect":
        path = write_package(tmp_path, modules={"instrument": INSTRUMENT, "effect": BAD_EFFECT, "kind": KIND})
        expect = ["gyro-rig-demo", "length_of_day", "MECHANICS ['frame_rates']"]
    else:
        path = write_package(tmp_path, entry_points=TAKEN, modules={"effect": TAKEN_EFFECT})
        expect = ["gyro-rig-demo", "air_drag = gyro_rig_demo.effect:LengthOfDay", "already registered"]
    shipped = cli(["describe", "quet_paris", "--json"], "")
    r = cli(["describe", "quet_paris", "--json"], path)
    assert r.returncode == 0 and r.stdout == shipped.stdout     # the shipped registry unchanged
    lines = [x for x in r.stderr.splitlines() if "plug-in" in x]
    assert len(lines) == (2 if case == "incomplete_kind" else 1), r.stderr
    for text in expect:
        assert any(text in x for x in lines), (text, lines)


def test_an_incomplete_kind_is_refused_by_name_in_process():
    from gyro_instrument.instruments.measurement import KINDS, MeasurementKind, register_kind

    class HalfKind(MeasurementKind):
        name = "half"
        summary = "a kind without its planner"
        RATE = True
        UNIT = "rad/s"

        def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
            return {}, None

    before = dict(KINDS)
    with pytest.raises(ValueError, match=r"measurement kind half .* incomplete: missing probe, bound, tracker$"):
        register_kind(HalfKind)
    assert KINDS == before


def test_a_kind_giving_a_block_as_the_main_measurement(tmp_path, monkeypatch):
    """A kind with ``RATE`` False named in ``MEASUREMENT`` (a north finder's kind: its answer is a block,
    not an Earth-rate component): its block goes under ``BLOCK`` in the instrument's entry and, combined,
    in the estimate; the instrument is measured and carries no 'not used' reason (in process, the
    plug-in's modules imported from the temporary directory and registered by hand)."""
    import importlib
    from gyro_instrument import instruments
    from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
    from gyro_instrument.instruments.measurement import measured, register_kind, unregister_kind
    from gyro_instrument.scenes import scene_from_data
    monkeypatch.syspath_prepend(write_package(tmp_path))
    inst_mod, kind_mod = (importlib.import_module(f"gyro_rig_demo.{m}") for m in ("instrument", "kind"))

    class VerticalRateBlock(kind_mod.VerticalRate):
        name = "vertical_rate_block"
        RATE = False
        BLOCK = "vertical"

        def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
            entry, _ = super().estimate(obs, rec, corrections, checks, sensor)
            return {"instrument": obs.name, **{k: v for k, v in entry.items() if k != "type"}}, None

        def combine(self, blocks) -> dict:
            return min(blocks, key=lambda b: b["vertical_rate_sigma_rad_s"])

    class BlockObservation(inst_mod.RateIntegration):
        MEASUREMENT = "vertical_rate_block"

    class BlockGyro(inst_mod.RateIntegratingGyro):
        type_name = "rate_integrating_gyro_block"
        OBSERVATION = BlockObservation

    register_kind(VerticalRateBlock)
    instruments.register(BlockGyro)
    try:
        data = scene()
        data["effects"] = {"earth_rotation": {}}
        data["instruments"] = {"rig": {"type": BlockGyro.type_name}}
        sc = scene_from_data(data)
        truth = simulate_truth(sc)
        assert measured(truth[1]["rig"])
        r = estimate_records(sc, truth[1], measure(sc, truth))
        entry = r["instruments"]["rig"]
        assert "reason" not in entry and r["vertical"] == entry["vertical"]
        # the slope of n sin(latitude) t within 4 sigma (one draw), sigma the straight line's bound
        k_true = EARTH_RATE * math.sin(math.radians(LATITUDE_DEG))
        assert abs(r["vertical"]["vertical_rate_rad_s"] - k_true) < 4 * r["vertical"]["vertical_rate_sigma_rad_s"]
        assert r["latitude_deg"] is None       # a block is no Earth-rate component: no latitude from it
    finally:
        instruments.unregister(BlockGyro.type_name)
        unregister_kind(VerticalRateBlock.name)
