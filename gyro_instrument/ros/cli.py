"""``gyro-instrument`` with the ROS subcommand ``run`` added to the core CLI (the core CLI never
imports rclpy; this module does, lazily, only for ``run``)."""

import json
import sys

from gyro_instrument import cli as core_cli
from gyro_instrument.core.errors import SceneError


def build_parser():
    parser = core_cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    p = sub.add_parser("run", help="run every node of the scene in one process (simulators, estimator, "
                                   "recorder) over DDS on loopback and print the recovered latitude and "
                                   "Earth rate next to the truth")
    core_cli.add_scene_arguments(p)
    p.add_argument("--bag", metavar="OUT.mcap", help="record every topic to this MCAP file (rosbag2 layout); an "
                                                     "existing file is refused unless --overwrite; never the scene file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --bag file")
    p.add_argument("--real-time-factor", type=float, default=0.0,
                   help="1.0 paces to the wall clock, 0 (default) runs as fast as possible")
    p.add_argument("--namespace", metavar="NS", default="",
                   help="run every node in this ROS namespace (e.g. /ship1): topics and the clock become "
                        "NS/...; suites in different namespaces run side by side")
    p.add_argument("--json", action="store_true", help="print the same JSON object as 'estimate'")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.epilog = ("Everything after --ros-args goes to the nodes (remapping, log levels, -p for parameters "
                "the suite does not set itself), e.g. gyro-instrument run quet_paris --ros-args "
                "--log-level warn")
    p.add_argument("--stats", action="store_true",
                   help="print the suite's statistics (samples, wall time, real-time factor, messages recorded "
                        "per topic) as one JSON line on stderr (implies --quiet)")
    return parser


def split_ros_args(argv):
    """(own arguments, arguments after ``--ros-args``) of a command line."""
    argv = list(argv)
    if "--ros-args" in argv:
        i = argv.index("--ros-args")
        return argv[:i], argv[i + 1:]
    return argv, []


def main(argv=None):
    parser = build_parser()
    full = list(sys.argv[1:] if argv is None else argv)
    own, ros_args = split_ros_args(full)
    args = parser.parse_args(own)
    if ros_args and args.command != "run":
        parser.error(f"--ros-args is only for 'run' (the ROS suite), not '{args.command}'")
    if args.command != "run":
        try:
            return core_cli.run_command(args)
        except SceneError as exc:
            print(f"gyro-instrument: error: {exc}", file=sys.stderr)
            return core_cli.EXIT_BAD_INPUT
    try:
        if args.bag:
            core_cli.check_output(args.bag, "--bag", core_cli.scene_inputs(args.scene), args.overwrite)
        if args.namespace and not args.namespace.lstrip("/").replace("/", "").replace("_", "a").isalnum():
            raise SceneError("--namespace", args.namespace, "must be a ROS namespace such as /ship1 (letters, "
                                                            "digits, _ and /)")
        if args.real_time_factor < 0:
            raise SceneError("--real-time-factor", args.real_time_factor, "must be >= 0 (0: as fast as possible)")
        from gyro_instrument.ros.suite import run_suite
        progress = None if (args.quiet or args.stats) else (lambda msg: print(msg, file=sys.stderr))
        result, stats = run_suite(args.scene, args.overrides, args.duration_s, args.bag, args.real_time_factor,
                                  command=" ".join(["gyro-instrument"] + full), progress=progress,
                                  overwrite=args.overwrite, namespace=args.namespace, ros_args=ros_args)
    except SceneError as exc:
        print(f"gyro-instrument: error: {exc}", file=sys.stderr)
        return core_cli.EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("gyro-instrument: interrupted", file=sys.stderr)
        return 130
    if result is None:
        print("gyro-instrument: the scene could not be loaded by the nodes", file=sys.stderr)
        return 3
    result = core_cli.to_jsonable(result)
    if args.stats:
        print(json.dumps({k: stats[k] for k in ("samples", "wall_s", "real_time_factor_achieved", "recorded")}),
              file=sys.stderr)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        core_cli.print_estimate(result)
        if not (args.quiet or args.stats):
            print(f"  suite: {stats['samples']} samples in {stats['wall_s']:.2f} s "
                  f"({stats['real_time_factor_achieved']:.1f}x real time); recorded {sum(stats['recorded'].values())} "
                  f"messages" + (f" to {args.bag}" if args.bag else ""), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
