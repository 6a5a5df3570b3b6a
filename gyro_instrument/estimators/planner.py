"""How long must I observe? The observation time a scene's instruments need for a target accuracy.

For every Earth-rate instrument of a scene the planner computes the Cramér–Rao bound of the
quantity its estimator measures, as a function of the observation time T (the scene's
``duration_s``, the same for every configuration), from the scene's own sensor model, and feeds the
bounds (at the scene's true values) into :func:`~gyro_instrument.estimators.latitude.solve_latitude`
with ``use_crlb=True`` to get the combined latitude and Earth-rate bounds. T for each target comes
from a bisection in log T; the bounds and their sources are :mod:`.bounds`'s (gyroscopes, pendulums,
short records, counting). The **floor**: a noise-free run of the scene at the planned T (sensor
noise, quantization, spin noise and dropouts 0) gives the estimator's bias, the way ``bench``'s
systematic-floor study does; a target below |bias| is unreachable, and switching the scene's
effects off one at a time in the noise-free run says which one sets the floor.
"""

import math

import numpy as np

from gyro_instrument import effects
from gyro_instrument.core.effect import FRAME_RATE
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S
from gyro_instrument.estimators.bounds import (CLOSED_FORM_CYCLES, EXACT_SAMPLES, GYRO_MIN_CYCLES,  # noqa: F401
                                               MAX_OBSERVATION_S, PENDULUM_MIN_PERIODS, YEAR_S, InstrumentModel,
                                               Planner, SensorSpec, combined, counting_sigma, instrument_models,
                                               instrument_sigma, samples, shortest_time, sine_fit_covariance)
from gyro_instrument.estimators.north.bounds import (NORTH_LAWS, NORTH_METHODS, azimuth_sigmas,
                                                       rotor_off_plan, solve_azimuth)
from gyro_instrument.instruments.measurement import kind, load as load_kinds

ARCSEC_RAD = math.pi / (180.0 * 3600.0)
DEG_H_RAD_S = math.pi / (180.0 * 3600.0)

#: one milligon (1e-3 gon, 400 gon to the circle: the unit of the Gyromat's datasheet), rad
MGON_RAD = math.pi / 200.0e3

#: Target names: quantity, the factor from the unit to SI (rad or rad/s). ``azimuth_*``: the mount
#: azimuth of a horizontal gyroscope (the estimate's ``north`` block; :func:`plan_azimuth`).
TARGETS = {"latitude_arcsec": ("latitude", ARCSEC_RAD), "latitude_deg": ("latitude", math.pi / 180.0),
           "latitude_rad": ("latitude", 1.0), "earth_rate_rad_s": ("earth_rate", 1.0),
           "earth_rate_deg_h": ("earth_rate", DEG_H_RAD_S), "azimuth_arcsec": ("azimuth", ARCSEC_RAD),
           "azimuth_mgon": ("azimuth", MGON_RAD), "azimuth_deg": ("azimuth", math.pi / 180.0)}


def parse_targets(specs) -> list:
    """``["latitude_arcsec=1", "earth_rate_rad_s=1e-10"]`` -> list of (name, value in its unit, SI value).

    Raises
    ------
    SceneError
        On ``--target``: not NAME=VALUE, an unknown name (with the closest one), a value that is not
        a positive finite number, or no target at all.
    """
    from gyro_instrument.core.params import unknown_key_hint
    if not specs:
        raise SceneError("--target", None, f"is required (repeatable), e.g. --target latitude_arcsec=1; names: "
                                           f"{', '.join(TARGETS)}")
    out = []
    for spec in specs:
        name, sep, text = str(spec).partition("=")
        name = name.strip()
        if not sep:
            raise SceneError("--target", spec, f"must be NAME=VALUE, e.g. latitude_arcsec=1; names: {', '.join(TARGETS)}")
        if name not in TARGETS:
            raise SceneError("--target", spec, unknown_key_hint(name, TARGETS, "target"))
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise SceneError(f"--target {name}", text, "must be a positive finite number (the 1-sigma accuracy wanted)")
        out.append((name, value, value * TARGETS[name][1]))
    return out


