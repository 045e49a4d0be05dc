"""The C++ exact kernel (boringbar._core.run_exact) against numba's, bit for bit.

    PYTHONPATH=src .venv/bin/python benchmarks/compare_exact_numba.py [--duration 0.2]
        [--repeat 1] [--only grid|extra|time] [--no-time] [--check-inputs]

Each case is packed by boringbar.simulate's own _setup (as simulate(..., integrator="exact")
packs it), then run by numba's kernels.exact.run_exact and by _core.run_exact on copies of
the same arrays, with prepare(p) computed once per side (the C++ side gets the prep, the
history step H and a cut's tables of boringbar.kernels.regimes when that module exists,
else numba's: they are meant to be identical, and this script checks that they are).
Reported per case: whether the final x, met, rec, imp, stick, strobe and the time reached
have the same bits (the whole arrays, compared as integers, so -0.0 and NaN payloads
count), and for a difference the largest one relative to the output's scale.

Cases: the 80 published harmonic cases of benchmarks/bench_grid.py (shortened to
``--duration``), then solid, TMD and locked bars, true stick-slip (static friction above the
sliding one), the printed friction reaction, strobe and history on, 1 to 4 modes, and
regenerative cuts (linear and cubic history, the solid, ball, TMD and locked bars, a stuck
ball with the printed reaction, one stopping at its first zero).  Then the kernels' wall
times over the 80-case grid, warm (compiled or loaded before timing), prepare excluded,
best of ``--repeat``, alternating which runs first (wall and CPU time: on a shared machine
the CPU time is the steadier).  ``--check-inputs``: spoilt arguments (dtypes, shapes,
strides, read-only outputs, non-finite or out-of-range scalars, prepare's dict) must each be
a ValueError.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from bench_grid import cases as grid_cases  # noqa: E402

from boringbar import Harmonic, make_system  # noqa: E402
from boringbar import _core  # noqa: E402
from boringbar.kernels import layout as L  # noqa: E402
from boringbar.kernels.exact import prepare as numba_prepare  # noqa: E402
from boringbar.kernels.exact import run_exact as numba_run_exact  # noqa: E402
from boringbar.kernels.exact.cut import cut_tables, history_step  # noqa: E402
from boringbar.model.forcing import Regenerative  # noqa: E402
from boringbar.reference.stability import limit_at_speeds  # noqa: E402
from boringbar.simulate import Initial, _setup  # noqa: E402

try:
    _regimes = importlib.import_module("boringbar.kernels.regimes")
    cxx_prepare = _regimes.prepare
    cxx_history_step, cxx_cut_tables = _regimes.history_step, _regimes.cut_tables
    PREP_SOURCE = "boringbar.kernels.regimes (prepare, history_step, cut_tables)"
except (ImportError, AttributeError):
    cxx_prepare, cxx_history_step, cxx_cut_tables = numba_prepare, history_step, cut_tables
    PREP_SOURCE = "numba's prepare and cut tables (kernels.regimes not there yet)"

OUTPUTS = ("x", "met", "rec", "imp", "stick", "strobe", "t")


def setup(system, forcing, duration, dt=1e-6, initial=None, record_every=0,
          steady_fraction=0.8, strobe=False):
    """simulate's packed run (its _setup), for the exact integrator."""
    return _setup(system, forcing, duration, dt, initial, record_every, steady_fraction, strobe,
                  "exact")


def _span(su):
    t0, dt = su.t0, su.dt
    return t0, t0 + su.n_steps * dt, t0 + su.steady_steps * dt, su.record_every * dt


def _fresh(su):
    """Copies of the arrays a run writes."""
    return {"x": su.x.copy(), "rec": su.rec.copy(), "imp": su.imp.copy(),
            "stick": su.stick.copy(), "strobe": su.stb.copy(), "met": su.met.copy()}


def run_numba(su, prep):
    """numba's run_exact as simulate calls it: (outputs, kernel seconds)."""
    o = _fresh(su)
    t0, t_end, t_steady, rec_dt = _span(su)
    tic, cpu = time.perf_counter(), time.thread_time()
    o["t"] = numba_run_exact(su.p, o["x"], t0, t_end, t_steady, rec_dt, o["rec"], o["imp"],
                             o["stick"], o["strobe"], o["met"], prep=prep, dt=su.dt)
    return o, (time.perf_counter() - tic, time.thread_time() - cpu)


