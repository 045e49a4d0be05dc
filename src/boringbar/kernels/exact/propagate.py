"""The closed form on a segment: the state at any time (:func:`state_at`), the forces, and the
segment's integrals of products of exponentials (:func:`segment_integrals`).
"""

import cmath
import math

from numba import njit

from boringbar.kernels.exact.consts import RECIP, RFACT, SEG_ACC, SEG_KRB, SEG_S
from boringbar.kernels.exact.prepare import basis_exponents
from boringbar.kernels.views import borrow


@njit(cache=True, inline="always")
def nq(nz, ks):
    """How many eigen-coordinates are evaluated: nz, or nz / 2 when ks = 2 (conjugate
    pairs, the first of each).  A loop over range(0, nz, ks) would cost an integer
    division per loop (its trip count), several per grid step."""
    return nz if ks == 1 else nz >> 1


@njit(cache=True, inline="always")
def phis(x):
    """(e^x, phi_1(x), .., phi_4(x)), phi_k(x) = sum_m x^m / (m + k)!: the Taylor series of
    phi_4 then phi_k = 1/k! + x phi_{k+1} for |x| < 1 (no cancellation), the recurrence
    phi_{k+1} = (phi_k - 1/k!) / x from e^x otherwise (each step divides the error by
    |x| >= 1)."""
    if x.real * x.real + x.imag * x.imag < 1.0:
        p4 = 0.0 + 0.0j
        for m in range(14, -1, -1):
            p4 = p4 * x + RFACT[m + 4]
        p3 = 1.0 / 6.0 + x * p4
        p2 = 0.5 + x * p3
        p1 = 1.0 + x * p2
        return 1.0 + x * p1, p1, p2, p3, p4
    ex = cmath.exp(x)
    p1 = (ex - 1.0) / x
    p2 = (p1 - 1.0) / x
    p3 = (p2 - 0.5) / x
    return ex, p1, p2, p3, (p3 - 1.0 / 6.0) / x


@njit(cache=True, inline="always")
def surface_at(seg, tau):
    """S(tau) and S'(tau): the cut surface's cubic on the segment (docs/model.md, section 4)."""
    s1 = seg[SEG_S + 1]
    s2 = seg[SEG_S + 2]
    s3 = seg[SEG_S + 3]
    return (seg[SEG_S] + tau * (s1 + tau * (s2 + tau * s3)),
            s1 + tau * (2.0 * s2 + 3.0 * tau * s3))


@njit(cache=True, inline="always")
def state_at(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X):
    """X = X(ts + tau) on the segment (regime r, eigen-coordinates q0 at ts = seg[0]);
    returns the forcing phasor e^{i Omega (ts + tau)}.

    In a cut the input Kr b S(tau) (a cubic, seg[SEG_S:SEG_S + 4]) adds
    bq Kr b sum_j S_j j! tau^(j+1) phi_(j+1)(lambda tau) to each eigen-coordinate."""
    nz = X.shape[0]
    ts = seg[0]
    fb = seg[1]
    ph = cmath.exp(1j * om * (ts + tau))
    krb = seg[SEG_KRB]
    if krb != 0.0:
        c0 = seg[SEG_S] * tau
        c1 = seg[SEG_S + 1] * tau * tau
        c2 = 2.0 * seg[SEG_S + 2] * tau ** 3
        c3 = 6.0 * seg[SEG_S + 3] * tau ** 4
        for kq in range(nq(nz, ks)):
            k = kq * ks
            ex, p1, p2, p3, p4 = phis(lam[r, k] * tau)
            q[k] = q0[k] * ex + krb * bq[r, k] * (c0 * p1 + c1 * p2 + c2 * p3 + c3 * p4)
    else:
        for kq in range(nq(nz, ks)):
            k = kq * ks
            q[k] = q0[k] * cmath.exp(lam[r, k] * tau)
    from_q(r, q, ph, fb, Z, D, V, ks, X)
    return ph


@njit(cache=True, inline="always")
def from_q(r, q, ph, fb, Z, D, V, ks, X):
    """X from the eigen-coordinates q and the forcing phasor ph = e^{i Omega t}."""
    nz = X.shape[0]
    for j in range(nz):
        s = (Z[r, j] * ph).imag + fb * D[r, j]
        for kq in range(nq(nz, ks)):
            k = kq * ks
            s += (V[r, j, k] * q[k]).real
        X[j] = s


@njit(cache=True, inline="always")
def cut_force(seg, tau, X, n, mk, f0, om):
    """The force at the tip at ts + tau: F0 sin(Omega t), or Kr b (S(tau) - W) in a cut."""
    f = f0 * math.sin(om * (seg[0] + tau))
    if seg[SEG_KRB] != 0.0:
        w = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
        f += seg[SEG_KRB] * (surface_at(seg, tau)[0] - w)
    return f


