"""Two-ring gimbal gyroscope: Quet 1853, sec. 4 §III–V.

* :mod:`.theory` — Quet's formulas: T, T', T'', T''', the locked-ring inertia, the exact
  small-oscillation constants, the free gimbal's mass matrix, the integrals (12), (13), §V (2);
* :mod:`.instrument` — :class:`GimbalGyroscope` (geometry, configurations, the hinge-chain model,
  parameter checks, predictions, simulate) and its module docstring: axes, angles, conventions.
"""

from gyro_instrument.instruments.gimbal.instrument import (CONFIGURATIONS, DEFAULT_SWING_DEG,
                                                           MAX_MASS_MATRIX_CONDITION, MIN_INERTIA_RATIO, OUTER_AXES,
                                                           GimbalGyroscope, outer_axis_direction_enu,
                                                           scaled_condition)
from gyro_instrument.instruments.gimbal.theory import (axial_momentum, free_mass_matrix, locked_swing_constant,
                                                       outer_fixed_swing_constant, quet_energy, quet_swing_durations_s,
                                                       spin_invariant, swing_duration_s, swing_inertias_kg_m2)

__all__ = ["CONFIGURATIONS", "DEFAULT_SWING_DEG", "MAX_MASS_MATRIX_CONDITION", "MIN_INERTIA_RATIO", "OUTER_AXES",
           "GimbalGyroscope", "axial_momentum", "free_mass_matrix", "locked_swing_constant",
           "outer_axis_direction_enu", "outer_fixed_swing_constant", "quet_energy", "quet_swing_durations_s",
           "scaled_condition", "spin_invariant", "swing_duration_s", "swing_inertias_kg_m2"]
