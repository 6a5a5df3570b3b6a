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
