"""``gyro-instrument sweep``: any scene over a grid of overridden values, seeds measured on each point.

A grid is the product of ``--vary KEY=START:STOP:STEP`` ranges (STOP included when it lands on the
grid, within 1e-9 of a STEP; at most :data:`MAX_POINTS` points). Each point's overrides are checked
by loading the scene once before anything runs. Each point is one task — one simulation, then every
seed measured and estimated on it (:func:`gyro_instrument.estimators.pipeline.seed_sweep`) — through
any ``concurrent.futures`` executor (a process pool by default; a Dask client's executor with
``--scheduler``). A point whose estimate is refused (``InadequateData``) or whose task fails twice
(a worker that died: the task is retried once) keeps its rows with the reason in ``error``.

One row per (point, seed): the varied values (columns named by their keys), ``seed``, every field
of the estimate JSON flattened (nested dicts as dotted names, lists as JSON text, None as null;
the truth as ``truth.*``) and ``error``. Written as Parquet with pyarrow.
"""

import itertools
import json
import math
import os
import time

from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.files import opened_unless_utf8, replaced_atomically
from gyro_instrument.core.jsonable import to_jsonable
from gyro_instrument.core.parallel import run_tasks
from gyro_instrument.estimators.pipeline import seed_sweep

#: Most grid points a sweep accepts.
MAX_POINTS = 10_000
VARY_FORM = "must be KEY=START:STOP:STEP with finite numbers, STEP > 0 and STOP >= START " \
            "(e.g. site.latitude_deg=0:60:30)"


def _number(text, key, part):
    try:
        v = int(text)
    except ValueError:
        try:
            v = float(text)
        except ValueError:
            raise SceneError(f"--vary {key} {part}", text, VARY_FORM) from None
    if not math.isfinite(v):
        raise SceneError(f"--vary {key} {part}", text, VARY_FORM)
    return v


def parse_vary(spec) -> tuple:
    """``KEY=START:STOP:STEP`` -> (key, values). STOP is included when START + k·STEP lands on it
    within 1e-9·STEP; integers stay integers when START and STEP are.

    Raises
    ------
    SceneError
        No '=', not three numbers, STEP <= 0, STOP < START, or over :data:`MAX_POINTS` values.
    """
    if "=" not in spec:
        raise SceneError("--vary", spec, VARY_FORM)
    key, rng = (s.strip() for s in spec.split("=", 1))
    parts = rng.split(":")
    if not key or len(parts) != 3:
        raise SceneError("--vary", spec, VARY_FORM)
    start, stop, step = (_number(p.strip(), key, name) for p, name in zip(parts, ("START", "STOP", "STEP")))
    if step <= 0:
        raise SceneError(f"--vary {key} STEP", step, "must be > 0")
    if stop < start:
        raise SceneError(f"--vary {key} STOP", stop, f"must be >= START ({start})")
    span = (stop - start) / step
    k = round(span)
    on_grid = abs(start + k * step - stop) <= 1e-9 * abs(step)
    n = (k if on_grid else math.floor(span)) + 1
    if n > MAX_POINTS:
        raise SceneError(f"--vary {key}", rng, f"gives {n} values: at most {MAX_POINTS} grid points")
    values = [start + i * step for i in range(n)]
    if on_grid:
        values[-1] = stop
    return key, values


def grid(specs) -> tuple:
    """(keys, points): the product of the ``--vary`` ranges, each point a tuple of values.

    Raises
    ------
    SceneError
        No spec, a key varied twice, a bad spec (:func:`parse_vary`), or over :data:`MAX_POINTS`
        points in all.
    """
    if not specs:
        raise SceneError("--vary", None, "give at least one --vary " + VARY_FORM[5:])
    parsed = [parse_vary(s) for s in specs]
    keys = [k for k, _ in parsed]
    if "seed" in keys:
        raise SceneError("--vary", "seed", "is the scene's seed; the sensor seeds of every point are --seeds N "
                                           "(0..N-1, the 'seed' column)")
    for i, k in enumerate(keys):
        if k in keys[:i]:
            raise SceneError("--vary", k, "is varied twice; give each key once")
    total = math.prod(len(v) for _, v in parsed)
    if total > MAX_POINTS:
        raise SceneError("--vary", " ".join(specs), f"gives {total} grid points: at most {MAX_POINTS}")
    return keys, list(itertools.product(*(v for _, v in parsed)))


def point_overrides(keys, point) -> list:
    """The ``--set`` strings of one grid point."""
    return [f"{k}={v!r}" for k, v in zip(keys, point)]


def check_points(scene, overrides, keys, points) -> None:
    """Load the scene once per grid point (a bad key or value raises its one-line SceneError,
    naming the point's value, before anything runs)."""
    from gyro_instrument.scenes import load_scene
    for point in points:
        load_scene(scene, list(overrides) + point_overrides(keys, point))


def sweep_point(job) -> dict:
    """One grid point: ``job`` = (scene, overrides, seeds) as for ``seed_sweep``. Returns
    ``{"estimates": [...]}`` or ``{"error": reason}`` when the estimate is refused (InadequateData,
    any SceneError) or the integration fails."""
    try:
        return {"estimates": to_jsonable(seed_sweep(job))}
    except (SceneError, IntegrationError) as exc:
        return {"error": f"{type(exc).__name__}: {exc}"}


