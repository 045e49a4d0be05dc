"""The exact event-driven integrator (docs/model.md, sections 2 and 5).

Between events the motion is linear with a constant friction force and the
harmonic input F0 sin(Omega t), so it has a closed form.  The ball case has
three regimes, each a linear system X' = A_r X + B_r f(t) + c_r F_b of the
bar coordinates X = [u, u'] (the ball is treated separately):

- FREE (the ball slides or flies): the modes decouple, A is block diagonal,
  F_b = -F_c sgn(y') is constant on the segment, and the ball's absolute
  motion is a parabola, u_d'' = F_b / m;
- STICK (off the walls, y' = 0): the ball is carried by the bar through
  friction, the bar sees (M + s m psi_d psi_d^T) u'' + C u' + K u = psi_L f
  with s = p[REACTION] (the reaction as printed, s = -1, applies to the
  friction force that carries the ball);
- CONTACT (on a wall, y' = 0): the same with s = +1 (a wall force is always
  reciprocal).

The solid bar (one FREE regime without ball), the locked ball (one coupled
regime) and the TMD bar (one regime of the 2n + 2 coordinates
[u, u', x_a, x_a']) have no events.  For each regime the per-run setup
(:func:`prepare`, NumPy, once per run) diagonalises A_r = V diag(lambda) V^-1
and solves for the particular solutions: X_p(t) = Im(Z e^{i Omega t}) + F_b D.
On a segment that starts at t_s the state is

    X(t_s + tau) = X_p(t_s + tau) + Re(V (q0 * exp(lambda tau))),
    q0 = V^-1 (X(t_s) - X_p(t_s)),

evaluated directly (complex exponentials) wherever an answer is needed, and
by the recurrence q <- q exp(lambda h) on the event-search grid.

Events (located by a safeguarded regula falsi, Illinois variant, to a
bracket of 4 ulp of t):

- FREE: y = +-delta/2 (impact, or capture on the wall when the impact is
  slower than p[V_IMPACT], the threshold of docs/model.md, section 2: a Zeno
  sequence ends in CONTACT after finitely many impacts); y' = 0 when
  F_c > 0 (a friction switch: the ball sticks if the force needed to carry
  it, |F_req| = |psi_d . a_0| / (1/m + s sum psi_d^2 / M), is at most F_s,
  else it slides back);
- STICK: |F_req| = F_s (slip starts, in the direction opposite to F_req);
- CONTACT: the wall force needed changes sign, wall * F_req = F_s (released
  into FREE, sliding inward).

Event search grid: h = (shortest period among the forcing and every
regime's eigenvalues) / ``GRID_PER_PERIOD``.  A sign change of an event
function between grid points brackets the event.  Grazing (a double
crossing inside one grid step) is guarded three ways: with friction the
ball's relative motion is monotone up to the y' = 0 switch, so walls are
sought on [a, switch] when the switch falls in the step; without friction
a sign change of y' inside a step near a wall is located and the extremum
of y checked, which splits the step into two monotone pieces; and when the
cubic Hermite interpolant of y (from y, y' at the step ends), widened by
twice its error bound h^4 max|y^(4)| / 384 (max|y^(4)| bounded per segment
from the closed form), comes within reach of a wall, the step is searched
again on NSUB sub-steps.  A segment never starts past a wall (y(0) is
clamped for the search).  Not guarded: an excursion of F_req across F_s and
back inside one grid step.  A free ball with more than one mode steps 2 h,
4 h, ... where Taylor bounds (|y'''|, |W'''| bounded per segment) prove that
the step holds no event and no new extremum (docs/exact.md, "Longer steps").

Metrics: the same vector as the RK4 kernel, but the steady sums are exact
integrals over the steady window [t_steady, t_end]: SUM_W2 = int W^2 dt,
SUM_W = int W dt, SUM_F = int f dt and N_STEADY = the window length (s), so
that SUM_W2 / N_STEADY is the mean square in both kernels.  The energy flows
are exact too: the work of the force, int f psi_L . u' dt, and the viscous
loss, int sum C_i u_i'^2 dt (+ the absorber's dashpot), are integrals of
products of exponentials, done in closed form per segment; friction
dissipation is -F_b (y(t_e) - y(t_s)) per sliding segment; the
non-reciprocal work (1 - s) int F_b psi_d . u' dt is closed form too.  The
balance then closes to round-off.  The ball's int y^2 (SUM_AUX2) is closed
form too under harmonic forcing (a parabola minus exponentials: phi_j
functions); an absorber's stroke (TMD) and a ball in a regenerative cut use the
endpoint-corrected trapezoid rule on the grid.  Maxima of
|W| are located exactly (W' = 0 roots on the grid); maxima of |aux| are
taken on the grid and at events.

Regenerative cutting (docs/model.md, section 4; docs/exact.md "Regenerative cuts"):
in the cut f = Kr b (S(t) - W), and -Kr b W joins the matrix (a second set of
regimes, ``prepare``); the surface S = min_k [k h_m + W(t - k tau)] is one cubic
per segment, the cubic Hermite of W, W' between stored knots (at the nodes
t0 + j H, H = tau / ceil(tau / dt), and at every event), and the input
bq Kr b S is propagated exactly with phi-functions (:func:`_eval`), so the
error is the interpolation's, O(H^4).  Segments end at every node, delayed
knot and change of the minimising revolution.  The tool leaving and
re-entering the cut (h = 0) are events (EV_CUT, with the extremum of h,
EV_HEXT, against grazes); the first exit is the chatter verdict.  The flows
of a cut are integrated by 4-point Gauss-Legendre per step (O(H^9) per step);
a whole step from node to node uses tabulated exponentials and phi's.
"""

