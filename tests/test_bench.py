"""``gyro-instrument bench --quick`` writes its CSVs, plots and summary; the studies measure physics:
DOP853's azimuth error falls with the tolerance, the parareal fast path reaches the tight
reference, Quet's fidelity tiers are ordered as their physics says, the fit beats Quet's counting
by orders of magnitude at every observation time, and the ROS suite records everything."""

import csv
import math

import pytest
from scipy.special import ellipk

from gyro_instrument.cli import main


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """``gyro-instrument bench --quick --scheduler ADDRESS``: the whole quick bench, its seeded sweeps on a
    LocalCluster of two worker processes on loopback (dashboard off), the CI machine's two cores as the
    process pool of a plain ``bench --quick`` (the sweeps' rows are the same on either executor:
    test_cluster.py). Returns the output directory; the task names the cluster's scheduler saw go to
    :data:`RAN_ON_THE_CLUSTER`."""
    import os

    from dask.distributed import Client, LocalCluster
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")          # one BLAS thread per worker process, as the process pool
    out = tmp_path_factory.mktemp("bench")
    with LocalCluster(host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        assert main(["bench", "--quick", "--out", str(out), "--scheduler", cluster.scheduler_address]) == 0
        with Client(cluster.scheduler_address, set_as_default=False) as client:
            ran = client.run_on_scheduler(lambda dask_scheduler: sorted(dask_scheduler.task_prefixes))
    RAN_ON_THE_CLUSTER[:] = ran
    return out


RAN_ON_THE_CLUSTER = []      # the task names (function names) the cluster's scheduler saw


def rows(out, name):
    return list(csv.DictReader(open(out / name)))


def test_bench_scheduler_runs_the_sweeps_on_dask(bench):
    # the quick bench's seeded studies ran their tasks on the cluster (none on a pool of its own): the
    # seed sweeps (observation time, planner, north scene rows), the sweep runner's points (site sweep),
    # the systematic floors and the effect cost, by the names of their task functions
    assert RAN_ON_THE_CLUSTER == ["scene_effect_cost", "seed_sweep", "sweep_point", "systematic_floor_rows"]


def test_bench_quick_writes_studies_and_plots(bench):
    for name in ("work_precision.csv", "targets.csv", "observation_time.csv", "systematic_floors.csv", "site_sweep.csv",
                 "effect_cost.csv", "summary.md", "spin_work_precision.csv", "compiled_reference.csv",
                 "sweep_throughput.csv", "marine_checks.csv",
                 "work_precision.png", "observation_time.png", "effect_cost.png"):
        assert (bench / name).exists(), name
    assert "Regenerate: `gyro-instrument bench --quick" in (bench / "summary.md").read_text()
    # a measurement kind's own study (the rate gyro's kind: north in the gyrotheodolite's hour)
    assert (bench / "north_rate_gyro.csv").exists()
    assert "## North in the same time" in (bench / "summary.md").read_text()


def test_work_precision_tiers(bench):
    wp = rows(bench, "work_precision.csv")
    fou = [r for r in wp if r["instrument"].startswith("Foucault")]
    dop = [r for r in fou if r["method"] == "full equations, DOP853"]
    errs = [float(r["error_rad"]) for r in sorted(dop, key=lambda r: -float(r["setting"].split()[1]))]
    assert errs == sorted(errs, reverse=True) and errs[-1] < 1e-9
    # the fast path integrates the full equations: as accurate as the tightest DOP853 here, cheaper
    fast = [r for r in fou if "parareal" in r["method"] and r["setting"].startswith("48")][0]
    assert float(fast["error_rad"]) < 1e-9
    assert float(fast["cpu_s"]) < min(float(r["cpu_s"]) for r in dop)
    # Quet's tiers over 1 h of the 2° Pantheon pendulum: the comparison pendulum (exact first
    # swing, turned) is off by less than 1e-5 rad; the small-angle model and Binet's ellipse miss
    # the Airy precession of the finite swing (~1e-4 rad) and agree with each other, Binet being
    # the linear model's exact solution (to 1e-8 rad).
    tier = {r["method"]: float(r["error_rad"]) for r in fou}
    comp = tier["Quet's comparison pendulum (first swing turned by its apsidal angle)"]
    lin, binet = tier["linear (small-angle) model, DOP853"], tier["Binet's closed form (linear model)"]
    assert comp < 1e-5 < lin
    assert abs(lin - binet) < 1e-8
    gyro = {r["method"] + r["setting"]: float(r["error_rad"]) for r in wp if r["instrument"].startswith("plane")}
    assert gyro["exact equations (hinge chain), DOP853rtol 1e-09"] < 1e-8
    # the reduced equations drop only O(n/ρ) terms (~1e-9 rad here): at rtol 1e-9 they are as good
    assert gyro["Quet's reduced equations, DOP853rtol 1e-09"] < 1e-8
    # the free gyroscope's closed form (sec. 4 §II) is exact for the rigid body: it agrees with the
    # numerical solution at rtol 1e-13 to round-off (1e-12 rad), at no integration cost
    free = [r for r in wp if r["instrument"].startswith("free_gyro") and r["method"].startswith("Quet")][0]
    assert float(free["error_rad"]) < 1e-12 and free["nfev"] == "0"
    # every instrument's DOP853 error falls as the tolerance tightens
    for inst, method in {(r["instrument"], r["method"]) for r in wp if r["method"].endswith("DOP853")}:
        d = sorted(((float(r["setting"].split()[1]), float(r["error_rad"])) for r in wp
                    if (r["instrument"], r["method"]) == (inst, method)), reverse=True)
        assert [e for _, e in d] == sorted((e for _, e in d), reverse=True), (inst, method)


def test_targets_and_observation_time(bench):
    tg = {r["target"]: r for r in rows(bench, "targets.csv")}
    suite = [r for k, r in tg.items() if k.startswith("ROS suite")][0]
    assert float(suite["measured"]) > 0          # measured, and the recording held every message
    az = [r for k, r in tg.items() if k.endswith("end azimuth error")][0]
    assert float(az["measured"]) <= 1e-6
    # the plotting row is measured (its ≤ 10 s target is the bench's to judge, not a timed test's: under
    # load a test machine takes longer); its pictures are there
    plot = [r for k, r in tg.items() if k.startswith("plot 3 h of pendulum data")][0]
    assert float(plot["measured"]) > 0 and plot["met"] in ("True", "False")
    assert sorted(p.name for p in (bench / "plot_day").iterdir()) == \
        ["angles.png", "bob_path.png", "residuals.png", "swing_azimuth.png"]
    for r in rows(bench, "observation_time.csv"):
        assert float(r["rms_counting_deg"]) > 100 * float(r["rms_fit_deg"])
        assert float(r["rms_counting_earth_rate_rad_s"]) > 100 * float(r["rms_fit_earth_rate_rad_s"])
        # the estimator's own (noise-free) floor is far below the Cramér–Rao bound at these lengths
        assert abs(float(r["noise_free_error_deg"])) < 0.01 * float(r["crlb_deg"])
        assert abs(float(r["noise_free_earth_rate_error_rad_s"])) < 0.01 * float(r["crlb_earth_rate_rad_s"])
    # systematic floors (noise-free, quet_paris with a 1 h spin decay added)
    obs = {float(r["minutes"]): r for r in rows(bench, "observation_time.csv")}
    fl = rows(bench, "systematic_floors.csv")
    pick = lambda left, scope: [r for r in fl if r["left_out"] == left and r["scope"].startswith(scope)]  # noqa: E731
    # the Foucault pendulum alone would be off by ~0.03° without the ellipse-precession correction
    # (sec. 2 §III: at 2° the ellipse's precession adds to k; issue 3 measured this 0.030°)
    airy = [abs(float(r["latitude_bias_deg"])) for r in pick("ellipse_precession", "Foucault")]
    assert airy and all(0.01 < a < 0.1 for a in airy)
    # with every correction the gyroscope pair's bias stays under a tenth of its Cramér–Rao bound:
    # the spin-warped fit absorbs a 1 h spin decay at these lengths
    for r in pick("none", "gyroscope pair"):
        o = obs[float(r["minutes"])]
        assert abs(float(r["latitude_bias_deg"])) < 0.1 * float(o["crlb_deg"]), r
        assert abs(float(r["earth_rate_bias_rad_s"])) < 0.1 * float(o["crlb_earth_rate_rad_s"]), r
    # without the finite-amplitude reduction eq. (10) reads T = T0 (2/π)K(sin(a/2)) as T0: n is low by
    # n (1 - 1/F²) with a = 0.1 rad (the scene's release); the amplitude grows as ρ^(-1/4) while the
    # spin decays (≤ 8 % in 5 min: ≤ 2 % on a², hence 5 %); item 9's ratio is unchanged (equal amplitudes)
    F = 2 / math.pi * ellipk(math.sin(0.05) ** 2)
    predicted = -7.292115e-5 * (1 - 1 / F ** 2)
    for r in pick("finite_amplitude", "gyroscope pair"):
        assert abs(float(r["earth_rate_bias_rad_s"]) / predicted - 1) < 0.05, r
    # a spin decay the estimator did not follow costs far more than the noise (τ = 1 h: ρ falls 1.7 %
    # a minute, T ∝ ρ^-1/2)
    for r in pick("spin_decay", "gyroscope pair"):
        assert abs(float(r["earth_rate_bias_rad_s"])) > 10 * float(obs[float(r["minutes"])]["crlb_earth_rate_rad_s"]), r


# The reported σ is the inverse Fisher information at the estimate, the Cramér–Rao bound the same at
# the truth: they differ by how the information changes over the estimate's scatter (measured 2026-12-07:
# 0.998, 1.012 on quet_paris at -33.9°, 48.85° and 1.011, 1.033 on quet_gyroscopes at 20°, 60°, spread
# over seeds 1e-3); the band of the suite's other calibrations (test_north_exact, test_gyrotheodolite).
SIGMA_OVER_BOUND = (0.95, 1.1)
SITE_SWEEP_SEEDS = 4            # the quick bench's site sweep (studies.run_bench)


def test_site_sweep(bench):
    # quet_paris moved to another site: the reported σ follows the Cramér–Rao bound (the fit is
    # efficient, issue 3's calibration), and the rms error over the quick bench's 4 seeds is of that
    # size. 4 seeds bound rms/σ only to [0.13, 2.24] (99.9 %): this catches a σ off by more than 2x,
    # no finer; raising the seeds to 24 ([0.56, 1.49]) would cost the bench ~15 s, so the calibration
    # proper is test_estimators' (60-200 seeds, on the same fit).
    # n (rms/σ)² is χ² with n = 4 degrees of freedom (Gaussian errors, σ the same on every seed to 1e-3)
    from scipy.stats import chi2
    lo, hi = (math.sqrt(chi2.ppf(q, SITE_SWEEP_SEEDS) / SITE_SWEEP_SEEDS) for q in (5e-4, 1 - 5e-4))
    for r in rows(bench, "site_sweep.csv"):
        ratio = float(r["mean_sigma_deg"]) / float(r["crlb_deg"])
        assert SIGMA_OVER_BOUND[0] < ratio < SIGMA_OVER_BOUND[1], r
        assert lo < float(r["rms_error_deg"]) / float(r["mean_sigma_deg"]) < hi, r
        # the Earth rate: against its bound, σ ≈ bound within the same band
        assert lo * SIGMA_OVER_BOUND[0] < float(r["rms_earth_rate_error_rad_s"]) / float(r["crlb_earth_rate_rad_s"]) \
            < hi * SIGMA_OVER_BOUND[1], r


def test_bench_planner_accuracy(bench):
    # the planner's accuracy (planned vs achieved) in the bench: quick runs 16 seeds, whose rms has a
    # relative standard deviation of 1/√32 = 18 %: within [0.55, 1.45] of the target is ±2.5 σ
    pl = rows(bench, "planner.csv")
    assert {r["target"] for r in pl} == {"latitude_arcsec", "earth_rate_rad_s"}
    for r in pl:
        assert 0.55 < float(r["achieved_over_target"]) < 1.45, r
    assert "How long must I observe?" in (bench / "summary.md").read_text()


def test_cost_studies(bench):
    """Issue 27's studies in the bench. Spin integrators: every row's error against its tight DOP853
    reference is finite, and each instrument's spin integrator reaches 1e-9 rad somewhere in its sweep
    (their rows at rtol 1e-10 to 1e-12 measured 1e-14 to 8e-11 rad). The compiled reference and the fast
    path integrate the same equations with the same 48 RK8 steps per swing, so their end azimuths agree
    with the DOP853 rtol 1e-13 reference to the fast path's own bound (1e-6 rad, the targets row above;
    measured 4e-14 and 5e-13 rad over the quick hour). The sweep's rows are the same on the process pool
    and on the Dask cluster (same seeds, same code)."""
    spin = rows(bench, "spin_work_precision.csv")
    assert {r["instrument"].split()[0] for r in spin} >= {"free_gyroscope", "spheroid", "body", "gimbal_paris"}
    assert all(math.isfinite(float(r["max_error_rad"])) for r in spin)
    for inst in {r["instrument"] for r in spin}:
        new = [float(r["max_error_rad"]) for r in spin if r["instrument"] == inst
               and r["integrator"].lower() != "dop853" and not r["integrator"].lower().startswith("fortran")]
        assert new and min(new) < 1e-9, inst
    cr = rows(bench, "compiled_reference.csv")
    assert len(cr) == 2 and all(float(r["end_error_rad"]) <= 1e-6 for r in cr)
    # sweep throughput (bench.sweep_bench.sweep_throughput_rows, quick): the quick grid on the process pool,
    # then on a Dask LocalCluster; every row of the cluster's table equal to the pool's (same seeds)
    from gyro_instrument.bench.sweep_bench import GRIDS
    scene, overrides, specs, n_seeds = GRIDS[True]
    sw = rows(bench, "sweep_throughput.csv")
    assert [r["scheduler"].split()[0] for r in sw] == ["process", "dask.distributed"]
    for r in sw:
        assert list(r) == ["scheduler", "scene", "overrides", "vary", "seeds", "points", "rows", "errors", "wall_s",
                           "rows_per_s", "startup_s", "same_rows_as_process_pool"]
        assert (r["scene"], r["overrides"], r["vary"], int(r["seeds"]), int(r["points"])) == \
            (scene, " ".join(overrides), " ".join(specs), n_seeds, 2)
        assert int(r["rows"]) == 2 * n_seeds and int(r["errors"]) == 0
        assert float(r["wall_s"]) > 0 and float(r["rows_per_s"]) == pytest.approx(int(r["rows"]) / float(r["wall_s"]))
        assert float(r["startup_s"]) >= 0 and r["same_rows_as_process_pool"] == "True"
