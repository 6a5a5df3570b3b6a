"""What the commands print: a scene's description, an estimate, a plan (text wrapped at
:data:`TEXT_WIDTH`, periods labelled with their convention)."""

import math
import sys

from gyro_instrument.recording.replay import damage_line

def print_scene_notes(scene, stream=None) -> None:
    """The scene's notes (:func:`gyro_instrument.scenes.scene_notes`) on stderr, one line each."""
    from gyro_instrument.scenes import scene_notes
    for note in scene_notes(scene):
        print(f"gyro-instrument: note: {note}", file=stream or sys.stderr)


SWING = "(one swing = half period)"
FULL_PERIOD = "(full period)"
QUARTER_PERIOD = "(quarter period, sec. 2 eq. 42)"


def deg_h(rate_rad_s) -> str:
    """A rate in rad/s as ``x deg/h`` (for printing beside the rad/s value)."""
    return "null deg/h" if rate_rad_s is None else f"{math.degrees(rate_rad_s) * 3600.0:.6g} deg/h"


def labelled(key, value) -> str:
    """``key = value`` for a prediction, with the period convention beside a period or duration and
    deg/h beside a rad/s rate."""
    text = f"{key} = {value:.10g}" if isinstance(value, float) else f"{key} = {_fmt(value, '')}"
    numbers = isinstance(value, (list, tuple)) and value and all(isinstance(v, (int, float)) for v in value)
    if (not isinstance(value, (int, float)) or isinstance(value, bool)) and not numbers:
        return text
    if "quarter_period" in key:
        return f"{text} {QUARTER_PERIOD}"
    if "half_period" in key:
        return f"{text} (half period)"
    if "swing_duration" in key or key.startswith("T_"):
        return f"{text} {SWING}"
    if "period" in key and key.endswith("_s"):
        return f"{text} {FULL_PERIOD}"
    if key.endswith("_rad_s") and not numbers:
        if "spin" in key:     # a rotor's spin: turn/s is how people think of it
            return f"{text} ({value / (2 * math.pi):.6g} turn/s)"
        return f"{text} ({deg_h(value)})"
    return text


#: Printed text is wrapped at this width (continuation lines indented under their first).
TEXT_WIDTH = 100


def wrapped_writer(stream) -> tuple:
    """(write, flush): ``write`` gathers text; ``flush`` writes it to ``stream`` with every line
    longer than :data:`TEXT_WIDTH` wrapped at spaces, continuations indented 4 more than the line."""
    import textwrap
    parts = []

    def flush():
        for line in "".join(parts).splitlines():
            lead = line[:len(line) - len(line.lstrip())]
            stream.write(textwrap.fill(line, TEXT_WIDTH, subsequent_indent=lead + "    ", break_long_words=False,
                                       break_on_hyphens=False) + "\n" if len(line) > TEXT_WIDTH else line + "\n")
    return parts.append, flush


def _hemisphere(lat) -> str:
    return f"{abs(lat):.4f}° {'N' if lat > 0 else 'S'}" if lat else "0° (equator)"


def description_headline(d) -> list:
    """What a person asks first, as lines: per horizontal gyroscope asked for north, the predicted
    swing centre on the scale and true north's reading (:func:`north_prediction_lines`); then the
    latitude and, per pendulum, the swing plane's turn in °/h (the exact finite-amplitude rate when it
    has one) and a full turn in hours."""
    lines = []
    for name, inst in d["instruments"].items():
        lines += north_prediction_lines(name, inst["predictions"])
    lines.append(f"latitude {_hemisphere(d['site']['latitude_deg'])}")
    for name, inst in d["instruments"].items():
        p = inst["predictions"]
        rate = p.get("apsidal_rate_from_rest_rad_s", p.get("foucault_rate_rad_s"))
        if rate is None or "foucault_rate_rad_s" not in p:
            continue
        lines.append(turn_line(name, rate) + (" (exact rate at this amplitude)" if "apsidal_rate_from_rest_rad_s" in p
                                              else ""))
    return lines


