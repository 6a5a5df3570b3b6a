"""The instrument protocol: everything the package needs to know about an instrument type.

An instrument type is one class; the rest of the package (scene loading, the sensor model and the
estimator, the recorder's joint layout, the ROS nodes, the bench) asks the class and never keys a
table by its ``type_name`` (``tests/test_architecture.py`` fails when a module outside
``instruments/`` does). The declared members, each documented on :class:`Instrument`:

=======================  ===================================================================
``type_name``            the ``type`` used in scene files
``summary``, ``PARAMS``  one line for ``describe``; the parameter specifications
``MECHANICS``            the kinds of mechanics its right-hand side sums effect terms for
                         (:mod:`gyro_instrument.core.effect`); ``SUPPORTED_EFFECTS`` follows
``MODELS``, ``model_taken``  the models it can integrate, the term kinds each carries
                         (:data:`~gyro_instrument.core.effect.TERM_KINDS`), and which one a run
                         takes: chosen from the effects' declared terms, never their names
``COLUMNS``              the simulated output channels
``MEASURED_CHANNELS``    the angles a sensor reads (:meth:`Instrument.measured_angles`)
``JOINTS``               the ``sensor_msgs/JointState`` joints it publishes
``OBSERVATION``          its :class:`~.observation.Observation` class: what it measures, the joint
                         layout, the sensor draws, how a record becomes a measurement
                         (:meth:`Instrument.observation` builds it); everything outside
                         ``instruments/`` asks the observation
``SIMULATOR_NODE``       the ROS simulator node that hosts it
``check_params``,        parameter checks beyond each parameter's own range (classmethods,
``check_effects``        called by scene loading for every instrument)
``directing_model``      a :class:`DirectingModel` for a gyroscope with a directing line (what
                         :class:`~.observation.SwingRate` is built from)
=======================  ===================================================================

What it asks of its active effects, by the kinds of their terms (never their names), is
:class:`~.effect_terms.EffectTerms`, mixed in.

Model: rosbags' typed ``StorageProtocol``; Drake's systems declaring their ports.
"""

import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.effect import EffectContext, Scales, supporting_effects
from gyro_instrument.core.integrate import Trajectory
from gyro_instrument.core.params import params_dataclass
from gyro_instrument.effects import canonical_order
from gyro_instrument.instruments.effect_terms import EffectTerms
from gyro_instrument.instruments.observation import Observation, SwingRate

#: Most periods (swings, turns) one run may hold. An adaptive 8th-order step covers a few percent
#: of a period at the default rtol (~50 right-hand-side evaluations per period), so 1e9 periods
#: is ~5e10 evaluations — weeks of CPU — and far before that a period shorter than
#: ~1e5 · eps · duration cannot be resolved in double-precision time at all (the solver fails).
MAX_PERIODS = 1.0e9


def check_period_count(field, value, period_s, duration_s) -> None:
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


@dataclass(frozen=True)
class DirectingModel:
    """What an estimator may know of a gyroscope whose axis swings about a directing line.

    Small swings last T0 = π/√K with K = ``gain`` · n ρ · s(γ) · (1 + ``second_order`` · n s(γ)/ρ),
    s(γ) = sin ω the sine of the angle between the swing plane's normal and Earth's axis (Quet
    1853 sec. 4 §1 eq. 9; sec. 4 §IV for the gimbal), n the Earth rate (rad/s), ρ the rotor's
    relative spin (rad/s).

    Attributes
    ----------
    gain : float
        Dimensionless: μ = C/A for the directing plane (μ / sin ε on a cone), C/J for the gimbal
        (J = A + C1 + A2 locked, A + A1 outer ring fixed).
    normal_enu : tuple of 3 float
        Unit normal of the swing plane in ENU; s(γ) = |normal × Earth axis|.
    label : str
        ``"horizontal"`` or ``"meridian"`` for the configurations Quet's item 9 and eq. (10)
        combine; any other text (``"polar"``, ``"custom"``, ``"outer_fixed"``...) otherwise.
    angle_channel : str
        The ``COLUMNS`` / ``MEASURED_CHANNELS`` name of the swing angle (rad).
    null_reason : str
        Why no oscillation may be measured (e.g. a plane perpendicular to Earth's axis), appended
        to the estimator's reason when the fit fails.
    second_order : float
        c2 of the exact equation's O(n²) term, K/(gain ρ) = y (1 + c2 y/ρ), y = n s(γ); (μ − 1)/μ for
        the directing plane (sec. 4 §1, the term eqs. (1)–(3) drop), 0 when not derived.
    spin_rate_rad_s : float
        ρ0, the rotor's relative spin at release (rad/s): K is proportional to it, so the
        planner's bound includes the spin-rate sensor's error; 0 when not stated.
    """

    gain: float
    normal_enu: tuple
    label: str
    angle_channel: str
    null_reason: str
    second_order: float = 0.0
    spin_rate_rad_s: float = 0.0


