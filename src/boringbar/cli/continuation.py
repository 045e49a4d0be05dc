"""``boringbar continue``: the orbit map of a problem by pseudo-arclength continuation."""

from __future__ import annotations

import argparse
import math

from boringbar._validate import ParameterError
from boringbar.analysis.continuation import (
    BRUTE_FORCE,
    ContinuationOptions,
    brute_force,
    continuation,
    summary,
)
from boringbar.cli.cut_orbits import cut_outcome
from boringbar.cli.options import (
    Outcome,
    add_common,
    add_cutting,
    check_gap,
    integration,
    one_bar,
    system_overrides,
    wrote,
)
from boringbar.io import save_figure_atomic, write_json_atomic, write_netcdf_atomic
from boringbar.model.forcing import Harmonic, check_force, check_ratio
from boringbar.model.system import make_system
from boringbar.orbits.branch import MAX_STEP, PARAMETERS
from boringbar.plot.orbits import plot_continuation


def add_continue(sub) -> None:
    """Register ``boringbar continue``."""
    p = sub.add_parser("continue", help="continue a periodic orbit in one parameter, with "
                                        "Floquet stability and bifurcations",
                       description="Shooting on the stroboscopic map with the exact flow and "
                                   "saltation-matrix monodromy, pseudo-arclength continuation "
                                   "in --parameter from its value (--force-n, --ratio, ...) to "
                                   "the end of --range (docs/continuation.md).  Orbits with "
                                   "stick phases or wall contact end the branch (refused).  "
                                   "Writes DIR/continuation.nc, .json and .png.")
    groups = add_common(p, many=False, initial=False)
    g = groups["run"]
    g.add_argument("--parameter", choices=(*PARAMETERS, "depth-mm", "rpm"), default=None,
                   help="the continued parameter (default: force-n; with --cut, depth-mm)")
    g.add_argument("--cut", action="store_true",
                   help="the chatter orbits of a regenerative cut instead: each bar's branch "
                        "from its Hopf point, in depth at --rpm over --range A:B (mm), or "
                        "with --parameter rpm in speed at --depth-mm over --range A:B (rpm), "
                        "from the Hopf point nearest --rpm (default: A); with folds, the tool "
                        "leaving the cut, the ball's grazing, period doublings and tori; "
                        "writes DIR/chatter_orbits.nc, .json and .png")
    g.add_argument("--rpm", type=float, metavar="RPM", help="with --cut: the spindle speed")
    g.add_argument("--depth-mm", type=float, metavar="MM",
                   help="with --cut --parameter rpm: the depth of cut")
    g.add_argument("--lobe", type=int, metavar="J",
                   help="with --cut: start from lobe J's Hopf point (default: the lowest "
                        "lobes')")
    add_cutting(p.add_argument_group("cut (with --cut)"))
    g.add_argument("--range", required=True, metavar="START:STOP",
                   help="START sets the parameter's first value, STOP the branch's end; "
                        "LO:START:HI maps [LO, HI] from an orbit at START inside it "
                        "(continued both ways)")
    g.add_argument("--periods", type=int, default=1, metavar="K", help="period-k orbits")
    g.add_argument("--max-points", type=int, default=None, metavar="N",
                   help="point budget of a branch (default: from --max-step, enough to "
                        "cross the range 12 times at the largest step)")
    g.add_argument("--step", type=float, default=0.02, metavar="S",
                   help="first step, relative to the range (default: 0.02)")
    g.add_argument("--max-step", type=float, default=MAX_STEP, metavar="S",
                   help=f"largest step, relative to the range (default: {MAX_STEP})")
    g.add_argument("--overlay", type=int, nargs="?", const=21, metavar="N",
                   help="draw the brute-force bifurcation diagram of the same case under the "
                        "branch: N values over --range (default 21), forward and backward "
                        "from rest, with --duration-s, --dt-s and --integrator (the last "
                        "half of each run sampled); force-n or ratio only")
    g.add_argument("--switch", action=argparse.BooleanOptionalAction, default=True,
                   help="follow the branches born at branch points, period doublings and "
                        "grazings (default: on)")
    g.add_argument("--seeds", type=int, default=3, metavar="N",
                   help="brute-force attractors at N values spread over --range seed "
                        "branches; those at 2N other values are checked against the map "
                        "(the free ball; default 3, 0: none)")
    g.add_argument("--max-branches", type=int, default=24, metavar="N",
                   help="at most N branches in the map (default 24)")
    g.add_argument("--return-periods", type=int, default=200, metavar="N",
                   help="the return check: the exact integrator runs N periods from every "
                        "stable point, perturbed by 1e-7, and must come back within 1e-6 "
                        "(default 200, 0: none)")
    g.add_argument("--start-from", choices=("simulation", "masri-caughey"),
                   default="simulation", help="first guess (default: a settled exact run)")
    p.set_defaults(func=_cmd_continue)


def _range(text: str) -> tuple[float, float, float | None]:
    """(start, stop, other end or None) of --range START:STOP or LO:START:HI."""
    parts = (text or "").split(":")
    try:
        values = [float(x) for x in parts]
    except ValueError:
        values = []
    if len(values) not in (2, 3):
        raise ParameterError(f"--range = {text!r} must be START:STOP or LO:START:HI "
                             "(two or three numbers)")
    if not all(math.isfinite(v) for v in values) or values[0] == values[1]:
        raise ParameterError(f"--range = {text!r}: the numbers must be finite and START must "
                             "differ from STOP")
    if len(values) == 2:
        return values[0], values[1], None
    lo, start, hi = values
    if not lo < start < hi:
        raise ParameterError(f"--range = {text!r}: LO:START:HI needs LO < START < HI")
    return start, hi, lo


