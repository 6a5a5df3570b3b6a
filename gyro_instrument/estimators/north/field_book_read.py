"""Reading a field book: the CSV a surveyor writes, into SI (issue 24 item 6, issue 33 item 5).

Part of :mod:`.field_book` (its docstring documents the columns, units and rules). One row is one
turning point, in the order observed; lines starting with ``#`` are comments. The separator is
sniffed from the header line as for ``estimate --data`` (``,``, ``;`` with decimal commas, or tab;
:func:`.table_read.csv_separator`) unless ``--separator`` names it. Errors are
:class:`~gyro_instrument.core.errors.SceneError` naming the file, the line, the column and the value.
"""

import csv
import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.angle_formats import ANGLE_UNITS, parse_angle, parse_clock
from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators.table_read import SEPARATORS, csv_separator

#: time units: seconds per unit; ``hms``: clock times ``mm:ss`` or ``hh:mm:ss`` (a bare ``time`` column
#: whose cells hold a colon is read as ``hms``)
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9, "min": 60.0, "hms": 1.0}
#: column stems and their kinds: angle and time columns take a unit suffix; the others none
COLUMNS = {"reading": "angle", "time": "time", "tape_reading": "angle", "tape_time": "time",
           "turning_point": "index", "side": "side", "remark": "text"}
#: the sides a ``side`` column may name (clockwise circle: the left turning points read less)
SIDES = {"left": -1, "l": -1, "west": -1, "w": -1, "right": 1, "r": 1, "east": 1, "e": 1}


@dataclass(frozen=True)
class Swing:
    """One swing's turning points as read (rotor on, or the tape alone with the rotor off).

    Attributes
    ----------
    column : str
        The readings' column.
    index : ndarray of int
        Turning-point number of each reading present, from 0 (missed ones are absent).
    readings_rad : ndarray
        The readings (rad), clockwise circle readings unwrapped about the first.
    lines : ndarray of int
        The file line of each reading.
    texts : tuple of str
        Each reading as written.
    time_index, time_values_s : ndarray
        Turning-point number and time (s) of every timed row, a missed reading's time included.
    missed : tuple of dict
        ``{turning_point, line, time_s}`` of each turning point whose reading is missing (line and
        time None when the book skips its number).
    first_number : int
        The book's number of turning point 0 (``turning_point`` column; else 1).
    """

    column: str
    index: np.ndarray
    readings_rad: np.ndarray
    lines: np.ndarray
    texts: tuple
    time_index: np.ndarray
    time_values_s: np.ndarray
    missed: tuple = ()
    first_number: int = 1

    @property
    def consecutive(self) -> bool:
        """True when no turning point is missing between the first and the last."""
        return bool(self.index.size and self.index[-1] - self.index[0] == self.index.size - 1)

    @property
    def reading_times_s(self) -> np.ndarray | None:
        """The time of each reading present (nan where none was written), or None without times."""
        if self.time_index.size == 0:
            return None
        lookup = dict(zip(self.time_index.tolist(), self.time_values_s.tolist()))
        return np.array([lookup.get(int(k), math.nan) for k in self.index])


@dataclass(frozen=True)
class FieldBook:
    """A field book in SI (rad, s): the rotor-on swing and, when written, the tape's.

    Attributes
    ----------
    on, off : Swing, Swing or None
    angle_unit, time_unit : str
        The units of the ``reading`` and ``time`` columns.
    notes : tuple of str
    path : str
    """

    on: Swing
    off: Swing | None = None
    angle_unit: str = "rad"
    time_unit: str = "s"
    notes: tuple = ()
    path: str = ""

    @property
    def readings_rad(self) -> np.ndarray:
        """The rotor-on readings present (rad)."""
        return self.on.readings_rad

    @property
    def times_s(self) -> np.ndarray | None:
        """Their times (s; nan where none), or None."""
        return self.on.reading_times_s

    @property
    def tape_readings_rad(self) -> np.ndarray | None:
        """The tape's readings present (rad), or None."""
        return None if self.off is None else self.off.readings_rad

    @property
    def tape_times_s(self) -> np.ndarray | None:
        """Their times (s), or None."""
        return None if self.off is None else self.off.reading_times_s


