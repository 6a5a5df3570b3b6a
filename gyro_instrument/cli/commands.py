"""The subcommands (``args`` in, exit status out) and :func:`main` with its exit statuses (see
:func:`guarded`)."""

import contextlib
import json
import math
import os
import re
import signal
import sys
import threading

from gyro_instrument import api
from gyro_instrument.api import damage_line, replay_bag
from gyro_instrument.cli.interrupt import LINE, SigintWatch, exit_interrupted
from gyro_instrument.cli.parser import (EXIT_BAD_INPUT, EXIT_CLOSED_PIPE, EXIT_INTEGRATION_FAILED, EXIT_INTERRUPTED,
                                        build_parser, scene_arg, scene_from_args)
from gyro_instrument.cli.simulate import simulate_to_file, terminal_progress
from gyro_instrument.cli.text import print_description, print_estimate, print_plan, print_scene_notes
from gyro_instrument.core.errors import IntegrationError, SceneError
from gyro_instrument.core.files import check_output, check_output_dir, scene_inputs
from gyro_instrument.core.jsonable import to_jsonable


def main(argv=None) -> int:
    """Run one command line (``argv``, default ``sys.argv[1:]``) and return the exit status.

    0 success, 2 bad input (SceneError or an argparse error: one line on stderr), 3 integration
    failed, 130 interrupted (Ctrl-C: one line, no output file left half-written). argparse's
    ``--help`` and its errors raise SystemExit (0 and 2).
    """
    return guarded(lambda: run_command(build_parser().parse_args(argv)), process=argv is None)


def guarded(body, process=False) -> int:
    """Call ``body()`` and turn the expected failures into one line on stderr and an exit status.

    SceneError -> 2, IntegrationError -> 3, a closed stdout pipe -> 141 quietly (:func:`closed_pipe`),
    KeyboardInterrupt (wherever it lands: imports,
    integration, progress drawing, writing) -> ``gyro-instrument: interrupted`` and 130. Any other
    exception is a bug and keeps its traceback. ``process``: this is the process's entry point
    (``argv`` not given): the body runs under a :class:`~gyro_instrument.cli.interrupt.SigintWatch`
    (an exception after a Ctrl-C is the interrupt, whatever an extension turned it into; one a
    finalizer swallowed is raised again), SIGINT is ignored once the status is decided, and an
    interrupted process ends with 130 (:func:`~gyro_instrument.cli.interrupt.exit_interrupted`).
    """
    names_as_given()
    watch = SigintWatch() if process else None
    try:
        try:
            with watch or contextlib.nullcontext():
                try:
                    return body()
                except Exception:
                    if watch is not None and watch.hit:
                        raise KeyboardInterrupt from None
                    raise
        except SceneError as exc:
            print(f"gyro-instrument: error: {one_line(exc)}", file=sys.stderr)
            return EXIT_BAD_INPUT
        except IntegrationError as exc:
            print(f"gyro-instrument: integration failed: {one_line(exc)}", file=sys.stderr)
            return EXIT_INTEGRATION_FAILED
        except BrokenPipeError:
            return closed_pipe()
    except KeyboardInterrupt:
        status = interrupted(process)
        return exit_interrupted(status) if process else status
    finally:
        if process:
            _ignore_sigint()


def names_as_given() -> None:
    """stdout and stderr write the bytes of a file name that is not UTF-8 as the name holds them
    (``errors="surrogateescape"``, what Python's C locale does; a UTF-8 locale's ``strict`` raised
    UnicodeEncodeError after the work was done, e.g. ``estimate --data $'caf\\xe9.csv'``). Only the
    process's own streams: one a caller put in their place (pytest's capture) is left as it is."""
    for stream in (sys.stdout, sys.stderr):
        if stream not in (sys.__stdout__, sys.__stderr__):    # a caller's own stream (a test's capture) is its own
            continue
        if getattr(stream, "errors", None) in ("strict", "backslashreplace") and hasattr(stream, "reconfigure"):
            with contextlib.suppress(ValueError, OSError, AttributeError):
                stream.reconfigure(errors="surrogateescape")


