"""Frozen, validated scenes loaded from YAML, with ``--set key.path=value`` overrides.

A scene names the site, the instruments and the list of effects; nothing else is simulated.
The core knows no instrument: the caller passes the instrument and effect registries (the
``scenes`` package does, in :func:`gyro_instrument.scenes.load_scene`).

Layout::

    name: quet_paris
    description: ...
    site: {latitude_deg: 48.85, earth_rate_rad_s: 7.292115e-5, gravity_m_s2: 9.81}
    duration_s: 600
    sample_rate_hz: 20
    seed: 1
    effects: {earth_rotation: {}, finite_amplitude: {}, spin_decay: {time_constant_s: 3600}}
    sensor: {noise_rad: 1.0e-4, quantization_rad: 0.0}
    instruments:
      gyro_h: {type: plane_gyroscope, plane: horizontal, ...}

An instrument may carry its own ``effects:`` list of names, a subset of the scene's. The full
format, generated from the parameter specifications, is docs/formats/scene.md.
"""

import math
import os
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
import yaml

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.motion import SHIP_COLUMNS, check_sailing, parse_motion
from gyro_instrument.core.params import Param, unknown_key_hint, validate_params
from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S, Site

SITE_PARAMS = (
    Param("latitude_deg", low=-90.0, high=90.0, doc="geodetic latitude, degrees (north positive)"),
    Param("earth_rate_rad_s", default=SIDEREAL_RATE_RAD_S, low=0.0, high=1.0,
          doc="Earth rotation rate n, rad/s (sidereal 7.2921150e-5)"),
    Param("gravity_m_s2", default=None, low=0.0, high=1000.0, open_low=True,
          doc="local gravity, m/s^2 (default: WGS-84 normal gravity at the latitude)"),
    Param("latitude_known", kind="bool", default=True,
          doc="false: the site's latitude is a placeholder (a record from an unknown place): estimates are not "
              "compared with it (no site check)"),
)

TOP_PARAMS = (
    Param("name", kind="str", default="scene", doc="scene name"),
    Param("description", kind="str", default="", doc="free text"),
    Param("duration_s", default=600.0, low=0.0, high=1.0e7, open_low=True,
          doc="simulated time per instrument, s"),
    Param("sample_rate_hz", default=20.0, low=0.0, high=1.0e4, open_low=True,
          doc="output sample rate, Hz"),
    Param("seed", kind="int", default=0, low=0, high=2 ** 63 - 1, doc="random seed (sensor noise)"),
)

SECTIONS = ("site", "effects", "instruments", "sensor", "estimator", "motion")


@dataclass(frozen=True)
class Scene:
    """A validated scene. Build it with :func:`gyro_instrument.scenes.load_scene`; it is immutable."""

    name: str
    description: str
    site: Site
    duration_s: float
    sample_rate_hz: float
    seed: int
    effects: MappingProxyType        # effect name -> Effect instance
    instruments: MappingProxyType    # instrument name -> (type name, validated params, effect names)
    sensor: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    estimator: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    source: str = ""
    raw: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    #: output channels per sample: ``time`` plus every instrument's ``COLUMNS`` (read from each
    #: instrument class when the scene is built; the memory and disk checks use it)
    output_channels: int = 0
    #: the ship carrying the instruments (:class:`~gyro_instrument.core.motion.Motion`), None on a fixed pier
    motion: object = None


def read_yaml(path) -> dict:
    """Read a scene file; a missing, unreadable, empty or non-mapping file is a SceneError."""
    if not os.path.exists(path):
        raise SceneError("scene", path, "file not found; give a shipped scene name or an existing YAML path")
    try:
        with open(path, encoding="utf-8") as fh:
            data = yaml.safe_load(fh)
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError("scene", path, f"cannot be read ({exc.__class__.__name__}: {exc})") from None
    except yaml.YAMLError as exc:
        msg = str(exc).replace("\n", " ")
        raise SceneError("scene", path, f"is not valid YAML ({msg})") from None
    if data is None:
        raise SceneError("scene", path, "is empty; a scene needs at least site and instruments")
    if not isinstance(data, dict):
        raise SceneError("scene", path, f"must be a YAML mapping, not a {type(data).__name__}")
    return data