def north_prediction_lines(name, p) -> list:
    """A horizontal gyroscope's north as ``describe`` predicts it (scale readings counter-clockwise,
    as the measured ``angle``): the swing centre and true north's reading, the centre's offset (the
    tape's pull, the exact equilibrium); a rotor-off swing as the torsion pendulum it is."""
    if "torsion_period_s" in p:
        return [f"{name}: a torsion pendulum on its tape (rotor off): period {p['torsion_period_s']:.6g} s "
                f"(2 pi sqrt(A/D_B), {p['torsion_period_damped_s']:.6g} s damped), swinging about the tape zero at "
                f"{p['tape_zero_reading_deg']:.6f}° on the scale, drifting {p['tape_zero_rate_arcsec_h']:.4g}\"/h"]
    if "north_reading_deg" not in p:
        return []
    north = f"true north reads {p['north_reading_deg']:.6f}° on the scale (mount azimuth {p['mount_azimuth_deg']:.6f}°)"
    if p.get("centre_reading_deg") is None:
        return [f"{name}: {north}; no directing torque, no swing centre"]
    pull = (f"; the tape pulls it toward its zero at {p['tape_zero_reading_deg']:.6f}° (exact equilibrium "
            f"K sin(c - N) = k_B (Z - c))" if "tape_zero_reading_deg" in p else "")
    off = -p["centre_from_north_arcsec"]           # the scale reads counter-clockwise: east of north is −
    side = "east" if off > 0 else "west"
    off = f"{abs(off):.4g}\"" if abs(off) < 3600.0 else f"{abs(off) / 3600.0:.6f}°"
    return [f"{name}: swing centre predicted at {p['centre_reading_deg']:.6f}° on the scale, {off} {side} of north "
            f"(the estimate's pre_orientation, clockwise){pull}", f"{name}: {north}"]


def turn_line(name, rate_rad_s) -> str:
    """``<name>: the swing plane turns R °/h <sense> seen from above, a full turn in H h`` (rate about
    the upward vertical, positive clockwise seen from above)."""
    turn = f"a full turn in {2 * math.pi / abs(rate_rad_s) / 3600.0:.1f} h" if rate_rad_s else "it does not turn"
    sense = "clockwise" if rate_rad_s > 0 else "counter-clockwise"
    return f"{name}: the swing plane turns {math.degrees(rate_rad_s) * 3600.0:.3f} °/h {sense} seen from above, {turn}"


def print_description(d, stream=None) -> None:
    """``describe``'s text: the answer first (:func:`description_headline`), then the site, each
    instrument's effects, predictions (one a line) and columns; lines wrapped at :data:`TEXT_WIDTH`."""
    w, flush = wrapped_writer(stream or sys.stdout)
    s = d["site"]
    w(f"scene {d['scene']}: {d['description']}\n")
    for line in description_headline(d):
        w(f"  {line}\n")
    w(f"  site: latitude {s['latitude_deg']:.6f} deg, n = {s['earth_rate_rad_s']:.8g} rad/s "
      f"({deg_h(s['earth_rate_rad_s'])}), "
      f"g = {s['gravity_m_s2']:.6f} m/s^2; {d['duration_s']:g} s at {d['sample_rate_hz']:g} Hz, seed {d['seed']}\n")
    w(f"  effects listed: {', '.join(d['scene_effects']) or 'none'}\n")
    if "kernels" in d:
        w(f"  kernels: {d['kernels']}\n")
    for note in d.get("scene_notes", []):
        w(f"  note: {note}\n")
    for name, inst in d["instruments"].items():
        w(f"\n  {name} ({inst['type']}): {inst['summary']}\n")
        if "integrator" in inst:
            w(f"    integrator: {inst['integrator']['chosen']} ({inst['integrator']['reason']})\n")
        w(f"    {'effect':<18}{'active':<8}{'relative size':>14}  estimate\n")
        for ename, e in inst["effects"].items():
            size = e["relative_size"]
            size_txt = f"{size:.3g}" if size is not None else "n/a"
            w(f"    {ename:<18}{'yes' if e['active'] else 'no':<8}{size_txt:>14}  {e['formula']}\n")
        w("    predictions:\n")
        for k, v in inst["predictions"].items():
            if k != "notes":
                w(f"      {labelled(k, v)}\n")
        for note in inst["predictions"].get("notes", []):
            w(f"    prediction note: {note}\n")
        w(f"    columns: {', '.join(inst['columns'])}\n")
    flush()


