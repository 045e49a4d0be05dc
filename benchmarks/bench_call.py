"""The per-call overhead of the core's entry points and of a short ``simulate`` call.

    .venv/bin/python benchmarks/bench_call.py [--repeat 2000] [--rounds 7]

Times, in microseconds of the thread's CPU time (median of ``--rounds`` rounds, each the
mean of ``--repeat`` calls; the garbage collector off while they run, as ``timeit``
does), calls whose integration is empty, so that what is timed is the boundary itself:
building the run description, setting its fields (each setter converting and checking
its value) and the checks when the run starts:

- ``kernels.run_rk4``, ``run_rk4_batch`` (4 runs) and ``run_exact`` (``prepare``'s setup
  given, harmonic and a cut) with zero steps (``t_end = t0`` for the exact integrator);
- ``simulate`` of the published ball bar for 10 steps with each integrator: the whole
  public call (the checks, the packing, the result).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time

import numpy as np

from boringbar import Harmonic, Regenerative, make_system, simulate
from boringbar.simulate import kernels, setup_run
from boringbar.simulate import layout as L

clock = time.thread_time


def rk4_args(cut: bool = False) -> tuple:
    s = make_system("ball", "paper", gap_m=0.1e-3, friction=True)
    f = Regenerative(depth_m=1e-3, rpm=1200.0) if cut else Harmonic(10.0, 1.0)
    su = setup_run(s, f, 2e-3, 1e-6, None, 10, 0.5, True, "rk4")
    return (su.p, su.x, kernels.Steps(su.t0, su.dt, 0, 0, su.record_every),
            kernels.Records(su.rec, su.imp, su.stick, su.stb, su.met), su.buf)


def batch_args(n: int = 4) -> tuple:
    p, x, steps, out, _ = rk4_args()
    rows = lambda v: np.ascontiguousarray(np.repeat(v[None], n, axis=0))  # noqa: E731
    return (rows(p), rows(x), kernels.Steps(steps.t0, steps.dt, 0, 0),
            kernels.Records(np.zeros((n, 0, 6)), rows(out.imp), rows(out.stick),
                            rows(out.strobe), rows(out.met)))


def exact_args(cut: bool = False) -> tuple:
    s = make_system("ball", "physical", gap_m=0.1e-3, friction=True)
    f = Regenerative(depth_m=0.1e-3, rpm=1200.0) if cut else Harmonic(10.0, 1.0)
    su = setup_run(s, f, 2e-3, 1e-6, None, 10, 0.5, True, "exact")
    prep = kernels.prepare(su.p)
    args = (su.p, su.x, kernels.Steps(su.t0, su.dt, 0, 0, su.record_every),
            kernels.Records(su.rec, su.imp, su.stick, su.stb, su.met))
    return args, {"prep": prep}


def per_call_us(fn, repeat: int, rounds: int) -> float:
    fn()
    means = []
    gc.collect()
    gc.disable()
    try:
        for _ in range(rounds):
            tic = clock()
            for _ in range(repeat):
                fn()
            means.append((clock() - tic) / repeat)
    finally:
        gc.enable()
    return statistics.median(means) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2000)
    ap.add_argument("--rounds", type=int, default=7)
    a = ap.parse_args()

    rk4, rk4_cut, batch = rk4_args(), rk4_args(cut=True), batch_args()
    (ex, ex_kw), (ex_cut, ex_cut_kw) = exact_args(), exact_args(cut=True)
    ball = make_system("ball", "paper", gap_m=0.1e-3, friction=True)
    forcing = Harmonic(10.0, 1.0)
    cases = {
        "kernels.run_rk4, 0 steps": lambda: kernels.run_rk4(*rk4),
        "kernels.run_rk4 cut, 0 steps": lambda: kernels.run_rk4(*rk4_cut),
        "kernels.run_rk4_batch (4 runs), 0 steps": lambda: kernels.run_rk4_batch(*batch),
        "kernels.run_exact, t_end = t0": lambda: kernels.run_exact(*ex, **ex_kw),
        "kernels.run_exact cut, t_end = t0": lambda: kernels.run_exact(*ex_cut, **ex_cut_kw),
    }
    slow = {
        f"simulate {integ}, 10 steps": (lambda integ=integ: simulate(
            ball, forcing, duration_s=1e-5, record_every=0, integrator=integ))
        for integ in ("rk4", "exact")
    }
    assert int(ex[0][L.FORCING]) == L.HARMONIC
    print(f"us of CPU time per call, median of {a.rounds} rounds of {a.repeat} calls "
          f"(simulate: of {a.repeat // 20})")
    for label, fn in cases.items():
        print(f"{label:42s} {per_call_us(fn, a.repeat, a.rounds):9.2f}", flush=True)
    for label, fn in slow.items():
        print(f"{label:42s} {per_call_us(fn, a.repeat // 20, a.rounds):9.2f}", flush=True)


if __name__ == "__main__":
    main()
