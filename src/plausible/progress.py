"""The progress protocol: one meaning of the keyword ``progress`` everywhere.

A long computation takes ``progress``, a *factory*: it calls ``progress(total)``
once, with the number of steps it is about to do (and optionally a ``label``
saying what they are), and gets back ``tick``, which it calls after each step
(``tick()`` advances by one, ``tick(n)`` by ``n``).  ``progress=None`` means
the ambient reporter, set with :func:`reporting` (the command line sets its
bar there for the whole command, so that work no keyword reaches, such as a
pumped-up albedo table built while a model spec is parsed, still shows), and
without one, no report (:func:`silent`).

    >>> from plausible.progress import Counter
    >>> c = Counter()
    >>> tick = c(3, "albedo")
    >>> for _ in range(3):
    ...     tick()
    >>> c.counts
    {'albedo': [3, 3]}

A computation that is one part of a larger one passes ``within(tick)``: a
factory whose ticks go to the caller's count (the callee's own ``total`` is
ignored, the caller already counted those steps).  A computation whose length
is not part of the caller's count (a pumped-up table built on first use)
passes the caller's factory on unchanged, and the display shows it as a task
of its own.

The display itself lives with its user: the command line's bar
(``plausible.cli._Bar``, a Rich progress bar that stops on every exit path,
used as a context manager) and the figures report.  The library only ticks.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import Protocol


class Tick(Protocol):
    def __call__(self, n: int = 1) -> None: ...


class Progress(Protocol):
    def __call__(self, total: int, label: str = "") -> Tick: ...


def _no_tick(n: int = 1) -> None:
    return None


def silent(total: int, label: str = "") -> Tick:
    """The null factory: announces nothing, ticks do nothing."""
    return _no_tick


_AMBIENT: ContextVar[Progress | None] = ContextVar("plausible_progress", default=None)


@contextmanager
def reporting(progress: Progress | None):
    """Make ``progress`` the reporter of every computation in the ``with`` block
    that is given ``progress=None``."""
    token = _AMBIENT.set(progress)
    try:
        yield progress
    finally:
        _AMBIENT.reset(token)


def ambient() -> Progress | None:
    """The reporter :func:`reporting` set for the current context, or None."""
    return _AMBIENT.get()


def start(progress: Progress | None, total: int, label: str = "") -> Tick:
    """``progress(total, label)``; with ``progress=None``, the ambient reporter's
    (:func:`reporting`), else a tick that does nothing."""
    if progress is None:
        progress = _AMBIENT.get() or silent
    return progress(total, label)


def within(tick: Tick) -> Progress:
    """A factory whose ticks advance ``tick``: for a callee whose steps the caller
    has already counted in its own total."""

    def factory(total: int, label: str = "") -> Tick:
        return tick

    return factory


class Counter:
    """A factory that records, per label, ``[total, ticks so far]`` (for tests and
    for callers that want the counts rather than a display)."""

    def __init__(self):
        self.counts: dict[str, list] = {}

    def __call__(self, total: int, label: str = "") -> Tick:
        key = label
        k = 2
        while key in self.counts:      # the same label twice: keep both
            key = f"{label}#{k}"
            k += 1
        entry = self.counts[key] = [int(total), 0]

        def tick(n: int = 1) -> None:
            entry[1] += n

        return tick


__all__ = ["Counter", "Progress", "Tick", "ambient", "reporting", "silent", "start", "within"]