def _fmt(v, spec):
    return "null" if v is None else format(v, spec)


def print_estimate(r, stream=None, angle_format="deg") -> None:
    """Human-readable estimate: the answer first (:func:`estimate_headline`, north's angles in
    ``angle_format``), then the recovered latitude and Earth rate next to the truth, the checks, each
    instrument and method; lines wrapped at :data:`TEXT_WIDTH`."""
    w, flush = wrapped_writer(stream or sys.stdout)
    for line in estimate_headline(r, angle_format):
        w(f"{line}\n")
    _print_estimate_body(r, w)
    flush()


def _angle(deg, fmt) -> str:
    from gyro_instrument.core.angle_formats import format_angle
    return format_angle(deg, fmt)


def _sigma(arcsec, fmt) -> str:
    from gyro_instrument.core.angle_formats import format_arcsec
    return format_arcsec(arcsec, fmt)


def _flat(d) -> str:
    """``key value; ...`` of a dict, nested dicts one level down, numbers to 4 significant digits."""
    def v(x):
        return f"{x:.4g}" if isinstance(x, float) else str(x)
    return "; ".join(f"{k} {'(' + _flat(x) + ')' if isinstance(x, dict) else v(x)}" for k, x in d.items())


def _method_line(name, m, fmt) -> str:
    bias = ""
    if m.get("bias_arcsec") is not None:
        bias = f"  bias {_sigma(m['bias_arcsec'], fmt)}" + (" [FLAGGED: > sigma/4]" if m.get("bias_flagged") else "")
    return (f"  {name:<13} {_angle(m['mount_azimuth_deg'], fmt)} +/- {_sigma(m['sigma_arcsec'], fmt)}{bias}  "
            f"({m['n_used']} used; needs {m['needs']})")


def _book_lines(n, fmt) -> list:
    """A field book's extra lines: the circle reading of north, the reduction, missed points, outliers."""
    lines = [f"  north reads {_angle(n['north_reading_deg'], fmt)} on the circle; {n['reduction']}"]
    if n.get("missed"):
        lines.append("  missed: " + ", ".join(f"turning point {m['turning_point']}" + (f" (line {m['line']})" if m["line"]
                                                                                      else "") for m in n["missed"]))
    lines += [f"  note: {note}" for note in n.get("notes", [])[:-1]]      # the last: the clockwise convention
    for o in n.get("outliers", []):
        lines.append(f"  outlier: turning point {o['turning_point']}, line {o['line']}, {o['column']} = {o['reading']}: "
                     f"{o['sigmas']:+.1f} sigma from its neighbours' mean (threshold {o['threshold_sigmas']:.2g}; kept)")
    return lines


