"""One segment of the exact kernel, between two events: its start (:func:`start_segment`),
the grid search for its first event with the outputs on the way (:func:`search_segment`) and its
flows (:func:`close_segment`); the pieces are inlined into the driver.
"""

import cmath
import math

from numba import njit

from boringbar.kernels import layout as L
from boringbar.kernels.exact.consts import (
    CONTACT,
    CP_DT_OUT,
    CP_F0,
    CP_FC,
    CP_FS,
    CP_H,
    CP_HALF,
    CP_KSTICK,
    CP_KWALL,
    CP_M,
    CP_OM,
    CP_REC_DT,
    CP_SR,
    CP_T0,
    CP_T_STEADY,
    CP_TSTROBE,
    CQ_CUBIC,
    CQ_FEED,
    CQ_H,
    CQ_KRB,
    CQ_MREV,
    CQ_NREV,
    CQ_T0,
    CQ_TAU,
    CQ_TTOL,
    CQ_W0,
    EV_CUT,
    EV_HEXT,
    EV_MINUS,
    EV_PLUS,
    EV_REL_NEG,
    EV_REL_POS,
    EV_VSTOP,
    EV_WALL_REL,
    EV_YEXT,
    FREE,
    N_EV,
    RO_K_REC,
    RO_MAX_ABS_W,
    RO_MAX_AUX,
    RO_MAX_AUX_ALL,
    RO_MAX_FORCE,
    RO_MAX_W,
    RO_MIN_W,
    RO_T_STROBE,
    RS_FIRST_ZERO,
    RS_INCUT,
    RS_MODE,
    RS_SDIR,
    RS_T_END,
    RS_WALL,
    RS_Y,
    RS_YD,
    SEG_ACC,
    SEG_CDIR,
    SEG_KRB,
    SEG_S,
    STICK,
    SV_ADAPT,
    SV_B3W,
    SV_B3Y,
    SV_B4,
    SV_BW4,
    SV_STEADY,
    SV_TLEN,
    SV_WATCH_EXT,
    SV_WATCH_V,
    SV_WHOLE,
    SV_YDD,
)
from boringbar.kernels.exact.cut import GL_W, GL_X, hermite_at, quad_cut, surface_piece
from boringbar.kernels.exact.events import (
    NSUB,
    find_root_any,
    g_value,
    hermite,
    hermite5,
    may_graze,
    quad_range,
    w_extremum_any,
    w_may_exceed,
    wall_step,
)
from boringbar.kernels.exact.propagate import (
    cut_force,
    freq_rhs,
    from_q,
    nq,
    segment_integrals,
    segment_integrals_1,
    segment_integrals_2,
    state_at,
    surface_at,
)
from boringbar.kernels.views import with_len


@njit(cache=True, inline="always")
def _grid_point(r, lev, qg, eh, phg, rot, fb, Z, D, V, ks, X, ev, b, seg, mode, n, mk, f0, om,
                ydd_on, acc, ddc, nz):
    """A whole grid step of level ``lev`` outside a cut: the eigen-coordinates qg and the
    forcing phasor phg advanced (returned), X from them, the event functions at the step's
    end b and (if ``ydd_on``) y'' and W'' there (else NaN).  X is seen with length ``nz``:
    the kernel inlines this with n, ks and nz constant for one and two modes."""
    X = with_len(X, nz)
    for kq in range(nq(nz, ks)):
        k = kq * ks
        qg[k] = qg[k] * eh[r, lev, k]
    phg = phg * rot
    from_q(r, qg, phg, fb, Z, D, V, ks, X)
    _events(ev, X, b, seg, mode, n, mk, f0, om)
    if ydd_on:
        ydd, wdd = _ydd(X, f0 * phg.imag, fb, acc, ddc, n)
        return phg, ydd, wdd
    return phg, math.nan, math.nan


@njit(cache=True, inline="always")
def _ydd(X, f, fb, acc, ddc, n):
    """(y'', W'') of a free ball's bar state X under the tip force f and F_b: y'' = acc -
    psi_d . u'', W'' = psi_L . u'', M u'' = psi_L f - K u - C u' - s psi_d F_b (ddc's rows)."""
    ydd = acc - (ddc[0, n] * f + ddc[0, n + 1] * fb)
    wdd = ddc[1, n] * f + ddc[1, n + 1] * fb
    for i in range(n):
        ydd -= ddc[0, i] * X[i] + ddc[2, i] * X[n + i]
        wdd += ddc[1, i] * X[i] + ddc[3, i] * X[n + i]
    return ydd, wdd


@njit(cache=True, inline="always")
def _close_flows(T, steady, mode, ball, fb, acc, pdu, out, seg, X, n, mk, cp, rs, met):
    """Adds a segment's flows ``out`` (over its length T) to the metrics and moves a free
    ball to the segment's end (into ``rs``; pdu: psi_d . u at its start)."""
    met[L.W_FORCE] += out[0]
    met[L.D_VISC] += out[1]
    met[L.W_NONRECIP] += out[5]
    if steady:
        met[L.SUM_W2] += out[2]
        met[L.SUM_W] += out[3]
        met[L.SUM_F] += out[4]
        met[L.N_STEADY] += T
        if mode == CONTACT:
            met[L.T_CONTACT] += T
    if ball:
        pdu1 = 0.0
        pdv1 = 0.0
        for i in range(n):
            pdu1 += mk[4, i] * X[i]
            pdv1 += mk[4, i] * X[n + i]
        if mode == FREE:
            y = rs[RS_Y]
            ynew = seg[2] + T * (seg[3] + 0.5 * acc * T) - pdu1
            rs[RS_YD] = seg[3] + acc * T - pdv1
            met[L.D_FRICTION] -= fb * (ynew - y)
            met[L.W_NONRECIP] += (1.0 - cp[CP_SR]) * fb * (pdu1 - pdu)
            rs[RS_Y] = ynew


