"""The validation gallery's figures (docs/validation.md): published results against ours.

1. Altintas' two-mode oriented example (Manufacturing Automation, 2nd ed., 2012, p. 131):
   our closed-form lobes, our simulated limits (the converged verdict) at five speeds,
   and the lobe bottoms of his formula, with the depth his lab's published figure shows.
2. Hunt and Crossley (1975): the restitution of a damped Hertz impact against its
   damping alpha = chi v_in, ours (the core's integration) against their small-damping
   law e = 1 - 2/3 alpha and the later closed forms of Lankarani and Nikravesh (1990,
   alpha = 3/4 (1 - e^2)) and Flores et al. (2011, alpha = 8/5 (1 - e) / e).

    .venv/bin/python benchmarks/validation_figures.py [--out docs/img]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_oriented import altintas  # noqa: E402

from boringbar.analysis.lobes import LobesOptions, lobes  # noqa: E402
from boringbar.reference.stability import analytic_lobes, min_limit  # noqa: E402
from boringbar.simulate.kernels import hunt_crossley_restitution  # noqa: E402

KF = 1e9  # Pa, Altintas' Kf = 1000 MPa
SPEEDS = (4049.0, 5521.0, 7000.0, 8678.0, 11849.0)
#: his formula's lobe bottoms (rpm) and the absolute limit his lab's figure shows (m)
PUBLISHED_BOTTOMS = (8678.0, 5521.0, 4049.0)
PUBLISHED_LIMIT = 7.2e-3


def altintas_figure(path: Path) -> None:
    system = altintas()
    lob = analytic_lobes(system, KF, lobes=range(0, 12))
    ds = lobes({"altintas": system}, LobesOptions(rpm=SPEEDS, kr_pa=KF, max_depth_m=0.1))
    sim = ds["limit_depth_m"].values[0]
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for j in range(len(lob["lobe"])):
        ax.plot(lob["rpm"][j], lob["b_lim"][j] * 1e3, color="C0", lw=1,
                label="ours, closed form" if j == 0 else None)
    ax.plot(SPEEDS, sim * 1e3, "o", color="C3", label="ours, simulated (converged verdict)")
    ax.plot(PUBLISHED_BOTTOMS, [PUBLISHED_LIMIT * 1e3] * 3, "kx", ms=9,
            label="Altintas: his formula's lobe bottoms, the depth his lab's figure shows")
    ax.axhline(min_limit(system, KF) * 1e3, color="C0", ls=":", lw=1)
    ax.set(xlim=(2000, 15000), ylim=(0, 60), xlabel="spindle speed (rpm)",
           ylabel="depth of cut (mm)",
           title="Altintas (2012), p. 131: two modes at 30 and -45 degrees, Kf = 1000 MPa")
    ax.legend(fontsize=8, loc="center right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}: absolute limit {min_limit(system, KF) * 1e3:.4f} mm; simulated "
          f"against closed form at {SPEEDS}: "
          + " ".join(f"{e:+.3%}" for e in sim / ds["host_analytic_limit_m"].values[0] - 1))


def hunt_crossley_figure(path: Path) -> None:
    alpha = np.geomspace(1e-3, 30, 60)
    e = np.array([hunt_crossley_restitution(a) for a in alpha])
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.semilogx(alpha, e, "o", ms=4, label="ours (the core's integration)")
    ax.semilogx(alpha, np.clip(1 - 2 / 3 * alpha, 0, 1), "k:",
                label="Hunt & Crossley: e = 1 - 2/3 alpha (small damping)")
    ee = np.linspace(0.05, 1.0, 200)
    ax.semilogx(0.75 * (1 - ee**2), ee, "C1--", label="Lankarani & Nikravesh: 3/4 (1 - e^2)")
    ax.semilogx(1.6 * (1 - ee) / ee, ee, "C2-.", label="Flores et al.: 8/5 (1 - e) / e")
    ax.set(xlabel="alpha = chi v_in", ylabel="restitution e", ylim=(0, 1.02),
           title="a damped Hertz impact: restitution against damping")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/img")
    args = ap.parse_args()
    out = Path(args.out)
    altintas_figure(out / "validation_altintas.png")
    hunt_crossley_figure(out / "validation_hunt_crossley.png")


if __name__ == "__main__":
    main()
