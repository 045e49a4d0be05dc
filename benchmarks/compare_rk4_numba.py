"""The C++ RK4 kernels (boringbar._core) against the numba ones, bit for bit.

    PYTHONPATH=src .venv/bin/python benchmarks/compare_rk4_numba.py [--duration 0.02]

Builds a spread of runs through boringbar.simulate's own packing (``_setup``: ``pack``,
``initial_state``, the record arrays), runs each through numba's ``run_rk4`` /
``run_rk4_batch`` and through ``_core.run_rk4`` / ``_core.run_rk4_batch`` on copies of
the same inputs, and prints, per case and output, whether the two are bitwise equal
(float64 bit patterns, so -0.0 != 0.0 and NaNs compare by payload) or the largest
difference.  Batches are also compared with the C++ single run of each of their runs.
Exits 1 if anything differs.

``--bad-input``: the C++ entry points' boundary checks: each bad argument must raise a
ValueError that names it (no crash, no silent run).

``--fuzz N``: N random single runs (1-4 modes, every case, both forcings, random
parameters with now and then a 0, -0, 1e+-300, inf or NaN) and N / 4 random batches,
numba against C++.  Runs that blow up to NaN may differ in the NaN's sign bit (IEEE
leaves which NaN operand propagates to the compiler); those are counted apart.
"""

from __future__ import annotations

import argparse
import math
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


def bad_inputs() -> int:
    """Call _core.run_rk4 / run_rk4_batch with one bad argument at a time."""
    def good(n=1):
        p = np.zeros(L.P_SIZE)
        p[L.N_MODES], p[L.CASE] = n, L.BALL
        p[L.M_:L.M_ + n], p[L.K_:L.K_ + n], p[L.PSI_L:L.PSI_L + n] = 1.0, 1e6, 1.0
        p[L.BALL_MASS], p[L.HALF_GAP], p[L.M_EFF], p[L.REACTION] = 0.02, 1e-4, 0.019, 1.0
        return dict(p=p, x=np.zeros(2 * n + 2), t0=0.0, dt=1e-6, n_steps=100, steady_start=0,
                    rec_every=1, rec=np.zeros((5, 6)), imp=np.zeros((1, 3)),
                    stick=np.zeros((1, 2)), strobe=np.zeros((1, 5)), met=fresh_met(),
                    buf=np.zeros((0, 2)))

    def p_with(**slots):
        p = good()["p"]
        for k, v in slots.items():
            p[getattr(L, k)] = v
        return p

    def met_with(slot, v):
        m = fresh_met()
        m[slot] = v
        return m

    def cut(rows, nrev=2, tau=1e-4):
        p = p_with(FORCING=1, N_REV=nrev, TAU=tau, CASE=L.SOLID)
        return {"p": p, "buf": np.zeros((rows, 2))}

    read_only = np.zeros((5, 6))
    read_only.flags.writeable = False
    single = {
        "p float32": {"p": good()["p"].astype(np.float32)}, "p short": {"p": np.zeros(5)},
        "p a list": {"p": list(good()["p"])}, "x length": {"x": np.zeros(6)},
        "rec read-only": {"rec": read_only}, "rec 5 columns": {"rec": np.zeros((5, 5))},
        "rec strided": {"rec": np.zeros((10, 6))[::2]},
        "rec Fortran order": {"rec": np.asfortranarray(np.zeros((5, 6)))},
        "imp 1-d": {"imp": np.zeros(3)}, "met short": {"met": np.zeros(10)},
        "N_MODES 0": {"p": p_with(N_MODES=0)}, "N_MODES 9": {"p": p_with(N_MODES=9)},
        "N_MODES 1.5": {"p": p_with(N_MODES=1.5)}, "N_MODES nan": {"p": p_with(N_MODES=math.nan)},
        "CASE 4": {"p": p_with(CASE=4)}, "FORCING 2": {"p": p_with(FORCING=2)},
        "n_steps -1": {"n_steps": -1}, "n_steps 2.5": {"n_steps": 2.5},
        "n_steps '3'": {"n_steps": "3"}, "dt 0": {"dt": 0.0}, "dt nan": {"dt": math.nan},
        "dt inf": {"dt": math.inf}, "t0 nan": {"t0": math.nan},
        "steady_start -1": {"steady_start": -1}, "steady_start > n_steps": {"steady_start": 101},
        "rec_every -1": {"rec_every": -1},
        "met N_IMP_REC -1": {"met": met_with(L.N_IMP_REC, -1)},
        "met N_REC nan": {"met": met_with(L.N_REC, math.nan)},
        "met STEPS_DONE 1e300": {"met": met_with(L.STEPS_DONE, 1e300)},
        "cut buf short": cut(150), "cut N_REV 0": cut(10, nrev=0), "cut N_REV 51": cut(10, 51),
        "cut TAU 0": cut(10, tau=0.0), "cut TAU nan": cut(10, tau=math.nan),
    }
    bad = 0
    for label, over in single.items():
        a = good()
        a.update(over)
        try:
            _core.run_rk4(**a)
            print(f"BAD  run_rk4 {label}: no error")
            bad += 1
        except ValueError as e:
            print(f"OK   run_rk4 {label}: {e}")

    def batch(nb=4):
        g = good()
        return dict(P=np.tile(g["p"], (nb, 1)), x=np.zeros((nb, 4)), t0=0.0, dt=1e-6,
                    n_steps=100, steady_start=0, imp=np.zeros((nb, 2, 3)),
                    stick=np.zeros((nb, 2, 2)), strobe=np.zeros((nb, 0, 5)),
                    met=fresh_met((nb,)))

    def rows(r, slot, v):
        P = batch()["P"]
        P[r, slot] = v
        return P

    negative = fresh_met((4,))
    negative[2, L.N_IMP_REC] = -5
    batches = {
        "0 runs": batch(0), "17 runs": batch(17),
        "mixed cases": {"P": rows(2, L.CASE, L.SOLID)},
        "mixed modes": {"P": rows(1, L.N_MODES, 2)},
        "a cut": {"P": rows(3, L.FORCING, 1)}, "x rows": {"x": np.zeros((3, 4))},
        "imp rows": {"imp": np.zeros((3, 2, 3))}, "strobe columns": {"strobe": np.zeros((4, 1, 4))},
        "met[2] negative count": {"met": negative}, "dt nan": {"dt": math.nan},
    }
    for label, over in batches.items():
        a = batch()
        a.update(over)
        try:
            _core.run_rk4_batch(**a)
            print(f"BAD  run_rk4_batch {label}: no error")
            bad += 1
        except ValueError as e:
            print(f"OK   run_rk4_batch {label}: {e}")
    print(f"bad input: {bad} accepted")
    return bad


