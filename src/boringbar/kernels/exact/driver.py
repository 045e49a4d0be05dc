"""The exact kernel's driver: :func:`_exact`, the event loop over segments, and
:func:`run_exact`, its entry point.
"""

import cmath
import math
from collections import namedtuple

import numpy as np
from numba import carray, njit

from boringbar.kernels import layout as L
from boringbar.kernels.exact.consts import (
    _DDC,
    _NB_MAX,
    _NB_MAX2,
    _NB_MAX_2,
    _NMAX6,
    _NZ_MAX,
    _NZB_MAX,
    CONTACT,
    CP_DT_OUT,
    CP_E,
    CP_F0,
    CP_FC,
    CP_FS,
    CP_H,
    CP_HALF,
    CP_KSTICK,
    CP_KWALL,
    CP_M,
    CP_MEFF,
    CP_OM,
    CP_REC_DT,
    CP_SIZE,
    CP_SR,
    CP_STICK_MIN,
    CP_STOP_AT_ZERO,
    CP_T0,
    CP_T_STEADY,
    CP_TSTROBE,
    CP_VIMP,
    CQ_CUBIC,
    CQ_FEED,
    CQ_H,
    CQ_KRB,
    CQ_MREV,
    CQ_NREV,
    CQ_SIZE,
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
    GRID_LEVELS,
    MAX_EVENTS,
    MAX_ZERO_LENGTH,
    N_EV,
    RO_K_REC,
    RO_MAX_ABS_W,
    RO_MAX_AUX,
    RO_MAX_AUX_ALL,
    RO_MAX_FORCE,
    RO_MAX_W,
    RO_MIN_W,
    RO_SIZE,
    RO_T_STROBE,
    RS_FIRST_ZERO,
    RS_INCUT,
    RS_MODE,
    RS_SDIR,
    RS_SIZE,
    RS_STICK_T0,
    RS_T_END,
    RS_WALL,
    RS_Y,
    RS_YD,
    SEG_ACC,
    SEG_CDIR,
    SEG_KRB,
    SEG_S,
    SEG_SIZE,
    STICK,
    SV_ADAPT,
    SV_B3W,
    SV_B3Y,
    SV_B4,
    SV_BW4,
    SV_REGEN,
    SV_SIZE,
    SV_STEADY,
    SV_TLEN,
    SV_WATCH_EXT,
    SV_WATCH_V,
    SV_WHOLE,
    SV_YDD,
)
from boringbar.kernels.exact.cut import (
    _GL_W,
    _GL_X,
    _hermite_at,
    _knot,
    _quad_cut,
    _surface_piece,
    cut_tables,
    history_step,
)
from boringbar.kernels.exact.events import (
    NSUB,
    _g,
    _hermite,
    _hermite5,
    _may_graze,
    _quad_range,
    _root_any,
    _w_extremum_any,
    _w_may_exceed,
    _wall_step,
)
from boringbar.kernels.exact.prepare import prepare
from boringbar.kernels.exact.propagate import (
    _eval,
    _force,
    _freq,
    _from_q,
    _integrals,
    _integrals_1,
    _integrals_2,
    _nq,
    _sizes,
    _surface,
)
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow, with_len


@njit(cache=True, inline="always")
def _grid_point(r, lev, qg, eh, phg, rot, fb, Z, D, V, ks, X, ev, b, seg, mode, n, mk, f0, om,
                ydd_on, acc, ddc, nz):
    """A whole grid step of level ``lev`` outside a cut: the eigen-coordinates qg and the
    forcing phasor phg advanced (returned), X from them, the event functions at the step's
    end b and (if ``ydd_on``) y'' and W'' there (else NaN).  X is seen with length ``nz``:
    the kernel inlines this with n, ks and nz constant for one and two modes."""
    X = with_len(X, nz)
    for kq in range(_nq(nz, ks)):
        k = kq * ks
        qg[k] = qg[k] * eh[r, lev, k]
    phg = phg * rot
    _from_q(r, qg, phg, fb, Z, D, V, ks, X)
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
def _zeros(ptr, n):
    """n zeros at ``ptr`` (stack scratch: kernels/stack.py)."""
    a = carray(ptr, n)
    for i in range(n):
        a[i] = 0.0
    return a


@njit(cache=True, inline="always")
def _zeros2(ptr, n, m):
    """An n x m array of zeros at ``ptr``."""
    a = carray(ptr, (n, m))
    for i in range(n):
        for j in range(m):
            a[i, j] = 0.0
    return a


