"""The lock-step kernel against the single-run kernel, and what it does for sweeps and basins.

    .venv/bin/python benchmarks/bench_batch.py [--steps 300000] [--skip-basin] [--skip-sweep]

1. ns per run-step of ``run_rk4`` (one run) and of ``run_rk4_batch``
   at B = 1, 2, 4, 8, 16 runs in lock-step, on realistic ball-damper runs
   (10 N at r = 1.01, gap 0.5 mm, friction on; the paper preset with 1 mode and
   the physical preset with 2), each run of a batch from a different initial
   tip state as in a basin grid; best of 3, warm JIT, ratios against the
   single-run kernel measured in the same process.
2. The published sweep (11 ratios x 6 cases, 10 N, 2 s each, paper and
   physical presets) and the published 30 x 30 basin (900 runs of 2 s, paper
   preset, gap 0.5 mm, no friction, 10 N, r = 1.01) on every core: one run at
   a time (``batch=1``, the code before the lock-step kernel) and in batches
   (the default), in the same process.  The results are identical (checked).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from dataclasses import replace

import numpy as np

from boringbar import Initial, make_system
from boringbar.analysis import basins as basins_mod
from boringbar.analysis import sweep as sweep_mod
from boringbar.simulate import Integration, initial_state, pack
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import Records, Steps, run_rk4, run_rk4_batch

FORCE, RATIO, DT = 10.0, 1.01, 1e-6


def fresh(shape: tuple) -> np.ndarray:
    met = np.zeros((*shape, L.MET_SIZE))
    met[..., L.STEADY_MAX_W] = -np.inf
    met[..., L.STEADY_MIN_W] = np.inf
    met[..., L.FIRST_ZERO_T] = -1.0
    return met


def kernel_figures(preset: str, n_modes: int, steps: int, rounds: int = 3) -> None:
    system = make_system("ball", preset, gap_m=0.5e-3, friction=True, n_modes=n_modes)
    omega = RATIO * system.reference_frequency_rad_s

    def batch_of(nb: int):
        P = np.array([pack(system, omega, FORCE, DT) for _ in range(nb)])
        X = np.array([initial_state(system, Initial(-1.5e-3 + 3e-3 * r / 15, 0.1 * (r % 3)))
                      for r in range(nb)])
        return P, X

    def single(P, X):
        run_rk4(P[0], X[0].copy(), Steps(0.0, DT, steps, steps // 5),
                Records(np.zeros((0, 6)), np.zeros((20000, 3)), np.zeros((20000, 2)),
                        np.zeros((0, 5)), fresh(())))

    def batch(P, X):
        nb = len(P)
        run_rk4_batch(P, X.copy(), Steps(0.0, DT, steps, steps // 5),
                      Records(np.zeros((nb, 0, 6)), np.zeros((nb, 20000, 3)),
                              np.zeros((nb, 20000, 2)), np.zeros((nb, 0, 5)), fresh((nb,))))

    configs = [("single", single, batch_of(1))] + [(nb, batch, batch_of(nb))
                                                    for nb in (1, 2, 4, 8, 16)]
    best = {}
    for name, fn, (P, X) in configs:  # compile / load from the cache
        fn(P, X)
        best[name] = math.inf
    # rounds over every configuration, so that a change of the machine's load
    # touches all of them; the best of the rounds per configuration
    for _ in range(rounds):
        for name, fn, (P, X) in configs:
            tic = time.perf_counter()
            fn(P, X)
            best[name] = min(best[name], time.perf_counter() - tic)
    base = best["single"] / steps * 1e9
    print(f"{preset} preset, {n_modes} mode(s), ball gap 0.5 mm, friction on, {FORCE:g} N, "
          f"r = {RATIO}:")
    print(f"  single-run kernel      : {base:5.1f} ns per step")
    for nb in (1, 2, 4, 8, 16):
        per = best[nb] / steps / nb * 1e9
        print(f"  lock-step, B = {nb:2d} runs : {per:5.1f} ns per run-step "
              f"({base / per:.2f}x the single-run kernel)")


def timed(fn, *args, **kw):
    tic = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - tic


def same(a, b) -> bool:
    return all(np.array_equal(a[k].values, b[k].values, equal_nan=a[k].dtype.kind == "f")
               for k in a.data_vars if k != "elapsed_s")


def sweep_figures() -> None:
    ratios = np.round(np.arange(0.95, 1.05 + 1e-9, 0.01), 2)
    for preset in ("paper", "physical"):
        cases = sweep_mod.published_cases(preset=preset)
        for b in (1, sweep_mod.BATCH):  # warm every kernel used
            sweep_mod.sweep(cases, sweep_mod.SweepOptions(ratios, (FORCE,), batch=b),
                            integration=Integration(duration_s=1e-3))
        one, t1 = timed(sweep_mod.sweep, cases, sweep_mod.SweepOptions(ratios, (FORCE,), batch=1))
        many, tb = timed(sweep_mod.sweep, cases, sweep_mod.SweepOptions(ratios, (FORCE,)))
        print(f"published sweep ({preset}, {len(ratios)} ratios x {len(cases)} cases, 2 s each, "
              f"{many.attrs['workers']} workers): one run at a time {t1:.2f} s, "
              f"batches of {many.attrs['batch']} {tb:.2f} s ({t1 / tb:.2f}x); "
              f"identical: {same(one, many)}")


def basin_figures() -> None:
    system = make_system("ball", "paper", gap_m=0.5e-3, friction=False)
    published = basins_mod.BasinOptions(force_n=FORCE, ratio=RATIO)
    small = basins_mod.BasinOptions((-1.5e-3, 1.5e-3, 4), (-1.5, 1.5, 4), force_n=FORCE,
                                    ratio=RATIO)
    warm = Integration(duration_s=1e-3)
    basins_mod.basins(system, replace(small, batch=1), integration=warm)
    basins_mod.basins(system, small, integration=warm)
    one, t1 = timed(basins_mod.basins, system, replace(published, batch=1))
    many, tb = timed(basins_mod.basins, system, published)
    print(f"published 30 x 30 basin (900 runs of 2 s, {many.attrs['workers']} workers): "
          f"one run at a time {t1:.1f} s, batches of {many.attrs['batch']} {tb:.1f} s "
          f"({t1 / tb:.2f}x); identical: {same(one, many)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300_000)
    ap.add_argument("--skip-basin", action="store_true")
    ap.add_argument("--skip-sweep", action="store_true")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    kernel_figures("paper", 1, args.steps)
    kernel_figures("physical", 2, args.steps)
    if not args.skip_sweep:
        sweep_figures()
    if not args.skip_basin:
        basin_figures()
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