# ----------------------------------------------------------------------------- the plan
#: Default sensitivity factors: sensor noise ×0.1 and ×10, sample rate ×2 and ×0.5.
NOISE_FACTORS, RATE_FACTORS = (0.1, 10.0), (2.0, 0.5)


def _quantity_value(quantity, si, name):
    """SI value back in the unit of target ``name``."""
    return None if si is None else si / TARGETS[name][1]


#: The overrides that switch the sensor off (the same as ``bench.effect_cost.NOISE_FREE``, which the
#: systematic-floor study uses; the bench is a layer above and cannot be imported here).
NOISE_FREE = ("sensor.noise_rad=0", "sensor.quantization_rad=0", "sensor.spin_noise_rad_s=0",
              "sensor.dropout_fraction=0")


def noise_free_overrides() -> list:
    """The overrides that switch the sensor off (as ``bench``'s systematic-floor study does)."""
    return list(NOISE_FREE)


def plan(scene_arg, overrides=(), targets=(), noise_factors=NOISE_FACTORS, rate_factors=RATE_FACTORS, floor=True,
         progress=None) -> dict:
    """The plan for ``scene_arg`` (shipped name or YAML path) with ``overrides``: per target, the
    observation time per configuration, the bound's dependence on T, the systematic floor at that T,
    the sensitivity to the sensor's noise and rate, and Quet's counting for the same target.

    Parameters
    ----------
    scene_arg : str
    overrides : sequence of str
        ``--set`` strings.
    targets : sequence of (name, value, SI value)
        From :func:`parse_targets`.
    noise_factors, rate_factors : sequence of float
        Factors on the sensor's noise (σ and spin σ) and on the sample rate for the sensitivity rows.
    floor : bool
        Run the noise-free estimate at each planned T (one simulation per target, more when the floor
        exceeds the target: one per effect, to name it).

    Returns
    -------
    dict (JSON-ready but for non-finite floats: pass through ``cli.to_jsonable``)

    Raises
    ------
    SceneError
        Bad scene or overrides; a scene with no Earth-rate instrument; a factor that is not positive.
    """
    from gyro_instrument.scenes import load_scene
    for what, factors in (("--noise-factor", noise_factors), ("--rate-factor", rate_factors)):
        for f in factors:
            if not (isinstance(f, (int, float)) and math.isfinite(f) and f > 0):
                raise SceneError(what, f, "must be a positive finite number")
    scene = load_scene(scene_arg, list(overrides))
    models, skipped = instrument_models(scene)
    azimuth = any(TARGETS[name][0] == "azimuth" for name, _, _ in targets)
    block_kinds = tuple(k for k, v in load_kinds().items() if v.TARGET == "azimuth")
    az_models, az_skipped = instrument_models(scene, block_kinds) if azimuth else ([], {})
    if not models and not az_models:
        what = ("horizontal gyroscope with earth_rotation (its swing centre is north) nor another instrument "
                f"measuring an azimuth with the Earth's rotation simulated (the kinds {', '.join(block_kinds)})"
                if azimuth else
                "an instrument that measures an Earth rate (a gyroscope with a directing line or a pendulum, with "
                "earth_rotation)")
        why = az_skipped if azimuth else skipped
        raise SceneError("scene", scene_arg, f"has no {what}: nothing to plan"
                         + (f" ({'; '.join(f'{k}: {v}' for k, v in why.items())})" if why else ""))
    if azimuth and not az_models:
        name = next(n for n, _, _ in targets if TARGETS[n][0] == "azimuth")
        raise SceneError(f"--target {name}", scene_arg, "needs a horizontal gyroscope (plane_gyroscope, plane: horizontal, "
                         "the rotor spinning, earth_rotation on: its swing centre is north) or another instrument "
                         f"measuring an azimuth (the kinds {', '.join(block_kinds)}); the scene has none"
                         + (f" ({'; '.join(f'{k}: {v}' for k, v in az_skipped.items())})" if az_skipped else ""))
    sensor = SensorSpec.from_scene(scene)
    hemi = scene.estimator.get("hemisphere")
    # the Earth rate as estimate takes it (pipeline.known_earth_rate): the site's, known where the
    # instruments cannot separate it from the latitude (a pendulum alone), unless estimator.earth_rate says
    n_known = scene.site.earth_rate_rad_s
    known = {"earth_rate": scene.estimator.get("earth_rate"), "n_known": n_known,
             "n_source": ("the IERS conventional value, the scene's site.earth_rate_rad_s"
                          if n_known == SIDEREAL_RATE_RAD_S else "the scene's site.earth_rate_rad_s")}
    planner = Planner(models, sensor, hemi, known) if models else None
    out = {"scene": scene.name, "source": scene.source, "overrides": list(overrides),
           "latitude_deg": scene.site.latitude_deg, "earth_rate_rad_s": scene.site.earth_rate_rad_s,
           "sensor": {"noise_rad": sensor.noise_rad, "quantization_rad": sensor.quantization_rad,
                      "effective_noise_rad": sensor.sigma_rad, "spin_noise_rad_s": sensor.spin_noise_rad_s,
                      "dropout_fraction": sensor.dropout_fraction, "sample_rate_hz": sensor.rate_hz},
           "instruments": {m.name: kind(m.kind).plan_entry(m) for m in models},
           "not_used": {n: why for n, why in skipped.items() if n not in {m.name for m in az_models}},
           "min_record_s": planner.min_record_s() if planner else None, "targets": []}
    if azimuth:
        out["north_instruments"] = {m.name: kind(m.kind).plan_entry(m) for m in az_models}
    for name, value, si in targets:
        if progress:
            progress(f"planning {name} = {value:g}")
        if TARGETS[name][0] == "azimuth":
            out["targets"].append(_plan_block(scene_arg, overrides, az_models, az_skipped, sensor, name, value, si,
                                              floor))
        elif planner is None:
            out["targets"].append({"target": name, "value": value, "quantity": TARGETS[name][0],
                                   "observation_s": None, "reason": "no instrument of the scene measures an Earth rate"})
        else:
            out["targets"].append(_plan_target(scene_arg, overrides, planner, name, value, si, noise_factors,
                                               rate_factors, floor))
    return out


