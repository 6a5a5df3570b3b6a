"""gyro_instrument: a gyrocompass and Foucault pendulum on the rotating Earth.

The simulation core (``core``, ``effects``, ``instruments``) is pure numpy/scipy and never
imports rclpy; ``gyro_instrument.ros`` holds the thin ROS 2 nodes over it.
"""

__version__ = "0.1.0"
