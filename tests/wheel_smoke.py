"""A built wheel's smoke test: the installed package imports and its compiled core runs.

    python tests/wheel_smoke.py

cibuildwheel runs it on every wheel it builds (pyproject.toml, [tool.cibuildwheel]), and
tests/test_wheel.py runs it in a fresh venv that has the wheel and no compiler.  Run it
from outside the source tree, so that the installed package is the one imported.  It
exits non-zero unless the published ball bar gives a finite, non-zero tip vibration
under the paper preset (the RK4 kernels), under the physical preset (the exact
integrator) and in a cut (RK4 with the regenerative delay).
"""

from __future__ import annotations

import math
import sys

import numpy as np

import boringbar as bb
from boringbar import core


def check(label: str, run) -> None:
    rms = float(run.summary()["rms_tip_m"])
    final = np.asarray(run.final.x)
    print(f"{label}: tip RMS {rms:.4e} m ({run.integrator})")
    if not (math.isfinite(rms) and rms > 0.0 and np.all(np.isfinite(final))):
        sys.exit(f"{label}: not a finite, non-zero result (tip RMS {rms}, final {final})")


def main() -> None:
    print(f"boringbar {bb.__version__} from {bb.__file__}")
    print(f"core: {core.__file__}")
    paper = bb.make_system("ball", preset="paper")
    check("paper preset, harmonic", bb.simulate(paper, bb.Harmonic(10.0, 1.0), duration_s=0.2))
    physical = bb.make_system("ball", preset="physical")
    check("physical preset, harmonic",
          bb.simulate(physical, bb.Harmonic(20.0, 1.0), duration_s=0.2))
    check("physical preset, a cut",
          bb.simulate(physical, bb.Regenerative(depth_m=0.2e-3, rpm=1200.0), duration_s=0.2))
    print("wheel smoke test passed")


if __name__ == "__main__":
    main()