def cut_args(p, prep, dt, step=history_step, tables=cut_tables):
    """(H, tabE, tabP) as numba's run_exact makes them (by default with numba's functions)."""
    if int(p[L.FORCING]) == L.REGENERATIVE:
        H = step(float(p[L.TAU]), float(dt))
        tabE, tabP = tables(prep, p, H)
        return H, tabE, tabP
    return 0.0, np.zeros((1, 5, 1), complex), np.zeros((1, 5, 4, 1), complex)


def cxx_cut_args(p, prep, dt):
    """(H, tabE, tabP) for the C++ kernel, from kernels.regimes when it exists."""
    return cut_args(p, prep, dt, cxx_history_step, cxx_cut_tables)


def run_cxx(su, prep, tables):
    """_core.run_exact on the same run: (outputs, kernel seconds)."""
    o = _fresh(su)
    t0, t_end, t_steady, rec_dt = _span(su)
    H, tabE, tabP = tables
    tic, cpu = time.perf_counter(), time.thread_time()
    o["t"] = _core.run_exact(su.p, o["x"], t0, t_end, t_steady, rec_dt, o["rec"], o["imp"],
                             o["stick"], o["strobe"], o["met"], prep, su.dt, H, tabE, tabP)
    return o, (time.perf_counter() - tic, time.thread_time() - cpu)


def same_bits(a, b) -> bool:
    a = np.ascontiguousarray(np.asarray(a, dtype=np.float64))
    b = np.ascontiguousarray(np.asarray(b, dtype=np.float64))
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def rel_diff(a, b) -> float:
    """The largest |a - b| relative to max |a| (inf where only one side is finite)."""
    a = np.asarray(a, dtype=float).ravel()
    b = np.asarray(b, dtype=float).ravel()
    if a.shape != b.shape:
        return math.inf
    fin = np.isfinite(a) & np.isfinite(b)
    if np.any(np.isfinite(a) != np.isfinite(b)):
        return math.inf
    if not np.any(fin):
        return 0.0
    scale = np.max(np.abs(a[fin])) or 1.0
    return float(np.max(np.abs(a[fin] - b[fin])) / scale)


def prep_same(pa, pb) -> bool:
    """Whether two prepare dicts hold the same keys, dtypes and bits."""
    if set(pa) != set(pb):
        return False
    for k in pa:
        a, b = np.asarray(pa[k]), np.asarray(pb[k])
        if a.dtype != b.dtype or a.shape != b.shape:
            return False
        if not np.array_equal(np.ascontiguousarray(a).view(np.uint8),
                              np.ascontiguousarray(b).view(np.uint8)):
            return False
    return True


def compare(label, su):
    """One case, both kernels: a row of the table."""
    prep_n = numba_prepare(su.p)
    prep_c = cxx_prepare(su.p)
    tables = cxx_cut_args(su.p, prep_c, su.dt)
    same_tables = all(same_bits(np.asarray(a).view(float), np.asarray(b).view(float))
                      for a, b in zip(cut_args(su.p, prep_n, su.dt), tables))
    on, _ = run_numba(su, prep_n)
    oc, _ = run_cxx(su, prep_c, tables)
    eq = {k: same_bits(on[k], oc[k]) for k in OUTPUTS}
    diffs = {k: rel_diff(on[k], oc[k]) for k in OUTPUTS if not eq[k]}
    met = on["met"]
    info = (f"ev {int(met[L.N_EVENTS]):6d} imp {int(met[L.N_IMP_ALL]):5d} "
            f"stk {int(met[L.N_STICK_REC]):4d} rec {int(met[L.N_REC]):5d} "
            f"stb {int(met[L.N_STROBE]):4d}")
    return {"label": label, "eq": eq, "diffs": diffs,
            "prep": prep_same(prep_n, prep_c) and same_tables,
            "info": info, "status": int(met[L.EXACT_STATUS])}


def _cut_depth(system, factor, rpm, bare=False):
    bar = system.bar if bare else system
    return factor * float(limit_at_speeds(bar, [rpm])[0])


