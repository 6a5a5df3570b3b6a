"""Free gyroscope: a body of revolution free about its fixed centre of mass, Quet 1853 sec. 4 §II.

* :mod:`.instrument` — :class:`FreeGyroscope` (parameters, predictions, the closed form's constants)
  and its module docstring: the model, the numerical path, conventions;
* :mod:`.runs` — :class:`~.runs.FreeGyroscopeRuns`: the integrator choice, the splitting's step, the
  drivers and the streamed run;
* :mod:`.theory` — the geometry (axes, equatorial basis) and the closed form's helpers.
"""

from gyro_instrument.instruments.free_gyroscope.instrument import (FreeGyroscope, angle_between,
                                                                   axis_from_alt_az, axis_relative_to_earth,
                                                                   body_frame, equatorial_basis)

__all__ = ["FreeGyroscope", "angle_between", "axis_from_alt_az", "axis_relative_to_earth", "body_frame",
           "equatorial_basis"]