def _split_header(name, path, field):
    """(stem, unit or None) of a header cell; SceneError for an unknown column or unit."""
    for stem in sorted(COLUMNS, key=len, reverse=True):
        kind = COLUMNS[stem]
        units = ANGLE_UNITS if kind == "angle" else TIME_UNITS if kind == "time" else ()
        if name == stem:
            return stem, None
        if name.startswith(stem + "_") and name[len(stem) + 1:] in units:
            return stem, name[len(stem) + 1:]
    raise SceneError(field, path, f"column {name!r} is not a field-book column; expected reading_<unit>, "
                                  f"time_<tunit>, tape_reading_<unit>, tape_time_<tunit>, turning_point, side, "
                                  f"remark with <unit> one of {', '.join(ANGLE_UNITS)} and <tunit> one of "
                                  f"{', '.join(TIME_UNITS)}")


def _unit(stem, header_unit, option, cells, path, field):
    """The column's unit: the header's, else the option's; refused when they disagree."""
    kind = COLUMNS[stem]
    units = ANGLE_UNITS if kind == "angle" else TIME_UNITS
    name = "--angle-unit" if kind == "angle" else "--time-unit"
    if option is not None and option not in units:
        raise SceneError(name, option, f"must be one of {', '.join(units)} with --reversal-points")
    if header_unit and option and header_unit != option:
        raise SceneError(name, option, f"contradicts the header of {path} (column {stem}_{header_unit}); "
                                       f"drop the option or the unit in the header")
    unit = header_unit or option
    if unit is None and kind == "time":
        return "hms" if any(":" in c for c in cells) else "s"
    if unit is None:
        raise SceneError(field, path, f"column {stem!r} states no unit: write {stem}_deg, {stem}_dms, "
                                      f"{stem}_gon, ... or pass --angle-unit ({', '.join(ANGLE_UNITS)})")
    return unit


def _rows(path, field, separator):
    """(file lines, rows of stripped cells, separator) without comments and blank lines."""
    if separator is not None and separator not in SEPARATORS:
        raise SceneError("--separator", separator, f"must be one of {', '.join(SEPARATORS)}")
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            lines = [(i, line) for i, line in enumerate(fh, start=1)
                     if line.strip() and not line.lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(field, path, f"cannot be read ({exc.__class__.__name__}); a UTF-8 CSV file expected") from None
    if len(lines) < 2:
        raise SceneError(field, path, "holds no turning points; expected a header such as time_s,reading_dms "
                                      "and one row per turning point")
    sep = csv_separator(lines[0][1], path, field, separator)
    rows = list(csv.reader([line for _, line in lines], delimiter=sep))
    return [n for n, _ in lines], [[c.strip() for c in r] for r in rows], sep


def _cells(values, lines):
    """[(row position, line, cell)] of the non-empty cells, and the position after the last one."""
    out = [(k, lines[k], c) for k, c in enumerate(values) if c]
    return out, (out[-1][0] + 1 if out else 0)


def _angles(cells, unit, name, path, field, division_rad, comma):
    out = []
    for _, line, cell in cells:
        try:
            v = parse_angle(cell, unit, division_rad, comma)
        except ValueError as exc:
            raise SceneError(field, path, f"line {line}, column {name}: {exc}") from None
        if abs(v) >= 2.0 * math.pi:
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} is outside the circle (one turn)")
        out.append(v)
    return np.array(out, dtype=float)


def _times(cells, unit, name, path, field, comma):
    out = []
    for _, line, cell in cells:
        try:
            text = cell.replace(",", ".") if comma else cell
            v = parse_clock(text) if unit == "hms" else float(text)
        except ValueError as exc:
            msg = str(exc) if unit == "hms" else f"{cell!r} is not a number"
            raise SceneError(field, path, f"line {line}, column {name}: {msg}") from None
        if not math.isfinite(v):
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} must be a finite number")
        out.append(v * TIME_UNITS[unit])
    t = np.array(out, dtype=float)
    bad = np.nonzero(np.diff(t) <= 0)[0]
    if bad.size:
        k = int(bad[0]) + 1
        raise SceneError(field, path, f"line {cells[k][1]}, column {name}: {cells[k][2]!r} must be later than the "
                                      f"previous time {cells[k - 1][2]!r} (times strictly increasing)")
    return t


