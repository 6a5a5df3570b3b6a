"""Frozen, validated scenes loaded from YAML, with ``--set key.path=value`` overrides.

A scene names the site, the instruments and the list of effects; nothing else is simulated.
The core knows no instrument: the caller describes what a scene may hold in a
:class:`SceneFormat` (the instrument and effect registries and the optional blocks; the
``scenes`` package builds the shipped one, :data:`gyro_instrument.scenes.FORMAT`).

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

Loading is one pass of four stages, each a public function called once, each taking what the
one before returned (:func:`load` composes the first three)::

    read_yaml(path)                       -> document   (a dict, as written)
    apply_overrides(document, sets, fmt)  -> document   (a new dict, --set applied)
    validate_scene(document, fmt, source) -> Scene      (frozen, every value checked)
    build_instruments(scene, fmt)         -> {name: instrument}

A new top-level block (a ship's ``motion:``) is one :class:`Block` added to the format's
``blocks``: the override stage then accepts ``--set motion...`` (and ``motion=null``), the
validation stage checks it after the instruments and the scene carries its value in
``Scene.blocks``.
"""

import copy
import math
import os
from dataclasses import dataclass, field
from types import MappingProxyType

import yaml

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import other_rate_spellings, unknown_key_hint, validate_params
from gyro_instrument.core.sampling import (DEFAULT_WINDOW_S, EPOCH_NS, SampleBlocks,  # noqa: F401 (re-exported:
                                           sample_blocks, sample_blocks_ns, sample_times,  # the stamps were
                                           sample_times_ns)                                # defined here first)
from gyro_instrument.core.scene_format import (CORE_SECTIONS, SITE_PARAMS, TOP_PARAMS, Block,  # noqa: F401
                                               SceneFormat, SceneParts)                         # (re-exported)
from gyro_instrument.core.site import Site


