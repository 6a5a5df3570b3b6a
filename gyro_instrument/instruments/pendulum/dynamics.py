"""The spherical pendulum's equations of motion and integrators (Quet 1853 sec. 2, eq. 21).

:class:`SwingDynamics` holds what :class:`~gyro_instrument.instruments.pendulum.SphericalPendulum`
integrates: the Cartesian constrained right-hand side summing the active effects' point-mass terms
(:meth:`SwingDynamics.rhs_exact`), the small-angle model (:meth:`SwingDynamics.rhs_linear`), the
streamed adaptive DOP853 runs and the fast path (:mod:`.fast_path`: windows of whole swings of a fixed-step RK8, compiled
swing after swing by :func:`~.fast_path.swing_grid` for long runs, else Newton-parareal from Quet's comparison
pendulum on numpy). The module docstring of :mod:`gyro_instrument.instruments.pendulum`
gives the equations; :mod:`~gyro_instrument.instruments.pendulum.columns` turns bob states into the
published columns.
"""

import math
from collections.abc import Callable, Iterator

import numpy as np

from gyro_instrument.core import dop853, jit
from gyro_instrument.core.angles import Unwrapper
from gyro_instrument.core.effect import CORIOLIS, POINT_MASS
from gyro_instrument.core.integrate import integration
from gyro_instrument.instruments.base import Simulation, check_period_count, run_span
from gyro_instrument.instruments.pendulum.columns import compiled_pendulum_columns, pendulum_columns
from gyro_instrument.instruments.pendulum.fast_path import (SwingRun, compiled_swing_grid, linear_point_mass_map,
                                                            swing_frames)
from gyro_instrument.instruments.pendulum.theory import (apsidal_rate_from_rest_rad_s, min_deflection_from_rest_rad,
                                                         quarter_period_s)



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
        last (:class:`~.fast_path.SwingRun`); the windows depend on the run, not on the blocks, so the
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
            yield from self._stream_fast(blocks, t0, t_end, r0, v0, amp, options.get("progress"), unwrappers)
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

    def first_swing(self, r0, v0) -> tuple:
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
        period, turn, nfev, sol = self.first_swing(r0, v0)
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

    def parareal_window(self, y_start, n_seg, period, phi, scale, progress, span=(0.0, 1.0)) -> tuple:
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
                                 tol=self.p.shooting_tol, align=lambda U: swing_frames(U, w0sq), progress=progress,
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
        """(kernel, lin, consts) for :func:`~.fast_path.swing_grid` when the fast path runs compiled: a run of at least
        :attr:`COMPILED_MIN_SWINGS` ``swings``, kernels compiled (:func:`~gyro_instrument.core.jit.enabled`)
        and the active point-mass terms affine (:func:`linear_point_mass_map` on the motion's scales,
        m and m/s); else None (Newton-parareal on numpy, :meth:`parareal_window`)."""
        if swings < self.COMPILED_MIN_SWINGS or not jit.enabled():
            return None
        lin = linear_point_mass_map(self.point_mass_terms(), scale_r, scale_v)
        if lin is None:
            return None
        g, l = self.context.gravity_m_s2, self.p.length_m
        consts = np.array([g, 2.0 * math.sqrt(g / l), 0.5 * (g / l), l * l, -l])
        return compiled_swing_grid(), lin, consts

    def serial_window(self, compiled, y_start, n_seg, period, span, buffers=None) -> tuple:
        """The fast path compiled: :func:`~.fast_path.swing_grid` over ``n_seg`` swings from ``y_start``, the
        sequential fine solution (what :meth:`parareal_window` converges to, with no shooting error).
        Returns (grid, info, end state) as :meth:`parareal_window`; the grid is written into
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

    def _stream_fast(self, blocks, t0, t_end, r0, v0, amp, progress, unwrappers) -> Iterator[Simulation]:
        """The fast path block by block: one :class:`~.fast_path.SwingRun` advanced over the blocks, the
        columns formed with :func:`compiled_pendulum_columns` when it runs compiled (the same doubles as
        :func:`pendulum_columns`)."""
        run = SwingRun(self, t0, t_end, r0, v0, amp, progress)
        w0sq = self.context.gravity_m_s2 / self.p.length_m
        columns = pendulum_columns if run.compiled is None else compiled_pendulum_columns
        for t in blocks:
            traj = run.advance(t)
            pos, vel = traj.y[:3], traj.y[3:]
            cols = columns(pos, vel, w0sq, unwrappers)
            yield Simulation(t, cols, traj, extra={"position_enu": pos, "velocity_enu": vel, "parareal": run.info,
                                                   "period_s": run.period_s, "segments": run.segments})
