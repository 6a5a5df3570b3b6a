"""Instrument interface shared by every instrument module."""

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from gyro_instrument.core.integrate import Trajectory


@dataclass(frozen=True)
class Column:
    """One output channel: ``name`` (without the instrument prefix), unit and meaning."""

    name: str
    unit: str
    doc: str


@dataclass
class Simulation:
    """What an instrument's ``simulate`` returns.

    Attributes
    ----------
    t : ndarray
        Sample times, s.
    columns : dict
        Column name (see ``Instrument.COLUMNS``) -> array sampled at ``t``.
    trajectory : Trajectory
        The integrator's result (state, nfev, wall time).
    """

    t: np.ndarray
    columns: dict
    trajectory: Trajectory
    extra: dict = field(default_factory=dict)


class Instrument:
    """Base class: parameters in, one ``simulate`` call, columns out.

    Subclasses set ``type_name``, ``PARAMS`` (tuple of Param), ``SUPPORTED_EFFECTS``,
    ``COLUMNS`` and implement ``simulate``, ``scales`` and ``predictions``.
    """

    type_name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    PARAMS: ClassVar[tuple] = ()
    SUPPORTED_EFFECTS: ClassVar[frozenset] = frozenset()
    COLUMNS: ClassVar[tuple] = ()

    def __init__(self, name, site, params, effects):
        """``effects`` maps name -> Effect for the effects active on this instrument only."""
        self.name = name
        self.site = site
        self.params = dict(params)
        self.effects = dict(effects)
        for key, value in self.params.items():
            setattr(self, key, value)

    def has(self, effect_name):
        """True when the effect is listed for this instrument (and so is evaluated)."""
        return effect_name in self.effects

    def effect(self, effect_name):
        """The active Effect object, or None."""
        return self.effects.get(effect_name)

    def scales(self, duration_s):
        """Characteristic scales for effect-size estimates (see ``Effect.relative_size``)."""
        raise NotImplementedError

    def simulate(self, t, **options):
        """Integrate and return a :class:`Simulation` sampled at times ``t`` (s)."""
        raise NotImplementedError

    def predictions(self):
        """The papers' analytic predictions for this instrument's configuration (dict)."""
        return {}
