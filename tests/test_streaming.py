"""Streaming (issue 13): blocks of sample times and instruments that yield one block at a time.

A streamed run must equal the one-shot run; for the default ``Instrument.stream`` (one simulate,
sliced) the equality is exact by construction, so these tests check the slicing bookkeeping.
"""

import numpy as np
import pytest

from gyro_instrument.core.errors import SceneError
from gyro_instrument.core.scene import sample_blocks, sample_blocks_ns, sample_times, sample_times_ns
from gyro_instrument.scenes import build_instruments, load_scene


@pytest.mark.parametrize("window_s", [0.01, 1.0, 7.3, 1e6])
def test_blocks_concatenate_to_the_one_shot_stamps(window_s):
    scene = load_scene("quet_paris", ["duration_s=60"])
    blocks = list(sample_blocks_ns(scene, window_s))
    assert np.array_equal(np.concatenate(blocks), sample_times_ns(scene))   # same integers
    assert np.array_equal(np.concatenate(list(sample_blocks(scene, window_s))), sample_times(scene))
    assert all(b.size >= 1 for b in blocks)


@pytest.mark.parametrize("window_s", [0.0, -1.0, float("nan"), float("inf"), "10"])
def test_bad_window_is_refused_by_name(window_s):
    scene = load_scene("quet_paris", ["duration_s=60"])
    with pytest.raises(SceneError, match="window_s"):
        next(sample_blocks_ns(scene, window_s))


def test_default_stream_equals_simulate():
    scene = load_scene("quet_paris", ["duration_s=30"])
    for inst in build_instruments(scene).values():
        one = inst.simulate(sample_times(scene))
        parts = list(inst.stream(sample_blocks(scene, 4.0)))
        for k, v in one.columns.items():
            assert np.array_equal(np.concatenate([p.columns[k] for p in parts]), v), (inst.name, k)


# --------------------------------------------------------------------------- streaming instruments
# Every instrument but the gimbal streams (STREAMS): it integrates window by window with its exact
# state carried, and ``simulate`` is its stream with one block. The adaptive drivers continue one
# step sequence bounded by the run's end and evaluate each sample from the step that reaches it, as
# one solve_ivp call does; so a streamed run equals the one-shot run bit for bit (np.array_equal, no
# tolerance), whatever the blocks. Irregular block sizes (1 sample, a prime, a long one) exercise
# samples on both sides of a step.

from gyro_instrument.core.site import Site                                   # noqa: E402
from gyro_instrument.instruments import REGISTRY                             # noqa: E402
from gyro_instrument.instruments.pendulum import CompoundPendulum, SphericalPendulum   # noqa: E402
from tests.conftest import make                                              # noqa: E402

PARIS = Site.from_degrees(48.8462)


def _cut(t, sizes=(1, 7, 113, 2, 997)):
    """``t`` cut into consecutive blocks of the given sizes, cycled."""
    out, i, k = [], 0, 0
    while i < t.size:
        out.append(t[i:i + sizes[k % len(sizes)]])
        i += sizes[k % len(sizes)]
        k += 1
    return out


def _assert_stream_equals_simulate(inst, t, **options):
    one = inst.simulate(t, **options)
    parts = list(inst.stream(_cut(t), t_end=float(t[-1]), **options))
    assert [p.t.size for p in parts] == [b.size for b in _cut(t)]
    for k, v in one.columns.items():
        assert np.array_equal(np.concatenate([p.columns[k] for p in parts]), v), (inst.type_name, k)
    # and without being told the end: the blocks are read once to find it (run_span)
    again = list(inst.stream(iter(_cut(t)), **options))
    for k, v in one.columns.items():
        assert np.array_equal(np.concatenate([p.columns[k] for p in again]), v), (inst.type_name, k)
    return one, parts


def test_every_instrument_but_the_gimbal_streams():
    streams = {name for name, cls in REGISTRY.items() if cls.STREAMS}
    assert streams >= {"spherical_pendulum", "compound_pendulum", "plane_gyroscope", "free_gyroscope"}


