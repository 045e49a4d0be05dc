"""The chance of chatter's cost: P(chatter) over a bar's first three lobes, through
``bb.lobes``, on its default executor and on Dask LocalClusters of 1 and 2 workers.

    .venv/bin/python benchmarks/bench_chatter_probability.py [--bar solid] [--draws 32]
        [--dask-draws 8] [--skip-dask] [--force-noise 0]

Prints the wall time (and this process's CPU time) of the deterministic lobes alone and
of the lobes with draws (the default Uncertainty but for --draws and --force-noise) on
the default executor (Execution "auto": a process per core for judged cuts), the cuts
run, and, on Dask, the wall time of --dask-draws draws on one worker and on two, their
ratio and whether both Datasets equal the default executor's bit for bit.
Numbers only, nothing is asserted.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

import boringbar as bb
from boringbar.analysis.speeds import lobe_speeds

#: the first three lobes drawn whole: from past lobe 1's pocket at 60 f1 rpm (k = 0.9) to
#: lobe 4's pocket (k = 4), k = 60 f1 / rpm
LOBES = (0.9, 4.1)


def timed(system, options, execution=None):
    """(Dataset, wall s); the CPU seconds of this process's threads go in the Dataset's
    ``cpu_s`` attribute (on a machine shared with other work, CPU / cores is what the
    wall time would be alone)."""
    tic, cpu = time.perf_counter(), time.process_time()
    ds = bb.lobes(system, options, execution=execution)
    ds.attrs["cpu_s"] = time.process_time() - cpu
    return ds, time.perf_counter() - tic


def same(a, b) -> bool:
    """Every data variable bit for bit (NaN where NaN)."""
    return all(np.array_equal(a[k].values, b[k].values, equal_nan=a[k].dtype.kind == "f")
               for k in a.data_vars)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bar", default="solid", choices=("solid", "ball", "tmd"))
    ap.add_argument("--draws", type=int, default=32)
    ap.add_argument("--dask-draws", type=int, default=8)
    ap.add_argument("--force-noise", type=float, default=0.0)
    ap.add_argument("--skip-dask", action="store_true")
    args = ap.parse_args()
    system = bb.make_system(args.bar)
    f1 = system.reference_frequency_rad_s / (2 * math.pi)
    rpm = lobe_speeds([f1], LOBES)
    print(f"machine: {os.cpu_count()} cores; {args.bar} bar, f1 = {f1:.0f} Hz; "
          f"{len(rpm)} speeds {rpm[0]:g}..{rpm[-1]:g} rpm (lobes 1-3)")
    ds, wall = timed(system, bb.LobesOptions(rpm))
    print(f"deterministic lobes, {ds.attrs['executor']}: {wall:.1f} s "
          f"({ds.attrs['cpu_s']:.1f} CPU s in this process), "
          f"{ds.attrs['runs']} cuts")
    uncertainty = bb.Uncertainty(draws=args.draws, force_noise=args.force_noise)
    options = bb.LobesOptions(rpm, uncertainty=uncertainty)
    ds, wall = timed(system, options)
    print(f"with {args.draws} draws (force noise {args.force_noise:g}), "
          f"{ds.attrs['executor']} x{ds.attrs['workers']}: {wall:.1f} s "
          f"({ds.attrs['cpu_s']:.1f} CPU s in this process), "
          f"{ds.attrs['runs']} + "
          f"{ds.attrs['draw_runs_total']} cuts, {ds.attrs['draw_mean_run_s']:.2f} s simulated "
          f"a drawn cut; min robust depth (P = {uncertainty.probability:g}) "
          f"{float(ds['min_robust_depth_m'][0]) * 1e3:.4f} mm, min chatter-free depth "
          f"{float(ds['min_chatter_free_depth_m'][0]) * 1e3:.4f} mm")
    if args.skip_dask:
        return
    small = bb.LobesOptions(rpm, uncertainty=bb.Uncertainty(draws=args.dask_draws,
                                                            force_noise=args.force_noise))
    ref, _ = timed(system, small)
    walls = {}
    for n in (1, 2):
        dsd, walls[n] = timed(system, small, bb.Execution(dask_local=n))
        print(f"Dask LocalCluster of {n} worker(s), {args.dask_draws} draws: {walls[n]:.1f} s "
              f"(cluster start included); equal to the default executor's bit for bit: "
              f"{same(dsd, ref)}")
    print(f"Dask speed-up 2 workers / 1 worker: {walls[1] / walls[2]:.2f}")


if __name__ == "__main__":
    main()
