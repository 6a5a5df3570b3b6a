"""The player streams a bag with bounded memory (issue 23, item 4): what the player node does
before and while playing — scan the bag (every CRC checked), log its damage, count its topics,
plan and stream its messages in log-time order — is measured with ``tracemalloc`` on bags of N and
8 N messages, intact and with a damaged chunk. No ROS graph: these are the pure functions the node
calls (``PlayerNode.__init__`` and, per message, ``peek``/``publish_next`` draw from the stream).

The bound: the scan keeps one :class:`~gyro_instrument.recording.scan_result.Container` per
chunk and the MCAP reader one ``ChunkIndex`` per chunk of an intact file, so the peak may grow by
at most ``PER_CHUNK_BYTES`` per extra chunk plus ``NOISE_BYTES``, derived below (measured: about
600 B per chunk intact, 350 B damaged; ~0.3-0.4 MB peak for either size). Holding the messages, as
the scan did before, grows the peak by at least the 7 N extra messages' bytes (7 x 4000 x 300 B =
8.4 MB; 27 MB measured on that scan), so the assertion tells the two apart by two orders of
magnitude.
"""

import gc
import tracemalloc

import numpy as np
import pytest

from gyro_instrument.recording.bag_layout import scan_path
from gyro_instrument.recording.mcap_io import BagWriter, play_plan, stream_messages

N = 4000                     # messages in the small bag; the large one has 8 N
PAYLOAD = 300                # bytes of CDR per message (a JointState of three joints is ~250)
CHUNK = 64 * 1024            # bytes of messages per chunk
#: per extra chunk, what the player may keep: the scan's Container (a 6-tuple of ints, ~250 B),
#: its entry in the scan's chunk index (~200 B) and, for an intact file, the MCAP reader's
#: ChunkIndex (a dataclass with a dict of message-index offsets per channel, ~1.1 KiB with two
#: channels): 2 KiB rounds their sum up
PER_CHUNK_BYTES = 2048
#: what tracemalloc's peak moves between two runs of the same work (measured: < 1 KiB)
NOISE_BYTES = 64 * 1024


def _write(path, n):
    """``n`` messages of ``PAYLOAD`` random (incompressible) bytes on two topics, 1 ms apart,
    with the project's own writer (zstd chunks of ``CHUNK`` bytes, CRCs)."""
    rng = np.random.default_rng(23)
    w = BagWriter(str(path), chunk_size=CHUNK, commit_period_s=1e9)
    w.add_topic("/a/joint_states", "sensor_msgs/msg/JointState")
    w.add_topic("/clock", "rosgraph_msgs/msg/Clock")
    for i in range(n):
        w.write("/a/joint_states" if i % 2 else "/clock", 1_000_000_000 + i * 1_000_000,
                rng.integers(0, 256, PAYLOAD, dtype=np.uint8).tobytes())
    w.close()


def _damage_a_middle_chunk(path):
    """Flip a byte inside the compressed records of the middle chunk."""
    from mcap.reader import make_reader
    with open(path, "rb") as fh:
        idx = sorted(make_reader(fh).get_summary().chunk_indexes, key=lambda ci: ci.chunk_start_offset)
    ci = idx[len(idx) // 2]
    data = bytearray(path.read_bytes())
    data[ci.chunk_start_offset + ci.chunk_length - ci.compressed_size // 2] ^= 0x10
    path.write_bytes(bytes(data))


def _play(bag):
    """What the player node does with ``bag``: scan, damage lines, topic counts, plan; then every
    message drawn from the stream. Returns (messages played, chunks, tracemalloc peak in bytes)."""
    gc.collect()
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        base = tracemalloc.get_traced_memory()[0]
        scan = scan_path(str(bag))
        damage = scan.damage_dicts(0)
        total = sum(n for _, _, n in scan.channel_counts())
        chunks = len(scan.containers)
        plan = play_plan(str(bag), scan)
        del scan
        played, last = 0, None
        for topic, _, t, data in stream_messages(plan):
            assert last is None or t >= last and len(data) == PAYLOAD and topic
            played, last = played + 1, t
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert played == total
    return played, chunks, damage, peak


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp("memory")
    out = {}
    for n in (N, 8 * N):
        out[n, False], out[n, True] = d / f"bag_{n}.mcap", d / f"bag_{n}_damaged.mcap"
        _write(out[n, False], n)
        out[n, True].write_bytes(out[n, False].read_bytes())
        _damage_a_middle_chunk(out[n, True])
    return out


@pytest.mark.parametrize("damaged", [False, True], ids=["intact", "damaged chunk"])
def test_the_players_peak_memory_does_not_grow_with_the_bag(bags, damaged):
    small = _play(bags[N, damaged])
    large = _play(bags[8 * N, damaged])
    for n, (played, chunks, damage, _) in zip((N, 8 * N), (small, large)):
        if damaged:                   # one chunk lost, reported; every other message played
            [d] = damage
            assert d["span_from"] == "chunk index" and 0 < n - played < 2 * CHUNK // PAYLOAD
        else:
            assert damage == [] and played == n
    slack = (large[1] - small[1]) * PER_CHUNK_BYTES + NOISE_BYTES
    growth = large[3] - small[3]
    assert growth <= slack, (f"peak {small[3]} B for {small[0]} messages in {small[1]} chunks, {large[3]} B for "
                             f"{large[0]} in {large[1]}: grew {growth} B, allowed {slack} B")
    # and far below what holding the extra messages would take
    assert slack < (large[0] - small[0]) * PAYLOAD / 20
