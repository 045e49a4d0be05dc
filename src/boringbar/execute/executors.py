"""The executors of :mod:`boringbar.execute` (see its docstring)."""

from __future__ import annotations

import contextlib
import logging
import multiprocessing as mp
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Hashable
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, replace

from boringbar._validate import ParameterError, check_choice

EXECUTORS = ("auto", "serial", "threads", "processes", "dask")
#: How often a broken process pool is recreated without any task finishing.
MAX_POOL_RESTARTS = 3
#: How often (s) a pool worker checks that its parent is still there.
ORPHAN_POLL_S = 1.0


@dataclass(frozen=True)
class Execution:
    """Where the points of an analysis run.

    ``executor``: one of :data:`EXECUTORS` ("auto": the one the analysis chooses,
    :meth:`resolve`); ``workers``: threads or processes (default: every core);
    ``scheduler``: a Dask scheduler's address, or ``dask_local``: the number of workers
    of a LocalCluster started for the run (either one selects ``dask``).
    """

    executor: str = "auto"
    workers: int | None = None
    scheduler: str | None = None
    dask_local: int | None = None

    def __post_init__(self):
        if self.scheduler is not None and self.dask_local is not None:
            raise ParameterError("give at most one of scheduler and dask_local")
        if self.executor not in EXECUTORS:
            raise ParameterError(f"executor = {self.executor!r} is not one of "
                                 f"{', '.join(EXECUTORS)}")
        if (self.scheduler is not None or self.dask_local is not None) \
                and self.executor != "dask":
            object.__setattr__(self, "executor", "dask")
        for name in ("workers", "dask_local"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, int)
                                  or not 1 <= v <= 4096):
                raise ParameterError(f"{name} = {v!r} must be an integer from 1 to 4096")

    def resolve(self, preferred: str = "threads") -> Execution:
        """This execution with "auto" made ``preferred`` (threads where an analysis states
        no preference; the others are kept as given)."""
        check_choice("preferred", preferred, EXECUTORS[1:])
        return replace(self, executor=preferred) if self.executor == "auto" else self

    @property
    def n_workers(self) -> int:
        """The number of workers the run will have (1 for serial)."""
        if self.executor == "serial":
            return 1
        return int(self.dask_local or self.workers or os.cpu_count() or 1)


def run_points(fn: Callable, points: list, *, execution: Execution | None = None,
               progress: Callable[[int, int], None] | None = None) -> list:
    """``[fn(p) for p in points]``, run on ``execution``'s executor, in point order.

    ``progress(done, total)`` is called (in this thread) as points finish.
    ``fn`` and the points must pickle for ``processes`` and ``dask`` (a
    module-level function, or a ``functools.partial`` of one).
    """
    results: list = [None] * len(points)
    done = 0

    def on_done(i, result):
        nonlocal done
        results[i] = result
        done += 1
        if progress is not None:
            progress(done, len(points))

    stream(fn, dict(enumerate(points)), on_done, execution=execution)
    return results


def stream(fn: Callable, tasks: dict[Hashable, object], on_done: Callable,
           *, execution: Execution | None = None, on_restart: Callable | None = None,
           task_name: str = "boringbar") -> None:
    """Run ``fn(task)`` for every value of ``tasks`` and call ``on_done(key, result)``
    in this thread as each finishes (in any order).  ``on_restart(message)`` is told
    when a broken process pool is recreated.  ``task_name`` prefixes Dask task keys."""
    execution = (execution or Execution()).resolve()
    if not tasks:
        return
    if execution.executor == "serial":
        for k, task in tasks.items():
            on_done(k, fn(task))
    elif execution.executor == "threads":
        _threads(fn, tasks, on_done, execution.n_workers)
    elif execution.executor == "processes":
        _processes(fn, tasks, on_done, execution.n_workers, on_restart)
    else:
        _dask(fn, tasks, on_done, execution, task_name)


