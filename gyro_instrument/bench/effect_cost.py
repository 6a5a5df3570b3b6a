"""The effect-cost study: what each listed effect costs in CPU time and what leaving it out costs
in accuracy.

For every effect a scene lists, the scene is simulated twice — with all its effects and with that
one effect left out (removed from the scene's ``effects`` and from any instrument's own
``effects:`` list) — and compared:

* CPU time (``time.process_time``) of simulating all the scene's instruments, both ways (short
  runs are repeated and the fastest kept, see :data:`MIN_TIMED_CPU_S`);
* per instrument, the largest absolute difference over the run of its primary angle channels
  (rad): the swing angle a sensor reads for a gyroscope with a directing line (``angle`` for the
  plane gyroscope, the swinging ring's angle for a gimbal), the bob's deflections east and north
  ``x_east/l``, ``y_north/l`` for a pendulum (the channels the estimator measures), the sensor
  angle channels otherwise (``axis_altitude``/``axis_azimuth``, ``tilt``/``tilt_azimuth``);
* the change (without − with) of the noise-free recovered latitude (deg) and Earth rate (rad/s):
  the pipeline (:func:`~gyro_instrument.estimators.pipeline.measure` with every sensor error set
  to zero, then :func:`~gyro_instrument.estimators.pipeline.estimate_records`, both data sets read
  through the instrument models *with* every effect, so the difference is the simulation's) run on each
  estimable instrument alone (its own result: Quet's eq. (10) n for a meridian gyroscope, the
  Foucault k/n latitude for a pendulum; a horizontal gyroscope alone gives neither) and on all
  instruments together (the row with instrument ``(combined)``: the profile-likelihood latitude
  and n, or the classic methods when the scene has only one Earth-rate measurement). Gyroscopes
  alone measure cos(latitude), which is even: when the combined interval holds both signs,
  |latitude| is compared.

Rows are ``(scene, effect, cpu_with_s, cpu_without_s, instrument, column, max_abs_diff_rad,
dlatitude_deg, dearth_rate_rad_s, note)``. A value that cannot be had — an effect the scene cannot
do without, an instrument that sees no Earth once ``earth_rotation`` is gone, a scene that lists
no effects — is ``None`` and ``note`` says why; the study never raises for one scene.

Scenes run in parallel through :func:`gyro_instrument.core.parallel.process_executor` (or any
``concurrent.futures``-compatible executor passed in); :func:`scene_effect_cost` is the picklable
worker.
"""

import csv
import math
import os
import time

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.parallel import process_executor
from gyro_instrument.core.scene import apply_overrides, read_yaml
from gyro_instrument.estimators.pipeline import estimable, estimate_records, measure, simulate_truth
from gyro_instrument.scenes import FORMAT, scene_from_data, scene_path, shipped_scene_names

HEADER = ("scene", "effect", "cpu_with_s", "cpu_without_s", "instrument", "column", "max_abs_diff_rad",
          "dlatitude_deg", "dearth_rate_rad_s", "note")

COMBINED = "(combined)"

#: Short simulations are repeated (at most MAX_REPEATS times, until MIN_TIMED_CPU_S of CPU is spent)
#: and the fastest run is reported, so millisecond timings are not dominated by one-off costs.
MIN_TIMED_CPU_S = 0.1
MAX_REPEATS = 5

#: Overrides that make the measurement exact (the ``sensor:`` section is created when absent).
NOISE_FREE = ("sensor.noise_rad=0", "sensor.quantization_rad=0", "sensor.spin_noise_rad_s=0",
              "sensor.dropout_fraction=0")


def effect_cost_rows(scenes=None, duration_s=None, executor=None, overrides=()) -> list:
    """Effect-cost rows (see the module docstring) for several scenes.

    Parameters
    ----------
    scenes : sequence of str, optional
        Shipped scene names or YAML paths; default every shipped scene.
    duration_s : float, optional
        Overrides each scene's ``duration_s`` (shorter runs for quick benches and tests).
    executor : concurrent.futures.Executor, optional
        Runs one scene per task. Default: a :func:`process_executor` when there is more than one
        scene (shut down afterwards), in-process for a single scene.
    overrides : sequence of str
        Extra ``key.path=value`` overrides applied to every scene.

    Returns
    -------
    list of tuple
        Rows in :data:`HEADER` order, scene by scene in the order given.
    """
    names = list(shipped_scene_names() if scenes is None else scenes)
    extra = list(overrides)
    if duration_s is not None:
        extra.append(f"duration_s={float(duration_s)!r}")
    jobs = [(name, tuple(extra)) for name in names]
    if executor is None and len(jobs) <= 1:
        results = [scene_effect_cost(job) for job in jobs]
    else:
        own = executor is None
        executor = executor or process_executor(max_workers=min(len(jobs), os.cpu_count() or 1))
        try:
            results = list(executor.map(scene_effect_cost, jobs))
        finally:
            if own:
                executor.shutdown()
    return [row for rows in results for row in rows]


