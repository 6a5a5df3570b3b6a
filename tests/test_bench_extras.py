"""The effect-cost study measures physics, and the bench plots are real PNGs.

Leaving an effect out of a shortened quet_paris (60 s, noise-free) changes each instrument's angle
by what the effect's size predicts: a relative frequency change ε accumulates a phase error ε ω t,
so the angle differs by at most a ω t ε (a the amplitude, ω = π/T the swing's angular frequency,
t the run). ε is the size ``gyro-instrument describe`` reports (``Effect.relative_size``), which is
an order-of-magnitude estimate (the exact frequency shift carries factors like sin ω / 2), so the
measured difference must agree with a ω t ε within a factor 10. Without ``earth_rotation`` the
gyroscopes have no restoring torque (Quet sec. 4 §1 eq. 9: the torque is μ n ρ sin ω) and stop
swinging, and the Foucault pendulum's swing plane stops turning.
"""

import math

import pytest

from gyro_instrument.bench.effect_cost import COMBINED, HEADER, effect_cost_rows, write_effect_cost_csv
from gyro_instrument.bench.plots import write_plots
from gyro_instrument.scenes import build_instruments, load_scene

DURATION = 60.0
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quet_rows():
    return effect_cost_rows(["quet_paris"], duration_s=DURATION)


def _row(rows, effect, instrument):
    (r,) = [r for r in rows if r[1] == effect and r[4] == instrument]
    return dict(zip(HEADER, r))


def _predicted_diff(effect, iname):
    """a ω t ε with ε the size ``describe`` reports for this instrument and effect."""
    scene = load_scene("quet_paris", [f"duration_s={DURATION}"])
    inst = build_instruments(scene)[iname]
    ctx = inst.effect_context(DURATION)
    eps, _ = scene.effects[effect].relative_size(ctx)
    return ctx.scales.amplitude_rad * ctx.scales.restoring_rate_rad_s * DURATION * eps


def test_rows_cover_every_effect_and_instrument(quet_rows):
    assert all(len(r) == len(HEADER) for r in quet_rows)
    effects = {r[1] for r in quet_rows}
    assert effects == {"earth_rotation", "centrifugal", "finite_amplitude"}
    for effect in effects:
        assert {r[4] for r in quet_rows if r[1] == effect} == {"gyro_horizontal", "gyro_meridian", "pendulum",
                                                               COMBINED}
    for r in quet_rows:
        assert r[2] > 0 and r[3] > 0, r  # CPU seconds with and without


@pytest.mark.parametrize("effect", ["centrifugal", "finite_amplitude"])
@pytest.mark.parametrize("iname", ["gyro_horizontal", "gyro_meridian", "pendulum"])
def test_angle_change_matches_the_reported_effect_size(quet_rows, effect, iname):
    row = _row(quet_rows, effect, iname)
    predicted = _predicted_diff(effect, iname)
    assert row["column"] == ("angle" if iname.startswith("gyro") else "deflection_east|deflection_north")
    ratio = row["max_abs_diff_rad"] / predicted
    assert 0.1 < ratio < 10, (row["max_abs_diff_rad"], predicted)


def test_centrifugal_barely_moves_the_recovered_latitude_and_rate(quet_rows):
    # O(n / μρ0) ~ 6e-8 relative: far below the demo's 3.9e-5 deg σ (README), but not zero
    row = _row(quet_rows, "centrifugal", COMBINED)
    assert 0 < abs(row["dlatitude_deg"]) < 1e-4
    assert 0 < abs(row["dearth_rate_rad_s"]) / 7.292115e-5 < 1e-6


def test_without_earth_rotation_the_instruments_do_not_see_the_earth(quet_rows):
    for iname in ("gyro_horizontal", "gyro_meridian"):
        row = _row(quet_rows, "earth_rotation", iname)
        # no restoring torque: the axis stays at its 0.1 rad release angle instead of swinging to -0.1
        assert row["max_abs_diff_rad"] == pytest.approx(0.2, rel=1e-3)
    # Foucault: the swing plane turns by k t (k = n sin γ); without the Earth it does not
    scene = load_scene("quet_paris")
    pend = _row(quet_rows, "earth_rotation", "pendulum")
    k = scene.site.earth_rate_rad_s * math.sin(scene.site.latitude_rad)
    assert pend["max_abs_diff_rad"] == pytest.approx(math.radians(2.0) * k * DURATION, rel=0.2)
    combined = _row(quet_rows, "earth_rotation", COMBINED)
    assert combined["dearth_rate_rad_s"] is None and "not estimable" in combined["note"]
    assert combined["dlatitude_deg"] is None or abs(combined["dlatitude_deg"]) > 10.0
    meridian = _row(quet_rows, "earth_rotation", "gyro_meridian")
    assert meridian["dearth_rate_rad_s"] is None and "no oscillation" in meridian["note"]