def _plan_block(scene_arg, overrides, models, skipped, sensor, name, value, si, floor):
    """The plan of a block kind's target (``azimuth_*``): each kind's own :meth:`plan` over its models,
    else the shortest T whose kind's ``bound`` meets it; the entry of the least T when several kinds
    serve it."""
    if not models:
        return plan_azimuth(scene_arg, overrides, [], skipped, sensor, name, value, si, floor)
    by_kind = {}
    for m in models:
        by_kind.setdefault(m.kind, []).append(m)
    entries = []
    for k, ms in by_kind.items():
        entry = kind(k).plan(scene_arg, overrides, ms, skipped, sensor, name, value, si, floor)
        entries.append(entry if entry is not None else _plan_by_bound(ms, skipped, sensor, name, value, si))
    timed = [e for e in entries if e.get("observation_s") is not None]
    return min(timed, key=lambda e: e["observation_s"]) if timed else entries[0]


def _plan_by_bound(models, skipped, sensor, name, value, si) -> dict:
    """The generic plan of a block kind: per instrument the shortest T whose ``bound`` is ≤ the target."""
    entry = {"target": name, "value": value, "quantity": TARGETS[name][0]}
    solved = {}
    for m in models:
        k = kind(m.kind)
        t_min = float(m.min_record_s)
        if k.bound(m, t_min, sensor)[0] <= si:
            solved[m.name] = (t_min, "the estimator's shortest record already meets the target")
        else:
            solved[m.name] = shortest_time(lambda T, m=m, k=k: k.bound(m, T, sensor)[0], t_min, si, 4.0, 1e-4)
    ok = {n: v for n, v in solved.items() if v[0] is not None}
    if not ok:
        entry.update({"observation_s": None, "reason": "; ".join(f"{n}: {v[1]}" for n, v in solved.items())
                      or "; ".join(f"{n}: {v}" for n, v in skipped.items())})
        return entry
    best = min(ok, key=lambda n: ok[n][0])
    T, note = ok[best]
    m = next(x for x in models if x.name == best)
    sig, how = kind(m.kind).bound(m, T, sensor)
    entry.update({"instrument": best, "observation_s": T, "samples_per_instrument": samples(T, sensor.rate_hz),
                  "planned_sigma": sig / TARGETS[name][1], "note": note or None, "limited_by": how,
                  "per_instrument_observation_s": {n: v[0] for n, v in solved.items()}})
    return entry