def flatten(d, prefix="") -> dict:
    """Nested dicts as dotted keys, lists as JSON text, everything else as is."""
    out = {}
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, name + "."))
        elif isinstance(v, (list, tuple)):
            out[name] = json.dumps(v, default=str)
        else:
            out[name] = v
    return out


def run_points(jobs, executor=None, progress=None, task=sweep_point) -> list:
    """``task`` of every job through ``executor`` (default: a process pool), in job order, by
    :func:`gyro_instrument.core.parallel.run_tasks`: a task that raises (a worker that died:
    BrokenProcessPool, Dask's KilledWorker) is retried once, then becomes ``{"error": ...}``;
    ``progress`` gets a line per finished point and per retry."""
    t0 = time.perf_counter()
    on_done = on_retry = None
    if progress:
        def on_done(done, total):
            progress(f"sweep: {done}/{total} points ({time.perf_counter() - t0:.1f} s)")

        def on_retry(i, why):
            progress(f"sweep: point {i + 1} failed ({why}); retrying it once")
    return run_tasks(task, jobs, executor, on_done, on_retry)


def sweep_rows(keys, points, seeds, results) -> list:
    """One dict per (point, seed): varied values, ``seed``, the flattened estimate, ``error``."""
    rows = []
    for point, res in zip(points, results):
        ests = res.get("estimates") or [None] * len(seeds)
        for seed, est in zip(seeds, ests):
            row = dict(zip(keys, point))
            row["seed"] = seed
            if est is not None:
                row.update({k: v for k, v in flatten(est).items() if k not in row})
            row["error"] = res.get("error")
            rows.append(row)
    return rows


def write_rows(path, rows, metadata) -> int:
    """Rows as a Parquet table at ``path`` (columns: the union of the rows' keys in first-seen order,
    absent values null; a column pyarrow cannot type as one kind written as JSON text). Returns
    the column count."""
    from gyro_instrument.estimators.table_read import import_pyarrow
    pa = import_pyarrow()
    names = list(dict.fromkeys(k for r in rows for k in r))
    arrays = []
    for name in names:
        vals = [r.get(name) for r in rows]
        try:
            arrays.append(pa.array(vals, type=pa.string() if name == "error" else None))
        except (pa.ArrowInvalid, pa.ArrowTypeError):
            arrays.append(pa.array([None if v is None else json.dumps(v, default=str) for v in vals]))
    table = pa.Table.from_arrays(arrays, names=names).replace_schema_metadata(metadata)
    with replaced_atomically(path) as tmp:
        import pyarrow.parquet as pq
        with opened_unless_utf8(tmp, "wb") as sink:     # pyarrow takes only UTF-8 names
            pq.write_table(table, sink)
    return len(names)


def run_grid(scene, overrides, keys, points, seeds, executor=None, progress=None, task=sweep_point) -> list:
    """The sweep without a file: ``scene`` with ``overrides`` at each grid point (``keys`` set to the
    point's values, as ``--set`` strings after ``overrides``), ``seeds`` measured on each. Every
    point's scene is loaded first (a bad value raises its SceneError before anything runs), then
    :func:`run_points`. Returns one result per point, in order: ``{"estimates": [one estimate dict
    per seed, JSON-ready]}`` or ``{"error": reason}``. The bench's site sweep and
    :func:`run_sweep` are both this call; ``points`` need not be a product grid."""
    points = [tuple(p) for p in points]
    check_points(scene, overrides, keys, points)
    seeds = list(seeds)
    jobs = [(scene, list(overrides) + point_overrides(keys, p), seeds) for p in points]
    if progress:
        progress(f"sweep: {len(points)} grid points x {len(seeds)} seeds of {scene}")
    return run_points(jobs, executor, progress, task)


def point_estimates(result) -> list:
    """The estimates of one :func:`run_grid` result, one dict per seed; [] for a point refused or
    failed (the bench's studies then give that point a row of NaN, as the sweep gives it null)."""
    return result.get("estimates") or []


def run_sweep(scene, overrides, specs, n_seeds, out, executor=None, progress=None, task=sweep_point) -> dict:
    """The whole sweep into ``out`` (Parquet); returns a summary (points, rows, columns, errors,
    wall_s, rows_per_s). The grid is parsed and every point's scene loaded before anything runs.

    Raises
    ------
    SceneError
        A bad ``--vary``, ``--seeds`` or scene value (one line).
    """
    if not isinstance(n_seeds, int) or n_seeds < 1:
        raise SceneError("--seeds", n_seeds, "must be an integer >= 1")
    keys, points = grid(specs)
    seeds = list(range(n_seeds))
    t0 = time.perf_counter()
    results = run_grid(scene, overrides, keys, points, seeds, executor, progress, task)
    rows = sweep_rows(keys, points, seeds, results)
    wall = time.perf_counter() - t0
    from gyro_instrument import __version__
    meta = {"gyro_instrument.sweep_scene": str(scene), "gyro_instrument.sweep_overrides": json.dumps(list(overrides)),
            "gyro_instrument.sweep_vary": json.dumps(list(specs)), "gyro_instrument.version": __version__}
    ncol = write_rows(out, rows, meta)
    return {"points": len(points), "rows": len(rows), "columns": ncol, "wall_s": wall,
            "errors": sum(1 for r in results if r.get("error")), "rows_per_s": len(rows) / wall if wall else math.nan,
            "path": os.fspath(out)}
