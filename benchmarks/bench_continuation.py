"""Continuation speed: N points with Floquet multipliers against brute force, and the
orbit map of the issue's case.

Branch: the one-mode physical bar with a frictionless ball (gap 0.5 mm, ratio 1),
from the Masri-Caughey orbit at 30 N down in F0 (boringbar.orbits.branch), its steps capped
at 0.005 of the range so that the N points do not reach its end.  Baseline, in the
same process: brute-force exact simulation of the same F0 values, each from the
previous final state, 100 forcing periods a value (what a bifurcation sweep spends
to settle; it gives neither unstable orbits nor multipliers).

The map: `boringbar continue --bar ball --preset paper --gap-mm 0.1 --friction off
--ratio 1.0 --parameter force-n --range 5:35` through `bb.continuation` (switching on,
3 seeds): its wall time, branches, the range their stable stretches cover and the
attractor check.

    .venv/bin/python benchmarks/bench_continuation.py [--points 200] [--no-map]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import boringbar as bb
from boringbar.analysis.continuation import ContinuationOptions, start_state, summary
from boringbar.model.forcing import Harmonic
from boringbar.model.system import make_system
from boringbar.orbits.continuation import continue_branch
from boringbar.orbits.shooting import make_flow
from boringbar.simulate import State, simulate


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=200)
    ap.add_argument("--settle-periods", type=int, default=100)
    ap.add_argument("--no-map", action="store_true")
    args = ap.parse_args()
    points(args)
    if not args.no_map:
        issue_map()


def points(args) -> None:
    system = make_system("ball", "physical", n_modes=1, friction=False, gap_m=0.5e-3)
    forcing = Harmonic(30.0, ratio=1.0)
    fl = make_flow(system, forcing)
    x0 = start_state(system, ContinuationOptions(start="masri-caughey"), fl)
    simulate(system, forcing, duration_s=1e-4, dt_s=1e-6, integrator="exact")  # compile
    tic = time.perf_counter()
    br = continue_branch(fl, "force-n", x0, 5.0, step=0.005, max_step=0.005,
                         max_points=args.points)
    t_cont = time.perf_counter() - tic
    values = [p.value for p in br.points]
    dt = fl.period / np.ceil(fl.period / 1e-6)
    state = State(x0, 0.0)
    tic = time.perf_counter()
    for v in values:
        run = simulate(system, Harmonic(v, ratio=1.0), duration_s=args.settle_periods * fl.period,
                       dt_s=dt, integrator="exact", initial=state)
        state = State(run.final.x, 0.0)
    t_brute = time.perf_counter() - tic
    n = len(values)
    print(f"continuation: {n} points with multipliers in {t_cont:.2f} s "
          f"({1e3 * t_cont / n:.1f} ms a point); F0 {values[0]:.3g} -> {values[-1]:.4g} N; "
          f"stop: {br.stop}; events: {br.events}")
    print(f"brute force (exact, {args.settle_periods} periods a value, same values): "
          f"{t_brute:.2f} s ({1e3 * t_brute / n:.1f} ms a value)")
    print(f"ratio continuation / brute force: {t_cont / t_brute:.2f}")


def issue_map() -> None:
    """The orbit map of the issue's case, timed."""
    system = make_system("ball", "paper", gap_m=0.1e-3, friction=False)
    tic = time.perf_counter()
    ds = bb.continuation(system, Harmonic(5.0, ratio=1.0),
                         options=ContinuationOptions(parameter="force-n", stop=35.0))
    wall = time.perf_counter() - tic
    s = summary(ds)
    stable = sorted(p["value"] for b in s["branches"] for p in b["points"] if p["stable"])
    covered = [p["value"] for b in s["branches"] for p in b["points"]]
    print(f"orbit map (paper, gap 0.1 mm, frictionless, 5-35 N): {wall:.1f} s, "
          f"{len(s['branches'])} branches, "
          f"{sum(any(p['stable'] for p in b['points']) for b in s['branches'])} with a "
          f"stable stretch; points cover {min(covered):.4g}-{max(covered):.4g} N; stable "
          f"points at {stable[0]:.4g}-{stable[-1]:.4g} N")
    for i, b in enumerate(s["branches"]):
        vals = [p["value"] for p in b["points"]]
        print(f"  {i}: period {b['periods']}, born {b['born']['kind']} "
              f"{b['born']['value']:.5g} (parent {b['parent']}), {min(vals):.4g}-"
              f"{max(vals):.4g} N, {sum(p['stable'] for p in b['points'])}/{len(vals)} "
              f"stable; events {[(e['kind'], round(e['value'], 4)) for e in b['events']]}")
    print("  attractor check:", json.dumps(s["attractor_check"]))
    print("  notes:", json.dumps(s["notes"]))


if __name__ == "__main__":
    main()
