"""The ``Effect`` interface: one physical effect, switched on by listing it in a scene.

Each effect lives in its own module under ``gyro_instrument.effects`` (model: Orekit's
``ForceModel``, whose ``acceleration`` the numerical propagator sums). An effect knows generic
mechanics, never an instrument: it declares in ``MECHANICS`` the kinds it contributes to and
supplies its terms for those kinds through the hooks below; an instrument declares the kinds its
right-hand side sums (``Instrument.MECHANICS``) and adds the terms of its active effects. An
instrument supports exactly the effects that contribute to one of its kinds, so a new effect of a
known kind needs its own module and a line in the registry, nothing else.

The kinds (:data:`MECHANICS`) and their hooks (SI units; a hook of a kind the effect does not
declare is never called):

==================  ==================================================================================
``point_mass``      :meth:`Effect.point_mass_term`: acceleration of a point (a pendulum bob) in the
                    Earth-fixed rotating frame, from its displacement from the rest point and its
                    velocity relative to the Earth (Quet 1853 sec. 1 eqs. 16, 19–20)
``rigid_body``      :meth:`Effect.rigid_body_torque`: part of the inertia torque of a body turning
                    about a fixed point, body axes (hinge chains; sec. 1 §III–IV for rigid bodies)
``damping``         :meth:`Effect.damping_torque`: torque on a swinging hinge
``spin``            :meth:`Effect.spin_torque`: torque on a rotor's spin hinge (its bearing)
``restoring_law``   :meth:`Effect.restoring_law`: the function of the swing angle in a restoring
                    torque (absent: the small-angle law, the angle itself)
``carrier_inertia`` :meth:`Effect.carrier_inertia`: the inertia of carriers (gimbal rings) taking part
                    in the motion (absent: massless carriers)
``frame_rate``      :meth:`Effect.frame_rate_rad_s`: the rotation rate of the Earth-fixed frame, for
                    closed forms that carry every order in it (absent: 0)
``torsion``         :meth:`Effect.torsion_term`: an elastic suspension (a torsion tape) on a swinging
                    hinge: its stiffness D (N m/rad), its zero on the instrument's scale and the zero's
                    drift rate; the hinge torque is −ΣD · (reading − ΣZ(t))
==================  ==================================================================================

Contributions are summed in the registry's order (:func:`gyro_instrument.effects.canonical_order`),
so a result does not depend on the order a scene lists its effects.

Every hook receives one :class:`EffectContext` first (model: Orekit's ``ForceModel``, which
receives the whole ``SpacecraftState``): the site, its local gravity g, the Earth-rate vector Ω in
ENU and the instrument's characteristic :class:`Scales`. An effect needing g or the latitude reads
them there, never off Ω's direction or a constant. The instrument builds the context
(``Instrument.effect_context``).

An effect also declares what its terms are (``TERMS``; model: Orekit's ``dependsOnPositionOnly``, a
force model telling the propagator what it is): each term kind refines one kind of mechanics (:data:`TERM_KINDS`, term kind
-> its kind of mechanics) and says the term's form, so a model derived by hand for that form can
carry it. A kind of mechanics the effect declares and no declared term kind refines is a term of
general form (:meth:`Effect.terms`): only a model summing that kind's hook carries it.

=========================  ================  =========================================================
term kind                  refines           the term, and how a hand-derived model reads it
=========================  ================  =========================================================
``coriolis_acceleration``  ``point_mass``    −2 Ω × v (Quet sec. 1 eq. 16)
``gyroscopic_torque``      ``rigid_body``    the inertia torque's part linear in Ω,
                                             I(Ω × w) + w × IΩ + Ω × Iw
``centrifugal_gradient``   ``point_mass``    −Ω × (Ω × δr) (sec. 1 eq. 19)
``centrifugal_torque``     ``rigid_body``    Ω × I Ω, the inertia torque's part quadratic in Ω
``sine_restoring_law``     ``restoring_law`` the exact law sin u (the law of the potential 1 − cos u)
``viscous_damping``        ``damping``       −d J q̇ on a hinge of inertia J: d from
                                             :meth:`Effect.viscous_damping_rate_per_s`
``viscous_spin_friction``  ``spin``          −C ρ / τ on a rotor of axial moment C: τ from
                                             :meth:`Effect.spin_decay_time_s`
=========================  ================  =========================================================

Every kind of mechanics is also a term kind of its own (a term of general form, read through the
kind's hook): ``torsion`` (D, Z0, Ż: already coefficients), ``frame_rate`` (a rate),
``carrier_inertia`` and the rest. :func:`register_term_kind` adds a term kind without editing this
module. An instrument declares, per model it can integrate, the term kinds that model carries
(``Instrument.MODELS``); a model carries an effect when it carries each of the effect's term kinds
or the kind of mechanics it refines (:func:`uncarried_terms`), and a scene listing an effect the
model taken cannot carry is refused, naming the effect, the instrument and the model.

An effect also declares capabilities (``CAPABILITIES``, a subset of :data:`CAPABILITIES`):

==================  ==================================================================================
``conservative``    its terms do no net work over a closed path of the relative motion: derivable from a
                    potential (centrifugal gradient, a gravity term) or gyroscopic (Coriolis, no work),
                    or a restoring law of a potential; no dissipation. An instrument's fast path that
                    needs a conservative motion (the pendulum's parareal shooting from a conservative
                    swing) accepts every such effect whose terms it sums.
``default_on``      a reader assumes it simulated unless a scene says otherwise (the Earth's rotation):
                    a scene leaving it out gets a note saying so (:func:`gyro_instrument.scenes.scene_notes`).
==================  ==================================================================================

``relative_size`` estimates, from the context's scales, how much leaving the effect out would
change the result, for ``gyro-instrument describe``. The scales are an open mapping
(:class:`Scales`): the instrument fills in what it has (a name per scale, SI units in the name), an
effect reads what it needs, with a default when an instrument does not provide it
(``ctx.scales.get("torsion_share", 0.0)``): a new effect needing a new scale edits the instruments
that provide it, never this module.
"""

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gyro_instrument.core.params import params_dataclass, validate_params

