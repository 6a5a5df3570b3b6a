"""The topics of a scene, in one registry: name -> ROS type (documented in msg_docs/topics.md), and
what each instrument publishes (:func:`publications`, the one place that reads an instrument's
published-stream flags).

Every name is relative, so ``-r __ns:=/ship1`` (or ``--namespace``) moves a node's topics and
remapping works; in the root namespace ``clock`` is ``/clock``, which rclpy's sim time listens to.
No rclpy here: the recorder, the player, replay, the bench and the views read the same names.
"""

from dataclasses import dataclass


CLOCK = "clock"
CLOCK_TYPE = "rosgraph_msgs/msg/Clock"
DIAGNOSTICS = "diagnostics"
ESTIMATOR_TOPICS = {
    "estimator/latitude_rad": "std_msgs/msg/Float64",
    "estimator/latitude_sigma_rad": "std_msgs/msg/Float64",
    "estimator/earth_rate_rad_s": "std_msgs/msg/Float64",
    "estimator/earth_rate_sigma_rad_s": "std_msgs/msg/Float64",
    "estimator/earth_rate_enu": "geometry_msgs/msg/Vector3Stamped",
    DIAGNOSTICS: "diagnostic_msgs/msg/DiagnosticArray",
}

#: the last part of an instrument's topics, ``<instrument>/<suffix>``
HEADING = "heading"
HEADING_NED = "heading_ned"
JOINT_STATES = "joint_states"
BOB_POSITION = "bob_position"
CONTACT_POINT = "contact_point"
SWING_PLANE = "swing_plane"
AXIS_DIRECTION = "axis_direction"
MARKERS = "markers"

JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
POINT_TYPE = "geometry_msgs/msg/PointStamped"
VECTOR_TYPE = "geometry_msgs/msg/Vector3Stamped"
MARKER_TYPE = "visualization_msgs/msg/MarkerArray"
IMU_TYPE = "sensor_msgs/msg/Imu"

#: frame of ENU vectors at the site (REP-105 'map'-like local frame)
SITE_FRAME = "site_enu"

#: swing plane, axis direction and markers are published once per this much sim time (the markers
#: with a trail of TRAIL of them)
VISUAL_PERIOD_S = 1.0
TRAIL = 30


def visual_every(sample_rate_hz) -> int:
    """Samples between two visual messages (:data:`VISUAL_PERIOD_S`; at least 1)."""
    return max(int(round(VISUAL_PERIOD_S * sample_rate_hz)), 1)


def instrument_topic(instrument, suffix) -> str:
    """``<instrument>/<suffix>``, relative."""
    return f"{instrument}/{suffix}"


def joint_topic(instrument) -> str:
    return instrument_topic(instrument, JOINT_STATES)


def is_joint_topic(topic) -> bool:
    """True for ``[/<namespace>]/<instrument>/joint_states``."""
    return topic.endswith("/" + JOINT_STATES)


def instrument_of(topic) -> str:
    """Instrument name of a ``[/<namespace>]/<instrument>/<suffix>`` topic (the inverse of
    :func:`instrument_topic`)."""
    parts = topic.strip("/").split("/")
    return parts[-2] if len(parts) >= 2 else parts[0]


@dataclass(frozen=True)
class Publication:
    """One stream an instrument publishes.

    Parameters
    ----------
    key : str
        Its name within the instrument (``joints``, ``bob``, ``contact``, ``plane``, ``axis``,
        ``markers``): what the simulator's output is keyed by.
    topic : str
        Relative topic name.
    type_name : str
        ``pkg/msg/Type``.
    names : tuple of str
        JointState joint names (empty for other types).
    frame_id : str
        Header frame of a PointStamped / Vector3Stamped ('' otherwise).
    sparse : bool
        Published once per :data:`VISUAL_PERIOD_S` of sim time, not per sample.
    """

    key: str
    topic: str
    type_name: str
    names: tuple = ()
    frame_id: str = ""
    sparse: bool = False