def closed_pipe() -> int:
    """The reader of stdout went away (``describe SCENE | head -2``): stop quietly with 141 (128 +
    SIGPIPE, what a shell reports for a command its pipe closed), stdout pointed at /dev/null so
    that Python's final flush cannot print a BrokenPipeError either."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):   # a stdout without a file descriptor (a test's)
        pass
    return EXIT_CLOSED_PIPE


def one_line(exc) -> str:
    """The message of ``exc`` on one line: newlines and other control characters in quoted
    values (a key or value given on the command line) shown escaped; a byte of a file name that is
    not UTF-8 (a surrogate of ``os.fsdecode``) as ``\\xNN``."""
    text = "".join(ch if ch.isprintable() else f"\\x{ord(ch) - 0xDC00:02x}" if "\udc80" <= ch <= "\udcff"
                   else repr(ch)[1:-1] for ch in str(exc))
    return re.sub(r"(?<!\\)\\udc([89a-f][0-9a-f])", r"\\x\1", text)     # the same byte inside a repr()


def interrupted(process=False) -> int:
    """Print ``gyro-instrument: interrupted`` and return 130, with further SIGINTs ignored while
    printing (a second Ctrl-C must not interrupt the message); in-process callers get their
    handler back."""
    for _ in range(3):   # a second SIGINT before the handler is swapped lands here: try again
        try:
            previous = _ignore_sigint()
            print(LINE, file=sys.stderr)
            if not process and previous is not None:
                signal.signal(signal.SIGINT, previous)
            return EXIT_INTERRUPTED
        except KeyboardInterrupt:
            continue
    return EXIT_INTERRUPTED


def _ignore_sigint():
    """Ignore SIGINT (main thread only); return the previous handler or None."""
    if threading.current_thread() is threading.main_thread():
        return signal.signal(signal.SIGINT, signal.SIG_IGN)
    return None


def run_command(args) -> int:
    """Run the parsed subcommand ``args.command``; its exit status."""
    report_plugins()
    return COMMANDS[args.command](args)


def report_plugins() -> None:
    """One line on stderr for each plug-in left out (:data:`gyro_instrument.core.plugins.REFUSED`:
    it could not be loaded, or its registry refused it, naming what is missing), once per process.
    The measurement kinds are loaded first, so instruments naming an incomplete kind are among them."""
    from gyro_instrument.core import plugins
    from gyro_instrument.instruments import measurement
    measurement.load()
    for line in plugins.REFUSED[len(_REPORTED):]:
        print(f"gyro-instrument: {line}", file=sys.stderr)
        _REPORTED.append(line)


_REPORTED = []


def scenes_command(args) -> int:
    """``gyro-instrument scenes``: the shipped scene names, one per line."""
    from gyro_instrument.scenes import shipped_scene_names
    print("\n".join(shipped_scene_names()))
    return 0


def describe_command(args) -> int:
    """``gyro-instrument describe``: instruments, active effects, predictions (text or ``--json``)."""
    d = api.describe(scene_from_args(args))
    if args.json:
        print(json.dumps(d, indent=2))
    else:
        print_description(d)
    return 0


def simulate_command(args) -> int:
    """``gyro-instrument simulate``: every instrument channel to CSV or Parquet (``--out``)."""
    from gyro_instrument.estimators.data_io import scene_sidecar_path, table_kind
    check_output(args.out, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{args.out}.partial",))
    if table_kind(args.out) == "csv":        # its scene beside it, under the same rule
        side = scene_sidecar_path(args.out)
        check_output(side, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{side}.partial",))
    scene = scene_from_args(args)
    print_scene_notes(scene)
    progress = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    rows, ncol, nfev, wall = simulate_to_file(scene, args.out, args.output_rate_hz, progress)
    if progress:
        progress(f"wrote {args.out}: {rows} rows x {ncol} columns "
                 f"({nfev} right-hand-side evaluations, {wall:.2f} s integrating)")
    return 0


def estimate_command(args) -> int:
    """``gyro-instrument estimate``: simulate through the sensors (or read ``--data``) and estimate."""
    from gyro_instrument.estimators.pipeline import simulate_truth
    if args.reversal_points:
        return _field_book_estimate(args)
    scene = data_scene(args) if scene_arg(args) is None and args.data else None
    if scene is None and scene_arg(args) is None:
        raise SceneError("scene", None, "give the scene: 'estimate SCENE' or 'estimate --data FILE --scene SCENE'"
                                        + (f" ({args.data} carries none: no Parquet metadata 'gyro_instrument."
                                           f"scene_yaml', no .scene.yaml beside it)" if args.data else ""))
    scene = scene or scene_from_args(args)
    table_flags = {"--time-column": (args.time_column, "time_s"), "--time-unit": (args.time_unit, None),
                   "--angle-unit": (args.angle_unit, None), "--column": (args.columns, []),
                   "--separator": (args.separator, None), "--scale-division": (args.scale_division, None)} | camera_flags(args)
    if args.data:
        from gyro_instrument.estimators.data_io import estimate_data
        if args.scale_division is not None:
            raise SceneError("--scale-division", args.scale_division, "reads a field book: give --reversal-points")
        result = api.finish_estimate(to_jsonable(estimate_data(scene, args.data, options=table_options(args))), scene)
    elif given := [(flag, v) for flag, (v, default) in table_flags.items() if v != default]:
        raise SceneError(*given[0], "reads a table: give --data FILE (or leave the flag out)")
    else:
        with terminal_progress("simulating"):
            truth = simulate_truth(scene)
        result = api.estimate(scene, truth)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print_estimate(result, angle_format=args.angle_format)
    return 0


def table_options(args) -> "TableOptions":
    """The table options of ``estimate --data`` and ``plot`` (the same flags, one reader:
    :func:`~gyro_instrument.estimators.table_read.load_table`), checked."""
    from gyro_instrument.estimators.table_read import TableOptions
    return with_camera(TableOptions.from_flags(args.time_column, args.time_unit, args.angle_unit or "rad",
                                               args.columns, args.separator), args)


def given_table_flags(args) -> list:
    """(flag, value) of every table flag given with a value other than its default."""
    flags = {"--time-column": (args.time_column, "time_s"), "--time-unit": (args.time_unit, None),
             "--angle-unit": (args.angle_unit, None), "--column": (args.columns, []),
             "--separator": (args.separator, None)} | camera_flags(args)
    return [(flag, v) for flag, (v, default) in flags.items() if v != default]


def camera_flags(args) -> dict:
    """The camera-track flags as ``flag: (value, default)`` (refused without a table)."""
    return {"--metres-per-pixel": (args.metres_per_pixel, None), "--y-down": (args.y_down, False),
            "--rotation-deg": (args.rotation_deg, None), "--frame-column": (args.frame_column, None),
            "--frame-rate": (args.frame_rate, None), "--no-header": (args.no_header, False),
            "--names": (args.names, None)}


def with_camera(options, args) -> "TableOptions":
    """``options`` (TableOptions) with the camera track's and a headerless file's flags, checked."""
    import dataclasses
    from gyro_instrument.estimators.table_camera import CameraOptions
    if args.names is not None and not args.no_header:
        raise SceneError("--names", args.names, "names the columns of a file without a header: add --no-header "
                                                "(a header's columns are renamed with --column)")
    names = tuple(n.strip() for n in (args.names or "").split(",")) if args.no_header else None
    if args.no_header and (not names or not all(names)):
        raise SceneError("--no-header", args.names, "needs the columns' names: --names time,x,y (one per column)")
    camera = CameraOptions.from_flags(args.metres_per_pixel, args.y_down, args.rotation_deg, args.frame_column,
                                      args.frame_rate, options.time_column, options.time_unit)
    time_column = args.frame_column if args.frame_column is not None else options.time_column
    return dataclasses.replace(options, camera=camera, names=names, time_column=time_column)


def _field_book_estimate(args) -> int:
    """``estimate --reversal-points FILE [--scene SCENE]``: north from a field book (no simulation); the
    scene, when given, lends its latitude and tape (:func:`.north.field_book_report.field_book_block`)."""
    from gyro_instrument.core.angle_formats import parse_scale_division
    from gyro_instrument.estimators.north.field_book_report import field_book_block
    if args.data:
        raise SceneError("--reversal-points", args.reversal_points, "reads a field book: leave --data out")
    if args.columns or args.time_column != "time_s":
        raise SceneError(*(("--column", args.columns[0]) if args.columns else ("--time-column", args.time_column)),
                         "reads a table (--data); a field book's columns are named by its header")
    division = None
    if args.scale_division is not None:
        try:
            division = parse_scale_division(args.scale_division)
        except ValueError as exc:
            raise SceneError("--scale-division", args.scale_division, str(exc)) from None
    scene = scene_from_args(args) if scene_arg(args) is not None else None
    if scene is None and args.overrides:
        raise SceneError("--set", args.overrides[0], "overrides a scene's value: give --scene SCENE (a field book "
                                                     "needs none)")
    block = field_book_block(args.reversal_points, args.angle_unit, args.time_unit, scene, args.separator, division)
    result = {"scene": None if scene is None else scene.name, "field_book": args.reversal_points, "north": block}
    if args.json:
        print(json.dumps(to_jsonable(result), indent=2))
    else:
        from gyro_instrument.cli.text import north_lines, wrapped_writer
        w, flush = wrapped_writer(sys.stdout)
        for line in north_lines(result["north"], args.angle_format):
            w(f"{line}\n")
        flush()
    return 0


def data_scene(args) -> "Scene | None":
    """The scene ``estimate --data FILE`` takes when no scene is given: the one the table carries
    (written by ``simulate``), with ``--set`` applied and a note on stderr; None when it carries none."""
    from gyro_instrument.estimators.data_io import scene_of_table
    found = scene_of_table(args.data, args.overrides)
    if found is None:
        return None
    scene, where = found
    print(f"gyro-instrument: note: no --scene given: using the scene {scene.name!r} from {where}", file=sys.stderr)
    return scene


def bench_command(args) -> int:
    """``gyro-instrument bench``: the studies of :mod:`gyro_instrument.bench.studies` into ``--out``."""
    from gyro_instrument.bench.studies import run_bench
    if args.overrides and args.scene is None:
        raise SceneError("--set", args.overrides[0], "applies to a --scene; give --scene SCENE")
    if args.scene is not None:
        from gyro_instrument.scenes import load_scene
        load_scene(args.scene, args.overrides)      # a bad scene stops here, before any directory is made
    progress = lambda m: print(m, file=sys.stderr)  # noqa: E731
    if args.scheduler:
        from gyro_instrument.core.parallel import dask_executor
        with dask_executor(args.scheduler) as ex:      # no scheduler: exit 2 before --out is made
            check_output_dir(args.out)
            progress(f"sweeps on the Dask scheduler {args.scheduler}")
            print(run_bench(args.out, args.quick, progress=progress, scene=args.scene, overrides=args.overrides,
                            executor=ex))
    else:
        check_output_dir(args.out)
        print(run_bench(args.out, args.quick, progress=progress, scene=args.scene, overrides=args.overrides))
    return 0


def sweep_command(args) -> int:
    """``gyro-instrument sweep``: :func:`gyro_instrument.bench.sweep.run_sweep` into ``--out``."""
    from gyro_instrument.bench.sweep import grid, run_sweep
    from gyro_instrument.estimators.data_io import table_kind
    if table_kind(args.out) != "parquet":
        raise SceneError("--out", args.out, "must be a Parquet file (name ending .parquet or .pq)")
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise SceneError("--timeout", args.timeout, "must be a finite number of seconds > 0")
    check_output(args.out, "--out", scene_inputs(args.scene), args.overwrite, also=(f"{args.out}.partial",))
    grid(args.vary)                                   # a bad --vary stops here, before any scheduler is asked
    if args.seeds < 1:
        raise SceneError("--seeds", args.seeds, "must be an integer >= 1")
    overrides = list(args.overrides) + ([f"duration_s={args.duration_s!r}"] if args.duration_s is not None else [])
    progress = lambda m: print(m, file=sys.stderr)  # noqa: E731
    if args.scheduler:
        from gyro_instrument.core.parallel import dask_executor
        with dask_executor(args.scheduler, args.timeout, need_workers=True, progress=progress) as ex:
            progress(f"sweep on the Dask scheduler {args.scheduler}")
            r = run_sweep(args.scene, overrides, args.vary, args.seeds, args.out, executor=ex, progress=progress)
    else:
        r = run_sweep(args.scene, overrides, args.vary, args.seeds, args.out, progress=progress)
    print(f"wrote {r['path']}: {r['rows']} rows x {r['columns']} columns ({r['points']} grid points, "
          f"{r['errors']} with an error) in {r['wall_s']:.1f} s ({r['rows_per_s']:.3g} rows/s)")
    return 0


def typetest_command(args) -> int:
    """``gyro-instrument typetest``: :func:`gyro_instrument.bench.typetest.run_typetest`, a table or JSON."""
    from gyro_instrument.bench.typetest import DEFAULT_LATITUDES, parse_latitudes, run_typetest
    from gyro_instrument.cli.typetest_text import print_typetest
    latitudes = DEFAULT_LATITUDES if args.latitudes is None else parse_latitudes(args.latitudes)
    if args.workers is not None and args.workers < 1:
        raise SceneError("--workers", args.workers, "must be an integer >= 1")
    overrides = list(args.overrides)
    api.load_scene(scene_arg(args), overrides)            # a bad scene stops here, before anything runs
    if args.out is not None:
        from gyro_instrument.views.typetest_view import check_pictures
        check_pictures(args.out, args.overwrite)
    result = run_typetest(scene_arg(args), overrides, latitudes, workers=args.workers,
                          progress=lambda m: print(m, file=sys.stderr))
    pictures = []
    if args.out is not None:
        from gyro_instrument.views.typetest_view import draw_typetest
        pictures = draw_typetest(result["curves"], args.out)
    if args.json:
        print(json.dumps(to_jsonable({"tests": result["tests"]}), indent=2))
    else:
        print_typetest(result["tests"])
    for path in pictures:
        print(f"wrote {path}", file=sys.stderr)
    return 0


def recover_command(args) -> int:
    """``gyro-instrument recover``: rewrite a damaged or cut bag's intact records (``--out``)."""
    from gyro_instrument.core.scene import EPOCH_NS
    from gyro_instrument.recording.bag_layout import bag_files, bag_inputs, scan_path
    from gyro_instrument.recording.mcap_io import recover
    bag_files(args.bag, "bag")
    check_output(args.out, "--out", bag_inputs(args.bag), args.overwrite)
    scan = scan_path(args.bag)
    n, scan = recover(args.bag, args.out, scan)
    print(f"recovered {n} messages from {args.bag} into {args.out}")
    for d in scan.damage_dicts(EPOCH_NS):
        print(f"  damaged: {damage_line(d)}")
    for note in scan.notes:
        print(f"  note: {note}")
    if scan.truncated:
        print("  note: the input was cut short (no summary): read up to its last complete record")
    return 0