@dataclass(frozen=True)
class ExpectedSwing:
    """The scene's prediction of an instrument's measured oscillation.

    Attributes
    ----------
    period_s : float
        Full period of the measured angle, s (a gyroscope's 2 T0, Quet sec. 4 §1 eq. 9; a
        pendulum's four quarter periods, sec. 2 eq. 42 exact form).
    amplitude_rad : float
        Amplitude of the measured angle at release, rad (the swing angle; a pendulum's deflection).
    source : str
        Which parameters set them, for messages ("mu, spin_rate_rad_s, latitude").
    min_samples_per_period : float
        Fewest samples per period the instrument's observation can use: 2.5 for a sine fit (the
        Nyquist limit 2, with room for the period's uncertainty); more where the estimator needs
        them (a pendulum's second moments per swing period).
    sampling_reason : str
        Why, for the refusal.
    """

    period_s: float
    amplitude_rad: float
    source: str
    min_samples_per_period: float = 2.5
    sampling_reason: str = "below it the swing aliases and a fit would find the alias"


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


def run_span(blocks, t_end=None) -> tuple:
    """The blocks of a streamed run, its start and its end (s).

    ``t_end`` is the last sample time of the run when given, else the blocks' ``end_s`` (as
    :func:`gyro_instrument.core.scene.sample_blocks` provides), else the blocks are read once to
    find it (their times are then held in memory). An adaptive integrator needs the end before its
    first step: it bounds the last step as in one call over the whole run.

    Returns
    -------
    (iterator of ndarray, float or None, float or None)
        The blocks (float arrays, the first already read), ``t0`` (the first sample) and the end;
        ``(iter(()), None, None)`` when there is no sample.
    """
    end = t_end if t_end is not None else getattr(blocks, "end_s", None)
    it = iter(blocks)
    if end is None:
        kept = [np.asarray(b, dtype=float) for b in it]
        kept = [b for b in kept if b.size]
        if not kept:
            return iter(()), None, None
        end, it = float(kept[-1][-1]), iter(kept)
    for first in it:
        first = np.asarray(first, dtype=float)
        if first.size:
            return itertools.chain([first], it), float(first[0]), float(end)
    return iter(()), None, None


class _SupportedEffects:
    """``SUPPORTED_EFFECTS`` of an instrument class or object: the registered effects that contribute
    to one of its ``MECHANICS`` kinds (frozenset of names), computed at each access so an effect
    registered later (:func:`gyro_instrument.effects.register`) is supported without editing the
    instrument."""

    def __get__(self, obj, cls):
        from gyro_instrument.effects import REGISTRY
        return supporting_effects(REGISTRY, cls.MECHANICS)