POINT_MASS = "point_mass"
RIGID_BODY = "rigid_body"
DAMPING = "damping"
SPIN = "spin"
RESTORING_LAW = "restoring_law"
CARRIER_INERTIA = "carrier_inertia"
FRAME_RATE = "frame_rate"
TORSION = "torsion"

#: Every kind of mechanics an effect may contribute to (see the module docstring).
MECHANICS = frozenset((POINT_MASS, RIGID_BODY, DAMPING, SPIN, RESTORING_LAW, CARRIER_INERTIA, FRAME_RATE, TORSION))


CONSERVATIVE = "conservative"
DEFAULT_ON = "default_on"

#: Every capability an effect may declare (see the module docstring).
CAPABILITIES = frozenset((CONSERVATIVE, DEFAULT_ON))

#: The hook of each kind of mechanics (the Effect method an instrument calls for it).
HOOKS = {POINT_MASS: "point_mass_term", RIGID_BODY: "rigid_body_torque", DAMPING: "damping_torque",
         SPIN: "spin_torque", RESTORING_LAW: "restoring_law", CARRIER_INERTIA: "carrier_inertia",
         FRAME_RATE: "frame_rate_rad_s", TORSION: "torsion_term"}


CORIOLIS = "coriolis_acceleration"
GYROSCOPIC = "gyroscopic_torque"
CENTRIFUGAL_GRADIENT = "centrifugal_gradient"
CENTRIFUGAL_TORQUE = "centrifugal_torque"
SINE_LAW = "sine_restoring_law"
VISCOUS_DAMPING = "viscous_damping"
VISCOUS_SPIN = "viscous_spin_friction"

#: Every term kind (see the module docstring) -> the kind of mechanics whose hook gives it; each kind
#: of mechanics is a term kind of its own (a term of general form). Open: :func:`register_term_kind`.
TERM_KINDS = {kind: kind for kind in sorted(MECHANICS)} | {
    CORIOLIS: POINT_MASS, GYROSCOPIC: RIGID_BODY, CENTRIFUGAL_GRADIENT: POINT_MASS, CENTRIFUGAL_TORQUE: RIGID_BODY,
    SINE_LAW: RESTORING_LAW, VISCOUS_DAMPING: DAMPING, VISCOUS_SPIN: SPIN}


