"""``simulate`` of the working tree against a git revision's, through the public call.

    .venv/bin/python benchmarks/bench_simulate_rev.py REV [--repeat 5] [--grid-repeat 3]
                                                      [--skip-grid] [--history] [--per-case]

Exports ``src/boringbar`` at REV as the package ``boringbar_rev`` (``bench_exact_rev.export``;
a numba revision such as fb3fab0 needs numba in the environment, ``pip install
'numba==0.68.*'``, and compiles its kernels on the first run) and times each version's own
``simulate(system, forcing, duration 2 s, integrator=...)`` with its own ``make_system`` and
``Harmonic``: the thread's CPU time (``time.thread_time``: on a shared machine the wall
clock counts the time the process waits for a core), each timed call right after an untimed
one of the same version (a warm call, as in a sweep), REV and the working tree alternating,
best of ``--repeat``, the garbage collector off while they run (as ``timeit`` does: numba
fills the process's heap, whose collections would land on either version's calls).  Both
get ``record_every = 0`` (no history: REV's default and what the analyses ask for);
``--history`` gives each its own default instead (the working tree's records about 20000
history rows).

Inside each call, the kernel alone is timed too: the version's ``run_exact`` (its
``prepare`` done first, off that clock) or ``run_rk4``, as its simulate calls them (wrapped
by :meth:`Version.time_the_kernels`), so that each call's overhead (the call less its
kernel: the checks, the packing, the exact integrator's setup, the result) is measured in
that very call, whatever the load did to the calls before and after; the table gives the
least (the machine at its quietest) and the median over the calls.

- first, the working tree's exact calls on the named cases alone, before REV is loaded;
- named published cases with a known impact pattern (no impact, sticking, symmetric,
  asymmetric, non-uniform), both integrators (the exact integrator's runs repeated
  :data:`EXACT_REPEAT` times as often); each run's pattern from both versions,
  and whether their final states and metrics are the same bits;
- the 48 published harmonic cases (presets paper and physical, gaps 0.1 and 0.5 mm,
  friction off and on, 10 and 20 N, Omega/omega_n 0.95, 1.00 and 1.05; the ball damper
  from rest) as totals per integrator (best of ``--grid-repeat`` each; each case's calls
  with both integrators one after the other, so that the machine's drift weighs on both
  alike), and the RK4/exact ratio of each version's calls over them; ``--per-case``: each
  case's calls as well.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import inspect
import itertools
import math
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_exact_rev import export  # noqa: E402
from machine import describe  # noqa: E402

import boringbar  # noqa: E402
from boringbar.simulate import engine, kernels  # noqa: E402

DURATION_S = 2.0
DT_S = 1e-6
STEADY_FRACTION = 0.8
INTEGRATORS = ("exact", "rk4")
#: the exact integrator's runs, 10-40 times shorter than RK4's, are repeated this many
#: times as often: the overhead of a call is a few percent of them, and noise is not
EXACT_REPEAT = 8

#: (label, preset, gap (m), friction, force (N), Omega/omega_n): published cases whose runs
#: take each pattern with both integrators (benchmarks/bench_grid.py's grid)
NAMED = (
    ("no impact", "physical", 0.5e-3, False, 10.0, 1.00),
    ("sticking", "paper", 0.5e-3, True, 20.0, 1.00),
    ("symmetric", "paper", 0.1e-3, False, 10.0, 1.02),
    ("symmetric, 2 modes", "physical", 0.1e-3, False, 20.0, 1.00),
    ("asymmetric", "paper", 0.1e-3, False, 20.0, 1.05),
    ("non-uniform", "physical", 0.1e-3, False, 10.0, 1.00),
)

#: the 48 published harmonic cases
GRID = tuple(
    (f"{preset} gap {gap * 1e3:.1f} mm friction {'on' if fr else 'off'} {force:g} N r {r:.2f}",
     preset, gap, fr, force, r)
    for preset, gap, fr, force, r in itertools.product(
        ("paper", "physical"), (0.1e-3, 0.5e-3), (False, True), (10.0, 20.0),
        (0.95, 1.00, 1.05)))

clock = time.thread_time


def _named(fn, name: str, old_name: str) -> str:
    """``name`` if ``fn`` takes it, else the name an older version gave it."""
    return name if name in inspect.signature(fn).parameters else old_name


@dataclass
class Version:
    """One version's public calls, with the kernel timed inside each of them."""

    name: str
    make_system: object
    harmonic: type
    simulate: object
    module: object  # the module whose simulate calls run_exact and run_rk4 by these names
    prepare: object
    record_every: int | None = 0
    inner: float = 0.0  # CPU seconds of the last call's kernel

    def __post_init__(self):
        # the keywords' names, looked up once (inspect is slow beside a call)
        self.gap_kw = _named(self.make_system, "gap_m", "gap")
        self.duration_kw = _named(self.simulate, "duration_s", "duration")
        self.time_the_kernels()

    def time_the_kernels(self) -> None:
        """The module's run_exact and run_rk4, as its simulate calls them, timed: the kernel
        alone (for the exact integrator its ``prepare`` done first, off the clock) inside
        the very call, so that call - kernel is that call's overhead."""
        run_exact, run_rk4, prepare = self.module.run_exact, self.module.run_rk4, self.prepare

        def timed_exact(p, *args, prep=None, **kwargs):  # (a revision's takes dt too)
            prep = prepare(p) if prep is None else prep
            tic = clock()
            out = run_exact(p, *args, prep=prep, **kwargs)
            self.inner = clock() - tic
            return out

        def timed_rk4(*args, **kwargs):
            tic = clock()
            run_rk4(*args, **kwargs)
            self.inner = clock() - tic

        self.module.run_exact, self.module.run_rk4 = timed_exact, timed_rk4

    def case(self, preset, gap, friction, force, ratio):
        """(system, forcing) of a ball damper case, by this version's own names."""
        return (self.make_system("ball", preset, **{self.gap_kw: gap, "friction": friction}),
                self.harmonic(force, ratio))

    def call(self, system, forcing, integrator, duration_s=DURATION_S):
        """The call and its run's impact pattern: the working tree classifies it when it
        is first read, REV in the call, so both pay for it here."""
        kw = {} if self.record_every is None else {"record_every": self.record_every}
        run = self.simulate(system, forcing, **{self.duration_kw: duration_s}, **kw,
                            integrator=integrator)
        run.pattern  # noqa: B018 (read for its cost)
        return run


