"""A new simulator node needs no table in ros/: its parameters and ``--help`` follow from the
instrument types that name it (``SIMULATOR_NODE``), its topics from their publications
(docs/extending.md, step 5: an entry point in setup.py and a function in ros/main.py)."""

import pytest

from gyro_instrument.instruments import REGISTRY
from gyro_instrument.recording.topics import publications
from gyro_instrument.ros import main, params

pytestmark = pytest.mark.ros


def test_help_of_a_simulator_node_no_table_names(monkeypatch):
    base = REGISTRY["spherical_pendulum"]
    new = type("LabPendulum", (base,), {"type_name": "lab_pendulum", "SIMULATOR_NODE": "lab_sim"})
    monkeypatch.setitem(REGISTRY, "lab_pendulum", new)
    text = main.help_text("lab_sim")
    assert text.startswith("usage: lab_sim") and "lab_pendulum" in text
    for spec in params.NODE_SPECS["lab_sim"]:
        assert f"  {spec.name} (" in text
    for p in publications("<instrument>", new):
        assert p.topic in text and p.type_name in text
    with pytest.raises(KeyError):
        params.NODE_SPECS["no_such_node"]


def test_every_shipped_node_has_help():
    for name in params.NODE_SPECS:
        assert main.help_text(name).startswith(f"usage: {name}")