#: The coefficient hook a term kind reads (the models carrying the form multiply by it): an effect
#: declaring the term kind implements it.
TERM_HOOKS = {VISCOUS_DAMPING: "viscous_damping_rate_per_s", VISCOUS_SPIN: "spin_decay_time_s"}


def register_term_kind(term, mechanics) -> str:
    """Add the term kind ``term`` refining the kind of mechanics ``mechanics`` (:data:`MECHANICS`) to
    :data:`TERM_KINDS` (a model derived by hand for a new form declares it in ``Instrument.MODELS``).
    Returns ``term``.

    Raises
    ------
    ValueError
        When ``mechanics`` is not a kind of mechanics, or ``term`` is taken by another kind.
    """
    if mechanics not in MECHANICS:
        raise ValueError(f"register_term_kind: {mechanics!r} is not a kind of mechanics ({sorted(MECHANICS)})")
    if TERM_KINDS.get(term, mechanics) != mechanics:
        raise ValueError(f"register_term_kind: {term!r} already refines {TERM_KINDS[term]}")
    TERM_KINDS[term] = mechanics
    return term


def uncarried_terms(effect, carried, mechanics=None) -> frozenset:
    """The term kinds of ``effect`` (an Effect or its class: :meth:`Effect.terms`) that a model carrying
    ``carried`` (term kinds, or kinds of mechanics: every term refining one) does not carry, among those
    refining one of ``mechanics`` (the instrument's kinds; None: all): an empty frozenset when it
    carries the effect."""
    out = set()
    for term in effect.terms():
        kind = TERM_KINDS.get(term, term)
        if mechanics is not None and kind not in mechanics:
            continue
        if term not in carried and kind not in carried:
            out.add(term)
    return frozenset(out)


class Scales(Mapping):
    """An instrument's characteristic scales, for effect-size estimates (``Effect.relative_size``): an
    open mapping, name -> value, that the instrument fills (``Instrument.scales``) and an effect reads.

    A scale is named with its unit (SI). The shipped instruments fill the scales below; any other name
    may be added by an instrument and read by an effect (``scales.get(name, default)``), so a new
    effect needing a new scale edits the instruments providing it, not this class. The ones below
    read as attributes too (``scales.amplitude_rad``), with their defaults when not filled.

    Common scales
    -------------
    earth_rate_rad_s : float
        The site's Earth rate n, rad/s (required).
    duration_s : float or None
        The run's duration, s (None when the context is built for dynamics only).
    restoring_rate_rad_s : float
        The restoring (swing) angular frequency, rad/s (√(g/l) for a pendulum); 0 when none.
    gyro_rate_rad_s : float or None
        μ ρ0, the gyroscopic rate, rad/s; None for an instrument without a rotor's directing torque.
    amplitude_rad : float
        The release amplitude, rad.

    Scales of one instrument kind are its own: the gimbal fills ``ring_inertia_ratio`` ((C1 + A2)/A
    of its rings), the plane gyroscope ``torsion_share`` (D_B / (D_K + D_B) of a torsion tape), the rate
    gyro ``sensed_rate_rad_s`` (n cos γ, the Earth rate its sensitive axis reads at most); the
    effects that need them read them with ``get`` and a default.
    """

    #: The common scales and their values when an instrument does not fill them.
    DEFAULTS = {"duration_s": None, "restoring_rate_rad_s": 0.0, "gyro_rate_rad_s": None, "amplitude_rad": 0.0}

    def __init__(self, earth_rate_rad_s, **scales) -> None:
        self._values = dict(self.DEFAULTS, earth_rate_rad_s=earth_rate_rad_s, **scales)

    def __getitem__(self, name):
        return self._values[name]

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __hash__(self) -> int:
        return hash(frozenset(self._values.items()))

    def __repr__(self) -> str:
        return f"Scales({', '.join(f'{k}={v!r}' for k, v in self._values.items())})"

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(f"Scales has no scale {name!r} (filled: {', '.join(sorted(self))}); "
                                 f"read an optional one with .get(name, default)") from None


