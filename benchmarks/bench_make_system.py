"""``make_system`` and a first exact run with one BLAS thread (the package's default,
boringbar/model/linalg.py) against OpenBLAS's own thread pool, in one process.

    .venv/bin/python benchmarks/bench_make_system.py [--repeat 5] [--systems 20]

The bar's finite-element eigensolve (about 90 degrees of freedom) and the exact
integrator's regimes (``regimes.system_regimes``: eig, inv and solve of a few stacked 6 x 6
to 10 x 10 matrices) run under ``one_blas_thread``; the baseline calls the same functions
unwrapped (their ``__wrapped__``), so that OpenBLAS uses as many threads as it found cores.
Each variant makes ``--systems`` ball bars (gaps 0.10-0.29 mm, each with its finite-element
model solved afresh: the kept models are cleared first) and runs each for 0.1 s with the
exact integrator (its regimes are new for each system), round robin, best of ``--repeat``:
wall time and the process's CPU time (all threads) per system. Twice: on an otherwise idle
machine, and beside a busy process on every other core (a pure-Python loop), as in a sweep's
workers, the design page's server or a test run.

Then ``make_system`` alone on a bar whose modal model is kept (``bar.kept_modal_model``: a
design search's or the page's next system on the same bar) against the same call with
the kept models cleared, best of ``--repeat`` rounds of ``--systems`` calls.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import time
from contextlib import contextmanager

import boringbar as bb
from boringbar.model import bar as bar_module
from boringbar.simulate import regimes


def spin(stop) -> None:
    while not stop.is_set():
        sum(range(10_000))


@contextmanager
def busy(n: int):
    """``n`` processes spinning on the CPU while the block runs."""
    stop = mp.Event()
    procs = [mp.Process(target=spin, args=(stop,), daemon=True) for _ in range(n)]
    for p in procs:
        p.start()
    time.sleep(0.5)
    try:
        yield
    finally:
        stop.set()
        for p in procs:
            p.join()


@contextmanager
def blas_threads(own: bool):
    """OpenBLAS's own thread pool inside the two calls (own), or the package's default."""
    eig, reg = bar_module.SteppedBar._eig, regimes.system_regimes
    if own:
        bar_module.SteppedBar._eig = staticmethod(eig.__wrapped__)
        regimes.system_regimes = reg.__wrapped__.__wrapped__  # past the cache and the limit
    try:
        yield
    finally:
        bar_module.SteppedBar._eig, regimes.system_regimes = staticmethod(eig), reg


def one_round(n: int, own: bool, offset: float) -> tuple[float, float]:
    """(wall, CPU) seconds per system for ``n`` new systems and their first exact run."""
    with blas_threads(own):
        wall, cpu = time.perf_counter(), time.process_time()
        for i in range(n):
            bar_module.kept_modal_model.cache_clear()
            s = bb.make_system("ball", gap_m=(0.10 + 0.01 * i + offset) * 1e-3)
            bb.simulate(s, bb.Harmonic(10.0), duration_s=0.1, record_every=0,
                        integrator="exact")
        return (time.perf_counter() - wall) / n, (time.process_time() - cpu) / n


def measure(n: int, repeat: int) -> dict:
    best = {False: (1e9, 1e9), True: (1e9, 1e9)}
    for r in range(repeat):
        for own in (False, True):
            # a new gap offset each round: every system is new to the caches
            w, c = one_round(n, own, 1e-4 * (2 * r + own + 1))
            best[own] = (min(best[own][0], w), min(best[own][1], c))
    return best


def kept_round(n: int, kept: bool) -> float:
    """Seconds per ``make_system`` of ``n`` ball bars on one bar, its modal model kept (or
    cleared before each)."""
    tic = time.perf_counter()
    for i in range(n):
        if not kept:
            bar_module.kept_modal_model.cache_clear()
        bb.make_system("ball", gap_m=(0.10 + 0.01 * i) * 1e-3)
    return (time.perf_counter() - tic) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--systems", type=int, default=20)
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    one_round(2, False, 0.5)  # imports and first calls
    print(f"{cores} cores; make_system + a 0.1 s exact run, per system, best of {args.repeat}")
    print(f"{'':28s} {'one thread':>22s} {'OpenBLAS threads':>22s} {'wall ratio':>11s}")
    for label, hogs in (("idle", 0), (f"beside {cores - 1} busy process(es)", cores - 1)):
        if hogs == 0:
            best = measure(args.systems, args.repeat)
        else:
            with busy(hogs):
                best = measure(args.systems, args.repeat)
        (w1, c1), (wn, cn) = best[False], best[True]
        print(f"{label:28s} {w1 * 1e3:7.2f} ms ({c1 * 1e3:6.2f} CPU) "
              f"{wn * 1e3:7.2f} ms ({cn * 1e3:6.2f} CPU) {wn / w1:10.2f}x")
    best = {True: 1e9, False: 1e9}
    for _ in range(args.repeat):
        for kept in (True, False):
            best[kept] = min(best[kept], kept_round(args.systems, kept))
    print(f"make_system alone: the bar's modal model kept {best[True] * 1e3:.3f} ms, solved "
          f"afresh {best[False] * 1e3:.3f} ms ({best[False] / best[True]:.1f}x)")


if __name__ == "__main__":
    main()
