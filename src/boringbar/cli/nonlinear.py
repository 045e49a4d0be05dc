"""``boringbar bifurcation``, ``basins`` and ``sensitivity``: the nonlinear analyses."""

from __future__ import annotations

import argparse
import math

import numpy as np

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.basins import MAX_BASIN_CELLS, BasinOptions, basins, check_cells
from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation, with_hysteresis
from boringbar.analysis.cases import parse_range
from boringbar.analysis.sensitivity import (
    KINDS,
    MAX_STARTS,
    Cuts,
    SensitivityOptions,
    sensitivity,
    with_cuts,
)
from boringbar.cli.options import (
    CUT_ONLY,
    PATTERN_KEY,
    Outcome,
    add_common,
    add_cutting,
    add_steady_fraction,
    check_dt,
    check_gap,
    check_rpm,
    check_workers,
    cut_options,
    execution,
    forces_and_ratios,
    gap_default_mm,
    initial_conditions,
    integration,
    one_bar,
    parse_numbers,
    parse_words,
    progress_printer,
    system_overrides,
    wrote,
)
from boringbar.cli.sweeps import short_pattern
from boringbar.model.dampers import MAX_GAP
from boringbar.model.forcing import MAX_FORCE, MAX_RATIO, check_depth, check_force, check_ratio
from boringbar.model.system import BALLS, make_system
from boringbar.report.outputs import basins_files, bifurcation_files, sensitivity_files
from boringbar.simulate import MAX_INITIAL_DISPLACEMENT, MAX_INITIAL_VELOCITY

#: bifurcation's published sweep: F0 from 5 to 50 N in 1 N steps
PUBLISHED_FORCES = "5:50:1"


def add_bifurcation(sub) -> None:
    p = sub.add_parser("bifurcation",
                       help="Poincare samples of the tip against F0 (or Omega/omega_n, gap, e)",
                       description="Bifurcation diagram by continuation (docs/model.md, section "
                                   "6): one run per value of the swept parameter, each from the "
                                   "previous run's final state (forcing phase continuous), forward"
                                   " and then backward; stroboscopic Poincare samples of the tip "
                                   "(Omega t = 0 mod 2 pi) over the last --steady-fraction of each"
                                   " run.  Exactly one of --force-n, --ratio, --gap-mm, "
                                   "--restitution is swept, written START:STOP:STEP (inclusive) or"
                                   " as a comma list in sweep order; the others take one value.  "
                                   "Default: --force-n 5:50:1 at --ratio 1 (published).  Writes "
                                   "DIR/bifurcation.nc and DIR/bifurcation.png.")
    groups = add_common(p, many=False, harmonic=False, ranges=True)
    g = groups["run"]
    g.add_argument("--force-n", metavar="N|START:STOP:STEP",
                   help=f"harmonic force amplitude F0 in N (default: {PUBLISHED_FORCES} swept, "
                        "published; 10 when another parameter is swept)")
    g.add_argument("--ratio", metavar="R|START:STOP:STEP",
                   help="Omega/omega_n of the host bar (default: 1.0)")
    add_steady_fraction(g)
    g.add_argument("--no-backward", action="store_true",
                   help="forward sweep only (then no hysteresis ranges)")
    p.set_defaults(func=_cmd_bifurcation)


def add_basins(sub) -> None:
    p = sub.add_parser("basins", help="basins of attraction over initial tip displacement x "
                                      "velocity",
                       description="Basins of attraction (docs/model.md, section 6): one run per "
                                   "initial tip displacement x initial tip velocity of a grid "
                                   "(ball centred and at rest unless --ball-position-mm / "
                                   "--ball-velocity-m-s), the final motions grouped into "
                                   "attractors by Poincare samples, impact pattern and RMS.  "
                                   "Grids are LO:HI:COUNT: COUNT values from LO to HI, both "
                                   "included (a count, not a step).  Published: 30 x 30 over "
                                   "-1.5..1.5 mm x -1.5..1.5 m/s, 2 s runs, at 10 N, r = 1.01 "
                                   "(gap 0.5 mm, friction off and on) and 20 N, r = 1.00 (gap "
                                   "0.5 mm, friction off).  Writes DIR/basins.nc and "
                                   "DIR/basins.png: the basin map beside the Poincare map of "
                                   "the run from --poincare-from.")
    groups = add_common(p, many=False, initial=False)
    g = groups["run"]
    add_steady_fraction(g)
    g.add_argument("--workers", type=int, metavar="N", help="threads (default: every core)")
    g = p.add_argument_group("initial conditions")
    g.add_argument("--displacement-mm", default="-1.5:1.5:30", metavar="LO:HI:COUNT",
                   help="initial tip displacements in mm: COUNT values from LO to HI, both "
                        "included (default: -1.5:1.5:30, published)")
    g.add_argument("--velocity-m-s", default="-1.5:1.5:30", metavar="LO:HI:COUNT",
                   help="initial tip velocities in m/s: COUNT values from LO to HI, both "
                        "included (default: -1.5:1.5:30, published)")
    g.add_argument("--ball-position-mm", type=float, metavar="MM",
                   help="ball position relative to the cavity centre, in [-gap/2, gap/2] "
                        "(default: 0)")
    g.add_argument("--ball-velocity-m-s", type=float, metavar="M/S",
                   help="ball velocity relative to the bar (default: 0)")
    g.add_argument("--poincare-from", default="0.5,0.5", metavar="MM,M/S",
                   help="initial tip displacement (mm) and velocity (m/s) of the run whose "
                        "Poincare map is drawn beside the basins (default: 0.5,0.5)")
    p.set_defaults(func=_cmd_basins)


