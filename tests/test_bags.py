"""Every shipped bag is read message by message by two independent readers, and replaying it
gives the estimate recorded beside it (issue 4)."""

import json
from pathlib import Path

import pytest

from gyro_instrument.cli import replay_bag

BAGS = sorted((Path(__file__).resolve().parents[1] / "bags").glob("*.mcap"))


def test_bags_are_shipped_and_small():
    assert {b.stem for b in BAGS} >= {"quet_paris", "gimbal_paris", "foucault_pantheon", "free_gyroscope",
                                      "puiseux_spheroid"}
    assert all(b.stat().st_size < 5 * 1024 * 1024 for b in BAGS)


@pytest.mark.parametrize("bag", BAGS, ids=lambda b: b.stem)
def test_independent_readers_decode_every_message(bag):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from rosbags.highlevel import AnyReader
    with AnyReader([bag]) as r:
        n_rosbags = sum(1 for c, t, raw in r.messages() if r.deserialize(raw, c.msgtype) is not None)
    with open(bag, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        n_mcap = sum(1 for _ in reader.iter_decoded_messages())
        stats = reader.get_summary().statistics
    assert n_rosbags == n_mcap == stats.message_count > 0


@pytest.mark.parametrize("bag", BAGS, ids=lambda b: b.stem)
def test_replay_gives_the_recorded_estimate(bag):
    recorded = json.loads(bag.with_suffix(".estimate.json").read_text())
    assert replay_bag(str(bag)) == recorded


def test_replay_decodes_with_the_live_layouts_exactly_as_the_dynamic_decoder(monkeypatch):
    # Issue 12: replay and the estimator node share one CDR codec (recording/cdr.py). Reading the
    # shipped bag through the fixed layouts must give the very floats mcap_ros2's dynamic decoder
    # gives (the same float64 bytes), and stamps to the nanosecond: exact equality.
    import numpy as np
    from gyro_instrument.core.scene import EPOCH_NS
    from gyro_instrument.recording import bag_samples, cdr
    from gyro_instrument.recording.bag_layout import scan_path
    scan = scan_path(str(next(b for b in BAGS if b.name == "quet_paris.mcap")))
    fast, n_fast, bad = bag_samples.joint_samples(scan, EPOCH_NS)

    def no_layout(*a):
        raise ValueError("dynamic decoder only")
    monkeypatch.setattr(cdr, "joint_state_layout", no_layout)
    slow, n_slow, _ = bag_samples.joint_samples(scan, EPOCH_NS)
    assert bad == 0 and n_fast == n_slow > 0 and fast.keys() == slow.keys()
    for name in fast:
        for a, b in zip(fast[name], slow[name]):
            assert a.dtype == b.dtype and np.array_equal(a, b), name
