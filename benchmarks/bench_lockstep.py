"""How much would advancing several runs in lock-step gain?  A sizing experiment.

    .venv/bin/python benchmarks/bench_lockstep.py

The kernel in ``boringbar.kernels.rk4`` advances one run at a time, and a
classical RK4 step is a chain of four dependent stage evaluations: the CPU
waits on latency, not on arithmetic.  Sweeps, lobes and basins are many
independent runs.  This prototype (one mode, frictionless ball, impacts at
step ends, the published RK4 and forcing-phase rotation, no metrics beyond a
sum of W^2) advances R runs together, stage by stage, and prints the time per
run-step against R = 1 in the same process.  It is not used by the package:
it sizes the lock-step kernel that the performance targets of issues #2-#4
call for (docs/performance.md).
"""

import math
import time

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", fastmath={"contract"})
def lockstep(n_runs, M, K, C, pL, pD, f0, om, dt, n_steps, half, e, meff):
    u = np.zeros(n_runs)
    v = np.zeros(n_runs)
    y = np.zeros(n_runs)
    yd = np.zeros(n_runs)
    for r in range(n_runs):
        v[r] = 1e-3 * r  # different initial conditions
    invM = 1.0 / M
    h2 = 0.5 * dt
    h6 = dt / 6.0
    s2 = np.zeros(n_runs)
    chh = math.cos(om * h2)
    shh = math.sin(om * h2)
    sn = 0.0
    cn = 1.0
    for _ in range(n_steps):
        s_h = sn * chh + cn * shh
        c_h = cn * chh - sn * shh
        s_1 = s_h * chh + c_h * shh
        c_1 = c_h * chh - s_h * shh
        fA = f0 * sn
        fB = f0 * s_h
        fC = f0 * s_1
        sn = s_1
        cn = c_1
        for r in range(n_runs):
            ur = u[r]
            vr = v[r]
            ydr = yd[r]
            a1 = (pL * fA - C * vr - K * ur) * invM
            u2 = ur + h2 * vr
            v2 = vr + h2 * a1
            a2 = (pL * fB - C * v2 - K * u2) * invM
            u3 = ur + h2 * v2
            v3 = vr + h2 * a2
            a3 = (pL * fB - C * v3 - K * u3) * invM
            u4 = ur + dt * v3
            v4 = vr + dt * a3
            a4 = (pL * fC - C * v4 - K * u4) * invM
            un = ur + h6 * (vr + 2 * v2 + 2 * v3 + v4)
            vn = vr + h6 * (a1 + 2 * a2 + 2 * a3 + a4)
            # y'' = -psi_d u'' (no friction): the ball's RK4 stages in closed form
            yn = y[r] + h6 * (6 * ydr - pD * (h2 * 2 * a1 + h2 * 2 * a2 + dt * a3))
            ydn = ydr - h6 * pD * (a1 + 2 * a2 + 2 * a3 + a4)
            if abs(yn) >= half:
                wall = 1.0 if yn > 0 else -1.0
                yn = wall * half
                if wall * ydn > 0:
                    vb = ydn
                    ydn = -e * vb
                    vn += (1 + e) * meff * pD * vb * invM
            u[r] = un
            v[r] = vn
            y[r] = yn
            yd[r] = ydn
            s2[r] += un * un
    return s2


def main() -> None:
    M = 0.1244
    K = M * (2 * math.pi * 461.0) ** 2
    C = 2 * 0.01 * math.sqrt(K * M)
    args = (M, K, C, 1.0, 0.49, 10.0, 2 * math.pi * 461.0, 1e-6)
    base = None
    for n_runs in (1, 2, 4, 8, 16):
        lockstep(n_runs, *args, 10, 0.05e-3, 0.7, 0.02)  # compile / load
        best = math.inf
        for _ in range(3):
            tic = time.perf_counter()
            lockstep(n_runs, *args, 500_000, 0.05e-3, 0.7, 0.02)
            best = min(best, time.perf_counter() - tic)
        per = best / 500_000 / n_runs * 1e9
        base = base or per
        print(f"{n_runs:2d} runs in lock-step: {per:5.1f} ns per run-step "
              f"({base / per:.1f}x the single run)")


if __name__ == "__main__":
    main()
