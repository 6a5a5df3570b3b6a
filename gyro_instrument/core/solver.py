"""One interface of every integration driver, with the shape of scipy's ``OdeSolver``.

scipy's ``scipy/integrate/_ivp/base.py`` separates the method from the driver: an ``OdeSolver``
takes one step at a time (:meth:`~Solver.step`, which calls the method's ``_step_impl``), gives the
dense output of its last step (:meth:`~Solver.dense_output`, ``_dense_output_impl``), counts the
right-hand-side evaluations (``nfev``) and says where it stands (``t``, ``t_old``, ``status``:
``running``, ``finished`` or ``failed``). :class:`Solver` is that shape plus what a resumable run of
this package needs: :meth:`~Solver.advance` — the states at the next block of sample times, the run
resumed where the previous block left it — and the wall and CPU time spent (``wall_time_s``,
``cpu_time_s``, as :class:`~gyro_instrument.core.trajectory.Trajectory` reports them).

Every driver implements it:

* :class:`gyro_instrument.core.integrate.Integration` — scipy's ``OdeSolver`` (DOP853 and the other
  ``solve_ivp`` methods), sampled by :meth:`Solver.sample_steps` (``solve_ivp``'s ``t_eval`` loop: the
  one implementation of that loop in the package);
* :class:`gyro_instrument.core.dop853.ScalarDOP853` — DOP853 on Python floats;
* :class:`gyro_instrument.core.dop853_jit.CompiledRun` — DOP853 compiled with numba;
* :class:`gyro_instrument.core.dop853_fortran.FortranRun` — Hairer's Fortran DOP853, sample to sample;
* :class:`gyro_instrument.core.rigid_body_flow.SplittingRun` — the free top's exact flow composed with
  torque kicks;
* :class:`gyro_instrument.instruments.puiseux.fixed_step.FixedStepRun` — fixed RK8 steps, compiled;
* :class:`gyro_instrument.instruments.pendulum.fast_path.SwingRun` — the pendulum's windows of whole
  swings (parareal on numpy, or compiled swing after swing).

A driver whose loop runs compiled (or in Fortran) keeps its own :meth:`advance`; one that steps in
Python uses :meth:`sample_steps`.
"""

import abc
import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np

from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.trajectory import Trajectory

__all__ = ["RUNNING", "FINISHED", "FAILED", "Solver"]

#: ``status`` values (scipy's ``OdeSolver.status``).
RUNNING, FINISHED, FAILED = "running", "finished", "failed"


