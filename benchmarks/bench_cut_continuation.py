"""Chatter orbit speed: a branch of cut orbits in depth, and a three-bar map, each
against simulating the same depths' cuts until they settle.

Branch: the carbide example's solid bar at 1200 rpm (examples/systems/
carbide_ld10_tungsten.toml, linear law, N = 3 revolutions), 200 points from its Hopf
point through `bb.cut_continuation` (each with its Floquet multipliers and events).
Baseline, in the same process: the compiled RK4 cut (`bb.simulate`, dt 2e-6 s)
knocked to the branch's amplitude at 5 of its depths beyond the tool's leaving the
cut, run 2 s each (the slowest orbit there settles over about 8 s, so 2 s is a lower
bound on what a simulated amplitude map pays); the ratio is per depth.

The map: `boringbar continue --cut --rpm 1200 --parameter depth-mm --range 0:1` on the
published bar's solid, TMD and ball bars (the ball: gap 0.5 mm, friction on), its wall
time and each bar's points and stop.

In speed: the carbide solid bar's branch at 0.04 mm over 1000-1400 rpm from the Hopf
point nearest 1150 rpm (`--parameter rpm`), which joins the lobe's two flanks.

    .venv/bin/python benchmarks/bench_cut_continuation.py [--points 200] [--no-map]
        [--no-speed]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import boringbar as bb
from boringbar.analysis.cut_continuation import cut_summary


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=200)
    ap.add_argument("--no-map", action="store_true")
    ap.add_argument("--no-speed", action="store_true")
    args = ap.parse_args()
    branch(args.points)
    if not args.no_map:
        three_bars()
    if not args.no_speed:
        in_speed(args.points)


def in_speed(points: int) -> None:
    solid = bb.variants(bb.load_system("examples/systems/carbide_ld10_tungsten.toml"))["solid"]
    options = bb.CutContinuationOptions(parameter="rpm", speed_range_rpm=(1000.0, 1400.0),
                                        max_points=points)
    tic = time.perf_counter()
    ds = bb.cut_continuation({"solid": solid}, bb.Regenerative(depth_m=0.04e-3, rpm=1150.0),
                             options)
    wall = time.perf_counter() - tic
    s = cut_summary(ds)["cases"][0]
    print(f"in speed (carbide solid, 0.04 mm): {s['points']} points in {wall:.1f} s "
          f"({wall / s['points'] * 1e3:.0f} ms a point); stop: {s['stop']}")


def branch(points: int) -> None:
    solid = bb.variants(bb.load_system("examples/systems/carbide_ld10_tungsten.toml"))["solid"]
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0)
    options = bb.CutContinuationOptions(depth_range_m=(0.0, 1e-3), max_points=points)
    tic = time.perf_counter()
    ds = bb.cut_continuation({"solid": solid}, forcing, options)
    t_branch = time.perf_counter() - tic
    s = cut_summary(ds)["cases"][0]
    print(f"branch: {s['points']} points in {t_branch:.1f} s "
          f"({t_branch / s['points'] * 1e3:.0f} ms a point); stop: {s['stop']}")
    print("  events: " + "; ".join(f"{e['kind']} {e['detail']} at {e['depth_mm']:.5f} mm"
                                   for e in s["events"]))
    depth = np.array(s["depth_mm"]) * 1e-3
    amp = np.array(s["amplitude_mm"]) * 1e-3
    picks = np.linspace(len(depth) // 2, len(depth) - 1, 5).astype(int)
    tic = time.perf_counter()
    for i in picks:
        cut = bb.Regenerative(depth_m=float(depth[i]), rpm=1200.0, start="static")
        bb.simulate(solid, cut, duration_s=2.0, dt_s=2e-6,
                    initial=bb.Initial(tip_displacement_m=float(amp[i])), record_every=0)
    t_sim = (time.perf_counter() - tic) / len(picks)
    per_point = t_branch / s["points"]
    print(f"baseline: a simulated 2 s cut takes {t_sim:.2f} s a depth; the branch "
          f"{per_point:.2f} s a point with its stability: {t_sim / per_point:.1f}x")


def three_bars() -> None:
    systems = {k: bb.make_system(k, "physical", **({"gap_m": 0.5e-3} if k == "ball" else {}))
               for k in ("solid", "tmd", "ball")}
    forcing = bb.Regenerative(depth_m=1e-5, rpm=1200.0)
    tic = time.perf_counter()
    ds = bb.cut_continuation(systems, forcing,
                             bb.CutContinuationOptions(depth_range_m=(0.0, 1e-3)))
    wall = time.perf_counter() - tic
    print(f"map (published solid, TMD, ball at 1200 rpm): {wall:.1f} s")
    for c in cut_summary(ds)["cases"]:
        print(f"  {c['case']}: {c['points']} points; {c['stop']}")


if __name__ == "__main__":
    main()
