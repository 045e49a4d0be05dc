"""Generic executors: a pure function over a list of points, on one of four backends.

They know no analysis.  :func:`run_points` returns the results in point order;
:func:`stream` hands each result to a callback as it finishes (the study runner
keeps them in its resumable store).  Whatever runs which point, the results are
the same, bit for bit: every point is computed by the same pure function.

- ``auto`` (the default): the analysis's choice (:meth:`Execution.resolve`), a thread
  pool where none states one;
- ``serial``: in this process, in order;
- ``threads``: a thread pool of ``workers`` (every core); the compiled core releases
  the GIL for a whole integration;
- ``processes``: a process pool (fork where there is one); a worker that dies
  breaks the pool, which is recreated and the unfinished tasks resubmitted
  (at most :data:`MAX_POOL_RESTARTS` times in a row without progress);
- ``dask``: a Dask cluster at ``scheduler``, or a LocalCluster of ``dask_local``
  single-threaded worker processes started here; tasks of a worker that dies
  are rerun by the scheduler (twice).
"""

from boringbar.execute.executors import (
    EXECUTORS,
    MAX_POOL_RESTARTS,
    Execution,
    run_points,
    stream,
)

__all__ = ["EXECUTORS", "MAX_POOL_RESTARTS", "Execution", "run_points", "stream"]
