"""The published scheme: classical RK4 at a fixed step, impacts at step ends.

docs/model.md, sections 2 and 5.  Per step:

1. four RK4 stages of the smooth equations, with the friction force
   F_b = -F_c sgn(y') (sgn(0) = 0) and the forcing evaluated at every stage;
2. at the end of the step, if |y| >= delta/2: put y back on the wall, and
   apply the impact law if y y' > 0 (moving outward):
   y'+ = -e y'-,  u_i'+ = u_i'- + (1+e) m_eff psi_d,i y'- / M_i,
   m_eff = 1 / (1/m + sum_i psi_d,i^2 / M_i);
3. stream the metrics (RMS, impacts, contact and stick, energy flows).

Energy flows are integrated with the RK4 weights on the stage values, so the
balance closes to the accuracy of RK4 between impacts (1e-11 relative at
dt = 1e-6) as long as friction does not switch inside a step; impact losses
are the exact kinetic-energy drops.  When the sgn() law chatters (a sticking
ball), the stage-weighted friction work is only first-order accurate and the
balance closes to O(dt) (2e-3 relative for the paper preset's 20.4 N at
dt = 1e-6; tests/test_kernel.py).  The state is one vector
X = [u_1..u_n, u_1'..u_n', aux, aux'] where aux is the ball's relative
displacement y (BALL, LOCKED) or the absorber's displacement x_a (TMD).

Speed: under harmonic forcing a step in which the ball's y' keeps one sign
at all four stages (every step of the solid, TMD and locked bars and of a
frictionless ball) is the same RK4 step written as one affine map of the
state, sin and cos of the forcing phase and F_b (kernels/linmap.py): its
critical path is a short dot product per component instead of four
dependent stage evaluations (1.3-1.4x faster per step,
benchmarks/bench_kernel.py).  Steps with a friction switch inside, y' = 0 or
inside the sgn() chatter band, and regenerative cuts take the stage loop:
the four stages as one loop over a Butcher tableau inside a single
function, with every accumulator a local scalar and the state and scratch
vectors on the stack (kernels/stack.py), so that nothing in the step
crosses a function boundary (numba would reference-count array arguments
there) or goes through memory that might alias.  One compiled
specialisation per mode count lets the mode loops unroll.  No fast-math
flag: plain IEEE arithmetic keeps the batched kernel's results equal to
these bit for bit (see the note above the specialisations).
"""

import math

import numpy as np
from numba import carray, njit

from boringbar.kernels import layout as L
from boringbar.kernels.core import (
    IMPACT,
    MICRO_IMPACT,
    ON_WALL,
    close_stick,
    load_extremes,
    load_flows,
    load_steady,
    steady_sample,
    stick_step,
    store_extremes,
    store_flows,
    store_steady,
    strobe_row,
    wall_rule,
)
from boringbar.kernels.linmap import NZ_MAX, PD_MAX, VR_MAX, WV_MAX, YR_MAX, build_map
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow

#: lengths of the stack scratch vectors (numba needs them as literal globals)
_NMAX = L.NMAX
_NX_MAX = 2 * L.NMAX + 2
#: most past revolutions in the chip-thickness minimum
_NREV_MAX = 50
_NREV_X3 = 3 * _NREV_MAX
_NREV_X12 = 12 * _NREV_MAX
#: exact sin/cos resynchronisation interval of the forcing-phase recurrence
_RESYNC = 256


