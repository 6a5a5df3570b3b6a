"""The one argument parser of ``gyro-instrument`` (every subcommand, ``run`` included: the ROS
nodes' parameters mirror the scene arguments) and the scene arguments' readers."""

import argparse
from typing import NoReturn

from gyro_instrument import api
from gyro_instrument.cli.interrupt import EXIT_INTERRUPTED
from gyro_instrument.core.angle_formats import ANGLE_UNITS
from gyro_instrument.core.angle_formats import FORMATS as ANGLE_FORMATS
from gyro_instrument.core.errors import SceneError

EXIT_BAD_INPUT = 2
EXIT_INTEGRATION_FAILED = 3
EXIT_CLOSED_PIPE = 141
#: ``--time-unit``: the units of ``--data`` (s, ms, us, ns, min) and, for ``--reversal-points``, clock
#: times (hms); equal to ``estimators.north.field_book_read.TIME_UNITS`` (tests/test_field_books.py)
BOOK_TIME_UNITS = ("s", "ms", "us", "ns", "min", "hms")


def add_scene_arguments(parser, positional=True) -> None:
    """The scene arguments shared by every subcommand (and mirrored by the ROS parameters).
    ``positional=False``: the scene is the option ``--scene`` (replay, plot); ``"optional"``: either
    (estimate: ``estimate SCENE`` or ``estimate --data FILE --scene SCENE``)."""
    scene_help = "shipped scene name (see 'gyro-instrument scenes') or a YAML path"
    if positional is True:
        parser.add_argument("scene", help=scene_help)
    else:
        if positional == "optional":
            parser.add_argument("scene", nargs="?", default=None, help=scene_help)
        parser.add_argument("--scene", dest="scene_option", default=None, metavar="SCENE",
                            help=scene_help + (" (the same as the positional SCENE)" if positional else ""))
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene value, e.g. --set site.latitude_deg=-33.87 "
                             "--set instruments.pendulum.length_m=20 (repeatable; values are YAML). "
                             "null removes: effects.NAME=null drops that effect (also from every "
                             "instrument's effects list), instruments.NAME=null drops that instrument "
                             "(not the last one); on any other key null restores its default (refused "
                             "if it has none). A new instrument needs its type: --set "
                             "instruments.p2.type=spherical_pendulum --set instruments.p2.length_m=10. "
                             "Unknown names get the closest match. Scene format: docs/formats/scene.md")
    parser.add_argument("--duration-s", type=float, default=None,
                        help="simulated time per instrument, s (default: the scene's duration_s)")


def add_scene_option(parser, scene_help, set_help="override a value of the --scene scene (as for 'estimate')",
                     dest="scene_option", topics_help=None) -> None:
    """``--scene SCENE`` and ``--set KEY=VALUE`` for a subcommand whose main input is a file or a bag
    (replay, plot, bench), and with ``topics_help`` the ``--topic INSTRUMENT=/TOPIC`` remaps of a
    foreign bag (:func:`gyro_instrument.recording.foreign.parse_topic_remaps`)."""
    parser.add_argument("--scene", dest=dest, default=None, metavar="SCENE", help=scene_help)
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=set_help)
    if topics_help:
        parser.add_argument("--topic", dest="topics", action="append", default=[], metavar="INSTRUMENT=/TOPIC",
                            help=topics_help)


def scene_arg(args) -> str | None:
    """The scene named by the positional SCENE or ``--scene`` (None when neither is given).

    Raises
    ------
    SceneError
        Both are given and differ.
    """
    pos, opt = getattr(args, "scene", None), getattr(args, "scene_option", None)
    if pos and opt and pos != opt:
        raise SceneError("--scene", opt, f"conflicts with the scene {pos!r} given before it; give one")
    return pos or opt


