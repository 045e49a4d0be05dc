"""Study executors: runs per second for serial, local processes and a Dask LocalCluster.

    .venv/bin/python benchmarks/bench_executors.py [--workers N] [--duration-s 1.0]

Runs one study (impact-damped sweep: gap {0.5, 0.1} mm x friction {off, on} x
F0 {10, 20} N x 11 ratios = 88 runs of ``--duration-s`` each) with each
executor into a fresh file and prints the wall time, runs per second and the
ratio against serial.  The wall time is the whole ``run_study`` call: planning,
starting the workers (the Dask cluster included), the runs, and assembling and
writing the result; a last row runs the study again on a Dask cluster that is
already up and has loaded the kernel (``--scheduler ADDRESS``), the steady
state of a long study.  The results are checked to be identical.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from boringbar.studies.load import study_from_dict
from boringbar.studies.runner import RunReport, run_study


def study(duration: float):
    return study_from_dict({
        "study": {"analysis": "sweep", "name": "bench_executors"},
        "run": {"duration_s": duration},
        "grid": {"gap_mm": [0.5, 0.1], "friction": ["off", "on"], "force_n": [10.0, 20.0],
                 "ratio": {"start": 0.95, "stop": 1.05, "step": 0.01}},
    })


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--duration-s", type=float, default=1.0)
    args = ap.parse_args()
    s = study(args.duration_s)
    # compile (or load the cache) once so no executor pays for it in the timing
    run_study(s, Path(tempfile.mkdtemp()) / "warm.nc", executor="serial")
    rows, results = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, kw in (("serial", {"executor": "serial"}),
                         ("processes", {"executor": "processes", "workers": args.workers}),
                         ("dask LocalCluster", {"dask_local": args.workers})):
            report = RunReport()
            tic = time.perf_counter()
            ds = run_study(s, Path(tmp) / f"{name.split()[0]}.nc", report=report, **kw)
            wall = time.perf_counter() - tic
            rows.append((name, report.workers, wall, report.points / wall))
            results[name] = ds
        # the steady state of a cluster that is already up and has loaded the kernel
        from distributed import LocalCluster

        with LocalCluster(n_workers=args.workers, threads_per_worker=1,
                          dashboard_address=None) as cluster:
            run_study(s, Path(tmp) / "dask_warm.nc", scheduler=cluster.scheduler_address)
            report = RunReport()
            tic = time.perf_counter()
            ds = run_study(s, Path(tmp) / "dask_up.nc", scheduler=cluster.scheduler_address,
                           report=report)
            wall = time.perf_counter() - tic
            rows.append(("dask, cluster up", report.workers, wall, report.points / wall))
            results["dask, cluster up"] = ds
    base = rows[0][3]
    print(f"study: {len(results['serial'].case)} cases x 2 forces x 11 ratios = "
          f"{int(results['serial'].rms_tip_m.size)} runs of {args.duration_s:g} s, dt = 1e-6 s")
    print(f"{'executor':<20}{'workers':>8}{'wall s':>10}{'runs/s':>10}{'vs serial':>11}")
    for name, w, wall, rate in rows:
        print(f"{name:<20}{w:>8}{wall:>10.2f}{rate:>10.2f}{rate / base:>10.2f}x")
    ref = results["serial"]
    same = all(np.array_equal(ref[k].values, r[k].values)
               for r in results.values() for k in ref.data_vars)
    print(f"identical results across executors: {same}")


if __name__ == "__main__":
    main()
