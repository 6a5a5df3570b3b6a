"""The real records no one here wrote (``../shared/realdata`` beside the checkout: CI runs a clean clone
of main with ``../shared`` beside it; ``GYRO_REALDATA`` overrides), and how the HEIG-VD tracks are read
(their README: rows ``x,y,date-time``, no header, mm in the camera frame, a 19.9 m pendulum at 46.78° N)."""

import os
from pathlib import Path

REALDATA = Path(os.environ.get("GYRO_REALDATA") or Path(__file__).resolve().parents[2] / "shared" / "realdata")

#: a scene for the HEIG-VD pendulum (its length and site from the records' README)
HEIGVD_SCENE = """\
name: heigvd
site: {latitude_deg: 46.78}
duration_s: 150
sample_rate_hz: 4
effects: {earth_rotation: {}, finite_amplitude: {}}
sensor: {noise_rad: 1.0e-5}
instruments:
  pendulum: {type: spherical_pendulum, length_m: 19.9, initial_deflection_deg: 4.0, initial_azimuth_deg: 90.0}
"""
#: the table options that read a HEIG-VD file as published (docs/formats/csv.md)
HEIGVD_OPTIONS = ["--no-header", "--names", "pendulum.x_east,pendulum.y_north,time_s", "--metres-per-pixel", "0.001"]
