"""The threads executor on two cores: a sweep with 2 worker threads against 1.

    .venv/bin/python benchmarks/bench_threads.py [--repeat 3] [--duration-s 0.5]

The compiled core releases the GIL for a whole integration, so worker threads run
kernels side by side.  Two sweeps of the published cases (solid, TMD and the four ball
dampers; 11 ratios at 10 N): under the physical preset (the exact integrator, one run a
point) and under the paper preset (RK4 in lock-step batches of 4 runs), each with
``Execution("threads", workers=1)`` and ``workers=2`` alternately in this process, best
of ``--repeat``; prints the wall times and their ratio, and checks that the two give the
same numbers bit for bit.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import boringbar as bb


def timed(cases, options, integration, workers):
    tic = time.perf_counter()
    ds = bb.sweep(cases, options, integration=integration,
                  execution=bb.Execution("threads", workers=workers))
    return time.perf_counter() - tic, ds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration-s", type=float, default=0.5)
    args = ap.parse_args()
    ratios = tuple(np.round(np.linspace(0.95, 1.05, 11), 3))
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; 6 cases x 11 "
          f"ratios, {args.duration_s:g} s runs, best of {args.repeat}")
    for preset, batch in (("physical", 1), ("paper", 4)):
        cases = bb.published_cases(preset=preset)
        options = bb.SweepOptions(ratios=ratios, forces_n=(10.0,), batch=batch)
        integration = bb.Integration(duration_s=args.duration_s)
        best, out = {1: np.inf, 2: np.inf}, {}
        for _ in range(args.repeat):
            for workers in (1, 2):
                wall, out[workers] = timed(cases, options, integration, workers)
                best[workers] = min(best[workers], wall)
        same = all(np.array_equal(out[1][v].values, out[2][v].values, equal_nan=True)
                   for v in out[1].data_vars if out[1][v].dtype.kind == "f")
        print(f"  {preset:8s} ({'exact' if batch == 1 else 'RK4, batches of 4'}): 1 thread "
              f"{best[1]:6.2f} s, 2 threads {best[2]:6.2f} s, speed-up "
              f"{best[1] / best[2]:.2f}x; {'bit-identical' if same else 'RESULTS DIFFER'}")


if __name__ == "__main__":
    main()
