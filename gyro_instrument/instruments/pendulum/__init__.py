"""Foucault (spherical) pendulum and compound pendulum: Quet 1853 sec. 2.

* :mod:`.instrument` — :class:`SphericalPendulum`, :class:`CompoundPendulum` (parameters, predictions,
  simulate) and its module docstring: the equations, axes and conventions;
* :mod:`.dynamics` — :class:`~.dynamics.SwingDynamics`: the right-hand sides, the streamed DOP853 runs
  and the fast path (whole swings of a fixed-step RK8, compiled or Newton-parareal);
* :mod:`.columns` — bob states to the published columns (numpy and compiled);
* :mod:`.theory` — Quet's and the exact formulas: periods, apsidal rates, the Binet ellipse.
"""

from gyro_instrument.instruments.pendulum.instrument import (CompoundPendulum, PENDULUM_COLUMNS,
                                                             PENDULUM_JOINTS, PENDULUM_MEASURED,
                                                             SWING_WINDOW_MIN_SAMPLES, SphericalPendulum,
                                                             WINDOW_SAMPLING, apsidal_angle,
                                                             apsidal_rate_exact_rad_s,
                                                             apsidal_rate_from_rest_exact_rad_s,
                                                             apsidal_rate_from_rest_rad_s,
                                                             areal_constant_over_omega0, binet_ellipse,
                                                             min_deflection_for_areal_constant,
                                                             min_deflection_from_rest_rad,
                                                             min_deflection_with_horizontal_rate_rad,
                                                             pendulum_columns, precession_sense,
                                                             quarter_period_s, quarter_period_series_s,
                                                             relative_spin_rad_s,
                                                             release_areal_constant_rad_s)

__all__ = ["CompoundPendulum", "PENDULUM_COLUMNS", "PENDULUM_JOINTS", "PENDULUM_MEASURED",
           "SWING_WINDOW_MIN_SAMPLES", "SphericalPendulum", "WINDOW_SAMPLING", "apsidal_angle",
           "apsidal_rate_exact_rad_s", "apsidal_rate_from_rest_exact_rad_s", "apsidal_rate_from_rest_rad_s",
           "areal_constant_over_omega0", "binet_ellipse", "min_deflection_for_areal_constant",
           "min_deflection_from_rest_rad", "min_deflection_with_horizontal_rate_rad", "pendulum_columns",
           "precession_sense", "quarter_period_s", "quarter_period_series_s", "relative_spin_rad_s",
           "release_areal_constant_rad_s"]
