"""The ship's gyrocompass (issue 39): the instrument (:mod:`.compass`), its equations of motion on a
ship (:mod:`.dynamics`) and its closed forms (:mod:`.theory`)."""

from gyro_instrument.instruments.marine_gyrocompass.compass import MarineGyrocompass

__all__ = ["MarineGyrocompass"]
