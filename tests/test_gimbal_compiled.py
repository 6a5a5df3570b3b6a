"""The gimbal's compiled kernels and driver (issue 27 item 1): ``integrator: compiled``.

* the kernels equal the chain's right-hand side, compiled equal to plain: in
  ``test_gimbal.test_closed_form_is_the_chain``;
* the compiled DOP853 run agrees with the Fortran / scipy drivers of the closed form and with a
  tight reference (Hairer's DOP853 at rtol 1e-13, atol 1e-16) over ``gimbal_paris``'s runs;
* Quet's integrals hold over a long free run; ``auto`` picks it and says why.
"""

import math

import numpy as np
import pytest

from gyro_instrument.core.scene import sample_times
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.core.dop853_fortran import FortranRun
from gyro_instrument.scenes import build_instruments, load_scene

CASES = {  # label: (instrument, overrides, duration s)
    "free": ("gimbal_locked", ["instruments.gimbal_locked.configuration=free"], 5.0),
    "free, massless rings": ("gimbal_locked", ["instruments.gimbal_locked.configuration=free",
                                               "effects={earth_rotation: {}, centrifugal: {}}"], 3.0),
    "free, pivot_damping and spin_decay": ("gimbal_locked", [
        "instruments.gimbal_locked.configuration=free",
        "effects={earth_rotation: {}, centrifugal: {}, ring_inertia: {}, pivot_damping: {time_constant_s: 600}, "
        "spin_decay: {time_constant_s: 3600}}"], 5.0),
    "locked": ("gimbal_locked", [], 120.0),
    "outer_fixed": ("gimbal_outer_fixed", [], 120.0),
}


@pytest.mark.parametrize("label", list(CASES))
def test_compiled_run_agrees_with_the_reference_and_the_closed_form(label):
    """``gimbal_paris`` (rtol 1e-11, atol 1e-13, 20 Hz): the compiled run's angles against Hairer's
    Fortran DOP853 at rtol 1e-13, atol 1e-16 (the bench's reference) and against today's closed-form
    driver (Fortran sample to sample for free rings, scipy dense output otherwise) at the scene's
    tolerance.

    Bounds: (a) the error is at most 100 rtol × the angle's scale (max |angle|): a global error of
    a tolerance-controlled run, rtol per step summed over tens of steps (observed ≤ 5 rtol × scale:
    8e-11 rad over 120 s locked, 6e-14 rad free over 5 s); (b) it is no worse than 3× today's
    driver's error plus rtol × scale (observed 0.9–1.7×: the step sequences differ by round-off in
    the first, round-off-limited, error estimates, then each carries its own ~rtol error)."""
    name, over, duration = CASES[label]
    scene = load_scene("gimbal_paris", [f"duration_s={duration}"] + over)
    g = build_instruments(scene)[name]
    t = sample_times(scene)
    chain = g.build_chain()
    nf = chain.nf
    rhs, y0 = g.closed_form(chain)
    ref = FortranRun(rhs, y0, t[0], 1e-13, 1e-16).advance(t).y[:nf - 1]
    run = g.compiled_run(chain, t[0])
    assert "numba" in run.meta["driver"]
    fast = run.advance(t).y[:nf - 1]
    today = g.closed_form_run(chain, t[0]).advance(t).y[:nf - 1]
    scale = np.max(np.abs(ref), axis=1)
    err, err_today = np.max(np.abs(fast - ref), axis=1), np.max(np.abs(today - ref), axis=1)
    assert np.all(err <= 100 * g.p.rtol * scale), (err, scale)
    assert np.all(err <= 3 * err_today + g.p.rtol * scale), (err, err_today)


@pytest.mark.parametrize("axis", ["vertical", "polar"])
def test_long_free_run_keeps_quets_integrals(axis):
    """60 s of ``gimbal_paris``'s free rings (~8000 nutations at 134 Hz), compiled, auto's choice:
    with no spin torque the rotor's axial momentum p_φ = C (ρ − k cos θ + k' sin θ sin ψ) (eq. 13)
    and the Jacobi integral T_rel − ½ Σ Ωᵀ I Ω are exact; each drifts less than 1e-12 of its size
    (observed 2e-13 and 4e-13 relative: rtol 1e-11 per step, errors of alternating sign over the
    nutations). With PP' polar (k' = 0) §V eq. (2, second), the momentum about Earth's axis, is
    exact too: spread below 1e-12 of C ρ0 (as ``test_gimbal.test_polar_axis_section_V``;
    observed 3e-14)."""
    scene = load_scene("gimbal_paris", ["duration_s=60", "instruments.gimbal_locked.configuration=free",
                                        f"instruments.gimbal_locked.outer_axis={axis}"])
    g = build_instruments(scene)["gimbal_locked"]
    assert g.integrator_choice()[0] == "compiled"
    sim = g.simulate(sample_times(scene))
    assert sim.trajectory.meta["integrator"] == "compiled"
    inv = g.invariants(sim)
    for key in ("spin_13_rad_s", "jacobi_J"):
        assert np.ptp(inv[key]) < 1e-12 * np.max(np.abs(inv[key])), key
    if axis == "polar":
        assert np.ptp(inv["axial_momentum_kg_m2_s"]) < 1e-12 * g.C * g.p.spin_rate_rad_s
    # the nutation was resolved, not averaged: θ moves by the §V eq. (7) swing, ~1e-7 rad
    assert np.ptp(sim.extra["theta"]) > 1e-9


