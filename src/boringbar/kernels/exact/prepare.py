"""The exact kernel's per-run setup: the regimes' matrices, diagonalised, and their constants
(once per run: LAPACK through NumPy, the bookkeeping compiled).
"""

import cmath
import math

import numpy as np
from numba import njit

from boringbar.kernels import layout as L
from boringbar.kernels.exact.consts import GRID_LEVELS, GRID_PER_PERIOD


# --- per-run setup (once per run: LAPACK through NumPy, the bookkeeping compiled) ---------
@njit(cache=True)
def _coupled(p, n, s, A, B):
    """A bar carrying the ball (share s of its inertia): (M + s m psi_d psi_d^T) u'' =
    psi_L f - K u - C u', into A and B."""
    m = p[L.BALL_MASS]
    Mm = np.zeros((n, n))
    for i in range(n):
        Mm[i, i] = p[L.M_ + i]
        for j in range(n):
            Mm[i, j] += s * m * p[L.PSI_D + i] * p[L.PSI_D + j]
    Mi = np.linalg.inv(Mm)
    for i in range(n):
        A[i, n + i] = 1.0
        b = 0.0
        for j in range(n):
            A[n + i, j] = -Mi[i, j] * p[L.K_ + j]
            A[n + i, n + j] = -Mi[i, j] * p[L.C_ + j]
            b += Mi[i, j] * p[L.PSI_L + j]
        B[n + i] = b


@njit(cache=True)
def _regimes(p):
    """The regimes' X' = A X + B f + c F_b, stacked: (A, B, c, nreg).  Ball: free, stick
    (reaction share s), contact (s = 1); other bars one regime; a regenerative cut adds
    each one's twin with -Kr b psi_L . u in A (in the cut)."""
    n = int(p[L.N_MODES])
    case = int(p[L.CASE])
    sr = p[L.REACTION]
    regen = int(p[L.FORCING]) == L.REGENERATIVE
    nz = 2 * n + 2 if case == L.TMD else 2 * n
    nreg = 3 if case == L.BALL else 1
    R = 2 * nreg if regen else nreg
    A = np.zeros((R, nz, nz))
    B = np.zeros((R, nz))
    c = np.zeros((R, nz))
    if case == L.LOCKED:
        _coupled(p, n, 1.0, A[0], B[0])
    else:
        for i in range(n):
            Mi = p[L.M_ + i]
            A[0, i, n + i] = 1.0
            A[0, n + i, i] = -p[L.K_ + i] / Mi
            A[0, n + i, n + i] = -p[L.C_ + i] / Mi
            B[0, n + i] = p[L.PSI_L + i] / Mi
            if case == L.BALL:
                c[0, n + i] = -sr * p[L.PSI_D + i] / Mi  # the bar's reaction to a unit F_b
    if case == L.TMD:
        ma, ka, ca = p[L.TMD_MASS], p[L.TMD_K], p[L.TMD_C]
        A[0, 2 * n, 2 * n + 1] = 1.0
        # bar: M u'' = psi_L f - K u - C u' + psi_a (k_a rel + c_a rel')
        for i in range(n):
            Mi = p[L.M_ + i]
            pai = p[L.PSI_A + i]
            for j in range(n):
                paj = p[L.PSI_A + j]
                A[0, n + i, j] -= ka * pai * paj / Mi
                A[0, n + i, n + j] -= ca * pai * paj / Mi
            A[0, n + i, 2 * n] = ka * pai / Mi
            A[0, n + i, 2 * n + 1] = ca * pai / Mi
            A[0, 2 * n + 1, i] = ka * pai / ma
            A[0, 2 * n + 1, n + i] = ca * pai / ma
        A[0, 2 * n + 1, 2 * n] = -ka / ma
        A[0, 2 * n + 1, 2 * n + 1] = -ca / ma
    if case == L.BALL:
        _coupled(p, n, sr, A[1], B[1])  # stick
        if sr == 1.0:  # contact: s = 1, the stick regime's matrices when sr = 1
            A[2] = A[1]
            B[2] = B[1]
        else:
            _coupled(p, n, 1.0, A[2], B[2])
    if regen:
        # in the cut, f = Kr b (S(t) - W): -Kr b W joins the matrix, Kr b S is the input
        krb = p[L.KR_B]
        for r in range(nreg):
            A[nreg + r] = A[r]
            B[nreg + r] = B[r]
            c[nreg + r] = c[r]
            for j in range(nz):
                for i in range(n):
                    A[nreg + r, j, i] -= krb * B[r, j] * p[L.PSI_L + i]
    return A, B, c, nreg


