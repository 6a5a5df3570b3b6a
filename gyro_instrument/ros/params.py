"""Node parameters: one table per node (name, type, default, description, range, read-only), used
to declare them with a ``ParameterDescriptor``, to check values (start-up overrides and later
changes alike), to print ``--help`` and to write ``msg_docs/parameters.md``.

The checks are what ROS users expect of a node run one by one:

* an integer is accepted where a double is declared (``-p duration_s:=60``, ``duration_s: 60`` in a
  params file, ``ros2 param set ... duration_s 60``);
* a wrong type or a value out of range is refused with a logged reason naming the field, the value
  and the valid range, and the node stays up (at start-up the default is kept and the node waits
  for a valid value when the value was needed to run);
* every parameter has a value (an empty string array included), so ``ros2 param dump`` is
  complete; a parameter whose change cannot take effect is declared read-only.
"""

import difflib
import math
from collections.abc import Callable
from dataclasses import dataclass

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, ParameterType
from rclpy.parameter import Parameter

from gyro_instrument.instruments import simulator_kinds

_TYPES = {
    "double": (Parameter.Type.DOUBLE, ParameterType.PARAMETER_DOUBLE),
    "int": (Parameter.Type.INTEGER, ParameterType.PARAMETER_INTEGER),
    "bool": (Parameter.Type.BOOL, ParameterType.PARAMETER_BOOL),
    "string": (Parameter.Type.STRING, ParameterType.PARAMETER_STRING),
    "string[]": (Parameter.Type.STRING_ARRAY, ParameterType.PARAMETER_STRING_ARRAY),
}
_ARRAYS = (Parameter.Type.BYTE_ARRAY, Parameter.Type.BOOL_ARRAY, Parameter.Type.INTEGER_ARRAY,
           Parameter.Type.DOUBLE_ARRAY, Parameter.Type.STRING_ARRAY)
INT32_MAX = 2 ** 31 - 1


@dataclass(frozen=True)
class Spec:
    """One node parameter.

    Parameters
    ----------
    name : str
    type : str
        ``double``, ``int``, ``bool``, ``string`` or ``string[]``.
    default
        The declared value (never unset).
    description : str
        Shown by ``ros2 param describe`` and ``--help``.
    lo, hi : float or int, optional
        Inclusive range of a number (a ``FloatingPointRange`` / ``IntegerRange``).
    read_only : bool
        True where a change after start-up cannot take effect (refused by rclpy with that reason).
    """

    name: str
    type: str
    default: object
    description: str
    lo: object = None
    hi: object = None
    read_only: bool = False

    def range_text(self) -> str:
        if self.type in ("double", "int") and self.lo is not None:
            fmt = (lambda v: str(int(v))) if self.type == "int" else (lambda v: f"{v:g}")
            return f"[{fmt(self.lo)}, {fmt(self.hi)}]"
        return {"bool": "true or false", "string": "a string", "string[]": "a list of strings"}.get(self.type, "")

    def descriptor(self) -> ParameterDescriptor:
        d = ParameterDescriptor(name=self.name, type=_TYPES[self.type][1], description=self.description,
                                read_only=self.read_only)
        if self.lo is not None and self.type == "double":
            d.floating_point_range = [FloatingPointRange(from_value=float(self.lo), to_value=float(self.hi), step=0.0)]
        elif self.lo is not None and self.type == "int":
            d.integer_range = [IntegerRange(from_value=int(self.lo), to_value=int(self.hi), step=1)]
        d.additional_constraints = f"valid: {self.range_text()}"
        return d

    def parameter(self, value=None) -> Parameter:
        """A typed ``Parameter`` (also for an empty string array)."""
        return Parameter(self.name, _TYPES[self.type][0], self.default if value is None else value)

    def check(self, param) -> tuple:
        """(converted Parameter, None) when ``param`` is valid, else (None, reason)."""
        t, v = param.type_, param.value
        want = _TYPES[self.type][0]
        bad = f"{self.name} = {v!r} is invalid: must be {self._must()}"
        if self.type == "double" and t == Parameter.Type.INTEGER:
            v, t = float(v), want
        # an empty array carries no element type: `overrides: []` in a params file (what `ros2 param
        # dump` writes) and -p "overrides:=[]" arrive as NOT_SET / None, `ros2 param set ... "[]"` as
        # another array type; all of them are the empty list
        if self.type == "string[]" and (t == Parameter.Type.NOT_SET or (t in _ARRAYS and len(v) == 0)):
            v, t = [], want
        if t != want:
            return None, bad
        if self.type == "double" and not math.isfinite(v):
            return None, bad
        if self.lo is not None and not (self.lo <= v <= self.hi):
            return None, bad
        return Parameter(self.name, want, list(v) if self.type == "string[]" else v), None

    def _must(self):
        kind = {"double": "a number (an integer is accepted)", "int": "an integer", "bool": "a boolean",
                "string": "a string", "string[]": "a list of strings"}[self.type]
        return f"{kind} in {self.range_text()}" if self.lo is not None else kind


