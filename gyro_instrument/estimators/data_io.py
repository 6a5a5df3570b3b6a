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

A gyroscope without ``spin_rate`` takes the scene's constant spin (its ``spin_rate_rad_s``, the
directing model's ρ0; noted). Samples may be missing (empty cell or ``nan``: left out, as a
dropout), irregular, duplicated or out of order (sorted by time, stable; the fits drop duplicated
stamps and say so); gaps and irregular sampling are noted (:func:`sampling_notes`). Times are
taken from the first valid sample when it is not 0 (a note says so). Fewer than two distinct
times is refused.

:class:`TableOptions` says how to read a table as users have it (``--time-column``,
``--time-unit``, ``--angle-unit``, ``--column NAME=SOURCE``, ``--separator``): see
:func:`load_table` and msg_docs/csv.md.
"""

import csv
import math
import os
import queue
import threading
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError

TIME_COLUMN = "time_s"

#: ``--time-unit``: how many of the unit make a second (divided by, so that a whole number of ms,
#: us or ns becomes the double nearest the exact time: IEEE division is correctly rounded), or for
#: minutes the seconds in one (multiplied by).
TIME_UNITS = {"s": 1, "ms": 1000, "us": 1_000_000, "ns": 1_000_000_000, "min": 60}

#: ``--angle-unit``: the channels read as angles (rad, or deg converted to rad). Not ``x_east`` /
#: ``y_north`` (m) nor ``spin_rate`` (rad/s, a rate).
ANGLE_CHANNELS = ("angle", "outer_angle", "inner_angle", "deflection_east", "deflection_north")
ANGLE_UNITS = ("rad", "deg")

#: ``--separator``: the CSV field separators; ``None`` sniffs it from the header line.
SEPARATORS = {",": ",", ";": ";", "tab": "\t"}

#: Arrow time units of a Parquet ``timestamp[...]`` / ``duration[...]`` column, per second.
ARROW_TIME_UNITS = {"s": 1, "ms": 1000, "us": 1_000_000, "ns": 1_000_000_000}


@dataclass(frozen=True)
class TableOptions:
    """How to read a measured table (``estimate --data`` flags).

    Attributes
    ----------
    time_column : str
        The table's time column (``--time-column``), read as ``time_s``.
    time_unit : str or None
        Unit of a numeric time column (``--time-unit``, a key of :data:`TIME_UNITS`); None: seconds,
        or the unit a Parquet ``timestamp``/``duration`` column carries.
    angle_unit : str
        ``rad`` or ``deg`` (``--angle-unit``): unit of the :data:`ANGLE_CHANNELS` columns.
    columns : tuple of (str, str)
        ``(NAME, SOURCE)`` pairs (``--column NAME=SOURCE``): the table's column SOURCE is read as the
        channel column NAME.
    separator : str or None
        CSV separator (``,``, ``;`` or ``tab``; ``--separator``); None sniffs it from the header.
    """

    time_column: str = TIME_COLUMN
    time_unit: str | None = None
    angle_unit: str = "rad"
    columns: tuple = ()
    separator: str | None = None

    @classmethod
    def from_flags(cls, time_column=TIME_COLUMN, time_unit=None, angle_unit="rad", columns=(),
                   separator=None) -> "TableOptions":
        """Options from the command-line strings, checked.

        Raises
        ------
        SceneError
            An unknown unit or separator, a ``--column`` without ``=`` or with an empty side, a NAME
            given twice, a NAME that is ``time_s`` (use ``--time-column``).
        """
        if not time_column or not str(time_column).strip():
            raise SceneError("--time-column", time_column, "must name a column of the table")
        if time_unit is not None and time_unit not in TIME_UNITS:
            raise SceneError("--time-unit", time_unit, f"must be one of {', '.join(TIME_UNITS)}")
        if angle_unit not in ANGLE_UNITS:
            raise SceneError("--angle-unit", angle_unit, f"must be one of {', '.join(ANGLE_UNITS)}")
        if separator is not None and separator not in SEPARATORS:
            raise SceneError("--separator", separator, f"must be one of {', '.join(SEPARATORS)}")
        pairs, seen = [], set()
        for spec in columns:
            name, eq, source = str(spec).partition("=")
            name, source = name.strip(), source.strip()
            if not eq or not name or not source:
                raise SceneError("--column", spec, "must be NAME=SOURCE, e.g. gyro_horizontal.angle=Theta "
                                                   "(the table's column SOURCE read as the channel NAME)")
            if name == TIME_COLUMN:
                raise SceneError("--column", spec, f"names the time column: give --time-column {source} instead")
            if name in seen:
                raise SceneError("--column", spec, f"{name} is given twice; give each channel one source")
            seen.add(name)
            pairs.append((name, source))
        return cls(str(time_column).strip(), time_unit, angle_unit, tuple(pairs), separator)


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


def _refuse_duplicates(names, path, field):
    seen = {}
    for i, name in enumerate(names, start=1):
        if name in seen:
            raise SceneError(field, path, f"column {name} appears twice (columns {seen[name]} and {i}); "
                                          f"rename one (a table's columns must be unique)")
        seen[name] = i


def _csv_separator(first_line, path, field, separator):
    """The CSV separator: ``separator`` when given, else the one of ``,``, ``;``, tab the header holds
    (``,`` when it holds none: a single column). SceneError when it holds several."""
    if separator is not None:
        return SEPARATORS[separator]
    found = [s for s in (",", ";", "\t") if s in first_line]
    if len(found) > 1:
        shown = " and ".join("tab" if s == "\t" else repr(s) for s in found)
        raise SceneError(field, path, f"the header line holds both {shown}: cannot tell the separator; "
                                      f"pass --separator , or --separator ';' or --separator tab")
    return found[0] if found else ","


def _read_csv(path, field, separator):
    """(names, arrays, notes) of a CSV file (UTF-8, with or without a byte-order mark)."""
    notes = []
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:     # the BOM, if any, is skipped
            first = ""
            for line in fh:
                if line.strip():
                    first = line
                    break
            sep = _csv_separator(first, path, field, separator)
            fh.seek(0)
            rows = list(csv.reader(fh, delimiter=sep))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        utf8 = "; UTF-8 expected" if isinstance(exc, UnicodeDecodeError) else ""
        raise SceneError(field, path, f"cannot be read as CSV ({exc.__class__.__name__}{utf8})") from None
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise SceneError(field, path, "is empty; expected a header row time_s,<instrument>.<channel>,...")
    header = [h.strip() for h in rows[0]]
    _refuse_duplicates(header, path, field)
    decimal_comma = sep == ";"
    if sep != ",":
        notes.append(f"CSV separated by {'tab' if sep == chr(9) else repr(sep)}"
                     + (" (decimal commas read as points)" if decimal_comma else ""))
    cols = [np.full(len(rows) - 1, np.nan) for _ in header]
    for i, row in enumerate(rows[1:], start=2):
        for j, (h, cell) in enumerate(zip(header, row)):
            cell = cell.strip()
            if cell:
                try:
                    cols[j][i - 2] = float(cell)
                except ValueError:
                    if decimal_comma and cell.count(",") == 1 and "." not in cell:
                        try:
                            cols[j][i - 2] = float(cell.replace(",", "."))
                            continue
                        except ValueError:
                            pass
                    raise SceneError(field, path, f"line {i}, column {h}: {cell!r} is not a number") from None
    return header, cols, notes


def _arrow_time_seconds(pa, column, name, time_unit, path, field):
    """Seconds (float64, NaN for nulls) of a ``timestamp``/``duration`` column, from its integer
    count of its own unit: a timestamp from its earliest value (integer subtraction, exact), a
    duration as it is; then divided by the unit's count per second (one correctly rounded division,
    exact to the nearest double for spans below 2**53 units: 104 days in ns)."""
    import pyarrow.compute as pc
    typ = column.type
    if time_unit is not None:
        raise SceneError("--time-unit", time_unit, f"does not apply: column {name} is stored as {typ}, which "
                                                   f"carries its unit; leave --time-unit out")
    valid = np.asarray(column.is_valid().to_numpy(zero_copy_only=False), dtype=bool)
    ints = np.asarray(pc.fill_null(column, pa.scalar(0, typ)).cast(pa.int64()).to_numpy(zero_copy_only=False),
                      dtype=np.int64)
    per = ARROW_TIME_UNITS[typ.unit]
    note = None
    if pa.types.is_timestamp(typ) and valid.any():
        ref = int(ints[valid].min())
        ints = ints - ref
        first = pa.scalar(ref, typ)
        note = f"{name} stored as {typ}: seconds from the earliest sample ({first})"
    elif pa.types.is_duration(typ):
        note = f"{name} stored as {typ}: converted to seconds (exactly, from whole {typ.unit})"
    secs = ints / per
    secs[~valid] = np.nan
    return secs, note


def _read_parquet(path, field, time_source, time_unit):
    """(names, arrays, notes) of a Parquet file; the ``time_source`` column may be a timestamp or a
    duration (converted to seconds), every other column must be numeric."""
    pa = _pyarrow()
    try:
        # the schema first: read_table fails on a name twice (ArrowInvalid of its dataset layer)
        names = list(pa.parquet.ParquetFile(path).schema_arrow.names)
    except Exception as exc:        # pyarrow raises its own error classes for a bad file
        raise SceneError(field, path, f"cannot be read as Parquet ({exc.__class__.__name__})") from None
    _refuse_duplicates(names, path, field)
    try:
        table = pa.parquet.read_table(path)
    except Exception as exc:
        raise SceneError(field, path, f"cannot be read as Parquet ({exc.__class__.__name__})") from None
    arrays, notes = [], []
    for i, name in enumerate(names):
        column = table.column(i)
        typ = column.type
        if name == time_source and (pa.types.is_timestamp(typ) or pa.types.is_duration(typ)):
            secs, note = _arrow_time_seconds(pa, column, name, time_unit, path, field)
            arrays.append(secs)
            if note:
                notes.append(note)
            continue
        if not (pa.types.is_integer(typ) or pa.types.is_floating(typ) or pa.types.is_decimal(typ)
                or pa.types.is_null(typ)):
            what = "a number, a timestamp or a duration" if name == time_source else "a number"
            raise SceneError(field, path, f"column {name} is {typ}, not {what}")
        try:
            arrays.append(np.asarray(column.cast(pa.float64()).to_numpy(zero_copy_only=False), dtype=float))
        except (TypeError, ValueError, pa.ArrowException):
            raise SceneError(field, path, f"column {name} ({typ}) is not numeric") from None
    return names, arrays, notes


def load_table(path, field="--data", options=None) -> tuple:
    """A CSV or Parquet table read as ``options`` say (:class:`TableOptions`; default: ``time_s`` in
    seconds, angles in radians, CSV separator sniffed).

    Returns
    -------
    cols : dict
        column name -> float ndarray (NaN for empty or ``nan`` cells), in file order, with the time
        column as ``time_s`` in seconds, ``--column`` sources under their channel names and the
        :data:`ANGLE_CHANNELS` columns in radians.
    notes : list of str
        What was converted (separator, decimal commas, units, renamed columns, a timestamp's origin).

    Raises
    ------
    SceneError
        Missing or unreadable file, an empty table, a cell that is not a number, a non-numeric
        Parquet column (the time column may be a timestamp or a duration), a column name twice, a
        ``--column`` source missing or its name already a column, no time column.
    """
    opts = options or TableOptions()
    if not os.path.isfile(path):
        raise SceneError(field, path, "file not found" if not os.path.exists(path) else "is not a file")
    if table_kind(path) == "csv":
        names, arrays, notes = _read_csv(path, field, opts.separator)
    else:
        names, arrays, notes = _read_parquet(path, field, opts.time_column, opts.time_unit)
    raw = dict(zip(names, arrays))

    def shown(cols):
        cols = list(cols)
        return ", ".join(cols[:6]) + (", ..." if len(cols) > 6 else "") or "none"

    if opts.time_column not in raw:
        hint = "pass --time-column NAME or " if opts.time_column == TIME_COLUMN else ""
        raise SceneError(field, path, f"has no time column '{opts.time_column}' (columns: {shown(raw)}); "
                                      f"{hint}see msg_docs/csv.md")
    sources = {src for _, src in opts.columns} | {opts.time_column}
    for name, src in opts.columns:
        if src not in raw:
            raise SceneError("--column", f"{name}={src}", f"the table has no column {src!r} (columns: {shown(raw)})")
        if name in raw and name not in sources:
            raise SceneError("--column", f"{name}={src}", f"the table already has a column {name}; "
                                                          f"rename one or leave out --column")
    cols = {TIME_COLUMN: raw[opts.time_column]}
    for name, src in opts.columns:
        cols[name] = raw[src]
    for name, arr in raw.items():
        if name not in sources and name not in cols:
            cols[name] = arr
    if opts.time_column != TIME_COLUMN:
        notes.append(f"time from column {opts.time_column}"
                     + (f" (its column {TIME_COLUMN} not used)" if TIME_COLUMN in raw and TIME_COLUMN not in sources
                        else ""))
    if opts.columns:
        notes.append("columns read as channels: " + ", ".join(f"{src} as {name}" for name, src in opts.columns))
    if opts.time_unit not in (None, "s"):
        k = TIME_UNITS[opts.time_unit]
        cols[TIME_COLUMN] = cols[TIME_COLUMN] * k if opts.time_unit == "min" else cols[TIME_COLUMN] / k
        notes.append(f"{opts.time_column} in {opts.time_unit}: converted to s")
    if opts.angle_unit == "deg":
        converted = [c for c in cols if "." in c and c.split(".", 1)[1] in ANGLE_CHANNELS]
        for c in converted:
            cols[c] = np.radians(cols[c])
        notes.append("angles in degrees converted to rad: " + (", ".join(converted) or "no angle column"))
    return cols, notes


def read_table(path, field="--data", options=None) -> dict:
    """Every column of a CSV or Parquet table as float arrays (:func:`load_table` without its notes).

    Returns
    -------
    dict
        column name -> ndarray (NaN for empty or ``nan`` cells), in file order.

    Raises
    ------
    SceneError
        See :func:`load_table`.
    """
    return load_table(path, field, options)[0]


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
        from gyro_instrument.core.files import replaced_atomically
        pa = _pyarrow()
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


#: Parquet key-value metadata of a table ``simulate`` wrote: the scene as YAML text, its name, seed,
#: the columns' units and the package version (:func:`table_metadata`).
SCENE_KEY = "gyro_instrument.scene_yaml"


def scene_sidecar_path(path) -> str:
    """``<name>.scene.yaml`` beside a CSV table ``<name>.csv`` (the scene ``simulate`` ran)."""
    return os.path.splitext(str(path))[0] + ".scene.yaml"


def table_metadata(scene_yaml, scene_name, seed) -> dict:
    """The key-value metadata ``simulate`` writes into a Parquet table (keys ``gyro_instrument.*``):
    ``scene_yaml`` (the scene, overrides applied, as YAML text), ``scene_name``, ``scene_seed``,
    ``units`` and ``version``."""
    from gyro_instrument import __version__
    return {SCENE_KEY: scene_yaml, "gyro_instrument.scene_name": scene_name, "gyro_instrument.scene_seed": seed,
            "gyro_instrument.units": "time_s in s; angles in rad, rates in rad/s, lengths in m (msg_docs/csv.md)",
            "gyro_instrument.version": __version__}


def table_scene(path) -> tuple | None:
    """The scene a table carries: (YAML text, where it was found) from a Parquet table's metadata
    key :data:`SCENE_KEY` or a CSV's ``<name>.scene.yaml`` (:func:`scene_sidecar_path`); None when
    it carries none (or the file cannot be read: :func:`read_table` says why)."""
    if table_kind(path) == "parquet":
        try:
            meta = _pyarrow().parquet.read_schema(path).metadata or {}
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


def _needs(inst):
    """Alternative column sets (each a tuple of channel names) that give this instrument's record;
    () for an instrument the estimator does not use."""
    from gyro_instrument.estimators.pipeline import estimable   # here: writing a table needs no estimator (nor scipy.optimize)
    if inst.IS_PENDULUM:
        return (("x_east", "y_north"), tuple(inst.MEASURED_CHANNELS))
    if not estimable(inst):
        return ()
    model = inst.directing_model()
    if model.spin_rate_rad_s:        # spin_rate optional: the scene's constant spin without it
        return ((model.angle_channel,),)
    return ((model.angle_channel, "spin_rate"),)


#: A sampling interval more than this many times the median interval is a gap (noted).
GAP_FACTOR = 3.0

#: Intervals (gaps aside) spread by more than this fraction of the median are noted as irregular
#: sampling: above the jitter of a clock stamped to a whole ms at a few Hz (333/334 ms: 0.3 %).
IRREGULAR_SPREAD = 0.01


def sampling_notes(t) -> list:
    """Notes on the sampling of the sorted distinct times ``t`` (s): gaps (an interval above
    :data:`GAP_FACTOR` times the median interval: how many, the longest and where) and irregular
    sampling (the other intervals spread by more than :data:`IRREGULAR_SPREAD` of the median).
    [] for regular sampling."""
    dt = np.diff(np.asarray(t, dtype=float))
    if dt.size < 2:
        return []
    med = float(np.median(dt))
    notes = []
    gaps = dt > GAP_FACTOR * med
    if gaps.any():
        g = int(np.argmax(np.where(gaps, dt, -np.inf)))
        n = int(gaps.sum())
        notes.append(f"{n} gap{'s' if n > 1 else ''} longer than {GAP_FACTOR:g}x the median interval "
                     f"({med:.6g} s): {'longest ' if n > 1 else ''}{dt[g]:.6g} s at t = {t[g]:.6g} s "
                     f"(from the first sample)")
    rest = dt[~gaps]
    if rest.size and float(rest.max() - rest.min()) > IRREGULAR_SPREAD * med:
        notes.append(f"irregular sampling: intervals from {rest.min():.6g} to {rest.max():.6g} s "
                     f"(median {med:.6g} s{', gaps aside' if gaps.any() else ''}; spread above "
                     f"{IRREGULAR_SPREAD:.0%} of the median)")
    return notes


def _table_times(cols, path, field, notes) -> tuple:
    """The time column sorted and from its first sample: ``(t, keep, order, distinct)``, ``keep``
    the rows with a finite time, ``order`` their stable sort, ``distinct`` the sorted distinct
    times as read; the notes (rows left out, re-ordering, gaps and irregular sampling, time origin)
    appended to ``notes``."""
    t = np.asarray(cols[TIME_COLUMN], dtype=float)
    bad_t = ~np.isfinite(t)
    if bad_t.all():
        raise SceneError(field, path, f"column {TIME_COLUMN} holds no finite time")
    if bad_t.any():
        notes.append(f"{int(bad_t.sum())} rows without a finite {TIME_COLUMN} left out")
    keep = ~bad_t
    t = t[keep]
    distinct = np.unique(t)         # fewer than 2: refused once the columns are known to match the scene
    order = np.argsort(t, kind="stable")
    if np.any(np.diff(order) < 0):
        reverse = bool(np.all(np.diff(t) <= 0))
        notes.append(f"rows {'in decreasing' if reverse else 'out of'} time order: sorted by {TIME_COLUMN}")
    t = t[order]
    notes.extend(sampling_notes(distinct - distinct[0]))
    t0 = float(t[0])
    if t0 != 0.0:
        notes.append(f"times taken from the first sample ({TIME_COLUMN} = {t0!r} s)")
        t = t - t0
    return t, keep, order, distinct


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
    t, keep, order, distinct = _table_times(cols, path, field, notes)

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
            if f"{name}.spin_rate" in cols:
                rec["spin_rate"] = col(f"{name}.spin_rate")
                used.add(f"{name}.spin_rate")
            else:
                spin = inst.directing_model().spin_rate_rad_s
                rec["spin_rate"] = np.full(t.size, spin)
                notes.append(f"{name}: no {name}.spin_rate column: the scene's constant spin "
                             f"{spin!r} rad/s used (spin_rate_rad_s)")
            rec["angle"] = rec[full[0]]
        n_nan = int(sum((~np.isfinite(rec[c])).sum() for c in rec if c not in ("t", "angle")))
        if n_nan:
            notes.append(f"{name}: {n_nan} missing or NaN values left out")
        records[name] = rec
    if not any(_needs(insts[n]) for n in records):
        raise SceneError(field, path, "does not match the scene: no instrument's columns found; expected "
                                      + "; ".join(wanted) if wanted else
                                      "the scene has no instrument the estimator uses")
    if distinct.size < 2:
        raise SceneError(field, path, f"column {TIME_COLUMN} never increases: its {t.size} finite "
                                      f"time{'s are all' if t.size > 1 else ' is'} {float(distinct[0])!r}; "
                                      f"at least two distinct times are needed (a wrong --time-column?)")
    # columns the instrument writes but the estimator does not read (angle_rate, swing_azimuth ...)
    # are passed over silently; columns of no instrument or channel of the scene are noted
    known = {f"{n}.{c.name}" for n, inst in insts.items() for c in inst.COLUMNS}
    unknown = [c for c in cols if c != TIME_COLUMN and c not in used and c not in known]
    if unknown:
        shown = ", ".join(unknown[:8]) + (f" and {len(unknown) - 8} more" if len(unknown) > 8 else "")
        notes.append(f"columns matching no channel of the scene's instruments, not used: {shown}")
    t_ok = t[np.isfinite(t)]
    return records, notes, float(t_ok[-1] - t_ok[0]) if t_ok.size else 0.0


#: Length units a logger may have written under ``x_east``/``y_north`` (metres): factor, name.
LENGTH_UNITS = ((100.0, "centimetres"), (1000.0, "millimetres"))


def _name_a_length_unit(exc, insts, cols) -> None:
    """A pendulum's amplitude refusal read from positions (``x_east``/``y_north``, metres divided by
    the scene's length): a ratio near 100 or 1000 is a length unit, not degrees — say that instead
    (there is no flag for it: the columns must be converted to metres)."""
    from gyro_instrument.estimators.adequacy import AMPLITUDE_FACTOR
    name, check = exc.check["instrument"], exc.check["check"]
    inst = insts.get(name)
    if check != "amplitude" or inst is None or not inst.IS_PENDULUM or f"{name}.x_east" not in cols:
        return
    ratio = exc.check["value"] / exc.check["expected"] if exc.check.get("expected") else math.inf
    unit = next((u for f, u in LENGTH_UNITS if abs(math.log(ratio / f)) < math.log(2.0)), None)
    cause = (f"{name}.x_east/y_north look like {unit}, not metres: convert them to metres" if unit else
             f"{name}.x_east/y_north are metres divided by the scene's length_m ({inst.pendulum_length_m():g} m): "
             "check the length and the columns' unit")
    exc.restate(f"deflection amplitude {exc.check['value']:.6g} rad (positions / length_m) is {ratio:.3g}x the "
                 f"scene's release {exc.check['expected']:.6g} rad (at most {AMPLITUDE_FACTOR:g}x): {cause}")


def estimate_data(scene, path, field="--data", options=None) -> dict:
    """The ``estimate`` JSON object from a CSV or Parquet table of measured channels, read as
    ``options`` say (:class:`TableOptions`), with ``data`` (the file), ``observation_s`` (the
    data's span) and ``data_notes`` (what reading converted, then what the records dropped).

    Raises
    ------
    SceneError
        See :func:`load_table` and :func:`records_from_table`.
    """
    from gyro_instrument.estimators.adequacy import InadequateData
    from gyro_instrument.estimators.pipeline import estimate_records
    from gyro_instrument.scenes import build_instruments
    insts = build_instruments(scene)
    cols, read_notes = load_table(path, field, options)
    records, notes, span = records_from_table(insts, cols, path, field)
    notes = read_notes + notes
    try:
        result = estimate_records(scene, {n: insts[n] for n in records}, records)
    except InadequateData as exc:
        _name_a_length_unit(exc, insts, cols)
        raise
    result["observation_s"] = span
    result["data"] = os.path.basename(path)
    if notes:
        result["data_notes"] = notes
    if not math.isfinite(span):
        result["observation_s"] = None
    return result
