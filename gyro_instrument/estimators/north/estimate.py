"""The ``north`` block of the estimate: where a horizontal gyroscope's scale zero points (issue 24).

The engine for the :data:`~gyro_instrument.instruments.observation_azimuth.AZIMUTH` measurement a
horizontal plane gyroscope's observation declares beside its swing rate
(:class:`~gyro_instrument.instruments.observation_azimuth.HorizontalSwing`). The record's ``angle``
reads counter-clockwise, so the clockwise reading of :mod:`.north` is w = −angle (azimuth − M),
unwrapped. The headline is the exact fit (:mod:`.north.exact`, issue 33): the swing equation itself
(sine law about north, the tape toward its drifting zero, damping) fitted jointly to the rotor-on
record and, with a torsion tape, the rotor-off companion's (:data:`ROTOR_OFF`), with σ the
Cramér–Rao bound of the whole problem. The surveyors' reductions (Schuler mean, Lavrov, transit)
run beside it on the reversal points, tape-corrected with the undamped periods, the rotor-off
centre with its drift and the exact relation N = c − atan(x (Z − c)) (:func:`.north.tape_corrected`);
each states its bias in this set-up (the method run on the fitted model's own noise-free records)
and is flagged where that exceeds a quarter of its σ. The mount azimuth is (−N) mod 360°.
The block (msg_docs/estimate.md)::

    north: {instrument, mount_azimuth_deg, sigma_arcsec, crlb_arcsec, method, tape,
            methods: {schuler_mean, lavrov, transit, fit: {mount_azimuth_deg, sigma_arcsec, bias_arcsec,
                                                          bias_flagged, ...}},
            refused, pre_orientation, notes}

Near a pole the directing torque n cos γ vanishes: without any (T infinite) the block is null
with the whole circle as its interval; when one swing outlasts the observation the estimate is
refused (:class:`~.adequacy.InadequateData`, exit 2) naming the latitude limit for that duration.
"""

import math

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.angles import unwrap
from gyro_instrument.estimators import north
from gyro_instrument.estimators.north import exact, joint
from gyro_instrument.estimators.north.block import (MethodEntry, NorthBlock, NullNorthBlock, PreOrientation, RateNorthBlock,
                                                     TapeEntry)
from gyro_instrument.estimators.adequacy import InadequateData, check_entry
from gyro_instrument.instruments.observation_azimuth import ROTOR_OFF

ARCSEC_PER_RAD = 648000.0 / math.pi

#: Each method's bias under tape torque, drift and damping (first order; :mod:`.north` derives them).
BIASES = {
    "schuler_mean": "tape: pulls every centre alike (removed with the rotor-off swing); linear amplitude decay: none; "
                    "exponential damping: second order d1(1-q)^2/(4(1+q)(nu-2)); a linear drift of the centre: the "
                    "centre at the weights' mean time",
    "lavrov": "tape: as every centre (removed); exponential damping: none (exact); linear decay: second order; "
              "drift: the centre at the middle reversal point's time, to first order",
    "transit": "tape: as every centre (removed); damping: none at a mark on the centre, the sine law's "
               "x0 = A sin(pi dt/(2T)) exact undamped; finite amplitude: the swing's third harmonic shifts the "
               "transit times off the sine law (first order in the mark's offset); drift: averaged over the runs "
               "of three transits",
    "fit": "none: the swing equation itself is fitted (sine law about north, the tape toward its drifting zero, "
           "damping), jointly to the rotor-on and rotor-off records; sigma at the Cramer-Rao bound of the whole problem",
}


def _deg(centre_rad) -> float:
    return math.degrees(north.mount_azimuth_rad(centre_rad))


def arcsec_or_none(x) -> float | None:
    """An angle in rad as arcsec (float), None kept."""
    return None if x is None else float(x) * ARCSEC_PER_RAD


def method_entry(est, bias_rad=None, crlb_rad=None) -> MethodEntry:
    """One method's entry (a :class:`.block.MethodEntry`); ``bias_rad``: its bias in this set-up (the method
    on the fitted model's own noise-free records), flagged when it exceeds a quarter of the method's σ."""
    out = {"mount_azimuth_deg": _deg(est.centre_rad), "sigma_arcsec": arcsec_or_none(est.sigma_rad),
           "sigma_source": est.sigma_source, "n_used": est.n_used, "needs": est.needs,
           "bias": BIASES[est.method.split("+")[0]], "notes": list(est.notes)}
    if bias_rad is not None:
        out["bias_arcsec"] = arcsec_or_none(bias_rad)
        out["bias_flagged"] = bool(est.sigma_rad is not None and abs(bias_rad) > 0.25 * est.sigma_rad)
    if est.period_s is not None:
        out["period_s"] = est.period_s
    if crlb_rad is not None:
        out["crlb_arcsec"] = arcsec_or_none(crlb_rad)
    return MethodEntry(**out)


