"""Scenes simulate what the user believes they do (issue 11, part 3).

* A scene without ``earth_rotation`` is allowed but announced by describe, simulate and estimate,
  and the predictions follow the model as simulated. Expected values come from the papers'
  formulas, not from the program: Foucault k = n sin γ (Quet sec. 2); the directing-plane
  gyroscope's one swing T = π/√(μ n ρ0 sin ω) (Quet sec. 4 §1 eq. 9); the locked gimbal's
  T' = π √((A + C1 + A2) / (C n cos γ ρ0)) (sec. 4 §IV, thick-ring form).
* ``--set key=null`` removes an effect or an instrument, or restores a key's default.
* Every unknown name is refused with the closest valid one.
"""

import json
import math
import subprocess
import sys

import pytest

from gyro_instrument.cli import main
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope

N = 7.2921150e-5                 # sidereal Earth rate (site default), rad/s
LAT = 48.85
NOTE = "earth_rotation is not simulated"

HANDWRITTEN = """\
name: handwritten
site: {latitude_deg: 48.85}
duration_s: 120
instruments:
  pendulum: {type: spherical_pendulum, length_m: 67.0}
  gyro_meridian: {type: plane_gyroscope, plane: meridian, inertia_ratio: 2.0, spin_rate_rad_s: 628.3185307179586}
"""


@pytest.fixture
def handwritten(tmp_path):
    p = tmp_path / "handwritten.yaml"
    p.write_text(HANDWRITTEN)
    return str(p)


