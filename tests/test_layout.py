"""The Foxglove layout shipped beside the bags names only topics and message paths that exist in a
shipped bag (issue 14): every plot path and raw-message path resolves on a decoded message, every
3D topic is a MarkerArray in ``site_enu``."""

import json
import re
from pathlib import Path

import pytest

BAGS = Path(__file__).resolve().parents[1] / "bags"
LAYOUT = BAGS / "foxglove_layout.json"


def _messages(bag):
    """{topic: (schema name, first decoded message)}."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    out = {}
    with open(bag, "rb") as fh:
        for schema, channel, _, msg in make_reader(fh, decoder_factories=[DecoderFactory()]).iter_decoded_messages():
            out.setdefault(channel.topic, (schema.name, msg))
    return out


@pytest.fixture(scope="module")
def shipped():
    topics = {}
    for bag in sorted(BAGS.glob("*.mcap")):
        for topic, v in _messages(bag).items():
            topics.setdefault(topic, v)
    return topics


def _paths(layout):
    for panel, cfg in layout["configById"].items():
        for p in cfg.get("paths", []):
            yield panel, p["value"]
        if "topicPath" in cfg:
            yield panel, cfg["topicPath"]


def _resolve(msg, path):
    for name, index in re.findall(r"\.?([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?", path):
        msg = getattr(msg, name)
        if index:
            msg = msg[int(index)]
    return msg


def test_layout_is_shipped_and_laid_out():
    layout = json.loads(LAYOUT.read_text())
    ids = set(layout["configById"])

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])
    assert set(leaves(layout["layout"])) == ids


def test_every_layout_path_exists_in_a_shipped_bag(shipped):
    layout = json.loads(LAYOUT.read_text())
    checked = 0
    for panel, path in _paths(layout):
        topic = max((t for t in shipped if path.startswith(t + ".")), key=len, default=None)
        assert topic is not None, (panel, path)
        value = _resolve(shipped[topic][1], path[len(topic):])
        if panel.startswith("Plot!"):
            assert isinstance(value, (int, float)), (path, value)     # plottable
        checked += 1
    assert checked >= 10


def test_3d_panel_shows_markers_in_site_enu(shipped):
    layout = json.loads(LAYOUT.read_text())
    for panel, cfg in layout["configById"].items():
        if not panel.startswith("3D!"):
            continue
        assert cfg["followTf"] == "site_enu"
        for topic in cfg["topics"]:
            schema, msg = shipped[topic]
            assert schema == "visualization_msgs/msg/MarkerArray"
            assert msg.markers and all(mk.header.frame_id == "site_enu" for mk in msg.markers)
