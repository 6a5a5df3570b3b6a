"""Declarative parameter specifications and their validation.

Every instrument, effect and scene section declares its parameters as :class:`Param` objects
(name with its unit, type, default, valid range, documentation). One validator turns a raw
mapping (from YAML, the CLI's ``--set`` or ROS parameters) into checked values, raising
:class:`SceneError` that names the field, the value and the valid range.
"""

import difflib
import math
from dataclasses import dataclass, make_dataclass

from gyro_instrument.core.errors import SceneError

REQUIRED = object()


@dataclass(frozen=True)
class Param:
    """One parameter: ``name`` carries its unit (``length_m``), ``kind`` is one of
    ``float``, ``int``, ``bool``, ``str``, ``vec3`` (and ``pair``, :class:`PairParam`);
    ``low``/``high`` bound numbers (``open_low`` and ``open_high`` make a bound strict);
    ``choices`` restricts strings."""

    name: str
    kind: str = "float"
    default: object = REQUIRED
    low: float = -math.inf
    high: float = math.inf
    open_low: bool = False
    open_high: bool = False
    choices: tuple = ()
    doc: str = ""

    def describe_range(self) -> str:
        """Human-readable valid range, as quoted in error messages and docs."""
        if self.kind == "bool":
            return "must be true or false"
        if self.kind == "str":
            return f"must be one of {', '.join(self.choices)}" if self.choices else "must be a string"
        lo = "(" if self.open_low else "["
        hi = ")" if self.open_high else "]"
        what = "an integer" if self.kind == "int" else "a finite number"
        if self.kind == "vec3":
            return "must be a list of 3 finite numbers, not all zero"
        if math.isinf(self.low) and math.isinf(self.high):
            return f"must be {what}"
        return f"must be {what} in {lo}{_fmt(self.low)}, {_fmt(self.high)}{hi}"

    def check(self, field, value) -> object:
        """Return the validated, converted value or raise :class:`SceneError`."""
        if self.kind == "bool":
            if isinstance(value, bool):
                return value
            raise SceneError(field, value, self.describe_range())
        if self.kind == "str":
            if not isinstance(value, str) or (self.choices and value not in self.choices):
                raise SceneError(field, value, self.describe_range())
            return value
        if self.kind == "vec3":
            if (not isinstance(value, (list, tuple)) or len(value) != 3
                    or not all(_is_number(v) and math.isfinite(float(v)) for v in value)
                    or all(float(v) == 0.0 for v in value)):
                raise SceneError(field, value, self.describe_range())
            return tuple(float(v) for v in value)
        if not _is_number(value):
            raise SceneError(field, value, self.describe_range())
        if self.kind == "int":
            if isinstance(value, float) and not value.is_integer():
                raise SceneError(field, value, self.describe_range())
            value = int(value)
        else:
            value = float(value)
        if not math.isfinite(value):
            raise SceneError(field, value, self.describe_range())
        too_low = value < self.low or (self.open_low and value == self.low)
        too_high = value > self.high or (self.open_high and value == self.high)
        if too_low or too_high:
            raise SceneError(field, value, self.describe_range())
        return value


class PairParam(Param):
    """A parameter holding two finite positive numbers (``kind = "pair"``), e.g. ρ, ρ'."""

    def describe_range(self) -> str:
        return "must be a list of 2 finite numbers > 0"

    def check(self, field, value) -> tuple:
        if (not isinstance(value, (list, tuple)) or len(value) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
                or not all(math.isfinite(float(v)) and float(v) > 0.0 for v in value)):
            raise SceneError(field, value, self.describe_range())
        return tuple(float(v) for v in value)


def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _fmt(x):
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:g}"


