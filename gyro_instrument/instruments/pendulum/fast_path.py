"""The pendulum's fast path: windows of whole swings of a fixed-step RK8, behind the
:class:`~gyro_instrument.core.solver.Solver` interface (:class:`SwingRun`).

A run is cut into swings of one period T (measured on the first swing of the full model) and the
swings into windows; each window is integrated at once — compiled swing after swing by
:func:`swing_grid` (the sequential fine solution) for long runs, else converged by Newton-parareal
from Quet's comparison pendulum on numpy (:func:`gyro_instrument.core.parareal.parareal`; Quet 1853
sec. 2) — and sampled by quintic Hermite interpolation on its grid (:func:`fill_samples`). A step of
:class:`SwingRun` is one window; its dense output, that window's interpolant.
"""

import bisect
import functools
import math
from collections.abc import Callable

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.parareal import compiled_hermite_samples, dense_output, hermite_rows
from gyro_instrument.core.solver import Solver
from gyro_instrument.core.trajectory import Trajectory


def swing_frames(U, w0sq) -> np.ndarray:
    """Rotations about the vertical by each state's swing-plane angle (Fradkin tensor), acting on
    position and velocity: the frame in which a swing's one-period Jacobian varies slowly."""
    x, y, vx, vy = U[:, 0], U[:, 1], U[:, 3], U[:, 4]
    txx, tyy, txy = w0sq * x * x + vx * vx, w0sq * y * y + vy * vy, w0sq * x * y + vx * vy
    a = 0.5 * np.unwrap(np.arctan2(2 * txy, txx - tyy))
    c, s = np.cos(a), np.sin(a)
    R = np.zeros((len(a), 6, 6))
    for b in (0, 3):
        R[:, b, b], R[:, b, b + 1], R[:, b + 1, b], R[:, b + 1, b + 1] = c, -s, s, c
        R[:, b + 2, b + 2] = 1.0
    return R


def swing_grid(y0, h, m, n, lin, consts, a, b, ys, fs) -> None:
    """Kernel: ``n`` swings of ``m`` fixed RK8 steps of size ``h`` (s) one after the other from ``y0``
    = [r, v] (m, m/s, ENU), on the equations of :meth:`~.dynamics.SwingDynamics.rhs_exact` with the point-mass
    terms given as the affine map ``lin`` (3 × 7: [δr, v, 1], :func:`linear_point_mass_map`).

    The same fixed-step formula as :func:`gyro_instrument.core.parareal.rk8_batch` (DOP853's
    8th-order tableau ``a`` (12 × 12), ``b`` (12,)), taken serially: this is the sequential fine
    solution that Newton-parareal converges to. Fills ``ys``, ``fs`` (shape (n, m + 1, 6): states
    and derivatives at every step of every swing, the last point of a swing repeated as the first
    of the next; swing-major, so that consecutive samples read nearby memory), the layout of
    :func:`~gyro_instrument.core.parareal.hermite_samples`.
    ``consts`` = (g (m/s²), a_b = 2 √(g/l) (1/s), b²/2 = g / (2 l) (1/s²), l² (m²), z_rest = −l (m)).
    Plain Python on floats and arrays, compiled by :func:`~gyro_instrument.core.jit.compiled`."""
    g, a_b, half_b2, l2, zr = consts[0], consts[1], consts[2], consts[3], consts[4]
    # the map's entries as scalars: loads the compiler cannot hoist past the stores to k (aliasing)
    x0, x1, x2, x3, x4, x5, x6 = lin[0, 0], lin[0, 1], lin[0, 2], lin[0, 3], lin[0, 4], lin[0, 5], lin[0, 6]
    y0_, y1, y2, y3, y4, y5, y6 = lin[1, 0], lin[1, 1], lin[1, 2], lin[1, 3], lin[1, 4], lin[1, 5], lin[1, 6]
    z0, z1, z2, z3, z4, z5, z6 = lin[2, 0], lin[2, 1], lin[2, 2], lin[2, 3], lin[2, 4], lin[2, 5], lin[2, 6]
    k = np.empty((12, 6))
    y = y0.copy()
    yt = np.empty(6)
    for i in range(n * m + 1):
        j, step = i // m, i % m
        for s in range(12):
            if s == 0:
                yt[:] = y
            else:
                for c in range(6):
                    acc = 0.0
                    for r in range(s):
                        acc += a[s, r] * k[r, c]
                    yt[c] = y[c] + acc * h
            x, yy, z, vx, vy, vz = yt[0], yt[1], yt[2], yt[3], yt[4], yt[5]
            dz = z - zr
            fx = x0 * x + x1 * yy + x2 * dz + x3 * vx + x4 * vy + x5 * vz + x6
            fy = y0_ * x + y1 * yy + y2 * dz + y3 * vx + y4 * vy + y5 * vz + y6
            fz = -g + (z0 * x + z1 * yy + z2 * dz + z3 * vx + z4 * vy + z5 * vz + z6)
            r2 = x * x + yy * yy + z * z
            rv = x * vx + yy * vy + z * vz
            lam = (vx * vx + vy * vy + vz * vz + x * fx + yy * fy + z * fz + a_b * rv + half_b2 * (r2 - l2)) / r2
            k[s, 0], k[s, 1], k[s, 2] = vx, vy, vz
            k[s, 3], k[s, 4], k[s, 5] = fx - lam * x, fy - lam * yy, fz - lam * z
            if s == 0:
                if j < n:
                    ys[j, step] = y
                    fs[j, step] = k[0]
                if step == 0 and j > 0:
                    ys[j - 1, m] = y
                    fs[j - 1, m] = k[0]
                if i == n * m:
                    return
        for c in range(6):
            acc = 0.0
            for s in range(12):
                acc += b[s] * k[s, c]
            y[c] = y[c] + acc * h