SCENE = [
    Spec("scene", "string", "quet_paris", "shipped scene name or scene YAML path (gyro-instrument scenes)"),
    Spec("overrides", "string[]", [], "key.path=value scene overrides, as --set (e.g. ['site.latitude_deg=-33.87', "
                                      "'seed=7']; =null removes an effect or instrument)"),
    Spec("duration_s", "double", 0.0, "simulated time in s; 0 keeps the scene's", 0.0, 1.0e7),
]
SCENE_NAMES = tuple(s.name for s in SCENE)
WAIT = [
    Spec("wait_timeout_s", "double", 10.0, "longest wait (wall time, s) for the subscribers named in wait_for "
                                           "before sim time starts; then it starts anyway with a warning", 0.0, 3600.0,
         read_only=True),
]
#: frames and stamps (issue 37): every node that names a frame or stamps a message
FRAMES = [
    Spec("frame_prefix", "string", "", "put before every frame id this node publishes (robot_state_publisher's "
                                       "convention, e.g. 'ship1/': two suites with the same frames side by side); "
                                       "letters, digits, '_' and '/', not starting with '/'", read_only=True),
    Spec("stamp_epoch", "string", "", "the stamp of sim time 0: an ISO 8601 date-time (no zone: UTC), 'wall' (the "
                                      "clock owner's wall clock when sim time starts; real_time_factor 1 only; the "
                                      "other nodes take it from the first stamp they receive), or '' for the "
                                      "simulation epoch 2001-09-09T01:46:40Z", read_only=True),
]
SIMULATOR = SCENE + FRAMES + [
    Spec("real_time_factor", "double", 1.0, "1: paced to the wall clock, 0: as fast as possible (RELIABLE / "
                                            "KEEP_ALL: nothing dropped); applies at once", 0.0, 1000.0),
    Spec("publish_clock", "bool", False, "true: this node owns clock (/clock in the root namespace) and drives sim "
                                         "time; false: it follows the clock another node publishes (one owner per "
                                         "namespace)", read_only=True),
    Spec("seed", "int", -1, "measurement-noise seed, -1: the scene's (a change restarts the run)", -1, INT32_MAX),
    Spec("window_s", "double", 10.0, "simulated seconds integrated per block: the node publishes a block before "
                                     "it integrates the next, so memory is one block whatever duration_s",
         1.0e-3, 1.0e6, read_only=True),
    Spec("wait_for", "string[]", ["estimator", "recorder"],
         "nodes (same namespace) whose subscriptions to this node's topics must be matched before sim time starts; "
         "the clock owner also waits for the scene's other simulators", read_only=True),
] + WAIT
ESTIMATOR = SCENE + FRAMES + [
    Spec("input_timeout_s", "double", 5.0, "wall time (s) without a joint sample or clock tick after input began "
                                           "(or after the clock reached the run's end) before the estimator "
                                           "publishes an estimate from what it has, with a WARN and a WARN "
                                           "diagnostic status", 0.1, 86400.0),
    Spec("publish_period_s", "double", 0.0, "also publish the estimate every this many s of wall time; 0: once, "
                                            "when every expected sample (or the last clock tick) has arrived",
         0.0, 86400.0, read_only=True),
    Spec("nmea_udp", "string", "", "HOST:PORT ([IPV6]:PORT) to send NMEA 0183 $HEHDT true-heading sentences to, one "
                                   "UDP datagram per heading published (the first horizontal gyroscope's or rate "
                                   "gyro's mount azimuth: at 10 Hz of sim time, every sample when slower, from the "
                                   "first swing or sequence of positions, and with the final estimate); empty: none. "
                                   "IANA's port for NMEA over UDP is 10110", read_only=True),
    Spec("nmea_decimals", "int", 3, "decimals of the $HEHDT heading in degrees (3: 0.001 deg = 3.6 arcsec)", 0, 6,
         read_only=True),
]
#: the ship's gyrocompass's node (issue 39 item 5): a simulator that also sends its heading as NMEA
COMPASS_NODE = "marine_gyrocompass"
COMPASS = SIMULATOR + [
    Spec("nmea_udp", "string", "", "HOST:PORT ([IPV6]:PORT) to send NMEA 0183 $HEHDT true-heading sentences to, one "
                                   "UDP datagram each: the first marine gyrocompass's heading reading at 10 Hz of sim "
                                   "time (every sample when it samples slower); empty: none. IANA's port for NMEA "
                                   "over UDP is 10110", read_only=True),
    Spec("nmea_decimals", "int", 1, "decimals of the $HEHDT heading in degrees (1: 0.1 deg, as ship's gyrocompasses "
                                    "send it)", 0, 6, read_only=True),
]
#: The recorder's parameters that may be set until its recording starts (a value refused at start-up
#: corrected at runtime starts it), and are refused once it records (a recording has one scene and
#: one file).
RECORDING_FIXED = " (fixed once recording starts: a recording has one scene and one file)"
RECORDING_FIXED_NAMES = SCENE_NAMES + ("output", "overwrite", "format", "max_bag_size", "max_bag_duration", "topics")
RECORDER = [Spec(s.name, s.type, s.default, s.description + RECORDING_FIXED, s.lo, s.hi) for s in SCENE] + [
    Spec("output", "string", "", ".mcap path to record to (refused if its directory is missing or not writable, "
                                 "if it is the scene file, or if it exists and overwrite is false)" + RECORDING_FIXED),
    Spec("overwrite", "bool", False, "replace an existing output file" + RECORDING_FIXED),
    Spec("format", "string", "", "mcap: one bare .mcap file; rosbag2: a bag directory (metadata.yaml + "
                                 "<dir>_0.mcap ...); empty: rosbag2 when output ends in '/' or splitting is asked "
                                 "for, else mcap" + RECORDING_FIXED),
    Spec("max_bag_size", "int", 0, "rosbag2 layout: start a new .mcap file at this many bytes (0: no limit; "
                                   "else at least 1 MiB = 1048576, the floor)" + RECORDING_FIXED, 0, 2 ** 62),
    Spec("max_bag_duration", "double", 0.0, "rosbag2 layout: start a new .mcap file when the current one spans "
                                            "this many s of log time (0: no limit; else at least 1 s, the floor)"
                                            + RECORDING_FIXED, 0.0, 1.0e9),
    Spec("topics", "string[]", [], "topics to record (relative names, e.g. 'pendulum/joint_states'); empty: every "
                                   "topic of the scene" + RECORDING_FIXED),
    Spec("command", "string", "recorder node", "command line stored in the bag's metadata", read_only=True),
    Spec("stop_when_complete", "bool", False, "finish the file and exit once every expected message is recorded "
                                              "(every sample of every topic, one estimate)", read_only=True),
] + FRAMES
PLAYER = [
    Spec("bag", "string", "", ".mcap file or rosbag2 bag directory to play (every chunk's CRC checked)",
         read_only=True),
    Spec("real_time_factor", "double", 1.0, "1: recorded pace, 0: as fast as possible (RELIABLE / KEEP_ALL: "
                                            "nothing dropped)", 0.0, 1000.0),
    Spec("loop", "bool", False, "start again at the end instead of exiting"),
    Spec("wait_for", "string[]", [], "nodes (same namespace) that must subscribe to one of the bag's topics before "
                                     "playing", read_only=True),
    Spec("min_subscribers", "int", 1, "subscriptions that must be matched on the bag's topics other than the "
                                      "clock (every sim-time node subscribes to it) before playing", 0, 1000,
         read_only=True),
    Spec("wait_topics", "string[]", [], "topics of the bag (relative names; '*': every one) that must each have a "
                                        "matched subscription before playing", read_only=True),
] + WAIT