def write_effect_cost_csv(path, rows) -> None:
    """Write rows to ``path`` (``effect_cost.csv``) with :data:`HEADER`; None is written empty."""
    from gyro_instrument.core.files import replaced_atomically
    with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(HEADER)
        w.writerows(rows)


# ----------------------------------------------------------------------------- worker
def scene_effect_cost(job) -> list:
    """Rows for one scene. ``job`` = (scene name or path, overrides): one picklable argument."""
    name, overrides = job
    label = str(name)
    try:
        path = scene_path(name)
        data = apply_overrides(read_yaml(path), list(overrides) + list(NOISE_FREE), FORMAT)
        base = scene_from_data(data, source=path)
        label = base.name
    except Exception as exc:  # noqa: BLE001 - SceneError by contract; report anything, never crash
        return [(label, None, None, None, None, None, None, None, None, f"scene not loaded: {exc}")]
    try:
        ref = _run(base)
    except Exception as exc:  # noqa: BLE001 - report, never crash the study
        return [(label, None, None, None, None, None, None, None, None,
                 f"scene not simulated: {type(exc).__name__}: {exc}")]
    if not base.effects:
        return [(label, None, ref["cpu"], None, None, None, None, None, None,
                 "the scene lists no effects: nothing to leave out")]
    rows = []
    for effect in base.effects:
        try:
            scene = scene_from_data(_without(data, effect), source=path)
        except SceneError as exc:
            rows.append((label, effect, ref["cpu"], None, None, None, None, None, None,
                         f"cannot be left out: {exc}"))
            continue
        try:
            run = _run(scene, model=ref)
        except Exception as exc:  # noqa: BLE001
            rows.append((label, effect, ref["cpu"], None, None, None, None, None, None,
                         f"simulation without {effect} failed: {type(exc).__name__}: {exc}"))
            continue
        for iname in ref["insts"]:
            rows.append(_instrument_row(label, effect, ref, run, iname, base))
        rows.append(_estimate_row(label, effect, ref, run, ref["combined"], run["combined"], COMBINED,
                                  "all instruments together"))
    return rows


def _without(data, effect):
    """Raw scene mapping with ``effect`` removed from the scene and from every instrument's list."""
    out = apply_overrides(data, (), FORMAT)  # deep copy
    eff = out.get("effects") or {}
    if isinstance(eff, list):
        out["effects"] = [e for e in eff if e != effect]
    else:
        out["effects"] = {k: v for k, v in eff.items() if k != effect}
    for spec in (out.get("instruments") or {}).values():
        if isinstance(spec, dict) and isinstance(spec.get("effects"), list):
            spec["effects"] = [e for e in spec["effects"] if e != effect]
    return out


def _run(scene, model=None):
    """Simulate (timed), measure noise-free, estimate each estimable instrument alone and all together.

    ``model`` is the reference run: its scene and instruments (with every effect) are what the
    estimator knows, so the without-effect data are read by the same estimator as the reference
    data and the difference is the simulation's alone.
    """
    cpu = math.inf
    spent = 0.0
    for _ in range(MAX_REPEATS):
        c0 = time.process_time()
        truth = simulate_truth(scene)
        dt = time.process_time() - c0
        cpu, spent = min(cpu, dt), spent + dt
        if spent >= MIN_TIMED_CPU_S:
            break
    t, insts, sims = truth
    est_scene, est_insts = (scene, insts) if model is None else (model["scene"], model["insts"])
    records = measure(est_scene, (t, est_insts, sims))
    alone = {}
    for iname, inst in est_insts.items():
        if estimable(inst) and iname in records:
            alone[iname] = _estimate(est_scene, {iname: inst}, {iname: records[iname]})
    return {"scene": scene, "cpu": cpu, "insts": insts, "sims": sims, "records": records, "alone": alone,
            "combined": _estimate(est_scene, est_insts, records)}


