"""The exact kernel's driver: :func:`run_exact`, its entry point, and :func:`_exact_body`, the
loop over segments (each searched by :mod:`.segment`), with the setup of a run, the
events applied between segments and the run's end, compiled as two kernels: :func:`_exact`
(harmonic forcing) and :func:`_exact_cut` (a regenerative cut).
"""

import cmath
import math
from collections import namedtuple

import numpy as np
from numba import carray, njit

from boringbar.kernels import layout as L
from boringbar.kernels.core import (
    close_stick,
    count_impact,
    impact_law,
    load_extremes,
    store_extremes,
)
from boringbar.kernels.exact.consts import (
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
    DDC,
    EV_CUT,
    EV_MINUS,
    EV_PLUS,
    EV_REL_NEG,
    EV_REL_POS,
    EV_VSTOP,
    EV_WALL_REL,
    FREE,
    GRID_LEVELS,
    MAX_EVENTS,
    MAX_ZERO_LENGTH,
    N_EV,
    NB_MAX,
    NB_MAX2,
    NB_MAX_2,
    NMAX6,
    NZ_MAX,
    NZB_MAX,
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
    SEG_SIZE,
    STICK,
    SV_SIZE,
)
from boringbar.kernels.exact.cut import add_knot, cut_tables, history_step
from boringbar.kernels.exact.prepare import prepare
from boringbar.kernels.exact.propagate import const_sizes, cut_force, freq_rhs
from boringbar.kernels.exact.segment import close_segment, search_segment, start_segment
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow


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
        F = freq_rhs(X, f_t0, n, mk, cp[CP_KWALL])
        if wall * F <= fs:
            mode = CONTACT
        elif fc > 0.0:
            sdir = -wall
    elif fc > 0.0:
        F = freq_rhs(X, f_t0, n, mk, cp[CP_KSTICK])
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
            yd, g_, loss = impact_law(vb, ee, cp[CP_MEFF])
            # the modes' jumps g psi_d,i / M_i, divided here (the RK4 kernels multiply by
            # 1 / M_i: the same law, other roundings)
            for i in range(n):
                X[n + i] += g_ * mk[4, i] / mk[0, i]
            met[L.D_IMPACT] += loss
            if abs(vb) > vimp:
                count_impact(met, imp, t, w_, vb, steady)
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
        F = freq_rhs(X, f_ev, n, mk, cp[CP_KSTICK])
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
            rs[RS_FIRST_ZERO] = t  # the chatter verdict (docs/model.md, section 4)
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
        close_stick(met, stick, rs[RS_STICK_T0], t, cp[CP_T_STEADY], cp[CP_STICK_MIN])
    rs[RS_MODE] = mode
    rs[RS_SDIR] = sdir
    rs[RS_WALL] = wall
    rs[RS_Y] = y
    rs[RS_YD] = yd


#: the driver's arrays, passed whole to its pieces (all borrowed or on the stack): states
#: and scratch, the segment record, the event functions at a, b and a sub-step's ends,
#: a cut's flow sums, the bar's rows and y'' coefficients, the run's constants, state and
#: running outputs, prepare's matrices, the grid's steps and phase steps, the outputs
Work = namedtuple("Work", "X Xa Xd dX q0 qs qg seg ev_a ev_b ev_s ev_t qsum out me G Cx cf ca cb "
                  "phj mk ddc cp rs ro lam V Vi Vfull Z D bq lvis cvis isum kstep bnd levmax "
                  "eh tabE tabP hl rotl x rec strobe met")


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
    (ro[RO_MAX_ABS_W], ro[RO_MAX_W], ro[RO_MIN_W], ro[RO_MAX_AUX],
     ro[RO_MAX_AUX_ALL]) = load_extremes(met)
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
    store_extremes(met, ro[RO_MAX_ABS_W], ro[RO_MAX_W], ro[RO_MIN_W], ro[RO_MAX_AUX],
                   ro[RO_MAX_AUX_ALL])
    met[L.N_EVENTS] = n_ev
    met[L.EXACT_STATUS] = status
    if regen:
        met[L.FIRST_ZERO_T] = rs[RS_FIRST_ZERO]
        met[L.MAX_FORCE] = ro[RO_MAX_FORCE]


