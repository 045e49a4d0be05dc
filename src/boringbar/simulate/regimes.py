"""The exact integrator's per-run setup: :func:`prepare` (the regimes' matrices,
diagonalised, and their constants; the part that depends on the system alone is kept per
system, :func:`system_regimes`, and the forcing's part taken from the core for each run),
:func:`history_step` and :func:`cut_tables` (a regenerative cut's knot spacing and
tabulated whole step); the compiled core (``boringbar.core``) takes these arrays.

The regimes' matrices come from the core (``core.regime_stack``: the stage derivative the
RK4 steps with, at unit vectors), so the equations of motion are not written here.  What
this module adds is spelled out so that its rounding does not depend on how NumPy
vectorises it, as the core's own arithmetic does (core/exact/nmath.hpp):

- complex products and quotients as (ac - bd, ad + bc) and CPython's division
  (``_Py_c_quot``), vectorised on the real and imaginary parts where a loop is vectorised
  (NumPy's own complex multiply and divide may use other sequences and FMA);
- ``abs(z)`` is the C library's hypot and the complex exponential is
  ``exp(x) (cos y + i sin y)`` from the C library's exp, cos, sin, as the core's ``cexp``
  (NumPy's ufuncs may use their own SIMD versions, so they are not used for these);
- the eigen-decomposition, inverse and solves of the stacked regimes are NumPy's;
- sums keep their order (a loop over the summed index, vectorised over the others).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from boringbar import core
from boringbar._validate import ParameterError
from boringbar.model.linalg import one_blas_thread
from boringbar.simulate import layout as L

#: event-search grid points per shortest period and grid levels (core/exact/consts.hpp)
GRID_PER_PERIOD: float = core.GRID_PER_PERIOD
GRID_LEVELS: int = core.GRID_LEVELS

#: Gauss-Legendre nodes on [0, 1], 4 points (the same expressions as core/exact/cut.hpp)
GL_X = (0.5 - 0.4305681557970263, 0.5 - 0.16999052179242816, 0.5 + 0.16999052179242816,
        0.5 + 0.4305681557970263)

#: 1 / k! (core/exact/consts.hpp's RFACT)
RFACT = tuple(1.0 / math.factorial(k) for k in range(20))


# --- scalar arithmetic, as the core does it ------------------------------------------------
def _cexp(z: complex) -> complex:
    """e^z as the core's ``cexp`` (core/exact/nmath.hpp): exp(x) (cos y + i sin y) from the
    C library's functions, with C99's special cases."""
    x, y = z.real, z.imag
    if math.isfinite(x):
        if math.isfinite(y):
            c = math.cos(y)
            s = math.sin(y)
            r = math.exp(x)
            return complex(r * c, r * s)
        return complex(math.nan, math.nan)
    if math.isnan(x):
        return complex(x, x) if y else complex(x, y)
    if x > 0.0:  # +inf
        if math.isfinite(y):
            real = math.cos(y)
            imag = math.sin(y)
            return complex(real * x if real != 0 else real, imag * x if imag != 0 else imag)
        return complex(x, math.nan)
    if math.isfinite(y):  # -inf
        r = math.exp(x)
        return complex(r * math.cos(y), r * math.sin(y))
    return complex(0.0, 0.0)


def _phis(x: complex):
    """The core's phis (core/exact/propagate.hpp) with Python complex numbers: CPython's
    complex arithmetic (a float promoted to complex; _Py_c_prod, _Py_c_quot)."""
    if x.real * x.real + x.imag * x.imag < 1.0:
        p4 = 0j
        for m in range(14, -1, -1):
            p4 = p4 * x + RFACT[m + 4]
        p3 = 1.0 / 6.0 + x * p4
        p2 = 0.5 + x * p3
        p1 = 1.0 + x * p2
        return 1.0 + x * p1, p1, p2, p3, p4
    ex = _cexp(x)
    p1 = (ex - 1.0) / x
    p2 = (p1 - 1.0) / x
    p3 = (p2 - 0.5) / x
    return ex, p1, p2, p3, (p3 - 1.0 / 6.0) / x


def _cmul_parts(ar, ai, br, bi):
    """(ar + i ai)(br + i bi) on arrays: CPython's (ac - bd, ad + bc), elementwise."""
    return ar * br - ai * bi, ar * bi + ai * br


