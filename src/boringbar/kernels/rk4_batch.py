"""The published RK4 scheme for a batch of runs advanced in lock-step.

One RK4 step is a chain of four dependent stage evaluations, so a single
run waits on latency (``kernels/rk4.py``, "Where the rest goes" in
docs/performance.md).  This kernel advances up to ``BMAX`` independent runs
together: every stage, the step-end impact law and the streamed metrics are
loops over the runs, innermost, so the runs' chains overlap (the stage loops
are vectorised: four runs to an instruction).

The runs of a batch share the mode count, the case (solid, ball, locked,
tmd), ``t0``, ``dt``, the number of steps and the steady start; each has its
own parameter vector (force, frequency, friction, gap, restitution, ...;
row ``r`` of ``P``), its own state (row ``r`` of ``x``), its own metrics
(row ``r`` of ``met``, layout in ``kernels/layout.py``) and its own impact,
stick and strobe records (``imp[r]``, ``stick[r]``, ``strobe[r]``).  Harmonic
forcing only: regenerative cuts (the delay buffer) and the decimated history
stay with the single-run kernel.

The arithmetic of a run is that of :func:`boringbar.kernels.rk4._rk4`, the
same operations in the same order (friction sgn() at every stage, the impact
law at step ends, stage-weighted energy flows, the forcing-phase rotation
with an exact sin/cos every 256 steps; the strobe interpolation is shared,
``kernels/interp.py``), so a run gives the single-run kernel's results:
tests/test_batch.py checks that they are bit-identical for the batch sizes
of ``LANES``.

Speed: per-run values are stored run-minor (``X[j, r]``) and the mode count,
the case and the batch size are compile-time constants, so each stage is one
loop over the runs with constant strides and no branch (the friction sgn()
becomes a select), which LLVM vectorises four runs to an AVX2 instruction.
With a run-time batch size LLVM guarded the vector loop with overlap checks
between the rows of the run-minor arrays and ran the scalar loop instead.
The step-end events (strobe, walls, stick intervals) are a scalar loop over
the runs; the streamed metrics vectorised loops (the steady part's its own
loop: folded into the other, ``if steady`` became masked loads and stores).
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
    steady_sample,
    stick_step,
    strobe_row,
    wall_rule,
)
from boringbar.kernels.linmap import NZ_MAX, PD_MAX, VR_MAX, WV_MAX, YR_MAX, build_map
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow

#: most runs in one batch
BMAX = 16
#: the batch sizes callers use (simulate_batch pads to one of them): multiples of
#: the 4 doubles of an AVX2 vector, so every run goes through the vectorised loops
LANES = (4, 8, 16)
_NX_MAX = 2 * L.NMAX + 2
_B = BMAX
_BN = BMAX * L.NMAX
_BX = BMAX * _NX_MAX
_BM = BMAX * L.MET_SIZE
_B4 = BMAX * 4
_RESYNC = 256
_BPD = BMAX * PD_MAX
_BYR = BMAX * YR_MAX
_BVR = BMAX * VR_MAX
_BWV = BMAX * WV_MAX
_BNZ = BMAX * NZ_MAX


@njit(cache=True, error_model="numpy", inline="always")
def _rk4_batch(n, case, nb, P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    """Advance the states ``x`` ((nb, 2n+2), updated in place) by ``n_steps`` steps.

    ``n`` modes and ``case`` (layout.SOLID, BALL, TMD, LOCKED) are the batch's;
    ``P`` (nb, P_SIZE) the runs' parameter vectors; ``met`` (nb, MET_SIZE) their
    metrics (fresh: zeros, STEADY_MAX_W = -inf, STEADY_MIN_W = +inf); ``imp``
    (nb, cap, 3), ``stick`` (nb, cap, 2), ``strobe`` (nb, cap, 5) their records,
    as in :func:`boringbar.kernels.rk4._rk4` (no history, no cutting).

    Per-run values are stored run-minor (``X[j, r]``), and the stages are loops
    over the runs with no branch that depends on a run's state except through
    selects, so LLVM vectorises them across runs (4 runs per AVX2 instruction).
    The step-end events (strobe, walls, stick) are a scalar loop over the runs.
    """
    f8 = np.float64
    # borrowed (kernels/views.py): a run's rows go to the shared helpers (kernels/core.py)
    # at every step without reference counting
    imp = borrow(imp)
    stick = borrow(stick)
    strobe = borrow(strobe)
    ball = case == L.BALL
    has_aux = case == L.BALL or case == L.TMD
    nx = 2 * n + 2
    iy = 2 * n
    iyd = 2 * n + 1

    # per-run modal constants, premultiplied as in _rk4: [mode, run]
    pL = carray(stack_ptr(_BN, f8), (n, nb))
    pD = carray(stack_ptr(_BN, f8), (n, nb))
    pA = carray(stack_ptr(_BN, f8), (n, nb))
    C = carray(stack_ptr(_BN, f8), (n, nb))
    invM = carray(stack_ptr(_BN, f8), (n, nb))
    fm = carray(stack_ptr(_BN, f8), (n, nb))
    km = carray(stack_ptr(_BN, f8), (n, nb))
    cm = carray(stack_ptr(_BN, f8), (n, nb))
    dm = carray(stack_ptr(_BN, f8), (n, nb))
    lm = carray(stack_ptr(_BN, f8), (n, nb))
    # per-run scalars
    f0 = carray(stack_ptr(_B, f8), nb)
    om = carray(stack_ptr(_B, f8), nb)
    half = carray(stack_ptr(_B, f8), nb)
    e = carray(stack_ptr(_B, f8), nb)
    fc = carray(stack_ptr(_B, f8), nb)
    sr = carray(stack_ptr(_B, f8), nb)
    meff = carray(stack_ptr(_B, f8), nb)
    vimp = carray(stack_ptr(_B, f8), nb)
    stick_min = carray(stack_ptr(_B, f8), nb)
    vstick = carray(stack_ptr(_B, f8), nb)
    ma = carray(stack_ptr(_B, f8), nb)
    ka = carray(stack_ptr(_B, f8), nb)
    ca = carray(stack_ptr(_B, f8), nb)
    tstrobe = carray(stack_ptr(_B, f8), nb)
    kappa = carray(stack_ptr(_B, f8), nb)
    chh = carray(stack_ptr(_B, f8), nb)
    shh = carray(stack_ptr(_B, f8), nb)
    sn = carray(stack_ptr(_B, f8), nb)
    cn = carray(stack_ptr(_B, f8), nb)
    t_next = carray(stack_ptr(_B, f8), nb)
    w_prev = carray(stack_ptr(_B, f8), nb)
    wd_prev = carray(stack_ptr(_B, f8), nb)
    aux_prev = carray(stack_ptr(_B, f8), nb)
    auxd_prev = carray(stack_ptr(_B, f8), nb)
    stick_t0 = carray(stack_ptr(_B, f8), nb)
    contact = carray(stack_ptr(_B, f8), nb)  # 1.0: the ball is on a wall this step
    in_stick = carray(stack_ptr(_B, np.int64), nb)
    n_stb = carray(stack_ptr(_B, np.int64), nb)
    # streamed metrics: [metric, run] (the events' counts and rows too, kernels/core.py)
    ms = carray(stack_ptr(_BM, f8), (L.MET_SIZE, nb))
    # state, stage derivative, weighted sum of the stage derivatives: [component, run]
    X = carray(stack_ptr(_BX, f8), (nx, nb))
    Kd = carray(stack_ptr(_BX, f8), (nx, nb))
    acc = carray(stack_ptr(_BX, f8), (nx, nb))
    fst = carray(stack_ptr(_B4, f8), (4, nb))  # forcing at the stages
    Xs = carray(stack_ptr(_NX_MAX, f8), nx)  # one run's stage state (registers)
    cst = carray(stack_ptr(4, f8), 4)
    wst = carray(stack_ptr(4, f8), 4)
    for st in range(4):
        cst[st] = (0.0, 0.5, 0.5, 1.0)[st] * dt
        wst[st] = (1.0, 2.0, 2.0, 1.0)[st] * (dt / 6.0)

    t_steady = t0 + steady_start * dt
    for r in range(nb):
        p = P[r]
        for i in range(n):
            invM[i, r] = 1.0 / p[L.M_ + i]
            C[i, r] = p[L.C_ + i]
            pL[i, r] = p[L.PSI_L + i]
            pD[i, r] = p[L.PSI_D + i]
            pA[i, r] = p[L.PSI_A + i]
        f0[r] = p[L.F0]
        om[r] = p[L.OMEGA]
        m = p[L.BALL_MASS]
        half[r] = p[L.HALF_GAP]
        e[r] = p[L.RESTITUTION]
        fc[r] = p[L.FRICTION]
        sr[r] = p[L.REACTION]
        meff[r] = p[L.M_EFF]
        vimp[r] = p[L.V_IMPACT]
        stick_min[r] = p[L.STICK_MIN]
        vstick[r] = p[L.V_STICK]
        ma[r] = p[L.TMD_MASS]
        ka[r] = p[L.TMD_K]
        ca[r] = p[L.TMD_C]
        tstrobe[r] = p[L.STROBE_PERIOD]
        kap = 1.0 / m if m > 0.0 else 0.0
        for i in range(n):
            fm[i, r] = pL[i, r] * invM[i, r]
            km[i, r] = p[L.K_ + i] * invM[i, r]
            cm[i, r] = C[i, r] * invM[i, r]
            dm[i, r] = sr[r] * pD[i, r] * invM[i, r]
            lm[i, r] = meff[r] * pD[i, r] * invM[i, r]
            kap += pD[i, r] * dm[i, r]
        kappa[r] = kap
        chh[r] = math.cos(om[r] * 0.5 * dt)
        shh[r] = math.sin(om[r] * 0.5 * dt)
        sn[r] = 0.0
        cn[r] = 1.0
        for j in range(nx):
            X[j, r] = x[r, j]
            Kd[j, r] = 0.0
        if case == L.LOCKED:
            X[iyd, r] = 0.0
        for q in range(L.MET_SIZE):
            ms[q, r] = met[r, q]
        n_stb[r] = int(met[r, L.N_STROBE])
        in_stick[r] = 0
        stick_t0[r] = 0.0
        contact[r] = 0.0
        wp = 0.0
        wdp = 0.0
        ap = X[iy, r]
        adp = X[iyd, r]
        for i in range(n):
            wp += pL[i, r] * X[i, r]
            wdp += pL[i, r] * X[n + i, r]
            if case == L.TMD:
                ap -= pA[i, r] * X[i, r]
                adp -= pA[i, r] * X[n + i, r]
        w_prev[r] = wp
        wd_prev[r] = wdp
        aux_prev[r] = ap
        auxd_prev[r] = adp
        tn = 0.0
        if tstrobe[r] > 0.0:
            tn = p[L.STROBE_T0]
            if tn < t0:
                tn += math.ceil((t0 - tn) / tstrobe[r]) * tstrobe[r]
        t_next[r] = tn
    cap_stb = strobe.shape[1]

    # the step as an affine map where F_b cannot switch (kernels/linmap.py), per
    # run: the single-run kernel's tables and arithmetic, run-minor
    tmd = case == L.TMD
    diag = case == L.SOLID or case == L.BALL
    nz = nx + 3
    iS = nx
    iC = nx + 1
    iF = nx + 2
    Pd = carray(stack_ptr(_BPD, f8), (nx, nz, nb))
    Yr = carray(stack_ptr(_BYR, f8), (3, nz, nb))
    Vr = carray(stack_ptr(_BVR, f8), (3, n + 1, nz, nb))
    Wv = carray(stack_ptr(_BWV, f8), (4, n + 1, nb))
    Fs = carray(stack_ptr(_BNZ, f8), (nz, nb))
    Fc = carray(stack_ptr(_BNZ, f8), (nz, nb))
    Pd1 = carray(stack_ptr(PD_MAX, f8), (nx, nz))
    Yr1 = carray(stack_ptr(YR_MAX, f8), (3, nz))
    Vr1 = carray(stack_ptr(VR_MAX, f8), (3, n + 1, nz))
    Wv1 = carray(stack_ptr(WV_MAX, f8), (4, n + 1))
    Fs1 = carray(stack_ptr(NZ_MAX, f8), nz)
    Fc1 = carray(stack_ptr(NZ_MAX, f8), nz)
    dX = carray(stack_ptr(_BX, f8), (nx, nb))
    S0 = carray(stack_ptr(_B, f8), nb)  # sin, cos of Omega t at the step's start
    C0 = carray(stack_ptr(_B, f8), nb)
    fz = carray(stack_ptr(_B, f8), nb)  # F_b of a mapped step
    um = carray(stack_ptr(_B, np.int64), nb)  # 1: the run takes the map this step
    staged = carray(stack_ptr(_B, np.int64), nb)  # 1: the run may take the map at all
    for r in range(nb):
        build_map(n, P[r], dt, Pd1, Yr1, Vr1, Wv1, Fs1, Fc1)
        for a in range(nz):
            for s3 in range(3):
                Yr[s3, a, r] = Yr1[s3, a]
                for i in range(n + 1):
                    Vr[s3, i, a, r] = Vr1[s3, i, a]
            Fs[a, r] = Fs1[a]
            Fc[a, r] = Fc1[a]
            for j in range(nx):
                Pd[j, a, r] = Pd1[j, a]
        for s4 in range(4):
            for i in range(n + 1):
                Wv[s4, i, r] = Wv1[s4, i]
        staged[r] = 1 if P[r, L.STAGE_LOOP] != 0.0 else 0

    for k in range(n_steps):
        t = t0 + k * dt
        t1 = t0 + (k + 1) * dt  # not t + dt: keeps event times inside [t0, t_end]
        steady = k >= steady_start
        if k % _RESYNC == 0:
            for r in range(nb):
                sn[r] = math.sin(om[r] * t)
                cn[r] = math.cos(om[r] * t)
        for r in range(nb):
            S0[r] = sn[r]
            C0[r] = cn[r]
            s_h = sn[r] * chh[r] + cn[r] * shh[r]
            c_h = cn[r] * chh[r] - sn[r] * shh[r]
            s_1 = s_h * chh[r] + c_h * shh[r]
            c_1 = c_h * chh[r] - s_h * shh[r]
            fst[0, r] = f0[r] * sn[r]
            fst[1, r] = f0[r] * s_h
            fst[2, r] = fst[1, r]
            fst[3, r] = f0[r] * s_1
            sn[r] = s_1
            cn[r] = c_1
            for j in range(nx):
                acc[j, r] = 0.0

        # --- the step as an affine map for the runs whose F_b keeps its sign ------
        # (the decision and the arithmetic of kernels/rk4.py, run by run)
        n_staged = 0
        for r in range(nb):
            ok = staged[r] == 0
            fzr = 0.0
            if ball and fc[r] > 0.0:
                yd0 = X[iyd, r]
                fzr = -fc[r] if yd0 > 0.0 else fc[r]
                ok = ok and abs(yd0) >= vstick[r]
                for s3 in range(3):
                    ys = Yr[s3, iS, r] * S0[r] + Yr[s3, iC, r] * C0[r] + Yr[s3, iF, r] * fzr
                    for j in range(nx):
                        ys += Yr[s3, j, r] * X[j, r]
                    ok = ok and ys * yd0 > 1e-12 * (yd0 * yd0 + abs(yd0 * (ys - yd0)))
            fz[r] = fzr
            um[r] = 1 if ok else 0
            n_staged += 0 if ok else 1
        if n_staged < nb:  # the map, unless no run takes it (every ball sticking, say)
            for r in range(nb):
                sn0 = S0[r]
                cn0 = C0[r]
                fzr = fz[r]
                if diag:
                    for i in range(n):
                        a = i
                        dX[a, r] = (Pd[a, iS, r] * sn0 + Pd[a, iC, r] * cn0 + Pd[a, iF, r] * fzr
                                    + Pd[a, i, r] * X[i, r] + Pd[a, n + i, r] * X[n + i, r])
                        a = n + i
                        dX[a, r] = (Pd[a, iS, r] * sn0 + Pd[a, iC, r] * cn0 + Pd[a, iF, r] * fzr
                                    + Pd[a, i, r] * X[i, r] + Pd[a, n + i, r] * X[n + i, r])
                    dX[iy, r] = 0.0
                    dX[iyd, r] = 0.0
                    if ball:
                        for a in range(iy, nx):
                            dj = Pd[a, iS, r] * sn0 + Pd[a, iC, r] * cn0 + Pd[a, iF, r] * fzr
                            for q in range(nx):
                                dj += Pd[a, q, r] * X[q, r]
                            dX[a, r] = dj
                else:
                    for a in range(nx):
                        dj = Pd[a, iS, r] * sn0 + Pd[a, iC, r] * cn0 + Pd[a, iF, r] * fzr
                        for q in range(nx):
                            dj += Pd[a, q, r] * X[q, r]
                        dX[a, r] = dj
                pv = 0.0
                for i in range(n):
                    pv += Wv[0, i, r] * X[n + i, r] * X[n + i, r]
                if tmd:
                    rd = X[iyd, r]
                    for i in range(n):
                        rd -= pA[i, r] * X[n + i, r]
                    pv += Wv[0, n, r] * rd * rd
                for s3 in range(3):
                    for i in range(n):
                        v = Vr[s3, i, iS, r] * sn0 + Vr[s3, i, iC, r] * cn0 + Vr[s3, i, iF, r] * fzr
                        if diag:
                            v += Vr[s3, i, i, r] * X[i, r] + Vr[s3, i, n + i, r] * X[n + i, r]
                        else:
                            for q in range(nx):
                                v += Vr[s3, i, q, r] * X[q, r]
                        pv += Wv[s3 + 1, i, r] * v * v
                    if tmd:
                        v = Vr[s3, n, iS, r] * sn0 + Vr[s3, n, iC, r] * cn0
                        for q in range(nx):
                            v += Vr[s3, n, q, r] * X[q, r]
                        pv += Wv[s3 + 1, n, r] * v * v
                ws_ = Fs[iS, r] * sn0 + Fs[iC, r] * cn0 + Fs[iF, r] * fzr
                wc_ = Fc[iS, r] * sn0 + Fc[iC, r] * cn0 + Fc[iF, r] * fzr
                for q in range(nx):
                    ws_ += Fs[q, r] * X[q, r]
                    wc_ += Fc[q, r] * X[q, r]
                if um[r] != 0:
                    ms[L.D_VISC, r] += pv
                    ms[L.W_FORCE, r] += sn0 * ws_ + cn0 * wc_
                    if ball:
                        ms[L.D_FRICTION, r] -= fzr * dX[iy, r]
                        pdu = 0.0
                        for i in range(n):
                            pdu += pD[i, r] * dX[i, r]
                        ms[L.W_NONRECIP, r] += (1.0 - sr[r]) * fzr * pdu

        # --- the others: the four RK4 stages, each a loop over the runs ---------
        if n_staged > 0:
            for st in range(4):
                cs = cst[st]
                w_s = wst[st]
                for r in range(nb):
                    for j in range(nx):
                        Xs[j] = X[j, r] + cs * Kd[j, r]
                    f = fst[st, r]
                    wd = 0.0
                    pvisc = 0.0
                    sfree = 0.0
                    for i in range(n):
                        vi = Xs[n + i]
                        Kd[i, r] = vi
                        ai = (fm[i, r] * f - km[i, r] * Xs[i]) - cm[i, r] * vi
                        Kd[n + i, r] = ai
                        sfree += pD[i, r] * ai
                        wd += pL[i, r] * vi
                        pvisc += C[i, r] * vi * vi
                    ydd = 0.0
                    if ball:
                        yds = Xs[iyd]
                        # F_b = -F_c sgn(y'), sgn(0) = 0
                        fb = -fc[r] if yds > 0.0 else (fc[r] if yds < 0.0 else 0.0)
                        pdv = 0.0
                        for i in range(n):
                            Kd[n + i, r] -= dm[i, r] * fb
                            pdv += pD[i, r] * Xs[n + i]
                        ydd = kappa[r] * fb - sfree
                        if um[r] == 0:
                            ms[L.D_FRICTION, r] -= w_s * fb * yds
                            ms[L.W_NONRECIP, r] += w_s * (1.0 - sr[r]) * fb * pdv
                    elif case == L.TMD:
                        rel = Xs[iy]
                        reld = Xs[iyd]
                        for i in range(n):
                            rel -= pA[i, r] * Xs[i]
                            reld -= pA[i, r] * Xs[n + i]
                        ft = ka[r] * rel + ca[r] * reld
                        for i in range(n):
                            Kd[n + i, r] += pA[i, r] * ft * invM[i, r]
                        ydd = -ft / ma[r]
                        pvisc += ca[r] * reld * reld
                    elif case == L.LOCKED:
                        for i in range(n):
                            Kd[n + i, r] -= lm[i, r] * sfree
                    Kd[iy, r] = Xs[iyd] if has_aux else 0.0
                    Kd[iyd, r] = ydd
                    for j in range(nx):
                        acc[j, r] += w_s * Kd[j, r]
                    if um[r] == 0:
                        ms[L.W_FORCE, r] += w_s * f * wd
                        ms[L.D_VISC, r] += w_s * pvisc
        for r in range(nb):
            for j in range(nx):
                X[j, r] += dX[j, r] if um[r] != 0 else acc[j, r]

        # --- step-end events, run by run ----------------------------------------
        for r in range(nb):
            # Poincare strobe: cubic Hermite in [t, t1]
            if tstrobe[r] > 0.0 and t_next[r] <= t1:
                tn = t_next[r]
                if tn > t and n_stb[r] < cap_stb:
                    w1 = 0.0
                    wd1 = 0.0
                    for i in range(n):
                        w1 += pL[i, r] * X[i, r]
                        wd1 += pL[i, r] * X[n + i, r]
                    a1 = X[iy, r]
                    ad1 = X[iyd, r]
                    if case == L.TMD:
                        for i in range(n):
                            a1 -= pA[i, r] * X[i, r]
                            ad1 -= pA[i, r] * X[n + i, r]
                    strobe_row(strobe[r, n_stb[r]], tn, t, dt, w_prev[r], wd_prev[r], w1, wd1,
                               aux_prev[r], auxd_prev[r], a1, ad1)
                    n_stb[r] += 1
                t_next[r] = tn + tstrobe[r]
            if not ball:
                continue
            # walls (docs/model.md, section 2)
            mr = ms[:, r]
            out, X[iy, r], X[iyd, r], g = wall_rule(mr, imp[r], X[iy, r], X[iyd, r], t1, steady,
                                                    half[r], e[r], meff[r], vimp[r])
            if out == IMPACT or out == MICRO_IMPACT:
                for i in range(n):
                    X[n + i, r] += g * pD[i, r] * invM[i, r]
            hit = out == MICRO_IMPACT or out == ON_WALL
            contact[r] = 1.0 if hit else 0.0
            # stick: off the walls with |y'| inside the chattering band
            stuck = fc[r] > 0.0 and not hit and abs(X[iyd, r]) < vstick[r]
            ins, stick_t0[r] = stick_step(stuck, in_stick[r] != 0, stick_t0[r], t, t1, mr,
                                          stick[r], t_steady, stick_min[r])
            in_stick[r] = 1 if ins else 0

        # --- streamed metrics: loops over the runs (the steady part's a loop of its
        # own: inside one loop LLVM turned `if steady` into masked loads and
        # stores, which took a third of the time on this CPU)
        for r in range(nb):
            w = 0.0
            wd = 0.0
            for i in range(n):
                w += pL[i, r] * X[i, r]
                wd += pL[i, r] * X[n + i, r]
            w_prev[r] = w
            wd_prev[r] = wd
            aux = 0.0
            auxd = 0.0
            if has_aux:
                aux = X[iy, r]
                auxd = X[iyd, r]
                if case == L.TMD:
                    for i in range(n):
                        aux -= pA[i, r] * X[i, r]
                        auxd -= pA[i, r] * X[n + i, r]
            aux_prev[r] = aux
            auxd_prev[r] = auxd
        if has_aux:  # a loop of its own, else a masked store again
            for r in range(nb):
                ms[L.MAX_ABS_AUX_ALL, r] = max(ms[L.MAX_ABS_AUX_ALL, r], abs(aux_prev[r]))
        if steady:
            for r in range(nb):
                (ms[L.SUM_W2, r], ms[L.SUM_W, r], ms[L.N_STEADY, r], ms[L.SUM_AUX2, r],
                 ms[L.SUM_F, r], ms[L.MAX_ABS_W, r], ms[L.STEADY_MAX_W, r],
                 ms[L.STEADY_MIN_W, r], ms[L.MAX_ABS_AUX, r]) = steady_sample(
                    w_prev[r], aux_prev[r], fst[3, r], ms[L.SUM_W2, r], ms[L.SUM_W, r],
                    ms[L.N_STEADY, r], ms[L.SUM_AUX2, r], ms[L.SUM_F, r], ms[L.MAX_ABS_W, r],
                    ms[L.STEADY_MAX_W, r], ms[L.STEADY_MIN_W, r], ms[L.MAX_ABS_AUX, r])
                ms[L.T_CONTACT, r] += contact[r] * dt

    t_end = t0 + n_steps * dt
    for r in range(nb):
        # a stick interval still open at the end is closed there
        if in_stick[r] != 0:
            close_stick(ms[:, r], stick[r], stick_t0[r], t_end, t_steady, stick_min[r])
        for j in range(nx):
            x[r, j] = X[j, r]
        for q in range(L.MET_SIZE):
            met[r, q] = ms[q, r]
        met[r, L.N_STROBE] = n_stb[r]
        met[r, L.STEPS_DONE] += n_steps


# One compiled specialisation per mode count and case (written out: numba
# caches functions, not closures), and per batch size: ``lanes`` is a tuple of
# nb zeros, whose length is part of its type.  With all three compile-time
# constants the mode loops unroll, the case branches fold away and the loops
# over the runs have constant strides and trip counts, so LLVM vectorises them
# without run-time overlap checks.  Each compiles on first use.


@njit(cache=True, error_model="numpy", nogil=True)
def _b1_solid(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(1, L.SOLID, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b1_ball(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(1, L.BALL, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b1_tmd(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(1, L.TMD, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b1_locked(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(1, L.LOCKED, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b2_solid(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(2, L.SOLID, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b2_ball(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(2, L.BALL, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b2_tmd(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(2, L.TMD, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b2_locked(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(2, L.LOCKED, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b3_solid(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(3, L.SOLID, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b3_ball(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(3, L.BALL, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b3_tmd(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(3, L.TMD, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b3_locked(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(3, L.LOCKED, len(lanes), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


@njit(cache=True, error_model="numpy", nogil=True)
def _b_any(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met, lanes):
    _rk4_batch(int(P[0, L.N_MODES]), int(P[0, L.CASE]), len(lanes), P, x, t0, dt, n_steps,
               steady_start, imp, stick, strobe, met)


_SPECIALISED = {
    (1, L.SOLID): _b1_solid, (1, L.BALL): _b1_ball, (1, L.TMD): _b1_tmd, (1, L.LOCKED): _b1_locked,
    (2, L.SOLID): _b2_solid, (2, L.BALL): _b2_ball, (2, L.TMD): _b2_tmd, (2, L.LOCKED): _b2_locked,
    (3, L.SOLID): _b3_solid, (3, L.BALL): _b3_ball, (3, L.TMD): _b3_tmd, (3, L.LOCKED): _b3_locked,
}


def run_rk4_batch(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    """Advance the batch's states ``x`` by ``n_steps`` RK4 steps (see :func:`_rk4_batch`).

    Every row of ``P`` must have the same mode count and case and harmonic
    forcing; at most ``BMAX`` rows.  Each batch size compiles once (per mode
    count and case); the sizes of ``LANES`` give the single-run kernel's results
    bit for bit (tests/test_batch.py), others are not checked (a batch of one,
    straight-line code, differs in the last bits).
    """
    nb = P.shape[0]
    if not 1 <= nb <= BMAX:
        raise ValueError(f"kernel: a batch of {nb} runs (1..{BMAX}) is not supported")
    modes = P[:, L.N_MODES]
    cases = P[:, L.CASE]
    if np.any(modes != modes[0]) or np.any(cases != cases[0]):
        raise ValueError("kernel: the runs of a batch must share the mode count and the case")
    if np.any(P[:, L.FORCING] != L.HARMONIC):
        raise ValueError("kernel: batches take harmonic forcing only (cuts: run_rk4)")
    n = int(modes[0])
    if not 1 <= n <= L.NMAX:
        raise ValueError(f"kernel: {n} modes (1..{L.NMAX}) are supported")
    nx = 2 * n + 2
    if (x.shape != (nb, nx) or met.shape != (nb, L.MET_SIZE) or imp.shape[0] != nb
            or stick.shape[0] != nb or strobe.shape[0] != nb):
        raise ValueError("kernel: x, met, imp, stick and strobe need one row per run")
    kernel = _SPECIALISED.get((n, int(cases[0])), _b_any)
    kernel(P, x, float(t0), float(dt), int(n_steps), int(steady_start), imp, stick, strobe, met,
           (0,) * nb)
