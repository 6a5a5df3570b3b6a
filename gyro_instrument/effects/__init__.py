"""Physical effects, one module each. Effects never import each other or any instrument.

``REGISTRY`` maps the name used in scene files to the effect class, in the order in which
instruments sum the effects' terms (:func:`canonical_order`): the shipped ones, then those of
plug-ins. A new effect is one class, found through an entry point of the group
``gyro_instrument.effects`` (:mod:`gyro_instrument.core.plugins`; the shipped ones are entry points of
it too, setup.py) or registered with :func:`register` (docs/extending.md).
"""

from gyro_instrument.core import plugins
from gyro_instrument.core.effect import CAPABILITIES, MECHANICS, TERM_HOOKS, TERM_KINDS, Effect
from gyro_instrument.effects.air_drag import AirDrag
from gyro_instrument.effects.centrifugal import Centrifugal
from gyro_instrument.effects.earth_rotation import EarthRotation
from gyro_instrument.effects.finite_amplitude import FiniteAmplitude
from gyro_instrument.effects.pivot_damping import PivotDamping
from gyro_instrument.effects.ring_inertia import RingInertia
from gyro_instrument.effects.spin_decay import SpinDecay
from gyro_instrument.effects.tape_drift import TapeDrift
from gyro_instrument.effects.tape_torsion import TapeTorsion

REGISTRY = {}


def register(cls) -> type:
    """Add an :class:`~gyro_instrument.core.effect.Effect` subclass to :data:`REGISTRY` under its
    ``name`` (usable as a class decorator; returns ``cls``). Every instrument whose ``MECHANICS``
    meet the effect's then supports it.

    Raises
    ------
    ValueError
        When ``cls`` is not an Effect subclass, its ``name`` is empty or taken, or its
        ``MECHANICS`` name no known kind (:data:`gyro_instrument.core.effect.MECHANICS`), its ``TERMS``
        a term kind not refining one of them (:data:`gyro_instrument.core.effect.TERM_KINDS`) or one
        whose coefficient hook (:data:`gyro_instrument.core.effect.TERM_HOOKS`) it does not implement, or its
        ``CAPABILITIES`` no known capability (:data:`gyro_instrument.core.effect.CAPABILITIES`).
    """
    if not (isinstance(cls, type) and issubclass(cls, Effect)):
        raise ValueError(f"register: {cls!r} is not an Effect subclass")
    if not cls.name or cls.name in REGISTRY:
        raise ValueError(f"register: effect name {cls.name!r} is empty or already registered "
                         f"({', '.join(REGISTRY)})")
    unknown = set(cls.MECHANICS) - MECHANICS
    if unknown or not cls.MECHANICS:
        raise ValueError(f"register: {cls.name} MECHANICS {sorted(cls.MECHANICS)} must be a non-empty subset "
                         f"of {sorted(MECHANICS)}")
    bad = sorted(t for t in cls.TERMS if TERM_KINDS.get(t) not in cls.MECHANICS)
    if bad:
        raise ValueError(f"register: {cls.name} TERMS {bad} are not term kinds refining its MECHANICS "
                         f"{sorted(cls.MECHANICS)} (gyro_instrument.core.effect.TERM_KINDS)")
    lacking = sorted(TERM_HOOKS[t] for t in cls.TERMS if t in TERM_HOOKS and
                     getattr(cls, TERM_HOOKS[t]) is getattr(Effect, TERM_HOOKS[t]))
    if lacking:
        raise ValueError(f"register: {cls.name} declares TERMS {sorted(cls.TERMS)} but does not implement "
                         f"{', '.join(lacking)}")
    if set(cls.CAPABILITIES) - CAPABILITIES:
        raise ValueError(f"register: {cls.name} CAPABILITIES {sorted(cls.CAPABILITIES)} must be a subset "
                         f"of {sorted(CAPABILITIES)}")
    REGISTRY[cls.name] = cls
    return cls


def unregister(name) -> None:
    """Remove the effect ``name`` from :data:`REGISTRY` (for tests that register their own)."""
    REGISTRY.pop(name, None)


def canonical_order(effects) -> dict:
    """``effects`` (name -> Effect) as a dict in :data:`REGISTRY` order: the order in which
    instruments sum terms, so results do not depend on the order a scene lists its effects."""
    order = {name: i for i, name in enumerate(REGISTRY)}
    return dict(sorted(effects.items(), key=lambda item: order.get(item[0], len(order))))


#: The shipped effects, in the order their terms are summed (also entry points of ``gyro_instrument.effects``).
SHIPPED = (EarthRotation, Centrifugal, FiniteAmplitude, RingInertia, SpinDecay, PivotDamping, AirDrag, TapeTorsion,
           TapeDrift)
plugins.discover("effects", register, lambda c: REGISTRY.get(getattr(c, "name", None)) is c, SHIPPED)

__all__ = ["REGISTRY", "AirDrag", "Centrifugal", "EarthRotation", "FiniteAmplitude", "PivotDamping",
           "RingInertia", "SpinDecay", "TapeDrift", "TapeTorsion", "canonical_order", "register", "unregister"]
