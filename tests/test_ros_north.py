"""North survives bags (issue 33 item 4): ``run gyrotheodolite --bag`` then ``replay`` equals the live estimate.

The shipped gyrotheodolite as is (1 h at 1 Hz, noise on, its scale zero at 359.75°) over real DDS on
loopback (tools/loopback). The estimator node keeps the joint states of the gyroscope and of its
rotor-off swing (the record its north reads beside its own); the bag holds both topics, and
``replay`` must build the same records and give the same estimate, ``north`` with its tape included.
The reference for the live run is the core's ``estimate_records`` on the same seed's draws.
"""

import pytest

from gyro_instrument.cli import replay_bag, to_jsonable
from gyro_instrument.estimators.pipeline import estimate_records, measure, simulate_truth
from gyro_instrument.recording.mcap_io import read_messages
from gyro_instrument.ros.suite import run_suite
from gyro_instrument.scenes import load_scene
from tests.test_north_files import assert_same_estimate

pytestmark = pytest.mark.ros


@pytest.fixture(scope="module")
def gt_run(tmp_path_factory):
    bag = str(tmp_path_factory.mktemp("north") / "gt.mcap")
    result, stats = run_suite("gyrotheodolite", [], None, bag)
    return bag, to_jsonable(result), stats


def test_the_bag_holds_the_rotor_off_swing(gt_run):
    bag, _, stats = gt_run
    n = stats["samples"]
    assert n == 3601                            # 3600 s at 1 Hz, both ends
    counts = {}
    for topic, *_ in read_messages(bag):
        counts[topic] = counts.get(topic, 0) + 1
    assert counts["/gak1/joint_states"] == n and counts["/gak1_rotor_off/joint_states"] == n


def test_replay_equals_the_live_estimate_and_the_core(gt_run):
    bag, live, _ = gt_run
    # REL of tests/test_north_files.py: the same doubles through the same code in one process
    assert_same_estimate(replay_bag(bag), live)
    scene = load_scene("gyrotheodolite")
    truth = simulate_truth(scene)
    core = to_jsonable(estimate_records(scene, truth[1], measure(scene, truth)))
    assert_same_estimate(live, core)
    north = live["north"]
    assert north["instrument"] == "gak1" and north["tape"]["instrument"] == "gak1_rotor_off"
    # the live run's instruments are the ones its estimator keeps: the rotor-off swing is one
    assert live["instruments"]["gak1_rotor_off"]["reason"].startswith("not used")