@njit(cache=True, inline="always")
def _cut_segment(t, t_stop, j_node, kn, nk, ip, sc, seg, cq, rs):
    """Where a segment of a cut that starts at t ends (the next node, delayed knot or
    change of the minimising revolution, before t_stop) and the surface on it, one cubic
    (into seg[SEG_S:SEG_S + 4]): (its end, whether that is a node, whether t is one, the
    last node reached).  ``cq``: the cut's constants (CQ_*)."""
    t0 = cq[CQ_T0]
    hh_ = cq[CQ_H]
    ttol = cq[CQ_TTOL]
    nrev = int(cq[CQ_NREV])
    tau_d = cq[CQ_TAU]
    feed = cq[CQ_FEED]
    w_before = cq[CQ_W0]
    m_rev = int(cq[CQ_MREV])
    cubic = cq[CQ_CUBIC] != 0.0
    # this segment ends at the next node, delayed knot or change of the minimising
    # revolution: the surface is one cubic on it
    while t0 + (j_node + 1) * hh_ <= t + ttol:
        j_node += 1
    t_seg_end = min(t0 + (j_node + 1) * hh_, t_stop)
    at_node = t_seg_end < t_stop
    from_node = abs(t - (t0 + j_node * hh_)) <= ttol
    if rs[RS_FIRST_ZERO] < 0.0:
        # one revolution (the minimum until the first zero): written out, as
        # surface_piece's k = 1 (no call: see the whole step below)
        for k in range(1, nrev + 1):
            kt = k * tau_d
            i = ip[k]
            while i + 1 < nk and kn[i + 1, 0] + kt <= t + ttol:
                i += 1
            ip[k] = i
        i = ip[1]
        if i < 0:
            seg[SEG_S] = feed + w_before
            seg[SEG_S + 1] = 0.0
            seg[SEG_S + 2] = 0.0
            seg[SEG_S + 3] = 0.0
        else:
            x0 = (t - tau_d) - kn[i, 0]
            if from_node and kn[i, 4] == j_node - m_rev:
                x0 = 0.0
            c0, c1, c2, c3 = hermite_at(kn[i, 0], kn[i, 1], kn[i, 3], kn[i + 1, 0],
                                         kn[i + 1, 1], kn[i + 1, 2], x0, cubic)
            seg[SEG_S] = feed + c0
            seg[SEG_S + 1] = c1
            seg[SEG_S + 2] = c2
            seg[SEG_S + 3] = c3
        if i + 1 < nk:
            tn = kn[i + 1, 0] + tau_d
            if t + ttol < tn < t_seg_end - ttol:
                t_seg_end = tn
                at_node = False
    else:
        t_piece = surface_piece(t, t_seg_end, ttol, kn, nk, ip, sc, nrev, nrev, feed,
                                 w_before, tau_d, seg, j_node if from_node else -1,
                                 m_rev, cubic)
        if t_piece < t_seg_end:
            t_seg_end = t_piece
            at_node = False
    return t_seg_end, at_node, from_node, j_node


@njit(cache=True, inline="always")
def _bounds(r, q0, seg, lam, bq, bnd, krb, ball, incut, w_steady, adapt):
    """Bounds over a segment (regime r, eigen-coordinates q0) from prepare's ``bnd``:
    (|y^(4)| if ``ball``, |W^(4)| if ``w_steady`` (else -1), |y^(3)| and |W^(3)| if
    ``adapt`` (else 0))."""
    nz = q0.shape[0]
    # a bound on |y^(4)| = |psi_d . u^(4)| over the segment (|exp(lambda tau)| <= 1)
    b4 = 0.0
    if ball:
        b4 = bnd[r, 0, nz]  # Omega^4 |psi_d . Z| (prepare's bnd)
        for k in range(nz):
            qk = q0[k]
            if incut:
                # minus the polynomial particular solution P of q' = lambda q + g(tau)
                # (P^(4) = 0 for a cubic g); |exp(lambda tau)| <= 1 still
                lk = lam[r, k]
                gk = krb * bq[r, k]
                p3 = -gk * seg[SEG_S + 3] / lk
                p2 = (3.0 * p3 - gk * seg[SEG_S + 2]) / lk
                p1 = (2.0 * p2 - gk * seg[SEG_S + 1]) / lk
                qk = qk - (p1 - gk * seg[SEG_S]) / lk
            b4 += bnd[r, 0, k] * abs(qk)  # |lambda_k|^4 |psi_d . V_k| |q_k|
    # the same bound on |W^(4)| = |psi_L . u^(4)| in the steady window under harmonic
    # forcing: a W' = 0 extremum is located only where it may beat the running extremes
    bw4 = -1.0
    if w_steady:
        bw4 = bnd[r, 1, nz]
        for k in range(nz):
            bw4 += bnd[r, 1, k] * abs(q0[k])
    # a free ball under harmonic forcing: y'' and W'' at its grid points (the walls'
    # and extrema's quintic starts); with more than one mode it steps longer than h
    # where it can, from bounds on |y'''| = |psi_d . u'''| and |W'''| over the segment
    b3y = 0.0
    b3w = 0.0
    if adapt:
        b3y = bnd[r, 2, nz]
        b3w = bnd[r, 3, nz]
        for k in range(nz):
            aq = abs(q0[k])
            b3y += bnd[r, 2, k] * aq
            b3w += bnd[r, 3, k] * aq
    return b4, bw4, b3y, b3w


