"""Real-time factor of every instrument configuration (issue 13 item 5), and the gimbal's
work-precision study that chooses its integrators.

* :func:`realtime_rows` — for every instrument of every shipped scene, as shipped and with each
  other choice of its ``configuration``, ``integrator`` and ``model`` parameters (one at a time; a
  combination the scene checks refuse is listed with the reason), and the free gimbal's harder
  variants (:data:`EXTRA_VARIANTS`), the simulated seconds per CPU
  second of ``simulate`` at the scene's sample rate and tolerance: the median of three runs that
  together take about ``target_cpu_s`` of CPU (never beyond the scene's ``duration_s``), interleaved
  across the configurations, so slow and fast variants are measured in one ``bench`` run. The goal
  is :data:`GOAL`.
* :func:`gimbal_work_precision_rows` — the two-ring gimbal's error against a tight reference versus
  CPU per simulated second, for the generic hinge chain (``solve_ivp`` DOP853) and the closed form
  (:mod:`gyro_instrument.instruments.gimbal.dynamics`) through three DOP853 drivers: Hairer's
  Fortran code from sample to sample (:class:`~gyro_instrument.core.dop853_fortran.FortranRun`),
  scipy's ``OdeSolver`` with dense output (:func:`~gyro_instrument.instruments.gimbal.runs.dense_run`)
  and the Python-float driver of :mod:`gyro_instrument.core.dop853`; for the free rings (the fast
  nutation) and the locked rings (a slow swing). The rows show why ``integrator: auto`` runs the
  closed form, with the Fortran driver for the free rings and the dense-output driver for the others.

CPU time (``time.process_time``) is the measure: the machine may be shared, and an emulator that
needs a tenth of a CPU second per simulated second keeps up with the clock whenever it gets a
tenth of a core. Wall time is recorded beside it.
"""

import math
import os
import time

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import sample_times
from gyro_instrument.scenes import build_instruments, load_scene, shipped_scene_names

#: Simulated seconds per CPU second every configuration must reach (issue 27 item 1; issue 13 asked 10).
GOAL = 100.0

#: Most probes :func:`_sized_duration` runs to size one configuration's runs.
SIZING_PROBES = 4

#: Parameters whose choices are an instrument's configurations and integrator variants.
VARIANT_PARAMS = ("configuration", "integrator", "model")

#: Variants beyond the parameters' choices, (scene, instrument, label, overrides): the free gimbal
#: with massless rings (faster nutation, μρ0/sin θ), twice the spin (twice the nutation rate), at
#: 100 Hz and 1 kHz, with PP' along Earth's axis, and with bearing and pivot friction.
EXTRA_VARIANTS = tuple(
    ("gimbal_paris", "gimbal_locked", f"configuration=free, {label}",
     ["instruments.gimbal_locked.configuration=free"] + over)
    for label, over in (
        ("massless rings (no ring_inertia)", ["effects={earth_rotation: {}, centrifugal: {}}"]),
        ("spin 2π·200 rad/s", ["instruments.gimbal_locked.spin_rate_rad_s=1256.6370614359173"]),
        ("100 Hz", ["sample_rate_hz=100"]),
        ("1 kHz", ["sample_rate_hz=1000"]),
        ("PP' polar", ["instruments.gimbal_locked.outer_axis=polar"]),
        ("pivot_damping and spin_decay", ["effects={earth_rotation: {}, centrifugal: {}, ring_inertia: {}, "
                                          "pivot_damping: {time_constant_s: 600}, "
                                          "spin_decay: {time_constant_s: 3600}}"]))) + (
    ("gimbal_paris", "gimbal_locked", "as shipped, 1 kHz", ["sample_rate_hz=1000"]),
    # the free gyroscope's numerical model: DOP853 (compiled, core.dop853_jit) resolving every nutation,
    # and a 0.1 mm mass unbalance (auto: the splitting)
    ("free_gyroscope", "free_gyro", "model=numerical, integrator=dop853",
     ["instruments.free_gyro.model=numerical", "instruments.free_gyro.integrator=dop853"]),
    ("free_gyroscope", "free_gyro", "model=numerical, center_of_mass_offset_m=1e-4",
     ["instruments.free_gyro.model=numerical", "instruments.free_gyro.center_of_mass_offset_m=1e-4"]),)

REALTIME_HEADER = ("scene", "instrument", "type", "variant", "integrator", "simulated_s", "sample_rate_hz",
                   "cpu_s", "wall_s", "real_time_factor", "nfev", "met", "note")

WP_HEADER = ("case", "driver", "rtol", "simulated_s", "cpu_s", "real_time_factor", "nfev", "max_error_rad")