def null_block(name, reason, refused=None) -> NullNorthBlock:
    """The ``north`` block when no azimuth can be had: nulls, the whole circle, the reason (and the
    methods ``refused``: name -> why)."""
    return NullNorthBlock(instrument=name, mount_azimuth_deg=None, sigma_arcsec=None, crlb_arcsec=None,
                          interval_deg=[0.0, 360.0], method=None, tape=None, methods={}, refused=refused or {},
                          reason=reason)


def _latitude_limit_deg(inst, duration_s) -> float | None:
    """|latitude| below which one full swing fits in ``duration_s`` (deg), or None."""
    A = inst.p.transverse_inertia_kg_m2
    need = (2.0 * math.pi / duration_s) ** 2 - inst.tape[0] / A
    per_cos = inst.C * inst.p.spin_rate_rad_s * inst.site.earth_rate_rad_s / A
    if per_cos <= 0 or need > per_cos:
        return None
    return math.degrees(math.acos(max(need, 0.0) / per_cos))


def _check_swing(name, inst, t):
    """Refuse a record shorter than one full swing of the scene's prediction (exit 2)."""
    period = 2.0 * inst.predictions()["swing_duration_small_s"]
    ok = t[np.isfinite(t)]
    dur = float(np.ptp(ok)) if ok.size else 0.0
    if period <= dur:
        return
    if dur <= 0.0:
        raise InadequateData(check_entry(name, "north", "refused",
                                         f"the record spans {dur:g} s ({ok.size} finite sample time(s)); one swing "
                                         f"lasts {period:.6g} s: observe >= {period:.6g} s", dur, period))
    lim = _latitude_limit_deg(inst, dur)
    where = (f"|site.latitude_deg| <= {lim:.4g}" if lim is not None else "no latitude does (spin up the rotor)")
    raise InadequateData(check_entry(name, "north", "refused",
                                     f"one swing lasts {period:.6g} s at site.latitude_deg = {inst.site.latitude_deg:g} "
                                     f"(the directing torque n cos(latitude) vanishes toward the pole), longer than the "
                                     f"{dur:.6g} s observation: observe >= {period:.6g} s, or for this duration "
                                     f"{where}", inst.site.latitude_deg, lim))


def _rotor_off(name, inst, off) -> np.ndarray:
    """The rotor-off record's clockwise readings, or SceneError naming what to add."""
    if off is None or "angle" not in off:
        raise SceneError(f"instruments.{name}.rotor_off_instrument", inst.p.rotor_off_instrument or None,
                         "the tape torsion is on: add the rotor-off swing (the same gyroscope with spin_rate_rad_s: 0 "
                         "and the same tape) to the scene and name it here")
    t, a = np.asarray(off["t"], dtype=float), np.asarray(off["angle"], dtype=float)
    ok = np.isfinite(t) & np.isfinite(a)
    return exact.Record(t[ok], unwrap(-a[ok]), "off")


def swing_equation(inst, t_ref_s) -> exact.SwingEquation:
    """What the exact fit knows of ``inst``'s swing (its reduced model's constants, the tape and its
    drift as the scene declares them; damping always fitted)."""
    c = inst.reduced_coefficients()
    return exact.SwingEquation(sine_law=c["sine_law"], second_order_per_s2=c["b"], spin_decay_per_s=c["decay"],
                               tape=bool(c["kb"]), drift=bool(c["kb"] and c["zero_rate"]), damping=True,
                               t_ref_s=float(t_ref_s))


def _declared(inst) -> dict:
    """The scene's declared tape and damping in the clockwise reading: the fit's fallback start where a
    record is too short for its own (never an answer: the fit converges to the data's optimum)."""
    c = inst.reduced_coefficients()
    return {"tape": c["kb"], "zero": -c["zero"], "zero_rate": -c["zero_rate"], "damping": c["damping"]}


def _surveyor_tape(eq, records, sigma) -> dict:
    """The tape calibration of the reversal-point methods (:func:`.north.joint.tape_from_records`)."""
    on = joint.summarise(records[0].t, records[0].w, sigma, eq.drift)
    off = joint.summarise(records[1].t, records[1].w, sigma, eq.drift)
    return joint.tape_from_records(on, off, eq.t_ref_s)


