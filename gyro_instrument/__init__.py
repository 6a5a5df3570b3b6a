"""gyro_instrument: a gyrocompass and Foucault pendulum on the rotating Earth.

The simulation core (``core``, ``effects``, ``instruments``) is pure numpy/scipy and never
imports rclpy; ``gyro_instrument.ros`` holds the thin ROS 2 nodes over it.

BLAS runs single-threaded unless the environment says otherwise (set ``OPENBLAS_NUM_THREADS``
etc. before importing numpy to choose): the linear algebra here is on matrices a few columns
wide, where OpenBLAS's busy-waiting threads only burn the other core (the estimator's fits took
twice the CPU for the same wall time); parallelism is by processes
(:mod:`gyro_instrument.core.parallel`).
"""

import os as _os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"
