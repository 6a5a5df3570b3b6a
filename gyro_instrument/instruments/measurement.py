"""Measurement kinds: what a record measures, declared in one place (issue 35 item 1).

An observation (:mod:`.observation`) names the kinds its record gives: ``MEASUREMENT`` (the kind
whose entry is the instrument's entry in the estimate) and ``ALSO_MEASURES`` (kinds measured beside
it from the same record, each under its own key of the entry). A kind is one
:class:`MeasurementKind` subclass declaring, together,

==================  ==================================================================================
``name``            the string observations name it by (``MEASUREMENT``, ``ALSO_MEASURES``)
``summary``         one line: what it measures
``RATE``            True: :meth:`~MeasurementKind.estimate` gives an Earth-rate component (a
                    ``RateMeasurement``, rad/s) that the latitude and the Earth rate combine; False:
                    it gives a block of its own (``BLOCK``)
``BLOCK``           for ``RATE`` False: the key of its block in the instrument's entry and in the
                    estimate (the estimate's block is :meth:`~MeasurementKind.combine` of the
                    instruments'), e.g. ``north``
``UNIT``            the unit of the measured quantity (``rad/s``, ``rad``)
``CLASSIC``         its role in Quet's classical methods (``gyro``: item 9, eq. 10; ``pendulum``), or None
``LIVE``            what the estimator node publishes while the record grows (``heading``: a
                    ``sensor_msgs/Imu`` on ``<instrument>/heading`` and ``$HEHDT``), or None
``estimate``        the estimator engine: ``(observation, record, corrections, checks, sensor) ->
                    (entry or block, RateMeasurement or None)``
``probe``           the planner's model of an instrument: ``(scene, observation) -> (model or None,
                    reason)``, the model carrying ``kind`` (this kind's name) and ``min_record_s``
``bound``           its Fisher information: ``(model, T, sensor) -> (1-σ Cramér–Rao bound over T s, how)``
``tracker``         the live tracker of the estimator node, ``(observation, scene, companions) ->
                    tracker or None`` (None: nothing live; see :class:`LiveTracker`)
``combine``         for ``RATE`` False: the estimate's ``BLOCK`` from the instruments' blocks
==================  ==================================================================================

Optional: ``TARGET`` and :meth:`~MeasurementKind.plan` (a block kind's ``plan --target``: by default
the shortest T whose ``bound`` meets it), :meth:`~MeasurementKind.plan_entry` (its entry in the plan),
:meth:`~MeasurementKind.plan_lines` (the text of a target its own ``plan`` made, with its ``kind``),
:meth:`~MeasurementKind.bench` (its own study in ``gyro-instrument bench``),
:meth:`~MeasurementKind.warm` (what its estimate loads on first use, loaded when the estimator node
starts).

:func:`register_kind` refuses a kind that leaves any of them out (one line naming what is missing);
registering an instrument (:func:`gyro_instrument.instruments.register`) refuses one whose
observation names a kind that is not registered or not complete (:func:`observation_problem`).
:func:`measured` is the one predicate of which instruments are measured: ``estimate``, the live
estimate of ``run``, the estimator node and ``replay`` all ask it.

The shipped kinds are in :mod:`gyro_instrument.estimators.kinds`; a package adds one with an entry
point of the group ``gyro_instrument.measurements`` (:mod:`gyro_instrument.core.plugins`). The
registry is filled on first use (the kinds' engines live in the estimator layer, above this one).
"""

from typing import ClassVar

from gyro_instrument.core import plugins

#: The shipped kinds, in order (also entry points of ``gyro_instrument.measurements``, setup.py).
SHIPPED = ("gyro_instrument.estimators.kinds:SwingKind", "gyro_instrument.estimators.kinds:PlaneKind",
           "gyro_instrument.estimators.kinds:AzimuthKind", "gyro_instrument.estimators.rate_gyro_kind:RateAzimuthKind",
           "gyro_instrument.estimators.compass_kind:CompassKind")

#: name -> the kind (an instance of its class), in registration order.
KINDS = {}
_LOADED = []
_ON_LOAD = []            # checks run by load() (on_load)


