"""rclpy's own publish-and-receive ceiling on this machine (issue 37 item 6): what the separate-node
route is measured against.

Two processes, as two nodes run with ``ros2 run``: one publishes ``count`` pre-serialized
``sensor_msgs/JointState`` messages of the size the simulators publish (three joints, raw CDR,
RELIABLE / KEEP_ALL, waiting and retrying when the writer's history is full, as the simulators do),
the other takes them with the cheapest loop rclpy offers (one wait, then every waiting message
taken with ``take_message``, :func:`gyro_instrument.ros.nodes.base.drain`), both with the nodes' Fast DDS
profile (:mod:`gyro_instrument.ros.dds_profile`). The rate is messages
received per second of wall time from the first to the last received. Run on loopback
(``tools/loopback``): ``python -m gyro_instrument.ros.ceiling [count]`` prints one JSON line.
"""

import json
import os
import subprocess
import sys
import time

TOPIC = "ceiling/joint_states"


def _publisher(count) -> None:
    import rclpy
    from rclpy._rclpy_pybind11 import RCLError
    from gyro_instrument.recording.cdr import joint_state_layout
    from gyro_instrument.ros import messages as m
    from gyro_instrument.ros.nodes.base import RELIABLE_ALL
    rclpy.init()
    node = rclpy.create_node("ceiling_publisher")
    pub = node.create_publisher(m.JointState, TOPIC, RELIABLE_ALL)
    lay = joint_state_layout(("a/angle", "a/rate", "a/third"))
    import numpy as np
    t = np.arange(count, dtype=np.int64) * 50_000_000
    datas = lay.encode(t, np.zeros((count, 3)), np.zeros((count, 3)), np.zeros((count, 3)))
    while pub.get_subscription_count() < 1:
        time.sleep(0.01)
    time.sleep(0.5)
    with pub.handle:
        publish = pub.handle.publish_raw
        for data in datas:
            while True:
                try:
                    publish(data)
                    break
                except RCLError:
                    time.sleep(0.001)
    pub.wait_for_all_acked(rclpy.duration.Duration(seconds=30))
    node.destroy_node()
    rclpy.shutdown()


def _subscriber(count) -> dict:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from gyro_instrument.ros import messages as m
    from gyro_instrument.ros.nodes.base import RELIABLE_ALL, drain
    rclpy.init()
    node = rclpy.create_node("ceiling_subscriber")
    got = [0, None, None]

    def on(_data):
        if got[0] == 0:
            got[1] = time.perf_counter()
        got[0] += 1
        got[2] = time.perf_counter()
    node.create_subscription(m.JointState, TOPIC, on, RELIABLE_ALL, raw=True)
    ex = SingleThreadedExecutor()
    ex.add_node(node)
    cpu0 = time.process_time()
    deadline = time.monotonic() + 120
    while got[0] < count and time.monotonic() < deadline:
        ex.spin_once(timeout_sec=0.1)
        drain(node)
    cpu = time.process_time() - cpu0
    node.destroy_node()
    rclpy.shutdown()
    wall = (got[2] - got[1]) if got[0] > 1 else float("nan")
    return {"received": got[0], "sent": count, "wall_s": wall, "messages_per_s": (got[0] - 1) / wall,
            "subscriber_cpu_s": cpu}


def measure(count=60000) -> dict:
    """Publish ``count`` messages from a child process to this process's subscriber; the JSON dict
    of :func:`_subscriber` (``messages_per_s``: rclpy's ceiling for one publisher and one subscriber)."""
    from gyro_instrument.ros.dds_profile import use_package_profile
    use_package_profile()              # the nodes' Fast DDS timing, in both processes, so that they compare
    env = dict(os.environ)
    child = subprocess.Popen([sys.executable, "-c", f"from gyro_instrument.ros.ceiling import _publisher; "
                              f"_publisher({int(count)})"], env=env)
    try:
        return _subscriber(int(count))
    finally:
        child.wait(timeout=60)


if __name__ == "__main__":
    print(json.dumps(measure(int(sys.argv[1]) if len(sys.argv) > 1 else 60000)))
