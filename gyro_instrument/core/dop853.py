"""DOP853 on a small state held in Python floats (``integrate(..., method="DOP853-scalar")``).

A state of three components with a right-hand side of a few sines (the directing-plane
gyroscope's reduced model) spends nearly all of its time in ``solve_ivp`` on per-step overhead
of numpy calls on length-3 arrays (~90 µs per step, 15 RHS calls per step through two
wrappers). This driver runs the same method with plain floats (~18 µs per step): scipy's DOP853
tableau (Hairer's 8(5,3) pair, read from the public ``scipy.integrate.DOP853`` class), the same
initial-step choice, error norm, step-size control and 7th-order dense output, so it takes the
same steps and the same number of RHS evaluations and agrees with ``integrate(...,
method="DOP853")`` to rounding (≤ 1e-13 rad in u over an hour of quet_paris, against the
~1e-10 rad integration error at rtol 1e-11). The stage arithmetic is generated once per state
size with the coefficients as literals; the dense output is evaluated for all sample times at
once after the run. Model: scipy's ``scipy/integrate/_ivp/rk.py`` (``RungeKutta._step_impl``,
``Dop853DenseOutput``) and ``scipy/integrate/_ivp/common.py`` (``select_initial_step``).
"""

import math
import time

import numpy as np
from scipy.integrate import DOP853

from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.integrate import Trajectory

#: Exponent of the step-size factor, −1/(error estimator order + 1) (scipy: 7 + 1).
_EXPONENT = -1.0 / 8.0


def _linear_combination(coeffs, terms):
    parts = [f"{float(c)!r} * {x}" for c, x in zip(coeffs, terms) if c != 0.0]
    return " + ".join(parts) if parts else "0.0"


def _dop853_source(n):
    """Source of ``attempt`` (one trial step: new state, new derivative, the 5th- and 3rd-order
    error estimates and the 13 stages) and ``dense`` (the three extra stages and the dense
    coefficients F3..F6 = h D K) for an ``n``-component state held in scalars."""
    A, B, C, E5, E3, D = DOP853.A, DOP853.B, DOP853.C, DOP853.E5, DOP853.E3, DOP853.D
    AX, CX, ns = DOP853.A_EXTRA, DOP853.C_EXTRA, DOP853.n_stages
    ys = ", ".join(f"y{i}" for i in range(n))

    def k(s):
        return ", ".join(f"k{s}_{i}" for i in range(n))

    def combo(coeffs, i, upto):
        return _linear_combination(coeffs[:upto], [f"k{j}_{i}" for j in range(upto)])

    allk = ", ".join(k(s) for s in range(ns + 1))
    src = [f"def attempt(f, t, h, {ys}, {k(0)}):"]
    for s in range(1, ns):
        args = ", ".join(f"y{i} + h * ({combo(A[s], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(C[s])!r} * h, {args})")
    for i in range(n):
        src.append(f"    z{i} = y{i} + h * ({combo(B, i, ns)})")
    zs = ", ".join(f"z{i}" for i in range(n))
    src.append(f"    {k(ns)}, = f(t + h, {zs})")
    e5 = ", ".join(combo(E5, i, ns + 1) for i in range(n))
    e3 = ", ".join(combo(E3, i, ns + 1) for i in range(n))
    src.append(f"    return ({zs},), ({k(ns)},), ({e5},), ({e3},), ({allk},)")
    src.append(f"def dense(f, t, h, {ys}, stages):")
    src.append(f"    {allk}, = stages")
    for r in range(AX.shape[0]):
        s = ns + 1 + r
        args = ", ".join(f"y{i} + h * ({combo(AX[r], i, s)})" for i in range(n))
        src.append(f"    {k(s)}, = f(t + {float(CX[r])!r} * h, {args})")
    rows = ", ".join(f"h * ({combo(D[r], i, D.shape[1])})" for r in range(D.shape[0]) for i in range(n))
    src.append(f"    return ({rows},)")
    return "\n".join(src) + "\n"


_DOP853_KERNELS = {}


def _dop853_kernels(n):
    if n not in _DOP853_KERNELS:
        namespace = {}
        exec(compile(_dop853_source(n), f"<DOP853 scalar kernels, n = {n}>", "exec"), namespace)
        _DOP853_KERNELS[n] = (namespace["attempt"], namespace["dense"])
    return _DOP853_KERNELS[n]


