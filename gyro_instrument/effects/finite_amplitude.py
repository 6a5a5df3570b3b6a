"""Finite amplitude: exact trigonometry instead of the small-angle (linear) model.

With this effect an instrument keeps sin u in its restoring torque (Quet sec. 4 §1 item 6:
"grandes et petites, suivent les mêmes lois que celles des pendules"); without it, the
linearised model is integrated (sin u → u, the pendulum's Binet ellipse). The one-swing
duration grows as (2/π) K(sin(a/2)) ≈ 1 + a²/16 (pendulum law; sec. 2 eq. 42).
"""

import math
from collections.abc import Callable

import numpy as np

from scipy.special import ellipk

from gyro_instrument.core.effect import CONSERVATIVE, RESTORING_LAW, SINE_LAW, Effect


class FiniteAmplitude(Effect):
    """Exact trigonometric restoring law (otherwise the small-angle model)."""

    name = "finite_amplitude"
    summary = "exact trigonometry (sin u) instead of the small-angle model (u)"
    MECHANICS = frozenset({RESTORING_LAW})
    TERMS = frozenset({SINE_LAW})
    CAPABILITIES = frozenset({CONSERVATIVE})   # the law of a potential (1 − cos u)

    def relative_size(self, ctx) -> tuple:
        a = ctx.scales.amplitude_rad
        return a * a / 16.0, "a^2 / 16 (relative period change, sec. 2 eq. 42)"

    def restoring_law(self, ctx) -> Callable:
        """``numpy.sin``: the exact restoring law (its absence means the small-angle law, u)."""
        return np.sin


def finite_amplitude_factor(amplitude_rad) -> float | np.ndarray:
    """(2/π) K(sin(a/2)): swing duration at amplitude a over the small-amplitude one (pendulum law,
    Quet sec. 4 §1 item 6; ≈ 1 + a²/16). Elementwise for an array."""
    if np.ndim(amplitude_rad):
        return 2.0 / math.pi * ellipk(np.sin(np.abs(np.asarray(amplitude_rad, dtype=float)) / 2.0) ** 2)
    m = math.sin(abs(amplitude_rad) / 2.0) ** 2
    return 2.0 / math.pi * float(ellipk(m))
