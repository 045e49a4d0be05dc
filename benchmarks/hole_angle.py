"""The ball's cavity angle against the chatter-free depth (docs/model.md, section 4.7).

The published ball bar in two bending planes (a round bar: equal planes), cut with
Kt / Kr = 2.5 at a zero lead angle: the ball's chatter-free depth at one speed by the
converged verdict (simulated cuts) as the cavity's axis turns from radial (0 degrees)
through the section, beside the plain (solid) bar's simulated limit and the locked
ball's closed-form one.  What a second plane costs: benchmarks/bench_ball_laws.py.

    .venv/bin/python benchmarks/hole_angle.py [--rpm 3000] [--out docs/img/hole_angle.png]
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import boringbar as bb  # noqa: E402
from boringbar.analysis.lobes import LobesOptions, lobes  # noqa: E402
from boringbar.model.oriented import CutGeometry  # noqa: E402

ANGLES = tuple(-90.0 + 7.5 * k for k in range(25))


def geometry(hole: float) -> CutGeometry:
    return CutGeometry(force_ratio=2.5, hole_angle_deg=hole)


def limits(rpm: float):
    """The chatter-free depth (m) of the ball bar at each cavity angle, the solid bar's
    (simulated) and the locked ball's closed form at each angle."""
    systems = {f"ball {a:g}": bb.make_system("ball", n_modes=1, planes=2,
                                             cut_geometry=geometry(a)) for a in ANGLES}
    systems["solid"] = bb.make_system("solid", n_modes=1, planes=2,
                                      cut_geometry=geometry(0.0))
    ds = lobes(systems, LobesOptions(rpm=(rpm,)))
    depth = dict(zip(ds["case"].values.tolist(), ds["limit_depth_m"].values[:, 0], strict=True))
    host = dict(zip(ds["case"].values.tolist(), ds["host_analytic_limit_m"].values[:, 0],
                    strict=True))
    return ([depth[f"ball {a:g}"] for a in ANGLES], depth["solid"],
            [host[f"ball {a:g}"] for a in ANGLES], float(ds.attrs["wall_time_s"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rpm", type=float, default=3000.0)
    ap.add_argument("--out", default="docs/img/hole_angle.png")
    args = ap.parse_args()
    ball, solid, host, wall = limits(args.rpm)
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.plot(ANGLES, np.array(ball) * 1e3, "o-", label="ball bar (converged verdict)")
    ax.axhline(solid * 1e3, color="k", ls="--", label="solid bar (converged verdict)")
    ax.plot(ANGLES, np.array(host) * 1e3, ":", color="C1",
            label="locked ball (closed form)")
    ax.set(xlabel="cavity axis from the radial direction (degrees)",
           ylabel="chatter-free depth (mm)", xticks=ANGLES[::4],
           title=f"published ball bar, bending along and across its cavity, Kt/Kr = 2.5, "
                 f"{args.rpm:g} rpm")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out} ({wall:.0f} s of lobes)")
    for a, d, h in zip(ANGLES, ball, host, strict=True):
        print(f"  cavity at {a:+6.1f} deg: ball {d * 1e3:.4f} mm, locked ball (closed form) "
              f"{h * 1e3:.4f} mm")
    print(f"  solid bar: {solid * 1e3:.4f} mm")


if __name__ == "__main__":
    main()
