"""Work-precision of the free gyroscope's spin integrators (issue 27 item 1).

The free gyroscope of the ``free_gyroscope`` scene (Paris, axis horizontal toward the east, μ = 1,
ρ0 = 60 rad/s, 1 Hz) without ``earth_rotation`` (so that the heavy top's energy is a constant) and
with a mass unbalance: the centre of mass 0.1 mm along
the figure axis (m = 1 kg, A = 1e-3 kg m²), a gravity torque m g d k × (−up) that precesses the
axis at ≈ 0.016 rad/s — the classic drift of a free gyro. Integrated by ``model: numerical`` with

* ``splitting`` of orders 2, 4 and 6 (:mod:`gyro_instrument.core.rigid_body_flow`), the step set by
  ``rtol`` through the measured law of
  :meth:`~gyro_instrument.instruments.free_gyroscope.FreeGyroscope.splitting_step`;
* ``dop853`` (quaternion + Euler equations) at several ``rtol``: Hairer's DOP853 compiled
  (:mod:`gyro_instrument.core.dop853_jit` on :func:`~gyro_instrument.core.rigid_body_flow.rhs_kernel`,
  the scene's path with numba), and one row of the same method on Python floats (the path with
  ``GYRO_INSTRUMENT_JIT=0``, the same steps) for the speed-up.

Error: the largest difference of the output angles (axis altitude and azimuth, rad) from DOP853 at
rtol 1e-13 (atol 1e-14) over every sample of the same span. Invariant: the energy of the heavy
(Lagrange) top, E = T + m g d k·up, its largest departure from its initial value relative to
m g d (the scale of the exchange between the potential and the transverse kinetic energy; T itself
is dominated by the constant spin energy). CPU time
is ``time.process_time`` of ``simulate`` after a warm-up run (the compiled kernel is loaded once).
"""

import time

import numpy as np

from gyro_instrument.core import jit
from gyro_instrument.core.scene import sample_times
from gyro_instrument.scenes import build_instruments, load_scene

KEYS = ("instrument", "integrator", "setting", "simulated_s", "cpu_s", "real_time_factor", "max_error_rad",
        "invariant", "invariant_drift")

#: The torqued configuration: the shipped scene with the numerical model and a 0.1 mm mass unbalance.
TORQUED = ("effects=null", "instruments.free_gyro.model=numerical", "instruments.free_gyro.center_of_mass_offset_m=1e-4")

#: (integrator, splitting order or None, rtols) of the rows.
SETTINGS = (("splitting", 2, (1e-6, 1e-8)), ("splitting", 4, (1e-6, 1e-8, 1e-10)),
            ("splitting", 6, (1e-6, 1e-8, 1e-10, 1e-12)), ("dop853", None, (1e-6, 1e-8, 1e-10, 1e-12)))

#: rtols of the DOP853 rows on Python floats (``compiled=False``), beside the compiled ones.
PYTHON_DOP853_RTOLS = (1e-10,)


def _simulate(duration_s, integrator, order, rtol, compiled=True):
    over = list(TORQUED) + [f"duration_s={duration_s!r}", f"instruments.free_gyro.integrator={integrator}",
                            f"instruments.free_gyro.rtol={rtol!r}"]
    if order is not None:
        over.append(f"instruments.free_gyro.splitting_order={order}")
    scene = load_scene("free_gyroscope", over)
    g = build_instruments(scene)["free_gyro"]
    t = sample_times(scene)
    c0 = time.process_time()
    sim = g.simulate(t) if compiled else g.simulate(t, compiled=False)
    return g, sim, time.process_time() - c0


def _angles(sim):
    return np.vstack([sim.columns["axis_altitude"], sim.columns["axis_azimuth"]])


def _energy_drift(g, sim):
    mgd = g.p.rotor_mass_kg * g.site.gravity_m_s2 * g.p.center_of_mass_offset_m
    energy = sim.extra["kinetic_energy_j"] + mgd * sim.extra["axis_inertial"][:, 2]
    return float(np.max(np.abs(energy - energy[0])) / abs(mgd))


def work_precision_rows(quick=False, progress=print) -> list:
    """Rows (dicts with :data:`KEYS`) for the torqued free gyroscope over 60 s (5 s with ``quick``):
    every (integrator, setting) of :data:`SETTINGS`, and DOP853 on Python floats at
    :data:`PYTHON_DOP853_RTOLS`, against DOP853 at rtol 1e-13."""
    duration = 5.0 if quick else 60.0
    _simulate(1.0, "splitting", 6, 1e-8)                         # warm-up: load the compiled kernels
    _simulate(1.0, "dop853", None, 1e-8)
    progress(f"  free gyroscope work-precision: reference DOP853 rtol 1e-13 over {duration:g} s")
    _, ref, _ = _simulate(duration, "dop853", None, 1e-13)
    ref_angles = _angles(ref)
    rows = []
    runs = [(integrator, order, rtol, True) for integrator, order, rtols in SETTINGS for rtol in rtols]
    runs += [("dop853", None, rtol, False) for rtol in PYTHON_DOP853_RTOLS]
    for integrator, order, rtol, compiled in runs:
        driver = "compiled" if compiled and jit.enabled() else "Python floats"
        progress(f"  free gyroscope work-precision: {integrator} order {order} rtol {rtol:g} ({driver})")
        g, sim, cpu = _simulate(duration, integrator, order, rtol, compiled)
        setting = f"{driver}, rtol {rtol:g}" if order is None else \
            f"order {order}, rtol {rtol:g}, step {g.splitting_step():.3g} s"
        rows.append({"instrument": "free_gyroscope free_gyro, unbalance 0.1 mm (precession 0.016 rad/s), "
                                   "60 rad/s, n = 0, 1 Hz",
                     "integrator": integrator, "setting": setting, "simulated_s": duration, "cpu_s": cpu,
                     "real_time_factor": duration / cpu if cpu > 0 else float("inf"),
                     "max_error_rad": float(np.max(np.abs(_angles(sim) - ref_angles))),
                     "invariant": "energy T + m g d k·up (/ m g d)",
                     "invariant_drift": _energy_drift(g, sim)})
    return rows


if __name__ == "__main__":
    for row in work_precision_rows(quick=False):
        print(row)
