"""``boringbar continue --cut``: the chatter orbit map of a system's bars at one speed."""

from __future__ import annotations

from boringbar._validate import ParameterError, check_int
from boringbar.analysis.cut_continuation import CutContinuationOptions, cut_continuation
from boringbar.cli.options import (
    Outcome,
    check_common,
    check_gap,
    check_rpm,
    cut_options,
    default_bars,
    gap_default_mm,
    parse_words,
    system_overrides,
    wrote,
)
from boringbar.model.forcing import Regenerative
from boringbar.model.system import BAR_KINDS, make_system
from boringbar.orbits.cut_branch import MAX_POINTS
from boringbar.report.outputs import chatter_orbit_files


def cut_systems(args) -> dict:
    """The bars of the map: --bar, by default every bar the system file has (the solid,
    TMD and ball bars of the published one); the ball with --gap-mm and --friction."""
    bars = parse_words(args.bar, "--bar", BAR_KINDS, default_bars(args, many=True))
    check_common(args, bars)
    friction = parse_words(args.friction, "--friction", ("on", "off"), ["on"])
    if len(friction) != 1:
        raise ParameterError(f"--friction = {args.friction!r} must be one of on, off")
    kw = system_overrides(args)
    out = {}
    for bar in bars:
        extra = {}
        if bar == "ball":
            gap = gap_default_mm(args) if args.gap_mm is None else float(args.gap_mm)
            extra = {"gap_m": check_gap(gap, args), "friction": friction[0] == "on"}
        out[bar] = make_system(bar, args.preset, **kw, **extra)
    return out


def cut_range(text: str) -> tuple[float, float]:
    """--range A:B of depths in mm, as (lo, hi) in m."""
    try:
        lo, hi = (float(v) for v in (text or "").split(":"))
    except ValueError:
        raise ParameterError(f"--range = {text!r} must be A:B, depths in mm (two numbers)") \
            from None
    if not 0.0 <= lo < hi <= 1000.0:
        raise ParameterError(f"--range = {text!r}: depths in mm with 0 <= A < B <= 1000")
    return lo * 1e-3, hi * 1e-3


def cut_outcome(args) -> Outcome:
    if args.parameter != "depth-mm":
        raise ParameterError(f"--parameter {args.parameter} with --cut: a cut's orbits are "
                             "continued in depth-mm")
    if args.rpm is None:
        raise ParameterError("--cut needs --rpm N, the spindle speed (rev/min, > 0)")
    rpm = check_rpm(args.rpm, args)
    depth_range = cut_range(args.range)
    if args.lobe is not None:
        check_int("--lobe", args.lobe, 0, 200)
    if args.max_points is not None:
        check_int("--max-points", args.max_points, 2, 10_000)
    cut = cut_options(args)
    forcing = Regenerative(depth_m=depth_range[1], rpm=rpm, kr_pa=cut.get("kr_pa", 850e6),
                           workpiece=cut.get("workpiece"), feed_m=cut["feed_m"],
                           revolutions=cut["revolutions"])
    options = CutContinuationOptions(depth_range_m=depth_range, lobe=args.lobe,
                                     max_points=args.max_points or MAX_POINTS)
    out = chatter_orbit_files(cut_continuation(cut_systems(args), forcing, options), args.out)
    files = out["files"]

    def text(say) -> None:
        say(f"chatter orbits at {rpm:g} rpm ({out['method']})")
        for c in out["cases"]:
            say(f"{c['case']}: {c['points']} orbits; {c['stop']}")
            for e in c["events"]:
                what = e["kind"] + (f" ({e['detail']})" if e["detail"] else "")
                say(f"  {what} at depth {e['depth_mm']:.6g} mm, amplitude "
                    f"{e['amplitude_mm'] * 1e3:.4g} um, {e['frequency_hz']:.6g} Hz")
        say(wrote(files))

    return Outcome(out, text)
