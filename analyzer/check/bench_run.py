"""How a run that moves a bench gimbal (``check``, ``replay``) opens its recording and ends."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from analyzer.capture import Capture
from analyzer.check.link import CheckLink
from analyzer.check.observer import Observer
from analyzer.errors import SourceError
from analyzer.mcapio.write.sink import McapSink
from analyzer.timefmt import UTC, TimeZone

DRAIN_S = 2.0  # what was sent has this long to come through the pipeline at the end
JOIN_S = 10.0  # the capture's thread has this long to end


def bench_sink(
    link: CheckLink,
    path: str,
    metadata: dict[str, str],
    *,
    force: bool,
    hold_back: float = 0.0,
    zone: TimeZone = UTC,
) -> McapSink:
    """The run's recording at ``path``; the link is closed if it cannot be opened."""
    try:
        return McapSink(path, metadata=metadata, force=force, hold_back=hold_back, zone=zone)
    except BaseException:
        link.close()
        raise


def kept_up_to_then(error: object, path: str) -> SourceError:
    """What failed, and that the recording at ``path`` keeps everything up to then."""
    return SourceError(f"{error}; the recording {path} keeps everything up to then")


def nothing_else() -> bool:
    return True


@dataclass
class BenchRecording:
    """A run on the bench: its link, the capture of the link through the analysis into
    the recording (``sink``, at ``path``) and the observer that reads what it captured."""

    link: CheckLink
    observer: Observer
    capture: Capture
    sink: McapSink
    path: str

    @contextlib.contextmanager
    def running(
        self,
        run: str,
        stop_gimbal: Callable[[bool], None],
        seen: Callable[[], bool] = nothing_else,
    ) -> Iterator[None]:
        """The body moves the gimbal (``run``: "the check"); a link that fails is said with
        what it leaves. Whatever happens, then: ``stop_gimbal(completed)``, everything
        sent (and what ``seen`` waits for) through the pipeline before it stops, the
        recording finished; a recording that failed raises."""
        completed = False
        try:
            yield
            completed = True
        except SourceError as exc:
            raise kept_up_to_then(
                f"{exc}; {run} stopped (the gimbal may not be centred)", self.path
            ) from None
        finally:
            stop_gimbal(completed)
            observer, sent = self.observer, self.link.last_sent
            observer.wait(
                lambda: observer.commands_until >= sent and seen(), time.monotonic() + DRAIN_S
            )
            self.capture.stop()
            self.capture.join(JOIN_S)
            with contextlib.suppress(SourceError):
                self.sink.close()
        if self.sink.error is not None:
            raise SourceError(self.sink.error)