def _finite(x):
    return None if x is None or not math.isfinite(x) else x


def plan_azimuth(scene_arg, overrides, models, skipped, sensor, name, value, si, floor=True) -> dict:
    """The plan of an azimuth target: per horizontal gyroscope the fit's T at the Cramér–Rao bound of
    the whole joint problem (:func:`.north.bounds.solve_azimuth`, :func:`.north.bounds.fit_bound`:
    the exact swing equation in scale readings, the rotor-off swing simultaneous over the same span,
    as the scene simulates it); for the instrument that needs the least (the one the estimate's
    top-level ``north`` would carry), T per north method by its σ law, each method's σ at the fit's T,
    σ(T) on a log grid, the rotor-off swing's part (:func:`.north.bounds.rotor_off_plan`) and the systematic floor
    (the noise-free estimate's azimuth error at the fit's T). ``observation_s`` is the fit's, on the
    sample grid (rounded up: the record passes the estimator's own check)."""
    entry = {"target": name, "value": value, "quantity": "azimuth"}
    if not models:
        entry.update({"observation_s": None, "reason": "no horizontal gyroscope measures an azimuth"
                      + (f" ({'; '.join(f'{k}: {v}' for k, v in skipped.items())})" if skipped else "")})
        return entry
    solved = {m.name: solve_azimuth(m, sensor, si) for m in models}
    ok = [m for m in models if solved[m.name][0] is not None]
    if not ok:
        entry.update({"observation_s": None, "reason": "; ".join(f"{k}: {v[1]}" for k, v in solved.items())})
        return entry
    m = min(ok, key=lambda x: solved[x.name][0])
    T, note = solved[m.name]
    at_plan = azimuth_sigmas(m, T, sensor)
    entry.update({"instrument": m.name, "mount_azimuth_deg_truth": math.degrees(m.mount_azimuth_rad),
                  "observation_s": T, "samples_per_instrument": samples(T, sensor.rate_hz),
                  "planned_sigma": at_plan["fit"] / TARGETS[name][1], "note": note or None,
                  "limited_by": (f"the shortest record: {m.record_limit()}" if note else
                                 "noise (Cramer-Rao bound of the whole joint fit, tape calibration included)"),
                  "per_instrument_observation_s": {k: v[0] for k, v in solved.items()}, "methods": {}})
    for method in NORTH_METHODS:
        Tm, why = (T, note) if method == "fit" else solve_azimuth(m, sensor, si, method)
        sig_m = None if Tm is None else azimuth_sigmas(m, Tm, sensor)[method]
        entry["methods"][method] = {
            "observation_s": Tm, "planned_sigma": _finite(None if sig_m is None else sig_m / TARGETS[name][1]),
            "sigma_at_plan": _finite(at_plan[method] / TARGETS[name][1]),
            "over_fit": None if Tm is None else Tm / T, "law": NORTH_LAWS[method], "note": why or None}
    entry["dependence"] = _azimuth_dependence(m, sensor, name, T)
    if m.off:
        entry["rotor_off"] = rotor_off_plan(m, sensor, T, TARGETS[name][1])
    if floor:
        entry["floor"] = systematic_floor(scene_arg, overrides, T, "azimuth", si, name, ref=(m.name, m.mount_azimuth_rad))
    return entry


def _azimuth_dependence(m, sensor, name, T):
    """σ of every north method on a log grid from one swing to 16 × the plan (the unit of ``name``)."""
    grid = sorted({*np.geomspace(m.min_record_s, max(16.0 * T, 2.0 * m.min_record_s), 9).tolist(), T})
    rows = [{"observation_s": t, "sigma": {k: _finite(v / TARGETS[name][1]) for k, v in azimuth_sigmas(m, t, sensor).items()}}
            for t in grid]
    return {"curve": rows, "law": "every method ~ T^-1/2 once many swings are in the record; the fit lowest"}


