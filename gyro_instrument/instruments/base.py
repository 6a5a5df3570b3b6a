"""Instrument interface shared by every instrument module."""

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.integrate import Trajectory

#: Most periods (swings, turns) one run may hold. An adaptive 8th-order step covers a few percent
#: of a period at the default rtol (~50 right-hand-side evaluations per period), so 1e9 periods
#: is ~5e10 evaluations — weeks of CPU — and far before that a period shorter than
#: ~1e5 · eps · duration cannot be resolved in double-precision time at all (the solver fails).
MAX_PERIODS = 1.0e9


def check_period_count(field, value, period_s, duration_s):
    """Refuse a parameter whose period makes a run impossible, before integrating.

    Raises
    ------
    SceneError
        On ``field`` when ``duration_s / period_s`` exceeds :data:`MAX_PERIODS` (or the period is
        not a positive finite number).
    """
    if not (period_s > 0.0 and math.isfinite(period_s)) or duration_s / period_s > MAX_PERIODS:
        raise SceneError(field, value, f"gives a period of {period_s:.3g} s: {duration_s:g} s of it would be "
                                       f"more than {MAX_PERIODS:g} periods, beyond what can be integrated; "
                                       f"shorten duration_s or choose a slower instrument")


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
        """The papers' analytic predictions for this instrument's configuration (dict).

        Predictions describe the model as simulated: an effect the instrument does not list is
        absent from them too (without ``earth_rotation``, n = 0). A ``notes`` entry (list of
        str), present only when needed, says which supported effects are left out and what the
        prediction would be with them.
        """
        return {}

    def model_earth_rate(self):
        """n as simulated: the site's Earth rate when ``earth_rotation`` is listed, else 0 (rad/s)."""
        return self.site.earth_rate_rad_s if self.has("earth_rotation") else 0.0

    def missing_effect_note(self, effect_name, consequence):
        """``"<effect> not simulated: <consequence>"`` when a supported effect is not listed, else None."""
        if effect_name in self.SUPPORTED_EFFECTS and not self.has(effect_name):
            return f"{effect_name} not simulated: {consequence}"
        return None


def with_notes(predictions, *notes):
    """``predictions`` with a ``notes`` list of the non-None notes (no key when there are none)."""
    notes = [n for n in notes if n]
    if notes:
        predictions["notes"] = notes
    return predictions
