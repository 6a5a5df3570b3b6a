"""TableWriter's background writing thread: errors reach the caller, the output stays atomic."""

import threading

import numpy as np
import pyarrow.parquet as pq
import pytest

from gyro_instrument.estimators import data_io
from gyro_instrument.estimators.data_io import ROWS_PER_WRITE, TableWriter, read_table


def _blocks(n_blocks, rows):
    rng = np.random.default_rng(3)
    for b in range(n_blocks):
        t = np.arange(b * rows, (b + 1) * rows, dtype=float) * 0.05
        yield t, {"p.a": rng.normal(size=rows), "p.b": rng.normal(size=rows)}


def _writer_threads():
    return [th for th in threading.enumerate() if th.name.startswith("TableWriter")]


@pytest.mark.parametrize("ext", ["parquet", "csv"])
def test_streamed_blocks_equal_one_block(tmp_path, ext):
    blocks = list(_blocks(7, ROWS_PER_WRITE // 3 + 17))
    streamed, whole = tmp_path / f"s.{ext}", tmp_path / f"w.{ext}"
    with TableWriter(str(streamed), ["p.a", "p.b"]) as w:
        for t, cols in blocks:
            w.write(t, cols)
    assert w.rows == sum(t.size for t, _ in blocks)
    data_io.write_table(str(whole), np.concatenate([t for t, _ in blocks]),
                        {c: np.concatenate([b[c] for _, b in blocks]) for c in ("p.a", "p.b")})
    a, b = read_table(str(streamed)), read_table(str(whole))
    assert list(a) == list(b) == ["time_s", "p.a", "p.b"]
    for c in a:
        assert np.array_equal(a[c], b[c])
    assert not _writer_threads()


def test_error_in_writing_thread_reaches_caller(tmp_path, monkeypatch):
    out = tmp_path / "run.parquet"
    out.write_bytes(b"previous run")

    def fail(self, table, *args, **kwargs):
        raise OSError(28, "No space left on device (test)")
    monkeypatch.setattr(pq.ParquetWriter, "write_table", fail)
    with pytest.raises(OSError, match="No space left"):
        with TableWriter(str(out), ["p.a", "p.b"]) as w:
            for t, cols in _blocks(12, ROWS_PER_WRITE // 2):
                w.write(t, cols)
    assert out.read_bytes() == b"previous run"
    assert not (tmp_path / "run.parquet.partial").exists()
    assert not _writer_threads()


@pytest.mark.parametrize("exc", [KeyboardInterrupt, RuntimeError])
def test_interruption_removes_partial_and_stops_thread(tmp_path, exc):
    out = tmp_path / "run.parquet"
    out.write_bytes(b"previous run")
    with pytest.raises(exc):
        with TableWriter(str(out), ["p.a", "p.b"]) as w:
            for i, (t, cols) in enumerate(_blocks(12, ROWS_PER_WRITE // 2)):
                w.write(t, cols)
                if i == 8:
                    raise exc()
    assert out.read_bytes() == b"previous run"
    assert not (tmp_path / "run.parquet.partial").exists()
    assert not _writer_threads()