@dataclass(frozen=True)
class EffectContext:
    """What every effect hook receives: the instrument's world, frozen.

    Attributes
    ----------
    site : gyro_instrument.core.site.Site
        The site (latitude, Earth rate, local gravity).
    gravity_m_s2 : float
        Local (plumb-line) gravity g at the rest point, m/s², from the site.
    omega_enu : tuple of 3 float
        The Earth-rate vector Ω in ENU, rad/s: n (0, cos γ, sin γ).
    scales : Scales or None
        The instrument's characteristic scales, an open mapping (None when built without them).
    """

    site: object
    gravity_m_s2: float
    omega_enu: tuple
    scales: Scales | None = None

    @classmethod
    def of_site(cls, site, scales=None) -> "EffectContext":
        """The context at ``site`` (g and Ω read from it) with optional ``scales``."""
        return cls(site, float(site.gravity_m_s2), tuple(float(o) for o in site.earth_rate_enu()), scales)


def bound_hooks(effects, kind, context) -> list:
    """The hooks of ``kind`` (:data:`MECHANICS`) of those ``effects`` declaring it, in their order,
    with ``context`` bound: callables taking the hook's remaining arguments."""
    return [functools.partial(getattr(e, HOOKS[kind]), context) for e in effects if kind in e.MECHANICS]


def supporting_effects(registry, kinds) -> frozenset:
    """Names of the effects of ``registry`` (name -> Effect subclass) that contribute to one of
    ``kinds`` (a set of :data:`MECHANICS`): frozenset of str."""
    kinds = frozenset(kinds)
    return frozenset(name for name, cls in registry.items() if cls.MECHANICS & kinds)