def _plan_target(scene_arg, overrides, planner, name, value, si, noise_factors, rate_factors, floor):
    quantity = TARGETS[name][0]
    T, note = planner.solve(quantity, si)
    entry = {"target": name, "value": value, "quantity": quantity}
    if T is None:
        entry.update({"observation_s": None, "reason": note})
        return entry
    comb, per = planner.bounds(T)
    sig = comb["latitude_rad" if quantity == "latitude" else "earth_rate_rad_s"]
    entry.update({"observation_s": T, "samples_per_instrument": samples(T, planner.sensor.rate_hz),
                  "planned_sigma": _quantity_value(quantity, sig, name),
                  "instrument_sigma_rad_s": per, "note": note or None,
                  "limited_by": ("the estimator's shortest record" if note else "noise (Cramer-Rao bound)")})
    if comb.get("latitude_note") and quantity == "latitude":
        entry["latitude_note"] = comb["latitude_note"]
    entry["methods"] = {m.name: instrument_sigma(m, T, planner.sensor)[1] for m in planner.models}
    entry["dependence"] = _dependence(planner, quantity, name, T)
    entry["sensitivity"] = _sensitivity(planner, quantity, si, T, noise_factors, rate_factors)
    entry["counting"] = _counting(planner, quantity, si)
    if floor:
        entry["floor"] = systematic_floor(scene_arg, overrides, T, quantity, si, name)
    return entry


def _dependence(planner, quantity, name, T):
    """σ(T) on a log grid from a quarter of the shortest record to 4 × the plan, and the local slope."""
    t_min = planner.min_record_s()
    grid = sorted({*np.geomspace(t_min / 4.0, max(4.0 * T, 2 * t_min), 9).tolist(), T, t_min})
    rows = []
    for t in grid:
        s = planner.sigma(quantity, t)
        rows.append({"observation_s": t, "sigma": _quantity_value(quantity, s, name),
                     "regime": "short record (below the estimator's minimum)" if t < t_min * (1 - 1e-9)
                     else "fit"})
    return {"curve": rows, "slope_at_plan": planner.slope(quantity, T),
            "slope_short_record": planner.slope(quantity, t_min / 2.0, factor=1.25),
            "law": "sigma ~ T^-3/2 once two cycles are in the record (24 sigma^2 / (A^2 dt^2 N (N^2 - 1)))"}


def _sensitivity(planner, quantity, si, T, noise_factors, rate_factors):
    """T for the sensor's noise or rate changed by a factor, replanned; beside the T^-3/2 law
    T ∝ (σ²/f)^(1/3) (σ² T^-3 / f fixed)."""
    rows = []
    for what, factors in (("noise", noise_factors), ("rate", rate_factors)):
        for f in factors:
            sensor = planner.sensor.scaled(noise=f) if what == "noise" else planner.sensor.scaled(rate=f)
            p = Planner(planner.models, sensor, planner.hemisphere, planner.known)
            T2, note = p.solve(quantity, si)
            law = T * (f ** 2) ** (1 / 3) if what == "noise" else T * (1.0 / f) ** (1 / 3)
            rows.append({"change": f"{what} x{f:g}", "factor": f, "observation_s": T2,
                         "law_observation_s": law, "note": note or None})
    return {"rows": rows, "law": "T ~ (sigma^2 / f)^(1/3) in the T^-3/2 regime"}


def _counting(planner, quantity, si):
    """Quet's counting for the same target: gyroscopes only (a period count); σ ∝ 1/T."""
    if not any(kind(m.kind).CLASSIC == "gyro" for m in planner.models):
        return {"observation_s": None, "reason": "no gyroscope: counting whole swings times a period, and the "
                                                 "Foucault rate is not a period"}
    T, note = planner.solve(quantity, si, counting=True)
    d = {"observation_s": T, "reason": note or None,
         "law": "sigma(T_swing) = T_swing / (N sqrt 3), N = T / T_swing swings: sigma ~ 1/T",
         "instruments": [m.name for m in planner.models if kind(m.kind).CLASSIC == "gyro"]}
    if any(kind(m.kind).CLASSIC == "pendulum" for m in planner.models):
        d["left_out"] = "the pendulum (its Foucault rate is not a period to count)"
    if T is not None:
        d["years"] = T / YEAR_S
        d["exceeds_a_year"] = T > YEAR_S
    return d