@njit(cache=True, inline="always")
def _bar(p, n, mk, ddc, cp, t0, t_steady, dt_out, h, rec_dt):
    """The bar's rows ``mk`` (M, K, C, psi_L, psi_d, psi_a), a free ball's y'' and W''
    coefficients ``ddc`` and the run's constants ``cp`` (CP_*) from ``p``."""
    for i in range(n):
        mk[0, i] = p[L.M_ + i]
        mk[1, i] = p[L.K_ + i]
        mk[2, i] = p[L.C_ + i]
        mk[3, i] = p[L.PSI_L + i]
        mk[4, i] = p[L.PSI_D + i]
        mk[5, i] = p[L.PSI_A + i]
    m = p[L.BALL_MASS]
    fc = p[L.FRICTION]
    sr = p[L.REACTION]
    spd = 0.0
    for i in range(n):
        spd += mk[4, i] * mk[4, i] / mk[0, i]
    # psi . u'' of a free ball's bar from its state, force f and F_b: rows 0 (psi_d) and 1
    # (psi_L) hold the coefficients of u_i, then of f and F_b; rows 2 and 3 those of u_i'
    for i in range(n):
        for row in range(2):
            pr = mk[4 - row, i] / mk[0, i]  # psi_d,i / M_i, then psi_L,i / M_i
            ddc[row, i] = -pr * mk[1, i]
            ddc[row + 2, i] = -pr * mk[2, i]
            ddc[row, n] += pr * mk[3, i]
            ddc[row, n + 1] -= pr * sr * mk[4, i]
    cp[CP_HALF] = p[L.HALF_GAP]
    cp[CP_E] = p[L.RESTITUTION]
    cp[CP_FC] = fc
    cp[CP_FS] = max(p[L.STATIC_FRICTION], fc)
    cp[CP_SR] = sr
    cp[CP_MEFF] = p[L.M_EFF]
    cp[CP_VIMP] = p[L.V_IMPACT]
    cp[CP_KSTICK] = (1.0 / m + sr * spd) if m > 0.0 else 1.0
    cp[CP_KWALL] = (1.0 / m + spd) if m > 0.0 else 1.0
    cp[CP_STICK_MIN] = p[L.STICK_MIN]
    cp[CP_T0] = t0
    cp[CP_T_STEADY] = t_steady
    cp[CP_DT_OUT] = dt_out
    cp[CP_STOP_AT_ZERO] = 1.0 if p[L.STOP_AT_ZERO] > 0.0 else 0.0
    cp[CP_F0] = p[L.F0]
    cp[CP_OM] = p[L.OMEGA]
    cp[CP_H] = h
    cp[CP_REC_DT] = rec_dt
    cp[CP_TSTROBE] = p[L.STROBE_PERIOD]
    cp[CP_M] = m


@njit(cache=True, inline="always")
def _cut_start(kn, X, n, mk, t0, krb, feed, w_before, rs, max_force):
    """The first knot of a cut, at t0, and whether the tool starts in it (into ``rs``);
    returns the largest cutting force so far."""
    w_ = 0.0
    wd_ = 0.0
    for i in range(n):
        w_ += mk[3, i] * X[i]
        wd_ += mk[3, i] * X[n + i]
    kn[0, 0] = t0
    kn[0, 1] = w_
    kn[0, 2] = wd_
    kn[0, 3] = wd_
    kn[0, 4] = 0.0
    incut = feed + w_before - w_ > 0.0
    rs[RS_INCUT] = 1.0 if incut else 0.0
    if not incut and rs[RS_FIRST_ZERO] < 0.0:
        rs[RS_FIRST_ZERO] = t0
    return max(max_force, krb * max(0.0, feed + w_before - w_))


@njit(cache=True, inline="always")
def _initial_regime(X, f_t0, n, mk, cp, rs):
    """A ball's regime at the start (into ``rs``), from y, y' and the tip force f_t0."""
    half = cp[CP_HALF]
    fc = cp[CP_FC]
    fs = cp[CP_FS]
    y = rs[RS_Y]
    yd = rs[RS_YD]
    mode = FREE
    sdir = 0.0
    wall = 0.0
    if yd != 0.0:
        sdir = 1.0 if yd > 0.0 else -1.0
    elif abs(y) >= half:
        wall = 1.0 if y > 0.0 else -1.0
        y = wall * half
        F = _freq(X, f_t0, n, mk, cp[CP_KWALL])
        if wall * F <= fs:
            mode = CONTACT
        elif fc > 0.0:
            sdir = -wall
    elif fc > 0.0:
        F = _freq(X, f_t0, n, mk, cp[CP_KSTICK])
        if abs(F) <= fs:
            mode = STICK
        else:
            sdir = -1.0 if F > 0.0 else 1.0
    rs[RS_MODE] = mode
    rs[RS_SDIR] = sdir
    rs[RS_WALL] = wall
    rs[RS_Y] = y


