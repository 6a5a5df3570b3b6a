"""From a scene to estimates: simulate the truth, measure through the sensor model, estimate.

``simulate_truth`` runs each instrument once; ``measure`` draws the sensor samples for one seed
(so 200 seeded runs cost one simulation; both in :mod:`.measure`); ``estimate_records`` turns
measured records into the ``estimate`` JSON object: per-instrument periods (fit and Quet's
counting), Quet's item 9 and eq. (10), the Foucault rate with its ellipse correction, and the
combined latitude and Earth rate (profile likelihood, :mod:`.latitude`) with their Cramér–Rao
bounds. Quantities that cannot be estimated are ``None`` with a reason — never NaN, infinity or a
crash.

Each instrument's record is estimated as its observation says
(:meth:`~gyro_instrument.instruments.base.Instrument.observation`): its ``MEASUREMENT`` kind picks
the fit (:data:`ENGINES`: a swing about a directing line, :func:`.swing.swing_estimate`; a swing
plane's precession, :func:`estimate_foucault`), and the observation supplies the laws.
"""

from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S
from gyro_instrument.estimators.adequacy import InadequateData, check_before_fit, check_entry, check_period, \
    halves_entry, hemisphere_entry, plane_fit_entry, site_check
from gyro_instrument.estimators.combine import classic_methods, combined, null_combined
from gyro_instrument.estimators.foucault import estimate_foucault
from gyro_instrument.estimators.latitude import RateMeasurement
from gyro_instrument.estimators.measure import MeasureStream, measure, simulate_truth
from gyro_instrument.estimators.north_estimate import best_block, north_entry
from gyro_instrument.estimators.period import DETECTION_SNR, EstimationError, NoSignal
from gyro_instrument.estimators import rate_gyro_north          # KINDS-REWIRE (issue 35): the rate gyro's engine
from gyro_instrument.estimators.swing import swing_estimate
from gyro_instrument.instruments.observation import (CORRECTIONS, ELLIPSE_CORRECTION, FINITE_AMPLITUDE_CORRECTIONS,
                                                     PLANE_RATE, SWING_RATE)
from gyro_instrument.instruments.observation_azimuth import AZIMUTH
from gyro_instrument.instruments.rate_gyro import RATE_AZIMUTH    # KINDS-REWIRE (issue 35)
from gyro_instrument.scenes import load_scene
from gyro_instrument.sensors import SensorModel

__all__ = ["CORRECTIONS", "ENGINES", "FINITE_AMPLITUDE_CORRECTIONS", "MeasureStream", "estimable", "estimate_records",
           "estimator_instruments", "known_earth_rate", "measure", "missing_companions", "seed_sweep",
           "simulate_truth"]


def estimable(inst) -> bool:
    """True for instruments whose observation gives an Earth-rate measurement (``MEASUREMENT`` not
    None): pendulums (k = n sin γ) and gyroscopes with a directing line (y = n s(γ)), or another
    measurement beside none (``ALSO_MEASURES``: a rate gyro's azimuth). Free gyroscopes and Puiseux's
    body do not."""
    obs = inst.observation()
    # KINDS-REWIRE (issue 35): a rate gyro measures an azimuth only (ALSO_MEASURES), no Earth rate
    return obs.MEASUREMENT is not None or bool(obs.ALSO_MEASURES)


def estimator_instruments(insts) -> list:
    """The names of the instruments whose records the estimator reads, in the scene's order: the
    estimable ones and the records they read beside their own (``companions()``: a horizontal
    gyroscope's rotor-off swing with a tape). What a live ``run`` keeps, ``replay`` decodes from a bag
    and ``estimate --data`` asks columns for, so that each builds the record ``estimate`` measures."""
    names = {n for n, inst in insts.items() if estimable(inst)}
    for n in list(names):
        names.update(v for v in insts[n].observation().companions().values() if v in insts)
    return [n for n in insts if n in names]


def missing_companions(insts, records) -> list:
    """``(name, record key, companion)`` for each instrument with a record whose companion (in ``insts``)
    has none: what a table or a bag lacks for an estimate the scene asks for."""
    return [(n, key, other) for n in records if n in insts
            for key, other in insts[n].observation().companions().items()
            if other in insts and other not in records]