import cmath
import math

import numpy as np
from numba import carray, njit

from boringbar.kernels import layout as L
from boringbar.kernels.stack import stack_ptr
from boringbar.kernels.views import borrow, with_len

#: event-search grid points per shortest period: about 16, but not a whole number, so that
#: events half a forcing period apart (the symmetric two-impact orbit, started at an impact)
#: do not fall on grid points, where the graze guard would search the step again for nothing
GRID_PER_PERIOD = 16.382
#: step lengths of the grid of a free ball: h, 2 h, 4 h, 8 h; a step longer than h is taken
#: only where Taylor bounds prove that no event and no new extremum can fall in it
GRID_LEVELS = 4
#: most events in one run before it stops with EXACT_STATUS = 1
MAX_EVENTS = 50_000_000
#: consecutive zero-length events (shorter than 1e-14 (|t| + h)) before a run stops with
#: EXACT_STATUS = 2
MAX_ZERO_LENGTH = 64

#: lengths of the stack scratch (numba needs them as literal globals)
_NZ_MAX = 2 * L.NMAX + 2
_NB_MAX = _NZ_MAX + 3
_NB_MAX2 = _NB_MAX * _NB_MAX
_NZB_MAX = _NZ_MAX * _NB_MAX
_NB_MAX_2 = 2 * _NB_MAX
_NMAX6 = 6 * L.NMAX
_DDC = 4 * (L.NMAX + 2)

FREE, STICK, CONTACT = 0, 1, 2
_RECIP = (0.0,) + tuple(1.0 / k for k in range(1, 24))  # 1 / k
_RFACT = tuple(1.0 / math.factorial(k) for k in range(20))  # 1 / k!
# event kinds; an event happens where g goes from <= 0 to > 0
EV_PLUS, EV_MINUS, EV_VSTOP, EV_YEXT, EV_REL_NEG, EV_REL_POS, EV_WALL_REL, EV_WEXT = range(8)
# regenerative cut: the tool leaves (in the cut) or re-enters (out of it) where the chip
# thickness h = S - W crosses zero; EV_HEXT = h' guards a graze of h = 0 inside a step
EV_CUT, EV_HEXT = 8, 9
N_EV = 10
# the segment's description ``seg``: see :func:`_g`
SEG_SIZE = 18
SEG_KRB = 11  # Kr b in the cut, 0 out of it (and for harmonic forcing)
SEG_S = 12  # S(tau) = seg[12] + seg[13] tau + seg[14] tau^2 + seg[15] tau^3, the surface
SEG_CDIR = 16  # +1 in the cut, -1 out of it, 0 harmonic forcing
SEG_ACC = 17  # fb / m, the ball's acceleration (one division per segment)


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
def _basis(lam, r, om, nz, mu):
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
        _basis(lam, r, om, nz, mu)
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


# --- the kernel ----------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _nq(nz, ks):
    """How many eigen-coordinates are evaluated: nz, or nz / 2 when ks = 2 (conjugate
    pairs, the first of each).  A loop over range(0, nz, ks) would cost an integer
    division per loop (its trip count), several per grid step."""
    return nz if ks == 1 else nz >> 1


@njit(cache=True, inline="always")
def _phis(x):
    """(e^x, phi_1(x), .., phi_4(x)), phi_k(x) = sum_m x^m / (m + k)!: the Taylor series of
    phi_4 then phi_k = 1/k! + x phi_{k+1} for |x| < 1 (no cancellation), the recurrence
    phi_{k+1} = (phi_k - 1/k!) / x from e^x otherwise (each step divides the error by
    |x| >= 1)."""
    if x.real * x.real + x.imag * x.imag < 1.0:
        p4 = 0.0 + 0.0j
        for m in range(14, -1, -1):
            p4 = p4 * x + _RFACT[m + 4]
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
def _surface(seg, tau):
    """S(tau) and S'(tau): the cut surface's cubic on the segment (docs/model.md, section 4)."""
    s1 = seg[SEG_S + 1]
    s2 = seg[SEG_S + 2]
    s3 = seg[SEG_S + 3]
    return (seg[SEG_S] + tau * (s1 + tau * (s2 + tau * s3)),
            s1 + tau * (2.0 * s2 + 3.0 * tau * s3))


@njit(cache=True, inline="always")
def _eval(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X):
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
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            ex, p1, p2, p3, p4 = _phis(lam[r, k] * tau)
            q[k] = q0[k] * ex + krb * bq[r, k] * (c0 * p1 + c1 * p2 + c2 * p3 + c3 * p4)
    else:
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            q[k] = q0[k] * cmath.exp(lam[r, k] * tau)
    for j in range(nz):
        s = (Z[r, j] * ph).imag + fb * D[r, j]
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            s += (V[r, j, k] * q[k]).real
        X[j] = s
    return ph


@njit(cache=True, inline="always")
def _from_q(r, q, ph, fb, Z, D, V, ks, X):
    """X from the eigen-coordinates q and the forcing phasor ph = e^{i Omega t}."""
    nz = X.shape[0]
    for j in range(nz):
        s = (Z[r, j] * ph).imag + fb * D[r, j]
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            s += (V[r, j, k] * q[k]).real
        X[j] = s