def parse_override(text) -> tuple:
    """Split ``key.path=value`` into (['key', 'path'], value parsed as YAML)."""
    if "=" not in text:
        raise SceneError("--set", text, "must look like key.path=value, e.g. site.latitude_deg=-33.87")
    key, _, value = text.partition("=")
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise SceneError("--set", text, "must look like key.path=value, e.g. site.latitude_deg=-33.87")
    try:
        parsed = yaml.safe_load(value) if value.strip() else ""
    except yaml.YAMLError:
        parsed = value
    if isinstance(parsed, str):
        # YAML 1.1 reads 1e-10 (no dot) as a string; on the command line it is surely a number.
        try:
            parsed = float(parsed) if parsed.strip().lower() not in ("nan", "inf", "-inf", "infinity") else parsed
        except ValueError:
            pass
    return key.split("."), parsed


def apply_overrides(data, overrides, effect_names=()) -> dict:
    """Return a copy of ``data`` with each ``key.path=value`` override applied, in order.

    A value sets the key, creating the mappings on its way. ``null`` removes:

    * ``effects.<name>=null`` removes that effect from the scene and from every instrument's
      ``effects:`` list (``effects=null``: every effect);
    * ``instruments.<name>=null`` removes that instrument (removing the last one is refused);
    * on any other key, ``null`` means "use its default" (:func:`validate_params`); a key with no
      default is then refused with its field and valid range.

    A path into an instrument the scene does not have is taken for a misspelling and refused
    with the closest name, unless the overrides also give that instrument's ``type`` (which adds
    a new instrument, e.g. ``instruments.p2.type=spherical_pendulum``). ``effect_names`` (the
    effect registry's names) lets ``effects.<name>=null`` refuse an unknown effect.

    A rate set in another spelling (``spin_rate_turn_s`` for ``spin_rate_rad_s``, see
    :data:`~gyro_instrument.core.params.RATE_ALIASES`) replaces the spelling the scene gave.
    """
    import copy
    data = copy.deepcopy(data)
    parsed = [parse_override(t) if isinstance(t, str) else (list(t[0]), t[1]) for t in overrides or ()]
    typed = set()
    for path, value in parsed:
        if len(path) == 3 and path[0] == "instruments" and path[2] == "type" and value is not None:
            typed.add(path[1])
        if len(path) == 2 and path[0] == "instruments" and isinstance(value, dict) and "type" in value:
            typed.add(path[1])
    for path, value in parsed:
        _check_instrument_name(data, path, value, typed)
        if value is None:
            _remove(data, path, effect_names)
        else:
            _drop_other_spellings(data, path)
            _set(data, path, value)
    return data


def _drop_other_spellings(data, path):
    """Before an override sets ``a.b.<stem><suffix>``, remove the same rate's other spellings there."""
    from gyro_instrument.core.params import RATE_ALIASES
    suffixes = ("_rad_s",) + tuple(s for s, _ in RATE_ALIASES)
    key = path[-1]
    stem = next((key[:-len(s)] for s in suffixes if key.endswith(s)), None)
    node = data
    for part in path[:-1]:
        node = node.get(part) if isinstance(node, dict) else None
    if stem and isinstance(node, dict):
        for s in suffixes:
            if stem + s != key:
                node.pop(stem + s, None)


def _check_instrument_name(data, path, value, typed):
    """Refuse ``instruments.<name>...`` for an instrument neither in the scene nor typed by an override."""
    if path[0] != "instruments" or len(path) < 2:
        return
    insts = data.get("instruments")
    if insts is not None and not isinstance(insts, dict):
        return                                   # build_scene names the bad section
    name = path[1]
    if name in (insts or {}) or (name in typed and value is not None):
        return
    hint = unknown_key_hint(name, insts or {}, "instrument")
    if value is not None:
        hint += f"; to add an instrument, also set instruments.{name}.type"
    raise SceneError(".".join(path), value, hint)


def _set(data, path, value):
    node = data
    for i, part in enumerate(path[:-1]):
        nxt = node.get(part)
        if nxt is None:
            nxt = {}
            node[part] = nxt
        if not isinstance(nxt, dict):
            raise SceneError(".".join(path[:i + 1]), nxt, "is not a mapping; cannot set a key inside it")
        node = nxt
    node[path[-1]] = value


