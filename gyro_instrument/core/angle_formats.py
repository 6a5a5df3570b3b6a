"""Angles as surveyors write them: parse and format at the edges (issue 33, item 5).

Inside, angles are radians; these helpers turn the written forms of a field book into radians and
an answer back into the forms a surveyor reads:

==============  =====================================================  ===========================
unit            written                                                 e.g. 179°01'56"
==============  =====================================================  ===========================
``dms``         degrees, minutes, seconds as printed: ``179°01'56"``,   ``179°01′56.5″``,
                ``179°01′56″``, ``179.01.56`` (two dots, two-digit      ``179 01 56``, ``179-01-56``,
                minutes and seconds; a third dot starts the decimals    ``179:01:56``, ``179 01.5``
                of the seconds), ``179 01 56``, ``179-01-56``,
                ``179:01:56``; two fields are degrees and minutes
``ddmmss``      the DD.MMSS notation of calculators: ``179.0156``;      ``179.01565`` = 179°01'56.5"
                the digits after the point are MM SS and the
                decimals of the seconds (``179.1`` = 179°10')
``div``         scale divisions, times a stated value (``--scale-division``, e.g. ``10arcmin``)
``rad`` ...     a number in rad, mrad, deg, gon (400 to the turn), mgon, arcmin, arcsec
==============  =====================================================  ===========================

A leading ``-`` or ``+`` signs the whole angle. Minutes and seconds must be below 60. A decimal
comma is read as a point when the caller says so (a ``;``-separated table).

Formatting (:func:`format_angle`) rounds first and wraps after rounding, so a circle reading a
hair below 360° prints ``0°00′00.0″`` and ``0.000000°``, never ``360°00′00.0″`` or ``360.000000°``.
"""

import math
import re

#: angle units written as one number: radians per unit (gon: 400 to the turn; mgon 1e-3 gon)
NUMBER_UNITS = {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0, "gon": math.pi / 200.0,
                "mgon": math.pi / 200000.0, "arcmin": math.pi / 10800.0, "arcsec": math.pi / 648000.0}
#: angle units written as text (degrees-minutes-seconds, DD.MMSS) or in scale divisions of a stated value
TEXT_UNITS = ("dms", "ddmmss", "div")
#: every angle unit a field book or ``--angle-unit`` accepts
ANGLE_UNITS = tuple(NUMBER_UNITS) + TEXT_UNITS
#: the forms :func:`format_angle` writes (``--angle-format``)
FORMATS = ("deg", "dms", "gon")

_SYMBOLS = re.compile(r"""^(\d+)\s*[°d]\s*(?:(\d+(?:\.\d*)?)\s*(?:'|′|m)\s*)?"""
                      r"""(?:(\d+(?:\.\d*)?)\s*(?:"|″|''|′′|s)\s*)?$""")
_NUMBER = re.compile(r"^\d+(?:\.\d*)?$")


def _sign(text):
    text = text.strip()
    if text[:1] in "+-−":
        return (-1.0 if text[0] in "-−" else 1.0), text[1:].strip()
    return 1.0, text


def _compose(deg, minutes, seconds, text):
    """Degrees from the three fields (strings or None); ValueError when minutes or seconds ≥ 60, or
    minutes carry decimals before a seconds field."""
    m = float(minutes) if minutes else 0.0
    s = float(seconds) if seconds else 0.0
    if seconds and minutes and "." in minutes:
        raise ValueError(f"{text!r}: minutes with decimals before a seconds field")
    if m >= 60.0 or s >= 60.0:
        raise ValueError(f"{text!r}: minutes and seconds must be below 60")
    return int(deg) + m / 60.0 + s / 3600.0


