"""The contract every analysis module meets.

An analysis (``sweep``, ``lobes``, ``bifurcation``, ``basins``, ``sensitivity``)
is one module that owns:

- its options: a frozen dataclass (units in the names) that validates itself,
  naming the parameter, the value and the allowed range;
- ``plan(..., options, integration) -> Plan``: the shared ``context`` (systems,
  options: everything every point needs, picklable) and the ordered list of
  independent ``points``;
- ``compute(context, point)``: one point's result, pure and picklable (the same
  point gives the same result, bit for bit, wherever it runs);
- ``assemble(plan, results) -> xarray.Dataset``: the results, in point order, with
  the full configuration and the package version in its attributes (wall-clock
  timings only in the attributes, so the data do not depend on where it ran);
- ``summary(ds) -> dict``: the JSON-able summary (what the CLI prints with --json).

Its public function (``sweep(...)``, ...) is ``plan``, then the points
on an executor (:func:`boringbar.execute.run_points`), then ``assemble``:
:func:`run_plan`.  The study files (:mod:`boringbar.studies.registry`) and the
command line build the same plans from their own inputs.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from types import ModuleType

from boringbar.execute import Execution, run_points


@dataclass
class Plan:
    """What an analysis computes: ``points`` in result order and the ``context`` they
    share; ``extra``: what assembly needs beyond them."""

    context: object
    points: list
    extra: dict = field(default_factory=dict)


def run_plan(module: ModuleType, plan: Plan, execution: Execution | None = None,
             progress=None) -> tuple[list, float]:
    """``module.compute`` of every point of ``plan`` on ``execution``; (results in point
    order, wall time in s)."""
    tic = time.perf_counter()
    results = run_points(functools.partial(module.compute, plan.context), plan.points,
                         execution=execution, progress=progress)
    return results, time.perf_counter() - tic


def execution_attrs(execution: Execution | None, wall_time_s: float) -> dict:
    """Where and how long a run took, for a Dataset's attributes."""
    execution = (execution or Execution()).resolve()
    return {"executor": execution.executor, "workers": execution.n_workers,
            "wall_time_s": wall_time_s}