@njit(cache=True, inline="always")
def _force(seg, tau, X, n, mk, f0, om):
    """The force at the tip at ts + tau: F0 sin(Omega t), or Kr b (S(tau) - W) in a cut."""
    f = f0 * math.sin(om * (seg[0] + tau))
    if seg[SEG_KRB] != 0.0:
        w = 0.0
        for i in range(n):
            w += mk[3, i] * X[i]
        f += seg[SEG_KRB] * (_surface(seg, tau)[0] - w)
    return f


@njit(cache=True, inline="always")
def _freq(X, f, n, mk, kappa):
    """The force that carries the ball with the bar, psi_d . a_0 / kappa (N), under the
    tip force f."""
    s = 0.0
    for i in range(n):
        s += mk[4, i] * (mk[3, i] * f - mk[1, i] * X[i] - mk[2, i] * X[n + i]) / mk[0, i]
    return s / kappa


@njit(cache=True, inline="always")
def _g(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, q, X, n, mk, f0, om):
    """Event function ``kind`` at tau on the segment described by ``seg``.

    seg = [ts, fb, ud0, vd0, y0, sdir, wall, kappa, fs, half, m, krb, S_0..S_3, cdir, fb / m]
    (SEG_* name the cut's slots and SEG_ACC the last).
    """
    _eval(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X)
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
        sv, sd = _surface(seg, tau)
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
    F = _freq(X, _force(seg, tau, X, n, mk, f0, om), n, mk, seg[7])
    if kind == EV_REL_NEG:
        return F - seg[8]
    if kind == EV_REL_POS:
        return -F - seg[8]
    return seg[6] * F - seg[8]


@njit(cache=True, inline="always")
def _eval2(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X, Xd):
    """X and X' at ts + tau on the segment (see :func:`_eval`); in a cut
    q' = lambda q + bq Kr b S(tau)."""
    nz = X.shape[0]
    ph = _eval(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X)
    sin_ = seg[SEG_KRB] * _surface(seg, tau)[0]
    for j in range(nz):
        sd = om * (Z[r, j] * ph).real
        for kq in range(_nq(nz, ks)):
            k = kq * ks
            sd += (V[r, j, k] * (q[k] * lam[r, k] + sin_ * bq[r, k])).real
        Xd[j] = sd


@njit(cache=True, inline="always")
def _gd(kind, tau, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om):
    """Event function ``kind`` (see :func:`_g`), its time derivative and its second
    derivative at tau: the second only where it comes free (the walls and the cut's h),
    NaN elsewhere."""
    ts = seg[0]
    _eval2(r, q0, seg, tau, om, lam, V, ks, Z, D, bq, q, X, Xd)
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
        sv, sd = _surface(seg, tau)
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
        sv, sd = _surface(seg, tau)
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
def _hermite(a, b, p0, p1, d0, d1, order):
    """Where the cubic Hermite interpolant of values p0, p1 and slopes d0, d1 on [a, b]
    (order 0), or its derivative (order 1), changes sign: a starting point for
    :func:`_root`, found by a few safeguarded Newton steps on the cubic (no
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
def _hermite5(a, b, p0, p1, d0, d1, e0, e1, order):
    """Where the quintic Hermite interpolant of values p0, p1, slopes d0, d1 and second
    derivatives e0, e1 on [a, b] (order 0), or its derivative (order 1, given d0 d1 < 0),
    changes sign: the cubic's (:func:`_hermite`) refined by safeguarded Newton on the
    quintic.  Its error is O(h^6) (order 0) or O(h^5) (order 1) instead of O(h^4) or
    O(h^3): the root search then usually accepts its first evaluation."""
    x0 = _hermite(a, b, p0, p1, d0, d1, order)
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
def _sizes(ks, n, nz):
    """Which compilation with constant sizes fits a regime: 1 (one mode, nz = 2) or 2 (two
    modes, nz = 4), each in conjugate pairs (ks = 2): the ball and the solid bar; 0 for any
    other (a TMD, an overdamped mode, three or more modes), which takes the generic code."""
    if ks == 2 and nz == 2 * n and n <= 2:
        return n
    return 0


@njit(cache=True, inline="always")
def _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om,
               c0, nz):
    """The root of event function ``kind`` in [a, b], where it changes sign (or ga = 0):
    Newton with the exact derivative, kept inside the shrinking bracket (a bisection
    whenever Newton leaves it or fails to halve it), to a bracket of 4 ulp of t or a
    Newton step below that, or a step whose own error, |g''| s^2 / (2 |g'|) to leading
    order, is below a quarter of that (where g'' comes free: usually one evaluation
    fewer).  Returns the end on gb's side (the event has happened).  X and Xd are seen
    with length ``nz``, constant in the specialisations (:func:`_root_any`)."""
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
def _root(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om, c0):
    """:func:`_root_body` for any bar."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk,
                      f0, om, c0, X.shape[0])


