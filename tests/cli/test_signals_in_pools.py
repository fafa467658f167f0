"""A SIGTERM or Ctrl-C while local workers run is acted on between results
(prsc/pipeline/executors.py, _DeferredSignals): the handler's exception is raised where
nothing is in flight, the workers end (even a frozen one), and none is left behind; a
worker's error is raised in the parent, and a worker that dies is an error, not a hang."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from prsc.pipeline.executors import LocalExecutor
from prsc.errors import PrscError


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


def _stops_itself(shared, item):
    if item == 3:
        os.kill(os.getpid(), signal.SIGSTOP)  # a worker frozen mid-item (a debugger, a full disk)
    time.sleep(0.01)
    return item


def _fails(shared, item):
    if item == 7:
        raise PrscError(f"item {item} is bad")
    return item


def _dies(shared, item):
    if item == 7:
        os._exit(3)  # as the kernel's OOM killer would end it
    return item


def test_a_stop_ends_even_a_frozen_worker_at_once():
    """The parent stops its workers by SIGKILL, on pipes of their own: a frozen worker (which
    ignores SIGTERM until continued) or one that held a shared queue's lock cannot keep it waiting."""
    previous = signal.signal(signal.SIGTERM, _raise)
    try:
        timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGTERM))
        timer.start()
        began = time.monotonic()
        with pytest.raises(Stopped):
            LocalExecutor(jobs=2, start="fork").map(_stops_itself, None, range(10_000))
        assert time.monotonic() - began < 5
    finally:
        signal.signal(signal.SIGTERM, previous)
    import multiprocessing

    assert multiprocessing.active_children() == []


@pytest.mark.parametrize("start", ["fork", "spawn"])
def test_a_worker_error_is_raised_here_and_a_dead_worker_is_an_error(start):
    import multiprocessing

    with pytest.raises(PrscError, match="item 7 is bad"):
        LocalExecutor(jobs=2, start=start).map(_fails, None, range(40))
    with pytest.raises(PrscError, match=r"a worker process ended unexpectedly \(exit code 3\)"):
        LocalExecutor(jobs=2, start=start).map(_dies, None, range(40))
    assert multiprocessing.active_children() == []
    seen: list[int] = []
    assert LocalExecutor(jobs=2, start=start).map(_fails, None, range(7), seen.append) == list(range(7))
    assert sorted(seen) == list(range(7))
