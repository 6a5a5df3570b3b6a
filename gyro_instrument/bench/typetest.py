"""``gyro-instrument typetest``: the type test of a ship's gyrocompass on the emulator (issue 39 step 2).

Each marine gyrocompass of the scene is put through the test methods of ISO 22090-1 §6.2–6.9 at each
latitude (:mod:`.typetest_runs`) and every figure is compared with its limit (§5.2–5.3), one row per
test, latitude and compass. The scene's site latitude and ``motion:`` block are not used: every test
builds its own pier, table or ship at the latitude tested.

Sources of the limits (the standards' public texts): ISO 22090-1 (the Japanese
translation site nippon.zaidan.info/seikabutsu/2000/00393/contents/003.htm, 005.htm §5.3, 006.htm §6.4–6.6);
IMO A.821(19) (high-speed craft; puc.overheid.nl/nsi/doc/PUC_2513_14/1/ §4.1–4.2); IMO A.424(XI)'s class
figures as summarised in nippon.zaidan.info/seikabutsu/2000/00402/contents/006.htm (its own text was
not stored past §2). Where a figure's clause was not in the stored text the row says whose it is.

A row's ``pass`` is ``value <= limit`` (the standard's "shall not exceed", "within" and "less than"
read alike); a figure the physics cannot give (a compass that did not settle, so that nothing after
settling can be measured) is ``value: null`` and ``pass: false`` with the reason in ``note``.
"""

import math
import os
from dataclasses import dataclass

from gyro_instrument.bench import typetest_runs as tr
from gyro_instrument.core.errors import IntegrationError, SceneError

#: The names of the tests, in the table's order.
NAMES = ("settling_time", "settle_point_error", "settle_point_rms", "repeatability", "scorsby_settling",
         "dynamic_error", "speed_error_residual", "speed_change", "course_change", "follow_up")
#: Default latitudes, degrees: the standard's range (0 to 70°) and both hemispheres.
DEFAULT_LATITUDES = (0.0, 30.0, 45.0, 60.0, 70.0, -45.0, -70.0)
#: ISO 22090-1 §5.3.3 and A.821(19) §4.1.1: latitudes up to 70° N or S.
STANDARD_LATITUDE_DEG = 70.0
#: --latitudes' valid range, degrees (a sea run sails 4° toward the equator; the track must stay within 89°).
LATITUDE_LIMIT_DEG = 88.0


@dataclass(frozen=True)
class Clause:
    """A test's clause (method and limit), its limit (``sec``: times sec φ), unit and the IMO figures."""

    clause: str
    limit: float
    unit: str
    sec: bool
    imo: str


CLAUSES = {
    "settling_time": Clause("ISO 22090-1 §6.2; limit §5.2 (settled: §3.10)", 6.0, "h", False,
                            "A.424(XI): 6 h up to 60 deg; A.821(19) §4.1.1: 6 h up to 70 deg"),
    "settle_point_error": Clause("ISO 22090-1 §6.3; limit §5.2 (§3.11-3.12)", 0.75, "deg", True,
                                 "A.424(XI) class A and A.821(19) §4.1.2: the same 0.75 sec(lat)"),
    "settle_point_rms": Clause("ISO 22090-1 §6.3 readings; limit A.821(19) §4.1.2 (not in the stored ISO text)",
                               0.25, "deg", True, "A.821(19) §4.1.2: < 0.25 sec(lat)"),
    "repeatability": Clause("ISO 22090-1 §6.4 (three run-ups, any two within)", 0.35, "deg", True,
                            "A.821(19) §4.1.3: 0.25 sec(lat)"),
    "scorsby_settling": Clause("ISO 22090-1 §6.5; limit §5.3.1", 6.0, "h", False, "A.821(19) §4.2.1: the same"),
    "dynamic_error": Clause("ISO 22090-1 §6.6; limit §5.3.2", 1.5, "deg", True,
                            "A.424(XI): 1.0 sec(lat) (turn rate < 5 deg/s, as summarised); A.821(19) §4.2.2: "
                            "1.0 sec(lat)"),
    "speed_error_residual": Clause("ISO 22090-1 §6.9; limit §5.3.3 (20 kn, 10-deg band)", 0.35, "deg", True,
                                   "A.821(19) §4.2.3: 0.25 sec(lat) at 70 kn"),
    "speed_change": Clause("ISO 22090-1 §5.3.3 (20 kn change, <= 2.0 m/s^2)", 3.0, "deg", False,
                           "A.821(19) §4.2.3: 2 deg for 70 kn"),
    "course_change": Clause("ISO 22090-1 §5.3.3 (180 deg at up to 20 deg/s, <= 20 kn, <= 2.0 m/s^2)", 4.5, "deg",
                            False, "A.821(19) §4.2.3: 3 deg at 70 kn"),
    "follow_up": Clause("ISO 22090-1 §5.3.4 (follow-up error §3.9)", 0.5, "deg", False,
                        "A.821(19): output at >= 10 readings/s"),
}
#: §5.3.4's second limit: between 10 and 20 deg/s.
FOLLOW_UP_FAST_LIMIT_DEG = 1.5


