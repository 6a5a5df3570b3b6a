"""Typed JSON records: frozen dataclasses that serialise to one JSON object each, and their JSON Schema.

The estimate (msg_docs/estimate.md) is a tree of :class:`Record` subclasses (:mod:`.estimate_types`,
:mod:`.entries`, :mod:`.north.block`). Each field is one key of the object, in declaration order
(the order of today's JSON, which the text output and the shipped files keep); a field that holds
:data:`ABSENT` is left out (a key the object has only sometimes); a field declared with
``inline=True`` holds a record (or a dict) whose keys are spliced into the parent at its place (the
combined latitude's variants at the estimate's top level; an observation's extra keys). Values are written as they are (no rounding, no
conversion: the floats of the JSON are the computation's, bit for bit).

:func:`schema_of` writes the JSON Schema (draft 2020-12) of a record class from the same
declarations: each field's Python type gives its JSON type (``float`` → number, ``int`` → integer,
``X | None`` → X or null, ``list[X]``, ``dict[str, X]``, a Record → ``$ref``), its ``doc`` the
description (with its unit), ``ABSENT`` defaults make a key optional, and an object whose keys are
closed has ``unevaluatedProperties: false``. An open object (a record's ``OPEN`` = True: an
observation's extra keys) admits others.
"""

import dataclasses
import types
import typing
from dataclasses import field

__all__ = ["ABSENT", "Json", "Record", "doc", "schema_of", "to_json"]

#: Any JSON value (a leaf whose structure the record does not fix: described by its ``schema``).
Json = typing.Any


class _Absent:
    """The marker of a key left out of the JSON (:data:`ABSENT`)."""

    _one = None

    def __new__(cls) -> "_Absent":
        if cls._one is None:
            cls._one = super().__new__(cls)
        return cls._one

    def __repr__(self) -> str:
        return "ABSENT"

    def __bool__(self) -> bool:
        return False


#: A field holding this is not written: the key is absent from the object.
ABSENT = _Absent()


def doc(description, default=dataclasses.MISSING, *, schema=None, inline=False, key=None) -> typing.Any:
    """A record field with its ``description`` (the schema's, with the unit), an optional ``default``
    (:data:`ABSENT`: the key may be absent), a ``schema`` fragment (or a function giving it, called when
    the schema is written) that replaces the one derived from the type, ``inline`` (splice a record's keys here) and ``key`` (the JSON key, when it is not the
    field's name)."""
    meta = {"doc": description, "schema": schema, "inline": inline, "key": key}
    return field(default=default, metadata=meta)


class Record:
    """Base of the typed JSON records (module docstring); subclasses are frozen dataclasses."""

    #: True when the object admits keys its fields do not name (an observation's extras).
    OPEN: typing.ClassVar[bool] = False
    #: The object's description in the schema (defaults to the class docstring's first paragraph).
    DOC: typing.ClassVar[str | None] = None

    def to_json(self) -> dict:
        """The JSON object (a dict of JSON values, keys in declaration order, ``ABSENT`` left out)."""
        return to_json(self)


def to_json(value, _memo=None) -> typing.Any:
    """``value`` with every :class:`Record` in it written as its JSON object (mappings and sequences
    walked; every other value kept as it is). A record met twice in one call (an instrument's ``north``
    block that is also the estimate's) is written once: both places hold the same dict, as before the
    records."""
    memo = {} if _memo is None else _memo
    if isinstance(value, Record):
        if id(value) in memo:
            return memo[id(value)]
        out = memo[id(value)] = {}
        for f in dataclasses.fields(value):
            v = getattr(value, f.name)
            if v is ABSENT:
                continue
            if f.metadata.get("inline"):
                out.update(to_json(v, memo))
            else:
                out[f.metadata.get("key") or f.name] = to_json(v, memo)
        return out
    if isinstance(value, dict):
        return {k: to_json(v, memo) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(v, memo) for v in value]
    return value


