"""What the instruments cannot determine is stated, never hidden in a σ (issue 11, part 1).

Quet sec. 4 §1 item 9 and the gimbal's T'/T'' (§IV) fix cos γ, which is even in γ: with those
instruments alone the profile likelihood has two equal modes ±γ̂ and a σ over both would be of the
size of the value. The estimate must report |γ| with ``hemisphere: "not determined by these
instruments"`` (or the signed value under ``estimator.hemisphere``), σ and the Cramér–Rao bound of
the one mode reported; a sign-sensitive measurement (the pendulum's k = n sin γ, sec. 2, or a
gyroscope plane tilted out of the horizontal and the meridian) decides the hemisphere.
"""

import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.estimators.latitude import HEMISPHERE_UNDETERMINED, RateMeasurement, solve_latitude


@pytest.fixture
def sweep(sweep_seeds):
    """Seeds 0..n-1 of a scene on the session's process pool (conftest ``sweep_seeds``)."""
    return sweep_seeds


# 200 seeds for one site per instrument set, 100 for its mirror in the other hemisphere in the
# default run (rms/σ measured 2026-11-30 at 100 seeds: 1.006 and 1.026; the [0.8, 1.2] band is 2.8
# sampling spreads of 1/sqrt(200) = 7 % there), 200 in `pytest -m slow` (the suite's 15-min budget).
def _cos_case(scene, lat, seeds, *marks):
    """One case, its seed sweep declared (submitted to the session's pool when collection ends)."""
    sweep = pytest.mark.seed_sweep(scene, [f"site.latitude_deg={lat}"], seeds)
    return pytest.param(scene, lat, seeds, marks=(sweep, *marks),
                        id=f"{scene}-{lat}-{seeds}" + ("-slow" if marks else ""))


COS_CASES = [_cos_case(*c) for c in (("quet_gyroscopes", 60.0, 200), ("quet_gyroscopes", -33.87, 100),
                                     ("gimbal_paris", 48.8462, 200), ("gimbal_paris", -48.8462, 100))] + [
    _cos_case(sc, lat, 200, pytest.mark.slow) for sc, lat in (("quet_gyroscopes", -33.87), ("gimbal_paris", -48.8462))]


@pytest.mark.parametrize("scene,lat,seeds", COS_CASES)
def test_cos_latitude_instruments_report_abs_latitude_calibrated(sweep, scene, lat, seeds):
    # Acceptance of issue 11: rms error / reported σ in [0.8, 1.2] (an rms from 200 draws has a
    # relative sampling spread of 1/√400 = 5 %: the band is 4 spreads; see COS_CASES for 100) and
    # every σ within [0.95, 1.1] of its Cramér–Rao bound (σ and the bound come from the same mode and
    # differ only by the fitted versus the bound's period σ). The truth they are compared with is |γ|.
    results = sweep(scene, [f"site.latitude_deg={lat}"], seeds)
    assert len(results) == seeds
    for r in results:
        assert r["hemisphere"] == HEMISPHERE_UNDETERMINED and r["latitude_is_absolute"] is True
        assert r["methods"]["item9"]["latitude_is_absolute"] is True
    err = np.array([r["latitude_deg"] - abs(lat) for r in results])
    sig = np.array([r["latitude_sigma_deg"] for r in results])
    crlb = np.array([r["crlb"]["latitude_deg"] for r in results])
    nerr = np.array([r["earth_rate_rad_s"] - r["truth"]["earth_rate_rad_s"] for r in results])
    nsig = np.array([r["earth_rate_sigma_rad_s"] for r in results])
    ncrlb = np.array([r["crlb"]["earth_rate_rad_s"] for r in results])
    # σ is local: nowhere near the size of the value (the bug was σ = |γ|)
    assert np.all(sig < 1e-3 * abs(lat))
    assert 0.8 <= math.sqrt(np.mean(err ** 2)) / np.mean(sig) <= 1.2
    assert np.all((sig / crlb >= 0.95) & (sig / crlb <= 1.1))
    assert 0.8 <= math.sqrt(np.mean(nerr ** 2)) / np.mean(nsig) <= 1.2
    assert np.all((nsig / ncrlb >= 0.95) & (nsig / ncrlb <= 1.1))