def _remove_effect(data, name):
    """Drop effect ``name`` from the scene's effects and from every instrument's ``effects:`` list."""
    effects = data.get("effects")
    if isinstance(effects, dict):
        effects.pop(name, None)
    elif isinstance(effects, list):
        data["effects"] = [e for e in effects if e != name]
    insts = data.get("instruments")
    for spec in (insts.values() if isinstance(insts, dict) else ()):
        if isinstance(spec, dict) and isinstance(spec.get("effects"), list):
            spec["effects"] = [e for e in spec["effects"] if e != name]


def _remove(data, path, effect_names):
    """``key.path=null``: remove an effect or an instrument, or reset a key to its default."""
    field_ = ".".join(path)
    known_top = {p.name for p in TOP_PARAMS} | set(SECTIONS)
    if path[0] not in known_top:
        raise SceneError(field_, None, unknown_key_hint(path[0], known_top))
    if path[0] == "effects":
        effects = data.get("effects")
        if len(path) == 1:
            for name in list(effects) if isinstance(effects, (dict, list)) else ():
                if isinstance(name, str):
                    _remove_effect(data, name)
            data.pop("effects", None)
            return
        name = path[1]
        if effect_names and name not in effect_names:
            raise SceneError(field_, None, unknown_key_hint(name, effect_names, "effect"))
        listed = name in effects if isinstance(effects, (dict, list)) else False
        if len(path) == 2:
            _remove_effect(data, name)
            return
        if not listed:
            return                               # not simulated: nothing to reset (never switch it on)
    if path == ["instruments"]:
        raise SceneError(field_, None, "removing every instrument leaves nothing to simulate; a scene needs "
                                       "at least one instrument")
    if path[0] == "instruments" and len(path) == 2:
        insts = data["instruments"]
        del insts[path[1]]
        if not insts:
            raise SceneError(field_, None, "removing it leaves the scene with no instrument; a scene needs "
                                           "at least one instrument")
        return
    _set(data, path, None)                       # None: the key's default (validate_params)


def build_scene(data, instrument_registry, effect_registry, sensor_params=(), estimator_params=(),
                source="") -> Scene:
    """Validate a raw scene mapping and build a frozen :class:`Scene`.

    Parameters
    ----------
    data : dict
        The raw scene (already overridden).
    instrument_registry : dict
        type name -> instrument class with ``PARAMS``, ``SUPPORTED_EFFECTS`` and the classmethods
        ``check_params(prefix, params)`` and ``check_effects(prefix, params, effect_names)`` (the
        instrument protocol, ``gyro_instrument.instruments.base``).
    effect_registry : dict
        effect name -> :class:`~gyro_instrument.core.effect.Effect` subclass.
    sensor_params, estimator_params : sequence of Param
        Specifications of the optional ``sensor`` and ``estimator`` sections.
    """
    if not isinstance(data, dict):
        raise SceneError("scene", data, "must be a YAML mapping")
    known = {p.name for p in TOP_PARAMS} | set(SECTIONS)
    for key in data:
        if key not in known:
            raise SceneError(str(key), data[key], unknown_key_hint(key, known))
    top = validate_params("", TOP_PARAMS, {k: v for k, v in data.items() if k not in SECTIONS})
    if "site" not in data:
        raise SceneError("site", None, "is required (a mapping with latitude_deg)")
    site_raw = validate_params("site", SITE_PARAMS, data["site"])
    site = Site(math.radians(site_raw["latitude_deg"]), site_raw["earth_rate_rad_s"], site_raw["gravity_m_s2"],
                site_raw["latitude_known"])
    effects_raw, effects = _build_effects(data.get("effects"), effect_registry)
    instruments = _build_instruments(data.get("instruments"), instrument_registry, effect_registry, effects)
    _check_effects_used(effects_raw, effects, instruments, instrument_registry)
    sensor = validate_params("sensor", sensor_params, data.get("sensor")) if sensor_params or data.get("sensor") else {}
    estimator = (validate_params("estimator", estimator_params, data.get("estimator"))
                 if estimator_params or data.get("estimator") else {})
    motion = parse_motion(data.get("motion"), site.latitude_rad, top["duration_s"])
    check_sailing(motion, instruments, instrument_registry)
    return Scene(name=top["name"], description=top["description"], site=site, duration_s=top["duration_s"],
                 sample_rate_hz=top["sample_rate_hz"], seed=top["seed"],
                 effects=MappingProxyType(effects), instruments=MappingProxyType(instruments),
                 sensor=MappingProxyType(sensor), estimator=MappingProxyType(estimator),
                 source=source, raw=MappingProxyType(data),
                 output_channels=1 + sum(len(instrument_registry[spec[0]].COLUMNS) for spec in instruments.values())
                 + (len(SHIP_COLUMNS) if motion else 0), motion=motion)


