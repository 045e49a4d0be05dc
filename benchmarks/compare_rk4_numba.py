"""The C++ RK4 kernels (boringbar._core) against the numba ones, bit for bit.

    PYTHONPATH=src .venv/bin/python benchmarks/compare_rk4_numba.py [--duration 0.02]

Builds a spread of runs through boringbar.simulate's own packing (``_setup``: ``pack``,
``initial_state``, the record arrays), runs each through numba's ``run_rk4`` /
``run_rk4_batch`` and through ``_core.run_rk4`` / ``_core.run_rk4_batch`` on copies of
the same inputs, and prints, per case and output, whether the two are bitwise equal
(float64 bit patterns, so -0.0 != 0.0 and NaNs compare by payload) or the largest
difference.  Batches are also compared with the C++ single run of each of their runs.
Exits 1 if anything differs.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from boringbar import Harmonic, Initial, _core, make_system
from boringbar.kernels import layout as L
from boringbar.kernels.rk4 import run_rk4 as numba_run
from boringbar.kernels.rk4_batch import LANES
from boringbar.kernels.rk4_batch import run_rk4_batch as numba_batch
from boringbar.model.forcing import Regenerative
from boringbar.simulate import _setup

OUTPUTS = ("x", "met", "rec", "imp", "stick", "strobe", "buf")
RATTLE = Initial(tip_velocity=0.1, ball_velocity=0.5)


def diff(a: np.ndarray, b: np.ndarray) -> str:
    """'=' if bitwise equal, else the largest absolute difference (and where)."""
    if a.shape != b.shape:
        return f"shape {a.shape} vs {b.shape}"
    if np.array_equal(a.view(np.uint64), b.view(np.uint64)):
        return "="
    d = np.abs(a - b)
    d = np.where(np.isnan(d), np.inf, d)
    i = np.unravel_index(int(np.argmax(d)), a.shape)
    return f"DIFF max {d[i]:.3g} at {i} ({a[i]!r} vs {b[i]!r})"


def arrays(su):
    buf = su.buf if su.buf is not None else np.zeros((0, 2))
    return {"p": su.p.copy(), "x": su.x.copy(), "rec": su.rec.copy(), "imp": su.imp.copy(),
            "stick": su.stick.copy(), "strobe": su.stb.copy(), "met": su.met.copy(),
            "buf": buf.copy()}


def call(fn, su, a, chunks=1):
    """Run ``fn`` (numba's or C++'s run_rk4) on the arrays ``a``, in ``chunks`` calls."""
    n = su.n_steps
    done = 0
    for c in range(chunks):
        k = n // chunks if c < chunks - 1 else n - done
        steady = min(max(su.steady_steps - done, 0), k)
        fn(a["p"], a["x"], su.t0 + done * su.dt, su.dt, k, steady, su.record_every, a["rec"],
           a["imp"], a["stick"], a["strobe"], a["met"], a["buf"])
        done += k
    return a


def single_case(system, forcing, duration, dt=1e-6, initial=None, record_every=0,
                strobe=False, stage_loop=False, chunks=1):
    su = _setup(system, forcing, duration, dt, initial, record_every, 0.8, strobe, "rk4")
    if stage_loop:
        su.p[L.STAGE_LOOP] = 1.0
    a = call(numba_run, su, arrays(su), chunks)
    b = call(_core.run_rk4, su, arrays(su), chunks)
    res = {k: diff(a[k], b[k]) for k in OUTPUTS}
    info = (f"imp {int(b['met'][L.N_IMP_ALL])}, stick {int(b['met'][L.N_STICK_REC])}, "
            f"strobe {int(b['met'][L.N_STROBE])}, rec {int(b['met'][L.N_REC])}")
    return res, info


def batch_case(jobs, nb, duration, dt=1e-6, strobe=True):
    """numba vs C++ batch of the jobs (padded with the last to nb), and each C++ batch run
    vs the C++ single run."""
    sus = [_setup(s, f, duration, dt, i, 0, 0.8, strobe, "rk4") for s, f, i in jobs]
    sus += [sus[-1]] * (nb - len(sus))
    P = np.array([su.p for su in sus])
    first = sus[0]

    def inputs():
        return (P.copy(), np.array([su.x for su in sus]), np.array([su.met for su in sus]),
                np.zeros((nb, max(len(su.imp) for su in sus), 3)),
                np.zeros((nb, max(len(su.stick) for su in sus), 2)),
                np.zeros((nb, max(len(su.stb) for su in sus), 5)))

    out = {}
    for name, fn in (("numba", numba_batch), ("cpp", _core.run_rk4_batch)):
        Pc, X, met, imp, stick, stb = inputs()
        fn(Pc, X, first.t0, dt, first.n_steps, first.steady_steps, imp, stick, stb, met)
        out[name] = {"x": X, "met": met, "imp": imp, "stick": stick, "strobe": stb}
    res = {k: diff(out["numba"][k], out["cpp"][k]) for k in ("x", "met", "imp", "stick",
                                                               "strobe")}
    # each run of the C++ batch against the C++ single run
    worst = "="
    for r, su in enumerate(sus):
        a = arrays(su)
        a["imp"] = np.zeros_like(out["cpp"]["imp"][r])
        a["stick"] = np.zeros_like(out["cpp"]["stick"][r])
        a["strobe"] = np.zeros_like(out["cpp"]["strobe"][r])
        call(_core.run_rk4, su, a)
        for k in ("x", "met", "imp", "stick", "strobe"):
            d = diff(out["cpp"][k][r], a[k])
            if d != "=":
                worst = f"run {r} {k}: {d}"
    res["vs single"] = worst
    return res, f"{nb} runs"


def cases(duration):
    d = duration
    paper = dict(preset="paper")
    yield "paper ball gap 0.1 friction", lambda: single_case(
        make_system("ball", "paper", gap=0.1e-3, friction=True), Harmonic(10.0, 1.0), d,
        strobe=True)
    yield "paper ball gap 0.5 friction", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction=True), Harmonic(20.0, 1.01), d,
        strobe=True, record_every=7)
    yield "paper ball gap 0.1 no friction", lambda: single_case(
        make_system("ball", "paper", gap=0.1e-3, friction=False), Harmonic(10.0, 1.0), d)
    yield "paper ball gap 0.5 no friction", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction=False), Harmonic(20.0, 0.97), d,
        strobe=True)
    yield "physical ball gap 0.5 friction (2 modes)", lambda: single_case(
        make_system("ball", "physical", gap=0.5e-3, friction=True), Harmonic(20.0, 1.0), d,
        strobe=True, record_every=1)
    yield "physical ball gap 0.1 no friction", lambda: single_case(
        make_system("ball", "physical", gap=0.1e-3, friction=False), Harmonic(10.0, 1.0), d)
    for nm in (1, 2, 3, 4):
        yield f"physical ball {nm} modes, F_c 2 N, rattle", lambda nm=nm: single_case(
            make_system("ball", "physical", gap=0.02e-3, friction_force=2.0, n_modes=nm),
            Harmonic(10.0, 1.0), d, initial=RATTLE, strobe=True, record_every=5)
    yield "paper ball 3 modes friction", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction=True, n_modes=3),
        Harmonic(20.0, 1.0), d, strobe=True)
    yield "printed reaction (REACTION -1), 2 modes", lambda: single_case(
        make_system("ball", "physical", gap=0.02e-3, friction_force=2.0,
                    friction_reaction="printed"), Harmonic(10.0, 1.0), d, initial=RATTLE,
        strobe=True)
    yield "printed reaction, paper 1 mode", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction_reaction="printed"),
        Harmonic(20.0, 1.0), d, strobe=True)
    yield "STAGE_LOOP=1 paper ball friction", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction=True), Harmonic(20.0, 1.0), d,
        strobe=True, stage_loop=True)
    yield "STAGE_LOOP=1 physical 2 modes", lambda: single_case(
        make_system("ball", "physical", gap=0.1e-3, friction=True), Harmonic(20.0, 1.0), d,
        stage_loop=True, record_every=3)
    for kind in ("solid", "tmd"):
        for pr in ("paper", "physical"):
            yield f"{kind} {pr}", lambda kind=kind, pr=pr: single_case(
                make_system(kind, pr), Harmonic(10.0, 1.0), d,
                initial=Initial(tip_velocity=0.05), strobe=True, record_every=4)
    yield "tmd 3 modes", lambda: single_case(
        make_system("tmd", "physical", n_modes=3), Harmonic(10.0, 1.0), d, strobe=True)
    yield "solid 5 modes", lambda: single_case(
        make_system("solid", "physical", n_modes=5), Harmonic(10.0, 1.0), d, strobe=True)
    for pr in ("paper", "physical"):
        yield f"locked {pr}", lambda pr=pr: single_case(
            make_system("ball", pr, locked=True), Harmonic(10.0, 1.0), d,
            initial=Initial(tip_velocity=0.05), strobe=True, record_every=2)
    yield "continued in 3 calls (ball friction, strobe, history)", lambda: single_case(
        make_system("ball", "paper", gap=0.5e-3, friction=True), Harmonic(20.0, 1.0), d,
        strobe=True, record_every=3, chunks=3)
    rpm = 60.0 / 3000e-6
    n_cut = max(d, 0.02)
    yield "cut solid cubic", lambda: single_case(
        make_system("solid"), Regenerative(depth=1e-3, rpm=rpm, interpolation="cubic"),
        n_cut, record_every=1)
    yield "cut solid linear", lambda: single_case(
        make_system("solid"), Regenerative(depth=1e-3, rpm=rpm, interpolation="linear"),
        n_cut, record_every=1)
    yield "cut solid cubic, stop at zero", lambda: single_case(
        make_system("solid"), Regenerative(depth=1e-3, rpm=rpm, stop_at_zero=True),
        n_cut, record_every=1)
    yield "cut locked, static start", lambda: single_case(
        make_system("ball", locked=True, friction=False),
        Regenerative(depth=1e-3, rpm=rpm, start="static"), n_cut,
        initial=Initial(tip_velocity=0.02), record_every=2)
    yield "cut tmd cubic", lambda: single_case(
        make_system("tmd"), Regenerative(depth=2e-3, rpm=rpm), n_cut)
    yield "cut solid 1 revolution, 3 calls", lambda: single_case(
        make_system("solid"), Regenerative(depth=1e-3, rpm=rpm, revolutions=1), n_cut,
        record_every=1, chunks=3)
    yield "cut ball (friction) 2 modes", lambda: single_case(
        make_system("ball", gap=0.1e-3), Regenerative(depth=1e-3, rpm=rpm), n_cut)

    def varied(system, k):
        forces, ratios = (10.0, 20.0), (0.97, 1.0, 1.01, 1.04)
        jobs = [(system, Harmonic(f, r), Initial(0.2e-3 * (j % 3 - 1), 0.3 * (j % 2)))
                for j, (f, r) in enumerate((f, r) for f in forces for r in ratios)]
        return (jobs * 2)[:k]

    ball1 = make_system("ball", "paper", gap=0.5e-3, friction=True, n_modes=1)
    for nb in (*LANES, 3, 1):
        yield f"batch paper ball friction, {nb} runs", lambda nb=nb: batch_case(
            varied(ball1, nb), nb, d)
    ball2 = make_system("ball", "physical", gap=0.5e-3, friction=True, n_modes=2)
    yield "batch physical ball 2 modes, 8 runs", lambda: batch_case(varied(ball2, 8), 8, d)
    nofr = make_system("ball", "paper", gap=0.5e-3, friction=False)
    yield "batch paper ball no friction, 4 runs", lambda: batch_case(varied(nofr, 4), 4, d)
    for kind, system in (("solid", make_system("solid", "paper")),
                         ("tmd", make_system("tmd", "physical")),
                         ("locked", make_system("ball", "physical", locked=True))):
        yield f"batch {kind}, 4 runs", lambda system=system: batch_case(
            varied(system, 4), 4, d)
    yield "batch ball 4 modes, 4 runs", lambda: batch_case(
        varied(make_system("ball", "physical", gap=0.5e-3, n_modes=4), 4), 4, d)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.02, help="s of each run (dt 1e-6)")
    ap.add_argument("--only", default="", help="run the cases whose name contains this")
    args = ap.parse_args()
    bad = 0
    for name, run in cases(args.duration):
        if args.only not in name:
            continue
        res, info = run()
        ok = all(v == "=" for v in res.values())
        bad += not ok
        cols = "  ".join(f"{k} {v}" for k, v in res.items())
        print(f"{'OK ' if ok else 'BAD'} {name:50s} {cols}  [{info}]", flush=True)
    print(f"{'all bit-identical' if not bad else f'{bad} case(s) differ'}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
