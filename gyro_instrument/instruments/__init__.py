"""Instruments: the kinematics of each instrument and the papers' predictions beside it.

``REGISTRY`` maps the ``type`` used in scene files to the instrument class; everything else the
package needs to know about a type is a declared member of the class (the protocol in
:mod:`.base`). A new instrument is one class and one :func:`register` call (docs/extending.md).
"""

from gyro_instrument.instruments.base import DirectingModel, Instrument
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.instruments.gimbal import GimbalGyroscope
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope
from gyro_instrument.instruments.puiseux import PuiseuxBody

REGISTRY = {}


def register(cls) -> type:
    """Add an :class:`~.base.Instrument` subclass to :data:`REGISTRY` under its ``type_name``
    (usable as a class decorator; returns ``cls``).

    Raises
    ------
    ValueError
        When ``cls`` is not an Instrument subclass, its ``type_name`` is empty or taken, or its
        protocol is incomplete: no ``SIMULATOR_NODE``, ``MEASURED_CHANNELS`` not leading
        ``JOINTS`` (plus ``deflection``, ``azimuth`` for a pendulum, one rotor joint otherwise),
        or a measured channel that is neither a column nor a pendulum deflection.
    """
    if not (isinstance(cls, type) and issubclass(cls, Instrument)):
        raise ValueError(f"register: {cls!r} is not an Instrument subclass")
    name = cls.type_name
    if not name or name in REGISTRY:
        raise ValueError(f"register: instrument type {name!r} is empty or already registered ({', '.join(REGISTRY)})")
    if not cls.SIMULATOR_NODE:
        raise ValueError(f"register: {name} declares no SIMULATOR_NODE")
    m = len(cls.MEASURED_CHANNELS)
    extra = 2 if cls.IS_PENDULUM else 1
    if len(cls.JOINTS) != m + extra:
        raise ValueError(f"register: {name} JOINTS {cls.JOINTS} must be the {m} measured channels' joints and "
                         f"{'deflection, azimuth' if cls.IS_PENDULUM else 'one rotor joint'}")
    columns = {c.name for c in cls.COLUMNS}
    if not cls.IS_PENDULUM and not set(cls.MEASURED_CHANNELS) <= columns:
        raise ValueError(f"register: {name} MEASURED_CHANNELS {cls.MEASURED_CHANNELS} must be columns "
                         f"({', '.join(sorted(columns))})")
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


for _cls in (PlaneGyroscope, SphericalPendulum, CompoundPendulum, FreeGyroscope, PuiseuxBody, GimbalGyroscope):
    register(_cls)

__all__ = ["REGISTRY", "CompoundPendulum", "DirectingModel", "FreeGyroscope", "GimbalGyroscope", "Instrument",
           "PlaneGyroscope", "PuiseuxBody", "SphericalPendulum", "register", "simulator_kinds", "unregister"]