@pytest.mark.parametrize("integrator,effects", [
    ("adaptive", ("earth_rotation", "finite_amplitude", "centrifugal")),     # Cartesian model, scipy DOP853
    ("adaptive", ("earth_rotation",)),                                       # linear model, scipy DOP853
    ("adaptive", ("earth_rotation", "finite_amplitude", "air_drag")),
    ("parareal", ("earth_rotation", "finite_amplitude", "centrifugal")),
])
def test_spherical_pendulum_streams_bit_for_bit(integrator, effects, monkeypatch):
    # parareal windows of 4 swings (16.4 s each on 67 m) so that 150 s holds three windows
    monkeypatch.setattr(SphericalPendulum, "WINDOW_SWINGS", 4)
    p = make(SphericalPendulum, PARIS, effects, length_m=67.0, initial_deflection_deg=2.0, integrator=integrator)
    one, parts = _assert_stream_equals_simulate(p, np.arange(0.0, 150.0 + 1e-9, 0.05))
    assert parts[-1].trajectory.nfev == one.trajectory.nfev        # the same work, counted over the run


def test_parareal_windows_agree_with_one_window(monkeypatch):
    # Windows of whole swings, each started from the fine end state of the last, against one window
    # over the whole run (10 swings): both are the full model converged to shooting_tol = 1e-9 of the
    # amplitude (2.34 m) at each swing start, so they may differ by that order, growing at most
    # linearly over the swings: bound 10 swings x 1e-9 x 2.34 m = 2.3e-8 m.
    t = np.arange(0.0, 164.0, 0.05)
    p = make(SphericalPendulum, PARIS, ("earth_rotation", "finite_amplitude"), length_m=67.0,
             initial_deflection_deg=2.0, integrator="parareal")
    whole = p.simulate(t)
    monkeypatch.setattr(SphericalPendulum, "WINDOW_SWINGS", 3)
    windowed = p.simulate(t)
    assert "4 windows" in windowed.trajectory.method
    d = np.max(np.abs(windowed.extra["position_enu"] - whole.extra["position_enu"]))
    assert d < 2.3e-8


def test_compound_pendulum_streams_bit_for_bit():
    cp = make(CompoundPendulum, PARIS, ("earth_rotation",), initial_deflection_deg=5.0)
    _assert_stream_equals_simulate(cp, np.arange(0.0, 4.0 + 1e-9, 0.01))     # a swing of λ = 1 m: 2 s


@pytest.mark.parametrize("scene,over", [
    ("quet_paris", []),                                                      # reduced model, scalar DOP853
    ("quet_paris", ["instruments.gyro_horizontal.model=chain", "instruments.gyro_meridian.model=chain"]),
    ("quet_gyroscopes", []),
    ("free_gyroscope", []),                                                  # closed form
    ("free_gyroscope", ["instruments.free_gyro.model=numerical", "duration_s=2"]),
    ("puiseux_spheroid", ["duration_s=2"]),
    ("puiseux_general", ["duration_s=2"]),                                  # sec. III body, contact point, turn
])
def test_scene_instruments_stream_bit_for_bit(scene, over):
    sc = load_scene(scene, ["duration_s=30"] + over)
    for inst in build_instruments(sc).values():
        if inst.STREAMS and not inst.OBSERVATION.SHOWS_BOB_POSITION:
            _assert_stream_equals_simulate(inst, sample_times(sc))


def test_stream_from_sample_blocks_knows_the_end():
    # sample_blocks carries the run's last sample time: an adaptive instrument needs it before its
    # first step (it bounds the last step as in one call over the whole run)
    sc = load_scene("quet_paris", ["duration_s=30"])
    blocks = sample_blocks(sc, 4.0)
    assert blocks.end_s == sample_times(sc)[-1]
    inst = build_instruments(sc)["gyro_meridian"]
    one = inst.simulate(sample_times(sc))
    got = np.concatenate([s.columns["angle"] for s in inst.stream(blocks)])
    assert np.array_equal(got, one.columns["angle"])


# --------------------------------------------------------------------------- simulate streams to disk

from gyro_instrument.cli import check_disk, main, simulate_scene              # noqa: E402
from gyro_instrument.estimators.data_io import ROWS_PER_WRITE, read_table     # noqa: E402


@pytest.mark.parametrize("ext", ["csv", "parquet"])
def test_simulate_writes_the_one_shot_columns_exactly(tmp_path, ext, capsys):
    # 3 600 s at 20 Hz = 72 001 rows: more than one write buffer (65 536 rows), so the file is
    # written in two pieces; read back, every value equals simulate_scene's to the last bit (the CSV
    # holds the shortest representation that reads back to the same double).
    out = tmp_path / f"run.{ext}"
    assert main(["simulate", "quet_paris", "--duration-s", "3600", "--quiet", "--out", str(out)]) == 0
    t, cols, _ = simulate_scene(load_scene("quet_paris", ["duration_s=3600"]))
    assert t.size > ROWS_PER_WRITE
    got = read_table(str(out))
    assert list(got) == ["time_s"] + list(cols)
    assert np.array_equal(got["time_s"], t)
    for k, v in cols.items():
        assert np.array_equal(got[k], v), k
    if ext == "csv":
        assert out.read_text().split("\n", 1)[0] == ",".join(["time_s"] + list(cols))   # header unquoted