def north_lines(n, angle_format="deg") -> list:
    """The ``north`` block as lines: the mount azimuth with its σ and bound, then each method (with its
    ``bias_arcsec``, flagged, when the block has one), the pre-orientation check and the tape; a field
    book's also the circle reading of north, the reduction, missed and outlying turning points. Angles
    in ``angle_format`` (``--angle-format``: deg, dms, gon)."""
    if n.get("mount_azimuth_deg") is None:
        return [f"north: not determined ({n.get('reason') or 'see the methods'}); azimuth in "
                f"[{n['interval_deg'][0]:g}, {n['interval_deg'][1]:g}]°"]
    fmt = angle_format
    what = n["instrument"] or f"the field book {n.get('field_book')}"
    how = (f"{n.get('method') or 'fit'}; Cramer-Rao" if n.get("crlb_arcsec") is not None
           else f"{n.get('method')}; no record, no bound")
    lines = [f"north: scale zero of {what} at azimuth {_angle(n['mount_azimuth_deg'], fmt)} +/- "
             f"{_sigma(n['sigma_arcsec'], fmt)} ({how}" + (f" {_sigma(n['crlb_arcsec'], fmt)})"
                                                            if n.get("crlb_arcsec") is not None else ")")]
    if "north_reading_deg" in n:
        lines += _book_lines(n, fmt)
    lines += [_method_line(name, m, fmt) for name, m in n.get("methods", {}).items()]
    for name, why in n.get("refused", {}).items():
        lines.append(f"  {name:<13} refused: {why}")
    if isinstance(n.get("pre_orientation"), dict):
        lines.append(f"  pre-orientation: {_flat(n['pre_orientation'])}")
    if n.get("tape"):
        t = n["tape"]
        src = t.get("source") or f"rotor-off swing {t['instrument']}"
        lines.append(f"  tape: D_B/D_K = {t['ratio_db_dk']:.4g} +/- {t['ratio_sigma']:.2g}, zero reads "
                     f"{_angle(t['zero_reading_deg'], fmt)} ({src}); every centre corrected")
    return lines


def estimate_headline(r, angle_format="deg") -> list:
    """The estimate's answer as lines: north first when a horizontal gyroscope gives it
    (:func:`north_lines`), the latitude (or why there is none) and each pendulum's measured
    swing-plane rate in °/h with its full turn in hours."""
    lat = r.get("latitude_deg")
    lines = north_lines(r["north"], angle_format) if r.get("north") else []
    site = r.get("site") or {}
    off = {d["instrument"]: d for d in site.get("disagreements") or ()}
    lines += [f"{d['headline']} (site check failed: {abs(d['z']):.3g} sigma)" for d in off.values()]
    if lat is None:
        lines += [f"latitude: not determined ({r.get('reason') or 'see the methods below'})"]
    else:
        sig = r.get("latitude_sigma_deg")
        lines += [f"latitude {'|' if r.get('latitude_is_absolute') else ''}{_hemisphere(lat)}"
                 f"{'|' if r.get('latitude_is_absolute') else ''}" + (f" +/- {sig:.2g}°" if sig is not None else "")
                 + (" if the pendulum were free" if set(off) - {"combined"} else "")
                 + (" (not the site's)" if "combined" in off else "")]
    for name, e in r.get("instruments", {}).items():
        k = e.get("foucault_rate_rad_s") if isinstance(e, dict) else None
        if k and name not in off:
            lines.append(turn_line(name, k))
    return lines


