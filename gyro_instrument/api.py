"""The front end's functions, shared by the CLI (:mod:`gyro_instrument.cli`), the ROS nodes and
the suite (:mod:`gyro_instrument.ros`) and the tests: load a scene with its overrides, estimate,
replay a bag, check a recording's destination and a run's options.

Same layer as the CLI (nothing below imports it); no rclpy, no argparse, no printing.
"""

import math

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import scene_inputs  # noqa: F401  (re-exported)
from gyro_instrument.core.jsonable import to_jsonable
from gyro_instrument.recording.replay import damage_line, replay_bag  # noqa: F401  (re-exported)

#: accepted ``window_s`` (simulated seconds per integrated block), as the simulators' parameter
MIN_WINDOW_S, MAX_WINDOW_S = 1.0e-3, 1.0e6
#: bytes per sample of the final estimate's work arrays, per instrument, with a margin of 1.5: 437
#: measured (peak RSS of estimate_records on 172 800 samples of one horizontal gyrocompass, +72 MB)
FIT_BYTES_PER_SAMPLE = 660


def load_scene(scene, overrides=(), duration_s=None) -> "Scene":  # noqa: F821
    """The scene ``scene`` (a shipped name or a YAML path) with the ``KEY=VALUE`` ``overrides``
    applied and, when given, ``duration_s`` (s) as the last override.

    Raises
    ------
    SceneError
        A bad scene, key or value (naming the field, the value and the valid range).
    """
    from gyro_instrument.scenes import load_scene as _load
    overrides = list(overrides) + ([f"duration_s={float(duration_s)!r}"] if duration_s is not None else [])
    return _load(scene, overrides)


def describe(scene) -> dict:
    """Dict describing a scene: site, instruments, active effects, effect sizes, predictions, and
    ``kernels``: whether a run under this process's environment takes the compiled kernels
    (:func:`gyro_instrument.core.jit.status`: numba and where it caches, or why not)."""
    from gyro_instrument.core import jit
    from gyro_instrument.effects import REGISTRY as EFFECTS
    from gyro_instrument.scenes import build_instruments, scene_notes
    insts = build_instruments(scene)
    out = {"scene": scene.name, "description": scene.description, "source": scene.source,
           "scene_notes": scene_notes(scene),
           "site": {"latitude_deg": scene.site.latitude_deg, "earth_rate_rad_s": scene.site.earth_rate_rad_s,
                    "gravity_m_s2": scene.site.gravity_m_s2},
           "duration_s": scene.duration_s, "sample_rate_hz": scene.sample_rate_hz, "seed": scene.seed,
           "scene_effects": list(scene.effects),
           "kernels": f"compiled, {jit.status()}" if jit.enabled() else jit.status(), "instruments": {}}
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


def estimate(scene, truth=None, seed=None) -> dict:
    """Simulate the scene's instruments (``truth``: a :func:`~gyro_instrument.estimators.pipeline.simulate_truth`
    already run), measure them through the scene's sensors and estimate latitude and Earth rate;
    the JSON-ready result with the seed and the scene's notes (msg_docs/estimate.md)."""
    from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
    truth = truth or simulate_truth(scene)
    result = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth, seed)))
    return finish_estimate(result, scene)


def finish_estimate(result, scene) -> dict:
    """An estimate's JSON (``result``, changed in place and returned) completed with the seed, the
    scene's notes and :func:`without_rotation_reason`."""
    from gyro_instrument.scenes import scene_notes
    result["seed"] = scene.seed
    result["scene_notes"] = scene_notes(scene)
    without_rotation_reason(result, scene)
    return result


def without_rotation_reason(result, scene) -> None:
    """When no pendulum of the scene turns with the Earth in the model (n = 0 as simulated,
    ``Instrument.model_earth_rate``), its k = 0 says nothing about the site (it is not "as at the
    equator"): the Foucault method's Earth-rate reason says so."""
    from gyro_instrument.scenes import build_instruments
    foucault = result.get("methods", {}).get("foucault")
    pendulums = [n for n, e in result.get("instruments", {}).items() if isinstance(e, dict) and "foucault_rate_rad_s" in e]
    if not (foucault and "reason_earth_rate" in foucault and pendulums):
        return
    insts = build_instruments(scene)
    if all(insts[n].model_earth_rate() == 0 for n in pendulums if n in insts):
        foucault["reason_earth_rate"] = ("earth_rotation is not simulated for the pendulum: it cannot precess, "
                                         "so n = k / sin(latitude) is undetermined")