def extra_cases(duration):
    """(label, _Setup) of the cases beyond the grid."""
    out = []
    d = duration
    ball2 = make_system("ball", "physical", gap=0.1e-3)
    out.append(("solid physical r 0.97", setup(make_system("solid"), Harmonic(10.0, 0.97), d)))
    out.append(("tmd physical r 1.00", setup(make_system("tmd", "physical"), Harmonic(10.0, 1.0),
                                             d)))
    out.append(("tmd paper r 1.00 hist+strobe", setup(make_system("tmd", "paper"),
                                                      Harmonic(10.0, 1.0), d, record_every=7,
                                                      strobe=True)))
    out.append(("locked ball physical r 1.02",
                setup(make_system("ball", "physical", locked=True), Harmonic(10.0, 1.02), d)))
    out.append(("stick-slip paper Fs = 2 Fc (printed)",
                setup(make_system("ball", "paper", gap=0.5e-3, static_ratio=2.0),
                      Harmonic(10.0, 1.0), d, record_every=10)))
    out.append(("stick-slip physical Fs = 1.5 Fc 2 N",
                setup(make_system("ball", "physical", gap=0.5e-3, friction_force=2.0,
                                  static_ratio=1.5), Harmonic(20.0, 1.0), d)))
    out.append(("stick-slip physical Fs = 3 Fc 2 N hist",
                setup(make_system("ball", "physical", gap=0.5e-3, friction_force=2.0,
                                  static_ratio=3.0), Harmonic(20.0, 0.98), d, record_every=4)))
    out.append(("stick-slip paper Fs = 1.5 Fc 20 N (printed)",
                setup(make_system("ball", "paper", gap=0.5e-3, static_ratio=1.5),
                      Harmonic(20.0, 1.0), d)))
    out.append(("printed reaction physical 2 N",
                setup(make_system("ball", "physical", gap=0.5e-3, friction_force=2.0,
                                  friction_reaction="printed"), Harmonic(20.0, 1.0), d)))
    out.append(("paper stick case r 1.00 (printed)",
                setup(make_system("ball", "paper", gap=0.5e-3), Harmonic(10.0, 1.0), d)))
    out.append(("ball physical strobe on", setup(ball2, Harmonic(20.0, 1.0), d, strobe=True)))
    out.append(("ball physical history dt 1e-5 every 7",
                setup(ball2, Harmonic(20.0, 0.98), d, dt=1e-5, record_every=7)))
    out.append(("ball physical history every 1 + strobe, ball off-centre",
                setup(ball2, Harmonic(10.0, 1.02), min(d, 0.05), record_every=1, strobe=True,
                      initial=Initial(tip_displacement=1e-5, ball_position=2e-5,
                                      ball_velocity=-0.01))))
    out.append(("ball physical frictionless history",
                setup(make_system("ball", "physical", gap=0.5e-3, friction=False),
                      Harmonic(20.0, 1.0), d, record_every=5)))
    for k in (1, 2, 3, 4):
        s = make_system("ball", "physical", gap=0.1e-3, n_modes=k)
        out.append((f"ball physical {k} mode(s) hist+strobe",
                    setup(s, Harmonic(20.0, 1.0), d, record_every=3, strobe=True)))
    for k in (1, 3, 4):
        out.append((f"solid physical {k} mode(s)", setup(make_system("solid", n_modes=k),
                                                         Harmonic(10.0, 1.0), d)))
        out.append((f"tmd physical {k} mode(s)", setup(make_system("tmd", n_modes=k),
                                                       Harmonic(10.0, 1.0), d)))
    out.append(("locked ball 3 modes",
                setup(make_system("ball", "physical", locked=True, n_modes=3),
                      Harmonic(10.0, 1.0), d)))
    out += cut_cases()
    return out


