"""The rate-gyro north finder (issue 35 item 3): physics of the estimate, not its shape.

Every scene is simulated once and measured with many sensor seeds (the gyro's own error model:
turn-on bias, Gauss–Markov bias instability, angle random walk; instruments/rate_gyro/sensor.py).
Calibration: Σ z² over N seeds, z = (M̂ − M)/σ, lies inside the χ²_N band (0.1 % – 99.9 %): σ is
neither optimistic nor pessimistic. σ is the Cramér–Rao bound of the bin means; it is checked
against the bound of the raw samples (dense covariance) on a short record.
"""

import math

import numpy as np
import pytest
from scipy.stats import chi2

from gyro_instrument.estimators.north import rate_gyro as R
from gyro_instrument.estimators.measure import MeasureStream, measure, simulate_truth
from gyro_instrument.estimators.pipeline import estimate_records
from gyro_instrument.instruments.rate_gyro.sensor import DEG_H, GM_ALLAN_PEAK, gm_allan_variance
from gyro_instrument.scenes import load_scene


def _one(name, overrides=()):
    scene = load_scene(name, list(overrides))
    truth = simulate_truth(scene)
    (iname, inst), = truth[1].items()
    return scene, truth, iname, inst


def _z(name, seeds, overrides=()):
    """z = (M̂ − M)/σ over ``seeds`` (M the scene's mount azimuth), and the fits."""
    scene, truth, iname, inst = _one(name, overrides)
    obs, m = inst.observation(), math.radians(inst.p.mount_azimuth_deg)
    fits = [R.fit_record(obs, measure(scene, truth, s)[iname]) for s in seeds]
    return np.array([R._wrap(f["mount_rad"] - m) / f["sigma_rad"] for f in fits]), fits


def _in_chi2_band(z):
    """Σ z² inside the χ²_N 0.1 %–99.9 % band (a calibrated σ fails this 1 time in 500)."""
    s, n = float(np.sum(z ** 2)), z.size
    return chi2.ppf(0.001, n) <= s <= chi2.ppf(0.999, n), s, n


# the default run: 40 seeds of each scene (the carousel shortened to 5 min: 0.05 s per fit), ~4 s in all
CASES = [("rate_gyro_four_position", ()), ("rate_gyro_two_position", ()),
         ("rate_gyro_carousel", ("duration_s=300",))]


@pytest.mark.parametrize("name, overrides", CASES)
def test_north_calibrated_over_seeds(name, overrides):
    z, fits = _z(name, range(40), overrides)
    ok, s, n = _in_chi2_band(z)
    assert ok, f"{name}: sum z^2 = {s:.1f} over {n} seeds, outside the chi2_{n} 0.1-99.9 % band"
    assert np.max(np.abs(z)) < 4.5            # P(|z| > 4.5 in 40 draws) = 3e-4
    assert all(abs(f["chi2"] / f["dof"] - 1.0) < 5.0 * math.sqrt(2.0 / f["dof"]) for f in fits)  # noise model fits


@pytest.mark.slow
@pytest.mark.parametrize("name", ["rate_gyro_four_position", "rate_gyro_two_position", "rate_gyro_carousel"])
def test_north_calibrated_over_200_seeds(name):
    z, _ = _z(name, range(1000, 1200))
    ok, s, n = _in_chi2_band(z)
    assert ok, f"{name}: sum z^2 = {s:.1f} over {n} seeds"
    assert abs(np.mean(z)) < 4.0 / math.sqrt(n)          # no bias beyond 4 standard errors of the mean