@njit(cache=True, inline="always")
def _level(ya, yda, ydd_a, wa, wda, wdd_a, b3y, b3w, ylim, wmar, max_w, min_w, hl, top,
           watch_v, steady):
    """The longest step 2^lev h (lev <= top) from a free ball's grid point a (y + delta/2 = ya,
    y' = yda, y'' = ydd_a, W, W', W'' = wa, wda, wdd_a) that Taylor's
    theorem proves free of events and of new extrema of |y| (below ylim) or (steady) of W:
    on [a, a + s], y lies within b3y s^3 / 6 of its quadratic Taylor polynomial at a, y'
    within b3y s^2 / 2 of its linear one, W within b3w s^3 / 6 of its quadratic; the step
    is taken if these ranges stay inside the walls and below the largest |y| seen, keep y'
    off 0 (friction) and keep W strictly between its running extremes (less wmar)."""
    lev = 0
    for lv in range(1, top + 1):
        hs = hl[lv]
        lo, hi = quad_range(ya, yda, ydd_a, hs)
        e3 = b3y * hs * hs * hs / 6.0
        if not (hi + e3 < ylim and lo - e3 > -ylim):
            break
        if watch_v:
            e2 = b3y * hs * hs * (0.5 + 1e-9)
            v1 = yda + ydd_a * hs
            if not ((yda > e2 and v1 > e2) or (yda < -e2 and v1 < -e2)):
                break
        if steady:
            lo, hi = quad_range(wa, wda, wdd_a, hs)
            e3 = b3w * hs * hs * hs / 6.0 + wmar
            if not (hi + e3 < max_w and lo - e3 > min_w):
                break
        lev = lv
    return lev