@njit(cache=True, inline="always")
def freq_rhs(X, f, n, mk, kappa):
    """The force that carries the ball with the bar, psi_d . a_0 / kappa (N), under the
    tip force f."""
    s = 0.0
    for i in range(n):
        s += mk[4, i] * (mk[3, i] * f - mk[1, i] * X[i] - mk[2, i] * X[n + i]) / mk[0, i]
    return s / kappa


@njit(cache=True, inline="always")
def state_at2(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X, Xd):
    """X and X' at ts + tau on the segment (see :func:`state_at`); in a cut
    q' = lambda q + bq Kr b S(tau)."""
    nz = X.shape[0]
    ph = state_at(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X)
    sin_ = seg[SEG_KRB] * surface_at(seg, tau)[0]
    for j in range(nz):
        sd = om * (Z[r, j] * ph).real
        for kq in range(nq(nz, ks)):
            k = kq * ks
            sd += (V[r, j, k] * (q[k] * lam[r, k] + sin_ * bq[r, k])).real
        Xd[j] = sd


@njit(cache=True, inline="always")
def const_sizes(ks, n, nz):
    """Which compilation with constant sizes fits a regime: 1 (one mode, nz = 2) or 2 (two
    modes, nz = 4), each in conjugate pairs (ks = 2): the ball and the solid bar; 0 for any
    other (a TMD, an overdamped mode, three or more modes), which takes the generic code."""
    if ks == 2 and nz == 2 * n and n <= 2:
        return n
    return 0


@njit(cache=True, inline="always")
def _phi1s(z, T, z2):
    """int_0^T exp(z tau / T) dtau = T (e^z - 1) / z by its series, for |z|^2 = z2 < 1/64
    (where the closed form cancels), with as many terms as |z| needs: the first term left
    out, |z|^(K+1) / (K+2)!, is below 3.1e-18."""
    top = 11 if z2 > 9e-4 else (8 if z2 > 2.5e-5 else 6)
    s = 0.0 + 0.0j
    for k in range(top, 1, -1):
        s = (s * z + 1.0) * RECIP[k]
    s = s * z + 1.0
    return T * s


@njit(cache=True, inline="always")
def _phij(z, phj):
    """phj[j] = phi_j(z) = int_0^1 s^j exp(z s) ds, j = 0, 1, 2, for |z| < 1 (where the
    upward recurrence phi_j = (e^z - j phi_(j-1)) / z cancels) by the series
    sum_m z^m / (m! (m + j + 1)), to the first term below 1e-18."""
    term = 1.0 + 0.0j
    f0 = 0.0 + 0.0j
    f1 = 0.0 + 0.0j
    f2 = 0.0 + 0.0j
    for mm in range(20):
        f0 += term * RECIP[mm + 1]
        f1 += term * RECIP[mm + 2]
        f2 += term * RECIP[mm + 3]
        term = term * z * RECIP[mm + 1]
        if term.real * term.real + term.imag * term.imag < 1e-36:
            break
    phj[0] = f0
    phj[1] = f1
    phj[2] = f2


@njit(cache=True, inline="always")
def _conj_index(k, nz, ks):
    """The basis function conjugate to exp(mu_k tau) when every eigenvalue has its
    conjugate beside it (ks = 2): the other of its pair, -i Omega for i Omega and back,
    itself for 0.  With ks = 1 (an overdamped mode among the others: a complex lambda_k
    may have no conjugate in the basis, and lambda_k - i Omega is then not conjugate
    to lambda_k + i Omega) every function is its own, and G is computed whole."""
    if ks != 2:
        return k
    if k < nz:
        return k ^ 1
    if k == nz:
        return nz + 1
    if k == nz + 1:
        return nz
    return k