# --- the regimes ----------------------------------------------------------------------------
def _pair_order(lr):
    """An ordering [l1, conj l1, l2, conj l2, ...] of ``lr``, or
    an empty array if its values are not all complex conjugate pairs."""
    nz = len(lr)
    none = np.empty(0, np.int64)
    ok = nz % 2 == 0
    if ok:
        for i in range(0, nz, 2):
            a = lr[i]
            if not (a.imag > 1e-12 * abs(a)) or lr[i + 1] != a.conjugate():
                ok = False
                break
    if ok:
        return np.arange(nz)
    for i in range(nz):
        if abs(lr[i].imag) <= 1e-12 * abs(lr[i]):
            return none
    up = [i for i in range(nz) if lr[i].imag > 0]
    down = [i for i in range(nz) if lr[i].imag < 0]
    if len(up) != len(down):
        return none
    order = np.empty(nz, np.int64)
    for u, i in enumerate(up):
        cj = lr[i].conjugate()
        j = down[0]
        for d in down:
            if abs(lr[d] - cj) < abs(lr[j] - cj):
                j = d
        if abs(lr[j] - cj) > 1e-9 * abs(lr[i]):
            return none
        order[2 * u] = i
        order[2 * u + 1] = j
    return order


def _pairing(lam, V, Vi):
    """The conjugate-pair ordering (in place in lam,
    V, Vi), Vh and kstep."""
    R, nz = lam.shape
    kstep = np.ones(R, np.int64)
    Vh = V.copy()
    paired = []
    for r, lr in enumerate(lam.tolist()):
        order = _pair_order(lr)
        if order.shape[0] == 0:
            continue
        if order.tolist() != list(range(nz)):
            lam[r] = lam[r][order]
            V[r] = V[r][:, order]
            Vi[r] = Vi[r][order, :]
        paired.append(r)
    if paired:
        # all regimes at once (a slice when all are paired: the usual case)
        pr = slice(None) if len(paired) == R else np.array(paired)
        kstep[pr] = 2
        # the conjugate: imag -> -0.0 - imag, the same bits as NumPy's sign flip
        V[pr, :, 1::2] = np.conj(V[pr, :, 0::2])
        Vi[pr, 1::2, :] = np.conj(Vi[pr, 0::2, :])
        # 2.0 * V[r, :, k] with 2.0 promoted to complex(2.0, 0.0)
        re, im = _cmul_parts(2.0, 0.0, V[pr, :, 0::2].real, V[pr, :, 0::2].imag)
        vh = np.zeros((len(paired), nz, nz), np.complex128)
        vh.real[:, :, 0::2] = re
        vh.imag[:, :, 0::2] = im
        Vh[pr] = vh
    return Vh, kstep


# The rest of the setup is written as loops on Python floats and complex numbers (CPython's
# complex arithmetic, as above): for the small sizes here faster than NumPy's per-call
# overhead, and evidently the same operations.
def _modal_inputs(Vi_l, B_l):
    """bq = Vi B per regime, each sum in order from 0j."""
    bq = []
    for Vr, Br in zip(Vi_l, B_l, strict=True):
        row = []
        for Vk in Vr:
            s = 0j
            for v, b in zip(Vk, Br, strict=True):
                s += v * b
            row.append(s)
        bq.append(row)
    return np.array(bq, np.complex128)


def _mode_bounds(psis, V_l, alam, nz):
    """bnd without its last column (the forcing's, :func:`_forcing_bounds`): the bounds on
    |y^(4)| (row 0: psi_d) and |W^(4)| (row 1: psi_L) over a segment are sum_k |lambda_k|^4
    |psi . V_k| |q_k| + Omega^4 |psi . Z|, rows 2 and 3 the same with the third powers, for
    |y'''| and |W'''|; each sum in order from 0j, |.| the C library's hypot."""
    bnd = np.zeros((len(V_l), 4, nz + 1))
    for r, Vr in enumerate(V_l):
        for row, ps in enumerate(psis):
            b4, b3 = [], []
            for k in range(nz):
                s = 0j
                for i, p_i in enumerate(ps):
                    s += p_i * Vr[i][k]
                a = alam[r][k]
                s = abs(s)
                b4.append(a * a * a * a * s)
                b3.append(a * a * a * s)
            bnd[r, row, :nz] = b4
            bnd[r, row + 2, :nz] = b3
    return bnd


