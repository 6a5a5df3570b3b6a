"""Measured data in and out: CSV and Parquet tables of instrument channels (msg_docs/csv.md).

``gyro-instrument estimate --data FILE --scene SCENE`` reads a table whose first column (or any
column) is ``time_s`` and whose other columns are ``<instrument>.<channel>``, matches them to the
scene's instruments and estimates from them with the same estimator as ``estimate`` and
``replay``. What each instrument type needs:

=====================================  ==================================================================
spherical / compound pendulum          ``x_east`` and ``y_north`` (m; divided by the scene's length to the
                                       deflections the sensor measures), or ``deflection_east`` and
                                       ``deflection_north`` (rad, x/l and y/l)
gyroscope with a directing line        its angle (``angle``; the gimbal: ``outer_angle`` or
(plane, cone, gimbal)                  ``inner_angle``, whichever the scene's configuration swings) and
                                       ``spin_rate`` (rad/s)
free gyroscope, Puiseux's body         nothing (not used by the estimator)
=====================================  ==================================================================

Samples may be missing (empty cell or ``nan``: left out, as a dropout), irregular, duplicated or
out of order (sorted by time, stable; the fits drop duplicated stamps and say so). Times are
taken from the first valid sample when it is not 0 (a note says so).
"""

import csv
import math
import os
import queue
import threading

import numpy as np

from gyro_instrument.core.errors import SceneError

TIME_COLUMN = "time_s"


def table_kind(path) -> str:
    """``parquet`` for a name ending in ``.parquet`` or ``.pq``, else ``csv``."""
    return "parquet" if str(path).lower().endswith((".parquet", ".pq")) else "csv"


def _pyarrow():
    try:
        import pyarrow
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        raise SceneError("parquet", "pyarrow", "is not installed: pip install pyarrow (a dependency of "
                                               "gyro_instrument; reinstall the package)") from None
    return pyarrow


def read_table(path, field="--data") -> dict:
    """Every column of a CSV or Parquet table as float arrays.

    Returns
    -------
    dict
        column name -> ndarray (NaN for empty or ``nan`` cells), in file order.

    Raises
    ------
    SceneError
        Missing or unreadable file, an empty table, a cell that is not a number, no ``time_s``
        column.
    """
    if not os.path.isfile(path):
        raise SceneError(field, path, "file not found" if not os.path.exists(path) else "is not a file")
    kind = table_kind(path)
    if kind == "csv":
        try:
            with open(path, newline="", encoding="utf-8") as fh:
                rows = list(csv.reader(fh))
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            raise SceneError(field, path, f"cannot be read as CSV ({exc.__class__.__name__})") from None
        rows = [r for r in rows if r and any(c.strip() for c in r)]
        if not rows:
            raise SceneError(field, path, "is empty; expected a header row time_s,<instrument>.<channel>,...")
        header = [h.strip() for h in rows[0]]
        cols = {h: np.full(len(rows) - 1, np.nan) for h in header}
        for i, row in enumerate(rows[1:], start=2):
            for h, cell in zip(header, row):
                cell = cell.strip()
                if cell:
                    try:
                        cols[h][i - 2] = float(cell)
                    except ValueError:
                        raise SceneError(field, path, f"line {i}, column {h}: {cell!r} is not a number") from None
    else:
        pa = _pyarrow()
        try:
            table = pa.parquet.read_table(path)
        except Exception as exc:        # pyarrow raises its own error classes for a bad file
            raise SceneError(field, path, f"cannot be read as Parquet ({exc.__class__.__name__})") from None
        cols = {}
        for name in table.column_names:
            try:
                cols[name] = np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=float)
            except (TypeError, ValueError, pa.ArrowException):
                raise SceneError(field, path, f"column {name} is not numeric") from None
    if TIME_COLUMN not in cols:
        shown = ", ".join(list(cols)[:6]) + (", ..." if len(cols) > 6 else "")
        raise SceneError(field, path, f"has no time column '{TIME_COLUMN}' (columns: {shown or 'none'}); "
                                      f"see msg_docs/csv.md")
    return cols