class Effect:
    """Base class of all physical effects.

    Subclasses set ``name``, ``summary``, ``PARAMS`` (a tuple of :class:`~gyro_instrument.core.params.Param`), ``MECHANICS``
    (the kinds they contribute to, a subset of :data:`MECHANICS`), ``TERMS`` (the forms of those terms
    a hand-derived model may carry, :data:`TERM_KINDS`; none: general form), ``CAPABILITIES`` (a subset of
    :data:`CAPABILITIES`), implement :meth:`relative_size` and the hook of each declared kind. A
    hook's default contributes nothing. Every hook takes an :class:`EffectContext` first.
    The validated parameters are ``self.p``, a frozen dataclass generated once per class from
    ``PARAMS`` (:func:`~gyro_instrument.core.params.params_dataclass`); ``self.params`` the same as a dict.
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    PARAMS: ClassVar[tuple] = ()
    MECHANICS: ClassVar[frozenset] = frozenset()
    #: The term kinds refining some of ``MECHANICS`` (:data:`TERM_KINDS`); the rest are of general form.
    TERMS: ClassVar[frozenset] = frozenset()
    CAPABILITIES: ClassVar[frozenset] = frozenset()
    #: For a ``default_on`` effect, the scene note's words when no instrument simulates it, when one
    #: instrument leaves it out, and for an instrument that cannot simulate it.
    ABSENT_MEANS: ClassVar[str] = "its terms are left out of the model and of the predictions"
    ABSENT_MEANS_FOR_ONE: ClassVar[str] = "its terms are left out of its model and of its predictions"
    UNSUPPORTED_MEANS: ClassVar[str] = "leaves it out by design"

    def __init__(self, field_prefix="effects", **params) -> None:
        self.params = validate_params(f"{field_prefix}.{self.name}", self.PARAMS, params)
        self.p = params_dataclass(type(self))(**self.params)

    @classmethod
    def terms(cls) -> frozenset:
        """Every term kind of the effect: its ``TERMS`` and each kind of ``MECHANICS`` none of them refines
        (a term of general form, carried only by a model summing that kind's hook)."""
        refined = {TERM_KINDS.get(t, t) for t in cls.TERMS}
        return frozenset(cls.TERMS) | (frozenset(cls.MECHANICS) - refined)

    @classmethod
    def is_conservative(cls) -> bool:
        """True when the effect declares :data:`CONSERVATIVE`."""
        return CONSERVATIVE in cls.CAPABILITIES

    def relative_size(self, ctx) -> tuple:
        """Estimated relative size of the effect for an instrument.

        Parameters
        ----------
        ctx : EffectContext
            Its ``scales`` (:class:`Scales`) are the instrument's characteristic scales.

        Returns
        -------
        (float, str)
            The size and the formula it comes from.
        """
        raise NotImplementedError

    # ------------------------------------------------------------------ terms, one hook per kind
    def point_mass_term(self, ctx) -> Callable | None:
        """``point_mass``: a function ``f(dx, dy, dz, vx, vy, vz) -> (ax, ay, az)`` giving this
        effect's acceleration (m/s²) of a point in the Earth-fixed frame rotating at ``ctx.omega_enu``
        (rad/s, ENU, constant), from the point's displacement (m) from its rest point (where local
        gravity is measured) and its velocity relative to the Earth (m/s), all ENU components.
        Built once per right-hand side (constants bound, like Orekit's ``ForceModel.init``), then
        called at every evaluation with floats or with arrays of equal shape (batched states).
        None: no contribution."""
        return None

    def rigid_body_torque(self, ctx, inertia, w_rel, omega_b) -> np.ndarray:
        """``rigid_body``: this effect's part of the inertia torque I α_abs + ω_abs × I ω_abs of a
        body turning about a fixed point in axes rotating at the constant ``omega_b`` (body axes,
        rad/s); ``inertia`` (3, 3) kg m² and ``w_rel`` (3,) rad/s the body's angular velocity
        relative to the Earth, body axes. Returns an ndarray (3,), N m, added to I α + w × I w."""
        raise NotImplementedError(f"{self.name} declares no rigid_body term")

    def damping_torque(self, ctx, inertia, rate) -> float:
        """``damping``: torque (N m) on a swinging hinge of swinging inertia ``inertia`` (kg m²)
        turning at ``rate`` (rad/s) relative to its carrier."""
        raise NotImplementedError(f"{self.name} declares no damping term")

    def spin_torque(self, ctx, inertia, spin_rate) -> float:
        """``spin``: torque (N m) on a rotor's spin hinge, axial moment ``inertia`` (kg m²),
        spinning at ``spin_rate`` (rad/s) relative to its carrier."""
        raise NotImplementedError(f"{self.name} declares no spin term")

    def restoring_law(self, ctx) -> Callable:
        """``restoring_law``: the function g(angle) replacing the angle in a restoring torque
        (``math.sin``-like, accepting floats and arrays)."""
        raise NotImplementedError(f"{self.name} declares no restoring law")

    def carrier_inertia(self, ctx, inertia) -> float | np.ndarray:
        """``carrier_inertia``: the inertia (kg m², scalar or tensor) a carrier of given
        ``inertia`` contributes to the motion."""
        raise NotImplementedError(f"{self.name} declares no carrier inertia")

    def frame_rate_rad_s(self, ctx) -> float:
        """``frame_rate``: the rotation rate (rad/s) this effect gives the Earth-fixed frame at
        ``ctx.site``."""
        raise NotImplementedError(f"{self.name} declares no frame rate")

    def viscous_damping_rate_per_s(self, ctx, inertia) -> float:
        """``viscous_damping``: d (1/s) of this effect's damping torque −d J q̇ on a hinge of swinging
        inertia J = ``inertia`` (kg m²), for the models that carry the form by its coefficient."""
        raise NotImplementedError(f"{self.name} declares no viscous damping")

    def spin_decay_time_s(self, ctx, inertia) -> float:
        """``viscous_spin_friction``: τ (s) of this effect's spin torque −C ρ / τ on a rotor of axial
        moment C = ``inertia`` (kg m²): the relative spin decays as e^(−t/τ)."""
        raise NotImplementedError(f"{self.name} declares no viscous spin friction")

    def torsion_term(self, ctx) -> tuple:
        """``torsion``: ``(stiffness_n_m_per_rad, zero_rad, zero_rate_rad_s)`` this effect adds to an
        elastic suspension of a swinging hinge: the hinge torque is −D (q_scale − Z0 − Ż t), D, Z0 and
        Ż the sums over the active ``torsion`` effects, q_scale the hinge angle read on the
        instrument's scale (rad), t the time since release (s)."""
        raise NotImplementedError(f"{self.name} declares no torsion term")

    def __repr__(self):
        return f"{type(self).__name__}({self.params})"