def tree_version(history: bool) -> Version:
    return Version("tree", boringbar.make_system, boringbar.Harmonic, boringbar.simulate,
                   engine, kernels.prepare, None if history else 0)


def rev_version(rev: str) -> Version:
    """REV's package (a numba revision: its simulate in boringbar_rev/simulate.py, its
    kernels under boringbar_rev.kernels)."""
    export(rev)
    pkg = importlib.import_module("boringbar_rev")
    sim = importlib.import_module("boringbar_rev.simulate")
    exact = importlib.import_module("boringbar_rev.kernels.exact")
    return Version(rev, pkg.make_system, pkg.Harmonic, pkg.simulate, sim, exact.prepare, 0)


@dataclass
class Timed:
    """One case and integrator, per version: the best call and kernel (CPU s), each call's
    overhead (call - its kernel), and the last run."""

    call: list
    kernel: list
    overhead: list
    runs: list

    def overhead_ms(self, i: int, q: float) -> float:
        return float(np.percentile(self.overhead[i], q)) * 1e3


def time_case(versions, spec, integrator, repeat) -> Timed:
    """Each version's call, alternating, best of ``repeat`` (RK4; the exact integrator
    :data:`EXACT_REPEAT` times as many); each timed call right after an untimed one of the
    same version."""
    repeat *= EXACT_REPEAT if integrator == "exact" else 1
    cases = [v.case(*spec) for v in versions]
    nv = len(versions)
    t = Timed([np.inf] * nv, [np.inf] * nv, [[] for _ in range(nv)], [None] * nv)
    gc.collect()
    gc.disable()  # as timeit does: a collection's cost is the whole process's heap (numba's)
    try:
        for _ in range(repeat):
            for i, (v, (system, forcing)) in enumerate(zip(versions, cases, strict=True)):
                v.call(system, forcing, integrator)
                tic = clock()
                t.runs[i] = v.call(system, forcing, integrator)
                call = clock() - tic
                t.call[i], t.kernel[i] = min(t.call[i], call), min(t.kernel[i], v.inner)
                t.overhead[i].append(call - v.inner)
    finally:
        gc.enable()
    return t


