"""The chatter map's cost: the carbide example's ball bar, 30 speeds x 20 depths.

    .venv/bin/python benchmarks/bench_chatter_map.py [--workers N] [--speeds N]
        [--depths N] [--dt-s S] [--stick-law hold|sgn] [--baseline] [--knock-um UM ...]
        [--save FILE.nc]

Runs ``bb.chatter_map`` on the ball bar of examples/systems/carbide_ld10_tungsten.toml at
its default grid (the boring speeds of the bar, 20 depths from 0.5 to 3 times its
bare-bar limit) and default verdict (a small and a 20 um knock), on ``--workers``
threads (default 2), and prints where the time goes, from the Dataset's own record of
the simulated time of every start of every cell:

- the wall time, the process's CPU time, the simulated time and the throughput (simulated
  s per wall s and per CPU s, ns per RK4 step of CPU), and the machine's load (other
  processes share the cores: the CPU time divided by the workers is what an idle
  machine would take);
- the simulated time by what decided each cell (onset stable, chatter, undecided; the
  settled status of each start), the cells that ran to the cap, the onset's minimum run
  (three segments of ``min_segment`` windows of whole revolutions) at each speed;
- the ten costliest cells;
- what the order of the cells does: a list schedule of the cells' simulated times on
  1 to 64 workers, in grid order and longest first (an oracle), against the ideal.

``--dt-s`` another RK4 step (default: the verdict's, ``verdict.judged_step``);
``--stick-law`` the friction's law (default: the verdict's, hold); ``--baseline`` runs the
map again in the same process by the verdict's former method (the published sgn() law at
1e-6 s) and prints the ratios; ``--knock-um`` other large knocks (none: ``--knock-um 0``).
Numbers only, nothing is asserted.
"""

from __future__ import annotations

import argparse
import heapq
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import boringbar as bb
from boringbar.analysis import chatter_map as cm
from boringbar.analysis.verdict import WINDOW_PERIODS, VerdictOptions
from boringbar.execute import Execution

CARBIDE = Path(__file__).resolve().parents[1] / "examples" / "systems" / \
    "carbide_ld10_tungsten.toml"


def schedule(costs, workers: int) -> float:
    """The time a pool of ``workers`` takes to run tasks of ``costs`` in this order, each
    to the first free worker (what a thread pool does)."""
    free = [0.0] * workers
    for c in costs:
        heapq.heappush(free, heapq.heappop(free) + c)
    return max(free)


def order_effect(ds) -> None:
    """Makespan / ideal of the cells in grid order and longest first."""
    cost = cell_seconds(ds).ravel()  # grid order: case, rpm, depth
    print("list schedule of the cells' simulated times, makespan / ideal (grid order, "
          "longest first):")
    for w in (1, 2, 8, 32, 64):
        ideal = cost.sum() / w
        print(f"  {w:3d} workers: {schedule(cost, w) / ideal:.3f}, "
              f"{schedule(np.sort(cost)[::-1], w) / ideal:.3f}")


def cell_seconds(ds) -> np.ndarray:
    """Simulated time of every cell (case, rpm, depth): its starts' together."""
    return ds["run_duration_s"].sum("start").values


def by_category(ds) -> None:
    """Simulated time by the onset's verdict and by each start's settled status."""
    cost = cell_seconds(ds)
    total = cost.sum()
    names = {1: "stable", 0: "chatter", 2: "undecided"}
    print("by onset (small knock): cells, share of simulated time, mean s a cell")
    for code, name in names.items():
        sel = ds["onset"].values == code
        if sel.any():
            print(f"  {name:10s} {sel.sum():4d}  {cost[sel].sum() / total:6.1%}  "
                  f"{cost[sel].mean():.2f} s")
    print("by start and settled status: cells, simulated s, mean s")
    for s, start in enumerate(ds["start"].values):
        t = ds["run_duration_s"].values[..., s]
        st = ds["settled_status"].values[..., s]
        for status in np.unique(st):
            sel = st == status
            print(f"  {start:12s} {status:13s} {sel.sum():4d}  {t[sel].sum():7.1f} s  "
                  f"{t[sel].mean():.2f} s")
    capped = ds["run_duration_s"].values >= ds.attrs["max_duration_s"] - 1e-9
    print(f"starts that ran to the {ds.attrs['max_duration_s']:g} s cap: {capped.sum()}, "
          f"{ds['run_duration_s'].values[capped].sum():.1f} s simulated")


def onset_floor(ds, ball) -> None:
    """The shortest onset verdict at each speed: three segments of min_segment windows,
    each window whole revolutions of at least WINDOW_PERIODS periods of f1."""
    f1 = ball.reference_frequency_rad_s / (2 * math.pi)
    rpm = ds["rpm"].values
    revs = np.maximum(1, np.ceil(WINDOW_PERIODS * rpm / (60 * f1) - 1e-9))
    floor = 3 * ds.attrs["min_segment"] * revs * 60 / rpm
    onset = ds["onset_duration_s"].values[0]
    print(f"onset's shortest run (3 x {ds.attrs['min_segment']} windows of whole revolutions, "
          f">= {WINDOW_PERIODS:g} periods of f1 = {f1:.0f} Hz): {floor.min():.2f} s at "
          f"{rpm.max():g} rpm to {floor.max():.2f} s at {rpm.min():g} rpm; the onsets ran "
          f"{onset.mean():.2f} s on average, {onset.mean() / floor.mean():.1f} x that")


