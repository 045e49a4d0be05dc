"""The physical preset's published sweep under the default integrator ("auto": exact)
against the published RK4 scheme in lock-step batches, in one process.

    .venv/bin/python benchmarks/bench_default.py [--repeat 3] [--duration 2.0]

The sweep: the six published cases (solid, TMD, ball at gaps 0.5 and 0.1 mm, friction
off and on) x F0 10 and 20 N x Omega/omega_n 0.95-1.05 by 0.01, physical preset, from
rest, dt = 1e-6, on one worker (so the figure is CPU per sweep, not the machine's
core count).  RK4 ("rk4", batched as every RK4 sweep is) and the default ("auto",
which is the exact integrator here) run alternately, best of ``--repeat`` each.

Prints both times and their ratio, then what the switch changes (docs/model.md,
section 5.3): per case the largest and the median relative change of the tip RMS,
and how many points changed their impact pattern.  The linear bars (solid, TMD) move
by RK4's own error only; the impacting cases by RK4's first-order impact times too,
which a non-uniform (chaotic) response amplifies.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from boringbar.analysis.cases import published_cases
from boringbar.analysis.sweep import PUBLISHED_RATIOS, SweepOptions, sweep
from boringbar.execute import Execution
from boringbar.simulate import Integration


def run(cases, options, integrator: str, duration: float):
    tic = time.perf_counter()
    ds = sweep(cases, options, execution=Execution("serial"),
               integration=Integration(duration_s=duration, integrator=integrator))
    return time.perf_counter() - tic, ds


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, default=2.0)
    args = ap.parse_args()
    cases = published_cases(preset="physical")
    options = SweepOptions(PUBLISHED_RATIOS, (10.0, 20.0))
    n = len(cases) * 2 * len(PUBLISHED_RATIOS)
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; {n} runs of "
          f"{args.duration:g} s, physical preset, one worker, best of {args.repeat}")
    short = SweepOptions((1.0,), (10.0,))
    for integrator in ("rk4", "auto"):  # compile, or load from the cache, first
        run(cases, short, integrator, 0.01)
    best = {"rk4": np.inf, "auto": np.inf}
    data = {}
    for i in range(args.repeat):
        for integrator in (("rk4", "auto") if i % 2 == 0 else ("auto", "rk4")):
            t, data[integrator] = run(cases, options, integrator, args.duration)
            best[integrator] = min(best[integrator], t)
    print(f"rk4 (batched) {best['rk4']:.2f} s, auto (exact) {best['auto']:.2f} s: "
          f"{best['rk4'] / best['auto']:.2f}x")
    rk, ex = data["rk4"], data["auto"]
    print(f"{'case':32s} {'max |d rms|/rms':>16s} {'median':>9s} {'patterns changed':>17s}")
    for i, label in enumerate(rk["case"].values):
        a, b = rk["rms_tip_m"].values[i], ex["rms_tip_m"].values[i]
        rel = np.abs(b / a - 1)
        changed = int(np.sum(rk["pattern"].values[i] != ex["pattern"].values[i]))
        print(f"{label:32s} {rel.max():16.2e} {np.median(rel):9.2e} "
              f"{changed:>10d} of {rel.size}")


if __name__ == "__main__":
    main()
