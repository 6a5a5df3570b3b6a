"""North from a horizontal gyroscope (issue 24 items 1, 2, 3, 6, 7 and its bad input).

Sign convention (estimators/north.py): the measured ``angle`` reads counter-clockwise like Quet's u,
offset by the mount: angle = u + M; the clockwise reading −angle is azimuth − M; the estimate's
``mount_azimuth_deg`` is M.
"""

import json
import math

import numpy as np
import pytest

from gyro_instrument.cli import main
from gyro_instrument.estimators import north
from gyro_instrument.estimators.north.field_book import write_field_book
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.instruments.observation_azimuth import HorizontalSwing
from gyro_instrument.scenes import load_scene
from gyro_instrument.sensors import SensorModel


def _wrap_arcsec(a_deg, b_deg):
    return ((a_deg - b_deg + 180.0) % 360.0 - 180.0) * 3600.0


def _quet(extra=()):
    return load_scene("quet_gyroscopes", ["duration_s=200", "instruments.gyro_meridian=null"] + list(extra))


def test_default_mount_reads_quet_u_and_a_mount_offsets_the_reading():
    scene0, scene1 = _quet(), _quet(["instruments.gyro_horizontal.mount_azimuth_deg=300.0"])
    r0 = measure(scene0, simulate_truth(scene0), 3)["gyro_horizontal"]
    r1 = measure(scene1, simulate_truth(scene1), 3)["gyro_horizontal"]
    # the same noise draws: the reading differs by M wrapped to (-180, 180] = -60 deg, exactly
    assert np.allclose(r1["angle"] - r0["angle"], math.radians(-60.0), atol=1e-12)


def _without_north(res):
    res = dict(res, instruments={k: {kk: vv for kk, vv in v.items() if kk != "north"}
                                 for k, v in res["instruments"].items()})
    res.pop("north", None)
    return res


def test_without_a_stated_mount_north_reads_mount_0_and_nothing_else_changes(monkeypatch):
    """Issue 24 item 1: every estimate with a horizontal gyroscope reports north; the default mount 0
    (the scale's zero on true north) keeps every other result of the estimate as it was without it."""
    scene = _quet()
    truth = simulate_truth(scene)
    recs = measure(scene, truth, 5)
    res = estimate_records(scene, truth[1], recs)
    n = res["north"]
    assert n is res["instruments"]["gyro_horizontal"]["north"]
    assert abs(_wrap_arcsec(n["mount_azimuth_deg"], 0.0)) < 5 * n["sigma_arcsec"]
    monkeypatch.setattr(HorizontalSwing, "ALSO_MEASURES", ())
    before = estimate_records(scene, truth[1], recs)
    assert "north" not in before and _without_north(res) == before


@pytest.mark.parametrize("sets,words", [
    (["duration_s=5"], ["one swing lasts", "observe >="]),
    (["site.latitude_deg=89.99"], ["one swing lasts", "site.latitude_deg = 89.99"]),
])
def test_unasked_north_on_an_inadequate_record_is_null_with_its_reason(sets, words, capsys):
    """No stated mount, no tape: a record shorter than one swing gives north null with the reason
    (never an exit 2, never a failed check); with a stated mount the same record is refused."""
    scene = _quet(sets)
    truth = simulate_truth(scene)
    res = estimate_records(scene, truth[1], measure(scene, truth, 2))
    n = res["north"]
    assert n["mount_azimuth_deg"] is None and n["interval_deg"] == [0.0, 360.0]
    assert all(w in n["reason"] for w in words), n["reason"]
    assert not [c for c in res["checks"] if c["check"] == "north"]
    args = ["estimate", "quet_gyroscopes", "--set", "instruments.gyro_meridian=null"]
    args += [x for s in sets + ["instruments.gyro_horizontal.mount_azimuth_deg=10"] for x in ("--set", s)]
    assert main(args) == 2 and "one swing lasts" in capsys.readouterr().err