def _turning_numbers(cols, lines, n, path, field):
    """Turning-point number of each row position (from 0): the ``turning_point`` column's, else the row's."""
    if "turning_point" not in cols:
        return np.arange(n), 1
    name, values = cols["turning_point"]
    out, prev = [], None
    for k in range(n):
        cell = values[k] if k < len(values) else ""
        if not cell and prev is not None:       # a row past the readings (the tape's): the next number
            out.append(prev + 1)
            prev += 1
            continue
        try:
            v = int(cell)
        except ValueError:
            raise SceneError(field, path, f"line {lines[k]}, column {name}: {cell!r} is not a whole number") from None
        if prev is not None and v <= prev:
            raise SceneError(field, path, f"line {lines[k]}, column {name}: {v} must exceed the previous {prev} "
                                          f"(turning points in the order observed; a skipped number is a missed point)")
        out.append(v)
        prev = v
    return np.array(out) - out[0], out[0]


def _check_alternating(sw, path, field):
    """Readings alternate: between turning points an odd number apart the swing's direction flips with
    the parity of the first (−1)^k; refused naming the later reading's line."""
    a, k = sw.readings_rad, sw.index
    ok = (np.diff(k) % 2) == 1
    d = np.diff(a)[ok] * (-1.0) ** k[:-1][ok]
    if d.size == 0:
        return
    wrong = np.nonzero(np.sign(d) != np.sign(d[0]))[0]
    if np.any(d == 0) or wrong.size:
        j = int(np.nonzero(ok)[0][wrong[0] if wrong.size else int(np.argmin(np.abs(d)))]) + 1
        raise SceneError(field, path, f"line {sw.lines[j]}, column {sw.column}: {sw.texts[j]!r}: turning points "
                                      f"must alternate about the centre (each on the other side from its "
                                      f"neighbours); this one continues the previous swing's direction")


def _side_of_index(sw):
    """s with side(k) = s (−1)^k (+1 right, −1 left) from the first readings an odd number apart, or None."""
    a, k = sw.readings_rad, sw.index
    for i in range(k.size - 1):
        if (k[i + 1] - k[i]) % 2:
            return int(np.sign(a[i + 1] - a[i])) * (-1) ** int(k[i + 1] % 2)
    return None


def _check_sides(sides, positions, sw, path, field):
    """A ``side`` column's left/right agree with the readings (clockwise circle: a left turning point
    reads less than the right ones beside it) and alternate; refused naming the line."""
    name, values = sides
    ref = _side_of_index(sw)
    for p, k, line in zip(positions, sw.index, sw.lines):
        cell = values[p] if p < len(values) else ""
        if not cell:
            continue
        if cell.lower() not in SIDES:
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} is not a side; write left or right")
        s = SIDES[cell.lower()] * (-1) ** int(k % 2)
        if ref is None:
            ref = s
        elif s != ref:
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} disagrees with the readings (a "
                                          f"left turning point reads less than the right ones beside it, and the "
                                          f"sides alternate)")


def _unwrapped(a, name, notes):
    un = a[0] + (a - a[0] + math.pi) % (2 * math.pi) - math.pi
    if np.any(np.abs(un - a) > 1):
        notes.append(f"{name}: readings across the circle's zero unwrapped about the first")
    return un


def _swing(cols, lines, stem, units, ctx, notes):
    """The :class:`Swing` of ``stem`` (``reading`` or ``tape_reading``) and its times, checked; None if empty.

    ``ctx``: (path, field, division_rad, decimal_comma, side column or None)."""
    path, field, division, comma, sides, (numbers, first) = ctx
    name, values = cols[stem]
    cells, end = _cells(values, lines)
    if not cells:
        return None
    pos = np.array([p for p, _, _ in cells])
    number = numbers if stem == "reading" else np.arange(len(lines))
    first = first if stem == "reading" else 1
    a = _unwrapped(_angles(cells, units[stem], name, path, field, division, comma), name, notes)
    tstem = "time" if stem == "reading" else "tape_time"
    t_idx, t_val = np.array([], dtype=int), np.array([])
    if tstem in cols:
        tname, tvalues = cols[tstem]
        tcells, tend = _cells(tvalues, lines)
        if tend > end:
            raise SceneError(field, path, f"line {lines[tend - 1]}, column {tname}: a time after the last reading "
                                          f"of {name}; every time belongs to a turning point's row")
        t_val = _times(tcells, units[tstem], tname, path, field, comma)
        t_idx = number[[p for p, _, _ in tcells]]
    times = dict(zip(t_idx.tolist(), t_val.tolist()))
    row_of = {int(number[p]): p for p in range(end)}
    present = set(number[pos].tolist())
    missed = tuple({"turning_point": k + first, "line": lines[row_of[k]] if k in row_of else None,
                    "time_s": times.get(k)} for k in range(int(number[pos[-1]])) if k not in present)
    sw = Swing(name, number[pos], a, np.array(lines)[pos], tuple(c for _, _, c in cells), t_idx, t_val, missed,
               first)
    _check_alternating(sw, path, field)
    if sides is not None and stem == "reading":
        _check_sides(sides, pos, sw, path, field)
    return sw


