"""Thin ROS 2 nodes over the core, one module per node: parameters in, one core call, messages out.

* :mod:`.simulator` (``gyrocompass_sim``, ``pendulum_sim``, ``top_sim``): :class:`SimulatorNode`
  publishes what :class:`~gyro_instrument.recording.sim_stream.SimulatorStream` encodes.
* :mod:`.estimator`: :class:`EstimatorNode` keeps the joint samples and calls the core estimator.
* :mod:`.recorder`: :class:`RecorderNode`, raw CDR to MCAP in rosbag2's layout.
* :mod:`.player`: :class:`PlayerNode`, a bag streamed back to DDS.

Topic names are relative (``-r __ns:=/ship1`` moves them) and come from
:mod:`gyro_instrument.recording.topics`. Every parameter is declared with a descriptor
(:mod:`gyro_instrument.ros.params`); a bad value is logged with the field, the value and the valid
range, the change is refused, and the node stays up.
"""

from gyro_instrument.recording.joint_buffer import JointBuffer
from gyro_instrument.ros.nodes.base import (FLOW_BATCH, LATCHED, PUBLISH_ALL, RELIABLE_1000, RELIABLE_ALL, STEADY,
                                            SceneNode)
from gyro_instrument.ros.nodes.estimator import EstimatorNode
from gyro_instrument.ros.nodes.player import PlayerNode
from gyro_instrument.ros.nodes.recorder import RecorderNode
from gyro_instrument.ros.nodes.simulator import SimulatorNode

__all__ = ["FLOW_BATCH", "LATCHED", "PUBLISH_ALL", "RELIABLE_1000", "RELIABLE_ALL", "STEADY", "EstimatorNode",
           "JointBuffer", "PlayerNode", "RecorderNode", "SceneNode", "SimulatorNode"]
