"""Scenes load, validate and override; the CLI's describe/simulate work and refuse bad input
with exit status 2 and one line naming the field, the value and the valid range."""

import csv
import math
import subprocess
import sys

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.core.errors import SceneError
from gyro_instrument.scenes import build_instruments, load_scene, shipped_scene_names

REQUIRED_SCENES = {"quet_paris", "gimbal_paris", "foucault_pantheon", "free_gyroscope", "puiseux_spheroid"}


def test_required_scenes_are_shipped():
    assert REQUIRED_SCENES <= set(shipped_scene_names())


@pytest.mark.parametrize("name", sorted(REQUIRED_SCENES))
def test_shipped_scenes_load_and_build(name):
    scene = load_scene(name)
    insts = build_instruments(scene)
    assert insts
    for inst in insts.values():
        assert set(inst.effects) <= inst.SUPPORTED_EFFECTS
        assert set(inst.effects) <= set(scene.effects)


def test_override_moves_scene_to_any_site():
    scene = load_scene("quet_paris", ["site.latitude_deg=-33.87", "seed=7"])
    assert scene.site.latitude_deg == pytest.approx(-33.87)
    assert scene.seed == 7
    g = build_instruments(scene)["gyro_horizontal"]
    assert g.sin_omega == pytest.approx(math.cos(math.radians(-33.87)))


def test_only_listed_effects_are_active():
    scene = load_scene("quet_paris", ["effects={earth_rotation: {}}"])
    for inst in build_instruments(scene).values():
        assert set(inst.effects) == {"earth_rotation"}


@pytest.mark.parametrize("override, field", [
    ("site.latitude_deg=91", "site.latitude_deg"),
    ("instruments.pendulum.length_m=-3", "instruments.pendulum.length_m"),
    ("instruments.gyro_meridian.inertia_ratio=0", "instruments.gyro_meridian.inertia_ratio"),
    ("instruments.pendulum.lenght_m=3", "instruments.pendulum.lenght_m"),
    ("effects.coriolis={}", "effects.coriolis"),
    ("instruments.pendulum.effects=[spin_decay]", "instruments.pendulum.effects"),
    ("duration_s=abc", "duration_s"),
    ("seed=1.5", "seed"),
])
def test_bad_values_name_field_value_and_range(override, field):
    with pytest.raises(SceneError) as err:
        load_scene("quet_paris", [override])
    assert err.value.field == field
    assert str(err.value).startswith(field)


def test_describe_lists_every_supported_effect_with_size(capsys):
    assert main(["describe", "quet_paris"]) == 0
    out = capsys.readouterr().out
    assert "centrifugal" in out and "5.8e-08" in out   # n/(μρ0) = 7.29e-5/(2·628) = 5.8e-8
    assert "spin_decay" in out


def test_simulate_writes_documented_csv(tmp_path):
    out = tmp_path / "q.csv"
    assert main(["simulate", "quet_paris", "--duration-s", "20", "--out", str(out), "--quiet"]) == 0
    with open(out) as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    assert header[0] == "time_s"
    assert "gyro_horizontal.angle" in header and "pendulum.swing_azimuth" in header
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (401, len(header))
    assert data[0, header.index("gyro_horizontal.angle")] == pytest.approx(0.1)


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "gyro_instrument.cli", *args], capture_output=True, text=True)


@pytest.mark.parametrize("args, field, value, valid", [
    # the value the user gave, as written back (a float: 120.0), and the range it had to be in
    (("simulate", "quet_paris", "--set", "site.latitude_deg=120", "--out", "/tmp/x.csv"),
     "site.latitude_deg", "120.0", "[-90, 90]"),
    (("simulate", "/nonexistent/scene.yaml", "--out", "/tmp/x.csv"),
     "scene", "'/nonexistent/scene.yaml'", "give a shipped scene name or an existing YAML path"),
    (("simulate", "quet_paris", "--out", "/nonexistent-dir/x.csv"),
     "--out", "'/nonexistent-dir/x.csv'", "directory /nonexistent-dir does not exist"),
    (("describe", "no_such_scene"), "scene", "'no_such_scene'", "shipped scenes: foucault_pantheon, "),
])
def test_cli_bad_input_exit_2_one_line_no_traceback(args, field, value, valid):
    # the one line is SceneError's: "gyro-instrument: error: FIELD = VALUE is invalid: WHAT IS VALID"
    r = run_cli(*args)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr
    assert lines[0].startswith(f"gyro-instrument: error: {field} = {value} is invalid: "), lines[0]
    assert valid in lines[0], lines[0]
    assert r.stdout == ""                  # nothing else said, nothing half done


def test_long_runs_report_progress():
    # A long integration reports how far it has got (rate-limited) to the active reporter:
    # fractions rise to 1 — for the adaptive driver (from the RHS's time) and for the parareal
    # fast path (from its Newton passes). The CLI draws them on a terminal line.
    import io
    from gyro_instrument.cli import terminal_progress
    from gyro_instrument.core.integrate import reporting
    from gyro_instrument.scenes import build_instruments, load_scene
    from gyro_instrument.core.scene import sample_times
    for extra in (["instruments.pendulum.integrator=adaptive"], ["instruments.pendulum.integrator=parareal"]):
        scene = load_scene("foucault_pantheon", ["duration_s=600"] + extra)
        p = build_instruments(scene)["pendulum"]
        seen = []
        with reporting(seen.append, every_s=0.0):
            p.simulate(sample_times(scene))
        assert seen and seen == sorted(seen) and 0.0 <= seen[0] and seen[-1] <= 1.0, seen
        assert seen[-1] > 0.9 if extra[0].endswith("adaptive") else len(seen) >= 2
    out = io.StringIO()
    with terminal_progress("  pendulum", stream=out, force=True):
        from gyro_instrument.core.integrate import report
        report(0.5)
        report(1.0)
    assert "  pendulum: 100.0 %" in out.getvalue() and out.getvalue().endswith("done   \n")