def _estimate(scene, insts, records):
    """Noise-free estimate from the pipeline: (latitude_deg, its source, earth_rate_rad_s, its source,
    reason the latitude is missing, reason the Earth rate is missing)."""
    try:
        r = estimate_records(scene, insts, records)
    except Exception as exc:  # noqa: BLE001
        why = f"estimator failed: {type(exc).__name__}: {exc}"
        return None, None, None, None, why, why
    m = r.get("methods", {})
    inst_reasons = [f"{iname}: {est['reason']}" for iname, est in r.get("instruments", {}).items()
                    if est.get("reason") and estimable(insts[iname])]

    def pick(key, combined_src, classic, reason_key):
        if r.get(key) is not None:
            return r[key], combined_src, None
        reasons = []
        for method, src in classic:
            entry = m.get(method, {})
            if entry.get(key) is not None:
                note = " (nominal n)" if "nominal" in entry.get("note", "") else ""
                return entry[key], src + note, None
            reasons.append(entry.get(reason_key))
        reasons = inst_reasons + [x for x in reasons if x] + [r.get("reason")]
        return None, None, next((x for x in reasons if x), "no reason given")

    lat, lat_src, lat_why = pick("latitude_deg", "combined profile fit",
                                 (("item9", "item 9"), ("foucault", "Foucault k/n")), "reason")
    lo, hi = (r.get("latitude_interval_deg") or (None, None))[:2] if lat_src == "combined profile fit" else (None, None)
    if lat and lo is not None and lo <= -lat <= hi:
        # gyroscopes alone measure cos(latitude), which is even: the profile's minimum may land in
        # either hemisphere, so compare |latitude| (item 9 assumes the northern one likewise)
        lat, lat_src = abs(lat), "combined profile fit, |latitude| (hemisphere not determined)"
    if r.get("earth_rate_known"):   # taken as known, not measured: not this data's Earth rate
        r = dict(r, earth_rate_rad_s=None, reason=f"Earth rate not estimable from these data: {r['earth_rate_basis']}")
    n, n_src, n_why = pick("earth_rate_rad_s", "combined profile fit",
                           (("item8_eq10", "eq. (10)"), ("foucault", "Foucault k/sin(latitude)")), "reason_earth_rate")
    return lat, lat_src, n, n_src, lat_why, n_why


def _primary_angles(inst, sim):
    """{column name: array (rad)}: the angle channels the sensor reads (see the module docstring)."""
    return inst.observation().signal_angles(sim.columns)


def _instrument_row(label, effect, ref, run, iname, base):
    inst = ref["insts"][iname]
    notes = []
    diff = column = None
    if iname not in run["insts"]:
        notes.append("instrument absent from the scene without the effect")
    else:
        a = _primary_angles(inst, ref["sims"][iname])
        b = _primary_angles(run["insts"][iname], run["sims"][iname])
        column = "|".join(a)
        with np.errstate(invalid="ignore"):
            d = [np.nanmax(np.abs(a[c] - b[c])) for c in a if c in b and np.size(a[c]) == np.size(b[c])]
        diff = float(max(d)) if d and all(math.isfinite(x) for x in d) else None
        if diff is None:
            notes.append("angle channels not comparable (missing, different lengths or not finite)")
        elif len(a) > 1:
            notes.append(f"max over {', '.join(a)}")
    if effect not in base.instruments[iname][2]:
        notes.append(f"{effect} is not active on this instrument")
    if iname in ref["alone"]:
        row = _estimate_row(label, effect, ref, run, ref["alone"][iname], run["alone"].get(iname),
                            iname, "this instrument alone")
        dlat, dn, enote = row[7], row[8], row[9]
        notes.append(enote)
    else:
        dlat = dn = None
        notes.append(f"{inst.type_name} measures no Earth rate: not estimable")
    return (label, effect, ref["cpu"], run["cpu"], iname, column, diff, dlat, dn, "; ".join(x for x in notes if x))


def _estimate_row(label, effect, ref, run, with_est, without_est, who, what):
    """Row for the change of the recovered latitude and Earth rate (without − with)."""
    notes = []
    out = []
    if without_est is None:
        without_est = (None, None, None, None, "not estimable without the effect", "not estimable without the effect")
    for i, qty in ((0, "latitude"), (2, "earth rate")):
        w, wo = with_est[i], without_est[i]
        why = 4 if i == 0 else 5
        if w is None:
            out.append(None)
            notes.append(f"{qty}: none from {what} ({with_est[why]})")
        elif wo is None:
            out.append(None)
            notes.append(f"{qty}: not estimable from {what} without {effect} ({without_est[why]})")
        else:
            out.append(float(wo - w))
            src, src_wo = with_est[i + 1], without_est[i + 1]
            src = src if src == src_wo else f"{src} -> {src_wo}"
            notes.append(f"{qty}: {src}")
    return (label, effect, ref["cpu"], run["cpu"], who, None if who != COMBINED else "latitude_deg|earth_rate_rad_s",
            None, out[0], out[1], "; ".join(notes))
