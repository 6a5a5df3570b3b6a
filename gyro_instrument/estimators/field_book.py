"""Field books: turning points written down by hand, read into SI (issue 24, item 6).

A surveyor with a gyrotheodolite reads the scale (or the horizontal circle, following the swing
with the tangent screw) at each reversal point, and perhaps times it; with a torsion tape she also
swings the gyroscope with the rotor off and reads the tape's turning points. A field book is a CSV
table of those readings, one turning point a row, in the order observed::

    # station A, 2024-05-02, GAK1 no. 123          (lines starting with # are comments)
    time_s,reading_gon,tape_time_s,tape_reading_gon
    0.0,399.8731,0.0,0.0213
    241.2,0.1478,300.5,-0.0188
    ...

Columns (any order; only ``reading`` is required; a column may end early — empty cells after its
last value — but may not have holes):

==========================  =====================================================================
``reading_<unit>``          rotor-on turning points (scale or circle readings)
``time_<tunit>``            their times (optional)
``tape_reading_<unit>``     rotor-off turning points of the tape alone (optional)
``tape_time_<tunit>``       their times (optional; with ``time`` they give the tape ratio D_B/D_K)
==========================  =====================================================================

Angle units ``<unit>``: rad, mrad, deg, gon, mgon, arcmin, arcsec (:data:`ANGLE_UNITS`); time units
``<tunit>``: s, min (:data:`TIME_UNITS`). A bare ``reading`` / ``time`` header takes its unit from the
``angle_unit`` / ``time_unit`` option; a header unit that contradicts the option is refused. Circle
readings that straddle the zero (399.98 gon, 0.02 gon) are unwrapped about the first reading, and a
note says so. Readings must alternate about the centre (a swing). Errors are
:class:`~gyro_instrument.core.errors.SceneError` naming the file, the line, the column, the value
and the valid range.

:func:`field_book_north` gives the Schuler mean and Lavrov's estimate with their σ from the scatter
(the same :mod:`gyro_instrument.estimators.north` code as on simulated records), tape-corrected
when the book holds the rotor-off swing and the times of both.
"""

import csv
import math
from dataclasses import dataclass, replace

import numpy as np

from gyro_instrument.core.errors import SceneError
from gyro_instrument.estimators import north

#: angle units: radians per unit (gon: 400 to the turn; mgon 1e-3 gon)
ANGLE_UNITS = {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0, "gon": math.pi / 200.0,
               "mgon": math.pi / 200000.0, "arcmin": math.pi / 10800.0, "arcsec": math.pi / 648000.0}
#: time units: seconds per unit
TIME_UNITS = {"s": 1.0, "min": 60.0}
#: column stems: (kind, required)
COLUMNS = {"reading": ("angle", True), "time": ("time", False), "tape_reading": ("angle", False),
           "tape_time": ("time", False)}


@dataclass(frozen=True)
class FieldBook:
    """A field book in SI (rad, s).

    Attributes
    ----------
    readings_rad : ndarray
        Rotor-on turning points, unwrapped about the first.
    times_s : ndarray or None
    tape_readings_rad, tape_times_s : ndarray or None
        Rotor-off turning points (tape alone) and their times.
    angle_unit, time_unit : str
        The units the book was written in.
    notes : tuple of str
    """

    readings_rad: np.ndarray
    times_s: np.ndarray | None = None
    tape_readings_rad: np.ndarray | None = None
    tape_times_s: np.ndarray | None = None
    angle_unit: str = "rad"
    time_unit: str = "s"
    notes: tuple = ()


def _split_header(name, path, field):
    """(stem, unit or None) of a header cell; SceneError for an unknown column or unit."""
    for stem in sorted(COLUMNS, key=len, reverse=True):
        kind = COLUMNS[stem][0]
        units = ANGLE_UNITS if kind == "angle" else TIME_UNITS
        if name == stem:
            return stem, None
        if name.startswith(stem + "_") and name[len(stem) + 1:] in units:
            return stem, name[len(stem) + 1:]
    valid = ", ".join(f"{s}_<{'unit' if k == 'angle' else 'tunit'}>" for s, (k, _) in COLUMNS.items())
    raise SceneError(field, path, f"column {name!r} is not a field-book column; expected {valid} with <unit> "
                                  f"one of {', '.join(ANGLE_UNITS)} and <tunit> one of {', '.join(TIME_UNITS)}")


