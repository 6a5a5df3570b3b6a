"""Parallel-in-time integration of a nearly periodic motion (parareal over its periods).

A Foucault pendulum swings ~5 250 times in a sidereal day; an adaptive integrator must take
those swings one after the other, and in Python its cost is the interpreter's, per step. Here
the day is cut into segments of one swing period ``T`` and every segment is integrated *at
once*: one fixed-step 8th-order Runge–Kutta (the DOP853 tableau of Hairer, Nørsett & Wanner)
on arrays of shape (state, segments), so numpy does the work and the interpreter runs only
``m`` × 12 stages per pass, whatever the number of swings.

The segments' initial states come from parareal (Lions, Maday & Turinici 2001):

    U[n+1]^(k+1) = G(U[n]^(k+1)) + F(U[n]^k) − G(U[n]^k)

with ``F`` the fine one-period integration (batched) and ``G`` a cheap linear coarse map
``U ↦ A U`` — for the pendulum, Quet's comparison pendulum: the swing is carried over one
period and turned about the vertical by the precession per period (sec. 2). After ``k``
iterations the first ``k`` segments equal the sequential fine solution exactly, and the
iteration stops when no segment start moves by more than ``tol`` (scaled), so the result is
the fine solution of the *full* equations to that tolerance — no term is dropped. Dense output
at any sample times comes from quintic Hermite interpolation of positions between the grid
points (position, velocity and acceleration known at both ends): :func:`dense_output` on numpy,
or :func:`hermite_samples`, the same doubles sample by sample, compiled.

Compiled (numba, :mod:`gyro_instrument.core.jit`) there is no interpreter to amortise and a
single core does the sequential fine integration in less CPU than parareal's ≥ 2 passes; the
pendulum then integrates its swings serially (:func:`gyro_instrument.instruments.pendulum.fast_path.swing_grid`)
and this module's Newton iteration is the path without numba (``GYRO_INSTRUMENT_JIT=0``) and for
short runs.
"""

import functools
import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core import dop853
from gyro_instrument.core.errors import IntegrationError
from gyro_instrument.core.integrate import report

# The 8th-order formula of the DOP853 tableau (core/dop853.py: the doubles of scipy's public class
# scipy.integrate.DOP853, A[:12, :12], B, C[:12] of its dop853_coefficients module).
_S = dop853.N_STAGES               # 12 stages of the 8th-order formula
_A = dop853.A
_B = dop853.B
_C = dop853.C


def rk8_batch(rhs, y0, h, m, keep=False) -> tuple:
    """Integrate ``m`` fixed steps of size ``h`` for every column of ``y0`` (shape (d, B)).

    ``rhs(t, y)`` must accept ``y`` of shape (d, B) and return the same shape; the systems are
    autonomous here (``t`` is passed as 0). Returns the final states, and with ``keep`` also
    the states and derivatives at every grid point, shape (m + 1, d, B) each.
    """
    y = np.array(y0, dtype=float)
    ys = fs = None
    if keep:
        ys = np.empty((m + 1,) + y.shape)
        fs = np.empty((m + 1,) + y.shape)
    k = np.empty((_S,) + y.shape)
    flat = k.reshape(_S, -1)                  # the stages as rows: one BLAS product per stage
    f0 = rhs(0.0, y)
    for step in range(m):
        if keep:
            ys[step], fs[step] = y, f0
        k[0] = f0
        for s in range(1, _S):
            k[s] = rhs(0.0, y + (_A[s, :s] @ flat[:s]).reshape(y.shape) * h)
        y = y + (_B @ flat).reshape(y.shape) * h
        f0 = rhs(0.0, y)
    if keep:
        ys[m], fs[m] = y, f0
    return y, ys, fs


