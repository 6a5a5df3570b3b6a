"""Docs stay true to the code: generated instrument and scene docs are current, every topic the suite
publishes is documented, every CLI subcommand is in the README."""

import importlib.util
from pathlib import Path

from gyro_instrument.ros.cli import build_parser
from gyro_instrument.recording.topics import ESTIMATOR_TOPICS

ROOT = Path(__file__).resolve().parents[1]


def test_instrument_docs_are_current():
    spec = importlib.util.spec_from_file_location("gen", ROOT / "tools" / "gen_instrument_docs.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert (ROOT / "msg_docs" / "instruments.md").read_text() == gen.render(), \
        "msg_docs/instruments.md is stale: run python tools/gen_instrument_docs.py"


def test_scene_docs_are_current():
    spec = importlib.util.spec_from_file_location("gen_scene", ROOT / "tools" / "gen_scene_docs.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert (ROOT / "msg_docs" / "scene.md").read_text() == gen.render(), \
        "msg_docs/scene.md is stale: run python tools/gen_scene_docs.py"


def test_scene_docs_cover_every_specified_key():
    # Whatever Param a section gains (e.g. estimator.hemisphere) appears in the generated format.
    from gyro_instrument.core.scene import SITE_PARAMS, TOP_PARAMS
    from gyro_instrument.effects import REGISTRY as EFFECTS
    from gyro_instrument.scenes import ESTIMATOR_PARAMS, FORMAT, SENSOR_PARAMS
    doc = (ROOT / "msg_docs" / "scene.md").read_text()
    keys = [p.name for p in TOP_PARAMS] + list(FORMAT.sections) + [f"site.{p.name}" for p in SITE_PARAMS] \
        + [f"sensor.{p.name}" for p in SENSOR_PARAMS] + [f"estimator.{p.name}" for p in ESTIMATOR_PARAMS] \
        + [f"effects.{e}.{p.name}" for e, c in EFFECTS.items() for p in c.PARAMS] + list(EFFECTS)
    for key in keys:
        assert f"`{key}`" in doc, key
    assert "instruments.md" in doc and "=null" in doc and "earth_rotation is not simulated" in doc


def test_topics_are_documented():
    doc = (ROOT / "msg_docs" / "topics.md").read_text()
    for topic in list(ESTIMATOR_TOPICS) + ["/clock", "joint_states", "bob_position"]:
        assert topic in doc, topic


def test_every_subcommand_is_in_the_readme():
    readme = (ROOT / "README.md").read_text()
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name in sub.choices:
        assert f"gyro-instrument {name}" in readme, name