def _build_effects(effects_raw, effect_registry):
    """The ``effects`` section (a list of names or a mapping name: {params}) as (raw mapping,
    name -> Effect instance)."""
    effects_raw = effects_raw or {}
    if isinstance(effects_raw, list):
        if not all(isinstance(e, str) for e in effects_raw):
            raise SceneError("effects", effects_raw, "must be a list of effect names or a mapping name: {params}")
        effects_raw = {e: {} for e in effects_raw}
    if not isinstance(effects_raw, dict):
        raise SceneError("effects", effects_raw, "must be a list of effect names or a mapping name: {params}")
    effects = {}
    for name, params in effects_raw.items():
        if name not in effect_registry:
            raise SceneError(f"effects.{name}", params, unknown_key_hint(name, effect_registry, "effect"))
        if params is None:
            params = {}
        if not isinstance(params, dict):
            raise SceneError(f"effects.{name}", params, "must be a mapping of parameters (or {})")
        effects[name] = effect_registry[name](**params)
    return effects_raw, effects


def _build_instruments(inst_raw, instrument_registry, effect_registry, effects):
    """The ``instruments`` section as name -> (type name, validated params, effect names)."""
    if not isinstance(inst_raw, dict) or not inst_raw:
        raise SceneError("instruments", inst_raw, "must be a non-empty mapping of name: {type: ..., ...}; a scene "
                                                  "needs at least one instrument")
    instruments = {}
    for iname, spec in inst_raw.items():
        prefix = f"instruments.{iname}"
        if not isinstance(iname, str) or not iname.replace("_", "").isalnum():
            raise SceneError(prefix, iname, "instrument names must be letters, digits and underscores")
        if not isinstance(spec, dict):
            raise SceneError(prefix, spec, "must be a mapping with at least 'type'")
        spec = dict(spec)
        itype = spec.pop("type", None)
        if itype is None:
            raise SceneError(f"{prefix}.type", itype, f"is required; must be one of {', '.join(sorted(instrument_registry))}")
        if not isinstance(itype, str) or itype not in instrument_registry:
            raise SceneError(f"{prefix}.type", itype, unknown_key_hint(itype, instrument_registry, "instrument type"))
        cls = instrument_registry[itype]
        names = _instrument_effects(prefix, itype, cls, spec.pop("effects", None), effect_registry, effects)
        params = validate_params(prefix, cls.PARAMS, spec)
        cls.check_params(prefix, params)
        cls.check_effects(prefix, params, tuple(names))
        instruments[iname] = (itype, MappingProxyType(params), tuple(names))
    return instruments


def _instrument_effects(prefix, itype, cls, names, effect_registry, effects):
    """An instrument's ``effects:`` list, checked against the registry, the scene's effects and the
    type's ``SUPPORTED_EFFECTS``; absent, every scene effect the type supports."""
    if names is None:
        return [e for e in effects if e in cls.SUPPORTED_EFFECTS]
    if not isinstance(names, list) or not all(isinstance(e, str) for e in names):
        raise SceneError(f"{prefix}.effects", names, "must be a list of effect names")
    for e in names:
        if e not in effect_registry:
            raise SceneError(f"{prefix}.effects", e, unknown_key_hint(e, effect_registry, "effect"))
        if e not in effects:
            raise SceneError(f"{prefix}.effects", e,
                             f"must be listed in the scene's effects ({', '.join(effects) or 'none'})")
        if e not in cls.SUPPORTED_EFFECTS:
            raise SceneError(f"{prefix}.effects", e,
                             f"is not supported by {itype}; supported: {', '.join(sorted(cls.SUPPORTED_EFFECTS))}")
    return names


def _check_effects_used(effects_raw, effects, instruments, instrument_registry):
    """Refuse a scene effect that no instrument of the scene simulates."""
    used = set()
    for _itype, _params, names in instruments.values():
        used.update(names)
    for e in effects:
        if e not in used:
            supporters = sorted(t for t, c in instrument_registry.items() if e in c.SUPPORTED_EFFECTS)
            raise SceneError(f"effects.{e}", effects_raw[e] or {},
                             f"is not supported by any instrument in this scene; instruments that support it: "
                             f"{', '.join(supporters) or 'none'} (remove it with --set effects.{e}=null)")