@njit(cache=True, inline="always")
def _find_event(w, a, b, r, ks, n, f0, om, mode, ball, regen, watch_v, watch_ext, b4, lev,
                ydd_a, ydd_b):
    """The first event in the grid step [a, b] of the segment (regime r, ``mode``) from the
    event functions at its ends (w.ev_a, w.ev_b) and (a free ball) y'' there: (kind, time),
    kind -1 if none.  ``w``: the driver's arrays (:data:`Work`); b4 bounds |y^(4)|."""
    seg = w.seg
    q0 = w.q0
    lam = w.lam
    V = w.V
    Z = w.Z
    D = w.D
    bq = w.bq
    qs = w.qs
    dX = w.dX
    Xd = w.Xd
    mk = w.mk
    ev_a = w.ev_a
    ev_b = w.ev_b
    ev_s = w.ev_s
    ev_t = w.ev_t
    half = w.cp[CP_HALF]
    watch_wall = ball and mode == FREE
    best = b
    kind = -1
    if ball and mode != FREE:
        for kk in (EV_REL_NEG, EV_REL_POS, EV_WALL_REL):
            if (mode == STICK) == (kk != EV_WALL_REL):
                if ev_a[kk] <= 0.0 < ev_b[kk]:
                    tr = find_root_any(kk, a, ev_a[kk], b, ev_b[kk], seg, r, q0, lam, V, ks, Z,
                                   D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
                    if tr < best or kind < 0:
                        best = tr
                        kind = kk
    elif watch_wall:
        # call the (not inlined) search only when an end value shows something, or
        # y' changes sign and the bound on y lets the ball reach a wall
        # (a longer step than h holds no wall event: see its choice)
        graze = lev == 0 and may_graze(a, b, ev_a, ev_b, half, b4)
        if ((ev_a[EV_PLUS] <= 0.0 < ev_b[EV_PLUS])
                or (ev_a[EV_MINUS] <= 0.0 < ev_b[EV_MINUS])
                or (watch_v and ev_a[EV_VSTOP] <= 0.0 < ev_b[EV_VSTOP])
                or (graze and watch_ext and ev_a[EV_YEXT] * ev_b[EV_YEXT] < 0.0)):
            kind, best = wall_step(a, b, ev_a, ev_b, watch_v, watch_ext, half, seg, r,
                                    q0, lam, V, ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om,
                                    ydd_a, ydd_b)
        if kind < 0 and graze:
            # the bound on y^(4) allows a crossing and return inside the step:
            # look again on NSUB sub-steps (direct evaluations)
            for kk in range(N_EV):
                ev_s[kk] = ev_a[kk]
            sa = a
            for j in range(1, NSUB + 1):
                sb = a + (b - a) * j / NSUB if j < NSUB else b
                if j < NSUB:
                    state_at(r, q0, seg, sb, om, lam, V, ks, Z, D, bq, qs, dX)
                    _events(ev_t, dX, sb, seg, mode, n, mk, f0, om)
                else:
                    for kk in range(N_EV):
                        ev_t[kk] = ev_b[kk]
                kind, best = wall_step(sa, sb, ev_s, ev_t, watch_v, watch_ext, half,
                                        seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, Xd, n,
                                        mk, f0, om, math.nan, math.nan)
                if kind >= 0:
                    break
                sa = sb
                for kk in range(N_EV):
                    ev_s[kk] = ev_t[kk]
    if regen:
        # the tool leaves (in the cut) or re-enters (out of it): h = 0, or a graze
        # of h = 0 between the step's ends, found at the extremum of h
        tr = -1.0
        if ev_a[EV_CUT] <= 0.0 < ev_b[EV_CUT]:
            tr = find_root_any(EV_CUT, a, ev_a[EV_CUT], b, ev_b[EV_CUT], seg, r, q0, lam, V,
                           ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
        elif ev_a[EV_HEXT] * ev_b[EV_HEXT] < 0.0:
            te = find_root_any(EV_HEXT, a, ev_a[EV_HEXT], b, ev_b[EV_HEXT], seg, r, q0, lam, V,
                           ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
            ge = g_value(EV_CUT, te, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk, f0, om)
            if ev_a[EV_CUT] <= 0.0 < ge:
                tr = find_root_any(EV_CUT, a, ev_a[EV_CUT], te, ge, seg, r, q0, lam, V, ks, Z,
                               D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
        if tr >= 0.0 and (kind < 0 or tr < best):
            best = tr
            kind = EV_CUT
    return kind, best


@njit(cache=True, inline="always")
def _cut_flows(w, a, b, r, ks, n, whole, sticking, steady, wb, max_force):
    """Adds a cut's flows over the grid step [a, b] to w.qsum (the slots of
    :func:`segment_integrals`' ``out``); ``whole``: a whole step H from a node, without event, from
    the tables (written out: no call); wb: W at b.  Returns the largest cutting force so
    far."""
    seg = w.seg
    q0 = w.q0
    lam = w.lam
    V = w.V
    Z = w.Z
    D = w.D
    bq = w.bq
    qs = w.qs
    dX = w.dX
    mk = w.mk
    qsum = w.qsum
    tabE = w.tabE
    tabP = w.tabP
    lvis = w.lvis
    cvis = w.cvis
    nz = q0.shape[0]
    fb = seg[1]
    sr = w.cp[CP_SR]
    kappa_stick = w.cp[CP_KSTICK]
    krb_seg = seg[SEG_KRB]
    s_0 = seg[SEG_S]
    s_1 = seg[SEG_S + 1]
    s_2 = seg[SEG_S + 2]
    s_3 = seg[SEG_S + 3]
    # Gauss-Legendre (4 points, exact to degree 7) for the flows of the step:
    # the input is a cubic, no longer a sum of exponentials
    if whole and not (sticking and sr != 1.0):
        # a whole step: tabulated values, written out (as above)
        for g in range(4):
            for kq in range(nq(nz, ks)):
                k = kq * ks
                qs[k] = (q0[k] * tabE[r, g, k] + s_0 * tabP[r, g, 0, k]
                         + s_1 * tabP[r, g, 1, k] + s_2 * tabP[r, g, 2, k]
                         + s_3 * tabP[r, g, 3, k])
            for j in range(nz):
                sx = fb * D[r, j]
                for kq in range(nq(nz, ks)):
                    k = kq * ks
                    sx += (V[r, j, k] * qs[k]).real
                dX[j] = sx
            wq = 0.0
            wdq = 0.0
            for i in range(n):
                wq += mk[3, i] * dX[i]
                wdq += mk[3, i] * dX[n + i]
            xg = GL_X[g] * b
            fq = krb_seg * (s_0 + xg * (s_1 + xg * (s_2 + xg * s_3)) - wq)
            max_force = max(max_force, fq)
            wg = GL_W[g] * b
            qsum[0] += wg * fq * wdq
            dv = 0.0
            for d in range(lvis.shape[0]):
                vv = 0.0
                for j in range(nz):
                    vv += lvis[d, j] * dX[j]
                dv += cvis[d] * vv * vv
            qsum[1] += wg * dv
            if steady:
                qsum[2] += wg * wq * wq
                qsum[3] += wg * wq
                qsum[4] += wg * fq
    else:
        max_force = max(max_force, quad_cut(a, b, seg, r, q0, lam, V, ks, Z, D, bq,
                                             qs, dX, n, mk, lvis, cvis,
                                             sticking, kappa_stick, sr, qsum,
                                             steady))
    max_force = max(max_force, krb_seg * (s_0 + b * (s_1 + b * (s_2 + b * s_3)) - wb))
    return max_force


@njit(cache=True, inline="always")
def _sample(w, tau, r, ks, n, om, mode, case, ball, x, row):
    """The state at ``tau`` into the work vector dX and row[1:5]: W, W', aux, aux' (a
    history or strobe row; its time, row[0], is the caller's)."""
    dX = w.dX
    mk = w.mk
    state_at(r, w.q0, w.seg, tau, om, w.lam, w.V, ks, w.Z, w.D, w.bq, w.qs, dX)
    wv = 0.0
    wdv = 0.0
    for i in range(n):
        wv += mk[3, i] * dX[i]
        wdv += mk[3, i] * dX[n + i]
    av, adv = _aux(dX, tau, w.seg, mode, case, n, mk, x, ball)
    row[1] = wv
    row[2] = wdv
    row[3] = av
    row[4] = adv


@njit(cache=True, inline="always")
def _samples(w, t, b, t_end, r, ks, n, f0, om, mode, case, ball, x, rec, strobe, rec_dt,
             tstrobe, k_rec, t_next_strobe, met):
    """The history rows (every rec_dt from t0) and strobe rows (every tstrobe) that fall in
    (t + a, t + b] of the segment from t; returns the next ones' (k_rec, t_next_strobe)."""
    seg = w.seg
    dX = w.dX
    mk = w.mk
    t0 = w.cp[CP_T0]
    n_rec = int(met[L.N_REC])
    while (rec_dt > 0.0 and n_rec < rec.shape[0]
           and t0 + k_rec * rec_dt <= t + b + 1e-9 * rec_dt):
        ts_ = t0 + k_rec * rec_dt
        if ts_ > t_end:
            break
        rec[n_rec, 0] = ts_
        _sample(w, ts_ - t, r, ks, n, om, mode, case, ball, x, rec[n_rec])
        rec[n_rec, 5] = cut_force(seg, ts_ - t, dX, n, mk, f0, om)
        n_rec += 1
        k_rec += 1
    met[L.N_REC] = n_rec
    n_stb = int(met[L.N_STROBE])
    while tstrobe > 0.0 and t_next_strobe <= t + b and t_next_strobe <= t_end:
        if n_stb < strobe.shape[0]:
            strobe[n_stb, 0] = t_next_strobe
            _sample(w, t_next_strobe - t, r, ks, n, om, mode, case, ball, x, strobe[n_stb])
            n_stb += 1
        t_next_strobe += tstrobe
    met[L.N_STROBE] = n_stb
    return k_rec, t_next_strobe


@njit(cache=True, inline="always")
def _advance(w, t, r, ks, sz, n, mode, lev, b, usual, tab_end, regen, ball, ydd_on, phg, ydd_b,
             wdd_b):
    """The state at the grid point b of the segment from t into w.X (and w.qg, the
    eigen-coordinates, and phg, the forcing phasor, on the usual grid) and the event
    functions there into w.ev_b: a usual grid step (``usual``) of level ``lev``, the
    tabulated end of a cut's whole step (``tab_end``), or the closed form.  Returns
    (phg, y'' and W'' at b, or ydd_b and wdd_b as they were where not evaluated)."""
    X = w.X
    q0 = w.q0
    qg = w.qg
    seg = w.seg
    ev_b = w.ev_b
    mk = w.mk
    ddc = w.ddc
    lam = w.lam
    V = w.V
    Z = w.Z
    D = w.D
    bq = w.bq
    eh = w.eh
    tabE = w.tabE
    tabP = w.tabP
    nz = q0.shape[0]
    f0 = w.cp[CP_F0]
    om = w.cp[CP_OM]
    fb = seg[1]
    acc = seg[SEG_ACC]
    s_0 = seg[SEG_S]
    s_1 = seg[SEG_S + 1]
    s_2 = seg[SEG_S + 2]
    s_3 = seg[SEG_S + 3]
    if usual:
        # the usual grid point, inlined with the sizes constant for one and two modes
        rot = w.rotl[lev]
        if sz == 1:
            phg, ydd_b, wdd_b = _grid_point(r, lev, qg, eh, phg, rot, fb, Z, D, V, 2, X,
                                            ev_b, b, seg, mode, 1, mk, f0, om, ydd_on,
                                            acc, ddc, 2)
        elif sz == 2:
            phg, ydd_b, wdd_b = _grid_point(r, lev, qg, eh, phg, rot, fb, Z, D, V, 2, X,
                                            ev_b, b, seg, mode, 2, mk, f0, om, ydd_on,
                                            acc, ddc, 4)
        else:
            phg, ydd_b, wdd_b = _grid_point(r, lev, qg, eh, phg, rot, fb, Z, D, V, ks, X,
                                            ev_b, b, seg, mode, n, mk, f0, om, ydd_on,
                                            acc, ddc, nz)
    elif tab_end:
        # the tabulated end of a whole step, written out: numba reference-counts
        # the array arguments of every call, even inlined (docs/performance.md)
        for kq in range(nq(nz, ks)):
            k = kq * ks
            qg[k] = (q0[k] * tabE[r, 4, k] + s_0 * tabP[r, 4, 0, k]
                     + s_1 * tabP[r, 4, 1, k] + s_2 * tabP[r, 4, 2, k]
                     + s_3 * tabP[r, 4, 3, k])
        for j in range(nz):
            sx = fb * D[r, j]
            for kq in range(nq(nz, ks)):
                k = kq * ks
                sx += (V[r, j, k] * qg[k]).real
            X[j] = sx
    else:
        state_at(r, q0, seg, b, om, lam, V, ks, Z, D, bq, qg, X)
        phg = cmath.exp(1j * om * (t + b))
    if not usual and (ball or not regen):
        _events(ev_b, X, b, seg, mode, n, mk, f0, om)
        if ydd_on:
            ydd_b, wdd_b = _ydd(X, f0 * phg.imag, fb, acc, ddc, n)
    elif regen:
        wq = 0.0
        wdq = 0.0
        for i in range(n):
            wq += mk[3, i] * X[i]
            wdq += mk[3, i] * X[n + i]
        ev_b[EV_CUT] = seg[SEG_CDIR] * (wq - (s_0 + b * (s_1 + b * (s_2 + b * s_3))))
        ev_b[EV_HEXT] = s_1 + b * (2.0 * s_2 + 3.0 * b * s_3) - wdq
    return phg, ydd_b, wdd_b


@njit(cache=True, inline="always")
def search_segment(w, t, r, ks, sz, n, case, mode, ph, sv, regen):
    """The grid search of the segment from t (regime r, ``mode``, forcing phasor ph at t,
    its description ``sv``, SV_*) for its first event, with the outputs on the way: the
    running extremes and output times in w.ro (RO_*), a cut's flows in w.qsum, history
    and strobe rows (``regen``: a cut, constant per kernel, driver.py).  Returns (event
    kind or -1, its time from t or the segment's length, the forcing phasor there, W, W')."""
    X = w.X
    Xa = w.Xa
    Xd = w.Xd
    dX = w.dX
    q0 = w.q0
    qs = w.qs
    qg = w.qg
    seg = w.seg
    ev_a = w.ev_a
    ev_b = w.ev_b
    qsum = w.qsum
    mk = w.mk
    lam = w.lam
    V = w.V
    Z = w.Z
    D = w.D
    bq = w.bq
    levmax = w.levmax
    hl = w.hl
    ddc = w.ddc
    x = w.x
    rec = w.rec
    strobe = w.strobe
    met = w.met
    ro = w.ro
    cp = w.cp
    nz = q0.shape[0]
    ball = case == L.BALL
    f0 = cp[CP_F0]
    om = cp[CP_OM]
    h = cp[CP_H]
    half = cp[CP_HALF]
    rec_dt = cp[CP_REC_DT]
    tstrobe = cp[CP_TSTROBE]
    t_end = w.rs[RS_T_END]
    fb = seg[1]
    acc = seg[SEG_ACC]
    s_0 = seg[SEG_S]
    s_1 = seg[SEG_S + 1]
    tlen = sv[SV_TLEN]
    b4 = sv[SV_B4]
    bw4 = sv[SV_BW4]
    b3y = sv[SV_B3Y]
    b3w = sv[SV_B3W]
    steady = sv[SV_STEADY] != 0.0
    whole = sv[SV_WHOLE] != 0.0
    adapt = sv[SV_ADAPT] != 0.0
    ydd_on = sv[SV_YDD] != 0.0
    watch_v = sv[SV_WATCH_V] != 0.0
    watch_ext = sv[SV_WATCH_EXT] != 0.0
    max_abs_w = ro[RO_MAX_ABS_W]
    max_w = ro[RO_MAX_W]
    min_w = ro[RO_MIN_W]
    max_aux = ro[RO_MAX_AUX]
    max_aux_all = ro[RO_MAX_AUX_ALL]
    max_force = ro[RO_MAX_FORCE]
    k_rec = ro[RO_K_REC]
    t_next_strobe = ro[RO_T_STROBE]
    ph_next = ph
    wb = 0.0
    wdb = 0.0
    # values at tau = 0
    a = 0.0
    for j in range(nz):
        Xa[j] = X[j]
    for k in range(nz):
        qg[k] = q0[k]
    phg = ph
    ev_kind = -1
    tau_ev = tlen
    istep = 0
    # the values at a (carried over from the previous grid point)
    wa = 0.0
    wda = 0.0
    for i in range(n):
        wa += mk[3, i] * Xa[i]
        wda += mk[3, i] * Xa[n + i]
    if ball or not regen:
        _events(ev_a, Xa, a, seg, mode, n, mk, f0, om)
    else:  # only h matters; written out (no call, see the whole step below)
        ev_a[EV_CUT] = seg[SEG_CDIR] * (wa - s_0)
        ev_a[EV_HEXT] = s_1 - wda
    # a segment never starts beyond a wall (events put the ball on it); the closed
    # form's y(0) may be a few ulp past it, which would hide a return to that wall
    ev_a[EV_PLUS] = min(ev_a[EV_PLUS], 0.0)
    ev_a[EV_MINUS] = min(ev_a[EV_MINUS], 0.0)
    # nor past h = 0 (an event put it there; the re-evaluated h may be a few ulp off)
    ev_a[EV_CUT] = min(ev_a[EV_CUT], 0.0)
    for c in range(6):
        qsum[c] = 0.0
    auxa = 0.0
    auxda = 0.0
    if case != L.SOLID:
        auxa, auxda = _aux(Xa, a, seg, mode, case, n, mk, x, ball)
    ydd_a = math.nan
    wdd_a = math.nan
    ydd_b = math.nan
    wdd_b = math.nan
    if ydd_on:
        ydd_a, wdd_a = _ydd(Xa, f0 * ph.imag, fb, acc, ddc, n)
    while True:
        # the step: h, or 2^lv h where Taylor's theorem proves that it holds no event
        # and no new extremum of |y| or (steady) of W: on [a, a + s], y lies within
        # b3y s^3 / 6 of its quadratic Taylor polynomial at a, y' within b3y s^2 / 2 of
        # its linear one, W within b3w s^3 / 6 of its quadratic; the step is taken if
        # these ranges stay inside the walls and below the largest |y| seen, keep y' off
        # 0 (friction) and keep W strictly between its running extremes
        lev = 0
        if adapt:
            ylim = min(half, max_aux if steady else max_aux_all) * (1.0 - 1e-9)
            lev = _level(ev_a[EV_PLUS] + half, ev_a[EV_YEXT], ydd_a, wa, wda, wdd_a, b3y,
                         b3w, ylim, 1e-9 * max_abs_w, max_w, min_w, hl, levmax[r], watch_v,
                         steady)
        b = a + hl[lev]
        full = True
        if b >= tlen:
            b = tlen
            full = False
        istep += 1
        usual = full and istep % 64 != 0 and not regen
        phg, ydd_b, wdd_b = _advance(w, t, r, ks, sz, n, mode, lev, b, usual,
                                     whole and not full, regen, ball, ydd_on, phg, ydd_b,
                                     wdd_b)
        # --- events in [a, b]
        kind, best = _find_event(w, a, b, r, ks, n, f0, om, mode, ball, regen, watch_v,
                                 watch_ext, b4, lev, ydd_a, ydd_b)
        if kind >= 0:
            b = best
            ph_next = state_at(r, q0, seg, b, om, lam, V, ks, Z, D, bq, qs, X)
            ev_kind = kind
            tau_ev = b
        # --- outputs on (a, b]
        wb = 0.0
        wdb = 0.0
        for i in range(n):
            wb += mk[3, i] * X[i]
            wdb += mk[3, i] * X[n + i]
        if steady:
            max_abs_w = max(max_abs_w, abs(wb))
            max_w = max(max_w, wb)
            min_w = min(min_w, wb)
            if lev == 0 and wda * wdb < 0.0 and (bw4 < 0.0 or w_may_exceed(
                    b - a, wa, wb, wda, wdb, bw4, max_w, min_w, max_abs_w)):
                if kind < 0 and wdd_a == wdd_a and wdd_b == wdd_b:  # W'' at both ends
                    c0 = hermite5(a, b, wa, wb, wda, wdb, wdd_a, wdd_b, 1)
                else:
                    c0 = hermite(a, b, wa, wb, wda, wdb, 1)
                we = w_extremum_any(a, wda, b, wdb, c0, h, seg, r, q0, lam, V, ks, Z, D,
                                     bq, qs, dX, Xd, n, mk, om)
                max_abs_w = max(max_abs_w, abs(we))
                max_w = max(max_w, we)
                min_w = min(min_w, we)
        if regen:
            max_force = _cut_flows(w, a, b, r, ks, n, whole and kind < 0, mode == STICK,
                                   steady, wb, max_force)
        # aux and aux' at a and b
        auxb = 0.0
        auxdb = 0.0
        if case != L.SOLID:
            auxb, auxdb = _aux(X, b, seg, mode, case, n, mk, x, ball)
        if kind == EV_PLUS or kind == EV_MINUS:
            auxb = half if kind == EV_PLUS else -half  # on the wall, up to round-off
        max_aux_all = max(max_aux_all, abs(auxb))
        if steady:
            max_aux = max(max_aux, abs(auxb))
            if regen or not ball:  # a ball's int y^2 is closed form (segment_integrals)
                hh = b - a
                met[L.SUM_AUX2] += (0.5 * hh * (auxa * auxa + auxb * auxb)
                             + hh * hh / 6.0 * (auxa * auxda - auxb * auxdb))
        # history and strobe samples in (t + a, t + b]
        if rec_dt > 0.0 or tstrobe > 0.0:
            k_rec, t_next_strobe = _samples(w, t, b, t_end, r, ks, n, f0, om, mode, case,
                                            ball, x, rec, strobe, rec_dt, tstrobe, k_rec,
                                            t_next_strobe, met)
        if kind >= 0 or not full:
            break
        a = b
        wa = wb
        wda = wdb
        ydd_a = ydd_b
        wdd_a = wdd_b
        auxa = auxb
        auxda = auxdb
        for kk in range(N_EV):
            ev_a[kk] = ev_b[kk]

    ro[RO_MAX_ABS_W] = max_abs_w
    ro[RO_MAX_W] = max_w
    ro[RO_MIN_W] = min_w
    ro[RO_MAX_AUX] = max_aux
    ro[RO_MAX_AUX_ALL] = max_aux_all
    ro[RO_MAX_FORCE] = max_force
    ro[RO_K_REC] = k_rec
    ro[RO_T_STROBE] = t_next_strobe
    return ev_kind, tau_ev, ph_next, wb, wdb


@njit(cache=True, inline="always")
def start_segment(w, t, t_stop, ph, n, case, nreg, j_node, kn, nk, ip, sc, cq, sv, regen):
    """A segment from t (forcing phasor ph there) in the run's state w.rs: its regime r,
    its eigen-coordinates into w.q0, its record into w.seg, its description into ``sv``
    (SV_*) and, in a cut (``regen``, constant), its end and surface.  Returns (r, ks, its
    end (at most t_stop), whether that is a cut's node, the last node reached, psi_d . u
    at t)."""
    X = w.X
    dX = w.dX
    q0 = w.q0
    seg = w.seg
    mk = w.mk
    lam = w.lam
    Z = w.Z
    D = w.D
    bq = w.bq
    Vi = w.Vi
    bnd = w.bnd
    rs = w.rs
    cp = w.cp
    nz = q0.shape[0]
    ball = case == L.BALL
    t_steady = cp[CP_T_STEADY]
    fc = cp[CP_FC]
    kappa_stick = cp[CP_KSTICK]
    kappa_wall = cp[CP_KWALL]
    fs = cp[CP_FS]
    half = cp[CP_HALF]
    m = cp[CP_M]
    h = cp[CP_H]
    hh_ = cq[CQ_H]
    krb = cq[CQ_KRB]
    mode = int(rs[RS_MODE])
    sdir = rs[RS_SDIR]
    wall = rs[RS_WALL]
    y = rs[RS_Y]
    yd = rs[RS_YD]
    incut = rs[RS_INCUT] != 0.0
    t_seg_end = t_stop
    steady = t >= t_steady
    r = 0
    if ball:
        r = mode
    if incut:
        r += nreg
    fb = 0.0
    if mode == FREE and ball:
        fb = -fc * sdir
    kap = kappa_stick if mode == STICK else kappa_wall
    ks = w.kstep[r]
    for j in range(nz):
        dX[j] = X[j] - ((Z[r, j] * ph).imag + fb * D[r, j])
    for k in range(nz):
        s = 0.0 + 0.0j
        for j in range(nz):
            s += Vi[r, k, j] * dX[j]
        q0[k] = s
    at_node = False
    whole = False
    if regen:
        t_seg_end, at_node, from_node, j_node = _cut_segment(t, t_stop, j_node, kn, nk, ip, sc,
                                                             seg, cq, rs)
        seg[SEG_KRB] = krb if incut else 0.0
        seg[SEG_CDIR] = 1.0 if incut else -1.0
        # a whole step H from node to node, inside one grid step: tabulated values
        whole = at_node and from_node and hh_ <= h
    pdu = 0.0
    pdv = 0.0
    for i in range(n):
        pdu += mk[4, i] * X[i]
        pdv += mk[4, i] * X[n + i]
    # bounds on |y^(4)|, |W^(4)| (steady, harmonic) and |y^(3)|, |W^(3)| (a free ball)
    # over the segment
    ydd_on = ball and mode == FREE and not regen
    adapt = ydd_on and w.levmax[r] > 0
    b4, bw4, b3y, b3w = _bounds(r, q0, seg, lam, bq, bnd, krb, ball, incut,
                                steady and not regen, adapt)
    seg[0] = t
    seg[1] = fb
    seg[2] = y + pdu  # the ball's absolute position and velocity
    seg[3] = yd + pdv
    seg[4] = y
    seg[5] = sdir
    seg[6] = wall
    seg[7] = kap
    seg[8] = fs
    seg[9] = half
    seg[10] = m if m > 0.0 else 1.0
    acc = fb / seg[10]
    seg[SEG_ACC] = acc
    # which events are watched
    watch_wall = ball and mode == FREE
    watch_v = watch_wall and fc > 0.0 and sdir != 0.0
    watch_ext = watch_wall and not watch_v
    tlen = t_seg_end - t
    sv[SV_TLEN] = tlen
    sv[SV_B4] = b4
    sv[SV_BW4] = bw4
    sv[SV_B3Y] = b3y
    sv[SV_B3W] = b3w
    sv[SV_STEADY] = 1.0 if steady else 0.0
    sv[SV_WHOLE] = 1.0 if whole else 0.0
    sv[SV_ADAPT] = 1.0 if adapt else 0.0
    sv[SV_YDD] = 1.0 if ydd_on else 0.0
    sv[SV_WATCH_V] = 1.0 if watch_v else 0.0
    sv[SV_WATCH_EXT] = 1.0 if watch_ext else 0.0
    return r, ks, t_seg_end, at_node, j_node, pdu


@njit(cache=True, inline="always")
def close_segment(w, t, T, r, ks, sz, n, case, mode, ph, steady, pdu, last_zero_step, regen):
    """The flows of the segment [t, t + T] (regime r, forcing phasor ph at t; a cut's from
    w.qsum (``regen``, constant), else closed form) into the metrics, a cut's steps with
    h = 0 counted, a free ball moved to t + T.  Returns the last step of length dt_out
    counted with h = 0."""
    X = w.X
    q0 = w.q0
    seg = w.seg
    mk = w.mk
    out = w.out
    qsum = w.qsum
    met = w.met
    cp = w.cp
    lam = w.lam
    Vfull = w.Vfull
    Z = w.Z
    D = w.D
    lvis = w.lvis
    cvis = w.cvis
    isum = w.isum
    me = w.me
    G = w.G
    Cx = w.Cx
    cf = w.cf
    ca = w.ca
    cb = w.cb
    phj = w.phj
    ball = case == L.BALL
    incut = w.rs[RS_INCUT] != 0.0
    t0 = cp[CP_T0]
    dt_out = cp[CP_DT_OUT]
    f0 = cp[CP_F0]
    om = cp[CP_OM]
    sr = cp[CP_SR]
    kappa_stick = cp[CP_KSTICK]
    fb = seg[1]
    acc = seg[SEG_ACC]
    if regen:
        for c in range(6):
            out[c] = qsum[c]
        if not incut:  # the steps of length dt_out touched with h = 0
            js = max(int(math.floor((t - t0) / dt_out)), last_zero_step + 1)
            je = int(math.ceil((t + T - t0) / dt_out)) - 1
            if je >= js:
                met[L.N_ZERO_STEPS] += je - js + 1
                last_zero_step = je
    else:
        kst = kappa_stick if (ball and mode == STICK) else 0.0
        # what to integrate: 0 the energy flows, 1 also the steady W sums, 2 also a
        # free ball's y^2
        level = (2 if ball and mode == FREE else 1) if steady else 0
        # compiled with the sizes constant for one and two modes (kept out of line:
        # the kernel's own compilation does not grow)
        if sz == 1:
            segment_integrals_1(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, mk, lvis, cvis, kst,
                         sr, me, G, Cx, cf, ca, cb, out, isum, level, seg, phj)
        elif sz == 2:
            segment_integrals_2(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, mk, lvis, cvis, kst,
                         sr, me, G, Cx, cf, ca, cb, out, isum, level, seg, phj)
        else:
            segment_integrals(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, n, mk, lvis, cvis, kst,
                       sr, me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj)
        if ball and steady:
            # the ball's int y^2: closed form when free, y constant otherwise
            met[L.SUM_AUX2] += out[6] if mode == FREE else seg[4] * seg[4] * T
    _close_flows(T, steady, mode, ball, fb, acc, pdu, out, seg, X, n, mk, cp, w.rs, met)
    return last_zero_step


@njit(cache=True, inline="always")
def _events(ev, X, tau, seg, mode, n, mk, f0, om):
    """All event functions from the state X at tau (see :func:`g_value`)."""
    pdu = 0.0
    pdv = 0.0
    for i in range(n):
        pdu += mk[4, i] * X[i]
        pdv += mk[4, i] * X[n + i]
    acc = seg[SEG_ACC]
    y = seg[2] + tau * (seg[3] + 0.5 * acc * tau) - pdu
    yd = seg[3] + acc * tau - pdv
    ev[EV_PLUS] = y - seg[9]
    ev[EV_MINUS] = -seg[9] - y
    ev[EV_VSTOP] = -seg[5] * yd
    ev[EV_YEXT] = yd
    if seg[SEG_CDIR] != 0.0:
        w = 0.0
        wd = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
            wd += mk[3, i] * X[n + i]
        sv, sd = surface_at(seg, tau)
        ev[EV_CUT] = seg[SEG_CDIR] * (w - sv)
        ev[EV_HEXT] = sd - wd
    if mode != FREE:
        F = freq_rhs(X, cut_force(seg, tau, X, n, mk, f0, om), n, mk, seg[7])
        ev[EV_REL_NEG] = F - seg[8]
        ev[EV_REL_POS] = -F - seg[8]
        ev[EV_WALL_REL] = seg[6] * F - seg[8]


@njit(cache=True, inline="always")
def _aux(X, tau, seg, mode, case, n, mk, x, ball):
    """(aux, aux'): the ball's y, y' or the absorber's stroke and its rate."""
    if ball:
        if mode != FREE:
            return seg[4], 0.0
        pdu = 0.0
        pdv = 0.0
        for i in range(n):
            pdu += mk[4, i] * X[i]
            pdv += mk[4, i] * X[n + i]
        acc = seg[SEG_ACC]
        return seg[2] + tau * (seg[3] + 0.5 * acc * tau) - pdu, seg[3] + acc * tau - pdv
    if case == L.TMD:
        a = X[2 * n]
        ad = X[2 * n + 1]
        for i in range(n):
            a -= mk[5, i] * X[i]
            ad -= mk[5, i] * X[n + i]
        return a, ad
    if case == L.LOCKED:
        return x[2 * n], 0.0
    return 0.0, 0.0
