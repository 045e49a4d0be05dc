"""The published RK4 scheme for a batch of runs advanced in lock-step.

One RK4 step is a chain of four dependent stage evaluations, so a single
run waits on latency (``kernels/rk4.py``, "Where the rest goes" in
docs/performance.md).  This kernel advances up to ``BMAX`` independent runs
together: every stage, the step-end impact law and the streamed metrics are
loops over the runs, innermost, so the CPU overlaps the runs' chains.

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
with an exact sin/cos every 256 steps), so a run gives the single-run
kernel's results; tests/test_batch.py checks that they are bit-identical.
The batch size is a run-time value (one compiled specialisation per mode
count), so a run's machine code, hence its results, do not depend on which
other runs share its batch.
"""

import math

import numpy as np
from numba import carray, njit, types
from numba.extending import intrinsic

from boringbar.kernels import layout as L
from boringbar.kernels.stack import stack_ptr

#: most runs in one batch
BMAX = 16
_NX_MAX = 2 * L.NMAX + 2
_B = BMAX
_BN = BMAX * L.NMAX
_BX = BMAX * _NX_MAX
_B4 = BMAX * 4
_BM = BMAX * L.MET_SIZE
_RESYNC = 256


@intrinsic
def _fma(typingctx, a, b, c):
    """a * b + c rounded once (llvm.fma), where the contraction must be pinned."""
    def codegen(context, builder, signature, args):
        return builder.fma(*args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@njit(cache=True, error_model="numpy", fastmath={"contract"}, inline="always")
def _rk4_batch(n, P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    """Advance the states ``x`` ((nb, 2n+2), updated in place) by ``n_steps`` steps.

    ``P`` (nb, P_SIZE) the runs' parameter vectors; ``met`` (nb, MET_SIZE) their
    metrics (fresh: zeros, STEADY_MAX_W = -inf, STEADY_MIN_W = +inf); ``imp``
    (nb, cap, 3), ``stick`` (nb, cap, 2), ``strobe`` (nb, cap, 5) their records,
    as in :func:`boringbar.kernels.rk4._rk4` (no history, no cutting).
    """
    nb = P.shape[0]
    f8 = np.float64
    case = int(P[0, L.CASE])
    ball = case == L.BALL
    has_aux = case == L.BALL or case == L.TMD
    nx = 2 * n + 2
    iy = 2 * n
    iyd = 2 * n + 1

    # per-run modal constants, premultiplied as in _rk4
    pL = carray(stack_ptr(_BN, f8), (nb, n))
    pD = carray(stack_ptr(_BN, f8), (nb, n))
    pA = carray(stack_ptr(_BN, f8), (nb, n))
    C = carray(stack_ptr(_BN, f8), (nb, n))
    invM = carray(stack_ptr(_BN, f8), (nb, n))
    fm = carray(stack_ptr(_BN, f8), (nb, n))
    km = carray(stack_ptr(_BN, f8), (nb, n))
    cm = carray(stack_ptr(_BN, f8), (nb, n))
    dm = carray(stack_ptr(_BN, f8), (nb, n))
    lm = carray(stack_ptr(_BN, f8), (nb, n))
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
    s1 = carray(stack_ptr(_B, f8), nb)
    c1 = carray(stack_ptr(_B, f8), nb)
    t_next = carray(stack_ptr(_B, f8), nb)
    w_prev = carray(stack_ptr(_B, f8), nb)
    wd_prev = carray(stack_ptr(_B, f8), nb)
    aux_prev = carray(stack_ptr(_B, f8), nb)
    auxd_prev = carray(stack_ptr(_B, f8), nb)
    stick_t0 = carray(stack_ptr(_B, f8), nb)
    in_stick = carray(stack_ptr(_B, np.int64), nb)
    n_imp = carray(stack_ptr(_B, np.int64), nb)
    n_stk = carray(stack_ptr(_B, np.int64), nb)
    n_stb = carray(stack_ptr(_B, np.int64), nb)
    # energy flows (the per-stage accumulators) and the other metrics
    w_force = carray(stack_ptr(_B, f8), nb)
    d_visc = carray(stack_ptr(_B, f8), nb)
    d_fric = carray(stack_ptr(_B, f8), nb)
    w_nr = carray(stack_ptr(_B, f8), nb)
    ms = carray(stack_ptr(_BM, f8), (nb, L.MET_SIZE))
    # state, stage derivative, sum of weighted derivatives; the stage state
    X = carray(stack_ptr(_BX, f8), (nb, nx))
    Kd = carray(stack_ptr(_BX, f8), (nb, nx))
    acc = carray(stack_ptr(_BX, f8), (nb, nx))
    Xs = carray(stack_ptr(_NX_MAX, f8), nx)
    fst = carray(stack_ptr(_B4, f8), (nb, 4))
    cst = carray(stack_ptr(4, f8), 4)
    wst = carray(stack_ptr(4, f8), 4)
    for st in range(4):
        cst[st] = (0.0, 0.5, 0.5, 1.0)[st] * dt
        wst[st] = (1.0, 2.0, 2.0, 1.0)[st] * (dt / 6.0)

    t_steady = t0 + steady_start * dt
    for r in range(nb):
        p = P[r]
        for i in range(n):
            M_i = p[L.M_ + i]
            invM[r, i] = 1.0 / M_i
            C[r, i] = p[L.C_ + i]
            pL[r, i] = p[L.PSI_L + i]
            pD[r, i] = p[L.PSI_D + i]
            pA[r, i] = p[L.PSI_A + i]
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
            fm[r, i] = pL[r, i] * invM[r, i]
            km[r, i] = p[L.K_ + i] * invM[r, i]
            cm[r, i] = C[r, i] * invM[r, i]
            dm[r, i] = sr[r] * pD[r, i] * invM[r, i]
            lm[r, i] = meff[r] * pD[r, i] * invM[r, i]
            kap += pD[r, i] * dm[r, i]
        kappa[r] = kap
        chh[r] = math.cos(om[r] * 0.5 * dt)
        shh[r] = math.sin(om[r] * 0.5 * dt)
        sn[r] = 0.0
        cn[r] = 1.0

        for j in range(nx):
            X[r, j] = x[r, j]
            Kd[r, j] = 0.0
        if case == L.LOCKED:
            X[r, iyd] = 0.0
        for q in range(L.MET_SIZE):
            ms[r, q] = met[r, q]
        w_force[r] = met[r, L.W_FORCE]
        d_visc[r] = met[r, L.D_VISC]
        d_fric[r] = met[r, L.D_FRICTION]
        w_nr[r] = met[r, L.W_NONRECIP]
        n_imp[r] = int(met[r, L.N_IMP_REC])
        n_stk[r] = int(met[r, L.N_STICK_REC])
        n_stb[r] = int(met[r, L.N_STROBE])
        in_stick[r] = 0
        stick_t0[r] = 0.0

        wp = 0.0
        wdp = 0.0
        ap = X[r, iy]
        adp = X[r, iyd]
        for i in range(n):
            wp += pL[r, i] * X[r, i]
            wdp += pL[r, i] * X[r, n + i]
            if case == L.TMD:
                ap -= pA[r, i] * X[r, i]
                adp -= pA[r, i] * X[r, n + i]
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
    cap_imp = imp.shape[1]
    cap_stk = stick.shape[1]
    cap_stb = strobe.shape[1]

    for k in range(n_steps):
        t = t0 + k * dt
        t1 = t0 + (k + 1) * dt  # not t + dt: keeps event times inside [t0, t_end]
        resync = k % _RESYNC == 0
        for r in range(nb):
            if resync:
                sn[r] = math.sin(om[r] * t)
                cn[r] = math.cos(om[r] * t)
            s_h = sn[r] * chh[r] + cn[r] * shh[r]
            c_h = cn[r] * chh[r] - sn[r] * shh[r]
            s1[r] = s_h * chh[r] + c_h * shh[r]
            c1[r] = c_h * chh[r] - s_h * shh[r]
            fst[r, 0] = f0[r] * sn[r]
            fst[r, 1] = f0[r] * s_h
            fst[r, 2] = fst[r, 1]
            fst[r, 3] = f0[r] * s1[r]
            for j in range(nx):
                acc[r, j] = 0.0

        # --- four RK4 stages, each over every run of the batch --------------------
        for st in range(4):
            cs = cst[st]
            w_s = wst[st]
            for r in range(nb):
                for j in range(nx):
                    Xs[j] = X[r, j] + cs * Kd[r, j]
                f = fst[r, st]
                wd = 0.0
                pvisc = 0.0
                sfree = 0.0
                for i in range(n):
                    vi = Xs[n + i]
                    Kd[r, i] = vi
                    ai = (fm[r, i] * f - km[r, i] * Xs[i]) - cm[r, i] * vi
                    Kd[r, n + i] = ai
                    sfree += pD[r, i] * ai
                    wd += pL[r, i] * vi
                    pvisc += C[r, i] * vi * vi
                ydd = 0.0
                if ball:
                    yds = Xs[iyd]
                    fb = 0.0  # F_b = -F_c sgn(y'), sgn(0) = 0
                    if yds > 0.0:
                        fb = -fc[r]
                    elif yds < 0.0:
                        fb = fc[r]
                    pdv = 0.0
                    for i in range(n):
                        Kd[r, n + i] -= dm[r, i] * fb
                        pdv += pD[r, i] * Xs[n + i]
                    ydd = kappa[r] * fb - sfree
                    d_fric[r] -= w_s * fb * yds
                    w_nr[r] += w_s * (1.0 - sr[r]) * fb * pdv
                elif case == L.TMD:
                    rel = Xs[iy]
                    reld = Xs[iyd]
                    for i in range(n):
                        rel -= pA[r, i] * Xs[i]
                        reld -= pA[r, i] * Xs[n + i]
                    ft = ka[r] * rel + ca[r] * reld
                    for i in range(n):
                        Kd[r, n + i] += pA[r, i] * ft * invM[r, i]
                    ydd = -ft / ma[r]
                    pvisc += ca[r] * reld * reld
                elif case == L.LOCKED:
                    for i in range(n):
                        Kd[r, n + i] -= lm[r, i] * sfree
                Kd[r, iy] = Xs[iyd] if has_aux else 0.0
                Kd[r, iyd] = ydd
                for j in range(nx):
                    acc[r, j] += w_s * Kd[r, j]
                w_force[r] += w_s * f * wd
                d_visc[r] += w_s * pvisc
        steady = k >= steady_start

        for r in range(nb):
            for j in range(nx):
                X[r, j] += acc[r, j]

            # --- Poincare strobe: cubic Hermite in [t, t1] ------------------------
            if tstrobe[r] > 0.0 and t_next[r] <= t1:
                tn = t_next[r]
                if tn > t and n_stb[r] < cap_stb:
                    w1 = 0.0
                    wd1 = 0.0
                    for i in range(n):
                        w1 += pL[r, i] * X[r, i]
                        wd1 += pL[r, i] * X[r, n + i]
                    s = (tn - t) / dt
                    s2 = s * s
                    s3 = s2 * s
                    wp = w_prev[r]
                    wdp = wd_prev[r]
                    q = n_stb[r]
                    strobe[r, q, 0] = tn
                    strobe[r, q, 1] = ((2 * s3 - 3 * s2 + 1) * wp
                                       + (s3 - 2 * s2 + s) * dt * wdp
                                       + (-2 * s3 + 3 * s2) * w1 + (s3 - s2) * dt * wd1)
                    strobe[r, q, 2] = ((6 * s2 - 6 * s) / dt * (wp - w1)
                                       + (3 * s2 - 4 * s + 1) * wdp + (3 * s2 - 2 * s) * wd1)
                    a1 = X[r, iy]
                    ad1 = X[r, iyd]
                    if case == L.TMD:
                        for i in range(n):
                            a1 -= pA[r, i] * X[r, i]
                            ad1 -= pA[r, i] * X[r, n + i]
                    # _rk4's LLVM contracts (1 - s) a0 + s a1 to this fma; left to
                    # itself it picks the other product here
                    strobe[r, q, 3] = _fma(1 - s, aux_prev[r], s * a1)
                    strobe[r, q, 4] = _fma(1 - s, auxd_prev[r], s * ad1)
                    n_stb[r] += 1
                t_next[r] = tn + tstrobe[r]

            # --- walls (MODEL.md section 2) --------------------------------------
            contact = False
            if ball:
                y = X[r, iy]
                if abs(y) >= half[r]:
                    wall = 1.0 if y > 0.0 else -1.0
                    X[r, iy] = wall * half[r]
                    vb = X[r, iyd]
                    if wall * vb > 0.0:
                        X[r, iyd] = -e[r] * vb
                        g = (1.0 + e[r]) * meff[r] * vb
                        for i in range(n):
                            X[r, n + i] += g * pD[r, i] * invM[r, i]
                        ms[r, L.D_IMPACT] += 0.5 * (1.0 - e[r] * e[r]) * meff[r] * vb * vb
                        if abs(vb) > vimp[r]:
                            ms[r, L.N_IMP_ALL] += 1
                            if steady:
                                if wall > 0:
                                    ms[r, L.N_IMP_PLUS] += 1
                                else:
                                    ms[r, L.N_IMP_MINUS] += 1
                                q = n_imp[r]
                                if q < cap_imp:
                                    imp[r, q, 0] = t1
                                    imp[r, q, 1] = wall
                                    imp[r, q, 2] = vb
                                n_imp[r] = q + 1
                        else:
                            ms[r, L.N_MICRO] += 1
                            contact = True
                    else:
                        contact = True
                # stick: off the walls with |y'| inside the chattering band
                stuck = fc[r] > 0.0 and not contact and abs(X[r, iyd]) < vstick[r]
                if stuck and in_stick[r] == 0:
                    in_stick[r] = 1
                    stick_t0[r] = t
                elif in_stick[r] != 0 and not stuck:
                    in_stick[r] = 0
                    s0 = max(stick_t0[r], t_steady)
                    if t1 - s0 >= stick_min[r]:
                        ms[r, L.T_STICK] += t1 - s0
                        q = n_stk[r]
                        if q < cap_stk:
                            stick[r, q, 0] = s0
                            stick[r, q, 1] = t1
                        n_stk[r] = q + 1

            # --- streamed metrics ------------------------------------------------
            w = 0.0
            wd = 0.0
            for i in range(n):
                w += pL[r, i] * X[r, i]
                wd += pL[r, i] * X[r, n + i]
            w_prev[r] = w
            wd_prev[r] = wd
            aux = 0.0
            auxd = 0.0
            if has_aux:
                aux = X[r, iy]
                auxd = X[r, iyd]
                if case == L.TMD:
                    for i in range(n):
                        aux -= pA[r, i] * X[r, i]
                        auxd -= pA[r, i] * X[r, n + i]
                ms[r, L.MAX_ABS_AUX_ALL] = max(ms[r, L.MAX_ABS_AUX_ALL], abs(aux))
            aux_prev[r] = aux
            auxd_prev[r] = auxd
            if steady:
                ms[r, L.SUM_W2] += w * w
                ms[r, L.SUM_W] += w
                ms[r, L.N_STEADY] += 1.0
                ms[r, L.SUM_AUX2] += aux * aux
                ms[r, L.SUM_F] += fst[r, 3]
                ms[r, L.MAX_ABS_W] = max(ms[r, L.MAX_ABS_W], abs(w))
                ms[r, L.STEADY_MAX_W] = max(ms[r, L.STEADY_MAX_W], w)
                ms[r, L.STEADY_MIN_W] = min(ms[r, L.STEADY_MIN_W], w)
                ms[r, L.MAX_ABS_AUX] = max(ms[r, L.MAX_ABS_AUX], abs(aux))
                if contact:
                    ms[r, L.T_CONTACT] += dt
            sn[r] = s1[r]
            cn[r] = c1[r]

    t_end = t0 + n_steps * dt
    for r in range(nb):
        # a stick interval still open at the end is closed there
        if in_stick[r] != 0:
            s0 = max(stick_t0[r], t_steady)
            if t_end - s0 >= stick_min[r]:
                ms[r, L.T_STICK] += t_end - s0
                q = n_stk[r]
                if q < cap_stk:
                    stick[r, q, 0] = s0
                    stick[r, q, 1] = t_end
                n_stk[r] = q + 1
        for j in range(nx):
            x[r, j] = X[r, j]
        for q in range(L.MET_SIZE):
            met[r, q] = ms[r, q]
        met[r, L.W_FORCE] = w_force[r]
        met[r, L.D_VISC] = d_visc[r]
        met[r, L.D_FRICTION] = d_fric[r]
        met[r, L.W_NONRECIP] = w_nr[r]
        met[r, L.N_IMP_REC] = n_imp[r]
        met[r, L.N_STICK_REC] = n_stk[r]
        met[r, L.N_STROBE] = n_stb[r]
        met[r, L.STEPS_DONE] += n_steps


# One compiled specialisation per mode count (the mode loops unroll), as _rk4's.
@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def _rk4_batch_n1(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    _rk4_batch(1, P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def _rk4_batch_n2(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    _rk4_batch(2, P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def _rk4_batch_n3(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    _rk4_batch(3, P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met)


@njit(cache=True, error_model="numpy", fastmath={"contract"}, nogil=True)
def _rk4_batch_any(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    _rk4_batch(int(P[0, L.N_MODES]), P, x, t0, dt, n_steps, steady_start, imp, stick, strobe,
               met)


_BY_MODES = {1: _rk4_batch_n1, 2: _rk4_batch_n2, 3: _rk4_batch_n3}


def run_rk4_batch(P, x, t0, dt, n_steps, steady_start, imp, stick, strobe, met):
    """Advance the batch's states ``x`` by ``n_steps`` RK4 steps (see :func:`_rk4_batch`).

    Every row of ``P`` must have the same mode count and case and harmonic
    forcing; at most ``BMAX`` rows.
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
    _BY_MODES.get(n, _rk4_batch_any)(P, x, float(t0), float(dt), int(n_steps),
                                     int(steady_start), imp, stick, strobe, met)
