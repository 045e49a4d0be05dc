"""The exact integrator's lower layer without numba, against the numba originals, bit for bit.

(a) boringbar.kernels.regimes: prepare, history_step and cut_tables (Python and NumPy, the
    per-run setup) give the same arrays, dtypes and bits as the numba package's, on 21
    parameter vectors packed as simulate packs them (every bar, 1 to 8 modes, an overdamped
    absorber, the printed friction reaction, static friction, regenerative cuts).
(b) core/exact/*.hpp, the C++ port of consts, propagate, events and cut, through the test
    hook boringbar._core._exact_lower (core/bind_exact_lower.cpp): each function against its
    numba original on inputs from real runs (the state a short exact run reaches, in every
    regime of the bar; the event functions on a grid over the following segment, their roots,
    the W extrema, the segment integrals at every level, a free ball's wall steps, a cut's
    flows, knots and surface pieces), plus numba's complex arithmetic and integer powers on
    signed zeros, infinities and NaNs.

"The same bits" is tested on the bytes (so -0.0 differs from 0.0, and NaNs compare by
payload).  These tests need numba (they compare with it): they go when numba goes.
"""

from __future__ import annotations

import cmath
import dataclasses
import math

import numpy as np
import pytest
from numba import njit

from boringbar import Harmonic, make_system
from boringbar.kernels import layout as L
from boringbar.kernels import regimes
from boringbar.kernels.exact import consts as NC
from boringbar.kernels.exact import cut as NCUT
from boringbar.kernels.exact import events as NE
from boringbar.kernels.exact import propagate as NP
from boringbar.kernels.exact.driver import run_exact
from boringbar.kernels.exact.prepare import prepare as numba_prepare
from boringbar.model.forcing import Regenerative
from boringbar.simulate import _setup

try:
    from boringbar import _core

    LOW = getattr(_core, "_exact_lower", None)
except ImportError:  # the compiled core not built
    LOW = None

needs_core = pytest.mark.skipif(LOW is None, reason="boringbar._core._exact_lower not built")


def same(a, b) -> bool:
    """The same type, dtype, shape and bytes."""
    if isinstance(a, tuple | list):
        return (isinstance(b, tuple | list) and len(a) == len(b)
                and all(same(x, y) for x, y in zip(a, b, strict=True)))
    if isinstance(a, complex | float) or isinstance(b, complex | float):
        ta = np.complex128 if isinstance(a, complex) else np.float64
        tb = np.complex128 if isinstance(b, complex) else np.float64
        return ta == tb and ta(a).tobytes() == tb(b).tobytes()
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


