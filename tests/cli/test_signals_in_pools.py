"""A SIGTERM or Ctrl-C while a local process pool runs is acted on between results
(prsc/commands/executors.py, _DeferredSignals): the handler's exception is raised where no
multiprocessing lock is held, the pool ends, and no worker is left behind."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from prsc.commands.executors import LocalExecutor


class Stopped(BaseException):
    """What the test's SIGTERM handler raises (the CLI raises Terminated)."""


def _slow(shared, item):
    time.sleep(shared)
    return item


def _raise(signum, frame):
    raise Stopped


@pytest.mark.parametrize("start", ["fork", "spawn"])
def test_sigterm_during_a_pool_stops_it_between_results(start):
    previous = signal.signal(signal.SIGTERM, _raise)
    seen = []
    try:
        timer = threading.Timer(1.5, os.kill, (os.getpid(), signal.SIGTERM))
        timer.start()
        began = time.monotonic()
        with pytest.raises(Stopped):
            LocalExecutor(jobs=2, start=start).map(_slow, 0.05, range(10_000), seen.append)
        assert time.monotonic() - began < 10  # not after 10,000 items: at once
        assert 0 < len(seen) < 10_000
        assert signal.getsignal(signal.SIGTERM) is _raise  # the handler is back
    finally:
        signal.signal(signal.SIGTERM, previous)
    import multiprocessing

    assert multiprocessing.active_children() == []
