"""Where a cold compile of the exact kernel goes, and what numba's code generation flags
change, in one process on an empty numba cache.

    .venv/bin/python benchmarks/compile_profile.py [--top 12] [--save F.npz] [--against F.npz]
                                                   [--asm F.s] [--numba-own]
    NUMBA_OPT=1 .venv/bin/python benchmarks/compile_profile.py ...   # numba's own flags
    NUMBA_SLP_VECTORIZE=0 NUMBA_LOOP_VECTORIZE=0 .venv/bin/python benchmarks/compile_profile.py

A fresh ``NUMBA_CACHE_DIR`` (a temporary directory) stands for a fresh clone.  One
0.01 s exact run of the default bar compiles the kernel; the script prints the
process's CPU time for it, then numba's own per-function record of each compiled
function (``pipeline_times``: the passes, summed per pass name, and the seconds under
numba's compiler and LLVM locks, which include what the function's compile compiled
of its callees), largest first.

Then the warm time of four 2 s exact runs (best of 5 each), and their final states
and tip RMS (and those of one 0.2 s RK4 run), saved with ``--save`` or compared bit
for bit ``--against`` a saved file, so that a flag's effect on the warm speed and on
the numbers shows beside its effect on the compile.  ``--asm F.s`` writes the
driver's assembly, with the names that change from one process to the next (numba's
unique ids in mangled names, its constant strings' hashes) made constant, so that
``cmp`` of two runs' files says whether a change to the compiler left the machine
code as it was.  ``--numba-own`` compiles with numba's own SSA, liveness and inlining
instead of the package's linear ones (kernels/ssa_blocks.py, live_bits.py,
inline_copy.py), for the same comparison.
"""

from __future__ import annotations

import argparse
import gc
import os
import re
import sys
import tempfile
import time

os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="numba-cold-")

import numpy as np  # noqa: E402
from numba.core.registry import CPUDispatcher  # noqa: E402

import boringbar as bb  # noqa: E402
from boringbar.kernels import inline_copy, live_bits, ssa_blocks  # noqa: E402
from boringbar.kernels.exact import driver  # noqa: E402

WARM_CASES = (("physical", 0.1e-3, True, 20.0), ("physical", 0.5e-3, True, 10.0),
              ("paper", 0.1e-3, False, 10.0), ("physical", 0.1e-3, False, 20.0))


def cold_compile() -> float:
    cpu = time.process_time()
    bb.simulate(bb.make_system(), bb.Harmonic(amplitude=20.0, ratio=1.0), duration=0.01,
                integrator="exact")
    return time.process_time() - cpu


def compiled_functions():
    """(seconds of all passes, name, pass totals, locks) of every compiled function."""
    rows = []
    for obj in gc.get_objects():
        if not isinstance(obj, CPUDispatcher):
            continue
        for cres in obj.overloads.values():
            md = cres.metadata or {}
            passes: dict[str, float] = {}
            for pipeline in md.get("pipeline_times", {}).values():
                for name, t in pipeline.items():
                    key = name.split("_", 1)[-1]
                    passes[key] = passes.get(key, 0.0) + t.init + t.run + t.finalize
            func = obj.py_func
            rows.append((sum(passes.values()), f"{func.__module__}.{func.__name__}", passes,
                         md.get("timers", {})))
    return sorted(rows, key=lambda r: -r[0])


def driver_asm() -> str:
    """The exact driver's assembly, process-specific names made constant."""
    asm = "\n".join(driver._exact.inspect_asm().values())
    asm = re.sub(r"0x[0-9a-f]+", "ADDR", asm)
    asm = re.sub(r'"?\.bytes\.-?[0-9]+"?', "BYTES", asm)
    return re.sub(r"B[0-9]+v[0-9]+B", "BvB", asm)


def warm_runs():
    times, out = [], {}
    for k, (preset, gap, friction, force) in enumerate(WARM_CASES):
        system = bb.make_system("ball", preset=preset, gap=gap, friction=friction)
        best = np.inf
        for _ in range(5):
            tic = time.perf_counter()
            run = bb.simulate(system, bb.Harmonic(amplitude=force, ratio=1.0), duration=2.0,
                              integrator="exact")
            best = min(best, time.perf_counter() - tic)
        times.append(best)
        out[f"x{k}"] = run.final.x
        out[f"rms{k}"] = np.array([run.summary()["rms_tip_m"]])
    # and one RK4 run (its kernel compiled here), whose numbers the passes must not move
    run = bb.simulate(bb.make_system(), bb.Harmonic(amplitude=20.0, ratio=1.0), duration=0.2,
                      integrator="rk4")
    out["x_rk4"], out["rms_rk4"] = run.final.x, np.array([run.summary()["rms_tip_m"]])
    return times, out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=12)
    ap.add_argument("--save")
    ap.add_argument("--against")
    ap.add_argument("--asm")
    ap.add_argument("--numba-own", action="store_true")
    args = ap.parse_args(argv)
    if args.numba_own:
        for patch in (inline_copy, live_bits, ssa_blocks):
            patch.apply(False)
    flags = {k: v for k, v in os.environ.items() if k.startswith("NUMBA_") and k !=
             "NUMBA_CACHE_DIR"}
    print(f"numba flags: {flags or 'none'}; numba's own passes: {args.numba_own}; "
          f"load {os.getloadavg()[0]:.1f}")
    print(f"cold compile of the exact kernel: {cold_compile():.1f} s CPU")
    for total, name, passes, timers in compiled_functions()[:args.top]:
        top = sorted(passes.items(), key=lambda kv: -kv[1])[:4]
        print(f"{total:7.1f} s  {name}  (compiler lock {timers.get('compiler_lock', 0):.1f} s,"
              f" LLVM lock {timers.get('llvm_lock', 0):.1f} s)")
        print("           " + ", ".join(f"{k} {v:.1f}" for k, v in top))
    if args.asm:
        with open(args.asm, "w") as f:
            f.write(driver_asm())
    times, out = warm_runs()
    print("warm, best of 5 (ms): " + ", ".join(
        f"{p} gap {g * 1e3:.1f} mm{' friction' if f else ''} {F:.0f} N {1e3 * t:.2f}"
        for (p, g, f, F), t in zip(WARM_CASES, times, strict=True)))
    if args.save:
        np.savez(args.save, **out)
    if args.against:
        ref = np.load(args.against)
        same = all(np.array_equal(ref[k], out[k]) for k in out)
        print(f"bit-identical to {args.against}: {same}")


if __name__ == "__main__":
    sys.exit(main())
