"""The pendulum's fast path against a compiled fixed-step RK8 on the same equations (issue 27 item 2).

The yardstick is what a compiled program on this machine does with the Foucault run: the 67 m
pendulum of ``foucault_pantheon`` released at 2° over a sidereal day (86 164 s, output at 20 Hz),
integrated serially by the 8th-order formula of DOP853's tableau (Hairer, Nørsett & Wanner; the
doubles of :mod:`gyro_instrument.core.dop853`) at a fixed 48 steps per swing, on the rotating-frame
equations of :meth:`~gyro_instrument.instruments.pendulum.dynamics.SwingDynamics.rhs_exact`
written out here from the site's Earth rate Ω (ENU), g and l:

    r̈ = g + a(δr, v) − λ r,   a = −2 Ω × v − Ω × (Ω × δr),   δr = r − (0, 0, −l),
    λ = (|v|² + r · (g + a) + 2 √(g/l) (r · v) + (g / 2l) (|r|² − l²)) / |r|²,

(the tension keeping |r| = l, with the constraint's drift damped as in the module docstring of
:mod:`gyro_instrument.instruments.pendulum`). :func:`rk8_reference` is that loop, compiled by
:func:`gyro_instrument.core.jit.compiled` (numba); it keeps only the end state, at the last
sample time (the last step shortened to reach it), and its CPU is the loop's alone (the step
comes from the swing period the fast path measures on its first swing).

:func:`compiled_reference_rows` measures, in one run and interleaved (median of :data:`REPEATS` CPU times,
``time.process_time``), that reference and the fast path (``simulate`` of the scene as shipped,
``integrator: auto``: every sample's columns at 20 Hz included), with both end errors: the
swing-plane azimuth at the last sample against DOP853 at rtol 1e-13 on the full equations (the
tight reference of :func:`gyro_instrument.bench.work_precision.foucault_work_precision`).
"""

import functools
import math
import os
import statistics
import time
from collections.abc import Callable

import numpy as np

from gyro_instrument.core import dop853, jit

#: The fast path's CPU may be at most this many times the compiled reference's (issue 27 item 2).
GOAL_RATIO = 2.5

#: Steps per swing of the reference (the fast path's default ``segment_steps``).
STEPS_PER_SWING = 48

#: Interleaved runs of each, of which the median CPU is reported: the fast path's output (1.7 million
#: samples, ~170 MB) is fresh memory each run, whose page faults (system time, part of the CPU) vary
#: from run to run on a shared machine; ``cpu_system_s`` reports that part.
REPEATS = 5


def rk8_reference(y0, h, n_steps, h_last, g, length, omega, a, b) -> np.ndarray:
    """Kernel: ``n_steps`` RK8 steps of ``h`` (s), then one of ``h_last`` (s), from ``y0`` = [r, v]
    (m, m/s, ENU, rotating frame); returns the end state. ``omega``: Earth rate Ω (rad/s, ENU);
    ``g`` (m/s²), ``length`` l (m); ``a`` (12 × 12), ``b`` (12,): the 8th-order formula of DOP853's
    tableau. The equations are the module docstring's. Plain Python on floats and arrays, compiled
    by :func:`~gyro_instrument.core.jit.compiled`."""
    ox, oy, oz = omega[0], omega[1], omega[2]
    o2 = ox * ox + oy * oy + oz * oz
    stab_v, stab_r, l2 = 2.0 * math.sqrt(g / length), 0.5 * (g / length), length * length
    k = np.empty((12, 6))
    y = y0.copy()
    st = np.empty(6)
    for step in range(n_steps + 1):
        hs = h if step < n_steps else h_last
        for s in range(12):
            for c in range(6):
                acc = 0.0
                for r in range(s):
                    acc += a[s, r] * k[r, c]
                st[c] = y[c] + acc * hs
            rx, ry, rz, vx, vy, vz = st[0], st[1], st[2], st[3], st[4], st[5]
            dz = rz + length
            od = ox * rx + oy * ry + oz * dz                      # Ω · δr
            ax = -2.0 * (oy * vz - oz * vy) + o2 * rx - od * ox   # Coriolis + centrifugal gradient
            ay = -2.0 * (oz * vx - ox * vz) + o2 * ry - od * oy
            az = -2.0 * (ox * vy - oy * vx) + o2 * dz - od * oz - g
            r2 = rx * rx + ry * ry + rz * rz
            lam = (vx * vx + vy * vy + vz * vz + rx * ax + ry * ay + rz * az
                   + stab_v * (rx * vx + ry * vy + rz * vz) + stab_r * (r2 - l2)) / r2
            k[s, 0], k[s, 1], k[s, 2] = vx, vy, vz
            k[s, 3], k[s, 4], k[s, 5] = ax - lam * rx, ay - lam * ry, az - lam * rz
        for c in range(6):
            acc = 0.0
            for s in range(12):
                acc += b[s] * k[s, c]
            y[c] = y[c] + acc * hs
    return y


@functools.cache
def compiled_rk8_reference() -> Callable:
    """:func:`rk8_reference` compiled (numba, cached), or the plain function when compilation is off."""
    return jit.compiled(rk8_reference)


def _scene(duration_s, **params):
    from gyro_instrument.core.scene import sample_times
    from gyro_instrument.scenes import build_instruments, load_scene
    over = [f"duration_s={duration_s}", "sample_rate_hz=20"]
    over += [f"instruments.pendulum.{k}={v}" for k, v in params.items()]
    scene = load_scene("foucault_pantheon", over)
    return build_instruments(scene)["pendulum"], sample_times(scene)