def test_sigma_is_the_raw_samples_cramer_rao_bound():
    """The bin means lose almost nothing: σ_M from them vs from the raw samples' Fisher information
    J = Hᵀ C⁻¹ H with the dense covariance σ_w² I + σ_g² ρ^|i−j| (400 s at 5 Hz, 1 800 used samples).
    Tolerance 1 %: bins of τ_c/16 keep the Gauss–Markov's shape (measured 0.17 %; 2.7 % with τ_c/4)."""
    scene, truth, iname, inst = _one("rate_gyro_four_position",
                                     ("duration_s=400", "sample_rate_hz=5", "instruments.fog.dwell_s=90",
                                      "instruments.fog.bias_correlation_time_s=60",
                                      "instruments.fog.bias_instability_deg_h=0.3"))
    obs = inst.observation()
    rec = measure(scene, truth, 1)[iname]
    f = R.fit_record(obs, rec)
    k, phi, r, dt, noise, d = R._prepare(obs, rec)
    used = np.concatenate([np.arange(s, e) for s, e in d["bins"]])
    H = np.column_stack([np.cos(phi[used]), -np.sin(phi[used]), np.ones(used.size)])
    ki = k[used]
    C = noise["sigma_white_rad_s"] ** 2 * np.eye(used.size) + noise["sigma_gm_rad_s"] ** 2 * \
        math.exp(-dt / noise["correlation_time_s"]) ** np.abs(ki[:, None] - ki[None, :])
    cov = np.linalg.inv(H.T @ np.linalg.solve(C, H))
    a, c = f["amplitude_rad_s"] * math.cos(f["mount_rad"]), f["amplitude_rad_s"] * math.sin(f["mount_rad"])
    g = np.array([-c, a, 0.0]) / (a * a + c * c)
    raw = math.sqrt(g @ cov @ g)
    assert raw <= f["sigma_rad"] <= 1.01 * raw


def test_four_position_closed_form_equals_least_squares_for_white_noise():
    """N = atan2(r90 − r270, r0 − r180): with white noise only (no bias instability) and the four
    positions' dwells sampled alike, the least squares is the closed form (the design is balanced:
    the same samples at each position) — equal to 1e-9 rad, and so are their σ."""
    scene, truth, iname, inst = _one("rate_gyro_four_position", ("instruments.fog.bias_instability_deg_h=0",
                                                                "sample_rate_hz=4"))
    f = R.fit_record(inst.observation(), measure(scene, truth, 3)[iname])
    n_per_position = {round(float(p), 9): 0 for p in f["design"]["phi"]}
    for p, n in zip(f["design"]["phi"], f["design"]["n"]):
        n_per_position[round(float(p), 9)] += n
    assert len(set(n_per_position.values())) == 1          # balanced: the premise of the equality
    cf = f["closed_form"]
    assert abs(R._wrap(cf["mount_rad"] - f["mount_rad"])) < 1e-9
    assert cf["sigma_rad"] == pytest.approx(f["sigma_rad"], rel=1e-9)


def test_two_positions_mirror_image_resolved_by_the_stated_prior():
    """cos(M + φ0) is all two positions measure: the candidates are M and −M − 2φ0 (75° and 285° here).
    The prior 60 ± 45° keeps 75°; a prior on the mirror side (300 ± 45°) keeps the mirror image, and
    says so; no prior (± 180°) gives a null azimuth with both candidates."""
    scene, truth, iname, inst = _one("rate_gyro_two_position")
    rec = measure(scene, truth, 7)[iname]
    block = R.north_block(inst.observation(), R.fit_record(inst.observation(), rec)).to_json()
    cands = block["sign"]["candidates_deg"]
    assert sorted(cands)[0] + sorted(cands)[1] == pytest.approx(360.0, abs=1e-9)  # M and −M (φ0 = 0)
    assert block["sign"]["resolved_by"] == "prior"
    assert abs(block["mount_azimuth_deg"] - 75.0) < 5.0 * block["sigma_arcsec"] / 3600.0
    for prior, tol, expect in ((300.0, 45.0, max(cands)), (60.0, 180.0, None)):
        sc, tr, _, inst2 = _one("rate_gyro_two_position", (f"instruments.mems.mount_azimuth_prior_deg={prior}",
                                                          f"instruments.mems.mount_azimuth_prior_tolerance_deg={tol}"))
        b = R.north_block(inst2.observation(), R.fit_record(inst2.observation(), measure(sc, tr, 7)[iname])).to_json()
        assert b["sign"]["candidates_deg"] == pytest.approx(cands)
        if expect is None:
            assert b["mount_azimuth_deg"] is None and b["sign"]["resolved_by"] is None and "mirror" in b["reason"]
        else:
            assert b["mount_azimuth_deg"] == pytest.approx(expect) and b["sign"]["resolved_by"] == "prior"