class _NodeSpecs(dict):
    """Node name -> its parameters; a simulator node an instrument type registered later names
    (``SIMULATOR_NODE``) has the simulators' parameters too."""

    def __missing__(self, name):
        if name == COMPASS_NODE:
            return COMPASS
        if name in simulator_kinds():
            return SIMULATOR
        raise KeyError(name)


#: node name -> its parameters: every simulator node the instrument types name (``SIMULATOR_NODE``),
#: then the estimator, the recorder and the player
NODE_SPECS = _NodeSpecs({**{sim: SIMULATOR for sim in simulator_kinds()}, COMPASS_NODE: COMPASS,
                         "estimator": ESTIMATOR, "recorder": RECORDER, "player": PLAYER})
#: parameters rclpy (or the RMW) declares itself; not reported as unknown
BUILTIN = ("use_sim_time", "start_type_description_service")


def unknown_parameter_message(name, specs, node_name, value=None) -> str:
    """Log text for an override (or a set) that names no parameter of this node, with its value."""
    names = [s.name for s in specs]
    hint = difflib.get_close_matches(name, names, n=1)
    if hint:
        tip = f"did you mean {hint[0]}?"
    elif "." in name or name.endswith(("_deg", "_m", "_s", "_hz", "_rad_s")):
        tip = f"scene values go in overrides, e.g. -p \"overrides:=['site.{name}=...']\""
    else:
        tip = f"valid: {', '.join(names)}"
    shown = f" = {value!r}" if value is not None else ""
    return f"parameter {name}{shown} is not a parameter of {node_name} and is ignored: {tip}"


