"""The exact kernel's event functions and their roots: Hermite starts, the safeguarded
Newton search (:func:`find_root`), W extrema, the ranges that rule steps out and a free
ball's wall step (:func:`wall_step`).
"""

import math

from numba import njit

from boringbar.kernels.exact.consts import (
    EV_CUT,
    EV_HEXT,
    EV_MINUS,
    EV_PLUS,
    EV_REL_NEG,
    EV_REL_POS,
    EV_VSTOP,
    EV_WEXT,
    EV_YEXT,
    SEG_ACC,
    SEG_CDIR,
    SEG_KRB,
    SEG_S,
)
from boringbar.kernels.exact.propagate import (
    const_sizes,
    cut_force,
    freq_rhs,
    state_at,
    state_at2,
    surface_at,
)
from boringbar.kernels.views import borrow, with_len


@njit(cache=True, inline="always")
def g_value(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, q, X, n, mk, f0, om):
    """Event function ``kind`` at tau on the segment described by ``seg``.

    seg = [ts, fb, ud0, vd0, y0, sdir, wall, kappa, fs, half, m, krb, S_0..S_3, cdir, fb / m]
    (SEG_* name the cut's slots and SEG_ACC the last).
    """
    state_at(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X)
    if kind == EV_WEXT:
        s = 0.0
        for i in range(n):
            s += mk[3, i] * X[n + i]
        return s
    if kind == EV_CUT or kind == EV_HEXT:
        w = 0.0
        wd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
        sv, sd = surface_at(seg, tau)
        return seg[SEG_CDIR] * (w - sv) if kind == EV_CUT else sd - wd
    if kind <= EV_YEXT:
        pdu = 0.0
        pdv = 0.0
        for i in range(n):
            pdu += mk[4, i] * X[i]
            pdv += mk[4, i] * X[n + i]
        acc = seg[SEG_ACC]
        if kind == EV_PLUS or kind == EV_MINUS:
            y = seg[2] + tau * (seg[3] + 0.5 * acc * tau) - pdu
            return y - seg[9] if kind == EV_PLUS else -seg[9] - y
        yd = seg[3] + acc * tau - pdv
        return -seg[5] * yd if kind == EV_VSTOP else yd
    F = freq_rhs(X, cut_force(seg, tau, X, n, mk, f0, om), n, mk, seg[7])
    if kind == EV_REL_NEG:
        return F - seg[8]
    if kind == EV_REL_POS:
        return -F - seg[8]
    return seg[6] * F - seg[8]


@njit(cache=True, inline="always")
def _gd(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om):
    """Event function ``kind`` (see :func:`g_value`), its time derivative and its second
    derivative at tau: the second only where it comes free (the walls and the cut's h),
    NaN elsewhere."""
    ts = seg[0]
    state_at2(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X, Xd)
    if kind == EV_WEXT:
        g = 0.0
        dg = 0.0
        for i in range(n):
            g += mk[3, i] * X[n + i]
            dg += mk[3, i] * Xd[n + i]
        return g, dg, math.nan
    if kind == EV_CUT or kind == EV_HEXT:
        w = 0.0
        wd = 0.0
        wdd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
            wdd += mk[3, i] * Xd[n + i]
        sv, sd = surface_at(seg, tau)
        sdd = 2.0 * seg[SEG_S + 2] + 6.0 * seg[SEG_S + 3] * tau
        if kind == EV_CUT:
            return (seg[SEG_CDIR] * (w - sv), seg[SEG_CDIR] * (wd - sd),
                    seg[SEG_CDIR] * (wdd - sdd))
        return sd - wd, sdd - wdd, math.nan
    if kind <= EV_YEXT:
        pdu = 0.0
        pdv = 0.0
        pda = 0.0
        for i in range(n):
            pdu += mk[4, i] * X[i]
            pdv += mk[4, i] * X[n + i]
            pda += mk[4, i] * Xd[n + i]
        acc = seg[SEG_ACC]
        y = seg[2] + tau * (seg[3] + 0.5 * acc * tau) - pdu
        yd = seg[3] + acc * tau - pdv
        ydd = acc - pda
        if kind == EV_PLUS:
            return y - seg[9], yd, ydd
        if kind == EV_MINUS:
            return -seg[9] - y, -yd, -ydd
        if kind == EV_VSTOP:
            return -seg[5] * yd, -seg[5] * ydd, math.nan
        return yd, ydd, math.nan
    t = ts + tau
    f = f0 * math.sin(om * t)
    fd = f0 * om * math.cos(om * t)
    if seg[SEG_KRB] != 0.0:
        w = 0.0
        wd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
        sv, sd = surface_at(seg, tau)
        f += seg[SEG_KRB] * (sv - w)
        fd += seg[SEG_KRB] * (sd - wd)
    F = 0.0
    Fd = 0.0
    for i in range(n):
        F += mk[4, i] * (mk[3, i] * f - mk[1, i] * X[i] - mk[2, i] * X[n + i]) / mk[0, i]
        Fd += mk[4, i] * (mk[3, i] * fd - mk[1, i] * X[n + i] - mk[2, i] * Xd[n + i]) / mk[0, i]
    F /= seg[7]
    Fd /= seg[7]
    if kind == EV_REL_NEG:
        return F - seg[8], Fd, math.nan
    if kind == EV_REL_POS:
        return -F - seg[8], -Fd, math.nan
    return seg[6] * F - seg[8], seg[6] * Fd, math.nan


