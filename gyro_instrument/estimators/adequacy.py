"""Adequacy: the data are checked against the scene and against themselves before a number is reported.

One mechanism for every estimate (a scene's simulation, a table, a bag, the live estimator node):
:func:`~gyro_instrument.estimators.pipeline.estimate_records` calls these checks on each
instrument's record, and each check's outcome goes into the estimate's ``checks`` list (and the
text). A check that fails in a way no estimate can survive raises :class:`InadequateData` (a
:class:`~gyro_instrument.core.errors.SceneError`: exit 2, one line naming the check, both numbers
and the likely cause); a softer failure is ``flagged`` with its figure.

The checks, per instrument whose class predicts its swing (:meth:`Instrument.expected_swing`):

``amplitude``
    The record's swing amplitude (half the 0.5–99.5 % range of a gyroscope's angle; the 99.5 %
    point of a pendulum's deflection) against the scene's release amplitude: more than
    :data:`AMPLITUDE_FACTOR` times it, or beyond π (no swing angle or deflection can exceed a half
    turn), is refused — "angles look like degrees" when the ratio is within a factor 4 of 180/π
    or the angle exceeds π. Smaller swings are legitimate (a gentler release); ``signal`` judges them.
``sampling``
    Samples per predicted period, P / Δt (Δt the median interval): below
    :data:`MIN_SAMPLES_PER_PERIOD` the swing aliases and a fit would find the alias, so the
    estimate is refused (never fitted); an instrument whose observation needs more says so
    (``ExpectedSwing.min_samples_per_period``: a pendulum's 8 per swing period). First the time unit is tried: when the record's own
    dominant period is a unit factor (10³, 10⁶, 10⁹, 1/60) times P within a factor 2 and is
    itself sampled well, the refusal says "time looks like milliseconds" instead.
``period``
    The fitted period against the scene's: beyond a factor :data:`PERIOD_FACTOR` (a directing
    torque K ∝ s(γ) ρ: a factor 4 in period is 16 in K, far beyond any latitude or spin error a
    scene could hold for a real instrument) it is refused, naming a unit when the ratio is one.
``signal``
    Detection: A² N / (4 σ²) ≥ :data:`~gyro_instrument.estimators.period.DETECTION_SNR` with σ the
    fit's residual but never below :data:`ROUNDOFF_RAD` — the resolution of a double-precision
    angle — so a pendulum at rest read from a file (deflections of 1e-17 rad) is "no swing" as it
    is when the scene adds its sensor noise: the same rule for files and scenes.
``fit``
    A gyroscope: χ²/dof = residual² / (σ_noise² + q²/12) with the scene's sensor model: outside
    1 ± 5 √(2/dof) it is ``flagged`` with the figure; above :data:`CHI2_WITHHOLD` (a residual 10×
    the sensor's noise: the model does not describe the signal) the estimate is withheld
    (refused). Not applicable when the scene's sensor has no noise model. A pendulum: the χ²/dof
    of the swing-plane azimuths about their line against the scatter the record's own noise
    explains; flagged beyond the same band, σ then from the scatter.
"""

import math

import numpy as np

from gyro_instrument.core.errors import SceneError

#: Fewest samples per predicted period that a fit may use: the Nyquist limit is 2; 2.5 leaves room
#: for the period's uncertainty (a scene's latitude and spin) and for irregular sampling.
MIN_SAMPLES_PER_PERIOD = 2.5

#: A fitted period more than this factor from the scene's prediction is refused (see ``period``).
PERIOD_FACTOR = 4.0

#: A swing amplitude more than this factor above the scene's release amplitude is refused. 30 is
#: below 180/π = 57.3 (angles in degrees) by a factor 1.9 and allows a release 30× the scene's.
AMPLITUDE_FACTOR = 30.0

#: The resolution of an angle stored as a double: 8 ulp of π (5.6e-15 rad); no residual is smaller.
ROUNDOFF_RAD = 8.0 * float(np.finfo(float).eps) * math.pi

#: χ²/dof above which the fit is withheld: a residual rms 10× the sensor model's noise.
CHI2_WITHHOLD = 100.0

#: Time units a user's clock may have written under ``time_s``: (factor of the period in those
#: units over seconds, the unit's name, its ``--time-unit`` value).
TIME_UNITS = ((1e3, "milliseconds", "ms"), (1e6, "microseconds", "us"), (1e9, "nanoseconds", "ns"),
              (1.0 / 60.0, "minutes", "min"))


