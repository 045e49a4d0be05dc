"""Kernel speed: one 2 s impact-damped run at dt = 1e-6, against scipy in the same process.

    .venv/bin/python benchmarks/bench_kernel.py [--scipy-duration 2.0] [--skip-scipy]

Prints the kernel's ns per RK4 step and simulated seconds per wall second for
1, 2 and 3 retained modes, the same physical run integrated by
``scipy.integrate.solve_ivp`` (RK45, terminal wall events, impact law applied
at each event, restart) and the ratio, and the published sweep (11 ratios x 6
cases) with a warm JIT on every core.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from scipy.integrate import solve_ivp

from boringbar import Harmonic, make_system, simulate
from boringbar.analysis.cases import published_cases
from boringbar.analysis.sweep import SweepOptions, sweep
from boringbar.simulate import Integration, simulate_stage_loop

CASE = {"bar": "ball", "preset": "paper", "gap_m": 0.1e-3, "friction": False}
FORCE, RATIO = 10.0, 1.0


def kernel_run(n_modes: int, duration: float = 2.0, dt: float = 1e-6, friction=None):
    """Best of three of the kernel (step map) and of its stage loop, rounds interleaved."""
    system = make_system(CASE["bar"], CASE["preset"], gap_m=CASE["gap_m"],
                         friction=CASE["friction"] if friction is None else friction,
                         n_modes=n_modes)
    forcing = Harmonic(FORCE, RATIO)
    for f in (simulate, simulate_stage_loop):  # JIT warm-up / cache load
        f(system, forcing, duration_s=1e-4, dt_s=dt)
    best = [math.inf, math.inf]
    runs = [None, None]
    for _ in range(3):
        for i, f in enumerate((simulate, simulate_stage_loop)):
            runs[i] = f(system, forcing, duration_s=duration, dt_s=dt)
            best[i] = min(best[i], runs[i].elapsed_s)
    return runs[0], best[0], runs[1], best[1]


def scipy_run(duration: float, rtol: float = 1e-8):
    """The same one-mode frictionless ball damper, event-driven with solve_ivp."""
    s = make_system(CASE["bar"], CASE["preset"], gap_m=CASE["gap_m"], friction=False, n_modes=1)
    bar, ball = s.bar, s.damper
    M, K, C = bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0]
    pl, pd = bar.psi_tip[0], bar.psi_damper[0]
    m, e, half = ball.mass_kg, ball.restitution, ball.gap_m / 2
    om = RATIO * s.reference_frequency_rad_s
    meff = 1.0 / (1.0 / m + pd**2 / M)

    def rhs(t, x):
        a = (pl * FORCE * math.sin(om * t) - C * x[1] - K * x[0]) / M
        return [x[1], a, x[3], -pd * a]

    def wall(t, x):
        return half - abs(x[2])

    wall.terminal = True
    wall.direction = -1
    t, x = 0.0, np.zeros(4)
    w_samples = []
    n_impacts = 0
    while t < duration:
        sol = solve_ivp(rhs, (t, duration), x, method="RK45", rtol=rtol, atol=1e-12,
                        events=wall, dense_output=False, max_step=2e-5)
        w_samples.append(sol.y[0])
        t, x = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            vb = x[3]
            x[2] = math.copysign(half, x[2])
            x[3] = -e * vb
            x[1] += (1 + e) * meff * pd * vb / M
            n_impacts += 1
    return n_impacts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scipy-duration", type=float, default=2.0)
    ap.add_argument("--skip-scipy", action="store_true")
    args = ap.parse_args()
    print(f"machine: {os.cpu_count()} cores; case {CASE}, F0 = {FORCE} N, ratio {RATIO}")
    base = None
    for n in (1, 2, 3):
        run, wall, run_s, wall_s = kernel_run(n)
        steps = round(run.duration_s / run.dt_s)
        if n == 1:
            base = wall
        print(f"kernel rk4, {n} mode(s): {wall:.4f} s per 2 s run, "
              f"{wall / steps * 1e9:.1f} ns/step, "
              f"{run.duration_s / wall:.1f} simulated s per wall s, "
              f"{run.metrics['impacts_total']} impacts, pattern {run.pattern.name}; "
              f"stage loop every step: {wall_s / steps * 1e9:.1f} ns/step "
              f"({wall_s / wall:.2f}x), {run_s.metrics['impacts_total']} impacts")
    for n in (1, 2):
        run, wall, run_s, wall_s = kernel_run(n, friction=True)
        steps = round(run.duration_s / run.dt_s)
        print(f"kernel rk4, {n} mode(s), friction on ({run.system.damper.friction_force_n:.3g} N):"
              f" {wall / steps * 1e9:.1f} ns/step, "
              f"{run.metrics['impacts_total']} impacts, pattern {run.pattern.name}; "
              f"stage loop every step: {wall_s / steps * 1e9:.1f} ns/step ({wall_s / wall:.2f}x)")
    if not args.skip_scipy:
        tic = time.perf_counter()
        n_imp = scipy_run(args.scipy_duration)
        ws = time.perf_counter() - tic
        per_2s = ws * 2.0 / args.scipy_duration
        print(f"scipy solve_ivp RK45 + wall events, 1 mode: {ws:.2f} s for "
              f"{args.scipy_duration} s simulated ({n_imp} impacts) -> {per_2s:.2f} s per 2 s run;"
              f" kernel is {per_2s / base:.0f}x faster")
    for preset in ("paper", "physical"):
        cases = published_cases(preset=preset)
        ratios = np.round(np.arange(0.95, 1.05 + 1e-9, 0.01), 2)
        sweep(cases[:1], SweepOptions(ratios[:1]), integration=Integration(duration_s=1e-3))
        tic = time.perf_counter()
        ds = sweep(cases, SweepOptions(ratios, (FORCE,)))
        wall = time.perf_counter() - tic
        print(f"published sweep ({preset}, {ds.sizes['ratio']} ratios x {ds.sizes['case']} cases, "
              f"2 s each) on {ds.attrs['workers']} workers: {wall:.2f} s "
              f"({wall / (ds.sizes['ratio'] * ds.sizes['case']):.3f} s per run)")


if __name__ == "__main__":
    main()
