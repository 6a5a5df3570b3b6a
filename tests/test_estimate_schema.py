"""The estimate's JSON Schema (issue 36 item 2): shipped, generated from the typed records, the docs generated
from it, and every estimate JSON of today valid against it.

The validator is an independent one: the ``jsonschema`` package (draft 2020-12), not code of this project.
What is validated: every shipped ``bags/*.estimate.json`` (``run --bag`` wrote them), the ``--json`` output of
``gyro-instrument estimate`` for every shipped scene (found from the scenes, not listed by hand), a table
``simulate`` wrote read back with ``estimate --data``, ``replay`` of two shipped bags, of a damaged copy and of
its recovery, and a field book. That the schema means something is checked by objects it must refuse (an
unknown key, a missing one, a wrong type or value).
"""

import copy
import importlib.util
import json
import math
from pathlib import Path

import jsonschema
import pytest

from gyro_instrument.cli import main
from gyro_instrument.estimators.estimate_types import estimate_schema, shipped_schema
from gyro_instrument.estimators.record import ABSENT, Record, doc, to_json
from gyro_instrument.scenes import shipped_scene_names

ROOT = Path(__file__).resolve().parents[1]
BAGS = sorted((ROOT / "bags").glob("*.estimate.json"))
#: Short records each scene allows (the reason per scene): the gyrotheodolite's rotor-off swing lasts 796 s
#: and its reduction needs 3 reversal points (its shipped hour); a rate gyro its schedule's whole sequence
#: of positions (test_north_files.py's durations); Puiseux's bodies their shipped 20 s / 30 s; the others
#: 120 s hold several swings (Quet's 12.8 s, the gimbal's, the pendulum's 16.4 s period).
DURATION_S = {"gyrotheodolite": 3600.0, "rate_gyro_two_position": 300.0, "rate_gyro_four_position": 400.0,
              "rate_gyro_carousel": 120.0, "puiseux_spheroid": 20.0, "puiseux_general": 30.0}
DEFAULT_DURATION_S = 120.0


