"""RK4 against the exact integrator over the held-out grid of 80 published harmonic cases.

    .venv/bin/python benchmarks/bench_grid.py [--repeat 1] [--duration 2.0] [--no-history]

The grid: presets paper and physical x gaps 0.1 and 0.5 mm x friction off and on x
forces 10 and 20 N x Omega/omega_n 0.95, 0.98, 1.00, 1.02, 1.05; the ball damper, each
preset's default modes (paper 1, physical 2), from rest, 2 s runs, RK4 at dt = 1e-6 and
the exact integrator (dt = 1e-6 only rounds its steady window).  Both kernels are
compiled (or loaded from the cache) before timing; then, case by case, RK4 and exact run
alternately (their order swapped every case, so that a burst of load on a shared
machine slows both sides), best of ``--repeat`` each, the kernel's wall time
(``Run.elapsed_s``; the exact integrator's includes its per-run preparation).

Each call keeps its default history (about 20000 rows); ``--no-history`` gives both
``record_every = 0``, what the analyses (sweeps, lobes, designs) ask for.

Prints each case's times and ratio RK4/exact, then the total ratio (sum of RK4 times
over sum of exact times), the median and the worst (smallest) per-case ratio.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time

from boringbar import Harmonic, make_system, simulate

PRESETS = ("paper", "physical")
GAPS = (0.1e-3, 0.5e-3)
FRICTION = (False, True)
FORCES = (10.0, 20.0)
RATIOS = (0.95, 0.98, 1.00, 1.02, 1.05)


def cases():
    """(label, system, forcing) of the 80 cases, in grid order."""
    out = []
    for preset in PRESETS:
        for gap in GAPS:
            for friction in FRICTION:
                s = make_system("ball", preset, gap_m=gap, friction=friction)
                for force in FORCES:
                    for ratio in RATIOS:
                        label = (f"{preset:8s} gap {gap * 1e3:.1f} mm friction "
                                 f"{'on ' if friction else 'off'} {force:4.0f} N r {ratio:.2f}")
                        out.append((label, s, Harmonic(force, ratio)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--duration", type=float, default=2.0)
    ap.add_argument("--no-history", action="store_true", help="record_every = 0 for both")
    args = ap.parse_args()
    kw = {"record_every": 0} if args.no_history else {}
    grid = cases()
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; {len(grid)} cases, "
          f"{args.duration:g} s runs, dt = 1e-6, best of {args.repeat}, "
          f"{'no history' if args.no_history else 'default history'}")
    tic = time.perf_counter()
    for _, s, f in {(c[1].preset, c[1].bar.n_modes): c for c in grid}.values():
        for integrator in ("rk4", "exact"):  # compile or load from the cache
            simulate(s, f, duration_s=1e-3, dt_s=1e-6, integrator=integrator)
    print(f"warm-up (compile or cache load): {time.perf_counter() - tic:.1f} s")
    rows = []
    print(f"{'case':48s} {'rk4 s':>8s} {'exact s':>8s} {'ratio':>6s}  patterns rk4 / exact")
    for i, (label, s, f) in enumerate(grid):
        best = {"rk4": math.inf, "exact": math.inf}
        runs = {}
        order = ("rk4", "exact") if i % 2 == 0 else ("exact", "rk4")
        for _ in range(args.repeat):
            for integrator in order:
                run = simulate(s, f, duration_s=args.duration, dt_s=1e-6, integrator=integrator,
                               **kw)
                runs[integrator] = run
                best[integrator] = min(best[integrator], run.elapsed_s)
        ratio = best["rk4"] / best["exact"]
        rows.append((label, best["rk4"], best["exact"], ratio))
        pat = " / ".join(runs[k].pattern.name if runs[k].pattern else "-" for k in ("rk4", "exact"))
        print(f"{label:48s} {best['rk4']:8.4f} {best['exact']:8.4f} {ratio:6.1f}  {pat}",
              flush=True)
    t_rk4 = sum(r[1] for r in rows)
    t_ex = sum(r[2] for r in rows)
    ratios = [r[3] for r in rows]
    worst = min(rows, key=lambda r: r[3])
    print(f"\ntotal: rk4 {t_rk4:.2f} s, exact {t_ex:.2f} s, ratio rk4/exact {t_rk4 / t_ex:.2f}")
    print(f"per case: median ratio {statistics.median(ratios):.2f}, worst {worst[3]:.2f} "
          f"({worst[0].strip()}), best {max(ratios):.2f}")
    print(f"load at the end {os.getloadavg()[0]:.2f}; wall {time.perf_counter() - tic:.0f} s")


if __name__ == "__main__":
    main()
