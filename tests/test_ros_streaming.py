"""Everything downstream of the instruments streams (issue 13 item 2): the simulators publish one
block of ``window_s`` simulated seconds before integrating the next, the recorder commits before
every integration, the estimator keeps only what it fits.

The physics is unchanged by streaming: the joint samples of :func:`joint_blocks` equal the one-shot
:func:`joint_streams` bit for bit (same sensor draws, same centred differences, carried running
sums), so a streamed run publishes the messages a one-shot run published and the shipped bags'
estimates stay what they are (tests/test_bags.py).
"""

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import streaming_instrument  # noqa: E402

from gyro_instrument.core.errors import SceneError  # noqa: E402
from gyro_instrument.recording.joints import GradientStream, joint_blocks, joint_streams  # noqa: E402
from gyro_instrument.recording.visual import SwingPlaneStream, swing_plane_azimuth  # noqa: E402
from gyro_instrument.scenes import load_scene  # noqa: E402

#: shipped scenes, short, with every sensor draw the measurement model can make (noise, quantization,
#: spin noise, dropouts); windows that cut blocks of 1 sample up to the whole run
CASES = [("quet_paris", ["duration_s=60"], 7.3),
         ("foucault_pantheon", ["duration_s=100", "sensor.dropout_fraction=0.01", "sensor.quantization_rad=1e-5"], 3.0),
         ("free_gyroscope", ["duration_s=100"], 10.0),
         ("puiseux_spheroid", ["duration_s=1"], 0.01),
         ("puiseux_general", ["duration_s=2"], 0.37),
         ("gimbal_paris", ["duration_s=3"], 1.0),
         ("quet_paris", ["duration_s=30", "sensor.spin_noise_rad_s=0.1", "sensor.dropout_fraction=0.05"], 1.0),
         ("quet_paris", ["duration_s=0.05"], 1e-3),
         ("quet_paris", ["duration_s=20"], 1e6)]


@pytest.mark.parametrize("name,overrides,window_s", CASES, ids=lambda c: str(c)[:40])
def test_joint_blocks_equal_the_one_shot_joint_streams_bit_for_bit(name, overrides, window_s):
    """Exact equality (no tolerance): the same floats from the same operations in the same order."""
    scene = load_scene(name, overrides)
    t_ns, streams = joint_streams(scene)
    blocks = list(joint_blocks(scene, window_s=window_s))
    assert np.array_equal(np.concatenate([b.t_ns for b in blocks]), t_ns)
    assert [b.start for b in blocks] == list(np.cumsum([0] + [b.t_ns.size for b in blocks[:-1]]))
    for k, s in streams.items():
        for f in ("position", "velocity", "effort", "bob_enu_m"):
            whole = getattr(s, f)
            parts = [getattr(b.streams[k], f) for b in blocks]
            if whole is None:
                assert all(p is None for p in parts)
            else:
                assert np.array_equal(np.concatenate(parts), whole, equal_nan=True), (k, f)
        assert set(s.extra) == set(blocks[0].streams[k].extra)     # the contact point of a Puiseux body
        for key, whole in s.extra.items():
            assert np.array_equal(np.concatenate([b.streams[k].extra[key] for b in blocks]), whole), (k, key)


def test_gradient_stream_takes_numpys_uniform_formula_when_the_run_is_uniform():
    """np.gradient switches to (f[i+1] - f[i-1]) / 2dx when every spacing is the same float; the
    stream does so from the run's spacing (integer times: uniform), and equals it exactly."""
    t = np.arange(50, dtype=float)
    y = np.sin(0.3 * t)[:, None] ** 3
    g = GradientStream(1.0)
    got = np.vstack([g.push(t[i:i + 7], y[i:i + 7]) for i in range(0, 50, 7)] + [g.finish()])
    assert np.array_equal(got[:, 0], np.gradient(y[:, 0], t))


