"""DOP853 compiled with numba over a compiled right-hand side: adaptive steps, dense output.

The method is that of :mod:`gyro_instrument.core.dop853` and ``scipy.integrate.DOP853`` (the
Python-float driver and scipy's ``OdeSolver``): Hairer's 8(5,3) pair with its 7th-order dense
output (E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed.,
Springer 1993, sec. II.10; the tableau is :mod:`gyro_instrument.core.dop853`'s, checked value for
value against scipy by ``tests/test_dop853_tableau.py``), the same initial step (II.4), error norm
(both embedded estimates, scaled by the larger of the old and new state) and step-size control
(safety 0.9, factors in [0.2, 10], exponent −1/8, no growth after a rejection). Its steps are
therefore those of ``scipy.integrate.DOP853`` run with no end (``t_bound`` = ∞), to round-off
(``tests/test_dop853_jit.py`` holds it to :class:`~gyro_instrument.core.dop853.ScalarDOP853`).

The steps run with no end and never depend on the sample times: each sample is read from the
dense output of the step that covers it (the three extra stages are evaluated only for a step
that covers a sample), and the last step is kept across calls, so :meth:`CompiledRun.advance`
over consecutive blocks gives the one-shot run bit for bit.

The right-hand side is a kernel ``f(t, y, p, dy) -> None`` on float64 arrays (state ``y``,
parameters ``p``, derivative written into ``dy``), compiled by :func:`gyro_instrument.core.jit.compiled`
with the signature :func:`rhs_signature`. The driver :func:`driver` is compiled once with that
kernel's type as a first-class function argument, so one cached machine code serves every
kernel (a dispatcher argument would compile, and not cache, the driver per kernel). With
``GYRO_INSTRUMENT_JIT=0`` (or no numba) the same driver runs as plain Python on the plain kernel:
identical up to round-off, and ~1000× slower.
"""

import functools
import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.dop853 import A, A_EXTRA, B, C, C_EXTRA, D, E3, E5, N_STAGES
from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory

# The tableau as contiguous arrays (numba freezes module-level arrays into the machine code).
_A, _AX, _D = (np.ascontiguousarray(m) for m in (A, A_EXTRA, D))
_B, _C, _CX, _E3, _E5 = (np.ascontiguousarray(v) for v in (B, C, C_EXTRA, E3, E5))
_NS = N_STAGES                                   # 12 stages; K has 16 rows (13 + 3 extra stages)

#: Status codes of :func:`_advance` (0: done; others name the failure).
OK, STEP_TOO_SMALL, NOT_FINITE, BEFORE_STEP = 0, 1, 2, 3
_FAILURES = {STEP_TOO_SMALL: "required step size is less than spacing between numbers",
             NOT_FINITE: "the state is not finite", BEFORE_STEP: "a sample time lies before the last step"}

# state (float array) layout
_T, _H_ABS, _T_OLD, _H, _NFEV, _NSTEPS, _NREJ, _HAS_STEP, _HAS_DENSE = range(9)


def _rms_scaled(a, b, y, z, rtol, atol):
    """√(mean((a − b)² / s²)) with s = atol + max(|y|, |z|) rtol (scipy's norm)."""
    total = 0.0
    n = a.size
    for i in range(n):
        s = atol + max(abs(y[i]), abs(z[i])) * rtol
        total += ((a[i] - b[i]) / s) ** 2
    return math.sqrt(total / n)


def _initial_step(f, p, t, y, fy, K, rtol, atol):
    """First step (Hairer, Nørsett & Wanner II.4; scipy's ``select_initial_step``, order 7, no end);
    one evaluation, into ``K[1]`` as scratch. Returns the step."""
    zero = np.zeros_like(y)
    d0 = _rms_scaled(y, zero, y, y, rtol, atol)
    d1 = _rms_scaled(fy, zero, y, y, rtol, atol)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    y1 = y + h0 * fy
    f(t + h0, y1, p, K[1])
    d2 = _rms_scaled(K[1], fy, y, y, rtol, atol) / h0
    h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100.0 * h0, h1)


def _stage_state(y, h, K, row, coeffs, upto, out):
    """out = y + h Σ_{j<upto} coeffs[row, j] K[j]."""
    n = y.size
    for i in range(n):
        acc = 0.0
        for j in range(upto):
            acc += coeffs[row, j] * K[j, i]
        out[i] = y[i] + h * acc
    return out