def parse_dms(text, decimal_comma=False) -> float:
    """Degrees from a degrees-minutes-seconds string as printed (module docstring).

    Parameters
    ----------
    text : str
        ``179°01'56"``, ``179.01.56``, ``179 01 56``, ``179-01-56``, ``179:01:56`` (signed or not).
    decimal_comma : bool
        Read ``,`` as the decimal point (a ``;``-separated table).

    Returns
    -------
    float
        Degrees.

    Raises
    ------
    ValueError
        Not one of the forms, or minutes/seconds ≥ 60; the message quotes the text.
    """
    sign, body = _sign(str(text))
    if decimal_comma:
        body = body.replace(",", ".")
    m = _SYMBOLS.match(body)
    if m:
        return sign * _compose(m.group(1), m.group(2), m.group(3), text)
    dotted = body.split(".")
    if len(dotted) in (3, 4) and all(p.isdigit() for p in dotted) and len(dotted[1]) == 2 == len(dotted[2]):
        sec = dotted[2] + ("." + dotted[3] if len(dotted) == 4 else "")
        return sign * _compose(dotted[0], dotted[1], sec, text)
    for sep in (" ", "-", ":"):
        parts = [p for p in body.split(sep)] if sep != " " else body.split()
        if 2 <= len(parts) <= 3 and parts[0].isdigit() and all(_NUMBER.match(p) for p in parts[1:]):
            if any("." in p for p in parts[1:-1]):
                break
            return sign * _compose(parts[0], parts[1], parts[2] if len(parts) == 3 else None, text)
    if _NUMBER.match(body):
        if "." in body:
            raise ValueError(f"{text!r} is a decimal number, not degrees-minutes-seconds: is it DD.MMSS "
                             f"(header reading_ddmmss) or decimal degrees (reading_deg)?")
        return sign * float(body)
    raise ValueError(f"{text!r} is not degrees-minutes-seconds: write 179°01'56\", 179.01.56, 179 01 56 or "
                     f"179-01-56")


def parse_ddmmss(text, decimal_comma=False) -> float:
    """Degrees from the DD.MMSS notation: ``179.0156`` = 179°01'56", ``179.01565`` = 179°01'56.5".

    The digits after the point are read as text (never through a float, which would turn
    ``179.0156`` into 179.01559999…): two of minutes, two of seconds, the rest the seconds'
    decimals; fewer digits are padded with zeros on the right (``179.1`` = 179°10').

    Raises
    ------
    ValueError
        Not a number, or minutes/seconds ≥ 60; the message quotes the text.
    """
    sign, body = _sign(str(text))
    if decimal_comma:
        body = body.replace(",", ".")
    m = re.match(r"^(\d+)(?:\.(\d*))?$", body)
    if not m:
        raise ValueError(f"{text!r} is not a DD.MMSS number (e.g. 179.0156 for 179°01'56\")")
    frac = (m.group(2) or "").ljust(4, "0")
    return sign * _compose(m.group(1), frac[:2], frac[2:4] + ("." + frac[4:] if len(frac) > 4 else ""), text)


def parse_scale_division(text) -> float:
    """The stated value of one scale division in rad, from ``<number><unit>`` (``10arcmin``,
    ``0.1852 gon``, ``2.9mrad``; units of :data:`NUMBER_UNITS`).

    Raises
    ------
    ValueError
        Not a number and a unit, or not > 0.
    """
    m = re.match(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?\d+)?)\s*([a-z]+)\s*$", str(text))
    if not m or m.group(2) not in NUMBER_UNITS or not float(m.group(1)) > 0:
        raise ValueError(f"must be a value > 0 with its unit, e.g. 10arcmin or 0.1852gon (units "
                         f"{', '.join(NUMBER_UNITS)})")
    return float(m.group(1)) * NUMBER_UNITS[m.group(2)]


def parse_angle(text, unit, division_rad=None, decimal_comma=False) -> float:
    """One written angle in rad (``unit`` of :data:`ANGLE_UNITS`).

    Raises
    ------
    ValueError
        Unreadable text or a non-finite number (the message quotes the text); a ``div`` reading
        without ``division_rad``.
    """
    text = str(text).strip()
    if unit == "dms":
        return math.radians(parse_dms(text, decimal_comma))
    if unit == "ddmmss":
        return math.radians(parse_ddmmss(text, decimal_comma))
    scale = division_rad if unit == "div" else NUMBER_UNITS[unit]
    if scale is None:
        raise ValueError("scale divisions need their stated value (--scale-division, e.g. 10arcmin)")
    try:
        v = float(text)
    except ValueError:
        if not (decimal_comma and text.count(",") == 1 and "." not in text):
            raise ValueError(f"{text!r} is not a number") from None
        v = float(text.replace(",", "."))
    if not math.isfinite(v):
        raise ValueError(f"{text!r} must be a finite number")
    return v * scale