@pytest.mark.parametrize("block", [1, 37, 2000])
def test_swing_plane_stream_equals_the_one_shot(block):
    rng = np.random.default_rng(1)
    n = 2001
    t = np.round(np.arange(n) * (1e9 / 20)) / 1e9
    e = 0.1 * np.sin(2 * math.pi * t / 16.4) * np.cos(1e-2 * t) + 1e-3 * rng.normal(size=n)
    north = 0.1 * np.sin(2 * math.pi * t / 16.4) * np.sin(1e-2 * t) + 1e-3 * rng.normal(size=n)
    e[::50] = np.nan                                  # dropouts count as nothing in both
    az, rate = swing_plane_azimuth(t, e, north, 16.4)
    s = SwingPlaneStream(16.4, n, t[-1])
    parts = [s.push(t[i:i + block], e[i:i + block], north[i:i + block]) for i in range(0, n, block)]
    assert np.array_equal(np.concatenate([p[0] for p in parts]), az)
    assert np.array_equal(np.concatenate([p[1] for p in parts]), rate)
    assert s.az.size <= s.w and s.sums.shape[0] <= s.w + 1          # bounded: one window kept


@pytest.fixture()
def analytic(tmp_path):
    cls = streaming_instrument.register()
    cls.EVENTS.clear()
    try:
        yield cls
    finally:
        cls.ON_BLOCK = None
        from gyro_instrument import instruments
        instruments.unregister(cls.type_name)


def test_run_publishes_and_commits_each_block_before_integrating_the_next(analytic, tmp_path):
    """The order of events, not wall times: when the integration of block i >= 1 starts, the bag on
    disk (a complete MCAP after every commit) already holds every sample published before the batch
    that needed block i — the suite commits before it integrates a block when the previous one took
    at least ros/suite.py QUICK_S (0.25 s; here each takes 0.3 s: ``block_cost_s``). The estimate of
    the streamed run equals the core's one-shot estimate of the same scene (same samples, same floats)."""
    from gyro_instrument.cli import to_jsonable
    from gyro_instrument.estimators.pipeline import estimable, estimate_records, measure, simulate_truth
    from gyro_instrument.recording.mcap_io import read_messages
    from gyro_instrument.ros.suite import BATCH, RunOptions, run_suite
    path = tmp_path / "streaming.yaml"
    path.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=60.0, block_cost_s=0.3)))
    bag = tmp_path / "s.mcap"
    on_disk = {}

    def probe(i):
        on_disk[i] = sum(1 for m in read_messages(str(bag)) if m[0] == "/clock") if bag.exists() else 0
    analytic.ON_BLOCK = probe
    result, stats = run_suite(str(path), bag=str(bag), options=RunOptions(window_s=10.0))
    # 60 s at 20 Hz: 1201 samples in blocks of 200 (the last one 1): 7 integrations, one per block;
    # published as 8 joint blocks (each one sample short, the held last sample alone at the end)
    assert [e[1] for e in analytic.EVENTS] == list(range(7)) and stats["blocks"] == {"gyrocompass_sim": 8}
    assert on_disk[0] == 0                                     # nothing before the first block
    for i in range(1, 7):
        # block i is pulled when sample 200 i - 1 is due (joint_blocks holds one sample back)
        assert on_disk[i] >= 200 * i - 1 - BATCH, (i, on_disk)
    assert on_disk[6] > 0 and stats["first_message_s"] is not None
    scene = load_scene(str(path))
    truth = simulate_truth(scene)
    core = estimate_records(scene, {n: i for n, i in truth[1].items() if estimable(i)}, measure(scene, truth))
    assert json.dumps(to_jsonable(result), sort_keys=True) == json.dumps(to_jsonable(core), sort_keys=True)
    assert result["latitude_deg"] is None or math.isfinite(result["earth_rate_rad_s"])