#: Estimated bytes per value written, by format, for the disk check before a run
#: (:func:`output_bytes`). CSV: a double in its shortest round-trip form is at most 24 characters
#: ("-2.2250738585072014e-308"), plus its separator; random doubles average 19.6 (pyarrow's writer,
#: 2e6 rows). Parquet: 8 bytes of float64 (values that do not compress) and ~2 % of page and
#: row-group overhead.
BYTES_PER_VALUE = {"csv": 25.0, "parquet": 8.2}

#: Rows buffered before a write: one Parquet row group (and one CSV batch) per 65 536 rows, so the
#: file is written as the run goes in memory of one buffer, whatever the duration.
ROWS_PER_WRITE = 65536

#: Buffers of :data:`ROWS_PER_WRITE` rows that may wait for :class:`TableWriter`'s writing thread
#: (besides the one it writes and the one being filled): bounds the memory of a run whose rows
#: come faster than the disk takes them.
QUEUED_WRITES = 2


def output_bytes(path, rows, columns) -> float:
    """Estimated size (bytes) of a table of ``rows`` rows and ``columns`` columns (``time_s``
    included) written to ``path`` (:data:`BYTES_PER_VALUE` of its format); an upper bound for CSV."""
    return rows * columns * BYTES_PER_VALUE[table_kind(path)]


class TableWriter:
    """Write ``time_s`` and the channel columns block by block: Parquet through pyarrow's
    ``ParquetWriter`` (float64 columns, plain-encoded, snappy, a row group per :data:`ROWS_PER_WRITE`
    rows) for a name
    ending in ``.parquet``/``.pq``, else CSV through pyarrow's ``CSVWriter`` (the shortest
    representation that reads back to the same double: full precision, ``nan``/``inf`` as Python
    writes them; header unquoted: ``time_s,<instrument>.<channel>,...``, as :func:`read_table`,
    ``estimate --data`` and ``plot`` read it).

    The buffers are encoded and written by a background thread (pyarrow releases the GIL while it
    encodes and writes), so the file is written while the caller computes the next rows: on
    foucault_pantheon's sidereal day at 20 Hz (1.72e6 rows x 7 columns) this hides the ~0.28 s of
    ``write_table`` behind the integration. At most :data:`QUEUED_WRITES` buffers wait for it, so
    memory stays that of a few buffers; an error in the thread is raised in the caller by the next
    :meth:`write` or on leaving the block.

    A context manager: the rows go to ``<path>.partial``, renamed onto ``path`` when the block
    ends normally; on any exception (a Ctrl-C included) the writing thread stops, the partial file
    is removed and ``path`` is left as it was (:func:`~gyro_instrument.core.files.replaced_atomically`).
    """

    def __init__(self, path, names, kind=None) -> None:
        self.path, self.names = path, [TIME_COLUMN] + list(names)
        self.kind = kind or table_kind(path)
        self.rows = 0
        self._buffer, self._buffered = [], 0
        self._writer = self._sink = self._replace = None
        self._queue = self._thread = self._error = None
        self._abort = threading.Event()

    def __enter__(self) -> "TableWriter":
        from gyro_instrument.core.files import replaced_atomically
        pa = _pyarrow()
        import pyarrow.csv  # noqa: F401
        self._pa = pa
        self._replace = replaced_atomically(self.path)
        tmp = self._replace.__enter__()
        try:
            self._schema = pa.schema([(n, pa.float64()) for n in self.names])
            if self.kind == "parquet":
                # no dictionary encoding: measured doubles hardly repeat, and trying it made writing
                # 5.6x slower (3.7 s against 0.66 s for 1.7e6 rows x 7 columns) and the file 25 % larger
                self._writer = pa.parquet.ParquetWriter(tmp, self._schema, use_dictionary=False)
            else:
                self._sink = open(tmp, "wb")
                self._sink.write((",".join(self.names) + "\n").encode())
                self._writer = pa.csv.CSVWriter(self._sink, self._schema,
                                                write_options=pa.csv.WriteOptions(include_header=False))
            self._queue = queue.Queue(maxsize=QUEUED_WRITES)
            self._thread = threading.Thread(target=self._drain, name=f"TableWriter {self.path}", daemon=True)
            self._thread.start()
        except BaseException as exc:
            self._close()
            self._replace.__exit__(type(exc), exc, exc.__traceback__)
            raise
        return self

    def write(self, t, columns) -> None:
        """Append rows: ``t`` (s, shape (m,)) and ``columns`` (name -> array (m,), every name of the
        header in order).

        Raises
        ------
        Exception
            Whatever writing an earlier buffer raised in the background thread (OSError, pyarrow's).
        """
        t = np.asarray(t, dtype=float)
        if not t.size:
            return
        self._buffer.append([t] + [np.asarray(columns[n], dtype=float) for n in self.names[1:]])
        self._buffered += t.size
        if self._buffered >= ROWS_PER_WRITE:
            self._flush()

    def _drain(self):
        """The writing thread: write the queued tables until the ``None`` that ends them; after an
        error (kept for the caller) or an abort, take the rest without writing it."""
        while True:
            table = self._queue.get()
            if table is None:
                return
            if self._error is None and not self._abort.is_set():
                try:
                    self._writer.write_table(table)
                except BaseException as exc:        # raised again in the caller's thread
                    self._error = exc

    def _raise_error(self):
        if self._error is not None:
            error, self._error = self._error, None
            self._abort.set()
            raise error

    def _flush(self):
        self._raise_error()
        if not self._buffer:
            return
        arrays = [np.concatenate([b[i] for b in self._buffer]) for i in range(len(self.names))]
        self._buffer, self._buffered = [], 0
        table = self._pa.Table.from_arrays([self._pa.array(a) for a in arrays], schema=self._schema)
        self._queue.put(table)                      # waits while QUEUED_WRITES tables are queued
        self.rows += table.num_rows

    def _stop(self):
        """End the writing thread (after the queued tables; at once with an abort) and wait for it."""
        if self._thread is not None:
            self._queue.put(None)
            self._thread.join()
            self._thread = None

    def _close(self):
        try:
            self._stop()
            if self._writer is not None:
                self._writer.close()
        finally:
            self._writer = None
            if self._sink is not None:
                self._sink.close()
                self._sink = None

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            if exc_type is None:
                self._flush()
                self._stop()
                self._raise_error()
            else:
                self._abort.set()
            self._close()
        except BaseException as err:
            self._abort.set()
            try:
                self._close()
            except BaseException:                   # the first error is the one reported
                pass
            return self._replace.__exit__(type(err), err, err.__traceback__)
        return self._replace.__exit__(exc_type, exc, tb)


