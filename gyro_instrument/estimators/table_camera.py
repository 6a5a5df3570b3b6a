"""Camera tracks as tables (docs/formats/csv.md): positions in pixels, an image y axis pointing down, a
camera turned from east, time as frame numbers at a frame rate or as date-time text.

:class:`CameraOptions` (``--metres-per-pixel``, ``--y-down``, ``--rotation-deg``, ``--frame-column``,
``--frame-rate``) is applied by :func:`~.table_read.load_table` after the columns are named
(``--column``): every pendulum's ``x_east``/``y_north`` pair is scaled to metres, its y flipped, then
turned to east/north; the frame column becomes ``time_s``. :func:`datetime_seconds` reads a time
column of ISO 8601 date-time text exactly.
"""

import datetime as dt
import math
from dataclasses import dataclass

import numpy as np

from gyro_instrument.core.errors import SceneError

#: The position channels a camera gives (metres once scaled).
POSITION_CHANNELS = ("x_east", "y_north")


@dataclass(frozen=True)
class CameraOptions:
    """How a camera wrote its track.

    Attributes
    ----------
    metres_per_pixel : float or None
        Positions in pixels, this many metres each (``--metres-per-pixel``); None: metres.
    y_down : bool
        The image y axis points down (``--y-down``): y is negated (before the rotation).
    rotation_deg : float
        The camera's x axis is this many degrees from east, counter-clockwise seen from above
        (``--rotation-deg``): east = x cos A − y sin A, north = x sin A + y cos A.
    frame_column : str or None
        Time from this column's frame numbers (``--frame-column``), divided by ``frame_rate_hz``.
    frame_rate_hz : float or None
        The camera's frame rate (``--frame-rate``), Hz.
    """

    metres_per_pixel: float | None = None
    y_down: bool = False
    rotation_deg: float = 0.0
    frame_column: str | None = None
    frame_rate_hz: float | None = None

    @classmethod
    def from_flags(cls, metres_per_pixel=None, y_down=False, rotation_deg=None, frame_column=None,
                   frame_rate_hz=None, time_column="time_s", time_unit=None) -> "CameraOptions | None":
        """The options from the command line, checked; None when no camera flag is given.

        Raises
        ------
        SceneError
            A scale or frame rate that is not a positive finite number, a rotation that is not finite,
            ``--frame-column`` without ``--frame-rate`` or the reverse, ``--frame-column`` with
            ``--time-column`` or ``--time-unit`` (contradictory: one time source).
        """
        given = (metres_per_pixel is not None or y_down or rotation_deg is not None or frame_column is not None
                 or frame_rate_hz is not None)
        if not given:
            return None
        for flag, v in (("--metres-per-pixel", metres_per_pixel), ("--frame-rate", frame_rate_hz)):
            if v is not None and not (math.isfinite(v) and v > 0.0):
                raise SceneError(flag, v, "must be a positive finite number")
        if rotation_deg is not None and not math.isfinite(rotation_deg):
            raise SceneError("--rotation-deg", rotation_deg, "must be a finite number of degrees")
        if frame_column is not None and frame_rate_hz is None:
            raise SceneError("--frame-column", frame_column, "needs the camera's frame rate: pass --frame-rate HZ "
                                                             "(e.g. 29.97)")
        if frame_rate_hz is not None and frame_column is None:
            raise SceneError("--frame-rate", frame_rate_hz, "needs the column of frame numbers: pass "
                                                            "--frame-column NAME")
        if frame_column is not None and time_column != "time_s":
            raise SceneError("--frame-column", frame_column, f"and --time-column {time_column} both give the time: "
                                                             "pass one of them")
        if frame_column is not None and time_unit is not None:
            raise SceneError("--time-unit", time_unit, "does not apply to frame numbers (--frame-column): the "
                                                       "frame rate gives the time; leave --time-unit out")
        return cls(metres_per_pixel, bool(y_down), float(rotation_deg or 0.0), frame_column, frame_rate_hz)

    def positions_given(self) -> bool:
        """True when a flag transforms positions (scale, y down or rotation)."""
        return self.metres_per_pixel is not None or self.y_down or self.rotation_deg != 0.0

    def flag(self) -> tuple:
        """(the first position flag given, its value) for messages."""
        if self.metres_per_pixel is not None:
            return "--metres-per-pixel", self.metres_per_pixel
        return ("--y-down", True) if self.y_down else ("--rotation-deg", self.rotation_deg)

    def apply(self, cols, notes, path, field) -> dict:
        """The columns with the frame numbers as seconds and every ``<name>.x_east``/``y_north`` pair in
        metres, east and north; what was done is appended to ``notes``. Raises SceneError when a
        position flag finds no position pair, or one of a pair alone."""
        cols = dict(cols)
        if self.frame_column is not None:
            frames = np.asarray(cols["time_s"], dtype=float)
            cols["time_s"] = frames / self.frame_rate_hz
            notes.append(f"time from the frame numbers of {self.frame_column} at {self.frame_rate_hz:g} Hz")
        if not self.positions_given():
            return cols
        names = sorted({c.rsplit(".", 1)[0] for c in cols if c.rsplit(".", 1)[-1] in POSITION_CHANNELS and "." in c})
        if not names:
            raise SceneError(*self.flag(), f"applies to a track's positions <instrument>.x_east and .y_north; {path} "
                                           "has none (name the track's columns: --column pendulum.x_east=X "
                                           "--column pendulum.y_north=Y)")
        a = math.radians(self.rotation_deg)
        for name in names:
            xk, yk = f"{name}.x_east", f"{name}.y_north"
            if xk not in cols or yk not in cols:
                have, miss = (xk, yk) if xk in cols else (yk, xk)
                raise SceneError(*self.flag(), f"needs both positions of {name}: {path} has {have} but not {miss}")
            s = self.metres_per_pixel or 1.0
            x = np.asarray(cols[xk], dtype=float) * s
            y = np.asarray(cols[yk], dtype=float) * s * (-1.0 if self.y_down else 1.0)
            cols[xk] = x * math.cos(a) - y * math.sin(a) if a else x
            cols[yk] = x * math.sin(a) + y * math.cos(a) if a else y
        what = ([f"pixels at {self.metres_per_pixel:g} m each"] if self.metres_per_pixel is not None else []) \
            + (["image y axis down: y negated"] if self.y_down else []) \
            + ([f"camera x axis {self.rotation_deg:g} deg from east (counter-clockwise)"] if a else [])
        notes.append(f"camera track {', '.join(names)}: " + "; ".join(what))
        return cols