class InadequateData(SceneError):
    """The data fail a check no estimate can survive: exit 2, one line.

    Attributes
    ----------
    field : str
        ``<instrument>.<check>``.
    check : dict
        The check's entry (as in the estimate's ``checks``).
    """

    def __init__(self, entry) -> None:
        self.check = entry
        self.field = f"{entry['instrument']}.{entry['check']}"
        self.value = entry.get("value")
        self.valid = entry["detail"]
        ValueError.__init__(self, self._text())

    def _text(self):
        return f"estimate refused by the {self.check['check']} check of {self.check['instrument']}: {self.valid}"

    def restate(self, detail) -> None:
        """Replace the check's detail (what failed and the likely cause) in the one-line message."""
        self.valid = detail
        self.args = (self._text(),)

    def add_hint(self, hint) -> None:
        """Append ``hint`` (what else the user can do) to the one-line message."""
        self.restate(f"{self.valid}; {hint}")


def check_entry(name, check, status, detail, value=None, expected=None) -> dict:
    """One entry of an estimate's ``checks``: instrument, check, status, value, expected, detail."""
    return {"instrument": name, "check": check, "status": status, "value": value, "expected": expected,
            "detail": detail}


def _unit_for(ratio):
    """The time unit whose factor is within a factor 2 of ``ratio`` (measured over predicted period)."""
    for factor, unit, flag in TIME_UNITS:
        if abs(math.log(ratio / factor)) < math.log(2.0):
            return unit, flag
    return None


def _time_unit_refusal(name, ratio, period_data, expected):
    unit, flag = _unit_for(ratio)
    return InadequateData(_with_periods(check_entry(
        name, "time_unit", "refused",
        f"the record's swing period is {period_data:.6g} time units against the scene's predicted "
        f"{expected.period_s:.6g} s (ratio {ratio:.4g}): time looks like {unit}; pass --time-unit {flag}",
        ratio, 1.0), period_data, expected))


def _with_periods(entry, period_data, expected):
    """``entry`` with ``record_period`` (the record's own period in its time units) and
    ``expected_period_s``: what a reader that knows the table's time conversion advises from
    (:mod:`.time_advice`)."""
    entry["record_period"] = period_data
    entry["expected_period_s"] = expected.period_s
    return entry


def check_before_fit(name, inst, rec) -> list:
    """The ``amplitude`` and ``sampling`` checks of one record; raises :class:`InadequateData`.

    Parameters
    ----------
    name : str
    inst : Instrument
        Its :meth:`expected_swing` gives the prediction; None: no check applies.
    rec : dict
        The measured record (``t`` and the channels, as :func:`pipeline.measure` makes them).

    Returns
    -------
    list of dict
        The checks' entries.
    """
    expected = inst.expected_swing()
    if expected is None:
        return [check_entry(name, "sampling", "not_applicable", "the scene predicts no swing for this instrument")]
    out = []
    a = inst.observation().swing_amplitude(rec)
    if math.isfinite(a):
        # a scene released at rest predicts no amplitude to compare with: only the half-turn limit applies
        ratio = a / expected.amplitude_rad if expected.amplitude_rad > 0 else 0.0
        if a > math.pi or ratio > AMPLITUDE_FACTOR:
            deg = a > math.pi or abs(math.log(max(ratio, 1e-300) / math.degrees(1.0))) < math.log(4.0)
            cause = ("angles look like degrees; pass --angle-unit deg" if deg else
                     f"the scene's release amplitude does not describe this record (set it from {expected.source})")
            raise InadequateData(check_entry(name, "amplitude", "refused",
                                        f"swing amplitude {a:.6g} rad is {ratio:.3g}x the scene's {expected.amplitude_rad:.6g} "
                                        f"rad (at most {AMPLITUDE_FACTOR:g}x, and never beyond pi): {cause}",
                                        a, expected.amplitude_rad))
        out.append(check_entry(name, "amplitude", "passed", f"swing amplitude {a:.4g} rad, scene's {expected.amplitude_rad:.4g} rad",
                          a, expected.amplitude_rad))
    t = np.asarray(rec["t"], dtype=float)
    t = np.unique(t[np.isfinite(t)])
    if t.size < 3:
        return out
    dt = float(np.median(np.diff(t)))
    spp = expected.period_s / dt
    need = max(MIN_SAMPLES_PER_PERIOD, expected.min_samples_per_period)
    if spp < need:
        _refuse_undersampled(name, inst, rec, dt, spp, expected, need)
    out.append(check_entry(name, "sampling", "passed",
                      f"{spp:.4g} samples per predicted period of {expected.period_s:.6g} s (at least "
                      f"{need:g})", spp, need))
    return out