def plot_command(args) -> int:
    """``gyro-instrument plot``: the standard views of a table or a bag to PNG."""
    import time
    from gyro_instrument.views import PlotOptions, plot_file
    from gyro_instrument.views.rosette import parse_window
    out = args.out or f"{os.path.basename(os.path.normpath(args.file)).rsplit('.', 1)[0]}_plots"
    t0 = time.perf_counter()
    window = parse_window(args.window)
    options = PlotOptions(scene=args.scene_option, overrides=args.overrides, topics=args.topics,
                          overwrite=args.overwrite, fmt=args.fmt, dpi=args.dpi, window=window, animate=args.animate,
                          table=table_options(args), given=given_table_flags(args))
    pngs, notes = plot_file(args.file, out, options)
    for note in notes:
        print(f"gyro-instrument: note: {note}", file=sys.stderr)
    views = [p for p in pngs if not p.endswith(".gif")]
    print(f"wrote {len(views)} views" + (" and an animation" if len(views) < len(pngs) else "")
          + f" in {time.perf_counter() - t0:.2f} s: " + ", ".join(pngs))
    return 0


def replay_command(args) -> int:
    """``gyro-instrument replay``: the estimate from a recorded bag (:func:`replay_bag`)."""
    result = replay_bag(args.bag, args.scene_option, args.overrides, args.topics)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print_estimate(result)
    return 0


