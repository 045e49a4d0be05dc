"""``boringbar continue --cut``: the chatter orbit map of a system's bars, in depth at one
speed or in speed at one depth."""

from __future__ import annotations

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.cut_continuation import (
    MAX_RPM,
    CutContinuationOptions,
    cut_continuation,
)
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
from boringbar.model.forcing import MAX_DEPTH, Regenerative
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


def cut_range(text: str, what: str = "depths in mm", top: float = 1000.0,
              positive: bool = False) -> tuple[float, float]:
    """--range A:B of ``what``, 0 <= A < B <= ``top`` (0 < A with ``positive``)."""
    try:
        lo, hi = (float(v) for v in (text or "").split(":"))
    except ValueError:
        raise ParameterError(f"--range = {text!r} must be A:B, {what} (two numbers)") \
            from None
    if not (0.0 < lo if positive else 0.0 <= lo) or not lo < hi <= top:
        raise ParameterError(f"--range = {text!r}: {what} with {'0 <' if positive else '0 <='}"
                             f" A < B <= {top:g}")
    return lo, hi


def cut_outcome(args) -> Outcome:
    parameter = args.parameter or "depth-mm"
    if parameter not in ("depth-mm", "rpm"):
        raise ParameterError(f"--parameter {parameter} with --cut: a cut's orbits are "
                             "continued in depth-mm (at --rpm) or rpm (at --depth-mm)")
    in_depth = parameter == "depth-mm"
    if in_depth and args.rpm is None:
        raise ParameterError("--cut needs --rpm N, the spindle speed (rev/min, > 0)")
    if not in_depth and args.depth_mm is None:
        raise ParameterError("--cut --parameter rpm needs --depth-mm B, the depth of cut "
                             "(mm, > 0)")
    if in_depth and args.depth_mm is not None:
        raise ParameterError("--depth-mm with --parameter depth-mm: the depths are --range's")
    if in_depth:
        lo, hi = cut_range(args.range)
        window, depth = (lo * 1e-3, hi * 1e-3), hi * 1e-3
        rpm = check_rpm(args.rpm, args)
    else:
        window = cut_range(args.range, "speeds in rpm", MAX_RPM, positive=True)
        for end in window:
            check_rpm(end, args, "--range")
        depth = check_range("--depth-mm", args.depth_mm, 0.0, MAX_DEPTH * 1e3, lo_open=True,
                            unit="mm") * 1e-3
        rpm = window[0] if args.rpm is None else check_rpm(args.rpm, args)
    if args.lobe is not None:
        check_int("--lobe", args.lobe, 0, 200)
    if args.max_points is not None:
        check_int("--max-points", args.max_points, 2, 10_000)
    cut = cut_options(args)
    forcing = Regenerative(depth_m=depth, rpm=rpm, kr_pa=cut.get("kr_pa", 850e6),
                           workpiece=cut.get("workpiece"), feed_m=cut["feed_m"],
                           revolutions=cut["revolutions"])
    where = ({"depth_range_m": window} if in_depth
             else {"parameter": "rpm", "speed_range_rpm": window})
    options = CutContinuationOptions(**where, lobe=args.lobe,
                                     max_points=args.max_points or MAX_POINTS)
    out = chatter_orbit_files(cut_continuation(cut_systems(args), forcing, options), args.out)
    return Outcome(out, lambda say: _say(say, out))


def _say(say, out: dict) -> None:
    held = (f"at {out['rpm']:g} rpm" if out["parameter"] == "depth"
            else f"at a depth of {out['depth_mm']:.6g} mm")
    say(f"chatter orbits {held} ({out['method']})")
    for c in out["cases"]:
        say(f"{c['case']}: {c['points']} orbits; {c['stop']}")
        for e in c["events"]:
            what = e["kind"] + (f" ({e['detail']})" if e["detail"] else "")
            say(f"  {what} at depth {e['depth_mm']:.6g} mm and {e['rpm']:.8g} rpm, amplitude "
                f"{e['amplitude_mm'] * 1e3:.4g} um, {e['frequency_hz']:.6g} Hz")
    say(wrote(out["files"]))
