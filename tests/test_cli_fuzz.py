"""Every subcommand, driven in-process through ``gyro_instrument.cli.main`` (``run`` through the
console script's ``gyro_instrument.ros.cli.main``) with random argument
lists and random scene overrides (hypothesis): the exit status is 0, 2 or 130, stderr never holds
a traceback, and a failure is one line on stderr.

Overrides use the real keys of the shipped scenes (and of every parameter of their instruments,
effects and sections), misspellings of them, and random YAML values: numbers including nan,
inf, huge and negative ones, strings, lists, null and nested mappings, and valid values at the
edges of each parameter's range (where the degenerate configurations are). Durations are always capped
(``--duration-s`` last wins) and a run still going after :data:`BUDGET_S` is interrupted by a
timer (exit 130 — which exercises the interrupt path in-process too), so the whole test stays
under a minute.
"""

import contextlib
import io
import os
import random
import shutil
import signal

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gyro_instrument.cli import main
from gyro_instrument.effects import REGISTRY as EFFECTS
from gyro_instrument.instruments import REGISTRY as INSTRUMENTS
from gyro_instrument.ros.cli import main as ros_main
from gyro_instrument.scenes import SENSOR_PARAMS, load_scene, scene_path, shipped_scene_names

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BAG = os.path.join(ROOT, "bags", "free_gyroscope.mcap")
SCENES = shipped_scene_names()
BUDGET_S = 3.0
DURATIONS = ["0.05", "0.3", "1", "2"]


def dotted(prefix, node):
    """Every dotted key path of a YAML mapping."""
    if isinstance(node, dict):
        for k, v in node.items():
            path = f"{prefix}.{k}" if prefix else str(k)
            yield path
            yield from dotted(path, v)


PARAMS = {}    # dotted key -> Param, for values at the edges of its range


def scene_keys(name):
    with open(scene_path(name)) as fh:
        keys = set(dotted("", yaml.safe_load(fh)))
    scene = load_scene(name)
    for iname, (itype, _, _) in scene.instruments.items():
        for p in INSTRUMENTS[itype].PARAMS:
            PARAMS[f"instruments.{iname}.{p.name}"] = p
        keys |= {f"instruments.{iname}.{p.name}" for p in INSTRUMENTS[itype].PARAMS}
        keys.add(f"instruments.{iname}.effects")
    keys |= {f"effects.{e}" for e in EFFECTS} | {f"sensor.{p.name}" for p in SENSOR_PARAMS}
    keys |= {"site.latitude_deg", "site.earth_rate_rad_s", "site.gravity_m_s2", "sample_rate_hz", "seed",
             "estimator.method", "duration_s"}
    return sorted(keys)


KEYS = {name: scene_keys(name) for name in SCENES}


def misspell(key, rnd):
    parts = key.split(".")
    i = rnd.randrange(len(parts))
    w = parts[i]
    if len(w) > 1:
        j = rnd.randrange(len(w))
        w = rnd.choice([w[:j] + w[j + 1:], w[:j] + w[j] * 2 + w[j:], w.upper(), w + "_x"])
    parts[i] = w
    return ".".join(parts)


numbers = st.one_of(st.sampled_from([0, -0.0, 1, -1, 1e-300, 1e300, -1e300, float("nan"), float("inf"),
                                     float("-inf"), 2 ** 63, -2 ** 63, 1e-9, 90, 180, 1e7]),
                    st.integers(-10 ** 6, 10 ** 6), st.floats(allow_nan=True, allow_infinity=True))
scalars = st.one_of(st.none(), st.booleans(), numbers, st.text(max_size=6),
                    st.sampled_from(["custom", "free", "locked", "vertical", "parareal", "ellipsoid", "[]", "{}",
                                     "nan", ".inf", "~", "1e5", "a: b", "- x", "[1, 2", "'"]))
values = st.recursive(scalars, lambda kids: st.one_of(st.lists(kids, max_size=4),
                                                      st.dictionaries(st.text(max_size=6), kids, max_size=3)),
                      max_leaves=8)


def yaml_text(v):
    if isinstance(v, str):
        return v                                   # raw text: the override parser reads it as YAML
    text = yaml.safe_dump(v, default_flow_style=True, width=10 ** 6).strip()
    return text[:-4].strip() if text.endswith("...") else text


def edge_values(p):
    """Valid values at and near the edges of a parameter's range (degenerate configurations live
    there: zero inertias, zero spin, poses at ±90°), or its choices."""
    if p.kind == "str":
        return list(p.choices) or ["x"]
    if p.kind == "bool":
        return [True, False]
    if p.kind == "vec3":
        return [[0, 0, 1], [1, 0, 0], [1e-300, 0, 0], [1, 1, 1e-12]]
    out = [0.0, 1e-12, -1e-12, 90.0, -90.0, 180.0, 1.0, 0.5]
    for b in (p.low, p.high):
        if abs(b) < 1e300:
            out += [b, b * (1 + 1e-12) + 1e-300, b * (1 - 1e-12)]
    return [v for v in out if p.low <= v <= p.high] or [1.0]


@st.composite
def overrides(draw, scene):
    out = []
    for _ in range(draw(st.integers(0, 3))):
        key = draw(st.sampled_from(KEYS[scene]))
        if key in PARAMS and draw(st.integers(0, 3)):
            value = draw(st.sampled_from(edge_values(PARAMS[key])))
        else:
            value = draw(values)
        if draw(st.integers(0, 7)) == 0:
            key = misspell(key, random.Random(draw(st.integers(0, 10 ** 6))))
        out += ["--set", f"{key}={yaml_text(value)}"]
    return out


