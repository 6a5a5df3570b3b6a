"""What an instrument asks of its active effects: by the kinds of their terms, never by their names.

:class:`EffectTerms` is mixed into :class:`~gyro_instrument.instruments.base.Instrument`, which supplies
``effects`` (name -> active Effect, summing order), ``context``, ``MECHANICS``, ``MODELS`` and
``model_taken``. The kinds of mechanics and the term kinds are :mod:`gyro_instrument.core.effect`'s: an
instrument sums the hooks of a kind of mechanics (:meth:`EffectTerms.effects_of`), reads a form's
coefficient (:meth:`EffectTerms.viscous_damping_rate_per_s`, :meth:`EffectTerms.spin_decay_time_s`),
asks whether a term of a kind is simulated (:meth:`EffectTerms.has_term`, :meth:`EffectTerms.frame_rotates`),
and refuses at scene loading an effect the model it takes cannot carry (:meth:`EffectTerms.check_carried`).
"""

from collections.abc import Callable

import numpy as np

from gyro_instrument.core.effect import (CARRIER_INERTIA, FRAME_RATE, RESTORING_LAW, VISCOUS_DAMPING, VISCOUS_SPIN, Effect,
                                         uncarried_terms)


class EffectTerms:
    """The instrument's questions to its effects (mixed into ``Instrument``)."""

    @classmethod
    def check_carried(cls, prefix, params, effect_names) -> None:
        """Refuse an effect the model taken (:meth:`model_taken`) cannot carry: one of its term kinds
        (those of this instrument's ``MECHANICS``) is not among the model's ``MODELS`` entry.

        Raises
        ------
        SceneError
            On ``<prefix>.effects`` with the effect's name, naming the instrument type, the model and the
            models that would carry it.
        """
        from gyro_instrument.core.errors import SceneError
        from gyro_instrument.effects import REGISTRY
        classes = {n: REGISTRY[n] for n in effect_names if n in REGISTRY}
        model = cls.model_taken(params, classes)
        if model is None:
            return
        for name, missing in cls.uncarried_effects(model, classes).items():
            others = [m for m in cls.MODELS if not cls.uncarried_effects(m, {name: classes[name]})]
            raise SceneError(f"{prefix}.effects", name,
                             f"cannot be carried by the {model} model of {cls.type_name}: its terms "
                             f"{', '.join(missing)} are not among those that model sums "
                             f"({', '.join(sorted(cls.MODELS[model]))}); "
                             + (f"the {' or '.join(others)} model of {cls.type_name} carries it" if others else
                                f"no model of {cls.type_name} carries it: leave it out for this instrument"))

    @classmethod
    def uncarried_effects(cls, model, effects) -> dict:
        """The effects of ``effects`` (name -> Effect class or object) the model ``model`` (a key of
        ``MODELS``) does not carry: name -> its term kinds that model lacks (sorted)."""
        out = {}
        for name, e in effects.items():
            missing = uncarried_terms(e, cls.MODELS[model], cls.MECHANICS)
            if missing:
                out[name] = sorted(missing)
        return out

    @staticmethod
    def named_with_term(effect_names, term) -> list:
        """The registered effects among ``effect_names`` with a term of kind ``term`` (a term kind, or a
        kind of mechanics: any term of it), in their order."""
        from gyro_instrument.effects import REGISTRY
        return [n for n in effect_names if n in REGISTRY and (term in REGISTRY[n].terms() or term in REGISTRY[n].MECHANICS)]

    def has(self, effect_name) -> bool:
        """True when the effect is listed for this instrument (and so is evaluated)."""
        return effect_name in self.effects

    def effect(self, effect_name) -> Effect | None:
        """The active Effect object, or None."""
        return self.effects.get(effect_name)

    def effects_of(self, kind) -> list:
        """The active effects contributing to the mechanics ``kind`` (list, summing order)."""
        return [e for e in self.effects.values() if kind in e.MECHANICS]

    def effects_with_term(self, term) -> list:
        """The active effects with a term of kind ``term`` (:data:`~gyro_instrument.core.effect.TERM_KINDS`;
        a kind of mechanics: a term of general form), list, summing order."""
        return [e for e in self.effects.values() if term in e.terms()]

    def has_term(self, term) -> bool:
        """True when an active effect has a term of kind ``term``."""
        return bool(self.effects_with_term(term))

    def taken_model(self) -> "str | None":
        """The model this instrument's runs take (:meth:`model_taken` with its parameters and effects)."""
        return self.model_taken(self.params, self.effects)

    def frame_rotates(self) -> bool:
        """True when an active effect turns the Earth-fixed frame (a ``frame_rate`` term: the Earth's
        rotation simulated)."""
        return bool(self.effects_of(FRAME_RATE))

    def viscous_damping_rate_per_s(self, inertia) -> float:
        """d (1/s): the sum over the active ``viscous_damping`` terms of their rates, the hinge torque
        being −d J q̇ on a hinge of inertia J = ``inertia`` (kg m²); 0.0 without one."""
        total = 0.0
        for e in self.effects_with_term(VISCOUS_DAMPING):
            total = total + e.viscous_damping_rate_per_s(self.context, inertia)
        return total

    def spin_decay_time_s(self, inertia) -> "float | None":
        """τ (s) of the active ``viscous_spin_friction`` terms together (the spin torque −C ρ/τ on a rotor
        of axial moment C = ``inertia``, kg m²): one term's own τ, several 1/Σ(1/τ_i); None without one."""
        times = [e.spin_decay_time_s(self.context, inertia) for e in self.effects_with_term(VISCOUS_SPIN)]
        if not times:
            return None
        return times[0] if len(times) == 1 else 1.0 / sum(1.0 / t for t in times)

    def restoring_law(self) -> Callable | None:
        """The restoring law g(u) of the active ``restoring_law`` effect (``numpy.sin`` for
        ``finite_amplitude``), or None: the small-angle law g(u) = u."""
        laws = [e.restoring_law(self.context) for e in self.effects_of(RESTORING_LAW)]
        return laws[-1] if laws else None

    def carrier_inertia(self, inertia) -> float | np.ndarray:
        """What a carrier (gimbal ring) of moment ``inertia`` (kg m²) contributes to the motion: the
        sum over the active ``carrier_inertia`` effects, 0.0 (massless) without one."""
        total = 0.0
        for e in self.effects_of(CARRIER_INERTIA):
            total = total + e.carrier_inertia(self.context, inertia)
        return total

    def model_earth_rate(self) -> float:
        """n as simulated (rad/s): the sum of the active ``frame_rate`` effects' rates (the site's
        Earth rate with ``earth_rotation``), 0 without one."""
        total = 0.0
        for e in self.effects_of(FRAME_RATE):
            total = total + e.frame_rate_rad_s(self.context)
        return total

    def missing_effect_note(self, effect_name, consequence) -> str | None:
        """``"<effect> not simulated: <consequence>"`` when a supported effect is not listed, else None."""
        if effect_name in self.SUPPORTED_EFFECTS and not self.has(effect_name):
            return f"{effect_name} not simulated: {consequence}"
        return None

    def missing_term_note(self, term, consequence) -> str | None:
        """``"<effects> not simulated: <consequence>"`` when some supported effect has a term of kind
        ``term`` and no active one has, else None; <effects> are those supported effects' names."""
        from gyro_instrument.effects import REGISTRY
        if self.has_term(term):
            return None
        names = [n for n, c in REGISTRY.items() if n in self.SUPPORTED_EFFECTS and term in c.terms()]
        return f"{' or '.join(names)} not simulated: {consequence}" if names else None