@njit(cache=True)
def _pair_order(lr):
    """An ordering [l1, conj l1, l2, conj l2, ...] of ``lr`` (LAPACK's own when each pair is
    adjacent, + imaginary first), or an empty array if its values are not all complex
    conjugate pairs (an overdamped mode)."""
    nz = lr.shape[0]
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
    up = np.array([i for i in range(nz) if lr[i].imag > 0])
    down = np.array([i for i in range(nz) if lr[i].imag < 0])
    if len(up) != len(down):
        return none
    order = np.empty(nz, np.int64)
    for u in range(len(up)):
        i = up[u]
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


@njit(cache=True, inline="always")
def basis_exponents(lam, r, om, nz, mu):
    """mu = (lambda_r, i Omega, -i Omega, 0): the exponents of a segment's basis functions."""
    for k in range(nz):
        mu[k] = lam[r, k]
    mu[nz] = 1j * om
    mu[nz + 1] = -1j * om
    mu[nz + 2] = 0.0


@njit(cache=True)
def _finish(p, lam, V, Vi, Z, B):
    """The conjugate-pair ordering (in place in lam, V, Vi), the halved eigenvectors Vh,
    kstep, bq = Vi B, the grid step h and its levels' exp(lambda 2^l h), levmax, the bound
    constants bnd and isum = 1 / (mu_m + mu_l) over the basis mu = (lambda, i Omega,
    -i Omega, 0)."""
    n = int(p[L.N_MODES])
    om = p[L.OMEGA]
    R, nz = lam.shape
    kstep = np.ones(R, np.int64)
    Vh = V.copy()
    for r in range(R):
        order = _pair_order(lam[r])
        if order.shape[0] == 0:
            continue
        # X is real, so a conjugate pair contributes 2 Re(V_k q_k): evaluate the first of
        # each pair, twice (halves the exponentials on the hot path)
        lr = lam[r].copy()
        Vr = V[r].copy()
        Vir = Vi[r].copy()
        for k in range(nz):
            lam[r, k] = lr[order[k]]
            V[r, :, k] = Vr[:, order[k]]
            Vi[r, k, :] = Vir[order[k], :]
        for k in range(0, nz, 2):
            V[r, :, k + 1] = np.conj(V[r, :, k])
            Vi[r, k + 1, :] = np.conj(Vi[r, k, :])
            Vh[r, :, k] = 2.0 * V[r, :, k]
            Vh[r, :, k + 1] = 0.0
        kstep[r] = 2
    bq = np.zeros((R, nz), np.complex128)
    for r in range(R):
        for k in range(nz):
            s = 0.0 + 0.0j
            for j in range(nz):
                s += Vi[r, k, j] * B[r, j]
            bq[r, k] = s
    fastest = om
    for r in range(R):
        for k in range(nz):
            fastest = max(fastest, abs(lam[r, k]))
    h = 2 * math.pi / fastest / GRID_PER_PERIOD
    # the bounds on |y^(4)| (row 0: psi_d) and |W^(4)| (row 1: psi_L) over a segment are
    # sum_k |lambda_k|^4 |psi . V_k| |q_k| + Omega^4 |psi . Z|: the regime's constants;
    # rows 2 and 3 the same with the third powers, for |y'''| and |W'''|
    bnd = np.empty((R, 4, nz + 1))
    for r in range(R):
        for row in range(2):
            ps = L.PSI_D if row == 0 else L.PSI_L
            for k in range(nz + 1):
                s = 0.0 + 0.0j
                for i in range(n):
                    s += p[ps + i] * (V[r, i, k] if k < nz else Z[r, i])
                a = abs(lam[r, k]) if k < nz else om
                bnd[r, row, k] = a * a * a * a * abs(s)
                bnd[r, row + 2, k] = a * a * a * abs(s)
    # the longest step worth trying per regime: 2^levmax h, where 2^levmax is how many times
    # faster the fastest eigenvalue is than the slower of the forcing and the slowest one
    # (one retained mode: h already fits it, no longer step)
    levmax = np.zeros(R, np.int64)
    for r in range(R):
        lo = math.inf
        hi = 0.0
        for k in range(nz):
            a = abs(lam[r, k])
            hi = max(hi, a)
            if a > 0.0:
                lo = min(lo, a)
        ratio = hi / max(lo, om)
        lv = 0
        while lv < GRID_LEVELS - 1 and ratio >= 2.0 ** (lv + 1):
            lv += 1
        levmax[r] = lv
    eh = np.empty((R, GRID_LEVELS, nz), np.complex128)
    for r in range(R):
        for lv in range(GRID_LEVELS):
            for k in range(nz):
                eh[r, lv, k] = cmath.exp(lam[r, k] * (h * 2.0 ** lv))
    nb = nz + 3
    mu = np.zeros(nb, np.complex128)
    isum = np.zeros((R, nb, nb), np.complex128)
    for r in range(R):
        basis_exponents(lam, r, om, nz, mu)
        for a in range(nb):
            for b in range(nb):
                sab = mu[a] + mu[b]
                if sab != 0.0:
                    isum[r, a, b] = 1.0 / sab
    return Vh, kstep, bq, h, bnd, levmax, eh, isum