def _print_estimate_body(r, w):
    tr = r["truth"]
    truth = "scene's" if r.get("data") else "truth"    # measured data: the scene's values are nominal, not a truth
    if r.get("data"):
        w(f"data {r['data']} read with scene {r['scene']}, {_fmt(r.get('observation_s'), 'g')} s of samples\n")
    elif r.get("recording_cut"):     # replay of a cut bag: what was read, and why it stopped
        w(f"scene {r['scene']} (seed {r.get('seed')}), {r['observation_read_s']:g} s of {r['observation_s']:g} s "
          f"read per instrument (recording cut: {r['recording_cut']})\n")
    else:
        w(f"scene {r['scene']} (seed {r.get('seed')}), {r['observation_s']:g} s per instrument\n")
    for note in r.get("scene_notes", []):
        w(f"  note: {note}\n")
    label = "|latitude|" if r.get("latitude_is_absolute") else "latitude  "
    w(f"  {label} {_fmt(r['latitude_deg'], '.7f')} +/- {_fmt(r['latitude_sigma_deg'], '.2g')} deg"
      f"   {truth} {tr['latitude_deg']:.7f}   (Cramer-Rao {_fmt(r['crlb']['latitude_deg'], '.2g')})\n")
    if r.get("latitude_sigma_reason"):
        lo, hi = r["latitude_interval_deg"]
        lo3, hi3 = r["latitude_interval_3sigma_deg"]
        w(f"             1-sigma interval [{lo:.7f}, {hi:.7f}], 3-sigma [{lo3:.7f}, {hi3:.7f}] deg: "
          f"{r['latitude_sigma_reason']}\n")
    if r.get("hemisphere") and r.get("latitude_deg") is not None:
        w(f"  hemisphere {r['hemisphere']} ({r.get('hemisphere_basis')})\n")
    for o in r.get("other_latitudes_deg") or ():
        w(f"  also consistent: latitude {o['latitude_deg']:.7f} deg (delta chi2 = {o['delta_chi2']:.3g})\n")
    if r.get("earth_rate_known"):
        w(f"  Earth rate {r['earth_rate_rad_s']:.9e} rad/s ({deg_h(r['earth_rate_rad_s'])}) {r['earth_rate_basis']}\n")
    else:
        w(f"  Earth rate {_fmt(r['earth_rate_rad_s'], '.9e')} +/- {_fmt(r['earth_rate_sigma_rad_s'], '.2g')} rad/s"
          f" ({deg_h(r['earth_rate_rad_s'])})"
          f"   {truth} {tr['earth_rate_rad_s']:.9e}   (Cramer-Rao {_fmt(r['crlb']['earth_rate_rad_s'], '.2g')})\n")
    if r.get("method"):
        w(f"  method: {r['method']}\n")
    print_checks(r.get("checks"), w)
    if r.get("reason"):
        w(f"  reason: {r['reason']}\n")
    print_damage(r, w)
    for name, e in r["instruments"].items():
        if e.get("swing_duration_s") is not None:
            c = e.get("counting", {})
            w(f"  {name}: T = {e['swing_duration_s']:.9f} +/- {e['swing_duration_sigma_s']:.2g} s (fit; one swing = "
              f"half period), T0 = {e['small_amplitude_swing_duration_s']:.9f} s (small amplitude, one swing); "
              f"counting: {_fmt(c.get('swing_duration_s'), '.6f')} s (one swing; {c.get('swings')} swings)\n")
        elif e.get("foucault_rate_rad_s") is not None:
            w(f"  {name}: k = {e['foucault_rate_rad_s']:.6e} +/- {e['foucault_rate_sigma_rad_s']:.2g} rad/s "
              f"({deg_h(e['foucault_rate_rad_s'])}; ellipse correction {e['ellipse_correction_rad_s']:.2g} rad/s), "
              f"swing period {e['period_s']:.6g} s {FULL_PERIOD}\n")
            sc = e.get("ellipse_scale") or {}
            if sc.get("matters"):
                w(f"    the ellipse (Airy) correction, {deg_h(e['ellipse_correction_rad_s'])}, is "
                  f"{100 * abs(sc['share_of_measured_rate'] or 0):.0f} % of the measured turn and grows as the square "
                  f"of the position scale: k = {deg_h(sc['k_at_half_scale_rad_s'])} at half the scale, "
                  f"{deg_h(sc['k_at_double_scale_rad_s'])} at twice it, {deg_h(sc['k_without_correction_rad_s'])} "
                  f"without it (positions in pixels need --metres-per-pixel; check the length)\n")
        elif isinstance(e.get("compass"), dict):
            from gyro_instrument.cli.compass_text import compass_lines
            w("".join(line + "\n" for line in compass_lines(name, e["compass"])))
        elif e.get("reason") is not None or len(e) <= 1:
            w(f"  {name}: null: {e.get('reason')}\n")
        else:                       # another kind's entry (a plug-in's): its numbers as they are, its blocks
            nums = [f"{k} = {_fmt(v, '.6g')}" for k, v in e.items() if isinstance(v, (int, float))
                    and not isinstance(v, bool)]
            blocks = [f"its {k} block (above)" for k, v in e.items() if isinstance(v, dict)]
            w(f"  {name}: " + ", ".join(nums + blocks) + "\n")
    for mname, m in r["methods"].items():
        lat = m.get("latitude_deg")
        w(f"  method {mname}:" + (f" latitude {_fmt(lat, '.7f')}" if "latitude_deg" in m else "")
          + (" (|latitude|: hemisphere not determined)" if m.get("latitude_is_absolute") else "")
          + (f" +/- {m['latitude_sigma_deg']:.2g}" if lat is not None and m.get("latitude_sigma_deg") is not None else "")
          + (("," if "latitude_deg" in m else "") + f" n = {m['earth_rate_rad_s']:.9e} rad/s "
             f"({deg_h(m['earth_rate_rad_s'])})"
             if m.get("earth_rate_rad_s") is not None else "")
          + (f"  [{m.get('reason') or m.get('reason_earth_rate')}]" if (m.get('reason') or m.get('reason_earth_rate')) else "")
          + "\n")


