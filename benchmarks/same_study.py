"""Whether two runs of the published study give the same numbers, bit for bit.

    .venv/bin/python benchmarks/same_study.py OLD_OUT NEW_OUT

OLD_OUT and NEW_OUT are two ``boringbar paper`` output directories (say one made
before a change and one after it, or one from an empty numba cache and one warm).
Every NetCDF data variable under OLD_OUT must be in NEW_OUT with the same shape and
the same values (NaN equal to NaN); variables named for a wall time are left out.
The manifests must list the same steps in the same order.  Prints each difference
and the counts; exits 1 if anything differs.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import xarray as xr

#: variables that hold a time measured on the clock, not a result
CLOCK_WORDS = ("wall", "elapsed", "time_s")


def same_values(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape:
        return False
    if a.dtype.kind in "fc":
        return bool(np.array_equal(a, b, equal_nan=True))
    return bool(np.array_equal(a, b))


def compare(old: Path, new: Path) -> tuple[int, list[str]]:
    """(variables compared, differences) over every NetCDF file under ``old``."""
    count, diffs = 0, []
    for f in sorted(old.rglob("*.nc")):
        g = new / f.relative_to(old)
        if not g.exists():
            diffs.append(f"missing: {g}")
            continue
        a, b = xr.load_dataset(f), xr.load_dataset(g)
        for name in a.data_vars:
            if any(w in str(name) for w in CLOCK_WORDS):
                continue
            count += 1
            if name not in b.data_vars or not same_values(a[name].values, b[name].values):
                diffs.append(f"differs: {f.relative_to(old)} {name}")
    return count, diffs


def step_order(out: Path) -> list[tuple]:
    steps = json.loads((out / "manifest.json").read_text())["steps"]
    return [(s["preset"], s["key"], s.get("shared_from")) for s in steps]


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    old, new = map(Path, argv)
    count, diffs = compare(old, new)
    if step_order(old) != step_order(new):
        diffs.append("the manifests list different steps or another order")
    for d in diffs:
        print(d)
    print(f"{count} variables compared, {len(diffs)} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
