"""``boringbar chatter-map``: the settled vibration of every cut of a grid of spindle speeds
x depths of cut (:mod:`boringbar.analysis.chatter_map`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from boringbar._validate import ParameterError, check_int
from boringbar.analysis.cases import MAX_GRID_VALUES, parse_range
from boringbar.analysis.chatter_map import (
    LARGE_KNOCK_M,
    NOT_FOR_A_MAP,
    ChatterMapOptions,
    chatter_map,
)
from boringbar.analysis.speeds import check_speeds
from boringbar.analysis.verdict import VerdictOptions
from boringbar.cli.options import (
    Outcome,
    add_common,
    add_cutting,
    add_verdict,
    check_rpm,
    check_workers,
    cut_options,
    execution,
    integration,
    many_cases,
    progress_printer,
    verdict_options,
    wrote,
)
from boringbar.model.forcing import check_depth
from boringbar.report.outputs import chatter_map_files
from boringbar.simulate import fixed_run_step
from boringbar.simulate.run_limits import check_steps


def add_chatter_map(sub) -> None:
    p = sub.add_parser(
        "chatter-map", help="the settled vibration of every cut of a speed x depth grid",
        description="The chatter amplitude map (docs/chatter_map.md): every (speed, depth) "
                    "cell a cut judged by the converged verdict: does a small knock grow, "
                    "what its vibration and a large knock's settle to (tip RMS and "
                    "peak-to-peak), whether the tool leaves the cut; per speed the "
                    "chatter-free depth and the onset.  Writes DIR/chatter_map.nc and "
                    "DIR/chatter_map.png.")
    groups = add_common(p, many=True, harmonic=False, initial=False)
    p.set_defaults(duration_s=None)  # so that a --duration-s given is told it does not apply
    g = p.add_argument_group("map grid")
    g.add_argument("--rpm", metavar="START:STOP:STEP",
                   help="spindle speeds in rev/min, START:STOP:STEP (inclusive) or comma list "
                        "(default: 30 speeds at which a carbide insert bores --workpiece "
                        "with the bar, evenly spaced in 1/rpm; a bar without a diameter: "
                        "its lobes 1 to 3)")
    g.add_argument("--depth-mm", metavar="START:STOP:N",
                   help="depths of cut in mm, N evenly spaced from START to STOP (inclusive) "
                        "or comma list (default: 20 depths from 0.5 to 3 times the smallest "
                        "analytic limit of the bare bar over the speeds)")
    g = p.add_argument_group("converged verdict")
    add_verdict(g, knocks=f"the small knock and one of {LARGE_KNOCK_M * 1e6:g} um")
    g.add_argument("--small-knock-only", action="store_true",
                   help="judge each cut from the small knock alone, without a large one")
    add_cutting(p.add_argument_group("regenerative cutting"))
    groups["run"].add_argument("--workers", type=int, metavar="N",
                               help="threads (default: every core)")
    p.set_defaults(func=_cmd_chatter_map)


def parse_depths_mm(text: str, name: str = "--depth-mm") -> list[float]:
    """'START:STOP:N' (N depths, both ends included) or a comma list, in mm, each checked
    (a depth of cut in (0, 1000] mm)."""
    if ":" in text:
        try:
            start, stop, count = text.split(":")
            start, stop, n = float(start), float(stop), float(count)
        except ValueError:
            raise ParameterError(f"{name} = {text!r} must be START:STOP:N (N depths from "
                                 "START to STOP) or a comma-separated list of numbers") from None
        n = check_int(f"{name} (its N)", n, 1, MAX_GRID_VALUES)
        check_depth(start, name)
        if not stop >= start:
            raise ParameterError(f"{name} = {text!r}: STOP must be >= START")
        values = np.round(np.linspace(start, stop, n), 12)
    else:
        values = parse_range(text, name)
    return [check_depth(float(v), name) for v in values]


def _check_not_for_a_map(args) -> None:
    for dest in NOT_FOR_A_MAP:
        if getattr(args, dest) is not None:
            flag = "--" + dest.replace("_", "-")
            raise ParameterError(f"{flag} does not apply to a chatter map: every cut starts in "
                                 "progress, knocked, and runs until its verdict (at most "
                                 "--max-run-s)")


def map_options(args, verdict: VerdictOptions) -> ChatterMapOptions:
    """The map's grid, cut and verdict of the command line, checked under its names."""
    rpm = None
    if args.rpm is not None:
        rpm = check_speeds("--rpm", parse_range(args.rpm, "--rpm"))
        for r in rpm:
            check_rpm(r, args)
    depths = None
    if args.depth_mm is not None:
        depths = [round(d * 1e-3, 15) for d in parse_depths_mm(args.depth_mm)]
        if np.any(np.diff(depths) <= 0):
            raise ParameterError(f"--depth-mm = {args.depth_mm!r} must increase, each depth "
                                 "once")
    check_workers(args.workers)
    cut = {k: v for k, v in cut_options(args).items() if k not in ("start", "bounded_fraction")}
    return ChatterMapOptions(rpm=rpm, depths_m=None if depths is None else tuple(depths),
                             **cut, verdict=verdict)


