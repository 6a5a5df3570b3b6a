"""Angle helpers shared by the instruments."""

import numpy as np

TWO_PI = 2.0 * np.pi


def unwrap(angle) -> np.ndarray:
    """Continuous angle from one wrapped to (−π, π]: removes the 2π jumps between samples.

    Same result as ``numpy.unwrap`` for sampled motion (steps below π between samples), in
    fewer passes over the data: a day of a 20 Hz pendulum is 1.7 million samples.
    """
    angle = np.asarray(angle, dtype=float)
    if angle.size < 2:
        return angle.copy()
    turns = np.rint(np.diff(angle) / TWO_PI)
    out = angle.copy()
    if turns.any():
        out[1:] -= TWO_PI * np.cumsum(turns)
    return out
