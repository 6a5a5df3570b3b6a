"""Interrupted recordings lose nothing already written (issue 6): SIGINT finishes a complete,
indexed MCAP; SIGKILL leaves a file that is read up to the last written chunk, and replay
estimates from it or says why not."""

import json
import signal
import subprocess
import sys
import time


from gyro_instrument.cli import replay_bag
from gyro_instrument.recording.mcap_io import read_messages


def start_run(bag, rtf="50"):
    return subprocess.Popen([sys.executable, "-m", "gyro_instrument.ros.cli", "run", "quet_paris", "--bag", str(bag),
                             "--real-time-factor", rtf, "--quiet", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def wait_for_messages(bag, timeout=60, size=800_000):
    """Until the recording holds ``size`` bytes: 800 kB is ~130 s of quet_paris (300 kB held 48-50 s,
    under two swings of the horizontal gyroscope, 25.6 s each: its estimate then came and went)."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        if bag.exists() and bag.stat().st_size > size:
            return
        time.sleep(0.2)
    raise AssertionError("the run never wrote enough to interrupt it")


def _check_estimate(result, bag):
    """What a replay of a cut quet_paris recording must say: how much it read (the span of the joint
    stamps in the file, the shortest over the instruments, under the scene's 600 s) and the latitude
    from it, within 5 of its reported sigma of the scene's (a Gaussian draw beyond 5 sigma: 6e-7). The
    interruption comes after 800 kB (:func:`wait_for_messages`), over 100 s of all three instruments:
    four swings and more of each."""
    spans = {}
    for tp, _, t, _ in read_messages(str(bag)):
        if tp.endswith("/joint_states"):
            lo, hi = spans.get(tp, (t, t))
            spans[tp] = (min(lo, t), max(hi, t))
    read_s = min(hi - lo for lo, hi in spans.values()) / 1e9
    assert result["observation_read_s"] == read_s and 0 < read_s < 600.0, (result.get("observation_read_s"), read_s)
    assert result["latitude_deg"] is not None, result.get("reason")
    assert abs(result["latitude_deg"] - 48.8462) < 5 * result["latitude_sigma_deg"], result   # quet_paris's site


def test_sigint_finishes_a_complete_indexed_mcap(tmp_path):
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    bag = tmp_path / "int.mcap"
    p = start_run(bag)
    wait_for_messages(bag)
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130 and "Traceback" not in err, err
    with open(bag, "rb") as fh:
        summary = make_reader(fh).get_summary()
    assert summary is not None and summary.chunk_indexes          # indexed and complete
    n = summary.statistics.message_count
    with AnyReader([bag]) as r:
        assert sum(1 for _ in r.messages()) == n
    from gyro_instrument.recording.mcap_io import recording_state
    assert recording_state(str(bag)) == "interrupted"             # the SIGINT landed between samples
    result = replay_bag(str(bag))                                  # estimates from what is there
    assert any("interrupted" in n for n in result.get("replay_notes", []))
    assert result["observation_s"] == 600.0
    _check_estimate(result, bag)
    json.dumps(result, allow_nan=False)


def test_sigkill_leaves_an_indexed_file_every_reader_opens_and_replay_says_what_it_did(tmp_path):
    """The recorder commits a chunk plus a provisional summary/footer in one write (mcap_io.BagWriter),
    so a SIGKILL at any moment leaves a complete MCAP holding everything up to the last commit."""
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    from gyro_instrument.recording.mcap_io import recording_state
    bag = tmp_path / "kill.mcap"
    p = start_run(bag)
    wait_for_messages(bag)
    p.kill()
    p.communicate(timeout=30)
    with open(bag, "rb") as fh:                      # mcap: indexed, CRCs valid, counts consistent
        reader = make_reader(fh, validate_crcs=True)
        summary = reader.get_summary()
        n = summary.statistics.message_count
        assert summary.chunk_indexes and sum(1 for _ in reader.iter_messages()) == n
    assert n > 1000
    with AnyReader([bag]) as r:                      # rosbags (needs the footer) reads every message
        assert sum(1 for _ in r.messages()) == n
    msgs = list(read_messages(str(bag)))
    assert len(msgs) == n
    t = [m[2] for m in msgs if m[0] == "/clock"]
    assert t == sorted(t)
    assert recording_state(str(bag)) == "recording"  # the status record says it was cut short
    result = replay_bag(str(bag))
    assert any("interrupted" in n for n in result.get("replay_notes", []))
    _check_estimate(result, bag)
    json.dumps(result, allow_nan=False)


def test_a_file_truncated_elsewhere_is_recovered_complete_and_indexed(tmp_path):
    """A file cut inside its data section (disk full, a copy taken mid-write) has no footer: replay
    reads it up to the last complete record and 'recover' rewrites it indexed for other readers."""
    import os
    from rosbags.highlevel import AnyReader
    from gyro_instrument.cli import main
    from gyro_instrument.recording.mcap_io import recording_state
    src = tmp_path / "src.mcap"
    p = start_run(src, rtf="0")
    p.communicate(timeout=300)
    size = os.path.getsize(src)
    os.truncate(src, size * 2 // 3)                  # well inside the data section
    assert recording_state(str(src)) == "no summary"
    msgs = list(read_messages(str(src)))
    assert len(msgs) > 1000
    result = replay_bag(str(src))
    assert any("interrupted" in n for n in result.get("replay_notes", []))
    fixed = tmp_path / "fixed.mcap"
    assert main(["recover", str(src), "--out", str(fixed)]) == 0
    with AnyReader([fixed]) as r:
        assert sum(1 for _ in r.messages()) == len(msgs)
    _check_estimate(result, src)
    assert replay_bag(str(fixed))["latitude_deg"] == result["latitude_deg"]
    json.dumps(result, allow_nan=False)


def test_sigkill_during_a_block_integration_keeps_what_was_published_a_second_before(tmp_path):
    """Issue 13: a SIGKILL at any time after the first message leaves a bag readable up to within
    1 s of wall time of the kill. The run streams a test instrument whose blocks take 1.5 s of wall
    time each (tests/streaming_instrument.py: as a slow integrator would), so the kill lands inside
    an integration, when no message is being written. ``run`` prints ``sample i/n`` after samples
    0..i-1 are delivered to the recorder; the kill comes 1.0 s after the line ``sample 300/2001``,
    so every sample it announces must be in the bag: read by the repo's reader and by two
    independent ones (``mcap`` with CRC validation, ``rosbags``), then ``recover`` and ``replay``."""
    import os
    import threading
    from pathlib import Path
    import yaml
    from mcap.reader import make_reader
    from rosbags.highlevel import AnyReader
    from gyro_instrument.cli import main
    from gyro_instrument.core.scene import EPOCH_NS
    from gyro_instrument.recording.mcap_io import recording_state
    tests = Path(__file__).resolve().parent
    sys.path.insert(0, str(tests))
    import streaming_instrument
    scene = tmp_path / "slow.yaml"
    scene.write_text(yaml.safe_dump(streaming_instrument.scene(duration_s=100.0, block_cost_s=1.5)))
    bag = tmp_path / "killed.mcap"
    child = (f"import sys; sys.path.insert(0, {str(tests)!r}); import streaming_instrument; "
             f"streaming_instrument.register(); from gyro_instrument.ros.cli import main; "
             f"sys.exit(main(['run', {str(scene)!r}, '--bag', {str(bag)!r}, '--window-s', '10']))")
    p = subprocess.Popen([sys.executable, "-c", child], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines = []
    seen = threading.Event()

    def read():
        for line in p.stderr:
            lines.append((time.monotonic(), line.strip()))
            if line.strip() == "sample 300/2001":
                seen.set()
    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert seen.wait(120), lines
        t_line = next(t for t, s in lines if s == "sample 300/2001")
        time.sleep(max(0.0, t_line + 1.0 - time.monotonic()))
        t_kill = time.monotonic()
        p.kill()
    finally:
        p.kill()
        p.wait(30)
    assert t_kill - t_line >= 1.0
    with open(bag, "rb") as fh:                      # mcap: indexed, CRCs valid, counts consistent
        r = make_reader(fh, validate_crcs=True)
        n = r.get_summary().statistics.message_count
        clock = [m.log_time for _, ch, m in r.iter_messages() if ch.topic == "/clock"]
    with AnyReader([bag]) as ar:
        assert sum(1 for _ in ar.messages()) == n
    msgs = list(read_messages(str(bag)))
    assert len(msgs) == n and [m[2] for m in msgs if m[0] == "/clock"] == clock
    # samples 0..299 were announced 1 s before the kill: their stamps (i / 20 Hz) are all in the bag
    assert len(clock) >= 300 and max(clock) - EPOCH_NS >= 299 * 50_000_000, (len(clock), lines[-3:])
    assert recording_state(str(bag)) == "recording"
    fixed = tmp_path / "recovered.mcap"
    assert main(["recover", str(bag), "--out", str(fixed)]) == 0
    with AnyReader([fixed]) as ar:
        assert sum(1 for _ in ar.messages()) == n
    assert os.path.getsize(fixed) > 0
    from gyro_instrument import instruments
    streaming_instrument.register()                  # replay rebuilds the scene the bag stores
    try:
        result = replay_bag(str(bag))
    finally:
        instruments.unregister(streaming_instrument.AnalyticCompass.type_name)
    assert any("interrupted" in note for note in result.get("replay_notes", []))
    json.dumps(result, allow_nan=False)