def _azimuth_error(result, ref, method="fit"):
    """Error (rad, wrapped to (−π, π]) of ``method``'s mount azimuth for instrument ``ref[0]`` (true
    azimuth ``ref[1]`` rad) in an estimate, or None: the instrument's ``north`` block (else the
    top-level one)."""
    name, truth = ref
    block = (result.get("instruments", {}).get(name) or {}).get("north") or result.get("north") or {}
    deg = block.get("mount_azimuth_deg") if method == "fit" else (block.get("methods", {}).get(method) or {}).get(
        "mount_azimuth_deg")
    return None if deg is None else math.remainder(math.radians(deg) - truth, 2.0 * math.pi)


def _bias(result, quantity, ref=None):
    """The noise-free estimate's error in SI (rad or rad/s), or None; an azimuth's against ``ref`` =
    (instrument, true mount azimuth rad) (:func:`_azimuth_error`)."""
    if quantity == "azimuth":
        return _azimuth_error(result, ref)
    truth = result["truth"]
    if quantity == "latitude":
        lat = result.get("latitude_deg")
        if lat is None:
            return None
        ref = abs(truth["latitude_deg"]) if result.get("latitude_is_absolute") else truth["latitude_deg"]
        return math.radians(lat - ref)
    n = result.get("earth_rate_rad_s")
    return None if n is None else n - truth["earth_rate_rad_s"]


def noise_free_estimate(scene_arg, overrides, T) -> tuple:
    """The estimate of the scene with the sensor switched off, over T s per configuration."""
    from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
    from gyro_instrument.scenes import load_scene
    scene = load_scene(scene_arg, list(overrides) + [f"duration_s={T!r}"] + noise_free_overrides())
    truth = simulate_truth(scene)
    return scene, estimate_records(scene, truth[1], measure(scene, truth))


def systematic_floor(scene_arg, overrides, T, quantity, si, name, ref=None) -> dict:
    """The estimator's noise-free bias at T against the target; when it exceeds the target, the bias
    with each of the scene's effects (but ``earth_rotation``) switched off names the one that sets it.
    ``ref``: (instrument, true mount azimuth rad) for an azimuth target."""
    try:
        scene, r = noise_free_estimate(scene_arg, overrides, T)
    except SceneError as exc:
        return {"bias": None, "reason": f"noise-free run at {T:.6g} s not possible: {exc}"}
    b = _bias(r, quantity, ref)
    d = {"bias": _quantity_value(quantity, b, name), "observation_s": T}
    if b is None:
        d["reason"] = r.get("reason") or "the noise-free estimate is null"
        return d
    d["reachable"] = abs(b) <= si
    if abs(b) > si:
        culprits = []
        for eff in scene.effects:
            if FRAME_RATE in effects.REGISTRY[eff].MECHANICS:     # the signal itself, not a bias
                continue
            try:
                _, r2 = noise_free_estimate(scene_arg, list(overrides) + [f"effects.{eff}=null"], T)
                b2 = _bias(r2, quantity, ref)
            except SceneError:
                continue
            culprits.append({"effect": eff, "bias_without": _quantity_value(quantity, b2, name)})
        d["effects"] = culprits
        best = [c for c in culprits if c["bias_without"] is not None]
        if best:
            top = min(best, key=lambda c: abs(c["bias_without"]))
            if abs(top["bias_without"]) < abs(d["bias"]):
                d["set_by"] = top["effect"]
    return d


# ----------------------------------------------------------------------------- verification
def _errors(results, quantity, ref=None):
    errs = [_bias(r, quantity, ref) for r in results]
    return [e for e in errs if e is not None], sum(e is None for e in errs)