def read_field_book(path, angle_unit=None, time_unit=None, field="--reversal-points", separator=None,
                    division_rad=None) -> FieldBook:
    """Read a field book (:mod:`.field_book`'s docstring) into SI.

    Parameters
    ----------
    path : str
        The CSV file.
    angle_unit, time_unit : str, optional
        Units of bare ``reading`` / ``time`` headers (a header's own unit must agree).
    field : str
        The option named in errors.
    separator : str, optional
        ``,``, ``;`` or ``tab`` (``--separator``); None sniffs it from the header line.
    division_rad : float, optional
        The value of one scale division (``div`` columns; ``--scale-division``).

    Returns
    -------
    FieldBook

    Raises
    ------
    SceneError
        Naming the file, the line, the column, the value and what is valid: an unknown column or
        unit, a unit the header and the option disagree on, an unreadable cell, readings that do not
        alternate, a side that disagrees, a time going back, fewer than 3 turning points.
    """
    path = str(path)
    lines, rows, sep = _rows(path, field, separator)
    header, body, lines = rows[0], rows[1:], lines[1:]
    cols, units = {}, {}
    for j, name in enumerate(header):
        stem, hunit = _split_header(name, path, field)
        if stem in cols:
            raise SceneError(field, path, f"columns {cols[stem][0]!r} and {name!r} are the same field; keep one")
        cols[stem] = (name, [r[j] if j < len(r) else "" for r in body])
        kind = COLUMNS[stem]
        if kind in ("angle", "time"):
            units[stem] = _unit(stem, hunit, angle_unit if kind == "angle" else time_unit, cols[stem][1], path, field)
    if "reading" not in cols:
        raise SceneError(field, path, f"has no reading column (header {','.join(header)}); add reading_<unit>")
    if "div" in units.values() and division_rad is None:
        col = next(cols[s][0] for s, u in units.items() if u == "div")
        raise SceneError("--scale-division", None, f"column {col} of {path} holds scale divisions: state the value "
                                                   f"of one, e.g. --scale-division 10arcmin")
    notes = [f"CSV separated by {'tab' if sep == chr(9) else repr(sep)}" + (" (decimal commas read as points)"
                                                                            if sep == ";" else "")] if sep != "," else []
    comma = sep == ";"
    ctx = (path, field, division_rad, comma, cols.get("side"), _turning_numbers(cols, lines, len(body), path, field))
    on = _swing(cols, lines, "reading", units, ctx, notes)
    if on is None or on.index.size < 3:
        raise SceneError(field, path, f"holds {0 if on is None else on.index.size} turning point readings; the "
                                      f"Schuler mean and Lavrov's method need >= 3 (>= 4 for a sigma from the scatter)")
    off = _swing(cols, lines, "tape_reading", units, ctx, notes) if "tape_reading" in cols else None
    for sw in (on, off):
        if sw is not None and sw.missed:
            notes.append(f"{sw.column}: turning point(s) " + ", ".join(
                f"{m['turning_point']}" + (f" (line {m['line']}" if m["line"] else " (no row")
                + (f", {m['time_s']:g} s)" if m["time_s"] is not None else ")")
                for m in sw.missed) + " missing: left out, the others kept in their places")
    return FieldBook(on, off, units["reading"], units.get("time", "s"), tuple(notes), path)
