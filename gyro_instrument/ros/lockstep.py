"""Lock-step delivery of the suite's published batches (:class:`LockStep`): every message of a
batch taken from the estimator's and recorder's subscriptions and their callbacks run sample by
sample, so the recorder writes the same ordered stream as one sample at a time."""

import time
from contextlib import ExitStack

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription


class DeliveryError(RuntimeError):
    """A message was not delivered in time (the suite never drops silently)."""


def _call(sub, taken):
    if sub._callback_type is Subscription.CallbackType.MessageOnly:
        sub.callback(taken[0])
    else:
        sub.callback(*taken)


class LockStep:
    """Delivery of published batches to subscriptions, without the executor's per-callback cost.

    Parameters
    ----------
    context : rclpy.Context
    counted : list of (topic, Subscription)
        Subscriptions that receive exactly one message per published sample of their topic.
    others : list of Subscription
        Subscriptions drained after each batch (whatever arrived), e.g. the nodes' ``/clock``.
    """

    def __init__(self, context, counted, others=()):
        self.context = context
        self.counted = list(counted)
        self.others = list(others)

    def deliver(self, published, timeout_s, describe=lambda: "") -> None:
        """Take ``published[topic]`` messages from every counted subscription of that topic, run
        the callbacks sample-major (message i of each subscription in order, then i + 1), then
        drain the other subscriptions. ``published[topic]`` is a count (one message per sample
        of the batch) or a list of the sample offsets in the batch its messages belong to (the
        markers, every few samples). Raises :class:`DeliveryError` after ``timeout_s`` without
        a complete batch."""
        offsets = [published.get(topic, 0) for topic, _ in self.counted]
        want = [len(o) if isinstance(o, list) else o for o in offsets]
        got = self._collect(want, timeout_s, describe)
        self._run_sample_major(self._calls(got), offsets)
        self.drain()

    def _collect(self, want, timeout_s, describe):
        """Take ``want[j]`` messages from counted subscription j, waiting on a wait set for any not
        yet delivered.

        Returns the list (one per counted subscription) of the taken tuples, in arrival order.
        Raises :class:`DeliveryError` (naming ``describe()`` and the short topics) when a
        subscription still lacks messages ``timeout_s`` after the first incomplete pass.
        """
        got = [[] for _ in self.counted]
        deadline = None
        while True:
            missing = []
            for (_, sub), q, n in zip(self.counted, got, want):
                if len(q) < n:
                    with sub.handle:
                        take, msg_type, raw = sub.handle.take_message, sub.msg_type, sub.raw
                        while len(q) < n:
                            taken = take(msg_type, raw)
                            if taken is None:
                                break
                            q.append(taken)
                    if len(q) < n:
                        missing.append(sub)
            if not missing:
                return got
            now = time.monotonic()
            if deadline is None:
                deadline = now + timeout_s
            elif now > deadline:
                short = ", ".join(f"{topic} {len(q)}/{n}" for (topic, _), q, n in zip(self.counted, got, want)
                                  if len(q) < n)
                raise DeliveryError(f"{describe()}: not delivered in {timeout_s} s: {short}")
            self._wait(missing, 0.01)

    def _calls(self, got):
        """Turn the taken messages into ``(callback, arguments)`` pairs, one list per counted
        subscription: MessageOnly callbacks get the message alone, the others the whole taken
        tuple (message and message info)."""
        calls = []
        for (_, sub), q in zip(self.counted, got):
            if sub._callback_type is Subscription.CallbackType.MessageOnly:
                calls.append([(sub.callback, (taken[0],)) for taken in q])
            else:
                calls.append([(sub.callback, taken) for taken in q])
        return calls

    @staticmethod
    def _run_sample_major(calls, offsets):
        """Run the calls sample-major: call i of every per-sample (dense) subscription in order,
        then the sparse subscriptions' (markers') calls at sample offset i, then i + 1. Dense
        subscriptions with different numbers of calls run row by row up to the longest."""
        dense = [c for c, o in zip(calls, offsets) if not isinstance(o, list)]
        sparse_at = {}                               # sample offset -> calls of sparse topics (markers)
        for c, o in zip(calls, offsets):
            if isinstance(o, list):
                for off, call in zip(o, c):
                    sparse_at.setdefault(off, []).append(call)
        if len({len(c) for c in dense}) <= 1:        # every per-sample topic published the same samples
            if not sparse_at:
                for row in zip(*dense):
                    for cb, args in row:
                        cb(*args)
            else:
                for i, row in enumerate(zip(*dense)):
                    for cb, args in row:
                        cb(*args)
                    for cb, args in sparse_at.get(i, ()):
                        cb(*args)
        else:
            for i in range(max(len(c) for c in dense)):
                for c in dense:
                    if i < len(c):
                        cb, args = c[i]
                        cb(*args)
                for cb, args in sparse_at.get(i, ()):
                    cb(*args)

    def drain(self) -> None:
        """Run the callbacks of whatever the other subscriptions hold."""
        for sub in self.others:
            with sub.handle:
                while True:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
                    if taken is None:
                        break
                    _call(sub, taken)

    def _wait(self, subs, timeout_s):
        with ExitStack() as stack:
            stack.enter_context(self.context.handle)
            for sub in subs:
                stack.enter_context(sub.handle)
            ws = _rclpy.WaitSet(len(subs), 0, 0, 0, 0, 0, self.context.handle)
            ws.clear_entities()
            for sub in subs:
                ws.add_subscription(sub.handle)
            ws.wait(int(timeout_s * 1e9))
