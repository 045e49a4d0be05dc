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
-DBB_NO_AVX2_CLONE: the baseline alone, RK4 and exact; or any other flags, set on a
copy of the sources.)  Two builds of the core cannot share a process (nanobind
registers each type once), so each round runs every module in a process of its own, in
a new random order every round: the module is imported as ``boringbar.core`` before the
package, and the workloads run through ``bb.simulate`` and ``bb.lobes``, each once to
warm up and once timed.  A slow spell of a shared machine then falls on every module
alike.  Prints per workload and module the best and the median CPU time over the
rounds, and against the first module the median of the rounds' ratios (> 1: faster
than the first).  Builds of the same sources compute the same bits: a workload whose
result differs between modules is reported.  On a shared VM one build's processes run
at two speeds, up to 1.7x apart, whichever CPU they are pinned to and with address
randomisation off (the same module given twice, two rounds: A/B 0.58-0.64), so the ratios
need many rounds.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import random
import statistics
import subprocess
import sys
import time


def load_as_core(path: str) -> None:
    """Import the built module at ``path`` as ``boringbar.core``, before the package."""
    spec = importlib.util.spec_from_file_location("boringbar.core", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["boringbar.core"] = module
    spec.loader.exec_module(module)


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
    hertz = bb.make_system("ball", "physical", gap_m=0.1e-3, contact="hertz")
    rolling = bb.make_system("ball", "physical", motion="roll")
    ball5 = bb.make_system("ball", "physical", gap_m=0.1e-3, n_modes=5)
    absorber5 = bb.make_system("tmd", "physical", n_modes=5)

    def result(run):
        return digest([run.summary()["rms_tip_m"]], run.final.x)

    def rk4(system, forcing, duration_s):
        # (in a cut "auto" takes RK4 as well)
        return result(bb.simulate(system, forcing, duration_s=duration_s, record_every=0,
                                  integrator="rk4"))

    def cut():
        # the published ball bar with friction in a cut: RK4 with the delay, the ball
        # sticking and slipping (the four stages) and the map step
        return rk4(ball_f, bb.Regenerative(depth_m=0.4e-3, rpm=1200.0), 3.0)

    def harmonic_map():
        # paper preset, no friction: every step one affine map (linmap.hpp)
        return rk4(paper, bb.Harmonic(10.0, 1.0), 10.0)

    def harmonic_map_history():
        # the same with simulate's default history (20000 rows: one every 500 steps)
        return result(bb.simulate(paper, bb.Harmonic(10.0, 1.0), duration_s=10.0,
                                  integrator="rk4"))

    def harmonic_stick():
        # a sticking ball with friction: the four RK4 stages at most steps
        return rk4(stick, bb.Harmonic(10.0, 1.0), 5.0)

    def exact():
        # the exact integrator (a harmonic run: its AVX2 copy where built), a rattling ball
        return result(bb.simulate(ball_f, bb.Harmonic(20.0, 0.97), duration_s=20.0,
                                  record_every=0, integrator="exact"))

    def contact():
        # a Hertz contact at the walls: the kernel of a run-time shape (RK4)
        return rk4(hertz, bb.Harmonic(20.0, 1.0), 1.0)

    def modes5():
        # a five-mode ball bar (the kernel of a run-time shape): harmonic, then in a cut
        return rk4(ball5, bb.Harmonic(20.0, 1.0), 2.0)

    def modes5_cut():
        return rk4(ball5, bb.Regenerative(depth_m=0.4e-3, rpm=1200.0), 1.0)

    def tmd5():
        # a five-mode bar with its tuned absorber (the kernel of a run-time shape)
        return rk4(absorber5, bb.Harmonic(20.0, 1.0), 2.0)

    def rolling_small():
        # a rolling ball under a small force: it rolls and slips in turn (RK4's roll law at
        # the four stages at 40 % of the steps, the rolled map at most of the others)
        return rk4(rolling, bb.Harmonic(0.05, 1.0), 3.0)

    def lobes():
        # the lobes of the ball bar with friction at one speed, serially: the converged
        # verdict's cuts (RK4)
        ds = bb.lobes(ball_f, bb.LobesOptions(rpm=(1300.0,), analytic=False),
                      execution=Execution("serial"))
        return digest(ds["min_chatter_free_depth_m"].values)

    return {"cut": cut, "harmonic_map": harmonic_map,
            "harmonic_map_history": harmonic_map_history, "harmonic_stick": harmonic_stick,
            "exact": exact, "contact": contact, "modes5": modes5, "modes5_cut": modes5_cut,
            "tmd5": tmd5, "rolling": rolling_small, "lobes": lobes}


def child(path: str, only) -> None:
    """One process's round: each workload warmed up, then timed; JSON on stdout."""
    load_as_core(path)
    out = {}
    for name, fn in workloads().items():
        if only and name not in only:
            continue
        fn()
        tic = time.process_time()
        out[name] = (fn(), time.process_time() - tic)
    print(json.dumps(out))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("modules", nargs="*", help="LABEL=PATH of a built core module")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--only", nargs="*", help="workloads to run (default: all)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        return child(args.child, args.only)
    modules = dict(item.partition("=")[::2] for item in args.modules)
    labels = list(modules)
    rng = random.Random(0)
    runs = {label: [] for label in labels}
    for _ in range(args.rounds):
        for label in rng.sample(labels, len(labels)):
            cmd = [sys.executable, __file__, "--child", modules[label]]
            if args.only:
                cmd += ["--only", *args.only]
            out = subprocess.run(cmd, capture_output=True, text=True, check=True)
            runs[label].append(json.loads(out.stdout.splitlines()[-1]))
    for name in runs[labels[0]][0]:
        results = {r[name][0] for label in labels for r in runs[label]}
        times = {label: [r[name][1] for r in runs[label]] for label in labels}
        same = "the same result" if len(results) == 1 else f"RESULTS DIFFER: {sorted(results)}"
        print(f"{name} ({same}, {args.rounds} rounds)", flush=True)
        first = times[labels[0]]
        for label in labels:
            ratio = statistics.median(a / b for a, b in zip(first, times[label], strict=True))
            print(f"  {label:12s} best {min(times[label]):7.3f} s  median "
                  f"{statistics.median(times[label]):7.3f} s CPU  "
                  f"{labels[0]}/{label} {ratio:5.3f}", flush=True)


if __name__ == "__main__":
    main()