def test_output_rate_decimates_without_changing_the_integration(tmp_path):
    # --output-rate-hz 2 of a 20 Hz scene keeps samples 0, 10, 20...: the same values as the full
    # output at those rows (the integration and its grid are unchanged)
    full, dec = tmp_path / "full.parquet", tmp_path / "dec.parquet"
    assert main(["simulate", "quet_paris", "--duration-s", "100", "--quiet", "--out", str(full)]) == 0
    assert main(["simulate", "quet_paris", "--duration-s", "100", "--quiet", "--output-rate-hz", "2",
                 "--out", str(dec)]) == 0
    a, b = read_table(str(full)), read_table(str(dec))
    assert b["time_s"].size == 201
    for k in a:
        assert np.array_equal(a[k][::10], b[k]), k


@pytest.mark.parametrize("rate", ["0", "-1", "nan", "inf", "40", "3"])
def test_bad_output_rate_is_refused_by_name(tmp_path, rate, capsys):
    # 20 Hz scene: 40 Hz is above the sample rate, 3 Hz does not divide it
    out = tmp_path / "x.csv"
    assert main(["simulate", "quet_paris", "--duration-s", "10", "--quiet", "--output-rate-hz", rate,
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--output-rate-hz" in err and "divides" in err, err
    assert not out.exists()


def test_output_that_does_not_fit_is_refused_before_the_run(tmp_path):
    # 1e6 rows x 8 columns of CSV at <= 25 bytes a value: 2e8 bytes against 1e6 free
    with pytest.raises(SceneError, match=r"--out.*2e\+08 bytes.*1000000 bytes free"):
        check_disk(str(tmp_path / "x.csv"), 1_000_000, 8, free=1_000_000)
    check_disk(str(tmp_path / "x.parquet"), 1_000_000, 8, free=10 ** 8)     # 6.56e7 bytes fit


def test_auto_integrator_picks_the_fast_path_and_says_why():
    # foucault_pantheon (full conservative model, 2 deg from rest) runs parareal by default; an
    # explicit choice wins; a model the fast path is not validated for keeps DOP853, with the reason
    from gyro_instrument.cli import describe
    d = describe(load_scene("foucault_pantheon"))["instruments"]["pendulum"]["integrator"]
    assert d["chosen"] == "parareal" and d["reason"].startswith("auto:")
    for over, reason in [("instruments.pendulum.integrator=adaptive", "chosen in the scene"),
                         ("instruments.pendulum.initial_deflection_deg=30", "beyond the 10 deg"),
                         # 1e-7 deg: height round-off 1.3e-7 of the amplitude (parareal stalls near it)
                         ("instruments.pendulum.initial_deflection_deg=1e-7", "round-off"),
                         ("effects.finite_amplitude=null", "linear")]:
        d = describe(load_scene("foucault_pantheon", [over]))["instruments"]["pendulum"]["integrator"]
        assert d["chosen"] == "adaptive" and reason in d["reason"], (over, d)
    d = describe(load_scene("quet_paris"))["instruments"]["gyro_horizontal"]["integrator"]
    assert d["chosen"] == "scalar" and d["reason"].startswith("auto:")


def test_plane_gyroscope_vector_driver_streams_and_matches_the_scalar_one():
    # integrator: vector runs the reduced model on scipy's DOP853: it streams bit for bit, and takes
    # the same steps as the scalar driver (the default, auto), so the two agree to rounding: the
    # module docstring of core/dop853.py measured <= 1e-13 rad over an hour; 1e-12 rad here over 30 s
    sc = load_scene("quet_paris", ["duration_s=30", "instruments.gyro_meridian.integrator=vector"])
    vec = build_instruments(sc)["gyro_meridian"]
    assert vec.chosen_integrator() == ("vector", "chosen in the scene")
    one, _ = _assert_stream_equals_simulate(vec, sample_times(sc))
    sca = build_instruments(load_scene("quet_paris", ["duration_s=30"]))["gyro_meridian"]
    assert sca.chosen_integrator()[0] == "scalar"
    ref = sca.simulate(sample_times(sc))
    assert np.max(np.abs(one.columns["angle"] - ref.columns["angle"])) < 1e-12
    assert one.trajectory.nfev == ref.trajectory.nfev