@njit(cache=True, error_model="numpy", inline="always")
def _rk4(n, case, regen, p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe,
         met, buf):
    """Advance state ``x`` (updated in place) by ``n_steps`` RK4 steps from ``t0``.

    Steps with index >= ``steady_start`` are the steady part.  Outputs:
    ``rec`` (t, W, W', aux, aux', f every ``rec_every`` steps; 0 = none),
    ``imp`` (t, wall, y'- of counted impacts in the steady part), ``stick``
    (start, end of stick intervals in the steady part), ``strobe`` (Poincare
    samples t, W, W', aux, aux' at t = STROBE_T0 + j STROBE_PERIOD), ``met``
    (metrics, see layout; pass zeros, with STEADY_MAX_W = -inf and
    STEADY_MIN_W = +inf, for a fresh run), ``buf`` (regenerative cutting:
    the circular history of W, W' at step ends, at least
    N_REV TAU / dt + 3 rows; node g is time t_cut + g dt, counted over every
    call since the cut began, and times before the cut read HIST_W0).
    """
    # borrowed (kernels/views.py): the shared helpers (kernels/core.py) take them at
    # every step without reference counting
    met = borrow(met)
    imp = borrow(imp)
    stick = borrow(stick)
    strobe = borrow(strobe)
    M = p[L.M_:L.M_ + n].copy()
    K = p[L.K_:L.K_ + n].copy()
    C = p[L.C_:L.C_ + n].copy()
    pL = p[L.PSI_L:L.PSI_L + n].copy()
    pD = p[L.PSI_D:L.PSI_D + n].copy()
    pA = p[L.PSI_A:L.PSI_A + n].copy()
    invM = 1.0 / M
    f0 = p[L.F0]
    krb = p[L.KR_B]
    feed = p[L.FEED]
    nrev = int(p[L.N_REV]) if regen else 0
    cubic = p[L.INTERP] > 0.0
    stop_at_zero = p[L.STOP_AT_ZERO] > 0.0
    w_before_cut = p[L.HIST_W0]
    nbuf = buf.shape[0]
    kg0 = int(met[L.STEPS_DONE])  # steps since the cut began
    # The delayed W at the three distinct stage times (c = 0, 1/2, 1) minus
    # j tau: node kg + c - j tau / dt = kg + off[q, j] + fraction, interpolated
    # between two stored nodes with fixed weights (cubic Hermite from W and W',
    # or linear), so each lookup is four multiply-adds.  ptr[j] is the buffer
    # row of node kg + off[0, j], advanced by one each step (no modulo).
    off = carray(stack_ptr(_NREV_X3, np.int64), (3, _NREV_MAX))
    wts = carray(stack_ptr(_NREV_X12, np.float64), (3, _NREV_MAX, 4))
    ptr = carray(stack_ptr(_NREV_MAX, np.int64), _NREV_MAX)
    for q in range(3):
        for j in range(nrev):
            d = 0.5 * q - (j + 1) * p[L.TAU] / dt
            off[q, j] = math.floor(d)
            fr = d - math.floor(d)
            if cubic:
                f2 = fr * fr
                f3 = f2 * fr
                wts[q, j, 0] = 2 * f3 - 3 * f2 + 1
                wts[q, j, 1] = (f3 - 2 * f2 + fr) * dt
                wts[q, j, 2] = -2 * f3 + 3 * f2
                wts[q, j, 3] = (f3 - f2) * dt
            else:
                wts[q, j, 0] = 1.0 - fr
                wts[q, j, 1] = 0.0
                wts[q, j, 2] = fr
                wts[q, j, 3] = 0.0
    for j in range(nrev):
        ptr[j] = (kg0 + off[0, j]) % nbuf
    hsurf = carray(stack_ptr(4, np.float64), 4)
    max_force = met[L.MAX_FORCE]
    first_zero = met[L.FIRST_ZERO_T]
    n_zero = met[L.N_ZERO_STEPS]
    steps_run = n_steps
    om = p[L.OMEGA]
    m = p[L.BALL_MASS]
    half = p[L.HALF_GAP]
    e = p[L.RESTITUTION]
    fc = p[L.FRICTION]
    sr = p[L.REACTION]
    meff = p[L.M_EFF]
    vimp = p[L.V_IMPACT]
    stick_min = p[L.STICK_MIN]
    vstick = p[L.V_STICK]
    ma = p[L.TMD_MASS]
    ka = p[L.TMD_K]
    ca = p[L.TMD_C]
    tstrobe = p[L.STROBE_PERIOD]
    ball = case == L.BALL
    has_aux = case == L.BALL or case == L.TMD

    nx = 2 * n + 2
    iy = 2 * n
    iyd = 2 * n + 1
    # the step's state and scratch live on the stack (kernels/stack.py)
    X = carray(stack_ptr(_NX_MAX, np.float64), nx)
    for j in range(nx):
        X[j] = x[j]
    if case == L.LOCKED:
        X[iyd] = 0.0
    Xs = carray(stack_ptr(_NX_MAX, np.float64), nx)  # stage state
    Kd = carray(stack_ptr(_NX_MAX, np.float64), nx)  # stage derivative
    acc = carray(stack_ptr(_NX_MAX, np.float64), nx)  # sum of weighted derivatives
    for j in range(nx):
        Kd[j] = 0.0
    # premultiplied modal constants: a_i = fm f - km u - cm v - dm F_b (ball)
    fm = carray(stack_ptr(_NMAX, np.float64), n)
    km = carray(stack_ptr(_NMAX, np.float64), n)
    cm = carray(stack_ptr(_NMAX, np.float64), n)
    dm = carray(stack_ptr(_NMAX, np.float64), n)
    lm = carray(stack_ptr(_NMAX, np.float64), n)
    kappa = 1.0 / m if m > 0.0 else 0.0
    for i in range(n):
        fm[i] = pL[i] * invM[i]
        km[i] = K[i] * invM[i]
        cm[i] = C[i] * invM[i]
        dm[i] = sr * pD[i] * invM[i]
        lm[i] = meff * pD[i] * invM[i]
        kappa += pD[i] * dm[i]
    fst = carray(stack_ptr(4, np.float64), 4)  # forcing at the stages
    cst = carray(stack_ptr(4, np.float64), 4)  # c_s h
    wst = carray(stack_ptr(4, np.float64), 4)  # b_s h
    for st in range(4):
        cst[st] = (0.0, 0.5, 0.5, 1.0)[st] * dt
        wst[st] = (1.0, 2.0, 2.0, 1.0)[st] * (dt / 6.0)

    # the step as an affine map where F_b cannot switch (kernels/linmap.py)
    linear = not regen and p[L.STAGE_LOOP] == 0.0
    nz = nx + 3
    iS = nx
    iC = nx + 1
    iF = nx + 2
    tmd = case == L.TMD
    Pd = carray(stack_ptr(PD_MAX, np.float64), (nx, nz))
    Yr = carray(stack_ptr(YR_MAX, np.float64), (3, nz))
    Vr = carray(stack_ptr(VR_MAX, np.float64), (3, n + 1, nz))
    Wv = carray(stack_ptr(WV_MAX, np.float64), (4, n + 1))
    Fs = carray(stack_ptr(NZ_MAX, np.float64), nz)
    Fc = carray(stack_ptr(NZ_MAX, np.float64), nz)
    dX = carray(stack_ptr(_NX_MAX, np.float64), nx)
    if linear:
        build_map(n, p, dt, Pd, Yr, Vr, Wv, Fs, Fc)
    check_fb = ball and fc > 0.0
    diag = case == L.SOLID or case == L.BALL

    chh = math.cos(om * 0.5 * dt)
    shh = math.sin(om * 0.5 * dt)
    sn = 0.0
    cn = 1.0

    # streamed metrics as locals (written back at the end); the events' counts and rows
    # go to met and the records directly (kernels/core.py)
    sum_w2, sum_w, n_steady, sum_aux2, sum_f, t_contact = load_steady(met)
    max_abs_w, max_w, min_w, max_aux, max_aux_all = load_extremes(met)
    w_force, d_visc, d_fric, w_nr = load_flows(met)
    n_rec = int(met[L.N_REC])
    n_stb = int(met[L.N_STROBE])
    cap_rec = rec.shape[0]
    cap_stb = strobe.shape[0]
    t_steady = t0 + steady_start * dt
    in_stick = False
    stick_t0 = 0.0

    w_prev = 0.0
    wd_prev = 0.0
    aux_prev = X[iy]
    auxd_prev = X[iyd]
    for i in range(n):
        w_prev += pL[i] * X[i]
        wd_prev += pL[i] * X[n + i]
        if case == L.TMD:
            aux_prev -= pA[i] * X[i]
            auxd_prev -= pA[i] * X[n + i]
    wptr = kg0 % nbuf if regen else 0  # the row of the newest node
    if regen and kg0 == 0:
        buf[0, 0] = w_prev
        buf[0, 1] = wd_prev
    t_next = 0.0
    if tstrobe > 0.0:
        t_next = p[L.STROBE_T0]
        if t_next < t0:
            t_next += math.ceil((t0 - t_next) / tstrobe) * tstrobe

    for k in range(n_steps):
        t = t0 + k * dt
        t1 = t0 + (k + 1) * dt  # not t + dt: keeps event times inside [t0, t_end]
        if k % _RESYNC == 0:
            sn = math.sin(om * t)
            cn = math.cos(om * t)
        kg = kg0 + k
        cut_zero = False
        if regen:
            # the surface the tool meets at each stage time: min_j [j h_m + W(t_s - j tau)],
            # from the stored history (stages 2 and 3 share t + dt/2).  Until h first
            # reaches zero the j = 1 term is the minimum (docs/model.md, section 4), so the
            # other revolutions are read only after that.
            nr_eff = nrev if first_zero >= 0.0 else 1
            for q in range(3):
                hmin = 1e300
                for j in range(nr_eff):
                    a = kg + off[q, j]
                    if a >= 0:
                        ia = ptr[j] + (off[q, j] - off[0, j])
                        if ia >= nbuf:
                            ia -= nbuf
                        ib = ia + 1 if ia + 1 < nbuf else 0
                        wdel = (wts[q, j, 0] * buf[ia, 0] + wts[q, j, 1] * buf[ia, 1]
                                + wts[q, j, 2] * buf[ib, 0] + wts[q, j, 3] * buf[ib, 1])
                    elif a + 1 >= 0:  # between the surface before the cut and node 0
                        wdel = ((wts[q, j, 0]) * w_before_cut + wts[q, j, 2] * buf[0, 0]
                                + wts[q, j, 3] * buf[0, 1])
                    else:
                        wdel = w_before_cut
                    hmin = min(hmin, (j + 1) * feed + wdel)
                hsurf[q if q < 2 else 3] = hmin  # stages 0, 1 (2 shares it), 3
            hsurf[2] = hsurf[1]
        s_h = sn * chh + cn * shh
        c_h = cn * chh - sn * shh
        s_1 = s_h * chh + c_h * shh
        c_1 = c_h * chh - s_h * shh
        fst[0] = f0 * sn
        fst[1] = f0 * s_h
        fst[2] = fst[1]
        fst[3] = f0 * s_1

        # --- the step as an affine map, if F_b keeps its sign ---------------------
        use_map = linear
        fz = 0.0
        if check_fb:
            yd0 = X[iyd]
            if yd0 > 0.0:
                fz = -fc
            else:
                fz = fc
            if abs(yd0) < vstick:  # inside the band where sgn() chatters
                use_map = False
            else:
                # y' at stages 2-4 must keep y0's sign, by more than their round-off
                for s3 in range(3):
                    ys = Yr[s3, iS] * sn + Yr[s3, iC] * cn + Yr[s3, iF] * fz
                    for j in range(nx):
                        ys += Yr[s3, j] * X[j]
                    if ys * yd0 <= 1e-12 * (yd0 * yd0 + abs(yd0 * (ys - yd0))):
                        use_map = False
        if use_map:
            # the increments; in the solid and ball bars a mode's rows involve only
            # its own u, u' (the modes are coupled through F_b alone)
            if diag:
                for i in range(n):
                    a = i
                    dX[a] = (Pd[a, iS] * sn + Pd[a, iC] * cn + Pd[a, iF] * fz
                             + Pd[a, i] * X[i] + Pd[a, n + i] * X[n + i])
                    a = n + i
                    dX[a] = (Pd[a, iS] * sn + Pd[a, iC] * cn + Pd[a, iF] * fz
                             + Pd[a, i] * X[i] + Pd[a, n + i] * X[n + i])
                dX[iy] = 0.0
                dX[iyd] = 0.0
                if ball:
                    for a in range(iy, nx):
                        dj = Pd[a, iS] * sn + Pd[a, iC] * cn + Pd[a, iF] * fz
                        for q in range(nx):
                            dj += Pd[a, q] * X[q]
                        dX[a] = dj
            else:
                for a in range(nx):
                    dj = Pd[a, iS] * sn + Pd[a, iC] * cn + Pd[a, iF] * fz
                    for q in range(nx):
                        dj += Pd[a, q] * X[q]
                    dX[a] = dj
            # viscous loss: the RK4 weights on the stage velocities squared
            pv = 0.0
            for i in range(n):
                pv += Wv[0, i] * X[n + i] * X[n + i]
            if tmd:
                rd = X[iyd]
                for i in range(n):
                    rd -= pA[i] * X[n + i]
                pv += Wv[0, n] * rd * rd
            for s3 in range(3):
                for i in range(n):
                    v = Vr[s3, i, iS] * sn + Vr[s3, i, iC] * cn + Vr[s3, i, iF] * fz
                    if diag:
                        v += Vr[s3, i, i] * X[i] + Vr[s3, i, n + i] * X[n + i]
                    else:
                        for q in range(nx):
                            v += Vr[s3, i, q] * X[q]
                    pv += Wv[s3 + 1, i] * v * v
                if tmd:  # the absorber's stroke rate
                    v = Vr[s3, n, iS] * sn + Vr[s3, n, iC] * cn
                    for q in range(nx):
                        v += Vr[s3, n, q] * X[q]
                    pv += Wv[s3 + 1, n] * v * v
            d_visc += pv
            # the force's work, S (Fs . z) + C (Fc . z)
            ws_ = Fs[iS] * sn + Fs[iC] * cn + Fs[iF] * fz
            wc_ = Fc[iS] * sn + Fc[iC] * cn + Fc[iF] * fz
            for q in range(nx):
                ws_ += Fs[q] * X[q]
                wc_ += Fc[q] * X[q]
            w_force += sn * ws_ + cn * wc_
            if ball:
                # sum_s b_s F_b y'_s = F_b dy; sum_s b_s psi_d u'_s = psi_d du
                d_fric -= fz * dX[iy]
                pdu = 0.0
                for i in range(n):
                    pdu += pD[i] * dX[i]
                w_nr += (1.0 - sr) * fz * pdu
            for j in range(nx):
                X[j] += dX[j]

        # --- otherwise the four RK4 stages ------------------------------------
        if not use_map:
            for j in range(nx):
                acc[j] = 0.0
            for st in range(4):
                cs = cst[st]
                for j in range(nx):
                    Xs[j] = X[j] + cs * Kd[j]
                f = fst[st]
                if regen:
                    # f = Kr b h, h = max(0, min_j [j h_m + W(t - j tau)] - W(t))
                    ws = 0.0
                    for i in range(n):
                        ws += pL[i] * Xs[i]
                    hmin = hsurf[st]
                    hh = hmin - ws
                    if hh <= 0.0:
                        hh = 0.0
                        if not cut_zero:
                            cut_zero = True
                            if first_zero < 0.0:
                                first_zero = t + (0.0, 0.5, 0.5, 1.0)[st] * dt
                    f = krb * hh
                    fst[st] = f
                    max_force = max(max_force, f)
                w_s = wst[st]
                # bar: M_i u_i'' + C_i u_i' + K_i u_i = psi_L,i f (+ damper terms below),
                # written with premultiplied constants and the stage velocity last, so
                # that little of it waits on the previous stage
                wd = 0.0
                pvisc = 0.0
                sfree = 0.0  # sum_i psi_d,i a_i of the free accelerations
                for i in range(n):
                    vi = Xs[n + i]
                    Kd[i] = vi
                    ai = (fm[i] * f - km[i] * Xs[i]) - cm[i] * vi
                    Kd[n + i] = ai
                    sfree += pD[i] * ai
                    wd += pL[i] * vi
                    pvisc += C[i] * vi * vi
                ydd = 0.0
                if ball:
                    yds = Xs[iyd]
                    fb = 0.0  # F_b = -F_c sgn(y'), sgn(0) = 0
                    if yds > 0.0:
                        fb = -fc
                    elif yds < 0.0:
                        fb = fc
                    pdv = 0.0
                    for i in range(n):
                        # reaction on the bar: -psi_d F_b (sr = 1) or as printed (sr = -1)
                        Kd[n + i] -= dm[i] * fb
                        pdv += pD[i] * Xs[n + i]
                    # y'' = F_b / m - sum psi_d u'' = kappa F_b - sum psi_d a_free
                    ydd = kappa * fb - sfree
                    d_fric -= w_s * fb * yds
                    w_nr += w_s * (1.0 - sr) * fb * pdv
                elif case == L.TMD:
                    rel = Xs[iy]
                    reld = Xs[iyd]
                    for i in range(n):
                        rel -= pA[i] * Xs[i]
                        reld -= pA[i] * Xs[n + i]
                    ft = ka * rel + ca * reld
                    for i in range(n):
                        Kd[n + i] += pA[i] * ft * invM[i]
                    ydd = -ft / ma
                    pvisc += ca * reld * reld
                elif case == L.LOCKED:
                    # the force that carries the ball with the bar, m_eff sum psi_d a_free,
                    # acts on mode i with psi_d,i
                    for i in range(n):
                        Kd[n + i] -= lm[i] * sfree
                Kd[iy] = Xs[iyd] if has_aux else 0.0
                Kd[iyd] = ydd
                for j in range(nx):
                    acc[j] += w_s * Kd[j]
                w_force += w_s * f * wd
                d_visc += w_s * pvisc
            for j in range(nx):
                X[j] += acc[j]
        steady = k >= steady_start

        # --- Poincare strobe: cubic Hermite in [t, t1] ------------------------
        if tstrobe > 0.0 and t_next <= t1:
            if t_next > t and n_stb < cap_stb:
                w1 = 0.0
                wd1 = 0.0
                for i in range(n):
                    w1 += pL[i] * X[i]
                    wd1 += pL[i] * X[n + i]
                a1 = X[iy]
                ad1 = X[iyd]
                if case == L.TMD:  # the absorber's stroke, as in the history
                    for i in range(n):
                        a1 -= pA[i] * X[i]
                        ad1 -= pA[i] * X[n + i]
                strobe_row(strobe[n_stb], t_next, t, dt, w_prev, wd_prev, w1, wd1, aux_prev,
                           auxd_prev, a1, ad1)
                n_stb += 1
            t_next += tstrobe

        # --- walls (docs/model.md, section 2) ----------------------------------------
        contact = False
        if ball:
            hit, X[iy], X[iyd], g = wall_rule(met, imp, X[iy], X[iyd], t1, steady, half, e,
                                              meff, vimp)
            if hit == IMPACT or hit == MICRO_IMPACT:
                for i in range(n):
                    X[n + i] += g * pD[i] * invM[i]
            contact = hit == MICRO_IMPACT or hit == ON_WALL
            # stick: off the walls with |y'| inside the band where the sgn() law
            # chatters (V_STICK = V_IMPACT + 2 F_c dt / m_eff)
            stuck = fc > 0.0 and not contact and abs(X[iyd]) < vstick
            in_stick, stick_t0 = stick_step(stuck, in_stick, stick_t0, t, t1, met, stick,
                                            t_steady, stick_min)

        # --- streamed metrics --------------------------------------------------
        w = 0.0
        wd = 0.0
        for i in range(n):
            w += pL[i] * X[i]
            wd += pL[i] * X[n + i]
        w_prev = w
        wd_prev = wd
        aux = 0.0
        auxd = 0.0
        if has_aux:
            aux = X[iy]
            auxd = X[iyd]
            if case == L.TMD:
                for i in range(n):
                    aux -= pA[i] * X[i]
                    auxd -= pA[i] * X[n + i]
            max_aux_all = max(max_aux_all, abs(aux))
        aux_prev = aux
        auxd_prev = auxd
        if regen:
            wptr += 1  # the row of node kg + 1
            if wptr == nbuf:
                wptr = 0
            buf[wptr, 0] = w
            buf[wptr, 1] = wd
            for j in range(nrev):
                ptr[j] += 1
                if ptr[j] == nbuf:
                    ptr[j] = 0
            if cut_zero:
                n_zero += 1
        if steady:
            (sum_w2, sum_w, n_steady, sum_aux2, sum_f, max_abs_w, max_w, min_w,
             max_aux) = steady_sample(w, aux, fst[3], sum_w2, sum_w, n_steady, sum_aux2, sum_f,
                                      max_abs_w, max_w, min_w, max_aux)
            if contact:
                t_contact += dt
        if rec_every > 0 and (k + 1) % rec_every == 0 and n_rec < cap_rec:
            rec[n_rec, 0] = t1
            rec[n_rec, 1] = w
            rec[n_rec, 2] = wd
            rec[n_rec, 3] = aux
            rec[n_rec, 4] = auxd
            rec[n_rec, 5] = fst[3]
            n_rec += 1
        sn = s_1
        cn = c_1
        if cut_zero and stop_at_zero:
            steps_run = k + 1
            break

    # a stick interval still open at the end is closed there
    if in_stick:
        close_stick(met, stick, stick_t0, t0 + steps_run * dt, t_steady, stick_min)

    x[:] = X
    store_steady(met, sum_w2, sum_w, n_steady, sum_aux2, sum_f, t_contact)
    store_extremes(met, max_abs_w, max_w, min_w, max_aux, max_aux_all)
    store_flows(met, w_force, d_visc, d_fric, w_nr)
    met[L.N_REC] = n_rec
    met[L.N_STROBE] = n_stb
    met[L.MAX_FORCE] = max_force
    met[L.FIRST_ZERO_T] = first_zero
    met[L.N_ZERO_STEPS] = n_zero
    met[L.STEPS_DONE] += steps_run


