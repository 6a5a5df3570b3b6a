"""``simulate``: every instrument of a scene on the common sample grid, in memory or streamed block
by block into a table (CSV or Parquet), with a progress line on a terminal."""

import math
import os
import shutil
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import replaced_atomically, shown
from gyro_instrument.core.motion import ship_columns
from gyro_instrument.core.scene import sample_times

def simulate_scene(scene, progress=None) -> tuple:
    """Simulate every instrument of a scene on the common sample grid.

    Returns
    -------
    t : ndarray
    columns : dict
        ``<instrument>.<column>`` -> array (radians, rad/s, metres).
    sims : dict
        instrument name -> Simulation (nfev, wall time).
    """
    from gyro_instrument.scenes import build_instruments
    t = sample_times(scene)
    columns, sims = {}, {}
    for name, inst in build_instruments(scene).items():
        if progress:
            progress(f"simulating {name} ({inst.type_name}) for {scene.duration_s:g} s")
        with terminal_progress(f"  {name}", enabled=progress is not None):
            sim = inst.simulate(t)
        sims[name] = sim
        columns.update(table_columns(name, inst, sim.columns))
    columns.update(ship_columns(scene.motion, t))
    return t, columns, sims


def table_columns(name, inst, sim_columns) -> dict:
    """``<name>.<column>`` -> array of one instrument's simulated columns as a table holds them: each
    channel the sensor reads with an offset as it reads it, noise-free (a horizontal gyroscope's
    ``angle`` on its scale, u + M: :func:`~gyro_instrument.instruments.observation_azimuth.read_on_scale`,
    the doubles ``estimate`` measures), the others as simulated."""
    from gyro_instrument.instruments.observation_azimuth import read_on_scale
    read = read_on_scale(inst.observation(), {c.name: sim_columns[c.name] for c in inst.COLUMNS})
    return {f"{name}.{c}": v for c, v in read.items()}


def scale_readings(insts) -> dict:
    """``{<name>.<channel>: offset (deg)}`` of the columns a table holds as scale readings (u + M, M the
    mount azimuth wrapped to (-180, 180]): the table's ``gyro_instrument.scale_readings``."""
    return {f"{n}.{c}": math.degrees(off) for n, inst in insts.items()
            for c, off in inst.observation().reading_offsets().items()}


#: Samples per block of a streamed ``simulate`` (each instrument's :meth:`stream`): large enough
#: that the per-block overhead (a few numpy calls per column) is negligible, small enough that a
#: block of every column is a few MB.
SIMULATE_BLOCK_SAMPLES = 65536


def output_step(scene, output_rate_hz) -> int:
    """Keep every k-th sample for ``--output-rate-hz`` (k = sample_rate_hz / output_rate_hz, 1 when
    None): the integration and its sample grid are unchanged.

    Raises
    ------
    SceneError
        On ``--output-rate-hz`` when the rate is not positive and finite, exceeds the sample rate or
        does not divide it.
    """
    if output_rate_hz is None:
        return 1
    rate = scene.sample_rate_hz
    valid = f"a rate in (0, {rate:g}] Hz that divides the scene's sample_rate_hz = {rate:g} Hz " \
            f"(sample_rate_hz / output_rate_hz a whole number)"
    if not (math.isfinite(output_rate_hz) and 0.0 < output_rate_hz <= rate * (1 + 1e-12)):
        raise SceneError("--output-rate-hz", output_rate_hz, valid)
    k = round(rate / output_rate_hz)
    if abs(rate / output_rate_hz - k) > 1e-9 * k:
        raise SceneError("--output-rate-hz", output_rate_hz, valid)
    return k


def check_disk(path, rows, columns, free=None) -> None:
    """Refuse an output that would not fit on its disk, before the run starts.

    Raises
    ------
    SceneError
        On ``--out``: "needs ~N bytes (R rows x C columns, B bytes a value); F bytes free".
    """
    from gyro_instrument.estimators.data_io import BYTES_PER_VALUE, output_bytes, table_kind
    need = output_bytes(path, rows, columns)
    if free is None:
        free = shutil.disk_usage(os.path.dirname(os.path.abspath(path)) or ".").free
    if need > free:
        raise SceneError("--out", path, f"needs ~{need:.4g} bytes ({rows} rows x {columns} columns at "
                                        f"~{BYTES_PER_VALUE[table_kind(path)]:g} bytes a value); {free} bytes "
                                        f"free on its disk: shorten duration_s, lower --output-rate-hz or "
                                        f"write elsewhere")


