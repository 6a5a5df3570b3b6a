"""Write the estimate's JSON Schema (gyro_instrument/estimators/estimate.schema.json, shipped in the
package) and msg_docs/estimate.md from the typed records (gyro_instrument/estimators/estimate_types.py,
entries.py, north/block.py); kept true by tests/test_estimate_schema.py: run
`python tools/gen_estimate_docs.py` after changing a record."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gyro_instrument.estimators.estimate_types import SCHEMA_FILE, estimate_schema  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCHEMA_OUT = ROOT / "gyro_instrument" / "estimators" / SCHEMA_FILE
DOCS_OUT = ROOT / "msg_docs" / "estimate.md"

HEAD = """# `gyro-instrument estimate SCENE --json`

Generated from the typed records of the estimate (`gyro_instrument/estimators/estimate_types.py`,
`entries.py`, `north/block.py`) through its JSON Schema (draft 2020-12), shipped in the package as
`gyro_instrument/estimators/estimate.schema.json`, by `tools/gen_estimate_docs.py`. Every
`estimate --json` (a scene, `--data`, `replay`), the estimator node's estimate and the
`.estimate.json` that `run --bag` writes validate against it (tests/test_estimate_schema.py).

"""


def render_schema() -> str:
    """The schema file's text (sorted nowhere: the keys keep the records' order)."""
    return json.dumps(estimate_schema(), indent=2, ensure_ascii=False) + "\n"


def _type(s, defs) -> str:
    """A property's type in words, with links to the objects it names."""
    if "$ref" in s:
        name = s["$ref"].rsplit("/", 1)[1]
        return f"[{name}](#{name.lower()})"
    if "anyOf" in s:
        return " or ".join(_type(p, defs) for p in s["anyOf"])
    if "enum" in s:
        return "one of " + ", ".join("`null`" if v is None else f"`{v}`" for v in s["enum"])
    if "not" in s:
        return "string"
    t = s.get("type")
    if t is None:
        return "any"
    if isinstance(t, list):
        return " or ".join("`null`" if x == "null" else x for x in t)
    if t == "array":
        inner = s.get("items")
        return "array" + (f" of {_type(inner, defs)}" if inner else "")
    if t == "object" and isinstance(s.get("additionalProperties"), dict):
        return f"object of {_type(s['additionalProperties'], defs)}"
    return "`null`" if t == "null" else t


def _table(props, required, defs) -> list:
    lines = ["| key | type | | meaning |", "|---|---|---|---|"]
    for key, s in props.items():
        need = "required" if key in required else "optional"
        text = s.get("description", "").replace("|", "\\|")
        lines.append(f"| `{key}` | {_type(s, defs)} | {need} | {text} |")
    return lines


def _section(name, s, defs) -> list:
    lines = [f"## {name}", "", s.get("description", ""), ""]
    if s.get("unevaluatedProperties") is False:
        lines += ["No other keys (closed).", ""]
    lines += _table(s.get("properties", {}), s.get("required", []), defs) + [""]
    for group in s.get("allOf", []):
        lines += ["Its other keys are those of one of:", ""]
        for variant in group["anyOf"]:
            lines += [f"**{variant['title']}**: {variant['description']}", ""]
            lines += _table(variant["properties"], variant["required"], defs) + [""]
    return lines


def render() -> str:
    """msg_docs/estimate.md from the schema: each object in the order the root names them."""
    schema = estimate_schema()
    defs = schema["$defs"]
    order, todo = [], [r["$ref"].rsplit("/", 1)[1] for r in schema["anyOf"]]
    while todo:
        name = todo.pop(0)
        if name in order:
            continue
        order.append(name)
        text = json.dumps(defs[name])
        todo += [part.split('"', 1)[0] for part in text.split('"$ref": "#/$defs/')[1:]]
    lines = [HEAD.rstrip("\n"), ""]
    lines += ["Objects: " + ", ".join(f"[{n}](#{n.lower()})" for n in order) + ".", ""]
    for name in order:
        lines += _section(name, defs[name], defs)
    return "\n".join(lines).rstrip("\n") + "\n\n" + TAIL