WEIRD = (0.0, -0.0, 1e-300, 1e300, math.inf, -math.inf, math.nan)


def random_params(rng, n, case, forcing, dt):
    """A random parameter vector and state for ``n`` modes (now and then a weird value)."""
    p = np.zeros(L.P_SIZE)
    p[L.N_MODES], p[L.CASE], p[L.FORCING] = n, case, forcing
    p[L.M_:L.M_ + n] = rng.uniform(0.1, 2, n)
    p[L.K_:L.K_ + n] = rng.uniform(1e5, 1e8, n)
    p[L.C_:L.C_ + n] = rng.uniform(0, 50, n)
    for s in (L.PSI_L, L.PSI_D, L.PSI_A):
        p[s:s + n] = rng.uniform(-2, 2, n)
    p[L.F0], p[L.OMEGA] = rng.uniform(0, 50), rng.uniform(0, 5000)
    p[L.BALL_MASS], p[L.HALF_GAP] = rng.uniform(0.005, 0.1), rng.uniform(1e-6, 1e-3)
    p[L.RESTITUTION] = rng.uniform(0, 1)
    p[L.FRICTION] = rng.choice([0.0, rng.uniform(0, 30)])
    p[L.REACTION] = rng.choice([1.0, -1.0])
    p[L.M_EFF], p[L.V_IMPACT] = rng.uniform(0.005, 0.1), rng.uniform(0, 0.01)
    p[L.V_STICK] = p[L.V_IMPACT] + rng.uniform(0, 0.05)
    p[L.STICK_MIN] = rng.uniform(0, 1e-4)
    p[L.TMD_MASS], p[L.TMD_K], p[L.TMD_C] = (rng.uniform(0.01, 1), rng.uniform(1e3, 1e6),
                                             rng.uniform(0, 20))
    p[L.STROBE_PERIOD] = rng.choice([0.0, rng.uniform(1e-6, 1e-3)])
    p[L.STROBE_T0] = rng.uniform(-1e-3, 1e-3)
    p[L.KR_B], p[L.FEED] = rng.uniform(1e5, 1e8), rng.uniform(0, 1e-4)
    p[L.TAU], p[L.N_REV] = dt * rng.uniform(1.5, 60), int(rng.integers(1, 6))
    p[L.INTERP], p[L.STOP_AT_ZERO] = rng.integers(0, 2), rng.integers(0, 2)
    p[L.HIST_W0], p[L.STAGE_LOOP] = rng.uniform(-1e-4, 1e-4), rng.integers(0, 2)
    if rng.random() < 0.15:  # a weird value in a slot the kernel takes as it comes
        slot = int(rng.integers(3, L.P_SIZE))
        if slot not in (L.TAU, L.N_REV):
            p[slot] = rng.choice(WEIRD)
    x = rng.normal(size=2 * n + 2) * rng.choice([1e-6, 1e-4, 1e-2])
    if case in (L.BALL, L.LOCKED):
        x[2 * n] = rng.uniform(-1, 1) * p[L.HALF_GAP]
    if rng.random() < 0.1:
        x[rng.integers(0, 2 * n + 2)] = rng.choice(WEIRD)
    return p, x