def test_assumed_hemisphere_signs_the_same_mode(sweep):
    # estimator.hemisphere = south: the mirror of the |γ| estimate, with the same σ and bound.
    over = ["site.latitude_deg=-33.87"]
    free = sweep("quet_gyroscopes", over, seeds=4)
    signed = sweep("quet_gyroscopes", over + ["estimator.hemisphere=south"], seeds=4)
    for a, b in zip(free, signed):
        assert b["hemisphere"] == "south" and "assumed" in b["hemisphere_basis"]
        assert b["latitude_deg"] == pytest.approx(-a["latitude_deg"], abs=1e-9)
        assert b["latitude_sigma_deg"] == pytest.approx(a["latitude_sigma_deg"], rel=1e-6)
        assert b["methods"]["item9"]["latitude_deg"] == pytest.approx(-a["methods"]["item9"]["latitude_deg"])
        assert abs(b["latitude_deg"] + 33.87) < 5 * b["latitude_sigma_deg"]


def test_pendulum_decides_the_hemisphere_and_overrules_a_wrong_assumption(sweep):
    # quet_paris at -33.87° with the user's assumption "north": k = n sin γ < 0 (sec. 2) decides.
    r = sweep("quet_paris", ["site.latitude_deg=-33.87", "estimator.hemisphere=north"], seeds=2)[0]
    assert r["hemisphere"] == "south" and r["latitude_is_absolute"] is False
    assert "measured" in r["hemisphere_basis"] and "contradicts" in r["hemisphere_basis"]
    assert abs(r["latitude_deg"] + 33.87) < 5 * r["latitude_sigma_deg"]


def test_tilted_gyroscope_plane_is_sign_sensitive(sweep):
    # A directing plane with normal (0, 1, 1)/√2 (ENU: tilted 45° in the meridian) has
    # sin ω = |sin(γ − 45°)|, not even in γ. Beside the horizontal (cos γ) and meridian (1) planes it
    # decides the hemisphere: at −33.87° it reads sin(78.87°) = 0.981, at +33.87° only 0.193.
    tilted = ["instruments.gyro_tilted.type=plane_gyroscope", "instruments.gyro_tilted.plane=custom",
              "instruments.gyro_tilted.normal_enu=[0, 1, 1]"]
    r = sweep("quet_gyroscopes", ["site.latitude_deg=-33.87"] + tilted, seeds=2)[0]
    assert r["hemisphere"] == "south" and "gyro_tilted" in r["hemisphere_basis"]
    assert abs(r["latitude_deg"] + 33.87) < 5 * r["latitude_sigma_deg"]


def test_two_exact_fits_in_opposite_hemispheres_are_both_reported(sweep):
    # Horizontal and tilted planes alone: two unknowns (n, γ), two measurements, and the ratio
    # |sin(γ − 45°)| / cos γ = 0.981 / 0.830 = 1.18 of −33.87° is met again in the north where the
    # ratio climbs from 0 at 45° to infinity at 90°: tan γ − 1 = 1.18·√2 gives γ = 69.5°. Both fit
    # exactly (χ² = 0): the hemisphere is not determined and the other solution is listed.
    over = ["site.latitude_deg=-33.87", "instruments.gyro_meridian.plane=custom",
            "instruments.gyro_meridian.normal_enu=[0, 1, 1]"]
    r = sweep("quet_gyroscopes", over, seeds=2)[0]
    assert r["hemisphere"] == HEMISPHERE_UNDETERMINED
    lats = sorted([r["latitude_deg"]] + [o["latitude_deg"] for o in r["other_latitudes_deg"]])
    ratio = math.sin(math.radians(33.87 + 45)) / math.cos(math.radians(33.87))
    mirror = math.degrees(math.atan(1 + ratio * math.sqrt(2)))
    assert lats[0] == pytest.approx(-33.87, abs=0.01) and lats[1] == pytest.approx(mirror, abs=0.01)