def _grid_exponentials(lam_l, h):
    """eh[r, lv, k] = exp(lambda_k h 2^lv), each as :func:`_cexp` computes it."""
    exp, cos, sin, isfinite = math.exp, math.cos, math.sin, math.isfinite
    eh = []
    for lr in lam_l:
        for lv in range(GRID_LEVELS):
            x = h * 2.0 ** lv
            for z in lr:
                w = z * x  # CPython: x promoted to complex(x, 0.0); the core's values
                if isfinite(w.real) and isfinite(w.imag):
                    e = exp(w.real)  # _cexp, written out (the common case)
                    eh.append(complex(e * cos(w.imag), e * sin(w.imag)))
                else:
                    eh.append(_cexp(w))
    return np.array(eh, np.complex128).reshape(len(lam_l), GRID_LEVELS, -1)


def _mode_sums(lam_l):
    """isum's entries that do not depend on the forcing, 1 / (mu_a + mu_b) for mu_a, mu_b
    among the modes' lambda and the basis exponent 0 (the last), 0 where the sum is 0, as
    nested lists per regime of isum's full size (the rest 0).  An IEEE sum is commutative:
    mu_a + mu_b and mu_b + mu_a are the same number, so one division serves both
    entries."""
    nz = len(lam_l[0])
    nb = nz + 3
    out = []
    for lr in lam_l:
        mu = [*lr, 0j]
        idx = [*range(nz), nb - 1]
        rows = [[0j] * nb for _ in range(nb)]
        for i, (a, ma) in enumerate(zip(idx, mu, strict=True)):
            for b, mb in zip(idx[i:], mu[i:], strict=True):
                sab = ma + mb
                if sab != 0.0:
                    rows[a][b] = rows[b][a] = 1.0 / sab
        out.append(rows)
    return out


# --- the per-system part, kept -------------------------------------------------------------
#: the slots of p the regimes read: the bar, the damper and a cut's Kr b; the forcing's
#: frequency and amplitude (OMEGA, F0) enter only the per-forcing part
SYSTEM_SLOTS = np.array([L.CASE, L.N_MODES, L.FORCING, L.REACTION, L.BALL_MASS, L.M_EFF, L.TMD_MASS,
                         L.TMD_K, L.TMD_C, L.KR_B, L.ROLL, *range(L.M_, L.P_SIZE)])

#: systems whose regimes are kept: a sweep runs one system at many forcings, and an
#: analysis over designs or gaps meets a new system with most runs
SYSTEM_CACHE_SIZE = 64


@dataclass(frozen=True)
class SystemRegimes:
    """What :func:`prepare` computes from the system slots alone, shared by every run of
    the system: its arrays are read-only and its lists are never modified."""

    A: np.ndarray
    B: np.ndarray
    nreg: int
    lam: np.ndarray
    V: np.ndarray
    Vi: np.ndarray
    Vh: np.ndarray
    kstep: np.ndarray
    D: np.ndarray
    bq: np.ndarray
    lvis: np.ndarray
    cvis: np.ndarray
    lam_l: list
    mode_sums: np.ndarray  # isum's entries without +-i Omega (_mode_sums)
    mode_bounds: np.ndarray  # bnd without the forcing's column
    psi: np.ndarray  # (psi_d, psi_L)
    hi: np.ndarray  # largest |lambda| of each regime
    lo: np.ndarray  # smallest nonzero |lambda| of each regime
    fastest: float  # largest |lambda| of all
    eh: np.ndarray | None  # the grid exponentials at h of ``fastest``
    core_regimes: object  # the arrays forcing_setup reads, as one core.Regimes, built once


def _check_diagonalisable(V, Vi, case, nreg):
    cond = (np.max(np.sum(np.abs(V), axis=2), axis=1)
            * np.max(np.sum(np.abs(Vi), axis=2), axis=1))  # infinity-norm condition
    for r, c in enumerate(cond):
        if not c <= 1e10:
            what = ("free", "stick", "contact", "rolled")[r % nreg] if case == L.BALL else "linear"
            raise ValueError(f"exact integrator: the {what} regime is not diagonalisable "
                             "(critically damped mode?)")