#: Other spellings of a rate: a parameter named ``<stem>_rad_s`` also accepts ``<stem>_turn_s``
#: (turns per second), ``<stem>_rpm`` and ``<stem>_deg_h`` (degrees per hour); the value is
#: converted and stored under the canonical ``_rad_s`` name. (suffix, factor to rad/s).
RATE_ALIASES = (("_turn_s", 2.0 * math.pi), ("_rpm", 2.0 * math.pi / 60.0), ("_deg_h", math.pi / 180.0 / 3600.0))


def other_rate_spellings(key) -> list:
    """The other spellings of the rate ``key`` names (``spin_rate_turn_s`` -> ``spin_rate_rad_s``,
    ``spin_rate_rpm``, ``spin_rate_deg_h``; :data:`RATE_ALIASES`); [] when ``key`` is not a rate."""
    suffixes = ("_rad_s",) + tuple(s for s, _ in RATE_ALIASES)
    stem = next((key[:-len(s)] for s in suffixes if key.endswith(s)), None)
    return [stem + s for s in suffixes if stem + s != key] if stem else []


def unit_aliases(param, known=()) -> list:
    """The accepted other spellings of ``param`` (a :class:`Param`): ``["spin_rate_turn_s", ...]``
    for a float named ``*_rad_s``, leaving out names in ``known`` (parameters of their own)."""
    if param.kind != "float" or not param.name.endswith("_rad_s"):
        return []
    stem = param.name[:-len("_rad_s")]
    return [stem + suffix for suffix, _ in RATE_ALIASES if stem + suffix not in known]


def alias_note(param, params=()) -> str:
    """Doc text for a rate's other spellings: ``also as `spin_rate_turn_s`, ... (converted)``, or ''."""
    names = unit_aliases(param, {p.name for p in params})
    if not names:
        return ""
    return "also as " + ", ".join(f"`{n}`" for n in names) + " (turn/s, rpm, deg/h; converted, stored as rad/s)"


def _canonical_rates(prefix, by_name, raw):
    """``raw`` with rate aliases (:data:`RATE_ALIASES`) converted to their ``_rad_s`` parameter.

    Raises
    ------
    SceneError
        Two spellings of one parameter (naming both), or an alias whose converted value is out of
        the parameter's range (quoting the conversion).
    """
    out, given = {}, {}
    for key, value in raw.items():
        canon, factor = key, None
        if key not in by_name and isinstance(key, str):
            for suffix, f in RATE_ALIASES:
                stem = key[:-len(suffix)] if key.endswith(suffix) else None
                p = by_name.get(f"{stem}_rad_s") if stem else None
                if p is not None and key in unit_aliases(p, by_name):
                    canon, factor = p.name, f
                    break
        if canon in given:
            field = f"{prefix}.{key}" if prefix else str(key)
            raise SceneError(field, value, f"gives {canon} a second time (also given as {given[canon]}); "
                                           f"give one of {canon}, {', '.join(unit_aliases(by_name[canon], by_name))}")
        given[canon] = key
        if factor is not None and value is not None:
            field = f"{prefix}.{key}" if prefix else str(key)
            p = by_name[canon]
            if not _is_number(value) or not math.isfinite(float(value)):
                raise SceneError(field, value, f"must be a finite number (converted to {canon}, which "
                                               f"{p.describe_range()})")
            converted = float(value) * factor
            try:
                p.check(field, converted)
            except SceneError:
                raise SceneError(field, value, f"is {converted:g} rad/s as {canon}, which {p.describe_range()}") from None
            value = converted
        out[canon] = value
    return out


