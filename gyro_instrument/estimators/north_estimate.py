"""The ``north`` block of the estimate: where a horizontal gyroscope's scale zero points (issue 24).

The engine for the :data:`~gyro_instrument.instruments.observation_azimuth.AZIMUTH` measurement a
horizontal plane gyroscope's observation declares beside its swing rate
(:class:`~gyro_instrument.instruments.observation_azimuth.HorizontalSwing`). The record's ``angle``
reads counter-clockwise, so the clockwise reading of :mod:`.north` is −angle (u = azimuth − M);
every method of :func:`.north.north_methods` runs on it with the sensor model's σ; with a torsion
tape the rotor-off companion record gives the tape zero Z (the fit's centre of the torsion
pendulum) and D_B/D_K from the two periods (:func:`.north.tape_ratio`), and each centre is
corrected, N = c + (D_B/D_K)(c − Z) (:func:`.north.tape_corrected`). The mount azimuth is
(−N) mod 360°. The block (msg_docs/estimate.md)::

    north: {instrument, mount_azimuth_deg, sigma_arcsec, crlb_arcsec, method, tape,
            methods: {schuler_mean, lavrov, transit, fit: {mount_azimuth_deg, sigma_arcsec, ...}},
            refused, notes}

Near a pole the directing torque n cos γ vanishes: without any (T infinite) the block is null
with the whole circle as its interval; when one swing outlasts the observation the estimate is
refused (:class:`~.adequacy.InadequateData`, exit 2) naming the latitude limit for that duration.
"""

import math

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators import north
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
    "fit": "tape: as every centre (removed); damping and a linear drift of the centre are fitted (the drift when "
           "the scene lists tape_drift): none; sigma at the Cramer-Rao bound",
}


def _deg(centre_rad) -> float:
    return math.degrees(north.mount_azimuth_rad(centre_rad))


def _arcsec(x) -> float | None:
    return None if x is None else float(x) * ARCSEC_PER_RAD


def _method_entry(est, crlb_rad=None) -> dict:
    out = {"mount_azimuth_deg": _deg(est.centre_rad), "sigma_arcsec": _arcsec(est.sigma_rad),
           "sigma_source": est.sigma_source, "n_used": est.n_used, "needs": est.needs,
           "bias": BIASES[est.method.split("+")[0]], "notes": list(est.notes)}
    if est.period_s is not None:
        out["period_s"] = est.period_s
    if crlb_rad is not None:
        out["crlb_arcsec"] = _arcsec(crlb_rad)
    return out


def null_block(name, reason) -> dict:
    """The ``north`` block when no azimuth can be had: nulls, the whole circle, the reason."""
    return {"instrument": name, "mount_azimuth_deg": None, "sigma_arcsec": None, "crlb_arcsec": None,
            "interval_deg": [0.0, 360.0], "method": None, "tape": None, "methods": {}, "refused": {},
            "reason": reason}


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


def _tape(name, inst, off, fit_on, sigma):
    """(zero_rad, zero_sigma, ratio, ratio_sigma, entry) from the rotor-off companion record."""
    if off is None:
        raise SceneError(f"instruments.{name}.rotor_off_instrument", inst.p.rotor_off_instrument or None,
                         "the tape torsion is on: add the rotor-off swing (the same gyroscope with spin_rate_rad_s: 0 "
                         "and the same tape) to the scene and name it here")
    z = north.fit_record(off["t"], -np.asarray(off["angle"], dtype=float), sigma)
    ratio, rs = north.tape_ratio(fit_on.period_s, z.period_s, fit_on.period_sigma_s or 0.0, z.period_sigma_s or 0.0)
    entry = {"instrument": inst.p.rotor_off_instrument, "ratio_db_dk": ratio, "ratio_sigma": rs,
             "zero_reading_deg": -math.degrees(z.centre_rad), "zero_sigma_arcsec": _arcsec(z.sigma_rad),
             "rotor_on_period_s": fit_on.period_s, "rotor_off_period_s": z.period_s,
             "source": "rotor-off swing (torsion pendulum): zero = its fitted centre; D_B/D_K = T_on^2/(T_off^2 - T_on^2)"}
    return z.centre_rad, z.sigma_rad or 0.0, ratio, rs, entry


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


def _north_block(obs, rec, sensor) -> dict:
    """The ``north`` block (:func:`north_entry`); raises as it says."""
    inst, name = obs.instrument, obs.name
    T = inst.predictions()["swing_duration_small_s"]
    if not (math.isfinite(T) and T > 0):
        return null_block(name, f"no directing torque: {obs.null_reason}; without earth_rotation none is simulated")
    t = np.asarray(rec["t"], dtype=float)
    _check_swing(name, inst, t)
    sigma = sensor.effective_sigma_rad() if sensor is not None else 0.0
    sigma = sigma if sigma > 0 else None
    ests, refused = north.north_methods(t, -np.asarray(rec["angle"], dtype=float), sigma,
                                        drift=obs.centre_drifts())
    if "fit" not in ests:
        return null_block(name, f"the fit was refused: {refused.get('fit')}") | {"refused": refused}
    fit = ests["fit"]
    ratio, tape = 0.0, None
    if obs.has_tape():
        zero, zs, ratio, rs, tape = _tape(name, inst, rec.get(ROTOR_OFF), fit, sigma)
        ests = {k: north.tape_corrected(v, zero, ratio, rs, zs) for k, v in ests.items()}
    crlb = None if fit.crlb_rad is None else fit.crlb_rad * (1.0 + ratio)
    best = ests["fit"]
    return {"instrument": name, "mount_azimuth_deg": _deg(best.centre_rad), "sigma_arcsec": _arcsec(best.sigma_rad),
            "crlb_arcsec": _arcsec(crlb), "method": "fit", "tape": tape,
            "methods": {k: _method_entry(v, crlb if k == "fit" else None) for k, v in ests.items()},
            "refused": refused,
            "notes": ["azimuth clockwise from true north of the scale's zero; the scale reads counter-clockwise "
                      "(Quet's u), true north reads +mount_azimuth"]}


def best_block(blocks) -> dict | None:
    """The estimate's top-level ``north``: the block with the smallest σ (nulls last), or None."""
    if not blocks:
        return None
    return min(blocks, key=lambda b: b["sigma_arcsec"] if b.get("sigma_arcsec") is not None else math.inf)


def field_book_block(path, angle_unit=None, time_unit=None, scene=None, separator=None, division_rad=None) -> dict:
    """The ``north`` block of a field book (``estimate --reversal-points FILE``): moved to
    :func:`.field_book_report.field_book_block` (issue 33 item 5), re-exported here."""
    from gyro_instrument.estimators.field_book_report import field_book_block as block
    return block(path, angle_unit, time_unit, scene, separator, division_rad)
