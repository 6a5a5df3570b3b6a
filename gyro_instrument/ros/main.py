"""Entry points of the nodes (``ros2 run gyro_instrument <node>``), Jazzy ``main()`` pattern."""

import sys

import rclpy
from rclpy.executors import ExternalShutdownException

from gyro_instrument.ros.nodes import EstimatorNode, PlayerNode, RecorderNode, SimulatorNode
from gyro_instrument.instruments import simulator_kinds


def _spin(node, on_exit=None):
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if on_exit:
            on_exit()
        node.destroy_node()
        rclpy.try_shutdown()


def _simulator(name, args=None):
    rclpy.init(args=args)
    node = SimulatorNode(name, simulator_kinds().get(name, ()))
    node.start()
    _spin(node)


def gyrocompass_sim(args=None):
    _simulator("gyrocompass_sim", args)


def pendulum_sim(args=None):
    _simulator("pendulum_sim", args)


def top_sim(args=None):
    _simulator("top_sim", args)


def estimator(args=None):
    rclpy.init(args=args)
    node = EstimatorNode()
    if not node.has_parameter("publish_period_s") or node.get_parameter("publish_period_s").value <= 0:
        node.create_timer(10.0, node.finalize)
    _spin(node)


def recorder(args=None):
    rclpy.init(args=args)
    node = RecorderNode()
    _spin(node, on_exit=node.close)      # SIGINT finishes a complete, indexed MCAP


def player(args=None):
    rclpy.init(args=args)
    node = PlayerNode()
    node.start()
    _spin(node)


if __name__ == "__main__":
    sys.exit(estimator())