class Instrument(EffectTerms):
    """Base class: parameters in, one ``simulate`` call, columns out.

    Subclasses set the class members below and implement ``simulate``, ``scales`` and
    ``predictions``; the hooks (``check_params``, ``check_effects``, ``directing_model``,
    ``measured_angles``) have defaults that fit an instrument without them.

    Attributes
    ----------
    type_name : str
        The ``type`` in scene files; the key of :data:`gyro_instrument.instruments.REGISTRY`.
    summary : str
        One line for ``describe`` and msg_docs/instruments.md.
    PARAMS : tuple of Param
        Parameter specifications (validated by scene loading; docs/formats/scene.md).
    MECHANICS : frozenset of str
        The kinds of mechanics whose effect terms the right-hand side sums
        (:data:`gyro_instrument.core.effect.MECHANICS`).
    SUPPORTED_EFFECTS : frozenset of str
        Derived, not set: the registered effects contributing to one of ``MECHANICS``.
    COLUMNS : tuple of Column
        The simulated channels, in ``Simulation.columns``.
    MEASURED_CHANNELS : tuple of str
        The angles (rad) the sensor model reads, in order (:meth:`measured_angles` gives their
        true values); they are the positions of the first ``len(MEASURED_CHANNELS)`` joints.
    JOINTS : tuple of str
        ``sensor_msgs/JointState`` joint names (prefixed ``<instrument>/`` on the wire). The
        measured channels first; then, for a pendulum, ``deflection`` (hypot of the two measured
        deflections) and ``azimuth`` (compass, atan2(east, north)); otherwise one rotor joint
        (position: integrated true spin; velocity: the measured ``spin_rate``, rad/s).
    OBSERVATION : type
        The :class:`~.observation.Observation` subclass that :meth:`observation` builds (default
        :class:`~.observation.SwingRate`: a directing swing when :meth:`directing_model` gives one,
        else measured angles and a rotor).
    SIMULATOR_NODE : str
        The ROS simulator node (an entry point in setup.py) that publishes it:
        ``gyrocompass_sim``, ``pendulum_sim`` or ``top_sim``.
    """

    type_name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    PARAMS: ClassVar[tuple] = ()
    MECHANICS: ClassVar[frozenset] = frozenset()
    SUPPORTED_EFFECTS = _SupportedEffects()
    COLUMNS: ClassVar[tuple] = ()
    MEASURED_CHANNELS: ClassVar[tuple] = ()
    JOINTS: ClassVar[tuple] = ()
    OBSERVATION: ClassVar[type] = SwingRate
    SIMULATOR_NODE: ClassVar[str] = ""
    #: True when :meth:`axis_direction_enu` gives the rotor axis (published as ``<name>/axis_direction``)
    SHOWS_AXIS: ClassVar[bool] = False
    #: True when :meth:`stream` is overridden to integrate window by window in bounded memory
    STREAMS: ClassVar[bool] = False
    #: The models (integration paths) the instrument can take: name -> the term kinds that model
    #: carries (:data:`~gyro_instrument.core.effect.TERM_KINDS`: a form a hand-derived equation holds,
    #: or a kind of mechanics whose hook the model sums, so every term of that kind). Empty: one model,
    #: which sums every kind of ``MECHANICS`` through the hooks (nothing to check).
    MODELS: ClassVar[dict] = {}

    @classmethod
    def model_taken(cls, params, effects) -> "str | None":
        """The key of ``MODELS`` a run with the validated ``params`` and the active ``effects`` (name ->
        Effect class or object) takes, chosen from what the effects' terms are (their term kinds), never
        from their names. The default: the first model (None without ``MODELS``)."""
        return next(iter(cls.MODELS), None)

    @classmethod
    def check_params(cls, prefix, params) -> None:
        """Check the validated parameters together (each was range-checked alone).

        Parameters
        ----------
        prefix : str
            Field prefix for messages, ``instruments.<name>``.
        params : dict
            Validated parameters (``PARAMS`` names -> values).

        Raises
        ------
        SceneError
            With the field, the value and the valid range. The default accepts everything.
        """

    @classmethod
    def check_effects(cls, prefix, params, effect_names) -> None:
        """Check the parameters against the instrument's effect list (tuple of names, all in
        ``SUPPORTED_EFFECTS``), e.g. an integrator that needs an effect. Raises SceneError; the
        default refuses an effect the model taken cannot carry (:meth:`check_carried`); an override
        calls it too (``super().check_effects(...)``)."""
        cls.check_carried(prefix, params, effect_names)

    def observation(self) -> Observation:
        """What this instrument measures and how (:class:`~.observation.Observation`), built by
        ``OBSERVATION.of(self)``."""
        return self.OBSERVATION.of(self)

    def directing_model(self) -> "DirectingModel | None":
        """The :class:`DirectingModel` of a gyroscope with a directing line, or None (the default:
        the instrument measures no Earth rate through a swing duration)."""
        return None

    def expected_swing(self) -> "ExpectedSwing | None":
        """What the scene predicts its measured oscillation to be (:class:`ExpectedSwing`: full
        period and amplitude of the measured angle), against which the estimator checks measured
        data before it believes them (``estimators/adequacy.py``); None (the default) when the
        instrument measures no swing or the scene predicts none (e.g. without ``earth_rotation``)."""
        return None

    def chosen_integrator(self, duration_s=None) -> "tuple | None":
        """(integrator, reason) for an instrument with several integrators (an ``integrator``
        parameter whose ``auto`` picks the fast path when the instrument and its effects allow it):
        what a run of ``duration_s`` seconds would use and why (``describe`` shows it). None (the
        default) for an instrument with one integrator."""
        return None

    def axis_direction_enu(self, position) -> "np.ndarray | None":
        """Unit rotor-axis vectors in ENU, shape (m, 3), from the published joint positions
        ``position`` (m, len(JOINTS)), rad; None for an instrument whose axis is not shown
        (``SHOWS_AXIS`` False)."""
        return None

    #: True when :meth:`contact_point_body` gives where the body touches its support (published as
    #: ``<name>/contact_point``, a PointStamped in the body frame ``<name>_body``, per sample)
    SHOWS_CONTACT_POINT: ClassVar[bool] = False

    def contact_point_body(self, columns) -> "np.ndarray | None":
        """Contact points in the body's principal axes from its centre of mass, shape (m, 3), m, from
        simulated ``columns`` (true values, not a measurement); None when ``SHOWS_CONTACT_POINT`` is False."""
        return None

    def pendulum_length_m(self) -> float:
        """For a pendulum (observed by :class:`~.observation.PlanePrecession`): the length l (m) whose ratio to the bob's east and north
        displacements is the measured deflection. Raises NotImplementedError otherwise."""
        raise NotImplementedError(f"{self.type_name} is not a pendulum")

    def measured_angles(self, columns) -> dict:
        """True values of the ``MEASURED_CHANNELS`` from simulated ``columns``: dict name -> array
        (rad), in ``MEASURED_CHANNELS`` order. The default reads the columns of the same names; for a
        pendulum, ``x_east / l`` and ``y_north / l`` (l = :meth:`pendulum_length_m`): the observation's
        :meth:`~.observation.Observation.true_values`."""
        return self.observation().true_values(columns)

    def __init__(self, name, site, params, effects) -> None:
        """``params``: the validated parameters (``PARAMS`` names -> values), read as ``self.p``, a
        frozen dataclass generated once per class (:func:`~gyro_instrument.core.params.params_dataclass`:
        ``self.p.length_m``, and radian views ``self.p.initial_deflection_rad`` of the ``*_deg``
        parameters); ``self.params`` is the same as a dict. ``effects`` maps name -> Effect for the
        effects active on this instrument only (kept in the registry's order, the order their terms
        are summed). ``self.context`` is the :class:`~gyro_instrument.core.effect.EffectContext`
        (without scales) the instrument gives its effects' dynamics hooks."""
        self.name = name
        self.site = site
        self.params = dict(params)
        self.p = params_dataclass(type(self))(**self.params)
        self.effects = canonical_order(dict(effects))
        self.context = EffectContext.of_site(site)

    def effect_context(self, duration_s=None) -> EffectContext:
        """The :class:`~gyro_instrument.core.effect.EffectContext` for this instrument: the site, its g
        and Ω, and, for a run of ``duration_s`` seconds, :meth:`scales` (None without a duration)."""
        if duration_s is None:
            return self.context
        return EffectContext.of_site(self.site, self.scales(duration_s))

    def scales(self, duration_s) -> Scales:
        """Characteristic scales (:class:`~gyro_instrument.core.effect.Scales`) of a run of
        ``duration_s`` seconds, for effect-size estimates (``Effect.relative_size`` reads them from
        :meth:`effect_context`)."""
        raise NotImplementedError

    def simulate(self, t, **options) -> Simulation:
        """Integrate and return a :class:`Simulation` sampled at times ``t`` (s).

        For an instrument that streams (``STREAMS``) this is :meth:`stream` with one block, ``t``
        (one code path: a streamed run's blocks concatenate to this result); others override it."""
        if not self.STREAMS:
            raise NotImplementedError
        t = np.asarray(t, dtype=float)
        return next(iter(self.stream([t], t_end=float(t[-1]), **options)))

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """Integrate block by block: yield one :class:`Simulation` per block of sample times.

        Parameters
        ----------
        blocks : iterable of ndarray
            Consecutive, increasing 1-D arrays of sample times (s); together they are the ``t`` of
            the equivalent one-shot :meth:`simulate` (e.g. :func:`gyro_instrument.core.scene.sample_blocks`).
        **options
            As for :meth:`simulate`; ``t_end`` (s), the last sample time of the run, when the blocks
            do not carry it (:func:`run_span`).

        Yields
        ------
        Simulation
            ``t`` is the block, ``columns`` the channels at those times; the state carries over to
            the next block, so the concatenated blocks equal ``simulate(concatenate(blocks))``.

        This default materialises every block and runs one :meth:`simulate` (correct, memory
        proportional to the run); an instrument that streams (``STREAMS`` True) overrides it so
        memory stays bounded by one block and the first block is yielded before the rest is
        integrated.
        """
        blocks = [np.asarray(b, dtype=float) for b in blocks]
        if not blocks:
            return
        sim = self.simulate(np.concatenate(blocks), **options)
        n = sim.t.size
        i = 0
        for b in blocks:
            j = i + b.size
            cut = {k: (v[i:j] if isinstance(v, np.ndarray) and v.shape[:1] == (n,) else v)
                   for k, v in sim.extra.items()}
            yield Simulation(b, {k: v[i:j] for k, v in sim.columns.items()}, sim.trajectory, cut)
            i = j

    def predictions(self) -> dict:
        """The papers' analytic predictions for this instrument's configuration (dict).

        Predictions describe the model as simulated: an effect the instrument does not list is
        absent from them too (without ``earth_rotation``, n = 0). A ``notes`` entry (list of
        str), present only when needed, says which supported effects are left out and what the
        prediction would be with them.
        """
        return {}

def with_notes(predictions, *notes) -> dict:
    """``predictions`` with a ``notes`` list of the non-None notes (no key when there are none)."""
    notes = [n for n in notes if n]
    if notes:
        predictions["notes"] = notes
    return predictions