class LiveTracker:
    """What a kind's live tracker offers the estimator node (the protocol; subclassing is optional).

    Attributes
    ----------
    reads : tuple of str
        The instruments whose joint states it is given (its own first, then its companions').
    """

    reads: tuple = ()

    def every_s_of(self, name) -> float:
        """Seconds of ``name``'s record between two looks (the node gives it the tail at most that often)."""
        return 1.0

    def window_s_of(self, name) -> float:
        """The tail of ``name``'s record it wants (s; ``math.inf``: the whole record so far)."""
        return 1.0

    def update(self, name, rec) -> tuple | None:
        """Take the tail ``rec`` (``t`` s and the record keys) of instrument ``name``; returns the
        live value when there is a new one (for ``LIVE = 'heading'``: ``(mount azimuth rad, σ rad)``),
        else None. The node keeps the last value and publishes it at
        :data:`~gyro_instrument.estimators.north.heading.HEADING_RATE_HZ` of sim time (every sample when the
        instrument samples slower), stamped with the instrument's latest sample."""
        return None

    def final(self, entry) -> tuple | None:
        """The live value from the final estimate's entry of the instrument (None parts when it has none)."""
        return None

    def restarted(self) -> "LiveTracker":
        """A fresh tracker with the same settings (the run restarted)."""
        return self


class MeasurementKind:
    """One measurement kind (module docstring): subclass it, set the class members, implement the
    four methods, and register the class (an entry point of ``gyro_instrument.measurements``, or
    :func:`register_kind`)."""

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    RATE: ClassVar[bool | None] = None
    BLOCK: ClassVar[str | None] = None
    UNIT: ClassVar[str] = ""
    CLASSIC: ClassVar[str | None] = None
    LIVE: ClassVar[str | None] = None
    #: The ``plan --target`` quantity a block kind serves (``azimuth``), None for a rate kind (its
    #: bounds combine into the latitude and the Earth rate).
    TARGET: ClassVar[str | None] = None

    #: The members every kind declares (methods: overridden); ``BLOCK`` and ``combine`` too when ``RATE`` is False.
    REQUIRED: ClassVar[tuple] = ("name", "summary", "RATE", "UNIT", "estimate", "probe", "bound", "tracker")
    #: What the estimator node can publish live (the ROS side knows each: ``heading`` is an Imu and HDT).
    LIVE_OUTPUTS: ClassVar[tuple] = ("heading",)

    def estimate(self, obs, rec, corrections, checks, sensor) -> tuple:
        """(the instrument's entry or the kind's block, RateMeasurement or None); appends to ``checks``."""
        raise NotImplementedError

    def probe(self, scene, obs) -> tuple:
        """(the planner's model of ``obs`` or None, the reason when None)."""
        raise NotImplementedError

    def bound(self, model, T, sensor) -> tuple:
        """(1-σ Cramér–Rao bound of the measured quantity over T s, in ``UNIT``, how it was computed)."""
        raise NotImplementedError

    def tracker(self, obs, scene, companions) -> "LiveTracker | None":
        """A :class:`LiveTracker` for ``obs`` (``companions``: record key -> instrument name present in
        the run), or None: nothing published before the final estimate."""
        raise NotImplementedError

    def combine(self, blocks) -> dict:
        """The estimate's ``BLOCK`` from the instruments' blocks (``RATE`` False only)."""
        raise NotImplementedError

    def plan_entry(self, model) -> dict:
        """The plan's entry of one instrument's model (``plan --json``); a default from the model's
        ``kind``, ``min_record_s`` and ``value``."""
        return {"kind": self.name, "measures": self.summary, "min_record_s": getattr(model, "min_record_s", None)}

    def plan(self, scene_arg, overrides, models, skipped, sensor, name, value, si, floor=True) -> dict | None:
        """The plan of a ``TARGET`` quantity from this kind's models (None: the planner's generic plan,
        the shortest T whose :meth:`bound` meets the target)."""
        return None

    def plan_lines(self, entry) -> list | None:
        """The ``plan`` text of a target entry this kind's :meth:`plan` made (the entry's ``kind`` is
        this kind's name): lines without newlines, or None: the command's own printing."""
        return None

    def warm(self) -> None:
        """Load what :meth:`estimate` needs that costs time on first use in a new process (imports,
        compiled kernels from numba's cache): the estimator node calls it at start-up, before it
        subscribes, so that the estimate that follows the last sample does not pay for it (issue 37
        item 6). Nothing by default."""

    def bench(self, out_dir, quick, write, progress, reference_rows) -> list:
        """Its own study for ``gyro-instrument bench``: CSVs written into ``out_dir`` through the bench's
        atomic ``write(path, header, rows)``, ``progress(text)`` as it goes, fewer seeds with ``quick``;
        returns the summary's lines (``reference_rows``: the bench's north rows of the gyrotheodolite,
        to compare with). [] by default: no study of its own."""
        return []

    @classmethod
    def missing(cls) -> list:
        """The members this kind leaves out (module docstring), [] when complete."""
        need = cls.REQUIRED + (("BLOCK", "combine") if cls.RATE is False else ())
        out = []
        for member in need:
            value = getattr(cls, member, None)
            if callable(getattr(MeasurementKind, member, None)):
                if value is getattr(MeasurementKind, member):
                    out.append(member)
            elif value is None or value == "":
                out.append(member)
        if cls.LIVE is not None and cls.LIVE not in cls.LIVE_OUTPUTS:
            out.append(f"LIVE {cls.LIVE!r} (one of {', '.join(cls.LIVE_OUTPUTS)} or None)")
        return out


