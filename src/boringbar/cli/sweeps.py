"""``boringbar sweep`` and ``boringbar lobes``: frequency sweeps and stability lobes."""

from __future__ import annotations

import math

import numpy as np

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.cases import parse_range
from boringbar.analysis.lobe_examples import examples as lobe_examples
from boringbar.analysis.lobes import (
    DEPTH_FLOOR,
    DEPTH_TOLERANCE,
    MAX_DEPTHS,
    PUBLISHED_DEPTH_STEP,
    LobesOptions,
    depth_grid,
    grid_index,
    lobes,
)
from boringbar.analysis.speeds import check_speeds, default_speeds
from boringbar.analysis.sweep import SweepOptions, default_ratios, sweep
from boringbar.cli.draws import add_draws, draws_text, uncertainty_options
from boringbar.cli.frf import analytic_lobes_outcome
from boringbar.cli.options import (
    AT_RPM_HELP,
    PATTERN_KEY,
    Outcome,
    add_common,
    add_cutting,
    add_verdict,
    check_dt,
    check_rpm,
    check_workers,
    cut_law,
    cut_options,
    execution,
    forces_and_ratios,
    initial_conditions,
    integration,
    many_cases,
    progress_printer,
    verdict_options,
    with_speed,
    wrote,
)
from boringbar.model.forcing import MAX_DEPTH, check_depth
from boringbar.report.outputs import lobes_files, sweep_files
from boringbar.simulate import HISTORY_ROWS


def add_sweep(sub) -> None:
    p = sub.add_parser("sweep", help="tip RMS and impact pattern against Omega/omega_n",
                       description="Frequency sweep of the bars (docs/model.md, section 6: "
                                   "the published study's on the published bar; yours with "
                                   "--system); writes DIR/sweep.nc and DIR/sweep.png (one "
                                   "DIR/sweep_F<F0>N.png per force when several).")
    groups = add_common(p, many=True)
    groups["run"].add_argument("--workers", type=int, metavar="N",
                               help="threads (default: every core)")
    p.set_defaults(func=_cmd_sweep)


def add_lobes(sub) -> None:
    p = sub.add_parser("lobes", help="stability lobes by time-domain simulation of cuts",
                       description="Stability lobes of the bars (docs/model.md, section 6: "
                                   "the published study's on the published bar; yours with "
                                   "--system): depth of cut against spindle speed, every grid "
                                   "point a "
                                   "regenerative cut; writes DIR/lobes.nc and DIR/lobes.png "
                                   "(with --examples also DIR/examples.nc and "
                                   "DIR/examples.png).")
    groups = add_common(p, many=True, harmonic=False, initial=False)
    g = p.add_argument_group("lobe grid")
    g.add_argument("--rpm", metavar="START:STOP:STEP",
                   help="spindle speeds in rev/min, START:STOP:STEP (inclusive) or comma list "
                        "(default: the bars' lobes 1 to 5, from 60 f1 / 6.1 to 60 f1 / 0.9, "
                        "10 speeds per lobe; published: 900:1600:50)")
    g.add_argument("--at-rpm", type=float, metavar="N", help=AT_RPM_HELP)
    g.add_argument("--analytic", action="store_true",
                   help="the classical frequency-domain lobes of the tip FRF instead of "
                        "simulated cuts (with --frf: of a measured FRF as it is); writes "
                        "DIR/lobes_analytic.json and .png (default --rpm: the bars' lobes 1 "
                        "to 5 as above; of a measured FRF, those of its most flexible mode)")
    g.add_argument("--depth-step-mm", type=float, metavar="MM",
                   help="depth-of-cut step in mm (default: --method search: geometric "
                        "steps of --depth-tolerance; scan: 0.01, published)")
    g.add_argument("--depth-tolerance", type=float, metavar="X",
                   help="instead of --depth-step-mm, each depth X above the one below, so a "
                        "limit is found to X of itself (default: 0.01 with --method search)")
    g.add_argument("--max-depth-mm", type=float, default=3.0, metavar="MM",
                   help="deepest cut tried in mm (default: 3)")
    g.add_argument("--method", choices=("scan", "search"), default="search",
                   help="search (default): doubling and bisection from the analytic limit "
                        "(assumes stability monotone below the bracket); scan: every depth "
                        "upwards (published)")
    g.add_argument("--successive", type=int, default=3, metavar="N",
                   help="a speed's scan ends after N successive chattering depths (default: 3)")
    g.add_argument("--criterion", choices=("growth", "zero", "bounded"),
                   help="how a cut is judged: growth (the converged verdict: a knock's growth "
                        "rate, run until certain, and the settled vibration within "
                        "--tolerance-um; the default), zero (published: the force reaches "
                        "zero within --duration-s; the default under --preset paper) or "
                        "bounded (also a steady amplitude above --bounded-fraction of the "
                        "feed); docs/chatter.md")
    add_verdict(p.add_argument_group("converged verdict (--criterion growth)"))
    add_draws(p.add_argument_group("chance of chatter (--draws)"))
    g = p.add_argument_group("regenerative cutting")
    add_cutting(g)
    groups["run"].add_argument("--workers", type=int, metavar="N",
                               help="threads (default: every core)")
    groups["output"].add_argument("--examples", action="store_true",
                                  help="rerun a stable and an unstable grid point of the "
                                       "first case with history: DIR/examples.nc, "
                                       "DIR/examples.png")
    p.set_defaults(func=_cmd_lobes)