@njit(cache=True)
def _root_1(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0):
    """:func:`_root_body` for one mode and its conjugate pair (n = 1, nz = 2, ks = 2)."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 1, mk, f0,
                      om, c0, 2)


@njit(cache=True)
def _root_2(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0):
    """:func:`_root_body` for two modes in conjugate pairs (n = 2, nz = 4, ks = 2)."""
    return _root_body(kind, a, ga, b, gb, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 2, mk, f0,
                      om, c0, 4)


@njit(cache=True, inline="always")
def _root_any(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om, c0):
    """:func:`_root`, or its compilation with the sizes constant where they fit (the
    ball or solid bar with one or two modes): the same operations, unrolled."""
    # a run-time kind: numba types the constants EV_* as literals and would compile each
    # function once per event kind passed as a constant (five times, 2 minutes cold)
    kind = kind + 0
    sz = _sizes(ks, n, X.shape[0])
    if sz == 1:
        return _root_1(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0)
    if sz == 2:
        return _root_2(kind, a, ga, b, gb, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, f0, om, c0)
    return _root(kind, a, ga, b, gb, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, f0, om, c0)


@njit(cache=True, inline="always")
def _phi1s(z, T, z2):
    """int_0^T exp(z tau / T) dtau = T (e^z - 1) / z by its series, for |z|^2 = z2 < 1/64
    (where the closed form cancels), with as many terms as |z| needs: the first term left
    out, |z|^(K+1) / (K+2)!, is below 3.1e-18."""
    top = 11 if z2 > 9e-4 else (8 if z2 > 2.5e-5 else 6)
    s = 0.0 + 0.0j
    for k in range(top, 1, -1):
        s = (s * z + 1.0) * _RECIP[k]
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
        f0 += term * _RECIP[mm + 1]
        f1 += term * _RECIP[mm + 2]
        f2 += term * _RECIP[mm + 3]
        term = term * z * _RECIP[mm + 1]
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
    _basis(lam, r, om, nz, mu)
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
def _integrals(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, n, mk, lvis, cvis, stick_k, sr,
               me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj):
    """:func:`_integrals_body` for any bar, regime and basis (nz = lam.shape[1])."""
    _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, n, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, ks, seg, phj, lam.shape[1])


@njit(cache=True)
def _integrals_1(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, mk, lvis, cvis, stick_k, sr,
                 me, G, Cx, cf, ca, cb, out, isum, level, seg, phj):
    """:func:`_integrals_body` for one mode and its conjugate pair (n = 1, nz = 2, ks = 2)."""
    _integrals_body(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, 1, mk, lvis, cvis, stick_k, sr,
                    me, G, Cx, cf, ca, cb, out, isum, level, 2, seg, phj, 2)


@njit(cache=True)
def _integrals_2(r, q0, ph, T, fb, om, f0, lam, VF, Z, D, mk, lvis, cvis, stick_k, sr,
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
        _eval2(r, q0, seg, c, om, lam, V, ks, Z, D, bq, q, X, Xd)
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
def _w_extremum(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om):
    """:func:`_w_extremum_body` for any bar."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n,
                            mk, om, X.shape[0])