def cut_cases():
    """Regenerative cuts (tests/test_exact_regen.py's)."""
    out = []
    solid = make_system("solid")
    rpm = 1210.0
    for interp in ("cubic", "linear"):
        for factor, dur in ((0.5, 0.3), (2.0, 0.9)):
            f = Regenerative(depth=_cut_depth(solid, factor, rpm), rpm=rpm, interpolation=interp)
            out.append((f"cut solid {interp} {factor} x limit {dur} s",
                        setup(solid, f, dur, record_every=80)))
    f = Regenerative(depth=_cut_depth(solid, 2.0, rpm), rpm=rpm, stop_at_zero=True)
    out.append(("cut solid 2 x limit, stop at zero", setup(solid, f, 2.0, dt=4e-6)))
    for interp in ("cubic", "linear"):
        f = Regenerative(depth=_cut_depth(solid, 2.0, rpm), rpm=rpm, interpolation=interp)
        out.append((f"cut solid {interp} 2 x limit 1.6 s (past the first zero)",
                    setup(solid, f, 1.6, dt=2e-6, record_every=20, strobe=True)))
    f = Regenerative(depth=_cut_depth(solid, 1.5, 1200.0), rpm=1200.0, revolutions=1,
                     start="static")
    out.append(("cut solid 1 revolution, static start", setup(solid, f, 0.3, dt=2e-6,
                                                              strobe=True)))
    for bar in ("tmd", "locked"):
        s = (make_system("ball", locked=True, friction=False) if bar == "locked"
             else make_system(bar))
        f = Regenerative(depth=_cut_depth(s, 1.5, 1200.0), rpm=1200.0)
        out.append((f"cut {bar} 1.5 x limit", setup(s, f, 0.3, dt=2e-6, record_every=40)))
        f = Regenerative(depth=_cut_depth(s, 3.0, 1200.0), rpm=1200.0, revolutions=2)
        out.append((f"cut {bar} 3 x limit 2 revolutions 1 s", setup(s, f, 1.0, dt=2e-6)))
    ball = make_system("ball", gap=10e-6)
    f = Regenerative(depth=_cut_depth(ball, 3.0, 1200.0, bare=True), rpm=1200.0)
    for dt in (1e-6, 2e-6):
        out.append((f"cut ball gap 10 um 3 x limit dt {dt:g}",
                    setup(ball, f, 0.02, dt=dt, steady_fraction=1.0, record_every=5)))
    out.append(("cut ball gap 10 um 3 x limit 0.5 s", setup(ball, f, 0.5, dt=2e-6)))
    ball3 = make_system("ball", gap=50e-6, n_modes=3, static_ratio=2.0)
    f = Regenerative(depth=_cut_depth(ball3, 2.0, 1100.0, bare=True), rpm=1100.0,
                     interpolation="linear")
    out.append(("cut ball 3 modes gap 50 um Fs = 2 Fc, linear", setup(ball3, f, 0.3, dt=2e-6,
                                                                        record_every=10)))
    paper = make_system("ball", "paper")
    f = Regenerative(depth=_cut_depth(paper, 3.0, 1200.0, bare=True), rpm=1200.0)
    out.append(("cut paper stuck ball (printed) 3 x", setup(paper, f, 0.2)))
    f = Regenerative(depth=_cut_depth(paper, 3.0, 1200.0, bare=True), rpm=1200.0,
                     interpolation="linear", stop_at_zero=True)
    out.append(("cut paper stuck ball linear, stop at zero", setup(paper, f, 0.3)))
    return out


