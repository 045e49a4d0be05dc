"""The order of the exact integrator in a regenerative cut, measured (issue #6).

    .venv/bin/python benchmarks/exact_cut_convergence.py [--out docs/img/exact_cut_convergence.png]

In a cut the exact integrator propagates the linear system exactly for a
delayed surface that is one cubic per history step H (the cubic Hermite of the
stored W, W'), so its only error is the interpolation's, O(H^4).  Two cuts of
the solid bar (physical preset) at 1210 rpm (tau / H not a whole number for
RK4's dt), from rest:

- stable, 0.5 x the analytic limit, 0.3 s;
- chattering, 2 x the analytic limit, up to 0.9 s (the force first reaches zero
  at 0.961 s; the growth amplifies every error).

For H (exact) and dt (RK4, cubic history) = 16 ... 0.5 us it prints and plots the
largest error of W sampled every 80 us, relative to max |W|, against RK4 at
dt = 0.125 us (independent of the exact integrator), and the observed orders
between successive steps.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from boringbar import make_system, simulate
from boringbar.model.forcing import Regenerative
from boringbar.reference.stability import limit_at_speeds

STEPS = [16e-6, 8e-6, 4e-6, 2e-6, 1e-6, 5e-7]
REF_DT = 1.25e-7
SAMPLE = 8e-5
RPM = 1210.0
CASES = [("stable, 0.5 x limit, 0.3 s", 0.5, 0.3), ("chattering, 2 x limit, 0.9 s", 2.0, 0.9)]


def history(system, depth, duration, integrator, dt):
    f = Regenerative(depth_m=depth, rpm=RPM)
    tic = time.perf_counter()
    run = simulate(system, f, duration_s=duration, dt_s=dt, integrator=integrator,
                   record_every=round(SAMPLE / dt))
    return run.history[:, 1], time.perf_counter() - tic


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img/exact_cut_convergence.png")
    args = ap.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    system = make_system("solid")
    b_lim = float(limit_at_speeds(system, [RPM])[0])
    history(system, b_lim, 1e-3, "exact", 1e-6)  # JIT warm-up / cache load
    history(system, b_lim, 1e-3, "rk4", 1e-6)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    steps = np.array(STEPS)
    for ax, (label, factor, duration) in zip(axes, CASES, strict=True):
        ref, _ = history(system, factor * b_lim, duration, "rk4", REF_DT)
        scale = np.max(np.abs(ref))
        print(f"{label} (reference: rk4 dt = {REF_DT:g} s)")
        for integ, marker in (("exact", "o-"), ("rk4", "s-")):
            errs = []
            for dt in STEPS:
                w, el = history(system, factor * b_lim, duration, integ, dt)
                errs.append(float(np.max(np.abs(w - ref)) / scale))
                print(f"  {integ:5s} step {dt:.2e} s: error {errs[-1]:.3e}  ({el:.2f} s)")
            orders = [math.log2(a / b) for a, b in zip(errs, errs[1:], strict=False)]
            print(f"  {integ:5s} observed orders: {' '.join(f'{q:.2f}' for q in orders)}")
            ax.loglog(steps, errs, marker, label=f"{integ} (H)" if integ == "exact"
                      else "rk4 (dt)")
        first = ax.get_lines()[0].get_ydata()[0]
        ax.loglog(steps, first * (steps / steps[0]) ** 4, "k--", lw=0.8, label="slope 4")
        ax.set_title(label, fontsize=10)
        ax.set_xlabel("history step H (exact) or time step dt (RK4) (s)")
        ax.set_ylabel("max |W - W_ref| / max |W_ref|")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"Regenerative cut, solid bar, {RPM:g} rpm: exact integrator vs RK4, "
                 f"reference RK4 at dt = {REF_DT:g} s")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
