"""Reading CSV and Parquet tables of instrument channels as users have them (docs/formats/csv.md).

:func:`load_table` reads ``time_s`` and the ``<instrument>.<channel>`` columns, as
:class:`TableOptions` says (``--time-column``, ``--time-unit``, ``--angle-unit``, ``--column
NAME=SOURCE``, ``--separator``); :mod:`.data_io` turns them into estimator records.
"""

import csv
import os
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.files import opened_unless_utf8
from gyro_instrument.instruments.channels import ANGLE

TIME_COLUMN = "time_s"

#: ``--time-unit``: how many of the unit make a second (divided by, so that a whole number of ms,
#: us or ns becomes the double nearest the exact time: IEEE division is correctly rounded), or for
#: minutes, hours and days (:data:`MULTIPLIED_UNITS`) the seconds in one (multiplied by; days, as a
#: spreadsheet's serial date-times are, from the earliest first: one exact subtraction, one rounding).
TIME_UNITS = {"s": 1, "ms": 1000, "us": 1_000_000, "ns": 1_000_000_000, "min": 60, "h": 3600, "day": 86400}
MULTIPLIED_UNITS = ("min", "h", "day")


def seconds_per_unit(time_unit) -> float:
    """Seconds in one ``--time-unit`` (1 for None): 1e-3 for ms, 60 for min, 86400 for day."""
    if time_unit is None:
        return 1.0
    k = TIME_UNITS[time_unit]
    return float(k) if time_unit in MULTIPLIED_UNITS else 1.0 / k

