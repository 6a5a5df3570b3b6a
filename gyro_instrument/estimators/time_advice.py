"""What to pass when a table's time axis is not in seconds (issue 34 item 4), computed from the record.

The ``sampling``, ``time_unit`` and ``period`` refusals of :mod:`.adequacy` see times after the
table's conversion (``--time-unit``, ``--frame-rate``); their entries carry the record's own swing
period in those converted units (``record_period``) and the scene's (``expected_period_s``).
:func:`advise_time` undoes the conversion the user asked for, so the advice is about the column as
written, never about the last flag tried: it cannot loop (``--time-unit min`` → "ms" → "min"), and
applying it puts the record's period within a factor 2 of the scene's in one step. Frame numbers
(whole numbers, a step of one) are named as such with the frame rate they imply; a column of
spreadsheet serial days (values of a date after 1954, a day's period ratio) as Excel serial days.
"""

import math

import numpy as np

from gyro_instrument.estimators.table_read import seconds_per_unit

#: Units a time column may be written in: (its ``--time-unit``, name, seconds in one).
UNITS = (("s", "seconds", 1.0), ("ms", "milliseconds", 1e-3), ("us", "microseconds", 1e-6),
         ("ns", "nanoseconds", 1e-9), ("min", "minutes", 60.0), ("h", "hours", 3600.0), ("day", "days", 86400.0))
#: A camera's frame rates, Hz: a record in frames whose period ratio lies here is named as frames.
FRAME_RATES_HZ = (4.0, 1000.0)
#: Spreadsheet serial days of the years 1955 to 2119 (days since 1899-12-30).
SERIAL_DAYS = (20000.0, 80000.0)
#: Notes of :func:`~.table_read.load_table` for a time read exactly in seconds (date-time text,
#: a Parquet timestamp or duration): no unit to advise.
EXACT_TIME_NOTES = ("date-time text", " stored as ")


def advise_time(exc, options, raw_times_s, read_notes) -> None:
    """Restate ``exc`` (an :class:`~.adequacy.InadequateData` of the ``sampling``, ``time_unit`` or
    ``period`` check carrying ``record_period``) with what to pass, computed from the column as
    written: its values are ``raw_times_s`` (the table's time in seconds after the conversion
    ``options`` asked for) divided back by that conversion. Other refusals are left as they are.
    """
    entry = exc.check
    p_rec, p_exp = entry.get("record_period"), entry.get("expected_period_s")
    if entry.get("check") not in ("sampling", "time_unit", "period") or not p_rec or not p_exp:
        return
    camera = getattr(options, "camera", None)
    fps = camera.frame_rate_hz if camera is not None and camera.frame_column else None
    per = 1.0 / fps if fps else seconds_per_unit(getattr(options, "time_unit", None))
    raw = np.asarray(raw_times_s, float)
    raw = raw[np.isfinite(raw)] / per
    ratio = (p_rec / per) / p_exp                       # the record's period in column units per scene second
    said = (f"the record's own swing period is {p_rec / per:.6g} in the time column's units against the scene's "
            f"predicted {p_exp:.6g} s (ratio {ratio:.4g})")
    if any(mark in n for n in read_notes for mark in EXACT_TIME_NOTES):
        exc.restate(f"{said}, and the time column holds date-times (seconds, exact): the scene does not describe "
                    f"this instrument (check its length or constants)")
        return
    advice = _what_to_pass(ratio, raw, options, fps, per)
    if advice:
        exc.restate(f"{said}: {advice}")


def _what_to_pass(ratio, raw, options, fps, per) -> str | None:
    """The advice for a column whose period is ``ratio`` of its units per scene second; None when the
    time is read as the column's unit says it is (or no unit explains it): not a time-unit problem
    (an alias, or a scene that does not describe the record), the check's own words stand."""
    column = getattr(camera_of(options), "frame_column", None) or getattr(options, "time_column", "time_s")
    unit = min(UNITS, key=lambda u: abs(math.log(ratio * u[2])))
    frames = _whole_steps(raw) and FRAME_RATES_HZ[0] <= ratio <= FRAME_RATES_HZ[1]
    if fps or (frames and abs(math.log(ratio * unit[2])) > math.log(1.25)):
        also = "" if fps else _leave_out(options, frame=True)
        return (f"time looks like frame numbers ({column}) at about {ratio:.4g} frames per second; pass --frame-column "
                f"{column} --frame-rate {ratio:.4g} (or the camera's exact rate near it){also}")
    if abs(math.log(ratio * unit[2])) > math.log(2.0) or unit[2] == per:
        return None
    flag, name, _ = unit
    if flag == "day" and raw.size and SERIAL_DAYS[0] <= float(np.median(raw)) <= SERIAL_DAYS[1]:
        name = "Excel serial days (days since 1899-12-30, the fraction the time of day)"
    given = getattr(options, "time_unit", None)
    if flag == "s":
        return f"the time ({column}) is in seconds; leave --time-unit {given} out"
    return f"time looks like {name} ({column}); pass --time-unit {flag}" + (f" (not {given})" if given else "")


def camera_of(options) -> "CameraOptions | None":
    """The table options' camera options, or None."""
    return getattr(options, "camera", None)


def _leave_out(options, frame=False) -> str:
    """The flags the frame advice replaces (``--time-column``, ``--time-unit``), as words."""
    out = []
    if frame and getattr(options, "time_column", "time_s") != "time_s":
        out.append(f"instead of --time-column {options.time_column}")
    if getattr(options, "time_unit", None):
        out.append(f"without --time-unit {options.time_unit}")
    return f" ({', '.join(out)})" if out else ""


def _whole_steps(raw) -> bool:
    """True when the column's values are whole numbers stepping by one mostly (frame numbers)."""
    if raw.size < 3:
        return False
    whole = np.abs(raw - np.rint(raw)) <= 1e-6 * np.maximum(1.0, np.abs(raw))
    steps = np.diff(np.unique(np.rint(raw)))
    return bool(whole.all() and steps.size and np.median(steps) == 1.0)
