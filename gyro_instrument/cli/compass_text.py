"""The text of a ship's gyrocompass's ``compass`` block in ``estimate`` (issue 39 item 6; the block:
:mod:`gyro_instrument.estimators.compass_entries`)."""


def _pm(v, s, fmt) -> str:
    return "null" if v is None else f"{v:{fmt}}" + ("" if s is None else f" +/- {s:.2g}")


def compass_lines(name, c) -> list:
    """Lines (no newlines) of one compass's block ``c`` (its JSON)."""
    if c.get("settled_at_s") is None and "settling_curve" not in c:
        return [f"  {name}: compass null: {c.get('reason')}"]
    if c.get("settled_at_s") is None:
        head = f"  {name}: not settled ({c.get('reason')})"
    else:
        head = (f"  {name}: settled at {c['settled_at_s']:.0f} s, settle-point error "
                f"{_pm(c['settle_point_error_deg'], c['settle_point_error_sigma_deg'], '.4f')} deg "
                f"(mean of {c['settle_point_samples']} readings; reading noise {c['reading_noise_deg']:.2g} deg)")
    lines = [head]
    k = c["settling_curve"]
    if k.get("period_s") is None:
        lines.append(f"    settling curve: period and damping null: {k['reason']}")
    else:
        th = k.get("theory_undamped_period_s")
        lines.append(f"    settling curve ({k['model']}): period {_pm(k['period_s'], k['period_sigma_s'], '.1f')} s, "
                     f"damping ratio {_pm(k['damping_ratio'], k['damping_ratio_sigma'], '.4f')}, swing ratio "
                     f"{_pm(k['swing_ratio'], k['swing_ratio_sigma'], '.3f')}, undamped period "
                     f"{k['undamped_period_s']:.1f} s (theory {'null' if th is None else f'{th:.1f}'} s"
                     + ("" if k.get("theory_damping_ratio") is None else f", damping {k['theory_damping_ratio']:.4f}")
                     + "), settles to " + _pm(k['settle_point_error_deg'], k['settle_point_error_sigma_deg'], '.4f')
                     + " deg")
    tr = c.get("track")
    if tr:
        lines.append(f"    along the track after settling: rms {tr['rms_deg']:.3g} deg, "
                     f"max {tr['max_abs_deg']:.3g} deg; "
                     f"the closed forms predict {tr['predicted_mean_deg']:.4f} deg, measured - predicted "
                     + _pm(tr['measured_minus_predicted_deg'], tr['measured_minus_predicted_sigma_deg'], '.4f')
                     + " deg")
    return lines