def _tool():
    spec = importlib.util.spec_from_file_location("gen_estimate", ROOT / "tools" / "gen_estimate_docs.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    return gen


@pytest.fixture(scope="module")
def validator():
    schema = shipped_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def _errors(validator, obj) -> list:
    return [f"{e.json_path}: {e.message[:300]}" for e in validator.iter_errors(obj)]


def _run_json(capsys, *argv) -> dict:
    code = main([*argv, "--json"])
    out = capsys.readouterr().out
    assert code == 0, out
    return json.loads(out)


def test_the_shipped_schema_is_the_generated_one():
    assert (ROOT / "gyro_instrument" / "estimators" / "estimate.schema.json").read_text(encoding="utf-8") == \
        _tool().render_schema(), "estimate.schema.json is stale: run python tools/gen_estimate_docs.py"
    assert shipped_schema() == estimate_schema()


def test_msg_docs_estimate_is_generated_from_the_schema():
    assert (ROOT / "msg_docs" / "estimate.md").read_text(encoding="utf-8") == _tool().render(), \
        "msg_docs/estimate.md is stale: run python tools/gen_estimate_docs.py"


def test_the_schema_is_draft_2020_12_and_ships_in_the_package():
    schema = shipped_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    setup = (ROOT / "setup.py").read_text(encoding="utf-8")
    assert '"gyro_instrument.estimators": ["estimate.schema.json"]' in setup


@pytest.mark.parametrize("path", BAGS, ids=lambda p: p.name)
def test_every_shipped_bag_estimate_validates(validator, path):
    assert not _errors(validator, json.loads(path.read_text(encoding="utf-8")))


def test_there_are_shipped_estimates_and_scenes_to_validate():
    assert len(BAGS) >= 6 and len(shipped_scene_names()) >= 11


@pytest.mark.parametrize("scene", shipped_scene_names())
def test_every_shipped_scene_estimate_validates(validator, capsys, scene):
    est = _run_json(capsys, "estimate", scene, "--duration-s", str(DURATION_S.get(scene, DEFAULT_DURATION_S)))
    assert est["scene"] == scene
    assert not _errors(validator, est)


@pytest.mark.parametrize("bag", ["puiseux_spheroid", "quet_paris"])
def test_a_replayed_bag_validates(validator, capsys, bag):
    """``replay`` of a shipped bag (the smallest, and one with a north block): the live estimate again."""
    est = _run_json(capsys, "replay", str(ROOT / "bags" / f"{bag}.mcap"))
    assert est["scene"] == bag
    assert not _errors(validator, est)


def test_a_damaged_and_a_recovered_bag_validate(validator, capsys, tmp_path):
    """4000 zero bytes written into a copy of quet_paris.mcap at 1.5 MB (inside its data section): ``replay``
    reports the lost stretch under ``damaged``; ``recover`` then ``replay`` reports it ``before_recovery``."""
    bag = tmp_path / "dmg.mcap"
    data = bytearray((ROOT / "bags" / "quet_paris.mcap").read_bytes())
    data[1_500_000:1_504_000] = bytes(4000)
    bag.write_bytes(bytes(data))
    est = _run_json(capsys, "replay", str(bag))
    assert est["damaged"] and not _errors(validator, est)
    assert main(["recover", str(bag), "--out", str(tmp_path / "rec.mcap")]) == 0
    capsys.readouterr()
    est = _run_json(capsys, "replay", str(tmp_path / "rec.mcap"))
    assert est["damaged"][0]["before_recovery"] is True and not _errors(validator, est)


def test_an_estimate_of_measured_data_validates(validator, capsys, tmp_path):
    """``simulate`` writes the table, ``estimate --data`` reads it: the object gains ``data``."""
    table = tmp_path / "q.csv"
    assert main(["simulate", "quet_paris", "--duration-s", "120", "--out", str(table), "--quiet"]) == 0
    capsys.readouterr()
    est = _run_json(capsys, "estimate", "--data", str(table), "--scene", "quet_paris")
    assert est["data"] == "q.csv"
    assert not _errors(validator, est)


def test_a_field_book_estimate_validates(validator, capsys, tmp_path):
    """A book with every part of the block: 16 turning points of a swing about 12.3° decaying by 0.93 a swing
    (deg on the circle, clockwise), number 5 missed (its reading empty), number 9 off by 0.05° (an outlier: the
    others scatter by 0.0003°), with times and the rotor-off tape's readings; alone and with the scene's latitude."""
    rows = ["turning_point,time_s,reading_deg,tape_time_s,tape_reading_deg"]
    for k in range(16):
        a = 12.3 + 2.0 * 0.93 ** k * (-1) ** k + (0.05 if k == 9 else 0.0) + 0.0003 * math.sin(7 * k)
        rows.append(f"{k},{30.0 * k:.1f},{'' if k == 5 else f'{a:.5f}'},{30.0 * k + 5:.1f},"
                    f"{0.4 + 0.3 * 0.95 ** k * (-1) ** k:.5f}")
    book = tmp_path / "book.csv"
    book.write_text("\n".join(rows) + "\n", encoding="utf-8")
    for scene in ([], ["--scene", "gyrotheodolite"]):
        est = _run_json(capsys, "estimate", "--reversal-points", str(book), *scene)
        north = est["north"]
        assert len(north["missed"]) == 1 and len(north["outliers"]) == 1 and north["tape"] is not None
        assert not _errors(validator, est)


def _quet(capsys) -> dict:
    return _run_json(capsys, "estimate", "quet_paris", "--duration-s", "120")


@pytest.mark.parametrize("change, why", [
    (lambda d: d.update(bogus=1), "an unknown top-level key"),
    (lambda d: d.pop("checks"), "a required key missing"),
    (lambda d: d.update(latitude_deg="48.8"), "a latitude as a string"),
    (lambda d: d["truth"].update(latitude_deg=None), "the truth's latitude null"),
    (lambda d: d["instruments"]["gyro_horizontal"].update(bogus=1), "an unknown key in a swing entry"),
    (lambda d: d["instruments"]["gyro_horizontal"].pop("period_s"), "a swing entry without its period"),
    (lambda d: d["north"]["methods"]["fit"].update(bogus=1), "an unknown key in a north method"),
    (lambda d: d["checks"][0].update(status="fine"), "a check status not in the list"),
    (lambda d: d["methods"]["item9"].update(latitude_deg="x"), "item 9's latitude as a string"),
])
def test_the_schema_refuses_what_is_not_an_estimate(validator, capsys, change, why):
    est = _quet(capsys)
    assert not _errors(validator, est)
    bad = copy.deepcopy(est)
    change(bad)
    assert _errors(validator, bad), why


def test_a_plug_in_entry_is_open_but_not_under_a_shipped_type(validator, capsys):
    """Another kind's entry as it gives it (docs/extending.md): any keys, under a type no shipped instrument has."""
    est = _quet(capsys)
    est["instruments"]["rig"] = {"type": "rate_integrating_gyro", "vertical_rate_rad_s": 5.5e-5}
    assert not _errors(validator, est)
    est["instruments"]["rig"]["type"] = "plane_gyroscope"
    assert _errors(validator, est)


def test_records_write_their_keys_in_order_and_leave_absent_ones_out():
    from dataclasses import dataclass

    @dataclass(frozen=True, kw_only=True)
    class Leaf(Record):
        b_s: float = doc("b, s")
        a_s: float = doc("a, s", ABSENT)

    @dataclass(frozen=True, kw_only=True)
    class Tree(Record):
        z: Leaf = doc("z")
        spliced: Leaf = doc("spliced", inline=True)
        again: Leaf = doc("the same leaf again")

    leaf = Leaf(b_s=1.0)
    out = to_json(Tree(z=leaf, spliced=Leaf(b_s=2.0, a_s=3.0), again=leaf))
    assert list(out) == ["z", "b_s", "a_s", "again"] and out["z"] == {"b_s": 1.0}
    assert out["z"] is out["again"]           # one record, one dict (an entry's north is the estimate's)