def test_text_output_states_the_hemisphere(capsys):
    assert main(["estimate", "gimbal_paris", "--set", "site.latitude_deg=-48.8462"]) == 0
    out = capsys.readouterr().out
    assert "|latitude| 48.846" in out and "hemisphere not determined by these instruments" in out
    assert "estimator.hemisphere" in out


def test_near_the_equator_cos_is_flat_so_no_local_sigma(sweep):
    # Gyroscope pair at 0.05°: 1 − cos γ = γ²/2 = 3.8e-7, about one σ of cos γ (item 9 measures it
    # to 4.3e-7 in 600 s), so the Δχ² = 9 region reaches the equator (unless a 4σ draw): σ is null
    # with the reason, and the Δχ² = 9 interval [0, ~0.1°] contains the true |γ|.
    rs = sweep("quet_gyroscopes", ["site.latitude_deg=0.05"], seeds=6)
    for r in rs:
        assert r["latitude_sigma_deg"] is None and "equator" in r["latitude_sigma_reason"]
        lo3, hi3 = r["latitude_interval_3sigma_deg"]
        assert lo3 == 0.0 and hi3 > 0.05
        assert r["earth_rate_sigma_rad_s"] < 1e-9          # n stays well measured by the meridian


def test_inseparable_measurements_give_null_latitude_with_the_reason():
    # Two horizontal gyroscopes measure only n cos γ: no latitude, no n. Two meridian gyroscopes
    # (sin ω = 1) measure n, not γ: n is their weighted mean, latitude null.
    y = 7.2921150e-5 * math.cos(math.radians(48.85))
    hh = [RateMeasurement("a", "gyro", y, 1e-11), RateMeasurement("b", "gyro", y * (1 + 1e-7), 1e-11)]
    r = solve_latitude(hh)
    assert r.latitude_rad is None and r.earth_rate_rad_s is None and "cannot be separated" in r.reason
    mm = [RateMeasurement("a", "gyro", 7.2921150e-5, 1e-11, (1, 0, 0)),
          RateMeasurement("b", "gyro", 7.2921170e-5, 2e-11, (1, 0, 0))]
    r = solve_latitude(mm)
    # weighted mean with weights 1/σ²: (4 · 7.2921150 + 1 · 7.2921170) / 5 e-5, σ = 1/√(1e22 + 0.25e22)
    assert r.latitude_rad is None and "not determined" in r.reason
    assert r.earth_rate_rad_s == pytest.approx((4 * 7.2921150e-5 + 7.2921170e-5) / 5, rel=1e-12)
    assert r.earth_rate_sigma_rad_s == pytest.approx(1 / math.sqrt(1.25e22), rel=1e-12)


def test_inseparable_scene_through_the_cli(capsys):
    # Issue 22: with estimator.earth_rate: estimate the two horizontal gyroscopes are refused as
    # before; unset, n is taken as known instead (tests/test_earth_rate_known.py)
    assert main(["estimate", "quet_gyroscopes", "--json", "--set", "instruments.gyro_meridian.plane=horizontal",
                 "--set", "estimator.earth_rate=estimate"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["latitude_deg"] is None and r["latitude_sigma_deg"] is None
    assert "cannot be separated" in r["reason"] and r["earth_rate_known"] is False
    json.dumps(r, allow_nan=False)


def test_single_measurement_states_what_it_determines():
    # Quet eq. (10): a meridian gyroscope alone gives n (sin ω = 1), not γ; a pendulum alone gives
    # k = n sin γ, a product (sec. 2); neither gets a latitude σ.
    k = 7.2921150e-5 * math.sin(math.radians(48.85))
    r = solve_latitude([RateMeasurement("pendulum", "pendulum", k, 1e-9)])
    assert r.latitude_rad is None and r.earth_rate_rad_s is None
    assert "cannot be separated" in r.reason and "meridian" in r.reason
    r = solve_latitude([RateMeasurement("gyro_meridian", "gyro", 7.2921150e-5, 1e-11, (1, 0, 0))])
    assert r.latitude_rad is None and "not determined" in r.reason
    assert r.earth_rate_rad_s == 7.2921150e-5 and r.earth_rate_sigma_rad_s == pytest.approx(1e-11, rel=1e-12)
