"""Shipped scenes and the scene loader.

``load_scene(name_or_path, overrides)`` reads a shipped scene by name (``quet_paris``) or any
YAML path, applies ``--set key.path=value`` overrides, validates every value against the
instruments' and effects' parameter specifications, and returns a frozen
:class:`~gyro_instrument.core.scene.Scene`. ``build_instruments`` turns it into instrument
objects, each given only the effects the scene lists for it. The stages are
:mod:`gyro_instrument.core.scene`'s, run once each in order with :data:`FORMAT`, the shipped
scene format (the registries and the optional blocks ``sensor:``, ``estimator:`` and a ship's ``motion:``; a new
top-level block is one more :class:`~gyro_instrument.core.scene.Block` in it).
"""

import os
from importlib import resources

from gyro_instrument.core import scene as stages
from gyro_instrument.core.effect import DEFAULT_ON
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.motion import SHIP_COLUMNS, check_sailing, parse_motion
from gyro_instrument.core.params import Param
from gyro_instrument.core.scene import Block, Scene, SceneFormat
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS

#: The ``sensor:`` section: the measurement model applied to every angle channel (issue 3).
SENSOR_PARAMS = (
    Param("noise_rad", default=1.0e-4, low=0.0, high=1.0, doc="white noise standard deviation on angles, rad"),
    Param("quantization_rad", default=0.0, low=0.0, high=1.0,
          doc="encoder resolution (0: none), rad"),
    Param("spin_noise_rad_s", default=0.0, low=0.0, doc="white noise on the measured spin rate, rad/s"),
    Param("dropout_fraction", default=0.0, low=0.0, high=0.5, open_high=True,
          doc="fraction of samples lost (NaN), chosen at random"),
)

#: The ``estimator:`` section.
ESTIMATOR_PARAMS = (
    Param("method", kind="str", default="sine_fit", choices=("sine_fit", "counting"),
          doc="period estimator: least-squares sine fit (reaches the Cramér–Rao bound) or Quet's counting"),
    Param("hemisphere", kind="str", default=None, choices=("north", "south"),
          doc="the hemisphere to assume when no instrument can tell +latitude from -latitude (item 9 and "
              "the gimbal's T'/T'' fix cos(latitude) only); a measured sign (a pendulum) always wins. "
              "Unset: such an estimate reports |latitude| with hemisphere 'not determined by these instruments'"),
    Param("earth_rate", kind="str", default=None, choices=("estimate", "known"),
          doc="Earth's rate n: 'estimate' fits it with the latitude (the latitude is null where the instruments "
              "cannot separate them), 'known' holds it at site.earth_rate_rad_s (IERS 7.292115e-5 rad/s by "
              "default) and fits the latitude alone. Unset: estimated where the instruments separate n and the "
              "latitude, known where they do not (a pendulum alone, one horizontal gyroscope)"),
)


def _motion(raw, parts):
    """The ``motion:`` block: the ship (core/motion.py), None on a fixed pier; only instrument types
    that can sail (``FEELS_MOTION``) may be carried. Raises SceneError."""
    motion = parse_motion(raw, parts.site.latitude_rad, parts.top["duration_s"])
    check_sailing(motion, parts.instruments, parts.fmt.instruments)
    return motion


def _sail(instrument, motion):
    if motion is not None:
        instrument.motion = motion


#: The shipped scene format: what :func:`load_scene` accepts. A new top-level block is one more
#: :class:`~gyro_instrument.core.scene.Block` here (validated after the ones before it).
FORMAT = SceneFormat(INSTRUMENTS, EFFECTS, blocks=(
    Block("sensor", SENSOR_PARAMS, doc="measurement model applied to every angle channel (optional; below)"),
    Block("estimator", ESTIMATOR_PARAMS,
          doc="how `estimate` measures periods and which hemisphere it may assume (optional; below)"),
    Block("motion", check_value=_motion, channels=lambda m: len(SHIP_COLUMNS) if m is not None else 0,
          attach=_sail, doc="the ship carrying the instruments (optional: without it, a fixed pier; below)"),
))