def costliest(ds, n: int = 10) -> None:
    cost = cell_seconds(ds)[0]
    print(f"the {n} costliest cells (simulated s): rpm, depth / bare-bar limit, onset, "
          "statuses")
    lim = ds["host_analytic_limit_m"].values[0]
    for flat in np.argsort(cost, axis=None)[::-1][:n]:
        j, k = np.unravel_index(flat, cost.shape)
        ratio = ds["depth_m"].values[k] / lim[j]
        statuses = ", ".join(ds["settled_status"].values[0, j, k])
        print(f"  {cost[j, k]:6.2f} s  {ds['rpm'].values[j]:6g} rpm  {ratio:5.2f}  "
              f"onset {int(ds['onset'].values[0, j, k])}  {statuses}")


def run_map(ball, options, dt, law, workers):
    """The map at step ``dt`` (None: the verdict's) with friction by ``law``: (Dataset,
    wall s, CPU s)."""
    options = replace(options, verdict=replace(options.verdict, stick_law=law))
    cpu, tic = time.process_time(), time.perf_counter()
    ds = bb.chatter_map(ball, options, integration=bb.Integration(dt_s=dt),
                        execution=Execution("threads", workers))
    return ds, time.perf_counter() - tic, time.process_time() - cpu


def report(ds, wall, cpu, workers) -> None:
    sim = cell_seconds(ds).sum()
    dt = ds.attrs["dt_s"]
    print(f"wall {wall:.1f} s for {ds.attrs['cells']} cells ({wall / ds.attrs['cells']:.3f} s "
          f"a cell); CPU {cpu:.1f} s ({cpu / workers:.1f} s a worker); simulated "
          f"{sim:.0f} s ({sim / ds.attrs['cells']:.2f} s a cell): {sim / wall:.2f} simulated "
          f"s per wall s, {sim / cpu:.2f} per CPU s, {cpu / (sim / dt) * 1e9:.0f} ns "
          f"of CPU a step; load now {os.getloadavg()[0]:.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--speeds", type=int, default=cm.MAP_SPEEDS)
    ap.add_argument("--depths", type=int, default=cm.DEPTHS)
    ap.add_argument("--dt-s", type=float, default=None)
    ap.add_argument("--stick-law", default="hold", choices=("hold", "sgn"))
    ap.add_argument("--baseline", action="store_true")
    ap.add_argument("--knock-um", type=float, nargs="*", default=[cm.LARGE_KNOCK_M * 1e6])
    ap.add_argument("--save", metavar="FILE.nc", help="write the map's Dataset here")
    args = ap.parse_args()
    ball = bb.variants(bb.load_system(CARBIDE))["ball"]
    case = [bb.Case.of(ball)]
    rpm = cm.map_speeds(case, n=args.speeds)
    depths = cm.map_depths(cm.host_limits(case, rpm, bb.LobesOptions().analytic_kr_pa),
                           n=args.depths)
    knocks = tuple(k * 1e-6 for k in args.knock_um if k > 0)
    options = cm.ChatterMapOptions(rpm=rpm, depths_m=depths,
                                   verdict=VerdictOptions(knocks_m=knocks))
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; {ball.kind} bar "
          f"of {CARBIDE.name}; {len(rpm)} speeds {rpm[0]:g}..{rpm[-1]:g} rpm x {len(depths)} "
          f"depths {depths[0] * 1e3:.4g}..{depths[-1] * 1e3:.4g} mm; knocks "
          f"{args.knock_um} um; dt = {args.dt_s or 'the verdict step'} s, the {args.stick_law} "
          f"law; {args.workers} threads", flush=True)
    ds, wall, cpu = run_map(ball, options, args.dt_s, args.stick_law, args.workers)
    report(ds, wall, cpu, args.workers)
    by_category(ds)
    onset_floor(ds, ball)
    costliest(ds)
    order_effect(ds)
    free = ds["chatter_free"].values[0]
    print(f"chatter-free cells {int((free == 1).sum())}, not {int((free == 0).sum())}, "
          f"undecided {int((free == 2).sum())}; min chatter-free depth "
          f"{float(ds['min_chatter_free_depth_m'].values[0]) * 1e3:.4g} mm")
    if args.baseline:
        print("baseline: the published sgn() law at 1e-6 s (the verdict's former method)",
              flush=True)
        base, bwall, bcpu = run_map(ball, options, 1e-6, "sgn", args.workers)
        report(base, bwall, bcpu, args.workers)
        same = int((base["chatter_free"].values == ds["chatter_free"].values).sum())
        print(f"baseline / this: wall {bwall / wall:.2f}x, CPU {bcpu / cpu:.2f}x; "
              f"chatter-free verdicts equal in {same} of {ds.attrs['cells']} cells")
    if args.save:
        ds.to_netcdf(args.save)
        print(f"wrote {args.save}")


if __name__ == "__main__":
    sys.exit(main())
