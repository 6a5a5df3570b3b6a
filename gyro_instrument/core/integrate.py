"""Integration driver: method versus driver, as in scipy.integrate's ``OdeSolver``.

:class:`Integration` is a resumable run of ``dy/dt = rhs(t, y)`` (a
:class:`~gyro_instrument.core.solver.Solver`, the interface of every driver): scipy's ``OdeSolver`` (any
``solve_ivp`` method, DOP853 by default) stepped by this driver toward the run's end, each
:meth:`~Integration.advance` returning the states at the next block of sample times from the dense
output of the steps that reach them, so the steps and samples are those of one ``solve_ivp`` call
however the run is cut into blocks. The driver counts right-hand-side evaluations itself and
measures wall and CPU time; every block comes back as a :class:`~gyro_instrument.core.trajectory.Trajectory`.
:func:`integration` picks the driver (``method="DOP853-scalar"``: the same DOP853 on a small state
held in Python floats, :class:`gyro_instrument.core.dop853.ScalarDOP853`); :func:`integrate` is
one block over the whole run. :func:`reporting` and :func:`report` carry a long run's progress to
a caller (the CLI's progress line).
"""

import contextvars
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from gyro_instrument.core.dop853 import ScalarDOP853
from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

__all__ = ["SCALAR_DOP853", "Integration", "Trajectory", "integrate", "integration", "report", "reporting"]


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
        self.reporting = _REPORTER.get() is not None and math.isfinite(self.span)

    def __call__(self, t, y):
        self.n += 1
        if self.reporting and not self.n & 1023:
            report((t - self.t0) / self.span)
        return self.f(t, y)


#: ``integrate``'s method for :func:`gyro_instrument.core.dop853.integrate_dop853_scalar`.
SCALAR_DOP853 = "DOP853-scalar"


def _solver_class(method):
    """The ``scipy.integrate`` OdeSolver class for a ``solve_ivp`` method name (or the class)."""
    import scipy.integrate as si
    if isinstance(method, type):
        return method
    if method not in ("RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"):
        raise ValueError(f"`method` must be one of RK23, RK45, DOP853, Radau, BDF, LSODA (got {method!r})")
    return getattr(si, method)


