"""Planning north (issue 24 item 4): ``plan SCENE --target azimuth_arcsec=N``.

The scene: quet_paris's horizontal gyroscope alone (μ = 2, 100 turn/s, one swing 12.8 s at Paris,
σ = 1e-4 rad at 20 Hz), its scale zero at 123.4567° (a mount azimuth not used elsewhere).

Tolerances: the plan's bisection stops at 1e-3 relative in T, so the bound at the plan is within
1e-3·(1/2) of the target below it (σ ∝ T^-1/2); the long-record bound σ/√N (``crlb_centre_long``)
is approached from above as (1 + 3/(π²K²)) for K cycles with ω fitted (north.crlb_centre's docstring),
plus the damping column's share, so over the 6.8 cycles at 86.8 s it lies within 1 % + 10 % of σ/√N.
The Monte Carlo: the rms over n seeds of a Gaussian error has relative σ 1/√(2n); with 24 seeds the
band [0.6, 1.4] around the planned σ is ±2.8 of those σ.
"""

import json
import math

import pytest

from gyro_instrument.cli import main as cli_main
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators import north
from gyro_instrument.estimators.bounds import SensorSpec
from gyro_instrument.estimators.north.bounds import AzimuthModel, azimuth_sigmas, solve_azimuth
from gyro_instrument.estimators.planner import ARCSEC_RAD, parse_targets, plan, verify_plan
from gyro_instrument.instruments.measurement import kind
from gyro_instrument.instruments.observation_azimuth import AZIMUTH

MOUNT_DEG = 123.4567
ALONE = ["instruments.gyro_meridian=null", "instruments.pendulum=null",
         f"instruments.gyro_horizontal.mount_azimuth_deg={MOUNT_DEG}"]


@pytest.fixture(scope="module")
def planned():
    return plan("quet_paris", ALONE, parse_targets(["azimuth_arcsec=0.5"]), floor=True)


def test_the_azimuth_kind_has_a_probe_not_a_type_switch():
    k = kind(AZIMUTH)
    assert k is not None and not k.missing() and k.BLOCK == "north" and k.TARGET == "azimuth"


def test_the_fit_time_meets_the_target_at_the_crlb_of_the_centre(planned):
    e = planned["targets"][0]
    assert e["quantity"] == "azimuth" and e["instrument"] == "gyro_horizontal"
    T = e["observation_s"]
    assert e["methods"]["fit"]["observation_s"] == T
    # the bound at T meets the target, and T is the shortest such time (bisection to 1e-3)
    assert 0.5 * (1 - 1e-3) <= e["planned_sigma"] <= 0.5
    # the bound recomputed independently with estimators.north.crlb_centre on the scene's grid
    m = planned["north_instruments"]["gyro_horizontal"]
    n = int(math.floor(T * 20.0 + 1e-9)) + 1
    long = north.crlb_centre_long(1e-4, n) / ARCSEC_RAD
    assert long < e["planned_sigma"] < 1.11 * long
    assert m["mount_azimuth_deg"] == pytest.approx(MOUNT_DEG, abs=1e-9)
    assert m["period_s"] == pytest.approx(2 * 12.8012, rel=2e-3)       # the probe's period, the scene's swing


def test_every_method_has_its_time_and_the_fit_needs_the_least(planned):
    e = planned["targets"][0]
    T = e["observation_s"]
    for name in ("schuler_mean", "lavrov", "transit"):
        mth = e["methods"][name]
        assert mth["observation_s"] > T and mth["planned_sigma"] <= 0.5
        # σ laws: each falls ~ T^-1/2, so its σ at the fit's T is ~ sqrt(its T / the fit's) × target
        assert mth["sigma_at_plan"] == pytest.approx(0.5 * math.sqrt(mth["over_fit"]), rel=0.25)
    # the full-record fit uses every sample, the reversal points only the samples near the turns
    assert e["methods"]["schuler_mean"]["over_fit"] > 3
    assert e["floor"]["reachable"] and abs(e["floor"]["bias"]) < 0.1


def test_sigma_law_of_the_schuler_mean_in_steps():
    # a synthetic model: no simulation; σ of the Schuler mean falls at each new reversal point
    model = AzimuthModel("g", omega=2 * math.pi / 20.0, amplitude=0.05)
    sensor = SensorSpec(2e-5, 0.0, 0.0, 0.0, 20.0)
    s = [azimuth_sigmas(model, T, sensor)["schuler_mean"] for T in (40.0, 60.0, 80.0, 160.0)]
    assert all(a >= b for a, b in zip(s, s[1:])) and s[-1] < s[0] / 1.5
    # below the shortest record: two full swings (the fit's start needs three complete reversal points)
    assert azimuth_sigmas(model, 30.0, sensor)["fit"] == math.inf
    T, note = solve_azimuth(model, sensor, 3e-7)            # the bound over two swings is 7.7e-7 rad: noise-limited
    assert T is not None and azimuth_sigmas(model, T, sensor)["fit"] <= 3e-7 and not note


def test_verify_over_seeds_matches_the_plan():
    d = plan("quet_paris", ALONE, parse_targets(["azimuth_arcsec=0.5"]), floor=False)
    verify_plan(d, 24)
    v = d["targets"][0]["verify"]
    assert v["used"] == 24 and v["null"] == 0
    assert 0.6 < v["achieved_over_planned"] < 1.4
    for name, mth in v["methods"].items():
        assert mth["used"] == 24 and 0.6 < mth["achieved_over_planned"] < 1.4, name


def test_cli_plan_azimuth_json_and_bad_input(capsys):
    assert cli_main(["plan", "quet_paris", *sum((["--set", o] for o in ALONE), []), "--target", "azimuth_mgon=0.5",
                     "--no-floor", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    e = d["targets"][0]
    assert e["target"] == "azimuth_mgon" and e["planned_sigma"] <= 0.5
    assert cli_main(["plan", "foucault_pantheon", "--target", "azimuth_arcsec=1"]) == 2
    err = capsys.readouterr().err
    assert "horizontal gyroscope" in err and "foucault_pantheon" in err
    with pytest.raises(SceneError, match="azimuth_arcsec"):
        parse_targets(["azimuth_arcsec=-1"])


def test_a_horizontal_gyroscope_without_a_stated_mount_is_planned_at_mount_0(capsys):
    """quet_paris states no mount_azimuth_deg (the estimate then reads the scale from north: mount 0); its
    azimuth plan ended in a TypeError traceback (the unset mount converted to radians). The plan is the
    one of the same scene with the mount stated as 0 (the model is the same)."""
    assert cli_main(["plan", "quet_paris", "--target", "azimuth_arcsec=10", "--json"]) == 0
    unset = json.loads(capsys.readouterr().out)
    assert cli_main(["plan", "quet_paris", "--target", "azimuth_arcsec=10", "--json",
                     "--set", "instruments.gyro_horizontal.mount_azimuth_deg=0"]) == 0
    stated = json.loads(capsys.readouterr().out)
    assert stated.pop("overrides") == ["instruments.gyro_horizontal.mount_azimuth_deg=0"] and unset.pop("overrides") == []
    assert stated == unset