# --- the parameter vectors ------------------------------------------------------------------
def _cases():
    """(name, system, forcing, dt): every bar and forcing kind simulate packs."""
    out = []
    s = make_system("tmd", "physical")
    d = s.damper
    over = dataclasses.replace(s, damper=dataclasses.replace(
        d, damping=3.0 * 2.0 * math.sqrt(d.stiffness * d.mass)))
    for name, system, forcing in (
            ("solid-paper", make_system("solid", "paper"), Harmonic(10.0, 0.93)),
            ("solid-phys", make_system("solid", "physical"), Harmonic(10.0, 0.97)),
            ("solid-4", make_system("solid", "physical", n_modes=4), Harmonic(10.0, 1.0)),
            ("tmd-phys", make_system("tmd", "physical"), Harmonic(10.0, 1.0)),
            ("tmd-overdamped", over, Harmonic(10.0, 1.0)),
            ("locked", make_system("ball", "physical", locked=True), Harmonic(10.0, 1.02)),
            ("ball-paper-1", make_system("ball", "paper", gap=0.5e-3), Harmonic(10.0, 1.0)),
            ("ball-phys-2", make_system("ball", "physical"), Harmonic(10.0, 1.0)),
            ("ball-nofric", make_system("ball", "physical", gap=0.1e-3, friction=False),
             Harmonic(5.0, 0.9)),
            ("ball-phys-3", make_system("ball", "physical", n_modes=3), Harmonic(10.0, 1.1)),
            ("ball-phys-1", make_system("ball", "physical", n_modes=1, friction=False,
                                        gap=0.5e-3), Harmonic(10.0, 1.0)),
            ("ball-printed", make_system("ball", "paper", gap=0.5e-3,
                                         friction_reaction="printed"), Harmonic(10.0, 1.0)),
            ("ball-static", make_system("ball", "paper", gap=0.5e-3, static_ratio=1.5),
             Harmonic(20.0, 0.8)),
            ("ball-e03", make_system("ball", "physical", gap=1e-4, restitution=0.3,
                                     friction=False), Harmonic(10.0, 1.2)),
            ("ball-8", make_system("ball", "physical", n_modes=8), Harmonic(10.0, 1.0)),
            ("cut-solid", make_system("solid"), Regenerative(depth=1e-3, rpm=1210.0)),
            ("cut-solid-lin", make_system("solid"),
             Regenerative(depth=1e-3, rpm=1210.0, interpolation="linear", revolutions=1)),
            ("cut-ball", make_system("ball", gap=10e-6), Regenerative(depth=2e-3, rpm=1210.0)),
            ("cut-tmd", make_system("tmd"),
             Regenerative(depth=1e-3, rpm=1210.0, start="static")),
            ("cut-locked", make_system("ball", locked=True, friction=False),
             Regenerative(depth=1e-3, rpm=3000.0)),
            ("cut-ball-paper", make_system("ball", "paper", gap=0.5e-3),
             Regenerative(depth=1e-3, rpm=900.0, stop_at_zero=True))):
        out.append((name, system, forcing))
    return out


CASES = _cases()
NAMES = [c[0] for c in CASES]


def _packed(name):
    """(setup, dt) of case ``name``, dt refined until the bar's highest mode allows it."""
    _, system, forcing = CASES[NAMES.index(name)]
    dt = 1e-6
    while True:
        try:
            return _setup(system, forcing, 0.01, dt, None, 0, 0.5, False, "exact"), dt
        except Exception as e:  # the step check: too coarse for the retained modes
            if "too coarse" not in str(e):
                raise
            dt /= 4


_PACKED = {}


def packed(name):
    if name not in _PACKED:
        _PACKED[name] = _packed(name)
    return _PACKED[name]


# --- (a) prepare, history_step, cut_tables ---------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_prepare_is_numbas_bit_for_bit(name):
    """regimes.prepare(p) == prepare(p) of the numba package: keys, types, dtypes, shapes,
    bytes."""
    p = packed(name)[0].p
    ref = numba_prepare(p.copy())
    got = regimes.prepare(p.copy())
    assert list(got) == list(ref)
    for key in ref:
        assert type(got[key]) is type(ref[key]), key
        assert same(got[key], ref[key]), key


@pytest.mark.parametrize("name", [n for n in NAMES if n.startswith("cut")])
def test_cut_tables_and_history_step_are_numbas_bit_for_bit(name):
    su, dt = packed(name)
    p = su.p
    tau = float(p[L.TAU])
    for step in (dt, 0.7 * dt, 3.3e-6, tau / 7.0, tau / 2.0, 2.0 * tau):
        assert same(regimes.history_step(tau, step), NCUT.history_step(tau, step))
    H = NCUT.history_step(tau, dt)
    ref = NCUT.cut_tables(numba_prepare(p), p, H)
    got = regimes.cut_tables(regimes.prepare(p), p, H)
    assert same(got[0], ref[0]) and same(got[1], ref[1])


# --- (b) the C++ headers ---------------------------------------------------------------------
@needs_core
def test_constants_are_pythons():
    recip, rfact, glx, glw, gpp = LOW.constants()
    assert same(tuple(recip), NC.RECIP) and same(tuple(rfact), NC.RFACT)
    assert same(tuple(glx), NCUT.GL_X) and same(tuple(glw), NCUT.GL_W)
    assert same(gpp, NC.GRID_PER_PERIOD)


