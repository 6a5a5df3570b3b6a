"""Angle helpers shared by the instruments."""

import numpy as np

TWO_PI = 2.0 * np.pi


def unwrap(angle) -> np.ndarray:
    """Continuous angle from one wrapped to (−π, π]: removes the 2π jumps between samples.

    Same result as ``numpy.unwrap`` for sampled motion (steps below π between samples), in
    fewer passes over the data: a day of a 20 Hz pendulum is 1.7 million samples.
    """
    angle = np.asarray(angle, dtype=float)
    if angle.size < 2:
        return angle.copy()
    turns = np.rint(np.diff(angle) / TWO_PI)
    out = angle.copy()
    if turns.any():
        out[1:] -= TWO_PI * np.cumsum(turns)
    return out


class _BlockUnwrapper:
    """An unwrapping continued across consecutive blocks of one angle history: the previous block's
    last sample is put in front of each block (:meth:`_unwrap` gets both) and kept for the next."""

    def __init__(self) -> None:
        self.prev = None

    def __call__(self, angle) -> np.ndarray:
        angle = np.asarray(angle, dtype=float)
        if angle.size == 0:
            return angle.copy()
        first = self.prev is None
        x = angle if first else np.concatenate([[self.prev], angle])
        out = self._unwrap(angle, x, first)
        self.prev = float(angle[-1])
        return out

    def _unwrap(self, angle, x, first):
        raise NotImplementedError


class Unwrapper(_BlockUnwrapper):
    """:func:`unwrap` continued across consecutive blocks of one angle history.

    Carries the last wrapped sample and the whole turns removed so far (an integer held exactly in a
    float), so ``concatenate([u(a) for a in blocks])`` equals ``unwrap(concatenate(blocks))`` bit for
    bit: both subtract 2π × the same integer from each sample.
    """

    def __init__(self) -> None:
        super().__init__()
        self.turns = 0.0

    def _unwrap(self, angle, x, first):
        turns = self.turns + np.cumsum(np.rint(np.diff(x) / TWO_PI))
        out = angle.copy()
        if turns.size and (turns.any() or self.turns):
            if first:
                out[1:] -= TWO_PI * turns
            else:
                out -= TWO_PI * turns
        self.turns = float(turns[-1]) if turns.size else self.turns
        return out


class NumpyUnwrapper(_BlockUnwrapper):
    """``numpy.unwrap`` (period 2π) continued across consecutive blocks of one angle history: the
    same corrections (numpy's formula on the differences, the previous block's last sample first)
    summed in the same order from the running total, so the blocks concatenate to
    ``numpy.unwrap(concatenate(blocks))`` bit for bit."""

    def __init__(self) -> None:
        super().__init__()
        self.total = 0.0

    def _unwrap(self, angle, x, first):
        period = 2 * np.pi
        low, high = -period / 2, period / 2
        dd = np.diff(x)
        ddmod = np.mod(dd - low, period) + low
        np.copyto(ddmod, high, where=(ddmod == low) & (dd > 0))
        correct = ddmod - dd
        np.copyto(correct, 0, where=abs(dd) < high)
        if first:
            out = angle.copy()
            out[1:] = angle[1:] + correct.cumsum()
            self.total = float(correct.cumsum()[-1]) if correct.size else 0.0
        else:
            running = np.concatenate([[self.total], correct]).cumsum()[1:]
            out = angle + running
            self.total = float(running[-1])
        return out