# One compiled specialisation per mode count: with n a compile-time constant
# the mode loops unroll (about 2.3x faster per step than a run-time n).  The
# harmonic ball damper with 1 and 2 modes (the published bar, the physical
# preset) has its own, with the case and the forcing constant as well, so
# that LLVM drops the other bars' and cutting's branches (measured in
# benchmarks/bench_kernel.py).  No fast-math flag at all: with multiply-adds
# allowed to fuse (``contract``), LLVM fused differently in differently
# shaped code, and the batched kernel's results no longer equalled these bit
# for bit; under plain IEEE arithmetic the same operations in the same order
# give the same bits whatever the code around them.
@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_n1(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met, buf):
    _rk4(1, int(p[L.CASE]), int(p[L.FORCING]) == L.REGENERATIVE, p, x, t0, dt, n_steps,
         steady_start, rec_every, rec, imp, stick, strobe, met, buf)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_n2(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met, buf):
    _rk4(2, int(p[L.CASE]), int(p[L.FORCING]) == L.REGENERATIVE, p, x, t0, dt, n_steps,
         steady_start, rec_every, rec, imp, stick, strobe, met, buf)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_n3(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met, buf):
    _rk4(3, int(p[L.CASE]), int(p[L.FORCING]) == L.REGENERATIVE, p, x, t0, dt, n_steps,
         steady_start, rec_every, rec, imp, stick, strobe, met, buf)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_any(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met, buf):
    _rk4(int(p[L.N_MODES]), int(p[L.CASE]), int(p[L.FORCING]) == L.REGENERATIVE, p, x, t0, dt,
         n_steps, steady_start, rec_every, rec, imp, stick, strobe, met, buf)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_ball1(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met,
               buf):
    _rk4(1, L.BALL, False, p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick,
         strobe, met, buf)