def plan_command(args) -> int:
    """``gyro-instrument plan``: see :mod:`gyro_instrument.estimators.planner`."""
    from gyro_instrument.estimators.planner import NOISE_FACTORS, RATE_FACTORS, parse_targets, plan, verify_plan
    targets = parse_targets(args.targets)
    if args.verify and args.seeds < 2:
        raise SceneError("--seeds", args.seeds, "must be an integer >= 2 (the rms of the Monte Carlo)")
    err = lambda m: print(m, file=sys.stderr)  # noqa: E731
    d = plan(args.scene, args.overrides, targets, args.noise_factors or NOISE_FACTORS,
             args.rate_factors or RATE_FACTORS, floor=not args.no_floor)
    if args.verify:
        verify_plan(d, args.seeds, progress=err)
    d = to_jsonable(d)
    if args.json:
        print(json.dumps(d, indent=2))
    else:
        print_plan(d)
    return 0


#: Subcommand name -> its function (``args`` in, exit status out).
COMMANDS = {
    "scenes": scenes_command,
    "describe": describe_command,
    "simulate": simulate_command,
    "estimate": estimate_command,
    "bench": bench_command,
    "plan": plan_command,
    "sweep": sweep_command,
    "typetest": typetest_command,
    "recover": recover_command,
    "plot": plot_command,
    "replay": replay_command,
}
