"""Instruments: the kinematics of each instrument and the papers' predictions beside it.

``REGISTRY`` maps the ``type`` used in scene files to the instrument class.
"""

from gyro_instrument.core.memory import CHANNELS
from gyro_instrument.instruments.free_gyroscope import FreeGyroscope
from gyro_instrument.instruments.gimbal import GimbalGyroscope
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum
from gyro_instrument.instruments.plane_gyroscope import PlaneGyroscope
from gyro_instrument.instruments.puiseux import PuiseuxBody

REGISTRY = {cls.type_name: cls for cls in (PlaneGyroscope, SphericalPendulum, CompoundPendulum, FreeGyroscope, PuiseuxBody, GimbalGyroscope)}

# output channels per type, for the core's up-front memory check (the core knows no instrument)
CHANNELS.update({name: len(cls.COLUMNS) for name, cls in REGISTRY.items()})

__all__ = ["REGISTRY", "CompoundPendulum", "FreeGyroscope", "GimbalGyroscope", "PlaneGyroscope", "PuiseuxBody", "SphericalPendulum"]