@dataclass(frozen=True)
class Scene:
    """A validated scene. Build it with :func:`gyro_instrument.scenes.load_scene`; it is immutable.

    A block the format registers beyond ``sensor`` and ``estimator`` is read as an attribute too
    (``scene.motion`` is ``scene.blocks["motion"]``); ``getattr(scene, name, None)`` is None for a
    block the format does not have."""

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
    #: every optional block of the format (``sensor``, ``estimator`` and any registered later), by
    #: name: its validated value (:meth:`Block.check`)
    blocks: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))

    def __getattr__(self, name) -> object:
        blocks = self.__dict__.get("blocks")      # (only reached for a name that is not a field)
        if blocks is not None and name in blocks:
            return blocks[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")


# ----------------------------------------------------------------------------- 1. parse
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


# ----------------------------------------------------------------------------- 2. override
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


def apply_overrides(data, overrides, fmt) -> dict:
    """Return a copy of ``data`` with each ``key.path=value`` override applied, in order.

    A value sets the key, creating the mappings on its way. ``null`` removes:

    * ``effects.<name>=null`` removes that effect from the scene and from every instrument's
      ``effects:`` list (``effects=null``: every effect);
    * ``instruments.<name>=null`` removes that instrument (removing the last one is refused);
    * on any other key, ``null`` means "use its default" (:func:`validate_params`); a key with no
      default is then refused with its field and valid range.

    A path into an instrument the scene does not have is taken for a misspelling and refused
    with the closest name, unless the overrides also give that instrument's ``type`` (which adds
    a new instrument, e.g. ``instruments.p2.type=spherical_pendulum``). ``fmt`` (a
    :class:`SceneFormat`) gives the top-level keys ``key=null`` may name and the effect names
    ``effects.<name>=null`` may name. Values are not checked here: that is the validation
    stage's (:func:`validate_scene`).

    A rate set in another spelling (``spin_rate_turn_s`` for ``spin_rate_rad_s``, see
    :data:`~gyro_instrument.core.params.RATE_ALIASES`) replaces the spelling the scene gave.
    """
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
            _remove(data, path, fmt)
        else:
            _drop_other_spellings(data, path)
            _set(data, path, value)
    return data


def _drop_other_spellings(data, path):
    """Before an override sets ``a.b.<stem><suffix>``, remove the same rate's other spellings there."""
    node = data
    for part in path[:-1]:
        node = node.get(part) if isinstance(node, dict) else None
    if isinstance(node, dict):
        for other in other_rate_spellings(path[-1]):
            node.pop(other, None)


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


def _remove(data, path, fmt):
    """``key.path=null``: remove an effect or an instrument, or reset a key to its default."""
    field_ = ".".join(path)
    known_top = fmt.known_keys()
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
        if fmt.effects and name not in fmt.effects:
            raise SceneError(field_, None, unknown_key_hint(name, fmt.effects, "effect"))
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


# ----------------------------------------------------------------------------- 3. validate
def validate_scene(data, fmt, source="") -> Scene:
    """Validate a scene document (already overridden) and return the frozen :class:`Scene`.

    Checked in this order, the first error raised: the top-level keys, the top-level values, the
    site, the effects, the instruments (each against its type's ``PARAMS``, ``check_params`` and
    ``check_effects``), every scene effect used by some instrument, then each of ``fmt``'s blocks.

    Parameters
    ----------
    data : dict
        The scene document.
    fmt : SceneFormat
        The instrument types, effects and optional blocks.
    source : str
        Where the document came from (a path, ``recorded``).

    Raises
    ------
    SceneError
        Naming the field, its value and what is valid.
    """
    if not isinstance(data, dict):
        raise SceneError("scene", data, "must be a YAML mapping")
    known = fmt.known_keys()
    for key in data:
        if key not in known:
            raise SceneError(str(key), data[key], unknown_key_hint(key, known))
    top = validate_params("", TOP_PARAMS, {k: v for k, v in data.items() if k not in fmt.sections})
    if "site" not in data:
        raise SceneError("site", None, "is required (a mapping with latitude_deg)")
    site_raw = validate_params("site", SITE_PARAMS, data["site"])
    site = Site(math.radians(site_raw["latitude_deg"]), site_raw["earth_rate_rad_s"], site_raw["gravity_m_s2"],
                site_raw["latitude_known"])
    effects_raw, effects = _build_effects(data.get("effects"), fmt.effects)
    instruments = _build_instruments(data.get("instruments"), fmt.instruments, fmt.effects, effects)
    _check_effects_used(effects_raw, effects, instruments, fmt.instruments)
    blocks = {}
    parts = SceneParts(top, site, effects, instruments, fmt)
    for block in fmt.blocks:
        blocks[block.name] = block.check(data.get(block.name), parts)
    return Scene(name=top["name"], description=top["description"], site=site, duration_s=top["duration_s"],
                 sample_rate_hz=top["sample_rate_hz"], seed=top["seed"],
                 effects=MappingProxyType(effects), instruments=MappingProxyType(instruments),
                 sensor=MappingProxyType(blocks.get("sensor", {})),
                 estimator=MappingProxyType(blocks.get("estimator", {})),
                 source=source, raw=MappingProxyType(data),
                 output_channels=1 + sum(len(fmt.instruments[spec[0]].COLUMNS) for spec in instruments.values())
                 + sum(b.channels(blocks[b.name]) for b in fmt.blocks if b.channels is not None),
                 blocks=MappingProxyType(blocks))


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

# ----------------------------------------------------------------------------- 4. build
def build_instruments(scene, fmt) -> dict:
    """Instrument objects of a validated scene: name -> instrument of ``fmt``'s type, each given
    the scene's site, its validated parameters and only the effects the scene lists for it; then
    each block with an ``attach`` hook is attached to every instrument (:class:`Block`)."""
    out = {}
    for name, (itype, params, effect_names) in scene.instruments.items():
        cls = fmt.instruments[itype]
        out[name] = cls(name, scene.site, params, {e: scene.effects[e] for e in effect_names})
        for block in fmt.blocks:
            if block.attach is not None:
                block.attach(out[name], scene.blocks.get(block.name))
    return out


def load(path, overrides, fmt, source=None) -> Scene:
    """Stages 1-3 in order, once each: :func:`read_yaml`, :func:`apply_overrides`,
    :func:`validate_scene` (``source`` defaults to ``path``). Raises SceneError."""
    return validate_scene(apply_overrides(read_yaml(path), overrides, fmt), fmt,
                          source=path if source is None else source)