def parse_clock(text) -> float:
    """Seconds from ``mm:ss(.s)`` or ``hh:mm:ss(.s)`` (minutes and seconds below 60).

    Raises
    ------
    ValueError
        Not of those forms.
    """
    parts = str(text).strip().split(":")
    if len(parts) not in (2, 3) or not all(_NUMBER.match(p) for p in parts) or any("." in p for p in parts[:-1]):
        raise ValueError(f"{text!r} is not a clock time mm:ss or hh:mm:ss")
    vals = [float(p) for p in parts]
    if any(v >= 60.0 for v in vals[1:]):
        raise ValueError(f"{text!r}: minutes and seconds must be below 60")
    return sum(v * 60.0 ** k for k, v in enumerate(reversed(vals)))


def _rounded(value, unit_per_turn, decimals, wrap):
    """(sign, integer count of 10^-decimals units) after rounding, wrapped to one turn if ``wrap``."""
    scale = 10 ** decimals
    n = round(value * scale)
    if wrap:
        n %= unit_per_turn * scale
    return (-1 if n < 0 else 1), abs(int(n))


def format_dms(deg, decimals=1, wrap=True) -> str:
    """``d°mm′ss.s″`` of an angle in degrees, rounded to ``decimals`` of a second, then wrapped to
    [0°, 360°) when ``wrap`` (so 359.99999999° prints 0°00′00.0″); signed when not wrapped."""
    sign, n = _rounded(float(deg) * 3600.0, 360 * 3600, decimals, wrap)
    scale = 10 ** decimals
    whole, frac = divmod(n, scale)
    d, rest = divmod(whole, 3600)
    m, s = divmod(rest, 60)
    sec = f"{s:02d}" + (f".{frac:0{decimals}d}" if decimals > 0 else "")
    return f"{'-' if sign < 0 else ''}{d}°{m:02d}′{sec}″"


def _format_decimal(value, per_turn, decimals, wrap, suffix):
    sign, n = _rounded(value, per_turn, decimals, wrap)
    whole, frac = divmod(n, 10 ** decimals)
    return f"{'-' if sign < 0 else ''}{whole}" + (f".{frac:0{decimals}d}" if decimals > 0 else "") + suffix


def format_angle(deg, fmt="deg", wrap=True) -> str:
    """An angle in degrees written in ``fmt`` (:data:`FORMATS`): ``deg`` to 1e-6° (``179.032222°``),
    ``dms`` to 0.1″ (``179°01′56.0″``), ``gon`` to 1e-5 gon (``198.92963 gon``, ≈ 0.03″); rounded,
    then wrapped to one turn when ``wrap``.

    Raises
    ------
    ValueError
        An unknown ``fmt``.
    """
    if fmt == "dms":
        return format_dms(deg, 1, wrap)
    if fmt == "gon":
        return _format_decimal(float(deg) * 400.0 / 360.0, 400, 5, wrap, " gon")
    if fmt == "deg":
        return _format_decimal(float(deg), 360, 6, wrap, "°")
    raise ValueError(f"angle format {fmt!r}: one of {', '.join(FORMATS)}")


def format_arcsec(arcsec, fmt="deg") -> str:
    """A small angle (a σ, a bias) given in arcseconds, written for ``fmt``: ``1.23″`` for deg and
    dms, ``0.38 mgon`` for gon (3 significant digits)."""
    if arcsec is None:
        return "null"
    if fmt == "gon":
        return f"{float(arcsec) / 3.24:.3g} mgon"
    return f"{float(arcsec):.3g}\""
