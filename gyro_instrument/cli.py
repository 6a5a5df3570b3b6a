"""``gyro-instrument``: command-line front end.

Subcommands: ``describe`` (instruments, active effects and every supported effect's
estimated size), ``simulate`` (CSV of every instrument channel), and the later stages.
Bad input exits with status 2 and one line naming the field, the value and the valid range;
Ctrl-C exits with status 130 and the one line ``gyro-instrument: interrupted``, leaving no
half-written output (see :func:`guarded`).
"""

if __name__ == "__main__":
    # ``python -m gyro_instrument.cli``: import this module (numpy, scipy: about a second) under
    # its own name inside the interrupt guard, so a Ctrl-C during the imports is one line too.
    import sys
    try:
        from gyro_instrument.cli import main as _main
    except KeyboardInterrupt:
        print("gyro-instrument: interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(_main())

import argparse
import json
import math
import os
import shutil
import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, NoReturn

import numpy as np

from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.files import (check_output, check_output_dir, check_writable, replaced_atomically,  # noqa: F401
                                        same_file, scene_inputs)
from gyro_instrument.core.jsonable import to_jsonable
from gyro_instrument.recording.replay import damage_line, read_span_s, replay_bag  # noqa: F401  (re-exported)
from gyro_instrument.core.scene import sample_times
from gyro_instrument.effects import REGISTRY as EFFECTS

if TYPE_CHECKING:
    from gyro_instrument.core.scene import Scene

EXIT_BAD_INPUT = 2
EXIT_INTEGRATION_FAILED = 3
EXIT_INTERRUPTED = 130
EXIT_CLOSED_PIPE = 141


def add_scene_arguments(parser, positional=True) -> None:
    """The scene arguments shared by every subcommand (and mirrored by the ROS parameters).
    ``positional=False``: the scene is the option ``--scene`` (replay, plot); ``"optional"``: either
    (estimate: ``estimate SCENE`` or ``estimate --data FILE --scene SCENE``)."""
    scene_help = "shipped scene name (see 'gyro-instrument scenes') or a YAML path"
    if positional is True:
        parser.add_argument("scene", help=scene_help)
    else:
        if positional == "optional":
            parser.add_argument("scene", nargs="?", default=None, help=scene_help)
        parser.add_argument("--scene", dest="scene_option", default=None, metavar="SCENE",
                            help=scene_help + (" (the same as the positional SCENE)" if positional else ""))
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


def add_scene_option(parser, scene_help, set_help="override a value of the --scene scene (as for 'estimate')",
                     dest="scene_option", topics_help=None) -> None:
    """``--scene SCENE`` and ``--set KEY=VALUE`` for a subcommand whose main input is a file or a bag
    (replay, plot, bench), and with ``topics_help`` the ``--topic INSTRUMENT=/TOPIC`` remaps of a
    foreign bag (:func:`gyro_instrument.recording.foreign.parse_topic_remaps`)."""
    parser.add_argument("--scene", dest=dest, default=None, metavar="SCENE", help=scene_help)
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=set_help)
    if topics_help:
        parser.add_argument("--topic", dest="topics", action="append", default=[], metavar="INSTRUMENT=/TOPIC",
                            help=topics_help)


def scene_arg(args) -> str | None:
    """The scene named by the positional SCENE or ``--scene`` (None when neither is given).

    Raises
    ------
    SceneError
        Both are given and differ.
    """
    pos, opt = getattr(args, "scene", None), getattr(args, "scene_option", None)
    if pos and opt and pos != opt:
        raise SceneError("--scene", opt, f"conflicts with the scene {pos!r} given before it; give one")
    return pos or opt


def scene_from_args(args) -> "Scene":
    """Load the scene named on the command line with its overrides."""
    from gyro_instrument.scenes import load_scene
    overrides = list(args.overrides)
    if getattr(args, "duration_s", None) is not None:
        overrides.append(f"duration_s={args.duration_s!r}")
    return load_scene(scene_arg(args), overrides)


def print_scene_notes(scene, stream=None) -> None:
    """The scene's notes (:func:`gyro_instrument.scenes.scene_notes`) on stderr, one line each."""
    from gyro_instrument.scenes import scene_notes
    for note in scene_notes(scene):
        print(f"gyro-instrument: note: {note}", file=stream or sys.stderr)


#: Period conventions printed beside every period (physics_notes, 'What a printed T means').
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


