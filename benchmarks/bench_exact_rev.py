"""The exact kernel against its own version at a git revision, in one process.

    .venv/bin/python benchmarks/bench_exact_rev.py REV [--repeat 7]
    .venv/bin/python benchmarks/bench_exact_rev.py REV --grid [--repeat 5]

Exports ``src/boringbar`` at REV into a temporary directory as the package
``boringbar_rev`` (its imports renamed, so both versions compile side by side;
a numba revision compiles on its first run, about 2 minutes, and needs numba in the
environment: ``pip install 'numba==0.68.*'``), then times ``run_exact`` of both (the run
packed by the working tree's ``setup_run``, its parameter vector moved into the revision's
layout for the revision's kernel: :func:`rev_params`)
on the harmonic cases of ``bench_exact.py`` (interleaved, best of
``--repeat``, the per-run ``prepare`` excluded and timed apart), with RK4 at
dt = 1e-6 as the machine's yardstick, and compares the results: metrics, final
state and impacts, bit for bit or the largest relative difference.

``--grid``: the 80 published harmonic cases of ``bench_grid.py`` instead (2 s runs from
rest), old and new alternating case by case, best of ``--repeat``; prints the totals of
the kernels' CPU times (``prepare`` excluded, as the per-run setup is timed apart) and how
many cases are bit-identical.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_exact import CASES, orbit_start  # noqa: E402
from bench_grid import cases as grid_cases  # noqa: E402
from machine import describe  # noqa: E402

from boringbar import Harmonic, make_system, simulate  # noqa: E402
from boringbar.simulate import kernels as E  # noqa: E402
from boringbar.simulate import layout as L  # noqa: E402
from boringbar.simulate.engine import setup_run  # noqa: E402
from boringbar.simulate.kernels import run_rk4  # noqa: E402

#: the revision's parameter layout (its kernels/layout.py), set by main
REV_LAYOUT = {}


def export(rev: str) -> Path:
    """src/boringbar at ``rev`` as the package boringbar_rev (cached per commit)."""
    sha = subprocess.run(["git", "rev-parse", rev], cwd=HERE, capture_output=True, text=True,
                         check=True).stdout.strip()
    root = Path(tempfile.gettempdir()) / f"boringbar_rev_{sha[:12]}"
    pkg = root / "boringbar_rev"
    if not pkg.exists():
        root.mkdir(parents=True, exist_ok=True)
        tar = root / "src.tar"
        with open(tar, "wb") as fh:
            subprocess.run(["git", "archive", sha, "src/boringbar"], cwd=HERE.parent, stdout=fh,
                           check=True)
        with tarfile.open(tar) as tf:
            tf.extractall(root)
        (root / "src" / "boringbar").rename(pkg)
        for f in pkg.rglob("*.py"):
            s = f.read_text()
            s = re.sub(r"\bfrom boringbar([ .])", r"from boringbar_rev\1", s)
            s = re.sub(r"\bimport boringbar\b", "import boringbar_rev", s)
            f.write_text(s)
    sys.path.insert(0, str(root))
    return root


#: the working tree's slots that nothing reads unless the slot named beside them is on
INERT = {"NOISE_INTERVAL": "NOISE_STD", "NOISE_SEED": "NOISE_STD", "ROLL_STATIC": "ROLL",
         "ROLL_KINETIC": "ROLL", "ROLL_BAND": "ROLL", "CONTACT_ALPHA": "CONTACT_K"}


def rev_params(p: np.ndarray, L0) -> np.ndarray:
    """``p`` (rows of ``p``) packed by the working tree, in the layout ``L0`` of a
    revision's kernels, slot by slot by name: each of the revision's scalar slots
    (``L0._SCALARS``) and per-mode blocks takes the working tree's slot of that name.  The
    tree's scalar slots the revision lacks (the cut law, the force noise, a Hertz contact,
    a rolling ball, ...) must hold 0 (or be :data:`INERT`, their feature off), and its
    force's mode shape PSI_F must be PSI_L (one bending plane), so that the run is one the
    revision can make."""
    if L0.P_SIZE == L.P_SIZE:
        return p
    used = [k for k in L.PARAM_NAMES if k not in L0._SCALARS
            and not (k in INERT and np.all(p[..., getattr(L, INERT[k])] == 0.0))
            and np.any(p[..., getattr(L, k)] != 0.0)]
    n = L.NMAX
    if (used or L0.NMAX != n
            or np.any(p[..., L.PSI_F:L.PSI_F + n] != p[..., L.PSI_L:L.PSI_L + n])):
        raise ValueError("the run uses slots the revision's parameter layout lacks: "
                         + ", ".join(used))
    out = np.zeros(p.shape[:-1] + (L0.P_SIZE,))
    for k in L0._SCALARS:
        out[..., getattr(L0, k)] = p[..., getattr(L, k)]
    for k in ("M_", "K_", "C_", "PSI_L", "PSI_D", "PSI_A"):
        out[..., getattr(L0, k):getattr(L0, k) + n] = p[..., getattr(L, k):getattr(L, k) + n]
    return out


def params(mod, p: np.ndarray) -> np.ndarray:
    """``p`` as the kernel module ``mod`` takes it (the revision's in its layout)."""
    return p if mod is E else rev_params(p, REV_LAYOUT["L"])


def cases():
    for label, preset, kw, force, ratio, periodic in CASES:
        s = make_system("ball", preset, **kw)
        f = Harmonic(force, ratio)
        dur, dt, init = 2.0, 1e-6, None
        if periodic == "orbit":
            orbit, start = orbit_start(s, force)
            period = 2 * orbit.system.half_period
            init, dur, dt = start, 5 * round(2.0 / period / 5) * period, period / 2000
        elif periodic == "settled":
            init = simulate(s, f, integrator="exact").final
        yield label, setup_run(s, f, dur, dt, init, 0, 0.8, False, "exact")


def fresh(su, mod=E):
    """The run's inputs for ``mod``'s kernel, with zeroed records (setup_run's are not)."""
    return (params(mod, su.p), su.x.copy(), np.zeros_like(su.rec), np.zeros_like(su.imp),
            np.zeros_like(su.stick), np.zeros_like(su.stb), su.met.copy())


def exact_call(mod, su, inputs, prep, record_every: int) -> None:
    """``mod``'s run_exact over the span of ``su`` on ``inputs`` (:func:`fresh`'s): the
    working tree's given its Steps and Records, a revision's its times and arrays."""
    p, x, rec, imp, stick, stb, met = inputs
    if mod is E:
        E.run_exact(p, x, E.Steps(su.t0, su.dt, su.n_steps, su.steady_steps, record_every),
                    E.Records(rec, imp, stick, stb, met), prep=prep)
    else:
        mod.run_exact(p, x, su.t0, su.t0 + su.n_steps * su.dt, su.t0 + su.steady_steps * su.dt,
                      record_every * su.dt, rec, imp, stick, stb, met, prep=prep, dt=su.dt)


def run(mod, su, prep):
    inputs = fresh(su, mod)
    tic = time.perf_counter()
    exact_call(mod, su, inputs, prep, su.record_every)
    _, x, _, imp, _, _, met = inputs
    return time.perf_counter() - tic, met, x, imp


def rk4(su):
    s2 = setup_run(su.system, su.forcing, 2.0, 1e-6, None, 0, 0.8, False, "rk4")
    p, x, rec, imp, stick, stb, met = fresh(s2)
    tic = time.perf_counter()
    run_rk4(p, x, E.Steps(s2.t0, s2.dt, s2.n_steps, s2.steady_steps),
            E.Records(rec, imp, stick, stb, met), s2.buf)
    return time.perf_counter() - tic


def cpu_run(mod, su, prep):
    inputs = fresh(su, mod)
    tic = time.process_time()
    exact_call(mod, su, inputs, prep, 0)
    _, x, _, imp, stick, stb, met = inputs
    return time.process_time() - tic, (x, met, imp, stick, stb)


def grid(E0, repeat: int) -> None:
    """The 80-case grid: CPU seconds of each kernel, best of ``repeat``, and bit identity."""
    total, same = [0.0, 0.0], 0
    sus = [(label, setup_run(s, f, 2.0, 1e-6, None, 0, 0.8, False, "exact"))
           for label, s, f in grid_cases()]
    for label, su in sus:
        preps = (E0.prepare(params(E0, su.p)), E.prepare(su.p))
        best, outs = [np.inf, np.inf], [None, None]
        for _ in range(repeat):
            for i, mod in enumerate((E0, E)):
                t, outs[i] = cpu_run(mod, su, preps[i])
                best[i] = min(best[i], t)
        ok = all(np.array_equal(a, b, equal_nan=True) for a, b in zip(*outs, strict=True))
        same += ok
        total = [total[0] + best[0], total[1] + best[1]]
        print(f"  {label:48s} old {best[0] * 1e3:7.2f} ms  new {best[1] * 1e3:7.2f} ms  "
              f"{'bit-identical' if ok else 'DIFFERS'}", flush=True)
    print(f"\n80-case grid, kernel CPU time: old {total[0]:.3f} s, new {total[1]:.3f} s, "
          f"old/new {total[0] / total[1]:.2f}; {same} of {len(sus)} cases bit-identical")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rev", help="git revision of the kernel to compare against")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--grid", action="store_true", help="the 80-case grid of bench_grid.py")
    args = ap.parse_args()
    export(args.rev)
    E0 = importlib.import_module("boringbar_rev.kernels.exact")
    REV_LAYOUT["L"] = importlib.import_module("boringbar_rev.kernels.layout")
    if args.grid:
        print(f"machine: {describe()}; exact kernel "
              f"at {args.rev} (old) against the working tree (new), best of {args.repeat}")
        grid(E0, args.repeat)
        return

    print(f"machine: {os.cpu_count()} cores; exact kernel at {args.rev} (old) against the "
          "working tree (new), best of", args.repeat)
    for label, su in cases():
        tic = time.perf_counter()
        prep0 = E0.prepare(params(E0, su.p))
        tp0 = time.perf_counter() - tic
        tic = time.perf_counter()
        prep1 = E.prepare(su.p)
        tp1 = time.perf_counter() - tic
        run(E0, su, prep0)
        run(E, su, prep1)
        b0 = b1 = br = np.inf
        for _ in range(args.repeat):
            t, m0, x0, i0 = run(E0, su, prep0)
            b0 = min(b0, t)
            t, m1, x1, i1 = run(E, su, prep1)
            b1 = min(b1, t)
            br = min(br, rk4(su))
        ev = m1[L.N_EVENTS]
        if np.array_equal(m0, m1) and np.array_equal(x0, x1) and np.array_equal(i0, i1):
            same = "bit-identical"
        else:
            rel = np.max(np.abs(m1 - m0) / np.maximum(np.abs(m0), 1e-300))
            same = (f"metrics: {np.count_nonzero(m0 != m1)} differ, by {rel:.1e} relative "
                    f"at most; "
                    f"final state {'equal' if np.array_equal(x0, x1) else 'differs'}, "
                    f"impacts {'equal' if np.array_equal(i0, i1) else 'differ'}")
        print(f"\n{label} ({int(ev)} events)")
        print(f"  rk4 dt=1e-6 {br * 1e3:7.2f} ms   exact old {b0 * 1e3:6.2f} ms   new "
              f"{b1 * 1e3:6.2f} ms   new/old speed-up {b0 / b1:4.2f}x   rk4/exact "
              f"{br / b0:4.1f}x -> {br / b1:4.1f}x   {b1 / ev * 1e9:5.0f} ns per event")
        print(f"  prepare {tp0 * 1e3:.2f} / {tp1 * 1e3:.2f} ms   {same}")


if __name__ == "__main__":
    main()