@njit(cache=True)
def _w_extremum_1(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om):
    """:func:`_w_extremum_body` for n = 1, nz = 2, ks = 2."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 1,
                            mk, om, 2)


@njit(cache=True)
def _w_extremum_2(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om):
    """:func:`_w_extremum_body` for n = 2, nz = 4, ks = 2."""
    return _w_extremum_body(a, ga, b, gb, c0, h, seg, r, q0, lam, V, 2, Z, D, bq, q, X, Xd, 2,
                            mk, om, 4)


@njit(cache=True, inline="always")
def _w_extremum_any(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om):
    """:func:`_w_extremum`, or a compilation with the sizes constant (see :func:`_root_any`)."""
    sz = _sizes(ks, n, X.shape[0])
    if sz == 1:
        return _w_extremum_1(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om)
    if sz == 2:
        return _w_extremum_2(a, ga, b, gb, c0, h, seg, r, q0, lam, V, Z, D, bq, q, X, Xd, mk, om)
    return _w_extremum(a, ga, b, gb, c0, h, seg, r, q0, lam, V, ks, Z, D, bq, q, X, Xd, n, mk, om)


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
def _quad_range(p, d, dd, s):
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
def _may_graze(a, b, ev_a, ev_b, half, b4):
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
def _w_may_exceed(h, wa, wb, wda, wdb, bw4, max_w, min_w, max_abs_w):
    """Whether W may go above max_w, below min_w or beyond max_abs_w in magnitude inside a
    step of length h: the cubic Hermite interpolant of W, W' at the ends, widened by twice
    its error bound bw4 h^4 / 384 (bw4 bounds |W^(4)| on the step)."""
    margin = bw4 * h ** 4 / 192.0
    lo, hi = _cubic_range(wa, wb, wda * h, wdb * h)
    hi += margin
    lo -= margin
    return hi >= max_w or lo <= min_w or max(hi, -lo) >= max_abs_w


@njit(cache=True)
def _wall_step(a, b, ev_a, ev_b, watch_v, watch_ext, half, seg, r, q0, lam, V, ks, Z, D, bq, qs,
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
        te = _root_any(EV_YEXT, a, ev_a[EV_YEXT], b, ev_b[EV_YEXT], seg, r, q0, lam,
                       V, ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om,
                       _hermite(a, b, ev_a[EV_PLUS], ev_b[EV_PLUS], ev_a[EV_YEXT],
                                ev_b[EV_YEXT], 1))
        gp = _g(EV_PLUS, te, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk, f0, om)
        gm = -2.0 * half - gp
        for kk in (EV_PLUS, EV_MINUS):
            ge = gp if kk == EV_PLUS else gm
            if ev_a[kk] <= 0.0 < ge:
                sg = 1.0 if kk == EV_PLUS else -1.0
                tr = _root_any(kk, a, ev_a[kk], te, ge, seg, r, q0, lam, V, ks, Z, D, bq,
                               qs, dX, Xd, n, mk, f0, om,
                               _hermite(a, te, ev_a[kk], ge, sg * ev_a[EV_YEXT], 0.0,
                                        0))
                if kind < 0 or tr < best:
                    best = tr
                    kind = kk
        if kind < 0:
            for kk in (EV_PLUS, EV_MINUS):
                ge = gp if kk == EV_PLUS else gm
                if ge <= 0.0 < ev_b[kk]:
                    sg = 1.0 if kk == EV_PLUS else -1.0
                    tr = _root_any(kk, te, ge, b, ev_b[kk], seg, r, q0, lam, V, ks,
                                   Z, D, bq, qs, dX, Xd, n, mk, f0, om,
                                   _hermite(te, b, ge, ev_b[kk], 0.0,
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
            best = _root_any(EV_VSTOP, a, ev_a[EV_VSTOP], b, ev_b[EV_VSTOP], seg, r,
                             q0, lam, V, ks, Z, D, bq, qs, dX, Xd, n, mk, f0, om, -1.0)
            kind = EV_VSTOP
            bend = best
            gpe = _g(EV_PLUS, bend, seg, r, q0, lam, V, ks, Z, D, bq, qs, dX, n, mk,
                     f0, om)
            gme = -2.0 * half - gpe
            yde = 0.0
        for kk in (EV_PLUS, EV_MINUS):
            ge = gpe if kk == EV_PLUS else gme
            if ev_a[kk] <= 0.0 < ge:
                sg = 1.0 if kk == EV_PLUS else -1.0
                if bend == b and ydd_a == ydd_a and ydd_b == ydd_b:  # y'' known at both ends
                    c0 = _hermite5(a, b, ev_a[kk], ge, sg * ev_a[EV_YEXT], sg * yde,
                                   sg * ydd_a, sg * ydd_b, 0)
                else:
                    c0 = _hermite(a, bend, ev_a[kk], ge, sg * ev_a[EV_YEXT], sg * yde,
                                  0)
                tr = _root_any(kk, a, ev_a[kk], bend, ge, seg, r, q0, lam, V, ks, Z,
                               D, bq, qs, dX, Xd, n, mk, f0, om, c0)
                if kind < 0 or tr <= best:
                    best = tr
                    kind = kk
    return kind, best


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
    taus = [x * H for x in _GL_X] + [H]
    tabE = np.zeros((R, 5, nz), complex)
    tabP = np.zeros((R, 5, 4, nz), complex)
    krb = p[L.KR_B]
    for r in range(R):
        for i, tau in enumerate(taus):
            for k in range(nz):
                ex, *ph = _phis(complex(lam[r, k] * tau))
                tabE[r, i, k] = ex
                if r >= prep["nreg"]:
                    for j in range(4):
                        tabP[r, i, j, k] = (krb * prep["bq"][r, k] * math.factorial(j)
                                            * tau ** (j + 1) * ph[j])
    return tabE, tabP


@njit(cache=True, inline="always")
def _hermite_at(t0, p0, d0, t1, p1, d1, x0, cubic):
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
_GL_X = (0.5 - 0.4305681557970263, 0.5 - 0.16999052179242816, 0.5 + 0.16999052179242816,
         0.5 + 0.4305681557970263)
_GL_W = (0.17392742256872692, 0.3260725774312731, 0.3260725774312731, 0.17392742256872692)


@njit(cache=True, inline="always")
def _quad_cut(a, b, seg, r, q0, lam, V, ks, Z, D, bq, q, X, n, mk, lvis, cvis, stick, kappa,
              sr, acc, steady):
    """Adds the flows over [a, b] of a cut segment to ``acc`` (the slots of
    :func:`_integrals`' ``out``) by 4-point Gauss-Legendre: error O((b - a)^9) per step,
    far below the scheme's O(H^4).  Returns the largest force at the nodes.  (A whole
    step, from the tables, is written out in :func:`_exact`.)"""
    fmax = 0.0
    hh = b - a
    for g in range(4):
        tau = a + _GL_X[g] * hh
        wg = _GL_W[g] * hh
        _eval(r, q0, seg, tau, 0.0, lam, V, ks, Z, D, bq, q, X)
        f = _force(seg, tau, X, n, mk, 0.0, 0.0)
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
            acc[5] += wg * (1.0 - sr) * _freq(X, f, n, mk, kappa) * pdv
    return fmax


@njit(cache=True)
def _knot(kn, nk, ip, t, Xm, Xp, n, mk, ttol, node):
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
def _surface_piece(t, t_end, ttol, kn, nk, ip, sc, nrev, nr_eff, feed, w_before, tau_d, seg,
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
            c0, c1, c2, c3 = _hermite_at(kn[i, 0], kn[i, 1], kn[i, 3], kn[i + 1, 0],
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
    for i in range(n):
        mk[0, i] = p[L.M_ + i]
        mk[1, i] = p[L.K_ + i]
        mk[2, i] = p[L.C_ + i]
        mk[3, i] = p[L.PSI_L + i]
        mk[4, i] = p[L.PSI_D + i]
        mk[5, i] = p[L.PSI_A + i]
    f0 = p[L.F0]
    om = p[L.OMEGA]
    m = p[L.BALL_MASS]
    half = p[L.HALF_GAP]
    e = p[L.RESTITUTION]
    fc = p[L.FRICTION]
    fs = max(p[L.STATIC_FRICTION], fc)
    sr = p[L.REACTION]
    meff = p[L.M_EFF]
    vimp = p[L.V_IMPACT]
    stick_min = p[L.STICK_MIN]
    tstrobe = p[L.STROBE_PERIOD]
    spd = 0.0
    for i in range(n):
        spd += mk[4, i] * mk[4, i] / mk[0, i]
    kappa_stick = (1.0 / m + sr * spd) if m > 0.0 else 1.0
    # psi . u'' of a free ball's bar from its state, force f and F_b: rows 0 (psi_d) and 1
    # (psi_L) hold the coefficients of u_i, then of f and F_b; rows 2 and 3 those of u_i'
    ddc = _zeros2(stack_ptr(_DDC, np.float64), 4, n + 2)
    for i in range(n):
        for row in range(2):
            pr = mk[4 - row, i] / mk[0, i]  # psi_d,i / M_i, then psi_L,i / M_i
            ddc[row, i] = -pr * mk[1, i]
            ddc[row + 2, i] = -pr * mk[2, i]
            ddc[row, n] += pr * mk[3, i]
            ddc[row, n + 1] -= pr * sr * mk[4, i]
    kappa_wall = (1.0 / m + spd) if m > 0.0 else 1.0

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
    # --- regenerative cut (docs/model.md, section 4): the history of W as knots -----------------
    # Knots (t, W, W'-, W'+) at the nodes t0 + j H, H = tau / m <= dt_out (so the delayed
    # nodes fall on nodes), and at every event (W' jumps at impacts, W'' at friction
    # switches).  The surface min_k [k h_m + W(t - k tau)] is the cubic Hermite of W, W'
    # between the two knots around t - k tau; a segment ends where any delayed knot falls,
    # so the input is one cubic on it.  ip[k]: the knot at or before t - k tau (-1: before
    # the cut, where W = HIST_W0).
    krb = p[L.KR_B]
    feed = p[L.FEED]
    tau_d = p[L.TAU]
    nrev = int(p[L.N_REV]) if regen else 0
    stop_at_zero = p[L.STOP_AT_ZERO] > 0.0
    w_before = p[L.HIST_W0]
    cubic = p[L.INTERP] > 0.0
    m_rev = int(round(tau_d / hist_step)) if regen else 1
    hh_ = hist_step  # H
    ttol = max(1e-9 * hh_, 4.0 * 2.2e-16 * (abs(t0) + abs(t_end)))
    cap_kn = nrev * m_rev + 64 if regen else 1
    kn = np.zeros((cap_kn, 5))
    nk = 0
    ip = np.full(nrev + 1, -1, np.int64)
    sc = np.zeros((nrev + 1, 4))
    qsum = _zeros(stack_ptr(6, np.float64), 6)
    first_zero = met[L.FIRST_ZERO_T]
    max_force = met[L.MAX_FORCE]
    n_zero_steps = met[L.N_ZERO_STEPS]
    last_zero_step = -1
    j_node = 0  # the last node reached
    incut = False
    if regen:
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
        nk = 1
        incut = feed + w_before - w_ > 0.0
        if not incut and first_zero < 0.0:
            first_zero = t0
        max_force = max(max_force, krb * max(0.0, feed + w_before - w_))
    f_t0 = f0 * math.sin(om * t0)
    if incut:
        f_t0 += krb * (feed + w_before - kn[0, 1])
    y = x[2 * n] if ball or case == L.LOCKED else 0.0
    yd = x[2 * n + 1] if ball else 0.0

    sum_w2 = met[L.SUM_W2]
    sum_w = met[L.SUM_W]
    n_steady = met[L.N_STEADY]
    max_abs_w = met[L.MAX_ABS_W]
    max_w = met[L.STEADY_MAX_W]
    min_w = met[L.STEADY_MIN_W]
    max_aux = met[L.MAX_ABS_AUX]
    max_aux_all = met[L.MAX_ABS_AUX_ALL]
    sum_aux2 = met[L.SUM_AUX2]
    sum_f = met[L.SUM_F]
    n_plus = met[L.N_IMP_PLUS]
    n_minus = met[L.N_IMP_MINUS]
    n_all = met[L.N_IMP_ALL]
    n_micro = met[L.N_MICRO]
    t_contact = met[L.T_CONTACT]
    t_stick = met[L.T_STICK]
    w_force = met[L.W_FORCE]
    d_visc = met[L.D_VISC]
    d_imp = met[L.D_IMPACT]
    d_fric = met[L.D_FRICTION]
    w_nr = met[L.W_NONRECIP]
    n_imp = int(met[L.N_IMP_REC])
    n_stk = int(met[L.N_STICK_REC])
    n_rec = int(met[L.N_REC])
    n_stb = int(met[L.N_STROBE])
    n_ev = int(met[L.N_EVENTS])
    status = 0
    cap_imp = imp.shape[0]
    cap_stk = stick.shape[0]
    cap_rec = rec.shape[0]
    cap_stb = strobe.shape[0]

    # next output sample times
    k_rec = 1
    t_next_strobe = 0.0
    if tstrobe > 0.0:
        t_next_strobe = p[L.STROBE_T0]
        if t_next_strobe <= t0:
            t_next_strobe += (math.floor((t0 - t_next_strobe) / tstrobe) + 1) * tstrobe

    # --- the initial regime ---------------------------------------------------------------
    mode = FREE
    sdir = 0.0
    wall = 0.0
    if ball:
        if yd != 0.0:
            sdir = 1.0 if yd > 0.0 else -1.0
        elif abs(y) >= half:
            wall = 1.0 if y > 0.0 else -1.0
            y = wall * half
            F = _freq(X, f_t0, n, mk, kappa_wall)
            if wall * F <= fs:
                mode = CONTACT
            elif fc > 0.0:
                sdir = -wall
        elif fc > 0.0:
            F = _freq(X, f_t0, n, mk, kappa_stick)
            if abs(F) <= fs:
                mode = STICK
            else:
                sdir = -1.0 if F > 0.0 else 1.0
    in_stick = mode == STICK
    stick_t0 = t0
    n_zero = 0

    # the grid's step lengths (h, 2 h, 4 h, ...) and their phase steps
    hl = _zeros(stack_ptr(GRID_LEVELS, np.float64), GRID_LEVELS)
    rotl = _zeros(stack_ptr(GRID_LEVELS, np.complex128), GRID_LEVELS)
    for lv in range(GRID_LEVELS):
        hl[lv] = h * 2.0 ** lv
        rotl[lv] = cmath.exp(1j * om * hl[lv]) if om != 0.0 else 1.0 + 0.0j
    ph_next = 1.0 + 0.0j
    ph_next_ok = False
    t = t0
    while t < t_end:
        if n_ev >= MAX_EVENTS:
            status = 1
            break
        t_stop = min(t_steady, t_end) if t < t_steady else t_end
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
        ks = kstep[r]
        sz = _sizes(ks, n, nz)  # 1, 2: the helpers compiled with constant sizes; 0: generic
        # eigen-coordinates of the homogeneous part at t
        if ph_next_ok:
            ph = ph_next  # exp(i Omega t), from the event's evaluation (the same expression)
        else:
            ph = cmath.exp(1j * om * t) if om != 0.0 else 1.0 + 0.0j
        ph_next_ok = False
        for j in range(nz):
            dX[j] = X[j] - ((Z[r, j] * ph).imag + fb * D[r, j])
        for k in range(nz):
            s = 0.0 + 0.0j
            for j in range(nz):
                s += Vi[r, k, j] * dX[j]
            q0[k] = s
        at_node = False
        whole = False
        sticking = mode == STICK
        krb_seg = 0.0
        s_0 = 0.0
        s_1 = 0.0
        s_2 = 0.0
        s_3 = 0.0
        if regen:
            # this segment ends at the next node, delayed knot or change of the minimising
            # revolution: the surface is one cubic on it
            while t0 + (j_node + 1) * hh_ <= t + ttol:
                j_node += 1
            t_seg_end = min(t0 + (j_node + 1) * hh_, t_stop)
            at_node = t_seg_end < t_stop
            from_node = abs(t - (t0 + j_node * hh_)) <= ttol
            if first_zero < 0.0:
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
            seg[SEG_KRB] = krb if incut else 0.0
            seg[SEG_CDIR] = 1.0 if incut else -1.0
            # a whole step H from node to node, inside one grid step: tabulated values
            whole = at_node and from_node and hh_ <= h
            krb_seg = seg[SEG_KRB]
            s_0 = seg[SEG_S]
            s_1 = seg[SEG_S + 1]
            s_2 = seg[SEG_S + 2]
            s_3 = seg[SEG_S + 3]
        pdu = 0.0
        pdv = 0.0
        for i in range(n):
            pdu += mk[4, i] * X[i]
            pdv += mk[4, i] * X[n + i]
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
        if steady and not regen:
            bw4 = bnd[r, 1, nz]
            for k in range(nz):
                bw4 += bnd[r, 1, k] * abs(q0[k])
        # a free ball under harmonic forcing: y'' and W'' at its grid points (the walls'
        # and extrema's quintic starts); with more than one mode it steps longer than h
        # where it can, from bounds on |y'''| = |psi_d . u'''| and |W'''| over the segment
        ydd_on = ball and mode == FREE and not regen
        adapt = ydd_on and levmax[r] > 0
        b3y = 0.0
        b3w = 0.0
        if adapt:
            b3y = bnd[r, 2, nz]
            b3w = bnd[r, 3, nz]
            for k in range(nz):
                aq = abs(q0[k])
                b3y += bnd[r, 2, k] * aq
                b3w += bnd[r, 3, k] * aq
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
                ya = ev_a[EV_PLUS] + half
                yda = ev_a[EV_YEXT]
                wmar = 1e-9 * max_abs_w
                for lv in range(1, levmax[r] + 1):
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
            b = a + hl[lev]
            full = True
            if b >= tlen:
                b = tlen
                full = False
            istep += 1
            usual = full and istep % 64 != 0 and not regen
            if usual:
                # the usual grid point, inlined with the sizes constant for one and two modes
                rot = rotl[lev]
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
            elif whole and not full:
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
            # --- events in [a, b]
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
                # Gauss-Legendre (4 points, exact to degree 7) for the flows of the step:
                # the input is a cubic, no longer a sum of exponentials
                if whole and kind < 0 and not (sticking and sr != 1.0):
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
                                                         mode == STICK, kappa_stick, sr, qsum,
                                                         steady))
                max_force = max(max_force, krb_seg * (s_0 + b * (s_1 + b * (s_2 + b * s_3)) - wb))
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
                    sum_aux2 += (0.5 * hh * (auxa * auxa + auxb * auxb)
                                 + hh * hh / 6.0 * (auxa * auxda - auxb * auxdb))
            # history and strobe samples in (t + a, t + b]
            while rec_dt > 0.0 and n_rec < cap_rec and t0 + k_rec * rec_dt <= t + b + 1e-9 * rec_dt:
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
            while tstrobe > 0.0 and t_next_strobe <= t + b and t_next_strobe <= t_end:
                if n_stb < cap_stb:
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

        # --- close the segment [t, t + T] ----------------------------------------------
        T = tau_ev
        if regen:
            for c in range(6):
                out[c] = qsum[c]
            if not incut:  # the steps of length dt_out touched with h = 0
                js = max(int(math.floor((t - t0) / dt_out)), last_zero_step + 1)
                je = int(math.ceil((t + T - t0) / dt_out)) - 1
                if je >= js:
                    n_zero_steps += je - js + 1
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
                sum_aux2 += out[6] if mode == FREE else seg[4] * seg[4] * T
        w_force += out[0]
        d_visc += out[1]
        w_nr += out[5]
        if steady:
            sum_w2 += out[2]
            sum_w += out[3]
            sum_f += out[4]
            n_steady += T
            if mode == CONTACT:
                t_contact += T
        if ball:
            pdu1 = 0.0
            pdv1 = 0.0
            for i in range(n):
                pdu1 += mk[4, i] * X[i]
                pdv1 += mk[4, i] * X[n + i]
            if mode == FREE:
                ynew = seg[2] + T * (seg[3] + 0.5 * acc * T) - pdu1
                yd = seg[3] + acc * T - pdv1
                d_fric -= fb * (ynew - y)
                w_nr += (1.0 - sr) * fb * (pdu1 - pdu)
                y = ynew
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
        was_stick = mode == STICK
        if ev_kind == EV_PLUS or ev_kind == EV_MINUS:
            w_ = 1.0 if ev_kind == EV_PLUS else -1.0
            y = w_ * half
            vb = yd
            if w_ * vb > 0.0:
                ee = e if abs(vb) > vimp else 0.0  # Zeno: captured on the wall
                g_ = (1.0 + ee) * meff * vb
                for i in range(n):
                    X[n + i] += g_ * mk[4, i] / mk[0, i]
                yd = -ee * vb
                d_imp += 0.5 * (1.0 - ee * ee) * meff * vb * vb
                if abs(vb) > vimp:
                    n_all += 1
                    if steady:
                        if w_ > 0:
                            n_plus += 1
                        else:
                            n_minus += 1
                        if n_imp < cap_imp:
                            imp[n_imp, 0] = t
                            imp[n_imp, 1] = w_
                            imp[n_imp, 2] = vb
                        n_imp += 1
                else:
                    n_micro += 1
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
                mode, sdir, wall = _at_wall(X, f_ev, w_, n, mk, kappa_wall, fs, fc)
        elif ev_kind == EV_VSTOP:
            yd = 0.0
            F = _freq(X, f_ev, n, mk, kappa_stick)
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
            incut = not incut
            if not incut and first_zero < 0.0:
                first_zero = t  # the chatter verdict (docs/model.md, section 4)
                if stop_at_zero:  # finish the step of length dt_out, as RK4 does
                    t_end = min(t_end, t0 + math.ceil((t - t0) / dt_out - 1e-9) * dt_out)
        if regen:
            kn, nk = _knot(kn, nk, ip, t, Xa, X, n, mk, ttol, -1.0)
        if mode == FREE and fc == 0.0 and yd == 0.0:
            sdir = 0.0
        # stick intervals
        if mode == STICK and not was_stick:
            stick_t0 = t
        elif was_stick and mode != STICK:
            s0 = max(stick_t0, t_steady)
            if t - s0 >= stick_min:
                t_stick += t - s0
                if n_stk < cap_stk:
                    stick[n_stk, 0] = s0
                    stick[n_stk, 1] = t
                n_stk += 1
        in_stick = mode == STICK

    if in_stick:
        s0 = max(stick_t0, t_steady)
        if t - s0 >= stick_min:
            t_stick += t - s0
            if n_stk < cap_stk:
                stick[n_stk, 0] = s0
                stick[n_stk, 1] = t
            n_stk += 1

    for j in range(nz):
        x[j] = X[j]
    if ball:
        x[2 * n] = y
        x[2 * n + 1] = yd
    met[L.SUM_W2] = sum_w2
    met[L.SUM_W] = sum_w
    met[L.N_STEADY] = n_steady
    met[L.MAX_ABS_W] = max_abs_w
    met[L.STEADY_MAX_W] = max_w
    met[L.STEADY_MIN_W] = min_w
    met[L.MAX_ABS_AUX] = max_aux
    met[L.MAX_ABS_AUX_ALL] = max_aux_all
    met[L.SUM_AUX2] = sum_aux2
    met[L.SUM_F] = sum_f
    met[L.N_IMP_PLUS] = n_plus
    met[L.N_IMP_MINUS] = n_minus
    met[L.N_IMP_ALL] = n_all
    met[L.N_MICRO] = n_micro
    met[L.T_CONTACT] = t_contact
    met[L.T_STICK] = t_stick
    met[L.W_FORCE] = w_force
    met[L.D_VISC] = d_visc
    met[L.D_IMPACT] = d_imp
    met[L.D_FRICTION] = d_fric
    met[L.W_NONRECIP] = w_nr
    met[L.N_IMP_REC] = n_imp
    met[L.N_STICK_REC] = n_stk
    met[L.N_REC] = n_rec
    met[L.N_STROBE] = n_stb
    met[L.N_EVENTS] = n_ev
    met[L.EXACT_STATUS] = status
    if regen:
        met[L.FIRST_ZERO_T] = first_zero
        met[L.MAX_FORCE] = max_force
        met[L.N_ZERO_STEPS] = n_zero_steps
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
