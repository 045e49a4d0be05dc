"""The draws' search against the deterministic lobes' on the same drawn bars.

For every ``--stride``-th speed of the published ball bar's first three lobes and each of
``--draws`` draws of the default Uncertainty, the drawn column is found twice:

- as the deterministic lobes find a column (``lobe_search.growth_column``: the onset's
  bisection from the drawn host's analytic limit, then the ball's search above it);
- as the chance of chatter finds it (``chatter_probability.compute``: the speed's draws in
  blocks, a free ball's column searched once on the chatter-free verdict, from the
  block's median limit).

Prints each column's two limits, cuts and times, and in all: the cuts, the time, and the
columns whose limits differ (by more than 1e-12, relative).

    .venv/bin/python benchmarks/draw_search.py [--draws 8] [--stride 4]

Numbers only, nothing is asserted; docs/chatter_probability.md shows a run.
"""

from __future__ import annotations

import argparse
import math
import time

import boringbar as bb
from boringbar.analysis import chatter_probability as cp
from boringbar.analysis import lobes as lb
from boringbar.analysis.cases import Case
from boringbar.analysis.lobe_search import free_limit, growth_column
from boringbar.analysis.speeds import lobe_speeds
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import Integration


def deterministic(context: dict, j: int, d: int) -> tuple[float, int]:
    """Draw ``d``'s limit (m) at speed ``j`` by the deterministic lobes' search, and its cuts."""
    o, integration = context["options"], context["integration"]
    case, rpm = context["cases"][0], o.rpm[j]
    draw = o.uncertainty.draw(d, case.system.bar.n_modes)
    system = cp.drawn_system(case.system, draw, o.uncertainty)
    host = float(limit_at_speeds(system.linear_host(), [rpm], o.analytic_kr_pa)[0])
    done = growth_column(Case.of(system, case.label), rpm,
                         cp.drawn_options(o, draw, o.uncertainty, system), integration,
                         o.index_below(host) if math.isfinite(host) else 1)
    return free_limit(done, o.depths), len(done)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=8)
    ap.add_argument("--stride", type=int, default=4)
    args = ap.parse_args()
    system = bb.make_system("ball")
    f1 = system.reference_frequency_rad_s / (2 * math.pi)
    rpm = lobe_speeds([f1], (0.9, 4.1))
    options = bb.LobesOptions(rpm, uncertainty=bb.Uncertainty(draws=args.draws))
    context = lb.plan([Case.of(system, "ball")], options, Integration()).context
    cuts, seconds, differ, columns = [0, 0], [0.0, 0.0], 0, 0
    blocks = math.ceil(args.draws / cp.DRAW_BLOCK)
    for j in range(0, len(rpm), args.stride):
        for b in range(blocks):
            tic = time.perf_counter()
            drawn = cp.compute(context, (0, j, b))
            seconds[1] += time.perf_counter() - tic
            for k, d in enumerate(cp.block_draws((0, j, b), args.draws)):
                tic = time.perf_counter()
                limit, runs = deterministic(context, j, d)
                seconds[0] += time.perf_counter() - tic
                new, new_runs = drawn["limit_depth_m"][k], drawn["runs"][k]
                cuts[0] += runs
                cuts[1] += new_runs
                columns += 1
                same = (limit == new or (math.isnan(limit) and math.isnan(new))
                        or abs(new / limit - 1) <= 1e-12)
                differ += not same
                print(f"{rpm[j]:7.0f} rpm, draw {d}: lobes' search {limit * 1e3:.5f} mm "
                      f"({runs} cuts), draws' {new * 1e3:.5f} mm ({new_runs} cuts)"
                      f"{'' if same else '  DIFFERENT'}", flush=True)
    print(f"{columns} drawn columns: the lobes' search {cuts[0]} cuts in {seconds[0]:.1f} s, "
          f"the draws' {cuts[1]} cuts in {seconds[1]:.1f} s ({seconds[0] / seconds[1]:.2f}x); "
          f"limits that differ: {differ}")


if __name__ == "__main__":
    main()