def register_kind(cls) -> type:
    """Add a :class:`MeasurementKind` subclass to :data:`KINDS` under its ``name`` (returns ``cls``).

    Raises
    ------
    ValueError
        When ``cls`` is not a MeasurementKind subclass, its ``name`` is taken, or it leaves a member
        out (one line naming them).
    """
    if not (isinstance(cls, type) and issubclass(cls, MeasurementKind)):
        raise ValueError(f"register: {cls!r} is not a MeasurementKind subclass")
    missing = cls.missing()
    label = cls.name or cls.__name__
    if missing:
        raise ValueError(f"register: measurement kind {label} ({cls.__module__}.{cls.__qualname__}) is incomplete: "
                         f"missing {', '.join(missing)}")
    if cls.name in KINDS:
        raise ValueError(f"register: measurement kind name {cls.name!r} is already registered ({', '.join(KINDS)})")
    KINDS[cls.name] = cls()
    return cls


def unregister_kind(name) -> None:
    """Remove the kind ``name`` from :data:`KINDS` (for tests that register their own)."""
    KINDS.pop(name, None)


def load() -> dict:
    """:data:`KINDS`, filled on first call: the shipped kinds, then the entry points of
    ``gyro_instrument.measurements`` (:func:`gyro_instrument.core.plugins.discover`). Then every
    instrument type registered before (at import, when the kinds' engines could not be imported yet)
    is checked as :func:`gyro_instrument.instruments.register` checks a later one: a plug-in whose
    observation names a kind that is not registered or not complete is unregistered, with one line in
    :data:`gyro_instrument.core.plugins.REFUSED`."""
    if not _LOADED:
        _LOADED.append(True)
        plugins.discover("measurements", register_kind, lambda c: type(KINDS.get(getattr(c, "name", None))) is c,
                         SHIPPED)
        for check in _ON_LOAD:
            check()
    return KINDS


def loaded() -> bool:
    """True once :func:`load` has run (a registration can then check its kinds at once)."""
    return bool(_LOADED)


def on_load(check) -> None:
    """Call ``check()`` when :func:`load` has filled :data:`KINDS` (at once if it has): the instrument
    registry (:mod:`gyro_instrument.instruments`) checks the types registered before the kinds were
    loaded this way, so that this module does not import the package that imports it."""
    _ON_LOAD.append(check)
    if _LOADED:
        check()


def kind(name) -> MeasurementKind | None:
    """The registered kind ``name``, or None."""
    return load().get(name)


def declared_kinds(obs) -> tuple:
    """The kinds an observation (or observation class) declares: ``MEASUREMENT`` (when not None), then
    ``ALSO_MEASURES``."""
    return tuple(k for k in (obs.MEASUREMENT,) + tuple(obs.ALSO_MEASURES) if k is not None)


def observation_problem(obs_cls) -> str | None:
    """Why the observation class ``obs_cls`` cannot be measured (a kind it names is not registered or
    incomplete), or None."""
    registry = load()
    for name in declared_kinds(obs_cls):
        found = registry.get(name)
        if found is None:
            return (f"{obs_cls.__name__} names the measurement kind {name!r}, which is not registered "
                    f"({', '.join(registry) or 'none'}); declare it (entry point gyro_instrument.measurements)")
        missing = type(found).missing()
        if missing:
            return f"{obs_cls.__name__}'s measurement kind {name!r} is incomplete: missing {', '.join(missing)}"
    return None


def measured(inst) -> bool:
    """True when the estimator measures the instrument ``inst``: its observation declares at least one
    registered kind. The one predicate of ``estimate``, ``run``, the estimator node and ``replay``."""
    registry = load()
    return any(k in registry for k in declared_kinds(inst.observation()))


def rate_kind(name) -> bool:
    """True when the kind ``name`` is registered and gives an Earth-rate component (``RATE``)."""
    found = kind(name)
    return found is not None and bool(found.RATE)