def _div(a, b):
    try:
        return a / b
    except Exception:  # numba catches only Exception: here its ZeroDivisionError
        return -7.0 - 7.0j


_jdiv = njit(_div)


def same_or_nans(a: complex, b: complex) -> bool:
    """The same bits, a NaN matching any NaN: which NaN an operation on two NaNs (or a NaN
    and an infinity times zero) returns depends on the order of the operands the compiler
    chose (x86 returns the first), which neither compiler promises."""
    return all((math.isnan(x) and math.isnan(y)) or same(x, y)
               for x, y in ((a.real, b.real), (a.imag, b.imag)))


@njit
def _numba_ops(z, w, x):
    return (z * w, _jdiv(z, w), z + w, z - w, z * x, x * z, z + x, x + z, z - x, x - z,
            _jdiv(z, x + 0j) if x == 0.0 else z / x, _jdiv(x + 0j, z) if z == 0j else x / z,
            -z, z.conjugate(), cmath.exp(z), abs(z) + 0j)


@njit
def _numba_pow(x):
    return x ** 2, x ** 3, x ** 4, x ** 5


@needs_core
def test_complex_arithmetic_is_numbas():
    """ncplx (exact/nmath.hpp) against numba: products, quotients (CPython's algorithm),
    a float operand promoted, negation, conjugate, exp and abs, on ordinary values and on
    signed zeros, infinities and NaNs; x ** k for literal k."""
    special = [0.0, -0.0, 1.0, -2.5, 1e-310, 3e300, math.inf, -math.inf, math.nan]
    rng = np.random.default_rng(3)
    zs = [complex(a, b) for a in special for b in special]
    zs += [complex(*v) for v in rng.normal(size=(40, 2)) * 10.0 ** rng.integers(-5, 5, (40, 2))]
    xs = special + list(rng.normal(size=5))
    bad = []
    for i, z in enumerate(zs):
        w = zs[(7 * i + 3) % len(zs)]
        for x in xs[i % 3::3]:
            ref = _numba_ops(z, w, x)
            got = LOW.complex_ops(z, w, x)
            for k, (g, r) in enumerate(zip(got, ref, strict=True)):
                if not same_or_nans(complex(g), complex(r)):
                    bad.append((z, w, x, k, g, r))
    assert not bad, bad[:5]
    for x in special + list(rng.normal(size=50) * 1e3):
        ref = _numba_pow(x)
        got = tuple(LOW.ipow(x, k) for k in (2, 3, 4, 5))
        assert same(got, ref), x