def parse_latitudes(text) -> tuple:
    """``--latitudes`` (comma-separated degrees) -> a tuple of floats.

    Raises
    ------
    SceneError
        Naming ``--latitudes``, the value and the valid range, for an empty item, a word, a non-finite
        number or one outside ±:data:`LATITUDE_LIMIT_DEG`.
    """
    valid = (f"must be comma-separated latitudes in degrees, each in [-{LATITUDE_LIMIT_DEG:g}, "
             f"{LATITUDE_LIMIT_DEG:g}], e.g. --latitudes=-23.5,61")
    out = []
    for item in str(text).split(","):
        try:
            v = float(item.strip())
        except ValueError:
            raise SceneError("--latitudes", text, valid) from None
        if not math.isfinite(v) or abs(v) > LATITUDE_LIMIT_DEG:
            raise SceneError("--latitudes", text, valid)
        out.append(v)
    return tuple(out)


def row(name, instrument, lat_deg, value, note="", limit=None) -> dict:
    """One row: its clause, the limit at ``lat_deg`` (sec φ applied), ``pass`` = value <= limit (False for a
    value of None, with ``note`` saying why)."""
    c = CLAUSES[name]
    if limit is None:
        limit = c.limit / math.cos(math.radians(lat_deg)) if c.sec else c.limit
    ok = value is not None and math.isfinite(value) and value <= limit
    if abs(lat_deg) > STANDARD_LATITUDE_DEG:
        note = "; ".join(filter(None, (note, f"beyond the standard's {STANDARD_LATITUDE_DEG:g} deg: its limit "
                                            f"extrapolated")))
    return {"instrument": instrument, "clause": c.clause, "name": name, "latitude_deg": lat_deg,
            "value": None if value is None else float(value), "limit": float(limit), "unit": c.unit,
            "pass": bool(ok), "note": note, "imo": c.imo}


def compass_names(scene) -> list:
    """The scene's marine gyrocompasses (instances of the class that sails and reads a heading).

    Raises
    ------
    SceneError
        The scene has none.
    """
    from gyro_instrument.instruments import REGISTRY
    from gyro_instrument.instruments.marine_gyrocompass import MarineGyrocompass
    names = [n for n, (t, _, _) in scene.instruments.items() if issubclass(REGISTRY[t], MarineGyrocompass)]
    if not names:
        raise SceneError("scene", scene.name, f"has no {MarineGyrocompass.type_name} instrument to type-test; "
                                              f"try the shipped scene marine_gyrocompass")
    return names


def not_settled(names, instrument, lat_deg, why) -> list:
    """FAIL rows (value null) for the tests ``names`` that need a settled compass (``why`` on one line)."""
    why = " ".join(str(why).split())
    return [row(n, instrument, lat_deg, None, f"not measured: {why}") for n in names]