def fresh_met(shape=()):
    met = np.zeros((*shape, L.MET_SIZE))
    met[..., L.STEADY_MAX_W], met[..., L.STEADY_MIN_W], met[..., L.FIRST_ZERO_T] = (
        -np.inf, np.inf, -1.0)
    return met


def verdict(a, b, keys):
    """'=' bitwise equal; 'nan' equal but for NaN bits; else the differing outputs."""
    diffs = [k for k in keys if not np.array_equal(a[k].view(np.uint64), b[k].view(np.uint64))]
    if not diffs:
        return "="
    if all(np.array_equal(a[k], b[k], equal_nan=True) for k in diffs):
        return "nan"
    return ",".join(diffs)


def fuzz(n_runs: int, seed: int = 0) -> int:
    rng = np.random.default_rng(seed)
    counts = {"=": 0, "nan": 0}
    bad = 0
    for it in range(n_runs):
        n, case, forcing = int(rng.integers(1, 5)), int(rng.integers(0, 4)), int(rng.integers(0, 2))
        dt = float(rng.choice([1e-6, 2e-6, 5e-7]))
        p, x = random_params(rng, n, case, forcing, dt)
        rows = int(math.ceil(p[L.N_REV] * p[L.TAU] / dt)) + 3 + int(rng.integers(0, 3))
        arrs = {"p": p, "x": x, "rec": np.zeros((int(rng.integers(0, 400)), 6)),
                "imp": np.zeros((int(rng.integers(0, 30)), 3)),
                "stick": np.zeros((int(rng.integers(0, 30)), 2)),
                "strobe": np.zeros((int(rng.integers(0, 30)), 5)), "met": fresh_met(),
                "buf": np.zeros((rows if forcing else 0, 2))}
        ns = int(rng.integers(1, 3000))
        scal = (float(rng.choice([0.0, rng.uniform(-1e-3, 1e-2)])), dt, ns,
                int(rng.integers(0, ns + 1)), int(rng.integers(0, 5)))
        outs = []
        for fn in (numba_run, _core.run_rk4):
            a = {k: v.copy() for k, v in arrs.items()}
            fn(a["p"], a["x"], *scal, a["rec"], a["imp"], a["stick"], a["strobe"], a["met"],
               a["buf"])
            outs.append(a)
        v = verdict(*outs, OUTPUTS)
        if v in counts:
            counts[v] += 1
        else:
            bad += 1
            print(f"DIFF single run {it} (seed {seed}): {n} modes, case {case}, forcing "
                  f"{forcing}: {v}", flush=True)
    # batches of the sizes numba has compiled for the published bars, and others
    combos = [(1, L.BALL, 4), (1, L.BALL, 8), (1, L.BALL, 16), (1, L.BALL, 3), (2, L.BALL, 8),
              (1, L.SOLID, 4), (2, L.TMD, 4), (2, L.LOCKED, 4), (2, L.BALL, 4)]
    for it in range(max(1, n_runs // 4)):
        n, case, nb = combos[it % len(combos)]
        dt = float(rng.choice([1e-6, 2e-6, 5e-7]))
        rows = [random_params(rng, n, case, L.HARMONIC, dt) for _ in range(nb)]
        ns = int(rng.integers(1, 3000))
        caps = [int(rng.integers(0, 30)) for _ in range(3)]
        scal = (float(rng.choice([0.0, 1e-3])), dt, ns, int(rng.integers(0, ns + 1)))
        outs = []
        for fn in (numba_batch, _core.run_rk4_batch):
            a = {"P": np.array([r[0] for r in rows]), "x": np.array([r[1] for r in rows]),
                 "imp": np.zeros((nb, caps[0], 3)), "stick": np.zeros((nb, caps[1], 2)),
                 "strobe": np.zeros((nb, caps[2], 5)), "met": fresh_met((nb,))}
            fn(a["P"], a["x"], *scal, a["imp"], a["stick"], a["strobe"], a["met"])
            outs.append(a)
        v = verdict(*outs, ("x", "met", "imp", "stick", "strobe"))
        if v in counts:
            counts[v] += 1
        else:
            bad += 1
            print(f"DIFF batch {it} (seed {seed}): {n} modes, case {case}, {nb} runs: {v}",
                  flush=True)
    print(f"fuzz: {counts['=']} bit-identical, {counts['nan']} equal but for NaN bits, "
          f"{bad} differ")
    return bad


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.02, help="s of each run (dt 1e-6)")
    ap.add_argument("--only", default="", help="run the cases whose name contains this")
    ap.add_argument("--fuzz", type=int, default=0, help="N random runs instead of the cases")
    ap.add_argument("--seed", type=int, default=0, help="of --fuzz")
    ap.add_argument("--bad-input", action="store_true", help="check the boundary instead")
    args = ap.parse_args()
    if args.bad_input:
        return 1 if bad_inputs() else 0
    if args.fuzz:
        return 1 if fuzz(args.fuzz, args.seed) else 0
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
