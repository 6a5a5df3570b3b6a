"""Instruments: the kinematics of each instrument and the papers' predictions beside it.

``REGISTRY`` maps the ``type`` used in scene files to the instrument class; everything else the
package needs to know about a type is a declared member of the class (the protocol in
:mod:`.base`). A new instrument is one class, found through an entry point of the group
``gyro_instrument.instruments`` (:mod:`gyro_instrument.core.plugins`; the shipped ones are entry points
of it too, setup.py) or registered with :func:`register` (docs/extending.md).
"""

from gyro_instrument.core import plugins
from gyro_instrument.instruments import measurement
from gyro_instrument.instruments.base import DirectingModel, Instrument
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.instruments.gimbal import GimbalGyroscope
from gyro_instrument.instruments.marine_gyrocompass import MarineGyrocompass
from gyro_instrument.instruments.observation import (JointLayout, Observation, PlanePrecession, RotorObservation,
                                                     SwingRate)
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope
from gyro_instrument.instruments.puiseux import PuiseuxBody
from gyro_instrument.instruments.rate_gyro import RateGyro

REGISTRY = {}


def register(cls) -> type:
    """Add an :class:`~.base.Instrument` subclass to :data:`REGISTRY` under its ``type_name``
    (usable as a class decorator; returns ``cls``).

    Raises
    ------
    ValueError
        When ``cls`` is not an Instrument subclass, its ``type_name`` is empty or taken, or its
        protocol is incomplete: no ``SIMULATOR_NODE``, ``JOINTS`` that do not fit its observation's
        joint layout (:meth:`~.observation.Observation.layout_of`: the measured channels, the joints
        derived from them, a rotor joint if it has one), a measured channel whose true value is not a
        column, or a measurement kind its observation names that is not registered or not complete
        (:func:`.measurement.observation_problem`).
    """
    if not (isinstance(cls, type) and issubclass(cls, Instrument)):
        raise ValueError(f"register: {cls!r} is not an Instrument subclass")
    name = cls.type_name
    if not name or name in REGISTRY:
        raise ValueError(f"register: instrument type {name!r} is empty or already registered ({', '.join(REGISTRY)})")
    if not cls.SIMULATOR_NODE:
        raise ValueError(f"register: {name} declares no SIMULATOR_NODE")
    obs = cls.OBSERVATION
    if not (isinstance(obs, type) and issubclass(obs, Observation)):
        raise ValueError(f"register: {name} OBSERVATION {obs!r} is not an Observation subclass")
    try:
        obs.layout_of(cls)
    except ValueError as exc:
        raise ValueError(f"register: {name} {exc} ({obs.__name__})") from None
    columns = {c.name for c in cls.COLUMNS}
    if not set(obs.true_columns(cls)) <= columns:
        raise ValueError(f"register: {name} MEASURED_CHANNELS {cls.MEASURED_CHANNELS} are read from the columns "
                         f"{obs.true_columns(cls)} ({obs.__name__}), which must be columns ({', '.join(sorted(columns))})")
    # the kinds' engines are in the estimator layer: checked here once loaded, else when they load
    problem = measurement.observation_problem(obs) if measurement.loaded() else None
    if problem:
        raise ValueError(f"register: {name} {problem}")
    REGISTRY[name] = cls
    return cls


def unregister(type_name) -> None:
    """Remove the instrument type ``type_name`` from :data:`REGISTRY` (for tests that register their own)."""
    REGISTRY.pop(type_name, None)


def simulator_kinds() -> dict:
    """ROS simulator node name -> tuple of the instrument types it hosts (``SIMULATOR_NODE``), in
    registry order."""
    out = {}
    for name, cls in REGISTRY.items():
        out.setdefault(cls.SIMULATOR_NODE, ())
        out[cls.SIMULATOR_NODE] += (name,)
    return out


def _check_registered() -> None:
    """Once the measurement kinds are loaded (:func:`.measurement.load`): every type registered before
    is checked as :func:`register` checks a later one; a plug-in whose observation names a kind that
    is not registered or not complete is unregistered, with one line in
    :data:`gyro_instrument.core.plugins.REFUSED` (a shipped one raises ValueError)."""
    for name, cls in list(REGISTRY.items()):
        problem = measurement.observation_problem(cls.OBSERVATION)
        if problem is None:
            continue
        if cls in SHIPPED:
            raise ValueError(f"register: {name} {problem}")
        unregister(name)
        line = f"plug-in instrument {name} ({cls.__module__}.{cls.__qualname__}) refused: {problem}"
        if line not in plugins.REFUSED:
            plugins.REFUSED.append(line)


#: The shipped instrument types, in registry order (also entry points of ``gyro_instrument.instruments``).
SHIPPED = (PlaneGyroscope, SphericalPendulum, CompoundPendulum, FreeGyroscope, PuiseuxBody, GimbalGyroscope, RateGyro,
           MarineGyrocompass)
plugins.discover("instruments", register, lambda c: REGISTRY.get(getattr(c, "type_name", None)) is c, SHIPPED,
                 key="type_name")
measurement.on_load(_check_registered)

__all__ = ["REGISTRY", "CompoundPendulum", "DirectingModel", "FreeGyroscope", "GimbalGyroscope", "Instrument",
           "JointLayout", "MarineGyrocompass", "Observation", "PlaneGyroscope", "PlanePrecession", "PuiseuxBody", "RateGyro",
           "RotorObservation", "SphericalPendulum", "SwingRate", "register", "simulator_kinds", "unregister"]