@njit(cache=True, inline="always")
def _apply_event(ev_kind, t, steady, X, f_ev, n, mk, cp, rs, imp, stick, met):
    """The event ``ev_kind`` at t under the tip force f_ev: an impact (X' jumps), a
    capture, a stick, a slip or a release of the ball, or the tool leaving or re-entering
    the cut, into the run's state ``rs``; its counts and the stick interval it closes
    into ``met``, ``imp`` and ``stick``."""
    mode = int(rs[RS_MODE])
    sdir = rs[RS_SDIR]
    wall = rs[RS_WALL]
    y = rs[RS_Y]
    yd = rs[RS_YD]
    half = cp[CP_HALF]
    fc = cp[CP_FC]
    fs = cp[CP_FS]
    vimp = cp[CP_VIMP]
    was_stick = mode == STICK
    if ev_kind == EV_PLUS or ev_kind == EV_MINUS:
        w_ = 1.0 if ev_kind == EV_PLUS else -1.0
        y = w_ * half
        vb = yd
        if w_ * vb > 0.0:
            ee = cp[CP_E] if abs(vb) > vimp else 0.0  # Zeno: captured on the wall
            g_ = (1.0 + ee) * cp[CP_MEFF] * vb
            for i in range(n):
                X[n + i] += g_ * mk[4, i] / mk[0, i]
            yd = -ee * vb
            met[L.D_IMPACT] += 0.5 * (1.0 - ee * ee) * cp[CP_MEFF] * vb * vb
            if abs(vb) > vimp:
                met[L.N_IMP_ALL] += 1
                if steady:
                    if w_ > 0:
                        met[L.N_IMP_PLUS] += 1
                    else:
                        met[L.N_IMP_MINUS] += 1
                    n_imp = int(met[L.N_IMP_REC])
                    if n_imp < imp.shape[0]:
                        imp[n_imp, 0] = t
                        imp[n_imp, 1] = w_
                        imp[n_imp, 2] = vb
                    met[L.N_IMP_REC] += 1
            else:
                met[L.N_MICRO] += 1
        elif w_ * vb < -vimp:
            # moving inward, faster than a capture: not a wall contact but the
            # round-off of a segment a few ulp long just after an impact (its end
            # a few ulp past the wall); the ball goes on, from the wall
            yd = vb
        else:
            yd = 0.0
        if yd != 0.0:
            mode = FREE
            sdir = 1.0 if yd > 0.0 else -1.0
        else:
            mode, sdir, wall = _at_wall(X, f_ev, w_, n, mk, cp[CP_KWALL], fs, fc)
    elif ev_kind == EV_VSTOP:
        yd = 0.0
        F = _freq(X, f_ev, n, mk, cp[CP_KSTICK])
        if abs(F) <= fs:
            mode = STICK
            sdir = 0.0
        else:
            mode = FREE
            sdir = -1.0 if F > 0.0 else 1.0
    elif ev_kind == EV_REL_NEG or ev_kind == EV_REL_POS:
        mode = FREE
        yd = 0.0
        sdir = -1.0 if ev_kind == EV_REL_NEG else 1.0
    elif ev_kind == EV_WALL_REL:
        mode = FREE
        yd = 0.0
        sdir = -wall if fc > 0.0 else 0.0
        y = wall * half
    elif ev_kind == EV_CUT:
        incut = rs[RS_INCUT] == 0.0
        rs[RS_INCUT] = 1.0 if incut else 0.0
        if not incut and rs[RS_FIRST_ZERO] < 0.0:
            rs[RS_FIRST_ZERO] = t  # the chatter verdict (MODEL.md section 4)
            if cp[CP_STOP_AT_ZERO] != 0.0:  # finish the step of length dt_out, as RK4 does
                t0 = cp[CP_T0]
                dt_out = cp[CP_DT_OUT]
                rs[RS_T_END] = min(rs[RS_T_END],
                                   t0 + math.ceil((t - t0) / dt_out - 1e-9) * dt_out)
    if mode == FREE and fc == 0.0 and yd == 0.0:
        sdir = 0.0
    # stick intervals
    if mode == STICK and not was_stick:
        rs[RS_STICK_T0] = t
    elif was_stick and mode != STICK:
        _stick_interval(t, cp, rs, stick, met)
    rs[RS_MODE] = mode
    rs[RS_SDIR] = sdir
    rs[RS_WALL] = wall
    rs[RS_Y] = y
    rs[RS_YD] = yd


@njit(cache=True, inline="always")
def _stick_interval(t, cp, rs, stick, met):
    """Records the stick interval from rs[RS_STICK_T0] (or the steady window's start) to t
    if it is long enough."""
    s0 = max(rs[RS_STICK_T0], cp[CP_T_STEADY])
    if t - s0 >= cp[CP_STICK_MIN]:
        met[L.T_STICK] += t - s0
        n_stk = int(met[L.N_STICK_REC])
        if n_stk < stick.shape[0]:
            stick[n_stk, 0] = s0
            stick[n_stk, 1] = t
        met[L.N_STICK_REC] += 1


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