def estimate_records(scene, insts, records, corrections=CORRECTIONS) -> dict:
    """The ``estimate`` JSON object (see module docstring) from measured records.

    ``corrections`` — the subset of :data:`CORRECTIONS` to apply (all by default); a study of
    what a correction is worth passes fewer.

    Raises
    ------
    gyro_instrument.estimators.adequacy.InadequateData
        The data fail a check no estimate can survive (estimators/adequacy.py): one line naming
        the check, and, in a scene of several instruments, how to leave the failing one out.
    """
    unknown = set(corrections) - CORRECTIONS
    if unknown:
        raise ValueError(f"unknown corrections {sorted(unknown)}; known: {sorted(CORRECTIONS)}")
    site = scene.site
    result = {"scene": scene.name, "seed": scene.seed, "observation_s": float(scene.duration_s),
              "truth": {"latitude_deg": site.latitude_deg, "earth_rate_rad_s": site.earth_rate_rad_s},
              "instruments": {}, "methods": {}}
    meas, gyros, pend, checks, norths = [], {}, None, [], []
    sensor = SensorModel.from_scene(scene)
    for name, inst in insts.items():
        obs = inst.observation()
        try:
            est, m = _instrument_estimate(name, obs, records[name], corrections, checks, sensor)
            norths += _also_measured(obs, est, records, corrections, checks, sensor)
        except InadequateData as exc:
            if len(insts) > 1:
                exc.add_hint(f"or leave {name} out: --set instruments.{name}=null")
            raise
        result["instruments"][name] = est
        if m is not None:
            meas.append(m)
            if m.kind == PLANE_RATE:
                pend = (obs, est, m)
            else:
                gyros[name] = (obs, est, m)
    if meas:
        result.update(combined(meas, scene.estimator.get("hemisphere"), *known_earth_rate(scene, insts, meas),
                               earth_rate=scene.estimator.get("earth_rate")))
    else:
        result.update(null_combined("no Earth-rate measurement: needs a gyroscope with a directing line "
                                     "(plane, cone, gimbal) or a pendulum with a measured oscillation"))
    if norths:
        result["north"] = best_block(norths)
    classic_methods(result, gyros, pend, scene.estimator.get("earth_rate"))
    entry = hemisphere_entry(result.get("hemisphere"), result.get("hemisphere_basis", ""), site.latitude_deg)
    result["checks"] = checks + ([entry] if entry else [])
    site_check(result, site)
    return result


def _instrument_estimate(name, obs, rec, corrections, checks, sensor):
    """(the instrument's entry of the estimate, its RateMeasurement or None); appends its checks."""
    engine = ENGINES.get(obs.MEASUREMENT)
    if engine is None or not obs.has_record(rec):
        also = " beside its north (the north block)" if obs.ALSO_MEASURES else ""     # KINDS-REWIRE (issue 35)
        return {"type": obs.type_name, "reason": "not used by the estimator (no Earth-rate measurement from this "
                                                 f"instrument{also})"}, None
    corrections = obs.applicable_corrections(corrections)
    checks += check_before_fit(name, obs.instrument, rec)
    return engine(obs, rec, corrections, checks, sensor)


def _also_measured(obs, est, records, corrections, checks, sensor) -> list:
    """The engines of the kinds an observation measures beside its ``MEASUREMENT``
    (``ALSO_MEASURES``: an azimuth), on its record and its companions' (``companions()``: record key ->
    instrument name); each result goes into the instrument's entry under the kind's key
    (:data:`ALSO_KEYS`). Returns the ``north`` blocks."""
    kinds = obs.ALSO_MEASURES
    if not kinds or not obs.has_record(records[obs.name]):
        return []
    rec = dict(records[obs.name])
    for key, other in obs.companions().items():
        rec[key] = records.get(other)
    out = []
    for kind in kinds:
        block, _ = ENGINES[kind](obs, rec, corrections, checks, sensor)
        est[ALSO_KEYS[kind]] = block
        out.append(block)
    return out


