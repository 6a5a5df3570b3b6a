"""Integration driver: method versus driver, as in scipy.integrate's ``OdeSolver``.

``integrate`` runs any right-hand side through ``scipy.integrate.solve_ivp`` (dense output
evaluated at the requested sample times), counts right-hand-side evaluations itself and
measures wall and CPU time, and returns a :class:`Trajectory`. ``method="DOP853-scalar"`` runs
the same DOP853 on a small state held in Python floats (:mod:`gyro_instrument.core.dop853`).
"""

import contextvars
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from gyro_instrument.core.errors import IntegrationError


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


_REPORTER = contextvars.ContextVar("gyro_instrument_progress", default=None)


@contextmanager
def reporting(callback, every_s=0.5) -> Iterator:
    """Within the block, long integrations call ``callback(fraction_done)`` (0 to 1) at most
    every ``every_s`` seconds of wall time (the CLI draws a progress line from it)."""
    token = _REPORTER.set((callback, float(every_s), [time.perf_counter()]))
    try:
        yield
    finally:
        _REPORTER.reset(token)


def report(fraction) -> None:
    """Tell the active :func:`reporting` block (if any) how far a run has got; rate-limited."""
    rep = _REPORTER.get()
    if rep is not None:
        callback, every, last = rep
        now = time.perf_counter()
        if now - last[0] >= every or fraction >= 1.0:
            last[0] = now
            callback(min(max(float(fraction), 0.0), 1.0))


class _Counted:
    __slots__ = ("f", "n", "t0", "span", "reporting")

    def __init__(self, f, t0=0.0, t1=1.0):
        self.f = f
        self.n = 0
        self.t0, self.span = t0, (t1 - t0) or 1.0
        self.reporting = _REPORTER.get() is not None

    def __call__(self, t, y):
        self.n += 1
        if self.reporting and not self.n & 1023:
            report((t - self.t0) / self.span)
        return self.f(t, y)


#: ``integrate``'s method for :func:`gyro_instrument.core.dop853.integrate_dop853_scalar`.
SCALAR_DOP853 = "DOP853-scalar"


def integrate(rhs, y0, t_eval, method="DOP853", rtol=1e-10, atol=1e-12, max_step=np.inf) -> Trajectory:
    """Integrate ``dy/dt = rhs(t, y)`` from ``t_eval[0]`` and sample at ``t_eval``.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, y) -> dy/dt`` with ``y`` a 1-D array; for ``method="DOP853-scalar"``
        ``rhs(t, *y) -> tuple`` of floats.
    y0 : array_like
        Initial state at ``t_eval[0]``.
    t_eval : array_like
        Increasing sample times in seconds (at least one).
    method : str
        Any ``solve_ivp`` method name (default DOP853, Hairer's 8(5,3) pair), or
        ``"DOP853-scalar"``: the same method, steps and dense output on Python floats, for a
        small state and increasing ``t_eval`` (no ``max_step``, no progress reports).
    rtol, atol : float
        Tolerances passed to the solver.
    max_step : float
        Largest step in seconds.

    Returns
    -------
    Trajectory

    Raises
    ------
    IntegrationError
        If the solver fails or the state becomes non-finite.
    """
    if method == SCALAR_DOP853:
        if max_step != np.inf:
            raise IntegrationError(f"method {SCALAR_DOP853} takes no max_step (got {max_step!r})")
        from gyro_instrument.core.dop853 import integrate_dop853_scalar   # it imports Trajectory from here
        return integrate_dop853_scalar(rhs, y0, t_eval, rtol=rtol, atol=atol)
    t_eval = np.asarray(t_eval, dtype=float)
    y0 = np.asarray(y0, dtype=float)
    if t_eval.ndim != 1 or t_eval.size == 0:
        raise IntegrationError("t_eval must be a non-empty 1-D array of times")
    if not np.all(np.isfinite(y0)):
        raise IntegrationError(f"initial state is not finite: {y0}")
    counted = _Counted(rhs, float(t_eval[0]), float(t_eval[-1]))
    w0, c0 = time.perf_counter(), time.process_time()
    if t_eval.size == 1 or t_eval[-1] == t_eval[0]:
        y = y0[:, None].repeat(t_eval.size, axis=1)
        return Trajectory(t_eval, y, 0, 0.0, 0.0, method)
    sol = solve_ivp(counted, (t_eval[0], t_eval[-1]), y0, method=method, t_eval=t_eval,
                    rtol=rtol, atol=atol, max_step=max_step)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    if sol.status < 0:
        raise IntegrationError(f"{method} failed at t = {sol.t[-1] if len(sol.t) else t_eval[0]:.6g} s: "
                               f"{sol.message}")
    if not np.all(np.isfinite(sol.y)):
        raise IntegrationError(f"{method} produced a non-finite state")
    return Trajectory(sol.t, sol.y, counted.n, wall, cpu, method,
                      {"rtol": rtol, "atol": atol, "nsteps": int(getattr(sol, "nfev", 0))})
