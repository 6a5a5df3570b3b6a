"""Bad input: exit status 2 and one line naming the field, the value and the valid range, with
no traceback; random YAML never raises anything but SceneError (hypothesis)."""

import subprocess
import sys

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyro_instrument.cli import main
from gyro_instrument.core.errors import SceneError
from gyro_instrument.scenes import load_scene

BAD_OVERRIDES = [
    ("site.latitude_deg=91", "site.latitude_deg", "91", "[-90, 90]"),
    ("site.latitude_deg=-91", "site.latitude_deg", "-91", "[-90, 90]"),
    ("site.earth_rate_rad_s=-1", "site.earth_rate_rad_s", "-1", "[0, 1]"),
    ("site.gravity_m_s2=0", "site.gravity_m_s2", "0", "(0, 1000]"),
    ("instruments.pendulum.length_m=-3", "instruments.pendulum.length_m", "-3", "(0, 10000]"),
    ("instruments.pendulum.length_m=abc", "instruments.pendulum.length_m", "'abc'", "finite number"),
    ("instruments.gyro_horizontal.inertia_ratio=3", "instruments.gyro_horizontal.inertia_ratio", "3", "(0, 2]"),
    ("instruments.gyro_horizontal.transverse_inertia_kg_m2=-1",
     "instruments.gyro_horizontal.transverse_inertia_kg_m2", "-1", "(0, inf]"),
    ("instruments.gyro_horizontal.plane=diagonal", "instruments.gyro_horizontal.plane", "'diagonal'",
     "horizontal, meridian"),
    ("instruments.gyro_horizontal.plane=custom", "instruments.gyro_horizontal.normal_enu", "None", "required"),
    ("instruments.gyro_horizontal.normal_enu=[0,0,0]", "instruments.gyro_horizontal.normal_enu", "[0, 0, 0]",
     "not all zero"),
    ("instruments.pendulum.effects=[spin_decay]", "instruments.pendulum.effects", "'spin_decay'", "listed"),
    ("instruments.gyro_horizontal.effects=[air_drag]", "instruments.gyro_horizontal.effects", "'air_drag'",
     "listed"),
    ("effects.coriolis={}", "effects.coriolis", "{}", "valid keys"),
    ("effects.spin_decay.time_constant_s=0", "effects.spin_decay.time_constant_s", "0", "(0, inf]"),
    ("instruments.pendulum.lenght_m=3", "instruments.pendulum.lenght_m", "3", "did you mean 'length_m'"),
    ("instruments.pendulum.initial_deflection_deg=200", "instruments.pendulum.initial_deflection_deg", "200",
     "[0, 180]"),
    # a release at 180 deg is the inverted bob: simulated (test_hard_cases), but no orbit for the apsidal
    # theory describe prints (issue 35; was a traceback)
    ("instruments.pendulum.initial_deflection_deg=180", "instruments.pendulum.initial_deflection_deg", "180",
     "[0, 180)"),
    ("instruments.gyro_horizontal.type=laser_gyro", "instruments.gyro_horizontal.type", "'laser_gyro'",
     "plane_gyroscope"),
    ("sample_rate_hz=0", "sample_rate_hz", "0", "(0, 10000]"),
    ("duration_s=-5", "duration_s", "-5", "(0, 1e+07]"),
    ("seed=-1", "seed", "-1", "integer"),
    ("seed=1.5", "seed", "1.5", "integer"),
    ("sensor.noise_rad=-1", "sensor.noise_rad", "-1", "[0, 1]"),
    ("sensor.dropout_fraction=0.7", "sensor.dropout_fraction", "0.7", "[0, 0.5)"),
    ("instrument.x=1", "instrument", "{'x': 1}", "did you mean 'instruments'"),
]


@pytest.mark.parametrize("override, field, value, valid", BAD_OVERRIDES, ids=[b[1] + "=" + b[2] for b in BAD_OVERRIDES])
def test_bad_override_exit_2_one_line_field_value_range(capsys, override, field, value, valid):
    rc = main(["describe", "quet_paris", "--set", override])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    line = err[0]
    assert line.startswith(f"gyro-instrument: error: {field} = ")
    assert value in line.split(" is invalid")[0], line
    assert valid in line, line


@pytest.mark.parametrize("content, expect", [
    ("", "is empty"),
    ("- a\n- b\n", "must be a YAML mapping"),
    ("site: {latitude_deg: 10\n", "not valid YAML"),
    ("site: {latitude_deg: 10}\n", "instruments"),
])
def test_bad_scene_files(tmp_path, capsys, content, expect):
    p = tmp_path / "s.yaml"
    p.write_text(content)
    assert main(["describe", str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and expect in err[0]


def test_missing_file_and_no_equals_sign(capsys):
    assert main(["describe", "/nonexistent/x.yaml"]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["describe", "quet_paris", "--set", "site.latitude_deg"]) == 2
    assert "key.path=value" in capsys.readouterr().err


def test_no_traceback_in_a_real_process():
    r = subprocess.run([sys.executable, "-m", "gyro_instrument.cli", "simulate", "quet_paris", "--set",
                        "instruments.pendulum.length_m=-1", "--out", "/tmp/x.csv"], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_unwritable_output_refused_before_simulation(tmp_path, capsys):
    # An unwritable path is refused before any simulation starts (the check comes first).
    assert main(["simulate", "quet_paris", "--out", "/proc/nope/x.csv"]) == 2
    assert "--out" in capsys.readouterr().err


scalars = st.one_of(st.none(), st.booleans(), st.integers(-10 ** 6, 10 ** 6), st.floats(allow_nan=True),
                    st.text(max_size=8))
yaml_values = st.recursive(scalars, lambda kids: st.one_of(st.lists(kids, max_size=4),
                                                           st.dictionaries(st.text(max_size=12), kids, max_size=4)),
                           max_leaves=12)
KEYS = ["site", "site.latitude_deg", "duration_s", "seed", "effects", "effects.spin_decay", "instruments",
        "instruments.gyro_horizontal", "instruments.gyro_horizontal.plane", "instruments.pendulum.length_m",
        "instruments.pendulum.effects", "sensor", "sensor.noise_rad", "sample_rate_hz", "name"]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.dictionaries(st.sampled_from(["site", "instruments", "effects", "sensor", "seed", "duration_s", "x"]),
                       yaml_values, max_size=5))
def test_random_yaml_documents_only_raise_scene_error(tmp_path_factory, doc):
    p = tmp_path_factory.mktemp("h") / "s.yaml"
    p.write_text(yaml.safe_dump(doc))
    try:
        load_scene(str(p))
    except SceneError:
        pass


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(KEYS), yaml_values), max_size=3))
def test_random_overrides_only_raise_scene_error(pairs):
    try:
        load_scene("quet_paris", [(k.split("."), v) for k, v in pairs])
    except SceneError:
        pass