def variants(scene_name) -> list:
    """(instrument, variant label, overrides) of one shipped scene: each instrument as shipped, then
    each other choice of its :data:`VARIANT_PARAMS`, one at a time."""
    scene = load_scene(scene_name)
    out = []
    for name, inst in build_instruments(scene).items():
        out.append((name, "as shipped", []))
        for p in inst.PARAMS:
            if p.name in VARIANT_PARAMS and p.choices:
                for choice in p.choices:
                    if choice != inst.params[p.name]:
                        out.append((name, f"{p.name}={choice}", [f"instruments.{name}.{p.name}={choice}"]))
    return out


def _timed_simulate(scene_name, name, overrides, duration_s):
    scene = load_scene(scene_name, list(overrides) + [f"duration_s={duration_s!r}"])
    inst = build_instruments(scene)[name]
    t = sample_times(scene)
    w0, c0 = time.perf_counter(), time.process_time()
    sim = inst.simulate(t)
    return inst, sim, time.process_time() - c0, time.perf_counter() - w0


def _sized_duration(scene_name, name, overrides, each_cpu_s, probe_s):
    """Simulated seconds of one run of ~``each_cpu_s`` CPU, at most the scene's ``duration_s``.

    A probe of ``probe_s`` simulated seconds is lengthened (at least doubled each time, at most
    :data:`SIZING_PROBES` probes, after one untimed warm-up) until it costs half of ``each_cpu_s``: a run whose cost is mostly
    a fixed start-up (the parareal path's first window, a driver's set-up) is not scaled linearly
    from a probe that measured only that start-up, so the factor is the instrument's running rate.
    Raises SceneError when the scene checks refuse the configuration."""
    full = load_scene(scene_name, overrides).duration_s
    d = min(full, probe_s)
    _timed_simulate(scene_name, name, overrides, d)      # warm-up: first imports, compiled kernels' cache
    for _ in range(SIZING_PROBES):
        _, _, cpu, _ = _timed_simulate(scene_name, name, overrides, d)
        if cpu >= 0.5 * each_cpu_s or d >= full:
            break
        d = min(full, d * max(2.0, each_cpu_s / max(cpu, 1e-3)))
    return d


def _timed_summary(scene_name, name, overrides, duration_s):
    """One timed run, kept small: (instrument, CPU s, wall s, nfev, integrator); the samples are
    dropped at once (a sweep holds three runs of every configuration)."""
    inst, sim, cpu, wall = _timed_simulate(scene_name, name, overrides, duration_s)
    meta = sim.trajectory.meta if sim.trajectory is not None else {}
    integrator = meta.get("integrator") or meta.get("driver") or getattr(sim.trajectory, "method", "")
    nfev = sim.trajectory.nfev if sim.trajectory is not None else 0
    return inst, cpu, wall, nfev, integrator