def type_test_compass(scene, name, lat_deg, which=NAMES) -> dict:
    """Every test of ``which`` on the compass ``name`` at ``lat_deg`` (:mod:`.typetest_runs`). Returns
    {"rows": [...], "curve": the first run-up's readings (t s, error, azimuth, tilt deg) for the pictures}."""
    rows, which = [], set(which)
    up = tr.run_up(scene, name, lat_deg)
    run = up["run"]
    settled_at = up["settle_s"]
    period = tr.compass_at(scene, name, lat_deg).predictions()["undamped_period_s"]
    why = (f"did not settle within {tr.MAX_RUN_UP_S / 3600:g} h on a pier (§3.10; undamped period here "
           f"{period / 60:.0f} min)")
    if "settling_time" in which:
        rows.append(row("settling_time", name, lat_deg, None if settled_at is None else settled_at / 3600,
                        why if settled_at is None else ""))
    need = [n for n in NAMES if n in which and n not in ("settling_time", "scorsby_settling", "follow_up")]
    settled = run.final
    if settled_at is None or up["settle_point"] is None:
        rows += not_settled(need, name, lat_deg, why)
    else:
        rows += _settled_rows(scene, name, lat_deg, up, settled, which)
    if "scorsby_settling" in which:
        ts = tr.scorsby_settling(scene, name, lat_deg)
        rows.append(row("scorsby_settling", name, lat_deg, None if ts is None else ts / 3600,
                        "" if ts is not None else "did not settle within 6 h on the Scorsby table"))
    if "follow_up" in which:
        rows += _follow_up_rows(scene, name, lat_deg, settled)
    curve = {"t_s": run.t, "error_deg": run.error_deg, "azimuth_deg": run.azimuth_deg, "tilt_deg": run.tilt_deg,
             "settle_s": settled_at}
    order = {n: i for i, n in enumerate(NAMES)}
    return {"rows": sorted(rows, key=lambda r: order[r["name"]]), "curve": curve}


def _settled_rows(scene, name, lat_deg, up, settled, which) -> list:
    """The rows of the tests that start from a settled compass."""
    rows = []
    mean, rms = up["settle_point"]
    if "settle_point_error" in which:
        rows.append(row("settle_point_error", name, lat_deg, abs(mean), f"settle point error {mean:+.4f} deg"))
    if "settle_point_rms" in which:
        rows.append(row("settle_point_rms", name, lat_deg, rms))
    if "repeatability" in which:
        rows.append(_repeatability(scene, name, lat_deg, mean))
    if "dynamic_error" in which:
        rows.append(row("dynamic_error", name, lat_deg, tr.dynamic_error(scene, name, lat_deg, settled),
                        "roll 20 deg/6 s, pitch 10 deg/10 s for 25 min, compass 2.30 m above the axes; the yaw "
                        "5 deg/15 s is not run"))
    if which & {"speed_error_residual", "speed_change", "course_change"}:
        fast = tr.sea_run(scene, name, lat_deg, settled, tr.SPEED_KN, tr.turn_rate_deg_s(tr.SPEED_KN))
        if "speed_error_residual" in which:
            rows.append(row("speed_error_residual", name, lat_deg, abs(fast["steady"] - mean),
                            f"steady error at 20 kn {fast['steady']:+.4f} deg less the settle point error"))
        if "speed_change" in which:
            rows.append(row("speed_change", name, lat_deg, fast["speed_change"], "0 to 20 kn at 2.0 m/s^2, "
                                                                                 "north-south"))
        if "course_change" in which:
            v = tr.turn_speed_kn(tr.MAX_TURN_DEG_S)
            slow = tr.sea_run(scene, name, lat_deg, settled, v, tr.MAX_TURN_DEG_S)
            worst = max((fast["course_change"], f"20 kn at {tr.turn_rate_deg_s(tr.SPEED_KN):.1f} deg/s"),
                        (slow["course_change"], f"{v:.1f} kn at 20 deg/s"))
            rows.append(row("course_change", name, lat_deg, worst[0], f"worst of two turns (2.0 m/s^2): {worst[1]}"))
    return rows