#: Sim time starts here (time 0 means "no time yet" to ROS): 1e9 s, 2001-09-09T01:46:40Z.
EPOCH_NS = 1_000_000_000 * 1_000_000_000


def sample_times_ns(scene) -> np.ndarray:
    """Sample stamps in integer nanoseconds from release: round(i · 1e9 / f) for i = 0..N.

    Raises SceneError (on ``duration_s``) when the run would not fit in the memory available
    (:func:`gyro_instrument.core.memory.check_memory`)."""
    from gyro_instrument.core.memory import check_memory
    n = int(math.floor(scene.duration_s * scene.sample_rate_hz + 1e-9)) + 1
    check_memory(scene, n)    # SceneError on duration_s before allocating a run that cannot fit
    return np.round(np.arange(n) * (1e9 / scene.sample_rate_hz)).astype(np.int64)


def sample_times(scene) -> np.ndarray:
    """Sample times in seconds, ``sample_times_ns / 1e9`` (the same floats a ROS stamp gives back)."""
    return sample_times_ns(scene) / 1e9


#: Default streaming window (s of simulated time per block of :func:`sample_blocks`).
DEFAULT_WINDOW_S = 10.0


class SampleBlocks:
    """The stamps of :func:`sample_times_ns` (or their seconds) in consecutive blocks of
    ``window_s`` seconds of simulated time (the last block shorter), generated block by block: an
    iterator whose memory is one block, whatever the duration.

    Attributes
    ----------
    count : int
        Samples in the run.
    block_samples : int
        Samples per block (the last may hold fewer).
    end_ns : int
        Stamp of the last sample (ns from release).
    end_s : float
        The last sample time in seconds as the last block gives it (``end_ns / 1e9``): what a
        streaming instrument bounds its last step with (:func:`gyro_instrument.instruments.base.run_span`).

    Raises
    ------
    SceneError
        On ``window_s`` when it is not a positive finite number; on ``duration_s`` when one block
        would not fit in the memory available (:func:`gyro_instrument.core.memory.check_memory`
        applied to one block: a streamed run holds one block at a time).
    """

    def __init__(self, scene, window_s=DEFAULT_WINDOW_S, seconds=False) -> None:
        from gyro_instrument.core.memory import check_memory
        if not (isinstance(window_s, (int, float)) and not isinstance(window_s, bool) and math.isfinite(window_s)
                and window_s > 0):
            raise SceneError("window_s", window_s, "must be a positive finite number of seconds")
        self.count = int(math.floor(scene.duration_s * scene.sample_rate_hz + 1e-9)) + 1
        self.block_samples = max(1, int(math.floor(window_s * scene.sample_rate_hz + 1e-9)))
        check_memory(scene, min(self.block_samples, self.count))
        self._step = 1e9 / scene.sample_rate_hz
        self._seconds = seconds
        self._next = 0
        self.end_ns = int(np.round(np.arange(self.count - 1, self.count) * self._step).astype(np.int64)[0])
        self.end_s = self.end_ns / 1e9

    def __iter__(self) -> "SampleBlocks":
        return self

    def __next__(self) -> np.ndarray:
        i = self._next
        if i >= self.count:
            raise StopIteration
        self._next = min(self.count, i + self.block_samples)
        block = np.round(np.arange(i, self._next) * self._step).astype(np.int64)
        return block / 1e9 if self._seconds else block


def sample_blocks_ns(scene, window_s=DEFAULT_WINDOW_S) -> SampleBlocks:
    """The stamps of :func:`sample_times_ns` in consecutive blocks of ``window_s`` seconds of
    simulated time (the last block shorter), generated block by block (:class:`SampleBlocks`):
    memory is one block, whatever the duration. Raises SceneError on ``window_s`` when it is not a
    positive finite number, on ``duration_s`` when one block would not fit in memory."""
    return SampleBlocks(scene, window_s)


def sample_blocks(scene, window_s=DEFAULT_WINDOW_S) -> SampleBlocks:
    """:func:`sample_blocks_ns` in seconds (``stamps / 1e9``, the floats of :func:`sample_times`);
    its ``end_s`` is the run's last sample time."""
    return SampleBlocks(scene, window_s, seconds=True)