def stream_scene(scene, block_samples=SIMULATE_BLOCK_SAMPLES, progress=None) -> Iterator[tuple]:
    """Simulate every instrument of a scene block by block on the common sample grid.

    Each instrument streams (:meth:`~gyro_instrument.instruments.base.Instrument.stream` over its
    own :func:`~gyro_instrument.core.scene.sample_blocks`); the blocks concatenate to
    :func:`simulate_scene` bit for bit for an instrument that ``STREAMS`` (the others run once
    and are sliced).

    Yields
    ------
    (t, columns, sims)
        One block: sample times (s), ``<instrument>.<column>`` -> array, instrument name ->
        Simulation of the block (its trajectory's nfev and wall time count the run so far).
    """
    from gyro_instrument.core.integrate import report
    from gyro_instrument.core.scene import sample_blocks
    from gyro_instrument.scenes import build_instruments
    window_s = block_samples / scene.sample_rate_hz
    times = sample_blocks(scene, window_s)
    span = times.end_s or 1.0
    insts = build_instruments(scene)
    if not all(i.STREAMS for i in insts.values()):
        from gyro_instrument.core.memory import check_memory
        check_memory(scene)          # an instrument that does not stream holds its whole run
    if progress:
        progress(f"simulating {', '.join(f'{n} ({i.type_name})' for n, i in insts.items())} for "
                 f"{scene.duration_s:g} s")
    streams = {name: inst.stream(sample_blocks(scene, window_s)) for name, inst in insts.items()}
    for t in times:
        columns, sims = {}, {}
        for name, inst in insts.items():
            sim = next(streams[name])
            sims[name] = sim
            columns.update(table_columns(name, inst, sim.columns))
        columns.update(ship_columns(scene.motion, t))
        report(t[-1] / span)
        yield t, columns, sims


def simulate_to_file(scene, out, output_rate_hz=None, progress=None) -> tuple:
    """``gyro-instrument simulate``: stream the scene into the table ``out`` (CSV or Parquet) block
    by block, every k-th sample (:func:`output_step`), after checking that it fits on the disk
    (:func:`check_disk`). Returns (rows written, columns, nfev, integration wall s)."""
    from gyro_instrument.core.memory import sample_count
    from gyro_instrument.estimators.data_io import TableWriter, scene_yaml_text, table_kind, table_metadata
    from gyro_instrument.scenes import build_instruments
    k = output_step(scene, output_rate_hz)
    insts = build_instruments(scene)
    names = [f"{n}.{c.name}" for n, i in insts.items() for c in i.COLUMNS]
    names += list(ship_columns(scene.motion, [0.0]))
    n = sample_count(scene)
    check_disk(out, (n - 1) // k + 1, len(names) + 1)
    first = 0                                  # index of the block's first sample in the run
    nfev = wall = 0.0
    text = scene_yaml_text(scene)
    readings = scale_readings(insts)
    meta = table_metadata(text, scene.name, scene.seed, readings) if table_kind(out) == "parquet" else None
    with TableWriter(out, names, metadata=meta) as writer:
        with terminal_progress("  simulating", enabled=progress is not None):
            for t, columns, sims in stream_scene(scene, progress=progress):
                keep = slice((-first) % k, None, k)
                writer.write(t[keep], {c: v[keep] for c, v in columns.items()})
                first += t.size
                nfev = sum(s.trajectory.nfev for s in sims.values())
                wall = sum(s.trajectory.wall_time_s for s in sims.values())
        if meta is None:    # before the table is renamed into place: a sidecar that fails leaves no table
            write_scene_sidecar(out, text, readings)
    return writer.rows, len(names) + 1, int(nfev), wall


def write_scene_sidecar(table, scene_yaml, readings=None) -> str:
    """Write ``<name>.scene.yaml`` beside the CSV ``table`` (atomically: an interrupted write leaves
    no partial file); return its path. ``readings`` ({column: M deg}, :func:`scale_readings`)
    goes into a comment line ``# gyro_instrument.scale_readings: {JSON}`` (the scene stays as it is)."""
    from gyro_instrument.estimators.data_io import SCALE_KEY, scale_readings_text, scene_sidecar_path
    path = scene_sidecar_path(table)
    with replaced_atomically(path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        fh.write(f"# the scene gyro-instrument simulate ran for {shown(os.path.basename(table))} (seed and overrides "
                 f"applied)\n")
        if readings:
            fh.write("# the columns read on a scale, u + M, with M (deg: mount_azimuth_deg wrapped to (-180, 180])\n"
                     f"# {SCALE_KEY}: {scale_readings_text(readings)}\n")
        fh.write(scene_yaml)
    return path


@contextmanager
def terminal_progress(label, enabled=True, stream=None, force=False) -> Iterator:
    """Draw ``label: NN.N %`` on one terminal line while long integrations inside the block
    report (:func:`gyro_instrument.core.integrate.reporting`); only on a terminal (or
    ``force``), so logs and pipes stay clean."""
    from gyro_instrument.core.integrate import reporting
    stream = stream or sys.stderr
    if not enabled or not (force or stream.isatty()):
        yield
        return
    drawn = []

    def draw(fraction):
        drawn.append(fraction)
        print(f"\r{label}: {100.0 * fraction:5.1f} %", end="", file=stream, flush=True)
    try:
        with reporting(draw):
            yield
    except BaseException:
        if drawn:  # erase the progress line so the error (or "interrupted") starts a clean line
            print(f"\r{' ' * (len(label) + 9)}\r", end="", file=stream, flush=True)
        raise
    if drawn:
        print(f"\r{label}: done   ", file=stream, flush=True)


def write_csv(path, t, columns) -> None:
    """CSV: first column ``time_s``, then one column per channel, full float precision
    (:func:`gyro_instrument.estimators.data_io.write_csv`)."""
    from gyro_instrument.estimators.data_io import write_csv as _write_csv
    return _write_csv(path, t, columns)