def prepare(p: np.ndarray) -> dict:
    """Per-run matrices of the exact kernel from the packed parameter vector ``p``."""
    n = int(p[L.N_MODES])
    case = int(p[L.CASE])
    om = p[L.OMEGA]
    A, B, c, nreg = _regimes(p)
    R, nz = B.shape
    # one stacked LAPACK call per kind (the same routine per matrix, so the same numbers as
    # one call per regime, without the Python overhead of a dozen small calls)
    lam, V = np.linalg.eig(A)
    Vi = np.linalg.inv(V)
    cond = (np.max(np.sum(np.abs(V), axis=2), axis=1)
            * np.max(np.sum(np.abs(Vi), axis=2), axis=1))  # infinity-norm condition
    for r in range(R):
        if not cond[r] <= 1e10:
            what = ("free", "stick", "contact")[r % nreg] if case == L.BALL else "linear"
            raise ValueError(f"exact integrator: the {what} regime is not diagonalisable "
                             "(critically damped mode?)")
    Z = np.linalg.solve(1j * om * np.eye(nz) - A, (B * p[L.F0])[:, :, None])[:, :, 0]
    D = -np.linalg.solve(A, c[:, :, None])[:, :, 0]
    Vh, kstep, bq, h, bnd, levmax, eh, isum = _finish(p, lam, V, Vi, Z, B)
    # dashpots: D_visc = sum_d c_d int (l_d . X)^2 dt
    nd = n + 1 if case == L.TMD else n
    lv = np.zeros((nd, nz))
    cv = np.zeros(nd)
    lv[np.arange(n), n + np.arange(n)] = 1.0
    cv[:n] = p[L.C_:L.C_ + n]
    if case == L.TMD:
        lv[n, 2 * n + 1] = 1.0
        lv[n, n:2 * n] = -p[L.PSI_A:L.PSI_A + n]
        cv[n] = p[L.TMD_C]
    return {"lam": lam, "V": V, "Vh": Vh, "kstep": kstep, "levmax": levmax, "Vi": Vi, "Z": Z,
            "D": D, "eh": eh, "h": h, "lvis": lv, "cvis": cv, "isum": isum, "bq": bq,
            "nreg": nreg, "bnd": bnd}
