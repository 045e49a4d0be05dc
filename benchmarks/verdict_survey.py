"""How often, and how fast, the converged verdict calls a linear bar's cut right near its
frequency-domain limit: every other speed of the first five lobes of eight linear bars
(tests/test_verdict.py's), each cut at 0.99, 0.997, 1.003 and 1.01 of the limit.

    .venv/bin/python benchmarks/verdict_survey.py [--every 2] [--factors 0.99,0.997,1.003,1.01]

Prints every wrong or undecided verdict and, per bar, the count so far and the simulated
time the verdicts took (mean and largest).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

import boringbar as bb
from boringbar.analysis.speeds import lobe_speeds
from boringbar.analysis.verdict import judge
from boringbar.reference.stability import limit_at_speeds

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_verdict import linear_bars  # noqa: E402  (the bars the tests check)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--every", type=int, default=2)
    ap.add_argument("--factors", default="0.99,0.997,1.003,1.01")
    args = ap.parse_args()
    factors = [float(f) for f in args.factors.split(",")]
    wrong, n, times = 0, 0, []
    for name, system in linear_bars().items():
        host = system.linear_host()
        speeds = lobe_speeds([host.reference_frequency_rad_s / (2 * math.pi)])[::args.every]
        for rpm, limit in zip(speeds, limit_at_speeds(host, np.array(speeds)), strict=True):
            for factor in factors:
                v = judge(system, bb.Regenerative(depth_m=factor * limit, rpm=rpm))
                n += 1
                times.append(v.onset_duration_s)
                if v.onset != ("stable" if factor < 1 else "chatter"):
                    wrong += 1
                    print(f"WRONG {name} {rpm:g} rpm x{factor:g}: {v.onset} "
                          f"({v.growth_rate_per_s:+.3f}/s after {v.onset_duration_s:.2f} s)")
        print(f"{name}: {wrong} wrong or undecided of {n} so far; simulated time per verdict "
              f"mean {np.mean(times):.2f} s, largest {np.max(times):.2f} s", flush=True)


if __name__ == "__main__":
    main()
