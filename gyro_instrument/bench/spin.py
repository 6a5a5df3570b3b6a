"""Work-precision of the spinning bodies' integrators (issue 27 item 1), one table for the bench.

Each instrument whose rotor spins far faster than the motion its scene measures has a study module
``bench/spin_<name>.py`` with ``work_precision_rows(quick, progress) -> list[dict]`` (keys
:data:`SPIN_WP_HEADER`): its spin integrators (splitting of the exact symmetric-top flow with the slow
torques, reductions by the cyclic coordinates, compiled drivers, averaged models) against DOP853 at
several tolerances, the error of the output angles against a tight DOP853 reference over the same span,
the CPU per simulated second and the drift of a conserved quantity over the run. This module runs them
and builds the summary's table (:mod:`.cost_studies` writes ``spin_work_precision.csv``).
"""

import importlib

#: The studies' modules (``gyro_instrument.bench.<name>``), one per spinning instrument type.
SPIN_STUDIES = ("spin_free", "spin_puiseux", "spin_gimbal")

#: Columns of ``spin_work_precision.csv`` (the keys every study's rows carry).
SPIN_WP_HEADER = ("instrument", "integrator", "setting", "simulated_s", "cpu_s", "real_time_factor",
                  "max_error_rad", "invariant", "invariant_drift")


def spin_work_precision_rows(quick=False, progress=print) -> list:
    """Every study's rows (dicts with the keys of :data:`SPIN_WP_HEADER`), in :data:`SPIN_STUDIES` order."""
    rows = []
    for name in SPIN_STUDIES:
        progress(f"spin integrators: {name}")
        mod = importlib.import_module(f"gyro_instrument.bench.{name}")
        for r in mod.work_precision_rows(quick, progress):
            rows.append({k: r.get(k) for k in SPIN_WP_HEADER})
    return rows


def _g(x, spec):
    return "—" if x is None or x == "" else format(x, spec)


def spin_summary_lines(rows) -> list:
    """summary.md's table of the spin integrators' work-precision."""
    lines = ["## Spinning bodies: work-precision of the spin integrators against DOP853", "",
             "Error: largest difference of the output angles from a tight DOP853 reference over the same span. "
             "Drift: largest relative change of the conserved quantity over the run.", "",
             "| instrument | integrator | setting | simulated s | CPU s | x real time | max error (rad) | invariant | drift |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['instrument']} | {r['integrator']} | {r['setting']} | {_g(r['simulated_s'], '.4g')} | "
                     f"{_g(r['cpu_s'], '.3g')} | {_g(r['real_time_factor'], '.3g')} | {_g(r['max_error_rad'], '.2e')} | "
                     f"{r['invariant'] or '—'} | {_g(r['invariant_drift'], '.1e')} |")
    return lines
