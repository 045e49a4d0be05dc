"""A regenerative cut's delay history: the history step, the tabulated whole step, the knots
of W and the surface as one cubic per segment (docs/model.md, section 4; docs/exact.md
"Regenerative cuts"), and its Gauss-Legendre flows.
"""

import math

import numpy as np
from numba import njit

from boringbar.kernels import layout as L
from boringbar.kernels.exact.consts import SEG_S
from boringbar.kernels.exact.propagate import cut_force, freq_rhs, phis, state_at


@njit(cache=True)
def history_step(tau, dt):
    """H = tau / ceil(tau / dt), at least two per revolution: a cut's knot spacing."""
    return tau / max(2, int(math.ceil(tau / dt - 1e-9)))


def cut_tables(prep, p, H):
    """exp(lambda tau_p) and Kr b bq j! tau_p^(j+1) phi_(j+1)(lambda tau_p) at the Gauss
    nodes and the end of a whole step H, per regime (the out-of-cut ones have no input):
    a whole step then needs no exponential."""
    lam = prep["lam"]
    R, nz = lam.shape
    taus = [x * H for x in GL_X] + [H]
    tabE = np.zeros((R, 5, nz), complex)
    tabP = np.zeros((R, 5, 4, nz), complex)
    krb = p[L.KR_B]
    for r in range(R):
        for i, tau in enumerate(taus):
            for k in range(nz):
                ex, *ph = phis(complex(lam[r, k] * tau))
                tabE[r, i, k] = ex
                if r >= prep["nreg"]:
                    for j in range(4):
                        tabP[r, i, j, k] = (krb * prep["bq"][r, k] * math.factorial(j)
                                            * tau ** (j + 1) * ph[j])
    return tabE, tabP


@njit(cache=True, inline="always")
def hermite_at(t0, p0, d0, t1, p1, d1, x0, cubic):
    """The cubic Hermite interpolant on [t0, t1] of values p0, p1 and slopes d0 (right of
    t0), d1 (left of t1), as a cubic in x - x0 (x = t' - t0): its 4 coefficients.
    ``cubic`` false: the straight line through p0, p1."""
    ln = t1 - t0
    if cubic:
        c2 = (3.0 * (p1 - p0) / ln - 2.0 * d0 - d1) / ln
        c3 = (2.0 * (p0 - p1) / ln + d0 + d1) / (ln * ln)
    else:
        d0 = (p1 - p0) / ln
        c2 = 0.0
        c3 = 0.0
    return (p0 + x0 * (d0 + x0 * (c2 + x0 * c3)), d0 + x0 * (2.0 * c2 + 3.0 * c3 * x0),
            c2 + 3.0 * c3 * x0, c3)


#: Gauss-Legendre nodes and weights on [0, 1], 4 points
GL_X = (0.5 - 0.4305681557970263, 0.5 - 0.16999052179242816, 0.5 + 0.16999052179242816,
         0.5 + 0.4305681557970263)
GL_W = (0.17392742256872692, 0.3260725774312731, 0.3260725774312731, 0.17392742256872692)


@njit(cache=True, inline="always")
def quad_cut(a, b, seg, r, q0, lam, V, ks, Z, D, bq, q, X, n, mk, lvis, cvis, stick, kappa,
              sr, acc, steady):
    """Adds the flows over [a, b] of a cut segment to ``acc`` (the slots of
    :func:`segment_integrals`' ``out``) by 4-point Gauss-Legendre: error O((b - a)^9) per step,
    far below the scheme's O(H^4).  Returns the largest force at the nodes.  (A whole
    step, from the tables, is written out in :func:`_exact`.)"""
    fmax = 0.0
    hh = b - a
    for g in range(4):
        tau = a + GL_X[g] * hh
        wg = GL_W[g] * hh
        state_at(r, q0, seg, tau, 0.0, lam, V, ks, Z, D, bq, q, X)
        f = cut_force(seg, tau, X, n, mk, 0.0, 0.0)
        fmax = max(fmax, f)
        w = 0.0
        wd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
        acc[0] += wg * f * wd
        dv = 0.0
        for d in range(lvis.shape[0]):
            v = 0.0
            for j in range(X.shape[0]):
                v += lvis[d, j] * X[j]
            dv += cvis[d] * v * v
        acc[1] += wg * dv
        if steady:
            acc[2] += wg * w * w
            acc[3] += wg * w
            acc[4] += wg * f
        if stick and sr != 1.0:
            pdv = 0.0
            for i in range(n):
                pdv += mk[4, i] * X[n + i]
            acc[5] += wg * (1.0 - sr) * freq_rhs(X, f, n, mk, kappa) * pdv
    return fmax


