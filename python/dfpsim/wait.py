"""Polling helpers: wait until something on the bus or at the drive has happened."""

import time

_NOTHING = object()


def _timeout_message(what, timeout, polls, last):
    seen = "nothing (no poll finished)" if last is _NOTHING else repr(last)
    return "timed out after %.3g s waiting for %s (%d polls); last value seen: %s" % (
        timeout, what, polls, seen)


def wait_until(predicate, timeout=2.0, interval=0.02, what=None):
    """Calls `predicate()` every `interval` s until it returns something true; returns that.

        wait_until(lambda: drive.speed_actual_rpm >= 299.5, timeout=2, what="300 rpm")

    Raises TimeoutError after `timeout` s, naming `what` (default: the predicate's name) and the
    last value `predicate()` returned. The predicate is always called once more at the deadline,
    so a slow poll cannot make it miss a state that was reached. Exceptions from the predicate
    (a refused request, a dead server) are not swallowed.
    """
    __tracebackhide__ = True  # pytest: the failure shows the caller's line, not this loop
    if what is None:
        what = getattr(predicate, "__name__", "the condition")
    end = time.monotonic() + timeout
    last = _NOTHING
    polls = 0
    while True:
        last = predicate()
        polls += 1
        if last:
            return last
        now = time.monotonic()
        if now >= end:
            break
        time.sleep(min(interval, end - now))
    raise TimeoutError(_timeout_message(what, timeout, polls, last))


def wait_for(getter, condition, timeout=2.0, interval=0.02, what=None):
    """Reads `getter()` every `interval` s until `condition(value)` holds; returns the value.

        rpm = wait_for(lambda: drive.speed_actual_rpm, lambda rpm: rpm >= 299.5,
                       timeout=2.5, what="speed ramped up to 300 rpm")

    As wait_until, but the TimeoutError shows the last value read (e.g. 212.4), not just False.
    """
    __tracebackhide__ = True
    if what is None:
        what = getattr(condition, "__name__", "the condition")
    end = time.monotonic() + timeout
    last = _NOTHING
    polls = 0
    while True:
        last = getter()
        polls += 1
        if condition(last):
            return last
        now = time.monotonic()
        if now >= end:
            break
        time.sleep(min(interval, end - now))
    raise TimeoutError(_timeout_message(what, timeout, polls, last))
