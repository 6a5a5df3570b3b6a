"""The bench studies (see the package docstring): the seeded ones — observation time with its
systematic floors, the site sweep, the planner's accuracy — and :func:`run_bench`, which runs every
study (the work-precision and speed targets of :mod:`.work_precision`, the real-time factors of
:mod:`.realtime`, the streaming rows of :mod:`.streaming`, the effect costs of :mod:`.effect_cost`)
and writes the CSVs, plots and summary."""

import contextlib
import math
import os
import time

import numpy as np

from gyro_instrument.bench.work_precision import REFERENCE, targets, work_precision
from gyro_instrument.core.files import replaced_atomically, write_csv
from gyro_instrument.core.parallel import process_executor
from gyro_instrument.core.scene import sample_times
from gyro_instrument.instruments.pendulum import binet_ellipse
from gyro_instrument.scenes import build_instruments, load_scene


def _obs_rows(minutes, results):
    out = []
    for r in results:
        truth = r["truth"]
        lat0 = abs(truth["latitude_deg"]) if r.get("latitude_is_absolute") else truth["latitude_deg"]
        cnt = r["methods"].get("item9_counting", {}).get("latitude_deg")
        lat, n = r.get("latitude_deg"), r.get("earth_rate_rad_s")
        crlb = r.get("crlb") or {}
        out.append((minutes, None if lat is None else lat - lat0, r.get("latitude_sigma_deg"),
                    crlb.get("latitude_deg"), None if cnt is None else cnt - abs(lat0),
                    None if n is None else n - truth["earth_rate_rad_s"], r.get("earth_rate_sigma_rad_s"),
                    crlb.get("earth_rate_rad_s"), _counting_earth_rate(r) - truth["earth_rate_rad_s"]))
    return out


def _meridian_gyro(r):
    """The estimate of the scene's meridian gyroscope (eq. 10's), or {}."""
    for e in r["instruments"].values():
        if isinstance(e, dict) and e.get("configuration") == "meridian" and e.get("swing_duration_s") is not None:
            return e
    return {}


def _counting_earth_rate(r):
    """Eq. (10) with Quet's counted meridian swing instead of the fitted one: n ∝ 1/T²."""
    g = _meridian_gyro(r)
    cnt = g.get("counting", {}).get("small_amplitude_swing_duration_s")
    if not cnt or r.get("earth_rate_rad_s") is None:
        return math.nan
    return r["earth_rate_rad_s"] * (g["small_amplitude_swing_duration_s"] / cnt) ** 2


OBS_HEADER = ("minutes", "rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg",
              "rms_fit_earth_rate_rad_s", "mean_sigma_earth_rate_rad_s", "crlb_earth_rate_rad_s",
              "rms_counting_earth_rate_rad_s", "noise_free_error_deg", "noise_free_earth_rate_error_rad_s")

FLOOR_HEADER = ("minutes", "left_out", "scope", "latitude_bias_deg", "earth_rate_bias_rad_s")

#: The floor scene: quet_paris with a spin decay added (τ = 1 h) so that all three corrections of
#: :data:`~gyro_instrument.estimators.pipeline.CORRECTIONS` have something to correct.
FLOOR_SCENE_EFFECTS = "effects={earth_rotation: {}, centrifugal: {}, finite_amplitude: {}, spin_decay: {time_constant_s: 3600}}"

#: What each scope of the floors measures, weight-free: the gyroscope pair is exactly determined
#: (item 9's cos γ from the ratio, eq. (10)'s n from the meridian configuration); the pendulum's
#: latitude is asin(k/n) with the true n, so only its own error enters.
GYRO_PAIR, PENDULUM_ALONE = "gyroscope pair (item 9, eq. 10)", "Foucault pendulum alone (asin k/n)"