def add_sensitivity(sub) -> None:
    p = sub.add_parser("sensitivity", help="tip RMS (and chatter of cuts) for several values "
                                           "of one parameter",
                       description="Sensitivity study (docs/model.md, section 6): KIND varies one "
                                   "thing, everything else fixed.  ball: carbide,steel; "
                                   "friction_number: 0.2,0.4,0.6,0.8 (read as the preset reads "
                                   "it; friction on); restitution: 0.6,0.7,0.8; initial: "
                                   "initial conditions MM/M_S (tip displacement in mm / tip "
                                   "velocity in m/s, optionally /Y_MM/Y_M_S for the ball), "
                                   "default 0.5/0.5,1/1.  Harmonic runs over --force-n x "
                                   "--ratios for each value; with --cut-rpm or --depths-mm "
                                   "also cuts at one spindle speed over a few depths.  Writes "
                                   "DIR/sensitivity.nc and DIR/sensitivity.png.")
    p.add_argument("kind", choices=KINDS, metavar="KIND", help=" | ".join(KINDS))
    groups = add_common(p, many=False, harmonic=False, initial=False)
    g = groups["run"]
    g.add_argument("--values", metavar="V,...",
                   help="the values of KIND, comma list (default: the published ones)")
    g.add_argument("--force-n", default="10", metavar="N,...",
                   help="harmonic force amplitudes F0 in N, comma list (default: 10)")
    g.add_argument("--ratios", default="0.95:1.05:0.01", metavar="START:STOP:STEP",
                   help="Omega/omega_n values, START:STOP:STEP (inclusive) or comma list "
                        "(default: 0.95:1.05:0.01)")
    g.add_argument("--starts", type=int, default=0, metavar="K",
                   help="run each harmonic point again from K starts, the ball at rest "
                        "across the cavity, to show a rattling ball's spread (0 or 2-64; "
                        "default 0)")
    g.add_argument("--workers", type=int, metavar="N", help="threads (default: every core)")
    g = p.add_argument_group("regenerative cuts (only with --cut-rpm or --depths-mm)")
    g.add_argument("--cut-rpm", type=float, metavar="RPM",
                   help="spindle speed in rev/min (default: 1200, published)")
    g.add_argument("--depths-mm", metavar="START:STOP:STEP",
                   help="depths of cut in mm, START:STOP:STEP (inclusive) or comma list "
                        "(default: 0.05:0.10:0.01, published)")
    add_cutting(g)
    p.set_defaults(func=_cmd_sensitivity)


#: What bifurcation can sweep: option -> (library parameter, SI per option unit,
#: allowed range (lo, hi, lo_open, hi_open), unit).
SWEEPABLE = {
    "--force-n": ("force", 1.0, (0.0, MAX_FORCE, False, False), "N"),
    "--ratio": ("ratio", 1.0, (0.0, MAX_RATIO, True, False), ""),
    "--gap-mm": ("gap", 1e-3, (0.0, MAX_GAP * 1e3, True, False), "mm"),
    "--restitution": ("restitution", 1.0, (0.0, 1.0, False, False), ""),
}


def _dest(option: str) -> str:
    return option[2:].replace("-", "_")


def _check_value(option: str, value: float) -> float:
    lo, hi, lo_open, hi_open = SWEEPABLE[option][2]
    return check_range(option, value, lo, hi, lo_open=lo_open, hi_open=hi_open,
                       unit=SWEEPABLE[option][3])