@st.composite
def command_lines(draw, tmp):
    cmd = draw(st.sampled_from(["scenes", "describe", "simulate", "simulate", "estimate", "estimate", "replay",
                                "recover", "bench", "run", "plan", "typetest", "noise"]))
    scene = draw(st.sampled_from(SCENES))
    dur = ["--duration-s", draw(st.sampled_from(DURATIONS))]
    out = os.path.join(tmp, draw(st.sampled_from(["o.csv"] * 6 + ["no/such/dir/o.csv", ""])))
    if cmd == "scenes":
        argv = ["scenes"]
    elif cmd == "describe":
        argv = ["describe", scene] + draw(overrides(scene)) + draw(st.sampled_from([[], ["--json"]]))
    elif cmd == "simulate":
        argv = ["simulate", scene, "--quiet"] + draw(overrides(scene)) + dur + ["--out", out]
    elif cmd == "estimate":
        argv = ["estimate", scene] + draw(overrides(scene)) + dur + draw(st.sampled_from([[], ["--json"]]))
    elif cmd in ("replay", "recover"):
        bag = draw(st.sampled_from(["bag", "cut", "empty", "garbage", "dir", "missing", "yaml"]))
        path = {"bag": BAG, "dir": tmp, "missing": os.path.join(tmp, "nope.mcap"),
                "yaml": scene_path(scene)}.get(bag, os.path.join(tmp, bag + ".mcap"))
        if bag == "cut":
            with open(BAG, "rb") as fh:
                data = fh.read()
            cut = draw(st.integers(0, len(data)))
            with open(path, "wb") as fh:
                fh.write(data[:cut])
        elif bag == "empty":
            open(path, "wb").close()
        elif bag == "garbage":
            with open(path, "wb") as fh:
                fh.write(draw(st.binary(max_size=64)))
        argv = [cmd, path] + (["--out", os.path.join(tmp, "fixed.mcap")] if cmd == "recover" else
                              draw(st.sampled_from([[], ["--json"]])))
    elif cmd == "run":                            # the ROS suite: fails fast, or a run of <= 2 s
        argv = ["run", scene, "--quiet"] + draw(overrides(scene)) + dur + draw(st.sampled_from(
            [[], ["--bag", os.path.join(tmp, "no/dir/b.mcap")], ["--real-time-factor", "-1"]]))
    elif cmd == "plan":                           # targets valid or not; the 3 s budget interrupts long plans
        targets = draw(st.lists(st.sampled_from(["latitude_arcsec=1", "earth_rate_rad_s=1e-10", "latitude_deg=1e-9",
                                                 "earth_rate_deg_h=100", "latitud_arcsec=1", "latitude_arcsec=-1",
                                                 "latitude_arcsec=nan", "x"]), max_size=2))
        argv = ["plan", scene] + draw(overrides(scene)) + [a for t in targets for a in ("--target", t)] + \
            draw(st.sampled_from([[], ["--no-floor"], ["--json", "--no-floor"], ["--noise-factor", "0"]]))
    elif cmd == "typetest":                       # bad latitudes fail fast; a good run is interrupted at 3 s
        lats = draw(st.sampled_from(["45", "91", "x", "-23.5,61", "", "nan", "45,,60", "-88"]))
        argv = ["typetest", scene, "--workers", "1", f"--latitudes={lats}"] + draw(overrides(scene)) + \
            draw(st.sampled_from([[], ["--json"], ["--out", os.path.join(BAG, "x")]]))
    elif cmd == "bench":                          # fails fast: an output path that cannot be a directory
        argv = ["bench", "--quick", "--out", draw(st.sampled_from(["/proc/nope", os.path.join(BAG, "x"), BAG]))]
    else:                                         # random tokens: argparse's errors
        argv = draw(st.lists(st.sampled_from(["simulate", "describe", "--out", "--set", "--json", "--quick",
                                              "--duration-s", "x", "-5", "nan", "quet_paris", "--help", "",
                                              "--nope", "a=b", "="]), max_size=5))
    return argv


@contextlib.contextmanager
def budget(seconds):
    """SIGINT ourselves after ``seconds``: a long example ends as an interrupted run (130)."""
    signal.setitimer(signal.ITIMER_REAL, seconds)
    previous = signal.signal(signal.SIGALRM, lambda *_: os.kill(os.getpid(), signal.SIGINT))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run(argv):
    err, out = io.StringIO(), io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
        try:
            with budget(BUDGET_S):
                rc = ros_main(argv) if argv[:1] == ["run"] else main(argv)
        except SystemExit as exc:               # argparse: --help (0) and usage errors (2)
            rc = exc.code
        except KeyboardInterrupt:               # only our timer, firing just as main returned
            rc = 130
    return rc, out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=int(os.environ.get("FUZZ_EXAMPLES", 150)), deadline=None, suppress_health_check=list(HealthCheck))
@given(data=st.data())
def test_every_subcommand_random_arguments(workdir, data):
    tmp = os.path.join(workdir, "case")
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    argv = data.draw(command_lines(tmp), label="argv")
    rc, out, err = run(argv)
    assert rc in (0, 2, 130), (argv, rc, err)
    assert "Traceback" not in err, (argv, err)
    if rc != 0:
        assert len(err.strip().splitlines()) == 1, (argv, err)
    assert not [f for f in os.listdir(tmp) if f.endswith(".partial")], (argv, os.listdir(tmp))