def _bad_inputs():
    """(what, how to spoil a valid call's arguments) for --check-inputs."""
    def p_(k, v):
        return lambda a: a["p"].__setitem__(k, v)

    def arg(k, v):
        return lambda a: a.__setitem__(k, v)

    def prep(k, f):
        return lambda a: a["prep"].__setitem__(k, f(a["prep"][k]))

    harmonic = [
        ("p float32", lambda a: a.__setitem__("p", a["p"].astype(np.float32))),
        ("p NaN", p_(L.F0, np.nan)),
        ("N_MODES 0", p_(L.N_MODES, 0)), ("N_MODES 9", p_(L.N_MODES, 9)),
        ("N_MODES 1.5", p_(L.N_MODES, 1.5)), ("CASE 7", p_(L.CASE, 7)),
        ("FORCING 2", p_(L.FORCING, 2)), ("modal mass 0", p_(L.M_, 0.0)),
        ("half gap 0", p_(L.HALF_GAP, 0.0)), ("strobe period 1e-300", p_(L.STROBE_PERIOD, 1e-300)),
        ("x too short", arg("x", np.zeros(3))), ("x a list", arg("x", [0.0] * 6)),
        ("x read-only", lambda a: a["x"].setflags(write=False)),
        ("x strided", arg("x", np.zeros(12)[::2])), ("rec 5 columns", arg("rec", np.zeros((9, 5)))),
        ("rec Fortran order", arg("rec", np.asfortranarray(np.zeros((9, 6))))),
        ("imp int64", arg("imp", np.zeros((9, 3), np.int64))),
        ("stick read-only", lambda a: a["stick"].setflags(write=False)),
        ("met N_REC -5", lambda a: a["met"].__setitem__(L.N_REC, -5)),
        ("met N_IMP_REC NaN", lambda a: a["met"].__setitem__(L.N_IMP_REC, np.nan)),
        ("t_end < t0", arg("t_end", -1.0)), ("t0 inf", arg("t0", np.inf)),
        ("rec_dt -1e-6", arg("rec_dt", -1e-6)), ("t0 a string", arg("t0", "zero")),
        ("prep a list", arg("prep", [])),
        ("prep without lam", lambda a: a["prep"].pop("lam")),
        ("prep lam (3, 2)", prep("lam", lambda v: v[:, :2].copy())),
        ("prep Vh float64", prep("Vh", lambda v: v.real.copy())),
        ("prep kstep 3", prep("kstep", lambda v: np.full_like(v, 3))),
        ("prep kstep int32", prep("kstep", lambda v: v.astype(np.int32))),
        ("prep levmax 9", prep("levmax", lambda v: np.full_like(v, 9))),
        ("prep nreg 1", prep("nreg", lambda v: 1)), ("prep h 0", prep("h", lambda v: 0.0)),
        ("prep h 1e-30", prep("h", lambda v: 1e-30)),
        ("prep eh inf", prep("eh", lambda v: np.where(v == v, np.inf, v))),
        ("prep bnd (3, 4, 4)", prep("bnd", lambda v: np.zeros((3, 4, 4)))),
        ("tabE (2, 5, 1)", arg("tabE", np.zeros((2, 5, 1), complex))),
    ]
    cut = [
        ("cut dt 0", arg("dt", 0.0)), ("cut H 0", arg("H", 0.0)),
        ("cut H = tau", lambda a: a.__setitem__("H", a["p"][L.TAU])),
        ("cut H 1e-15", arg("H", 1e-15)), ("cut N_REV 0", p_(L.N_REV, 0)),
        ("cut N_REV 2.5", p_(L.N_REV, 2.5)), ("cut TAU 0", p_(L.TAU, 0.0)),
        ("cut harmonic tables", arg("tabE", np.zeros((1, 5, 1), complex))),
        ("cut t0 1e12", lambda a: a.update(t0=1e12, t_end=1e12 + 0.01, t_steady=1e12)),
    ]
    return harmonic, cut


def check_inputs():
    """Every spoilt argument must be a ValueError that names it (never a crash)."""
    def valid(su):
        prep = cxx_prepare(su.p)
        H, tabE, tabP = cxx_cut_args(su.p, prep, su.dt)
        t0, t_end, t_steady, rec_dt = _span(su)
        return dict(p=su.p.copy(), x=su.x.copy(), t0=t0, t_end=t_end, t_steady=t_steady,
                    rec_dt=rec_dt, rec=np.zeros((9, 6)), imp=np.zeros((9, 3)),
                    stick=np.zeros((9, 2)), strobe=np.zeros((9, 5)), met=su.met.copy(),
                    prep=dict(prep), dt=su.dt, H=H, tabE=tabE, tabP=tabP)

    keys = ("p", "x", "t0", "t_end", "t_steady", "rec_dt", "rec", "imp", "stick", "strobe",
            "met", "prep", "dt", "H", "tabE", "tabP")
    ball = setup(make_system("ball", gap=0.1e-3), Harmonic(20.0, 1.0), 0.01, record_every=10)
    cut = setup(make_system("solid"), Regenerative(depth=1e-4, rpm=1210.0), 0.01)
    harmonic_bad, cut_bad = _bad_inputs()
    ok = 0
    for su, bad in ((ball, harmonic_bad), (cut, cut_bad)):
        _core.run_exact(*(valid(su)[k] for k in keys))  # the valid call runs
        for what, spoil in bad:
            a = valid(su)
            spoil(a)
            try:
                _core.run_exact(*(a[k] for k in keys))
                print(f"  ACCEPTED {what}")
            except ValueError as e:
                ok += 1
                print(f"  ValueError  {what:24s} {str(e)[:90]}")
    n = len(harmonic_bad) + len(cut_bad)
    print(f"{ok} of {n} spoilt calls refused with a ValueError")