def validate_params(prefix, params, raw) -> dict:
    """Validate ``raw`` (a mapping) against ``params`` (a sequence of :class:`Param`).

    Unknown keys are refused with a close-match suggestion; missing required keys are
    refused; defaults fill the rest. A rate ``<stem>_rad_s`` may be given as ``<stem>_turn_s``,
    ``<stem>_rpm`` or ``<stem>_deg_h`` (:data:`RATE_ALIASES`): converted, stored under its ``_rad_s``
    name; two spellings of one parameter are refused. A key given as ``None`` (YAML ``null``, ``--set key=null``)
    means "use the default": it takes the default when there is one and is refused, naming the
    field and the valid range, when the key is required.

    Returns
    -------
    dict
        name -> checked value.
    """
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise SceneError(prefix, raw, "must be a mapping of key: value")
    by_name = {p.name: p for p in params}
    raw = _canonical_rates(prefix, by_name, raw)
    for key in raw:
        if key not in by_name:
            raise SceneError(f"{prefix}.{key}" if prefix else str(key), raw[key],
                             unknown_key_hint(key, by_name))
    out = {}
    for p in params:
        field = f"{prefix}.{p.name}" if prefix else p.name
        if raw.get(p.name) is not None:
            out[p.name] = p.check(field, raw[p.name])
        elif p.default is REQUIRED:
            raise SceneError(field, None, f"is required (it has no default); {p.describe_range()}")
        else:
            out[p.name] = p.default
    return out


#: Typed fields by ``Param.kind`` (annotations of the generated parameter dataclasses).
_KIND_TYPES = {"float": float, "int": int, "bool": bool, "str": str, "vec3": tuple, "pair": tuple}

#: Angle suffixes a parameter is given in at the edge, and the SI suffix of its radian view.
_RADIAN_VIEWS = (("_deg_s", "_rad_s"), ("_deg", "_rad"))


def _radian_view(name):
    def view(self):
        return math.radians(getattr(self, name))
    view.__doc__ = f"``{name}`` in radians (``math.radians``)."
    return property(view)


def params_dataclass(owner) -> type:
    """The frozen dataclass of ``owner``'s validated parameters, generated once per class.

    ``owner`` is a class with ``PARAMS`` (a tuple of :class:`Param`: an instrument or an effect).
    The dataclass ``<Owner>Params`` has one typed field per parameter, in ``PARAMS`` order, and for
    each float given in degrees (``*_deg``, ``*_deg_s``) a read-only radian view (``*_rad``,
    ``*_rad_s``; ``math.radians`` of the value) unless a parameter already has that name. Build it
    from :func:`validate_params`'s result: ``params_dataclass(cls)(**validated)``; read
    ``p.length_m``, ``p.initial_deflection_rad``.

    Returns
    -------
    type
        The dataclass (cached on ``owner``; regenerated when ``owner.PARAMS`` is another tuple).
    """
    cached = owner.__dict__.get("_params_dataclass")
    if cached is not None and cached[0] is owner.PARAMS:
        return cached[1]
    names = {p.name for p in owner.PARAMS}
    views = {}
    for p in owner.PARAMS:
        for deg, rad in _RADIAN_VIEWS:
            if p.kind == "float" and p.name.endswith(deg):
                view = p.name[:-len(deg)] + rad
                if view not in names:
                    views[view] = _radian_view(p.name)
                break
    fields = [(p.name, _KIND_TYPES.get(p.kind, object)) for p in owner.PARAMS]
    cls = make_dataclass(f"{owner.__name__}Params", fields, frozen=True, namespace=views)
    cls.__doc__ = f"Validated parameters of {owner.__name__} (frozen; generated from its PARAMS)."
    setattr(owner, "_params_dataclass", (owner.PARAMS, cls))
    return cls


def unknown_key_hint(key, known, what="key") -> str:
    """Message for an unknown name, with the closest known one when one is near.

    ``what`` names the kind of name (``key``, ``instrument``, ``effect``, ``instrument type``):
    ``unknown instrument (did you mean 'pendulum'?); valid keys: gyro_horizontal, pendulum``.
    """
    names = [str(k) for k in known]
    close = difflib.get_close_matches(str(key), names, n=1)
    hint = f"unknown {what} (did you mean '{close[0]}'?)" if close else f"unknown {what}"
    return f"{hint}; valid keys: {', '.join(sorted(names)) or 'none'}"
