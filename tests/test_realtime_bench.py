"""The real-time-factor study (``gyro_instrument.bench.realtime``, issue 13 item 5) covers every
instrument configuration of every shipped scene. The speeds themselves are measured by
``gyro-instrument bench`` (docs/bench/realtime.md), not asserted here."""

import math

from gyro_instrument.bench.realtime import EXTRA_VARIANTS, REALTIME_HEADER, measure_realtime, realtime_rows, variants
from gyro_instrument.scenes import build_instruments, load_scene, shipped_scene_names


def test_every_instrument_and_choice_is_a_row():
    """Each instrument of each shipped scene appears as shipped and with every other choice of its
    configuration, integrator and model parameters (counted from the classes' PARAMS)."""
    for scene_name in shipped_scene_names():
        listed = variants(scene_name)
        for name, inst in build_instruments(load_scene(scene_name)).items():
            mine = [label for n, label, _ in listed if n == name]
            choices = sum(len(p.choices) - 1 for p in inst.PARAMS
                          if p.name in ("configuration", "integrator", "model") and p.choices)
            assert mine[0] == "as shipped" and len(mine) == 1 + choices, (scene_name, name)
    assert all(load_scene(s, over) for s, _, _, over in EXTRA_VARIANTS)


def test_a_refused_combination_is_reported_not_raised():
    """gimbal_locked switched to outer_fixed keeps its initial outer angle, which the scene checks
    refuse: the row carries the reason (field and value) instead of a number."""
    rows = realtime_rows(progress=lambda *_: None, scenes=["gimbal_paris"], target_cpu_s=0.01, repeats=1)   # probes
    row = dict(zip(REALTIME_HEADER, next(r for r in rows if r[1] == "gimbal_locked"
                                         and r[3] == "configuration=outer_fixed")))
    assert row["real_time_factor"] is None and "initial_outer_angle_deg" in row["note"]
    shipped = dict(zip(REALTIME_HEADER, next(r for r in rows if r[1] == "gimbal_locked" and r[3] == "as shipped")))
    assert shipped["integrator"] == "closed_form" and shipped["simulated_s"] <= 600.0
    assert math.isclose(shipped["real_time_factor"], shipped["simulated_s"] / shipped["cpu_s"])


def test_measure_respects_the_scene_duration():
    """A run is sized to the CPU target but never past the scene's duration_s (puiseux_spheroid: 20 s)."""
    _, d, cpu, wall, nfev, _ = measure_realtime("puiseux_spheroid", "spheroid", ["duration_s=0.5"], 0.05, 0.2)
    assert 0.2 <= d <= 0.5 and cpu > 0 and wall > 0 and nfev > 0
