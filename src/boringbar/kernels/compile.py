"""Compilation of the kernels: a notice before a long compile, and all of it ahead of time.

Every kernel is compiled by numba on its first use on a machine, one
specialisation per mode count (kernels/rk4.py), per mode count, case and
batch size (kernels/rk4_batch.py), and twice for the exact integrator
(kernels/exact/driver.py: harmonic forcing, and regenerative cuts), and cached
on disk afterwards (``cache=True``; the lock of kernels/cache.py makes the
cache safe for several processes).

:func:`announce` wraps kernel calls: when numba is about to compile (its
``numba:compile`` event, which fires only on a cache miss, never when a
specialisation loads from disk) it prints one line to stderr saying what
compiles and about how long it takes (:data:`ESTIMATE_S`, measured cold).

:func:`compile_all` compiles every specialisation the package uses, in
parallel processes, so that a cluster image can be warmed
(``boringbar compile``).  :func:`compile_in_background` starts one
specialisation's compile in another process while this one goes on (the
published study compiles the exact kernel so while its first steps run on RK4);
:func:`await_background`, called before that kernel runs, waits for it, so the
kernel then loads from the cache instead of compiling a second time.

This module imports nothing from the layers above the kernels.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import sys
import threading
import time
from collections.abc import Callable, Iterable
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from typing import NamedTuple

import numpy as np
from numba.core import event

from boringbar.kernels import layout as L
from boringbar.kernels.exact import run_exact
from boringbar.kernels.rk4 import run_rk4
from boringbar.kernels.rk4_batch import LANES, run_rk4_batch

#: the kinds of kernel :func:`compile_all` takes
KINDS = ("exact", "rk4", "rk4_batch")
_CASES = {L.SOLID: "solid", L.BALL: "ball", L.TMD: "tmd", L.LOCKED: "locked"}
_CASE_WORDS = {"solid": "solid bar", "ball": "ball damper", "tmd": "tuned mass damper",
               "locked": "locked ball"}
#: the mode count standing for the run-time-n kernels (4 to NMAX modes share one)
_ANY = 4


class Spec(NamedTuple):
    """One compiled specialisation: ``kind`` (of :data:`KINDS`), the mode count (4: the
    kernel shared by 4 to NMAX modes), the case ("" where the kernel takes any; for the
    exact kernel, "cut": its regenerative cut's kernel) and the batch size (0: a single
    run)."""

    kind: str
    modes: int = 0
    case: str = ""
    size: int = 0

    @property
    def name(self) -> str:
        if self.kind == "exact":
            return "exact" + (" cut" if self.case == "cut" else "")
        modes = f"{self.modes}-{L.NMAX}" if self.modes == _ANY else str(self.modes)
        parts = [self.kind, f"n={modes}"] + ([self.case] if self.case else [])
        return " ".join(parts + ([f"x{self.size}"] if self.size else []))

    def describe(self) -> str:
        """What compiles, in words."""
        if self.kind == "exact":
            return "the exact integrator" + (" for cuts" if self.case == "cut" else "")
        modes = (f"{self.modes} to {L.NMAX} modes" if self.modes == _ANY else
                 f"{self.modes} mode" + ("s" if self.modes > 1 else ""))
        case = f", {_CASE_WORDS[self.case]}" if self.case else ""
        if self.kind == "rk4":
            return f"the RK4 kernel ({modes}{case})"
        return f"the lock-step RK4 kernel ({self.size} runs, {modes}{case})"


def specs(kinds: Iterable[str] = KINDS) -> list[Spec]:
    """Every specialisation of ``kinds`` that the package's entry points dispatch to.

    ``exact``: the harmonic kernel and the regenerative cut's (kernels/exact/driver.py).
    ``rk4``: one kernel per mode count 1-3 (any case, harmonic or cutting), one for
    4 to NMAX modes, and the harmonic ball damper's of 1 and 2 modes
    (kernels/rk4.py).  ``rk4_batch``: one per mode count 1-3 and case, and one for
    4 to NMAX modes, each compiled per batch size of ``LANES`` (kernels/rk4_batch.py;
    sweeps and basins pad their batches to these sizes).
    """
    kinds = tuple(kinds)
    for k in kinds:
        if k not in KINDS:
            raise ValueError(f"kind {k!r} is not one of {KINDS}")
    out = []
    if "exact" in kinds:
        out += [Spec("exact"), Spec("exact", case="cut")]
    if "rk4" in kinds:
        out += [Spec("rk4", n) for n in (1, 2, 3, _ANY)]
        out += [Spec("rk4", n, "ball") for n in (1, 2)]
    if "rk4_batch" in kinds:
        for size in LANES:
            out += [Spec("rk4_batch", n, case, size) for n in (1, 2, 3)
                    for case in _CASES.values()]
            out.append(Spec("rk4_batch", _ANY, "", size))
    return out


# --- measured cold compile times ---------------------------------------------------------
#: CPU seconds to compile each specialisation on an empty cache (``compile_all(workers=2)``
#: on the development machine's 2 cores, shared, 2026-11-24, numba 0.68.1, with
#: kernels/inline_copy.py); wall time is about this on an idle core.  Before
#: inline_copy.py: exact 129 s, rk4 15-20 s, rk4_batch 10-19 s (836 s in all, now 418 s).
#: The exact kernel measured again 2026-11-25 on the idle machine: 212 s
#: (benchmarks/compile_profile.py; docs/performance.md, "First use"); 118 s (the first
#: ``boringbar simulate``'s compiles, benchmarks/first_use.py) once numba's SSA, liveness
#: and inlining were made linear (kernels/ssa_blocks.py, live_bits.py, inline_copy.py);
#: then split in two kernels, each without the other forcing's code (exact/driver.py),
#: 91.0 s (harmonic) and 92.3 s (cut) by ``compile_one`` on an empty cache, side by side.
ESTIMATE_S: dict[str, float] = {
    "exact": 91.0, "exact cut": 92.3, "rk4 n=1": 9.9, "rk4 n=2": 9.7, "rk4 n=3": 7.7,
    "rk4 n=1 ball": 5.0, "rk4 n=4-8": 8.8, "rk4 n=2 ball": 6.0, "rk4_batch n=1 ball x16": 6.8,
    "rk4_batch n=1 locked x16": 7.3, "rk4_batch n=1 solid x16": 7.0,
    "rk4_batch n=1 tmd x16": 6.9, "rk4_batch n=1 ball x4": 6.5, "rk4_batch n=1 locked x4": 6.4,
    "rk4_batch n=1 solid x4": 6.7, "rk4_batch n=1 tmd x4": 6.8, "rk4_batch n=1 ball x8": 6.7,
    "rk4_batch n=1 locked x8": 8.6, "rk4_batch n=1 solid x8": 6.6, "rk4_batch n=1 tmd x8": 7.3,
    "rk4_batch n=2 ball x16": 6.6, "rk4_batch n=2 locked x16": 6.8,
    "rk4_batch n=2 solid x16": 6.4, "rk4_batch n=2 tmd x16": 8.2, "rk4_batch n=2 ball x4": 6.8,
    "rk4_batch n=2 locked x4": 6.2, "rk4_batch n=2 solid x4": 6.8, "rk4_batch n=2 tmd x4": 6.0,
    "rk4_batch n=2 ball x8": 7.3, "rk4_batch n=2 locked x8": 7.0,
    "rk4_batch n=2 solid x8": 6.8, "rk4_batch n=2 tmd x8": 7.1, "rk4_batch n=3 ball x16": 8.3,
    "rk4_batch n=3 locked x16": 6.8, "rk4_batch n=3 solid x16": 6.2,
    "rk4_batch n=3 tmd x16": 8.3, "rk4_batch n=3 ball x4": 5.0, "rk4_batch n=3 locked x4": 5.7,
    "rk4_batch n=3 solid x4": 5.9, "rk4_batch n=3 tmd x4": 5.1, "rk4_batch n=3 ball x8": 6.6,
    "rk4_batch n=3 locked x8": 7.0, "rk4_batch n=3 solid x8": 6.9, "rk4_batch n=3 tmd x8": 6.1,
    "rk4_batch n=4-8 x16": 9.8, "rk4_batch n=4-8 x4": 8.6, "rk4_batch n=4-8 x8": 8.5,
}
#: estimates of the specialisations not measured one by one, per kind
_KIND_ESTIMATE_S = {"exact": 91.0, "rk4": 10.0, "rk4_batch": 10.0}
#: compiles estimated under this many seconds get no notice
NOTICE_MIN_S = 2.0
_notices = {"on": True}


def notices(enabled: bool) -> bool:
    """Whether :func:`announce` prints at all (the command line's ``--quiet``: off).
    Returns the setting before, to restore."""
    before, _notices["on"] = _notices["on"], bool(enabled)
    return before


def estimate(spec: Spec) -> float:
    """The measured (or, for a specialisation not measured, its kind's) cold compile time, s."""
    return ESTIMATE_S.get(spec.name, _KIND_ESTIMATE_S[spec.kind])


def _spec_of(dispatcher, args) -> Spec | None:
    """The specialisation whose compilation a ``numba:compile`` event announces, from the
    compiled function's module and name (None: not one of the kernels)."""
    func = getattr(dispatcher, "py_func", None)
    module, name = getattr(func, "__module__", ""), getattr(func, "__name__", "")
    if module == "boringbar.kernels.exact" or module.startswith("boringbar.kernels.exact."):
        return Spec("exact", case="cut" if name == "_exact_cut" else "")
    if module == "boringbar.kernels.rk4":
        # _rk4_n1.._rk4_n3, _rk4_any, _rk4_ball1, _rk4_ball2
        if name == "_rk4_any":
            return Spec("rk4", _ANY)
        for prefix, case in (("_rk4_n", ""), ("_rk4_ball", "ball")):
            if name.startswith(prefix) and name[len(prefix):].isdigit():
                return Spec("rk4", int(name[len(prefix):]), case)
        return Spec("rk4", _ANY)
    if module == "boringbar.kernels.rk4_batch":
        # _b1_solid.._b3_locked, _b_any; the last argument's length is the batch size
        size = getattr(args[-1], "count", 0) if args else 0
        head, _, case = name[2:].partition("_")
        if head.isdigit() and case in _CASE_WORDS:
            return Spec("rk4_batch", int(head), case, size)
        return Spec("rk4_batch", _ANY, "", size)
    return None


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{max(5, int(round(seconds / 5)) * 5)} s"
    return f"{int(round(seconds / 60))} min"


def notice(spec: Spec) -> str:
    """The line :func:`announce` prints before ``spec`` compiles."""
    return (f"boringbar: compiling {spec.describe()} (first use on this machine, about "
            f"{_duration(estimate(spec))}; cached afterwards)")


class _Notice(event.Listener):
    """Prints :func:`notice` once, at the first kernel compile started by its own thread."""

    def __init__(self, stream):
        self.thread = threading.get_ident()
        self.stream = stream
        self.printed = False

    def on_start(self, ev):
        if self.printed or not _notices["on"] or threading.get_ident() != self.thread:
            return
        data = ev.data or {}
        spec = _spec_of(data.get("dispatcher"), data.get("args"))
        if spec is None or estimate(spec) < NOTICE_MIN_S:
            return
        self.printed = True
        print(notice(spec), file=self.stream or sys.stderr, flush=True)

    def on_end(self, ev):
        pass


@contextmanager
def announce(stream=None):
    """Context manager (or decorator, ``@announce()``) around kernel calls: if numba
    compiles a kernel inside it (a cache miss), one line on ``stream`` (stderr) says
    what and about how long, before it starts; nothing when the kernels load from the
    cache.  Only compilations started by the entering thread count (sweeps run kernels
    in threads); at most one line per use."""
    listener = _Notice(stream)
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


# --- compiling ahead of time ----------------------------------------------------------------
class Compiled(NamedTuple):
    """What :func:`compile_all` did for one specialisation."""

    name: str  #: :attr:`Spec.name`
    seconds: float  #: wall time of compiling (or loading) it
    status: str  #: "compiled" or "cached" (loaded from numba's cache on disk)
    cpu_seconds: float  #: CPU time of its process meanwhile (less load-dependent than wall)


def _params(n: int, case: int, regenerative: bool = False) -> np.ndarray:
    """A valid parameter vector of ``n`` modes and ``case`` for a few steps (the values do
    not matter to compilation; they only have to run)."""
    p = L.empty_params()
    p[L.N_MODES] = n
    p[L.CASE] = case
    p[L.FORCING] = L.REGENERATIVE if regenerative else L.HARMONIC
    p[L.F0] = 0.0 if regenerative else 10.0
    p[L.REACTION] = 1.0
    w = 2 * math.pi * 200.0 * (1.0 + 2.5 * np.arange(n)) ** 2
    p[L.OMEGA] = 0.0 if regenerative else w[0]
    p[L.M_:L.M_ + n] = 1.0
    p[L.K_:L.K_ + n] = w**2
    p[L.C_:L.C_ + n] = 2 * 0.01 * w
    p[L.PSI_L:L.PSI_L + n] = 1.0
    p[L.PSI_D:L.PSI_D + n] = 0.8
    p[L.PSI_A:L.PSI_A + n] = 0.8
    if case in (L.BALL, L.LOCKED):
        m = 0.05
        p[L.BALL_MASS] = m
        p[L.HALF_GAP] = 2.5e-4
        p[L.RESTITUTION] = 0.7
        p[L.FRICTION] = 0.5
        p[L.STATIC_FRICTION] = 0.5
        p[L.M_EFF] = 1.0 / (1.0 / m + float(np.sum(p[L.PSI_D:L.PSI_D + n] ** 2)))
        p[L.V_IMPACT] = 1e-3 * w[0] * 2.5e-4
        p[L.V_STICK] = 2 * p[L.V_IMPACT]
        p[L.STICK_MIN] = 1e-4
    elif case == L.TMD:
        p[L.TMD_MASS] = 0.05
        p[L.TMD_K] = 0.05 * w[0] ** 2
        p[L.TMD_C] = 2 * 0.1 * 0.05 * w[0]
    if regenerative:
        p[L.KR_B] = 1e5
        p[L.FEED] = 1e-4
        p[L.TAU] = 1e-3
        p[L.N_REV] = 1
        p[L.INTERP] = 1.0
    return p


def _outputs(nb: int = 0):
    """Empty output arrays of a single run (``nb`` = 0) or of a batch of ``nb``."""
    lead = (nb,) if nb else ()
    met = np.zeros(lead + (L.MET_SIZE,))
    met[..., L.STEADY_MAX_W] = -np.inf
    met[..., L.STEADY_MIN_W] = np.inf
    met[..., L.FIRST_ZERO_T] = -1.0
    return (np.zeros(lead + (100, 3)), np.zeros(lead + (100, 2)), np.zeros(lead + (4, 5)),
            met)


_CASE_IDS = {v: k for k, v in _CASES.items()}


def _run(spec: Spec) -> None:
    """Run ``spec``'s kernel for a few steps through its public entry point, which
    compiles it or loads it from the cache (the types are the ones real runs pass)."""
    dt, steps = 1e-6, 20
    if spec.kind == "exact":  # harmonic (a ball) or, "cut", a cut and its history tables
        regenerative = spec.case == "cut"
        p = _params(1, L.SOLID if regenerative else L.BALL, regenerative)
        x = np.zeros(4)
        imp, stick, strobe, met = _outputs()
        run_exact(p, x, 0.0, steps * dt, 0.0, dt, np.zeros((steps, 6)), imp, stick,
                  strobe, met, dt=dt)
    elif spec.kind == "rk4":
        case = _CASE_IDS.get(spec.case, L.SOLID)
        p = _params(spec.modes, case)
        x = np.zeros(2 * spec.modes + 2)
        imp, stick, strobe, met = _outputs()
        run_rk4(p, x, 0.0, dt, steps, 0, 1, np.zeros((steps, 6)), imp, stick, strobe, met)
    else:
        case = _CASE_IDS.get(spec.case, L.SOLID)
        P = np.array([_params(spec.modes, case)] * spec.size)
        x = np.zeros((spec.size, 2 * spec.modes + 2))
        imp, stick, strobe, met = _outputs(spec.size)
        run_rk4_batch(P, x, 0.0, dt, steps, 0, imp, stick, strobe, met)


def compile_one(spec: Spec) -> Compiled:
    """Compile ``spec`` (or load it from the cache) in this process."""
    tic, cpu = time.perf_counter(), time.process_time()
    with event.install_recorder("numba:compile") as rec:
        _run(spec)
    return Compiled(spec.name, time.perf_counter() - tic, "compiled" if rec.buffer else "cached",
                    time.process_time() - cpu)


def compile_all(kinds: Iterable[str] = KINDS, *, workers: int | None = None,
                progress: Callable[[Compiled, int, int], None] | None = None
                ) -> list[Compiled]:
    """Compile every specialisation of ``kinds`` (:func:`specs`) that is not in numba's
    cache yet, so that later runs on this machine (or image) load them from disk.

    ``workers`` processes compile independent specialisations at once (default: one
    per core; 1: in this process).  ``progress(compiled, done, total)`` is called in
    this process as each finishes.  Returns one :class:`Compiled` (name, seconds,
    "compiled" or "cached", CPU seconds) per specialisation, longest estimate first.  The cache is
    where numba puts it (``NUMBA_CACHE_DIR`` if set, else beside the kernels' sources).
    """
    todo = sorted(specs(kinds), key=estimate, reverse=True)
    workers = int(workers or os.cpu_count() or 1)
    out: list[Compiled] = []

    def done(c: Compiled):
        out.append(c)
        if progress is not None:
            progress(c, len(out), len(todo))

    if workers == 1 or len(todo) <= 1:
        for spec in todo:
            done(compile_one(spec))
        return out
    # spawned, not forked: a fresh numba in each process (the lock of kernels/cache.py
    # is applied there when this module's package is imported)
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(min(workers, len(todo)), mp_context=ctx) as pool:
        futures = [pool.submit(compile_one, spec) for spec in todo]
        for fut in as_completed(futures):
            done(fut.result())
    order = {s.name: i for i, s in enumerate(todo)}
    return sorted(out, key=lambda c: order[c.name])


# --- compiling in the background -------------------------------------------------------------
#: compiles this process started in another: spec name -> (pid, start, process)
_BACKGROUND: dict[str, tuple[int, float, multiprocessing.process.BaseProcess]] = {}
#: one waiting thread at a time (a sweep's threads may all reach their first exact run)
_AWAIT = threading.Lock()


def compile_in_background(spec: Spec = Spec("exact")) -> None:
    """Start compiling ``spec`` (or loading it from the cache) in a spawned process and
    return at once; a second call for the same spec does nothing.  The process is a
    daemon: if this one ends first (an error, Ctrl-C), it ends too."""
    if spec.name in _BACKGROUND:
        return
    proc = multiprocessing.get_context("spawn").Process(
        target=compile_one, args=(spec,), name=f"boringbar compile {spec.name}", daemon=True)
    proc.start()
    _BACKGROUND[spec.name] = (os.getpid(), time.perf_counter(), proc)


def await_background(spec: Spec = Spec("exact"), stream=None) -> bool:
    """Wait for :func:`compile_in_background`'s compile of ``spec`` if this process
    started one (one line on ``stream``, stderr, if it is still compiling).  Returns
    whether it finished well; if not, or if there was none, the kernel compiles (or
    loads) here as without it."""
    job = _BACKGROUND.get(spec.name)
    if job is None or job[0] != os.getpid():  # none, or started by the parent of a fork
        return False
    _, start, proc = job
    with _AWAIT:
        if proc.is_alive() and _notices["on"]:
            left = max(0.0, estimate(spec) - (time.perf_counter() - start))
            print(f"boringbar: waiting for {spec.describe()}, compiling in another process "
                  f"(first use on this machine, about {_duration(left)} more; cached "
                  "afterwards)", file=stream or sys.stderr, flush=True)
        proc.join()
    return proc.exitcode == 0