def _attempt(f, p, t, h, y, K, z, ytmp, e5, e3):
    """One trial step of size ``h`` from (t, y) with K[0] = f(t, y): stages into K[1..12], the new
    state into ``z`` and its derivative into K[12], the 5th- and 3rd-order error estimates."""
    n = y.size
    for s in range(1, _NS):
        _stage_state(y, h, K, s, _A, s, ytmp)
        f(t + _C[s] * h, ytmp, p, K[s])
    for i in range(n):
        acc = 0.0
        for j in range(_NS):
            acc += _B[j] * K[j, i]
        z[i] = y[i] + h * acc
    f(t + h, z, p, K[_NS])
    for i in range(n):
        a5 = 0.0
        a3 = 0.0
        for j in range(_NS + 1):
            a5 += _E5[j] * K[j, i]
            a3 += _E3[j] * K[j, i]
        e5[i] = a5
        e3[i] = a3


def _error_norm(y, z, e5, e3, h_abs, rtol, atol):
    """scipy's DOP853 error norm of one trial step."""
    n5 = 0.0
    n3 = 0.0
    n = y.size
    for i in range(n):
        s = atol + max(abs(y[i]), abs(z[i])) * rtol
        n5 += (e5[i] / s) ** 2
        n3 += (e3[i] / s) ** 2
    if n5 == 0.0 and n3 == 0.0:
        return 0.0
    return h_abs * n5 / math.sqrt((n5 + 0.01 * n3) * n)


def _step(f, p, st, W, K, rtol, atol):
    """One accepted step from t = st[_T], y = W[0] with K[0] = f(t, y) (scipy's step-size control):
    the old state into W[1], the new into W[0], the stages in K. W's rows 2..5 are scratch (trial
    state, stage state, the two error estimates). Returns a status code."""
    t = st[_T]
    h_abs = st[_H_ABS]
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    if h_abs < min_step:
        h_abs = min_step
    rejected = False
    y, z = W[1], W[2]
    y[:] = W[0]
    while True:
        if h_abs < min_step:
            return STEP_TOO_SMALL
        t_new = t + h_abs
        h = t_new - t
        h_abs = abs(h)
        _attempt(f, p, t, h, y, K, z, W[3], W[4], W[5])
        st[_NFEV] += 12.0
        err = _error_norm(y, z, W[4], W[5], h_abs, rtol, atol)
        if err < 1.0:
            fac = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0))
            if rejected and fac > 1.0:
                fac = 1.0
            st[_T_OLD] = t
            st[_H] = h
            st[_T] = t_new
            st[_H_ABS] = h_abs * fac
            W[0, :] = z
            return OK
        fac = 0.9 * err ** (-1.0 / 8.0)
        if not fac > 0.2:                     # also a NaN error: the step shrinks
            fac = 0.2
        h_abs *= fac
        rejected = True
        st[_NREJ] += 1.0


def _dense_coefficients(f, p, st, W, K, F):
    """The last step's dense output (scipy's ``Dop853DenseOutput``): three extra stages into
    K[13..15], F[0..6] the coefficients, F[7] the step's initial state W[1] (W[0] its end)."""
    t, h = st[_T_OLD], st[_H]
    y_old, ytmp = W[1], W[3]
    n = y_old.size
    for r in range(3):
        s = _NS + 1 + r
        _stage_state(y_old, h, K, r, _AX, s, ytmp)
        f(t + _CX[r] * h, ytmp, p, K[s])
    st[_NFEV] += 3.0
    for i in range(n):
        dy = W[0, i] - y_old[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[0, i] + K[_NS, i])
        for r in range(4):
            acc = 0.0
            for j in range(_NS + 4):
                acc += _D[r, j] * K[j, i]
            F[3 + r, i] = h * acc
        F[7, i] = y_old[i]


def _dense_value(st, F, ts, out, col):
    """The dense output at ``ts`` into ``out[:, col]`` (scipy's Horner form)."""
    x = (ts - st[_T_OLD]) / st[_H]
    n = out.shape[0]
    for i in range(n):
        v = 0.0
        for k in range(6, -1, -1):
            v += F[k, i]
            v *= x if k % 2 == 0 else 1.0 - x
        out[i, col] = v + F[7, i]


def _start(f, p, st, W, K, rtol, atol):
    """K[0] = f(t0, y0) and the first step (two evaluations); a status code."""
    f(st[_T], W[0], p, K[0])
    st[_H_ABS] = _initial_step(f, p, st[_T], W[0], K[0], K, rtol, atol)
    st[_NFEV] = 2.0
    for i in range(W.shape[1]):
        if not math.isfinite(W[0, i]) or not math.isfinite(K[0, i]):
            return NOT_FINITE
    return OK


