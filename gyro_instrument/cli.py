"""``gyro-instrument``: command-line front end.

Subcommands: ``describe`` (instruments, active effects and every supported effect's
estimated size), ``simulate`` (CSV of every instrument channel), and the later stages.
Bad input exits with status 2 and one line naming the field, the value and the valid range.
"""

import argparse
import csv
import json
import math
import os
import sys
from contextlib import contextmanager

import numpy as np

from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.scene import sample_times
from gyro_instrument.effects import REGISTRY as EFFECTS

EXIT_BAD_INPUT = 2


def add_scene_arguments(parser):
    """The scene arguments shared by every subcommand (and mirrored by the ROS parameters)."""
    parser.add_argument("scene", help="shipped scene name (see 'gyro-instrument scenes') or a YAML path")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene value, e.g. --set site.latitude_deg=-33.87 "
                             "--set instruments.pendulum.length_m=20 (repeatable; values are YAML). "
                             "null removes: effects.NAME=null drops that effect (also from every "
                             "instrument's effects list), instruments.NAME=null drops that instrument "
                             "(not the last one); on any other key null restores its default (refused "
                             "if it has none). A new instrument needs its type: --set "
                             "instruments.p2.type=spherical_pendulum --set instruments.p2.length_m=10. "
                             "Unknown names get the closest match. Scene format: msg_docs/scene.md")
    parser.add_argument("--duration-s", type=float, default=None,
                        help="simulated time per instrument, s (default: the scene's duration_s)")


def scene_from_args(args):
    """Load the scene named on the command line with its overrides."""
    from gyro_instrument.scenes import load_scene
    overrides = list(args.overrides)
    if getattr(args, "duration_s", None) is not None:
        overrides.append(f"duration_s={args.duration_s!r}")
    return load_scene(args.scene, overrides)


def print_scene_notes(scene, stream=None):
    """The scene's notes (:func:`gyro_instrument.scenes.scene_notes`) on stderr, one line each."""
    from gyro_instrument.scenes import scene_notes
    for note in scene_notes(scene):
        print(f"gyro-instrument: note: {note}", file=stream or sys.stderr)


def check_writable(path, field="--out"):
    """Refuse an output path that cannot be written, before any simulation starts.

    Raises
    ------
    SceneError
        ``path`` is a directory, its directory is missing, or it is not writable.
    """
    directory = os.path.dirname(os.path.abspath(path)) or "."
    if os.path.isdir(path):
        raise SceneError(field, path, "is a directory; give a file path")
    if not os.path.isdir(directory):
        raise SceneError(field, path, f"directory {directory} does not exist")
    if not os.access(directory, os.W_OK) or (os.path.exists(path) and not os.access(path, os.W_OK)):
        raise SceneError(field, path, "is not writable")


def same_file(a, b):
    """True when paths ``a`` and ``b`` name the same file (inode when both exist, else realpath)."""
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


def check_output(path, field="--out", inputs=(), overwrite=False, also=()):
    """Refuse an output path before anything is simulated, read or written: it must be writable,
    never one of the command's ``inputs`` (compared by inode/realpath, whatever ``overwrite`` says),
    and not an existing file unless ``overwrite``. ``also``: other paths the command writes on the
    way (e.g. ``<out>.partial``), which must not be inputs either.

    Raises
    ------
    SceneError
        One line naming ``field``, the path and why.
    """
    check_writable(path, field)
    for inp in inputs:
        for p in (path, *also):
            if inp and same_file(p, inp):
                what = "is" if p == path else f"writes {p}, which is"
                raise SceneError(field, path, f"{what} the input {inp}; write elsewhere (--overwrite never "
                                              f"replaces an input)")
    if os.path.lexists(path) and not overwrite:
        raise SceneError(field, path, "exists; pass --overwrite to replace it, or give a new path")


def scene_inputs(scene_arg):
    """The files a scene argument reads (a YAML path; none for a shipped scene name)."""
    return (scene_arg,) if os.path.isfile(scene_arg) else ()


