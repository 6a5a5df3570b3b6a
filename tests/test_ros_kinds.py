"""One predicate says which instruments are measured (issue 35 item 1): ``estimate``, the live
estimate of ``run`` (the suite in this process, rclpy and DDS on loopback), the estimator node fed
the same joint states by its callbacks, and ``replay`` of the run's bag report the same instruments
with equal estimates, for every registered instrument type in a short form of a shipped scene."""

import json

import pytest
from rclpy.parameter import Parameter

from gyro_instrument.cli import to_jsonable
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.instruments import REGISTRY
from gyro_instrument.instruments.measurement import measured
from gyro_instrument.recording.replay import replay_bag
from gyro_instrument.scenes import build_instruments, load_scene

pytestmark = pytest.mark.ros

#: Short forms of the shipped scenes, every registered type at least once (the durations of
#: tests/test_effect_sizes.py's CASES: two to five swings, so each estimator has a record to fit).
CASES = {
    "quet_paris": ["seed=5", "duration_s=60"],                               # plane gyroscopes, a pendulum
    "foucault_pantheon": ["duration_s=50", "instruments.cp.type=compound_pendulum",
                          "instruments.cp.spin_rate_rad_s=3.0"],             # and a compound pendulum
    "gimbal_paris": ["duration_s=30"],
    "free_gyroscope": ["duration_s=60"],
    "puiseux_spheroid": ["duration_s=1"],
    # the rate gyro (tests/test_effect_sizes.py's 300 s: a whole sequence of its two positions, so the
    # live tracker publishes once before the final estimate), a carousel of six turns, four positions
    # of which three are reached (north needs three headings or two and a prior)
    "rate_gyro_two_position": ["duration_s=300"],
    "rate_gyro_carousel": ["duration_s=60"],
    "rate_gyro_four_position": ["duration_s=400"],
    # the ship's gyrocompass (its compass block: issue 39 item 6), two hours at 0.1 Hz: more than one swing
    # (about 88 min at 45 deg), so the settling curve is fitted; settled it is not (ISO 22090-1 §3.10)
    "marine_gyrocompass": ["duration_s=7200", "sample_rate_hz=0.1"],
}
#: The estimate's keys the four compare (the whole estimate but the run's own bookkeeping).
KEYS = ("instruments", "latitude_deg", "latitude_sigma_deg", "earth_rate_rad_s", "earth_rate_sigma_rad_s", "crlb",
        "north", "methods", "checks", "reason")


def test_the_cases_hold_every_registered_type():
    types = {inst.type_name for name, over in CASES.items() for inst in build_instruments(load_scene(name, over)).values()}
    assert types == set(REGISTRY)


def _node_estimate(ctx, name, over, scene, truth):
    """The estimator node given every joint state through its callback (no DDS traffic)."""
    from gyro_instrument.recording.joints import joint_streams
    from gyro_instrument.ros import messages as m
    from gyro_instrument.ros.nodes import EstimatorNode
    node = EstimatorNode(context=ctx, parameter_overrides=[Parameter("scene", value=name),
                                                           Parameter("overrides", value=list(over))])
    t_ns, streams = joint_streams(scene, truth=truth)
    for inst, s in streams.items():
        if inst in node.buffers:
            for i in range(len(t_ns)):
                node._on_joint(inst, m.joint_state(int(t_ns[i]), s.names, s.position[i], s.velocity[i], s.effort[i]))
    try:
        return to_jsonable(node.finalize())
    finally:
        node.destroy_node()


@pytest.mark.parametrize("name", CASES)
def test_estimate_run_node_and_replay_agree(name, ctx, tmp_path, capsys):
    from gyro_instrument.ros.cli import main as run_main
    over = CASES[name]
    scene = load_scene(name, over)
    truth = simulate_truth(scene)
    insts = truth[1]
    core = to_jsonable(estimate_records(scene, insts, measure(scene, truth)))
    node = _node_estimate(ctx, name, over, scene, truth)
    bag = str(tmp_path / f"{name}.mcap")
    args = ["run", name, "--bag", bag, "--json", "--quiet"] + [x for o in over for x in ("--set", o)]
    capsys.readouterr()
    assert run_main(args) == 0
    live = json.loads(capsys.readouterr().out)
    replayed = to_jsonable(replay_bag(bag))
    # the same instruments: every instrument of the scene, measured or with the reason it is not
    assert set(core["instruments"]) == set(insts)
    used = {n for n, e in core["instruments"].items() if not e.get("reason", "").startswith("not used by the estimator")}
    assert used == {n for n, inst in insts.items() if measured(inst)}
    for r in (node, live, replayed):
        assert set(r["instruments"]) == set(core["instruments"])
        for key in KEYS:
            assert json.dumps(r.get(key), sort_keys=True) == json.dumps(core.get(key), sort_keys=True), (name, key)