def _unit(stem, header_unit, option, path, field):
    kind = COLUMNS[stem][0]
    units = ANGLE_UNITS if kind == "angle" else TIME_UNITS
    name = "--angle-unit" if kind == "angle" else "--time-unit"
    if option is not None and option not in units:
        raise SceneError(name, option, f"must be one of {', '.join(units)}")
    if header_unit and option and header_unit != option:
        raise SceneError(name, option, f"contradicts the header of {path} (column {stem}_{header_unit}); "
                                       f"drop the option or the unit in the header")
    unit = header_unit or option
    if unit is None:
        if kind == "time":
            return "s"
        raise SceneError(field, path, f"column {stem!r} states no unit: write {stem}_deg, {stem}_gon, ... or "
                                      f"pass --angle-unit ({', '.join(ANGLE_UNITS)})")
    return unit


def _rows(path, field):
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            lines = [(i, line) for i, line in enumerate(fh, start=1) if line.strip() and not line.lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(field, path, f"cannot be read ({exc.__class__.__name__}); a UTF-8 CSV file expected") from None
    if len(lines) < 2:
        raise SceneError(field, path, "holds no turning points; expected a header such as time_s,reading_deg "
                                      "and one row per turning point")
    rows = list(csv.reader([line for _, line in lines]))
    return [n for n, _ in lines], [[c.strip() for c in r] for r in rows]


def _column(values, lines, name, path, field):
    """Floats of one column: empty cells only after its last value; SceneError naming the line."""
    out = []
    for line, cell in zip(lines, values):
        if not cell:
            out.append(None)
            continue
        try:
            v = float(cell)
        except ValueError:
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} is not a number") from None
        if not math.isfinite(v):
            raise SceneError(field, path, f"line {line}, column {name}: {cell!r} must be a finite number")
        out.append(v)
    while out and out[-1] is None:
        out.pop()
    if None in out:
        line = lines[out.index(None)]
        raise SceneError(field, path, f"line {line}, column {name}: empty cell inside the column; turning points "
                                      f"must be consecutive (end the column early instead)")
    return np.array(out, dtype=float)


def _check_angles(x, unit, lines, name, path, field):
    """In SI, |reading| < one turn; circle readings unwrapped about the first. Returns (rad, note)."""
    turn = 2.0 * math.pi / ANGLE_UNITS[unit]
    bad = np.nonzero(np.abs(x) >= turn)[0]
    if bad.size:
        k = int(bad[0])
        raise SceneError(field, path, f"line {lines[k]}, column {name}: {float(x[k])!r} is outside the scale, "
                                      f"(−{turn:g}, {turn:g}) {unit}")
    rad = x * ANGLE_UNITS[unit]
    un = rad[0] + (rad - rad[0] + math.pi) % (2 * math.pi) - math.pi
    note = f"{name}: readings across the scale's zero unwrapped about the first" if np.any(np.abs(un - rad) > 1) else None
    return un, note


def _check_alternating(rad, lines, name, path, field):
    d = np.diff(rad)
    bad = np.nonzero(d[1:] * d[:-1] >= 0)[0]
    if bad.size:
        k = int(bad[0]) + 2
        raise SceneError(field, path, f"line {lines[k]}, column {name}: turning points must alternate about the "
                                      f"centre (each between its neighbours' sides); this one continues the previous "
                                      f"swing's direction")


def _check_times(ts, lines, name, path, field):
    bad = np.nonzero(np.diff(ts) <= 0)[0]
    if bad.size:
        k = int(bad[0]) + 1
        raise SceneError(field, path, f"line {lines[k]}, column {name}: {float(ts[k])!r} must be later than the previous "
                                      f"time {float(ts[k - 1])!r} (times strictly increasing)")


def _read_pair(cols, lines, stem, units, path, field, notes):
    """(angles_rad, times_s or None) of ``stem``'s readings and its times column, checked."""
    name, values = cols[stem]
    a = _column(values, lines, name, path, field)
    if a.size == 0:
        return None, None
    a, note = _check_angles(a, units[stem], lines, name, path, field)
    if note:
        notes.append(note)
    _check_alternating(a, lines, name, path, field)
    tstem = "time" if stem == "reading" else "tape_time"
    if tstem not in cols:
        return a, None
    tname, tvalues = cols[tstem]
    ts = _column(tvalues, lines, tname, path, field)
    if ts.size != a.size:
        raise SceneError(field, path, f"column {tname} holds {ts.size} times for {a.size} readings in {name}; "
                                      f"give one time per turning point (or none)")
    _check_times(ts, lines, tname, path, field)
    return a, ts * TIME_UNITS[units[tstem]]


