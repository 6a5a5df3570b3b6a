"""The joint samples the estimator node keeps (no rclpy): :class:`JointBuffer`."""

import numpy as np

from gyro_instrument.core.scene import EPOCH_NS
from gyro_instrument.recording.cdr import cdr_stamp_ns


class JointBuffer:
    """The joint samples one instrument's topic delivered, in arrival order, kept as the estimator
    needs them: the stamp, the measured channels' positions (the first ``keep`` joints) and the last
    joint's velocity (a gyroscope's measured spin) — 8 (2 + ``keep``) bytes per sample, in arrays
    that grow by doubling (what grows with the run: the samples the estimator fits, nothing else).
    Serialized messages of the expected layout are kept as bytes, at most :attr:`DECODE_EVERY`,
    and decoded together; any other accepted message (decoded by rclpy) is appended after them.
    Both give the same float64 values bit for bit, so the estimate does not depend on which path
    a message took."""

    def __init__(self, layout, keep=None):
        self.layout = layout
        k = layout.fields[0][1]
        self.keep = k if keep is None else int(keep)
        self._raw = []
        self._t = np.zeros(0, dtype=np.int64)
        self._pos = np.zeros((0, self.keep))
        self._vel = np.zeros((0, 1))
        self._n = 0                # rows of the arrays in use
        self.count = 0

    def __len__(self):
        return self.count

    #: serialized messages kept before they are decoded into arrays (at most this many bytes objects)
    DECODE_EVERY = 4096

    def add_raw(self, data) -> None:
        """A serialized message that ``layout.matches``."""
        self._raw.append(data)
        self.count += 1
        if len(self._raw) >= self.DECODE_EVERY:
            self._flush()

    def add(self, t_ns, position, velocity) -> None:
        self._flush()
        self._append(np.array([t_ns], dtype=np.int64), np.array([position], dtype=np.float64),
                     np.array([velocity], dtype=np.float64))
        self.count += 1

    def _append(self, t, pos, vel):
        m_ = t.size
        need = self._n + m_
        if need > self._t.size:
            cap = max(need, 2 * self._t.size, 1024)
            for name in ("_t", "_pos", "_vel"):
                old = getattr(self, name)
                new = np.empty((cap,) + old.shape[1:], dtype=old.dtype)
                new[:self._n] = old[:self._n]
                setattr(self, name, new)
        self._t[self._n:need] = t
        self._pos[self._n:need] = pos[:, :self.keep]
        self._vel[self._n:need] = vel[:, -1:]
        self._n = need

    def _flush(self):
        if self._raw:
            t, (pos, vel, _) = self.layout.decode(self._raw)
            self._raw = []
            self._append(t, pos, vel)

    def arrays(self) -> tuple:
        """(t_ns (m,), position (m, keep), velocity (m, 1): the last joint's) of everything received;
        views of the buffer, valid until the next sample arrives."""
        self._flush()
        n = self._n
        return self._t[:n], self._pos[:n], self._vel[:n]

    def split_run(self) -> tuple:
        """(the samples before the last place the stamps go back, those after it: a new run's that
        arrived before its first clock tick) as two buffers; all before when they never go back."""
        t, pos, vel = self.arrays()
        back = np.flatnonzero(t[1:] < t[:-1])
        k = int(back[-1]) + 1 if back.size else t.size
        parts = []
        for a, z in ((0, k), (k, t.size)):
            out = JointBuffer(self.layout, keep=self.keep)
            if z > a:
                out._append(t[a:z].copy(), pos[a:z].copy(), vel[a:z].copy())
                out.count = z - a
            parts.append(out)
        return tuple(parts)

    def nbytes(self) -> int:
        """Bytes held (the arrays' capacity and the serialized messages not yet decoded)."""
        return self._t.nbytes + self._pos.nbytes + self._vel.nbytes + sum(len(d) for d in self._raw)

    def last_stamp(self) -> int | None:
        if self._raw:
            return cdr_stamp_ns(self._raw[-1]) - EPOCH_NS
        return int(self._t[self._n - 1]) if self._n else None
