"""The RK4 kernels (single run and lock-step batch) against their own version at a git
revision, in one process: results bit for bit, and the speed.

    .venv/bin/python benchmarks/bench_rk4_rev.py REV [--repeat 5] [--skip-timing] [--cpu-time]

Exports ``src/boringbar`` at REV as the package ``boringbar_rev`` (as
``bench_exact_rev.py`` does; a numba revision compiles its kernels on the first run
and needs numba in the environment: ``pip install 'numba==0.68.*'``), packs every run with
the working tree's ``setup_run`` (the parameter vector moved into the revision's layout for
the revision's kernels: ``bench_exact_rev.rev_params``), then

- runs the same cases through ``run_rk4`` of both versions (solid, TMD, locked, the
  ball with and without friction in the paper and physical presets with 1, 2 and 3
  modes, the stage loop forced, a regenerative cut of the solid bar and of the ball
  bar; strobe and history on) and compares metrics, final state, impact, stick,
  strobe and history rows bit for bit;
- does the same for ``run_rk4_batch`` (batches of 4 and 16 runs of each bar);
- times the single-run kernel (ns per step, the 2 s runs of ``bench_kernel.py``
  with 1 and 2 modes) and a batch of 16 (ns per run-step), old and new
  alternately, best of ``--repeat``; the wall clock, or with ``--cpu-time`` the thread's
  CPU time (on a loaded machine the process is descheduled in mid-run, which the wall
  clock counts).
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_exact_rev import export, rev_params  # noqa: E402
from machine import describe  # noqa: E402

from boringbar import Harmonic, Initial, make_system  # noqa: E402
from boringbar.model.forcing import Regenerative  # noqa: E402
from boringbar.simulate import kernels as R1  # noqa: E402
from boringbar.simulate import layout as L  # noqa: E402
from boringbar.simulate.engine import setup_run  # noqa: E402

#: the working tree's batch entry point is in the same module as the single run's
B1 = R1
#: the revision's parameter layout (its kernels/layout.py), set by main
REV_LAYOUT = {}


def single_cases():
    ball = "ball"
    yield "solid paper", make_system("solid", "paper"), Harmonic(10.0, 1.0), {}
    yield "tmd physical 2 modes", make_system("tmd", "physical"), Harmonic(20.0, 1.0), {}
    yield "locked paper", make_system(ball, "paper", gap_m=0.5e-3, locked=True), \
        Harmonic(10.0, 1.0), {}
    yield "ball paper 0.1 mm", make_system(ball, "paper", gap_m=0.1e-3, friction=False), \
        Harmonic(10.0, 1.0), {}
    yield "ball paper 0.5 mm friction 20 N", make_system(ball, "paper", gap_m=0.5e-3,
                                                         friction=True), Harmonic(20.0, 0.98), {}
    yield "ball physical 2 modes friction", make_system(ball, "physical", gap_m=0.5e-3,
                                                        friction=True), Harmonic(20.0, 1.0), {}
    yield "ball physical 3 modes friction", make_system(ball, "physical", gap_m=0.1e-3,
                                                        friction=True, n_modes=3), \
        Harmonic(10.0, 1.02), {}
    yield "ball paper friction, stage loop", make_system(ball, "paper", gap_m=0.5e-3,
                                                         friction=True), \
        Harmonic(10.0, 1.0), {"stage_loop": True}
    yield "solid cut", make_system("solid", "paper"), Regenerative(depth_m=1e-3, rpm=1200.0), {}
    yield "ball physical cut", make_system(ball, "physical", gap_m=0.1e-3, friction=True), \
        Regenerative(depth_m=2e-3, rpm=1200.0, revolutions=2), {}


def setup(system, forcing, duration, init=None, record_every=10, strobe=True):
    return setup_run(system, forcing, duration, 1e-6, init, record_every, 0.8, strobe, "rk4")


def params(mod, p):
    """``p`` (or rows of it) as the kernel module ``mod`` takes it (the revision's in its
    layout)."""
    return p.copy() if mod is R1 else rev_params(p, REV_LAYOUT["L"])


def records(su):
    """Zeroed copies of the run's records (setup_run's are not zeroed)."""
    return [np.zeros_like(a) for a in (su.rec, su.imp, su.stick, su.stb)]


#: the timer of the kernel calls (--cpu-time: time.thread_time)
clock = time.perf_counter


def run_single(mod, su, stage_loop=False):
    p = su.p.copy()
    if stage_loop:
        p[L.STAGE_LOOP] = 1.0
    p = params(mod, p)
    out = [su.x.copy(), *records(su), su.met.copy()]
    x, rec, imp, stick, stb, met = out
    buf = None if su.buf is None else su.buf.copy()
    tic = clock()
    if mod is R1:  # the working tree's: the span and the records, each one description
        R1.run_rk4(p, x, R1.Steps(su.t0, su.dt, su.n_steps, su.steady_steps, su.record_every),
                   R1.Records(rec, imp, stick, stb, met), buf)
    else:
        mod.run_rk4(p, x, su.t0, su.dt, su.n_steps, su.steady_steps, su.record_every, rec, imp,
                    stick, stb, met, buf)
    return clock() - tic, out


def batch_arrays(jobs, duration):
    sus = [setup(s, f, duration, i, 0) for s, f, i in jobs]
    P = np.array([su.p for su in sus])
    X = np.array([su.x for su in sus])
    met = np.array([su.met for su in sus])
    imp = np.zeros((len(sus), max(len(su.imp) for su in sus), 3))
    stick = np.zeros((len(sus), max(len(su.stick) for su in sus), 2))
    stb = np.zeros((len(sus), max(len(su.stb) for su in sus), 5))
    return sus[0], (P, X, imp, stick, stb, met)


def run_batch(mod, su, arrays):
    P, X, imp, stick, stb, met = (a.copy() for a in arrays)
    P = params(mod, P)
    # the revision's metric vector: the working tree's first slots (the names agree; the
    # tree's later slots are its own), as its batch kernel checks the length
    size = REV_LAYOUT["L"].MET_SIZE if mod is not B1 else met.shape[1]
    m = np.ascontiguousarray(met[:, :size])
    tic = clock()
    if mod is B1:
        B1.run_rk4_batch(P, X, B1.Steps(su.t0, su.dt, su.n_steps, su.steady_steps),
                         B1.Records(np.zeros((len(P), 0, 6)), imp, stick, stb, m))
    else:
        mod.run_rk4_batch(P, X, su.t0, su.dt, su.n_steps, su.steady_steps, imp, stick, stb, m)
    elapsed = clock() - tic
    met[:, :size] = m
    return elapsed, [X, imp, stick, stb, met]


def batch_cases():
    def varied(system, nb):
        forces, ratios = (10.0, 20.0), (0.97, 1.0, 1.01, 1.04)
        pairs = [(f, r) for f in forces for r in ratios]
        return [(system, Harmonic(*pairs[j % 8]), Initial(0.2e-3 * (j % 3 - 1), 0.3 * (j % 2)))
                for j in range(nb)]
    for nb in (4, 16):
        for preset, nm in (("paper", 1), ("physical", 2)):
            for friction in (False, True):
                yield (f"ball {preset} friction {friction} B={nb}",
                       varied(make_system("ball", preset, gap_m=0.5e-3, friction=friction,
                                          n_modes=nm), nb))
            yield f"solid {preset} B={nb}", varied(make_system("solid", preset, n_modes=nm), nb)
            yield f"tmd {preset} B={nb}", varied(make_system("tmd", preset, n_modes=nm), nb)
            yield (f"locked {preset} B={nb}",
                   varied(make_system("ball", preset, gap_m=0.5e-3, locked=True, n_modes=nm), nb))


def compare(label, a, b):
    names = (("x", "rec", "imp", "stick", "strobe", "met") if len(a) == 6
             else ("x", "imp", "stick", "strobe", "met"))
    bad = [n for n, u, v in zip(names, a, b, strict=True)
           if not np.array_equal(u, v, equal_nan=True)]
    met = a[-1]
    info = (f"{int(met[..., L.N_IMP_ALL].sum())} impacts, "
            f"{int(met[..., L.N_STICK_REC].sum())} sticks, "
            f"{int(met[..., L.N_STROBE].sum())} strobe rows")
    print(f"  {label:38s} {'bit-identical' if not bad else 'DIFFERS: ' + ', '.join(bad)}"
          f"  ({info})")
    return not bad


def best_ns(run, mods, per_step: int, repeat: int) -> list[float]:
    """ns per step of ``run(mod)`` (its first result the wall time), old and new
    alternately, best of ``repeat``."""
    best = [np.inf, np.inf]
    for _ in range(repeat):
        for i, mod in enumerate(mods):
            best[i] = min(best[i], run(mod)[0])
    return [b / per_step * 1e9 for b in best]


def single_ns(R0, su, repeat: int) -> list[float]:
    return best_ns(lambda mod: run_single(mod, su), (R0, R1), su.n_steps, repeat)


def timing(R0, B0, repeat):
    print(f"\nspeed, old and new alternately, best of {repeat}:")
    for nm, gap, friction in ((1, 0.1e-3, False), (1, 0.5e-3, True), (2, 0.1e-3, False)):
        system = make_system("ball", "paper" if nm == 1 else "physical", gap_m=gap,
                             friction=friction, n_modes=nm)
        ns = single_ns(R0, setup(system, Harmonic(10.0, 1.0), 2.0, record_every=0,
                                 strobe=False), repeat)
        print(f"  run_rk4 ball {nm} mode(s), gap {gap * 1e3:.1f} mm, friction "
              f"{'on ' if friction else 'off'}, 2 s: old {ns[0]:.1f} ns/step, new {ns[1]:.1f} "
              f"ns/step (old/new {ns[0] / ns[1]:.2f}x)")
    ns = single_ns(R0, setup(make_system("solid", "paper"), Regenerative(depth_m=1e-3, rpm=1200.0),
                             1.0, record_every=0, strobe=False), repeat)
    print(f"  run_rk4 solid bar cut, 1 s: old {ns[0]:.1f} ns/step, new {ns[1]:.1f} ns/step "
          f"(old/new {ns[0] / ns[1]:.2f}x)")
    system = make_system("ball", "paper", gap_m=0.5e-3, friction=True)
    jobs = [(system, Harmonic(10.0 + j % 2 * 10.0, 0.97 + 0.005 * j), None) for j in range(16)]
    su, arrays = batch_arrays(jobs, 0.3)
    ns = best_ns(lambda mod: run_batch(mod, su, arrays), (B0, B1), su.n_steps * 16, repeat)
    print(f"  run_rk4_batch ball paper friction B=16, 0.3 s: old {ns[0]:.1f} ns/run-step, "
          f"new {ns[1]:.1f} (old/new {ns[0] / ns[1]:.2f}x)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="git revision of the kernels to compare against")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--duration", type=float, default=0.2)
    ap.add_argument("--skip-timing", action="store_true")
    ap.add_argument("--skip-check", action="store_true")
    ap.add_argument("--cpu-time", action="store_true",
                    help="time the thread's CPU time instead of the wall clock")
    args = ap.parse_args()
    global clock
    if args.cpu_time:
        clock = time.thread_time
    export(args.rev)
    R0 = importlib.import_module("boringbar_rev.kernels.rk4")
    REV_LAYOUT["L"] = importlib.import_module("boringbar_rev.kernels.layout")
    B0 = importlib.import_module("boringbar_rev.kernels.rk4_batch")

    print(f"machine: {describe()}; RK4 kernels at "
          f"{args.rev} (old) against the working tree (new); timed by the "
          f"{'thread CPU time' if args.cpu_time else 'wall clock'}")
    if not args.skip_check:
        check(args.duration, R0, B0)
    if not args.skip_timing:
        timing(R0, B0, args.repeat)


def check(duration, R0, B0):
    ok = True
    print(f"run_rk4, {duration} s at dt = 1e-6:")
    for label, system, forcing, kw in single_cases():
        su = setup(system, forcing, duration)
        a = run_single(R0, su, **kw)[1]
        b = run_single(R1, su, **kw)[1]
        ok &= compare(label, a, b)
    print(f"run_rk4_batch, {duration / 2} s:")
    for label, jobs in batch_cases():
        su, arrays = batch_arrays(jobs, duration / 2)
        a = run_batch(B0, su, arrays)[1]
        b = run_batch(B1, su, arrays)[1]
        ok &= compare(label, a, b)
    print("ALL BIT-IDENTICAL" if ok else "SOME RESULTS DIFFER")


if __name__ == "__main__":
    main()