# The body of both exact kernels, compiled once per forcing: ``regen`` (a cut) is a
# constant of each kernel (:func:`_exact`, :func:`_exact_cut`), so numba prunes the other
# forcing's code before typing it (its dead-branch pass follows the constant into the
# inlined pieces), and a harmonic run's kernel compiles in 10-16 % less time
# (docs/performance.md).  Each is one compilation for every bar and mode count; its hot
# parts (segment integrals, event roots, W extrema, the usual grid point) run compiled or
# inlined with the sizes constant where n = 1 or 2, nz = 2 n and ks = 2 (the ball or solid
# bar with one or two modes): 1.2-1.4x, the same bits, under a minute more to compile.
# The whole body specialised was as fast but took minutes per mode count.  ``span``:
# (t0, t_end, t_steady, rec_dt), one argument so that the call stays under CPython's 30
# positional arguments (beyond them it passes a tuple, which numba does not inline).
@njit(cache=True, inline="always")
def _exact_body(p, x, span, rec, imp, stick, strobe, met, lam, V, Vi, Z, D, eh, h, lvis, cvis,
                isum, Vfull, kstep, bq, nreg, dt_out, hist_step, tabE, tabP, bnd, levmax, regen):
    t0, t_end, t_steady, rec_dt = span
    n = int(p[L.N_MODES])
    case = int(p[L.CASE])
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
    mk = _zeros2(stack_ptr(NMAX6, np.float64), 6, n)  # M, K, C, psi_L, psi_d, psi_a
    ddc = _zeros2(stack_ptr(DDC, np.float64), 4, n + 2)
    cp = _zeros(stack_ptr(CP_SIZE, np.float64), CP_SIZE)
    _bar(p, n, mk, ddc, cp, t0, t_steady, dt_out, h, rec_dt)
    f0 = p[L.F0]
    om = p[L.OMEGA]

    # scratch
    X = _zeros(stack_ptr(NZ_MAX, np.float64), nz)
    Xa = _zeros(stack_ptr(NZ_MAX, np.float64), nz)
    Xd = _zeros(stack_ptr(NZ_MAX, np.float64), nz)
    q0 = _zeros(stack_ptr(NZ_MAX, np.complex128), nz)
    qs = _zeros(stack_ptr(NZ_MAX, np.complex128), nz)
    qg = _zeros(stack_ptr(NZ_MAX, np.complex128), nz)
    me = _zeros2(stack_ptr(NB_MAX_2, np.complex128), 2, nb)  # mu, exp(mu T)
    G = _zeros2(stack_ptr(NB_MAX2, np.complex128), nb, nb)
    Cx = _zeros2(stack_ptr(NZB_MAX, np.complex128), nz, nb)
    cf = _zeros(stack_ptr(NB_MAX, np.complex128), nb)
    ca = _zeros(stack_ptr(NB_MAX, np.complex128), nb)
    cb = _zeros(stack_ptr(NB_MAX, np.complex128), nb)
    out = _zeros(stack_ptr(7, np.float64), 7)
    phj = _zeros(stack_ptr(3, np.complex128), 3)
    seg = _zeros(stack_ptr(SEG_SIZE, np.float64), SEG_SIZE)
    dX = _zeros(stack_ptr(NZ_MAX, np.float64), nz)
    ev_a = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_b = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_s = _zeros(stack_ptr(N_EV, np.float64), N_EV)
    ev_t = _zeros(stack_ptr(N_EV, np.float64), N_EV)

    for j in range(nz):
        X[j] = x[j]
    # --- regenerative cut (docs/model.md, section 4): the history of W as knots -----------------
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
        r, ks, t_seg_end, at_node, j_node, pdu = start_segment(
            w, t, t_stop, ph, n, case, nreg, j_node, borrow(kn), nk, borrow(ip), borrow(sc), cq,
            sv, regen)
        mode = int(rs[RS_MODE])
        steady = t >= t_steady
        sz = const_sizes(ks, n, nz)  # 1, 2: the helpers compiled with constant sizes; 0: generic
        ev_kind, tau_ev, ph_next, wb, wdb = search_segment(w, t, r, ks, sz, n, case, mode, ph, sv,
                                                            regen)

        # --- close the segment [t, t + T] ----------------------------------------------
        T = tau_ev
        last_zero_step = close_segment(w, t, T, r, ks, sz, n, case, mode, ph, steady, pdu,
                                        last_zero_step, regen)
        t_new = t + T if ev_kind >= 0 else t_seg_end
        if ev_kind < 0:
            t = t_new
            if regen and at_node:  # a cut's node (``regen`` first: pruned in _exact)
                if nk < kn.shape[0] and t > kn[nk - 1, 0] + ttol:  # written out
                    kn[nk, 0] = t
                    kn[nk, 1] = wb
                    kn[nk, 2] = wdb
                    kn[nk, 3] = wdb
                    kn[nk, 4] = j_node + 1.0
                    nk += 1
                else:
                    kn, nk = add_knot(kn, nk, ip, t, X, X, n, mk, ttol, float(j_node + 1))
            continue
        n_ev += 1
        # the next segment starts at t + T = seg[0] + T, where the event's evaluation was
        ph_next_ok = om != 0.0
        f_ev = cut_force(seg, T, X, n, mk, f0, om)  # the tip force at the event
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
            kn, nk = add_knot(kn, nk, ip, t, Xa, X, n, mk, ttol, -1.0)

    if rs[RS_MODE] == STICK:
        close_stick(met, stick, rs[RS_STICK_T0], t, cp[CP_T_STEADY], cp[CP_STICK_MIN])

    _finish_run(x, X, met, rs, ro, n, ball, regen, n_ev, status)
    return t