def declare_all(node, specs) -> dict:
    """Declare ``specs`` on ``node`` with descriptors; start-up overrides are checked first (an integer
    for a double converted; a bad one logged, dropped for the default and returned).

    Returns
    -------
    dict
        name -> reason of each refused start-up value.
    """
    refused = {}
    overrides = node._parameter_overrides
    for spec in specs:
        if node.has_parameter(spec.name):
            continue
        value = None
        if spec.name in overrides:
            param, reason = spec.check(overrides[spec.name])
            if param is None:
                refused[spec.name] = reason
                node.get_logger().error(f"parameter refused at start-up: {reason}; keeping the default "
                                        f"{spec.default!r}")
            else:
                value = param.value
        # declared with an explicit type (an empty string array included) and its descriptor
        node._declare_parameter_common([spec.parameter(value)], {spec.name: spec.descriptor()})
    known = {s.name for s in specs}
    for name in overrides:
        if name not in known and name not in BUILTIN and not name.startswith("qos_overrides."):
            node.get_logger().warning(unknown_parameter_message(name, specs, node.get_name(), overrides[name].value))
    return refused


def pre_set_checker(node, specs) -> Callable:
    """A pre-set callback: converts an integer for a double, logs every value that will be refused
    (wrong type, out of range, read-only) with its reason."""
    by_name = {s.name: s for s in specs}

    def pre_set(params):
        out = []
        for p in params:
            spec = by_name.get(p.name)
            if spec is None:
                if p.name not in BUILTIN and not node.has_parameter(p.name):
                    node.get_logger().error(unknown_parameter_message(p.name, specs, node.get_name(), p.value))
                out.append(p)
                continue
            if spec.read_only:
                node.get_logger().error(f"parameter refused: {p.name} is read-only (a change cannot take effect "
                                        f"after start-up; restart the node with the new value)")
                out.append(p)
                continue
            conv, reason = spec.check(p)
            if conv is None:
                node.get_logger().error(f"parameter refused: {reason}")
                out.append(p)
            else:
                out.append(conv)
        return out
    return pre_set


def help_text(node_name, summary, specs, topics, example) -> str:
    """``--help`` of a node executable."""
    lines = [f"usage: {node_name} [--help] [--ros-args ...]", "", summary, "", "parameters (-p NAME:=VALUE, or "
             "--params-file FILE):"]
    for s in specs:
        ro = ", read-only" if s.read_only else ""
        rng = f", {s.range_text()}" if s.lo is not None else ""
        lines.append(f"  {s.name} ({s.type}, default {s.default!r}{rng}{ro})")
        lines.append(f"      {s.description}")
    lines.append("  use_sim_time (bool, default False) rclpy's; refused on a clock owner")
    lines += ["", "topics (relative: -r __ns:=/ship1 moves them all):"] + [f"  {t}" for t in topics]
    lines += ["", "example:", f"  {example}", "", "docs: msg_docs/parameters.md, msg_docs/topics.md"]
    return "\n".join(lines)
