"""What each instruction-set copy of the kernels is worth, through the calls a user makes.

    .venv/bin/python benchmarks/bench_isa.py LABEL=MODULE [LABEL=MODULE ...]
        [--rounds 7] [--only NAME ...]

The core compiles its kernels for more than one instruction set and picks one at run
time (core/rk4.hpp, core/exact/driver.cpp); a copy that gives little speed costs every
build from source its compile time.  Each MODULE is a core built with some copies left
out, e.g.

    cmake -S . -B /tmp/b -G Ninja -DPython_EXECUTABLE=.venv/bin/python \\
          -DCMAKE_CXX_FLAGS=-DBB_NO_AVX512_CLONE -DBORINGBAR_OUTPUT_DIR=/tmp/noavx512
    cmake --build /tmp/b

(-DBB_NO_AVX512_CLONE: no AVX-512 copy, so an AVX-512 CPU runs the AVX2 one;
-DBB_NO_AVX2_CLONE: the baseline alone, RK4 and exact.)  All the modules are loaded into
this one process and the workloads run through ``bb.simulate`` and ``bb.lobes`` with
each module in turn, in a new random order every round: a slow spell of a shared
machine (another job on the other core slows this one, CPU time included) then falls on
every module alike.  Prints per workload and module the best and the median CPU time
over the rounds, and against the first module the median of the rounds' ratios (> 1:
faster than the first).  The copies compute the same bits: a workload whose result
differs between modules stops the script.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import random
import statistics
import sys
import time


def load(label: str, path: str):
    # an extension's init function is found by the last part of the name: PyInit_core
    spec = importlib.util.spec_from_file_location(f"_bench_{label}.core", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def use(module) -> None:
    """Route the package's kernel calls to ``module``."""
    from boringbar.simulate import kernels, regimes
    kernels.core = module
    regimes.core = module


def digest(*arrays) -> str:
    import numpy as np
    h = hashlib.sha1()
    for a in arrays:
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()[:10]


def workloads():
    import boringbar as bb
    from boringbar.execute import Execution

    ball_f = bb.make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    paper = bb.make_system("ball", "paper", gap_m=0.1e-3, friction=False)
    stick = bb.make_system("ball", "paper", gap_m=0.5e-3, friction=True)

    def result(run):
        return digest([run.summary()["rms_tip_m"]], run.final.x)

    def cut():
        # the published ball bar with friction in a cut: RK4 with the delay, the ball
        # sticking and slipping (the four stages) and the map step
        return result(bb.simulate(ball_f, bb.Regenerative(depth_m=0.4e-3, rpm=1200.0),
                                  duration_s=3.0, record_every=0))

    def harmonic_map():
        # paper preset, no friction: every step one affine map (linmap.hpp)
        return result(bb.simulate(paper, bb.Harmonic(10.0, 1.0), duration_s=10.0,
                                  record_every=0, integrator="rk4"))

    def harmonic_stick():
        # a sticking ball with friction: the four RK4 stages at most steps
        return result(bb.simulate(stick, bb.Harmonic(10.0, 1.0), duration_s=5.0,
                                  record_every=0, integrator="rk4"))

    def exact():
        # the exact integrator (a harmonic run: its AVX2 copy where built), a rattling ball
        return result(bb.simulate(ball_f, bb.Harmonic(20.0, 0.97), duration_s=20.0,
                                  record_every=0, integrator="exact"))

    def lobes():
        # the lobes of the ball bar with friction at one speed, serially: the converged
        # verdict's cuts (RK4)
        ds = bb.lobes(ball_f, bb.LobesOptions(rpm=(1300.0,), analytic=False),
                      execution=Execution("serial"))
        return digest(ds["min_chatter_free_depth_m"].values)

    return {"cut": cut, "harmonic_map": harmonic_map, "harmonic_stick": harmonic_stick,
            "exact": exact, "lobes": lobes}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("modules", nargs="+", help="LABEL=PATH of a built core module")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--only", nargs="*", help="workloads to run (default: all)")
    args = ap.parse_args()
    modules = {}
    for item in args.modules:
        label, _, path = item.partition("=")
        modules[label] = load(label, path)
    import boringbar as bb
    use(next(iter(modules.values())))
    # the imports and the first call's set-up
    bb.simulate(bb.make_system(), bb.Harmonic(10.0, 1.0), duration_s=1e-3, integrator="rk4")
    labels = list(modules)
    rng = random.Random(0)
    for name, fn in workloads().items():
        if args.only and name not in args.only:
            continue
        times = {label: [] for label in labels}
        checks = set()
        for _ in range(args.rounds):
            for label in rng.sample(labels, len(labels)):
                use(modules[label])
                tic = time.process_time()
                checks.add(fn())
                times[label].append(time.process_time() - tic)
        if len(checks) != 1:
            sys.exit(f"{name}: the modules gave different results: {sorted(checks)}")
        first = times[labels[0]]
        print(f"{name} (result {checks.pop()}, {args.rounds} rounds)", flush=True)
        for label in labels:
            ratio = statistics.median(a / b for a, b in zip(first, times[label], strict=True))
            print(f"  {label:12s} best {min(times[label]):7.3f} s  median "
                  f"{statistics.median(times[label]):7.3f} s CPU  "
                  f"{labels[0]}/{label} {ratio:5.3f}", flush=True)


if __name__ == "__main__":
    main()