@njit(cache=True, nogil=True)
def _exact(p, x, t0, t_end, t_steady, rec_dt, rec, imp, stick, strobe, met,
           lam, V, Vi, Z, D, eh, h, lvis, cvis, isum, Vfull, kstep, bq, nreg, dt_out, hist_step,
           tabE, tabP, bnd, levmax):
    """The kernel of harmonic (and free) runs: :func:`_exact_body` without a cut's code."""
    return _exact_body(p, x, (t0, t_end, t_steady, rec_dt), rec, imp, stick, strobe, met,
                       lam, V, Vi, Z, D, eh, h, lvis, cvis, isum, Vfull, kstep, bq, nreg,
                       dt_out, hist_step, tabE, tabP, bnd, levmax, False)


@njit(cache=True, nogil=True)
def _exact_cut(p, x, t0, t_end, t_steady, rec_dt, rec, imp, stick, strobe, met,
               lam, V, Vi, Z, D, eh, h, lvis, cvis, isum, Vfull, kstep, bq, nreg, dt_out,
               hist_step, tabE, tabP, bnd, levmax):
    """The kernel of regenerative cuts: :func:`_exact_body` with the cut's code."""
    return _exact_body(p, x, (t0, t_end, t_steady, rec_dt), rec, imp, stick, strobe, met,
                       lam, V, Vi, Z, D, eh, h, lvis, cvis, isum, Vfull, kstep, bq, nreg,
                       dt_out, hist_step, tabE, tabP, bnd, levmax, True)


@njit(cache=True, inline="always")
def _at_wall(X, f, w_, n, mk, kappa_wall, fs, fc):
    """Regime of a ball at rest on wall w_ under the tip force f: held (CONTACT) or leaving
    inward (FREE)."""
    F = freq_rhs(X, f, n, mk, kappa_wall)
    if w_ * F <= fs:
        return CONTACT, 0.0, w_
    return FREE, (-w_ if fc > 0.0 else 0.0), w_


def run_exact(p, x, t0, t_end, t_steady, rec_dt, rec, imp, stick, strobe, met, prep=None,
              dt=0.0):
    """Advance ``x`` exactly from ``t0`` to ``t_end``; same outputs as ``run_rk4`` (the
    steady sums are integrals, see the module docstring).  ``prep``: :func:`prepare`'s
    result, computed here if not given.  ``dt``: a regenerative cut's history step
    (H = tau / ceil(tau / dt)), the step a cut stopped at its first zero finishes, and the
    unit of N_ZERO_STEPS.  Returns the time reached."""
    regen = int(p[L.FORCING]) == L.REGENERATIVE
    if prep is None:
        prep = prepare(p)
    if regen and not dt > 0.0:
        raise ValueError("exact integrator: a regenerative cut needs dt > 0")
    H = 0.0
    tabE = np.zeros((1, 5, 1), complex)
    tabP = np.zeros((1, 5, 4, 1), complex)
    kernel = _exact
    if regen:
        H = history_step(float(p[L.TAU]), float(dt))
        tabE, tabP = cut_tables(prep, p, H)
        kernel = _exact_cut
    return kernel(p, x, float(t0), float(t_end), float(t_steady), float(rec_dt), rec, imp,
                  stick, strobe, met, prep["lam"], prep["Vh"], prep["Vi"], prep["Z"],
                  prep["D"], prep["eh"], float(prep["h"]), prep["lvis"], prep["cvis"],
                  prep["isum"], prep["V"], prep["kstep"], prep["bq"], int(prep["nreg"]),
                  float(dt), H, tabE, tabP, prep["bnd"], prep["levmax"])