@njit(cache=True, inline="always")
def hermite(a, b, p0, p1, d0, d1, order):
    """Where the cubic Hermite interpolant of values p0, p1 and slopes d0, d1 on [a, b]
    (order 0), or its derivative (order 1), changes sign: a starting point for
    :func:`find_root`, found by a few safeguarded Newton steps on the cubic (no
    exponentials)."""
    h = b - a
    m0 = d0 * h
    m1 = d1 * h
    lo = 0.0
    hi = 1.0
    if order == 0:
        flo = p0
        x = p0 / (p0 - p1) if p0 != p1 else 0.5
    else:
        flo = m0
        x = m0 / (m0 - m1) if m0 != m1 else 0.5
    for _ in range(8):
        if not (lo < x < hi):
            x = 0.5 * (lo + hi)
        s2 = x * x
        if order == 0:
            f = ((2 * s2 * x - 3 * s2 + 1) * p0 + (s2 * x - 2 * s2 + x) * m0
                 + (-2 * s2 * x + 3 * s2) * p1 + (s2 * x - s2) * m1)
            df = ((6 * s2 - 6 * x) * p0 + (3 * s2 - 4 * x + 1) * m0
                  + (-6 * s2 + 6 * x) * p1 + (3 * s2 - 2 * x) * m1)
        else:
            f = ((6 * s2 - 6 * x) * p0 + (3 * s2 - 4 * x + 1) * m0
                 + (-6 * s2 + 6 * x) * p1 + (3 * s2 - 2 * x) * m1)
            df = ((12 * x - 6) * p0 + (6 * x - 4) * m0 + (-12 * x + 6) * p1
                  + (6 * x - 2) * m1)
        if (f > 0.0) == (flo > 0.0):
            lo = x
        else:
            hi = x
        xn = x - f / df if df != 0.0 else 0.5 * (lo + hi)
        if abs(xn - x) <= 1e-13:  # converged (the cubic is only a starting point)
            x = xn
            break
        x = xn
    if not (0.0 < x < 1.0):
        x = 0.5 * (lo + hi)
    return a + x * h