def _methods(eq, records, sigma, drift) -> tuple:
    """The reversal-point methods on the rotor-on record, tape-corrected (exact relation, undamped
    periods, the drifting zero fitted): ({name: NorthEstimate}, refused, tape dict or None)."""
    on = records[0]
    ests, refused = north.north_methods(on.t, on.w, sigma, drift=drift, fit=False)
    refused.pop("fit", None)
    tape = None
    if eq.tape:
        try:
            tape = _surveyor_tape(eq, records, sigma)
        except (SceneError, np.linalg.LinAlgError, ValueError) as exc:
            why = f"no tape calibration from the rotor-off swing ({exc})"
            return {}, refused | {k: why for k in ests}, None
        ests = {k: north.tape_corrected(v, tape["zero_rad"], tape["ratio"], tape["ratio_sigma"], tape["zero_sigma_rad"])
                for k, v in ests.items()}
    return ests, refused, tape


def _biases(eq, fitted, records, sigma, drift) -> dict:
    """Each method's bias in this set-up, in mount azimuth (rad): the method run on the fitted model's
    noise-free records, its mount azimuth less the model's (the readings are clockwise: the mount is
    −N, so the bias is −(N_method − N_model)). A method the model's records refuse is left out."""
    model = joint.model_records(eq, fitted, records)
    ests, _, _ = _methods(eq, model, sigma or 1e-9, drift)
    return {k: -north.wrap_pi(v.centre_rad - fitted.north_rad) for k, v in ests.items()}


def _fit_entry(fitted, eq, records) -> "north.NorthEstimate":
    par = fitted.par()
    notes = [f"t_ref = {eq.t_ref_s:.9g} s", f"residual rms {fitted.residual_rms_rad:.6g} rad",
             f"K = D_K/A {par.get('directing', 0.0):.9g} 1/s^2", f"damping {par.get('damping', 0.0):.6g} 1/s"]
    if eq.tape:
        notes.append(f"tape: k_B = D_B/A {par['tape']:.9g} 1/s^2, zero {par['zero']:.9g} rad at t_ref"
                     + (f", drifting {par['zero_rate']:.6g} rad/s" if eq.drift else ""))
    needs = "about one swing (≥ 2 reversal points) to start" + ("; the rotor-off swing (the tape)" if eq.tape else "")
    return north.NorthEstimate("fit", fitted.north_rad, fitted.sigma_rad, fitted.sigma_source, fitted.n_samples,
                               needs, tuple(notes), crlb_rad=fitted.sigma_rad)


def north_entry(obs, rec, corrections=(), checks=None, sensor=None) -> tuple:
    """The ``north`` block of one horizontal gyroscope's record (``ENGINES[AZIMUTH]``).

    ``rec`` holds ``t`` and ``angle`` (rad) and, with a tape, the rotor-off companion's record under
    :data:`~gyro_instrument.instruments.observation_azimuth.ROTOR_OFF`. Returns (block, None): an
    azimuth is not an Earth-rate measurement. When the scene asks for north (``obs.north_asked``: a
    stated ``mount_azimuth_deg`` or a tape) raises InadequateData (one swing outlasts the record) or
    SceneError (a tape without its rotor-off swing); when it does not (mount 0 by default), an
    inadequate record gives the null block with its reason instead (issue 24 item 1: every estimate
    with a horizontal gyroscope reports ``north``, and none is refused for it).
    """
    if obs.north_asked:
        return _north_block(obs, rec, sensor), None
    try:
        return _north_block(obs, rec, sensor), None
    except InadequateData as exc:
        return null_block(obs.name, exc.check["detail"]), None
    except (SceneError, np.linalg.LinAlgError, ValueError) as exc:
        return null_block(obs.name, str(exc)), None