#: ``--angle-unit``: the unit of the channels whose observation says they are angles
#: (:func:`channel_meanings`; rad, or deg converted to rad). Not positions (m) nor rates (rad/s).
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
        ``rad`` or ``deg`` (``--angle-unit``): unit of the angle columns (:func:`channel_meanings`).
    columns : tuple of (str, str)
        ``(NAME, SOURCE)`` pairs (``--column NAME=SOURCE``): the table's column SOURCE is read as the
        channel column NAME.
    separator : str or None
        CSV separator (``,``, ``;`` or ``tab``; ``--separator``); None sniffs it from the header.
    camera : CameraOptions or None
        A camera track's pixels, y axis, rotation and frame numbers (:mod:`.table_camera`).
    names : tuple of str or None
        A CSV without a header: its columns' names (``--no-header --names a,b,c``).
    """

    time_column: str = TIME_COLUMN
    time_unit: str | None = None
    angle_unit: str = "rad"
    columns: tuple = ()
    separator: str | None = None
    camera: object = None
    names: tuple | None = None

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


def import_pyarrow() -> "types.ModuleType":
    """pyarrow with its parquet module (a dependency); raises SceneError naming the package when it is missing."""
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


def csv_separator(first_line, path, field, separator) -> str:
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


def _open_text(path):
    """A text file, gzip, bz2 or xz compressed by its suffix (as pandas reads ``.csv.gz``)."""
    import bz2
    import gzip
    import lzma
    opener = {".gz": gzip.open, ".bz2": bz2.open, ".xz": lzma.open}.get(os.path.splitext(str(path))[1].lower(), open)
    return opener(path, "rt", newline="", encoding="utf-8-sig")       # the BOM, if any, is skipped


def _read_csv(path, field, separator, time_source=None, names=None):
    """(names, arrays, notes) of a CSV file (UTF-8, with or without a byte-order mark; compressed
    by its suffix; a spreadsheet's ``sep=;`` first line read as the separator); a ``time_source``
    column of ISO date-time text converted to seconds; ``names`` for a file without a header."""
    notes = []
    try:
        with _open_text(path) as fh:
            first = ""
            for line in fh:
                if line.strip():
                    first = line
                    break
            excel = first.strip().lower().startswith("sep=") and len(first.strip()) == 5
            sep = first.strip()[4] if excel and separator is None else csv_separator(
                first if not excel else "", path, field, separator)
            fh.seek(0)
            rows = list(csv.reader(fh, delimiter=sep))
            if excel:
                notes.append(f"first line {first.strip()!r}: the separator")
                rows = rows[[bool(r and any(c.strip() for c in r)) for r in rows].index(True) + 1:]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        utf8 = "; UTF-8 expected" if isinstance(exc, UnicodeDecodeError) else ""
        raise SceneError(field, path, f"cannot be read as CSV ({exc.__class__.__name__}{utf8})") from None
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise SceneError(field, path, "is empty; expected a header row time_s,<instrument>.<channel>,...")
    if names:
        if len(names) != len(rows[0]):
            raise SceneError("--names", ",".join(names), f"gives {len(names)} names for the {len(rows[0])} columns "
                                                         f"of {path}'s first row")
        rows = [list(names)] + rows
        notes.append(f"no header: columns named {', '.join(names)}")
    elif _numeric_row(rows[0], sep):
        raise SceneError(field, path, f"its first row ({sep.join(rows[0])[:60]}) is numbers, not a header: the file "
                                      f"has none; pass --no-header --names NAME,NAME,... ({len(rows[0])} names)")
    header = [h.strip() for h in rows[0]]
    _refuse_duplicates(header, path, field)
    decimal_comma = sep == ";"
    if sep != ",":
        notes.append(f"CSV separated by {'tab' if sep == chr(9) else repr(sep)}"
                     + (" (decimal commas read as points)" if decimal_comma else ""))
    cols = [np.full(len(rows) - 1, np.nan) for _ in header]
    texts = ([], [], [])                          # the time column's date-time texts: row, line, text
    line0 = 1 if names else 2
    for i, row in enumerate(rows[1:], start=line0):
        for j, (h, cell) in enumerate(zip(header, row)):
            cell = cell.strip()
            if cell:
                try:
                    cols[j][i - line0] = float(cell)
                except ValueError:
                    if decimal_comma and cell.count(",") == 1 and "." not in cell:
                        try:
                            cols[j][i - line0] = float(cell.replace(",", "."))
                            continue
                        except ValueError:
                            pass
                    if h == time_source and cell[:1].isdigit():
                        for k, v in zip(texts, (i - line0, i, cell)):
                            k.append(v)
                        continue
                    raise SceneError(field, path, f"line {i}, column {h}: {cell!r} is not a number") from None
    if texts[0]:
        from gyro_instrument.estimators.table_camera import datetime_seconds
        j = header.index(time_source)
        if len(texts[0]) < int(np.isfinite(cols[j]).sum()) + len(texts[0]):
            raise SceneError(field, path, f"column {time_source} mixes numbers and date-time text")
        secs, note = datetime_seconds(texts[2], texts[1], time_source, path, field)
        cols[j][np.array(texts[0])] = secs
        notes.append(note)
    return header, cols, notes


def _numeric_row(row, sep):
    """True when every non-empty cell of ``row`` reads as a number (decimal commas with ``;``) or an
    ISO date-time, and one at least as a number: data, not a header."""
    import datetime as dt
    cells = [c.strip() for c in row if c.strip()]
    numbers = 0
    for c in cells:
        try:
            float(c.replace(",", ".") if sep == ";" and c.count(",") == 1 and "." not in c else c)
            numbers += 1
        except ValueError:
            try:
                dt.datetime.fromisoformat(c[:-1] + "+00:00" if c.endswith("Z") else c)
            except ValueError:
                return False
    return numbers > 0


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
    pa = import_pyarrow()
    try:
        # the schema first: read_table fails on a name twice (ArrowInvalid of its dataset layer)
        with opened_unless_utf8(path) as src:
            names = list(pa.parquet.ParquetFile(src).schema_arrow.names)
    except Exception as exc:        # pyarrow raises its own error classes for a bad file
        raise SceneError(field, path, f"cannot be read as Parquet ({exc.__class__.__name__})") from None
    _refuse_duplicates(names, path, field)
    try:
        with opened_unless_utf8(path) as src:
            table = pa.parquet.read_table(src)
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


def channel_meanings(insts=None) -> dict:
    """{column: meaning} of a table's channel columns, as the observations declare them
    (:meth:`~gyro_instrument.instruments.observation.Observation.table_channels`: ``angle``, ``rate``,
    ``position``). ``insts`` (name -> instrument): the columns ``<name>.<channel>`` of the scene's
    instruments; None: by bare channel name over every registered instrument type, a name that is an
    angle for one type and something else for another left out (no scene says which)."""
    if insts is not None:
        return {f"{n}.{c.name}": c.meaning for n, i in insts.items()
                for c in i.OBSERVATION.table_channels(type(i))}
    from gyro_instrument.instruments import REGISTRY
    seen = {}
    for cls in REGISTRY.values():
        for c in cls.OBSERVATION.table_channels(cls):
            seen.setdefault(c.name, set()).add(c.meaning)
    return {name: next(iter(m)) for name, m in seen.items() if len(m) == 1}


def _meaning(meanings, column) -> str | None:
    """The meaning of ``column`` (``<instrument>.<channel>``) in :func:`channel_meanings`' dict."""
    if column in meanings:
        return meanings[column]
    return meanings.get(column.split(".", 1)[1]) if "." in column else None


def load_table(path, field="--data", options=None, meanings=None) -> tuple:
    """A CSV or Parquet table read as ``options`` say (:class:`TableOptions`; default: ``time_s`` in
    seconds, angles in radians, CSV separator sniffed). ``meanings``: :func:`channel_meanings` of the
    scene's instruments (default: of every registered type), which says which columns are angles.

    Returns
    -------
    cols : dict
        column name -> float ndarray (NaN for empty or ``nan`` cells), in file order, with the time
        column as ``time_s`` in seconds, ``--column`` sources under their channel names and the
        angle columns (:func:`channel_meanings`) in radians.
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
        names, arrays, notes = _read_csv(path, field, opts.separator, opts.time_column, opts.names)
    else:
        names, arrays, notes = _read_parquet(path, field, opts.time_column, opts.time_unit)
    raw = dict(zip(names, arrays))

    def shown(cols):
        cols = list(cols)
        return ", ".join(cols[:6]) + (", ..." if len(cols) > 6 else "") or "none"

    if opts.time_column not in raw:
        hint = ("pass --time-column NAME (frame numbers: --frame-column NAME --frame-rate HZ) or "
                if opts.time_column == TIME_COLUMN else "")
        raise SceneError(field, path, f"has no time column '{opts.time_column}' (columns: {shown(raw)}); "
                                      f"{hint}see docs/formats/csv.md")
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
        k, t = TIME_UNITS[opts.time_unit], cols[TIME_COLUMN]
        if opts.time_unit == "day" and np.isfinite(t).any():
            t = t - np.nanmin(t)                  # a serial date (45000 days): seconds from the earliest
        cols[TIME_COLUMN] = t * k if opts.time_unit in MULTIPLIED_UNITS else t / k
        notes.append(f"{opts.time_column} in {opts.time_unit}: converted to s"
                     + (" from the earliest sample" if opts.time_unit == "day" else ""))
    if opts.angle_unit == "deg":
        meanings = channel_meanings() if meanings is None else meanings
        converted = [c for c in cols if "." in c and _meaning(meanings, c) == ANGLE]
        for c in converted:
            cols[c] = np.radians(cols[c])
        notes.append("angles in degrees converted to rad: " + (", ".join(converted) or "no angle column"))
    if opts.camera is not None:
        cols = opts.camera.apply(cols, notes, path, field)
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