# ----------------------------------------------------------------------------- schema
_SCALARS = {float: {"type": "number"}, int: {"type": "integer"}, bool: {"type": "boolean"},
            str: {"type": "string"}, type(None): {"type": "null"}}


def _type_schema(tp, defs) -> dict:
    """The JSON Schema of the Python type ``tp`` (module docstring); records go into ``defs``."""
    origin = typing.get_origin(tp)
    if tp is typing.Any:
        return {}
    if tp in _SCALARS:
        return dict(_SCALARS[tp])
    if isinstance(tp, type) and issubclass(tp, Record):
        _record_def(tp, defs)
        return {"$ref": f"#/$defs/{tp.__name__}"}
    if origin in (typing.Union, types.UnionType):
        parts = [_type_schema(a, defs) for a in typing.get_args(tp)]
        simple = [p["type"] for p in parts if set(p) == {"type"} and isinstance(p["type"], str)]
        if len(simple) == len(parts):
            return {"type": simple}
        return {"anyOf": parts}
    if origin is typing.Literal:
        return {"enum": list(typing.get_args(tp))}
    if origin in (list, tuple):
        args = typing.get_args(tp)
        if origin is tuple and args and args[-1] is not Ellipsis:
            return {"type": "array", "prefixItems": [_type_schema(a, defs) for a in args],
                    "minItems": len(args), "maxItems": len(args)}
        return {"type": "array", "items": _type_schema(args[0], defs) if args else {}}
    if origin is dict:
        args = typing.get_args(tp)
        return {"type": "object", "additionalProperties": _type_schema(args[1], defs) if args else {}}
    raise TypeError(f"no JSON Schema for the type {tp!r}")


def _fields_schema(cls, defs) -> tuple:
    """(properties, required, inline variants) of a record class's own fields."""
    hints = typing.get_type_hints(cls)
    props, required, inline = {}, [], []
    for f in dataclasses.fields(cls):
        if f.metadata.get("inline"):
            if typing.get_origin(hints[f.name]) is dict:      # open keys spliced in: the class is OPEN
                continue
            variants = typing.get_args(hints[f.name]) or (hints[f.name],)
            inline.append([_inline_schema(v, defs) for v in variants])
            continue
        name = f.metadata.get("key") or f.name
        given = f.metadata.get("schema")
        s = dict((given() if callable(given) else given) or _type_schema(hints[f.name], defs))
        s["description"] = f.metadata.get("doc") or ""
        props[name] = s
        if f.default is not ABSENT:
            required.append(name)
    return props, required, inline


def _inline_schema(cls, defs) -> dict:
    props, required, inline = _fields_schema(cls, defs)
    out = {"title": cls.__name__, "description": _class_doc(cls), "properties": props, "required": required}
    for group in inline:
        out.setdefault("allOf", []).append({"anyOf": group})
    return out


def _class_doc(cls) -> str:
    text = cls.DOC or (cls.__doc__ or "").strip().split("\n\n")[0]
    return " ".join(text.split())


def _record_def(cls, defs) -> None:
    """Put the schema of the record class ``cls`` into ``defs`` (once)."""
    if cls.__name__ in defs:
        return
    defs[cls.__name__] = {}                       # recursion guard
    props, required, inline = _fields_schema(cls, defs)
    out = {"type": "object", "description": _class_doc(cls), "properties": props, "required": required}
    for group in inline:
        out.setdefault("allOf", []).append({"anyOf": group})
    if not cls.OPEN:
        out["unevaluatedProperties"] = False
    defs[cls.__name__] = out


def schema_of(roots, schema_id, title, description) -> dict:
    """The JSON Schema (draft 2020-12) document of the record classes ``roots`` (an object valid against
    any one of them): ``$id`` ``schema_id``, ``title``, ``description``, every record under ``$defs``."""
    defs = {}
    for cls in roots:
        _record_def(cls, defs)
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": schema_id, "title": title,
            "description": description, "anyOf": [{"$ref": f"#/$defs/{cls.__name__}"} for cls in roots],
            "$defs": dict(sorted(defs.items()))}
