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
