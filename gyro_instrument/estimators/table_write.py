"""Writing tables of instrument channels (CSV or Parquet) as a run goes, and the scene they carry.

:class:`TableWriter` writes blocks of rows from a thread in bounded memory; :func:`table_metadata`
and :func:`scene_of_table` keep and read back the scene a table was simulated from (Parquet
metadata or a ``.scene.yaml`` sidecar).
"""

import os
import queue
import threading

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import opened_unless_utf8
from gyro_instrument.estimators.table_read import TIME_COLUMN, import_pyarrow, table_kind

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

    def __init__(self, path, names, kind=None, metadata=None) -> None:
        self.path, self.names = path, [TIME_COLUMN] + list(names)
        self.metadata = dict(metadata or {})        # Parquet key-value metadata (str -> str)
        self.kind = kind or table_kind(path)
        self.rows = 0
        self._buffer, self._buffered = [], 0
        self._writer = self._sink = self._replace = None
        self._queue = self._thread = self._error = None
        self._abort = threading.Event()

    def __enter__(self) -> "TableWriter":
        from gyro_instrument.core.files import is_utf8, replaced_atomically
        pa = import_pyarrow()
        import pyarrow.csv  # noqa: F401
        self._pa = pa
        self._replace = replaced_atomically(self.path)
        tmp = self._replace.__enter__()
        try:
            self._schema = pa.schema([(n, pa.float64()) for n in self.names],
                                     metadata={k.encode(): str(v).encode() for k, v in self.metadata.items()} or None)
            if self.kind == "parquet":
                # no dictionary encoding: measured doubles hardly repeat, and trying it made writing
                # 5.6x slower (3.7 s against 0.66 s for 1.7e6 rows x 7 columns) and the file 25 % larger
                if not is_utf8(tmp):            # pyarrow takes only UTF-8 names: give it the open file
                    self._sink = open(tmp, "wb")
                self._writer = pa.parquet.ParquetWriter(self._sink or tmp, self._schema, use_dictionary=False)
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


#: Parquet key-value metadata of a table ``simulate`` wrote: the scene as YAML text, its name, seed,
#: the columns' units and the package version (:func:`table_metadata`).
SCENE_KEY = "gyro_instrument.scene_yaml"


def scene_sidecar_path(path) -> str:
    """``<name>.scene.yaml`` beside a CSV table ``<name>.csv`` (the scene ``simulate`` ran)."""
    return os.path.splitext(str(path))[0] + ".scene.yaml"


#: The key (Parquet metadata; a comment line of the CSV's sidecar) of the columns a table holds as scale
#: readings: JSON ``{"<instrument>.<channel>": M}``, the column reading u + M, M (deg) the instrument's
#: ``mount_azimuth_deg`` wrapped to (-180, 180] (docs/formats/csv.md).
SCALE_KEY = "gyro_instrument.scale_readings"


def scale_readings_text(readings) -> str:
    """The value of :data:`SCALE_KEY`: ``readings`` ({column: M deg}) as JSON."""
    import json
    return json.dumps(readings)


def table_metadata(scene_yaml, scene_name, seed, scale_readings=None) -> dict:
    """The key-value metadata ``simulate`` writes into a Parquet table (keys ``gyro_instrument.*``):
    ``scene_yaml`` (the scene, overrides applied, as YAML text), ``scene_name``, ``scene_seed``,
    ``units``, ``version`` and, when some column is a scale reading, ``scale_readings``
    (:data:`SCALE_KEY`)."""
    from gyro_instrument import __version__
    meta = {SCENE_KEY: scene_yaml, "gyro_instrument.scene_name": scene_name, "gyro_instrument.scene_seed": seed,
            "gyro_instrument.units": "time_s in s; angles in rad, rates in rad/s, lengths in m (docs/formats/csv.md)",
            "gyro_instrument.version": __version__}
    if scale_readings:
        meta[SCALE_KEY] = scale_readings_text(scale_readings)
    return meta


def table_scene(path) -> tuple | None:
    """The scene a table carries: (YAML text, where it was found) from a Parquet table's metadata
    key :data:`SCENE_KEY` or a CSV's ``<name>.scene.yaml`` (:func:`scene_sidecar_path`); None when
    it carries none (or the file cannot be read: :func:`read_table` says why)."""
    if table_kind(path) == "parquet":
        try:
            with opened_unless_utf8(path) as src:
                meta = import_pyarrow().parquet.read_schema(src).metadata or {}
        except Exception:               # noqa: BLE001 - read_table reports an unreadable file
            return None
        text = meta.get(SCENE_KEY.encode())
        return (text.decode(), f"{path}'s Parquet metadata ({SCENE_KEY})") if text else None
    side = scene_sidecar_path(path)
    if os.path.isfile(side):
        with open(side, encoding="utf-8") as fh:
            return fh.read(), side
    return None


def scene_yaml_text(scene) -> str:
    """The scene as YAML text (its mapping with the overrides applied, as a bag records it)."""
    import yaml
    return yaml.safe_dump(dict(scene.raw), sort_keys=False, allow_unicode=True)


def scene_of_table(path, overrides=()) -> tuple | None:
    """(Scene, where it was found) for a table that carries its scene (:func:`table_scene`), else None.

    Raises
    ------
    SceneError
        The carried scene is not a valid scene (its own message, naming where it was found).
    """
    import yaml
    from gyro_instrument.scenes import scene_from_data
    found = table_scene(path)
    if found is None:
        return None
    text, where = found
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise SceneError("scene", where, f"is not valid YAML ({exc.__class__.__name__})") from None
    return scene_from_data(data, source=where, overrides=list(overrides)), where


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