def to_jsonable(x):
    """Floats for JSON: non-finite values become None (never NaN or Infinity)."""
    if isinstance(x, dict):
        return {k: to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


# ----------------------------------------------------------------------------- describe
def describe(scene):
    """Dict describing a scene: site, instruments, active effects, effect sizes, predictions."""
    from gyro_instrument.scenes import build_instruments, scene_notes
    insts = build_instruments(scene)
    out = {"scene": scene.name, "description": scene.description, "source": scene.source,
           "scene_notes": scene_notes(scene),
           "site": {"latitude_deg": scene.site.latitude_deg, "earth_rate_rad_s": scene.site.earth_rate_rad_s,
                    "gravity_m_s2": scene.site.gravity_m_s2},
           "duration_s": scene.duration_s, "sample_rate_hz": scene.sample_rate_hz, "seed": scene.seed,
           "scene_effects": list(scene.effects), "instruments": {}}
    for name, inst in insts.items():
        scales = inst.scales(scene.duration_s)
        effects = {}
        for ename in sorted(inst.SUPPORTED_EFFECTS):
            eff = scene.effects.get(ename) or EFFECTS[ename]()
            size, formula = eff.relative_size(scales)
            effects[ename] = {"active": inst.has(ename), "relative_size": float(size), "formula": formula}
        out["instruments"][name] = {"type": inst.type_name, "summary": inst.summary,
                                    "parameters": dict(inst.params), "effects": effects,
                                    "predictions": inst.predictions(),
                                    "columns": [f"{name}.{c.name} [{c.unit}]" for c in inst.COLUMNS]}
    return to_jsonable(out)


def print_description(d, stream=None):
    w = (stream or sys.stdout).write
    s = d["site"]
    w(f"scene {d['scene']}: {d['description']}\n")
    w(f"  site: latitude {s['latitude_deg']:.6f} deg, n = {s['earth_rate_rad_s']:.8g} rad/s, "
      f"g = {s['gravity_m_s2']:.6f} m/s^2; {d['duration_s']:g} s at {d['sample_rate_hz']:g} Hz, seed {d['seed']}\n")
    w(f"  effects listed: {', '.join(d['scene_effects']) or 'none'}\n")
    for note in d.get("scene_notes", []):
        w(f"  note: {note}\n")
    for name, inst in d["instruments"].items():
        w(f"\n  {name} ({inst['type']}): {inst['summary']}\n")
        w(f"    {'effect':<18}{'active':<8}{'relative size':>14}  estimate\n")
        for ename, e in inst["effects"].items():
            size = e["relative_size"]
            size_txt = f"{size:.3g}" if size is not None else "n/a"
            w(f"    {ename:<18}{'yes' if e['active'] else 'no':<8}{size_txt:>14}  {e['formula']}\n")
        preds = ", ".join(f"{k} = {v:.10g}" if isinstance(v, float) else f"{k} = {_fmt(v, '')}"
                          for k, v in inst["predictions"].items() if k != "notes")
        w(f"    predictions: {preds}\n")
        for note in inst["predictions"].get("notes", []):
            w(f"    prediction note: {note}\n")
        w(f"    columns: {', '.join(inst['columns'])}\n")


# ----------------------------------------------------------------------------- simulate
def simulate_scene(scene, progress=None):
    """Simulate every instrument of a scene on the common sample grid.

    Returns
    -------
    t : ndarray
    columns : dict
        ``<instrument>.<column>`` -> array (radians, rad/s, metres).
    sims : dict
        instrument name -> Simulation (nfev, wall time).
    """
    from gyro_instrument.scenes import build_instruments
    t = sample_times(scene)
    columns, sims = {}, {}
    for name, inst in build_instruments(scene).items():
        if progress:
            progress(f"simulating {name} ({inst.type_name}) for {scene.duration_s:g} s")
        with terminal_progress(f"  {name}", enabled=progress is not None):
            sim = inst.simulate(t)
        sims[name] = sim
        for c in inst.COLUMNS:
            columns[f"{name}.{c.name}"] = sim.columns[c.name]
    return t, columns, sims


@contextmanager
def terminal_progress(label, enabled=True, stream=None, force=False):
    """Draw ``label: NN.N %`` on one terminal line while long integrations inside the block
    report (:func:`gyro_instrument.core.integrate.reporting`); only on a terminal (or
    ``force``), so logs and pipes stay clean."""
    from gyro_instrument.core.integrate import reporting
    stream = stream or sys.stderr
    if not enabled or not (force or stream.isatty()):
        yield
        return
    drawn = []

    def draw(fraction):
        drawn.append(fraction)
        print(f"\r{label}: {100.0 * fraction:5.1f} %", end="", file=stream, flush=True)
    with reporting(draw):
        yield
    if drawn:
        print(f"\r{label}: done   ", file=stream, flush=True)


def write_csv(path, t, columns):
    """CSV: first column ``time_s``, then one column per channel, full float precision."""
    keys = list(columns)
    tmp = f"{path}.partial"
    with open(tmp, "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["time_s"] + keys)
        data = np.column_stack([t] + [columns[k] for k in keys])
        for row in data:
            wr.writerow([repr(float(v)) for v in row])
    os.replace(tmp, path)


def _fmt(v, spec):
    return "null" if v is None else format(v, spec)


def without_rotation_reason(result, scene):
    """When no pendulum of the scene simulates ``earth_rotation``, its k = 0 says nothing about the
    site (it is not "as at the equator"): the Foucault method's Earth-rate reason says so."""
    foucault = result.get("methods", {}).get("foucault")
    pendulums = [n for n, e in result.get("instruments", {}).items() if isinstance(e, dict) and "foucault_rate_rad_s" in e]
    if foucault and "reason_earth_rate" in foucault and pendulums and \
            all("earth_rotation" not in scene.instruments[n][2] for n in pendulums if n in scene.instruments):
        foucault["reason_earth_rate"] = ("earth_rotation is not simulated for the pendulum: it cannot precess, "
                                         "so n = k / sin(latitude) is undetermined")


def print_estimate(r, stream=None):
    """Human-readable estimate: recovered latitude and Earth rate next to the truth."""
    w = (stream or sys.stdout).write
    tr = r["truth"]
    w(f"scene {r['scene']} (seed {r.get('seed')}), {r['observation_s']:g} s per instrument\n")
    for note in r.get("scene_notes", []):
        w(f"  note: {note}\n")
    label = "|latitude|" if r.get("latitude_is_absolute") else "latitude  "
    w(f"  {label} {_fmt(r['latitude_deg'], '.7f')} +/- {_fmt(r['latitude_sigma_deg'], '.2g')} deg"
      f"   truth {tr['latitude_deg']:.7f}   (Cramer-Rao {_fmt(r['crlb']['latitude_deg'], '.2g')})\n")
    if r.get("latitude_sigma_reason"):
        lo, hi = r["latitude_interval_deg"]
        lo3, hi3 = r["latitude_interval_3sigma_deg"]
        w(f"             1-sigma interval [{lo:.7f}, {hi:.7f}], 3-sigma [{lo3:.7f}, {hi3:.7f}] deg: "
          f"{r['latitude_sigma_reason']}\n")
    if r.get("hemisphere") and r.get("latitude_deg") is not None:
        w(f"  hemisphere {r['hemisphere']} ({r.get('hemisphere_basis')})\n")
    for o in r.get("other_latitudes_deg") or ():
        w(f"  also consistent: latitude {o['latitude_deg']:.7f} deg (delta chi2 = {o['delta_chi2']:.3g})\n")
    w(f"  Earth rate {_fmt(r['earth_rate_rad_s'], '.9e')} +/- {_fmt(r['earth_rate_sigma_rad_s'], '.2g')} rad/s"
      f"   truth {tr['earth_rate_rad_s']:.9e}   (Cramer-Rao {_fmt(r['crlb']['earth_rate_rad_s'], '.2g')})\n")
    if r.get("method"):
        w(f"  method: {r['method']}\n")
    if r.get("reason"):
        w(f"  reason: {r['reason']}\n")
    print_damage(r, w)
    for name, e in r["instruments"].items():
        if e.get("swing_duration_s") is not None:
            c = e.get("counting", {})
            w(f"  {name}: T = {e['swing_duration_s']:.9f} +/- {e['swing_duration_sigma_s']:.2g} s (fit), "
              f"T0 = {e['small_amplitude_swing_duration_s']:.9f} s; counting: {_fmt(c.get('swing_duration_s'), '.6f')} s"
              f" ({c.get('swings')} swings)\n")
        elif e.get("foucault_rate_rad_s") is not None:
            w(f"  {name}: k = {e['foucault_rate_rad_s']:.6e} +/- {e['foucault_rate_sigma_rad_s']:.2g} rad/s "
              f"(ellipse correction {e['ellipse_correction_rad_s']:.2g})\n")
        else:
            w(f"  {name}: null: {e.get('reason')}\n")
    for mname, m in r["methods"].items():
        lat = m.get("latitude_deg")
        w(f"  method {mname}:" + (f" latitude {_fmt(lat, '.7f')}" if "latitude_deg" in m else "")
          + (" (|latitude|: hemisphere not determined)" if m.get("latitude_is_absolute") else "")
          + (f" +/- {m['latitude_sigma_deg']:.2g}" if lat is not None and m.get("latitude_sigma_deg") is not None else "")
          + (f", n = {m['earth_rate_rad_s']:.9e}" if m.get("earth_rate_rad_s") is not None else "")
          + (f"  [{m.get('reason') or m.get('reason_earth_rate')}]" if (m.get('reason') or m.get('reason_earth_rate')) else "")
          + "\n")


def _span_s(v, end):
    if v is None:
        return end
    txt = f"{v:.3f}".rstrip("0")
    return f"{txt}0 s" if txt.endswith(".") else f"{txt} s"


def damage_line(d):
    """One line for a lost stretch of a bag (a ``damaged`` entry of the replay JSON)."""
    reason = d.get("reason") or "damaged"
    where = f" at byte {d['offset']}" if d.get("offset") is not None else ""
    what = (f"chunk{where} failed its CRC" if reason.startswith("chunk CRC mismatch")
            else f"{reason}{where}")
    if d.get("before_recovery"):
        what = f"before recovery: {what}"
    if d.get("lost_from_s") is None and d.get("lost_to_s") is None and d.get("span_from") is None:
        return f"{what}: no message in it"
    span = f"lost {_span_s(d.get('lost_from_s'), 'the start')} to {_span_s(d.get('lost_to_s'), 'the end')}"
    if d.get("span_from") == "neighbouring messages":
        span += " (between the intact messages around it)"
    return f"{what}: {span}"


def print_damage(r, w):
    """The bag's lost stretches and the reader's notes (replay); nothing for a live estimate."""
    for d in r.get("damaged") or ():
        w(f"  damaged: {damage_line(d)}\n")
    for n in r.get("replay_notes") or ():
        w(f"  note: {n}\n")


# ----------------------------------------------------------------------------- main
def build_parser():
    parser = argparse.ArgumentParser(
        prog="gyro-instrument",
        description="Gyrocompass and Foucault pendulum on the rotating Earth (Quet 1853, Puiseux 1852).")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("scenes", help="list the shipped scenes")
    p = sub.add_parser("describe", help="list a scene's instruments, active effects and the estimated size of "
                                        "every effect each instrument supports")
    add_scene_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p = sub.add_parser("simulate", help="simulate a scene and write every instrument channel to CSV")
    add_scene_arguments(p)
    p.add_argument("--out", required=True, metavar="FILE.csv",
                   help="output CSV: time_s, then <instrument>.<channel> in rad, rad/s or m (see msg_docs/csv.md); "
                        "an existing file is refused unless --overwrite; never the scene file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p = sub.add_parser("estimate", help="simulate the scene's instruments through their sensors and estimate "
                                        "latitude and Earth rate (Quet items 8-9, Foucault) with standard errors")
    add_scene_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (documented in msg_docs/estimate.md)")
    p = sub.add_parser("replay", help="run the estimator over a recorded bag without DDS; reproduces the "
                                      "live 'run' estimate to the last digit. Every chunk's CRC is checked: a "
                                      "damaged chunk is left out and the log-time span it held is reported")
    p.add_argument("bag", help="an .mcap file written by 'gyro-instrument run --bag' or the recorder node")
    p.add_argument("--json", action="store_true", help="print the same JSON object as 'estimate', with "
                                                       "'damaged' and 'replay_notes' when the bag lost data")
    p = sub.add_parser("bench", help="what accuracy costs: work-precision by fidelity tier, speed targets, "
                                     "latitude and Earth-rate error versus observation time with the systematic "
                                     "floors, a site sweep, effect cost; CSV, PNG (with matplotlib) and "
                                     "summary.md in --out")
    p.add_argument("--quick", action="store_true", help="short runs and few seeds (about a minute; the full "
                                                        "bench, with a sidereal day of the pendulum, takes minutes)")
    p.add_argument("--out", default="bench_out", metavar="DIR", help="output directory (default bench_out)")
    p = sub.add_parser("recover", help="rewrite a recording truncated inside its data (no footer: disk "
                                       "full, copied mid-write) or damaged (chunks failing their CRC, a broken "
                                       "summary) into a complete, indexed MCAP of its intact records; the lost "
                                       "spans are printed and kept in the new file (metadata "
                                       "'gyro_instrument_damage'). Exit 2 when nothing intact is found")
    p.add_argument("bag", help="the damaged .mcap")
    p.add_argument("--out", required=True, metavar="FIXED.mcap",
                   help="where to write the recovered file: never the input; an existing file is refused "
                        "unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file (never the input)")
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return run_command(args)
    except SceneError as exc:
        print(f"gyro-instrument: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except IntegrationError as exc:
        print(f"gyro-instrument: integration failed: {exc}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        print("gyro-instrument: interrupted", file=sys.stderr)
        return 130


def run_command(args):
    if args.command == "scenes":
        from gyro_instrument.scenes import shipped_scene_names
        print("\n".join(shipped_scene_names()))
        return 0
    if args.command == "describe":
        d = describe(scene_from_args(args))
        if args.json:
            print(json.dumps(d, indent=2))
        else:
            print_description(d)
        return 0
    if args.command == "simulate":
        check_output(args.out, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{args.out}.partial",))
        scene = scene_from_args(args)
        print_scene_notes(scene)
        progress = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
        t, columns, sims = simulate_scene(scene, progress)
        write_csv(args.out, t, columns)
        if progress:
            nfev = sum(s.trajectory.nfev for s in sims.values())
            wall = sum(s.trajectory.wall_time_s for s in sims.values())
            progress(f"wrote {args.out}: {t.size} rows x {len(columns) + 1} columns "
                     f"({nfev} right-hand-side evaluations, {wall:.2f} s integrating)")
        return 0
    if args.command == "estimate":
        from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
        from gyro_instrument.scenes import scene_notes
        scene = scene_from_args(args)
        with terminal_progress("simulating"):
            truth = simulate_truth(scene)
        result = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
        result["seed"] = scene.seed
        result["scene_notes"] = scene_notes(scene)
        without_rotation_reason(result, scene)
        if args.json:
            print(json.dumps(result, indent=2))
        else:
            print_estimate(result)
        return 0
    if args.command == "bench":
        from gyro_instrument.bench.studies import run_bench
        print(run_bench(args.out, args.quick, progress=lambda m: print(m, file=sys.stderr)))
        return 0
    if args.command == "recover":
        from gyro_instrument.core.scene import EPOCH_NS
        from gyro_instrument.recording.bag_scan import check_mcap, scan_bag
        from gyro_instrument.recording.mcap_io import recover
        check_mcap(args.bag, "bag")
        check_output(args.out, "--out", (args.bag,), args.overwrite)
        scan = scan_bag(args.bag)
        n, scan = recover(args.bag, args.out, scan)
        print(f"recovered {n} messages from {args.bag} into {args.out}")
        for d in scan.damage_dicts(EPOCH_NS):
            print(f"  damaged: {damage_line(d)}")
        for note in scan.notes:
            print(f"  note: {note}")
        if scan.truncated:
            print("  note: the input was cut short (no summary): read up to its last complete record")
        return 0
    if args.command == "replay":
        result = replay_bag(args.bag)
        if args.json:
            print(json.dumps(result, indent=2))
        else:
            print_estimate(result)
        return 0
    raise AssertionError(args.command)


def replay_bag(path):
    """Estimate from a recorded bag (no DDS): the scene from the bag's metadata, the samples from its
    JointState messages decoded without ROS. Every chunk's CRC is checked; a damaged chunk is left
    out and listed under ``damaged`` with the log-time span it held (seconds from the scene's start).

    Raises
    ------
    SceneError
        ``path`` is missing or not an MCAP file, or holds no scene metadata record.
    """
    from gyro_instrument.estimators.pipeline import estimable, estimate_records
    from gyro_instrument.recording.bag_samples import samples_from_bag
    from gyro_instrument.recording.joints import records_from_joints
    from gyro_instrument.scenes import build_instruments, scene_from_data
    meta, samples, notes, damaged = samples_from_bag(path)
    if meta is None or "scene_yaml" not in meta:
        lost = " (damaged stretches: it may have been lost)" if damaged else ""
        raise SceneError("bag", path, "has no gyro_instrument metadata record (scene); record it with "
                                      f"'gyro-instrument run --bag' or the recorder node{lost}")
    scene = scene_from_data(json.loads(meta["scene_yaml"]), source=path)
    insts = build_instruments(scene)
    # in the scene's instrument order, whatever order the bag's topics first appear in
    samples = {n: samples[n] for n in insts if n in samples and estimable(insts[n]) and len(samples[n][0]) >= 3}
    result = estimate_records(scene, {n: insts[n] for n in samples}, records_from_joints(insts, samples))
    result = to_jsonable(result)
    if damaged:
        result["damaged"] = to_jsonable(damaged)
    if notes:
        result["replay_notes"] = notes
    return result


if __name__ == "__main__":
    sys.exit(main())