@functools.lru_cache(maxsize=SYSTEM_CACHE_SIZE)
@one_blas_thread
def system_regimes(key: bytes) -> SystemRegimes:
    """The regimes of the system whose :data:`SYSTEM_SLOTS` of p have the bytes ``key``,
    diagonalised (one stacked LAPACK call per kind, NumPy's, as the reference's setup).
    Kept per system, bounded; the other slots are NaN here, so nothing else can enter."""
    p = np.full(L.P_SIZE, np.nan)
    p[SYSTEM_SLOTS] = np.frombuffer(key)
    n, case = int(p[L.N_MODES]), int(p[L.CASE])
    A, B, c, nreg = core.regime_stack(p)  # the equations of motion, from the core
    lam, V = np.linalg.eig(A)
    Vi = np.linalg.inv(V)
    _check_diagonalisable(V, Vi, case, nreg)
    D = -np.linalg.solve(A, c[:, :, None])[:, :, 0]
    Vh, kstep = _pairing(lam, V, Vi)
    lam_l = lam.tolist()
    alam = [[abs(z) for z in row] for row in lam_l]  # hypot, as the core's abs
    psis = (p[L.PSI_D:L.PSI_D + n].tolist(), p[L.PSI_L:L.PSI_L + n].tolist())
    hi = [max([0.0, *row]) for row in alam]
    lo = [min([math.inf, *(a for a in row if a > 0.0)]) for row in alam]
    fastest = max([0.0, *hi])
    eh = (_grid_exponentials(lam_l, 2 * math.pi / fastest / GRID_PER_PERIOD)
          if fastest > 0.0 else None)
    bq = _modal_inputs(Vi.tolist(), B.tolist())
    lvis, cvis = core.dashpots(p)  # their rows, from the core as well
    bounds = _mode_bounds(psis, V.tolist(), alam, B.shape[1])
    sums = np.array(_mode_sums(lam_l), np.complex128)
    psi, hi_a, lo_a = np.array(psis), np.array(hi), np.array(lo)
    for a in (A, B, lam, V, Vi, Vh, kstep, D, bq, lvis, cvis, bounds, eh, sums, psi, hi_a, lo_a):
        if a is not None:
            a.flags.writeable = False
    regimes = core.Regimes(A=A, B=B, lam=lam, mode_sums=sums, mode_bounds=bounds, psis=psi,
                           hi=hi_a, lo=lo_a)
    return SystemRegimes(A, B, nreg, lam, V, Vi, Vh, kstep, D, bq, lvis, cvis, lam_l, sums,
                         bounds, psi, hi_a, lo_a, fastest, eh, regimes)


#: A forcing whose i Omega lies within this fraction of Omega of a regime's eigenvalue (an
#: undamped mode at resonance) is refused: the forced response grows without bound, and
#: the closed form's particular solution, 1 / that distance large, drowns the motion in its
#: roundings
RESONANCE_TOL = 1e-8
_REGIME_NAMES = ("with its ball free", "holding its ball", "with its ball on a wall",
                 "with its ball rolling")


@functools.lru_cache(maxsize=SYSTEM_CACHE_SIZE)
def check_resonance(key: bytes, om: float) -> None:
    """Refuses a forcing at Omega (rad/s) at an undamped natural frequency of a regime of
    the system of ``key`` (:data:`RESONANCE_TOL`); kept per system and Omega."""
    s = system_regimes(key)
    if om <= 0.0:
        return
    gap = np.abs(1j * om - s.lam)
    r, k = np.unravel_index(int(np.argmin(gap)), gap.shape)
    if gap[r, k] <= RESONANCE_TOL * om:
        what = "bar" if s.nreg == 1 else f"bar {_REGIME_NAMES[r % s.nreg]}"
        raise ParameterError(
            f"exact integrator: Omega = {om:.8g} rad/s ({om / (2 * math.pi):.8g} Hz) is a "
            f"natural frequency of the {what}, undamped (its root {s.lam[r, k]:.8g}): the "
            "response grows without bound and has no steady closed form; give the bar "
            "damping (damping_ratio > 0), another frequency, or integrator = 'rk4'")


