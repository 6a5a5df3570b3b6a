"""ROS 2 message definitions as rosbag2 stores them, read from the installed share directories.

rosbag2 (jazzy, ``local_message_definition_source.cpp``) writes one schema per type: the root
``.msg`` text, then — depth-first through each type's dependencies in sorted order, each once —
a newline, a line of 80 ``=``, a line ``MSG: pkg/Type`` (the name as the field writes it) and that
type's text. (An early working note of this project said breadth-first with ``pkg/msg/Type``; the source
says otherwise, and ``tests/test_recording.py`` holds the order.) The type hash (``RIHS01_…``) comes from the
``.json`` type description installed beside the ``.msg``. No rclpy needed.
"""

import json
import os
import re
import sys
from functools import lru_cache

SEPARATOR = "=" * 80


def share_dirs() -> list:
    """Prefixes to search: ``AMENT_PREFIX_PATH`` entries, then this interpreter's prefix."""
    dirs = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    for p in (sys.prefix, os.environ.get("VIRTUAL_ENV", "")):
        if p and p not in dirs:
            dirs.append(p)
    return [os.path.join(p, "share") for p in dirs]


def _find(pkg, name, ext):
    for d in share_dirs():
        path = os.path.join(d, pkg, "msg", f"{name}.{ext}")
        if os.path.exists(path):
            return path
    raise FileNotFoundError(f"no {pkg}/msg/{name}.{ext} under {', '.join(share_dirs())} "
                            f"(set AMENT_PREFIX_PATH to the prefix holding the ROS message packages)")


#: types written to bags that the wheels do not install (tf2_msgs, issue 37): their ``.msg`` text
#: (tf2_msgs jazzy ``msg/TFMessage.msg``) and, for the type hash, their one field as a type
#: description (``type_description_interfaces/FieldType``: 145 = a nested type's unbounded sequence)
EMBEDDED = {
    "tf2_msgs/msg/TFMessage": ("geometry_msgs/TransformStamped[] transforms\n",
                               [("transforms", 145, "geometry_msgs/msg/TransformStamped")]),
}


@lru_cache(maxsize=None)
def msg_text(type_name) -> str:
    """The ``.msg`` text of ``pkg/msg/Type`` (installed, or :data:`EMBEDDED`)."""
    pkg, _, name = type_name.split("/")
    try:
        path = _find(pkg, name, "msg")
    except FileNotFoundError:
        if type_name in EMBEDDED:
            return EMBEDDED[type_name][0]
        raise
    with open(path, encoding="utf-8") as fh:
        return fh.read()


# Field types as rosbag2 matches them (local_message_definition_source.cpp, MSG_FIELD_TYPE_REGEX).
_FIELD_TYPE = re.compile(r"(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+")
_RB_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32",
                  "uint32", "int64", "uint64", "string"}


def _rb_dependencies(text, package):
    """rosbag2's dependency set of a .msg text: names as written (``pkg/Type``), relative ones
    prefixed with the package; a sorted set (``std::set``)."""
    deps = set()
    for m in _FIELD_TYPE.finditer(text):
        t = m.group(1)
        if t in _RB_PRIMITIVES:
            continue
        deps.add(t if "/" in t else f"{package}/{t}")
    return sorted(deps)


def _msg_text_any(name):
    """Text for ``pkg/Type`` or ``pkg/msg/Type``."""
    parts = name.split("/")
    return msg_text(f"{parts[0]}/msg/{parts[-1]}")


@lru_cache(maxsize=None)
def concatenated_definition(type_name) -> str:
    """rosbag2's schema text for ``pkg/msg/Type``, exactly as ``get_full_text`` builds it: the root
    text, then depth-first over each type's dependencies in sorted order, each once:
    ``"\\n" + "=" * 80 + "\\nMSG: " + name + "\\n" + text``."""
    seen = set()

    def rec(name, depth):
        if depth <= 0:
            raise RuntimeError(f"max recursion depth resolving {type_name}")
        text = _msg_text_any(name)
        out = text
        for dep in _rb_dependencies(text, name.split("/")[0]):
            if dep not in seen:
                seen.add(dep)
                out += "\n" + SEPARATOR + "\nMSG: " + dep + "\n" + rec(dep, depth - 1)
        return out

    return rec(type_name, 50)


def rihs01(description) -> str:
    """The RIHS01 hash of a type description (REP-2011, as ``rosidl_generator_type_description``
    computes it): SHA-256 of its JSON (``type_description`` and ``referenced_type_descriptions``,
    default values left out, separators ``', '`` and ``': '``, keys in order)."""
    import copy
    import hashlib
    h = copy.deepcopy(description)
    for td in [h["type_description"]] + h["referenced_type_descriptions"]:
        for f in td["fields"]:
            f.pop("default_value", None)
    text = json.dumps(h, ensure_ascii=True, allow_nan=False, indent=None, separators=(", ", ": "), sort_keys=False)
    return "RIHS01_" + hashlib.sha256(text.encode("utf-8")).hexdigest()


def _embedded_description(type_name) -> dict:
    """The type description of an :data:`EMBEDDED` type from its fields and the installed ``.json``
    of the nested types (their own description and everything they reference, sorted by name)."""
    fields, refs = [], {}
    for name, type_id, nested in EMBEDDED[type_name][1]:
        fields.append({"name": name, "type": {"type_id": type_id, "capacity": 0, "string_capacity": 0,
                                              "nested_type_name": nested}, "default_value": ""})
        pkg, _, n = nested.split("/")
        with open(_find(pkg, n, "json"), encoding="utf-8") as fh:
            d = json.load(fh)["type_description_msg"]
        for td in [d["type_description"]] + d["referenced_type_descriptions"]:
            refs[td["type_name"]] = td
    return {"type_description": {"type_name": type_name, "fields": fields},
            "referenced_type_descriptions": [refs[k] for k in sorted(refs)]}


@lru_cache(maxsize=None)
def type_hash(type_name) -> str:
    """RIHS01 type hash from the installed ``.json`` type description (for an :data:`EMBEDDED`
    type, computed from its description, :func:`rihs01`)."""
    pkg, _, name = type_name.split("/")
    if type_name in EMBEDDED:
        try:
            _find(pkg, name, "json")
        except FileNotFoundError:
            return rihs01(_embedded_description(type_name))
    with open(_find(pkg, name, "json"), encoding="utf-8") as fh:
        data = json.load(fh)
    for h in data.get("type_hashes", []):
        if h.get("type_name") == type_name:
            return h["hash_string"]
    raise KeyError(f"no type hash for {type_name}")
