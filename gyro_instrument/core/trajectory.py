"""The result of an integration (:func:`gyro_instrument.core.integrate.integrate` and the
resumable drivers' ``advance``): sample times, states, counted right-hand-side evaluations and the
time they took. Its own module so that every driver (:mod:`gyro_instrument.core.integrate`,
:mod:`gyro_instrument.core.dop853`) can return it without importing another.
"""

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Trajectory:
    """Result of an integration.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Sample times in seconds.
    y : ndarray, shape (n, m)
        State at the sample times.
    nfev : int
        Number of right-hand-side evaluations (counted by the driver).
    wall_time_s, cpu_time_s : float
        Elapsed wall-clock and process CPU time of the integration.
    method : str
        Integrator name.
    meta : dict
        Free-form information (tolerances, step counts).
    """

    t: np.ndarray
    y: np.ndarray
    nfev: int
    wall_time_s: float
    cpu_time_s: float
    method: str
    meta: dict = field(default_factory=dict)