def test_north_block_recovers_the_mount_azimuth():
    scene = _quet(["instruments.gyro_horizontal.mount_azimuth_deg=123.4"])
    truth = simulate_truth(scene)
    res = estimate_records(scene, truth[1], measure(scene, truth, 5))
    n = res["north"]
    assert n is res["instruments"]["gyro_horizontal"]["north"] and n["instrument"] == "gyro_horizontal"
    assert set(n["methods"]) == {"schuler_mean", "lavrov", "transit", "fit"}
    assert n["sigma_arcsec"] == n["methods"]["fit"]["sigma_arcsec"] and n["crlb_arcsec"] > 0
    for name, m in n["methods"].items():
        assert abs(_wrap_arcsec(m["mount_azimuth_deg"], 123.4)) < 5 * m["sigma_arcsec"] + (3.0 if name == "transit" else 0)
        assert m["needs"] and m["bias"]
    # the fit at the Cramer-Rao bound beats the reversal-point reductions
    assert n["sigma_arcsec"] < n["methods"]["schuler_mean"]["sigma_arcsec"]


def test_gyrotheodolite_scene_corrects_the_tape(capsys):
    assert main(["estimate", "gyrotheodolite", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    n = d["north"]
    assert n["instrument"] == "gak1" and n["tape"]["instrument"] == "gak1_rotor_off"
    assert n["tape"]["ratio_db_dk"] == pytest.approx(0.1, rel=5e-3)
    assert abs(_wrap_arcsec(n["mount_azimuth_deg"], 359.75)) < 4 * n["sigma_arcsec"]
    assert abs(_wrap_arcsec(n["methods"]["schuler_mean"]["mount_azimuth_deg"], 359.75)) < 4 * \
        n["methods"]["schuler_mean"]["sigma_arcsec"]
    # the uncorrected centre is pulled toward the tape zero by D_B/(D_K + D_B) (Z - N) ~ 98"
    assert d["instruments"]["gak1_rotor_off"]["reason"].startswith("not used")
    assert main(["estimate", "gyrotheodolite"]) == 0
    assert capsys.readouterr().out.startswith("north: scale zero of gak1 at azimuth 359.7")


def test_describe_predicts_the_tape(capsys):
    assert main(["describe", "gyrotheodolite", "--json"]) == 0
    pred = json.loads(capsys.readouterr().out)["instruments"]["gak1"]["predictions"]
    assert pred["tape_ratio"] == pytest.approx(0.1, rel=1e-9)
    assert 2 * pred["swing_duration_small_s"] == pytest.approx(480.0, rel=1e-6)
    assert pred["rotor_off_swing_duration_s"] == pytest.approx(240.0 * math.sqrt(11.0), rel=1e-6)


@pytest.mark.parametrize("sets,words", [
    (["instruments.gak1.mount_azimuth_deg=360"], ["mount_azimuth_deg", "360", "[0, 360)"]),
    (["instruments.gak1.mount_azimuth_deg=-0.5"], ["mount_azimuth_deg", "-0.5"]),
    (["effects.tape_torsion.torsion_constant_n_m_rad=3e-7"], ["torsion_constant_n_m_rad", "3e-07", "must be < D_K"]),
    (["site.latitude_deg=89.9"], ["torsion_constant_n_m_rad", "must be < D_K", "|site.latitude_deg| < 86.12"]),
    (["site.latitude_deg=89.9", "effects.tape_torsion=null", "effects.tape_drift=null"],
     ["site.latitude_deg = 89.9", "one swing lasts", "|site.latitude_deg| <="]),
    (["instruments.gak1_rotor_off=null"], ["rotor_off_instrument", "gak1_rotor_off", "rotor-off swing"]),
])
def test_bad_input_exits_2_naming_field_value_and_range(sets, words, capsys):
    args = ["estimate", "gyrotheodolite"] + [x for s in sets for x in ("--set", s)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and all(w in err for w in words), err


def test_at_the_pole_north_is_null_with_the_whole_circle():
    scene = _quet(["site.latitude_deg=90", "instruments.gyro_horizontal.mount_azimuth_deg=10.0"])
    truth = simulate_truth(scene)
    res = estimate_records(scene, truth[1], measure(scene, truth, 1))
    n = res["north"]
    assert n["mount_azimuth_deg"] is None and n["sigma_arcsec"] is None and n["interval_deg"] == [0.0, 360.0]
    assert "directing torque" in n["reason"]


def test_a_field_book_from_a_run_gives_what_the_run_gives(tmp_path, capsys):
    scene = _quet(["instruments.gyro_horizontal.mount_azimuth_deg=77.7"])
    truth = simulate_truth(scene)
    rec = measure(scene, truth, 2)["gyro_horizontal"]
    sigma = SensorModel.from_scene(scene).effective_sigma_rad()
    x = -rec["angle"]
    rp = north.reversal_points(rec["t"], x, sigma)
    run = north.north_methods(rec["t"], x, sigma)[0]
    write_field_book(tmp_path / "book.csv", rp.readings_rad, rp.times_s, angle_unit="gon")
    assert main(["estimate", "--reversal-points", str(tmp_path / "book.csv"), "--scene", "quet_gyroscopes",
                 "--json"]) == 0
    book = json.loads(capsys.readouterr().out)["north"]
    for name in ("schuler_mean", "lavrov"):
        b = book["methods"][name]
        # the same readings, the same Schuler weights; Lavrov's fit is weighted by the readings' sigmas in the
        # run and unweighted in the book (no sigmas written): equal to a small part of sigma
        tol = 1e-6 if name == "schuler_mean" else 0.05 * b["sigma_arcsec"]
        assert _wrap_arcsec(b["mount_azimuth_deg"], math.degrees(run[name].mount_azimuth_rad)) == pytest.approx(0, abs=tol)
        # sigma from the scatter (field book) against sigma propagated from the sensor (run)
        assert 0.5 < b["sigma_arcsec"] / (run[name].sigma_rad * 648000 / math.pi) < 2.0


CAL_SCENE = """
name: north_calibration
site: {{latitude_deg: {lat}}}
duration_s: 240
sample_rate_hz: 10
seed: 1
effects: {{earth_rotation: {{}}, pivot_damping: {{time_constant_s: 2000.0}}}}
sensor: {{noise_rad: 2.0e-4}}
instruments:
  g:
    type: plane_gyroscope
    plane: horizontal
    spin_rate_rad_s: 314.1592653589793
    initial_angle_deg: 3.0
    mount_azimuth_deg: 211.3
"""


@pytest.mark.slow
@pytest.mark.parametrize("lat", [33.0, -52.0])
def test_north_is_calibrated_over_seeds(lat, tmp_path):
    """Over 200 seeds: rms error / sigma in [0.8, 1.2], sigma / bound in [0.95, 1.1] for the fit (the
    bound: the fit's sigma on the noise-free record, the inverse Fisher information at the truth)."""
    path = tmp_path / "cal.yaml"
    path.write_text(CAL_SCENE.format(lat=lat))
    scene = load_scene(str(path))
    truth = simulate_truth(scene)
    t = truth[0]
    clean = -(truth[2]["g"].columns["angle"] + truth[1]["g"].mount_reading_rad)
    sensor = SensorModel.from_scene(scene)
    bound = north.fit_record(t, clean, sensor.noise_rad).sigma_rad
    rng = np.random.default_rng(24)
    noise = rng.normal(0.0, sensor.noise_rad, (200, t.size))       # the sensor's white noise, all seeds at once
    err, sig = {"fit": [], "schuler_mean": []}, {"fit": [], "schuler_mean": []}
    for row in noise:
        ests = north.north_methods(t, clean + row, sensor.noise_rad)[0]
        for k in err:
            err[k].append(_wrap_arcsec(math.degrees(ests[k].mount_azimuth_rad), 211.3))
            sig[k].append(ests[k].sigma_rad * 648000 / math.pi)
    for k in err:
        ratio = math.sqrt(np.mean(np.square(err[k]))) / np.mean(sig[k])
        print(f"latitude {lat}: {k} rms error / sigma = {ratio:.3f}")
        assert 0.8 <= ratio <= 1.2, (k, ratio)
    assert 0.95 <= np.mean(sig["fit"]) / (bound * 648000 / math.pi) <= 1.1


def test_a_record_of_one_sample_is_refused_not_divided_by(capsys):
    """A record shorter than one sample interval (0.05 s at 1 Hz: one sample, a span of 0 s) asked
    for north is refused with the span and the swing time (found by the CLI fuzz test: the latitude
    limit for a 0 s observation divided by zero)."""
    assert main(["estimate", "gyrotheodolite", "--duration-s", "0.05"]) == 2
    err = capsys.readouterr().err
    assert "record spans 0 s" in err and "observe >= 480 s" in err and "Traceback" not in err