def parareal(rhs, y0, segment_s, predictor, steps, scale, tol=1e-9, jacobian_stride=32, align=None,
             max_iter=8, progress=None, span=(0.0, 1.0)) -> tuple:
    """Segment starts ``U`` (shape (n + 1, d)) of the whole run, converged by Newton-type parareal.

    The coarse propagator over segment ``j`` is the linearisation of the fine one about the
    current iterate, ``G_j(U) = F(U_j^k) + J_j (U − U_j^k)``, so an iteration reads

        U[j+1]^(k+1) = F(U[j]^k) + J_j (U[j]^(k+1) − U[j]^k)

    (Newton's method for the matching conditions of multiple shooting; it converges
    quadratically). ``J_j`` is computed by finite differences in the same batch as ``F``, but only
    on every ``jacobian_stride``-th segment: in a frame that follows the motion (``align``) it
    varies slowly along the run and is interpolated linearly in between.

    Parameters
    ----------
    rhs : callable
        Vectorised autonomous right-hand side (see :func:`rk8_batch`).
    y0 : array (d,)
        Initial state (``U[0]``, never changed).
    segment_s : float
        Segment length, seconds.
    predictor : array (n + 1, d)
        First guess of the segment starts (the comparison solution); ``n`` segments.
    steps : int
        Fixed RK8 steps per segment.
    scale : array (d,)
        Per-component scale of the state (convergence test and difference steps).
    tol : float
        Stop when no segment start changes by more than ``tol`` (scaled): the error of the starts.
    jacobian_stride : int
        Segments between exact Jacobians.
    align : callable or None
        ``align(U) -> (n + 1, d, d)`` orthogonal matrices ``R_j`` such that ``R_(j+1)ᵀ J_j R_j``
        varies slowly in ``j`` (default: identity).
    span : (float, float)
        The fraction of the whole run these segments cover: progress is reported in it (a streamed
        run converges one window of segments after another).

    Returns
    -------
    U : array (n + 1, d)
        The segment starts of the accepted pass: the next Newton update moves none of them by
        more than ``tol`` (scaled), which bounds their error.
    grid : (ys, fs)
        That pass's states and derivatives at every step, shape (steps + 1, d, n) each, for
        :func:`dense_output`.
    info : dict
        ``iterations`` (fine passes), ``changes`` (per pass), ``rhs_columns`` (right-hand-side
        evaluations × columns: the batched analogue of nfev).

    Raises
    ------
    IntegrationError
        A non-finite state, or no convergence in ``max_iter`` iterations.
    """
    U = np.array(predictor, dtype=float)
    n, d = U.shape[0] - 1, U.shape[1]
    U[0] = y0
    h = segment_s / steps
    if n == 1:                  # one segment from the exact start: its fine pass is the solution
        Y, ys, fs = rk8_batch(rhs, U[:1].T, h, steps, keep=True)
        if not np.all(np.isfinite(Y)):
            raise IntegrationError("parareal: a segment became non-finite")
        U[1] = Y[:, 0]
        report(span[1])
        return U, (ys, fs), {"iterations": 1, "changes": [0.0], "rhs_columns": steps * _S + 1}
    nodes = np.unique(np.r_[np.arange(0, n, max(1, int(jacobian_stride))), n - 1])
    delta = 1e-7 * np.asarray(scale, dtype=float)
    eye = np.eye(d)
    evals, changes = 0, []
    for it in range(1, max_iter + 1):
        cols = np.hstack([U[:-1].T] + [U[nodes].T + (delta[i] * eye[i])[:, None] for i in range(d)])
        Y, ys, fs = rk8_batch(rhs, cols, h, steps, keep=True)
        evals += (steps * _S + 1) * cols.shape[1]
        if not np.all(np.isfinite(Y)):
            raise IntegrationError("parareal: a segment became non-finite")
        F = Y[:, :n].T
        Jn = np.stack([(Y[:, n + i * len(nodes): n + (i + 1) * len(nodes)] - F[nodes].T) / delta[i]
                       for i in range(d)], axis=-1)              # (d, nodes, d)
        Jn = np.moveaxis(Jn, 1, 0)                               # (nodes, d, d)
        R = align(U) if align is not None else np.broadcast_to(eye, (n + 1, d, d))
        Jp = np.einsum("nji,njk,nkl->nil", R[nodes + 1], Jn, R[nodes])     # R_(j+1)ᵀ J R_j
        idx = np.arange(n)
        Ji = np.empty((n, d, d))
        for a in range(d):
            for b in range(d):
                Ji[:, a, b] = np.interp(idx, nodes, Jp[:, a, b])
        J = np.einsum("nij,njk,nlk->nil", R[1:], Ji, R[:-1])              # back: R_(j+1) J' R_jᵀ
        new = np.empty_like(U)
        new[0] = y0
        for j in range(n):                                               # the sequential part: n 6×6 products
            new[j + 1] = F[j] + J[j] @ (new[j] - U[j])
        change = float(np.max(np.abs(new - U) / scale))
        changes.append(change)
        # quadratic convergence: passes still needed ~ log2(log(change)/log(tol))
        left = max(math.log2(max(math.log(tol) / math.log(min(change, 0.5)), 1.0)), 0.0) if change > tol else 0.0
        report(span[0] + (span[1] - span[0]) * it / (it + 1.0 + left))
        if progress:
            progress(f"parareal pass {it}: the next update moves segment starts by {change:.2e} "
                     f"(tolerance {tol:.1e})")
        if change <= tol:            # this pass started from converged starts: accept its grid
            return U, (ys[:, :, :n], fs[:, :, :n]), {"iterations": it, "changes": changes, "rhs_columns": evals}
        U = new
    raise IntegrationError(f"parareal did not converge in {max_iter} iterations (changes {changes})")


