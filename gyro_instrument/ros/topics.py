"""The topics of a scene: name -> ROS type (documented in msg_docs/topics.md).

Every name is relative, so ``-r __ns:=/ship1`` (or ``--namespace``) moves a node's topics and
remapping works; in the root namespace ``clock`` is ``/clock``, which rclpy's sim time listens to.
"""

CLOCK = "clock"
ESTIMATOR_TOPICS = {
    "estimator/latitude_rad": "std_msgs/msg/Float64",
    "estimator/latitude_sigma_rad": "std_msgs/msg/Float64",
    "estimator/earth_rate_rad_s": "std_msgs/msg/Float64",
    "estimator/earth_rate_sigma_rad_s": "std_msgs/msg/Float64",
    "estimator/earth_rate_enu": "geometry_msgs/msg/Vector3Stamped",
    "diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
}


def joint_topic(instrument) -> str:
    return f"{instrument}/joint_states"


def bob_topic(instrument) -> str:
    return f"{instrument}/bob_position"


#: swing plane, axis direction and markers are published once per this much sim time (the markers
#: with a trail of TRAIL of them)
VISUAL_PERIOD_S = 1.0
TRAIL = 30


def visual_every(sample_rate_hz) -> int:
    """Samples between two visual messages (:data:`VISUAL_PERIOD_S`; at least 1)."""
    return max(int(round(VISUAL_PERIOD_S * sample_rate_hz)), 1)


def contact_point_topic(instrument) -> str:
    return f"{instrument}/contact_point"


def swing_plane_topic(instrument) -> str:
    return f"{instrument}/swing_plane"


def axis_topic(instrument) -> str:
    return f"{instrument}/axis_direction"


def markers_topic(instrument) -> str:
    return f"{instrument}/markers"


def visual_topics(name, inst) -> dict:
    """The topics to look at for one instrument, with their types."""
    out = {}
    if inst.IS_PENDULUM:
        out[swing_plane_topic(name)] = "sensor_msgs/msg/JointState"
    if inst.SHOWS_AXIS:
        out[axis_topic(name)] = "geometry_msgs/msg/Vector3Stamped"
    if out:
        out[markers_topic(name)] = "visualization_msgs/msg/MarkerArray"
    return out


def scene_topics(insts) -> dict:
    """All topics the suite publishes for these instruments, with their types."""
    out = {CLOCK: "rosgraph_msgs/msg/Clock"}
    for name, inst in insts.items():
        out[joint_topic(name)] = "sensor_msgs/msg/JointState"
        if inst.IS_PENDULUM:
            out[bob_topic(name)] = "geometry_msgs/msg/PointStamped"
        if inst.SHOWS_CONTACT_POINT:
            out[contact_point_topic(name)] = "geometry_msgs/msg/PointStamped"
        out.update(visual_topics(name, inst))
    out.update(ESTIMATOR_TOPICS)
    return out


def resolve(namespace, topic) -> str:
    """Fully qualified name of a relative ``topic`` in ``namespace``."""
    if topic.startswith("/"):
        return topic
    return "/" + "/".join(p for p in (namespace.strip("/"), topic) if p)


def instrument_of(topic) -> str:
    """Instrument name of a ``.../<instrument>/joint_states`` (or ``bob_position``) topic."""
    parts = topic.strip("/").split("/")
    return parts[-2] if len(parts) >= 2 else parts[0]
