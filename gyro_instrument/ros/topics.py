"""The topics of a scene: name -> ROS type (documented in msg_docs/topics.md)."""

CLOCK = "/clock"
ESTIMATOR_TOPICS = {
    "/estimator/latitude_rad": "std_msgs/msg/Float64",
    "/estimator/latitude_sigma_rad": "std_msgs/msg/Float64",
    "/estimator/earth_rate_rad_s": "std_msgs/msg/Float64",
    "/estimator/earth_rate_sigma_rad_s": "std_msgs/msg/Float64",
    "/estimator/earth_rate_enu": "geometry_msgs/msg/Vector3Stamped",
    "/diagnostics": "diagnostic_msgs/msg/DiagnosticArray",
}


def joint_topic(instrument):
    return f"/{instrument}/joint_states"


def bob_topic(instrument):
    return f"/{instrument}/bob_position"


def scene_topics(insts):
    """All topics the suite publishes for these instruments, with their types."""
    out = {CLOCK: "rosgraph_msgs/msg/Clock"}
    for name, inst in insts.items():
        out[joint_topic(name)] = "sensor_msgs/msg/JointState"
        if inst.IS_PENDULUM:
            out[bob_topic(name)] = "geometry_msgs/msg/PointStamped"
    out.update(ESTIMATOR_TOPICS)
    return out