def _refuse_undersampled(name, inst, rec, dt, spp, expected, need):
    """Raise for a record with fewer than :data:`MIN_SAMPLES_PER_PERIOD` samples per predicted
    period: as a time unit when the record's own period says so, else as an alias."""
    from gyro_instrument.estimators.period import EstimationError, fft_guess
    y = inst.observation().swing_signal(rec)
    ok = np.isfinite(rec["t"]) & np.isfinite(y)
    try:
        period_data = 2.0 * math.pi / fft_guess(np.asarray(rec["t"])[ok], np.asarray(y)[ok], min_cycles=2.0)
    except (EstimationError, ValueError, ZeroDivisionError):
        period_data = math.nan
    if math.isfinite(period_data) and period_data / dt >= MIN_SAMPLES_PER_PERIOD \
            and _unit_for(period_data / expected.period_s):
        raise _time_unit_refusal(name, period_data / expected.period_s, period_data, expected)
    raise InadequateData(_with_periods(check_entry(
        name, "sampling", "refused",
        f"{spp:.3g} samples per predicted period of {expected.period_s:.6g} s (one every {dt:.6g} s); below "
        f"{need:g} {expected.sampling_reason}: sample at least {need / expected.period_s:.3g} Hz", spp, need),
        period_data if math.isfinite(period_data) and period_data / dt >= need else None, expected))


def check_period(name, inst, period_s) -> dict | None:
    """The ``period`` check of a fitted full period (s); raises :class:`InadequateData`."""
    expected = inst.expected_swing()
    if expected is None or not (period_s and math.isfinite(period_s)):
        return None
    ratio = period_s / expected.period_s
    if _unit_for(ratio) and not (1.0 / PERIOD_FACTOR <= ratio <= PERIOD_FACTOR):
        raise _time_unit_refusal(name, ratio, period_s, expected)
    if not (1.0 / PERIOD_FACTOR <= ratio <= PERIOD_FACTOR):
        raise InadequateData(_with_periods(check_entry(
            name, "period", "refused",
            f"the fitted period {period_s:.6g} s is {ratio:.4g}x the scene's predicted {expected.period_s:.6g} s "
            f"(within a factor {PERIOD_FACTOR:g} is accepted): the scene does not describe this instrument "
            f"(check {expected.source})", ratio, 1.0), period_s, expected))
    return check_entry(name, "period", "passed", f"fitted period {period_s:.6g} s, predicted {expected.period_s:.6g} s "
                                            f"(ratio {ratio:.6g})", ratio, 1.0)


def detection_snr(amplitude, n_samples, residual_rms) -> float:
    """A² N / (4 σ²), σ the residual rms but at least :data:`ROUNDOFF_RAD` (see ``signal``)."""
    sigma = max(float(residual_rms), ROUNDOFF_RAD)
    return float(amplitude) ** 2 * n_samples / (4.0 * sigma * sigma)


def signal_entry(name, snr, threshold) -> dict:
    """The ``signal`` check's entry (``no_signal``: the instrument's estimate is null with a reason)."""
    ok = snr >= threshold
    return check_entry(name, "signal", "passed" if ok else "no_signal",
                  f"detection A^2 N / (4 sigma^2) = {snr:.4g} ({'>=' if ok else '<'} {threshold:g})", snr, threshold)


def check_fit(name, residual_rms, dof, sensor) -> dict:
    """The ``fit`` check: χ²/dof of the residual against the sensor model; raises :class:`InadequateData`
    above :data:`CHI2_WITHHOLD`."""
    var = sensor.noise_rad ** 2 + sensor.quantization_rad ** 2 / 12.0
    if var <= 0.0:
        return check_entry(name, "fit", "not_applicable", "the scene's sensor has no noise model (noise_rad = 0): "
                                                     "chi2/dof cannot be formed")
    chi2 = float(residual_rms) ** 2 / var
    band = 5.0 * math.sqrt(2.0 / max(dof, 1))
    if chi2 > CHI2_WITHHOLD:
        raise InadequateData(check_entry(
            name, "fit", "refused",
            f"chi2/dof = {chi2:.4g}: the residual rms {residual_rms:.4g} rad is {math.sqrt(chi2):.3g}x the sensor "
            f"model's {math.sqrt(var):.4g} rad, so the model does not describe this record (another instrument, "
            f"a disturbance, or a sensor noisier than the scene says: if so, set its noise, --set "
            f"sensor.noise_rad={residual_rms:.2g}); estimate withheld", chi2, 1.0))
    if abs(chi2 - 1.0) > band:
        how = "above" if chi2 > 1.0 else "below"
        return check_entry(name, "fit", "flagged",
                      f"chi2/dof = {chi2:.4g}, {how} 1 +/- {band:.2g}: the residual rms {residual_rms:.4g} rad against "
                      f"the sensor model's {math.sqrt(var):.4g} rad" + (" (data smoother than the sensor model: a "
                                                                         "noise-free simulation?)" if chi2 < 1 else ""),
                      chi2, 1.0)
    return check_entry(name, "fit", "passed", f"chi2/dof = {chi2:.4g} (1 +/- {band:.2g})", chi2, 1.0)