def test_gauss_markov_matches_the_datasheet_allan_minimum():
    """The bias instability B is the Allan deviation's floor (ADI's convention): the Gauss–Markov's
    Allan deviation peaks at B, at τ = 1.89 τ_c (IEEE Std 952 annex C); its known peak 0.6174 σ."""
    assert GM_ALLAN_PEAK == pytest.approx(0.6174, abs=2e-4)
    scene, truth, iname, inst = _one("rate_gyro_two_position")
    sigma_g = inst.observation().noise_model(0.05)["sigma_gm_rad_s"]
    taus = np.linspace(10.0, 2000.0, 2000)
    peak = float(np.max(np.sqrt(gm_allan_variance(taus, sigma_g, inst.p.bias_correlation_time_s))))
    assert peak / DEG_H == pytest.approx(inst.p.bias_instability_deg_h, rel=1e-4)


def test_streamed_draws_equal_the_one_shot_draws():
    """The estimator node and the recorder draw block by block (MeasureStream): the same doubles as
    ``measure`` (the Gauss–Markov state carried across blocks)."""
    from gyro_instrument.scenes import build_instruments
    scene, truth, iname, _ = _one("rate_gyro_two_position")
    t = truth[0]
    whole = measure(scene, truth, 5)[iname]
    inst = build_instruments(scene)[iname]         # a fresh one, as the recorder's: not yet simulated
    ms = MeasureStream(scene, inst, t.size, 5)
    inst.simulate(t)
    cols = truth[2][iname].columns
    parts = [ms.block(t[i:j], {k: v[i:j] for k, v in cols.items()}) for i, j in ((0, 1000), (1000, 1001), (1001, t.size))]
    assert np.array_equal(np.concatenate([p["rate"] for p in parts]), whole["rate"])


def test_estimate_reports_the_north_block_and_no_latitude():
    """Through the pipeline: the top-level ``north`` is the rate gyro's; no latitude (one horizontal
    axis reads (1 + s) n cos γ: latitude and scale factor are not separable), said in ``undetermined``."""
    scene, truth, iname, inst = _one("rate_gyro_four_position")
    est = estimate_records(scene, truth[1], measure(scene, truth))
    assert est["north"]["instrument"] == iname and est["latitude_deg"] is None
    assert est["instruments"][iname]["north"] is est["north"]
    assert any("latitude and scale factor" in u for u in est["north"]["undetermined"])
    # the FOG's amplitude gives the scale factor (50 ppm simulated) within 4 sigma
    sf = est["north"]["scale_factor"]
    assert abs(sf["ppm"] - 50.0) < 4.0 * sf["sigma_ppm"]


def test_one_position_gives_a_null_block_with_its_reason():
    scene, truth, iname, inst = _one("rate_gyro_four_position", ("instruments.fog.positions=1",))
    b = R.north_block(inst.observation(), R.fit_record(inst.observation(), measure(scene, truth)[iname])).to_json()
    assert b["mount_azimuth_deg"] is None and "one position" in b["reason"]


def test_plan_bound_is_the_estimators_sigma_and_its_time_reaches_the_target():
    """``plan --target azimuth_arcsec``: its bound for the scene's own record is the estimate's σ (2 %:
    the planner bins more coarsely), and at the planned number of sequences the bound meets the target
    while one sequence fewer does not (the search's 2 % tolerance aside)."""
    from gyro_instrument.estimators.planner import parse_targets, plan
    from gyro_instrument.estimators.north.rate_gyro_plan import sigma_mount_rad
    scene, truth, iname, inst = _one("rate_gyro_four_position")
    f = R.fit_record(inst.observation(), measure(scene, truth, 1)[iname])
    assert sigma_mount_rad(inst, inst.p, scene.duration_s, scene.sample_rate_hz) == pytest.approx(f["sigma_rad"], rel=0.02)
    d = plan("rate_gyro_four_position", [], parse_targets(["azimuth_arcsec=600"]))
    e = d["targets"][0]
    assert e["instrument"] == iname and e["planned_sigma"] <= 600.0
    seq = inst.p.positions * (inst.p.dwell_s + inst.p.slew_s)
    fewer = sigma_mount_rad(inst, inst.p, e["observation_s"] - seq, scene.sample_rate_hz) * R.ARCSEC_PER_RAD
    assert fewer > 600.0
    assert e["schedule"]["time_per_position_s"] == e["schedule"]["sequences"] * inst.p.dwell_s