def _advance(f, p, st, W, K, F, ts, out, rtol, atol):
    """States at the sample times ``ts`` (non-decreasing, from the previous call's last sample on)
    into ``out`` (n, len(ts)), stepping with no end from the state (st, W, K, F) and reading each
    sample from the dense output of the step that covers it (the first call starts the run:
    :func:`_start`); a status code."""
    if st[_NFEV] == 0.0:
        status = _start(f, p, st, W, K, rtol, atol)
        if status != OK:
            return status
    i = 0
    m = ts.size
    while i < m:
        ti = ts[i]
        if st[_HAS_STEP] == 0.0:
            if ti == st[_T]:
                out[:, i] = W[0]
                i += 1
                continue
            if ti < st[_T]:
                return BEFORE_STEP
        else:
            if ti <= st[_T]:
                if ti < st[_T_OLD]:
                    return BEFORE_STEP
                if st[_HAS_DENSE] == 0.0:
                    _dense_coefficients(f, p, st, W, K, F)
                    st[_HAS_DENSE] = 1.0
                _dense_value(st, F, ti, out, i)
                i += 1
                continue
            K[0, :] = K[_NS]                        # f at the new step's start
        status = _step(f, p, st, W, K, rtol, atol)
        if status != OK:
            return status
        st[_HAS_STEP] = 1.0
        st[_HAS_DENSE] = 0.0
        st[_NSTEPS] += 1.0
        for j in range(W.shape[1]):
            if not math.isfinite(W[0, j]):
                return NOT_FINITE
    return OK


#: The driver's functions, callees first (:func:`_namespace` compiles them in this order).
_FUNCTIONS = ("_rms_scaled", "_initial_step", "_stage_state", "_attempt", "_error_norm", "_step",
              "_dense_coefficients", "_dense_value", "_start", "_advance")


def rhs_signature() -> "numba.core.typing.templates.Signature":
    """numba's signature of a right-hand-side kernel, ``void(float64, float64[::1] y, float64[::1] p,
    float64[::1] dy)``: compile a kernel with ``jit.compiled(f, signature_or_function=rhs_signature())``
    so that :func:`driver` takes it. Imports numba (call only when :func:`jit.enabled`)."""
    from numba import types  # noqa: PLC0415 - lazy (numba's import cost)
    vec = types.float64[::1]
    return types.void(types.float64, vec, vec, vec)


@functools.cache
def _namespace(compiled: bool) -> dict:
    """The driver's functions bound to one namespace: compiled (callees first, :func:`_advance` with
    the kernel's first-class function type, so one cached machine code serves every kernel; one
    cache entry to load, ~0.02 s once numba's runtime is up, ~0.6 s with numba's import) when ``compiled`` and :func:`jit.enabled`, else the plain Python functions."""
    import types as pytypes  # noqa: PLC0415
    ns = dict(globals())
    compiled = compiled and jit.enabled()
    signatures = {}
    if compiled:
        from numba import types  # noqa: PLC0415 - lazy (numba's import cost)
        fty, vec, mat = types.FunctionType(rhs_signature()), types.float64[::1], types.float64[:, ::1]
        signatures["_advance"] = types.int64(fty, vec, vec, mat, mat, mat, vec, mat, types.float64, types.float64)
    for name in _FUNCTIONS:
        fn = globals()[name]
        clone = pytypes.FunctionType(fn.__code__, ns, fn.__name__, fn.__defaults__, fn.__closure__)
        clone.__qualname__, clone.__module__, clone.__doc__ = fn.__qualname__, fn.__module__, fn.__doc__
        if compiled:
            sig = signatures.get(name)
            clone = jit.compiled(clone, signature_or_function=sig) if sig is not None else jit.compiled(clone)
        ns[name] = clone
    return ns


def driver(compiled: bool = True) -> "Callable":
    """:func:`_advance`, compiled when ``compiled`` and numba is enabled (:mod:`gyro_instrument.core.jit`;
    the first call on a machine compiles, ~15 s, later processes load numba's cache), else plain
    Python (the reference the tests hold it to)."""
    return _namespace(compiled)["_advance"]