def _check_samples(t, after, t_end):
    """Sample times of one block: 1-D, strictly increasing, after ``after`` and not past ``t_end``."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise ValueError("`t_eval` must be 1-dimensional.")
    if t.size and (np.any(np.diff(t) <= 0) or (after is not None and t[0] <= after)):
        raise ValueError("Values in `t_eval` are not properly sorted.")
    if t.size and t[-1] > t_end:
        raise IntegrationError(f"sample time {t[-1]!r} s is after the run's end {t_end!r} s")
    return t


class Integration(Solver):
    """A resumable integration of ``dy/dt = rhs(t, y)`` from ``t0`` toward ``t_end``: scipy's
    ``OdeSolver`` behind the :class:`~gyro_instrument.core.solver.Solver` interface.

    :meth:`advance` takes the next block of sample times and returns the states there, carrying
    the solver's exact state (current step, step size, last derivative) to the next block. The
    solver is scipy's ``OdeSolver`` driven step by step with ``t_bound = t_end`` — the loop of
    ``scipy.integrate.solve_ivp`` with ``t_eval`` (:meth:`Solver.sample_steps`): each sample is
    evaluated with the dense output of the first step that reaches it — so the steps and the
    samples are those of one ``solve_ivp`` call over the whole run, bit for bit, however the
    samples are cut into blocks (``tests/test_streaming.py``). Memory is one step and one block,
    whatever ``t_end``; ``t_end = math.inf`` runs the steps with no end.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, y) -> dy/dt``, ``y`` a 1-D array.
    y0 : array_like
        State at ``t0``.
    t0, t_end : float
        Start and end of the run, s (the end bounds the last step, as ``solve_ivp``'s ``t_span``).
    method, rtol, atol, max_step
        As for :func:`integrate`.
    meta : dict, optional
        Entries added to the trajectories' ``meta`` (the gimbal names its ``driver``).

    Raises
    ------
    IntegrationError
        A non-finite initial state; from :meth:`advance`, a failed step or a non-finite state.
    """

    def __init__(self, rhs, y0, t0, t_end, method="DOP853", rtol=1e-10, atol=1e-12, max_step=np.inf,
                 meta=None) -> None:
        super().__init__(t0, t_end)
        self.y0 = np.asarray(y0, dtype=float)
        if not np.all(np.isfinite(self.y0)):
            raise IntegrationError(f"initial state is not finite: {self.y0}")
        self.method = method
        self.meta = {"rtol": rtol, "atol": atol, "nsteps": 0, **(meta or {})}
        self._last = None                       # last sample time returned
        self._counted = _Counted(rhs, self.t0, self.t_end)
        self._solver = None
        if self.t_end != self.t0:
            with self.clock():
                self._solver = _solver_class(method)(self._counted, self.t0, self.y0, self.t_end, vectorized=False,
                                                     rtol=rtol, atol=atol, max_step=max_step)

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far (counted by the driver)."""
        return self._counted.n

    @property
    def y(self) -> np.ndarray:
        """The state at :attr:`t`."""
        return self.y0 if self._solver is None else self._solver.y

    def _step_impl(self):
        solver = self._solver
        t_old = solver.t
        message = solver.step()
        if solver.status == "failed":
            raise IntegrationError(f"{self.method} failed at t = {solver.t:.6g} s: {message}")
        self.t_old, self.t = t_old, float(solver.t)
        self.meta["nsteps"] += 1

    def _dense_output_impl(self):
        return self._solver.dense_output()

    def advance(self, t, progress=None) -> Trajectory:
        """States at the sample times ``t`` (1-D, increasing, after the previous block's, not past
        ``t_end``), s. Returns a :class:`Trajectory` of this block whose ``nfev``, ``wall_time_s``
        and ``cpu_time_s`` count the whole run so far; ``progress(t)`` after each step."""
        if self._solver is None:              # a run of zero length: the initial state throughout
            t = np.asarray(t, dtype=float)
            return Trajectory(t, self.y0[:, None].repeat(t.size, axis=1), 0, 0.0, 0.0, self.method)
        t = _check_samples(t, self._last, self.t_end)
        if t.size:
            self._last = float(t[-1])
        with self.clock():
            y = self.sample_steps(t, self.y0.size, progress)
        return self.trajectory(t, y)


def integration(rhs, y0, t0, t_end, method="DOP853", rtol=1e-10, atol=1e-12, max_step=np.inf) -> "Integration":
    """A resumable integration from ``t0`` to ``t_end`` (:class:`Integration`, or for
    ``method="DOP853-scalar"`` :class:`gyro_instrument.core.dop853.ScalarDOP853`): call
    ``advance(block)`` block after block; the concatenated states equal :func:`integrate` over the
    concatenated blocks, bit for bit."""
    if method == SCALAR_DOP853:
        if max_step != np.inf:
            raise IntegrationError(f"method {SCALAR_DOP853} takes no max_step (got {max_step!r})")
        return ScalarDOP853(rhs, y0, t0, t_end, rtol=rtol, atol=atol)
    return Integration(rhs, y0, t0, t_end, method=method, rtol=rtol, atol=atol, max_step=max_step)


def integrate(rhs, y0, t_eval, method="DOP853", rtol=1e-10, atol=1e-12, max_step=np.inf) -> Trajectory:
    """Integrate ``dy/dt = rhs(t, y)`` from ``t_eval[0]`` and sample at ``t_eval``.

    One block of :func:`integration` from ``t_eval[0]`` to ``t_eval[-1]``: the same steps and
    samples as ``scipy.integrate.solve_ivp(rhs, (t_eval[0], t_eval[-1]), y0, method, t_eval)``.

    Parameters
    ----------
    rhs : callable
        ``rhs(t, y) -> dy/dt`` with ``y`` a 1-D array; for ``method="DOP853-scalar"``
        ``rhs(t, *y) -> tuple`` of floats.
    y0 : array_like
        Initial state at ``t_eval[0]``.
    t_eval : array_like
        Strictly increasing sample times in seconds (at least one).
    method : str
        Any ``solve_ivp`` method name (default DOP853, Hairer's 8(5,3) pair), or
        ``"DOP853-scalar"``: the same method, steps and dense output on Python floats, for a
        small state (no ``max_step``).
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
    ValueError
        Sample times not 1-D or not strictly increasing (as ``solve_ivp``).
    """
    t_eval = np.asarray(t_eval, dtype=float)
    if t_eval.ndim != 1 or t_eval.size == 0:
        raise IntegrationError("t_eval must be a non-empty 1-D array of times")
    return integration(rhs, y0, t_eval[0], t_eval[-1], method, rtol, atol, max_step).advance(t_eval)