def test_auto_picks_compiled_and_falls_back():
    """``auto`` runs the compiled kernels for free rings and ``describe`` says so (numba and its
    cache); the slow locked and outer-fixed swings keep the closed form, whose dense output already
    runs thousands of times faster than real time, and never import numba (a subprocess); a hinge
    torque not linear in its rate does not fit them: auto falls back to the Python closed form,
    an explicit ``compiled`` is refused by name; with numba off (GYRO_INSTRUMENT_JIT=0) auto
    keeps the closed form (tested in a subprocess: the switch is read once per process)."""
    import os
    import subprocess
    import sys

    from gyro_instrument.api import describe
    from gyro_instrument.core.effect import DAMPING, Effect
    from gyro_instrument.core.errors import SceneError
    from gyro_instrument.core.params import validate_params
    from gyro_instrument.instruments.gimbal import GimbalGyroscope
    from tests.test_gimbal import SITE
    out = describe(load_scene("gimbal_paris", ["instruments.gimbal_locked.configuration=free"]))
    chosen = out["instruments"]["gimbal_locked"]["integrator"]
    assert chosen["chosen"] == "compiled" and "numba" in chosen["reason"], chosen

    class QuadraticDrag(Effect):
        name = "quadratic_drag"
        MECHANICS = frozenset({DAMPING})

        def damping_torque(self, ctx, inertia, rate):
            return -0.05 * inertia * rate * abs(rate)

    effects = {"earth_rotation": EFFECTS["earth_rotation"](), "quadratic_drag": QuadraticDrag()}
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, {"configuration": "free"})
    choice, why = GimbalGyroscope("g", SITE, p, effects).integrator_choice()
    assert choice == "closed_form" and "not linear" in why
    p = validate_params("instruments.g", GimbalGyroscope.PARAMS, {"configuration": "free", "integrator": "compiled"})
    with pytest.raises(SceneError) as err:
        GimbalGyroscope("g", SITE, p, effects)
    assert err.value.field == "g.integrator"
    code = ("from gyro_instrument.scenes import build_instruments, load_scene; "
            "g = build_instruments(load_scene('gimbal_paris', ['instruments.gimbal_locked.configuration=free']))"
            "['gimbal_locked']; print(*g.integrator_choice(), sep='|')")
    env = dict(os.environ, GYRO_INSTRUMENT_JIT="0")
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                         cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    assert res.stdout.startswith("closed_form|") and "GYRO_INSTRUMENT_JIT=0" in res.stdout
    code = ("import sys; from gyro_instrument.core.scene import sample_times; "
            "from gyro_instrument.scenes import build_instruments, load_scene; "
            "scene = load_scene('gimbal_paris', ['duration_s=20']); "
            "sims = [g.simulate(sample_times(scene)) for g in build_instruments(scene).values()]; "
            "print(*[s.trajectory.meta['integrator'] for s in sims]); sys.exit('numba' in sys.modules)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    assert res.stdout.split() == ["closed_form", "closed_form"]


def test_spin_scale_free_gimbal_costs_a_few_evaluations_per_nutation():
    """The compiled run resolves the nutation with the closed form's step count: over 1 s of the
    free rings at 2π·200 rad/s (nutation ≈ 268 Hz) DOP853 needs ~12 steps per nutation at rtol
    1e-11; the count is within 10 % of the Fortran driver's (same method and tolerance)."""
    scene = load_scene("gimbal_paris", ["duration_s=1", "instruments.gimbal_locked.configuration=free",
                                        f"instruments.gimbal_locked.spin_rate_rad_s={2 * math.pi * 200!r}"])
    g = build_instruments(scene)["gimbal_locked"]
    t = sample_times(scene)
    chain = g.build_chain()
    fast, today = g.compiled_run(chain, t[0]), g.closed_form_run(chain, t[0])
    fast.advance(t)
    today.advance(t)
    assert abs(fast.nfev - today.nfev) < 0.1 * today.nfev, (fast.nfev, today.nfev)
