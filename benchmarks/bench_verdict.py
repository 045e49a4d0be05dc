"""The converged verdict against the published fixed-run criterion, side by side in one
process, through the call a user makes (``bb.lobes``): the same bars and speeds, the
same search, each way of judging a cut.

    .venv/bin/python benchmarks/bench_verdict.py [--speeds N] [--workers W]

Prints per bar and criterion: the runs, the simulated seconds per run, the wall time and
the worst relative error of the limit against the frequency-domain limit of the bar's
linear host (for the linear bars), and the ratio of the wall times.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import boringbar as bb
from boringbar.analysis.lobes import LobesOptions
from boringbar.analysis.speeds import lobe_speeds

SYSTEMS = Path(__file__).resolve().parents[1] / "examples" / "systems"


def bars() -> dict[str, bb.System]:
    carbide = bb.load_system(SYSTEMS / "carbide_ld10_tungsten.toml")
    return {"carbide solid": bb.variants(carbide)["solid"],
            "published tmd": bb.make_system("tmd"),
            "published ball, friction": bb.make_system("ball", gap_m=0.1e-3)}


def measure(system: bb.System, speeds, criterion: str, workers: int) -> dict:
    tic = time.perf_counter()
    ds = bb.lobes({"bar": system}, LobesOptions(rpm=tuple(speeds), criterion=criterion),
                  execution=bb.Execution("threads", workers=workers))
    wall = time.perf_counter() - tic
    sim = (float(np.nansum(ds["run_duration_s"].values)) if criterion == "growth"
           else _fixed_seconds(ds))
    exact = ds["host_analytic_limit_m"].values[0]
    err = np.abs(ds["limit_depth_m"].values[0] / exact - 1)
    return {"runs": int(ds.attrs["runs"]), "wall_s": wall, "sim_per_run_s": sim / ds.attrs["runs"],
            "worst_error": float(np.nanmax(err)) if system.kind != "ball" else math.nan}


def _fixed_seconds(ds) -> float:
    """Simulated time of the fixed-run cuts: a run stops at the first zero of the force."""
    t = ds["first_zero_time_s"].values
    ran = ds["verdict"].values >= 0
    return float(np.where(np.isnan(t), ds.attrs["duration_s"], t)[ran].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--speeds", type=int, default=12, help="speeds over lobes 1-5")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    print(f"{'bar':28} {'criterion':9} {'runs':>5} {'s/run sim':>10} {'wall s':>8} "
          f"{'worst err':>10}")
    for name, system in bars().items():
        f1 = system.linear_host().reference_frequency_rad_s / (2 * math.pi)
        all_speeds = lobe_speeds([f1])
        speeds = all_speeds[:: max(1, len(all_speeds) // args.speeds)]
        rows = {c: measure(system, speeds, c, args.workers) for c in ("zero", "growth")}
        for c, r in rows.items():
            print(f"{name:28} {c:9} {r['runs']:5d} {r['sim_per_run_s']:10.3f} "
                  f"{r['wall_s']:8.1f} {r['worst_error']:10.2%}")
        g, z = rows["growth"], rows["zero"]
        print(f"{'':28} growth / zero wall time: {g['wall_s'] / z['wall_s']:.2f}; per run: "
              f"{(g['wall_s'] / g['runs']) / (z['wall_s'] / z['runs']):.2f}")


if __name__ == "__main__":
    main()