def print_checks(checks, w) -> None:
    """One line for the adequacy checks that passed, one per check that did not (estimators/adequacy.py)."""
    if not checks:
        return
    passed = [c for c in checks if c["status"] == "passed"]
    w(f"  checks: {len(passed)} of {len(checks)} passed"
      f" ({', '.join(sorted({c['check'] for c in passed}))})\n" if passed else "  checks: none passed\n")
    for c in checks:
        if c["status"] != "passed":
            w(f"  check {c['check']} of {c['instrument']}: {c['status']}: {c['detail']}\n")


def print_damage(r, w) -> None:
    """The bag's lost stretches and the reader's notes (replay, estimate --data); nothing for a
    live estimate."""
    for d in r.get("damaged") or ():
        w(f"  damaged: {damage_line(d)}\n")
    for n in (r.get("replay_notes") or []) + (r.get("data_notes") or []):
        w(f"  note: {n}\n")


# ----------------------------------------------------------------------------- plan
def human_duration(s) -> str:
    """``161.6 s (2.69 min)``: seconds with the largest sensible unit beside them."""
    if s is None:
        return "null"
    for unit, size in (("years", 365.25 * 86400), ("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if s >= 2 * size:
            return f"{s:.4g} s ({s / size:.3g} {unit})"
    return f"{s:.4g} s"


def print_plan(d, stream=None) -> None:
    """Human-readable plan (:func:`gyro_instrument.estimators.planner.plan`)."""
    w = (stream or sys.stdout).write
    sen = d["sensor"]
    n = d["earth_rate_rad_s"]
    w(f"plan for {d['scene']}: latitude {d['latitude_deg']:.6f} deg, n = {n:.8g} rad/s ({deg_h(n)}); sensor "
      f"{sen['effective_noise_rad']:.3g} rad rms" + (f" (incl. quantization {sen['quantization_rad']:.3g} rad)"
                                                    if sen["quantization_rad"] else "")
      + (f", {100 * sen['dropout_fraction']:.3g} % dropouts" if sen["dropout_fraction"] else "")
      + f" at {sen['sample_rate_hz']:g} Hz\n")
    for name, m in d["instruments"].items():
        # a swing's duration, a period, an amplitude: what the kind's plan entry gives (plan_entry)
        what = [f"swing {m['swing_duration_s']:.6g} s {SWING}" if "swing_duration_s" in m
                else f"period {m['period_s']:.6g} s {FULL_PERIOD}" if "period_s" in m else ""]
        what += [f"amplitude {m['amplitude_rad']:.3g} rad"] if "amplitude_rad" in m else []
        w(f"  {name} ({m.get('configuration') or m['kind']}): {', '.join(x for x in what if x)}"
          f"{', ' if any(what) else ''}measures {m['measures']}\n")
    for name, why in d.get("not_used", {}).items():
        w(f"  {name}: not used ({why})\n")
    for e in d["targets"]:
        lines = _kind_plan_lines(e)
        if lines is not None:                         # a kind that words its own plan (plan_lines)
            w("\n" + "\n".join(lines) + "\n")
            _print_verify(e, w)
            continue
        if e["quantity"] == "azimuth":
            _print_azimuth_target(e, w)
            continue
        unit = e["target"].split("_", 1)[1] if e["target"].startswith("latitude") else e["target"][len("earth_rate_"):]
        unit = unit.replace("_", "/")
        w(f"\ntarget {e['target']} = {e['value']:g} (1 sigma):\n")
        if e.get("observation_s") is None:
            w(f"  not reachable: {e.get('reason')}\n")
            continue
        w(f"  observe {human_duration(e['observation_s'])} per configuration ({e['samples_per_instrument']} samples "
          f"each): Cramer-Rao bound {e['planned_sigma']:.4g} {unit}; limited by {e['limited_by']}\n")
        if e.get("latitude_note"):
            w(f"  note: {e['latitude_note']}\n")
        dep = e["dependence"]
        sl, ss = dep["slope_at_plan"], dep["slope_short_record"]
        w(f"  dependence: bound ~ T^{_fmt(sl, '.2f')} around the plan (T^-1.5 law once two cycles are in the "
          f"record); below the estimator's shortest record ({d['min_record_s']:.4g} s) ~ T^{_fmt(ss, '.2f')}\n")
        w("      T (s)        bound\n")
        for row in dep["curve"]:
            mark = "  <- plan" if row["observation_s"] == e["observation_s"] else (
                "  (short record)" if row["regime"].startswith("short") else "")
            w(f"    {row['observation_s']:10.4g}  {_fmt(row['sigma'], '11.4g')} {unit}{mark}\n")
        fl = e.get("floor")
        if fl:
            if fl.get("bias") is None:
                w(f"  floor: {fl.get('reason')}\n")
            elif fl["reachable"]:
                w(f"  floor: noise-free bias {fl['bias']:.2g} {unit} at the planned T: below the target\n")
            else:
                by = (f": set by {fl['set_by']}, a systematic effect the estimator does not correct" if fl.get("set_by")
                      else ": no single effect sets it (the estimator's own bias at this record length)")
                w(f"  floor: NOT REACHABLE: the noise-free estimate is off by {fl['bias']:.3g} {unit} at the planned T"
                  f"{by}\n")
                for c in fl.get("effects", []):
                    w(f"    without {c['effect']}: bias {_fmt(c['bias_without'], '.3g')} {unit}\n")
        rows = "; ".join(f"{r['change']} -> {human_duration(r['observation_s'])} (law {r['law_observation_s']:.4g} s)"
                         for r in e["sensitivity"]["rows"])
        w(f"  sensitivity: {rows}; law T ~ (sigma^2/f)^(1/3)\n")
        c = e["counting"]
        if c.get("observation_s") is None:
            w(f"  Quet's counting: {c.get('reason')}\n")
        else:
            yr = " -- more than a year" if c["exceeds_a_year"] else ""
            w(f"  Quet's counting of whole swings ({', '.join(c['instruments'])}): {human_duration(c['observation_s'])}"
              f" ({c['observation_s'] / e['observation_s']:.3g}x the fit's){yr}\n")
        v = e.get("verify")
        if v:
            w(f"  verify: {v['used']} seeds at the planned T: achieved rms {_fmt(v['achieved_rms'], '.4g')} {unit} "
              f"(target {v['target']:g}, achieved/target {_fmt(v['achieved_over_target'], '.3f')})"
              + (f"; {v['null']} null" if v["null"] else "") + "\n")


def _kind_plan_lines(e) -> list | None:
    """The plan text of a target entry made by a kind's own ``plan`` (its ``kind``): the kind's
    :meth:`~gyro_instrument.instruments.measurement.MeasurementKind.plan_lines`, or None (printed here)."""
    from gyro_instrument.instruments.measurement import kind
    found = kind(e["kind"]) if isinstance(e.get("kind"), str) else None
    return None if found is None else found.plan_lines(e)


def _print_verify(e, w) -> None:
    """The ``verify`` line of a target (``plan --verify``)."""
    v = e.get("verify")
    if v:
        unit = e["target"].split("_", 1)[1].replace("_", "/")
        w(f"  verify: {v['used']} seeds at the planned T: achieved rms {_fmt(v['achieved_rms'], '.4g')} {unit} "
          f"(target {v['target']:g}, achieved/planned {_fmt(v['achieved_over_planned'], '.3f')})\n")


def time_up(s) -> str:
    """A planned time in s, never printed shorter than it is: 6 significant digits rounded up, with
    the largest sensible unit beside it (:func:`human_duration`)."""
    if s is None or not math.isfinite(s) or s <= 0:
        return human_duration(s)
    places = max(0, 5 - math.floor(math.log10(s)))
    up = math.ceil(s * 10 ** places - 1e-6) / 10 ** places
    text = f"{up:.{places}f}".rstrip("0").rstrip(".") if places else f"{up:.0f}"
    return text + " s" + human_duration(s)[len(f"{s:.4g} s"):]


def _print_azimuth_target(e, w) -> None:
    """An azimuth target of the plan: the fit's time (its σ the whole joint problem's bound), each
    north method's, the rotor-off swing's part, the floor, the check."""
    unit = e["target"][len("azimuth_"):]
    w(f"\ntarget {e['target']} = {e['value']:g} (1 sigma):\n")
    if e.get("observation_s") is None:
        w(f"  not reachable: {e.get('reason')}\n")
        return
    w(f"  observe {time_up(e['observation_s'])} with {e['instrument']} ({e['samples_per_instrument']} samples): "
      f"the exact joint fit at the Cramer-Rao bound of the whole problem, {e['planned_sigma']:.4g} {unit}; limited by "
      f"{e['limited_by']}\n")
    w("      method          T for the target          sigma at the fit's T\n")
    for name, m in e["methods"].items():
        t = time_up(m["observation_s"]) if m["observation_s"] is not None else f"null ({m['note']})"
        ratio = f" ({m['over_fit']:.3g}x the fit's)" if m.get("over_fit") and name != "fit" else ""
        w(f"    {name:<14} {t + ratio:<28} {_fmt(m['sigma_at_plan'], '.4g')} {unit}\n")
    off = e.get("rotor_off")
    if off:
        sets = " -- it sets the planned time" if off["sets_the_time"] else ""
        w(f"  rotor-off swing {off['instrument']} (period {off['period_s']:.6g} s {FULL_PERIOD}): {off['assumed']}; "
          f"shortest record {time_up(off['min_record_s'])}{sets}\n")
        rows = "; ".join(f"{time_up(r['rotor_off_s'])} -> {_fmt(r['sigma'], '.4g')} {unit}" for r in off["curve"])
        w(f"    the fit's sigma at the planned T with a rotor-off record of: {rows}\n")
        ba = off["before_after"]
        w(f"    in the field, half before and half after the rotor-on swing ({time_up(ba['field_time_s'])} in all): "
          f"{_fmt(ba['sigma'], '.4g')} {unit}\n")
    fl = e.get("floor")
    if fl:
        if fl.get("bias") is None:
            w(f"  floor: {fl.get('reason')}\n")
        else:
            state = "below the target" if fl["reachable"] else "NOT REACHABLE" + (
                f": set by {fl['set_by']}" if fl.get("set_by") else "")
            w(f"  floor: the noise-free estimate's azimuth is off by {fl['bias']:.3g} {unit} at the planned T: {state}\n")
    v = e.get("verify")
    if v:
        w(f"  verify: {v['used']} seeds at the planned T: the fit's rms {_fmt(v['achieved_rms'], '.4g')} {unit} "
          f"(target {v['target']:g}, achieved/target {_fmt(v['achieved_over_target'], '.3f')}, achieved/planned "
          f"{_fmt(v['achieved_over_planned'], '.3f')})" + (f"; {v['null']} null" if v["null"] else "") + "\n")
        for name, m in v.get("methods", {}).items():
            w(f"    {name:<14} rms {_fmt(m['achieved_rms'], '.4g')} {unit}, planned {_fmt(m['planned_sigma'], '.4g')} "
              f"(achieved/planned {_fmt(m['achieved_over_planned'], '.3f')})\n")