def print_row(row):
    flags = " ".join(("=" if row["eq"][k] else "X") for k in OUTPUTS)
    ok = all(row["eq"].values())
    tail = ""
    if not ok:
        tail = "  " + ", ".join(f"{k} {v:.1e}" for k, v in row["diffs"].items())
    prep = "" if row["prep"] else "  [prep or cut tables differ]"
    st = f" status {row['status']}" if row["status"] else ""
    print(f"{row['label']:56s} {flags}  {'SAME' if ok else 'DIFF'}  {row['info']}{st}"
          f"{tail}{prep}", flush=True)


def summary(rows):
    n_same = sum(all(r["eq"].values()) for r in rows)
    print(f"\n{n_same} of {len(rows)} cases bit-identical in every output")
    for k in OUTPUTS:
        bad = [r["label"].strip() for r in rows if not r["eq"][k]]
        print(f"  {k:6s}: {len(rows) - len(bad)}/{len(rows)} identical"
              + (f"; differ: {', '.join(bad[:5])}{' ...' if len(bad) > 5 else ''}" if bad else ""))
    print(f"  prep dicts and cut tables identical: {sum(r['prep'] for r in rows)}/{len(rows)}")


def timing(grid, duration, repeat):
    """Kernel times over the grid (warm), prepare excluded: the sums over the cases of each
    case's best wall and best CPU (thread) time, numba's then C++'s."""
    tot = np.zeros((2, 2))  # [numba, C++] x [wall, cpu]
    for i, (_, s, f) in enumerate(grid):
        su = setup(s, f, duration)
        prep_n = numba_prepare(su.p)
        prep_c = cxx_prepare(su.p)
        tables = cxx_cut_args(su.p, prep_c, su.dt)
        best = np.full((2, 2), math.inf)
        for _ in range(repeat):
            for side in ((0, 1) if i % 2 == 0 else (1, 0)):
                o, t = run_numba(su, prep_n) if side == 0 else run_cxx(su, prep_c, tables)
                best[side] = np.minimum(best[side], t)
        tot += best
    return tot


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.2, help="grid and extra runs (s)")
    ap.add_argument("--time-duration", type=float, default=2.0, help="timed grid runs (s)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--only", choices=("grid", "extra", "time"),
                    help="only the grid's or the extra cases' comparison, or only the timing")
    ap.add_argument("--no-time", action="store_true")
    ap.add_argument("--check-inputs", action="store_true",
                    help="only check that spoilt arguments are refused (ValueError)")
    args = ap.parse_args()
    if args.check_inputs:
        check_inputs()
        return
    print(f"prep for C++: {PREP_SOURCE}; outputs {' '.join(OUTPUTS)} (= same bits, X differ)")
    grid = grid_cases()
    rows = []
    tic = time.perf_counter()
    # compile or load both numba kernels before anything is timed
    warm = [setup(grid[0][1], grid[0][2], 1e-3)]
    if args.only in (None, "extra"):
        solid = make_system("solid")
        warm.append(setup(solid, Regenerative(depth=1e-4, rpm=1210.0), 1e-3))
    for su in warm:
        run_numba(su, numba_prepare(su.p))
    print(f"numba warm-up: {time.perf_counter() - tic:.1f} s")
    if args.only not in ("extra", "time"):
        for label, s, f in grid:
            rows.append(compare(label, setup(s, f, args.duration)))
            print_row(rows[-1])
    if args.only not in ("grid", "time"):
        for label, su in extra_cases(args.duration):
            rows.append(compare(label, su))
            print_row(rows[-1])
    if rows:
        summary(rows)
    if not args.no_time:
        tot = timing(grid, args.time_duration, args.repeat)
        print(f"\n80-case grid, {args.time_duration:g} s runs, best of {args.repeat} per case, "
              "summed (numba / C++):")
        for k, what in enumerate(("wall", "CPU")):
            print(f"  {what:4s} time: numba {tot[0, k]:.3f} s, C++ {tot[1, k]:.3f} s, "
                  f"numba / C++ {tot[0, k] / tot[1, k]:.2f}")


if __name__ == "__main__":
    main()