def plane_fit_entry(name, chi2, dof, noise_rad) -> dict:
    """The pendulum's ``fit`` check: χ²/dof of the swing-plane azimuths about their line against the
    scatter the record's own noise explains (estimators/foucault.py); flagged beyond 1 + 5 √(2/dof)
    (σ is then taken from the scatter, never withheld: the line is still the best rate)."""
    band = 5.0 * math.sqrt(2.0 / max(dof, 1))
    if not math.isfinite(chi2) or (noise_rad < 1e-9 and chi2 > 1.0 + band):
        return check_entry(name, "fit", "flagged", f"the record shows almost no noise ({noise_rad:.3g} rad: a noise-free "
                                              "simulation?), so the swing-plane azimuths' own scatter sets sigma",
                      None if not math.isfinite(chi2) else chi2, 1.0)
    status = "passed" if chi2 <= 1.0 + band else "flagged"
    return check_entry(name, "fit", status,
                  f"swing-plane azimuths about their line: chi2/dof = {chi2:.4g} over {dof} swings (1 + {band:.2g} at "
                  f"most) for the noise {noise_rad:.3g} rad" + ("" if status == "passed" else
                                                                 ": sigma from their scatter"), chi2, 1.0)


def hemisphere_entry(hemisphere, basis, scene_latitude_deg) -> dict | None:
    """The ``hemisphere`` check: a hemisphere measured by the data (a pendulum's sign of k) against
    the scene's latitude; a contradiction is ``flagged`` (east and north swapped, a mirrored axis,
    or the wrong scene). None when the data do not measure the hemisphere or the scene is at the equator."""
    if hemisphere not in ("north", "south") or not basis.startswith("measured") or scene_latitude_deg == 0.0:
        return None
    scene_side = "north" if scene_latitude_deg > 0 else "south"
    if hemisphere == scene_side:
        return check_entry("combined", "hemisphere", "passed", f"measured {hemisphere}, as the scene's latitude "
                                                          f"{scene_latitude_deg:g} deg", hemisphere, scene_side)
    return check_entry("combined", "hemisphere", "flagged",
                  f"the data measure the {hemisphere}ern hemisphere but the scene's latitude is {scene_latitude_deg:g} "
                  "deg: east and north swapped, an axis mirrored (a pendulum's sense of turning reversed), or the "
                  "wrong scene", hemisphere, scene_side)


def halves_entry(name, line) -> dict:
    """The pendulum's ``halves`` check: the swing plane's rate over the first and the second half of
    the record (estimators/scatter.py); ``flagged`` beyond :data:`~.scatter.HALVES_Z` σ (σ then from
    the record's scatter), ``not_applicable`` with fewer than 6 swings."""
    from gyro_instrument.estimators.scatter import HALVES_Z
    if line is None or line.halves is None:
        return check_entry(name, "halves", "not_applicable", "fewer than 6 swings: the halves are not compared")
    b1, s1, b2, s2, z = line.halves
    ok = abs(z) <= HALVES_Z
    return check_entry(name, "halves", "passed" if ok else "flagged",
                       f"plane rate over the first half {_deg_h(b1)} +/- {_deg_h(s1, '.2g')}, over the second "
                       f"{_deg_h(b2)} +/- {_deg_h(s2, '.2g')} deg/h: {abs(z):.3g} sigma apart (at most {HALVES_Z:g})"
                       + ("" if ok else ": the rate changes within the record; sigma from its scatter"), z, 0.0)


def _deg_h(rate_rad_s, spec="+.4g") -> str:
    return format(math.degrees(rate_rad_s) * 3600.0, spec)


#: An estimate further than this many σ from what the scene's site predicts fails the ``site`` check.
SITE_Z = 4.0

SITE_CAUSES = ("a driven or damped pendulum (a drive, a Charron ring or the air moves the plane), an anisotropic "
               "support, a wrong length or pixel scale (the ellipse correction scales with the swing in radians), "
               "or the wrong scene (set site.latitude_deg, or site.latitude_known=false for an unknown place)")