@njit(cache=True)
def add_knot(kn, nk, ip, t, Xm, Xp, n, mk, ttol, node):
    """Store the knot (t, W, W'- from Xm, W'+ from Xp, node index or -1); one closer than
    ``ttol`` to the last knot replaces its value and W'+.  Drops knots no revolution
    needs any more when the store is full, and doubles it if that frees less than half.
    Returns (kn, nk)."""
    w = 0.0
    wdm = 0.0
    wdp = 0.0
    for i in range(n):
        w += mk[3, i] * Xp[i]
        wdm += mk[3, i] * Xm[n + i]
        wdp += mk[3, i] * Xp[n + i]
    if nk > 0 and t <= kn[nk - 1, 0] + ttol:
        kn[nk - 1, 1] = w
        kn[nk - 1, 3] = wdp
        kn[nk - 1, 4] = max(kn[nk - 1, 4], node)
        return kn, nk
    if nk == kn.shape[0]:
        lo = nk
        for k in range(1, ip.shape[0]):
            lo = min(lo, ip[k])
        if lo > 0:
            for i in range(lo, nk):
                for c in range(5):
                    kn[i - lo, c] = kn[i, c]
            nk -= lo
            for k in range(1, ip.shape[0]):
                ip[k] -= lo
        if nk > kn.shape[0] // 2:
            big = np.zeros((2 * kn.shape[0], 5))
            big[:nk] = kn[:nk]
            kn = big
    kn[nk, 0] = t
    kn[nk, 1] = w
    kn[nk, 2] = wdm
    kn[nk, 3] = wdp
    kn[nk, 4] = node
    return kn, nk + 1


@njit(cache=True, inline="always")
def surface_piece(t, t_end, ttol, kn, nk, ip, sc, nrev, nr_eff, feed, w_before, tau_d, seg,
                   j_now, m_rev, cubic):
    """The surface min_k [k h_m + W(t + tau - k tau)] from ``t`` as one cubic in tau, into
    seg[SEG_S:SEG_S + 4], and the time (<= ``t_end``) up to which it is one cubic: the next
    delayed knot of any revolution, or where another revolution becomes the minimum.

    Advances the pointers ip[k] (all revolutions, so that old knots can be dropped);
    sc[k] receives revolution k's cubic.  ``j_now``: the node t is on (-1: none); a
    delayed node then falls exactly on its knot (no rounding of t - k tau).  ``cubic``
    false: linear interpolation of W instead (docs/model.md, section 4's option)."""
    t_piece = t_end
    for k in range(1, nrev + 1):
        kt = k * tau_d
        i = ip[k]
        while i + 1 < nk and kn[i + 1, 0] + kt <= t + ttol:
            i += 1
        ip[k] = i
        if k > nr_eff:
            continue
        if i < 0:  # before the cut: the surface W = HIST_W0
            sc[k, 0] = k * feed + w_before
            sc[k, 1] = 0.0
            sc[k, 2] = 0.0
            sc[k, 3] = 0.0
        else:
            x0 = (t - kt) - kn[i, 0]
            if j_now >= 0 and kn[i, 4] == j_now - k * m_rev:
                x0 = 0.0
            c0, c1, c2, c3 = hermite_at(kn[i, 0], kn[i, 1], kn[i, 3], kn[i + 1, 0],
                                         kn[i + 1, 1], kn[i + 1, 2], x0, cubic)
            sc[k, 0] = k * feed + c0
            sc[k, 1] = c1
            sc[k, 2] = c2
            sc[k, 3] = c3
        if i + 1 < nk:
            tn = kn[i + 1, 0] + kt
            if t + ttol < tn < t_piece - ttol:  # (a delayed node is the node itself)
                t_piece = tn
    # the minimising revolution at t (a tie goes to the one falling faster)
    km = 1
    tie = 1e-12 * feed
    for k in range(2, nr_eff + 1):
        if (sc[k, 0] < sc[km, 0] - tie
                or (abs(sc[k, 0] - sc[km, 0]) <= tie and sc[k, 1] < sc[km, 1])):
            km = k
    # where another revolution drops below it: 16 samples, then bisection on the cubic
    T = t_piece - t
    for k in range(1, nr_eff + 1):
        if k == km:
            continue
        lo = 0.0
        for j in range(1, 17):
            x = T * j / 16.0
            d = 0.0
            for c in range(3, -1, -1):
                d = d * x + (sc[k, c] - sc[km, c])
            if d < 0.0:
                hi = x
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    d = 0.0
                    for c in range(3, -1, -1):
                        d = d * mid + (sc[k, c] - sc[km, c])
                    if d < 0.0:
                        hi = mid
                    else:
                        lo = mid
                    if hi - lo <= ttol:
                        break
                if hi > ttol and hi < T:
                    T = hi
                break
            lo = x
    for c in range(4):
        seg[SEG_S + c] = sc[km, c]
    return t + T if T < t_piece - t else t_piece