def _swept(args) -> tuple[str, np.ndarray]:
    """The one swept option of bifurcation and its values (in the option's unit),
    checked.  Every option of SWEEPABLE in ``args`` becomes a float (the swept
    one its first value), so the common checks apply."""

    ranges = {}
    for option in SWEEPABLE:
        text = getattr(args, _dest(option))
        if text is None:
            continue
        if ":" in text or "," in text:
            ranges[option] = parse_range(text, option)
        else:
            setattr(args, _dest(option), _check_value(option, text))
    if len(ranges) > 1:
        both = "both" if len(ranges) == 2 else "all"
        raise ParameterError(f"{' and '.join(ranges)} are {both} ranges: a bifurcation sweeps "
                             "one parameter (START:STOP:STEP or a list), give the others one "
                             "value")
    if not ranges:
        if args.force_n is not None:
            raise ParameterError(f"--force-n = {args.force_n:g} is one value and nothing is "
                                 f"swept: give one of {', '.join(SWEEPABLE)} as "
                                 "START:STOP:STEP")
        ranges["--force-n"] = parse_range(PUBLISHED_FORCES, "--force-n")
    (option, values), = ranges.items()
    step = np.diff(values)
    if not (np.all(step > 0) or np.all(step < 0)):
        raise ParameterError(f"{option} = {getattr(args, _dest(option))!r} must be strictly "
                             "increasing or decreasing (the continuation visits the values "
                             "in order)")
    for v in values:
        _check_value(option, float(v))
    setattr(args, _dest(option), float(values[0]))
    return option, values


def _cmd_bifurcation(args) -> Outcome:
    args = argparse.Namespace(**vars(args))  # _swept turns the strings into numbers
    option, values = _swept(args)
    bar, friction_on = one_bar(args, "bifurcation")
    check_range("--steady-fraction", args.steady_fraction, 0, 1, lo_open=True)
    parameter, si = SWEEPABLE[option][:2]
    fixed_gap = gap_default_mm(args) if args.gap_mm is None else args.gap_mm
    gaps = values if option == "--gap-mm" else [fixed_gap]
    gaps = [check_gap(g, args) for g in gaps]
    force = 10.0 if args.force_n is None else args.force_n
    ratio = 1.0 if args.ratio is None else args.ratio

    kw = system_overrides(args)
    if bar == "ball":
        kw.update(gap_m=gaps[0], friction=friction_on)
    target = make_system(bar, args.preset, **kw)
    if parameter in ("gap", "restitution"):
        keyword = {"gap": "gap_m"}.get(parameter, parameter)  # make_system's name for it

        def target(value):  # the factory: one System per value
            return make_system(bar, args.preset, **{**kw, keyword: value})
    options = BifurcationOptions(parameter, tuple(values * si), force, ratio,
                                 backward=not args.no_backward,
                                 units="m" if parameter == "gap" else "1")
    initial = initial_conditions(args, gaps if bar == "ball" else [])
    ds = bifurcation(target, options,
                     integration=integration(args, initial, steady_fraction=args.steady_fraction),
                     progress=progress_printer(args, "bifurcation", "continuations"))
    ds = with_hysteresis(ds)
    ds.attrs.update(preset=args.preset, bar=bar, swept_option=option)

    summary = bifurcation_files(ds, args.out)

    def text(say) -> None:
        say(_bifurcation_text(ds, summary["hysteresis_ranges"]))
        say(wrote(summary["files"]))

    return Outcome(summary, text)


#: How bifurcation shows each parameter: (label, unit, option units per SI unit).
PARAMETER_DISPLAY = {"force": ("F0", "N", 1.0), "ratio": ("Omega/omega_n", "", 1.0),
                     "gap": ("gap", "mm", 1e3), "restitution": ("e", "", 1.0)}