@functools.cache
def compiled_swing_grid() -> Callable:
    """:func:`swing_grid` compiled (:func:`~gyro_instrument.core.jit.compiled`: numba with its cache), or
    the plain function when compilation is off."""
    return jit.compiled(swing_grid)


def linear_point_mass_map(terms, scale_r, scale_v) -> np.ndarray | None:
    """The sum of point-mass terms f(δr, v) as a 3 × 7 matrix ``L`` (f = L[:, :6] [δr, v] + L[:, 6], m/s²)
    when it is affine in the state, else None.

    The constant column is the sum at 0, the others the sum at the unit vectors less it (exact for
    a linear term: Coriolis −2 Ω × v and the centrifugal gradient −Ω × (Ω × δr) are). The map is
    accepted when it matches the sum to 1e-12 of its size at two random probes ``u`` on the
    motion's scales ``scale_r`` (m) and ``scale_v`` (m/s) and at 1000 times them (a quadratic term
    would differ by its own size there)."""
    def total(u):
        out = np.zeros(3)
        for term in terms:
            out += np.array(term(*u), dtype=float)
        return out
    const = total(np.zeros(6))
    lin = np.column_stack([total(np.eye(6)[i]) - const for i in range(6)] + [const])
    rng = np.random.default_rng(27)
    for mag in (1.0, 1e3):
        u = mag * rng.standard_normal(6) * np.array([scale_r] * 3 + [scale_v] * 3)
        want = lin[:, :6] @ u + const
        size = np.max(np.abs(lin[:, :6])) * np.sum(np.abs(u)) + np.max(np.abs(const))
        if not np.all(np.isfinite(want)) or np.max(np.abs(total(u) - want)) > 1e-12 * size:
            return None
    return lin


def fill_samples(grid, rows, segment_s, t, t0, offset, out) -> None:
    """Positions and velocities at times ``t`` into ``out`` (6, len(t)), from a window's grid whose first
    segment starts at ``t0 + offset`` (s; the time taken as (t − t0) − offset):
    :func:`~gyro_instrument.core.parareal.dense_output` on its table ``rows``, or with ``rows`` None its
    compiled kernel :func:`~gyro_instrument.core.parareal.hermite_samples` (the same doubles)."""
    if rows is None:
        compiled_hermite_samples()(grid[0], grid[1], 3, segment_s, t, t0, offset, out)
    else:
        out[:] = dense_output(grid, segment_s, (t - t0) - offset, 3, rows=rows)