def shipped_scene_names() -> list:
    """Names of the scenes installed with the package."""
    root = resources.files(__name__)
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".yaml"))


def scene_path(name_or_path) -> str:
    """Resolve a shipped scene name or a path to a file path."""
    text = str(name_or_path)
    if os.path.exists(text) or text.endswith((".yaml", ".yml")) or os.sep in text:
        return text
    root = resources.files(__name__)
    candidate = root / f"{text}.yaml"
    if candidate.is_file():
        return str(candidate)
    raise SceneError("scene", text, f"is neither a file nor a shipped scene; shipped scenes: "
                                    f"{', '.join(shipped_scene_names())}")


def load_scene(name_or_path, overrides=()) -> Scene:
    """Load, override and validate a scene (see module docstring). Raises SceneError."""
    return stages.load(scene_path(name_or_path), overrides, FORMAT)


def scene_from_data(data, source="recorded", overrides=()) -> Scene:
    """Validate an already-read scene mapping (e.g. the one stored in a bag or beside a table),
    with ``--set`` ``overrides`` applied first."""
    if overrides:                  # without overrides the mapping is validated as given (not copied)
        data = stages.apply_overrides(data, overrides, FORMAT)
    return stages.validate_scene(data, FORMAT, source=source)


def build_instruments(scene) -> dict:
    """Instrument objects of a scene: name -> instrument, each with only its listed effects."""
    return stages.build_instruments(scene, FORMAT)


def not_simulated(effect_name) -> str:
    """Start of the note for a scene (or instrument) that does not simulate ``effect_name``."""
    return f"{effect_name} is not simulated"


def default_on_effects() -> list:
    """The registered effect classes a reader assumes simulated (``DEFAULT_ON`` in their
    ``CAPABILITIES``: the Earth's rotation), in registry order."""
    return [cls for cls in EFFECTS.values() if DEFAULT_ON in cls.CAPABILITIES]


#: Start of the note for a scene (or instrument) that does not simulate the Earth's rotation (the
#: shipped default-on effect).
NO_EARTH_ROTATION = not_simulated(default_on_effects()[0].name)


def scene_notes(scene) -> list:
    """What the scene leaves out that a reader would assume is there, one sentence each.

    ``describe`` (text and ``scene_notes`` in JSON), ``simulate`` (stderr) and ``estimate`` (text
    and ``scene_notes`` in JSON) all print these: one per ``DEFAULT_ON`` effect
    (:func:`default_on_effects`; today the Earth's rotation) that the scene leaves out. A scene in
    which no instrument lists ``earth_rotation`` (a hand-written file without an ``effects:``
    block, or ``--set effects.earth_rotation=null``) is simulated on a non-rotating Earth; one
    whose instrument leaves it out of its own ``effects:`` list is so for that instrument. The
    words are the effect's own (``ABSENT_MEANS``, ``ABSENT_MEANS_FOR_ONE``, ``UNSUPPORTED_MEANS``).

    Returns
    -------
    list of str
    """
    notes = []
    for cls in default_on_effects():
        note = _absent_note(scene, cls)
        if note:
            notes.append(note)
    return notes


def _absent_note(scene, cls) -> str | None:
    """The note for the default-on effect class ``cls`` (:func:`scene_notes`), or None."""
    effect = cls.name
    with_it, without, unsupported = [], [], []
    for name, (itype, _params, effect_names) in scene.instruments.items():
        if effect in effect_names:
            with_it.append(name)
        elif effect in INSTRUMENTS[itype].SUPPORTED_EFFECTS:
            without.append(name)
        else:
            unsupported.append(f"{name} ({itype})")
    if not with_it:
        text = f"{not_simulated(effect)}: {cls.ABSENT_MEANS}"
        if without:
            text += f"; add it with an effects: block in the scene file or --set effects.{effect}={{}}"
        if unsupported:
            text += f"; {', '.join(unsupported)} {cls.UNSUPPORTED_MEANS}"
        return text
    if without:
        return f"{not_simulated(effect)} for {', '.join(without)}: left out of its effects: list, {cls.ABSENT_MEANS_FOR_ONE}"
    return None