def same_value(a, b) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a)
                      and math.isnan(b))


def same_bits(a, b) -> bool:
    """The two runs' final states and the metrics both have are the same bits."""
    return (np.array_equal(a.final.x, b.final.x)
            and all(same_value(a.metrics[k], b.metrics[k]) for k in a.metrics if k in b.metrics))


def pattern_name(run) -> str:
    return run.pattern.name if run.pattern is not None else "-"


def warm_up(versions) -> None:
    """A short run of each version, integrator and mode count (numba compiles here)."""
    tic = time.perf_counter()
    for v in versions:
        for preset in ("paper", "physical"):
            system, forcing = v.case(preset, 0.5e-3, True, 10.0, 1.0)
            for integrator in INTEGRATORS:
                v.call(system, forcing, integrator, duration_s=1e-3)
    print(f"warm-up (numba's compile or cache load): {time.perf_counter() - tic:.1f} s")


def named_table(versions, repeat) -> bool:
    old, new = versions
    print(f"\nnamed cases, 2 s runs, ms of CPU time, best of {repeat} (exact: "
          f"{EXACT_REPEAT * repeat}); kernel: timed inside the call; overhead: each call "
          "less its kernel, the least and the median over the calls")
    print(f"{'':20s} {'':5s} {'':36s} {old.name + ' (old)':^32s} {'tree (new)':^32s}")
    print(f"{'case':20s} {'integ':5s} {'pattern old / new':36s}"
          + f" {'call':>7s} {'kernel':>7s} {'ovh min':>8s} {'ovh med':>8s}" * 2
          + f" {'old/new: call':>13s} {'kernel':>6s}  bits")
    agree = True
    for label, *spec in NAMED:
        for integrator in INTEGRATORS:
            t = time_case(versions, spec, integrator, repeat)
            pats = [pattern_name(r) for r in t.runs]
            agree &= pats[0] == pats[1]
            cols = "".join(f" {t.call[i] * 1e3:7.2f} {t.kernel[i] * 1e3:7.2f} "
                           f"{t.overhead_ms(i, 0):8.3f} {t.overhead_ms(i, 50):8.3f}"
                           for i in range(2))
            print(f"{label:20s} {integrator:5s} {' / '.join(pats):36s}{cols} "
                  f"{t.call[0] / t.call[1]:12.2f}x {t.kernel[0] / t.kernel[1]:5.2f}x  "
                  f"{'same' if same_bits(*t.runs) else 'DIFFER'}", flush=True)
    print("patterns: " + ("the two versions agree on every case" if agree else "SOME DIFFER"))
    return agree


