"""The cutting law's and the force noise's cost: ns per RK4 step of a stable cut.

    .venv/bin/python benchmarks/bench_cut_law.py [--duration-s S] [--repeat N]

Through the public call (``bb.simulate``, no history): a 2 s cut at 1200 rpm at half
the analytic limit of the solid bar and of the ball damper (physical preset), with
the linear law (the published cut), Kienzle's law (steel), and each with 5 % force
noise.  Numbers only, nothing is asserted.  A baseline build's figure for the linear
cut comes from running this script on that build (the other cases need this one).
"""

from __future__ import annotations

import argparse

from boringbar import make_system, simulate
from boringbar.model.forcing import Regenerative
from boringbar.reference.stability import limit_at_speeds

CASES = {
    "linear": {},
    "kienzle": {"workpiece": "steel"},
    "linear+noise": {"force_noise": 0.05},
    "kienzle+noise": {"workpiece": "steel", "force_noise": 0.05},
}


def ns_per_step(system, forcing, duration: float, repeat: int) -> float:
    """The best of ``repeat`` runs, ns per step."""
    simulate(system, forcing, duration_s=1e-3, record_every=0)  # loads the core
    best = min(simulate(system, forcing, duration_s=duration, record_every=0).elapsed_s
               for _ in range(repeat))
    return best / (duration / 1e-6) * 1e9


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration-s", type=float, default=2.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args()
    for bar in ("solid", "ball"):
        system = make_system(bar)
        b = 0.5 * float(limit_at_speeds(system.linear_host(), [1200.0])[0])
        for name in args.cases.split(","):
            forcing = Regenerative(depth_m=b, rpm=1200.0, **CASES[name])
            cost = ns_per_step(system, forcing, args.duration_s, args.repeat)
            print(f"{bar:6s} {name:14s} {cost:6.1f} ns/step", flush=True)


if __name__ == "__main__":
    main()