def _bifurcation_text(ds, ranges) -> str:
    name, unit, k = PARAMETER_DISPLAY[ds.attrs["parameter"]]
    dirs = [str(d) for d in ds["direction"].values]
    lines = [f"bifurcation over {name}{f' ({unit})' if unit else ''}: Poincare verdict, "
             "tip RMS (mm) [pattern]",
             f"{name:>10} " + "".join(f"{d:>36}" for d in dirs)]
    for i, v in enumerate(ds["value"].values):
        cells = []
        for d in dirs:
            row = ds.sel(direction=d).isel(value=i)
            pat = short_pattern(row["pattern"].values)
            cell = (f"{str(row['verdict'].values)} {float(row['rms_tip_m']) * 1e3:.4f}"
                    + (f" [{pat}]" if pat else ""))
            cells.append(f"{cell:>36}")
        lines.append(f"{v * k:10.4g} " + "".join(cells))
    if ranges is not None:
        text = ", ".join(f"{a * k:g}" if a == b else f"{a * k:g}-{b * k:g}" for a, b in ranges)
        lines.append(f"hysteresis (forward and backward differ): {text or 'none'}"
                     + (f" {unit}" if text and unit else ""))
    lines.append(f"{ds.sizes['direction'] * ds.sizes['value']} runs in "
                 f"{ds.attrs['wall_time_s']:.1f} s")
    return "\n".join(lines)


def _grid(text: str, name: str) -> tuple[float, float, int]:
    """'LO:HI:COUNT' -> (lo, hi, count): COUNT values from LO to HI, both included."""
    parts = text.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise ParameterError(f"{name} = {text!r} must be LO:HI:COUNT (COUNT values from LO "
                             "to HI, both included; COUNT an integer)") from None
    check_range(f"{name} LO", lo, -math.inf, math.inf, lo_open=True, hi_open=True)
    check_range(f"{name} HI", hi, lo, math.inf, hi_open=True)
    check_int(f"{name} COUNT", n, 1, MAX_BASIN_CELLS)
    return lo, hi, n


def _pair(text: str, name: str) -> tuple[float, float]:
    values = parse_numbers(text, name)
    if len(values) != 2:
        raise ParameterError(f"{name} = {text!r} must be two numbers, MM,M/S")
    d, v = MAX_INITIAL_DISPLACEMENT * 1e3, MAX_INITIAL_VELOCITY
    return (check_range(f"{name} MM", values[0], -d, d, unit="mm"),
            check_range(f"{name} M/S", values[1], -v, v, unit="m/s"))


def _cmd_basins(args) -> Outcome:
    bar, friction_on = one_bar(args, "basins")
    gap = check_gap(gap_default_mm(args) if args.gap_mm is None else args.gap_mm, args)
    force = 10.0 if args.force_n is None else args.force_n
    ratio = 1.0 if args.ratio is None else args.ratio
    check_force(force)
    check_ratio(ratio)
    check_range("--steady-fraction", args.steady_fraction, 0, 1, lo_open=True)
    lo, hi, n = _grid(args.displacement_mm, "--displacement-mm")
    d = MAX_INITIAL_DISPLACEMENT * 1e3
    check_range("--displacement-mm LO", lo, -d, d, unit="mm")
    check_range("--displacement-mm HI", hi, -d, d, unit="mm")
    displacement = (lo * 1e-3, hi * 1e-3, n)
    velocity = _grid(args.velocity_m_s, "--velocity-m-s")
    for end, value in zip(("LO", "HI"), velocity[:2], strict=True):
        check_range(f"--velocity-m-s {end}", value, -MAX_INITIAL_VELOCITY,
                    MAX_INITIAL_VELOCITY, unit="m/s")
    check_cells(n, velocity[2], ("--displacement-mm", "--velocity-m-s"))
    w0, v0 = _pair(args.poincare_from, "--poincare-from")
    check_workers(args.workers)
    y0 = 0.0
    if args.ball_position_mm is not None:
        y0 = check_range("--ball-position-mm", args.ball_position_mm, -gap / 2 * 1e3,
                         gap / 2 * 1e3, unit="mm") * 1e-3
    yv0 = check_range("--ball-velocity-m-s", args.ball_velocity_m_s or 0.0,
                      -MAX_INITIAL_VELOCITY, MAX_INITIAL_VELOCITY, unit="m/s")

    kw = system_overrides(args)
    if bar == "ball":
        kw.update(gap_m=gap, friction=friction_on)
    system = make_system(bar, args.preset, **kw)
    check_dt(args, [system], ratio)
    options = BasinOptions(displacement, velocity, y0, yv0, force, ratio,
                           poincare_from=(w0 * 1e-3, v0))
    ds = basins(system, options,
                integration=integration(args, steady_fraction=args.steady_fraction),
                execution=execution(args), progress=progress_printer(args, "basins", "batches"))
    ds.attrs.update(bar=bar)

    summary = basins_files(ds, args.out)

    def text(say) -> None:
        say(_basins_text(summary))
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def _basins_text(s: dict) -> str:
    g = s["grid"]
    f = s["forcing"]
    lines = [f"basins at F0 = {f['amplitude_n']:g} N, Omega/omega_n = {f['ratio']:g}: "
             f"{g['displacement_m'][2]} x {g['velocity_m_s'][2]} initial conditions, "
             f"{len(s['attractors'])} attractors",
             f"{'id':>4} {'fraction':>9} {'period':>7} {'RMS (mm)':>9}  pattern "
             "(representative W0 mm, W0' m/s)"]
    for a in s["attractors"]:
        r = a["representative"]
        lines.append(f"{a['id']:>4} {a['fraction']:9.3f} {a['period'] or '-':>7} "
                     f"{a['rms_tip_m'] * 1e3:9.4f}  {a['pattern'] or '-'} "
                     f"({r['tip_displacement_m'] * 1e3:g}, {r['tip_velocity_m_s']:g})")
    p = s["poincare_from"]
    lines.append(f"Poincare map from W0 = {p['tip_displacement_m'] * 1e3:g} mm, "
                 f"W0' = {p['tip_velocity_m_s']:g} m/s: {p['verdict']}, "
                 f"{p['n_samples']} samples, pattern {p['pattern'] or '-'}")
    lines.append(f"{g['displacement_m'][2] * g['velocity_m_s'][2]} runs in "
                 f"{s['wall_time_s']:.1f} s")
    return "\n".join(lines)