# ----------------------------------------------------------------------------- describe
def describe(scene) -> dict:
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
        context = inst.effect_context(scene.duration_s)
        effects = {}
        for ename in sorted(inst.SUPPORTED_EFFECTS):
            eff = scene.effects.get(ename) or EFFECTS[ename]()
            size, formula = eff.relative_size(context)
            effects[ename] = {"active": inst.has(ename), "relative_size": float(size), "formula": formula}
        out["instruments"][name] = {"type": inst.type_name, "summary": inst.summary,
                                    "parameters": dict(inst.params), "effects": effects,
                                    "predictions": inst.predictions(),
                                    "columns": [f"{name}.{c.name} [{c.unit}]" for c in inst.COLUMNS]}
        chosen = inst.chosen_integrator(scene.duration_s)
        if chosen is not None:           # an instrument with several integrators: which one runs, and why
            out["instruments"][name]["integrator"] = {"chosen": chosen[0], "reason": chosen[1]}
    return to_jsonable(out)


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
    """What a person asks first, as lines: the latitude and, per pendulum, the swing plane's turn in
    °/h (the exact finite-amplitude rate when it has one) and a full turn in hours."""
    lines = [f"latitude {_hemisphere(d['site']['latitude_deg'])}"]
    for name, inst in d["instruments"].items():
        p = inst["predictions"]
        rate = p.get("apsidal_rate_from_rest_rad_s", p.get("foucault_rate_rad_s"))
        if rate is None or "foucault_rate_rad_s" not in p:
            continue
        lines.append(turn_line(name, rate) + (" (exact rate at this amplitude)" if "apsidal_rate_from_rest_rad_s" in p
                                              else ""))
    return lines


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


# ----------------------------------------------------------------------------- simulate
def simulate_scene(scene, progress=None) -> tuple:
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


#: Samples per block of a streamed ``simulate`` (each instrument's :meth:`stream`): large enough
#: that the per-block overhead (a few numpy calls per column) is negligible, small enough that a
#: block of every column is a few MB.
SIMULATE_BLOCK_SAMPLES = 65536


def output_step(scene, output_rate_hz) -> int:
    """Keep every k-th sample for ``--output-rate-hz`` (k = sample_rate_hz / output_rate_hz, 1 when
    None): the integration and its sample grid are unchanged.

    Raises
    ------
    SceneError
        On ``--output-rate-hz`` when the rate is not positive and finite, exceeds the sample rate or
        does not divide it.
    """
    if output_rate_hz is None:
        return 1
    rate = scene.sample_rate_hz
    valid = f"a rate in (0, {rate:g}] Hz that divides the scene's sample_rate_hz = {rate:g} Hz " \
            f"(sample_rate_hz / output_rate_hz a whole number)"
    if not (math.isfinite(output_rate_hz) and 0.0 < output_rate_hz <= rate * (1 + 1e-12)):
        raise SceneError("--output-rate-hz", output_rate_hz, valid)
    k = round(rate / output_rate_hz)
    if abs(rate / output_rate_hz - k) > 1e-9 * k:
        raise SceneError("--output-rate-hz", output_rate_hz, valid)
    return k


def check_disk(path, rows, columns, free=None) -> None:
    """Refuse an output that would not fit on its disk, before the run starts.

    Raises
    ------
    SceneError
        On ``--out``: "needs ~N bytes (R rows x C columns, B bytes a value); F bytes free".
    """
    from gyro_instrument.estimators.data_io import BYTES_PER_VALUE, output_bytes, table_kind
    need = output_bytes(path, rows, columns)
    if free is None:
        free = shutil.disk_usage(os.path.dirname(os.path.abspath(path)) or ".").free
    if need > free:
        raise SceneError("--out", path, f"needs ~{need:.4g} bytes ({rows} rows x {columns} columns at "
                                        f"~{BYTES_PER_VALUE[table_kind(path)]:g} bytes a value); {free} bytes "
                                        f"free on its disk: shorten duration_s, lower --output-rate-hz or "
                                        f"write elsewhere")


def stream_scene(scene, block_samples=SIMULATE_BLOCK_SAMPLES, progress=None) -> Iterator[tuple]:
    """Simulate every instrument of a scene block by block on the common sample grid.

    Each instrument streams (:meth:`~gyro_instrument.instruments.base.Instrument.stream` over its
    own :func:`~gyro_instrument.core.scene.sample_blocks`); the blocks concatenate to
    :func:`simulate_scene` bit for bit for an instrument that ``STREAMS`` (the others run once
    and are sliced).

    Yields
    ------
    (t, columns, sims)
        One block: sample times (s), ``<instrument>.<column>`` -> array, instrument name ->
        Simulation of the block (its trajectory's nfev and wall time count the run so far).
    """
    from gyro_instrument.core.integrate import report
    from gyro_instrument.core.scene import sample_blocks
    from gyro_instrument.scenes import build_instruments
    window_s = block_samples / scene.sample_rate_hz
    times = sample_blocks(scene, window_s)
    span = times.end_s or 1.0
    insts = build_instruments(scene)
    if not all(i.STREAMS for i in insts.values()):
        from gyro_instrument.core.memory import check_memory
        check_memory(scene)          # an instrument that does not stream holds its whole run
    if progress:
        progress(f"simulating {', '.join(f'{n} ({i.type_name})' for n, i in insts.items())} for "
                 f"{scene.duration_s:g} s")
    streams = {name: inst.stream(sample_blocks(scene, window_s)) for name, inst in insts.items()}
    for t in times:
        columns, sims = {}, {}
        for name, inst in insts.items():
            sim = next(streams[name])
            sims[name] = sim
            for c in inst.COLUMNS:
                columns[f"{name}.{c.name}"] = sim.columns[c.name]
        report(t[-1] / span)
        yield t, columns, sims