TAIL = """## Where the object comes from

**Measured data** (`gyro-instrument estimate --data FILE --scene SCENE --json`): the same object,
with `data` (the file's name), `observation_s` the data's span (first to last valid sample, s),
`truth` the scene's nominal site values, and `data_notes` (absent when empty): what was left out,
sorted or not used (see docs/formats/csv.md).

**A bag recorded by another tool** (`gyro-instrument replay BAG --scene SCENE --json`, or with
`--topic`): the same object, with `observation_s` the longest matched topic's span, and `topics`:
`matched` (instrument -> topic it was read from), `unmatched` (instrument -> why: `no topic
/<instrument>/joint_states in the bag`, `topic ... has type ..., expected
sensor_msgs/msg/JointState`, `topic ... lacks the joints ... of a <type>`, or too few messages) and
`unused` (every other topic of the bag -> its type). `replay_notes` repeats the unmatched
instruments and unused topics, and says when times are counted from the first sample (stamps not
from the simulator's epoch) or taken from the log time (header stamps all 0).

**Lost data in a replayed bag** (`gyro-instrument replay BAG --json`). When the bag lost data,
the object has a key `damaged`: a list with one entry per lost stretch, absent when nothing was
lost. Each entry: `offset` and `length` (bytes in the file; null for a loss recorded by an
earlier `recover`, or for messages whose channel definition was lost), `lost_from_s`,
`lost_to_s` (the log-time span that was lost, s from the scene's start like `observation_s`;
null at an end that is unknown), `span_from` (`chunk index`: the span is the damaged chunk's
`message_start_time`–`message_end_time` from the intact summary; `neighbouring messages`: the
summary is unusable, the span is open between the last intact message before and the first
after), `reason` (e.g. `chunk CRC mismatch`, `chunk undecodable (ZstdError)`, `unreadable
records (framing lost)`), `before_recovery: true` for losses read from a recovered file's
`gyro_instrument_damage` record, and `file` (the `.mcap` of a bag directory the loss is in; absent
for a bare `.mcap`, whose `offset` is in that file). The estimate uses only the intact messages; `replay_notes`
lists what else the reader noticed (a damaged summary that was ignored, an interrupted
recording). The text output prints one line per entry, e.g.
`  damaged: chunk at byte 104637 failed its CRC: lost 24.25 s to 26.65 s`.

**Field books** (`gyro-instrument estimate --reversal-points FILE [--scene SCENE] --json`): north from
turning points written down by hand (estimators/north/field_book.py documents the columns and rules). A CSV,
one turning point a row in the order observed, `#` lines comments; columns `reading_<unit>` (required),
`time_<tunit>`, `tape_reading_<unit>`, `tape_time_<tunit>`, `turning_point` (the book's numbers; a
skipped number is a missed point), `side` (`left`/`right`, checked against the readings), `remark`.
Angle units: rad, mrad, deg, gon, mgon, arcmin, arcsec; `dms` as printed (`179°01'56"`, `179.01.56`,
`179 01 56`, `179-01-56`); `ddmmss` (`179.0156`, the DD.MMSS notation, never guessed from a decimal
column); `div`, scale divisions of the value given with `--scale-division` (e.g. `10arcmin`). Time units:
s, ms, us, ns, min, `hms` (`mm:ss` or `hh:mm:ss`). `--angle-unit` / `--time-unit` give a bare
`reading` / `time` column its unit (any unit a header takes); a header unit they contradict is refused.
The separator is sniffed as for `--data` (`;` reads decimal commas), or `--separator`. A row whose
reading is empty is a missed turning point: left out in its place, the others kept (its time still times
the swing). The readings are the circle's, clockwise.

One object: `scene` (null without `--scene`), `field_book`, and `north` as above with `instrument`
`null`, `field_book` the file, `scene`, `scene_instrument` and `latitude_deg` (the scene's first
horizontal gyroscope; null without a scene), `mount_azimuth_deg` with `mount_azimuth_dms` (d°m′s″ to
0.1″) and `mount_azimuth_gon`, the circle reading of north `north_reading_deg` / `_dms` / `_gon`
(= −mount, in [0, 360°)), `method` `schuler_mean` (the headline), `reduction` (`raw: ...` when neither
the book nor the scene has a tape, else `tape removed (...)`), `tape` (null for the raw reduction; else
`source`, `ratio_db_dk`, `ratio_sigma`, `zero_reading_deg` / `_dms` / `_gon` the tape zero's circle
reading, `zero_sigma_arcsec`, and from the book's times the half periods, the undamped ones and each
swing's damping ratio per swing, each method's tape zero `zero_reading_by_method_deg`), `methods` `schuler_mean` and `lavrov` (each with the same angle fields,
σ from the scatter of the turning points, ≥ 4 of them, `null` with 3; `schuler_mean.triple_means`: the
means (a_k + 2a_(k+1) + a_(k+2))/4 a surveyor prints beside the readings, with their turning points),
`turning_points` (the number read), `missed` (`turning_point`, `line`, `time_s`), `outliers` (`column`,
`turning_point`, `line`, `reading` as written, `sigmas` from its neighbours' mean, `threshold_sigmas`,
`residual_arcsec`: named, not dropped), `crlb_arcsec` `null` (no record). The tape: with the book's
rotor-off readings and the times of both swings, D_B/D_K from the undamped half periods (ω_u² = ω_d² +
δ², δ from Lavrov's damping ratio per swing) and the exact relation N = c − atan(x (Z − c)), each
method's own tape zero; without tape readings (or without their times) on a scene whose tape is on, the
scene's D_B/D_K at its latitude and its tape zero (said in `reduction` and in the text). Bad input —
fewer than 3 turning points, readings that do not alternate, a time going back, a unit the header and
the option disagree on, a scene latitude where the directing torque vanishes — exits 2 with one line
naming the line, column or field and the value. The text output prints the angles in
`--angle-format` (deg, dms, gon), the circle reading of north, the reduction, missed points and outliers.
"""


def main() -> None:
    SCHEMA_OUT.write_text(render_schema(), encoding="utf-8")
    DOCS_OUT.write_text(render(), encoding="utf-8")
    print(f"wrote {SCHEMA_OUT.relative_to(ROOT)} and {DOCS_OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