#: sensitivity: the option each KIND replaces
KIND_OPTIONS = {"ball": ("ball", "--ball"), "restitution": ("restitution", "--restitution"),
                "friction_number": ("friction_number", "--friction-number")}


def _starts_table(kind: str, force: float, rows: list[dict], heads: list[str]) -> list[str]:
    """The tip RMS of each ratio and value over its runs from every start (its own and
    the further ones): their mean and their least and largest."""
    width = max(26, *(len(h) + 2 for h in heads))
    n = len(rows[0]["starts"]["rms_tip_m"]) + 1
    lines = [f"{kind}, F0 = {force:g} N: tip RMS (mm) over {n} starts: mean [least, largest]",
             "ratio ".rjust(8) + "".join(h.rjust(width) for h in heads)]
    for k, ratio in enumerate(rows[0]["ratio"]):
        cells = []
        for h in rows:
            runs = np.array([h["rms_tip_m"][k], *(r[k] for r in h["starts"]["rms_tip_m"])])
            cells.append(f"{runs.mean() * 1e3:.4f} [{runs.min() * 1e3:.4f}, "
                         f"{runs.max() * 1e3:.4f}]".rjust(width))
        lines.append(f"{ratio:7.3f} " + "".join(cells))
    return lines + [""]


def _check_starts(starts: int, kind: str) -> None:
    check_int("--starts", starts, 0, MAX_STARTS)
    if starts == 1:
        raise ParameterError(f"--starts = 1 must be 0 (the runs' own start alone) or 2 to "
                             f"{MAX_STARTS}")
    if starts and kind == "initial":
        raise ParameterError(f"--starts = {starts} conflicts with KIND initial (its values "
                             "are the starts)")


def _sensitivity_values(args, bar: str, gap: float):
    """--values as the library takes them (SI), or None for the published ones."""

    kind, text = args.kind, args.values
    if text is None:
        return None
    if kind == "ball":
        return parse_words(text, "--values", BALLS, [])
    if kind != "initial":
        values = parse_numbers(text, "--values")
        hi = 1.0 if kind == "restitution" else 100.0
        for v in values:
            check_range(f"--values ({kind})", v, 0.0, hi)
        return values
    out = []
    for item in text.split(","):
        try:
            parts = [float(v) for v in item.split("/")]
            if len(parts) not in (2, 4):
                raise ValueError
        except ValueError:
            raise ParameterError(f"--values = {text!r}: initial conditions are MM/M_S or "
                                 "MM/M_S/Y_MM/Y_M_S (tip displacement mm / tip velocity m/s "
                                 "/ ball position mm / ball velocity m/s), comma "
                                 "separated") from None
        d, v = MAX_INITIAL_DISPLACEMENT * 1e3, MAX_INITIAL_VELOCITY
        for x, bound, unit in zip(parts, (d, v, d, v), ("mm", "m/s", "mm", "m/s"), strict=False):
            check_range(f"--values ({kind})", x, -bound, bound, unit=unit)
        if len(parts) == 4:
            if bar != "ball":
                raise ParameterError(f"--values = {item!r}: a ball position and velocity "
                                     f"apply only to --bar ball (bar = {bar})")
            check_range("--values ball position", parts[2], -gap / 2 * 1e3, gap / 2 * 1e3,
                        unit="mm")
            parts[2] *= 1e-3
        parts[0] *= 1e-3
        out.append(tuple(parts))
    return out