def hermite_rows(grid, npos, segment_s, block=256) -> np.ndarray:
    """The quintic Hermite interpolants :func:`dense_output` evaluates, one column per step of
    every segment: shape (6 npos, segments × steps), in blocks of ``npos`` rows r0, v0, a0 / 2, c3,
    c4, c5 (``r`` positions, ``v = h ṙ``, ``a = h² r̈`` at the step's start (0) and end (1), ``h`` the
    step, ``c3..c5`` the coefficients matching both ends) for the scaled time ``s = (t − t0) / h`` in
    [0, 1]: r(s) = r0 + s v0 + s² a0 / 2 + s³ c3 + s⁴ c4 + s⁵ c5.

    Computed once per step rather than once per sample (~7 samples per step at 20 Hz on the 67 m
    pendulum, 48 steps per swing), with the same operations as per sample, so the values are the
    same doubles; ``block`` segments at a time (the temporaries stay small). Build it once per grid
    and pass it to every :func:`dense_output` call on it; ``segment_s`` (s) as there."""
    ys, fs = grid
    m, n_seg = ys.shape[0] - 1, ys.shape[2]
    h = segment_s / m
    table = np.empty((6, npos, n_seg, m))
    for a in range(0, n_seg, block):
        b = min(a + block, n_seg)
        ends = np.concatenate([ys[:, :2 * npos, a:b], fs[:, npos:2 * npos, a:b]], axis=1)   # (m + 1, 3 npos, n)
        e0, e1 = ends[:-1], ends[1:]
        r0, v0, a0 = e0[:, :npos], h * e0[:, npos:2 * npos], h * h * e0[:, 2 * npos:]  # (m, npos, n) each
        r1, v1, a1 = e1[:, :npos], h * e1[:, npos:2 * npos], h * h * e1[:, 2 * npos:]
        d = r1 - r0
        coefficients = (r0, v0, 0.5 * a0,
                        10 * d - 6 * v0 - 4 * v1 - 1.5 * a0 + 0.5 * a1,
                        -15 * d + 8 * v0 + 7 * v1 + 1.5 * a0 - a1,
                        6 * d - 3 * v0 - 3 * v1 - 0.5 * a0 + 0.5 * a1)
        for i, c in enumerate(coefficients):
            table[i, :, a:b] = c.transpose(1, 2, 0)
    return table.reshape(6 * npos, n_seg * m)


def dense_output(grid, segment_s, t, npos, chunk=16384, rows=None) -> np.ndarray:
    """States at times ``t`` (seconds from the start of segment 0) from a pass's grid
    (:func:`parareal`): quintic Hermite interpolation of the first ``npos`` components
    (positions) from their values, velocities (the next ``npos`` components) and accelerations
    (the derivatives' last ``npos`` components) at both ends of each step; the velocities are
    the interpolant's derivative. ``rows``: :func:`hermite_rows` of ``grid`` when already built.
    Returns an array (2 npos, len(t))."""
    ys = grid[0]
    m, n_seg = ys.shape[0] - 1, ys.shape[2]
    h = segment_s / m
    t = np.asarray(t, dtype=float)
    rows = hermite_rows(grid, npos, segment_s) if rows is None else rows
    out = np.empty((2 * npos, t.size))
    # blocks that stay in cache, each coefficient gathered as a row of the block's samples: the
    # arithmetic runs on contiguous rows (on (samples, npos) arrays with a broadcast s it was 3x
    # slower: numpy's inner loops ran over npos = 3 elements)
    for a in range(0, t.size, chunk):
        tt = t[a:a + chunk]
        # floor of the quotient (not floor division, whose fmod costs the compiled kernel half its time):
        # a sample an ulp before a grid point may be taken from the next step, a continuous interpolant
        seg = np.clip(np.floor(tt / segment_s).astype(np.int64), 0, n_seg - 1)
        tau = tt - seg * segment_s
        j = np.clip(np.floor(tau / h).astype(np.int64), 0, m - 1)
        s = tau / h - j
        p = rows.take(seg * m + j, axis=1)
        r0, v0, ha0, c3, c4, c5 = (p[i * npos:(i + 1) * npos] for i in range(6))
        out[:npos, a:a + chunk] = r0 + s * (v0 + s * (ha0 + s * (c3 + s * (c4 + s * c5))))
        # a0 = 2 (a0 / 2) exactly (a power of two)
        out[npos:, a:a + chunk] = (v0 + s * (2.0 * ha0 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))) / h
    return out