@njit(cache=True, inline="always")
def _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, n, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj, nz):
    """Closed-form integrals over a segment [ts, ts + T]: out = [int f psi_L.u',
    sum_d c_d int (l_d.X)^2, int W^2, int W, int f, (1-s) int F_stick psi_d.u', int y^2]
    (the steady-only ones, 2-4 and 6, only if ``level`` >= 1; 6 only if ``level`` = 2: a
    free ball, whose y = P(tau) - psi_d . u, P = p0 + p1 tau + p2 tau^2 its absolute
    position, p0, p1 and 2 p2 in ``seg``).  ``me`` holds the basis exponents mu and exp(mu T)
    (scratch, like G to phj).  Inlined into the compiled wrappers below: with n, ks and nz
    constant its loops unroll (33 % less time for one mode).
    Every quantity is sum_m c_m exp(mu_m tau) over mu = (lambda_r, i Omega, -i Omega, 0), so a
    product integrates to sum_ml a_m b_l G_ml, G_ml = int_0^T exp((mu_m + mu_l) tau);
    ``isum`` holds 1 / (mu_m + mu_l), precomputed per regime; ``ph`` = exp(i Omega ts),
    the segment's forcing phasor at its start (the caller's); ``ks`` = 2 when the
    eigenvalues come in adjacent conjugate pairs.  G is conjugate-symmetric (G of the
    conjugate basis functions is conj(G)), so only one of each conjugate entry is
    computed; where |mu_m + mu_l| T < 1/8 the closed form would cancel, and a series
    (complex) or expm1 (real) takes its place."""
    # borrowed: not reference-counted in this call's inlined helpers (kernels/views.py)
    q0 = borrow(q0)
    lam = borrow(lam)
    VF = borrow(VF)
    Z = borrow(Z)
    D = borrow(D)
    mk = borrow(mk)
    lvis = borrow(lvis)
    cvis = borrow(cvis)
    me = borrow(me)
    mu = me[0]  # the basis exponents
    em = me[1]  # exp(mu T)
    seg = borrow(seg)
    G = borrow(G)
    Cx = borrow(Cx)
    cf = borrow(cf)
    ca = borrow(ca)
    cb = borrow(cb)
    out = borrow(out)
    isum = borrow(isum)
    phj = borrow(phj)
    p0 = seg[2]  # a free ball's absolute position P = p0 + p1 tau + p2 tau^2
    p1 = seg[3]
    p2 = 0.5 * seg[SEG_ACC]
    nb = nz + 3
    basis_exponents(lam, r, om, nz, mu)
    # exp(conj z) = conj(exp(z)) exactly: a conjugate pair's second exponential and the
    # forcing's -i Omega are conjugates, exp(0) = 1
    for k in range(nz):
        if k > 0 and mu[k] == mu[k - 1].conjugate():
            em[k] = em[k - 1].conjugate()
        else:
            em[k] = cmath.exp(mu[k] * T)
    em[nz] = cmath.exp(mu[nz] * T)
    em[nz + 1] = em[nz].conjugate()
    em[nz + 2] = 1.0
    lim = 0.015625 / (T * T)  # |mu_m + mu_l| T < 1/8: the series
    for a in range(nb):
        ja = _conj_index(a, nz, ks)
        for b in range(a, nb):
            jb = _conj_index(b, nz, ks)
            lo = min(ja, jb)
            hi = max(ja, jb)
            if lo < a or (lo == a and hi < b):
                # the conjugate entry, already computed: G is conjugate-symmetric
                g = G[lo, hi].conjugate()
            else:
                s = mu[a] + mu[b]
                if s.imag == 0.0:
                    # a conjugate pair, or the forcing's two terms, or 0: real
                    x = s.real * T
                    g = (T * math.expm1(x) / x if x != 0.0 else T) + 0.0j
                else:
                    z2 = s.real * s.real + s.imag * s.imag
                    if z2 < lim:
                        g = _phi1s(s * T, T, z2 * T * T)
                    else:
                        g = (em[a] * em[b] - 1.0) * isum[r, a, b]
            G[a, b] = g
            G[b, a] = g
    ph2 = -0.5j * ph  # a sine's phasors: Im(z e^{i Omega t}) = (z ph2) e^{..} + conj; no division
    for j in range(nz):
        for k in range(nz):
            Cx[j, k] = VF[r, j, k] * q0[k]
        zz = Z[r, j] * ph2
        Cx[j, nz] = zz
        Cx[j, nz + 1] = zz.conjugate()
        Cx[j, nz + 2] = fb * D[r, j]
    for k in range(nb):
        cf[k] = 0.0
    cf[nz] = f0 * ph2
    cf[nz + 1] = cf[nz].conjugate()
    # work of the force: f psi_L . u' (f has only the terms nz, nz + 1)
    _psi_dot(mk, 3, Cx, n, n, nb, ca)
    w = 0.0
    for i in range(nz, nz + 2):
        t = 0.0 + 0.0j
        for j in range(nb):
            t += G[i, j] * ca[j]
        w += (cf[i] * t).real
    out[0] = w
    out[4] = (cf[nz] * G[nz, nb - 1]).real + (cf[nz + 1] * G[nz + 1, nb - 1]).real
    out[5] = 0.0
    if stick_k != 0.0 and sr != 1.0:
        # F_stick = psi_d . a_0 / kappa, a_0,i = (psi_L,i f - K_i u_i - C_i u_i') / M_i
        for k in range(nb):
            s = 0.0 + 0.0j
            pv = 0.0 + 0.0j
            for i in range(n):
                s += mk[4, i] * (mk[3, i] * cf[k] - mk[1, i] * Cx[i, k]
                                 - mk[2, i] * Cx[n + i, k]) / mk[0, i]
                pv += mk[4, i] * Cx[n + i, k]
            ca[k] = s / stick_k
            cb[k] = pv
        out[5] = (1.0 - sr) * _quad(ca, cb, G, nb)
    # viscous loss
    dv = 0.0
    for d in range(lvis.shape[0]):
        for k in range(nb):
            s = 0.0 + 0.0j
            for j in range(nz):
                if lvis[d, j] != 0.0:
                    s += lvis[d, j] * Cx[j, k]
            ca[k] = s
        dv += cvis[d] * _quad_sym(ca, G, nb)
    out[1] = dv
    if level == 0:
        return
    # W = psi_L . u
    _psi_dot(mk, 3, Cx, 0, n, nb, ca)
    out[2] = _quad_sym(ca, G, nb)
    w1 = 0.0
    for k in range(nb):
        w1 += (ca[k] * G[k, nb - 1]).real
    out[3] = w1
    if level == 1:
        return
    # int y^2 = int P^2 - 2 int P psi_d.u + int (psi_d.u)^2, with
    # int_0^T tau^j exp(mu tau) = T^(j+1) phi_j(mu T), phi_j(z) = int_0^1 s^j e^(z s) ds
    _psi_dot(mk, 4, Cx, 0, n, nb, cb)  # psi_d . u
    uu = _quad_sym(cb, G, nb)
    # mu = 0 (the last basis function): phi_j = 1 / (j + 1)
    cross = (cb[nb - 1] * T * (p0 + T * (0.5 * p1 + T * p2 / 3.0))).real
    for k in range(nb - 1):
        jk = _conj_index(k, nz, ks)
        if jk < k:
            continue  # the conjugate of an earlier term: counted there
        z = mu[k] * T
        if z.real * z.real + z.imag * z.imag >= 1.0:
            # upward recurrence phi_j = (e^z - j phi_(j-1)) / z; 1 / mu_k = 2 isum[r, k, k]
            iz = 2.0 * isum[r, k, k] / T
            ez = em[k]
            f0_ = (ez - 1.0) * iz
            f1_ = (ez - f0_) * iz
            acc_ = p0 * f0_ + T * p1 * f1_
            if p2 != 0.0:
                acc_ += T * T * p2 * ((ez - 2.0 * f1_) * iz)
        else:
            _phij(z, phj)
            acc_ = p0 * phj[0] + T * (p1 * phj[1] + T * p2 * phj[2])
        v = (cb[k] * acc_).real * T
        cross += v if jk == k else 2.0 * v
    pp = T * (p0 * p0 + T * (p0 * p1 + T * ((p1 * p1 + 2.0 * p0 * p2) / 3.0
                                            + T * (0.5 * p1 * p2 + 0.2 * T * p2 * p2))))
    out[6] = pp - 2.0 * cross + uu