# --- real inputs: the state a short run reaches, in every regime --------------------------------
class Inputs:
    """A case's prepare, bar rows and, per regime r, a segment ``seg`` and eigen-coordinates
    ``q0`` from the state a short exact run reaches (the driver's start_segment, written out)."""

    def __init__(self, name):
        su, dt = packed(name)
        p = su.p.copy()
        x = su.x.copy()
        n = int(p[L.N_MODES])
        case = int(p[L.CASE])
        self.p, self.n, self.ball = p, n, case == L.BALL
        self.regen = int(p[L.FORCING]) == L.REGENERATIVE
        self.prep = prep = regimes.prepare(p)
        self.om, self.f0 = float(p[L.OMEGA]), float(p[L.F0])
        self.h = float(prep["h"])
        nz = prep["lam"].shape[1]
        self.nz, self.nb = nz, nz + 3
        self.mk = np.array([p[k:k + n] for k in (L.M_, L.K_, L.C_, L.PSI_L, L.PSI_D, L.PSI_A)])
        # a short run of the numba kernel: a real state
        met = np.zeros(L.MET_SIZE)
        met[L.STEADY_MAX_W], met[L.STEADY_MIN_W], met[L.FIRST_ZERO_T] = -np.inf, np.inf, -1.0
        t_run = 0.004 if not self.regen else 0.012
        t = run_exact(p, x, 0.0, t_run, 0.0, 0.0, np.zeros((0, 6)), np.zeros((100000, 3)),
                      np.zeros((100000, 2)), np.zeros((0, 5)), met, dt=dt)
        self.t, self.x = t, x
        m = float(p[L.BALL_MASS])
        fc, sr = float(p[L.FRICTION]), float(p[L.REACTION])
        half = float(p[L.HALF_GAP])
        spd = float(np.sum(self.mk[4] ** 2 / self.mk[0]))
        kstick = (1.0 / m + sr * spd) if m > 0.0 else 1.0
        kwall = (1.0 / m + spd) if m > 0.0 else 1.0
        self.kstick, self.half, self.sr = kstick, half, sr
        nreg = prep["nreg"]
        R = prep["lam"].shape[0]
        X = x[:nz].copy()
        w = float(self.mk[3] @ X[:n])
        wd = float(self.mk[3] @ X[n:2 * n])
        self.segs = []
        for r in range(R):
            mode = r % nreg if self.ball else 0
            incut = r >= nreg
            y, yd = (x[2 * n], x[2 * n + 1]) if self.ball else (0.0, 0.0)
            sdir, wall, fb = 0.0, 0.0, 0.0
            if self.ball and mode == 0:
                sdir = 1.0 if yd >= 0.0 else -1.0
                fb = -fc * sdir
            elif mode == 1:
                yd = 0.0
            elif mode == 2:
                wall = 1.0 if y >= 0.0 else -1.0
                y, yd = wall * half, 0.0
            ph = cmath.exp(1j * self.om * t)
            dX = X - ((prep["Z"][r] * ph).imag + fb * prep["D"][r])
            q0 = prep["Vi"][r] @ dX
            seg = np.zeros(NC.SEG_SIZE)
            pdu = float(self.mk[4] @ X[:n])
            pdv = float(self.mk[4] @ X[n:2 * n])
            seg[:11] = (t, fb, y + pdu, yd + pdv, y, sdir, wall,
                        kstick if mode == 1 else kwall, max(float(p[L.STATIC_FRICTION]), fc),
                        half, m if m > 0.0 else 1.0)
            if self.regen:
                feed = float(p[L.FEED])
                seg[NC.SEG_KRB] = float(p[L.KR_B]) if incut else 0.0
                seg[NC.SEG_CDIR] = 1.0 if incut else -1.0
                # a surface crossing W near the segment's start: h = S - W changes sign
                seg[NC.SEG_S:NC.SEG_S + 4] = (w + 0.02 * feed, 0.8 * wd - 3e3 * feed,
                                              -2e6 * feed, 1e9 * feed)
            seg[NC.SEG_ACC] = fb / seg[10]
            self.segs.append((r, int(prep["kstep"][r]), q0, seg))

    def args(self, r, ks):
        """prepare's arrays as the kernel takes them (lam, Vh, ks, Z, D, bq)."""
        pr = self.prep
        return pr["lam"], pr["Vh"], ks, pr["Z"], pr["D"], pr["bq"]

    def taus(self, span=48):
        return [0.0] + [self.h * (k + 0.37 * (k % 3)) for k in range(1, span)]


_INPUTS = {}


def inputs(name) -> Inputs:
    if name not in _INPUTS:
        _INPUTS[name] = Inputs(name)
    return _INPUTS[name]


LOWER_CASES = ["solid-paper", "solid-phys", "tmd-phys", "tmd-overdamped", "locked",
               "ball-paper-1", "ball-phys-2", "ball-phys-3", "ball-printed", "ball-nofric",
               "cut-solid", "cut-ball", "cut-tmd"]


def _z(n, dtype=float):
    return np.zeros(n, dtype)


