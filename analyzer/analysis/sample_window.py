"""The attitude samples a pending judgement can still need, found by bisection."""

from __future__ import annotations

from bisect import bisect_right
from collections import deque

from analyzer.analysis.samples import Sample

HISTORY = 4096  # samples kept at most (over half an hour at 2 Hz), whatever is pending
_COMPACT = 4096  # drop the list's dead head once it is this long and half the list


class SampleWindow:
    """Attitude samples oldest first, kept from the last one at or before a time still
    needed (``forget_before``), and never more than ``HISTORY``.

    ``before`` and ``between`` bisect the times when they arrived in order; when a sample
    came with an earlier time than the one before it (a clock that jumped back), they scan
    the kept samples in arrival order instead, and nothing is forgotten early until that
    sample has left the window. ``examined`` counts the samples every look-up touched.
    """

    def __init__(self, history: int = HISTORY) -> None:
        self.history = history
        self._samples: list[Sample] = []
        self._times: list[float] = []
        self._head = 0  # index of the oldest kept sample
        self._descents: deque[int] = deque()  # indexes of samples earlier than the one before
        self.examined = 0

    def __len__(self) -> int:
        return len(self._samples) - self._head

    @property
    def last(self) -> Sample | None:
        return self._samples[-1] if len(self) else None

    def append(self, sample: Sample) -> None:
        times = self._times
        if len(self) and sample.time < times[-1]:
            self._descents.append(len(times))
        self._samples.append(sample)
        times.append(sample.time)
        if len(self) > self.history:
            self._drop_to(self._head + 1)

    def forget_before(self, needed: float) -> None:
        """Nothing will be asked about samples before the last one at or before ``needed``."""
        if self._descents or not len(self):
            return
        keep = bisect_right(self._times, needed, self._head) - 1
        if keep > self._head:
            self._drop_to(keep)

    def before(self, t: float) -> Sample | None:
        """The last sample at or before ``t`` (of those that came before a later one)."""
        head, samples = self._head, self._samples
        if not self._descents:
            i = bisect_right(self._times, t, head) - 1
            self.examined += 1
            return samples[i] if i >= head else None
        found = None
        for s in samples[head:]:
            self.examined += 1
            if s.time > t:
                break
            found = s
        return found

    def between(self, start: float, end: float) -> list[Sample]:
        """The samples with ``start < time <= end``, in the order they came."""
        head, samples = self._head, self._samples
        if not self._descents:
            lo = bisect_right(self._times, start, head)
            hi = bisect_right(self._times, end, lo)
            self.examined += hi - lo + 1
            return samples[lo:hi]
        self.examined += len(self)
        return [s for s in samples[head:] if start < s.time <= end]

    def _drop_to(self, head: int) -> None:
        self._head = head
        descents = self._descents
        while descents and descents[0] <= head:  # its pair (one before, it) is gone
            descents.popleft()
        if head >= _COMPACT and head * 2 >= len(self._samples):
            del self._samples[:head]
            del self._times[:head]
            self._descents = deque(i - head for i in descents)
            self._head = 0