def _cmd_sweep(args) -> Outcome:
    cases, bars, gaps = many_cases(args)
    forces, ratios = forces_and_ratios(args)
    if ratios is None:  # the library's default, resolved here to check the step against it
        ratios = default_ratios(cases)
    check_dt(args, [c.system for c in cases], max(ratios))

    initial = initial_conditions(args, gaps if "ball" in bars else [])
    ds = sweep(cases, SweepOptions(tuple(ratios), tuple(forces)),
               integration=integration(args, initial), execution=execution(args),
               progress=progress_printer(args, "sweep", "batches of runs"))
    summary = sweep_files(ds, args.out)

    def text(say) -> None:
        say(_sweep_text(ds))
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def short_pattern(name: str) -> str:
    """'2 symmetric' -> '2s', '3 asymmetric (period 2)' -> '3a/2', for the table."""
    name = str(name)
    fixed = {"": "", "no impact": "0", "sticking": "st", "no impact with sticking": "0+st",
             "non-uniform": "nu"}
    if name in fixed:
        return fixed[name]
    parts = name.replace("(period ", "").replace(")", "").split()
    code = parts[0] + ("s" if parts[1] == "symmetric" else "a")
    return code + (f"/{parts[2]}" if len(parts) > 2 else "")


def _sweep_text(ds) -> str:
    heads = []
    for label, bar, gap, fr in zip(ds["case"].values, ds["bar"].values, ds["gap_m"].values,
                                   ds["friction"].values, strict=True):
        heads.append(f"ball {gap * 1e3:g}/{fr}" if bar == "ball" else str(label))
    width = max(14, *(len(h) + 2 for h in heads))
    lines = []
    for j, force in enumerate(ds["force_n"].values):
        lines.append(f"F0 = {force:g} N: tip RMS (mm) [pattern]; ball columns: gap mm/friction")
        lines.append("ratio ".rjust(8) + "".join(h.rjust(width) for h in heads))
        for k, ratio in enumerate(ds["ratio"].values):
            cells = []
            for i in range(len(heads)):
                pat = short_pattern(ds["pattern"].values[i, j, k])
                cell = f"{ds['rms_tip_m'].values[i, j, k] * 1e3:.4f}"
                cells.append((cell + (f" [{pat}]" if pat else "")).rjust(width))
            lines.append(f"{ratio:7.3f} " + "".join(cells))
        lines.append("")
    lines.append(PATTERN_KEY)
    return "\n".join(lines)


#: lobes options (dest names, default None or False) that concern simulated cuts alone:
#: given with --analytic, which runs none, they are refused rather than left unread
SIMULATED_ONLY = ("dt_s", "stick_law", "depth_step_mm", "depth_tolerance", "criterion",
                  "tolerance_um", "knock_um", "confidence", "max_run_s", "draws", "seed",
                  "stiffness_cov", "damping_cov", "friction_spread", "restitution_spread",
                  "force_noise", "fixed_ball_start", "probability", "revolutions",
                  "delay_interp", "start", "bounded_fraction", "workers", "examples")


