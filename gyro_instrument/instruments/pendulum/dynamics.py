"""The spherical pendulum's equations of motion and integrators (Quet 1853 sec. 2, eq. 21).

:class:`SwingDynamics` holds what :class:`~gyro_instrument.instruments.pendulum.SphericalPendulum`
integrates: the Cartesian constrained right-hand side summing the active effects' point-mass terms
(:meth:`SwingDynamics.rhs_exact`), the small-angle model (:meth:`SwingDynamics.rhs_linear`), the
streamed adaptive DOP853 runs and the fast path (windows of whole swings of a fixed-step RK8: compiled
swing after swing by :func:`swing_grid` for long runs, else Newton-parareal from Quet's comparison
pendulum on numpy). The module docstring of :mod:`gyro_instrument.instruments.pendulum`
gives the equations; :mod:`~gyro_instrument.instruments.pendulum.columns` turns bob states into the
published columns.
"""

import bisect
import functools
import math
import time
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core import dop853, jit
from gyro_instrument.core.angles import Unwrapper
from gyro_instrument.core.effect import CORIOLIS, POINT_MASS
from gyro_instrument.core.integrate import Trajectory, integration
from gyro_instrument.core.parareal import compiled_hermite_samples, dense_output, hermite_rows
from gyro_instrument.instruments.base import Simulation, check_period_count, run_span
# The columns live in .columns; re-exported here, where they were defined.
from gyro_instrument.instruments.pendulum.columns import (angle_arguments, compiled_column_kernels,  # noqa: F401
                                                          compiled_pendulum_columns, pendulum_columns,
                                                          unwrap_in_place)
from gyro_instrument.instruments.pendulum.theory import (apsidal_rate_from_rest_rad_s, min_deflection_from_rest_rad,
                                                         quarter_period_s)



def _swing_frames(U, w0sq):
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
    = [r, v] (m, m/s, ENU), on the equations of :meth:`SwingDynamics.rhs_exact` with the point-mass
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


def _fill_samples(grid, rows, segment_s, t, t0, offset, out) -> None:
    """Positions and velocities at times ``t`` into ``out`` (6, len(t)), from a window's grid whose first
    segment starts at ``t0 + offset`` (s; the time taken as (t − t0) − offset):
    :func:`~gyro_instrument.core.parareal.dense_output` on its table ``rows``, or with ``rows`` None its
    compiled kernel :func:`~gyro_instrument.core.parareal.hermite_samples` (the same doubles)."""
    if rows is None:
        compiled_hermite_samples()(grid[0], grid[1], 3, segment_s, t, t0, offset, out)
    else:
        out[:] = dense_output(grid, segment_s, (t - t0) - offset, 3, rows=rows)


