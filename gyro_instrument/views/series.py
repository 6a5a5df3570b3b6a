"""What ``plot`` draws, read from a table or a bag: per instrument its times, its angles in degrees
(or positions in metres when a pendulum's length is unknown), a pendulum's bob path and release."""

import json
import math
import os

import numpy as np

from gyro_instrument.core.errors import SceneError


def load_series(path, scene_arg=None, overrides=(), topics=(), field="FILE", options=None) -> tuple:
    """What to draw from a table (read as ``options`` say: :class:`~gyro_instrument.estimators.
    table_read.TableOptions`, the reader of ``estimate --data``) or a bag.

    Returns
    -------
    series : dict
        instrument -> {``type`` (None when unknown), ``t`` (s), ``channels`` [(label, values,
        unit)] with unit ``deg`` or ``m``; pendulums also ``east``, ``north`` (bob from above),
        ``path_unit`` (``m``, or ``deg`` for a deflection of unknown length); ``simulated``: the
        scene is the file's own (a table written by ``simulate``, a bag of ``run``), so a pendulum's
        release is known (else the expected line goes through the first measured swing)}.
    scene : Scene or None
        ``--scene``, the bag's record or the table's own (:func:`~gyro_instrument.estimators.
        data_io.scene_of_table`).
    notes : list of str

    Raises
    ------
    SceneError
        Unreadable input, a bag without a scene record and no ``--scene``, nothing to draw.
    """
    from gyro_instrument.scenes import load_scene
    scene = load_scene(scene_arg, list(overrides)) if scene_arg else None
    if not os.path.isdir(path) and not str(path).lower().endswith(".mcap"):
        series, scene, notes = _table_series(path, field, scene, overrides, options)
    else:
        series, scene, notes = _bag_series(path, scene, topics)
    if not series:
        raise SceneError(field, path, "holds no angle or pendulum channel to draw (columns as in docs/formats/csv.md)")
    return series, scene, notes


def _table_scene(path, scene, overrides):
    """(scene, notes): ``--scene``, else the one the table carries (noted), else None (noted)."""
    from gyro_instrument.estimators.data_io import scene_of_table
    if scene is not None:
        return scene, []
    found = scene_of_table(path, overrides)
    if found is None:
        return None, [f"{path} carries no scene (no Parquet metadata, no .scene.yaml beside it) and no --scene "
                      f"was given: pendulum positions are drawn in metres, their angles unknown (the length is "
                      f"not in the table)"]
    return found[0], [f"no --scene given: using the scene {found[0].name!r} from {found[1]}"]


def _table_series(path, field, scene, overrides=(), options=None):
    """:func:`load_series` for a CSV or Parquet table; returns (series, scene, notes)."""
    from gyro_instrument.estimators.data_io import TIME_COLUMN, load_table
    from gyro_instrument.instruments import REGISTRY
    from gyro_instrument.scenes import build_instruments
    cols, read_notes = load_table(path, field, options)
    simulated = scene is None                 # the table's own scene (written by simulate), if it has one
    scene, notes = _table_scene(path, scene, overrides)
    simulated = simulated and scene is not None
    notes = read_notes + notes
    t = cols[TIME_COLUMN]
    insts = build_instruments(scene) if scene else {}
    names = list(dict.fromkeys(c.split(".", 1)[0] for c in cols if "." in c))
    angle_names = {c for cls in REGISTRY.values() if not cls.OBSERVATION.SHOWS_BOB_POSITION
                   for c in cls.MEASURED_CHANNELS} | {"deflection"}
    series = {}
    for name in names:
        ch = {c.split(".", 1)[1]: cols[c] for c in cols if c.startswith(f"{name}.")}
        inst = insts.get(name)
        if {"x_east", "y_north"} <= set(ch) or {"deflection_east", "deflection_north"} <= set(ch):
            s = _pendulum_series(t, ch, inst)
        else:
            s = {"type": inst.type_name if inst else None, "t": t,
                 "channels": [(c, np.degrees(v), "deg") for c, v in ch.items() if c in angle_names]}
        if s["channels"]:
            s["simulated"] = simulated
            series[name] = s
    return series, scene, notes


