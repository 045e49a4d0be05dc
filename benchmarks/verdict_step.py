"""The converged verdict's RK4 step: the carbide example's ball-bar chatter map (30 speeds
x 20 depths, a small and a 20 um knock) judged at several steps, each against the
finest, with the friction rendered by ``--stick-law`` (the verdict's "hold" by default,
or the published "sgn").

    .venv/bin/python benchmarks/verdict_step.py [--steps 5e-7,1e-6,2e-6,5e-6]
        [--stick-law hold|sgn] [--workers 2] [--keep DIR]

A step may carry its onset's step ratio (``VerdictOptions.onset_step_ratio``) as
``STEP:RATIO``, ``2e-6:1`` for a whole cut at 2e-6 s; without one, the verdict's
default.  The finest step (the smallest ratio first) is the reference.

For each step it prints the wall time and, against the finest step's map: the cells
whose onset and whose chatter-free verdict differ, the speeds whose chatter-free depth
differs, the minimum chatter-free depth, and the settled tip peak-to-peak of every
start (median and 90th percentile of the relative difference; the starts beyond 5 %,
by their settled status).  ``--keep DIR`` writes each map there (map_<step>.nc).
Numbers only, nothing is asserted; docs/chatter.md, "The step of a judged cut", shows
a run.
"""

from __future__ import annotations

import argparse
import collections
import time
from pathlib import Path

import numpy as np

import boringbar as bb
from boringbar.analysis import chatter_map as cm
from boringbar.analysis.verdict import VerdictOptions
from boringbar.execute import Execution
from boringbar.io import write_netcdf_atomic

CARBIDE = Path(__file__).resolve().parents[1] / "examples" / "systems" / \
    "carbide_ld10_tungsten.toml"


def one_map(ball, rpm, depths, dt: float, ratio: float, workers: int, stick_law: str):
    options = cm.ChatterMapOptions(rpm=rpm, depths_m=depths,
                                   verdict=VerdictOptions(knocks_m=(cm.LARGE_KNOCK_M,),
                                                          stick_law=stick_law,
                                                          onset_step_ratio=ratio))
    tic = time.perf_counter()
    ds = bb.chatter_map(ball, options, integration=bb.Integration(dt_s=dt),
                        execution=Execution("threads", workers))
    return ds, time.perf_counter() - tic


def compare(ref, ds) -> str:
    """The differences of ``ds`` from ``ref`` in one paragraph."""
    onset = int(np.sum(ref["onset"].values != ds["onset"].values))
    free = int(np.sum(ref["chatter_free"].values != ds["chatter_free"].values))
    depth = int(np.sum(~np.isclose(ref["chatter_free_depth_m"].values,
                                   ds["chatter_free_depth_m"].values, rtol=1e-12, equal_nan=True)))
    pa, pb = ref["settled_pp_m"].values, ds["settled_pp_m"].values
    both = (pa > 0) & (pb > 0)
    rel = np.abs(pa - pb)[both] / np.maximum(pa, pb)[both]
    status = ref["settled_status"].values[both][rel > 0.05]
    far = ", ".join(f"{n} {s}" for s, n in collections.Counter(status).most_common())
    return (f"onset differs in {onset} cells, chatter-free in {free}; chatter-free depth at "
            f"{depth} speeds; min chatter-free depth "
            f"{float(ds['min_chatter_free_depth_m'][0]) * 1e3:.4g} mm; settled p-p of "
            f"{both.sum()} starts: median {np.median(rel):.2%}, 90 % {np.quantile(rel, 0.9):.2%}, "
            f"{int(np.sum(rel > 0.05))} beyond 5 % ({far or 'none'})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="5e-7,1e-6,2e-6,5e-6")
    ap.add_argument("--stick-law", default="hold", choices=("hold", "sgn"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--keep", type=Path)
    args = ap.parse_args()
    default = VerdictOptions().onset_step_ratio
    steps = sorted((float(dt), float(ratio[0]) if ratio else default)
                   for dt, *ratio in (s.split(":") for s in args.steps.split(",")))
    ball = bb.variants(bb.load_system(CARBIDE))["ball"]
    case = [bb.Case.of(ball)]
    rpm = cm.map_speeds(case)
    depths = cm.map_depths(cm.host_limits(case, rpm, bb.LobesOptions().analytic_kr_pa))
    maps = {}
    for dt, ratio in steps:
        maps[dt, ratio], wall = one_map(ball, rpm, depths, dt, ratio, args.workers,
                                        args.stick_law)
        print(f"dt = {dt:g} s, onset ratio {ratio:g}: {wall:.1f} s wall", flush=True)
        if args.keep:
            args.keep.mkdir(parents=True, exist_ok=True)
            write_netcdf_atomic(maps[dt, ratio], args.keep / f"map_{dt:g}_{ratio:g}.nc")
    ref = maps[steps[0]]
    for key in steps[1:]:
        print(f"dt = {key[0]:g} s, onset ratio {key[1]:g} against {steps[0][0]:g} s, "
              f"{steps[0][1]:g}: {compare(ref, maps[key])}")


if __name__ == "__main__":
    main()
