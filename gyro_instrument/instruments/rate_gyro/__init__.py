"""A single-axis rate gyroscope on a turntable (indexer or carousel): a north finder (issue 35 item 3).

* :mod:`.instrument` — :class:`RateGyro` (parameters, the index schedule, simulate) and its module
  docstring: what the sensor reads;
* :mod:`.sensor` — the sensor's error model (turn-on bias, Gauss–Markov bias instability, angle random
  walk) and its datasheet units.
"""

from gyro_instrument.instruments.rate_gyro.instrument import (RATE_AZIMUTH, RateGyro, RateGyroObservation,
                                                              schedule)

__all__ = ["RATE_AZIMUTH", "RateGyro", "RateGyroObservation", "schedule"]