def write_table(path, t, columns) -> None:
    """Write ``time_s`` and the channel columns in one block (:class:`TableWriter`: Parquet for a
    name ending in ``.parquet``/``.pq``, else CSV, full precision); written to ``<path>.partial``
    and renamed."""
    with TableWriter(path, list(columns)) as w:
        w.write(t, columns)


def write_csv(path, t, columns) -> None:
    """CSV: first column ``time_s``, then one column per channel, full float precision (the shortest
    representation that reads back to the same double); written to ``<path>.partial`` and renamed
    when complete: an interrupted write leaves no ``path`` (or the previous one) and no
    ``.partial`` (:class:`TableWriter`)."""
    with TableWriter(path, list(columns), kind="csv") as w:
        w.write(t, columns)


def _needs(inst):
    """Alternative column sets (each a tuple of channel names) that give this instrument's record;
    () for an instrument the estimator does not use."""
    from gyro_instrument.estimators.pipeline import estimable   # here: writing a table needs no estimator (nor scipy.optimize)
    if inst.IS_PENDULUM:
        return (("x_east", "y_north"), tuple(inst.MEASURED_CHANNELS))
    if not estimable(inst):
        return ()
    model = inst.directing_model()
    return ((model.angle_channel, "spin_rate"),)


def records_from_table(insts, cols, path="data", field="--data") -> tuple:
    """Estimator records from table columns (see the module docstring).

    Returns
    -------
    records : dict
        instrument name -> record (``t`` and the measured channels), for the instruments matched.
    notes : list of str
        Instruments left out, columns not used, rows dropped, re-ordering, time origin.
    observation_s : float
        Time from the first to the last valid sample.

    Raises
    ------
    SceneError
        An instrument has some of its columns but not a complete set (the scene does not match the
        data: wrong type, or columns missing), or no instrument the estimator uses has its columns.
    """
    notes = []
    t = np.asarray(cols[TIME_COLUMN], dtype=float)
    bad_t = ~np.isfinite(t)
    if bad_t.all():
        raise SceneError(field, path, f"column {TIME_COLUMN} holds no finite time")
    if bad_t.any():
        notes.append(f"{int(bad_t.sum())} rows without a finite {TIME_COLUMN} left out")
    keep = ~bad_t
    t = t[keep]
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(order) < 0):
        notes.append(f"rows out of time order: sorted by {TIME_COLUMN}")
    t = t[order]
    t0 = float(t[0])
    if t0 != 0.0:
        notes.append(f"times taken from the first sample ({TIME_COLUMN} = {t0!r} s)")
        t = t - t0

    def col(name):
        return np.asarray(cols[name], dtype=float)[keep][order]

    records, used = {}, set()
    wanted = []
    for name, inst in insts.items():
        present = sorted(c.split(".", 1)[1] for c in cols if c.startswith(f"{name}."))
        options = _needs(inst)
        if not options:
            used.update(f"{name}.{c}" for c in present)
            records[name] = {"t": t.copy()}
            continue
        wanted.append(f"{name} ({inst.type_name}): " + " or ".join(
            "+".join(f"{name}.{c}" for c in opt) for opt in options))
        full = next((opt for opt in options if all(c in present for c in opt)), None)
        if full is None:
            if not present:
                notes.append(f"{name} ({inst.type_name}): no column in the data; left out")
                continue
            need = " or ".join(", ".join(f"{name}.{c}" for c in opt) for opt in options)
            raise SceneError(field, path, f"does not match the scene's {name} ({inst.type_name}): needs {need}; "
                                          f"the data has {', '.join(f'{name}.{c}' for c in present)}")
        used.update(f"{name}.{c}" for c in full)
        rec = {"t": t.copy()}
        if inst.IS_PENDULUM:
            if full[0] == "x_east":
                l = inst.pendulum_length_m()
                rec["deflection_east"] = col(f"{name}.x_east") / l
                rec["deflection_north"] = col(f"{name}.y_north") / l
            else:
                rec["deflection_east"] = col(f"{name}.deflection_east")
                rec["deflection_north"] = col(f"{name}.deflection_north")
        else:
            for chan in inst.MEASURED_CHANNELS:
                if f"{name}.{chan}" in cols:
                    rec[chan] = col(f"{name}.{chan}")
            rec["spin_rate"] = col(f"{name}.spin_rate")
            rec["angle"] = rec[full[0]]
        n_nan = int(sum((~np.isfinite(rec[c])).sum() for c in rec if c not in ("t", "angle")))
        if n_nan:
            notes.append(f"{name}: {n_nan} missing or NaN values left out")
        records[name] = rec
    if not any(_needs(insts[n]) for n in records):
        raise SceneError(field, path, "does not match the scene: no instrument's columns found; expected "
                                      + "; ".join(wanted) if wanted else
                                      "the scene has no instrument the estimator uses")
    # columns the instrument writes but the estimator does not read (angle_rate, swing_azimuth ...)
    # are passed over silently; columns of no instrument or channel of the scene are noted
    known = {f"{n}.{c.name}" for n, inst in insts.items() for c in getattr(inst, "COLUMNS", ())}
    unknown = [c for c in cols if c != TIME_COLUMN and c not in used and c not in known]
    if unknown:
        shown = ", ".join(unknown[:8]) + (f" and {len(unknown) - 8} more" if len(unknown) > 8 else "")
        notes.append(f"columns matching no channel of the scene's instruments, not used: {shown}")
    t_ok = t[np.isfinite(t)]
    return records, notes, float(t_ok[-1] - t_ok[0]) if t_ok.size else 0.0


def estimate_data(scene, path, field="--data") -> dict:
    """The ``estimate`` JSON object from a CSV or Parquet table of measured channels, with
    ``data`` (the file), ``observation_s`` (the data's span) and ``data_notes``.

    Raises
    ------
    SceneError
        See :func:`read_table` and :func:`records_from_table`.
    """
    from gyro_instrument.estimators.pipeline import estimate_records
    from gyro_instrument.scenes import build_instruments
    insts = build_instruments(scene)
    cols = read_table(path, field)
    records, notes, span = records_from_table(insts, cols, path, field)
    result = estimate_records(scene, {n: insts[n] for n in records}, records)
    result["observation_s"] = span
    result["data"] = os.path.basename(path)
    if notes:
        result["data_notes"] = notes
    if not math.isfinite(span):
        result["observation_s"] = None
    return result