def scene_from_args(args) -> "Scene":
    """Load the scene named on the command line with its overrides."""
    return api.load_scene(scene_arg(args), args.overrides, getattr(args, "duration_s", None))


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors on one line (no usage block), like every other error here; exit 2."""

    def error(self, message) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser(run=False) -> argparse.ArgumentParser:
    """The one argument parser of ``gyro-instrument``; ``run``: with the ROS subcommand ``run``
    (:func:`add_run_command`; the console script :mod:`gyro_instrument.ros.cli` runs it)."""
    parser = OneLineParser(
        prog="gyro-instrument",
        description="Gyrocompass and Foucault pendulum on the rotating Earth (Quet 1853, Puiseux 1852).")
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("scenes", help="list the shipped scenes")
    _add_scene_commands(sub)
    _add_bag_commands(sub)
    _add_study_commands(sub)
    _add_recover_command(sub)
    if run:
        add_run_command(sub)
    return parser


def _add_scene_commands(sub):
    """describe, simulate, estimate: a scene in, a description, a table or an estimate out."""
    p = sub.add_parser("describe", help="list a scene's instruments, active effects and the estimated size of "
                                        "every effect each instrument supports")
    add_scene_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p = sub.add_parser("simulate", help="simulate a scene and write every instrument channel to CSV or Parquet")
    add_scene_arguments(p)
    p.add_argument("--out", required=True, metavar="FILE.csv|FILE.parquet",
                   help="output table: time_s, then <instrument>.<channel> in rad, rad/s or m (see docs/formats/csv.md); "
                        "Parquet (float64 columns, pyarrow) for a name ending in .parquet, else CSV (full precision); "
                        "written block by block as the run streams to FILE.partial, renamed when complete (a Ctrl-C "
                        "leaves no partial file); refused before the run when it would not fit on the disk; "
                        "an existing file is refused unless --overwrite; never the scene file. The scene (YAML, seed, "
                        "units, package version, the mount of each scale reading) goes into Parquet's key-value "
                        "metadata (gyro_instrument.scene_yaml, ...) or, for a CSV, into <name>.scene.yaml beside it "
                        "(same overwrite rule). A horizontal gyroscope's angle is its scale reading u + M, as the "
                        "sensor reads it")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--output-rate-hz", type=float, default=None, metavar="HZ",
                   help="write every k-th sample, k = sample_rate_hz / HZ (a whole number; HZ <= sample_rate_hz): "
                        "the integration and its sample grid are unchanged")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p = sub.add_parser("estimate", help="simulate the scene's instruments through their sensors and estimate "
                                        "latitude and Earth rate (Quet items 8-9, Foucault) with standard errors; "
                                        "with --data, estimate from measured data instead")
    add_scene_arguments(p, positional="optional")
    p.add_argument("--data", metavar="FILE.csv|FILE.parquet",
                   help="estimate from this table of measured channels instead of simulating: time_s and "
                        "<instrument>.<channel> columns as in docs/formats/csv.md (pendulums: x_east, y_north in m or "
                        "deflection_east, deflection_north in rad; gyroscopes: their angle and spin_rate); the scene "
                        "gives the instruments (types, lengths, inertia ratios) and the site's nominal values "
                        "(without --scene: the scene the table carries, written by simulate, noted on stderr). "
                        "Missing values, NaN, gaps, irregular and out-of-order times are accepted and noted; a "
                        "gyroscope without spin_rate takes the scene's constant spin (noted). CSV: UTF-8 (a "
                        "byte-order mark is read), separator sniffed from the header (',' or ';' with decimal "
                        "commas, or tab). Parquet: time_s may be a timestamp (seconds from the earliest sample) "
                        "or a duration")
    p.add_argument("--time-column", default="time_s", metavar="NAME",
                   help="with --data: the table's time column (default time_s)")
    p.add_argument("--time-unit", default=None, choices=list(BOOK_TIME_UNITS) + ["h", "day"],
                   help="with --data: unit of a numeric time column, converted to s (s, ms, us, ns, min, h, day: "
                        "Excel serial days; default s; "
                        "not for a Parquet timestamp or duration, which carries its unit); with --reversal-points: "
                        "the unit of a bare time column (also hms: clock times mm:ss or hh:mm:ss)")
    p.add_argument("--angle-unit", default=None, choices=list(ANGLE_UNITS),
                   help="with --data: unit of the angle channels angle, outer_angle, inner_angle, "
                        "deflection_east, deflection_north, index (rad or deg; default rad; x_east/y_north stay m, "
                        "spin_rate and rate rad/s); with --reversal-points: the unit of a bare reading column, any unit a "
                        "header takes (dms: 179°01'56\", 179.01.56, 179 01 56, 179-01-56; ddmmss: 179.0156; div: "
                        "scale divisions of --scale-division)")
    p.add_argument("--reversal-points", metavar="FILE.csv",
                   help="estimate north from a field book instead of simulating: a CSV of turning-point readings "
                        "of the circle (clockwise), one a row, header reading_<unit> (rad, mrad, deg, gon, mgon, "
                        "arcmin, arcsec, dms, ddmmss, div), optional time_<tunit> (s, min, hms, ...), "
                        "tape_reading_<unit>, tape_time_<tunit>, turning_point, side, remark; a row with an empty "
                        "reading is a missed turning point. Gives the Schuler mean and Lavrov's estimate with "
                        "their sigma from the scatter, the mount azimuth and the circle reading of north; --scene "
                        "is optional (its latitude and tape; a book without tape readings on a scene with a tape "
                        "takes the scene's tape, said in the output) (msg_docs/estimate.md)")
    p.add_argument("--angle-format", default="deg", choices=list(ANGLE_FORMATS),
                   help="the text output's north angles: deg (179.832222°), dms (179°49'56.0\") or gon "
                        "(199.81358 gon); the JSON always carries degrees, the d°m′s″ string and gon")
    p.add_argument("--scale-division", metavar="VALUE", default=None,
                   help="with --reversal-points: the value of one scale division for div columns, a number and "
                        "its unit, e.g. 10arcmin or 0.1852gon")
    p.add_argument("--column", dest="columns", action="append", default=[], metavar="NAME=SOURCE",
                   help="with --data: read the table's column SOURCE as the channel column NAME, e.g. "
                        "--column gyro_horizontal.angle=Theta (repeatable)")
    p.add_argument("--separator", default=None, choices=[",", ";", "tab"],
                   help="with --data or --reversal-points, CSV: the field separator (default: sniffed from the "
                        "header line; ';' reads decimal commas)")
    add_camera_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (documented in msg_docs/estimate.md)")


def add_camera_arguments(p, when="with --data: ") -> None:
    """A camera track's table options (estimators/table_camera.py; docs/formats/csv.md); ``when`` starts
    each help ("with --data: " for estimate, "" for plot, whose FILE is the table)."""
    p.add_argument("--metres-per-pixel", type=float, default=None, metavar="S",
                   help=f"{when}the track's x_east, y_north are pixels of S metres each (the ellipse correction "
                        "scales as S squared; positions that cannot be metres exit 2 asking for it)")
    p.add_argument("--y-down", action="store_true", help=f"{when}the image y axis points down (y is negated)")
    p.add_argument("--rotation-deg", type=float, default=None, metavar="A",
                   help=f"{when}the camera's x axis is A degrees from east, counter-clockwise seen from above")
    p.add_argument("--frame-column", default=None, metavar="NAME",
                   help=f"{when}time from this column's frame numbers (with --frame-rate; instead of "
                        "--time-column)")
    p.add_argument("--frame-rate", type=float, default=None, metavar="HZ", help="with --frame-column: frames per second")
    p.add_argument("--no-header", action="store_true",
                   help=f"{when}CSV: the file has no header row (name its columns with --names)")
    p.add_argument("--names", default=None, metavar="A,B,C", help="with --no-header: the columns' names, in order")


def add_table_arguments(p) -> None:
    """plot: every table option of ``estimate --data`` (the same reader, estimators/table_read.py)."""
    from gyro_instrument.estimators.table_read import ANGLE_UNITS as TABLE_ANGLE_UNITS
    from gyro_instrument.estimators.table_read import TIME_UNITS as TABLE_TIME_UNITS
    p.add_argument("--time-column", default="time_s", metavar="NAME",
                   help="a table's time column (default time_s)")
    p.add_argument("--time-unit", default=None, choices=list(TABLE_TIME_UNITS),
                   help="unit of a numeric time column, converted to s (default s; day: Excel serial days)")
    p.add_argument("--angle-unit", default=None, choices=list(TABLE_ANGLE_UNITS),
                   help="unit of the angle channels (default rad)")
    p.add_argument("--column", dest="columns", action="append", default=[], metavar="NAME=SOURCE",
                   help="read the table's column SOURCE as the channel column NAME, e.g. --column "
                        "pendulum.x_east=X (repeatable)")
    p.add_argument("--separator", default=None, choices=[",", ";", "tab"],
                   help="CSV: the field separator (default: sniffed from the header line; ';' reads decimal commas)")
    add_camera_arguments(p, when="")


def _add_bag_commands(sub):
    """replay, plot: a recorded bag or a table in."""
    p = sub.add_parser("replay", help="run the estimator over a recorded bag without DDS; reproduces the "
                                      "live 'run' estimate to the last digit. Every chunk's CRC is checked: a "
                                      "damaged chunk is left out and the log-time span it held is reported")
    p.add_argument("bag", help="a bag written by 'gyro-instrument run --bag' or the recorder node: an .mcap file "
                               "or a rosbag2 bag directory (metadata.yaml + .mcap files, split or not)")
    p.add_argument("--json", action="store_true", help="print the same JSON object as 'estimate', with "
                                                       "'damaged' and 'replay_notes' when the bag lost data")
    add_scene_option(p, "the scene of a bag recorded by another tool (no gyro_instrument record; or to use instead "
                        "of the bag's record): the instruments' topics are found by the documented names and types "
                        "(/<instrument>/joint_states, sensor_msgs/msg/JointState, joints as in msg_docs/topics.md); "
                        "the JSON gains 'topics' (matched, unmatched with the reason, unused)",
                     topics_help="read this instrument's JointState from another topic (repeatable)")
    p = sub.add_parser("plot", help="draw the standard views of a table or a bag: angles over time (degrees), "
                                    "the swing-plane azimuth with its expected line from the release (rate in "
                                    "deg/h, full turn in hours), the rosette (the bob seen from above, coloured by "
                                    "time), the fit residuals; --animate adds animation.gif (needs matplotlib: pip "
                                    "install 'gyro_instrument[plot]')")
    p.add_argument("file", help="a CSV or Parquet table (docs/formats/csv.md), an .mcap or a rosbag2 bag directory, or "
                                "a field book (a CSV with a reading_<unit> column, as for estimate --reversal-points: "
                                "one view, field_book: readings, turning points, centre, north)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="directory for angles, swing_azimuth, bob_path (the rosette) and residuals .png/.svg/.pdf "
                        "(default: <file name>_plots in the current directory); files already there are refused "
                        "unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace the view files already in --out")
    p.add_argument("--format", dest="fmt", default="png", choices=["png", "svg", "pdf"],
                   help="file format of the views (default png)")
    p.add_argument("--dpi", type=float, default=110, help="resolution of a PNG (default 110: 1760 px wide)")
    p.add_argument("--window", default=None, metavar="START:END",
                   help="the rosette's time window, seconds since release (default: the whole record; either "
                        "side may be empty, e.g. 0:600)")
    p.add_argument("--animate", action="store_true",
                   help="also write animation.gif: the bob's path and turning swing plane seen from above (a "
                        "gyroscope: its axis swinging about the meridian), a day in about 20 s, with a clock and "
                        "the latitude")
    add_table_arguments(p)
    add_scene_option(p, "the scene (a table's instrument types and lengths, a foreign bag's instruments; the "
                        "expected line's latitude). A bag written by this package carries its own, and so does "
                        "a table written by 'simulate' (used when --scene is absent, noted)",
                     set_help="override a value of the --scene scene",
                     topics_help="a foreign bag's topic for an instrument (as for replay)")


def _add_study_commands(sub):
    """bench, plan: studies over many runs."""
    p = sub.add_parser("bench", help="what accuracy costs: work-precision by fidelity tier, speed targets, "
                                     "real-time factors, latitude and Earth-rate error versus observation time "
                                     "with the systematic floors, a site sweep, effect cost; CSV, PNG (with "
                                     "matplotlib) and summary.md in --out")
    p.add_argument("--quick", action="store_true", help="short runs and few seeds (about a minute; the full "
                                                        "bench, with a sidereal day of the pendulum, takes minutes)")
    p.add_argument("--out", default="bench_out", metavar="DIR", help="output directory (default bench_out)")
    add_scene_option(p, "run only the observation-time study (error versus observation time, systematic floors "
                        "with the scene's own effects) and the planner's accuracy on this scene (name or YAML path)",
                     set_help="override a value of the --scene (as for 'estimate')", dest="scene")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the sweeps (observation time, site sweep, effect cost; with --scene, its "
                        "observation-time study and planner accuracy) on the Dask cluster whose "
                        "scheduler is at ADDRESS (tcp://HOST:8786; its workers need gyro_instrument installed) "
                        "instead of local processes; needs the 'cluster' extra (pip install "
                        "'gyro_instrument[cluster]')")
    _add_sweep_command(sub)
    _add_typetest_command(sub)
    p = sub.add_parser("plan", help="how long must I observe? the observation time per configuration each "
                                    "--target needs (Cramer-Rao bound of the scene's sensor model), its dependence "
                                    "on the time, the systematic floor, the effect of the sensor's noise and "
                                    "rate, and Quet's counting for the same target")
    p.add_argument("scene", help="shipped scene name (see 'gyro-instrument scenes') or a YAML path")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene value, as for 'estimate' (e.g. --set "
                        "instruments.gyro_meridian.spin_rate_turn_s=200); duration_s is what is planned")
    p.add_argument("--target", dest="targets", action="append", default=[], metavar="NAME=VALUE",
                   help="a 1-sigma accuracy wanted (repeatable): latitude_arcsec, latitude_deg, latitude_rad, "
                        "earth_rate_rad_s, earth_rate_deg_h, or the mount azimuth of a horizontal gyroscope "
                        "(north): azimuth_arcsec, azimuth_mgon, azimuth_deg (the time per north method and for the "
                        "fit; for a rate gyro the sequences of its positions and the fastest schedule), e.g. --target latitude_arcsec=1 --target earth_rate_rad_s=1e-10 --target "
                        "azimuth_arcsec=3")
    p.add_argument("--noise-factor", dest="noise_factors", action="append", type=float, default=None,
                   metavar="X", help="sensitivity: replan with the sensor noise times X (repeatable; default 0.1 and 10)")
    p.add_argument("--rate-factor", dest="rate_factors", action="append", type=float, default=None,
                   metavar="X", help="sensitivity: replan with the sample rate times X (repeatable; default 2 and 0.5)")
    p.add_argument("--no-floor", action="store_true",
                   help="skip the noise-free run at the planned time (the systematic floor)")
    p.add_argument("--verify", action="store_true",
                   help="run a seeded Monte Carlo at each planned time (process pool, progress on stderr) and "
                        "print the achieved rms next to the target")
    p.add_argument("--seeds", type=int, default=100, help="seeds for --verify (default 100)")
    p.add_argument("--json", action="store_true", help="print one JSON object (documented in docs/formats/plan.md)")


def _add_sweep_command(sub):
    """sweep: any scene over a grid of values, seeds on each point, one Parquet row per (point, seed)."""
    p = sub.add_parser("sweep", help="run a scene over a grid of values (--vary, repeatable: the product) with "
                                     "--seeds seeds measured on one simulation per grid point; one Parquet row "
                                     "per (point, seed): the varied values (columns named by their keys), seed, "
                                     "every field of the estimate JSON flattened (nested as dotted names, lists "
                                     "as JSON text, the truth as truth.*) and error (a refused estimate, or a "
                                     "task that failed twice: a dead worker's task is retried once)")
    add_scene_arguments(p)
    p.add_argument("--vary", dest="vary", action="append", default=[], metavar="KEY=START:STOP:STEP",
                   help="a scene key over START, START+STEP, ... up to STOP (included when it lands on the grid "
                        "within 1e-9 of a STEP), e.g. --vary site.latitude_deg=-60:60:30 (repeatable; at most "
                        "10000 grid points; every point's scene is checked before anything runs)")
    p.add_argument("--seeds", type=int, default=10, help="sensor seeds 0..N-1 per grid point (default 10)")
    p.add_argument("--out", required=True, metavar="FILE.parquet",
                   help="the Parquet table to write; an existing file is refused unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the grid points on the Dask cluster whose scheduler is at ADDRESS (tcp://HOST:8786; "
                        "its workers need gyro_instrument installed) instead of a local process pool; needs the "
                        "'cluster' extra")
    p.add_argument("--timeout", type=float, default=10.0, metavar="S",
                   help="with --scheduler: seconds to wait for the scheduler to answer, when it has no "
                        "workers for one to join, and for the cluster's versions and every worker's import of "
                        "gyro_instrument (another Dask, Python or gyro_instrument version, or a worker without "
                        "it: exit 2 naming them), before exit 2 (default 10)")


def _add_typetest_command(sub):
    """typetest: a marine gyrocompass through the type tests of ISO 22090-1 (docs/typetest.md)."""
    p = sub.add_parser("typetest", help="run the type tests of ISO 22090-1 sections 6.2-6.9 on every marine_gyrocompass "
                                        "of the scene at each latitude (the scene's own latitude and motion block "
                                        "are not used) and compare each figure with its limit (sections 5.2-5.3, "
                                        "IMO A.424(XI) and A.821(19) beside them): a table of PASS/FAIL rows "
                                        "(docs/typetest.md)")
    p.add_argument("scene", help="shipped scene name (see 'gyro-instrument scenes') or a YAML path, with at least "
                                 "one marine_gyrocompass")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a value of the scene, as for 'simulate' (e.g. --set "
                        "instruments.sperry.latitude_setting_deg=0); the site's latitude, duration_s and the "
                        "motion block are not used by the tests")
    p.add_argument("--latitudes", default=None, metavar="LAT,LAT,...",
                   help="comma-separated latitudes in degrees, each in [-88, 88] (default 0,30,45,60,70,-45,-70); "
                        "a negative first one needs the = form: --latitudes=-23.5,61")
    p.add_argument("--json", action="store_true",
                   help='print {"tests": [{"clause", "name", "latitude_deg", "value", "limit", "unit", "pass", '
                        '"instrument", "note", "imo"}, ...]}, one row per test, latitude and compass; value null '
                        '(pass false) when the figure cannot be measured, with the reason in note')
    p.add_argument("--out", default=None, metavar="DIR",
                   help="also draw, per compass, the settling curve (heading error against time, the 0.7-deg band) "
                        "and the spiral (tilt against azimuth) at every latitude as settling_<compass>.png and "
                        "spiral_<compass>.png (needs matplotlib); files already there are refused unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace the pictures already in --out")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes for the (compass, latitude) pairs (default: the CPU count; 1: in this process)")


def _add_recover_command(sub):
    """recover: a damaged or cut bag rewritten."""
    p = sub.add_parser("recover", help="rewrite a recording truncated inside its data (no footer: disk "
                                       "full, copied mid-write) or damaged (chunks failing their CRC, a broken "
                                       "summary) into a complete, indexed MCAP of its intact records; the lost "
                                       "spans are printed and kept in the new file (metadata "
                                       "'gyro_instrument_damage'). Exit 2 when nothing intact is found")
    p.add_argument("bag", help="the damaged .mcap, or a rosbag2 bag directory (every file is read; the "
                               "output is one .mcap)")
    p.add_argument("--out", required=True, metavar="FIXED.mcap",
                   help="where to write the recovered file: never the input; an existing file is refused "
                        "unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file (never the input)")



def add_run_command(sub) -> None:
    """run: every node of the scene in one process over DDS (the ROS suite, :mod:`gyro_instrument.ros`)."""
    p = sub.add_parser("run", help="run every node of the scene in one process (simulators, estimator, "
                                   "recorder) over DDS on loopback and print the recovered latitude and "
                                   "Earth rate next to the truth")
    add_scene_arguments(p)
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
    p.add_argument("--nmea-udp", metavar="HOST:PORT", default=None,
                   help="send the heading of the scene's first horizontal gyroscope or rate gyro (its scale "
                        "zero's azimuth) as NMEA 0183 $HEHDT sentences, one UDP datagram each, to HOST:PORT "
                        "([IPV6]:PORT; IANA's NMEA port is 10110; a HOST that resolves to several addresses, as "
                        "localhost to ::1 and 127.0.0.1, gets each sentence at every one, noted once): from the "
                        "first swing (a rate gyro: its first sequence of positions) on at 10 Hz of sim time (every "
                        "sample of a slower instrument) as the estimate converges, and with the final estimate "
                        "(the estimator's parameter nmea_udp); a scene with a marine gyrocompass: its node sends the "
                        "first compass's reading at 10 Hz of sim time (its parameter nmea_udp)")
    p.add_argument("--json", action="store_true", help="print the same JSON object as 'estimate'")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.epilog = ("Everything after --ros-args goes to the nodes (remapping, log levels, -p for parameters "
                "the suite does not set itself), e.g. gyro-instrument run quet_paris --ros-args "
                "--log-level warn")
    p.add_argument("--stats", action="store_true",
                   help="print the suite's statistics (samples, wall time, real-time factor, messages recorded "
                        "per topic) as one JSON line on stderr (implies --quiet)")
