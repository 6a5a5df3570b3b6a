"""Work-precision of the free two-ring gimbal's integrators (issue 27 item 1): CPU per simulated
second against the error, and the drift of the rotor's axial momentum.

The case is ``gimbal_paris``'s ``gimbal_locked`` with free rings (rotor 2π·100 rad/s, nutation
C ρ0 / √((A + A1) u²) ≈ 840 rad/s, 134 Hz) at the scene's 20 Hz, over 10 s (1 s with ``quick``).
Rows, each at rtol 1e-7, 1e-9 and 1e-11 (atol 1e-13):

* ``compiled DOP853 (numba)``: the closed form's numba kernel through
  :class:`~gyro_instrument.core.dop853_jit.CompiledRun` (``integrator: compiled``, auto's choice);
* ``Fortran DOP853 (scipy.integrate.ode)``: the closed form on Python floats through Hairer's
  Fortran code from sample to sample (:class:`~gyro_instrument.core.dop853_fortran.FortranRun`,
  ``integrator: closed_form``).

Error: the largest difference of the output angles (``outer_angle`` ψ − 90°, ``inner_angle``,
rad) over every sample from the Fortran driver at rtol 1e-13, atol 1e-16 (the tightest that runs
in reasonable time; the closed form equals the chain's right-hand side to round-off,
``tests/test_gimbal.py``). Invariant: eq. (13), p_φ / C = ρ − k cos θ + k' sin θ sin ψ (the
rotor's absolute spin: exact with no spin torque), its largest relative change over the run.
CPU: ``time.process_time`` of the run after an untimed warm-up (numba's cache loaded, ~0.6 s
once per process).

No averaged (nutation-free) model is listed: its neglected nutation (§V eq. 7, ~1e-7 rad here)
is four orders above the scene's tolerance (rtol 1e-11 × the O(1) rad angles).
"""

import math
import time

import numpy as np

#: Output keys of every row (common to the spin-integrator studies of issue 27).
KEYS = ("instrument", "integrator", "setting", "simulated_s", "cpu_s", "real_time_factor", "max_error_rad",
        "invariant", "invariant_drift")

#: Relative tolerances of the rows; atol of every row (rad, rad/s) and of the reference.
RTOLS = (1e-7, 1e-9, 1e-11)
ATOL, REF_RTOL, REF_ATOL = 1e-13, 1e-13, 1e-16


def _free_gimbal(duration_s):
    from gyro_instrument.core.scene import sample_times
    from gyro_instrument.scenes import build_instruments, load_scene
    scene = load_scene("gimbal_paris", [f"duration_s={duration_s!r}", "instruments.gimbal_locked.configuration=free"])
    return build_instruments(scene)["gimbal_locked"], sample_times(scene)


def _spin_drift(g, y) -> float:
    """Largest relative change of eq. (13) over states ``y`` (free layout ψ, θ, φ, ψ̇, θ̇, φ̇)."""
    from gyro_instrument.instruments.gimbal.theory import spin_invariant
    psi, theta, psid, phid = y[0], y[1], y[3], y[5]
    inv = spin_invariant(phid + psid * np.cos(theta), theta, psi, g.k, g.k_prime)
    return float(np.max(np.abs(inv - inv[0])) / abs(inv[0]))


def work_precision_rows(quick=False, progress=print) -> list:
    """Rows (dicts with :data:`KEYS`) of the free gimbal's integrators; see the module docstring.
    ``quick``: 1 s simulated (~5 s of CPU in all)."""
    from gyro_instrument.core.dop853_fortran import FortranRun
    from gyro_instrument.core.dop853_jit import CompiledRun
    from gyro_instrument.instruments.gimbal.kernels import compiled_kernel
    duration = 1.0 if quick else 10.0
    g, t = _free_gimbal(duration)
    chain = g.build_chain()
    rhs, y0 = g.closed_form(chain)
    name, params = g.kernel_params(chain)
    kernel = compiled_kernel(name)
    CompiledRun(kernel, params, y0, t[0], 1e-7, ATOL).advance(t[:2])          # warm-up: numba's cache
    progress(f"  spin_gimbal: reference (Fortran DOP853, rtol {REF_RTOL:g}, atol {REF_ATOL:g}), {duration:g} s")
    ref = FortranRun(rhs, y0, t[0], REF_RTOL, REF_ATOL).advance(t).y[:2]
    makers = (("compiled DOP853 (numba)", lambda rtol: CompiledRun(kernel, params, y0, t[0], rtol, ATOL)),
              ("Fortran DOP853 (scipy.integrate.ode)", lambda rtol: FortranRun(rhs, y0, t[0], rtol, ATOL)))
    rows = []
    for rtol in RTOLS:
        for label, make in makers:
            progress(f"  spin_gimbal: {label}, rtol {rtol:g}")
            c0 = time.process_time()
            y = make(rtol).advance(t).y
            cpu = time.process_time() - c0
            rows.append({"instrument": "gimbal_paris gimbal_locked, free rings (nutation 134 Hz), 20 Hz",
                         "integrator": label, "setting": f"rtol {rtol:g}, atol {ATOL:g}",
                         "simulated_s": duration, "cpu_s": cpu,
                         "real_time_factor": duration / cpu if cpu > 0 else math.inf,
                         "max_error_rad": float(np.max(np.abs(y[:2] - ref))),
                         "invariant": "p_phi/C (eq. 13)", "invariant_drift": _spin_drift(g, y)})
    return rows


if __name__ == "__main__":
    for row in work_precision_rows(quick=True):
        print(row)
