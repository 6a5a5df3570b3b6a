"""Write docs/formats/scene.md, the scene file format, from the parameter specifications (kept true by
tests/test_docs.py: run `python tools/gen_scene_docs.py` after changing a Param of the scene, its
site, sensor or estimator sections or an effect)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gyro_instrument.core.params import REQUIRED, alias_note  # noqa: E402
from gyro_instrument.core.motion import CHANGE_PARAMS, MOTION_PARAMS  # noqa: E402
from gyro_instrument.core.scene import SITE_PARAMS, TOP_PARAMS  # noqa: E402
from gyro_instrument.effects import REGISTRY as EFFECTS  # noqa: E402
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS  # noqa: E402
from gyro_instrument.scenes import ESTIMATOR_PARAMS, FORMAT, NO_EARTH_ROTATION, SENSOR_PARAMS  # noqa: E402

#: The core sections' lines; an optional block's line is its Block.doc (the scene format's blocks).
SECTION_DOCS = {
    "site": "where the instruments stand (below)",
    "effects": "the physical effects simulated; nothing else is (below)",
    "instruments": "name: {type: ..., parameters...}; at least one (below)",
}


def _default(p):
    if p.default is REQUIRED:
        return "required"
    if p.default is None:
        return "null"
    if isinstance(p.default, bool):
        return "true" if p.default else "false"
    return f"`{p.default!r}`" if isinstance(p.default, str) else f"{p.default!r}"


def _cell(text):
    """Table-safe text: a literal | (as in |v|) would end the cell."""
    return str(text).replace("|", "\\|")


def _optional(params):
    required = [p.name for p in params if p.default is REQUIRED]
    if required:
        return f"Required keys: {', '.join(f'`{r}`' for r in required)}; the others have defaults."
    return "Optional: every key has a default, so the section (or any key) may be left out."


def param_table(params, prefix):
    rows = ["| key | default | valid | meaning |", "|---|---|---|---|"]
    for p in params:
        note = alias_note(p, params)
        rows.append(f"| `{prefix}{p.name}` | {_default(p)} | {p.describe_range().replace('must be ', '')} | "
                    f"{_cell(p.doc)}{'; ' + note if note else ''} |")
    return rows


def render():
    out = ["# Scene files", "",
           "Generated from the parameter specifications by `tools/gen_scene_docs.py`; `tests/test_docs.py`",
           "fails when it is stale. A scene is one YAML mapping; every value is checked against the",
           "specifications below, and a bad one stops `describe`, `simulate`, `estimate`, `run` and the",
           "ROS nodes with exit status 2 and one line `field = value is invalid: valid range`. An unknown",
           "name anywhere (top-level key, section key, effect, instrument, instrument type) is refused",
           "with the closest valid name: `unknown instrument (did you mean 'pendulum'?)`.", "",
           "Rates: a key `<stem>_rad_s` may also be written `<stem>_turn_s` (turns per second), `<stem>_rpm`",
           "or `<stem>_deg_h` (degrees per hour), e.g. `spin_rate_turn_s: 200` or `earth_rate_deg_h: 15.04`;",
           "the value is converted and the scene holds the `_rad_s` name after loading. Two spellings of one",
           "key in a mapping are refused, naming both; a `--set` in one spelling replaces the other.", "",
           "```yaml",
           "name: quet_paris",
           "site: {latitude_deg: 48.8462}",
           "duration_s: 600",
           "effects: {earth_rotation: {}, centrifugal: {}, finite_amplitude: {}}",
           "sensor: {noise_rad: 1.0e-4}",
           "instruments:",
           "  gyro_meridian: {type: plane_gyroscope, plane: meridian, spin_rate_rad_s: 628.3185307179586}",
           "  pendulum: {type: spherical_pendulum, length_m: 67.0, effects: [earth_rotation]}",
           "```", "",
           "## Top-level keys", ""]
    out += param_table(TOP_PARAMS, "")
    docs = dict(SECTION_DOCS, **{b.name: b.doc for b in FORMAT.blocks})
    out += [f"| `{s}` | section | mapping | {docs.get(s, '')} |" for s in FORMAT.sections]
    out += ["", "## `site`", "", "Required, with at least `latitude_deg`.", ""]
    out += param_table(SITE_PARAMS, "site.")
    out += ["", "## `effects`", "",
            "A mapping `name: {parameters}` (or a list of names, each with its default parameters). An",
            "effect is simulated only when listed: a scene without `earth_rotation` is a non-rotating",
            "Earth (see *Scenes without Earth rotation* below). In a scene file `name:` or `name: null`",
            "lists the effect with its default parameters. Every listed effect must be supported by at",
            "least one instrument of the scene.", "",
            "| effect | parameter | default | valid | meaning | supported by |", "|---|---|---|---|---|---|"]
    for name, cls in sorted(EFFECTS.items()):
        users = ", ".join(sorted(t for t, c in INSTRUMENTS.items() if name in c.SUPPORTED_EFFECTS)) or "none"
        if not cls.PARAMS:
            out.append(f"| `{name}` | none | | | {_cell(cls.summary)} | {users} |")
        for i, p in enumerate(cls.PARAMS):
            what = cls.summary if i == 0 else ""
            out.append(f"| `{name}` | `effects.{name}.{p.name}` | {_default(p)} | "
                       f"{p.describe_range().replace('must be ', '')} | {_cell(what)}{'; ' if what else ''}{_cell(p.doc)}"
                       f"{'; ' + alias_note(p, cls.PARAMS) if alias_note(p, cls.PARAMS) else ''} | {users} |")
    out += ["", "## `sensor`", "", _optional(SENSOR_PARAMS), ""]
    out += param_table(SENSOR_PARAMS, "sensor.")
    out += ["", "## `estimator`", "", _optional(ESTIMATOR_PARAMS), ""]
    out += param_table(ESTIMATOR_PARAMS, "estimator.")
    out += ["", "## `motion`", "", "Optional. Without it every instrument is on a fixed pier; with it the",
            "instruments that sail (`marine_gyrocompass`) are carried by a ship starting at the site's latitude",
            "(dead reckoning on a sphere; core/motion.py). `--set 'motion={speed_kn: 20, course_deg: 0}'`",
            "replaces the whole block; `--set motion=null` removes it. An instrument that cannot sail is refused.", ""]
    out += param_table(MOTION_PARAMS, "motion.")
    out += ["", "`motion.schedule`: a list of changes, each a ramp at a constant rate:", ""]
    out += param_table(CHANGE_PARAMS, "motion.schedule[i].")
    out += ["", "## `instruments`", "",
            "A non-empty mapping `name: {type: TYPE, parameters...}`; names are letters, digits and",
            "underscores. `type` is one of " + ", ".join(f"`{t}`" for t in sorted(INSTRUMENTS)) + ";",
            "each type's parameters, defaults, ranges and output channels are in",
            "[instruments.md](../../msg_docs/instruments.md).", "",
            "An instrument may carry its own `effects:` list, a subset of the scene's effects that its type",
            "supports. Without it the instrument gets every scene effect its type supports; with it, only",
            "those listed (`effects: []`: none).", "",
            "## Command-line and ROS overrides (`--set key.path=value`)", "",
            "`--set` (repeatable; the ROS parameter `overrides` takes the same strings) sets any key by its",
            "dotted path; the value is read as YAML (`--set effects.spin_decay={time_constant_s: 600}`).",
            "Mappings on the way are created, so an override can switch an effect on",
            "(`--set effects.earth_rotation={}`) or add an instrument, provided the overrides give its",
            "`type` (`--set instruments.p2.type=spherical_pendulum --set instruments.p2.length_m=10`). A path",
            "into an instrument the scene does not have and whose `type` no override gives is a misspelling:",
            "`instruments.pendlum.length_m = 20 is invalid: unknown instrument (did you mean 'pendulum'?)`.", "",
            "`null` removes:", "",
            "| override | effect |", "|---|---|",
            "| `effects.NAME=null` | the effect is no longer simulated: removed from `effects` and from every instrument's `effects:` list (an unknown NAME is refused with the closest effect) |",
            "| `effects=null` | every effect removed |",
            "| `instruments.NAME=null` | the instrument removed; removing the last one is refused (`a scene needs at least one instrument`) |",
            "| any other key `=null` | the key takes its default (the `default` columns above and in instruments.md); a key without a default is refused: `site.latitude_deg = None is invalid: is required (it has no default); ...` |",
            "", "In a scene file a parameter given as `null` also takes its default.", "",
            "## Scenes without Earth rotation", "",
            "A scene in which no instrument simulates `earth_rotation` (for example a hand-written file",
            "without an `effects:` block) is allowed, and announced: `describe` prints a `note:` line and",
            "`scene_notes` in `--json`, `simulate` prints a `gyro-instrument: note:` line on stderr, and",
            "`estimate` prints a `note:` line and `scene_notes` in `--json`, each starting",
            f"`{NO_EARTH_ROTATION}: ...`; an instrument that leaves it out of its own `effects:` list is",
            f"announced as `{NO_EARTH_ROTATION} for NAME: ...`. The predictions in `describe` follow the",
            "model as simulated (Foucault rate 0, gyroscope swing durations `null`: no directing torque)",
            "and a `notes` list in each instrument's predictions says what the value would be with the",
            "Earth's rotation. `puiseux_body` never simulates it (as in Puiseux 1852).", ""]
    return "\n".join(out)


if __name__ == "__main__":
    (Path(__file__).resolve().parents[1] / "docs" / "formats" / "scene.md").write_text(render())
