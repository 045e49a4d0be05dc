"""Stability-lobe cost: the published time-domain lobes, scan against search.

    .venv/bin/python benchmarks/bench_lobes.py [--skip-ball] [--speeds N]

Prints the wall time (and number of 2 s runs) of

- the published solid-bar scan (rpm 900..1600 step 50, depth step 0.01 mm,
  until 3 successive depths chatter), physical and paper presets;
- the same with ``method="search"``;
- the TMD bar with search, paper and physical;
- the ball damper, gap 0.5 / 0.1 mm x friction off / on, paper preset, search;

and the delay buffer's cost: ns per RK4 step of a stable regenerative cut
against a harmonic run of the same bar in the same process.  Numbers only,
nothing is asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import time

from boringbar import Harmonic, make_system, simulate
from boringbar.analysis.cases import Case, published_cases
from boringbar.analysis.lobes import (
    PUBLISHED_DEPTH_STEP,
    PUBLISHED_RPM,
    LobesOptions,
    compare_methods,
    lobes,
)
from boringbar.model.forcing import Regenerative
from boringbar.reference.stability import limit_at_speeds


def timed_lobes(cases, rpm, method):
    tic = time.perf_counter()
    # the published 0.01 mm grid for both methods, so the two compare
    ds = lobes(cases, LobesOptions(rpm, method=method, depth_step_m=PUBLISHED_DEPTH_STEP))
    return ds, time.perf_counter() - tic


def report(label, ds, wall):
    mins = ", ".join(f"{c}: {v * 1e3:.2f} mm" for c, v in
                     zip(ds["case"].values, ds["min_chatter_free_depth_m"].values, strict=True))
    print(f"{label}: {wall:.1f} s wall, {ds.attrs['runs']} runs "
          f"({wall / max(ds.attrs['runs'], 1):.3f} s per run) on {ds.attrs['workers']} "
          f"workers; min chatter-free depth {mins}")


def step_cost(bar: str = "solid", preset: str = "physical", repeats: int = 3):
    """ns/step of a stable 2 s cut and of a 2 s harmonic run, best of ``repeats``."""
    system = make_system(bar, preset)
    b = 0.5 * float(limit_at_speeds(system, [1200.0])[0])
    cut = Regenerative(depth_m=b, rpm=1200.0)
    harmonic = Harmonic(10.0, 1.0)
    for forcing in (cut, harmonic):  # JIT warm-up / cache load
        simulate(system, forcing, duration_s=1e-3)
    best = {}
    for name, forcing in (("cut", cut), ("harmonic", harmonic)):
        best[name] = math.inf
        for _ in range(repeats):
            run = simulate(system, forcing, duration_s=2.0)
            assert not (name == "cut" and run.cutting["chatter"])
            best[name] = min(best[name], run.elapsed_s / round(run.duration_s / run.dt_s) * 1e9)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-ball", action="store_true", help="skip the ball-damper lobes")
    ap.add_argument("--speeds", type=int, default=len(PUBLISHED_RPM),
                    help="use the first N published speeds (default all 15)")
    args = ap.parse_args()
    rpm = PUBLISHED_RPM[:args.speeds]
    print(f"machine: {os.cpu_count()} cores; {len(rpm)} speeds {rpm[0]:g}..{rpm[-1]:g} rpm, "
          "2 s runs at dt = 1e-6 s, runs stop at the first zero of the force")

    for bar in ("solid", "ball"):
        nm = step_cost(bar)
        print(f"delay buffer ({bar} bar, physical, {make_system(bar).bar.n_modes} modes): "
              f"stable cut {nm['cut']:.1f} ns/step, harmonic {nm['harmonic']:.1f} ns/step, "
              f"cost of the cut {nm['cut'] - nm['harmonic']:+.1f} ns/step "
              f"({nm['cut'] / nm['harmonic']:.2f}x)")

    for preset in ("physical", "paper"):
        cases = [Case("solid", make_system("solid", preset), "solid")]
        scan, w_scan = timed_lobes(cases, rpm, "scan")
        report(f"solid {preset}, scan (published)", scan, w_scan)
        search, w_search = timed_lobes(cases, rpm, "search")
        report(f"solid {preset}, search", search, w_search)
        print(f"  search / scan wall time {w_search / w_scan:.2f}; "
              f"methods differ at {len(compare_methods(scan, search))} speeds")

    for preset in ("paper", "physical"):
        cases = [Case("tmd", make_system("tmd", preset), "tmd")]
        ds, wall = timed_lobes(cases, rpm, "search")
        report(f"TMD {preset}, search", ds, wall)

    if not args.skip_ball:
        cases = published_cases(bars=("ball",), preset="paper")
        ds, wall = timed_lobes(cases, rpm, "search")
        report("ball damper paper, 4 cases, search", ds, wall)


if __name__ == "__main__":
    main()