def read_field_book(path, angle_unit=None, time_unit=None, field="--reversal-points") -> FieldBook:
    """Read a field book (module docstring) into SI.

    Parameters
    ----------
    path : str
        The CSV file.
    angle_unit, time_unit : str, optional
        Units for bare ``reading`` / ``time`` headers (a header's own unit must agree).
    field : str
        The option named in errors.

    Returns
    -------
    FieldBook

    Raises
    ------
    SceneError
        Naming the file, the line, the column, the value and the valid range or what to write.
    """
    path = str(path)
    lines, rows = _rows(path, field)
    header, body, lines = rows[0], rows[1:], lines[1:]
    cols, units = {}, {}
    for j, name in enumerate(header):
        stem, hunit = _split_header(name, path, field)
        if stem in cols:
            raise SceneError(field, path, f"columns {cols[stem][0]!r} and {name!r} are the same field; keep one")
        cols[stem] = (name, [r[j] if j < len(r) else "" for r in body])
        units[stem] = _unit(stem, hunit, angle_unit if COLUMNS[stem][0] == "angle" else time_unit, path, field)
    if "reading" not in cols:
        raise SceneError(field, path, f"has no reading column (header {','.join(header)}); add reading_<unit>")
    notes = []
    a, ts = _read_pair(cols, lines, "reading", units, path, field, notes)
    if a is None or a.size < 3:
        raise SceneError(field, path, f"holds {0 if a is None else a.size} turning points; the Schuler mean and "
                                      f"Lavrov's method need ≥ 3 (≥ 4 for a σ from the scatter)")
    za, zt = _read_pair(cols, lines, "tape_reading", units, path, field, notes) if "tape_reading" in cols else (None, None)
    return FieldBook(a, ts, za, zt, units["reading"], units.get("time", "s"), tuple(notes))


def write_field_book(path, readings_rad, times_s=None, tape_readings_rad=None, tape_times_s=None,
                     angle_unit="deg", decimals=None) -> None:
    """Write a field book (module docstring): readings in ``angle_unit`` (``decimals`` places, else
    full precision, 17 significant digits), times in s; columns of unequal length end early."""
    if angle_unit not in ANGLE_UNITS:
        raise SceneError("angle_unit", angle_unit, f"must be one of {', '.join(ANGLE_UNITS)}")
    k = ANGLE_UNITS[angle_unit]
    cols = [(f"reading_{angle_unit}", np.asarray(readings_rad, dtype=float) / k)]
    if times_s is not None:
        cols.append(("time_s", np.asarray(times_s, dtype=float)))
    if tape_readings_rad is not None:
        cols.append((f"tape_reading_{angle_unit}", np.asarray(tape_readings_rad, dtype=float) / k))
        if tape_times_s is not None:
            cols.append(("tape_time_s", np.asarray(tape_times_s, dtype=float)))

    def fmt(v, angle):
        return f"{v:.{decimals}f}" if (decimals is not None and angle) else repr(float(v))

    n = max(c.size for _, c in cols)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([name for name, _ in cols])
        for i in range(n):
            w.writerow([fmt(c[i], "reading" in name) if i < c.size else "" for name, c in cols])


def field_book_north(book) -> dict:
    """The Schuler mean and Lavrov's estimate of a field book, σ from the scatter.

    Returns ``{name: NorthEstimate}`` for ``schuler_mean`` and ``lavrov``; when the book holds the
    rotor-off swing with the times of both swings, each is tape-corrected: the tape zero Z is the
    Schuler mean of the tape readings, D_B/D_K comes from the two half periods (the mean spacing of
    the turning times, :func:`gyro_instrument.estimators.north.tape_ratio`). Without the times the
    centres stay uncorrected and a note says the tape was not removed.
    """
    out = {"schuler_mean": north.schuler_mean(book.readings_rad), "lavrov": north.lavrov(book.readings_rad)}
    if book.tape_readings_rad is None:
        return out
    if book.times_s is None or book.tape_times_s is None or book.tape_readings_rad.size < 3:
        note = ("tape readings given without the times of both swings (or < 3 of them): the tape ratio "
                "D_B/D_K is unknown and the tape torque is not removed",)
        return {k: replace(v, notes=v.notes + note) for k, v in out.items()}
    zero = north.schuler_mean(book.tape_readings_rad)
    on, off = (north.half_period(ts) for ts in (book.times_s, book.tape_times_s))
    ratio, ratio_sigma = north.tape_ratio(on[0], off[0], on[1], off[1])
    zs = zero.sigma_rad or 0.0
    return {k: north.tape_corrected(v, zero.centre_rad, ratio, ratio_sigma, zs) for k, v in out.items()}
