"""Design search at scale: the issue's target study, measured on a slice and extrapolated.

    .venv/bin/python benchmarks/bench_design.py [--candidates 8] [--samples 32] [--dask 1,2]

The target is 200 candidates x 32 Monte Carlo samples x an 11-ratio band: about
70,000 runs of 2 s with the exact integrator, within 10 minutes on the 2-core
machine. This script runs ``--candidates`` of those candidates in full (every
sample and ratio, F0 = 20 N, the published ball damper, friction and
restitution uncertain) on threads, and then on a Dask LocalCluster of each size in
``--dask``, already up with its kernels loaded (the state of a long study; the
cluster's start is a one-off of seconds). It prints the runs per second and the
whole study's projected time, with each figure's ratio against the threads
baseline run in the same process.
Optuna's own work per trial is measured as well, with a closed-form objective,
and is added to the projection; it is milliseconds against seconds of runs.
"""

from __future__ import annotations

import argparse
import os
import time

from distributed import LocalCluster

from boringbar.analysis.design import design
from boringbar.analysis.design_options import DesignOptions, Uncertain, Variable
from boringbar.execute import Execution
from boringbar.model.system import published_system_spec
from boringbar.model.system_file import parse_system

TARGET_CANDIDATES, TARGET_SAMPLES, TARGET_RATIOS = 200, 32, 11


def options(candidates: int, samples: int) -> DesignOptions:
    ratios = tuple(round(0.95 + 0.01 * i, 2) for i in range(TARGET_RATIOS))
    return DesignOptions("ball", (Variable("gap_m", 0.05e-3, 1e-3),
                                  Variable("restitution", 0.5, 0.9)),
                         ratios=ratios, forces_n=(20.0,), duration_s=2.0, integrator="exact",
                         samples=samples, trials=candidates, seed=1,
                         uncertain=(Uncertain("friction_force_n", "uniform", 0.0, 0.5),
                                    Uncertain("ball_position_m", "uniform", -0.05e-3, 0.05e-3)))


def timed(opts, execution) -> tuple[float, object]:
    t0 = time.perf_counter()
    ds = design(opts, spec=published_system_spec(), execution=execution)
    return time.perf_counter() - t0, ds


def optuna_overhead(trials: int = 200) -> float:
    """Seconds of Optuna work per trial (a closed-form objective, no runs)."""
    spec = parse_system({"bar": {"material": "steel", "modes": 1,
                                 "sections": [{"end_mm": 200, "diameter_mm": 25}]},
                         "tmd": {"mass_kg": 0.01, "position_mm": 200}}, "one mode")
    o = DesignOptions("tmd", (Variable("tmd_frequency_ratio", 0.85, 1.15),),
                      objective="frf_peak", trials=trials)
    t0 = time.perf_counter()
    design(o, spec=spec)
    return (time.perf_counter() - t0) / trials


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=8)
    ap.add_argument("--samples", type=int, default=TARGET_SAMPLES)
    ap.add_argument("--dask", default="1,2", help="LocalCluster sizes (comma list; '' none)")
    args = ap.parse_args()
    opts = options(args.candidates, args.samples)
    runs = (args.candidates + 1) * args.samples * TARGET_RATIOS  # + the published design
    target_runs = TARGET_CANDIDATES * TARGET_SAMPLES * TARGET_RATIOS
    per_trial = optuna_overhead()
    print(f"cores: {os.cpu_count()}; slice: {args.candidates} candidates x {args.samples} "
          f"samples x {TARGET_RATIOS} ratios (+ the published design) = {runs} runs of 2 s, "
          f"exact integrator; target {target_runs} runs")
    print(f"Optuna per trial: {per_trial * 1e3:.1f} ms")
    timed(options(1, 1), Execution("threads"))  # compile and warm
    base, ref = timed(opts, Execution("threads"))
    rate = runs / base
    projected = target_runs / rate + TARGET_CANDIDATES * per_trial
    print(f"{'executor':<22}{'wall (s)':>10}{'runs/s':>10}{'ratio':>8}{'projected (min)':>18}")
    print(f"{'threads':<22}{base:>10.1f}{rate:>10.1f}{1.0:>8.2f}{projected / 60:>18.1f}")
    for n in [int(x) for x in args.dask.split(",") if x.strip()]:
        with LocalCluster(n_workers=n, threads_per_worker=1, processes=True) as cluster:
            execution = Execution("dask", scheduler=cluster.scheduler_address)
            timed(options(1, 2), execution)  # workers up, kernels loaded: a long study's state
            wall, ds = timed(opts, execution)
        same = bool((ds["statistic"].values == ref["statistic"].values).all())
        r = runs / wall
        proj = target_runs / r + TARGET_CANDIDATES * per_trial
        print(f"{f'dask LocalCluster {n}':<22}{wall:>10.1f}{r:>10.1f}{base / wall:>8.2f}"
              f"{proj / 60:>18.1f}   same results: {same}")


if __name__ == "__main__":
    main()