def _cmd_continue(args) -> Outcome:
    if args.cut:
        return cut_outcome(args)
    if args.parameter in ("depth-mm", "rpm"):
        raise ParameterError(f"--parameter {args.parameter} continues a cut's orbits: add "
                             "--cut")
    if args.rpm is not None or args.lobe is not None or args.depth_mm is not None:
        raise ParameterError("--rpm, --depth-mm and --lobe describe a cut: add --cut")
    args.parameter = args.parameter or "force-n"
    bar, friction_on = one_bar(args, "continue")
    start, stop, other_end = _range(args.range)
    force = 10.0 if args.force_n is None else args.force_n
    ratio = 1.0 if args.ratio is None else args.ratio
    gap = 0.5 if args.gap_mm is None else args.gap_mm
    kw = system_overrides(args)
    name = args.parameter
    force, ratio = (start, ratio) if name == "force-n" else (force, start if name == "ratio"
                                                            else ratio)
    gap = start if name == "gap-mm" else gap
    if name == "restitution":
        kw["restitution"] = start
    if name == "friction-force-n":
        kw["friction_force_n"] = start
    if name == "ball-mass-g":
        raise ParameterError("--parameter ball-mass-g: give it through the Python API "
                             "(the command line sets the ball by --ball)")
    check_force(force)
    check_ratio(ratio)
    if args.overlay is not None and (name not in BRUTE_FORCE or not 2 <= args.overlay <= 1000):
        raise ParameterError(f"--overlay {args.overlay} with --parameter {name}: the overlay "
                             f"needs --parameter {' or '.join(BRUTE_FORCE)} and N in [2, 1000]")
    if bar == "ball":
        kw.update(gap_m=check_gap(gap, args), friction=friction_on or name == "friction-force-n")
    system = make_system(bar, args.preset, **kw)
    options = ContinuationOptions(parameter=name, stop=stop, force_n=force, ratio=ratio,
                                  periods=args.periods, step=args.step,
                                  max_step=args.max_step, max_points=args.max_points,
                                  switch=args.switch, seeds=args.seeds,
                                  max_branches=args.max_branches, start=args.start_from,
                                  other_end=other_end, return_periods=args.return_periods)
    ds = continuation(system, Harmonic(force, ratio=ratio), options=options)
    out = summary(ds)
    files = {"netcdf": str(write_netcdf_atomic(ds, f"{args.out}/continuation.nc"))}
    bf = None
    if args.overlay is not None:
        bf = brute_force(system, options, start if other_end is None else other_end,
                         args.overlay, integration(args, steady_fraction=0.5))
        files["overlay"] = str(write_netcdf_atomic(bf, f"{args.out}/overlay.nc"))
    files["figure"] = str(save_figure_atomic(plot_continuation(ds, overlay=bf),
                                             f"{args.out}/continuation.png", dpi=130))
    files["json"] = f"{args.out}/continuation.json"
    out["files"] = files
    write_json_atomic(out, files["json"])

    def text(say) -> None:
        for i, b in enumerate(out["branches"]):
            say(_branch_line(i, b, name))
            for e in b["events"]:
                say(f"  {e['kind']} at {name} = {e['value']:.6g}")
        for note in out["notes"]:
            say(f"note: {note}")
        for c in out["attractor_check"]:
            say(_check_line(c, name))
        for line in _return_lines(out["return_check"], name, args.return_periods):
            say(line)
        say(wrote(files))

    return Outcome(out, text)


def _return_lines(rc: dict, name: str, periods: int) -> list[str]:
    """The return check: one line, and one a stable point that did not come back."""
    if not rc["checked_count"]:
        return []
    head = (f"return check: {rc['checked_count']} stable points, {len(rc['failed'])} not "
            f"back within 1e-6 after {periods} periods (largest distance "
            f"{rc['largest_relative']:.2g})")
    return [head] + [f"  branch {f['branch']} at {name} = {f['value']:.6g}: "
                     f"{f['distance_relative']:.2g}" for f in rc["failed"]]


def _branch_line(i: int, b: dict, name: str) -> str:
    """One line of a branch: its points, range, stability, birth and stop."""
    pts = b["points"]
    if not pts:
        return f"branch {i}: no points; stop: {b['stop']}"
    vals = [p["value"] for p in pts]
    born = b.get("born", {"kind": "start", "value": vals[0]})
    parent = "" if b.get("parent") is None else f" on branch {b['parent']}"
    mirror = "" if b.get("mirror") is None else f", the mirror image of branch {b['mirror']}"
    return (f"branch {i} (period {b.get('periods', 1)}, born at {born['kind']} "
            f"{born['value']:.6g}{parent}{mirror}): {len(pts)} points, {name} "
            f"{min(vals):.6g} .. {max(vals):.6g}, {sum(p['stable'] for p in pts)} stable; "
            f"stop: {b['stop']}")


def _check_line(c: dict, name: str) -> str:
    """One line of the attractor check."""
    where = (f"on stable branch {c['branch']}" if c["on_stable_branch"] else
             f"NOT on a stable branch (nearest {c['distance']:.2g})")
    return (f"attractor at {name} = {c['value']:.6g} (period {c['periods']}, "
            f"{c['impacts']:.3g} impacts a period): {where}")
