"""The instruments' measurements combined: latitude and Earth rate by profile likelihood, and Quet's
classic methods side by side (item 9, eq. (10), the Foucault pendulum alone).
"""

import math

from gyro_instrument.estimators.estimate_types import (ClassicMethods, Combined, Crlb, Foucault, Item8, Item9, Item9Counting,
                                                      Item9Null, NoRateMeasurement, OtherLatitude, Unresolved)
from gyro_instrument.estimators.latitude import HEMISPHERE_UNDETERMINED, item9_cos_latitude, solve_latitude
from gyro_instrument.estimators.record import ABSENT


def combined(meas, hemisphere=None, n_known=None, n_source="", earth_rate=None) -> "Combined | Unresolved":
    """The combined latitude and Earth rate (profile likelihood) with their Cramér–Rao bounds from
    the same mode, and what the instruments cannot determine (hemisphere, separability); Earth's
    rate held at ``n_known`` where they cannot separate it from the latitude (or where
    ``earth_rate`` = 'known'), said in ``earth_rate_basis``. A :class:`.estimate_types.Combined`, or
    :class:`.estimate_types.Unresolved` when the latitude is not determined."""
    how = {"earth_rate": earth_rate, "n_known": n_known, "n_source": n_source}
    sol = solve_latitude(meas, hemisphere=hemisphere, **how)
    deg = lambda x: None if x is None else math.degrees(x)  # noqa: E731
    rate = {"earth_rate_rad_s": sol.earth_rate_rad_s, "earth_rate_sigma_rad_s": sol.earth_rate_sigma_rad_s,
            "earth_rate_known": sol.earth_rate_known, "earth_rate_basis": sol.earth_rate_basis,
            "hemisphere": sol.hemisphere, "hemisphere_basis": sol.hemisphere_basis}
    if sol.latitude_rad is None:
        return Unresolved(**rate, latitude_deg=None, latitude_sigma_deg=None, reason=sol.reason,
                          crlb=Crlb(latitude_deg=None, earth_rate_rad_s=sol.earth_rate_sigma_rad_s),
                          method=(f"weighted mean over {len(meas)} measurement(s) independent of the latitude"
                                  if sol.earth_rate_rad_s is not None else None))
    crlb = solve_latitude(meas, use_crlb=True, domain=sol.domain, **how)
    lead = max(sol.carried_by, key=sol.carried_by.get)
    kinds = "+".join(sorted({("pendulum" if m.kind == "pendulum" else "gyroscope") for m in meas}))
    method = (f"{'least squares over the latitude with n known' if sol.earth_rate_known else 'profile least squares'}"
              f" over {kinds} ({len(meas)} measurement{'s' if len(meas) > 1 else ''}); "
              f"latitude carried by {lead} ({100 * sol.carried_by[lead]:.1f} % of the information)")
    others = [OtherLatitude(latitude_deg=math.degrees(g), delta_chi2=d) for g, d in sol.other_modes]
    return Combined(**rate, latitude_deg=math.degrees(sol.latitude_rad), latitude_sigma_deg=deg(sol.latitude_sigma_rad),
                    latitude_interval_deg=[math.degrees(sol.latitude_lo_rad), math.degrees(sol.latitude_hi_rad)],
                    latitude_interval_3sigma_deg=[math.degrees(v) for v in sol.interval_3sigma_rad],
                    latitude_is_absolute=sol.latitude_is_absolute,
                    crlb=Crlb(latitude_deg=deg(crlb.latitude_sigma_rad), earth_rate_rad_s=crlb.earth_rate_sigma_rad_s),
                    carried_by=sol.carried_by, chi2=sol.chi2, dof=sol.dof,
                    latitude_sigma_reason=sol.sigma_reason or ABSENT, other_latitudes_deg=others or ABSENT,
                    left_out_of_latitude=sol.dropped or ABSENT, method=method)