class CompiledRun(Solver):
    """A resumable DOP853 run of a kernel ``f(t, y, p, dy)`` (see the module docstring), a
    :class:`~gyro_instrument.core.solver.Solver` with no end (``t_end`` = ∞).

    Parameters
    ----------
    kernel : callable
        The right-hand side: compiled with :func:`rhs_signature` when ``compiled`` (and numba is
        enabled), plain Python otherwise.
    params : array_like
        The kernel's parameters ``p`` (float64).
    y0 : array_like
        State at ``t0``.
    t0 : float
        Start, s.
    rtol, atol : float
        Tolerances (rtol at least 100 eps, as scipy's).
    compiled : bool
        Run the compiled driver (default) or the plain Python one.

    Raises
    ------
    IntegrationError
        A non-finite initial state or derivative; from :meth:`advance`, a step size below the
        spacing of floats, a non-finite state, or a sample time before the last step.
    """

    #: Samples per compiled call of :meth:`advance` between two ``progress`` reports.
    CHUNK = 1024
    method = "DOP853"

    def __init__(self, kernel, params, y0, t0, rtol, atol, compiled=True) -> None:
        super().__init__(t0)
        with self.clock():
            self.kernel, self.compiled = kernel, bool(compiled and jit.enabled())
            self._advance = driver(self.compiled)
            n = len(y0)
            self.p = np.ascontiguousarray(params, dtype=float)
            self.st = np.zeros(9)
            self.st[_T] = float(t0)
            self.W, self.K, self.F = np.zeros((6, n)), np.zeros((_NS + 4, n)), np.zeros((8, n))
            self.W[0] = np.asarray(y0, dtype=float)
            self.rtol, self.atol = max(float(rtol), 100 * np.finfo(float).eps), float(atol)
            if not np.all(np.isfinite(self.W[0])):
                raise IntegrationError(f"DOP853 (compiled) cannot start at t = {t0:.6g} s: the initial state "
                                       f"{self.W[0].tolist()} is not finite")
        self.meta = {"rtol": self.rtol, "atol": self.atol,
                     "driver": f"DOP853 (core.dop853_jit, {jit.status() if self.compiled else 'plain Python'})"}

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations so far (2 at the start: f(t0, y0) and the initial-step probe)."""
        return int(self.st[_NFEV])

    @property
    def y(self) -> np.ndarray:
        """The state at :attr:`t` (a copy)."""
        return self.W[0].copy()

    def _run(self, t, out):
        """The compiled driver over the samples ``t`` into ``out``; raises on its failure codes."""
        status = self._advance(self.kernel, self.p, self.st, self.W, self.K, self.F, t, out, self.rtol, self.atol)
        self.t = float(self.st[_T])
        if self.st[_HAS_STEP]:
            self.t_old = float(self.st[_T_OLD])
        if status != OK:
            self._failed = True
            raise IntegrationError(f"DOP853 (compiled) failed at t = {self.t:.6g} s: {_FAILURES[status]}")

    def _step_impl(self):
        """One step: the driver asked for the next double after the current step's end, which the
        next step covers (the steps never depend on the samples); that sample's dense output costs
        the step's three extra stages, which a sample in the step would have cost anyway."""
        self._run(np.array([np.nextafter(self.t, np.inf)]), np.empty((self.W.shape[1], 1)))

    def _dense_output_impl(self):
        """The last step's 7th-order interpolant (scipy's ``Dop853DenseOutput``, Horner form as
        :func:`_dense_value`), from the coefficients the driver keeps."""
        if not self.st[_HAS_DENSE]:
            self._run(np.array([self.t]), np.empty((self.W.shape[1], 1)))     # makes F (a sample in the step)
        t_old, h, F = float(self.st[_T_OLD]), float(self.st[_H]), self.F.copy()

        def sol(t):
            x = (np.atleast_1d(np.asarray(t, dtype=float)) - t_old) / h
            v = np.zeros((F.shape[1], x.size))
            for k in range(6, -1, -1):
                v += F[k][:, None]
                v *= x if k % 2 == 0 else 1.0 - x
            return v + F[7][:, None]
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """States at the sample times ``t`` (1-D, non-decreasing, from the previous block's last
        sample on, not before ``t0``) as a :class:`Trajectory` (y of shape (n, len(t)));
        ``progress(t_i)`` after each chunk of :data:`CHUNK` samples."""
        t = np.ascontiguousarray(t, dtype=float)
        with self.clock():
            out = np.empty((self.W.shape[1], t.size))
            for lo in range(0, t.size, self.CHUNK):
                hi = min(lo + self.CHUNK, t.size)
                part = np.empty((out.shape[0], hi - lo))
                self._run(t[lo:hi], part)
                out[:, lo:hi] = part
                if progress is not None:
                    progress(t[hi - 1])
            self.meta["nsteps"], self.meta["nrejected"] = int(self.st[_NSTEPS]), int(self.st[_NREJ])
        self._dense = None
        return Trajectory(t, out, self.nfev, self.wall_time_s, self.cpu_time_s, self.method, dict(self.meta))