def simulate_to_file(scene, out, output_rate_hz=None, progress=None) -> tuple:
    """``gyro-instrument simulate``: stream the scene into the table ``out`` (CSV or Parquet) block
    by block, every k-th sample (:func:`output_step`), after checking that it fits on the disk
    (:func:`check_disk`). Returns (rows written, columns, nfev, integration wall s)."""
    from gyro_instrument.core.memory import sample_count
    from gyro_instrument.estimators.data_io import TableWriter, scene_yaml_text, table_kind, table_metadata
    from gyro_instrument.scenes import build_instruments
    k = output_step(scene, output_rate_hz)
    names = [f"{n}.{c.name}" for n, i in build_instruments(scene).items() for c in i.COLUMNS]
    n = sample_count(scene)
    check_disk(out, (n - 1) // k + 1, len(names) + 1)
    first = 0                                  # index of the block's first sample in the run
    nfev = wall = 0.0
    text = scene_yaml_text(scene)
    meta = table_metadata(text, scene.name, scene.seed) if table_kind(out) == "parquet" else None
    with TableWriter(out, names, metadata=meta) as writer:
        with terminal_progress("  simulating", enabled=progress is not None):
            for t, columns, sims in stream_scene(scene, progress=progress):
                keep = slice((-first) % k, None, k)
                writer.write(t[keep], {c: v[keep] for c, v in columns.items()})
                first += t.size
                nfev = sum(s.trajectory.nfev for s in sims.values())
                wall = sum(s.trajectory.wall_time_s for s in sims.values())
    if meta is None:
        write_scene_sidecar(out, text)
    return writer.rows, len(names) + 1, int(nfev), wall


def write_scene_sidecar(table, scene_yaml) -> str:
    """Write ``<name>.scene.yaml`` beside the CSV ``table`` (atomically: an interrupted write leaves
    no partial file); return its path."""
    from gyro_instrument.estimators.data_io import scene_sidecar_path
    path = scene_sidecar_path(table)
    with replaced_atomically(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(f"# the scene gyro-instrument simulate ran for {os.path.basename(table)} (seed and overrides "
                 f"applied)\n")
        fh.write(scene_yaml)
    return path


@contextmanager
def terminal_progress(label, enabled=True, stream=None, force=False) -> Iterator:
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
    try:
        with reporting(draw):
            yield
    except BaseException:
        if drawn:  # erase the progress line so the error (or "interrupted") starts a clean line
            print(f"\r{' ' * (len(label) + 9)}\r", end="", file=stream, flush=True)
        raise
    if drawn:
        print(f"\r{label}: done   ", file=stream, flush=True)


def write_csv(path, t, columns) -> None:
    """CSV: first column ``time_s``, then one column per channel, full float precision
    (:func:`gyro_instrument.estimators.data_io.write_csv`)."""
    from gyro_instrument.estimators.data_io import write_csv as _write_csv
    return _write_csv(path, t, columns)


def _fmt(v, spec):
    return "null" if v is None else format(v, spec)


def without_rotation_reason(result, scene) -> None:
    """When no pendulum of the scene simulates ``earth_rotation``, its k = 0 says nothing about the
    site (it is not "as at the equator"): the Foucault method's Earth-rate reason says so."""
    foucault = result.get("methods", {}).get("foucault")
    pendulums = [n for n, e in result.get("instruments", {}).items() if isinstance(e, dict) and "foucault_rate_rad_s" in e]
    if foucault and "reason_earth_rate" in foucault and pendulums and \
            all("earth_rotation" not in scene.instruments[n][2] for n in pendulums if n in scene.instruments):
        foucault["reason_earth_rate"] = ("earth_rotation is not simulated for the pendulum: it cannot precess, "
                                         "so n = k / sin(latitude) is undetermined")


def print_estimate(r, stream=None) -> None:
    """Human-readable estimate: the answer first (:func:`estimate_headline`), then the recovered
    latitude and Earth rate next to the truth, the checks, each instrument and method; lines
    wrapped at :data:`TEXT_WIDTH`."""
    w, flush = wrapped_writer(stream or sys.stdout)
    for line in estimate_headline(r):
        w(f"{line}\n")
    _print_estimate_body(r, w)
    flush()


def estimate_headline(r) -> list:
    """The estimate's answer as lines: the latitude (or why there is none) and each pendulum's
    measured swing-plane rate in °/h with its full turn in hours."""
    lat = r.get("latitude_deg")
    if lat is None:
        lines = [f"latitude: not determined ({r.get('reason') or 'see the methods below'})"]
    else:
        sig = r.get("latitude_sigma_deg")
        lines = [f"latitude {'|' if r.get('latitude_is_absolute') else ''}{_hemisphere(lat)}"
                 f"{'|' if r.get('latitude_is_absolute') else ''}" + (f" +/- {sig:.2g}°" if sig is not None else "")]
    for name, e in r.get("instruments", {}).items():
        k = e.get("foucault_rate_rad_s") if isinstance(e, dict) else None
        if k:
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
        else:
            w(f"  {name}: null: {e.get('reason')}\n")
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
        what = (f"swing {m['swing_duration_s']:.6g} s {SWING}" if m["kind"] == "gyro"
                else f"period {m['period_s']:.6g} s {FULL_PERIOD}")
        w(f"  {name} ({m['configuration']}): {what}, amplitude {m['amplitude_rad']:.3g} rad, measures "
          f"{m['measures']}\n")
    for name, why in d.get("not_used", {}).items():
        w(f"  {name}: not used ({why})\n")
    for e in d["targets"]:
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


# ----------------------------------------------------------------------------- main
class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors on one line (no usage block), like every other error here; exit 2."""

    def error(self, message) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="gyro-instrument",
        description="Gyrocompass and Foucault pendulum on the rotating Earth (Quet 1853, Puiseux 1852).")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("scenes", help="list the shipped scenes")
    _add_scene_commands(sub)
    _add_bag_commands(sub)
    _add_study_commands(sub)
    _add_recover_command(sub)
    return parser


def _add_scene_commands(sub):
    """describe, simulate, estimate: a scene in, a description, a table or an estimate out."""
    p = sub.add_parser("describe", help="list a scene's instruments, active effects and the estimated size of "
                                        "every effect each instrument supports")
    add_scene_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p = sub.add_parser("simulate", help="simulate a scene and write every instrument channel to CSV or Parquet")
    add_scene_arguments(p)
    p.add_argument("--out", required=True, metavar="FILE.csv|FILE.parquet",
                   help="output table: time_s, then <instrument>.<channel> in rad, rad/s or m (see msg_docs/csv.md); "
                        "Parquet (float64 columns, pyarrow) for a name ending in .parquet, else CSV (full precision); "
                        "written block by block as the run streams to FILE.partial, renamed when complete (a Ctrl-C "
                        "leaves no partial file); refused before the run when it would not fit on the disk; "
                        "an existing file is refused unless --overwrite; never the scene file. The scene (YAML, seed, "
                        "units, package version) goes into Parquet's key-value metadata (gyro_instrument.scene_yaml, "
                        "...) or, for a CSV, into <name>.scene.yaml beside it (same overwrite rule)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--output-rate-hz", type=float, default=None, metavar="HZ",
                   help="write every k-th sample, k = sample_rate_hz / HZ (a whole number; HZ <= sample_rate_hz): "
                        "the integration and its sample grid are unchanged")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p = sub.add_parser("estimate", help="simulate the scene's instruments through their sensors and estimate "
                                        "latitude and Earth rate (Quet items 8-9, Foucault) with standard errors; "
                                        "with --data, estimate from measured data instead")
    add_scene_arguments(p, positional="optional")
    p.add_argument("--data", metavar="FILE.csv|FILE.parquet",
                   help="estimate from this table of measured channels instead of simulating: time_s and "
                        "<instrument>.<channel> columns as in msg_docs/csv.md (pendulums: x_east, y_north in m or "
                        "deflection_east, deflection_north in rad; gyroscopes: their angle and spin_rate); the scene "
                        "gives the instruments (types, lengths, inertia ratios) and the site's nominal values "
                        "(without --scene: the scene the table carries, written by simulate, noted on stderr). "
                        "Missing values, NaN, gaps, irregular and out-of-order times are accepted and noted; a "
                        "gyroscope without spin_rate takes the scene's constant spin (noted). CSV: UTF-8 (a "
                        "byte-order mark is read), separator sniffed from the header (',' or ';' with decimal "
                        "commas, or tab). Parquet: time_s may be a timestamp (seconds from the earliest sample) "
                        "or a duration")
    p.add_argument("--time-column", default="time_s", metavar="NAME",
                   help="with --data: the table's time column (default time_s)")
    p.add_argument("--time-unit", default=None, choices=["s", "ms", "us", "ns", "min"],
                   help="with --data: unit of a numeric time column, converted to s (default s; not for a "
                        "Parquet timestamp or duration, which carries its unit)")
    p.add_argument("--angle-unit", default="rad", choices=["rad", "deg"],
                   help="with --data: unit of the angle channels angle, outer_angle, inner_angle, "
                        "deflection_east, deflection_north (default rad; x_east/y_north stay m, spin_rate rad/s)")
    p.add_argument("--column", dest="columns", action="append", default=[], metavar="NAME=SOURCE",
                   help="with --data: read the table's column SOURCE as the channel column NAME, e.g. "
                        "--column gyro_horizontal.angle=Theta (repeatable)")
    p.add_argument("--separator", default=None, choices=[",", ";", "tab"],
                   help="with --data, CSV: the field separator (default: sniffed from the header line; ';' "
                        "reads decimal commas)")
    p.add_argument("--json", action="store_true", help="print one JSON object (documented in msg_docs/estimate.md)")


def _add_bag_commands(sub):
    """replay, plot: a recorded bag or a table in."""
    p = sub.add_parser("replay", help="run the estimator over a recorded bag without DDS; reproduces the "
                                      "live 'run' estimate to the last digit. Every chunk's CRC is checked: a "
                                      "damaged chunk is left out and the log-time span it held is reported")
    p.add_argument("bag", help="a bag written by 'gyro-instrument run --bag' or the recorder node: an .mcap file "
                               "or a rosbag2 bag directory (metadata.yaml + .mcap files, split or not)")
    p.add_argument("--json", action="store_true", help="print the same JSON object as 'estimate', with "
                                                       "'damaged' and 'replay_notes' when the bag lost data")
    add_scene_option(p, "the scene of a bag recorded by another tool (no gyro_instrument record; or to use instead "
                        "of the bag's record): the instruments' topics are found by the documented names and types "
                        "(/<instrument>/joint_states, sensor_msgs/msg/JointState, joints as in msg_docs/topics.md); "
                        "the JSON gains 'topics' (matched, unmatched with the reason, unused)",
                     topics_help="read this instrument's JointState from another topic (repeatable)")
    p = sub.add_parser("plot", help="draw the standard views of a table or a bag: angles over time (degrees), "
                                    "the swing-plane azimuth with its expected line from the release (rate in "
                                    "deg/h, full turn in hours), the rosette (the bob seen from above, coloured by "
                                    "time), the fit residuals; --animate adds animation.gif (needs matplotlib: pip "
                                    "install 'gyro_instrument[plot]')")
    p.add_argument("file", help="a CSV or Parquet table (msg_docs/csv.md), an .mcap or a rosbag2 bag directory")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="directory for angles, swing_azimuth, bob_path (the rosette) and residuals .png/.svg/.pdf "
                        "(default: <file name>_plots in the current directory); files already there are refused "
                        "unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace the view files already in --out")
    p.add_argument("--format", dest="fmt", default="png", choices=["png", "svg", "pdf"],
                   help="file format of the views (default png)")
    p.add_argument("--dpi", type=float, default=110, help="resolution of a PNG (default 110: 1760 px wide)")
    p.add_argument("--window", default=None, metavar="START:END",
                   help="the rosette's time window, seconds since release (default: the whole record; either "
                        "side may be empty, e.g. 0:600)")
    p.add_argument("--animate", action="store_true",
                   help="also write animation.gif: the bob's path and turning swing plane seen from above (a "
                        "gyroscope: its axis swinging about the meridian), a day in about 20 s, with a clock and "
                        "the latitude")
    add_scene_option(p, "the scene (a table's instrument types and lengths, a foreign bag's instruments; the "
                        "expected line's latitude). A bag written by this package carries its own, and so does "
                        "a table written by 'simulate' (used when --scene is absent, noted)",
                     set_help="override a value of the --scene scene",
                     topics_help="a foreign bag's topic for an instrument (as for replay)")


def _add_study_commands(sub):
    """bench, plan: studies over many runs."""
    p = sub.add_parser("bench", help="what accuracy costs: work-precision by fidelity tier, speed targets, "
                                     "real-time factors, latitude and Earth-rate error versus observation time "
                                     "with the systematic floors, a site sweep, effect cost; CSV, PNG (with "
                                     "matplotlib) and summary.md in --out")
    p.add_argument("--quick", action="store_true", help="short runs and few seeds (about a minute; the full "
                                                        "bench, with a sidereal day of the pendulum, takes minutes)")
    p.add_argument("--out", default="bench_out", metavar="DIR", help="output directory (default bench_out)")
    add_scene_option(p, "run only the observation-time study (error versus observation time, systematic floors "
                        "with the scene's own effects) and the planner's accuracy on this scene (name or YAML path)",
                     set_help="override a value of the --scene (as for 'estimate')", dest="scene")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the sweeps (observation time, site sweep, effect cost) on the Dask cluster whose "
                        "scheduler is at ADDRESS (tcp://HOST:8786; its workers need gyro_instrument installed) "
                        "instead of local processes; needs the 'cluster' extra (pip install "
                        "'gyro_instrument[cluster]')")
    _add_sweep_command(sub)
    p = sub.add_parser("plan", help="how long must I observe? the observation time per configuration each "
                                    "--target needs (Cramer-Rao bound of the scene's sensor model), its dependence "
                                    "on the time, the systematic floor, the effect of the sensor's noise and "
                                    "rate, and Quet's counting for the same target")
    p.add_argument("scene", help="shipped scene name (see 'gyro-instrument scenes') or a YAML path")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene value, as for 'estimate' (e.g. --set "
                        "instruments.gyro_meridian.spin_rate_turn_s=200); duration_s is what is planned")
    p.add_argument("--target", dest="targets", action="append", default=[], metavar="NAME=VALUE",
                   help="a 1-sigma accuracy wanted (repeatable): latitude_arcsec, latitude_deg, latitude_rad, "
                        "earth_rate_rad_s or earth_rate_deg_h, e.g. --target latitude_arcsec=1 --target "
                        "earth_rate_rad_s=1e-10")
    p.add_argument("--noise-factor", dest="noise_factors", action="append", type=float, default=None,
                   metavar="X", help="sensitivity: replan with the sensor noise times X (repeatable; default 0.1 and 10)")
    p.add_argument("--rate-factor", dest="rate_factors", action="append", type=float, default=None,
                   metavar="X", help="sensitivity: replan with the sample rate times X (repeatable; default 2 and 0.5)")
    p.add_argument("--no-floor", action="store_true",
                   help="skip the noise-free run at the planned time (the systematic floor)")
    p.add_argument("--verify", action="store_true",
                   help="run a seeded Monte Carlo at each planned time (process pool, progress on stderr) and "
                        "print the achieved rms next to the target")
    p.add_argument("--seeds", type=int, default=100, help="seeds for --verify (default 100)")
    p.add_argument("--json", action="store_true", help="print one JSON object (documented in msg_docs/plan.md)")


def _add_sweep_command(sub):
    """sweep: any scene over a grid of values, seeds on each point, one Parquet row per (point, seed)."""
    p = sub.add_parser("sweep", help="run a scene over a grid of values (--vary, repeatable: the product) with "
                                     "--seeds seeds measured on one simulation per grid point; one Parquet row "
                                     "per (point, seed): the varied values (columns named by their keys), seed, "
                                     "every field of the estimate JSON flattened (nested as dotted names, lists "
                                     "as JSON text, the truth as truth.*) and error (a refused estimate, or a "
                                     "task that failed twice: a dead worker's task is retried once)")
    add_scene_arguments(p)
    p.add_argument("--vary", dest="vary", action="append", default=[], metavar="KEY=START:STOP:STEP",
                   help="a scene key over START, START+STEP, ... up to STOP (included when it lands on the grid "
                        "within 1e-9 of a STEP), e.g. --vary site.latitude_deg=-60:60:30 (repeatable; at most "
                        "10000 grid points; every point's scene is checked before anything runs)")
    p.add_argument("--seeds", type=int, default=10, help="sensor seeds 0..N-1 per grid point (default 10)")
    p.add_argument("--out", required=True, metavar="FILE.parquet",
                   help="the Parquet table to write; an existing file is refused unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the grid points on the Dask cluster whose scheduler is at ADDRESS (tcp://HOST:8786; "
                        "its workers need gyro_instrument installed) instead of a local process pool; needs the "
                        "'cluster' extra")
    p.add_argument("--timeout", type=float, default=10.0, metavar="S",
                   help="with --scheduler: seconds to wait for the scheduler to answer and, when it has no "
                        "workers, for one to join, before exit 2 (default 10)")


def _add_recover_command(sub):
    """recover: a damaged or cut bag rewritten."""
    p = sub.add_parser("recover", help="rewrite a recording truncated inside its data (no footer: disk "
                                       "full, copied mid-write) or damaged (chunks failing their CRC, a broken "
                                       "summary) into a complete, indexed MCAP of its intact records; the lost "
                                       "spans are printed and kept in the new file (metadata "
                                       "'gyro_instrument_damage'). Exit 2 when nothing intact is found")
    p.add_argument("bag", help="the damaged .mcap, or a rosbag2 bag directory (every file is read; the "
                               "output is one .mcap)")
    p.add_argument("--out", required=True, metavar="FIXED.mcap",
                   help="where to write the recovered file: never the input; an existing file is refused "
                        "unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file (never the input)")


def main(argv=None) -> int:
    """Run one command line (``argv``, default ``sys.argv[1:]``) and return the exit status.

    0 success, 2 bad input (SceneError or an argparse error: one line on stderr), 3 integration
    failed, 130 interrupted (Ctrl-C: one line, no output file left half-written). argparse's
    ``--help`` and its errors raise SystemExit (0 and 2).
    """
    return guarded(lambda: run_command(build_parser().parse_args(argv)), process=argv is None)


def guarded(body, process=False) -> int:
    """Call ``body()`` and turn the expected failures into one line on stderr and an exit status.

    SceneError -> 2, IntegrationError -> 3, a closed stdout pipe -> 141 quietly (:func:`closed_pipe`),
    KeyboardInterrupt (wherever it lands: imports,
    integration, progress drawing, writing) -> ``gyro-instrument: interrupted`` and 130. Any other
    exception is a bug and keeps its traceback. ``process``: this is the process's entry point
    (``argv`` not given); SIGINT is then ignored once the status is decided, so a Ctrl-C while
    Python exits cannot print a traceback after the one line.
    """
    try:
        try:
            return body()
        except SceneError as exc:
            print(f"gyro-instrument: error: {one_line(exc)}", file=sys.stderr)
            return EXIT_BAD_INPUT
        except IntegrationError as exc:
            print(f"gyro-instrument: integration failed: {one_line(exc)}", file=sys.stderr)
            return EXIT_INTEGRATION_FAILED
        except BrokenPipeError:
            return closed_pipe()
    except KeyboardInterrupt:
        return interrupted(process)
    finally:
        if process:
            _ignore_sigint()


def closed_pipe() -> int:
    """The reader of stdout went away (``describe SCENE | head -2``): stop quietly with 141 (128 +
    SIGPIPE, what a shell reports for a command its pipe closed), stdout pointed at /dev/null so
    that Python's final flush cannot print a BrokenPipeError either."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):   # a stdout without a file descriptor (a test's)
        pass
    return EXIT_CLOSED_PIPE


def one_line(exc) -> str:
    """The message of ``exc`` on one line: newlines and other control characters in quoted
    values (a key or value given on the command line) shown escaped."""
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in str(exc))