def hermite_samples(ys, fs, npos, segment_s, t, t0, offset, out) -> None:
    """Kernel: :func:`dense_output` sample by sample, straight from the grid ``(ys, fs)`` (shape
    (segments, m + 1, d), states and derivatives at every step: the grid of :func:`parareal` with its
    segment axis first, so that consecutive samples read nearby memory) without the table of
    :func:`hermite_rows`: the same operations in the same order (the step's quintic coefficients,
    then Horner's scheme), so the same doubles. Sample times ``t`` (s, increasing), taken from the
    start of segment 0 as (t − t0) − offset; ``out`` (2 npos, len(t)) receives positions and velocities.
    Plain Python on floats and arrays, compiled by :func:`~gyro_instrument.core.jit.compiled`.

    Blocks of at most 4096 samples: first every sample's step and scaled time ``s`` (a loop without
    branches), then each run of samples in one step from that step's coefficients, computed once per
    run (a run cut by a block boundary computes them again: the same doubles). Grouping the samples
    so, rather than testing for a new step at every sample, took a third off the CPU (a sidereal day
    at 20 Hz: 0.032 s against 0.049 s)."""
    m, n_seg = ys.shape[1] - 1, ys.shape[0]
    h = segment_s / m
    hh = h * h
    coef = np.empty((6, npos))           # the current step's r0, v0, a0 / 2, c3, c4, c5 (hermite_rows)
    block = min(t.size, 4096)
    step = np.empty(block, np.int64)
    scaled = np.empty(block)
    for b0 in range(0, t.size, block):
        b1 = min(b0 + block, t.size)
        for i in range(b0, b1):
            tt = (t[i] - t0) - offset
            seg = min(max(int(math.floor(tt / segment_s)), 0), n_seg - 1)
            tl = tt - seg * segment_s
            j = min(max(int(math.floor(tl / h)), 0), m - 1)
            scaled[i - b0] = tl / h - j
            step[i - b0] = seg * m + j
        i = b0
        while i < b1:
            cur = step[i - b0]
            seg, j = cur // m, cur % m
            for c in range(npos):
                r0, r1 = ys[seg, j, c], ys[seg, j + 1, c]
                v0, v1 = h * ys[seg, j, npos + c], h * ys[seg, j + 1, npos + c]
                a0, a1 = hh * fs[seg, j, npos + c], hh * fs[seg, j + 1, npos + c]
                d = r1 - r0
                coef[0, c], coef[1, c], coef[2, c] = r0, v0, 0.5 * a0
                coef[3, c] = 10 * d - 6 * v0 - 4 * v1 - 1.5 * a0 + 0.5 * a1
                coef[4, c] = -15 * d + 8 * v0 + 7 * v1 + 1.5 * a0 - a1
                coef[5, c] = 6 * d - 3 * v0 - 3 * v1 - 0.5 * a0 + 0.5 * a1
            e = i + 1
            while e < b1 and step[e - b0] == cur:
                e += 1
            for c in range(npos):
                r0, v0, ha0, c3, c4, c5 = coef[0, c], coef[1, c], coef[2, c], coef[3, c], coef[4, c], coef[5, c]
                for k in range(i, e):
                    s = scaled[k - b0]
                    out[c, k] = r0 + s * (v0 + s * (ha0 + s * (c3 + s * (c4 + s * c5))))
                    out[npos + c, k] = (v0 + s * (2.0 * ha0 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))) / h
            i = e


@functools.cache
def compiled_hermite_samples() -> Callable:
    """:func:`hermite_samples` compiled (:func:`~gyro_instrument.core.jit.compiled`), or the plain
    function when compilation is off."""
    from gyro_instrument.core import jit
    return jit.compiled(hermite_samples)
