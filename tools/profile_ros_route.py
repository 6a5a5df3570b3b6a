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


class _CpuWatch:
    """Each node process's CPU time (user + system, all threads: DDS's too) read from /proc every
    50 ms, so that the CPU each node spent inside the timed window (sim time starts to the complete
    bag) is known apart from its start-up and exit."""

    def __init__(self):
        import threading
        self.samples, self._stop = [], threading.Event()
        self._tick = os.sysconf("SC_CLK_TCK")
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()

    def _read(self):
        import re
        cpu = {}
        for pid in (p for p in os.listdir("/proc") if p.isdigit()):
            try:
                argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
                found = re.search(rb"gyro_instrument.ros.main import (\w+)", b" ".join(argv))
                if not found or b"py-spy" in argv[0]:
                    continue
                f = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
                cpu[found.group(1).decode()] = (int(f[11]) + int(f[12])) / self._tick
            except OSError:
                pass
        return cpu

    def _loop(self):
        while not self._stop.wait(0.05):
            self.samples.append((time.time(), self._read()))

    def stop(self):
        self._stop.set()
        self._thread.join()

    def at(self, t, node) -> float:
        """CPU s of ``node`` at wall time ``t`` (the last reading before it)."""
        return max((c[node] for w, c in self.samples if w <= t and node in c), default=0.0)


def _window_table(watch, logs) -> list:
    """Markdown lines: each node's CPU in the timed window, beside the window's wall time."""
    owner = next((n for n, text in logs.items() if "]: sim time starts" in text), None)
    start = L._log_time(logs[owner], "]: sim time starts") if owner else None
    end = L._log_time(logs.get("recorder", ""), "every expected message recorded")
    if start is None or end is None:
        return ["(the timed window was not found in the logs)", ""]
    rows = [(n, watch.at(end, n) - watch.at(start, n), watch.at(start, n)) for n in logs]
    lines = [f"Timed window (the clock owner's first tick to the recorder's complete bag): {end - start:.2f} s of "
             f"wall time; CPU per node from /proc (all its threads, DDS's included; py-spy's sampling adds some):", "",
             "| node | CPU before the window (s) | CPU in the window (s) | share of one core |", "|---|---|---|---|"]
    lines += [f"| {n} | {b:.2f} | {c:.2f} | {c / (end - start):.0%} |" for n, c, b in rows]
    lines += [f"| all | | {sum(r[1] for r in rows):.2f} | {sum(r[1] for r in rows) / (end - start):.0%} |", ""]
    return lines


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
    watch = _CpuWatch()
    # sampled interpreters start slowly: the clock owner waits up to 120 s for the other nodes
    res = L.launch(args.scene, os.path.join(out_dir, "route.mcap"), duration_s=args.duration_s,
                   real_time_factor=0.0, timeout_s=900, log_dir=out_dir,
                   extra_ros_args=["-p", "wait_timeout_s:=120.0"])
    wall = time.monotonic() - t0
    watch.stop()
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
    doc[4:4] = _window_table(watch, res["logs"])
    Path(args.out).write_text("\n".join(doc) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