def datetime_seconds(texts, rows, column, path, field) -> tuple:
    """Seconds from the earliest of ISO 8601 date-time texts (``2023-06-22 07:23:55.963``,
    ``2023-06-22T07:23:55.963+02:00``, ``...Z``), exactly: whole microseconds between each and the
    earliest (integer arithmetic), divided once by 10⁶ (correctly rounded). Offsets are honoured
    (compared in UTC); texts with and without an offset together are refused.

    Returns
    -------
    (ndarray of float seconds, note)

    Raises
    ------
    SceneError
        A text that does not parse (naming its line), or offsets mixed with local times.
    """
    stamps = []
    for text, line in zip(texts, rows):
        try:
            stamps.append(dt.datetime.fromisoformat(text.replace("Z", "+00:00") if text.endswith("Z") else text))
        except ValueError:
            raise SceneError(field, path, f"line {line}, column {column}: {text!r} is neither a number nor an ISO "
                                          "date-time (e.g. 2023-06-22 07:23:55.963 or 2023-06-22T07:23:55.963+02:00)"
                             ) from None
    aware = {s.tzinfo is not None for s in stamps}
    if len(aware) > 1:
        raise SceneError(field, path, f"column {column} mixes date-times with and without a UTC offset: give "
                                      "every time with its offset (or none)")
    first = min(stamps)
    us = np.array([(s - first) // dt.timedelta(microseconds=1) for s in stamps], dtype=np.int64)
    return us / 1_000_000, f"{column}: date-time text, seconds from the earliest ({first.isoformat(sep=' ')})"