def _pendulum_estimate(obs, rec, corrections, checks, sensor):
    """The Foucault rate of one pendulum record (estimators/foucault.py) and its checks."""
    name, inst = obs.name, obs.instrument
    east, north = obs.layout.measured
    try:
        f = estimate_foucault(rec["t"], rec[east], rec[north], correct_ellipse=ELLIPSE_CORRECTION in corrections,
                              noise_rad=sensor.effective_sigma_rad())
    except EstimationError as exc:
        if isinstance(exc, NoSignal):
            checks.append(check_entry(name, "signal", "no_signal", str(exc), expected=DETECTION_SNR))
        return {"type": inst.type_name, "foucault_rate_rad_s": None, "reason": str(exc)}, None
    est = {"type": inst.type_name, "foucault_rate_rad_s": f.k_rad_s,
           "foucault_rate_sigma_rad_s": f.k_sigma_rad_s, "crlb_foucault_rate_rad_s": f.crlb_k_rad_s,
           "measured_plane_rate_rad_s": f.measured_rate_rad_s,
           "measured_plane_rate_sigma_rad_s": f.measured_rate_sigma_rad_s, "sigma_basis": f.sigma_basis,
           "sigma_basis_detail": f.sigma_basis_text,
           "ellipse_correction_rad_s": f.airy_correction_rad_s, "amplitude_rad": f.amplitude_rad,
           "minor_axis_rad": f.minor_axis_rad, "period_s": f.period_s, "period_sigma_s": f.period_sigma_s,
           "rest_point": f.rest_point, "windows": f.windows, "notes": f.notes,
           "ellipse_scale": ellipse_scale(f.measured_rate_rad_s, f.airy_correction_rad_s, f.k_sigma_rad_s)}
    checks.append(check_entry(name, "signal", "passed", f"swing detected (A^2 N / (4 sigma^2) >= {DETECTION_SNR:g}; "
                                                       "estimators/foucault.py)", expected=DETECTION_SNR))
    entry = check_period(name, inst, f.period_s)
    if entry:
        checks.append(entry)
    checks.append(plane_fit_entry(name, f.plane_chi2_per_dof, f.plane_dof, f.noise_rad))
    checks.append(halves_entry(name, f.plane_line))
    # a noise-free record's bound is 0; the combination weights it as exact (1/σ² finite)
    return est, RateMeasurement(name, PLANE_RATE, f.k_rad_s, f.k_sigma_rad_s, crlb_sigma=max(f.crlb_k_rad_s, 1e-150))


def ellipse_scale(measured_rad_s, correction_rad_s, sigma_rad_s) -> dict:
    """How the ellipse (Airy) correction hangs on the position scale: it is (3/8) a b / l² times the
    swing frequency (physics_notes "Real Foucault pendulums"), a and b the axes read from the track, so
    a scale s times the assumed one multiplies it by s² while the measured turn is unchanged. ``matters``:
    halving the scale would move k by more than its σ (3/4 of the correction > σ) — then positions given
    in pixels (or a wrong length) decide the answer, and ``k_at_half_scale_rad_s`` /
    ``k_at_double_scale_rad_s`` say by how much."""
    m, c = float(measured_rad_s), float(correction_rad_s)
    return {"exponent": 2, "share_of_measured_rate": c / m if m else None,
            "k_without_correction_rad_s": m, "k_at_half_scale_rad_s": m - c / 4.0, "k_at_double_scale_rad_s": m - 4.0 * c,
            "matters": bool(abs(0.75 * c) > float(sigma_rad_s or 0.0))}


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


#: The fit for each measurement kind an observation declares
#: (:data:`~gyro_instrument.instruments.observation.SWING_RATE`, ``PLANE_RATE``): ``engine(observation,
#: record, corrections, checks, sensor) -> (entry, RateMeasurement or None)``.
#: An azimuth (:data:`~gyro_instrument.instruments.observation_azimuth.AZIMUTH`): the ``north`` block of a
#: horizontal gyroscope (:func:`.north_estimate.north_entry`; its second item is always None).
#: A rate gyro's azimuth (:data:`~gyro_instrument.instruments.rate_gyro.RATE_AZIMUTH`): its ``north`` block
#: (:func:`.rate_gyro_north.north_entry`). KINDS-REWIRE (issue 35): these two entries move to the kind.
ENGINES = {SWING_RATE: swing_estimate, PLANE_RATE: _pendulum_estimate, AZIMUTH: north_entry,
           RATE_AZIMUTH: rate_gyro_north.north_entry}
#: The key of the estimate entry each ``ALSO_MEASURES`` kind's result goes under.
ALSO_KEYS = {AZIMUTH: "north", RATE_AZIMUTH: "north"}


def seed_sweep(job) -> list:
    """Estimates of one scene over many sensor seeds, simulating the truth once.

    ``job`` = (scene name or path, overrides, seeds) — one picklable argument, so a sweep can be
    ``executor.map``-ed over any ``concurrent.futures`` executor. Returns the estimate dicts.
    """
    name, overrides, seeds = job
    scene = load_scene(name, list(overrides))
    truth = simulate_truth(scene)
    return [estimate_records(scene, truth[1], measure(scene, truth, s)) for s in seeds]
