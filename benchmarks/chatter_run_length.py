"""Why a fixed short run places the chatter limit too high, and what the converged verdict
does instead: the figure of docs/chatter.md.

    .venv/bin/python benchmarks/chatter_run_length.py [--out docs/img/chatter_run_length.png]

Left: the tip amplitude (half its peak-to-peak, revolution by revolution) of the carbide
example's solid bar cut at 1200 rpm, knocked in the cut, at depths about its
frequency-domain limit: near the limit a vibration grows or dies at a fraction of a
percent a revolution.  Right: over the bar's first five lobes, the simulated limit over
the frequency-domain one, by the published criterion (the force reaches zero) in runs
of 2 s and 8 s from rest, and by the converged verdict.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter, ScalarFormatter

import boringbar as bb
from boringbar.analysis.lobes import LobesOptions
from boringbar.analysis.speeds import lobe_speeds
from boringbar.analysis.verdict import window_steps
from boringbar.plot.palette import OKABE_ITO
from boringbar.plot.style import COLUMN_WIDTH_IN
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import CutStepper, knocked_cut

SYSTEMS = Path(__file__).resolve().parents[1] / "examples" / "systems"
RPM = 1200.0
FACTORS = (0.98, 0.995, 1.005, 1.02)


def envelopes(system, limit: float, seconds: float = 4.0) -> dict:
    out = {}
    for factor in FACTORS:
        cut = bb.Regenerative(depth_m=factor * limit, rpm=RPM, start="static")
        steps = window_steps(system, cut, 1e-6)
        stepper = CutStepper(system, cut, dt_s=1e-6, window_steps=steps,
                             initial=knocked_cut(system, cut, 1e-6))
        windows = [stepper.advance() for _ in range(int(seconds / (steps * 1e-6)))]
        out[factor] = (np.array([w.t_end_s for w in windows]),
                       np.array([w.half_pp_m for w in windows]))
    return out


def ratios(system, speeds) -> dict:
    out = {}
    for label, criterion, seconds in (("published, 2 s runs", "zero", 2.0),
                                      ("published, 8 s runs", "zero", 8.0),
                                      ("converged verdict", "growth", 2.0)):
        ds = bb.lobes({"bar": system}, LobesOptions(rpm=tuple(speeds), criterion=criterion),
                      integration=bb.Integration(duration_s=seconds))
        out[label] = ds["limit_depth_m"].values[0] / ds["host_analytic_limit_m"].values[0]
        print(f"{label}: {ds.attrs['runs']} runs in {ds.attrs['wall_time_s']:.1f} s; limit / "
              f"analytic {np.nanmin(out[label]):.4f} to {np.nanmax(out[label]):.4f}")
    return out


def figure(env: dict, speeds, rat: dict) -> Figure:
    fig = Figure(figsize=(COLUMN_WIDTH_IN, 3.4), layout="constrained")
    left, right = fig.subplots(1, 2)
    colours = [OKABE_ITO[c] for c in ("bluish green", "sky blue", "orange", "vermillion")]
    for (factor, (t, a)), colour in zip(env.items(), colours, strict=True):
        left.semilogy(t, a * 1e6, color=colour, lw=1.2, label=f"{factor:g} x limit")
    left.axvline(2.0, color="0.5", ls=":", lw=1)
    left.text(2.02, left.get_ylim()[1], "published 2 s", va="top", fontsize="x-small",
              color="0.4")
    left.set(xlabel="time (s)", ylabel="tip amplitude (um)",
             title=f"a 1 um knock at {RPM:g} rpm")
    left.yaxis.set_major_formatter(ScalarFormatter())
    left.yaxis.set_minor_formatter(ScalarFormatter())
    left.legend(fontsize="x-small", frameon=False)
    styles = {"published, 2 s runs": dict(color=OKABE_ITO["vermillion"], marker="x"),
              "published, 8 s runs": dict(color=OKABE_ITO["orange"], marker="+"),
              "converged verdict": dict(color=OKABE_ITO["blue"], marker="o", mfc="none")}
    for label, r in rat.items():
        right.plot(speeds, r, ls="-", lw=0.8, ms=4, label=label, **styles[label])
    right.axhline(1.0, color="black", lw=0.8)
    right.set_xscale("log")
    ticks = [t for t in (3000, 5000, 7000, 10000, 15000)
             if min(speeds) <= t <= max(speeds)]
    right.set_xticks(ticks, [f"{t:g}" for t in ticks])
    right.xaxis.set_minor_formatter(NullFormatter())
    right.set(xlabel="spindle speed (rpm)", ylabel="simulated / frequency-domain limit",
              title="first five lobes")
    right.legend(fontsize="x-small", frameon=False)
    fig.suptitle("carbide example, solid bar: a fixed run stops before a slow vibration "
                 "shows", fontsize="small")
    return fig


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="docs/img/chatter_run_length.png")
    ap.add_argument("--every", type=int, default=2, help="every n-th speed of lobes 1-5")
    args = ap.parse_args()
    system = bb.variants(bb.load_system(SYSTEMS / "carbide_ld10_tungsten.toml"))["solid"]
    limit = float(limit_at_speeds(system, [RPM])[0])
    speeds = lobe_speeds([system.reference_frequency_rad_s / (2 * math.pi)])[::args.every]
    fig = figure(envelopes(system, limit), speeds, ratios(system, speeds))
    fig.savefig(args.out, dpi=150)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