def _repeatability(scene, name, lat_deg, first_mean) -> dict:
    """§6.4: two more run-ups switched on at the opposite initial heading error and at half of it; the
    largest difference between two of the three settle point headings."""
    a0 = float(scene.instruments[name][1]["initial_azimuth_deg"]) or 20.0
    means = [first_mean]
    for a in (-a0, a0 / 2):
        up = tr.run_up(scene, name, lat_deg, a)
        if up["settle_point"] is None:
            return row("repeatability", name, lat_deg, None, f"a run-up from {a:g} deg did not settle")
        means.append(up["settle_point"][0])
    return row("repeatability", name, lat_deg, max(means) - min(means),
               f"run-ups from {a0:g}, {-a0:g} and {a0 / 2:g} deg (the emulator is deterministic: only the "
               f"start differs)")


def _follow_up_rows(scene, name, lat_deg, settled) -> list:
    """§5.3.4: two rows, up to 10 deg/s (limit 0.5 deg) and 10-20 deg/s (1.5 deg)."""
    bw = float(scene.instruments[name][1]["follow_up_bandwidth_hz"])
    got = tr.follow_up(scene, name, lat_deg, settled)
    slow, fast = tr.FOLLOW_UP_RATES_DEG_S
    note = f"first-order follow-up, bandwidth {bw:g} Hz (lag r/(2 pi f)); a full turn at {{:g}} deg/s"
    return [row("follow_up", name, lat_deg, got[slow], note.format(slow)),
            row("follow_up", name, lat_deg, got[fast], note.format(fast), limit=FOLLOW_UP_FAST_LIMIT_DEG)]


def typetest_job(job) -> dict:
    """One (compass, latitude) in a worker: ``job`` = (scene name or path, overrides, compass, latitude,
    tests). A run that fails (an integration error, a track the motion refuses) gives FAIL rows saying so."""
    from gyro_instrument.scenes import load_scene
    scene_arg, overrides, name, lat, which = job
    scene = load_scene(scene_arg, list(overrides))
    return guarded_test(scene, name, lat, which)


def guarded_test(scene, name, lat, which=NAMES) -> dict:
    """:func:`type_test_compass`, with an integration failure or a refused run as FAIL rows (never a traceback)."""
    try:
        return type_test_compass(scene, name, lat, which)
    except (IntegrationError, SceneError) as exc:
        return {"rows": not_settled([n for n in NAMES if n in which], name, lat,
                                    f"{type(exc).__name__}: {exc}"), "curve": None}


def run_typetest(scene_arg, overrides=(), latitudes=DEFAULT_LATITUDES, which=NAMES, workers=None,
                 progress=None) -> dict:
    """The type test of every marine gyrocompass of the scene at every latitude.

    Returns {"tests": rows in (compass, latitude, test) order, "curves": {(compass, latitude): curve}}.
    Several (compass, latitude) pairs run in a process pool (:func:`gyro_instrument.core.parallel.run_tasks`,
    ``workers`` processes, default the CPU count); one runs here.

    Raises
    ------
    SceneError
        The scene does not load or has no marine gyrocompass.
    """
    from gyro_instrument.scenes import load_scene
    scene = load_scene(scene_arg, list(overrides))
    jobs = [(scene_arg, tuple(overrides), n, float(lat), tuple(which)) for n in compass_names(scene)
            for lat in latitudes]
    if len(jobs) == 1 or workers == 1:
        results = [guarded_test(scene, j[2], j[3], which) for j in jobs]
    else:
        from gyro_instrument.core.parallel import run_tasks
        done = (lambda d, n: progress(f"typetest: {d}/{n} (compass, latitude) done")) if progress else None
        results = run_tasks(typetest_job, jobs, on_done=done, workers=min(workers or os.cpu_count() or 1, len(jobs)))
    rows, curves = [], {}
    for job, res in zip(jobs, results):
        if "error" in res:
            res = {"rows": not_settled([n for n in NAMES if n in which], job[2], job[3], res["error"]), "curve": None}
        rows += res["rows"]
        if res.get("curve") is not None:
            curves[(job[2], job[3])] = res["curve"]
    return {"tests": rows, "curves": curves}
