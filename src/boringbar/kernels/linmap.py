"""One RK4 step of the published scheme as an affine map, for steps without a switch.

Under harmonic forcing the equations between impacts are linear with a
constant friction force, except that F_b = -F_c sgn(y') is re-evaluated at
every stage.  When y' keeps one sign (not zero) at all four stages, F_b is
the same at every stage and the RK4 step is exactly (in exact arithmetic)
an affine function of

    z = [X (the state, 2n + 2 values), S, C, F_b],

with S = sin(Omega t), C = cos(Omega t) at the step's start (the forcing at
the stage times is F0 (alpha_s S + beta_s C)).  This module builds that map
once per run by pushing the basis vectors of z through the stage
recursion:

- ``Pd`` (nx, nz): the step's increment, X_new - X = Pd z (the same
  sum of weighted stage derivatives RK4 adds, so the state is updated by
  a small increment as in the stage loop);
- ``Yr`` (3, nz): the ball's y' at stages 2, 3 and 4 (stage 1 is X's own),
  to check that F_b did not switch inside the step;
- ``Vr`` (3, n + 1, nz): the velocities that viscous damping acts on at
  stages 2-4 (the modal velocities u_i', and the absorber's stroke rate for
  the TMD in row n), and ``Wv`` (4, n + 1) their weights b_s c_k, so that the
  viscous loss of the step is sum_s sum_k Wv[s, k] v_sk^2 (b_s the RK4
  weights times dt, c_k = C_i or c_a), as the stage loop integrates it;
- ``Fs``, ``Fc`` (nz): the force's work over the step,
  sum_s b_s f_s W'_s = S (Fs . z) + C (Fc . z).

The friction work and the non-reciprocal work need no table: sum_s b_s y'_s
is the step's increment of y, and sum_s b_s psi_d . u'_s that of psi_d . u.

The kernels (``kernels/rk4.py``, ``kernels/rk4_batch.py``) use the map for
every harmonic step where the ball's y' has one sign at all four stages
(and every step of the solid, TMD and locked bars, and of a frictionless
ball), and the stage loop otherwise: a friction switch inside the step,
y' = 0 at a stage, a regenerative cut.  The two give the same RK4 step to
round-off (tests/test_kernel.py compares the two, and both with the NumPy
reference stepper); the map's critical path is one short dot product per state
component instead of four dependent stage evaluations.
"""

import math

import numpy as np
from numba import carray, njit

from boringbar.kernels import layout as L
from boringbar.kernels.stack import stack_ptr

_NX_MAX = 2 * L.NMAX + 2
#: most entries of the tables (stack allocations in the kernels need literal sizes)
NZ_MAX = _NX_MAX + 3
PD_MAX = _NX_MAX * NZ_MAX
YR_MAX = 3 * NZ_MAX
VR_MAX = 3 * (L.NMAX + 1) * NZ_MAX
WV_MAX = 4 * (L.NMAX + 1)