def _cmd_sensitivity(args) -> Outcome:
    kind = args.kind
    bar, friction_on = one_bar(args, f"sensitivity {kind}")
    if kind != "initial" and bar != "ball":
        raise ParameterError(f"--bar = {bar!r}: KIND {kind} varies the ball damper, it needs "
                             "--bar ball")
    if kind in KIND_OPTIONS and getattr(args, KIND_OPTIONS[kind][0]) is not None:
        raise ParameterError(f"{KIND_OPTIONS[kind][1]} conflicts with KIND {kind}: the "
                             "values come from --values")
    if kind == "friction_number" and (args.friction_force_n is not None or not friction_on):
        given = "--friction-force-n" if args.friction_force_n is not None else "--friction off"
        raise ParameterError(f"{given} conflicts with KIND friction_number (friction on, its "
                             "size from --values)")
    gap = check_gap(gap_default_mm(args) if args.gap_mm is None else args.gap_mm, args)
    _check_starts(args.starts, kind)
    values = _sensitivity_values(args, bar, gap)
    forces, ratios = forces_and_ratios(args)
    cuts = None
    if args.cut_rpm is not None or args.depths_mm is not None:
        rpm = check_rpm(1200.0 if args.cut_rpm is None else args.cut_rpm, args, "--cut-rpm")
        depths = parse_range(args.depths_mm or "0.05:0.10:0.01", "--depths-mm")
        for d in depths:
            check_depth(d, "--depths-mm")
        cuts = Cuts(rpm, tuple(float(d) * 1e-3 for d in depths), args.duration_s,
                    cut_options(args))
    else:
        given = [o for o in CUT_ONLY if getattr(args, o, None) not in (None, False)]
        if given:
            raise ParameterError(f"--{given[0].replace('_', '-')} applies only to cuts "
                                 "(--cut-rpm or --depths-mm)")

    common = dict(preset=args.preset, bar=bar, gap_m=gap, friction=friction_on,
                  overrides=system_overrides(args), integration=integration(args),
                  execution=execution(args))
    options = SensitivityOptions(kind, values, tuple(forces), tuple(ratios),
                                 starts=args.starts)
    ds = sensitivity(options, progress=progress_printer(args, f"sensitivity {kind}", "runs"),
                     **common)
    if cuts is not None:
        ds = with_cuts(ds, sensitivity(SensitivityOptions(kind, values, cuts=cuts), **common))

    summary = sensitivity_files(ds, args.out)

    def text(say) -> None:
        say(_sensitivity_text(summary))
        say(wrote(summary["files"]))

    return Outcome(summary, text)


def _sensitivity_text(s: dict) -> str:
    kind = s["kind"]
    heads = [str(v) for v in s["values"]]
    width = max(16, *(len(h) + 2 for h in heads))
    lines = []
    for force in sorted({h["force_n"] for h in s["harmonic"]}):
        rows = [h for h in s["harmonic"] if h["force_n"] == force]
        lines.append(f"{kind}, F0 = {force:g} N: tip RMS (mm) [pattern]")
        lines.append("ratio ".rjust(8) + "".join(h.rjust(width) for h in heads))
        for k, ratio in enumerate(rows[0]["ratio"]):
            cells = []
            for h in rows:
                pat = short_pattern(h["pattern"][k])
                cells.append((f"{h['rms_tip_m'][k] * 1e3:.4f}"
                              + (f" [{pat}]" if pat else "")).rjust(width))
            lines.append(f"{ratio:7.3f} " + "".join(cells))
        lines.append("")
        if rows[0].get("starts"):
            lines += _starts_table(kind, force, rows, heads)
    if s["cuts"]:
        c = s["cuts"]
        lines.append(f"cuts at {c['rpm']:g} rpm: steady amplitude (mm), * = chatter (the "
                     "force reaches zero)")
        lines.append("depth mm".rjust(9) + "".join(h.rjust(width) for h in heads))
        for k, depth in enumerate(c["depth_m"]):
            cells = [(f"{r['amplitude_m'][k] * 1e3:.4f}" + (" *" if r["chatter"][k] else "  "))
                     .rjust(width) for r in c["results"]]
            lines.append(f"{depth * 1e3:9.3f}" + "".join(cells))
        lines.append("")
    lines.append(PATTERN_KEY)
    return "\n".join(lines)