def reference_run(p, t_end_s, steps_per_swing=STEPS_PER_SWING) -> tuple:
    """The compiled reference over [0, ``t_end_s``] for the pendulum ``p``: (end state [r, v], CPU s of
    the loop). Step = the first swing's period (as the fast path measures it) / ``steps_per_swing``."""
    period = p.first_swing(*p.initial_state())[0]
    h = period / steps_per_swing
    n_steps = int(math.floor(t_end_s / h))
    from gyro_instrument.core.effect import CENTRIFUGAL_GRADIENT, CORIOLIS, SINE_LAW, uncarried_terms
    held = {CORIOLIS, CENTRIFUGAL_GRADIENT, SINE_LAW}                 # the terms the reference's kernel holds
    other = [e.name for e in p.effects.values() if uncarried_terms(e, held, p.MECHANICS)]
    if other:
        raise ValueError(f"compiled reference: {', '.join(other)} are not terms of its equations")
    omega = p.site.earth_rate_enu() if p.has_term(CORIOLIS) else np.zeros(3)
    if not p.has_term(CENTRIFUGAL_GRADIENT) and np.any(omega):
        raise ValueError("compiled reference: the Coriolis term without the centrifugal gradient is not its equations")
    kernel = compiled_rk8_reference()
    y0 = np.concatenate(p.initial_state())
    c0 = time.process_time()
    y = kernel(y0, h, n_steps, t_end_s - n_steps * h, p.context.gravity_m_s2, p.p.length_m,
               np.asarray(omega, dtype=float), dop853.A, dop853.B)
    return y, time.process_time() - c0


def _end_azimuth(p, y) -> float:
    from gyro_instrument.instruments.pendulum.columns import pendulum_columns
    cols = pendulum_columns(y[:3, None], y[3:, None], p.context.gravity_m_s2 / p.p.length_m)
    return float(cols["swing_azimuth"][-1])


def _tight_reference(duration_s, progress) -> float:
    """Swing azimuth (rad) at the last sample from DOP853 at rtol 1e-13 (the work-precision study's
    reference, reused when that study ran in this process)."""
    from gyro_instrument.bench import work_precision as wp
    key = (duration_s, 20.0)
    if key not in wp.REFERENCE:
        progress(f"  reference: DOP853 rtol 1e-13 over {duration_s:g} s")
        p, t = _scene(duration_s, rtol=1e-13, integrator="adaptive")
        wp.REFERENCE[key] = float(p.simulate(t).columns["swing_azimuth"][-1])
    return wp.REFERENCE[key]


def compiled_reference_rows(quick=False, progress=print) -> list[dict]:
    """Two rows measured in one run: the compiled reference (:func:`rk8_reference`) and the fast
    path (``simulate`` of ``foucault_pantheon`` as shipped, ``integrator: auto``) over a sidereal
    day (``quick``: one hour, compiled although shorter than
    :attr:`~gyro_instrument.instruments.pendulum.dynamics.SwingDynamics.COMPILED_MIN_SWINGS`), each
    with its CPU (median of :data:`REPEATS`, interleaved), its CPU over the reference's, its end error (swing azimuth at the last sample against DOP853 rtol 1e-13, rad)
    and the numba status line (:func:`gyro_instrument.core.jit.status`). Keys: ``case``, ``method``,
    ``simulated_s``, ``cpu_s`` (median of :data:`REPEATS`), ``cpu_system_s`` (its system part),
    ``cpu_ratio``, ``goal``, ``met``, ``end_error_rad``, ``numba``."""
    from gyro_instrument.bench.work_precision import wrapped
    duration = 3600.0 if quick else 86164.0989          # a sidereal day (2π / n)
    p, t = _scene(duration)
    if quick:               # one hour is shorter than the compiled path's minimum run: asked for here
        p.COMPILED_MIN_SWINGS = 1
    p.simulate(t)                                        # loads (or compiles) the fast path's kernels
    reference_run(p, 1.0)                                # and the reference's
    ref_cpu, fast_cpu, fast_sys = [], [], []
    for _ in range(REPEATS):
        y, cpu = reference_run(p, float(t[-1]))
        ref_cpu.append(cpu)
        c0, s0 = time.process_time(), os.times().system
        sim = p.simulate(t)
        fast_cpu.append(time.process_time() - c0)
        fast_sys.append(os.times().system - s0)
    rc, fc = statistics.median(ref_cpu), statistics.median(fast_cpu)
    progress(f"  compiled reference {rc:.3f} s CPU, fast path {fc:.3f} s CPU over {duration:g} s")
    tight = _tight_reference(duration, progress)
    ref_err = abs(wrapped(_end_azimuth(p, y) - tight))
    fast_err = abs(wrapped(float(sim.columns["swing_azimuth"][-1]) - tight))
    case = f"Foucault pendulum 67 m, {duration:g} s at 20 Hz"
    common = {"case": case, "simulated_s": float(t[-1]), "numba": jit.status()}
    return [{**common, "method": f"compiled reference: serial fixed-step RK8 (DOP853 tableau), "
                                 f"{STEPS_PER_SWING} steps/swing, end state only",
             "cpu_s": rc, "cpu_system_s": 0.0, "cpu_ratio": 1.0, "goal": "", "met": True, "end_error_rad": ref_err},
            {**common, "method": f"fast path (integrator: auto, every 20 Hz sample's columns): "
                                 f"{sim.trajectory.method}",
             "cpu_s": fc, "cpu_system_s": statistics.median(fast_sys), "cpu_ratio": fc / rc,
             "goal": f"<= {GOAL_RATIO:g}", "met": fc / rc <= GOAL_RATIO, "end_error_rad": fast_err}]


if __name__ == "__main__":
    import sys
    for row in compiled_reference_rows(quick="--quick" in sys.argv[1:]):
        print(row)
