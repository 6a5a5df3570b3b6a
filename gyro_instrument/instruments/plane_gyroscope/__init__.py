"""Directing-plane gyroscope: Quet 1853 sec. 4 §1 (the gyrocompass), and its cone variant.

* :mod:`.instrument` — :class:`PlaneGyroscope` (parameters, predictions, the reduced model and the
  hinge chain, simulate) and its module docstring: axes, angles, conventions.
"""

from gyro_instrument.instruments.plane_gyroscope.instrument import (PlaneGyroscope, plane_normal_enu,
                                                                    swing_duration_small_s)

__all__ = ["PlaneGyroscope", "plane_normal_enu", "swing_duration_small_s"]