class SwingDynamics:
    """The spherical pendulum's right-hand sides and integrators, mixed into
    :class:`~gyro_instrument.instruments.pendulum.SphericalPendulum` (which supplies ``p``,
    ``context``, ``site``, the effects, :meth:`initial_state` and :meth:`chosen_integrator`)."""

    def point_mass_terms(self) -> list:
        """The active effects' ``point_mass`` terms f(δr, v) -> a (ENU, rotating frame), summing order."""
        terms = (e.point_mass_term(self.context) for e in self.effects_of(POINT_MASS))
        return [f for f in terms if f is not None]

    def rhs_exact(self) -> Callable:
        """Cartesian constrained right-hand side for y = [r, v] (ENU): gravity, the tension and the
        sum of the active effects' point-mass accelerations at δr = r − r_rest (module docstring).
        Accepts a batch of states (y of shape (6, m)) when every term does."""
        l2 = self.p.length_m * self.p.length_m
        g = self.context.gravity_m_s2
        terms = self.point_mass_terms()
        a_b = 2.0 * math.sqrt(g / self.p.length_m)
        b2 = g / self.p.length_m
        zr = -self.p.length_m

        half_b2 = 0.5 * b2

        def rhs(t, y):
            x, yy, z, vx, vy, vz = y
            fx, fy, fz = 0.0, 0.0, -g
            dz = z - zr
            for term in terms:
                ax, ay, az = term(x, yy, dz, vx, vy, vz)
                fx += ax
                fy += ay
                fz += az
            r2 = x * x + yy * yy + z * z
            rv = x * vx + yy * vy + z * vz
            lam = (vx * vx + vy * vy + vz * vz + x * fx + yy * fy + z * fz + a_b * rv
                   + half_b2 * (r2 - l2)) / r2
            return np.array([vx, vy, vz, fx - lam * x, fy - lam * yy, fz - lam * z])
        return rhs

    def rhs_linear(self) -> Callable:
        """Small-angle model for y = [x, y, vx, vy] (horizontal, ENU): ẍ = −(g/l) x plus the
        horizontal part of the active effects' point-mass accelerations, taken on the horizontal
        plane (δr = (x, y, 0), v = (vx, vy, 0): Coriolis from the vertical Earth-rate part, ...)."""
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        terms = self.point_mass_terms()

        def rhs(t, y):
            x, yy, vx, vy = y
            ax, ay = -w0sq * x, -w0sq * yy
            for term in terms:
                tx, ty, _ = term(x, yy, 0.0, vx, vy, 0.0)
                ax += tx
                ay += ty
            return np.array([vx, vy, ax, ay])
        return rhs

    def stream(self, blocks, **options) -> Iterator[Simulation]:
        """Integrate block by block (:meth:`Instrument.stream`), carrying the exact state.

        The adaptive paths (full Cartesian model, linear model) continue one DOP853 step sequence
        bounded by the run's end (:class:`~gyro_instrument.core.integrate.Integration`): the blocks
        concatenate to :meth:`simulate` bit for bit. The parareal path converges windows of
        :attr:`WINDOW_SWINGS` whole swings one after the other, each from the end state of the
        last (:meth:`_stream_parareal`); the windows depend on the run, not on the blocks, so the
        blocks concatenate to :meth:`simulate` bit for bit there too. ``options``: ``progress``
        (callable taking a line of text: parareal passes), ``t_end``.

        Raises
        ------
        SceneError
            The run would hold more swings than can be integrated (``length_m``).
        IntegrationError
            A failed step or a non-finite state.
        """
        blocks, t0, t_end = run_span(blocks, options.pop("t_end", None))
        if t0 is None:
            return
        r0, v0 = self.initial_state()
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        # Absolute tolerances scale with the motion, not the rod: a 1e-9 rad swing on 67 m moves
        # the bob 7e-8 m, which an atol of 1e-12 l would resolve to only 1e-3 of itself.
        w0 = math.sqrt(w0sq)
        check_period_count(f"instruments.{self.name}.length_m", self.p.length_m, 2.0 * math.pi / w0, t_end - t0)
        amp = max(self.p.length_m * math.sin(self.p.initial_deflection_rad), float(np.linalg.norm(v0)) / w0, 1e-12 * self.p.length_m)
        atol_r, atol_v = self.p.rtol * amp, self.p.rtol * amp * w0
        # Vertically tension and gravity cancel (g − λ z ≈ 0): z and v_z carry round-off at the ε g
        # level, which no tolerance may ask to resolve (an inverted bob took 7e6 evaluations).
        atol_z, atol_vz = max(atol_r, 1e-14 * self.p.length_m), max(atol_v, 1e-14 * self.p.length_m * w0)
        unwrappers = (Unwrapper(), Unwrapper())
        if self.chosen_integrator(t_end - t0)[0] == "parareal":
            yield from self._stream_parareal(blocks, t0, t_end, r0, v0, amp, options.get("progress"), unwrappers)
            return
        exact = self.restoring_law() is not None          # finite_amplitude: the exact (Cartesian) model
        if exact:
            run = integration(self.rhs_exact(), np.concatenate([r0, v0]), t0, t_end, rtol=self.p.rtol,
                              atol=np.array([atol_r, atol_r, atol_z, atol_v, atol_v, atol_vz]))
        else:
            run = integration(self.rhs_linear(), [r0[0], r0[1], v0[0], v0[1]], t0, t_end, rtol=self.p.rtol,
                              atol=np.array([atol_r] * 2 + [atol_v] * 2))
        for t in blocks:
            traj = run.advance(t)
            if exact:
                pos, vel = traj.y[:3], traj.y[3:]
            else:
                x, y, vx, vy = traj.y
                rh2 = x * x + y * y
                pos = np.vstack([x, y, -np.sqrt(np.maximum(self.p.length_m ** 2 - rh2, 0.0))])
                vel = np.vstack([vx, vy, np.zeros_like(vx)])
            cols = pendulum_columns(pos, vel, w0sq, unwrappers)
            yield Simulation(t, cols, traj, extra={"position_enu": pos, "velocity_enu": vel})

    def _first_swing(self, r0, v0):
        """Period and apsidal turn of the first swing, from the full equations (DOP853, rtol 1e-12).

        The guess is Quet's: T = 4 × the quarter period (42) between θ0 and the minimum deflection
        β of sec. 2 §II, and a turn of −k′ T with k′ the apsidal rate of sec. 2 §III. The swing is
        then integrated to its second apocentre (x ẋ + y ẏ = 0, decreasing) after 0.9 T: that time and
        the azimuth turned there are the comparison pendulum's period and turn, exact for this
        release, which the first guess of every swing start uses (sec. 2: the non-rotating
        motion turned by k t)."""
        from gyro_instrument.core.dop853 import first_crossing
        k = self.site.k_vertical_rad_s if self.has_term(CORIOLIS) else 0.0
        beta = min_deflection_from_rest_rad(self.p.length_m, self.context.gravity_m_s2, k, self.p.initial_deflection_rad)
        guess = 4.0 * quarter_period_s(self.p.length_m, self.context.gravity_m_s2, self.p.initial_deflection_rad, beta)
        rhs = self.rhs_exact()

        def f(tt, *y):
            return tuple(rhs(tt, np.array(y)).tolist())

        def apocentre(y):
            return y[0] * y[3] + y[1] * y[4]                      # d(x² + y²)/dt / 2
        # DOP853 on floats (core/dop853.py: scipy's method and step control; not scipy.integrate,
        # whose import costs the command line 0.25-0.4 s), the apocentre by bisection on its dense output
        period, y1, sol, nfev = first_crossing(f, np.concatenate([r0, v0]), 1.2 * guess, apocentre,
                                               after=0.9 * guess, rtol=1e-12, atol=1e-14 * self.p.length_m)
        if period is None:
            return guess, -apsidal_rate_from_rest_rad_s(k, self.p.initial_deflection_rad) * guess, nfev, sol
        turn = math.atan2(r0[0] * y1[1] - r0[1] * y1[0], r0[0] * y1[0] + r0[1] * y1[1])
        return period, turn, nfev, sol

    def comparison_solution(self, t) -> tuple:
        """Quet's comparison pendulum (sec. 2): the first swing of the full model (DOP853, rtol
        1e-12), repeated every period and turned about the vertical by its apsidal angle each time
        — the non-rotating motion turned by k t, with the swing's exact period and turn. Exact
        for the first swing; it misses what the horizontal Earth rate and the slow change of the
        ellipse do later (the parareal fast path adds them). Returns (position, velocity, nfev)."""
        r0, v0 = self.initial_state()
        period, turn, nfev, sol = self._first_swing(r0, v0)
        t = np.asarray(t, dtype=float) - float(t[0])
        n = np.floor(t / period)
        y = sol(t - n * period)
        c, s = np.cos(n * turn), np.sin(n * turn)
        out = y.copy()
        for b in (0, 3):
            out[b] = c * y[b] - s * y[b + 1]
            out[b + 1] = s * y[b] + c * y[b + 1]
        return out[:3], out[3:], nfev

    #: Swings per parareal window of a streamed run: memory ~10 kB per swing at 48 steps (the grid
    #: of positions and derivatives, the Newton pass's stages), so a window of 2048 swings (9.3 h of
    #: the 67 m pendulum) holds ~20 MB whatever the duration; long enough that the Python overhead
    #: of a window (~600 batched right-hand-side calls per Newton pass) stays small against the
    #: numpy work it drives (the whole ``simulate`` of a sidereal day at 20 Hz to Parquet, median of 3
    #: with the CPU shared: one window of 5 247 swings 2.4 s and 203 MB peak RSS, windows of 2048
    #: swings 2.6 s and 164 MB, of 512 swings 2.6 s and 145 MB; the times differ within the noise).
    WINDOW_SWINGS = 2048

    def _parareal_window(self, y_start, n_seg, period, phi, scale, progress, span=(0.0, 1.0)):
        """Newton-parareal over ``n_seg`` whole swings from ``y_start`` (:func:`~gyro_instrument.core.
        parareal.parareal`); first guess of each swing's start: ``y_start`` turned about the vertical by
        ``phi`` per swing (Quet's comparison pendulum, sec. 2). Returns (grid, info, end state)."""
        from gyro_instrument.core.parareal import parareal
        ang = phi * np.arange(n_seg + 1)
        pred = np.empty((n_seg + 1, 6))
        for b in (0, 3):
            pred[:, b] = np.cos(ang) * y_start[b] - np.sin(ang) * y_start[b + 1]
            pred[:, b + 1] = np.sin(ang) * y_start[b] + np.cos(ang) * y_start[b + 1]
            pred[:, b + 2] = y_start[b + 2]
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        _, grid, info = parareal(self.rhs_exact(), y_start, period, pred, self.p.segment_steps, scale,
                                 tol=self.p.shooting_tol, align=lambda U: _swing_frames(U, w0sq), progress=progress,
                                 span=span)
        return grid, info, grid[0][-1, :, -1].copy()

    #: Fewest swings of a run the fast path integrates compiled (:meth:`compiled_swings`). Loading
    #: numba and its cached kernels costs a process ~0.7 s CPU once (numba's import 0.4 s, the first
    #: kernel 0.25 s), while the numpy Newton-parareal costs ~0.2 ms per swing (a sidereal day of the
    #: 67 m pendulum, 5 247 swings at 20 Hz: 1.05 s against 0.25 s compiled): shorter runs (the
    #: shipped hour: 220 swings) stay on numpy, so that a command's first message is not delayed by
    #: numba; runs of more than a window of swings are compiled.
    COMPILED_MIN_SWINGS = 2048

    def compiled_swings(self, scale_r, scale_v, swings) -> tuple | None:
        """(kernel, lin, consts) for :func:`swing_grid` when the fast path runs compiled: a run of at least
        :attr:`COMPILED_MIN_SWINGS` ``swings``, kernels compiled (:func:`~gyro_instrument.core.jit.enabled`)
        and the active point-mass terms affine (:func:`linear_point_mass_map` on the motion's scales,
        m and m/s); else None (Newton-parareal on numpy, :meth:`_parareal_window`)."""
        if swings < self.COMPILED_MIN_SWINGS or not jit.enabled():
            return None
        lin = linear_point_mass_map(self.point_mass_terms(), scale_r, scale_v)
        if lin is None:
            return None
        g, l = self.context.gravity_m_s2, self.p.length_m
        consts = np.array([g, 2.0 * math.sqrt(g / l), 0.5 * (g / l), l * l, -l])
        return compiled_swing_grid(), lin, consts

    def _serial_window(self, compiled, y_start, n_seg, period, span, buffers=None):
        """The fast path compiled: :func:`swing_grid` over ``n_seg`` swings from ``y_start``, the
        sequential fine solution (what :meth:`_parareal_window` converges to, with no shooting error).
        Returns (grid, info, end state) as :meth:`_parareal_window`; the grid is written into
        ``buffers`` (the previous window's grid, no longer needed) when they hold ``n_seg`` swings."""
        from gyro_instrument.core.integrate import report
        kernel, lin, consts = compiled
        m = self.p.segment_steps
        if buffers is None or buffers[0].shape[0] < n_seg:
            buffers = (np.empty((n_seg, m + 1, 6)), np.empty((n_seg, m + 1, 6)))
        ys, fs = buffers[0][:n_seg], buffers[1][:n_seg]
        kernel(np.array(y_start, dtype=float), period / m, m, n_seg, lin, consts, dop853.A, dop853.B, ys, fs)
        if not np.all(np.isfinite(fs[-1, -1])):          # a non-finite state stays so to the window's end
            from gyro_instrument.core.errors import IntegrationError
            raise IntegrationError("compiled RK8: a swing became non-finite")
        report(span[1])
        info = {"iterations": 1, "changes": [], "rhs_columns": n_seg * m * dop853.N_STAGES + 1, "compiled": True}
        return (ys, fs), info, ys[-1, -1].copy()

    def _stream_parareal(self, blocks, t0, t_end, r0, v0, amp, progress, unwrappers):
        """The fast path (:mod:`gyro_instrument.core.parareal`), window by window of whole swings.

        Segments are one swing period T, measured on the first swing of the full model
        (:meth:`_first_swing`: Quet's quarter period (42) with the minimum deflection β of sec. 2 §II
        as the guess); the first guess of each swing's start is the window's start turned by the
        apsidal angle per period (sec. 2 §III: the comparison pendulum). Newton-parareal then
        converges the starts on the full equations (:meth:`rhs_exact`, every listed effect), so the
        result is the full model to ``shooting_tol``, not the comparison solution. A run of at least
        :attr:`COMPILED_MIN_SWINGS` swings with numba (:meth:`compiled_swings`) integrates the same grid
        compiled, swing after swing (:meth:`_serial_window`: the sequential fine solution that Newton
        converges to, without its shooting error), samples it with the compiled Hermite kernel and forms
        the columns with :func:`compiled_pendulum_columns` (the same doubles as :func:`pendulum_columns`). The run's
        ceil((t_end − t0)/T) swings are cut into windows of :attr:`WINDOW_SWINGS`; window w + 1 starts
        from the fine end state of window w's last swing, so the state carried is the integrated one
        and the windows do not depend on how the samples are cut into blocks."""
        c0, w0t = time.process_time(), time.perf_counter()
        cpu = wall = 0.0                     # this generator's own time (not the consumer's between blocks)
        period, phi, evals, _ = self._first_swing(r0, v0)
        n_total = max(1, int(math.ceil((t_end - t0) / period)))
        per = self.WINDOW_SWINGS
        scale = np.array([amp] * 3 + [amp * math.sqrt(self.context.gravity_m_s2 / self.p.length_m)] * 3)
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        compiled = self.compiled_swings(scale[0], scale[3], n_total)
        window, grid, info, y_next = -1, None, None, np.concatenate([r0, v0])
        passes = 0
        for t in blocks:
            if c0 is None:
                c0, w0t = time.process_time(), time.perf_counter()
            y = np.empty((6, t.size))

            def win(i):                      # the window of sample i: its swing min(⌊(t − t0) / T⌋, last) // per
                return min(max(math.floor((t[i] - t0) / period), 0), n_total - 1) // per
            first, last = win(0), win(t.size - 1)
            # the blocks increase, so the windows do: each window's samples are a slice (found by bisection)
            bounds = [bisect.bisect_left(range(t.size), w, key=win) for w in range(first, last + 2)]
            for w in range(first, last + 1):
                while window < w:            # every window in turn: the state is carried through all
                    window += 1
                    n_seg = min(per, n_total - window * per)
                    span = (window * per / n_total, (window * per + n_seg) / n_total)   # of the run, for progress
                    rows = None                      # the previous window's grid is not needed any more
                    if compiled is None:
                        grid = None
                        grid, info, y_next = self._parareal_window(y_next, n_seg, period, phi, scale, progress, span)
                        rows = hermite_rows(grid, 3, period)  # once per window, for every block in it
                    else:
                        grid, info, y_next = self._serial_window(compiled, y_next, n_seg, period, span, grid)
                    evals += info["rhs_columns"]
                    passes += info["iterations"]
                a, b = bounds[w - first], bounds[w - first + 1]
                if b > a:
                    _fill_samples(grid, rows, period, t[a:b], t0, (w * per) * period, y[:, a:b])
            pos, vel = y[:3], y[3:]
            cols = (pendulum_columns if compiled is None else compiled_pendulum_columns)(pos, vel, w0sq, unwrappers)
            cpu, wall = cpu + time.process_time() - c0, wall + time.perf_counter() - w0t
            c0 = None
            how = "compiled, serial" if compiled is not None else f"{passes} parareal pass{'es' if passes != 1 else ''}"
            traj = Trajectory(t, y, evals, wall, cpu,
                              f"fast path RK8 ({self.p.segment_steps} steps/period, {how} in "
                              f"{window + 1} window{'s' if window else ''})")
            yield Simulation(t, cols, traj, extra={"position_enu": pos, "velocity_enu": vel, "parareal": info,
                                                   "period_s": period, "segments": n_total})
