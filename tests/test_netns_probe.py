"""The test session runs on loopback only (brief: never send traffic to any other address)."""

import os
import socket

import pytest


def test_discovery_range_is_localhost():
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"


@pytest.mark.skipif(os.geteuid() != 0, reason="namespaces need root; discovery range still LOCALHOST")
def test_root_session_is_in_a_loopback_only_namespace():
    # Only the loopback interface exists in this network namespace (netlink, not /sys, which
    # stays mounted from the parent namespace).
    assert os.environ.get("GYRO_IN_NETNS") == "1"
    assert [name for _, name in socket.if_nameindex()] == ["lo"]
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        with pytest.raises(OSError):
            s.connect(("192.0.2.1", 9))       # TEST-NET-1: no route exists outside loopback