def check_bag(scene, bag, bag_format=None, overwrite=False, max_bag_size=0, max_bag_duration_s=0.0,
              field="--bag", format_field="--bag-format") -> str:
    """Resolve the bag layout (``mcap`` or ``rosbag2``) of the output path ``bag`` and refuse an
    output that exists without ``overwrite`` or holds one of the scene's input files; return the
    layout.

    Raises
    ------
    SceneError
        As :func:`~gyro_instrument.recording.bag_layout.check_bag_output`.
    """
    from gyro_instrument.recording.bag_layout import bag_format as layout_of, check_bag_output
    fmt = layout_of(bag, bag_format, max_bag_size, max_bag_duration_s, field=format_field)
    check_bag_output(bag, fmt, field, scene_inputs(scene) if scene else (), overwrite, max_bag_size,
                     max_bag_duration_s)
    return fmt


def check_window(window_s, field="--window-s") -> None:
    """Refuse a window that cannot work: not a number, not finite, or outside [:data:`MIN_WINDOW_S`,
    :data:`MAX_WINDOW_S`] (below a millisecond every block is one sample and the run crawls).

    Raises
    ------
    SceneError
        Naming ``field``, the value and the valid range.
    """
    ok = isinstance(window_s, (int, float)) and not isinstance(window_s, bool) and math.isfinite(window_s)
    if not (ok and MIN_WINDOW_S <= window_s <= MAX_WINDOW_S):
        raise SceneError(field, window_s, f"must be a number of simulated seconds in [{MIN_WINDOW_S:g}, "
                                          f"{MAX_WINDOW_S:g}]")


def check_run_options(namespace="", real_time_factor=0.0, window_s=10.0) -> None:
    """Refuse the options of a ``run`` that cannot work: a namespace that is not a ROS namespace,
    a negative (or NaN) real-time factor, a bad window (:func:`check_window`).

    Raises
    ------
    SceneError
        Naming the option, the value and the valid range.
    """
    if namespace and not namespace.lstrip("/").replace("/", "").replace("_", "a").isalnum():
        raise SceneError("--namespace", namespace, "must be a ROS namespace such as /ship1 (letters, "
                                                   "digits, _ and /)")
    check_window(window_s)
    if real_time_factor < 0 or real_time_factor != real_time_factor:
        raise SceneError("--real-time-factor", real_time_factor, "must be >= 0 (0: as fast as possible)")


def check_run_memory(scene) -> None:
    """Refuse a run that cannot fit in memory, before any node starts. Instruments that stream hold
    one block; one that does not (``STREAMS`` False) holds the run (``core.memory.check_memory``'s
    estimate). The estimator keeps 8 (2 + k) bytes per sample of each instrument (k its measured
    channels) in arrays that double (2x), and its final fits take :data:`FIT_BYTES_PER_SAMPLE` more.

    Raises
    ------
    SceneError
        On ``duration_s``, with the memory needed and available.
    """
    from gyro_instrument.core.memory import available_bytes, check_memory, sample_count
    from gyro_instrument.instruments import REGISTRY
    types = [spec[0] for spec in scene.instruments.values()]
    if not all(REGISTRY[t].STREAMS for t in types):
        check_memory(scene)
        return
    n = sample_count(scene)
    need = n * sum(2 * 8 * (2 + len(REGISTRY[t].MEASURED_CHANNELS)) + FIT_BYTES_PER_SAMPLE for t in types)
    available = available_bytes()
    if available is not None and need > available:
        raise SceneError("duration_s", scene.duration_s,
                         f"the estimator would keep ~{need / 1e9:.3g} GB for {n} samples at {scene.sample_rate_hz:g} "
                         f"Hz; {available / 1e9:.3g} GB available: lower duration_s or sample_rate_hz")