@njit(cache=True, inline="always")
def hermite5(a, b, p0, p1, d0, d1, e0, e1, order):
    """Where the quintic Hermite interpolant of values p0, p1, slopes d0, d1 and second
    derivatives e0, e1 on [a, b] (order 0), or its derivative (order 1, given d0 d1 < 0),
    changes sign: the cubic's (:func:`hermite`) refined by safeguarded Newton on the
    quintic.  Its error is O(h^6) (order 0) or O(h^5) (order 1) instead of O(h^4) or
    O(h^3): the root search then usually accepts its first evaluation."""
    x0 = hermite(a, b, p0, p1, d0, d1, order)
    h = b - a
    m0 = d0 * h
    m1 = d1 * h
    k0 = e0 * h * h
    k1 = e1 * h * h
    # p(x) = p0 + m0 x + k0 x^2 / 2 + c3 x^3 + c4 x^4 + c5 x^5 on [0, 1]
    c3 = -10.0 * p0 - 6.0 * m0 - 1.5 * k0 + 0.5 * k1 - 4.0 * m1 + 10.0 * p1
    c4 = 15.0 * p0 + 8.0 * m0 + 1.5 * k0 - k1 + 7.0 * m1 - 15.0 * p1
    c5 = -6.0 * p0 - 3.0 * m0 - 0.5 * k0 + 0.5 * k1 - 3.0 * m1 + 6.0 * p1
    flo = p0 if order == 0 else m0
    lo = 0.0
    hi = 1.0
    x = (x0 - a) / h
    for _ in range(6):
        if not (lo < x < hi):
            x = 0.5 * (lo + hi)
        dp = m0 + x * (k0 + x * (3.0 * c3 + x * (4.0 * c4 + x * 5.0 * c5)))
        if order == 0:
            f = p0 + x * (m0 + x * (0.5 * k0 + x * (c3 + x * (c4 + x * c5))))
            df = dp
        else:
            f = dp
            df = k0 + x * (6.0 * c3 + x * (12.0 * c4 + x * 20.0 * c5))
        if (f > 0.0) == (flo > 0.0):
            lo = x
        else:
            hi = x
        xn = x - f / df if df != 0.0 else 0.5 * (lo + hi)
        if abs(xn - x) <= 1e-15:
            x = xn
            break
        x = xn
    if not (0.0 < x < 1.0):
        return x0
    return a + x * h


@njit(cache=True, inline="always")
def _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om,
               c0, nz):
    """The root of event function ``kind`` in [a, b], where it changes sign (or ga = 0):
    Newton with the exact derivative, kept inside the shrinking bracket (a bisection
    whenever Newton leaves it or fails to halve it), to a bracket of 4 ulp of t or a
    Newton step below that, or a step whose own error, |g''| s^2 / (2 |g'|) to leading
    order, is below a quarter of that (where g'' comes free: usually one evaluation
    fewer).  Returns the end on gb's side (the event has happened).  X and Xd are seen
    with length ``nz``, constant in the specialisations (:func:`find_root_any`)."""
    # borrowed: not reference-counted in this call's inlined helpers (kernels/views.py)
    seg = borrow(seg)
    q0 = borrow(q0)
    lam = borrow(lam)
    V = borrow(V)
    Z = borrow(Z)
    D = borrow(D)
    bq = borrow(bq)
    q = borrow(q)
    X = with_len(X, nz)
    Xd = with_len(Xd, nz)
    mk = borrow(mk)
    ts = seg[0]
    pos = gb > 0.0
    c = c0
    if not (a < c < b):
        c = (a * gb - b * ga) / (gb - ga) if gb != ga else 0.5 * (a + b)
    w_ref = b - a
    slow = 0
    for _ in range(100):
        tol = 4.4e-16 * (abs(ts) + abs(b)) + 1e-300
        if b - a <= tol:
            break
        if slow >= 3 or not (a < c < b):
            c = 0.5 * (a + b)
            slow = 0
            if not (a < c < b):
                break
        g, dg, ddg = _gd(kind, c, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om)
        if g == 0.0:
            return c
        if (g > 0.0) == pos:
            b = c
        else:
            a = c
        if b - a <= 0.5 * w_ref:
            w_ref = b - a
            slow = 0
        else:
            slow += 1
        cn = 0.5 * (a + b)
        if dg != 0.0:
            cn = c - g / dg
            if abs(cn - c) <= tol and a <= cn <= b:
                return b if pos == (g > 0.0) else min(b, cn + tol)
            # the root is within |g''| s^2 / (2 |g'|) < tol / 4 of cn (NaN: not known)
            s_ = cn - c
            if a <= cn <= b and abs(ddg) * s_ * s_ <= 0.5 * tol * abs(dg):
                return min(b, cn + tol)
        c = cn
    return b


@njit(cache=True)
def find_root(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om, c0):
    """:func:`_root_body` for any bar."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk,
                      f0, om, c0, X.shape[0])


@njit(cache=True)
def find_root_1(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0):
    """:func:`_root_body` for one mode and its conjugate pair (n = 1, nz = 2, ks = 2)."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 1, mk, f0,
                      om, c0, 2)


