"""What the ball's laws cost through bb.simulate, side by side in one process.

The published ball bar (physical preset, 2 modes, gap 0.5 mm, friction on) at F0 = 20 N,
Omega = omega_n, 2 s of RK4 at dt = 1e-6 s: the sliding ball and the impact law (the
published model), a Hertz contact (docs/model.md, section 2.6) and a rolling ball
(section 2.7); CPU time, best of ``--repeat``, with the ratios to the sliding ball's.

    .venv/bin/python benchmarks/bench_ball_laws.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import math
import time

import boringbar as bb

LAWS = {"slide, impact law": {}, "slide, Hertz contact": {"contact": "hertz"},
        "roll, impact law": {"motion": "roll"}}


def best_of(system, repeat: int) -> float:
    forcing = bb.Harmonic(amplitude_n=20.0)
    bb.simulate(system, forcing, duration_s=0.01, record_every=0, integrator="rk4")
    best = math.inf
    for _ in range(repeat):
        tic = time.process_time()
        bb.simulate(system, forcing, duration_s=2.0, record_every=0, integrator="rk4")
        best = min(best, time.process_time() - tic)
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    times = {name: best_of(bb.make_system("ball", **kw), args.repeat)
             for name, kw in LAWS.items()}
    base = times["slide, impact law"]
    for name, t in times.items():
        print(f"  {name:22s} {t:.3f} s  ({t / base:.2f}x)")


if __name__ == "__main__":
    main()
