"""What a scene may hold (its format): the top-level values, the site, and a :class:`SceneFormat`
naming the instrument types, the effects and the optional top-level blocks (:class:`Block`).

The loading stages (:mod:`gyro_instrument.core.scene`) take the format as an argument; the
``scenes`` package builds the shipped one (:data:`gyro_instrument.scenes.FORMAT`). A new
top-level block (a ship's ``motion:``) is one :class:`Block` added to it.
"""

from dataclasses import dataclass, replace

from gyro_instrument.core.params import Param, validate_params
from gyro_instrument.core.site import SIDEREAL_RATE_RAD_S

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

#: The sections every scene has, whatever its format (site, effects, instruments); the optional
#: blocks (``sensor``, ``estimator``, ...) are the format's (:attr:`SceneFormat.sections`).
CORE_SECTIONS = ("site", "effects", "instruments")



@dataclass(frozen=True)
class Block:
    """An optional top-level block of a scene (``sensor:``, ``estimator:``, a ship's ``motion:``).

    Attributes
    ----------
    name : str
        The top-level key.
    params : tuple of Param
        Its keys, checked by :func:`~gyro_instrument.core.params.validate_params` (an absent block
        takes every default).
    check_value : callable or None
        Instead of ``params``, for a block that is not flat or that depends on the rest of the
        scene: ``check_value(raw, parts)`` returns the validated value (``raw`` is None when the
        scene has no such block; ``parts``, a :class:`SceneParts`, is what is validated before it)
        or raises :class:`SceneError` naming the field.
    channels : callable or None
        ``channels(value)``: output channels per sample the block adds (a ship's track columns);
        None: none.
    attach : callable or None
        ``attach(instrument, value)``, called on every instrument the build stage makes (a ship
        carrying the instruments); None: nothing.
    doc : str
        Its line in the scene format's table of top-level keys (docs/formats/scene.md).
    """

    name: str
    params: tuple = ()
    check_value: object = None
    channels: object = None
    attach: object = None
    doc: str = ""

    def check(self, raw, parts) -> object:
        """The block's validated value from its ``raw`` document value (None: absent) and the scene's
        ``parts`` validated before it (:class:`SceneParts`). Raises SceneError."""
        if self.check_value is not None:
            return self.check_value(raw, parts)
        return validate_params(self.name, self.params, raw) if self.params or raw else {}


@dataclass(frozen=True)
class SceneParts:
    """What the validation stage has checked when it reaches the blocks: the top-level values
    (``top``: name, description, duration_s, sample_rate_hz, seed), the :class:`Site`, the effects
    (name -> Effect), the instruments (name -> (type, params, effect names)) and the format."""

    top: dict
    site: object
    effects: dict
    instruments: dict
    fmt: "SceneFormat"


@dataclass(frozen=True)
class SceneFormat:
    """What a scene may hold: the instrument types, the effects and the optional blocks.

    Attributes
    ----------
    instruments : mapping
        type name -> instrument class with ``PARAMS``, ``SUPPORTED_EFFECTS``, ``COLUMNS`` and the
        classmethods ``check_params(prefix, params)`` and ``check_effects(prefix, params,
        effect_names)`` (the instrument protocol, ``gyro_instrument.instruments.base``).
    effects : mapping
        effect name -> :class:`~gyro_instrument.core.effect.Effect` subclass.
    blocks : tuple of Block
        The optional top-level blocks, validated in this order after the instruments.
    """

    instruments: object
    effects: object
    blocks: tuple = ()

    @property
    def sections(self) -> tuple:
        """The top-level mappings: :data:`CORE_SECTIONS` then the blocks' names."""
        return CORE_SECTIONS + tuple(b.name for b in self.blocks)

    def known_keys(self) -> set:
        """Every top-level key a scene of this format may have."""
        return {p.name for p in TOP_PARAMS} | set(self.sections)

    def with_block(self, block) -> "SceneFormat":
        """This format with ``block`` added (validated after the ones it has)."""
        return replace(self, blocks=self.blocks + (block,))