@njit(cache=True)
def find_root_2(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0):
    """:func:`_root_body` for two modes in conjugate pairs (n = 2, nz = 4, ks = 2)."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 2, mk, f0,
                      om, c0, 4)


@njit(cache=True, inline="always")
def find_root_any(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om,
                  c0):
    """:func:`find_root`, or its compilation with the sizes constant where they fit (the
    ball or solid bar with one or two modes): the same operations, unrolled."""
    # a run-time kind: numba types the constants EV_* as literals and would compile each
    # function once per event kind passed as a constant (five times, 2 minutes cold)
    kind = kind + 0
    sz = const_sizes(ks, n, X.shape[0])
    if sz == 1:
        return find_root_1(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0,
                           om, c0)
    if sz == 2:
        return find_root_2(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0,
                           om, c0)
    return find_root(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0,
                     om, c0)


@njit(cache=True, inline="always")
def _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk,
                     om, nz):
    """W at its extremum in [a, b], where W' changes sign (ga, gb: W' at a, b): Newton on W'
    from c0, kept inside the shrinking bracket, until the step s is below 2e-5 h; then W
    plus the step's quadratic correction, W - W'^2 / (2 W'').  The value's error is then
    of order |W^(3)| s^3 / 6, (Omega_max s)^3 / 6 relative, below round-off (h is
    1/16.382 of the shortest period, so Omega_max s < 7.7e-6 and the error below
    7.6e-17): no need to locate the time to 4 ulp.  From the cubic Hermite start that
    takes two evaluations, from the quintic one (a free ball's grid) usually one."""
    # borrowed: not reference-counted in this call's inlined helpers (kernels/views.py)
    seg = borrow(seg)
    q0 = borrow(q0)
    lam = borrow(lam)
    V = borrow(V)
    Z = borrow(Z)
    D = borrow(D)
    bq = borrow(bq)
    q = borrow(q)
    X = with_len(X, nz)
    Xd = with_len(Xd, nz)
    mk = borrow(mk)
    pos = gb > 0.0
    c = c0 if a < c0 < b else 0.5 * (a + b)
    tol = 2e-5 * h
    w = 0.0
    for _ in range(100):
        state_at2(r, q0, seg, c, om, lam, V, ks, Z, D, bq, q, X, Xd)
        w = 0.0
        wd = 0.0
        wdd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
            wdd += mk[3, i] * Xd[n + i]
        if wd == 0.0:
            return w
        step = -wd / wdd if wdd != 0.0 else b - a
        if abs(step) <= tol:
            return w + 0.5 * wd * step
        if (wd > 0.0) == pos:
            b = c
        else:
            a = c
        if b - a <= tol:
            return w
        cn = c + step
        c = cn if a < cn < b else 0.5 * (a + b)
    return w


@njit(cache=True)
def w_extremum(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om):
    """:func:`_w_extremum_body` for any bar."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n,
                            mk, om, X.shape[0])


@njit(cache=True)
def w_extremum_1(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om):
    """:func:`_w_extremum_body` for n = 1, nz = 2, ks = 2."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 1,
                            mk, om, 2)