def site_check(result, site) -> tuple:
    """The ``site`` checks: each pendulum's Foucault rate against n sin γ at the scene's site, and a
    combination with a gyroscope's latitude (and an estimated Earth rate) against the site's; beyond
    :data:`SITE_Z` σ ``failed`` (the estimate stands: the measurement is the answer). ``result``: the
    estimate's JSON so far (its ``instruments`` and the combined keys). Returns (the ``site`` block, a
    :class:`.estimate_types.Site`, and the checks' entries); nothing is compared when
    ``site.latitude_known`` is false."""
    from gyro_instrument.estimators.estimate_types import Disagreement, Site
    lat = site.latitude_deg
    block = {"latitude_known": site.latitude_known, "latitude_deg": lat, "earth_rate_rad_s": site.earth_rate_rad_s}
    if not site.latitude_known:
        block["detail"] = "site.latitude_known is false: the estimate is not compared with the site"
        return Site(**block), []
    where = f"{abs(lat):.2f}° {'N' if lat >= 0 else 'S'}"
    k0 = site.k_vertical_rad_s
    block["expected_foucault_rate_rad_s"] = k0
    entries, disagree = [], []
    gyro = False
    for name, e in result.get("instruments", {}).items():
        gyro = gyro or e.get("swing_duration_s") is not None
        k, sk = e.get("foucault_rate_rad_s"), e.get("foucault_rate_sigma_rad_s")
        if k is None:
            continue
        z = _z(k - k0, sk)
        ell = e.get("ellipse_correction_rad_s") or 0.0
        m, sm = e.get("measured_plane_rate_rad_s", k), e.get("measured_plane_rate_sigma_rad_s", sk)
        said = (f"the plane turns {_deg_h(m, '+.2f')} ± {_deg_h(sm, '.2g')} °/h"
                + (f" ({_deg_h(k, '+.2f')} ± {_deg_h(sk, '.2g')} °/h less the ellipse's {_deg_h(ell, '+.2f')})"
                   if ell else "")
                + f"; a free pendulum at {where} turns {_deg_h(k0, '+.2f')} °/h"
                + (f" ({_deg_h(k0 + ell, '+.2f')} with this swing's ellipse)" if ell else ""))
        entries.append(_site_entry(name, z, said, k, k0))
        if entries[-1]["status"] == "failed":
            disagree.append({"instrument": name, "what": "foucault_rate", "z": z, "measured_rad_s": m,
                             "measured_sigma_rad_s": sm, "foucault_rate_rad_s": k, "foucault_rate_sigma_rad_s": sk,
                             "expected_rad_s": k0 + ell, "free_rate_rad_s": k0, "headline": f"{name}: {said}"})
    glat = result.get("latitude_deg")
    if gyro and glat is not None:
        sig = result.get("latitude_sigma_deg")
        if sig is None and result.get("latitude_interval_3sigma_deg"):
            lo3, hi3 = result["latitude_interval_3sigma_deg"]
            sig = (glat - lo3 if lat < glat else hi3 - glat) / 3.0
        z = _z(glat - lat, sig)
        said = f"latitude {glat:.4f} ± {_fmt_sig(sig)}° against the site's {lat:.4f}°"
        if result.get("earth_rate_known") is False and result.get("earth_rate_rad_s") is not None:
            zn = _z(result["earth_rate_rad_s"] - site.earth_rate_rad_s, result.get("earth_rate_sigma_rad_s"))
            said += f", Earth rate {zn:+.3g} sigma from the site's"
            z = max(z, zn, key=abs)
        entries.append(_site_entry("combined", z, said, glat, lat))
        if entries[-1]["status"] == "failed":
            disagree.append({"instrument": "combined", "what": "latitude", "z": z, "headline": said})
    block["agrees"] = not disagree
    block["disagreements"] = [Disagreement(**d) for d in disagree]
    return Site(**block), entries


def _z(diff, sigma) -> float:
    if sigma is not None and sigma > 0:
        return diff / sigma
    return 0.0 if abs(diff) <= 1e-12 else math.copysign(math.inf, diff)


def _fmt_sig(sig) -> str:
    return "null" if sig is None else f"{sig:.2g}"


def _site_entry(name, z, said, value, expected) -> dict:
    ok = abs(z) <= SITE_Z
    return check_entry(name, "site", "passed" if ok else "failed",
                       f"{said}: {abs(z):.3g} sigma apart (at most {SITE_Z:g})"
                       + ("" if ok else f"; likely causes: {SITE_CAUSES}"), value, expected)