def _north_block(obs, rec, sensor) -> "NorthBlock | NullNorthBlock":
    """The ``north`` block (:func:`north_entry`); raises as it says."""
    inst, name = obs.instrument, obs.name
    T = inst.predictions()["swing_duration_small_s"]
    if not (math.isfinite(T) and T > 0):
        return null_block(name, f"no directing torque: {obs.null_reason}; without earth_rotation none is simulated")
    t = np.asarray(rec["t"], dtype=float)
    _check_swing(name, inst, t)
    sigma = sensor.effective_sigma_rad() if sensor is not None else 0.0
    sigma = sigma if sigma > 0 else None
    a = np.asarray(rec["angle"], dtype=float)
    ok = np.isfinite(t) & np.isfinite(a)
    records = [exact.Record(t[ok], unwrap(-a[ok]), "on")]
    eq = swing_equation(inst, float(np.mean(t[ok])))
    if eq.tape:
        records.append(_rotor_off(name, inst, rec.get(ROTOR_OFF)))
    drift = obs.centre_drifts()
    ests, refused, tape = _methods(eq, records, sigma, drift)
    try:
        fitted = joint.joint_fit(eq, records, sigma, _declared(inst))
    except (SceneError, np.linalg.LinAlgError, ValueError) as exc:
        return null_block(name, f"the fit was refused: {exc}", refused)
    ests["fit"] = _fit_entry(fitted, eq, records)
    biases = _biases(eq, fitted, records, sigma, drift)
    biases["fit"] = 0.0
    best = ests["fit"]
    methods = {k: method_entry(v, biases.get(k), best.sigma_rad if k == "fit" else None) for k, v in ests.items()}
    return NorthBlock(
        instrument=name, mount_azimuth_deg=_deg(best.centre_rad), sigma_arcsec=arcsec_or_none(best.sigma_rad),
        crlb_arcsec=arcsec_or_none(best.sigma_rad), method="fit", tape=_tape_entry(inst, fitted, tape, eq),
        methods=methods, refused=refused, pre_orientation=_pre_orientation(fitted, eq, biases, tape),
        notes=["azimuth clockwise from true north of the scale's zero; the scale reads counter-clockwise "
                       "(Quet's u), true north reads +mount_azimuth",
                       "fit: the swing equation itself (sine law, tape toward its drifting zero, damping) fitted "
                       "jointly to the rotor-on and rotor-off records; sigma at the Cramer-Rao bound of the whole "
                       "problem, tape calibration included"])


def _tape_entry(inst, fitted, tape, eq) -> "TapeEntry | None":
    """The ``tape`` entry: the joint fit's k_B, zero and drift, and the surveyors' calibration."""
    if not eq.tape:
        return None
    par, K = fitted.par(), fitted.par()["directing"]
    i, j = fitted.names.index("tape"), fitted.names.index("directing")
    g = np.zeros(len(fitted.names))
    g[i], g[j] = 1.0 / K, -par["tape"] / K ** 2            # ∂(k_B/K)
    return TapeEntry(
        instrument=inst.p.rotor_off_instrument, ratio_db_dk=par["tape"] / K,
        ratio_sigma=float(math.sqrt(g @ fitted.cov @ g)), zero_reading_deg=-math.degrees(par["zero"]),
        zero_sigma_arcsec=arcsec_or_none(fitted.sigma("zero")),
        zero_rate_arcsec_h=-arcsec_or_none(par.get("zero_rate", 0.0)) * 3600.0,
        surveyor_ratio=tape["ratio"] if tape else None, surveyor_ratio_sigma=tape["ratio_sigma"] if tape else None,
        source="the joint fit of both swings (k_B/K, the zero at t_ref and its drift); the reversal-point "
                      "methods use the surveyors' calibration: x = T_on^2/(T_off^2 - T_on^2) from undamped periods, "
               "the rotor-off centre with its drift, and the exact relation N = c - atan(x (Z - c))")


def _pre_orientation(fitted, eq, biases, tape) -> PreOrientation:
    """How far the swing's centre sits from north and what that costs each method (arcsec)."""
    par = fitted.par()
    N = fitted.north_rad
    K, kb = par["directing"], par.get("tape", 0.0)
    c = joint.equilibrium(N, K, kb, par.get("zero", 0.0))
    out = {"centre_from_north_deg": math.degrees(c - N),
           "cost_arcsec": {k: arcsec_or_none(v) for k, v in biases.items()}}
    if eq.tape:                             # x = k_B/(K cos(c − N)): the ratio the periods measure
        out["tape_zero_from_north_deg"] = math.degrees(north.wrap_pi(par["zero"] - N))
        x = kb / (K * math.cos(c - N))
        out["linear_tape_law_error_arcsec"] = arcsec_or_none(joint.linear_law_error_rad(c, par["zero"], x))
    return PreOrientation(**out)


def best_block(blocks) -> "NorthBlock | RateNorthBlock | NullNorthBlock | None":
    """The estimate's top-level ``north``: the block with the smallest σ (nulls last), or None. A block is a
    record (:mod:`.block`) or, from a plug-in kind, its JSON dict."""
    if not blocks:
        return None

    def sigma(b):
        value = b.get("sigma_arcsec") if isinstance(b, dict) else b.sigma_arcsec
        return math.inf if value is None else value
    return min(blocks, key=sigma)

