"""Refuse a run that cannot fit in memory, before anything is allocated.

A run held in memory whole (``estimate``, the sensor model and the estimator, an instrument that
does not stream) holds the sample grid, the integrator's states at the samples, the output
columns, the sensor model's copies and the estimator's work arrays. A streamed run (``simulate``,
:class:`gyro_instrument.core.scene.SampleBlocks`) holds one block of them: the check is then
applied to one block, not the run. :func:`check_memory` estimates the peak as

    samples × channels × 8 bytes × :data:`PEAK_FACTOR`

(channels: ``time`` plus every instrument's output columns) and compares it with the memory
available now; :func:`gyro_instrument.core.scene.sample_times_ns` calls it before building the
grid (and :class:`~gyro_instrument.core.scene.SampleBlocks` for one block), so ``estimate``,
``run``, the bench and ``simulate`` all refuse up front with a
:class:`SceneError` on ``duration_s`` instead of dying in numpy's ``_ArrayMemoryError``.
"""

import math
import os

from gyro_instrument.core.errors import SceneError

#: Peak memory above the interpreter's baseline (the imports: 89-91 MB maximum RSS with a 1 s run)
#: over the output size samples × channels × 8 B, measured with ``/usr/bin/time -v`` (maximum RSS):
#:   simulate foucault_pantheon (7 channels): 3.67, 3.83, 3.56 at 4e5, 8e5, 2e6 samples
#:     (169, 256, 478 MB peak);
#:   estimate foucault_pantheon: 9.0, 9.03 at 4e5, 8e5 samples (287, 485 MB);
#:   estimate quet_paris (13 channels): 7.8, 6.9 at 6e4, 2.4e5 samples (138, 260 MB).
#: The estimate path (sensor copies, estimator work arrays) sets it: 9.0, taken as 12 for margin.
PEAK_FACTOR = 12.0

#: Channels assumed for a scene built without its instruments' classes (``Scene.output_channels`` 0).
DEFAULT_CHANNELS = 8


def sample_count(scene) -> int:
    """Samples per instrument, ``floor(duration_s · sample_rate_hz) + 1`` (as ``sample_times_ns``)."""
    return int(math.floor(scene.duration_s * scene.sample_rate_hz + 1e-9)) + 1


def channel_count(scene) -> int:
    """``time`` plus the output columns of every instrument of the scene."""
    return scene.output_channels or 1 + DEFAULT_CHANNELS * len(scene.instruments)


def available_bytes() -> int | None:
    """Memory available to this process now, bytes, or None when unknown: the smaller of
    /proc/meminfo's MemAvailable (or ``SC_AVPHYS_PAGES`` × ``SC_PAGE_SIZE``) and the cgroup v2
    limit less its current use."""
    found = []
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    found.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    if not found:
        try:
            found.append(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (OSError, ValueError, AttributeError):
            pass
    try:
        with open("/sys/fs/cgroup/memory.max") as fh:
            limit = fh.read().strip()
        if limit != "max":
            with open("/sys/fs/cgroup/memory.current") as fh:
                found.append(int(limit) - int(fh.read().strip()))
    except (OSError, ValueError):
        pass
    return max(min(found), 0) if found else None


def needed_bytes(scene, n=None) -> float:
    """Estimated peak bytes of a run of ``scene`` (``n`` samples per instrument, default from the scene)."""
    n = sample_count(scene) if n is None else n
    return n * channel_count(scene) * 8 * PEAK_FACTOR


def check_memory(scene, n=None, available=None) -> None:
    """Refuse a run whose estimated peak exceeds the memory available.

    Parameters
    ----------
    scene : Scene
    n : int, optional
        Samples per instrument (default :func:`sample_count`).
    available : int, optional
        Bytes available (default :func:`available_bytes`; no check when that is unknown).

    Raises
    ------
    SceneError
        On ``duration_s``: "needs ~X GB for N samples x M channels; Y GB available: lower
        duration_s or sample_rate_hz".
    """
    n = sample_count(scene) if n is None else n
    available = available_bytes() if available is None else available
    need = needed_bytes(scene, n)
    if available is not None and need > available:
        raise SceneError("duration_s", scene.duration_s,
                         f"needs ~{need / 1e9:.3g} GB for {n} samples x {channel_count(scene)} channels at "
                         f"{scene.sample_rate_hz:g} Hz; {available / 1e9:.3g} GB available: lower duration_s or "
                         f"sample_rate_hz")