@needs_core
@pytest.mark.parametrize("name", LOWER_CASES)
def test_state_and_event_functions_are_numbas(name):
    """state_at, state_at2, phis, g_value and _gd (every event kind) on a grid over a segment
    of every regime."""
    I = inputs(name)
    nz, n = I.nz, I.n
    for r, ks, q0, seg in I.segs:
        lam, V, ks, Z, D, bq = I.args(r, ks)
        for tau in I.taus():
            outs = []
            for impl in (NP.state_at, LOW.state_at):
                q, X = _z(nz, complex), _z(nz)
                ph = impl(r, q0, seg, tau, I.om, lam, V, ks, Z, D, bq, q, X)
                outs.append((complex(ph), q, X))
            assert same(outs[0], outs[1]), (r, tau)
            outs = []
            for impl in (NP.state_at2, LOW.state_at2):
                q, X, Xd = _z(nz, complex), _z(nz), _z(nz)
                impl(r, q0, seg, tau, I.om, lam, V, ks, Z, D, bq, q, X, Xd)
                outs.append((q, X, Xd))
            assert same(outs[0], outs[1]), (r, tau)
            z = complex(lam[r, 0] * tau)
            assert same([complex(v) for v in NP.phis(z)], [complex(v) for v in LOW.phis(z)])
            for kind in range(NC.N_EV):
                g = [impl(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex), _z(nz),
                          n, I.mk, I.f0, I.om) for impl in (NE.g_value, LOW.g_value)]
                assert same(g[0], g[1]), (r, tau, kind)
                gd = [tuple(impl(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex),
                                 _z(nz), _z(nz), n, I.mk, I.f0, I.om))
                      for impl in (NE._gd, LOW.gd)]
                assert same(gd[0], gd[1]), (r, tau, kind)
            assert same(NP.cut_force(seg, tau, outs[0][1], n, I.mk, I.f0, I.om),
                        LOW.cut_force(seg, tau, outs[0][1], n, I.mk, I.f0, I.om))
            assert same(NP.freq_rhs(outs[0][1], 3.7, n, I.mk, seg[7]),
                        LOW.freq_rhs(outs[0][1], 3.7, n, I.mk, seg[7]))
            assert same(tuple(NP.surface_at(seg, tau)), tuple(LOW.surface_at(seg, tau)))


def _variants(I, ks):
    """The C++ variants to compare (0 generic, 3 *_any, and the constant-size copy that
    fits: 1 or 2) and numba's function for each."""
    sz = NP.const_sizes(ks, I.n, I.nz)
    return [0, 3] + ([sz] if sz else []), sz


@needs_core
@pytest.mark.parametrize("name", LOWER_CASES)
def test_roots_and_w_extrema_are_numbas(name):
    """find_root (and its _1/_2/_any copies) at every sign change of every event function on
    the grid, from the Hermite starts the kernel uses; w_extremum likewise at every W' = 0."""
    I = inputs(name)
    nz, n, h = I.nz, I.n, I.h
    found = 0
    for r, ks, q0, seg in I.segs:
        lam, V, ks, Z, D, bq = I.args(r, ks)
        taus = I.taus(64)
        variants, sz = _variants(I, ks)
        for kind in range(NC.N_EV):
            g = [NE.g_value(kind, t, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex), _z(nz),
                            n, I.mk, I.f0, I.om) for t in taus]
            gd = [NE._gd(kind, t, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex), _z(nz),
                         _z(nz), n, I.mk, I.f0, I.om)[1] for t in taus]
            for i in range(len(taus) - 1):
                a, b, ga, gb = taus[i], taus[i + 1], g[i], g[i + 1]
                if not (ga <= 0.0 < gb):
                    continue
                found += 1
                for c0 in (-1.0, NE.hermite(a, b, ga, gb, gd[i], gd[i + 1], 0)):
                    ref = NE.find_root(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq,
                                       _z(nz, complex), _z(nz), _z(nz), n, I.mk, I.f0, I.om, c0)
                    if sz:
                        fn = NE.find_root_1 if sz == 1 else NE.find_root_2
                        spec = fn(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq,
                                  _z(nz, complex), _z(nz), _z(nz), I.mk, I.f0, I.om, c0)
                        assert same(spec, ref)
                    for v in variants:
                        got = LOW.find_root(v, kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D,
                                            bq, _z(nz, complex), _z(nz), _z(nz), n, I.mk, I.f0,
                                            I.om, c0)
                        assert same(got, ref), (r, kind, a, v)
        # W extrema: W' = g_value(EV_WEXT) changes sign
        wd = [NE.g_value(NC.EV_WEXT, t, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex),
                         _z(nz), n, I.mk, I.f0, I.om) for t in taus]
        for i in range(len(taus) - 1):
            a, b, ga, gb = taus[i], taus[i + 1], wd[i], wd[i + 1]
            if not ga * gb < 0.0:
                continue
            found += 1
            for c0 in (0.5 * (a + b), a + 0.3 * (b - a)):
                ref = NE.w_extremum(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq,
                                    _z(nz, complex), _z(nz), _z(nz), n, I.mk, I.om)
                for v in variants:
                    got = LOW.w_extremum(v, a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D,
                                         bq, _z(nz, complex), _z(nz), _z(nz), n, I.mk, I.om)
                    assert same(got, ref), (r, a, v)
    assert found > 0