@functools.lru_cache(maxsize=SYSTEM_CACHE_SIZE)
def forcing_exponentials(key: bytes, h: float) -> np.ndarray:
    """The grid's exponentials (:func:`_grid_exponentials`) of the system of ``key`` at a
    step ``h`` set by a forcing faster than its regimes; kept per system and step, as a
    sweep at one Omega asks for them run after run."""
    eh = _grid_exponentials(system_regimes(key).lam_l, h)
    eh.flags.writeable = False
    return eh


#: the fields of the exact kernel's per-run setup (``core.ExactSetup``), as :func:`prepare`
#: sets them
SETUP_FIELDS = ("lam", "V", "Vh", "kstep", "levmax", "Vi", "Z", "D", "eh", "h", "lvis", "cvis",
                "isum", "bq", "nreg", "bnd")


def exact_setup(fields: dict) -> core.ExactSetup:
    """A ``core.ExactSetup`` with ``fields`` (names of :data:`SETUP_FIELDS`): each field
    refuses a value of another type when it is set, and a run refuses one left unset or of
    the wrong shape when it starts."""
    setup = core.ExactSetup()
    for name, value in fields.items():
        setattr(setup, name, value)
    return setup


def setup_fields(setup: core.ExactSetup) -> dict:
    """The fields of ``setup`` by name (the arrays themselves, not copies)."""
    return {name: getattr(setup, name) for name in SETUP_FIELDS}


def prepare(p: np.ndarray) -> core.ExactSetup:
    """Per-run matrices of the exact kernel from the packed parameter vector ``p``: the
    same, bit for bit, as the setup the reference outputs were computed with
    (tests/data/kernel_reference.npz, ``prep_*``).  The system's part is kept
    (:func:`system_regimes`); the forcing's (Z, the inverse sums and bounds with Omega,
    the levels) is the core's (``core.forcing_setup``), the step h computed here.  The
    arrays the runs of a system share are read-only."""
    key = p[SYSTEM_SLOTS].tobytes()
    s = system_regimes(key)
    om = float(p[L.OMEGA])
    check_resonance(key, om)
    Z, isum, bnd, levmax = core.forcing_setup(s.core_regimes, omega=om, f0=float(p[L.F0]),
                                              levels=GRID_LEVELS)
    # the reference's running maximum from Omega up: Omega unless some |lambda| exceeds it
    fastest = s.fastest if s.fastest > om else om
    h = 2 * math.pi / fastest / GRID_PER_PERIOD
    eh = s.eh if fastest == s.fastest else forcing_exponentials(key, h)
    return exact_setup({"lam": s.lam, "V": s.V, "Vh": s.Vh, "kstep": s.kstep,
                        "levmax": levmax, "Vi": s.Vi, "Z": Z, "D": s.D, "eh": eh, "h": h,
                        "lvis": s.lvis, "cvis": s.cvis, "isum": isum, "bq": s.bq,
                        "nreg": s.nreg, "bnd": bnd})


# --- a regenerative cut ---------------------------------------------------------------------
def history_step(tau: float, dt: float) -> float:
    """H = tau / ceil(tau / dt), at least two per revolution: a cut's knot spacing."""
    return tau / max(2, int(math.ceil(tau / dt - 1e-9)))


def cut_tables(prep: core.ExactSetup, p: np.ndarray, H: float):
    """exp(lambda tau_p) and Kr b bq j! tau_p^(j+1) phi_(j+1)(lambda tau_p) at the Gauss
    nodes and the end of a whole step H, per regime (the out-of-cut ones have no input):
    the tables a cut's whole step reads instead of the closed form (the core's tab_state,
    core/exact/segment.hpp)."""
    lam, nreg, bq = prep.lam, prep.nreg, prep.bq
    R, nz = lam.shape
    taus = [x * H for x in GL_X] + [H]
    tabE = np.zeros((R, 5, nz), complex)
    tabP = np.zeros((R, 5, 4, nz), complex)
    krb = p[L.KR_B]
    for r in range(R):
        for i, tau in enumerate(taus):
            for k in range(nz):
                ex, *ph = _phis(complex(lam[r, k] * tau))
                tabE[r, i, k] = ex
                if r >= nreg:
                    for j in range(4):
                        tabP[r, i, j, k] = (krb * bq[r, k] * math.factorial(j)
                                            * tau ** (j + 1) * ph[j])
    return tabE, tabP