@njit(cache=True)
def w_extremum_2(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om):
    """:func:`_w_extremum_body` for n = 2, nz = 4, ks = 2."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 2,
                            mk, om, 4)


@njit(cache=True, inline="always")
def w_extremum_any(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om):
    """:func:`w_extremum`, or a compilation with the sizes constant (see :func:`find_root_any`)."""
    sz = const_sizes(ks, n, X.shape[0])
    if sz == 1:
        return w_extremum_1(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om)
    if sz == 2:
        return w_extremum_2(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om)
    return w_extremum(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om)


@njit(cache=True, inline="always")
def quad_range(p, d, dd, s):
    """(lowest, highest) value of p + d x + dd x^2 / 2 on [0, s]."""
    p1 = p + s * (d + 0.5 * dd * s)
    lo = min(p, p1)
    hi = max(p, p1)
    if dd != 0.0:
        x = -d / dd
        if 0.0 < x < s:
            v = p + 0.5 * d * x
            lo = min(lo, v)
            hi = max(hi, v)
    return lo, hi


#: sub-steps of a grid step in which the bound on y^(4) allows an undetected graze
NSUB = 16


@njit(cache=True, inline="always")
def _cubic_range(p0, p1, m0, m1):
    """(lowest, highest) value on (0, 1] of the cubic Hermite interpolant of values p0, p1
    and slopes m0, m1 (per unit of s): the end s = 1 and the interior zeros of its
    derivative (s = 0 is the previous step's end, already checked)."""
    hi = p1
    lo = p1
    # p'(s) = qa s^2 + qb s + qc on (0, 1)
    qa = 6 * p0 + 3 * m0 - 6 * p1 + 3 * m1
    qb = -6 * p0 - 4 * m0 + 6 * p1 - 2 * m1
    qc = m0
    r0 = -1.0
    r1 = -1.0
    if abs(qa) > 1e-300:
        disc = qb * qb - 4 * qa * qc
        if disc >= 0.0:
            sq = math.sqrt(disc)
            r0 = (-qb - sq) / (2 * qa)
            r1 = (-qb + sq) / (2 * qa)
    elif abs(qb) > 1e-300:
        r0 = -qc / qb
    for x in (r0, r1):
        if 0.0 < x < 1.0:
            s2 = x * x
            v = ((2 * s2 * x - 3 * s2 + 1) * p0 + (s2 * x - 2 * s2 + x) * m0
                 + (-2 * s2 * x + 3 * s2) * p1 + (s2 * x - s2) * m1)
            hi = max(hi, v)
            lo = min(lo, v)
    return lo, hi


@njit(cache=True, inline="always")
def may_graze(a, b, ev_a, ev_b, half, b4):
    """Whether y may reach a wall inside [a, b]: the cubic Hermite interpolant of y from
    y, y' at the ends, widened by its error bound b4 h^4 / 384 (twice, for safety), comes
    within reach of a wall.  False guarantees that no wall event lies in the step (and
    the y' = 0 extremum of a frictionless ball need not be located)."""
    h = b - a
    p0 = ev_a[EV_PLUS] + half
    p1 = ev_b[EV_PLUS] + half
    m0 = ev_a[EV_YEXT] * h
    m1 = ev_b[EV_YEXT] * h
    margin = b4 * h ** 4 / 192.0
    # |p| <= max(|p0|, |p1|) + 4/27 (|m0| + |m1|) on [0, 1] (the Hermite basis): far from
    # both walls, nothing more to check
    if max(abs(p0), abs(p1)) + 0.15 * (abs(m0) + abs(m1)) + margin < half:
        return False
    lo, hi = _cubic_range(p0, p1, m0, m1)
    return hi + margin >= half or lo - margin <= -half


@njit(cache=True, inline="always")
def w_may_exceed(h, wa, wb, wda, wdb, bw4, max_w, min_w, max_abs_w):
    """Whether W may go above max_w, below min_w or beyond max_abs_w in magnitude inside a
    step of length h: the cubic Hermite interpolant of W, W' at the ends, widened by twice
    its error bound bw4 h^4 / 384 (bw4 bounds |W^(4)| on the step)."""
    margin = bw4 * h ** 4 / 192.0
    lo, hi = _cubic_range(wa, wb, wda * h, wdb * h)
    hi += margin
    lo -= margin
    return hi >= max_w or lo <= min_w or max(hi, -lo) >= max_abs_w


@njit(cache=True)
def wall_step(a, b, ev_a, ev_b, watch_v, watch_ext, half, seg, r, q0, lam, V, ks, Z, D, bq, qs,
               dX, Xd, n, mk, f0, om, ydd_a, ydd_b):
    """The first wall or friction-switch event of a FREE ball in [a, b], from the event
    functions at the ends and y'' there (NaN: not known): (kind, time), kind -1 if none."""
    # borrowed: not reference-counted in this call's inlined helpers (kernels/views.py)
    ev_a = borrow(ev_a)
    ev_b = borrow(ev_b)
    seg = borrow(seg)
    q0 = borrow(q0)
    lam = borrow(lam)
    V = borrow(V)
    Z = borrow(Z)
    D = borrow(D)
    bq = borrow(bq)
    qs = borrow(qs)
    dX = borrow(dX)
    Xd = borrow(Xd)
    mk = borrow(mk)
    best = b
    kind = -1
    lo = a
    hi = b
    # without friction, split the step at an extremum of y, if the extremum
    # can reach a wall: y' changes sign inside, so |y'| <= |y'(a)| + |y'(b)|
    # there to first order, and the excursion past the ends is below
    # h (|y'(a)| + |y'(b)|) (a factor 2 of margin on the mean value theorem)
    near = False
    if watch_ext and ev_a[EV_YEXT] * ev_b[EV_YEXT] < 0.0:
        reach = (b - a) * (abs(ev_a[EV_YEXT]) + abs(ev_b[EV_YEXT]))
        dmin = -max(ev_a[EV_PLUS], ev_a[EV_MINUS], ev_b[EV_PLUS], ev_b[EV_MINUS])
        near = dmin <= reach
    if near:
        te = find_root_any(EV_YEXT, a, ev_a[EV_YEXT], b, ev_b[EV_YEXT], seg, r, q0, lam,
                       V, ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om,
                       hermite(a, b, ev_a[EV_PLUS], ev_b[EV_PLUS], ev_a[EV_YEXT],
                                ev_b[EV_YEXT], 1))
        gp = g_value(EV_PLUS, te, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk, f0, om)
        gm = -2.0 * half - gp
        for kk in (EV_PLUS, EV_MINUS):
            ge = gp if kk == EV_PLUS else gm
            if ev_a[kk] <= 0.0 < ge:
                sg = 1.0 if kk == EV_PLUS else -1.0
                tr = find_root_any(kk, a, ev_a[kk], te, ge, seg, r, q0, lam, V, ks, Z, D, bq,
                               qs, dX, Xd, n, mk, f0, om,
                               hermite(a, te, ev_a[kk], ge, sg * ev_a[EV_YEXT], 0.0,
                                        0))
                if kind < 0 or tr < best:
                    best = tr
                    kind = kk
        if kind < 0:
            for kk in (EV_PLUS, EV_MINUS):
                ge = gp if kk == EV_PLUS else gm
                if ge <= 0.0 < ev_b[kk]:
                    sg = 1.0 if kk == EV_PLUS else -1.0
                    tr = find_root_any(kk, te, ge, b, ev_b[kk], seg, r, q0, lam, V, ks,
                                   Z, D, bq, qs, dX, Xd, n, mk, f0, om,
                                   hermite(te, b, ge, ev_b[kk], 0.0,
                                            sg * ev_b[EV_YEXT], 0))
                    if kind < 0 or tr < best:
                        best = tr
                        kind = kk
        lo = hi  # handled
    if lo < hi:
        # with friction, y is monotone only up to the y' = 0 switch: if the
        # switch falls in this step, look for the walls on [a, switch] only
        # (the ball may reach a wall and, past it, turn back inside the step)
        bend = b
        gpe = ev_b[EV_PLUS]
        gme = ev_b[EV_MINUS]
        yde = ev_b[EV_YEXT]
        if watch_v and ev_a[EV_VSTOP] <= 0.0 < ev_b[EV_VSTOP]:
            best = find_root_any(EV_VSTOP, a, ev_a[EV_VSTOP], b, ev_b[EV_VSTOP], seg, r,
                             q0, lam, V, ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
            kind = EV_VSTOP
            bend = best
            gpe = g_value(EV_PLUS, bend, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk,
                     f0, om)
            gme = -2.0 * half - gpe
            yde = 0.0
        for kk in (EV_PLUS, EV_MINUS):
            ge = gpe if kk == EV_PLUS else gme
            if ev_a[kk] <= 0.0 < ge:
                sg = 1.0 if kk == EV_PLUS else -1.0
                if bend == b and ydd_a == ydd_a and ydd_b == ydd_b:  # y'' known at both ends
                    c0 = hermite5(a, b, ev_a[kk], ge, sg * ev_a[EV_YEXT], sg * yde,
                                   sg * ydd_a, sg * ydd_b, 0)
                else:
                    c0 = hermite(a, bend, ev_a[kk], ge, sg * ev_a[EV_YEXT], sg * yde,
                                  0)
                tr = find_root_any(kk, a, ev_a[kk], bend, ge, seg, r, q0, lam, V, ks, Z,
                               D, bq, qs, dX, Xd, n, mk, f0, om, c0)
                if kind < 0 or tr <= best:
                    best = tr
                    kind = kk
    return kind, best
