"""``gyro-instrument`` with the ROS subcommand ``run`` added to the core CLI (the core CLI never
imports rclpy; this module does, lazily, only for ``run``).

This is the console script's module: it imports nothing heavy at the top, so a Ctrl-C at any
moment after Python starts (even while numpy and scipy are being imported) ends in the one line
``gyro-instrument: interrupted`` and exit status 130 (:func:`gyro_instrument.cli.guarded`).
"""

import argparse
import json
import sys


def build_parser() -> argparse.ArgumentParser:
    from gyro_instrument import cli as core_cli
    parser = core_cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    p = sub.add_parser("run", help="run every node of the scene in one process (simulators, estimator, "
                                   "recorder) over DDS on loopback and print the recovered latitude and "
                                   "Earth rate next to the truth")
    core_cli.add_scene_arguments(p)
    p.add_argument("--bag", metavar="OUT.mcap|DIR/", help="record every topic: to this MCAP file (rosbag2's MCAP "
                                                          "layout), or, for a path ending in '/' (or --bag-format "
                                                          "rosbag2), to a rosbag2 bag directory (metadata.yaml + "
                                                          "DIR_0.mcap, DIR_1.mcap ...); an existing file or "
                                                          "directory is refused unless --overwrite; never the scene file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --bag file (or the bag files of an "
                                                            "existing bag directory; any other directory is refused)")
    p.add_argument("--bag-format", choices=("mcap", "rosbag2"), default=None,
                   help="mcap: one bare .mcap file; rosbag2: a bag directory as 'ros2 bag record' writes it "
                        "(default: rosbag2 when --bag ends in '/' or splitting is asked for, else mcap)")
    p.add_argument("--max-bag-size", type=float, default=0, metavar="BYTES",
                   help="rosbag2 layout: start a new .mcap file when the current one reaches this many bytes "
                        "(0, default: no limit; else >= 1048576, the floor)")
    p.add_argument("--max-bag-duration", type=float, default=0, metavar="S",
                   help="rosbag2 layout: start a new .mcap file when the current one spans this many seconds of "
                        "log time (0, default: no limit; else >= 1, the floor)")
    p.add_argument("--real-time-factor", type=float, default=0.0,
                   help="1.0 paces to the wall clock, 0 (default) runs as fast as possible")
    p.add_argument("--window-s", type=float, default=10.0, metavar="S",
                   help="simulated seconds integrated per block (default 10): each block is published before the "
                        "next is integrated, so the first message leaves at once and memory does not grow with "
                        "--duration-s; in [0.001, 1e6]")
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


def split_ros_args(argv) -> tuple:
    """(own arguments, arguments after ``--ros-args``) of a command line."""
    argv = list(argv)
    if "--ros-args" in argv:
        i = argv.index("--ros-args")
        return argv[:i], argv[i + 1:]
    return argv, []


def main(argv=None) -> int:
    """Run one command line; exit status as :func:`gyro_instrument.cli.main` (0, 2, 3, 130)."""
    try:
        from gyro_instrument import cli as core_cli
    except KeyboardInterrupt:
        print("gyro-instrument: interrupted", file=sys.stderr)
        return 130
    return core_cli.guarded(lambda: _command(core_cli, argv), process=argv is None)


def _command(core_cli, argv):
    from gyro_instrument.core.errors import SceneError
    parser = build_parser()
    full = list(sys.argv[1:] if argv is None else argv)
    own, ros_args = split_ros_args(full)
    args = parser.parse_args(own)
    if ros_args and args.command != "run":
        parser.error(f"--ros-args is only for 'run' (the ROS suite), not '{args.command}'")
    if args.command != "run":
        return core_cli.run_command(args)
    if args.namespace and not args.namespace.lstrip("/").replace("/", "").replace("_", "a").isalnum():
        raise SceneError("--namespace", args.namespace, "must be a ROS namespace such as /ship1 (letters, "
                                                        "digits, _ and /)")
    bag_format = None
    if args.bag:
        from gyro_instrument.recording.bag_layout import bag_format as layout_of, check_bag_output
        bag_format = layout_of(args.bag, args.bag_format, args.max_bag_size, args.max_bag_duration)
        check_bag_output(args.bag, bag_format, "--bag", core_cli.scene_inputs(args.scene), args.overwrite,
                         args.max_bag_size, args.max_bag_duration)
    elif args.bag_format or args.max_bag_size or args.max_bag_duration:
        raise SceneError("--bag", None, "is needed by --bag-format, --max-bag-size and --max-bag-duration")
    from gyro_instrument.ros.suite import check_window
    check_window(args.window_s)
    if args.real_time_factor < 0 or args.real_time_factor != args.real_time_factor:
        raise SceneError("--real-time-factor", args.real_time_factor, "must be >= 0 (0: as fast as possible)")
    from gyro_instrument.ros.suite import run_suite
    progress = None if (args.quiet or args.stats) else (lambda msg: print(msg, file=sys.stderr))
    result, stats = run_suite(args.scene, args.overrides, args.duration_s, args.bag, args.real_time_factor,
                              command=" ".join(["gyro-instrument"] + full), progress=progress,
                              overwrite=args.overwrite, bag_format=bag_format,
                              max_bag_size=int(args.max_bag_size), max_bag_duration_s=args.max_bag_duration,
                              namespace=args.namespace, ros_args=ros_args, window_s=args.window_s)
    if result is None:
        print("gyro-instrument: the scene could not be loaded by the nodes", file=sys.stderr)
        return 3
    result = core_cli.to_jsonable(result)
    if args.stats:
        print(json.dumps({k: stats[k] for k in ("samples", "wall_s", "real_time_factor_achieved", "recorded",
                                                "first_message_s", "blocks", "estimator_bytes",
                                                "peak_rss_streaming_mb", "peak_rss_mb")}),
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
