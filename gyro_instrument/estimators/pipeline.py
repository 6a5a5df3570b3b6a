"""From a scene to estimates: simulate the truth, measure through the sensor model, estimate.

``simulate_truth`` runs each instrument once; ``measure`` draws the sensor samples for one seed
(so 200 seeded runs cost one simulation; both in :mod:`.measure`); ``estimate_records`` turns
measured records into the ``estimate`` JSON object: per-instrument periods (fit and Quet's
counting), Quet's item 9 and eq. (10), the Foucault rate with its ellipse correction, and the
combined latitude and Earth rate (profile likelihood, :mod:`.latitude`) with their Cramér–Rao
bounds. Quantities that cannot be estimated are ``None`` with a reason — never NaN, infinity or a
crash.

Each instrument's record is estimated as its observation says
(:meth:`~gyro_instrument.instruments.base.Instrument.observation`): each measurement kind it declares
(:mod:`gyro_instrument.instruments.measurement`; the shipped ones in :mod:`.kinds`) runs its engine
on the record, and the observation supplies the laws.
"""

import dataclasses

from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S
from gyro_instrument.estimators.adequacy import InadequateData, check_before_fit, hemisphere_entry, site_check
from gyro_instrument.estimators.combine import classic_methods, combined, null_combined
from gyro_instrument.estimators.entries import UnusedEntry
from gyro_instrument.estimators.estimate_types import Check, Estimate, Truth
from gyro_instrument.estimators.latitude import RateMeasurement
from gyro_instrument.estimators.measure import MeasureStream, measure, simulate_truth
from gyro_instrument.estimators.record import ABSENT, Record, to_json
from gyro_instrument.instruments.measurement import declared_kinds, kind, measured
from gyro_instrument.instruments.observation import CORRECTIONS, FINITE_AMPLITUDE_CORRECTIONS
from gyro_instrument.scenes import load_scene
from gyro_instrument.sensors import SensorModel

__all__ = ["CORRECTIONS", "FINITE_AMPLITUDE_CORRECTIONS", "MeasureStream", "build_estimate", "estimable", "estimate_records",
           "estimated_instruments", "estimator_instruments", "known_earth_rate", "measure", "missing_companions",
           "seed_sweep", "simulate_truth", "with_block"]


def estimable(inst) -> bool:
    """True for the instruments the estimator measures: those whose observation declares a registered
    measurement kind (:func:`~gyro_instrument.instruments.measurement.measured`, the one predicate of
    ``estimate``, ``run``, the estimator node and ``replay``). Free gyroscopes and Puiseux's body are not."""
    return measured(inst)


def estimator_instruments(insts) -> list:
    """The names of the instruments whose records the estimator reads, in the scene's order: the
    measured ones and the records they read beside their own (``companions()``: a horizontal
    gyroscope's rotor-off swing with a tape). What a live ``run`` keeps, ``replay`` decodes from a bag
    and ``estimate --data`` asks columns for, so that each builds the record ``estimate`` measures."""
    names = {n for n, inst in insts.items() if measured(inst)}
    for n in list(names):
        names.update(v for v in insts[n].observation().companions().values() if v in insts)
    return [n for n in insts if n in names]


def estimated_instruments(insts, records) -> dict:
    """The instruments an estimate reports on, in the scene's order: every one that has a record and
    every one the estimator does not measure (its entry says why); a measured instrument without a
    record (a bag cut before its third message) is left out. What ``estimate``, the live estimate of
    ``run`` and ``replay`` pass to :func:`estimate_records`."""
    return {n: inst for n, inst in insts.items() if n in records or not measured(inst)}


def missing_companions(insts, records) -> list:
    """``(name, record key, companion)`` for each instrument with a record whose companion (in ``insts``)
    has none: what a table or a bag lacks for an estimate the scene asks for."""
    return [(n, key, other) for n in records if n in insts
            for key, other in insts[n].observation().companions().items()
            if other in insts and other not in records]


def estimate_records(scene, insts, records, corrections=CORRECTIONS) -> dict:
    """The ``estimate`` JSON object (see module docstring) from measured records: the JSON of
    :func:`build_estimate`'s typed :class:`.estimate_types.Estimate` (msg_docs/estimate.md).

    ``corrections`` — the subset of :data:`CORRECTIONS` to apply (all by default); a study of
    what a correction is worth passes fewer.

    Raises
    ------
    gyro_instrument.estimators.adequacy.InadequateData
        The data fail a check no estimate can survive (estimators/adequacy.py): one line naming
        the check, and, in a scene of several instruments, how to leave the failing one out.
    """
    return build_estimate(scene, insts, records, corrections).to_json()