def _cmd_lobes(args) -> Outcome:
    if args.analytic:
        given = [d for d in SIMULATED_ONLY if getattr(args, d, None) not in (None, False)]
        if given:
            option = "--" + given[0].replace("_", "-")
            raise ParameterError(f"{option} with --analytic: it concerns simulated cuts, and "
                                 "the closed form runs none; leave out one of them")
        cut = cut_options(args)
        return analytic_lobes_outcome(args, cut_law(cut), cut["feed_m"])
    cases, _, _ = many_cases(args)
    options = _lobe_options(args, cases)
    integ = integration(args)
    ds = lobes(cases, options, integration=integ, execution=execution(args),
               progress=progress_printer(args, "lobes", "(case, speed) columns"))

    if args.at_rpm is not None:  # the figure drawn again from lobes.nc marks it too
        ds.attrs["at_rpm"] = float(args.at_rpm)
    exds = None
    if args.examples:
        exds = lobe_examples(ds, cases[0], options, integration=integ, rows=HISTORY_ROWS)
    summary = _at_rpm_summary(ds, lobes_files(ds, args.out, exds))
    examples = summary.get("examples", [])

    def text(say) -> None:
        say(_lobes_text(ds, summary))
        if draws_text(ds):
            say(draws_text(ds))
        for e in examples:
            verdict = (f"chatter (force first zero at {e['first_zero_time_s']:.3g} s)"
                       if e["chatter"] else "stable (force never zero)")
            say(f"example {e['example']}: {e['case']} at {e['rpm']:g} rpm, depth "
                  f"{e['depth_m'] * 1e3:g} mm: {verdict}")
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def _lobe_options(args, cases) -> LobesOptions:
    """The lobe grid and cut of the command line, checked under the options' names;
    the speeds, when --rpm is not given, are the cases' lobes (the library's rule)."""
    rpm = (default_speeds(cases, args.workpiece) if args.rpm is None
           else check_speeds("--rpm", parse_range(args.rpm, "--rpm")))
    for r in rpm:
        check_rpm(r, args)
    if args.at_rpm is not None:
        rpm = with_speed(rpm, check_rpm(args.at_rpm, args, "--at-rpm"))
    step, tol = args.depth_step_mm, args.depth_tolerance
    if depth_grid(args.method, step, tol, ("--depth-step-mm", "--depth-tolerance")) == "linear":
        step = check_depth(PUBLISHED_DEPTH_STEP * 1e3 if step is None else step,
                           "--depth-step-mm")
    else:
        tol = check_range("--depth-tolerance", DEPTH_TOLERANCE if tol is None else tol,
                          0.0, 0.5, lo_open=True)
    check_range("--max-depth-mm", args.max_depth_mm, DEPTH_FLOOR * 1e3 if step is None
                else step, MAX_DEPTH * 1e3, unit="mm")
    count = grid_index(args.max_depth_mm * 1e-3, None if step is None else step * 1e-3, tol)
    if count > MAX_DEPTHS:
        given = (f"--depth-step-mm = {step:g} mm" if step is not None
                 else f"--depth-tolerance = {tol:g}")
        raise ParameterError(f"{given} gives {count} depths up to --max-depth-mm = "
                             f"{args.max_depth_mm:g} mm; the allowed maximum is {MAX_DEPTHS}")
    check_int("--successive", args.successive, 1, 100)
    check_workers(args.workers)
    cut = cut_options(args)
    uncertainty = uncertainty_options(args)
    criterion = args.criterion
    if uncertainty is not None:  # draws are judged by the converged verdict alone
        if criterion not in (None, "growth"):
            raise ParameterError(f"--criterion = {criterion!r} with --draws: the chance of "
                                 "chatter is found by the converged verdict; use --criterion "
                                 "growth")
        criterion = "growth"
    return LobesOptions(tuple(rpm), args.method, criterion,
                        None if step is None else step * 1e-3, args.max_depth_mm * 1e-3,
                        args.successive, **cut, depth_tolerance=tol,
                        verdict=verdict_options(args), uncertainty=uncertainty)