@njit(cache=True, error_model="numpy", nogil=True)
def _rk4_ball2(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met,
               buf):
    _rk4(2, L.BALL, False, p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick,
         strobe, met, buf)


_BY_MODES = {1: _rk4_n1, 2: _rk4_n2, 3: _rk4_n3}
_BALL_BY_MODES = {1: _rk4_ball1, 2: _rk4_ball2}


def run_rk4(p, x, t0, dt, n_steps, steady_start, rec_every, rec, imp, stick, strobe, met,
            buf=None):
    """Advance ``x`` by ``n_steps`` RK4 steps (see :func:`_rk4` for the arguments)."""
    if not 1 <= int(p[L.N_MODES]) <= L.NMAX or int(p[L.N_REV]) > _NREV_MAX:
        raise ValueError(f"kernel: {int(p[L.N_MODES])} modes (1..{L.NMAX}) and "
                         f"{int(p[L.N_REV])} revolutions (at most {_NREV_MAX}) are supported")
    n = int(p[L.N_MODES])
    kernel = _BY_MODES.get(n, _rk4_any)
    if int(p[L.CASE]) == L.BALL and int(p[L.FORCING]) == L.HARMONIC:
        kernel = _BALL_BY_MODES.get(n, kernel)
    if buf is None:
        buf = np.zeros((0, 2))
    kernel(p, x, float(t0), float(dt), int(n_steps), int(steady_start), int(rec_every), rec,
           imp, stick, strobe, met, buf)