class SwingRun(Solver):
    """The fast path of a pendulum (:class:`~.dynamics.SwingDynamics`) from ``t0`` to ``t_end``, window by
    window of whole swings.

    Segments are one swing period T, measured on the first swing of the full model
    (:meth:`~.dynamics.SwingDynamics.first_swing`: Quet's quarter period (42) with the minimum
    deflection β of sec. 2 §II as the guess); the first guess of each swing's start is the window's
    start turned by the apsidal angle per period (sec. 2 §III: the comparison pendulum). Newton-parareal
    then converges the starts on the full equations (``rhs_exact``, every listed effect), so the result
    is the full model to ``shooting_tol``, not the comparison solution. A run of at least
    ``COMPILED_MIN_SWINGS`` swings with numba (``compiled_swings``) integrates the same grid compiled,
    swing after swing (:meth:`~.dynamics.SwingDynamics.serial_window`: the sequential fine solution that
    Newton converges to, without its shooting error) and samples it with the compiled Hermite kernel.
    The run's ceil((t_end − t0)/T) swings are cut into windows of ``WINDOW_SWINGS``; window w + 1 starts
    from the fine end state of window w's last swing, so the state carried is the integrated one and the
    windows do not depend on how the samples are cut into blocks. :meth:`step` converges the next
    window; :meth:`dense_output` is its Hermite interpolant.

    Parameters
    ----------
    dyn : SwingDynamics
        The pendulum (its parameters, right-hand side, window sizes and drivers).
    t0, t_end : float
        Start and end of the run, s.
    r0, v0 : array (3,)
        Bob's position and velocity at ``t0`` (m, m/s; ENU from the suspension point).
    amp : float
        The motion's scale, m (convergence test and difference steps).
    progress : callable or None
        Takes a line of text per parareal pass.

    Attributes
    ----------
    period_s : float
        The swing period T, s.
    segments : int
        Swings in the run.
    info : dict
        The last window's ``parareal`` information (iterations, changes, rhs_columns).
    compiled : tuple or None
        The compiled kernels' arguments when the windows run compiled.
    """

    method = "fast path RK8"

    def __init__(self, dyn, t0, t_end, r0, v0, amp, progress=None) -> None:
        super().__init__(t0, t_end)
        self.dyn, self.progress = dyn, progress
        with self.clock():
            self.period_s, self.phi, self._nfev, _ = dyn.first_swing(r0, v0)
            self.segments = max(1, int(math.ceil((self.t_end - self.t0) / self.period_s)))
            self.per = dyn.WINDOW_SWINGS
            self.scale = np.array([amp] * 3 + [amp * math.sqrt(dyn.context.gravity_m_s2 / dyn.p.length_m)] * 3)
            self.compiled = dyn.compiled_swings(self.scale[0], self.scale[3], self.segments)
        self.window, self.grid, self.rows, self.info = -1, None, None, None
        self.y = np.concatenate([r0, v0])
        self.passes = 0

    @property
    def nfev(self) -> int:
        """Right-hand-side evaluations (× columns for the batched passes) so far, the first swing's included."""
        return self._nfev

    def _offset(self, window) -> float:
        """Start of ``window``'s first swing from ``t0``, s."""
        return (window * self.per) * self.period_s

    def _step_impl(self):
        """The next window of swings: converged (numpy) or integrated (compiled) from the last one's end."""
        self.window += 1
        n_seg = min(self.per, self.segments - self.window * self.per)
        span = (self.window * self.per / self.segments, (self.window * self.per + n_seg) / self.segments)
        self.rows = None                     # the previous window's grid is not needed any more
        if self.compiled is None:
            self.grid = None
            self.grid, self.info, self.y = self.dyn.parareal_window(self.y, n_seg, self.period_s, self.phi,
                                                                    self.scale, self.progress, span)
            self.rows = hermite_rows(self.grid, 3, self.period_s)   # once per window, for every block in it
        else:
            self.grid, self.info, self.y = self.dyn.serial_window(self.compiled, self.y, n_seg, self.period_s, span,
                                                                  self.grid)
        self._nfev += self.info["rhs_columns"]
        self.passes += self.info["iterations"]
        self.t_old = self.t0 + self._offset(self.window)
        self.t = self.t0 + self._offset(self.window) + n_seg * self.period_s

    def _dense_output_impl(self):
        grid, rows, offset = self.grid, self.rows, self._offset(self.window)

        def sol(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            out = np.empty((6, t.size))
            fill_samples(grid, rows, self.period_s, t, self.t0, offset, out)
            return out
        return sol

    def advance(self, t, progress=None) -> Trajectory:
        """Positions and velocities (6, len(t)) at the sample times ``t`` (s, increasing, from the
        previous block's on): every window in turn up to the block's last (the state is carried through
        all), each window's samples read from its grid; ``progress(t)`` after each window."""
        t = np.asarray(t, dtype=float)
        with self.clock():
            y = np.empty((6, t.size))
            last_swing = self.segments - 1

            def win(i):                      # the window of sample i: its swing min(⌊(t − t0) / T⌋, last) // per
                return min(max(math.floor((t[i] - self.t0) / self.period_s), 0), last_swing) // self.per
            if t.size:
                first, last = win(0), win(t.size - 1)
                # the blocks increase, so the windows do: each window's samples are a slice (found by bisection)
                bounds = [bisect.bisect_left(range(t.size), w, key=win) for w in range(first, last + 2)]
                for w in range(first, last + 1):
                    while self.window < w:
                        self.take_step()
                        if progress is not None:
                            progress(self.t)
                    a, b = bounds[w - first], bounds[w - first + 1]
                    if b > a:
                        fill_samples(self.grid, self.rows, self.period_s, t[a:b], self.t0, self._offset(w), y[:, a:b])
        return Trajectory(t, y, self.nfev, self.wall_time_s, self.cpu_time_s, self.method_name(), dict(self.meta))

    def method_name(self) -> str:
        """The method as the trajectories name it: steps per period, compiled or the parareal passes, windows."""
        how = "compiled, serial" if self.compiled is not None else \
            f"{self.passes} parareal pass{'es' if self.passes != 1 else ''}"
        return (f"fast path RK8 ({self.dyn.p.segment_steps} steps/period, {how} in "
                f"{self.window + 1} window{'s' if self.window else ''})")