def _at_rpm_summary(ds, summary: dict) -> dict:
    """The summary with the user's speed (``ds.attrs["at_rpm"]``, on the grid) and each
    case's limiting depth there (None: no chatter up to the deepest cut)."""
    if "at_rpm" not in ds.attrs:
        return summary
    at = float(ds.attrs["at_rpm"])
    j = int(np.flatnonzero(ds["rpm"].values == at)[0])
    # a lobe's depth can change sharply within a few rpm: the grid's speeds either side
    # say how far the answer holds if the spindle's speed drifts
    near = [k for k in (j - 1, j + 1) if 0 <= k < ds.sizes["rpm"]]
    for case in summary["cases"]:
        case["depth_at_rpm_m"] = case["speeds"][j]["limit_depth_m"]
        case["at_rpm_neighbours"] = [{"rpm": float(case["speeds"][k]["rpm"]),
                                      "limit_depth_m": case["speeds"][k]["limit_depth_m"]}
                                     for k in near]
    return {**summary, "at_rpm": at}


def _neighbour_words(near: list, mm) -> str:
    """" (grid neighbours 1488 rpm: 0.0653 mm, 1508 rpm: 0.0705 mm)", or "" without."""
    if not near:
        return ""
    return " (grid neighbours " + ", ".join(
        f"{n['rpm']:g} rpm: " + (f"{mm(n['limit_depth_m'])} mm" if n["limit_depth_m"]
                                 is not None else "-") for n in near) + ")"


def _lobes_text(ds, summary: dict) -> str:
    lines = []
    analytic = ds["analytic_limit_m"].values if "analytic_limit_m" in ds else None
    host = ds["host_analytic_limit_m"].values if "host_analytic_limit_m" in ds else None
    hosted = False
    depths = ds["depth_m"].values
    chosen = ds["verdict_bounded" if ds.attrs["criterion"] == "bounded" else "verdict"].values
    onset = ds["onset_depth_m"].values if "onset_depth_m" in ds else None

    def mm(v: float) -> str:
        return f"{v * 1e3:.4g}" if math.isfinite(v) else "-"  # 1 % of a 0.03 mm limit

    for i, label in enumerate(ds["case"].values):
        limit = ds["limit_depth_m"].values[i]
        first = ds["first_unstable_depth_m"].values[i]
        mcf = float(ds["min_chatter_free_depth_m"].values[i])
        at = (f" at {ds['rpm'].values[int(np.nanargmin(limit))]:g} rpm"
              if np.isfinite(limit).any() else "")
        mine = ""
        if "at_rpm" in summary:
            d = summary["cases"][i]["depth_at_rpm_m"]
            mine = (f"; at your speed {summary['at_rpm']:g} rpm: "
                    + (f"{mm(d)} mm" if d is not None else "no chatter up to the deepest cut")
                    + _neighbour_words(summary["cases"][i]["at_rpm_neighbours"], mm))
        lines.append(f"{label}: minimum chatter-free depth {mm(mcf)} mm{at}{mine}")
        lines.append(f"{'rpm':>8} {'limit (mm)':>12} {'first unstable (mm)':>20} "
                     f"{'analytic (mm)':>14}" + (f" {'onset (mm)':>12}" if onset is not None
                                                else ""))
        islands = []
        for j, r in enumerate(ds["rpm"].values):
            a = math.nan if analytic is None else float(analytic[i, j])
            star = ""
            if not math.isfinite(a) and host is not None and math.isfinite(host[i, j]):
                a, star, hosted = float(host[i, j]), "*", True
            lines.append(f"{r:8g} {mm(limit[j]):>12} {mm(first[j]):>20} {mm(a) + star:>14}"
                         + (f" {mm(onset[i, j]):>12}" if onset is not None else ""))
            above = (depths > first[j]) & (chosen[i, j] == 1)
            if math.isfinite(first[j]) and above.any():
                islands.append(f"{r:g}")
        if islands:
            lines.append(f"  chatter-free again above the first depth that chatters, at "
                         f"{', '.join(islands)} rpm")
        lines.append("")
    lines.append("'-': no chatter up to the deepest cut tried (or no analytic limit)")
    if hosted:
        lines.append("*: the free ball's linear host (the bar with the ball held by its "
                     "friction, or without friction not acting): where a small vibration "
                     "starts to grow; the ball's own limit is simulated")
    lines.append(f"{ds.attrs.get('cutting_law', 'linear law')}; method: "
                 f"{ds.attrs['method_text']}; {ds.attrs['runs']} runs in "
                 f"{ds.attrs['wall_time_s']:.1f} s")
    return "\n".join(lines)