#: the driver's arrays, passed whole to its pieces (all borrowed or on the stack): states
#: and scratch, the segment record, the event functions at a, b and a sub-step's ends,
#: a cut's flow sums, the bar's rows and y'' coefficients, the run's constants, state and
#: running outputs, prepare's matrices, the grid's steps and phase steps, the outputs
Work = namedtuple("Work", "X Xa Xd dX q0 qs qg seg ev_a ev_b ev_s ev_t qsum out me G Cx cf ca cb "
                  "phj mk ddc cp rs ro lam V Vi Vfull Z D bq lvis cvis isum kstep bnd levmax "
                  "eh tabE tabP hl rotl x rec strobe met")


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
        # _surface_piece's k = 1 (no call: see the whole step below)
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
            c0, c1, c2, c3 = _hermite_at(kn[i, 0], kn[i, 1], kn[i, 3], kn[i + 1, 0],
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
        t_piece = _surface_piece(t, t_seg_end, ttol, kn, nk, ip, sc, nrev, nrev, feed,
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
        lo, hi = _quad_range(ya, yda, ydd_a, hs)
        e3 = b3y * hs * hs * hs / 6.0
        if not (hi + e3 < ylim and lo - e3 > -ylim):
            break
        if watch_v:
            e2 = b3y * hs * hs * (0.5 + 1e-9)
            v1 = yda + ydd_a * hs
            if not ((yda > e2 and v1 > e2) or (yda < -e2 and v1 < -e2)):
                break
        if steady:
            lo, hi = _quad_range(wa, wda, wdd_a, hs)
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
                    tr = _root_any(kk, a, ev_a[kk], b, ev_b[kk], seg, r, q0, lam, V, ks, Z,
                                   D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
                    if tr < best or kind < 0:
                        best = tr
                        kind = kk
    elif watch_wall:
        # call the (not inlined) search only when an end value shows something, or
        # y' changes sign and the bound on y lets the ball reach a wall
        # (a longer step than h holds no wall event: see its choice)
        graze = lev == 0 and _may_graze(a, b, ev_a, ev_b, half, b4)
        if ((ev_a[EV_PLUS] <= 0.0 < ev_b[EV_PLUS])
                or (ev_a[EV_MINUS] <= 0.0 < ev_b[EV_MINUS])
                or (watch_v and ev_a[EV_VSTOP] <= 0.0 < ev_b[EV_VSTOP])
                or (graze and watch_ext and ev_a[EV_YEXT] * ev_b[EV_YEXT] < 0.0)):
            kind, best = _wall_step(a, b, ev_a, ev_b, watch_v, watch_ext, half, seg, r,
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
                    _eval(r, q0, seg, sb, om, lam, V, ks, Z, D, bq, qs, dX)
                    _events(ev_t, dX, sb, seg, mode, n, mk, f0, om)
                else:
                    for kk in range(N_EV):
                        ev_t[kk] = ev_b[kk]
                kind, best = _wall_step(sa, sb, ev_s, ev_t, watch_v, watch_ext, half,
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
            tr = _root_any(EV_CUT, a, ev_a[EV_CUT], b, ev_b[EV_CUT], seg, r, q0, lam, V,
                           ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
        elif ev_a[EV_HEXT] * ev_b[EV_HEXT] < 0.0:
            te = _root_any(EV_HEXT, a, ev_a[EV_HEXT], b, ev_b[EV_HEXT], seg, r, q0, lam, V,
                           ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
            ge = _g(EV_CUT, te, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk, f0, om)
            if ev_a[EV_CUT] <= 0.0 < ge:
                tr = _root_any(EV_CUT, a, ev_a[EV_CUT], te, ge, seg, r, q0, lam, V, ks, Z,
                               D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
        if tr >= 0.0 and (kind < 0 or tr < best):
            best = tr
            kind = EV_CUT
    return kind, best


@njit(cache=True, inline="always")
def _cut_flows(w, a, b, r, ks, n, whole, sticking, steady, wb, max_force):
    """Adds a cut's flows over the grid step [a, b] to w.qsum (the slots of
    :func:`_integrals`' ``out``); ``whole``: a whole step H from a node, without event, from
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
            for kq in range(_nq(nz, ks)):
                k = kq * ks
                qs[k] = (q0[k] * tabE[r, g, k] + s_0 * tabP[r, g, 0, k]
                         + s_1 * tabP[r, g, 1, k] + s_2 * tabP[r, g, 2, k]
                         + s_3 * tabP[r, g, 3, k])
            for j in range(nz):
                sx = fb * D[r, j]
                for kq in range(_nq(nz, ks)):
                    k = kq * ks
                    sx += (V[r, j, k] * qs[k]).real
                dX[j] = sx
            wq = 0.0
            wdq = 0.0
            for i in range(n):
                wq += mk[3, i] * dX[i]
                wdq += mk[3, i] * dX[n + i]
            xg = _GL_X[g] * b
            fq = krb_seg * (s_0 + xg * (s_1 + xg * (s_2 + xg * s_3)) - wq)
            max_force = max(max_force, fq)
            wg = _GL_W[g] * b
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
        max_force = max(max_force, _quad_cut(a, b, seg, r, q0, lam, V, ks, Z, D, bq,
                                             qs, dX, n, mk, lvis, cvis,
                                             sticking, kappa_stick, sr, qsum,
                                             steady))
    max_force = max(max_force, krb_seg * (s_0 + b * (s_1 + b * (s_2 + b * s_3)) - wb))
    return max_force


@njit(cache=True, inline="always")
def _samples(w, t, b, t_end, r, ks, n, f0, om, mode, case, ball, x, rec, strobe, rec_dt,
             tstrobe, k_rec, t_next_strobe, met):
    """The history rows (every rec_dt from t0) and strobe rows (every tstrobe) that fall in
    (t + a, t + b] of the segment from t; returns the next ones' (k_rec, t_next_strobe)."""
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
    t0 = w.cp[CP_T0]
    n_rec = int(met[L.N_REC])
    while (rec_dt > 0.0 and n_rec < rec.shape[0]
           and t0 + k_rec * rec_dt <= t + b + 1e-9 * rec_dt):
        ts_ = t0 + k_rec * rec_dt
        if ts_ > t_end:
            break
        _eval(r, q0, seg, ts_ - t, om, lam, V, ks, Z, D, bq, qs, dX)
        wv = 0.0
        wdv = 0.0
        for i in range(n):
            wv += mk[3, i] * dX[i]
            wdv += mk[3, i] * dX[n + i]
        av, adv = _aux(dX, ts_ - t, seg, mode, case, n, mk, x, ball)
        rec[n_rec, 0] = ts_
        rec[n_rec, 1] = wv
        rec[n_rec, 2] = wdv
        rec[n_rec, 3] = av
        rec[n_rec, 4] = adv
        rec[n_rec, 5] = _force(seg, ts_ - t, dX, n, mk, f0, om)
        n_rec += 1
        k_rec += 1
    met[L.N_REC] = n_rec
    n_stb = int(met[L.N_STROBE])
    while tstrobe > 0.0 and t_next_strobe <= t + b and t_next_strobe <= t_end:
        if n_stb < strobe.shape[0]:
            _eval(r, q0, seg, t_next_strobe - t, om, lam, V, ks, Z, D, bq, qs, dX)
            wv = 0.0
            wdv = 0.0
            for i in range(n):
                wv += mk[3, i] * dX[i]
                wdv += mk[3, i] * dX[n + i]
            av, adv = _aux(dX, t_next_strobe - t, seg, mode, case, n, mk, x, ball)
            strobe[n_stb, 0] = t_next_strobe
            strobe[n_stb, 1] = wv
            strobe[n_stb, 2] = wdv
            strobe[n_stb, 3] = av
            strobe[n_stb, 4] = adv
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
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            qg[k] = (q0[k] * tabE[r, 4, k] + s_0 * tabP[r, 4, 0, k]
                     + s_1 * tabP[r, 4, 1, k] + s_2 * tabP[r, 4, 2, k]
                     + s_3 * tabP[r, 4, 3, k])
        for j in range(nz):
            sx = fb * D[r, j]
            for kq in range(_nq(nz, ks)):
                k = kq * ks
                sx += (V[r, j, k] * qg[k]).real
            X[j] = sx
    else:
        _eval(r, q0, seg, b, om, lam, V, ks, Z, D, bq, qg, X)
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
def _search(w, t, r, ks, sz, n, case, mode, ph, sv):
    """The grid search of the segment from t (regime r, ``mode``, forcing phasor ph at t,
    its description ``sv``, SV_*) for its first event, with the outputs on the way: the
    running extremes and output times in w.ro (RO_*), a cut's flows in w.qsum, history
    and strobe rows.  Returns (event kind or -1, its time from t or the segment's length,
    the forcing phasor there, W and W' there)."""
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
    regen = sv[SV_REGEN] != 0.0
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
            ph_next = _eval(r, q0, seg, b, om, lam, V, ks, Z, D, bq, qs, X)
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
            if lev == 0 and wda * wdb < 0.0 and (bw4 < 0.0 or _w_may_exceed(
                    b - a, wa, wb, wda, wdb, bw4, max_w, min_w, max_abs_w)):
                if kind < 0 and wdd_a == wdd_a and wdd_b == wdd_b:  # W'' at both ends
                    c0 = _hermite5(a, b, wa, wb, wda, wdb, wdd_a, wdd_b, 1)
                else:
                    c0 = _hermite(a, b, wa, wb, wda, wdb, 1)
                we = _w_extremum_any(a, wda, b, wdb, c0, h, seg, r, q0, lam, V, ks, Z, D,
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
            if regen or not ball:  # a ball's int y^2 is closed form (_integrals)
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
def _start_segment(w, t, t_stop, ph, n, case, nreg, j_node, kn, nk, ip, sc, cq, sv):
    """A segment from t (forcing phasor ph there) in the run's state w.rs: its regime r,
    its eigen-coordinates into w.q0, its record into w.seg, its description into ``sv``
    (SV_*) and, in a cut, its end and surface.  Returns (r, ks, its end (at most t_stop),
    whether that is a cut's node, the last node reached, psi_d . u at t)."""
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
    regen = sv[SV_REGEN] != 0.0
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
def _close_segment(w, t, T, r, ks, sz, n, case, mode, ph, steady, pdu, last_zero_step):
    """The flows of the segment [t, t + T] (regime r, forcing phasor ph at t; a cut's from
    w.qsum, else closed form) into the metrics, a cut's steps with h = 0 counted, a free
    ball moved to t + T.  Returns the last step of length dt_out counted with h = 0."""
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
    regen = seg[SEG_CDIR] != 0.0  # +-1 in a cut, 0 under harmonic forcing
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
            _integrals_1(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, mk, lvis, cvis, kst,
                         sr, me, G, Cx, cf, ca, cb, out, isum, level, seg, phj)
        elif sz == 2:
            _integrals_2(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, mk, lvis, cvis, kst,
                         sr, me, G, Cx, cf, ca, cb, out, isum, level, seg, phj)
        else:
            _integrals(r, q0, ph, T, fb, om, f0, lam, Vfull, Z, D, n, mk, lvis, cvis, kst,
                       sr, me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj)
        if ball and steady:
            # the ball's int y^2: closed form when free, y constant otherwise
            met[L.SUM_AUX2] += out[6] if mode == FREE else seg[4] * seg[4] * T
    _close_flows(T, steady, mode, ball, fb, acc, pdu, out, seg, X, n, mk, cp, w.rs, met)
    return last_zero_step


@njit(cache=True, inline="always")
def _cut_consts(p, cq, t0, t_end, hist_step, regen):
    """A regenerative cut's constants into ``cq`` (CQ_*) from ``p``, the run's span and the
    history step H."""
    tau_d = p[L.TAU]
    cq[CQ_T0] = t0
    cq[CQ_H] = hist_step
    cq[CQ_TTOL] = max(1e-9 * hist_step, 4.0 * 2.2e-16 * (abs(t0) + abs(t_end)))
    cq[CQ_NREV] = int(p[L.N_REV]) if regen else 0
    cq[CQ_TAU] = tau_d
    cq[CQ_FEED] = p[L.FEED]
    cq[CQ_W0] = p[L.HIST_W0]
    cq[CQ_MREV] = int(round(tau_d / hist_step)) if regen else 1
    cq[CQ_CUBIC] = 1.0 if p[L.INTERP] > 0.0 else 0.0
    cq[CQ_KRB] = p[L.KR_B]


@njit(cache=True, inline="always")
def _outputs_start(ro, met, p, t0, max_force):
    """The running extremes from ``met`` and the first output times into ``ro`` (RO_*)."""
    tstrobe = p[L.STROBE_PERIOD]
    ro[RO_MAX_ABS_W] = met[L.MAX_ABS_W]
    ro[RO_MAX_W] = met[L.STEADY_MAX_W]
    ro[RO_MIN_W] = met[L.STEADY_MIN_W]
    ro[RO_MAX_AUX] = met[L.MAX_ABS_AUX]
    ro[RO_MAX_AUX_ALL] = met[L.MAX_ABS_AUX_ALL]
    ro[RO_MAX_FORCE] = max_force
    ro[RO_K_REC] = 1.0  # the next history row is at t0 + k_rec rec_dt
    if tstrobe > 0.0:
        t_next_strobe = p[L.STROBE_T0]
        if t_next_strobe <= t0:
            t_next_strobe += (math.floor((t0 - t_next_strobe) / tstrobe) + 1) * tstrobe
        ro[RO_T_STROBE] = t_next_strobe


@njit(cache=True, inline="always")
def _finish_run(x, X, met, rs, ro, n, ball, regen, n_ev, status):
    """The final state into ``x`` and the running outputs into ``met``."""
    nz = X.shape[0]
    for j in range(nz):
        x[j] = X[j]
    if ball:
        x[2 * n] = rs[RS_Y]
        x[2 * n + 1] = rs[RS_YD]
    met[L.MAX_ABS_W] = ro[RO_MAX_ABS_W]
    met[L.STEADY_MAX_W] = ro[RO_MAX_W]
    met[L.STEADY_MIN_W] = ro[RO_MIN_W]
    met[L.MAX_ABS_AUX] = ro[RO_MAX_AUX]
    met[L.MAX_ABS_AUX_ALL] = ro[RO_MAX_AUX_ALL]
    met[L.N_EVENTS] = n_ev
    met[L.EXACT_STATUS] = status
    if regen:
        met[L.FIRST_ZERO_T] = rs[RS_FIRST_ZERO]
        met[L.MAX_FORCE] = ro[RO_MAX_FORCE]


@njit(cache=True, nogil=True)
def _exact(p, x, t0, t_end, t_steady, rec_dt, rec, imp, stick, strobe, met,
           lam, V, Vi, Z, D, eh, h, lvis, cvis, isum, Vfull, kstep, bq, nreg, dt_out, hist_step,
           tabE, tabP, bnd, levmax):
    # one compilation of this body for every bar, forcing and mode count; its hot parts
    # (segment integrals, event roots, W extrema, the usual grid point) run compiled or
    # inlined with the sizes constant where n = 1 or 2, nz = 2 n and ks = 2 (the ball or
    # solid bar with one or two modes): 1.2-1.4x, the same bits, under a minute more to
    # compile.  The whole body specialised was as fast but took minutes per mode count
    # (docs/performance.md)
    n = int(p[L.N_MODES])
    case = int(p[L.CASE])
    regen = int(p[L.FORCING]) == L.REGENERATIVE
    # borrowed views of the arguments and scratch on the stack: numba reference-counts
    # every array argument of every call, even inlined (an atomic operation each time:
    # 40 % of the run time), but not arrays without a memory owner (kernels/views.py)
    p = borrow(p)
    x = borrow(x)
    rec = borrow(rec)
    imp = borrow(imp)
    stick = borrow(stick)
    strobe = borrow(strobe)
    met = borrow(met)
    lam = borrow(lam)
    V = borrow(V)
    Vi = borrow(Vi)
    Z = borrow(Z)
    D = borrow(D)
    eh = borrow(eh)
    lvis = borrow(lvis)
    cvis = borrow(cvis)
    isum = borrow(isum)
    Vfull = borrow(Vfull)
    kstep = borrow(kstep)
    levmax = borrow(levmax)
    bq = borrow(bq)
    tabE = borrow(tabE)
    tabP = borrow(tabP)
    bnd = borrow(bnd)
    nz = lam.shape[1]
    nb = nz + 3
    ball = case == L.BALL
    mk = _zeros2(stack_ptr(_NMAX6, np.float64), 6, n)  # M, K, C, psi_L, psi_d, psi_a
    ddc = _zeros2(stack_ptr(_DDC, np.float64), 4, n + 2)
    cp = _zeros(stack_ptr(CP_SIZE, np.float64), CP_SIZE)
    _bar(p, n, mk, ddc, cp, t0, t_steady, dt_out, h, rec_dt)
    f0 = p[L.F0]
    om = p[L.OMEGA]

    # scratch
    X = _zeros(stack_ptr(_NZ_MAX, np.float64), nz)
    Xa = _zeros(stack_ptr(_NZ_MAX, np.float64), nz)
    Xd = _zeros(stack_ptr(_NZ_MAX, np.float64), nz)
    q0 = _zeros(stack_ptr(_NZ_MAX, np.complex128), nz)
    qs = _zeros(stack_ptr(_NZ_MAX, np.complex128), nz)
    qg = _zeros(stack_ptr(_NZ_MAX, np.complex128), nz)
    me = _zeros2(stack_ptr(_NB_MAX_2, np.complex128), 2, nb)  # mu, exp(mu T)
    G = _zeros2(stack_ptr(_NB_MAX2, np.complex128), nb, nb)
    Cx = _zeros2(stack_ptr(_NZB_MAX, np.complex128), nz, nb)
    cf = _zeros(stack_ptr(_NB_MAX, np.complex128), nb)
    ca = _zeros(stack_ptr(_NB_MAX, np.complex128), nb)
    cb = _zeros(stack_ptr(_NB_MAX, np.complex128), nb)
    out = _zeros(stack_ptr(7, np.float64), 7)
    phj = _zeros(stack_ptr(3, np.complex128), 3)
    seg = _zeros(stack_ptr(SEG_SIZE, np.float64), SEG_SIZE)
    dX = _zeros(stack_ptr(_NZ_MAX, np.float64), nz)
    ev_a = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_b = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_s = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_t = _zeros(stack_ptr(N_EV, np.float64), N_EV)

    for j in range(nz):
        X[j] = x[j]
    # --- regenerative cut (MODEL.md section 4): the history of W as knots -----------------
    # Knots (t, W, W'-, W'+) at the nodes t0 + j H, H = tau / m <= dt_out (so the delayed
    # nodes fall on nodes), and at every event (W' jumps at impacts, W'' at friction
    # switches).  The surface min_k [k h_m + W(t - k tau)] is the cubic Hermite of W, W'
    # between the two knots around t - k tau; a segment ends where any delayed knot falls,
    # so the input is one cubic on it.  ip[k]: the knot at or before t - k tau (-1: before
    # the cut, where W = HIST_W0).
    cq = _zeros(stack_ptr(CQ_SIZE, np.float64), CQ_SIZE)
    _cut_consts(p, cq, t0, t_end, hist_step, regen)
    krb = cq[CQ_KRB]
    feed = cq[CQ_FEED]
    w_before = cq[CQ_W0]
    nrev = int(cq[CQ_NREV])
    ttol = cq[CQ_TTOL]
    kn = np.zeros((nrev * int(cq[CQ_MREV]) + 64 if regen else 1, 5))
    nk = 0
    ip = np.full(nrev + 1, -1, np.int64)
    sc = np.zeros((nrev + 1, 4))
    qsum = _zeros(stack_ptr(6, np.float64), 6)
    rs = _zeros(stack_ptr(RS_SIZE, np.float64), RS_SIZE)
    rs[RS_FIRST_ZERO] = met[L.FIRST_ZERO_T]
    rs[RS_T_END] = t_end
    max_force = met[L.MAX_FORCE]
    last_zero_step = -1
    j_node = 0  # the last node reached
    if regen:
        max_force = _cut_start(kn, X, n, mk, t0, krb, feed, w_before, rs, max_force)
        nk = 1
    f_t0 = f0 * math.sin(om * t0)
    if rs[RS_INCUT] != 0.0:
        f_t0 += krb * (feed + w_before - kn[0, 1])
    rs[RS_Y] = x[2 * n] if ball or case == L.LOCKED else 0.0
    rs[RS_YD] = x[2 * n + 1] if ball else 0.0

    # the running extremes and output times (the other metrics add up in ``met`` itself)
    ro = _zeros(stack_ptr(RO_SIZE, np.float64), RO_SIZE)
    _outputs_start(ro, met, p, t0, max_force)
    n_ev = int(met[L.N_EVENTS])
    status = 0

    # --- the initial regime ---------------------------------------------------------------
    if ball:
        _initial_regime(X, f_t0, n, mk, cp, rs)
    rs[RS_STICK_T0] = t0
    n_zero = 0

    # the grid's step lengths (h, 2 h, 4 h, ...) and their phase steps
    hl = _zeros(stack_ptr(GRID_LEVELS, np.float64), GRID_LEVELS)
    rotl = _zeros(stack_ptr(GRID_LEVELS, np.complex128), GRID_LEVELS)
    for lv in range(GRID_LEVELS):
        hl[lv] = h * 2.0 ** lv
        rotl[lv] = cmath.exp(1j * om * hl[lv]) if om != 0.0 else 1.0 + 0.0j
    w = Work(X, Xa, Xd, dX, q0, qs, qg, seg, ev_a, ev_b, ev_s, ev_t, qsum, out, me, G, Cx, cf, ca,
             cb, phj, mk, ddc, cp, rs, ro, lam, V, Vi, Vfull, Z, D, bq, lvis, cvis, isum, kstep,
             bnd, levmax, eh, tabE, tabP, hl, rotl, x, rec, strobe, met)
    sv = _zeros(stack_ptr(SV_SIZE, np.float64), SV_SIZE)
    sv[SV_REGEN] = 1.0 if regen else 0.0
    ph_next = 1.0 + 0.0j
    ph_next_ok = False
    t = t0
    while t < t_end:
        if n_ev >= MAX_EVENTS:
            status = 1
            break
        # eigen-coordinates of the homogeneous part at t
        if ph_next_ok:
            ph = ph_next  # exp(i Omega t), from the event's evaluation (the same expression)
        else:
            ph = cmath.exp(1j * om * t) if om != 0.0 else 1.0 + 0.0j
        ph_next_ok = False
        t_stop = min(t_steady, t_end) if t < t_steady else t_end
        r, ks, t_seg_end, at_node, j_node, pdu = _start_segment(
            w, t, t_stop, ph, n, case, nreg, j_node, borrow(kn), nk, borrow(ip), borrow(sc), cq,
            sv)
        mode = int(rs[RS_MODE])
        steady = t >= t_steady
        sz = _sizes(ks, n, nz)  # 1, 2: the helpers compiled with constant sizes; 0: generic
        ev_kind, tau_ev, ph_next, wb, wdb = _search(w, t, r, ks, sz, n, case, mode, ph, sv)

        # --- close the segment [t, t + T] ----------------------------------------------
        T = tau_ev
        last_zero_step = _close_segment(w, t, T, r, ks, sz, n, case, mode, ph, steady, pdu,
                                        last_zero_step)
        t_new = t + T if ev_kind >= 0 else t_seg_end
        if ev_kind < 0:
            t = t_new
            if at_node:
                if nk < kn.shape[0] and t > kn[nk - 1, 0] + ttol:  # written out
                    kn[nk, 0] = t
                    kn[nk, 1] = wb
                    kn[nk, 2] = wdb
                    kn[nk, 3] = wdb
                    kn[nk, 4] = j_node + 1.0
                    nk += 1
                else:
                    kn, nk = _knot(kn, nk, ip, t, X, X, n, mk, ttol, float(j_node + 1))
            continue
        n_ev += 1
        # the next segment starts at t + T = seg[0] + T, where the event's evaluation was
        ph_next_ok = om != 0.0
        f_ev = _force(seg, T, X, n, mk, f0, om)  # the tip force at the event
        if T <= 1e-14 * (abs(t) + h):  # no progress: a few ulp of t
            n_zero += 1
            if n_zero > MAX_ZERO_LENGTH:
                status = 2
                t = t_new
                break
        else:
            n_zero = 0
        t = t_new
        steady = t >= t_steady
        for j in range(nz):
            Xa[j] = X[j]  # before the event (a knot keeps W'- and W'+)
        # --- apply the event -------------------------------------------------------------
        _apply_event(ev_kind, t, steady, X, f_ev, n, mk, cp, rs, imp, stick, met)
        t_end = rs[RS_T_END]
        if regen:
            kn, nk = _knot(kn, nk, ip, t, Xa, X, n, mk, ttol, -1.0)

    if rs[RS_MODE] == STICK:
        _stick_interval(t, cp, rs, stick, met)

    _finish_run(x, X, met, rs, ro, n, ball, regen, n_ev, status)
    return t


@njit(cache=True, inline="always")
def _at_wall(X, f, w_, n, mk, kappa_wall, fs, fc):
    """Regime of a ball at rest on wall w_ under the tip force f: held (CONTACT) or leaving
    inward (FREE)."""
    F = _freq(X, f, n, mk, kappa_wall)
    if w_ * F <= fs:
        return CONTACT, 0.0, w_
    return FREE, (-w_ if fc > 0.0 else 0.0), w_


@njit(cache=True, inline="always")
def _events(ev, X, tau, seg, mode, n, mk, f0, om):
    """All event functions from the state X at tau (see :func:`_g`)."""
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
        sv, sd = _surface(seg, tau)
        ev[EV_CUT] = seg[SEG_CDIR] * (w - sv)
        ev[EV_HEXT] = sd - wd
    if mode != FREE:
        F = _freq(X, _force(seg, tau, X, n, mk, f0, om), n, mk, seg[7])
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


def run_exact(p, x, t0, t_end, t_steady, rec_dt, rec, imp, stick, strobe, met, prep=None,
              dt=0.0):
    """Advance ``x`` exactly from ``t0`` to ``t_end``; same outputs as ``run_rk4`` (the
    steady sums are integrals, see the module docstring).  ``prep``: :func:`prepare`'s
    result, computed here if not given.  ``dt``: a regenerative cut's history step
    (H = tau / ceil(tau / dt)), the step a cut stopped at its first zero finishes, and the
    unit of N_ZERO_STEPS.  Returns the time reached."""
    if prep is None:
        prep = prepare(p)
    if int(p[L.FORCING]) == L.REGENERATIVE and not dt > 0.0:
        raise ValueError("exact integrator: a regenerative cut needs dt > 0")
    H = 0.0
    tabE = np.zeros((1, 5, 1), complex)
    tabP = np.zeros((1, 5, 4, 1), complex)
    if int(p[L.FORCING]) == L.REGENERATIVE:
        H = history_step(float(p[L.TAU]), float(dt))
        tabE, tabP = cut_tables(prep, p, H)
    return _exact(p, x, float(t0), float(t_end), float(t_steady), float(rec_dt), rec, imp,
                  stick, strobe, met, prep["lam"], prep["Vh"], prep["Vi"], prep["Z"],
                  prep["D"], prep["eh"], float(prep["h"]), prep["lvis"], prep["cvis"],
                  prep["isum"], prep["V"], prep["kstep"], prep["bq"], int(prep["nreg"]),
                  float(dt), H, tabE, tabP, prep["bnd"], prep["levmax"])
