"""Degenerate poses, impossible sizes and cut recordings are refused or reported up front:
exit 2 and one line naming the parameters, never a LinAlgError or a MemoryError traceback."""

import math
import os

import numpy as np
import pytest

from gyro_instrument.cli import main, replay_bag
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.memory import PEAK_FACTOR, check_memory, channel_count, needed_bytes
from gyro_instrument.core.params import validate_params
from gyro_instrument.core.site import Site
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments.gimbal import (MAX_MASS_MATRIX_CONDITION, GimbalGyroscope, free_mass_matrix,
                                                scaled_condition)
from gyro_instrument.scenes import load_scene

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SITE = Site.from_degrees(48.85)
MASSLESS = ("earth_rotation", "centrifugal")
FREE = ["--set", "instruments.gimbal_locked.configuration=free",
        "--set", "instruments.gimbal_locked.effects=[earth_rotation,centrifugal]"]


def make(effects=MASSLESS, **raw):
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, raw)
    GimbalGyroscope.check_params("instruments.g", p)
    return GimbalGyroscope("g", SITE, p, {e: EFFECTS[e]() for e in effects})


# ------------------------------------------------------------------ gimbal lock
@pytest.mark.parametrize("inner_deg", [-90.0, 90.0])
def test_massless_free_gimbal_at_lock_is_refused_naming_the_parameters(capsys, inner_deg):
    """det M = a C u², u² = (A + C1) sin²θ + A1 cos²θ + A2: zero exactly for A1 = A2 = 0 (massless
    rings) and θ = 0 or π (inner_angle = ∓90°, rotor axis along PP'). Was LinAlgError."""
    rc = main(["simulate", "gimbal_paris", "--duration-s", "1", "--quiet", "--out", "/tmp/never.csv"] + FREE
              + ["--set", f"instruments.gimbal_locked.initial_inner_angle_deg={inner_deg}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    line = err[0]
    assert line.startswith("gyro-instrument: error: instruments.gimbal_locked.initial_inner_angle_deg = ")
    for word in ("gimbal lock", "ring_inertia", "inner_ring_diametral_inertia_kg_m2",
                 "outer_ring_diametral_inertia_kg_m2", "singular"):
        assert word in line, line


def test_rings_of_zero_inertia_listed_are_refused_too():
    with pytest.raises(SceneError) as err:
        make(effects=MASSLESS + ("ring_inertia",), configuration="free", initial_inner_angle_deg=-90.0,
             inner_ring_diametral_inertia_kg_m2=0.0, outer_ring_diametral_inertia_kg_m2=0.0)
    assert err.value.field == "g.initial_inner_angle_deg"        # the constructor's prefix is the name
    assert "inner_ring_diametral_inertia_kg_m2 = 0" in str(err.value)


@pytest.mark.parametrize("effects, raw", [
    (MASSLESS + ("ring_inertia",), dict(configuration="free", initial_inner_angle_deg=-90.0)),     # rings: regular
    (MASSLESS + ("ring_inertia",), dict(configuration="free", initial_inner_angle_deg=-90.0,
                                        inner_ring_diametral_inertia_kg_m2=0.0)),                  # A2 alone
    (MASSLESS, dict(configuration="locked")),
    (MASSLESS, dict(configuration="outer_fixed", initial_inner_angle_deg=-90.0)),
])
def test_regular_configurations_are_accepted(effects, raw):
    make(effects=effects, **raw)


def test_a_pose_1e3_rad_from_the_lock_runs():
    """θ0 = 1e-3 rad with massless rings: scaled cond ≈ 8/θ² = 8e6, accepted and integrated
    (0.01 s: the near-lock motion is fast, ~1 ms per sample of work)."""
    g = make(configuration="free", initial_outer_angle_deg=0.0, initial_inner_angle_deg=math.degrees(1e-3) - 90.0)
    M = g.mass_matrix(g.build_chain(), [g.psi0, g.theta0, 0.0])
    np.testing.assert_allclose(M, free_mass_matrix(g.p.transverse_inertia_kg_m2, g.C, g.A1, g.C1, g.A2, g.theta0), rtol=1e-12, atol=1e-18)
    assert scaled_condition(M) == pytest.approx(8e6, rel=1e-3)
    sim = g.simulate(np.linspace(0.0, 0.01, 11))
    assert all(np.all(np.isfinite(v)) for v in sim.columns.values())
    assert np.min(sim.extra["theta"]) > 0.0


def test_the_threshold_is_where_the_condition_number_says():
    """Refused exactly beyond MAX_MASS_MATRIX_CONDITION: θ ≈ √(8/1e12) = 2.83e-6 rad (μ = 2)."""
    edge = math.sqrt(8.0 / MAX_MASS_MATRIX_CONDITION)
    make(configuration="free", initial_inner_angle_deg=math.degrees(1.01 * edge) - 90.0)
    with pytest.raises(SceneError, match="keep inner_angle at least 0.000162 deg"):
        make(configuration="free", initial_inner_angle_deg=math.degrees(0.99 * edge) - 90.0)


# ------------------------------------------------------------------ impossible sizes
def test_a_run_too_large_for_memory_is_refused_before_integrating(capsys):
    """10 kHz for a day: ~0.9 TB in memory for estimate, which holds the run; refused in about a second,
    exit 2, with the sizes. simulate streams (memory of one block, issue 13): its CSV would need
    864000001 rows x 13 columns x <= 25 bytes = 2.8e11 bytes, refused by the disk check with the
    needed and free bytes, before integrating."""
    rc = main(["estimate", "quet_paris", "--set", "sample_rate_hz=10000", "--duration-s", "86400"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("gyro-instrument: error: duration_s = 86400.0 is invalid: needs ~")
    assert "864000001 samples x 13 channels" in err[0] and "GB available: lower duration_s or sample_rate_hz" \
        in err[0]
    rc = main(["simulate", "quet_paris", "--quiet", "--out", "/tmp/never.csv", "--set", "sample_rate_hz=10000",
               "--duration-s", "86400"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith("gyro-instrument: error: --out = '/tmp/never.csv' is invalid: needs ~2.808e+11 bytes "
                             "(864000001 rows x 13 columns") and "bytes free" in err[0], err
    assert not os.path.exists("/tmp/never.csv")


def test_memory_estimate_is_samples_channels_8_bytes_factor():
    scene = load_scene("quet_paris", ["duration_s=100", "sample_rate_hz=10"])
    assert channel_count(scene) == 13                       # time + the columns of its 3 instruments (3 + 3 + 6)
    assert needed_bytes(scene) == 1001 * 13 * 8 * PEAK_FACTOR
    check_memory(scene, available=needed_bytes(scene))      # fits exactly
    with pytest.raises(SceneError, match=r"1001 samples x 13 channels at 10 Hz; 1e-06 GB available"):
        check_memory(scene, available=1000)


# ------------------------------------------------------------------ cut recordings
def test_replay_of_a_cut_bag_says_how_much_was_read(tmp_path, capsys):
    src = os.path.join(ROOT, "bags", "foucault_pantheon.mcap")
    cut = tmp_path / "cut.mcap"
    with open(src, "rb") as fh:
        cut.write_bytes(fh.read(900_000))
    r = replay_bag(str(cut))
    assert 0 < r["observation_read_s"] < r["observation_s"] == 600.0
    assert "no summary" in r["recording_cut"]
    assert main(["replay", str(cut)]) == 0
    # the text leads with the answer (issue 26); the line after the headline says how much was read
    # (long lines are wrapped, continuation lines indented: read them joined)
    text = " ".join(line.strip() for line in capsys.readouterr().out.splitlines())
    assert (f"scene foucault_pantheon (seed 1), {r['observation_read_s']:g} s of 600 s read per instrument "
            f"(recording cut: bag has no summary") in text
    whole = replay_bag(src)
    # a whole recording reads as the live run did (replay equals live): no cut keys
    assert "observation_read_s" not in whole and "recording_cut" not in whole


# ------------------------------------------------------------------ what the fuzzer found (test_cli_fuzz)
@pytest.mark.parametrize("argv, field", [
    (["estimate", "foucault_pantheon", "--duration-s", "0.05", "--set", "instruments.pendulum.length_m=1e-300"],
     "instruments.pendulum.length_m"),                                     # was AttributeError in integrate
    (["estimate", "gimbal_paris", "--duration-s", "2", "--set", "instruments.gimbal_locked.inertia_ratio=1e-300"],
     "instruments.gimbal_locked.inertia_ratio"),                           # was an overflow, then a hang
    (["describe", "quet_paris", "--set", "instruments.pendulum.type=[1]"], "instruments.pendulum.type"),  # TypeError
    (["replay", "EMPTY_DIR"], "bag"),                                      # was IsADirectoryError
    (["recover", "EMPTY_DIR", "--out", "OUT_DIR/never.mcap"], "bag"),
    (["bench", "--quick", "--out", "/proc/nope"], "--out"),                # was FileNotFoundError
    (["describe", "quet_paris", "--set", "effects={\"\\r\": null}"], "effects.\\r"),  # was two lines
])
def test_fuzzer_findings_are_one_line_exit_2(capsys, tmp_path, argv, field):
    # a directory holding no bag (a directory of .mcap files is a bag since rosbag2 layouts are read)
    (tmp_path / "empty").mkdir()
    (tmp_path / "out").mkdir()
    argv = [a.replace("EMPTY_DIR", str(tmp_path / "empty")).replace("OUT_DIR", str(tmp_path / "out")) for a in argv]
    rc = main(argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert err[0].startswith(f"gyro-instrument: error: {field} = "), err


def test_unstable_puiseux_roots_are_json(capsys):
    """Below the critical spin eq. (15)'s roots are complex: JSON {"real", "imag"} (was TypeError)."""
    import json
    assert main(["describe", "puiseux_spheroid", "--json", "--set", "instruments.spheroid.spin_rate_turn_s=0.5"]) == 0
    d = json.loads(capsys.readouterr().out)
    roots = d["instruments"]["spheroid"]["predictions"]["omega_sq_rad2_s2"]
    assert all(set(r) == {"real", "imag"} for r in roots)