def interrupted(process=False) -> int:
    """Print ``gyro-instrument: interrupted`` and return 130, with further SIGINTs ignored while
    printing (a second Ctrl-C must not interrupt the message); in-process callers get their
    handler back."""
    for _ in range(3):   # a second SIGINT before the handler is swapped lands here: try again
        try:
            previous = _ignore_sigint()
            print("gyro-instrument: interrupted", file=sys.stderr)
            if not process and previous is not None:
                signal.signal(signal.SIGINT, previous)
            return EXIT_INTERRUPTED
        except KeyboardInterrupt:
            continue
    return EXIT_INTERRUPTED


def _ignore_sigint():
    """Ignore SIGINT (main thread only); return the previous handler or None."""
    if threading.current_thread() is threading.main_thread():
        return signal.signal(signal.SIGINT, signal.SIG_IGN)
    return None


def run_command(args) -> int:
    """Run the parsed subcommand ``args.command``; its exit status."""
    return COMMANDS[args.command](args)


def scenes_command(args) -> int:
    """``gyro-instrument scenes``: the shipped scene names, one per line."""
    from gyro_instrument.scenes import shipped_scene_names
    print("\n".join(shipped_scene_names()))
    return 0


def describe_command(args) -> int:
    """``gyro-instrument describe``: instruments, active effects, predictions (text or ``--json``)."""
    d = describe(scene_from_args(args))
    if args.json:
        print(json.dumps(d, indent=2))
    else:
        print_description(d)
    return 0


