"""Sample stamps of a scene's run: the times every instrument is read at, whole or in blocks.

(Split from :mod:`gyro_instrument.core.scene`, which re-exports these names: a scene's loading
and its sampling are two subjects.)
"""

import math

import numpy as np

from gyro_instrument.core.errors import SceneError


#: Sim time starts here (time 0 means "no time yet" to ROS): 1e9 s, 2001-09-09T01:46:40Z.
EPOCH_NS = 1_000_000_000 * 1_000_000_000


def sample_times_ns(scene) -> np.ndarray:
    """Sample stamps in integer nanoseconds from release: round(i · 1e9 / f) for i = 0..N.

    Raises SceneError (on ``duration_s``) when the run would not fit in the memory available
    (:func:`gyro_instrument.core.memory.check_memory`)."""
    from gyro_instrument.core.memory import check_memory
    n = int(math.floor(scene.duration_s * scene.sample_rate_hz + 1e-9)) + 1
    check_memory(scene, n)    # SceneError on duration_s before allocating a run that cannot fit
    return np.round(np.arange(n) * (1e9 / scene.sample_rate_hz)).astype(np.int64)


def sample_times(scene) -> np.ndarray:
    """Sample times in seconds, ``sample_times_ns / 1e9`` (the same floats a ROS stamp gives back)."""
    return sample_times_ns(scene) / 1e9


#: Default streaming window (s of simulated time per block of :func:`sample_blocks`).
DEFAULT_WINDOW_S = 10.0


class SampleBlocks:
    """The stamps of :func:`sample_times_ns` (or their seconds) in consecutive blocks of
    ``window_s`` seconds of simulated time (the last block shorter), generated block by block: an
    iterator whose memory is one block, whatever the duration.

    Attributes
    ----------
    count : int
        Samples in the run.
    block_samples : int
        Samples per block (the last may hold fewer).
    end_ns : int
        Stamp of the last sample (ns from release).
    end_s : float
        The last sample time in seconds as the last block gives it (``end_ns / 1e9``): what a
        streaming instrument bounds its last step with (:func:`gyro_instrument.instruments.base.run_span`).

    Raises
    ------
    SceneError
        On ``window_s`` when it is not a positive finite number; on ``duration_s`` when one block
        would not fit in the memory available (:func:`gyro_instrument.core.memory.check_memory`
        applied to one block: a streamed run holds one block at a time).
    """

    def __init__(self, scene, window_s=DEFAULT_WINDOW_S, seconds=False) -> None:
        from gyro_instrument.core.memory import check_memory
        if not (isinstance(window_s, (int, float)) and not isinstance(window_s, bool) and math.isfinite(window_s)
                and window_s > 0):
            raise SceneError("window_s", window_s, "must be a positive finite number of seconds")
        self.count = int(math.floor(scene.duration_s * scene.sample_rate_hz + 1e-9)) + 1
        self.block_samples = max(1, int(math.floor(window_s * scene.sample_rate_hz + 1e-9)))
        check_memory(scene, min(self.block_samples, self.count))
        self._step = 1e9 / scene.sample_rate_hz
        self._seconds = seconds
        self._next = 0
        self.end_ns = int(np.round(np.arange(self.count - 1, self.count) * self._step).astype(np.int64)[0])
        self.end_s = self.end_ns / 1e9

    def __iter__(self) -> "SampleBlocks":
        return self

    def __next__(self) -> np.ndarray:
        i = self._next
        if i >= self.count:
            raise StopIteration
        self._next = min(self.count, i + self.block_samples)
        block = np.round(np.arange(i, self._next) * self._step).astype(np.int64)
        return block / 1e9 if self._seconds else block


def sample_blocks_ns(scene, window_s=DEFAULT_WINDOW_S) -> SampleBlocks:
    """The stamps of :func:`sample_times_ns` in consecutive blocks of ``window_s`` seconds of
    simulated time (the last block shorter), generated block by block (:class:`SampleBlocks`):
    memory is one block, whatever the duration. Raises SceneError on ``window_s`` when it is not a
    positive finite number, on ``duration_s`` when one block would not fit in memory."""
    return SampleBlocks(scene, window_s)


def sample_blocks(scene, window_s=DEFAULT_WINDOW_S) -> SampleBlocks:
    """:func:`sample_blocks_ns` in seconds (``stamps / 1e9``, the floats of :func:`sample_times`);
    its ``end_s`` is the run's last sample time."""
    return SampleBlocks(scene, window_s, seconds=True)