def publications(name, inst) -> list:
    """What instrument ``inst`` (named ``name`` in the scene) publishes, in publishing order.

    The one place outside ``instruments/`` that turns what an instrument declares about its
    published streams into topics: the joints of its observation's layout
    (``OBSERVATION.layout_of``), a bob position when the observation has a bob
    (``OBSERVATION.SHOWS_BOB_POSITION``), ``SHOWS_AXIS``, ``SHOWS_CONTACT_POINT`` and ``SHOWS_HEADING`` (a
    compass's heading Imu, and its NED twin when the instrument's ``ned_heading`` is true; a class lists both). The simulator
    node, the recorder, the suite, ``--help`` and the docs take the topics from here. ``inst`` may be
    the instrument or its class.
    """
    def topic(suffix):
        return instrument_topic(name, suffix)
    cls = inst if isinstance(inst, type) else type(inst)
    bob = cls.OBSERVATION.SHOWS_BOB_POSITION
    layout = cls.OBSERVATION.layout_of(cls)
    out = [Publication("joints", topic(JOINT_STATES), JOINT_STATE_TYPE, tuple(f"{name}/{j}" for j in layout.names))]
    if bob:
        out.append(Publication("bob", topic(BOB_POSITION), POINT_TYPE, frame_id=f"{name}_pivot"))
    if inst.SHOWS_CONTACT_POINT:
        out.append(Publication("contact", topic(CONTACT_POINT), POINT_TYPE, frame_id=f"{name}_body"))
    if getattr(cls, "SHOWS_HEADING", False):          # a compass's own heading (the marine gyrocompass)
        out.append(Publication("heading", heading_topic(name), IMU_TYPE, frame_id=compass_frame(name)))
        if isinstance(inst, type) or getattr(inst.p, "ned_heading", False):
            out.append(Publication("heading_ned", topic(HEADING_NED), IMU_TYPE,
                                   frame_id=compass_frame(name, ned=True)))
    visual = []
    if bob:
        visual.append(Publication("plane", topic(SWING_PLANE), JOINT_STATE_TYPE, (f"{name}/swing_plane_azimuth",),
                                  sparse=True))
    if inst.SHOWS_AXIS:
        visual.append(Publication("axis", topic(AXIS_DIRECTION), VECTOR_TYPE, frame_id=SITE_FRAME, sparse=True))
    if visual:
        visual.append(Publication("markers", topic(MARKERS), MARKER_TYPE, sparse=True))
    return out + visual


def joint_names(name, inst) -> tuple:
    """The JointState joint names ``<name>/<joint>`` instrument ``inst`` publishes (and the estimator reads)."""
    return publications(name, inst)[0].names


def scene_publications(insts) -> list:
    """Every instrument publication of the scene, in scene order."""
    return [p for name, inst in insts.items() for p in publications(name, inst)]


def heading_topic(instrument) -> str:
    """``<instrument>/heading``: the estimator's ``sensor_msgs/Imu`` of a horizontal gyroscope's
    reference direction (msg_docs/topics.md)."""
    return instrument_topic(instrument, HEADING)


def heading_frame(instrument) -> str:
    """Header frame of an instrument's heading: its body frame, x along the scale's zero, y left, z up."""
    return f"{instrument}_scale"


def compass_frame(instrument, ned=False) -> str:
    """Header frame of a compass's own heading (``SHOWS_HEADING``): the ship's body frame at the
    compass, ``<instrument>_body`` (x forward, y to port, z up; it moves with the ship), or its NED
    twin ``<instrument>_body_ned`` (x forward, y starboard, z down: REP-103's ``_ned`` suffix)."""
    return f"{instrument}_body" + ("_ned" if ned else "")


def live_kinds(inst) -> list:
    """The measurement kinds of the instrument ``inst`` that the estimator publishes live (their
    ``LIVE``: ``heading``), registered ones only; needs the instrument, not its class."""
    from gyro_instrument.instruments.measurement import declared_kinds, kind
    if isinstance(inst, type):
        return []
    found = [kind(k) for k in declared_kinds(inst.observation())]
    return [k for k in found if k is not None and k.LIVE is not None]


def measures_azimuth(inst) -> bool:
    """True when the instrument's observation measures a heading the estimator publishes (a kind whose
    ``LIVE`` is ``heading``: a horizontal gyroscope with its rotor on); needs the instrument, not its class."""
    return any(k.LIVE == "heading" for k in live_kinds(inst))


def estimator_topics(insts) -> dict:
    """The estimator's topics for these instruments, with their types: :data:`ESTIMATOR_TOPICS` and
    the heading of every instrument that measures one (:func:`heading_topic`)."""
    out = dict(ESTIMATOR_TOPICS)
    out.update({heading_topic(name): IMU_TYPE for name, inst in insts.items() if measures_azimuth(inst)})
    return out


def scene_topics(insts) -> dict:
    """All topics the suite publishes for these instruments, with their types: the clock, the
    instruments' (:func:`publications`), the estimator's (:func:`estimator_topics`)."""
    out = {CLOCK: CLOCK_TYPE}
    out.update({p.topic: p.type_name for p in scene_publications(insts)})
    out.update(estimator_topics(insts))
    return out


def sparse_topics(insts) -> set:
    """The relative topics published once per :data:`VISUAL_PERIOD_S`, not per sample."""
    return {p.topic for p in scene_publications(insts) if p.sparse}


def resolve(namespace, topic) -> str:
    """Fully qualified name of a relative ``topic`` in ``namespace``."""
    if topic.startswith("/"):
        return topic
    return "/" + "/".join(p for p in (namespace.strip("/"), topic) if p)
