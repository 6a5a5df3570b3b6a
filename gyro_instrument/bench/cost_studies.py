"""Issue 27's cost studies in ``gyro-instrument bench``: the spinning bodies' integrators, the
pendulum's fast path against a compiled reference, and the sweep's throughput.

* :func:`gyro_instrument.bench.spin.spin_work_precision_rows` → ``spin_work_precision.csv``;
* :func:`gyro_instrument.bench.compiled_reference.compiled_reference_rows` → ``compiled_reference.csv``
  and a ``targets.csv`` row (the fast path's CPU over the compiled RK8's, goal ≤ 2.5);
* :func:`gyro_instrument.bench.sweep_bench.sweep_throughput_rows` → ``sweep_throughput.csv``
  (rows/s on the process pool and on a two-worker Dask ``LocalCluster`` on loopback).
"""

import csv
import os

from gyro_instrument.core.files import replaced_atomically


def _write_dicts(path, rows):
    """Write dict rows (all with the first row's keys, in its order) as CSV, atomically."""
    with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def cost_studies(out_dir, quick=False, progress=print) -> tuple:
    """Run the three studies, write their CSVs into ``out_dir`` and return (``targets.csv`` rows as
    (target, measured, unit, goal, met), summary.md lines)."""
    from gyro_instrument.bench.compiled_reference import GOAL_RATIO, compiled_reference_rows
    from gyro_instrument.bench.spin import spin_summary_lines, spin_work_precision_rows
    from gyro_instrument.bench.sweep_bench import sweep_throughput_rows
    progress("spinning bodies: work-precision of the spin integrators")
    spin = spin_work_precision_rows(quick, progress)
    _write_dicts(os.path.join(out_dir, "spin_work_precision.csv"), spin)
    progress("the pendulum's fast path against a compiled fixed-step RK8 (same run)")
    cr = compiled_reference_rows(quick, progress)
    _write_dicts(os.path.join(out_dir, "compiled_reference.csv"), cr)
    progress("sweep throughput: process pool and a two-worker Dask LocalCluster")
    sw = sweep_throughput_rows(quick, progress)
    _write_dicts(os.path.join(out_dir, "sweep_throughput.csv"), sw)
    ref, fast = cr
    targets = [(f"{fast['case']}: fast path CPU / compiled fixed-step RK8 on the same equations, same run "
                f"(reference {ref['cpu_s']:.3g} s, fast path {fast['cpu_s']:.3g} s; end errors "
                f"{ref['end_error_rad']:.1e} / {fast['end_error_rad']:.1e} rad; {fast['numba']})",
                fast["cpu_ratio"], "x", f"<= {GOAL_RATIO:g}", bool(fast["met"]))]
    lines = [""] + spin_summary_lines(spin)
    lines += ["", "## The pendulum's fast path against a compiled reference (same run)", "",
              "| case | method | CPU s (median) | of which system | / reference | end error (rad) | numba |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['case']} | {r['method']} | {r['cpu_s']:.3g} | {r['cpu_system_s']:.3g} | {r['cpu_ratio']:.2f} | "
              f"{r['end_error_rad']:.1e} | {r['numba']} |" for r in cr]
    lines += ["", "## Sweep throughput (`gyro-instrument sweep`'s runner, same grid and seeds)", "",
              "| executor | scene | grid | seeds | rows | wall s | rows/s | executor start s | rows equal the pool's |",
              "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['scheduler']} | {r['scene']} {r['overrides']} | {r['vary']} | {r['seeds']} | {r['rows']} | "
              f"{r['wall_s']:.3g} | {r['rows_per_s']:.3g} | {r['startup_s']:.3g} | {r['same_rows_as_process_pool']} |"
              for r in sw]
    return targets, lines