def _threads(fn, tasks, on_done, workers):
    with ThreadPoolExecutor(max_workers=min(workers, len(tasks))) as pool:
        futs = {pool.submit(fn, task): k for k, task in tasks.items()}
        try:
            for fut in as_completed(futs):
                on_done(futs[fut], fut.result())
        except BaseException:
            # a failed point or a caller that stops (on_done raising) ends the work: the
            # points not started are dropped rather than run for nobody
            pool.shutdown(wait=True, cancel_futures=True)
            raise


def _mp_context():
    """fork where there is one: no re-import of the caller's main module (a script
    without an ``if __name__ == "__main__"`` guard works) and a fast start."""
    return mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")


def _worker_start(parent: int) -> None:
    """A pool worker's initializer.  Its parent ends it (Ctrl-C and SIGTERM reach the
    parent, which terminates its workers): the worker ignores Ctrl-C, and SIGTERM ends
    it at once whatever handler it inherited.  And it ends itself once its parent is gone
    (killed outright, as SIGKILL does), rather than wait for ever on a queue nobody
    closes."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(ORPHAN_POLL_S)
        os._exit(1)

    threading.Thread(target=watch, name="boringbar-orphan-watch", daemon=True).start()


def _end_workers(workers: set) -> None:
    """Terminate the pool's worker processes at once and reap them."""
    for p in workers:
        p.terminate()
    for p in workers:
        p.join(timeout=5.0)


def _processes(fn, tasks, on_done, workers, on_restart):
    pending = dict(tasks)
    restarts = 0
    while pending:
        before = set(mp.active_children())
        pool = ProcessPoolExecutor(max_workers=min(workers, len(pending)),
                                   mp_context=_mp_context(), initializer=_worker_start,
                                   initargs=(os.getpid(),))
        progressed = False
        futs: dict = {}
        try:
            futs = {pool.submit(fn, task): k for k, task in pending.items()}
            for fut in as_completed(futs):
                k = futs[fut]
                on_done(k, fut.result())
                pending.pop(k)
                progressed = True
        except BrokenProcessPool:
            progressed |= _keep_finished(futs, pending, on_done)
            restarts = 0 if progressed else restarts + 1
            if on_restart is not None:
                on_restart(f"a worker process died; {len(pending)} unfinished tasks are "
                           "resubmitted to a new pool")
            if restarts > MAX_POOL_RESTARTS:
                raise ChildProcessError(
                    f"worker processes died {restarts} times in a row without finishing a "
                    "task; giving up") from None
        except BaseException:
            # interrupted (Ctrl-C, SIGTERM) or a task failed: the workers end now.  An
            # interrupt that lands while the pool starts them can cut them off from their
            # queue, and a graceful shutdown would then wait for them for ever.
            _end_workers(set(mp.active_children()) - before)
            raise
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


def _keep_finished(futs, pending, on_done) -> bool:
    """Hand on what finished before a pool broke; whether anything did."""
    kept = False
    for fut, k in futs.items():
        if k in pending and fut.done() and not fut.cancelled() and fut.exception() is None:
            on_done(k, fut.result())
            pending.pop(k)
            kept = True
    return kept


def _dask(fn, tasks, on_done, execution, task_name):
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise ParameterError("executor = 'dask' needs dask and distributed: "
                             "pip install 'boringbar[dask]'") from None
    with contextlib.ExitStack() as stack:
        if execution.scheduler is None:
            cluster = stack.enter_context(LocalCluster(
                n_workers=execution.n_workers, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.ERROR))
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(Client(execution.scheduler))
        run_id = uuid.uuid4().hex[:8]  # task keys unique to this run on a shared cluster
        futs = {client.submit(fn, task, pure=False, retries=2,
                              key=f"{task_name}-{run_id}-{i}"): k
                for i, (k, task) in enumerate(tasks.items())}
        for fut in as_completed(list(futs)):
            try:
                result = fut.result()
            except Exception as exc:
                if type(exc).__name__ != "KilledWorker":
                    raise
                raise ChildProcessError(f"Dask gave up on a task whose workers kept dying "
                                        f"({exc})") from None
            on_done(futs[fut], result)
