"""RK4 speed: ns per step of the C++ core (boringbar._core) and of the numba kernels.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_core_rk4.py [--duration 0.5] [--cpp-only]

Same process, same inputs (packed by boringbar.simulate._setup), warm (numba compiled or
loaded from its cache by a short first call), best of ``--repeat`` rounds interleaved.
Times are the calling thread's CPU time (time.thread_time: both kernels run in it), which
a busy machine disturbs far less than the wall clock.
Cases: the published ball bar with 1 mode (paper preset, harmonic; with its friction and
without), the physical preset's 2-mode ball bar, the solid bar, a regenerative cut, and
the lock-step batch (16 runs of the 1-mode ball bar; ns per run-step).  ``--cpp-only``
times the C++ core alone (no numba import).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from boringbar import Harmonic, Initial, _core, make_system
from boringbar.model.forcing import Regenerative
from boringbar.simulate import _setup


def single_inputs(su):
    buf = su.buf if su.buf is not None else np.zeros((0, 2))
    return (su.p.copy(), su.x.copy(), su.t0, su.dt, su.n_steps, su.steady_steps,
            su.record_every, su.rec.copy(), su.imp.copy(), su.stick.copy(), su.stb.copy(),
            su.met.copy(), buf.copy())


def batch_inputs(sus):
    first = sus[0]
    nb = len(sus)
    return (np.array([su.p for su in sus]), np.array([su.x for su in sus]), first.t0,
            first.dt, first.n_steps, first.steady_steps, np.zeros((nb, len(first.imp), 3)),
            np.zeros((nb, len(first.stick), 2)), np.zeros((nb, len(first.stb), 5)),
            np.array([su.met for su in sus]))


def best_times(fns, make_args, repeat):
    """Best CPU time of each of ``fns``, rounds interleaved."""
    best = [float("inf")] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            args = make_args()
            tic = time.thread_time()
            fn(*args)
            best[i] = min(best[i], time.thread_time() - tic)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.5, help="simulated s (dt = 1e-6)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cpp-only", action="store_true", help="time the C++ core alone")
    args = ap.parse_args()
    kernels = {"C++": (_core.run_rk4, _core.run_rk4_batch)}
    if not args.cpp_only:
        from boringbar.kernels.rk4 import run_rk4
        from boringbar.kernels.rk4_batch import run_rk4_batch
        kernels = {"numba": (run_rk4, run_rk4_batch), **kernels}

    d = args.duration
    singles = {
        "ball 1 mode, paper preset (friction 20.4 N), gap 0.5 mm": (
            make_system("ball", "paper", gap=0.5e-3), Harmonic(20.0, 1.0)),
        "ball 1 mode, paper preset, gap 0.1 mm, no friction": (
            make_system("ball", "paper", gap=0.1e-3, friction=False), Harmonic(10.0, 1.0)),
        "ball 2 modes, physical preset, gap 0.5 mm": (
            make_system("ball", "physical", gap=0.5e-3), Harmonic(20.0, 1.0)),
        "solid 2 modes, physical preset": (make_system("solid"), Harmonic(10.0, 1.0)),
        "cut, solid, cubic, 1 revolution of 3000 steps": (
            make_system("solid"), Regenerative(depth=1e-3, rpm=20000.0, revolutions=1)),
    }
    names = list(kernels)
    print(f"ns per step, {d:g} s at dt = 1e-6, best of {args.repeat}:")
    header = "".join(f"{n:>10s}" for n in names)
    print(f"  {'case':58s}{header}" + ("     ratio" if len(names) == 2 else ""))
    for label, (system, forcing) in singles.items():
        su = _setup(system, forcing, d, 1e-6, None, 0, 0.8, False, "rk4")
        warm = _setup(system, forcing, 1e-3, 1e-6, None, 0, 0.8, False, "rk4")
        for n in names:
            kernels[n][0](*single_inputs(warm))
        ts = best_times([kernels[n][0] for n in names], lambda: single_inputs(su), args.repeat)
        ns = [t / su.n_steps * 1e9 for t in ts]
        row = "".join(f"{v:10.1f}" for v in ns)
        ratio = f"{ns[0] / ns[1]:9.2f}x" if len(ns) == 2 else ""
        print(f"  {label:58s}{row}{ratio}", flush=True)

    system = make_system("ball", "paper", gap=0.5e-3)
    for nb in (16, 4):
        jobs = [(Harmonic(10.0 + j, 0.97 + 0.01 * (j % 8)), Initial(0.0, 0.1 * (j % 3)))
                for j in range(nb)]
        sus = [_setup(system, f, d, 1e-6, i, 0, 0.8, False, "rk4") for f, i in jobs]
        warm = [_setup(system, f, 1e-3, 1e-6, i, 0, 0.8, False, "rk4") for f, i in jobs]
        for n in names:
            kernels[n][1](*batch_inputs(warm))
        ts = best_times([kernels[n][1] for n in names], lambda: batch_inputs(sus), args.repeat)
        ns = [t / (sus[0].n_steps * nb) * 1e9 for t in ts]
        row = "".join(f"{v:10.1f}" for v in ns)
        ratio = f"{ns[0] / ns[1]:9.2f}x" if len(ns) == 2 else ""
        label = f"batch of {nb}, ball 1 mode paper (ns per run-step)"
        print(f"  {label:58s}{row}{ratio}", flush=True)


if __name__ == "__main__":
    main()