def verify(scene_arg, overrides, T, n_seeds=100, executor=None, progress=None, chunk=None, ref=None) -> dict:
    """Seeded Monte Carlo at observation time T: ``n_seeds`` sensor draws of one simulation per
    chunk (:func:`~gyro_instrument.estimators.pipeline.seed_sweep` through ``executor``, by default
    :func:`~gyro_instrument.core.parallel.process_executor`, by the sweep's runner
    :func:`~gyro_instrument.core.parallel.run_tasks`: a chunk whose worker died is retried once);
    ``progress(done, total)`` after each chunk. Raises IntegrationError when a chunk fails twice
    (its reason in the message). Returns {quantity: (rms error in SI, number of seeds used, number null)}; with ``ref`` =
    (instrument, true mount azimuth rad) also ``azimuth`` (the fit's) and ``azimuth_methods``
    {method: (rms rad, used, null)} for every north method."""
    from gyro_instrument.core.parallel import run_tasks
    from gyro_instrument.estimators.pipeline import seed_sweep
    over = list(overrides) + [f"duration_s={T!r}"]
    chunk = chunk or max(1, math.ceil(n_seeds / 8))
    jobs = [(scene_arg, over, list(range(i, min(i + chunk, n_seeds)))) for i in range(0, n_seeds, chunk)]
    sizes = [len(j[2]) for j in jobs]

    def on_done(done, total):
        if progress:
            progress(min(sum(sizes[:done]), n_seeds), n_seeds)
    # the sweep's runner (its own pool of up to 2 workers unless given one): a chunk whose worker died
    # is retried once, then the verification fails
    chunks = run_tasks(seed_sweep, jobs, executor, on_done, workers=min(len(jobs), 2))
    failed = [res["error"] for res in chunks if isinstance(res, dict)]
    if failed:
        from gyro_instrument.core.errors import IntegrationError
        raise IntegrationError(f"--verify: {len(failed)} of {len(jobs)} chunks of seeds failed twice "
                               f"(first: {failed[0]})")
    results = [r for res in chunks for r in res]
    def rms_of(errs, null):
        return (float(np.sqrt(np.mean(np.square(errs)))) if errs else None, len(errs), null)
    out = {q: rms_of(*_errors(results, q)) for q in ("latitude", "earth_rate")}
    if ref is not None:
        out["azimuth"] = rms_of(*_errors(results, "azimuth", ref))
        out["azimuth_methods"] = {}
        for method in NORTH_METHODS:
            errs = [_azimuth_error(r, ref, method) for r in results]
            out["azimuth_methods"][method] = rms_of([e for e in errs if e is not None], sum(e is None for e in errs))
    return out


def verify_plan(result, n_seeds=100, executor=None, progress=None) -> dict:
    """Add ``verify`` to each planned target of ``result`` (from :func:`plan`): the achieved rms over
    ``n_seeds`` at the planned T next to the target and the planned σ (ratio achieved / target)."""
    for entry in result["targets"]:
        T = entry.get("observation_s")
        if T is None:
            continue
        name = entry["target"]
        if progress:
            progress(f"verify {name}: {n_seeds} seeds at {T:.6g} s per configuration")
        rep = (lambda d, n: progress(f"  {d}/{n} seeds")) if progress else None
        ref = (entry["instrument"], math.radians(entry["mount_azimuth_deg_truth"])) if entry["quantity"] == "azimuth" \
            else None
        got = verify(result["source"], result["overrides"], T, n_seeds, executor, rep, ref=ref)
        rms, used, null = got[entry["quantity"]]
        v = _quantity_value(entry["quantity"], rms, name)
        entry["verify"] = {"seeds": n_seeds, "used": used, "null": null, "achieved_rms": v,
                           "target": entry["value"], "planned_sigma": entry["planned_sigma"],
                           "achieved_over_target": None if v is None else v / entry["value"],
                           "achieved_over_planned": None if v is None else v / entry["planned_sigma"]}
        if ref is not None and "methods" in entry:        # a kind's plan with north methods (the swing's)
            entry["verify"]["methods"] = {
                k: {"achieved_rms": _quantity_value("azimuth", r, name), "used": u, "null": n0,
                    "planned_sigma": entry["methods"][k]["sigma_at_plan"],
                    "achieved_over_planned": None if r is None or not entry["methods"][k]["sigma_at_plan"] else
                    _quantity_value("azimuth", r, name) / entry["methods"][k]["sigma_at_plan"]}
                for k, (r, u, n0) in got["azimuth_methods"].items()}
    return result
