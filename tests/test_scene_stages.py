"""Scene loading is one pass (issue 36): parse -> override -> validate -> build, each stage a public
function of core/scene.py called once, in order, each given what the one before returned; and a
new top-level block (a ship's ``motion:``) is one Block added to the format."""

import pytest

from gyro_instrument.core import scene as stages
from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.params import Param, validate_params
from gyro_instrument.core.scene import Block
from gyro_instrument.scenes import FORMAT, build_instruments, load_scene, scene_from_data, scene_path

OVERRIDES = ["site.latitude_deg=-33.87", "seed=7", "effects.finite_amplitude=null",
             "instruments.gyro_meridian.spin_rate_turn_s=50"]


def _view(scene):
    """What a Scene says, comparable (its effects are instances: compared by type and parameters)."""
    return (scene.name, scene.site, scene.duration_s, scene.sample_rate_hz, scene.seed,
            {k: (type(v), vars(v)) for k, v in scene.effects.items()}, dict(scene.instruments),
            dict(scene.sensor), dict(scene.estimator), dict(scene.blocks), dict(scene.raw), scene.source,
            scene.output_channels)


def test_load_scene_is_the_composition_of_the_stages():
    path = scene_path("quet_paris")
    by_hand = stages.validate_scene(stages.apply_overrides(stages.read_yaml(path), OVERRIDES, FORMAT), FORMAT,
                                    source=path)
    assert _view(load_scene("quet_paris", OVERRIDES)) == _view(by_hand)
    # the block values are the sections the Scene has always carried
    assert by_hand.blocks["sensor"] == dict(by_hand.sensor) and by_hand.blocks["estimator"] == dict(by_hand.estimator)
    built = build_instruments(by_hand)
    assert list(built) == list(by_hand.instruments)


def test_each_stage_runs_once_in_order_on_what_the_last_returned(monkeypatch):
    calls = []

    def spy(name):
        real = getattr(stages, name)

        def wrapped(*args, **kwargs):
            calls.append((name, args[0]))
            out = real(*args, **kwargs)
            calls.append((name + " ->", out))
            return out
        monkeypatch.setattr(stages, name, wrapped)

    for name in ("read_yaml", "apply_overrides", "validate_scene"):
        spy(name)
    scene = load_scene("quet_paris", OVERRIDES)
    assert [c[0] for c in calls] == ["read_yaml", "read_yaml ->", "apply_overrides", "apply_overrides ->",
                                     "validate_scene", "validate_scene ->"]
    # data passed forward: each stage's input is the object the previous stage returned
    assert calls[2][1] is calls[1][1] and calls[4][1] is calls[3][1] and calls[5][1] is scene


def test_scene_from_data_without_overrides_validates_the_mapping_as_given():
    data = stages.read_yaml(scene_path("quet_paris"))
    scene = scene_from_data(data)
    assert scene.raw == data and scene.source == "recorded"


CURRENT_PARAMS = (Param("speed_kn", default=0.0, low=0.0, high=100.0, doc="current speed, knots"),
                 Param("course_deg", default=0.0, low=0.0, high=360.0, open_high=True, doc="set (direction), degrees"))


def _check_current(raw, parts):
    # a stand-in for the block such as a sea current: absent is a fixed pier (None); present, it needs what
    # was validated before it (the site's latitude, the duration), as a drifting track does
    if raw is None:
        return None
    return dict(validate_params("current", CURRENT_PARAMS, raw), start_latitude_rad=parts.site.latitude_rad,
                duration_s=parts.top["duration_s"])


def _attach(instrument, current):
    if current is not None:
        instrument.current = current


CURRENT = Block("current", check_value=_check_current, channels=lambda m: 2 if m else 0, attach=_attach,
               doc="the sea current under the instruments (optional)")


def test_a_new_block_is_one_registration():
    fmt = FORMAT.with_block(CURRENT)
    path = scene_path("quet_paris")
    pier = stages.load(path, [], fmt)
    base = load_scene("quet_paris")
    assert pier.current is None and pier.output_channels == base.output_channels
    assert getattr(base, "current", None) is None                    # the shipped format has no such block
    given = stages.load(path, ["current={speed_kn: 20, course_deg: 90}"], fmt)   # replaces the whole block
    assert given.current == {"speed_kn": 20.0, "course_deg": 90.0, "start_latitude_rad": given.site.latitude_rad,
                            "duration_s": given.duration_s}
    assert given.output_channels == base.output_channels + 2        # the block's own columns
    built = stages.build_instruments(given, fmt)
    assert all(inst.current is given.current for inst in built.values())
    assert stages.load(path, ["current.speed_kn=12", "current=null"], fmt).current is None
    assert stages.load(path, ["current.speed_kn=12", "current.speed_kn=null"], fmt).current["speed_kn"] == 0.0
    with pytest.raises(SceneError) as err:
        stages.load(path, ["current.course_deg=360"], fmt)
    assert err.value.field == "current.course_deg" and err.value.value == 360.0
    # the shipped format does not know the block: the same refusal as any unknown key, naming it
    with pytest.raises(SceneError) as err:
        load_scene("quet_paris", ["current.speed_kn=20"])
    assert err.value.field == "current" and "unknown key" in str(err.value)
    with pytest.raises(SceneError) as err:
        load_scene("quet_paris", ["current=null"])
    assert err.value.field == "current"