def systematic_floor_rows(minutes) -> list:
    """:data:`FLOOR_HEADER` rows for one observation time: the noise-free bias of the estimates on
    the floor scene with every correction applied (``left_out`` = ``none``: the estimator's own
    floor with all three effects present) and with each correction of
    :data:`~gyro_instrument.estimators.pipeline.CORRECTIONS` left out (the floor a user would hit
    without it). One picklable argument, so it runs through any executor: ``minutes`` alone (the
    floor scene, quet_paris with a 1 h spin decay) or ``(scene, overrides, minutes)`` for any scene
    with its own effects."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    from gyro_instrument.estimators.pipeline import CORRECTIONS, estimate_records, measure, simulate_truth
    from gyro_instrument.instruments.observation import AMPLITUDE_CORRECTION, ELLIPSE_CORRECTION, SPIN_CORRECTION
    from gyro_instrument.scenes import load_scene
    if isinstance(minutes, tuple):
        name, overrides, minutes = minutes
        over = list(overrides)
    else:
        name, over = "quet_paris", [FLOOR_SCENE_EFFECTS]
    scene = load_scene(name, [f"duration_s={60.0 * minutes}"] + over + list(NOISE_FREE))
    truth = simulate_truth(scene)
    records = measure(scene, truth)
    lat0, n0 = scene.site.latitude_deg, scene.site.earth_rate_rad_s
    rows = []
    for left_out in ("none", AMPLITUDE_CORRECTION, SPIN_CORRECTION, ELLIPSE_CORRECTION):
        r = estimate_records(scene, truth[1], records, corrections=CORRECTIONS - {left_out})
        if left_out != ELLIPSE_CORRECTION:
            lat = r["methods"].get("item9", {}).get("latitude_deg")
            n = r["methods"].get("item8_eq10", {}).get("earth_rate_rad_s")
            rows.append((minutes, left_out, GYRO_PAIR, None if lat is None else lat - lat0,
                         None if n is None else n - n0))
        if left_out in ("none", ELLIPSE_CORRECTION):
            k = next((e.get("foucault_rate_rad_s") for e in r["instruments"].values()
                      if isinstance(e, dict) and "foucault_rate_rad_s" in e), None)
            lat = None if k is None or abs(k) > n0 else math.degrees(math.asin(k / n0))
            rows.append((minutes, left_out, PENDULUM_ALONE, None if lat is None else lat - lat0, None))
    return rows


def observation_time(minutes_list, n_seeds, executor=None, scene="quet_paris", overrides=()) -> tuple:
    """Rows :data:`OBS_HEADER` (rms over seeds of the fit, its reported σ, the Cramér–Rao bound
    and Quet's counting, for the latitude and eq. (10)'s Earth rate; the noise-free error is the
    estimator's own systematic floor) and :data:`FLOOR_HEADER` rows from
    :func:`systematic_floor_rows`: the bias left with every correction and without each of
    finite amplitude, spin decay and the Foucault ellipse precession. ``scene`` (name or YAML path)
    with ``overrides``: the study on any scene (its floors then with the scene's own effects). The
    seeded and noise-free runs go through the sweep runner (:func:`gyro_instrument.bench.sweep.run_grid`,
    as ``gyro-instrument sweep --vary duration_s=…``); a refused observation time gives a row of NaN."""
    from gyro_instrument.bench.effect_cost import NOISE_FREE
    from gyro_instrument.bench.sweep import point_estimates, run_grid
    over = list(overrides)
    points = [(60.0 * m,) for m in minutes_list]
    floor_jobs = list(minutes_list) if scene == "quet_paris" and not over else \
        [(scene, over, m) for m in minutes_list]
    own = executor is None
    executor = executor or process_executor()
    try:
        # the sweep runner over the observation times: the seeded draws, then the noise-free run
        results = [_obs_rows(m, point_estimates(out)) for m, out in
                   zip(minutes_list, run_grid(scene, over, ["duration_s"], points, range(n_seeds), executor))]
        noise_free = [point_estimates(out) for out in
                      run_grid(scene, over + list(NOISE_FREE), ["duration_s"], points, [0], executor)]
        floor_rows = list(executor.map(systematic_floor_rows, floor_jobs))
    finally:
        if own:
            executor.shutdown()
    rows = []
    for m, res, nf in zip(minutes_list, results, noise_free):
        if not res:                                   # the point was refused: a row of NaN
            rows.append((float(m),) + (None,) * (len(OBS_HEADER) - 1))
            continue
        a = np.array([[x if x is not None else np.nan for x in r] for r in res], dtype=float)
        rms = lambda j: float(np.sqrt(np.nanmean(a[:, j] ** 2))) if np.isfinite(a[:, j]).any() else None  # noqa: E731
        mean = lambda j: float(np.nanmean(a[:, j])) if np.isfinite(a[:, j]).any() else None  # noqa: E731
        e = _obs_rows(a[0, 0], nf)[0] if nf else (None,) * 9
        rows.append((a[0, 0], rms(1), mean(2), mean(3), rms(4), rms(5), mean(6), mean(7), rms(8), e[1], e[5]))
    # a scope the scene has no instrument for (no pendulum, no gyroscope pair) gives only empty rows
    scopes = {r[2] for rws in floor_rows for r in rws if r[3] is not None or r[4] is not None}
    fl = [row for rws in floor_rows for row in rws if row[2] in scopes]
    return rows, fl


SITE_HEADER = ("latitude_deg", "rms_error_deg", "mean_sigma_deg", "crlb_deg", "rms_earth_rate_error_rad_s",
               "crlb_earth_rate_rad_s")


def site_sweep(latitudes_deg, n_seeds, minutes=10.0, executor=None, scene="quet_paris", overrides=()) -> list:
    """Rows :data:`SITE_HEADER`: ``scene`` (name or YAML path, with ``overrides``) moved to each
    latitude (10 min per configuration), rms errors over seeds against the reported σ and the
    Cramér–Rao bound — the sweep runner (:func:`gyro_instrument.bench.sweep.run_grid`, as
    ``gyro-instrument sweep``) over the points ``site.latitude_deg``, through the executor (any
    ``concurrent.futures`` executor); a point whose estimate was refused gives NaN."""
    from gyro_instrument.bench.sweep import point_estimates, run_grid
    results = run_grid(scene, list(overrides) + [f"duration_s={60.0 * minutes}"], ["site.latitude_deg"],
                       [(lat,) for lat in latitudes_deg], range(n_seeds), executor)
    rows = []
    for lat, out in zip(latitudes_deg, results):
        res = point_estimates(out)
        dl = [r["latitude_deg"] - r["truth"]["latitude_deg"] for r in res if r.get("latitude_deg") is not None]
        dn = [r["earth_rate_rad_s"] - r["truth"]["earth_rate_rad_s"] for r in res
              if r.get("earth_rate_rad_s") is not None]
        rms = lambda v: float(np.sqrt(np.mean(np.square(v)))) if v else math.nan  # noqa: E731
        mean = lambda v: float(np.mean(v)) if v else math.nan  # noqa: E731
        crlb = [r.get("crlb") or {} for r in res]
        rows.append((float(lat), rms(dl), mean([r["latitude_sigma_deg"] for r in res if r.get("latitude_sigma_deg")]),
                     mean([c["latitude_deg"] for c in crlb if c.get("latitude_deg")]), rms(dn),
                     mean([c["earth_rate_rad_s"] for c in crlb if c.get("earth_rate_rad_s")])))
    return rows


PLANNER_HEADER = ("scene", "target", "value", "planned_observation_s", "planned_sigma", "achieved_rms", "seeds",
                  "achieved_over_target")


def default_targets(scene, overrides=()) -> list:
    """Targets whose plans land near the scene's own duration_s: its latitude and Earth-rate bounds there,
    rounded to two significant digits (SceneError when the scene has no Earth-rate instrument)."""
    from gyro_instrument.estimators.planner import ARCSEC_RAD, Planner, SensorSpec, instrument_models
    sc = load_scene(scene, list(overrides))
    models = instrument_models(sc)[0]
    if not models:
        return []
    b = Planner(models, SensorSpec.from_scene(sc), sc.estimator.get("hemisphere")).bounds(sc.duration_s)[0]
    two = lambda x: format(x, ".2g")  # noqa: E731
    out = []
    if b.get("latitude_rad"):
        out.append("latitude_arcsec=" + two(b["latitude_rad"] / ARCSEC_RAD))
    if b.get("earth_rate_rad_s"):
        out.append("earth_rate_rad_s=" + two(b["earth_rate_rad_s"]))
    return out


def planner_accuracy(cases, n_seeds, executor=None, progress=print) -> list:
    """Rows :data:`PLANNER_HEADER`: for each (scene, overrides, target strings) the planned
    observation time and bound (:func:`gyro_instrument.estimators.planner.plan`) and the rms achieved
    over ``n_seeds`` seeded runs at that time (``verify_plan``, through the executor)."""
    from gyro_instrument.estimators.planner import parse_targets, plan, verify_plan
    own = executor is None
    executor = executor or process_executor()
    rows = []
    try:
        for scene, overrides, targets in cases:
            d = plan(scene, overrides, parse_targets(targets), noise_factors=(), rate_factors=(), floor=False)
            verify_plan(d, n_seeds, executor, progress=lambda m: progress(f"  {scene}: {m.strip()}"))
            for e in d["targets"]:
                v = e.get("verify") or {}
                rows.append((d["scene"], e["target"], e["value"], e.get("observation_s"), e.get("planned_sigma"),
                             v.get("achieved_rms"), n_seeds, v.get("achieved_over_target")))
    finally:
        if own:
            executor.shutdown()
    return rows


def _planner_lines(pl):
    lines = ["", "## How long must I observe? The planner against the Monte Carlo", "",
             "`gyro-instrument plan SCENE --target ...`: the observation time per configuration from the "
             "Cramér–Rao bound, and the rms achieved by seeded runs at that time.", "",
             "| scene | target | planned T (s) | planned σ | achieved rms | seeds | achieved / target |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {sc} | {t} = {v:g} | {_fmt(T, '.4g')} | {_fmt(s, '.3g')} | {_fmt(a, '.3g')} | {n} | {_fmt(r, '.3f')} |"
              for sc, t, v, T, s, a, n, r in pl]
    return lines


def run_scene_bench(out_dir, scene, overrides=(), quick=False, progress=print, executor=None) -> str:
    """``bench --scene``: the observation-time study (with its systematic floors, the scene's own
    effects) and the planner's accuracy on any scene; CSVs, plot and summary.md. Returns the text.
    ``executor``: where both studies' seeds run (``bench --scene --scheduler``: a Dask client's
    executor); default one process pool for both."""
    os.makedirs(out_dir, exist_ok=True)
    name = load_scene(scene, list(overrides)).name
    with (contextlib.nullcontext(executor) if executor is not None else process_executor()) as executor:
        progress(f"observation time ({name})")
        ot, floors = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40,
                                      executor=executor, scene=scene, overrides=overrides)
        write_csv(os.path.join(out_dir, "observation_time.csv"), OBS_HEADER, ot)
        write_csv(os.path.join(out_dir, "systematic_floors.csv"), FLOOR_HEADER, floors)
        progress(f"planner accuracy ({name})")
        targets = default_targets(scene, overrides)
        pl = planner_accuracy([(scene, list(overrides), targets)], 16 if quick else 100, executor=executor,
                              progress=progress) if targets else []
    write_csv(os.path.join(out_dir, "planner.csv"), PLANNER_HEADER, pl)
    from gyro_instrument.bench.plots import write_plots
    pngs = write_plots(out_dir)
    lines = [f"# gyro-instrument bench --scene {scene}" + (" (quick)" if quick else ""), "",
             f"Regenerate: `gyro-instrument bench --scene {scene}" + "".join(f" --set {o}" for o in overrides)
             + (" --quick" if quick else "") + f" --out {out_dir}`.", ""]
    lines += _obs_lines(ot, floors, name, "the scene's own effects")
    lines += _planner_lines(pl)
    return _write_summary(out_dir, lines, pngs)


def _write_summary(out_dir, lines, pngs):
    """summary.md in ``out_dir`` from ``lines`` and the plots' PNG paths (written last, atomically:
    a bench directory without it is an interrupted bench); returns the text."""
    if pngs:
        lines = lines + ["", "## Plots", ""] + [f"![{os.path.basename(p)}]({os.path.basename(p)})" for p in pngs]
    text = "\n".join(lines) + "\n"
    with replaced_atomically(os.path.join(out_dir, "summary.md")) as tmp, open(tmp, "w") as fh:
        fh.write(text)
    return text


def _obs_lines(ot, floors, name, floor_scene):
    lines = ["## Error versus observation time (" + name + ", per configuration)", "",
             "| minutes | latitude rms, fit (deg) | reported σ | Cramér–Rao | rms, counting | noise-free error | "
             "Earth rate n rms, fit (rad/s) | reported σ | Cramér–Rao | rms, counting | noise-free error |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    obs_cols = ("rms_fit_deg", "mean_sigma_deg", "crlb_deg", "rms_counting_deg", "noise_free_error_deg",
                "rms_fit_earth_rate_rad_s", "mean_sigma_earth_rate_rad_s", "crlb_earth_rate_rad_s",
                "rms_counting_earth_rate_rad_s", "noise_free_earth_rate_error_rad_s")
    for r in ot:
        d = dict(zip(OBS_HEADER, r))
        lines.append("| {:g} | ".format(d["minutes"]) + " | ".join(
            _fmt(d[k], ".1e" if k.startswith("noise_free") else ".2e") for k in obs_cols) + " |")
    lines += ["", f"Systematic floors: the noise-free bias on {floor_scene}, with every "
              "correction of the estimator applied (left out: none) and with one left out:", "",
              "| minutes | correction left out | scope | latitude bias (deg) | Earth-rate bias (rad/s) |",
              "|---|---|---|---|---|"]
    lines += [f"| {m:g} | {e} | {sc} | {_fmt(a, '.2e')} | {_fmt(b, '.2e')} |" for m, e, sc, a, b in floors]
    return lines


def run_bench(out_dir, quick=False, progress=print, scene=None, overrides=(), executor=None) -> str:
    """Run every study, write CSVs, PNGs (with matplotlib) and summary.md; return the summary text.
    With ``scene``: only the observation-time study and the planner's accuracy on that scene
    (:func:`run_scene_bench`).

    ``executor``: where the sweeps run (observation time, planner accuracy, site sweep, effect
    cost); default one spawned process pool (:func:`~gyro_instrument.core.parallel.process_executor`)
    for all of them, started after the timed speed studies, e.g. a Dask client's executor for
    ``bench --scheduler``."""
    if scene is not None:
        return run_scene_bench(out_dir, scene, overrides, quick, progress, executor=executor)
    from gyro_instrument.bench.plots import write_plots
    os.makedirs(out_dir, exist_ok=True)
    progress("work-precision (Foucault pendulum, plane gyroscope)")
    wp = work_precision(quick, progress)
    write_csv(os.path.join(out_dir, "work_precision.csv"),
           ("instrument", "method", "setting", "cpu_s", "nfev", "error_rad"), wp)
    tg, st, rt, gwp, cost_lines = _speed_studies(out_dir, wp, quick, progress)
    own = executor is None
    executor = executor or process_executor()
    try:
        ot, floors, pl, ss, ec, north = _sweep_studies(out_dir, quick, progress, executor)
    finally:
        if own:
            executor.shutdown()
    # each measurement kind's own study (its optional ``bench``: the rate gyro's north in the same time)
    from gyro_instrument.instruments.measurement import load as load_kinds
    kind_lines = [line for k in load_kinds().values() for line in k.bench(out_dir, quick, write_csv, progress, north[1])]
    from gyro_instrument.bench.marine_checks import HEADER as MARINE_HEADER, marine_check_lines, marine_check_rows
    marine = marine_check_rows(quick, progress)      # issue 39 item 4: the compass against published figures
    write_csv(os.path.join(out_dir, "marine_checks.csv"), MARINE_HEADER, marine)
    pngs = write_plots(out_dir)
    if not pngs:
        progress("plots need matplotlib: pip install matplotlib (or the 'plot' extra); the CSVs are written")
    from gyro_instrument.bench.north_study import north_lines
    lines = (_bench_summary_lines(out_dir, quick, tg, st, wp, rt, gwp, ot, floors, pl, ss, ec) + cost_lines
             + north_lines(*north) + kind_lines + marine_check_lines(marine))
    return _write_summary(out_dir, lines, pngs)


def _sweep_studies(out_dir, quick, progress, executor) -> tuple:
    """The seeded studies through ``executor``, each written to its CSV: (observation-time rows,
    floor rows, planner rows, site-sweep rows, effect-cost rows, north-study rows)."""
    from gyro_instrument.bench.effect_cost import effect_cost_rows, write_effect_cost_csv
    progress("observation time")
    ot, floors = observation_time((1, 2, 5) if quick else (1, 2, 5, 10, 20, 60), 8 if quick else 40,
                                  executor=executor)
    write_csv(os.path.join(out_dir, "observation_time.csv"), OBS_HEADER, ot)
    write_csv(os.path.join(out_dir, "systematic_floors.csv"), FLOOR_HEADER, floors)
    progress("planner accuracy (plan, then the Monte Carlo at the planned time)")
    pl = planner_accuracy([("quet_paris", [], ["latitude_arcsec=1", "earth_rate_rad_s=1e-10"])]
                          + ([] if quick else [("quet_gyroscopes", ["site.latitude_deg=60"], ["latitude_arcsec=1"])]),
                          16 if quick else 200, executor=executor, progress=progress)
    write_csv(os.path.join(out_dir, "planner.csv"), PLANNER_HEADER, pl)
    progress("site sweep")
    ss = site_sweep((-85, -60, -33.9, 5, 30, 48.8462, 70, 85) if not quick else (-33.9, 48.8462),
                    40 if not quick else 4, minutes=10.0 if not quick else 2.0, executor=executor)
    write_csv(os.path.join(out_dir, "site_sweep.csv"), SITE_HEADER, ss)
    progress("effect cost")
    ec = effect_cost_rows(["quet_paris", "foucault_pantheon"] if quick else None,
                          duration_s=120.0 if quick else None, executor=executor)
    write_effect_cost_csv(os.path.join(out_dir, "effect_cost.csv"), ec)
    progress("north: accuracy versus observation time per method, systematic floors, the gyrotheodolite")
    from gyro_instrument.bench.north_study import north_bench, write_north_csv
    north = north_bench(quick, executor=executor)
    write_north_csv(os.path.join(out_dir, "north_accuracy.csv"), os.path.join(out_dir, "north_gyrotheodolite.csv"),
                    *north, write_csv)
    return ot, floors, pl, ss, ec, north


def _speed_studies(out_dir, wp, quick, progress) -> tuple:
    """The speed targets (targets.csv: work-precision targets, run as it streams, real time of every
    instrument configuration, the pendulum against a compiled reference, plot of a day), the
    streaming rows (streaming.csv) and issue 27's cost studies (:mod:`.cost_studies`); returns
    (targets, streaming rows, real-time rows, gimbal work-precision rows, the cost studies' summary lines)."""
    progress("speed targets")
    tg = targets(wp, quick, progress)
    if not quick:       # child processes for minutes: the full bench only (issue 13: bench/live.py)
        from gyro_instrument.bench.live import live_rows
        progress("run as it streams: time to first message (1 h, 48 h), peak memory (1 h vs 48 h)")
        tg += live_rows(quick, progress)
    from gyro_instrument.bench.realtime import gimbal_work_precision_rows, realtime_rows, realtime_target, write_realtime
    progress("real-time factor of every instrument configuration; the gimbal's work-precision")
    rt, gwp = realtime_rows(quick, progress), gimbal_work_precision_rows(quick, progress)
    write_realtime(out_dir, rt, gwp)
    tg.append(realtime_target(rt))
    from gyro_instrument.bench.cost_studies import cost_studies
    cost_targets, cost_lines = cost_studies(out_dir, quick, progress)
    tg += cost_targets
    hours = 3.0 if quick else 24.0
    progress(f"  plot: {hours:g} h of Foucault pendulum data from Parquet")
    secs, n = plot_day_seconds(out_dir, hours=hours)
    tg.append((f"plot {hours:g} h of pendulum data at 20 Hz ({n} samples, Parquet, 4 views to PNG), wall time",
               secs if secs is not None else float("nan"), "s" + ("" if secs is not None else
                                                                   " (matplotlib or pyarrow missing)"),
               "<= 10", secs is not None and secs <= 10.0))
    write_csv(os.path.join(out_dir, "targets.csv"), ("target", "measured", "unit", "goal", "met"), tg)
    progress("streaming: whole simulate process against the textbook script, peak memory, output throughput")
    from gyro_instrument.bench.streaming import streaming_rows
    st = streaming_rows(wp, REFERENCE[(3600.0 if quick else 86164.0989, 20.0)], quick, progress)
    write_csv(os.path.join(out_dir, "streaming.csv"), ("target", "measured", "unit", "goal", "met"), st)
    return tg, st, rt, gwp, cost_lines


def _bench_summary_lines(out_dir, quick, tg, st, wp, rt, gwp, ot, floors, pl, ss, ec) -> list:
    """summary.md's lines (every table of the full bench; the plots are appended by
    :func:`_write_summary`)."""
    from gyro_instrument.bench.effect_cost import HEADER as EC_HEADER
    from gyro_instrument.bench.realtime import summary_lines
    lines = ["# gyro-instrument bench" + (" (quick)" if quick else ""), "",
             "Regenerate: `gyro-instrument bench" + (" --quick" if quick else "") + f" --out {out_dir}`.", "",
             "## Speed targets (measured in this run)", "",
             "| target | measured | unit | goal | met |", "|---|---|---|---|---|"]
    lines += [f"| {a} | {b:.4g} | {c} | {d} | {'yes' if e else 'no'} |" for a, b, c, d, e in tg]
    lines += streaming_lines(st)
    lines += ["", "## Work-precision (error at the end against a tight reference)", "",
              "| instrument | method | setting | CPU s | RHS evaluations | error (rad) |", "|---|---|---|---|---|---|"]
    lines += [f"| {i} | {m} | {st} | {c:.3g} | {n} | {e:.2e} |" for i, m, st, c, n, e in wp]
    lines += [""] + summary_lines(rt, gwp)
    lines += [""] + _obs_lines(ot, floors, "quet_paris", "quet_paris with a 1 h spin decay added")
    lines += _planner_lines(pl)
    lines += ["", "## Error versus site latitude (quet_paris moved, rms over seeds)", "",
              "| latitude (deg) | rms error (deg) | reported σ (deg) | Cramér–Rao (deg) | n rms error (rad/s) | "
              "n Cramér–Rao (rad/s) |", "|---|---|---|---|---|---|"]
    lines += ["| {:g} | {:.2e} | {:.2e} | {:.2e} | {:.2e} | {:.2e} |".format(*r) for r in ss]
    lines += ["", "## Effect cost (leave one effect out; noise-free)", "",
              "| scene | effect | instrument | CPU with (s) | CPU without (s) | largest angle change (rad) | "
              "latitude change (deg) | Earth-rate change (rad/s) |", "|---|---|---|---|---|---|---|---|"]
    for r in ec:
        d = dict(zip(EC_HEADER, r))
        lines.append("| {scene} | {effect} | {instrument} | {a} | {b} | {c} | {dl} | {dn} |".format(
            scene=d["scene"], effect=d["effect"] or "— (" + (d.get("note") or "no effect to leave out") + ")",
            instrument=d["instrument"] or "—", a=_fmt(d["cpu_with_s"], ".3g"),
            b=_fmt(d["cpu_without_s"], ".3g"), c=_fmt(d["max_abs_diff_rad"], ".2e"),
            dl=_fmt(d["dlatitude_deg"], ".2e"), dn=_fmt(d["dearth_rate_rad_s"], ".2e")))
    return lines


def streaming_lines(rows) -> list:
    """summary.md's section of the streaming rows (:mod:`.streaming`)."""
    lines = ["", "## Streaming: whole simulate process, peak memory, output (measured in this run)", "",
             "| target | measured | unit | goal | met |", "|---|---|---|---|---|"]
    return lines + [f"| {a} | {b:.4g} | {c} | {d} | {'yes' if e else ('—' if d == '—' else 'no')} |"
                    for a, b, c, d, e in rows]


def plot_day_seconds(out_dir, hours=24.0, rate_hz=20.0) -> tuple:
    """Wall time of ``gyro-instrument plot`` on a day of pendulum data: the 67 m Foucault pendulum
    of ``foucault_pantheon`` from Binet's closed form over ``hours`` at ``rate_hz`` (1.7 million
    samples for a day at 20 Hz), written as Parquet, then every view drawn from the file (read,
    swing-plane azimuth per period, bob path, residuals). Returns (seconds, samples); (None, n)
    without matplotlib or pyarrow."""
    import tempfile
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.estimators.data_io import write_table
    from gyro_instrument.views import PlotOptions, plot_file
    scene = load_scene("foucault_pantheon", [f"duration_s={hours * 3600.0}", f"sample_rate_hz={rate_hz}"])
    p = build_instruments(scene)["pendulum"]
    t = sample_times(scene)
    r0, v0 = p.initial_state()
    x, y = binet_ellipse(t, p.p.length_m, p.context.gravity_m_s2, scene.site.k_vertical_rad_s, r0[0], r0[1], v0[0], v0[1])
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "day.parquet")
        try:
            write_table(data, t, {"pendulum.x_east": x, "pendulum.y_north": y})
            t0 = time.perf_counter()
            plot_file(data, os.path.join(out_dir, "plot_day"), PlotOptions(scene="foucault_pantheon", overwrite=True))
        except SceneError:
            return None, t.size
        return time.perf_counter() - t0, t.size


def _fmt(x, spec):
    return "—" if x is None else format(x, spec)