def map_verdict(args) -> VerdictOptions:
    """The verdict of the command line: the library's large knock unless --knock-um gives
    others or --small-knock-only none."""
    verdict = verdict_options(args)
    if args.small_knock_only and args.knock_um:
        raise ParameterError("--small-knock-only and --knock-um: give one (no large knock, "
                             "or these)")
    knocks = (LARGE_KNOCK_M,) if args.knock_um is None and not args.small_knock_only \
        else verdict.knocks_m
    # rounded so that --knock-um 20 is the library's 20e-6 m, not a neighbour of it
    return replace(verdict, knocks_m=tuple(round(k, 15) for k in knocks),
                   tolerance_m=round(verdict.tolerance_m, 15))


def _cmd_chatter_map(args) -> Outcome:
    _check_not_for_a_map(args)
    verdict = map_verdict(args)
    check_steps(verdict.max_duration_s, fixed_run_step(args.dt_s), ("--max-run-s", "--dt-s"))
    args.duration_s = verdict.max_duration_s  # the longest run, as the shared checks see it
    cases, _, _ = many_cases(args)
    options = map_options(args, verdict)
    ds = chatter_map(cases, options, integration=integration(args), execution=execution(args),
                     progress=progress_printer(args, "chatter-map", "cells"))
    summary = chatter_map_files(ds, args.out)

    def text(say) -> None:
        say(map_text(ds))
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def _mm(v: float) -> str:
    return f"{v * 1e3:.4g}" if math.isfinite(v) else "-"


def map_text(ds) -> str:
    """The map in words: per case and speed the chatter-free, first not chatter-free and
    onset depths and the bare-bar limit; what the cells did; the method."""
    lines = []
    for i, label in enumerate(ds["case"].values):
        lines += _case_lines(ds, i, str(label))
    lines.append("'-': none on the grid (every depth chatter-free, or no onset up to the "
                 "deepest)")
    a = ds.attrs
    lines.append(f"{a['cutting_law']}; speeds: {a['rpm_source']}; depths: {a['depth_source']}")
    lines.append(f"method: {a['method_text']}; {a['cells']} cells in {a['wall_time_s']:.1f} s")
    return "\n".join(lines)


def _case_lines(ds, i: int, label: str) -> list[str]:
    free = ds["chatter_free_depth_m"].values[i]
    mcf = float(ds["min_chatter_free_depth_m"].values[i])
    at = f" at {ds['rpm'].values[int(np.nanargmin(free))]:g} rpm" if np.isfinite(free).any() \
        else ""
    lines = [f"{label}: minimum chatter-free depth {_mm(mcf)} mm{at}",
             f"{'rpm':>8} {'chatter-free (mm)':>18} {'first not (mm)':>15} {'onset (mm)':>11} "
             f"{'bare-bar limit (mm)':>20}"]
    for j, r in enumerate(ds["rpm"].values):
        lines.append(f"{r:8g} {_mm(free[j]):>18} "
                     f"{_mm(ds['first_not_free_depth_m'].values[i, j]):>15} "
                     f"{_mm(ds['onset_depth_m'].values[i, j]):>11} "
                     f"{_mm(ds['host_analytic_limit_m'].values[i, j]):>20}")
    code, onset = ds["chatter_free"].values[i], ds["onset"].values[i]
    bounded = int(((code == 1) & (onset != 1)).sum())
    ball = (f" ({bounded} of them where a small knock grows and the ball bounds it)"
            if str(ds["bar"].values[i]) == "ball" else "")
    left = int(ds["left_cut"].values[i].any(axis=-1).sum())
    lines.append(f"  cells: {int((code == 1).sum())} chatter-free{ball}, "
                 f"{int((code == 0).sum())} not, {int((code == 2).sum())} undecided; the tool "
                 f"leaves the cut in {left}")
    return lines + [""]
