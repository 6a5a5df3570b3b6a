"""Write msg_docs/instruments.md from the instrument and effect registries (kept true by
tests/test_docs.py: run `python tools/gen_instrument_docs.py` after changing a Param or Column)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gyro_instrument.core.errors import SceneError  # noqa: E402
from gyro_instrument.core.params import REQUIRED, alias_note, validate_params  # noqa: E402
from gyro_instrument.core.site import Site  # noqa: E402
from gyro_instrument.effects import REGISTRY as EFFECTS  # noqa: E402
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS  # noqa: E402


#: Where the "beyond the paper" statements are computed: the papers' site (Quet's Paris) with the
#: exact model (every one of these effects an instrument supports) and the instrument's defaults.
EXAMPLE_LATITUDE_DEG = 48.85
EXACT_EFFECTS = ("earth_rotation", "centrifugal", "finite_amplitude")


def beyond_the_paper(cls):
    """The ``beyond_the_paper`` prediction (str or None) of an instrument type at its default
    parameters, at :data:`EXAMPLE_LATITUDE_DEG` with the :data:`EXACT_EFFECTS` it supports."""
    if any(p.default is REQUIRED for p in cls.PARAMS):
        return None
    params = validate_params("example", cls.PARAMS, {})
    effects = {e: EFFECTS[e]() for e in EXACT_EFFECTS if e in cls.SUPPORTED_EFFECTS}
    try:
        cls.check_params("example", params)
        cls.check_effects("example", params, tuple(effects))
    except SceneError:          # its defaults alone are not a configuration (e.g. a body without a shape)
        return None
    inst = cls("example", Site.from_degrees(EXAMPLE_LATITUDE_DEG), params, effects)
    return inst.predictions().get("beyond_the_paper")


def render():
    out = ["# Instruments and effects", "",
           "Generated from the code by `tools/gen_instrument_docs.py`; `tests/test_docs.py` fails when it",
           "is stale. Angles are given in degrees only in parameter names ending in `_deg`; channels are",
           "in radians, rad/s and metres. A rate `<stem>_rad_s` may also be given as `<stem>_turn_s`,",
           "`<stem>_rpm` or `<stem>_deg_h`; it is converted and stored under its `_rad_s` name.", ""]
    for name, cls in sorted(INSTRUMENTS.items()):
        out += [f"## `{name}`", "", cls.summary, "",
                f"Supported effects: {', '.join(sorted(cls.SUPPORTED_EFFECTS)) or 'none (exact model)'}"
                f" (it sums the terms of: {', '.join(sorted(cls.MECHANICS)) or 'none'}).", "",
                f"Measured: {', '.join(f'`{c}`' for c in cls.MEASURED_CHANNELS)}"
                f"{' (deflections x/l, y/l: a pendulum)' if cls.OBSERVATION.SHOWS_BOB_POSITION else ''}; "
                f"JointState joints: {', '.join(f'`{j}`' for j in cls.JOINTS)}; published by `{cls.SIMULATOR_NODE}`"
                f"{'; estimable through its directing model' if 'directing_model' in vars(cls) else ''}.", "",
                "| parameter | default | valid | meaning |", "|---|---|---|---|"]
        for p in cls.PARAMS:
            default = "required" if p.default is REQUIRED else repr(p.default)
            note = alias_note(p, cls.PARAMS)
            out.append(f"| `{p.name}` | {default} | {p.describe_range().replace('must be ', '')} | {p.doc}"
                       f"{'; ' + note if note else ''} |")
        out += ["", "| channel | unit | meaning |", "|---|---|---|"]
        out += [f"| `{c.name}` | {c.unit} | {c.doc} |" for c in cls.COLUMNS]
        out.append("")
        beyond = beyond_the_paper(cls)
        if beyond:
            out += [f"Beyond the paper (prediction `beyond_the_paper` of `describe`; here computed for the defaults "
                    f"at {EXAMPLE_LATITUDE_DEG}° with {', '.join(e for e in EXACT_EFFECTS if e in cls.SUPPORTED_EFFECTS)}; "
                    f"`describe` computes it for the scene's configuration): {beyond}.", ""]
    out += ["## Effects", "", "Each effect contributes terms to the kinds of mechanics it names (gyro_instrument/core/effect.py);",
            "an instrument supports the effects whose kinds it sums (docs/extending.md).", "",
            "| effect | parameters | contributes to | what it adds |", "|---|---|---|---|"]
    for name, cls in sorted(EFFECTS.items()):
        params = ", ".join(f"`{p.name}` (default {p.default!r}; {p.describe_range().replace('must be ', '')}"
                           f"{'; ' + alias_note(p, cls.PARAMS) if alias_note(p, cls.PARAMS) else ''})"
                           for p in cls.PARAMS) or "none"
        out.append(f"| `{name}` | {params} | {', '.join(sorted(cls.MECHANICS))} | {cls.summary} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    (Path(__file__).resolve().parents[1] / "msg_docs" / "instruments.md").write_text(render())