@njit(cache=True, error_model="numpy")
def build_map(n, p, dt, Pd, Yr, Vr, Wv, Fs, Fc):
    """Fill the step tables (module docstring) for ``n`` modes, parameters ``p``, step ``dt``."""
    case = int(p[L.CASE])
    ball = case == L.BALL
    tmd = case == L.TMD
    has_aux = ball or tmd
    nx = 2 * n + 2
    nz = nx + 3
    iy = 2 * n
    iyd = 2 * n + 1
    f0 = p[L.F0]
    om = p[L.OMEGA]
    m = p[L.BALL_MASS]
    sr = p[L.REACTION]
    meff = p[L.M_EFF]
    ma = p[L.TMD_MASS]
    ka = p[L.TMD_K]
    ca = p[L.TMD_C]
    kappa = 1.0 / m if m > 0.0 else 0.0
    for i in range(n):
        kappa += p[L.PSI_D + i] * (sr * p[L.PSI_D + i] / p[L.M_ + i])
    # forcing at the stage times t + c_s dt: F0 (alpha_s S + beta_s C)
    ch = math.cos(om * 0.5 * dt)
    sh = math.sin(om * 0.5 * dt)
    c1 = math.cos(om * dt)
    s1 = math.sin(om * dt)
    alpha = (1.0, ch, ch, c1)
    beta = (0.0, sh, sh, s1)
    cst = (0.0, 0.5 * dt, 0.5 * dt, dt)
    wst = (dt / 6.0, dt / 3.0, dt / 3.0, dt / 6.0)
    for s in range(4):
        for i in range(n):
            Wv[s, i] = wst[s] * p[L.C_ + i]
        Wv[s, n] = wst[s] * ca if tmd else 0.0

    X = carray(stack_ptr(_NX_MAX, np.float64), nx)
    Xs = carray(stack_ptr(_NX_MAX, np.float64), nx)
    Kd = carray(stack_ptr(_NX_MAX, np.float64), nx)
    acc = carray(stack_ptr(_NX_MAX, np.float64), nx)
    for col in range(nz):  # the response to the basis vector e_col of z
        for j in range(nx):
            X[j] = 1.0 if j == col else 0.0
            Kd[j] = 0.0
            acc[j] = 0.0
        S = 1.0 if col == nx else 0.0
        C = 1.0 if col == nx + 1 else 0.0
        fb = 1.0 if col == nx + 2 else 0.0
        fs = 0.0
        fc = 0.0
        for s in range(4):
            for j in range(nx):
                Xs[j] = X[j] + cst[s] * Kd[j]
            f = f0 * (alpha[s] * S + beta[s] * C)
            # the derivative, as in the stage loop of kernels/rk4.py (F_b given)
            sfree = 0.0
            wd = 0.0
            for i in range(n):
                vi = Xs[n + i]
                Kd[i] = vi
                minv = 1.0 / p[L.M_ + i]
                ai = (p[L.PSI_L + i] * minv * f - p[L.K_ + i] * minv * Xs[i]) \
                    - p[L.C_ + i] * minv * vi
                Kd[n + i] = ai
                sfree += p[L.PSI_D + i] * ai
                wd += p[L.PSI_L + i] * vi
            ydd = 0.0
            reld = 0.0
            if ball:
                for i in range(n):
                    Kd[n + i] -= sr * p[L.PSI_D + i] / p[L.M_ + i] * fb
                ydd = kappa * fb - sfree
            elif tmd:
                rel = Xs[iy]
                reld = Xs[iyd]
                for i in range(n):
                    rel -= p[L.PSI_A + i] * Xs[i]
                    reld -= p[L.PSI_A + i] * Xs[n + i]
                ft = ka * rel + ca * reld
                for i in range(n):
                    Kd[n + i] += p[L.PSI_A + i] * ft / p[L.M_ + i]
                ydd = -ft / ma
            elif case == L.LOCKED:
                for i in range(n):
                    Kd[n + i] -= meff * p[L.PSI_D + i] / p[L.M_ + i] * sfree
            Kd[iy] = Xs[iyd] if has_aux else 0.0
            Kd[iyd] = ydd
            if s > 0:
                Yr[s - 1, col] = Xs[iyd] if ball else 0.0
                for i in range(n):
                    Vr[s - 1, i, col] = Xs[n + i]
                Vr[s - 1, n, col] = reld
            for j in range(nx):
                acc[j] += wst[s] * Kd[j]
            fs += wst[s] * f0 * alpha[s] * wd
            fc += wst[s] * f0 * beta[s] * wd
        for j in range(nx):
            Pd[j, col] = acc[j]
        # the work sum_s b_s f_s W'_s, with f_s = F0 (alpha_s S + beta_s C) and W'_s
        # linear in z, is S (Fs . z) + C (Fc . z)
        Fs[col] = fs
        Fc[col] = fc