def test_bench_rows_noise_free_exact_and_sigma_at_the_bound():
    """The bench's table (estimators/north/rate_gyro_study.py, the kind's bench study) at 10 min: the noise-free record gives the mount
    azimuth exactly (the linear model is the simulated one: < 1e-6″), and the mean reported σ is the
    planner's bound to 10 % (the estimator's bins vs the planner's; a carousel's long bins lose most)."""
    from gyro_instrument.estimators.north.rate_gyro_study import rate_gyro_rows, same_time_lines
    rows = rate_gyro_rows(quick=True, duration_s=600.0)
    assert {r["scene"] for r in rows} == {c[0] for c in CASES}
    for r in rows:
        assert abs(r["noise_free_error_arcsec"]) < 1e-6
        assert r["mean_sigma_arcsec"] == pytest.approx(r["crlb_arcsec"], rel=0.10)
    assert len(same_time_lines(rows, [])) == 5 + len(rows)


def test_the_registered_kind_gives_the_same_block_bound_and_a_live_heading():
    """The registered kind ``rate_azimuth`` (estimators/rate_gyro_kind.py, complete: nothing missing):
    its engine's block is the estimate's, its bound the estimate's σ (to 2 %: the planner's binning), its
    live tracker's north from the first half of the record within 4 of its σ of the truth and its σ
    larger than the whole record's."""
    from gyro_instrument.estimators.rate_gyro_kind import RateAzimuthKind
    from gyro_instrument.instruments.measurement import kind, measured
    k = kind("rate_azimuth")
    assert type(k) is RateAzimuthKind and RateAzimuthKind.missing() == []
    scene, truth, iname, inst = _one("rate_gyro_four_position")
    obs = inst.observation()
    assert measured(inst)
    assert estimate_records(scene, truth[1], measure(scene, truth, 2))["north"] == \
        R.north_block(obs, R.fit_record(obs, measure(scene, truth, 2)[iname])).to_json()
    rec = measure(scene, truth, 2)[iname]
    block, none = k.estimate(obs, rec, (), [], None)
    assert none is None and block == R.north_block(obs, R.fit_record(obs, rec))
    model, _ = k.probe(scene, obs)
    assert k.bound(model, scene.duration_s, None)[0] == pytest.approx(block.sigma_arcsec / R.ARCSEC_PER_RAD, rel=0.02)
    half = {key: v[: v.size // 2] for key, v in rec.items()}
    m_half, s_half = k.tracker(obs, scene, {}).update(iname, half)
    assert abs(R._wrap(m_half - math.radians(inst.p.mount_azimuth_deg))) < 4.0 * s_half
    assert s_half > block.sigma_arcsec / R.ARCSEC_PER_RAD


def test_an_index_logged_in_degrees_just_below_a_turn_is_the_same_heading():
    """A table's index 359.9999999° (read with --angle-unit deg) is the heading 0°: the four positions
    stay four, and the estimate is the one from the exact index to 1e-9 of σ."""
    scene, truth, iname, inst = _one("rate_gyro_four_position", ("duration_s=1440",))
    obs = inst.observation()
    rec = measure(scene, truth, 4)[iname]
    f = R.fit_record(obs, rec)
    shifted = dict(rec, index=np.where(rec["index"] == 0.0, 2 * math.pi - 1e-12, rec["index"]))
    g = R.fit_record(obs, shifted)
    assert g["headings"] == 4 and g["closed_form"] is not None
    assert abs(R._wrap(g["mount_rad"] - f["mount_rad"])) < 1e-9 * f["sigma_rad"] + 1e-11
