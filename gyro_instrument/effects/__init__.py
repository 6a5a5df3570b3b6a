"""Physical effects, one module each. Effects never import each other or any instrument.

``REGISTRY`` maps the name used in scene files to the effect class.
"""

from gyro_instrument.effects.air_drag import AirDrag
from gyro_instrument.effects.centrifugal import Centrifugal
from gyro_instrument.effects.earth_rotation import EarthRotation
from gyro_instrument.effects.finite_amplitude import FiniteAmplitude
from gyro_instrument.effects.pivot_damping import PivotDamping
from gyro_instrument.effects.ring_inertia import RingInertia
from gyro_instrument.effects.spin_decay import SpinDecay

REGISTRY = {cls.name: cls for cls in
            (EarthRotation, Centrifugal, FiniteAmplitude, RingInertia, SpinDecay, PivotDamping, AirDrag)}

__all__ = ["REGISTRY", "AirDrag", "Centrifugal", "EarthRotation", "FiniteAmplitude", "PivotDamping",
           "RingInertia", "SpinDecay"]
