"""Continuation speed: N points with Floquet multipliers against brute force.

Branch: the one-mode physical bar with a frictionless ball (gap 0.5 mm, ratio 1),
from the Masri-Caughey orbit at 30 N down in F0 (boringbar.branch).  Baseline,
in the same process: brute-force exact simulation of the same F0 values, each
from the previous final state, 100 forcing periods a value (what a bifurcation
sweep spends to settle; it gives neither unstable orbits nor multipliers).

    .venv/bin/python benchmarks/bench_continuation.py [--points 200]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from boringbar.analysis.continuation import ContinuationOptions, start_state
from boringbar.branch import continue_branch
from boringbar.model.forcing import Harmonic
from boringbar.model.system import make_system
from boringbar.shooting import make_flow
from boringbar.simulate import State, simulate


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=200)
    ap.add_argument("--settle-periods", type=int, default=100)
    args = ap.parse_args()
    system = make_system("ball", "physical", n_modes=1, friction=False, gap=0.5e-3)
    forcing = Harmonic(30.0, ratio=1.0)
    fl = make_flow(system, forcing)
    x0 = start_state(system, ContinuationOptions(start="masri-caughey"), fl)
    simulate(system, forcing, duration=1e-4, dt=1e-6, integrator="exact")  # compile
    tic = time.perf_counter()
    br = continue_branch(fl, "force-n", x0, 5.0, step=0.02, max_points=args.points)
    t_cont = time.perf_counter() - tic
    values = [p.value for p in br.points]
    dt = fl.period / np.ceil(fl.period / 1e-6)
    state = State(x0, 0.0)
    tic = time.perf_counter()
    for v in values:
        run = simulate(system, Harmonic(v, ratio=1.0), duration=args.settle_periods * fl.period,
                       dt=dt, integrator="exact", initial=state)
        state = State(run.final.x, 0.0)
    t_brute = time.perf_counter() - tic
    n = len(values)
    print(f"continuation: {n} points with multipliers in {t_cont:.2f} s "
          f"({1e3 * t_cont / n:.1f} ms a point); F0 {values[0]:.3g} -> {values[-1]:.4g} N; "
          f"stop: {br.stop}; events: {br.events}")
    print(f"brute force (exact, {args.settle_periods} periods a value, same values): "
          f"{t_brute:.2f} s ({1e3 * t_brute / n:.1f} ms a value)")
    print(f"ratio continuation / brute force: {t_cont / t_brute:.2f}")


if __name__ == "__main__":
    main()
