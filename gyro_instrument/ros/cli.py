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
    """The CLI's one parser with ``run`` (:func:`gyro_instrument.cli.parser.build_parser`)."""
    from gyro_instrument.cli.parser import build_parser as core_parser
    return core_parser(run=True)


def split_ros_args(argv) -> tuple:
    """(own arguments, arguments after ``--ros-args``) of a command line."""
    argv = list(argv)
    if "--ros-args" in argv:
        i = argv.index("--ros-args")
        return argv[:i], argv[i + 1:]
    return argv, []


def main(argv=None) -> int:
    """Run one command line; exit status as :func:`gyro_instrument.cli.main` (0, 2, 3, 130)."""
    from gyro_instrument.cli.interrupt import EXIT_INTERRUPTED, LINE, guarded_import, interrupted_while_importing

    def load():
        from gyro_instrument.cli import commands
        from gyro_instrument.cli import text  # noqa: F401  (imported here, inside the guard)
        return commands
    try:
        core_cli = guarded_import(load)
    except KeyboardInterrupt:
        if argv is None:                      # the process's entry point: the line, then exit 130
            interrupted_while_importing()
        print(LINE, file=sys.stderr)
        return EXIT_INTERRUPTED
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
    core_cli.report_plugins()
    from gyro_instrument import api
    bag_format = None
    if args.namespace:
        api.check_run_options(namespace=args.namespace)
    if args.bag:
        bag_format = api.check_bag(args.scene, args.bag, args.bag_format, args.overwrite, args.max_bag_size,
                                   args.max_bag_duration)
    elif args.bag_format or args.max_bag_size or args.max_bag_duration:
        raise SceneError("--bag", None, "is needed by --bag-format, --max-bag-size and --max-bag-duration")
    api.check_run_options(args.namespace, args.real_time_factor, args.window_s)
    if args.nmea_udp:
        from gyro_instrument.recording.nmea import resolve_udp_targets, targets_note
        note = targets_note(args.nmea_udp, resolve_udp_targets(args.nmea_udp))
        if note:
            print(f"gyro-instrument: note: --nmea-udp {note}", file=sys.stderr)
    from gyro_instrument.ros.lockstep import DeliveryError
    from gyro_instrument.ros.suite import NodeFailure, run_suite
    try:
        result, stats = run_suite(args.scene, args.overrides, args.duration_s, args.bag,
                                  run_options(args, full, bag_format, ros_args))
    except NodeFailure as exc:       # the last line names the node and the reason
        print(f"gyro-instrument: {exc}", file=sys.stderr)
        return 3
    except DeliveryError as exc:
        print(f"gyro-instrument: the estimator or recorder did not receive every sample: {exc}", file=sys.stderr)
        return 3
    result = api.to_jsonable(result)
    if args.stats:
        print(json.dumps({k: stats[k] for k in ("samples", "wall_s", "real_time_factor_achieved", "recorded",
                                                "first_message_s", "blocks", "estimator_bytes",
                                                "peak_rss_streaming_mb", "peak_rss_mb")}),
              file=sys.stderr)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        from gyro_instrument.cli.text import print_estimate
        print_estimate(result)
        if not (args.quiet or args.stats):
            print(f"  suite: {stats['samples']} samples in {stats['wall_s']:.2f} s "
                  f"({stats['real_time_factor_achieved']:.1f}x real time); recorded {sum(stats['recorded'].values())} "
                  f"messages" + (f" to {args.bag}" if args.bag else ""), file=sys.stderr)
    return 0


def run_options(args, full, bag_format, ros_args) -> "RunOptions":  # noqa: F821
    """The :class:`~gyro_instrument.ros.suite.RunOptions` of ``run``'s parsed ``args`` (``full``: the
    whole command line, recorded in the bag; ``bag_format`` as checked; ``ros_args``: after
    ``--ros-args``)."""
    from gyro_instrument.ros.suite import RunOptions
    progress = None if (args.quiet or args.stats) else (lambda msg: print(msg, file=sys.stderr))
    return RunOptions(real_time_factor=args.real_time_factor, command=" ".join(["gyro-instrument"] + full),
                      progress=progress, overwrite=args.overwrite, bag_format=bag_format,
                      max_bag_size=int(args.max_bag_size), max_bag_duration_s=args.max_bag_duration,
                      namespace=args.namespace, ros_args=tuple(ros_args), window_s=args.window_s,
                      nmea_udp=args.nmea_udp or "")


if __name__ == "__main__":
    sys.exit(main())