def _scratch(I):
    nz, nb = I.nz, I.nb
    return [np.zeros((2, nb), complex), np.zeros((nb, nb), complex), np.zeros((nz, nb), complex),
            _z(nb, complex), _z(nb, complex), _z(nb, complex), _z(7)]


@needs_core
@pytest.mark.parametrize("name", LOWER_CASES)
def test_segment_integrals_are_numbas(name):
    """segment_integrals (and _1/_2) at levels 0, 1, 2, with and without the stick work, on
    segments of a few lengths in every regime: out and every scratch array."""
    I = inputs(name)
    pr = I.prep
    n = I.n
    for r, ks, q0, seg in I.segs:
        lam = pr["lam"]
        variants, sz = _variants(I, ks)
        ph = complex(cmath.exp(1j * I.om * seg[0]))
        for T in (I.h, 7.7 * I.h, 1e-9, 40.0 * I.h):
            for level in (0, 1, 2):
                for kst in (0.0, I.kstick):
                    head = (r, q0, ph, T, seg[1], I.om, I.f0, lam, pr["V"], pr["Z"], pr["D"])
                    mid = (pr["lvis"], pr["cvis"], kst, I.sr)
                    ref = _scratch(I)
                    phj = _z(3, complex)
                    NP.segment_integrals(*head, n, I.mk, *mid, *ref, pr["isum"], level, ks, seg,
                                         phj)
                    ref.append(phj)
                    if sz:
                        spec = _scratch(I)
                        phj = _z(3, complex)
                        fn = NP.segment_integrals_1 if sz == 1 else NP.segment_integrals_2
                        fn(*head, I.mk, *mid, *spec, pr["isum"], level, seg, phj)
                        assert same(spec + [phj], ref)
                    for v in [0] + ([sz] if sz else []):
                        got = _scratch(I)
                        phj = _z(3, complex)
                        LOW.segment_integrals(v, *head, n, I.mk, *mid, *got, pr["isum"], level,
                                              ks, seg, phj)
                        got.append(phj)
                        for k, (g, rf) in enumerate(zip(got, ref, strict=True)):
                            assert same(g, rf), (r, T, level, kst, v, k)