@njit(cache=True)
def segment_integrals(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, n, mk, lvis, cvis, stick_k, sr,
               me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj):
    """:func:`_integrals_body` for any bar, regime and basis (nz = lam.shape[1])."""
    _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, n, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj, lam.shape[1])


@njit(cache=True)
def segment_integrals_1(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, mk, lvis, cvis, stick_k, sr,
                 me, G, Cx, cf, ca, cb, out, isum, level, seg, phj):
    """:func:`_integrals_body` for one mode and its conjugate pair (n = 1, nz = 2, ks = 2)."""
    _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, 1, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, 2, seg, phj, 2)


@njit(cache=True)
def segment_integrals_2(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, mk, lvis, cvis, stick_k, sr,
                 me, G, Cx, cf, ca, cb, out, isum, level, seg, phj):
    """:func:`_integrals_body` for two modes in conjugate pairs (n = 2, nz = 4, ks = 2)."""
    _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, 2, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, 2, seg, phj, 4)


@njit(cache=True, inline="always")
def _psi_dot(mk, row, Cx, off, n, nb, dst):
    """dst[k] = sum_i mk[row, i] Cx[off + i, k]: the basis coefficients of psi . u (off 0)
    or psi . u' (off n), psi the row of mk (3: psi_L, 4: psi_d)."""
    for k in range(nb):
        s = 0.0 + 0.0j
        for i in range(n):
            s += mk[row, i] * Cx[off + i, k]
        dst[k] = s


@njit(cache=True, inline="always")
def _quad_sym(a, G, nb):
    """Re(a^T G a) for a symmetric G."""
    s = 0.0
    for i in range(nb):
        t = 0.5 * G[i, i] * a[i]
        for j in range(i + 1, nb):
            t += G[i, j] * a[j]
        s += (a[i] * t).real
    return 2.0 * s


@njit(cache=True, inline="always")
def _quad(a, b, G, nb):
    s = 0.0
    for i in range(nb):
        t = 0.0 + 0.0j
        for j in range(nb):
            t += G[i, j] * b[j]
        s += (a[i] * t).real
    return s