def test_inactive_effect_changes_nothing_and_effectless_scenes_do_not_crash():
    rows = effect_cost_rows(["quet_paris"], duration_s=20.0,
                            overrides=["instruments.pendulum.effects=[earth_rotation, finite_amplitude]"])
    pend = _row(rows, "centrifugal", "pendulum")
    assert pend["max_abs_diff_rad"] == 0.0 and "not active" in pend["note"]
    assert _row(rows, "centrifugal", "gyro_meridian")["max_abs_diff_rad"] > 0
    rows = effect_cost_rows(["puiseux_spheroid", "no_such_scene"], duration_s=2.0, executor=_SerialExecutor())
    (spheroid,) = [r for r in rows if r[0] == "puiseux_spheroid"]
    assert spheroid[1] is None and spheroid[6] is None and "no effects" in spheroid[9]
    (missing,) = [r for r in rows if r[0] == "no_such_scene"]
    assert missing[6] is None and "not loaded" in missing[9]


def test_worker_runs_in_the_process_pool():
    # two scenes: the default spawned process pool runs the picklable worker
    rows = effect_cost_rows(["free_gyroscope", "puiseux_spheroid"], duration_s=2.0)
    free = dict(zip(HEADER, [r for r in rows if r[0] == "free_gyroscope" and r[4] == "free_gyro"][0]))
    # the free gyroscope measures no Earth rate; without the Earth's rotation its axis stays put
    # relative to the ground instead of following the stars (hour angle grows at n)
    assert free["dlatitude_deg"] is None and "no Earth rate" in free["note"]
    assert free["max_abs_diff_rad"] > 0


def test_plots_are_png(tmp_path, quet_rows):
    import matplotlib  # the plot extra: this test needs it, it is not skipped
    assert matplotlib.__version__
    (tmp_path / "work_precision.csv").write_text(
        "instrument,method,setting,cpu_s,nfev,error_rad\n"
        "pendulum,DOP853,rtol 1e-06,0.05,4055,2.7e-08\npendulum,DOP853,rtol 1e-10,0.3,25000,4.8e-12\n"
        "pendulum,Binet closed form,,0.0004,0,1.3e-05\n")
    (tmp_path / "observation_time.csv").write_text(
        "minutes,rms_fit_deg,mean_sigma_deg,crlb_deg,rms_counting_deg\n"
        "1.0,1e-3,1.1e-3,1e-3,5.0\n2.0,3.5e-4,3.9e-4,3.5e-4,2.4\n")
    write_effect_cost_csv(tmp_path / "effect_cost.csv", quet_rows)
    paths = write_plots(str(tmp_path))
    assert [p.rsplit("/", 1)[-1] for p in paths] == ["work_precision.png", "observation_time.png",
                                                     "effect_cost.png"]
    for p in paths:
        with open(p, "rb") as fh:
            assert fh.read(8) == PNG_SIGNATURE, p


def test_plots_without_matplotlib_write_nothing(tmp_path, monkeypatch):
    import sys
    (tmp_path / "observation_time.csv").write_text("minutes,rms_fit_deg,mean_sigma_deg,crlb_deg,rms_counting_deg\n"
                                                   "1.0,1e-3,1.1e-3,1e-3,5.0\n")
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib now raises ImportError
    assert write_plots(str(tmp_path)) == []
    assert not list(tmp_path.glob("*.png"))


class _SerialExecutor:
    """In-process stand-in with the ``concurrent.futures`` ``map`` interface."""

    def map(self, fn, *iterables):
        return map(fn, *iterables)


def test_site_sweep_gives_the_same_numbers_on_any_executor(pool):
    # The sweep's only contract with its executor is concurrent.futures' ``map``: a thread pool (a
    # stand-in for a Dask client's get_executor(), which is not installed here) and the default
    # spawned process pool must give bit-identical rows, because every seed's noise comes from its
    # own seeded generator (sensors.scene_rng), never from the worker it lands on.
    from concurrent.futures import ThreadPoolExecutor

    from gyro_instrument.bench.studies import site_sweep
    sites = (-33.9, 48.8462)
    with ThreadPoolExecutor(2) as ex:
        threads = site_sweep(sites, 3, minutes=1.0, executor=ex)
    procs = site_sweep(sites, 3, minutes=1.0, executor=pool)          # the session's spawned pool
    assert threads == procs
    assert [r[0] for r in threads] == list(sites)
