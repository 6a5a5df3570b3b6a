"""Where the time goes in the route ROS users take (issue 37 item 6): every node of a scene as its
own process (gyro_instrument.ros.launch, real-time factor 0, recording), each sampled by py-spy
(100 Hz, CPU samples only; cProfile in each node when py-spy is not installed), and the functions
that hold the samples, per node, written as Markdown.

    AMENT_PREFIX_PATH=$PWD/.venv tools/loopback .venv/bin/python tools/profile_ros_route.py \
        [--duration-s 600] [--out docs/bench/ros_route_profile.md]
"""

import argparse
import collections
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gyro_instrument.ros.launch as L  # noqa: E402

#: (node, CPU s sampled, of which imports) of the nodes read so far
_SUMMARY = []


def _wrap(pyspy, out_dir):
    orig = L._command

    def command(node):
        if pyspy:
            return [pyspy, "record", "-r", "100", "-f", "speedscope", "-o", os.path.join(out_dir, node + ".json"),
                    "--"] + orig(node)
        code = orig(node)[-1]
        return [sys.executable, "-c", f"import cProfile; cProfile.run({code!r}, {os.path.join(out_dir, node + '.prof')!r})"]
    L._command = command


def _speedscope(path, top):
    d = json.loads(Path(path).read_text())
    frames = d["shared"]["frames"]
    own, incl, total, imports = collections.Counter(), collections.Counter(), 0.0, 0.0
    for p in d["profiles"]:
        for stack, w in zip(p["samples"], p["weights"]):
            total += w
            names = [frames[i] for i in stack]
            if any(f["name"] in ("_find_and_load",) for f in names):
                imports += w
                continue
            if stack:
                own[stack[-1]] += w
            for i in set(stack):
                incl[i] += w

    def name(i):
        f = frames[i]
        return f"`{f['name']}` ({Path(f.get('file', '')).name}:{f.get('line', '')})"
    _SUMMARY.append((Path(path).stem, total, imports))
    lines = [f"CPU samples {total:.2f} s, of which imports (interpreter start) {imports:.2f} s", "",
             "| self | function |", "|---|---|"]
    lines += [f"| {w / total:.1%} | {name(i)} |" for i, w in own.most_common(top)]
    lines += ["", "| inclusive | function |", "|---|---|"]
    lines += [f"| {w / total:.1%} | {name(i)} |" for i, w in incl.most_common(top + 10)
              if not frames[i]["name"].startswith("<")]
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="quet_paris")
    ap.add_argument("--duration-s", type=float, default=600.0)
    ap.add_argument("--top", type=int, default=12)
    ap.add_argument("--out", default="docs/bench/ros_route_profile.md")
    args = ap.parse_args(argv)
    pyspy = shutil.which("py-spy") or (str(Path(sys.executable).parent / "py-spy")
                                        if (Path(sys.executable).parent / "py-spy").exists() else None)
    out_dir = tempfile.mkdtemp()
    _wrap(pyspy, out_dir)
    t0 = time.monotonic()
    # sampled interpreters start slowly: the clock owner waits up to 120 s for the other nodes
    res = L.launch(args.scene, os.path.join(out_dir, "route.mcap"), duration_s=args.duration_s,
                   real_time_factor=0.0, timeout_s=900, log_dir=out_dir,
                   extra_ros_args=["-p", "wait_timeout_s:=120.0"])
    wall = time.monotonic() - t0
    doc = [f"# Where the time goes: {args.scene}, {args.duration_s:g} s, separate nodes at real-time factor 0",
           "", f"Written by `tools/profile_ros_route.py` ({'py-spy, 100 Hz, CPU samples' if pyspy else 'cProfile'}); "
           f"launch to exit {wall:.1f} s on this machine (load average {os.getloadavg()[0]:.1f} on "
           f"{os.cpu_count()} cores when it ended); exit codes {res['returncodes']}.", ""]
    for node in res["returncodes"]:
        doc += [f"## {node}", ""]
        if pyspy:
            doc += _speedscope(os.path.join(out_dir, node + ".json"), args.top)
        else:
            import pstats
            import io
            buf = io.StringIO()
            pstats.Stats(os.path.join(out_dir, node + ".prof"), stream=buf).sort_stats("tottime").print_stats(args.top)
            doc += ["```", buf.getvalue().strip(), "```"]
        doc.append("")
    if _SUMMARY:
        head = ["| node | CPU sampled (s) | imports (s) | the run itself (s) |", "|---|---|---|---|"]
        head += [f"| {n} | {t:.2f} | {i:.2f} | {t - i:.2f} |" for n, t, i in _SUMMARY]
        doc[4:4] = head + [""]
    Path(args.out).write_text("\n".join(doc) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
