"""Every effect changes what it says it changes (issue 12 part 3).

For every instrument type and every effect it supports, a short scene is simulated with and
without the effect. The output is what a sensor reads: the measured angles
(``Instrument.measured_angles``) and, where the instrument has one, the spin rate. Its relative
change R is the larger of

    R_angle = max_(c,t) |y_with,c(t) − y_without,c(t)| / max_c (max_t y_with,c − min_t y_with,c),
    R_spin  = max_t |ρ_with(t) − ρ_without(t)| / max_t |ρ_with(t)|,

and must be at least ``LOWER`` times the relative size ``describe`` predicts for the effect, and at
most ``UPPER`` times that size times (N + 1), N the number of swings in the run. Why these factors:
the sizes are first-order estimates of a relative change of the amplitude, the spin, the period
or the swing plane (``Effect.relative_size``); an amplitude change δ moves the angle by ~δ a
against a range of 2a (R ≈ δ/2), a period change δ grows into a phase drift of up to 2π δ per
swing (R up to ~π δ N), the swing-plane turn n t of a pendulum shows as R ≈ (n sin γ t)/2 ≥
0.37 n t at Paris, a spin change δ as R_spin = δ. Measured here: R/size in [0.37, 1.3 (N + 1)];
the factors leave a margin of ~2 below and ~3 above. An effect an instrument does not support
is refused by name (SceneError, exit status 2 from the CLI).
"""

import math

import numpy as np
import pytest

from gyro_instrument.cli import describe, main
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import sample_times
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS
from gyro_instrument.scenes import build_instruments, load_scene

LOWER = 1.0 / 5.0
UPPER = 4.0

#: One short scene per instrument type: (scene, overrides, instrument name). Durations hold 2–5
#: swings; every supported effect is listed with its default parameters.
CASES = {
    "plane_gyroscope": ("quet_gyroscopes", ["duration_s=40", "instruments.gyro_meridian=null"], "gyro_horizontal"),
    "spherical_pendulum": ("foucault_pantheon", ["duration_s=50"], "pendulum"),
    "compound_pendulum": ("foucault_pantheon", ["duration_s=8", "instruments.cp.type=compound_pendulum",
                                                "instruments.cp.spin_rate_rad_s=3.0", "instruments.pendulum=null"],
                          "cp"),
    "free_gyroscope": ("free_gyroscope", ["duration_s=600", "instruments.free_gyro.model=numerical"], "free_gyro"),
    "gimbal_gyroscope": ("gimbal_paris", ["duration_s=30", "instruments.gimbal_outer_fixed=null"], "gimbal_locked"),
    "puiseux_body": ("puiseux_spheroid", ["duration_s=1"], "spheroid"),
    "rate_gyro": ("rate_gyro_two_position", ["duration_s=300"], "mems"),
    # two hours (2.7 swings of the 88-min compass at 45 deg), at rest heading 090 (its reading away from the wrap)
    "marine_gyrocompass": ("marine_gyrocompass", ["duration_s=7200", "instruments.anschutz=null",
                                                  "motion={speed_kn: 0, course_deg: 90}"], "sperry"),
}


def _scene(itype, effects, extra=()):
    scene, over, _ = CASES[itype]
    return load_scene(scene, list(over) + ["effects=null"] + [f"effects.{e}={{}}" for e in effects] + list(extra))


def _measured(scene, name):
    """(instrument, measured angles, the spin rate column or the measured rate (a rate gyro's, its
    observation's rate joint) or None) of one simulation."""
    inst = build_instruments(scene)[name]
    cols = inst.simulate(sample_times(scene)).columns
    return inst, inst.measured_angles(cols), cols.get(inst.observation().spin_channel or "spin_rate")


PAIRS = [(t, e) for t in CASES for e in sorted(INSTRUMENTS[t].SUPPORTED_EFFECTS)]


def test_every_instrument_type_has_a_case():
    assert set(CASES) == set(INSTRUMENTS)


@pytest.mark.parametrize("itype,effect", PAIRS, ids=[f"{t}-{e}" for t, e in PAIRS])
def test_leaving_an_effect_out_changes_the_output_as_describe_predicts(itype, effect):
    name = CASES[itype][2]
    supported = sorted(INSTRUMENTS[itype].SUPPORTED_EFFECTS)
    with_scene = _scene(itype, supported)
    size = describe(with_scene)["instruments"][name]["effects"][effect]["relative_size"]
    inst, with_, spin = _measured(with_scene, name)
    _, without, spin_without = _measured(_scene(itype, [e for e in supported if e != effect]), name)
    R = max(np.max(np.abs(with_[c] - without[c])) for c in with_) / max(np.ptp(y) for y in with_.values())
    if spin is not None and np.max(np.abs(spin)) > 0:
        R = max(R, np.max(np.abs(spin - spin_without)) / np.max(np.abs(spin)))
    T = inst.scales(with_scene.duration_s).restoring_rate_rad_s
    swings = with_scene.duration_s * T / math.pi if T and math.isfinite(T) else 0.0
    assert R >= LOWER * size, f"{itype} without {effect}: R = {R:.3g} < {LOWER:g} x predicted {size:.3g}"
    assert R <= UPPER * size * (swings + 1.0), \
        f"{itype} without {effect}: R = {R:.3g} > {UPPER:g} x predicted {size:.3g} x ({swings:.2g} swings + 1)"


UNSUPPORTED = [(t, e) for t in CASES for e in sorted(set(EFFECTS) - INSTRUMENTS[t].SUPPORTED_EFFECTS)]


@pytest.mark.parametrize("itype,effect", UNSUPPORTED, ids=[f"{t}-{e}" for t, e in UNSUPPORTED])
def test_an_unsupported_effect_is_refused_by_name(itype, effect):
    name = CASES[itype][2]
    with pytest.raises(SceneError) as err:
        _scene(itype, [effect], [f"instruments.{name}.effects=[{effect}]"])
    assert f"instruments.{name}.effects" in str(err.value)
    assert effect in str(err.value) and f"is not supported by {itype}" in str(err.value)


def test_the_cli_refuses_an_unsupported_effect_with_exit_status_2(capsys):
    assert main(["describe", "puiseux_spheroid", "--set", "effects.earth_rotation={}",
                 "--set", "instruments.spheroid.effects=[earth_rotation]"]) == 2
    err = capsys.readouterr().err
    assert "earth_rotation" in err and "is not supported by puiseux_body" in err