def _initial_step(f, t, y, fy, t_end, rtol, atol):
    """First step size: Hairer, Nørsett & Wanner II.4, as scipy's ``select_initial_step`` (order 7).
    Costs one RHS evaluation."""
    n = len(y)
    sc = [atol + abs(v) * rtol for v in y]
    d0 = math.sqrt(sum((v / s) ** 2 for v, s in zip(y, sc)) / n)
    d1 = math.sqrt(sum((v / s) ** 2 for v, s in zip(fy, sc)) / n)
    h0 = min(1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1, t_end - t)
    f1 = f(t + h0, *[v + h0 * w for v, w in zip(y, fy)])
    d2 = math.sqrt(sum(((a - b) / s) ** 2 for a, b, s in zip(f1, fy, sc)) / n) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / 8)
    return min(100 * h0, h1, t_end - t)


def _error_norm(y, z, e5, e3, h_abs, rtol, atol):
    """scipy's DOP853 error norm of one trial step (both embedded estimates, scaled by the larger
    of the old and new state)."""
    n5 = n3 = 0.0
    for a, b, e, g in zip(y, z, e5, e3):
        s = atol + max(abs(a), abs(b)) * rtol
        n5 += (e / s) ** 2
        n3 += (g / s) ** 2
    return 0.0 if n5 == 0.0 and n3 == 0.0 else h_abs * n5 / math.sqrt((n5 + 0.01 * n3) * len(y))


def _accepted_step(attempt, f, t, y, fy, h_abs, t_end, rtol, atol):
    """Try steps from ``t`` until one passes the error test (scipy's step-size control).

    Returns
    -------
    tuple
        (t_new, h, z, fz, stages, next h_abs, RHS evaluations, rejected attempts).
    """
    min_step = 10 * abs(math.nextafter(t, math.inf) - t)
    h_abs = max(h_abs, min_step)
    rejected = False
    nfev = nrej = 0
    while True:
        if h_abs < min_step:
            raise IntegrationError(f"DOP853 failed at t = {t:.6g} s: required step size is less than "
                                   f"spacing between numbers")
        t_new = min(t + h_abs, t_end)
        h = t_new - t
        h_abs = abs(h)
        z, fz, e5, e3, stages = attempt(f, t, h, *y, *fy)
        nfev += 12
        err = _error_norm(y, z, e5, e3, h_abs, rtol, atol)
        if err < 1.0:
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** _EXPONENT)
            h_abs *= min(1.0, fac) if rejected else fac
            return t_new, h, z, fz, stages, h_abs, nfev, nrej
        h_abs *= max(0.2, 0.9 * err ** _EXPONENT)   # also for a NaN error: the step shrinks
        rejected = True
        nrej += 1


def _dense_samples(t_eval, t_old, t_new_all, h_all, y_old, coef, n):
    """Dense output at every sample time at once (scipy's ``Dop853DenseOutput``, vectorised);
    shape (len(t_eval), n)."""
    idx = np.minimum(np.searchsorted(np.array(t_new_all), t_eval, side="left"), len(t_old) - 1)
    x = ((t_eval - np.array(t_old)[idx]) / np.array(h_all)[idx])[:, None]
    F = np.array(coef).reshape(len(coef), 7, n)[idx]
    out = np.zeros((t_eval.size, n))
    for i in range(6, -1, -1):
        out += F[:, i]
        out *= x if i % 2 == 0 else 1.0 - x
    out += np.array(y_old)[idx]
    return out


