"""Hairer's Fortran DOP853 (``scipy.integrate.ode(...).set_integrator("dop853")``) from sample to
sample, behind the :class:`~gyro_instrument.core.solver.Solver` interface.

For a right-hand side on Python floats whose motion takes tens of steps per sample (the free
gimbal's nutation), the stage arithmetic in Fortran halves the CPU of the Python-float driver of
:mod:`gyro_instrument.core.dop853` (``gimbal_work_precision.csv``); only the right-hand side runs
in Python. Each sample is reached by one call of the Fortran driver from the previous one, so the
states depend on the sample times only, never on how they are cut into blocks. Hairer's code:
E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer
1993, sec. II.10, and dop853.f (http://www.unige.ch/~hairer/software.html).
"""

import time
import warnings

import numpy as np

from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

#: Hairer's DOP853 return codes (IDID) on failure.
DOP853_FAILURES = {-1: "input is not consistent", -2: "larger nsteps is needed", -3: "step size becomes too small",
                   -4: "problem is probably stiff (interrupted)"}


class FortranRun(Solver):
    """A resumable run of ``rhs(t, *y) -> tuple`` through Hairer's Fortran DOP853, from sample to sample.

    Each sample time is reached by one call of the driver from the previous sample (its last step
    lands on the sample; each call starts from the last step length that no sample cut short, or
    Hairer's initial-step guess), so the states depend on the sample times only — never on how they
    are cut into blocks: :meth:`advance` over consecutive blocks gives the one-shot run bit for bit,
    in memory of one block. Method and error control are those of ``solve_ivp``'s DOP853 (the same
    8(5,3) pair and error norm); the steps are not (they stop at the samples). :meth:`step` takes one
    step of the driver (stopped by its ``solout``); the Fortran code's own interpolant (CONTD8) is not
    reachable through scipy, so :meth:`dense_output` is the cubic Hermite interpolant on the step's
    ends (third order; two evaluations of the right-hand side).

    Parameters
    ----------
    rhs : callable
        ``rhs(t, *y) -> tuple`` (the gimbal's :func:`~gyro_instrument.instruments.gimbal.dynamics.closed_form_rhs`);
        an ``rhs.on_array(t, y)`` taking the driver's array is called instead when present (one Python
        frame less per evaluation).
    y0 : array_like
        State at ``t0``.
    t0 : float
        Start, s.
    rtol, atol : float
        DOP853's tolerances.

    Raises
    ------
    IntegrationError
        From :meth:`advance` or :meth:`step`: the driver's failure (its message: step size too small,
        probably stiff...) or a non-finite state.
    """

    #: Most steps the driver may take between two samples (its ``nsteps``; a 32-bit integer).
    MAX_STEPS_PER_SAMPLE = 2 ** 31 - 1
    method = "DOP853"

    def __init__(self, rhs, y0, t0, rtol, atol) -> None:
        from scipy.integrate import ode  # noqa: PLC0415 - lazy (scipy.integrate's import cost)

        super().__init__(t0)
        self.rhs = rhs
        count = self._count = [0]

        def counted(t, y):
            count[0] += 1
            return rhs(t, *y.tolist())
        # The free rings' RHS reads the driver's array itself, counted by the driver (Hairer's
        # NFCN, IWORK(17)) when scipy's integrator exposes it; otherwise the counting wrapper.
        on_array = getattr(rhs, "on_array", None)
        for f in ((on_array, counted) if on_array is not None else (counted,)):
            self.solver = ode(f).set_integrator("dop853", rtol=rtol, atol=atol, nsteps=self.MAX_STEPS_PER_SAMPLE)
            self.solver.set_solout(self._accepted)
            self.solver.set_initial_value(np.asarray(y0, dtype=float), float(t0))   # makes WORK, IWORK
            integrator = getattr(self.solver, "_integrator", None)
            self._iwork = getattr(integrator, "iwork", None) if f is on_array else None
            if f is counted or (self._iwork is not None and self._iwork.size > 16):
                break
        # The driver's first step of each call (its WORK(7), 0 = Hairer's initial guess): the last
        # step not cut short by a sample, so a call resumes the step sequence instead of ramping
        # up from a guess (~5 evaluations per sample saved). Left at 0 if scipy's layout differs.
        self._work = getattr(integrator, "work", None)
        self._t_step = self._target = None
        self._h = 0.0
        self._one_step = False
        self.y = np.asarray(y0, dtype=float).copy()
        self._y_old = None
        self.meta = {"rtol": rtol, "atol": atol, "driver": "DOP853 (Fortran, scipy.integrate.ode)"}

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far."""
        return self._count[0]

    def _accepted(self, t, y):
        """``solout``: after each accepted step (and at each call's start), keep the last step
        length that no sample cut short; stop the driver after one step when :meth:`step` asks."""
        if self._t_step is not None and t != self._target and t > self._t_step:
            self._h = t - self._t_step
        start = self._t_step is None
        self._t_step = t
        return -1 if self._one_step and not start else 0

    def _call(self, target):
        """One call of the driver from (t, y) toward ``target``; returns (t reached, y there)."""
        self._t_step = None
        if self._work is not None and self._work.size > 6:
            self._work[6] = min(self._h, target - self.t)
        t_from = self.t
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")           # the failure is raised below instead
            y = self.solver.integrate(target)
        if self._iwork is not None:
            self._count[0] += int(self._iwork[16])
        if not self.solver.successful():
            code = self.solver.get_return_code()
            msg = DOP853_FAILURES.get(code, f"return code {code}")
            self._failed = True
            raise IntegrationError(f"DOP853 failed between t = {t_from:.6g} s and {target:.6g} s: {msg}")
        return float(self.solver.t), y

    def _step_impl(self):
        """One step of the driver, stopped by ``solout`` after it (toward a target far enough that
        the step is not cut: ``t`` + 2³⁰ of the last uncut step, at least 1 s)."""
        self._target = None
        self._one_step = True
        try:
            t_new, y = self._call(self.t + max(self._h, 1.0) * 2.0 ** 30)
        finally:
            self._one_step = False
        self.t_old, self._y_old = self.t, self.y
        self.t, self.y = t_new, y

    def _dense_output_impl(self):
        """Cubic Hermite interpolant on the last step's ends (values and derivatives)."""
        def f(t, y):
            self._count[0] += 1
            return np.array(self.rhs(t, *y.tolist()), dtype=float)
        t0, t1, y0, y1 = self.t_old, self.t, self._y_old, self.y
        h = t1 - t0
        d0, d1 = h * f(t0, y0), h * f(t1, y1)

        def sol(t):
            s = (np.atleast_1d(np.asarray(t, dtype=float)) - t0) / h
            h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
            h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
            return (y0[:, None] * h00 + d0[:, None] * h10 + y1[:, None] * h01 + d1[:, None] * h11)
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """States at the sample times ``t`` (1-D, non-decreasing, from the previous block's last
        sample on) as a :class:`Trajectory`; ``progress(t_i)`` is called after each sample when given."""
        t = np.asarray(t, dtype=float)
        w0, c0 = time.perf_counter(), time.process_time()
        out = np.empty((self.y.size, t.size))
        for i, ti in enumerate(t):
            if ti != self.t:
                self._target = ti
                _, y = self._call(ti)
                self.t_old, self._y_old = self.t, self.y        # dense output: this call's span
                self.t, self.y = float(ti), y
                if progress is not None:
                    progress(ti)
            out[:, i] = self.y
        self.wall_time_s += time.perf_counter() - w0
        self.cpu_time_s += time.process_time() - c0
        self._dense = None
        return self.trajectory(t, out)