def test_estimator_keeps_8_bytes_per_kept_value_and_nothing_per_message(analytic, tmp_path):
    """What grows with the run in the estimator: t (int64), the measured channels and the spin
    (float64) per sample, in arrays that at most double — no list of messages."""
    from gyro_instrument.ros.suite import RunOptions, run_suite
    path = tmp_path / "streaming.yaml"
    path.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=600.0)))
    _, stats = run_suite(str(path), options=RunOptions(window_s=100.0))
    n = 12001                                       # 600 s at 20 Hz
    per_sample = 8 * (1 + 1 + 1)                    # t, angle, spin
    assert n * per_sample <= stats["estimator_bytes"] <= 2 * n * per_sample


@pytest.mark.parametrize("window", ["0", "-1", "nan", "inf", "1e7", "0.0001"])
def test_a_window_that_cannot_work_is_refused_by_name(window, capsys):
    from gyro_instrument.ros.cli import main
    assert main(["run", "quet_paris", "--window-s", window]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--window-s" in err[0] and "[0.001, 1e+06]" in err[0], err
    assert "Traceback" not in "".join(err)


def test_check_window_names_the_field():
    from gyro_instrument.ros.suite import check_window
    check_window(10.0)
    for bad in (0.0, float("nan"), "10", True, 2e6):
        with pytest.raises(SceneError, match="window_s"):
            check_window(bad, field="window_s")


def test_a_streaming_run_too_large_for_memory_is_refused_before_anything_starts(analytic, tmp_path, monkeypatch):
    """With every instrument streaming, what scales with the run is the estimator's kept samples and
    its final fits (ros/suite.py FIT_BYTES_PER_SAMPLE): 1e9 samples need ~7e11 bytes, refused on
    duration_s with the numbers (1e7 s at 100 Hz, with 8 GB available); 1 h at 20 Hz (72 001 samples,
    ~51 MB) is not."""
    from gyro_instrument.core import memory
    from gyro_instrument.ros.suite import check_run_memory
    monkeypatch.setattr(memory, "available_bytes", lambda: 8 * 10 ** 9)
    path = tmp_path / "streaming.yaml"
    path.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=1.0e7, rate_hz=100.0)))
    scene = load_scene(str(path))
    with pytest.raises(SceneError, match="duration_s") as e:
        check_run_memory(scene)
    assert "GB available" in str(e.value)
    path.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=3600.0)))
    check_run_memory(load_scene(str(path)))


def test_a_simulator_node_integrates_a_block_only_when_its_samples_are_due(analytic, tmp_path):
    """The node run alone (``ros2 run``) and in the suite shares publish_steps: a block is integrated
    when the samples asked for reach it, never ahead; the follower's sample index from a clock stamp
    matches the stamps round(i · 1e9 / f)."""
    import rclpy
    from rclpy.parameter import Parameter
    from gyro_instrument.core.scene import sample_times_ns
    from gyro_instrument.ros.nodes import SimulatorNode
    path = tmp_path / "streaming.yaml"
    path.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=60.0)))
    context = rclpy.Context()
    rclpy.init(context=context, args=[])
    try:
        node = SimulatorNode("gyrocompass_sim", ("analytic_compass",), context=context,
                             parameter_overrides=[Parameter("scene", value=str(path)),
                                                  Parameter("window_s", value=10.0)])
        assert analytic.EVENTS == [] and node.samples == 1201       # nothing integrated at start-up
        assert node.publish_steps(1) == 1 and [e[1] for e in analytic.EVENTS] == [0]
        assert node.publish_steps(198) == 198 and len(analytic.EVENTS) == 1   # samples 0..198: block 0
        assert node.publish_steps(1) == 1 and len(analytic.EVENTS) == 2       # sample 199 needs block 1
        while node.publish_steps(150):
            pass
        assert node.index == 1201 and len(analytic.EVENTS) == 7
        t = sample_times_ns(load_scene(str(path)))
        for stamp in (0, 1, 49_999_999, 50_000_000, int(t[600]) + 1, int(t[-1]), int(t[-1]) + 10**9):
            assert node.sample_index(stamp) == int(np.searchsorted(t, stamp, side="right"))
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
