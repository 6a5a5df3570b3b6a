"""Write msg_docs/parameters.md, every node parameter with its descriptor, from the tables in
gyro_instrument/ros/params.py (kept true by tests/test_docs.py: run `python tools/gen_param_docs.py`
after changing a parameter)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gyro_instrument.ros.params import NODE_SPECS  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "msg_docs" / "parameters.md"

HEAD = """# Node parameters

Generated from `gyro_instrument/ros/params.py` by `tools/gen_param_docs.py`; every node prints the
same table with `--help`, and `ros2 param describe` shows each descriptor (description, range,
read-only). Every node takes the scene the same way as the command line (`gyro-instrument … SCENE
--set K=V --duration-s S`): one definition, two front ends.

How values are checked (at start-up from `-p`/`--params-file`, and on every `ros2 param set`):

* an integer is accepted where a double is declared (`-p duration_s:=60`, `duration_s: 60` in a
  params file, `ros2 param set /pendulum_sim duration_s 60`);
* a wrong type or a value out of range is refused with a logged error naming the field, the value
  and the valid range (`seed = 7.5 is invalid: must be an integer in [-1, 2147483647]`); the node
  stays up. At start-up the default is kept and, when the value was needed to run (`scene`,
  `overrides`, `duration_s`, `seed`), the node waits idle until a valid value is set;
* scene values (`site.latitude_deg`, …) go in `overrides`; an unknown parameter
  (`-p latitude_deg:=48`, or a name in a `ros2 param load` file) is reported as ignored, with its
  value and the fix (`parameter latitude_deg = 48 is not a parameter of pendulum_sim and is ignored:
  ...`), and the node keeps running;
* a set that changes no value (`ros2 param set` of the current value, `ros2 param load` of an
  unchanged dump) changes nothing: logged (`parameters set to the values they had: seed; nothing
  changes`), no restart, no new file;
* every parameter has a value, an empty list included, so `ros2 param dump` is complete;
* a read-only parameter (its change cannot take effect after start-up) is refused by rclpy with
  "Trying to set a read-only parameter" and logged; a real change of `scene`, `overrides`,
  `duration_s` (or a simulator's `seed`) is applied and restarts the whole run together: on the
  clock owner it rewinds to t = 0 (its clock goes back to the epoch) and every follower rewinds
  when it sees the clock go back, each with its own current values; on a follower the change
  asks the owner to restart (its service `~/restart`, `std_srvs/srv/Trigger`) and the follower
  takes its new values when the clock goes back. The recorder starts one new file for the new
  run (every topic's stamps go back together), the estimator a new estimate. (A node whose topics
  change with the scene, or with no clock owner, tears down and waits for its subscribers again.)
  On the recorder these parameters are fixed once it records: set them on the simulators and the
  estimator;
* `use_sim_time` is rclpy's; on a clock owner (a simulator with `publish_clock:=true`, the
  player) `true` is refused with a logged reason: the node would wait for its own clock.

"""

TAIL = """
## Clock, waiting and completeness

One node owns `clock` in a namespace (`/clock` in the root namespace): the simulator started
with `publish_clock:=true` (or the player). Every other simulator follows it: it publishes each
sample when the owner's clock reaches the sample's time, so separate simulators share one time
line. Before sim time starts a simulator waits (at most `wait_timeout_s`, logged) until the
nodes in `wait_for` subscribe to its topics (the recorder: every topic it records, its subscriptions
unchanged for 0.3 s as the graph shows them one by one; the estimator: the
joint states of the instruments it reads, the estimable ones and a gyroscope's rotor-off swing;
any other name: one of its topics) and every subscription the graph knows of is matched; the clock owner also waits for the scene's other
simulators, which subscribe to the clock once their own subscribers are matched, and an owner listens for another owner's ticks until its
watch has matched every other publisher of the clock (0.3 s more) before it decides. Publishers
are RELIABLE / KEEP_ALL when run alone, so at real-time factor 0 a slow subscriber delays the
data but loses none.

The recorder knows what the scene publishes (every sample on `clock` and the instruments'
topics, at least one estimate on each estimator topic) and writes its status record
`gyro_instrument_status` with `state` `complete` or `incomplete`, `topics` = {topic:
[recorded, expected]} and `late` (messages that arrived after later stamps had been written;
they carry that later log time). Log time is sim time: the message stamp, or for the estimator's
`Float64` topics the latest stamp received; messages are written in log-time order.

## The separate-node route with a params file

```yaml
recorder:
  ros__parameters: {scene: quet_paris, duration_s: 60.0, output: out/quet_paris.mcap, stop_when_complete: true}
estimator:
  ros__parameters: {scene: quet_paris, duration_s: 60.0}
gyrocompass_sim:
  ros__parameters: {scene: quet_paris, duration_s: 60.0, real_time_factor: 0.0, publish_clock: true}
pendulum_sim:
  ros__parameters: {scene: quet_paris, duration_s: 60.0, real_time_factor: 0.0}
```

Each node: `ros2 run gyro_instrument <node> --ros-args --params-file params.yaml` (add
`-r __ns:=/ship1` to run a second suite beside the first; key the sections `/**/<node>` then).
`gyro_instrument.ros.launch.launch()` starts them this way (`tests/test_ros_nodes.py`).
"""


def _cell(v):
    return "`" + repr(v).replace("'", "\"") + "`" if not isinstance(v, bool) else f"`{str(v).lower()}`"


def render():
    out = [HEAD]
    done = {}
    for node, specs in NODE_SPECS.items():
        key = id(specs)
        if key in done:
            continue
        same = [n for n, s in NODE_SPECS.items() if s is specs]
        done[key] = same
        out.append("## " + ", ".join(f"`{n}`" for n in same) + "\n")
        out.append("| parameter | type | default | range | read-only | description |")
        out.append("|---|---|---|---|---|---|")
        for s in specs:
            rng = s.range_text() if s.lo is not None else ""
            out.append(f"| `{s.name}` | {s.type} | {_cell(s.default)} | {rng} | {'yes' if s.read_only else ''} | "
                       f"{s.description} |")
        out.append("")
    out.append(TAIL)
    return "\n".join(out)


if __name__ == "__main__":
    OUT.write_text(render())
    print(f"wrote {OUT}")