def _median_run(runs, d):
    """(instrument, simulated s, CPU s, wall s, nfev, integrator) of the run of median CPU."""
    inst, cpu, wall, nfev, integrator = sorted(runs, key=lambda r: r[1])[len(runs) // 2]
    return inst, d, cpu, wall, nfev, integrator


def measure_realtime(scene_name, name, overrides, target_cpu_s=3.0, probe_s=1.0, repeats=3) -> tuple:
    """(instrument, simulated s, CPU s, wall s, nfev, integrator) of one configuration: a probe of
    ``probe_s`` simulated seconds, then ``repeats`` runs each sized to ~``target_cpu_s / repeats`` of
    CPU (at most the scene's ``duration_s``), back to back; the run of median CPU is returned.
    Raises SceneError when the scene checks refuse the configuration."""
    d = _sized_duration(scene_name, name, overrides, target_cpu_s / repeats, probe_s)
    return _median_run([_timed_summary(scene_name, name, overrides, d) for _ in range(repeats)], d)


def realtime_rows(quick=False, progress=print, scenes=None, target_cpu_s=None, repeats=None) -> list:
    """Rows of :data:`REALTIME_HEADER` for every configuration of every shipped scene (or ``scenes``):
    the median of ``repeats`` runs (default 3; 1 with ``quick``, a smoke run of the study) that
    together take ~``target_cpu_s`` of CPU (default 3 s; 0.3 s with ``quick``).

    The repeats are interleaved: every configuration once, then every configuration again, so a
    configuration's runs lie minutes apart. On the shared 2-core virtual machine a slow spell of the
    host lasted ~2 minutes and made every row measured in it 1.5-2.4x slower (the plane gyroscopes
    and pendulums too, not one instrument): back-to-back repeats all fell inside it."""
    target = target_cpu_s or (0.3 if quick else 3.0)
    repeats = repeats or (1 if quick else 3)
    cases = [(sc, *v) for sc in scenes or shipped_scene_names() for v in variants(sc)]
    cases += [v for v in EXTRA_VARIANTS if scenes is None or v[0] in scenes]
    sized, refused, runs = {}, {}, {i: [] for i in range(len(cases))}
    for rep in range(repeats):
        for i, (scene_name, name, label, overrides) in enumerate(cases):
            if i in refused:
                continue
            progress(f"  real time ({rep + 1}/{repeats}): {scene_name}/{name} {label}")
            if i not in sized:
                try:
                    sized[i] = _sized_duration(scene_name, name, overrides, target / repeats, 1.0)
                except SceneError as e:
                    refused[i] = f"refused by the scene checks: {e}"
                    continue
            runs[i].append(_timed_summary(scene_name, name, overrides, sized[i]))
    rows = []
    for i, (scene_name, name, label, overrides) in enumerate(cases):
        if i in refused:
            rows.append((scene_name, name, "", label, "", None, None, None, None, None, None, None, refused[i]))
            continue
        inst, d, cpu, wall, nfev, integ = _median_run(runs[i], sized[i])
        rate = load_scene(scene_name, overrides).sample_rate_hz
        rtf = d / cpu if cpu > 0 else math.inf
        rows.append((scene_name, name, inst.type_name, label, integ, d, rate, cpu, wall, rtf, nfev, rtf >= GOAL, ""))
    return rows


# ------------------------------------------------------------------ the gimbal's work-precision
def _gimbal(configuration, duration_s, integrator="closed_form"):
    over = [f"duration_s={duration_s!r}", f"instruments.gimbal_locked.integrator={integrator}"]
    if configuration == "free":
        over.append("instruments.gimbal_locked.configuration=free")
    scene = load_scene("gimbal_paris", over)
    return build_instruments(scene)["gimbal_locked"], sample_times(scene)


def _angles(y, nf):
    """The swinging coordinates (ψ, and θ when free) of states in the chain's layout."""
    return y[:nf - 1]


def gimbal_work_precision_rows(quick=False, progress=print) -> list:
    """Rows of :data:`WP_HEADER`: the gimbal of ``gimbal_paris`` (``gimbal_locked``) with free rings
    over 1 s (0.3 s with ``quick``) and with the rings locked over 600 s (120 s), at 20 Hz.

    Error: the largest difference of the swinging angles (ψ, θ; rad) from the closed form at rtol
    1e-13 and atol 1e-16 through the Fortran driver, over every sample. The closed form equals the
    chain's right-hand side to round-off (``tests/test_gimbal.py``), so it may serve as the
    reference of both."""
    from gyro_instrument.core.integrate import integrate
    from gyro_instrument.core.dop853_fortran import FortranRun
    from gyro_instrument.instruments.gimbal.runs import dense_run
    from gyro_instrument.instruments.gimbal.instrument import ATOL
    rows = []
    cases = (("free rings (nutation 134 Hz)", "free", 0.3 if quick else 1.0, (1e-7, 1e-9, 1e-11)),
             ("locked rings (swing 17.2 s)", "locked", 120.0 if quick else 600.0, (1e-7, 1e-9, 1e-11)))
    for label, conf, dur, rtols in cases:
        g, t = _gimbal(conf, dur)
        chain = g.build_chain()
        rhs, y0 = g.closed_form(chain)
        nf = chain.nf
        progress(f"  gimbal work-precision: {label}, reference")
        ref = _angles(FortranRun(rhs, y0, t[0], 1e-13, 1e-16).advance(t).y, nf)
        case = f"gimbal_paris gimbal_locked, {label}, {dur:g} s at 20 Hz"

        def add(driver, rtol, run):
            c0 = time.process_time()
            y, nfev = run()
            cpu = time.process_time() - c0
            err = float(np.max(np.abs(_angles(y, nf) - ref)))
            rows.append((case, driver, rtol, dur, cpu, dur / cpu if cpu > 0 else math.inf, nfev, err))

        for rtol in rtols:
            progress(f"  gimbal work-precision: {label}, rtol {rtol:g}")
            for driver, make in (("closed form, Fortran DOP853 sample to sample", FortranRun),
                                 ("closed form, scipy DOP853 dense output", dense_run)):
                def run(make=make, rtol=rtol):
                    r = make(rhs, y0, t[0], rtol, ATOL)
                    return r.advance(t).y, r.nfev
                add(driver, rtol, run)

            def scalar(rtol=rtol):
                tr = integrate(rhs, y0, t, method="DOP853-scalar", rtol=rtol, atol=ATOL)
                return tr.y, tr.nfev
            add("closed form, DOP853 on Python floats (core.dop853)", rtol, scalar)

            def chain_run(rtol=rtol):
                tr = integrate(chain.rhs, np.asarray(y0), t, rtol=rtol, atol=ATOL)
                return tr.y, tr.nfev
            add("hinge chain, solve_ivp DOP853", rtol, chain_run)
    return rows


# ------------------------------------------------------------------ the table
def _fmt(x, spec):
    return "—" if x is None else format(x, spec)


def summary_lines(rt, wp) -> list:
    """Markdown for ``summary.md`` (and the table of docs/bench/README.md)."""
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    below = [r for r in rt if r[11] is False]
    lines = [f"## Real-time factor of every instrument configuration (simulated s per CPU s; goal >= {GOAL:g})", "",
             f"Each shipped scene's instruments as shipped and with each other `configuration`, `integrator` "
             f"and `model` choice, at the scene's sample rate and tolerance; the median of three interleaved runs of ~1 s of CPU each "
             f"(load average {load:.1f} during the run). {len(below)} below the goal.", "",
             "| scene | instrument | variant | integrator | simulated s | CPU s | wall s | x real time | met |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rt:
        d = dict(zip(REALTIME_HEADER, r))
        if d["note"]:
            lines.append(f"| {d['scene']} | {d['instrument']} | {d['variant']} | — | — | — | — | — | "
                         f"{d['note']} |")
            continue
        lines.append(f"| {d['scene']} | {d['instrument']} | {d['variant']} | {d['integrator']} | "
                     f"{d['simulated_s']:.4g} | {d['cpu_s']:.3g} | {d['wall_s']:.3g} | "
                     f"{d['real_time_factor']:.3g} | {'yes' if d['met'] else '**no**'} |")
    lines += ["", "## Gimbal work-precision (error of ψ, θ against the closed form at rtol 1e-13)", "",
              "| case | driver | rtol | CPU s | x real time | RHS evaluations | max error (rad) |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| {c} | {dr} | {rt_:g} | {cpu:.3g} | {f:.3g} | {n} | {e:.2e} |"
              for c, dr, rt_, _, cpu, f, n, e in wp]
    return lines


def realtime_target(rt) -> tuple:
    """The ``targets.csv`` row: the slowest configuration's real-time factor against :data:`GOAL`."""
    done = [r for r in rt if r[9] is not None]
    slow = min(done, key=lambda r: r[9])
    below = sum(1 for r in done if not r[11])
    return (f"every instrument configuration of every shipped scene >= {GOAL:g}x real time (slowest: {slow[0]}/"
            f"{slow[1]} {slow[3]}; {below} of {len(done)} below)", slow[9], "x real time (CPU)", f">= {GOAL:g}",
            below == 0)


def write_realtime(out_dir, rt, wp) -> list:
    """Write ``realtime.csv`` and ``gimbal_work_precision.csv`` to ``out_dir``; return the paths."""
    import csv

    from gyro_instrument.core.files import replaced_atomically
    paths = []
    for fname, header, rows in (("realtime.csv", REALTIME_HEADER, rt), ("gimbal_work_precision.csv", WP_HEADER, wp)):
        path = os.path.join(out_dir, fname)
        with replaced_atomically(path) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            w.writerows(rows)
        paths.append(path)
    return paths


def main(argv=None) -> int:
    """``python -m gyro_instrument.bench.realtime [--quick] [--out DIR]``: this study alone (the
    CSVs and ``realtime.md`` in ``DIR``); ``gyro-instrument bench`` runs it with the others."""
    import argparse
    ap = argparse.ArgumentParser(prog="python -m gyro_instrument.bench.realtime", description=main.__doc__)
    ap.add_argument("--quick", action="store_true", help="one short run (~0.3 s of CPU) per configuration")
    ap.add_argument("--out", default="bench_out", help="output directory (default: bench_out)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    rt = realtime_rows(args.quick)
    wp = gimbal_work_precision_rows(args.quick)
    write_realtime(args.out, rt, wp)
    text = "\n".join(["# Real-time factors and the gimbal's work-precision", "",
                      f"Regenerate: `python -m gyro_instrument.bench.realtime{' --quick' if args.quick else ''} "
                      f"--out {args.out}` (also part of `gyro-instrument bench`).", ""]
                     + [f"Target: {realtime_target(rt)[0]}: {'met' if realtime_target(rt)[4] else 'NOT met'}.", ""]
                     + summary_lines(rt, wp)) + "\n"
    with open(os.path.join(args.out, "realtime.md"), "w") as fh:
        fh.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
