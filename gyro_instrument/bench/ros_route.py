"""The route ROS users take, measured beside the one-process run (issue 37 item 6).

Three children, each on loopback like :func:`.work_precision.suite_real_time_factor` (discovery range
LOCALHOST and, as root, a loopback-only network namespace), one after the other:

* ``gyro-instrument run quet_paris`` (600 s at 20 Hz, real-time factor 0, recording): every node in
  one process, the lock-step suite; its real-time factor over its streaming loop (``--stats``);
* the same scene as separate processes, one per node, as ``ros2 run`` starts them
  (:func:`gyro_instrument.ros.launch.timed_launch`): the wall time from the clock owner's first tick
  to the recorder's "every expected message recorded" (the estimate's own computation included,
  which the one-process figure leaves out), the bag checked complete;
* rclpy's own publish-and-receive ceiling on this machine (:mod:`gyro_instrument.ros.ceiling`): one
  publisher process, one subscriber taking raw messages with the cheapest loop rclpy offers.

The target is met when the separate nodes reach 100× real time, or, where rclpy is the ceiling, when
their messages per second are within 2× of rclpy's own (the machine's load moves both alike: they are
measured minutes apart in the same bench run). ``tools/profile_ros_route.py`` shows where the time
goes in each node (docs/bench/ros_route_profile.md).
"""

import json
import os
import subprocess
import sys

from gyro_instrument.bench.live import loopback


def _json_child(args, stream="stdout"):
    """Run ``python args`` on loopback; its last JSON line (on ``stream``), or (None, reason)."""
    cmd, env = loopback([sys.executable] + list(args))
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    text = p.stdout if stream == "stdout" else p.stderr
    if p.returncode != 0 or not text.strip():
        last = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
        return None, last
    return json.loads(text.strip().splitlines()[-1]), ""


def _median_launch(launches) -> dict:
    """The launch of median real-time factor (the lower middle one of an even count)."""
    ranked = sorted(launches, key=lambda x: x["real_time_factor"])
    return ranked[(len(ranked) - 1) // 2]


def ros_route_rows(duration_s=600.0, progress=print, repeats=5) -> list:
    """Rows (target, measured, unit, goal, met) of the separate-node route beside the one-process run
    and rclpy's ceiling (module docstring). The separate nodes are launched ``repeats`` times and the
    launch of median real-time factor is reported (its range in the unit column): one launch varies
    by up to 1.5x on this machine; any launch that does not complete fails the row. The ceiling is
    the median of 3 runs."""
    import importlib.util
    import tempfile
    if importlib.util.find_spec("rclpy") is None:
        return [("ROS separate nodes", float("nan"), "rclpy not installed", ">= 100", False)]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        progress("  one process: run quet_paris (subprocess on loopback)")
        one, note = _json_child(["-m", "gyro_instrument.ros.cli", "run", "quet_paris", "--duration-s",
                                 f"{duration_s:g}", "--bag", os.path.join(tmp, "one.mcap"), "--json", "--stats"],
                                stream="stderr")
    rtf_one = one["real_time_factor_achieved"] if one else float("nan")
    rows.append((f"run quet_paris {duration_s:g} s at 20 Hz, rtf 0, recording: one process", rtf_one,
                 "x real time" + (f" ({note})" if note else ""), "", one is not None))
    progress(f"  separate nodes: one process per node (subprocesses on loopback), {repeats} launches")
    launches, notes = [], []
    for _ in range(repeats):
        sep, note = _json_child(["-m", "gyro_instrument.ros.launch", "quet_paris", f"{duration_s:g}"])
        if sep is not None and sep["state"] == "complete" and sep["real_time_factor"]:
            launches.append(sep)
        else:
            notes.append(note or (sep or {}).get("state", "failed"))
    ok = len(launches) == repeats                 # a launch that did not complete fails the row
    sep = _median_launch(launches) if launches else None
    rtfs = sorted(x["real_time_factor"] for x in launches)
    rtf = sep["real_time_factor"] if sep else float("nan")
    rate = sep["messages_per_s"] if sep else float("nan")
    spread = (f"; median of {len(launches)} launches (range {rtfs[0]:.1f}-{rtfs[-1]:.1f}x), launch to exit "
              f"{sep['launch_wall_s']:.1f} s, {sep['messages']} messages" if sep else "")
    failed = f"; {len(notes)} of {repeats} launches did not complete ({notes[0]})" if notes else ""
    rows.append((f"ROS separate nodes (ros2 run route), quet_paris {duration_s:g} s at 20 Hz, rtf 0, recording "
                 "complete: first tick to complete bag", rtf, "x real time" + spread + failed, ">= 100",
                 ok and rtf >= 100))
    s_rtf = sep.get("samples_real_time_factor") if sep else None
    rows.append(("ROS separate nodes: first tick to every sample at the estimator (the estimate's computation "
                 "left out, as in the one-process figure)", s_rtf if s_rtf else float("nan"), "x real time", "",
                 bool(s_rtf)))
    rows.append(("ROS separate nodes: messages recorded per second", rate, "messages/s", "", ok))
    progress("  rclpy's own publish-and-receive ceiling (two processes on loopback)")
    ceils = [c for c, _ in (_json_child(["-m", "gyro_instrument.ros.ceiling", "60000"]) for _ in range(3)) if c]
    ceil = sorted(ceils, key=lambda c: c["messages_per_s"])[len(ceils) // 2] if ceils else None
    c_rate = ceil["messages_per_s"] if ceil else float("nan")
    rows.append(("rclpy's ceiling: one publisher process to one subscriber, raw JointStates", c_rate,
                 f"messages/s; median of {len(ceils)} of 3 runs", "", ceil is not None))
    ratio = c_rate / rate if sep and ceil else float("nan")
    rows.append(("rclpy's ceiling / separate nodes' messages per second", ratio, "x", "<= 2 (or the 100x above)",
                 bool(ok and ceil) and (ratio <= 2 or rtf >= 100)))
    d_rate = sep.get("deliveries_per_s") if ok else None
    d_ratio = c_rate / d_rate if d_rate and ceil else float("nan")
    rows.append(("rclpy's ceiling / separate nodes' DDS deliveries per second (a clock tick to 3 subscribers, a "
                 "joint state to 2)", d_ratio, "x", "", bool(d_rate and ceil)))
    return rows


if __name__ == "__main__":
    # python -m gyro_instrument.bench.ros_route [OUT.csv]: the rows alone (about a minute), written as
    # targets.csv is (docs/bench/ros_route.csv); run on loopback (tools/loopback)
    from gyro_instrument.core.files import write_csv
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join("docs", "bench", "ros_route.csv")
    write_csv(out, ("target", "measured", "unit", "goal", "met"), ros_route_rows())
    print(f"wrote {out}")
