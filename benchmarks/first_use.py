"""A fresh clone's first use: the README's install, then the first commands, timed.

    .venv/bin/python benchmarks/first_use.py [--paper] [--keep DIR]

Clones this repository's committed HEAD into a new directory, then times, each in a new
process, as a new user meets them:

1. ``python3 -m venv .venv && .venv/bin/pip install -e .`` (the README's install, the
   compiled core built by scikit-build-core included; pip's download cache as this
   machine has it); then a second fresh clone's ``pip install -e .`` into that venv, whose
   dependencies are installed: pip's build environment and the build, the step a
   developer's venv repeats for every clone;
2. ``python -c "import boringbar"``, three times (the first reads the files from disk);
3. the first ``boringbar simulate`` after the install (the published ball bar, the
   physical preset: the exact integrator), then the same with ``--integrator rk4``;
4. with ``--paper``, ``boringbar paper --quick`` twice: the first run after the install
   and a warm rerun into a new directory.

Every figure is a wall time of the whole command, so process start-up counts.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine import describe

ROOT = Path(__file__).resolve().parent.parent


def timed(label: str, cmd: str, cwd: Path) -> float:
    """Run ``cmd`` in a shell in ``cwd``; print and return its wall time (s)."""
    tic = time.perf_counter()
    out = subprocess.run(cmd, shell=True, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - tic
    if out.returncode != 0:
        sys.exit(f"{label} failed ({out.returncode}):\n{out.stdout[-2000:]}{out.stderr[-2000:]}")
    print(f"  {label:58s} {wall:7.2f} s", flush=True)
    return wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paper", action="store_true", help="also time boringbar paper --quick")
    ap.add_argument("--keep", type=Path, help="clone into DIR (kept) instead of a temp dir")
    args = ap.parse_args()
    where = args.keep or Path(tempfile.mkdtemp(prefix="boringbar-first-use-"))
    clone = where / "boringbar"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone,
                          capture_output=True, text=True, check=True).stdout.strip()
    print(f"machine: {describe()}; fresh clone of "
          f"{head} in {clone}")
    bb = ".venv/bin/boringbar"
    timed("install: python3 -m venv .venv && pip install -e .",
          "python3 -m venv .venv && .venv/bin/pip install -q -e .", clone)
    second = where / "second"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(second)], check=True)
    timed("a second fresh clone's pip install -e . (dependencies in)",
          f"{clone}/.venv/bin/pip install -q -e .", second)
    # the venv back on the first clone (its build folder kept: nothing recompiles)
    subprocess.run([f"{clone}/.venv/bin/pip", "install", "-q", "-e", "."], cwd=clone,
                   check=True)
    for i in range(3):
        timed(f"python -c 'import boringbar' ({i + 1})", ".venv/bin/python -c 'import boringbar'",
              clone)
    timed("boringbar --help", f"{bb} --help", clone)
    timed("first boringbar simulate (physical preset: exact)",
          f"{bb} simulate --force-n 20 --out out/first", clone)
    timed("boringbar simulate --integrator rk4", f"{bb} simulate --force-n 20 --integrator rk4 "
          "--out out/first-rk4", clone)
    if args.paper:
        timed("boringbar paper --quick (first run)", f"{bb} paper --quick --out out/paper",
              clone)
        timed("boringbar paper --quick (warm rerun, new dir)",
              f"{bb} paper --quick --out out/paper2", clone)


if __name__ == "__main__":
    main()