def null_combined(reason) -> NoRateMeasurement:
    """No Earth-rate measurement: every combined value ``null`` with ``reason``."""
    return NoRateMeasurement(latitude_deg=None, latitude_sigma_deg=None, earth_rate_rad_s=None,
                             earth_rate_sigma_rad_s=None, crlb=Crlb(latitude_deg=None, earth_rate_rad_s=None),
                             hemisphere=HEMISPHERE_UNDETERMINED, method=None, reason=reason)


def classic_methods(hemisphere, nominal_n, gyros, pend, earth_rate=None) -> ClassicMethods:
    """Quet's item 9 and eq. (10), and the pendulum-only results, side by side (the pendulum's
    asin(k/n) with the nominal n (``nominal_n``, rad/s) only where ``earth_rate`` (``estimator.earth_rate``)
    allows a known n); ``hemisphere`` the combination's, which signs item 9's latitude.

    ``gyros``: name -> (observation, :class:`.entries.SwingEntry`, RateMeasurement) of the swings (their
    ``label`` and ``gain``); ``pend``: the same of the first pendulum (its :class:`.entries.PlaneEntry`), or
    None."""
    methods = {}
    hor = [g for g in gyros.values() if g[0].label == "horizontal"]
    mer = [g for g in gyros.values() if g[0].label == "meridian"]
    if hor and mer:
        methods.update(_item9(hemisphere, hor[0], mer[0], pend))
    elif hor or mer:
        methods["item9"] = Item9Null(latitude_deg=None, reason="item 9 needs both a horizontal and a meridian "
                                     "configuration with a measured oscillation")
    if mer:
        om, em, mm = mer[0]
        methods["item8_eq10"] = Item8(earth_rate_rad_s=mm.value, earth_rate_sigma_rad_s=mm.sigma,
                                      formula="n = pi^2 / (mu rho0 T_m^2) (eq. 10; item 8's printed pi/(mu rho0 T^2) "
                                              "is a misprint)", gain=om.gain)
    if pend is not None and getattr(pend[1], "foucault_rate_rad_s", None) is not None:
        methods["foucault"] = _foucault_method(methods, nominal_n, pend, earth_rate)
    return ClassicMethods(**methods)


def _item9(hemisphere, hor, mer, pend) -> dict:
    """Quet's item 9, cos γ = (T_m/T_h)² ρ_m/ρ_h, from the first horizontal and meridian gyroscopes:
    ``{"item9_counting": (from the counted swings, when both were counted), "item9": ...}``."""
    (ih, eh, mh), (im, em, mm) = hor, mer
    # cos γ = y_h / y_m with y = K/(gain ρ): Quet's (T_m/T_h)² ρ_m/ρ_h, with the finite-amplitude
    # and (gimbal) ring-inertia corrections carried by T0 and the gains.
    c = mh.value / mm.value
    rel = math.hypot(mh.sigma / mh.value, mm.sigma / mm.value)
    entry = {"cos_latitude": c, "cos_latitude_sigma": c * rel}
    if c + c * rel >= 1.0 and c <= 1.0 + 3 * c * rel:
        entry.update({"latitude_deg": None,
                      "reason": f"cos(latitude) = {c:.9f} is within 1 sigma ({c * rel:.2g}) of 1: near the "
                                "equator item 9 cannot resolve the latitude (cos is flat, "
                                "d(latitude) = d(cos)/sin(latitude) diverges)"
                                + ("; the pendulum carries the latitude" if pend is not None else "")})
    elif 0.0 < c <= 1.0:
        lat = math.degrees(math.acos(c))
        # cos is even: the sign comes from the combination's hemisphere (measured by a pendulum, or
        # the user's estimator.hemisphere); otherwise item 9 reports |latitude|
        sign = {"north": 1.0, "south": -1.0}.get(hemisphere, 1.0)
        entry["hemisphere"] = hemisphere if hemisphere in ("north", "south") else HEMISPHERE_UNDETERMINED
        entry["latitude_is_absolute"] = hemisphere not in ("north", "south")
        s = math.sqrt(max(1 - c * c, 0.0))
        lo = math.degrees(math.acos(min(c + c * rel, 1.0)))
        hi = math.degrees(math.acos(max(c - c * rel, 0.0)))
        entry.update({"latitude_deg": sign * lat, "latitude_sigma_deg": 0.5 * (hi - lo),
                      "linear_sigma_deg": (math.degrees(c * rel / s) if s > 0 else None)})
    else:
        entry.update({"latitude_deg": None, "reason": f"(T_m/T_h)^2 rho_m/rho_h = {c:.9g} is outside (0, 1]"})
    # uncorrected (printed T at unequal amplitudes, no spin ratio) for comparison
    entry["uncorrected_cos_latitude"] = (em.swing_duration_s / eh.swing_duration_s) ** 2
    out = {}
    ch, cm = eh.counting, em.counting
    if getattr(ch, "swing_duration_s", None) and getattr(cm, "swing_duration_s", None):
        gain_ratio = im.gain / ih.gain
        cc = item9_cos_latitude(cm.small_amplitude_swing_duration_s, ch.small_amplitude_swing_duration_s,
                                em.mean_spin_rad_s, eh.mean_spin_rad_s) * gain_ratio
        out["item9_counting"] = Item9Counting(cos_latitude=cc, latitude_deg=math.degrees(math.acos(cc)) if 0 < cc <= 1
                                              else None, swings=[ch.swings, cm.swings])
    out["item9"] = Item9(**entry)
    return out