class ScalarDOP853:
    """DOP853 on a small state held in Python floats, resumable block by block.

    ``f(t, *y) -> tuple`` of the derivatives. Same method, step control and dense output as
    ``integrate(..., method="DOP853")`` (see the module docstring). :meth:`advance` steps until the
    block's last sample is reached, evaluates the block from the steps taken for it and keeps only
    the last step (the next block's first samples may lie in it), so the steps are those of one run
    from ``t0`` to ``t_end`` and every sample is evaluated from the same step as in one call over the
    whole run: the blocks concatenate bit for bit (``tests/test_streaming.py``), in memory of one
    block. ``nfev`` counts every RHS evaluation as ``integrate`` does (15 per accepted step, 12 per
    rejected, 2 at the start).

    Raises
    ------
    IntegrationError
        A non-finite initial state; from :meth:`advance`, a step size below the spacing of floats
        or a non-finite state.
    """

    def __init__(self, f, y0, t0, t_end, rtol=1e-10, atol=1e-12) -> None:
        y = tuple(float(v) for v in y0)
        if not all(math.isfinite(v) for v in y):
            raise IntegrationError(f"initial state is not finite: {y}")
        self.f, self.y, self.n = f, y, len(y)
        self.t0 = self.t = float(t0)
        self.t_end = float(t_end)
        self.rtol = max(float(rtol), 100 * np.finfo(float).eps)   # as scipy's validate_tol
        self.atol = float(atol)
        self.nfev = self.nsteps = self.nrej = 0
        self.wall_time_s = self.cpu_time_s = 0.0
        self._steps = ([], [], [], [], [])      # t_old, t_new, h, y_old, dense coefficients
        if self.t_end != self.t0:
            w0, c0 = time.perf_counter(), time.process_time()
            self.attempt, self.dense = _dop853_kernels(self.n)
            self.fy = tuple(f(self.t, *y))
            self.h_abs = _initial_step(f, self.t, y, self.fy, self.t_end, self.rtol, self.atol)
            self.nfev = 2
            self.wall_time_s += time.perf_counter() - w0
            self.cpu_time_s += time.process_time() - c0

    def _step(self):
        """One accepted step from the current state; its dense coefficients are kept."""
        f, t, y, fy = self.f, self.t, self.y, self.fy
        t_new, h, z, fz, stages, self.h_abs, evals, rejections = _accepted_step(
            self.attempt, f, t, y, fy, self.h_abs, self.t_end, self.rtol, self.atol)
        dy = [b - a for a, b in zip(y, z)]
        t_old, t_new_all, h_all, y_old, coef = self._steps
        coef.append((*dy, *[h * a - d for a, d in zip(fy, dy)],
                     *[2 * d - h * (a + b) for a, b, d in zip(fy, fz, dy)], *self.dense(f, t, h, *y, stages)))
        t_old.append(t)
        t_new_all.append(t_new)
        h_all.append(h)
        y_old.append(y)
        self.nfev += evals + 3
        self.nrej += rejections
        self.nsteps += 1
        self.t, self.y, self.fy = t_new, z, fz

    def advance(self, t) -> Trajectory:
        """States at the sample times ``t`` (1-D, non-decreasing, not before the previous block's
        last sample nor past ``t_end``), s. Returns a :class:`Trajectory` of this block whose
        ``nfev``, ``wall_time_s`` and ``cpu_time_s`` count the whole run so far."""
        t = np.asarray(t, dtype=float)
        if self.t_end == self.t0:
            return Trajectory(t, np.array(self.y)[:, None].repeat(t.size, axis=1), 0, 0.0, 0.0, "DOP853")
        if t.size and t[-1] > self.t_end:
            raise IntegrationError(f"sample time {t[-1]!r} s is after the run's end {self.t_end!r} s")
        w0, c0 = time.perf_counter(), time.process_time()
        last = float(t[-1]) if t.size else self.t
        while self.t < last or not self._steps[0]:
            self._step()
        out = _dense_samples(t, *self._steps, self.n) if t.size else np.empty((0, self.n))
        for kept in self._steps:               # the last step may hold the next block's first samples
            del kept[:-1]
        self.wall_time_s += time.perf_counter() - w0
        self.cpu_time_s += time.process_time() - c0
        if not np.all(np.isfinite(out)):
            raise IntegrationError("DOP853 produced a non-finite state")
        return Trajectory(t, out.T.copy(), self.nfev, self.wall_time_s, self.cpu_time_s, "DOP853",
                          {"rtol": self.rtol, "atol": self.atol, "nsteps": self.nsteps, "nrejected": self.nrej,
                           "driver": "scalar"})


def integrate_dop853_scalar(f, y0, t_eval, rtol=1e-10, atol=1e-12) -> Trajectory:
    """DOP853 on a small state held in Python floats over ``t_eval`` at once: one
    :meth:`ScalarDOP853.advance` from ``t_eval[0]`` to ``t_eval[-1]`` (``t_eval`` non-decreasing)."""
    t_eval = np.asarray(t_eval, dtype=float)
    return ScalarDOP853(f, y0, t_eval[0], t_eval[-1], rtol=rtol, atol=atol).advance(t_eval)