@needs_core
@pytest.mark.parametrize("name", ["ball-paper-1", "ball-phys-2", "ball-phys-3", "ball-nofric"])
def test_wall_steps_are_numbas(name):
    """wall_step of a free ball over every grid step of its segment, the ball started as it
    was and started near each wall moving towards it, every watch flag, y'' known or not."""
    I = inputs(name)
    nz, n = I.nz, I.n
    r, ks, q0, seg0 = I.segs[0]
    lam, V, ks, Z, D, bq = I.args(r, ks)
    hits = 0
    for start in (None, 0.8, -0.8, 0.97):
        seg = seg0.copy()
        if start is not None:
            # y(0) = start * half, moving towards that wall fast enough to reach it within
            # about 20 grid steps, sliding that way (friction against it)
            sg = math.copysign(1.0, start)
            dy = start * I.half - seg[4]
            seg[2] += dy
            seg[4] += dy
            seg[3] += sg * 2.0 * I.half / (20.0 * I.h)
            if seg[1] != 0.0:
                seg[1] = -abs(seg[1]) * sg
                seg[5] = sg
            seg[NC.SEG_ACC] = seg[1] / seg[10]
        taus = I.taus(40)
        evs = []
        for t in taus:
            ev = np.array([NE.g_value(k, t, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex),
                                      _z(nz), n, I.mk, I.f0, I.om) for k in range(NC.N_EV)])
            ydd = NE._gd(NC.EV_YEXT, t, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex),
                         _z(nz), _z(nz), n, I.mk, I.f0, I.om)[1]
            evs.append((ev, ydd))
        for i in range(len(taus) - 1):
            a, b = taus[i], taus[i + 1]
            (ev_a, ydd_a), (ev_b, ydd_b) = evs[i], evs[i + 1]
            for watch_v, watch_ext in ((True, False), (False, True), (False, False)):
                for ydds in ((ydd_a, ydd_b), (math.nan, math.nan)):
                    args = (a, b, ev_a, ev_b, watch_v, watch_ext, I.half, seg, r, q0, lam, V,
                            ks, Z, D, bq, _z(nz, complex), _z(nz), _z(nz), n, I.mk, I.f0,
                            I.om, *ydds)
                    ref = NE.wall_step(*args)
                    got = LOW.wall_step(*args)
                    assert same(tuple(got), tuple(ref)), (start, i, watch_v, watch_ext)
                    hits += ref[0] >= 0
            b4 = 1e3 * (1 + i)
            assert LOW.may_graze(a, b, ev_a, ev_b, I.half, b4) == \
                NE.may_graze(a, b, ev_a, ev_b, I.half, b4)
    assert hits > 0


@needs_core
def test_scalar_helpers_are_numbas():
    """hermite, hermite5, quad_range, _cubic_range, w_may_exceed, hermite_at and
    history_step on random inputs (and their degenerate ones)."""
    rng = np.random.default_rng(11)
    for _ in range(3000):
        a = float(rng.normal())
        b = a + float(rng.uniform(1e-9, 2.0))
        v = [float(x) for x in rng.normal(size=8) * 10.0 ** rng.integers(-3, 3, 8)]
        if rng.uniform() < 0.1:
            v[1] = v[0]
            v[3] = v[2]
        for order in (0, 1):
            assert same(LOW.hermite(a, b, *v[:4], order), NE.hermite(a, b, *v[:4], order))
            assert same(LOW.hermite5(a, b, *v[:6], order), NE.hermite5(a, b, *v[:6], order))
        s = abs(v[3])
        assert same(tuple(LOW.quad_range(*v[:3], s)), tuple(NE.quad_range(*v[:3], s)))
        assert same(tuple(LOW.cubic_range(*v[:4])), tuple(NE._cubic_range(*v[:4])))
        args = (b - a, *v[:4], abs(v[4]), v[5], v[6], abs(v[7]))
        assert LOW.w_may_exceed(*args) == NE.w_may_exceed(*args)
        for cubic in (True, False):
            args = (a, v[0], v[1], b, v[2], v[3], v[4], cubic)
            assert same(tuple(LOW.hermite_at(*args)), tuple(NCUT.hermite_at(*args)))
        tau, dt = abs(v[5]) + 1e-3, abs(v[6]) * 1e-3 + 1e-7
        assert same(LOW.history_step(tau, dt), NCUT.history_step(tau, dt))