class Solver(abc.ABC):
    """A resumable integration of ``dy/dt = f(t, y)`` from ``t0`` toward ``t_end`` (∞: a run with no end).

    Attributes
    ----------
    t0, t_end : float
        Start and end of the run, s (``t_end`` bounds the last step; ``math.inf`` when the steps run
        with no end and never depend on the samples).
    t : float
        Time the solver has reached (the end of its last step), s.
    t_old : float or None
        Start of the last step, s (None before the first step).
    status : str
        ``running``, ``finished`` (``t`` reached ``t_end``) or ``failed`` (a step raised).
    nfev : int
        Right-hand-side evaluations so far (counted by the driver).
    wall_time_s, cpu_time_s : float
        Wall-clock and process CPU time spent in the driver so far, s.
    method : str
        The method's name (a :class:`Trajectory`'s ``method``).
    meta : dict
        Tolerances, step counts, which driver.
    """

    method = ""

    def __init__(self, t0, t_end=math.inf) -> None:
        self.t0 = self.t = float(t0)
        self.t_end = float(t_end)
        self.t_old = None
        self.wall_time_s = self.cpu_time_s = 0.0
        self.meta = {}
        self._failed = False
        self._dense = None          # the last step's dense output (None: not made yet)
        self._clock_depth = 0

    # ------------------------------------------------------------------ scipy's OdeSolver
    @property
    def status(self) -> str:
        """``running``, ``finished`` or ``failed`` (scipy's ``OdeSolver.status``)."""
        if self._failed:
            return FAILED
        return FINISHED if self.t >= self.t_end else RUNNING

    @property
    @abc.abstractmethod
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""

    def step(self) -> None:
        """Take one step (the method's :meth:`_step_impl`); ``t_old`` and ``t`` bound it afterwards.

        Raises
        ------
        IntegrationError
            The step failed (``status`` is then ``failed``), or the run has already finished.
        """
        if self.status != RUNNING:
            raise IntegrationError(f"{self.method}: no step to take, the run is {self.status} at t = {self.t:.6g} s")
        with self.clock():
            self.take_step()

    def take_step(self) -> None:
        """:meth:`step` without its check and clock, for a driver's own loop (inside its clock)."""
        self._dense = None
        try:
            self._step_impl()
        except IntegrationError:
            self._failed = True
            raise

    def dense_output(self) -> Callable:
        """The dense output of the last step: ``sol(t) -> array (n, len(t))`` for times in
        [``t_old``, ``t``] (scipy's ``OdeSolver.dense_output``); made once per step.

        Raises
        ------
        IntegrationError
            No step taken yet.
        """
        if self.t_old is None:
            raise IntegrationError(f"{self.method}: no step taken yet, so no dense output")
        if self._dense is None:
            with self.clock():
                self._dense = self._dense_output_impl()
        return self._dense

    @abc.abstractmethod
    def _step_impl(self) -> None:
        """One step: update ``t_old`` and ``t`` (and the state); raise IntegrationError on failure."""

    @abc.abstractmethod
    def _dense_output_impl(self) -> Callable:
        """The interpolant of the last step, ``sol(t) -> (n, len(t))``."""

    # ------------------------------------------------------------------ resuming
    @abc.abstractmethod
    def advance(self, t, progress=None) -> Trajectory:
        """States at the sample times ``t`` (1-D, increasing, from the previous block's last sample
        on, not past ``t_end``), s: the run resumed where the previous block left it, so blocks
        concatenate to one call over their concatenation. ``progress(t_i)`` (optional) is called as
        the run gets on. Returns a :class:`Trajectory` of this block whose ``nfev``, ``wall_time_s``
        and ``cpu_time_s`` count the whole run so far."""

    def sample_steps(self, t, n, progress=None) -> np.ndarray:
        """The ``t_eval`` loop of ``scipy.integrate.solve_ivp``: step until the samples ``t`` are
        reached, each evaluated with the dense output of the first step that reaches it (the
        samples of a step: ``searchsorted(t, step end, side="right")``), so the steps never depend on
        the samples and a step's dense output is kept for the next block's samples in it. Returns
        the states, shape (``n``, len(t)); ``progress(t)`` after each step."""
        out = np.empty((n, t.size))
        i = 0
        while i < t.size:
            if self.t_old is not None:
                j = int(np.searchsorted(t, self.t, side="right"))
                if j > i:
                    out[:, i:j] = self.dense_output()(t[i:j])
                    i = j
                    continue
            self.take_step()
            if progress is not None:
                progress(self.t)
        return out

    # ------------------------------------------------------------------ clocks and results
    @contextmanager
    def clock(self) -> Iterator[None]:
        """Add the block's wall and CPU time to ``wall_time_s``, ``cpu_time_s`` (the outermost
        block only, so nested calls count once)."""
        self._clock_depth += 1
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self._clock_depth -= 1
            if self._clock_depth == 0:
                self.wall_time_s += time.perf_counter() - w0
                self.cpu_time_s += time.process_time() - c0

    def trajectory(self, t, y) -> Trajectory:
        """A block's :class:`Trajectory`: its samples and this run's counts and times so far, after
        checking that every state is finite.

        Raises
        ------
        IntegrationError
            A non-finite state.
        """
        if not np.all(np.isfinite(y)):
            self._failed = True
            raise IntegrationError(f"{self.method} produced a non-finite state")
        return Trajectory(t, y, self.nfev, self.wall_time_s, self.cpu_time_s, self.method, dict(self.meta))