def build_estimate(scene, insts, records, corrections=CORRECTIONS) -> Estimate:
    """The typed estimate (:class:`.estimate_types.Estimate`) of :func:`estimate_records`; raises as it says."""
    unknown = set(corrections) - CORRECTIONS
    if unknown:
        raise ValueError(f"unknown corrections {sorted(unknown)}; known: {sorted(CORRECTIONS)}")
    site = scene.site
    truth = Truth(latitude_deg=site.latitude_deg, earth_rate_rad_s=site.earth_rate_rad_s)
    entries, meas, gyros, pend, checks, blocks = {}, [], {}, None, [], {}
    sensor = SensorModel.from_scene(scene)
    for name, inst in insts.items():
        obs = inst.observation()
        try:
            est, m = _instrument_estimate(name, obs, records.get(name, {}), corrections, checks, sensor)
            for key, k, block in _also_measured(obs, est, records, corrections, checks, sensor):
                est = with_block(est, key, block)
                blocks.setdefault(key, []).append((k, block))
        except InadequateData as exc:
            if len(insts) > 1:
                exc.add_hint(f"or leave {name} out: --set instruments.{name}=null")
            raise
        entries[name] = est
        if m is not None:
            meas.append(m)
            role = kind(m.kind).CLASSIC
            if role == "pendulum":
                pend = (obs, est, m)
            elif role == "gyro":
                gyros[name] = (obs, est, m)
    if meas:
        combination = combined(meas, scene.estimator.get("hemisphere"), *known_earth_rate(scene, insts, meas),
                               earth_rate=scene.estimator.get("earth_rate"))
    else:
        combination = null_combined("no Earth-rate measurement: needs a gyroscope with a directing line "
                                    "(plane, cone, gimbal) or a pendulum with a measured oscillation")
    found = {key: f[0][0].combine([b for _, b in f]) for key, f in blocks.items()}
    found = {key: b for key, b in found.items() if b is not None}      # a kind whose blocks stay each its own
    methods = classic_methods(combination.hemisphere, truth.earth_rate_rad_s, gyros, pend,
                              scene.estimator.get("earth_rate"))
    entry = hemisphere_entry(combination.hemisphere, getattr(combination, "hemisphere_basis", ""), site.latitude_deg)
    checks += [entry] if entry else []
    evidence, site_entries = site_check({"instruments": to_json(entries), **combination.to_json()}, site)
    return Estimate(scene=scene.name, seed=scene.seed, observation_s=float(scene.duration_s), truth=truth,
                    instruments=entries, methods=methods, combination=combination,
                    north=found.pop("north", ABSENT), blocks=found or ABSENT,
                    checks=[Check(**c) for c in checks + site_entries], site=evidence)


def _instrument_estimate(name, obs, rec, corrections, checks, sensor):
    """(the instrument's entry of the estimate, its RateMeasurement or None); appends its checks. The
    entry is the engine's of the observation's ``MEASUREMENT`` kind when that kind gives a rate
    (``RATE``); a kind that gives a block (an azimuth) goes under its ``BLOCK``
    (:func:`_also_measured`); with neither (or without a record) the entry says the instrument is not
    used."""
    engine = kind(obs.MEASUREMENT) if obs.MEASUREMENT is not None else None
    if engine is None or not engine.RATE or not obs.has_record(rec):
        reason = ABSENT
        if not _block_kinds(obs) or not obs.has_record(rec):
            reason = "not used by the estimator (no Earth-rate measurement from this instrument)"
        return UnusedEntry(type=obs.type_name, reason=reason), None
    corrections = obs.applicable_corrections(corrections)
    checks += check_before_fit(name, obs.instrument, rec)
    return engine.estimate(obs, rec, corrections, checks, sensor)


def with_block(entry, key, block) -> "Record | dict":
    """``entry`` (a record, or a plug-in kind's dict) with its kind's block under ``key`` (the kind's
    ``BLOCK``): a record's field of that name, else its open ``extra``; a dict gains the key."""
    if isinstance(entry, dict):
        return entry | {key: block}
    if key in {f.name for f in dataclasses.fields(entry)}:
        return dataclasses.replace(entry, **{key: block})
    if "extra" in {f.name for f in dataclasses.fields(entry)}:
        return dataclasses.replace(entry, extra=(entry.extra or {}) | {key: block})
    raise ValueError(f"the entry {type(entry).__name__} has no place for a {key!r} block")


def _block_kinds(obs) -> list:
    """The registered kinds of ``obs`` that give a block of their own (``RATE`` False: an azimuth),
    ``MEASUREMENT`` first, then ``ALSO_MEASURES``."""
    found = [kind(k) for k in declared_kinds(obs)]
    return [k for k in found if k is not None and not k.RATE]


def _also_measured(obs, est, records, corrections, checks, sensor) -> list:
    """The engines of the kinds an observation measures that give a block (:func:`_block_kinds`: the
    azimuth of ``ALSO_MEASURES``), on its record and its companions' (``companions()``: record key ->
    instrument name); the caller puts each into the instrument's entry under the kind's ``BLOCK``
    (:func:`with_block`).
    Returns ``(BLOCK, kind, block)`` for each."""
    kinds = _block_kinds(obs)
    if not kinds or not obs.has_record(records.get(obs.name, {})):
        return []
    rec = dict(records[obs.name])
    for key, other in obs.companions().items():
        rec[key] = records.get(other)
    out = []
    for k in kinds:
        block, _ = k.estimate(obs, rec, corrections, checks, sensor)
        out.append((k.BLOCK, k, block))
    return out


def known_earth_rate(scene, insts, meas) -> tuple:
    """(n, source): the Earth rate the estimator may take as known — the scene's
    ``site.earth_rate_rad_s`` (IERS conventional 7.292115e-5 rad/s by default) — or (None, "") when
    no measured instrument's observation sees the Earth rotate (a non-rotating Earth has no known n)."""
    names = {m.name for m in meas}
    if not any(insts[n].observation().rotating() for n in names if n in insts):
        return None, ""
    n = scene.site.earth_rate_rad_s
    source = ("the IERS conventional value, the scene's site.earth_rate_rad_s" if n == SIDEREAL_RATE_RAD_S
              else "the scene's site.earth_rate_rad_s")
    return n, source


def seed_sweep(job) -> list:
    """Estimates of one scene over many sensor seeds, simulating the truth once.

    ``job`` = (scene name or path, overrides, seeds) — one picklable argument, so a sweep can be
    ``executor.map``-ed over any ``concurrent.futures`` executor. Returns the estimate dicts.
    """
    name, overrides, seeds = job
    scene = load_scene(name, list(overrides))
    truth = simulate_truth(scene)
    return [estimate_records(scene, truth[1], measure(scene, truth, s)) for s in seeds]