def _foucault_method(methods, nominal_n, pend, earth_rate=None) -> Foucault:
    """The pendulum alone: latitude from k / n (n from eq. (10) when a meridian gyroscope gave it
    (``methods["item8_eq10"]``), else the nominal sidereal rate ``nominal_n``) and n = k / sin(latitude
    from item 9)."""
    k, sk = pend[1].foucault_rate_rad_s, pend[1].foucault_rate_sigma_rad_s
    entry = {"foucault_rate_rad_s": k, "foucault_rate_sigma_rad_s": sk}
    n_ref = methods["item8_eq10"].earth_rate_rad_s if "item8_eq10" in methods else None
    if n_ref is None and earth_rate == "estimate":
        entry.update({"latitude_deg": None, "reason": "asin(k / n) needs n: no meridian gyroscope measures it, and "
                                                      "estimator.earth_rate: estimate forbids taking it as known"})
        n_ref = math.nan
    elif n_ref is None:
        n_ref = nominal_n
        entry["note"] = "latitude from k / n with the nominal sidereal n (no meridian gyroscope)"
    x = k / n_ref
    if not math.isfinite(x):
        pass
    elif abs(x) <= 1.0 + 3 * sk / n_ref:
        xc = max(min(x, 1.0), -1.0)
        lo = math.degrees(math.asin(max(xc - sk / n_ref, -1.0)))
        hi = math.degrees(math.asin(min(xc + sk / n_ref, 1.0)))
        entry.update({"latitude_deg": math.degrees(math.asin(xc)), "latitude_sigma_deg": 0.5 * (hi - lo)})
    else:
        entry.update({"latitude_deg": None, "reason": f"k/n = {x:.6g} exceeds 1 by more than 3 sigma"})
    lat9 = getattr(methods.get("item9"), "latitude_deg", None)
    if abs(k) < 3 * sk:
        entry["earth_rate_rad_s"] = None
        entry["reason_earth_rate"] = ("the pendulum does not precess measurably here (|k| < 3 sigma_k, as at "
                                      "the equator): n = k / sin(latitude) is undetermined")
    elif lat9 is None:
        entry["earth_rate_rad_s"] = None
        entry["reason_earth_rate"] = "n = k / sin(latitude) needs the latitude from item 9, which is null here"
    else:
        s = math.sin(math.radians(lat9))
        entry["earth_rate_rad_s"] = k / s
        entry["earth_rate_sigma_rad_s"] = sk / abs(s)
        entry["earth_rate_formula"] = "n = k / sin(latitude from item 9): needs no inertia ratio"
    return Foucault(**entry)
