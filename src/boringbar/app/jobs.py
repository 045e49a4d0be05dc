"""Computations the page runs off its event loop, newest first: a view asks for a
result and the request before it, if still running, is cancelled rather than queued.

A request not yet started is dropped from the pool; one running is told to stop
through its ``progress(done, total)`` callback (the analyses call it as points
finish; it raises :class:`Superseded` once the request is stale), so a sweep or a
simulated lobe diagram stops at its next point; a single run of a few milliseconds
finishes and its result is thrown away.
"""

from __future__ import annotations

import asyncio
import threading
from concurrent.futures import ThreadPoolExecutor
from functools import partial


class Superseded(Exception):
    """A newer request replaced this one."""


class Latest:
    """One view's computations on ``pool``: :meth:`run` awaits the newest request."""

    def __init__(self, pool: ThreadPoolExecutor):
        self.pool = pool
        self.future: asyncio.Future | None = None
        self.stop: threading.Event | None = None

    def cancel(self) -> None:
        """Stop the request in flight (if any)."""
        if self.stop is not None:
            self.stop.set()
        if self.future is not None and not self.future.done():
            self.future.cancel()

    async def run(self, fn, *args, progress=None, **kwargs):
        """``fn(*args, **kwargs)`` in the pool, after cancelling the request before;
        with ``progress``, ``fn`` is also given a ``progress(done, total)`` that
        reports to it and raises :class:`Superseded` once a newer request came.
        Raises asyncio.CancelledError (or Superseded) if this request is replaced."""
        self.cancel()
        stop = self.stop = threading.Event()
        if progress is not None:
            kwargs["progress"] = partial(_checked, stop, progress)
        loop = asyncio.get_running_loop()
        self.future = loop.run_in_executor(self.pool, partial(fn, *args, **kwargs))
        return await self.future


def _checked(stop: threading.Event, report, done: int, total: int) -> None:
    if stop.is_set():
        raise Superseded
    report(done, total)