def simulate_command(args) -> int:
    """``gyro-instrument simulate``: every instrument channel to CSV or Parquet (``--out``)."""
    from gyro_instrument.estimators.data_io import scene_sidecar_path, table_kind
    check_output(args.out, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{args.out}.partial",))
    if table_kind(args.out) == "csv":        # its scene beside it, under the same rule
        side = scene_sidecar_path(args.out)
        check_output(side, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{side}.partial",))
    scene = scene_from_args(args)
    print_scene_notes(scene)
    progress = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    rows, ncol, nfev, wall = simulate_to_file(scene, args.out, args.output_rate_hz, progress)
    if progress:
        progress(f"wrote {args.out}: {rows} rows x {ncol} columns "
                 f"({nfev} right-hand-side evaluations, {wall:.2f} s integrating)")
    return 0


def estimate_command(args) -> int:
    """``gyro-instrument estimate``: simulate through the sensors (or read ``--data``) and estimate."""
    from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
    from gyro_instrument.scenes import scene_notes
    scene = data_scene(args) if scene_arg(args) is None and args.data else None
    if scene is None and scene_arg(args) is None:
        raise SceneError("scene", None, "give the scene: 'estimate SCENE' or 'estimate --data FILE --scene SCENE'"
                                        + (f" ({args.data} carries none: no Parquet metadata 'gyro_instrument."
                                           f"scene_yaml', no .scene.yaml beside it)" if args.data else ""))
    scene = scene or scene_from_args(args)
    table_flags = {"--time-column": (args.time_column, "time_s"), "--time-unit": (args.time_unit, None),
                   "--angle-unit": (args.angle_unit, "rad"), "--column": (args.columns, []),
                   "--separator": (args.separator, None)}
    if args.data:
        from gyro_instrument.estimators.data_io import TableOptions, estimate_data
        options = TableOptions.from_flags(args.time_column, args.time_unit, args.angle_unit, args.columns,
                                          args.separator)
        result = to_jsonable(estimate_data(scene, args.data, options=options))
    elif given := [(flag, v) for flag, (v, default) in table_flags.items() if v != default]:
        raise SceneError(*given[0], "reads a table: give --data FILE (or leave the flag out)")
    else:
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


def data_scene(args) -> "Scene | None":
    """The scene ``estimate --data FILE`` takes when no scene is given: the one the table carries
    (written by ``simulate``), with ``--set`` applied and a note on stderr; None when it carries none."""
    from gyro_instrument.estimators.data_io import scene_of_table
    found = scene_of_table(args.data, args.overrides)
    if found is None:
        return None
    scene, where = found
    print(f"gyro-instrument: note: no --scene given: using the scene {scene.name!r} from {where}", file=sys.stderr)
    return scene


def bench_command(args) -> int:
    """``gyro-instrument bench``: the studies of :mod:`gyro_instrument.bench.studies` into ``--out``."""
    from gyro_instrument.bench.studies import run_bench
    if args.overrides and args.scene is None:
        raise SceneError("--set", args.overrides[0], "applies to a --scene; give --scene SCENE")
    if args.scene is not None:
        from gyro_instrument.scenes import load_scene
        load_scene(args.scene, args.overrides)      # a bad scene stops here, before any directory is made
    progress = lambda m: print(m, file=sys.stderr)  # noqa: E731
    if args.scheduler:
        from gyro_instrument.core.parallel import dask_executor
        with dask_executor(args.scheduler) as ex:      # no scheduler: exit 2 before --out is made
            check_output_dir(args.out)
            progress(f"sweeps on the Dask scheduler {args.scheduler}")
            print(run_bench(args.out, args.quick, progress=progress, scene=args.scene, overrides=args.overrides,
                            executor=ex))
    else:
        check_output_dir(args.out)
        print(run_bench(args.out, args.quick, progress=progress, scene=args.scene, overrides=args.overrides))
    return 0


def sweep_command(args) -> int:
    """``gyro-instrument sweep``: :func:`gyro_instrument.bench.sweep.run_sweep` into ``--out``."""
    from gyro_instrument.bench.sweep import grid, run_sweep
    from gyro_instrument.estimators.data_io import table_kind
    if table_kind(args.out) != "parquet":
        raise SceneError("--out", args.out, "must be a Parquet file (name ending .parquet or .pq)")
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise SceneError("--timeout", args.timeout, "must be a finite number of seconds > 0")
    check_output(args.out, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{args.out}.partial",))
    grid(args.vary)                                   # a bad --vary stops here, before any scheduler is asked
    if args.seeds < 1:
        raise SceneError("--seeds", args.seeds, "must be an integer >= 1")
    overrides = list(args.overrides) + ([f"duration_s={args.duration_s!r}"] if args.duration_s is not None else [])
    progress = lambda m: print(m, file=sys.stderr)  # noqa: E731
    if args.scheduler:
        from gyro_instrument.core.parallel import dask_executor
        with dask_executor(args.scheduler, args.timeout, need_workers=True, progress=progress) as ex:
            progress(f"sweep on the Dask scheduler {args.scheduler}")
            r = run_sweep(args.scene, overrides, args.vary, args.seeds, args.out, executor=ex, progress=progress)
    else:
        r = run_sweep(args.scene, overrides, args.vary, args.seeds, args.out, progress=progress)
    print(f"wrote {r['path']}: {r['rows']} rows x {r['columns']} columns ({r['points']} grid points, "
          f"{r['errors']} with an error) in {r['wall_s']:.1f} s ({r['rows_per_s']:.3g} rows/s)")
    return 0


def recover_command(args) -> int:
    """``gyro-instrument recover``: rewrite a damaged or cut bag's intact records (``--out``)."""
    from gyro_instrument.core.scene import EPOCH_NS
    from gyro_instrument.recording.bag_layout import bag_files, bag_inputs, scan_path
    from gyro_instrument.recording.mcap_io import recover
    bag_files(args.bag, "bag")
    check_output(args.out, "--out", bag_inputs(args.bag), args.overwrite)
    scan = scan_path(args.bag)
    n, scan = recover(args.bag, args.out, scan)
    print(f"recovered {n} messages from {args.bag} into {args.out}")
    for d in scan.damage_dicts(EPOCH_NS):
        print(f"  damaged: {damage_line(d)}")
    for note in scan.notes:
        print(f"  note: {note}")
    if scan.truncated:
        print("  note: the input was cut short (no summary): read up to its last complete record")
    return 0


def plot_command(args) -> int:
    """``gyro-instrument plot``: the standard views of a table or a bag to PNG."""
    import time
    from gyro_instrument.views import plot_file
    from gyro_instrument.views.rosette import parse_window
    out = args.out or f"{os.path.basename(os.path.normpath(args.file)).rsplit('.', 1)[0]}_plots"
    t0 = time.perf_counter()
    window = parse_window(args.window)
    pngs, notes = plot_file(args.file, out, args.scene_option, args.overrides, args.topics, args.overwrite,
                            fmt=args.fmt, dpi=args.dpi, window=window, animate=args.animate)
    for note in notes:
        print(f"gyro-instrument: note: {note}", file=sys.stderr)
    views = [p for p in pngs if not p.endswith(".gif")]
    print(f"wrote {len(views)} views" + (" and an animation" if len(views) < len(pngs) else "")
          + f" in {time.perf_counter() - t0:.2f} s: " + ", ".join(pngs))
    return 0


def replay_command(args) -> int:
    """``gyro-instrument replay``: the estimate from a recorded bag (:func:`replay_bag`)."""
    result = replay_bag(args.bag, args.scene_option, args.overrides, args.topics)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print_estimate(result)
    return 0


def plan_command(args) -> int:
    """``gyro-instrument plan``: see :mod:`gyro_instrument.estimators.planner`."""
    from gyro_instrument.estimators.planner import NOISE_FACTORS, RATE_FACTORS, parse_targets, plan, verify_plan
    targets = parse_targets(args.targets)
    if args.verify and args.seeds < 2:
        raise SceneError("--seeds", args.seeds, "must be an integer >= 2 (the rms of the Monte Carlo)")
    err = lambda m: print(m, file=sys.stderr)  # noqa: E731
    d = plan(args.scene, args.overrides, targets, args.noise_factors or NOISE_FACTORS,
             args.rate_factors or RATE_FACTORS, floor=not args.no_floor)
    if args.verify:
        verify_plan(d, args.seeds, progress=err)
    d = to_jsonable(d)
    if args.json:
        print(json.dumps(d, indent=2))
    else:
        print_plan(d)
    return 0


#: Subcommand name -> its function (``args`` in, exit status out).
COMMANDS = {
    "scenes": scenes_command,
    "describe": describe_command,
    "simulate": simulate_command,
    "estimate": estimate_command,
    "bench": bench_command,
    "plan": plan_command,
    "sweep": sweep_command,
    "recover": recover_command,
    "plot": plot_command,
    "replay": replay_command,
}