def describe_json(capsys, *args):
    assert main(["describe", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def refused(capsys, *args):
    """Run describe with bad input: exit 2 and exactly one line on stderr; return that line."""
    rc = main(["describe", *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("gyro-instrument: error: ")
    return err[0]


# ----------------------------------------------------------------------------- no Earth rotation
def test_scene_without_effects_is_announced_by_describe(capsys, handwritten):
    assert main(["describe", handwritten]) == 0
    out = capsys.readouterr().out
    assert f"note: {NOTE}" in out
    d = describe_json(capsys, handwritten)
    assert d["scene_effects"] == []
    assert len(d["scene_notes"]) == 1 and d["scene_notes"][0].startswith(NOTE)


def test_predictions_without_earth_rotation_are_those_of_a_non_rotating_earth(capsys, handwritten):
    d = describe_json(capsys, handwritten)
    pend = d["instruments"]["pendulum"]["predictions"]
    assert pend["foucault_rate_rad_s"] == 0.0 and pend["foucault_rate_deg_h"] == 0.0
    assert pend["full_turn_h"] is None                                 # never turns: null, not infinity
    assert any(n.startswith("earth_rotation not simulated") for n in pend["notes"])
    gyro = d["instruments"]["gyro_meridian"]["predictions"]
    assert gyro["swing_duration_small_s"] is None and gyro["swing_duration_s"] is None   # no directing torque
    assert gyro["conserved_spin_rad_s"] == pytest.approx(628.3185307179586, rel=1e-15)  # ρ0 + 0 · sin ω cos u0
    assert any("no directing torque" in n for n in gyro["notes"])


def test_predictions_with_earth_rotation_follow_the_papers(capsys, handwritten):
    d = describe_json(capsys, handwritten, "--set", "effects={earth_rotation: {}, finite_amplitude: {}}")
    assert d["scene_notes"] == []
    pend = d["instruments"]["pendulum"]["predictions"]
    k = N * math.sin(math.radians(LAT))                                # Quet sec. 2: k = n sin γ
    assert pend["foucault_rate_rad_s"] == pytest.approx(k, rel=1e-12)
    assert pend["foucault_rate_deg_h"] == pytest.approx(math.degrees(k) * 3600.0, rel=1e-12)
    assert "notes" not in pend
    gyro = d["instruments"]["gyro_meridian"]["predictions"]
    T9 = math.pi / math.sqrt(2.0 * N * 628.3185307179586 * 1.0)        # eq. (9), meridian: sin ω = 1
    assert gyro["swing_duration_small_s"] == pytest.approx(T9, rel=1e-12)


def test_an_instrument_leaving_earth_rotation_out_is_announced(capsys):
    d = describe_json(capsys, "quet_paris", "--set", "instruments.pendulum.effects=[finite_amplitude]")
    assert d["scene_notes"] == [n for n in d["scene_notes"] if n.startswith(f"{NOTE} for pendulum")]
    assert len(d["scene_notes"]) == 1
    assert d["instruments"]["pendulum"]["predictions"]["foucault_rate_rad_s"] == 0.0
    T9 = math.pi / math.sqrt(2.0 * N * 628.3185307179586 * 1.0)
    assert d["instruments"]["gyro_meridian"]["predictions"]["swing_duration_small_s"] \
        == pytest.approx(T9, rel=1e-12)


def test_gimbal_free_compound_and_puiseux_without_earth_rotation(capsys):
    # Gimbal (sec. 4 §IV): with rotation the locked swing is T' = π √((A + C1 + A2)/(C n cos γ ρ0));
    # without it there is no directing torque: null, with a note.
    lat = 48.8462
    A, mu, C1, A2, rho0 = 1.0e-3, 2.0, 3.0e-4, 5.0e-4, 628.3185307179586
    T_prime = math.pi * math.sqrt((A + C1 + A2) / (mu * A * N * math.cos(math.radians(lat)) * rho0))
    d = describe_json(capsys, "gimbal_paris")
    assert d["instruments"]["gimbal_locked"]["predictions"]["swing_duration_small_s"] \
        == pytest.approx(T_prime, rel=1e-12)
    d = describe_json(capsys, "gimbal_paris", "--set", "effects.earth_rotation=null")
    assert d["scene_notes"][0].startswith(NOTE)
    for name in ("gimbal_locked", "gimbal_outer_fixed"):
        p = d["instruments"][name]["predictions"]
        assert p["swing_duration_small_s"] is None and p["swing_duration_exact_s"] is None
        assert any("no directing torque" in n for n in p["notes"])
    # Free gyroscope: the axis' hour angle grows at n (eq. 47), at 0 without rotation.
    d = describe_json(capsys, "free_gyroscope")
    name = next(iter(d["instruments"]))
    assert d["instruments"][name]["predictions"]["mean_axis_rate_rad_s"] == pytest.approx(N, rel=1e-12)
    d = describe_json(capsys, "free_gyroscope", "--set", "effects.earth_rotation=null")
    assert d["instruments"][name]["predictions"]["mean_axis_rate_rad_s"] == 0.0
    assert d["scene_notes"][0].startswith(NOTE)
    # Compound pendulum added by override to a scene without rotation: k = 0.
    d = describe_json(capsys, "gimbal_paris", "--set", "effects=null", "--set", "instruments.cp.type=compound_pendulum")
    assert d["instruments"]["cp"]["predictions"]["foucault_rate_rad_s"] == 0.0
    # Puiseux's body never has it (as in the paper): announced as such.
    d = describe_json(capsys, "puiseux_spheroid")
    assert d["scene_notes"][0].startswith(NOTE) and "by design" in d["scene_notes"][0]


def test_simulate_announces_on_stderr(capsys, handwritten, tmp_path):
    out = tmp_path / "h.csv"
    assert main(["simulate", handwritten, "--duration-s", "2", "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert f"gyro-instrument: note: {NOTE}" in err
    assert out.exists()
    assert main(["simulate", "quet_paris", "--duration-s", "2", "--out", str(tmp_path / "q.csv"), "--quiet"]) == 0
    assert NOTE not in capsys.readouterr().err


def test_estimate_announces_in_text_and_json(capsys, handwritten):
    assert main(["estimate", handwritten]) == 0
    text = capsys.readouterr().out
    assert f"note: {NOTE}" in text
    assert "as at the equator" not in text           # k = 0 here is no equator: the scene does not rotate
    assert main(["estimate", handwritten, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["scene_notes"][0].startswith(NOTE)


# ----------------------------------------------------------------------------- --set key=null
def test_null_removes_an_effect_everywhere(capsys):
    d = describe_json(capsys, "gimbal_paris", "--set", "effects.ring_inertia=null")
    assert "ring_inertia" not in d["scene_effects"]
    for inst in d["instruments"].values():
        assert inst["effects"]["ring_inertia"]["active"] is False
    # ... also from an instrument's own effects list
    d = describe_json(capsys, "quet_paris", "--set", "instruments.pendulum.effects=[earth_rotation, centrifugal]",
                      "--set", "effects.centrifugal=null")
    assert "centrifugal" not in d["scene_effects"]
    active = {e for e, v in d["instruments"]["pendulum"]["effects"].items() if v["active"]}
    assert active == {"earth_rotation"}


def test_null_removes_an_instrument(capsys):
    d = describe_json(capsys, "quet_paris", "--set", "instruments.gyro_horizontal=null")
    assert set(d["instruments"]) == {"gyro_meridian", "pendulum"}


def test_removing_the_last_instrument_is_exit_2_one_line(capsys):
    line = refused(capsys, "foucault_pantheon", "--set", "instruments.pendulum=null")
    assert "instruments.pendulum" in line and "at least one instrument" in line
    r = subprocess.run([sys.executable, "-m", "gyro_instrument.cli", "describe", "foucault_pantheon", "--set",
                        "instruments.pendulum=null"], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_null_on_a_parameter_restores_its_default_or_is_refused(capsys):
    default = {p.name: p.default for p in PlaneGyroscope.PARAMS}["spin_rate_rad_s"]
    d = describe_json(capsys, "quet_paris", "--set", "instruments.gyro_meridian.spin_rate_rad_s=100",
                      "--set", "instruments.gyro_meridian.spin_rate_rad_s=null")
    assert d["instruments"]["gyro_meridian"]["parameters"]["spin_rate_rad_s"] == default
    line = refused(capsys, "quet_paris", "--set", "site.latitude_deg=null")
    assert "site.latitude_deg = None is invalid" in line and "[-90, 90]" in line


def test_null_on_an_unlisted_effect_parameter_does_not_switch_it_on(capsys):
    d = describe_json(capsys, "quet_paris", "--set", "effects.spin_decay.time_constant_s=null")
    assert "spin_decay" not in d["scene_effects"]


# ----------------------------------------------------------------------------- did you mean
@pytest.mark.parametrize("scene, override, field, hint", [
    ("quet_paris", "instruments.pendlum.length_m=20", "instruments.pendlum.length_m",
     "unknown instrument (did you mean 'pendulum'?)"),
    ("quet_paris", "instruments.pendlum=null", "instruments.pendlum", "unknown instrument (did you mean 'pendulum'?)"),
    ("gimbal_paris", "effects.ring_inertai=null", "effects.ring_inertai", "unknown effect (did you mean 'ring_inertia'?)"),
    ("quet_paris", "effects.centrifugl={}", "effects.centrifugl", "unknown effect (did you mean 'centrifugal'?)"),
    ("quet_paris", "instruments.pendulum.effects=[earth_rotaton]", "instruments.pendulum.effects",
     "unknown effect (did you mean 'earth_rotation'?)"),
    ("quet_paris", "instruments.pendulum.type=spherical_pendulm", "instruments.pendulum.type",
     "(did you mean 'spherical_pendulum'?)"),
    ("quet_paris", "sensr.noise_rad=0", "sensr", "(did you mean 'sensor'?)"),
    ("quet_paris", "sensr=null", "sensr", "(did you mean 'sensor'?)"),
    ("quet_paris", "sensor.noise=0", "sensor.noise", "(did you mean 'noise_rad'?)"),
    ("quet_paris", "estimator.methd=counting", "estimator.methd", "(did you mean 'method'?)"),
    ("quet_paris", "duraton_s=5", "duraton_s", "(did you mean 'duration_s'?)"),
    ("quet_paris", "site.latitude=5", "site.latitude", "(did you mean 'latitude_deg'?)"),
])
def test_unknown_names_get_the_closest_match(capsys, scene, override, field, hint):
    line = refused(capsys, scene, "--set", override)
    assert line.startswith(f"gyro-instrument: error: {field} = ")
    assert hint in line, line


def test_a_new_instrument_needs_its_type_in_the_overrides(capsys):
    d = describe_json(capsys, "quet_paris", "--set", "instruments.p2.length_m=10",
                      "--set", "instruments.p2.type=spherical_pendulum")
    assert d["instruments"]["p2"]["parameters"]["length_m"] == 10.0
    assert d["instruments"]["p2"]["type"] == "spherical_pendulum"
    line = refused(capsys, "quet_paris", "--set", "instruments.p2.length_m=10")
    assert "unknown instrument" in line and "instruments.p2.type" in line