@needs_core
@pytest.mark.parametrize("name", ["cut-solid", "cut-ball", "cut-tmd"])
def test_cut_flows_knots_and_surface_are_numbas(name):
    """quad_cut over steps of a cut segment (in and out of the cut, a stuck ball's work);
    add_knot through a history that fills, compacts and grows its store; surface_piece on
    that history, for every revolution count and both interpolations."""
    I = inputs(name)
    nz, n = I.nz, I.n
    pr = I.prep
    for r, ks, q0, seg in I.segs:
        lam, V, ks, Z, D, bq = I.args(r, ks)
        for a, b in ((0.0, I.h), (0.3 * I.h, 2.9 * I.h), (I.h, 1.0001 * I.h)):
            for stick, steady in ((False, True), (True, False), (True, True)):
                outs = []
                for impl in (NCUT.quad_cut, LOW.quad_cut):
                    acc, X = _z(6), _z(nz)
                    f = impl(a, b, seg, r, q0, lam, V, ks, Z, D, bq, _z(nz, complex), X, n,
                             I.mk, pr["lvis"], pr["cvis"], stick, I.kstick, I.sr, acc, steady)
                    outs.append((f, acc, X))
                assert same(outs[0], outs[1]), (r, a, stick, steady)
    # knots: W, W' from states along a run of made-up times, some closer than ttol
    rng = np.random.default_rng(5)
    nrev = 3
    H = 1e-4
    ttol = 1e-9 * H
    kn_ref = np.zeros((8, 5))
    kn_got = kn_ref.copy()
    ip_ref = np.full(nrev + 1, -1, np.int64)
    ip_got = ip_ref.copy()
    nk_ref = nk_got = 0
    t = 0.0
    for step in range(200):
        t += H * (0.5 if step % 7 else 1e-12)  # every 7th a knot within ttol of the last
        Xm = rng.normal(size=nz) * 1e-5
        Xp = Xm + rng.normal(size=nz) * 1e-7
        node = float(step) if step % 3 else -1.0
        kn_ref, nk_ref = NCUT.add_knot(kn_ref, nk_ref, ip_ref, t, Xm, Xp, n, I.mk, ttol, node)
        rows, n0, nk_got = LOW.add_knot(kn_got, nk_got, ip_got, t, Xm, Xp, n, I.mk, ttol, node)
        kn_got = np.array(rows).reshape(n0, 5)
        assert same(kn_got, kn_ref) and nk_got == nk_ref and same(ip_got, ip_ref), step
        if step % 10 == 9:  # revolutions move on: old knots may be dropped
            for k in range(1, nrev + 1):
                ip_ref[k] = ip_got[k] = max(-1, nk_ref - 1 - 6 * k)
    # surfaces: from times along that history, a delay of 7.3 H
    tau_d = 7.3 * H
    feed = 1e-4
    for cubic in (True, False):
        for nr_eff in (1, 2, 3):
            ip_ref = np.full(nrev + 1, -1, np.int64)
            ip_got = ip_ref.copy()
            sc_ref, sc_got = np.zeros((nrev + 1, 4)), np.zeros((nrev + 1, 4))
            seg_ref, seg_got = I.segs[-1][3].copy(), I.segs[-1][3].copy()
            # up to the last knot plus one delay: the pointers stay before the last knot
            # (beyond it both versions would read the row after it)
            t_last = kn_ref[nk_ref - 1, 0] + 0.9 * tau_d
            for j, tt in enumerate(np.linspace(kn_ref[0, 0], t_last, 97)):
                args = (tt, tt + 2 * H, ttol, kn_ref, nk_ref)
                tail = (nrev, nr_eff, feed, -3e-6, tau_d)
                ref = NCUT.surface_piece(*args, ip_ref, sc_ref, *tail, seg_ref, j % 5 - 1, 7,
                                         cubic)
                got = LOW.surface_piece(*args, ip_got, sc_got, *tail, seg_got, j % 5 - 1, 7,
                                        cubic)
                assert same(got, ref) and same(ip_got, ip_ref) and same(sc_got, sc_ref)
                assert same(seg_got, seg_ref), (cubic, nr_eff, j)