def _pendulum_series(t, ch, inst):
    """A pendulum's series from its table channels: deflections in degrees when its length is known
    (from the scene), else positions in metres; never angles it cannot know."""
    length = inst.observation().table_length_m() if inst is not None else None
    s = {"type": inst.type_name if inst is not None else "pendulum", "t": t}
    if {"x_east", "y_north"} <= set(ch):
        s["east"], s["north"], s["path_unit"] = ch["x_east"], ch["y_north"], "m"
        if length:
            s["channels"] = [("deflection east (x/length)", np.degrees(ch["x_east"] / length), "deg"),
                             ("deflection north (y/length)", np.degrees(ch["y_north"] / length), "deg")]
        else:
            s["channels"] = [("bob east of the rest point", ch["x_east"], "m"),
                             ("bob north of the rest point", ch["y_north"], "m")]
        return s
    de, dn = ch["deflection_east"], ch["deflection_north"]
    if length:
        s["east"], s["north"], s["path_unit"] = de * length, dn * length, "m"
    else:
        s["east"], s["north"], s["path_unit"] = np.degrees(de), np.degrees(dn), "deg"
    s["channels"] = [("deflection east", np.degrees(de), "deg"), ("deflection north", np.degrees(dn), "deg")]
    return s


def _bag_series(path, scene, topics):
    """:func:`load_series` for a bag: its own scene record, or ``scene`` and ``topics`` for a
    foreign bag. Returns (series, scene, notes)."""
    from gyro_instrument.recording.bag_layout import scan_path
    from gyro_instrument.recording.joints import records_from_joints
    from gyro_instrument.scenes import build_instruments
    scan = scan_path(path)
    simulated = scene is None and not topics      # the bag's own scene record: a run of this package
    if scene is None and not topics:
        from gyro_instrument.recording.bag_samples import samples_from_bag
        from gyro_instrument.scenes import scene_from_data
        meta, samples, notes, _ = samples_from_bag(path, scan)
        if meta is None or "scene_yaml" not in meta:
            raise SceneError("bag", path, "has no gyro_instrument metadata record (scene): give the scene "
                                          "with --scene SCENE")
        scene = scene_from_data(json.loads(meta["scene_yaml"]), source=path)
        insts = build_instruments(scene)
        samples = {n: v for n, v in samples.items() if n in insts and len(v[0]) >= 3}
    else:
        from gyro_instrument.recording.foreign import foreign_samples, parse_topic_remaps
        if scene is None:
            raise SceneError("--topic", topics[0], "needs --scene")
        insts = build_instruments(scene)
        samples, report, notes = foreign_samples(scan, insts, parse_topic_remaps(topics, insts))
        notes = list(notes) + [f"{n} not matched: {r}" for n, r in report["unmatched"].items()]
    series = {}
    for name, rec in records_from_joints(insts, samples).items():
        inst = insts[name]
        obs = inst.observation()
        if obs.SHOWS_BOB_POSITION:
            s = _pendulum_series(rec["t"], {"deflection_east": rec["deflection_east"],
                                            "deflection_north": rec["deflection_north"]}, inst)
        else:
            s = {"type": inst.type_name, "t": rec["t"],
                 "channels": [(c, np.degrees(rec[c]), "deg") for c in obs.layout.measured if c in rec]}
        s["simulated"] = simulated
        series[name] = s
    return series, scene, list(notes)


def finite(*arrays) -> list:
    """The arrays (as float) where all are finite, sorted by the first (stable)."""
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    ok = np.ones(len(arrays[0]), bool)
    for a in arrays:
        ok &= np.isfinite(a)
    order = np.argsort(arrays[0][ok], kind="stable")
    return [a[ok][order] for a in arrays]


def record_span(series) -> tuple:
    """(first, last) finite sample time over every instrument, s."""
    lo, hi = math.inf, -math.inf
    for s in series.values():
        t = np.asarray(s["t"], float)
        t = t[np.isfinite(t)]
        if t.size:
            lo, hi = min(lo, float(t.min())), max(hi, float(t.max()))
    return lo, hi