def grid_totals(versions, repeat, per_case: bool = False) -> dict:
    """{integrator: (call totals, kernel totals)} over the 48 cases, in seconds; prints
    them with the overhead per call (each case's least and median, averaged), and
    (``per_case``) each case's calls and their ratio first.  Each case's calls with both
    integrators are made one after the other, so that the machine's drift over the run
    (up to 2x from minute to minute on a shared VM) weighs on both integrators alike."""
    tot = {i: {"calls": np.zeros(2), "kerns": np.zeros(2), "ovh": np.zeros((2, 2)),
               "same": 0, "agree": 0} for i in INTEGRATORS}
    for label, *spec in GRID:
        for integrator in INTEGRATORS:
            t = time_case(versions, spec, integrator, repeat)
            if per_case:
                print(f"    {integrator:5s} {label:48s} {t.call[0] * 1e3:7.2f} "
                      f"{t.call[1] * 1e3:7.2f} ms {t.call[0] / t.call[1]:5.2f}x  "
                      f"{pattern_name(t.runs[1])}", flush=True)
            a = tot[integrator]
            a["calls"] += t.call
            a["kerns"] += t.kernel
            a["ovh"] += [[t.overhead_ms(i, q) / len(GRID) for q in (0, 50)] for i in range(2)]
            a["same"] += same_bits(*t.runs)
            a["agree"] += pattern_name(t.runs[0]) == pattern_name(t.runs[1])
    out = {}
    for integrator, a in tot.items():
        calls, kerns, ovh = a["calls"], a["kerns"], a["ovh"]
        out[integrator] = (calls, kerns)
        print(f"  {integrator:5s} calls: {versions[0].name} {calls[0]:.3f} s, tree "
              f"{calls[1]:.3f} s ({calls[0] / calls[1]:.2f}x); kernels: {kerns[0]:.3f} s, "
              f"{kerns[1]:.3f} s ({kerns[0] / kerns[1]:.2f}x); overhead per call (least, "
              f"median): {ovh[0, 0]:.3f}, {ovh[0, 1]:.3f} ms and {ovh[1, 0]:.3f}, "
              f"{ovh[1, 1]:.3f} ms; {a['same']} of {len(GRID)} same bits, patterns agree on "
              f"{a['agree']}", flush=True)
    return out


def grid_ratios(versions, totals) -> None:
    (rc, rk), (ec, ek) = totals["rk4"], totals["exact"]
    for i, v in enumerate(versions):
        print(f"  RK4/exact over the grid, {v.name:8s}: through simulate {rc[i] / ec[i]:5.2f}x, "
              f"the kernels {rk[i] / ek[i]:5.2f}x")


def tree_alone(tree: Version, repeat: int) -> None:
    """The working tree's exact calls on the named cases before REV is loaded (numba's
    kernels and heap beside it make the tree's calls' overhead 0.1-0.2 ms larger)."""
    print(f"\nthe working tree alone (REV not loaded yet), exact, best of "
          f"{EXACT_REPEAT * repeat}: call, kernel, overhead least and median, ms")
    for label, *spec in NAMED:
        t = time_case([tree], spec, "exact", repeat)
        print(f"  {label:20s} {pattern_name(t.runs[0]):22s} {t.call[0] * 1e3:6.2f} "
              f"{t.kernel[0] * 1e3:6.2f} {t.overhead_ms(0, 0):6.3f} {t.overhead_ms(0, 50):6.3f}",
              flush=True)


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="git revision to compare against (a numba one: fb3fab0)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--grid-repeat", type=int, default=3)
    ap.add_argument("--skip-grid", action="store_true")
    ap.add_argument("--per-case", action="store_true",
                    help="each grid case's calls (REV's, the tree's) and their ratio")
    ap.add_argument("--history", action="store_true",
                    help="each version's default record_every (the tree's: ~20000 rows)")
    args = ap.parse_args()
    print(f"REV {args.rev} (old) against the working tree (new); thread CPU time; "
          f"{uptime()}\nmachine: {describe()}")
    tree = tree_version(args.history)
    warm_up([tree])
    tree_alone(tree, args.repeat)
    versions = [rev_version(args.rev), tree]
    warm_up(versions)
    named_table(versions, args.repeat)
    if not args.skip_grid:
        print(f"\nthe 48 published harmonic cases, best of {args.grid_repeat} each (exact: "
              f"{EXACT_REPEAT * args.grid_repeat}):")
        grid_ratios(versions, grid_totals(versions, args.grid_repeat, args.per_case))
    print(uptime())


if __name__ == "__main__":
    main()
