"""The ``boringbar`` command: ``boringbar simulate`` and ``boringbar sweep``.

Units are in the option names (MODEL.md section 7): ``--gap-mm``,
``--force-n``, ``--duration-s``...; everything is converted to SI here and
handed to the library.  Every bad value ends the command with one line,
``boringbar: error: <message>``, and exit code 2; results go to files in
``--out`` (written atomically) and a summary to stdout (``--json``: exactly
one JSON object).  A new subcommand is a ``_add_<name>`` function that
builds its subparser and a ``_cmd_<name>(args) -> int`` handler.
"""

from __future__ import annotations

import argparse
import math
import sys
import textwrap
from pathlib import Path

from boringbar import __version__
from boringbar._validate import ParameterError, check_range
from boringbar.system import BALLS, BAR_KINDS, PRESETS, READINGS

PROG = "boringbar"
#: Default history length of ``simulate`` (rows), when --record-every is not given.
HISTORY_ROWS = 20000
BALL_OPTIONS = ("gap_mm", "friction", "friction_force_n", "friction_number", "ball",
                "restitution", "locked", "ball_position_mm", "ball_velocity_m_s")


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (exit code 2) instead of usage + error."""

    def error(self, message):
        self.exit(2, f"{PROG}: error: {message} (see '{self.prog} --help')\n")


# --- parser ----------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    readings = "\n".join(textwrap.fill(f"{k}: {v}", 79, initial_indent="  ",
                                       subsequent_indent="    ")
                         for k, v in READINGS.items())
    parser = _Parser(
        prog=PROG, formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Vibration of impact-damped boring bars (ball damper, TMD, solid bar).",
        epilog="Presets: 'physical' (default) is the model as physics demands; 'paper'\n"
               "switches on the published readings:\n" + readings)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_simulate(sub)
    _add_sweep(sub)
    return parser


def _add_common(p: argparse.ArgumentParser, many: bool) -> dict:
    """Options shared by simulate and sweep; ``many``: the sweep's list forms.
    Returns the option groups by name, for command-specific options."""
    groups = {}
    lst = ", comma list" if many else ""
    g = p.add_argument_group("bar and damper")
    g.add_argument("--bar", action="append", metavar="solid|ball|tmd",
                   help="solid bar, ball damper or tuned mass damper"
                        + ("; repeatable or comma list (default: solid,tmd,ball)" if many
                           else " (default: ball)"))
    g.add_argument("--preset", choices=PRESETS, default="physical",
                   help="physical (default) or paper (the published readings)")
    g.add_argument("--gap-mm", metavar="MM" + (",..." if many else ""),
                   type=None if many else float,
                   help=f"total ball clearance delta in mm{lst} "
                        f"(default: {'0.5,0.1' if many else '0.5'})")
    g.add_argument("--friction", metavar="on|off" + (",..." if many else ""),
                   help=f"ball friction{lst} (default: {'off,on' if many else 'on'}); "
                        "its size depends on the preset")
    g.add_argument("--friction-force-n", type=float, metavar="N",
                   help="friction force F_c in N (overrides the preset's)")
    g.add_argument("--friction-number", type=float, metavar="X",
                   help="published rolling-resistance number (0.6 nominal), read as the "
                        "preset reads it")
    g.add_argument("--ball", choices=BALLS, help="ball material (default: carbide)")
    g.add_argument("--restitution", type=float, metavar="E",
                   help="coefficient of restitution in [0, 1] (default: 0.7)")
    g.add_argument("--locked", action="store_true", help="fix the ball to the bar")
    g.add_argument("--modes", type=int, metavar="N",
                   help="retained bending modes (default: physical 2, paper 1)")
    g.add_argument("--tmd-design", choices=("published", "den-hartog"),
                   help="TMD tuning (default: physical den-hartog, paper published)")

    g = groups["run"] = p.add_argument_group("forcing and integration")
    if many:
        g.add_argument("--force-n", default="10,20", metavar="N,...",
                       help="harmonic force amplitudes F0 in N (default: 10,20)")
        g.add_argument("--ratios", default="0.95:1.05:0.01", metavar="START:STOP:STEP",
                       help="Omega/omega_n values, START:STOP:STEP (inclusive) or comma list "
                            "(default: 0.95:1.05:0.01)")
    else:
        g.add_argument("--force-n", type=float, default=10.0, metavar="N",
                       help="harmonic force amplitude F0 in N (default: 10)")
        g.add_argument("--ratio", type=float, default=1.0, metavar="R",
                       help="Omega/omega_n of the host bar (default: 1.0)")
    g.add_argument("--duration-s", type=float, default=2.0, metavar="S",
                   help="simulated time in s (default: 2.0)")
    g.add_argument("--dt-s", type=float, default=1e-6, metavar="S",
                   help="RK4 time step in s (default: 1e-6)")

    g = p.add_argument_group("initial conditions (default: at rest, ball centred)")
    g.add_argument("--tip-displacement-mm", type=float, default=0.0, metavar="MM")
    g.add_argument("--tip-velocity-m-s", type=float, default=0.0, metavar="M/S")
    g.add_argument("--ball-position-mm", type=float, metavar="MM",
                   help="ball position relative to the cavity centre, in [-gap/2, gap/2]")
    g.add_argument("--ball-velocity-m-s", type=float, metavar="M/S",
                   help="ball velocity relative to the bar")

    g = groups["output"] = p.add_argument_group("output")
    g.add_argument("--out", default="out", metavar="DIR", help="output directory (default: out)")
    g.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    g.add_argument("--quiet", action="store_true", help="no progress and no human summary")
    return groups


def _add_simulate(sub) -> None:
    p = sub.add_parser("simulate", help="one time-domain run under harmonic forcing",
                       description="One run; writes DIR/run.nc, DIR/run.png, DIR/summary.json.")
    groups = _add_common(p, many=False)
    groups["output"].add_argument("--record-every", type=int, metavar="N",
                   help=f"keep every N-th step in run.nc (default: about {HISTORY_ROWS} rows)")
    p.set_defaults(func=_cmd_simulate)


def _add_sweep(sub) -> None:
    p = sub.add_parser("sweep", help="tip RMS and impact pattern against Omega/omega_n",
                       description="Frequency sweep of the published study (MODEL.md section "
                                   "6); writes DIR/sweep.nc and DIR/sweep.png (one "
                                   "DIR/sweep_F<F0>N.png per force when several).")
    groups = _add_common(p, many=True)
    groups["run"].add_argument("--workers", type=int, metavar="N",
                               help="threads (default: every core)")
    p.set_defaults(func=_cmd_sweep)


# --- option checks (errors name the option, its value and the allowed range) -----

def _words(values, name: str, choices, default) -> list[str]:
    """Repeatable and/or comma-separated choices -> list, in order, without repeats."""
    if values is None:
        return list(default)
    if isinstance(values, str):
        values = [values]
    out = []
    for w in (w.strip() for v in values for w in v.split(",")):
        if w not in choices:
            raise ParameterError(f"{name} = {w!r} is not one of {', '.join(choices)}")
        if w not in out:
            out.append(w)
    return out


def _numbers(text: str, name: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise ParameterError(f"{name} = {text!r} must be a comma-separated list of "
                             "numbers") from None


def _check_common(args, bars: list[str]) -> None:
    has_ball = "ball" in bars
    if not has_ball:
        given = [o for o in BALL_OPTIONS if getattr(args, o) not in (None, False)]
        if given:
            opt = "--" + given[0].replace("_", "-")
            raise ParameterError(f"{opt} applies only to --bar ball (bar = {','.join(bars)})")
    if args.tmd_design is not None and "tmd" not in bars:
        raise ParameterError(f"--tmd-design applies only to --bar tmd "
                             f"(bar = {','.join(bars)})")
    if args.friction_force_n is not None and args.friction_number is not None:
        raise ParameterError("give at most one of --friction-force-n and --friction-number")
    if args.friction_force_n is not None:
        check_range("--friction-force-n", args.friction_force_n, 0, math.inf, hi_open=True,
                    unit="N")
    if args.friction_number is not None:
        check_range("--friction-number", args.friction_number, 0, 100)
    if args.restitution is not None:
        check_range("--restitution", args.restitution, 0, 1)
    if args.modes is not None:
        check_range("--modes", args.modes, 1, 8)
    check_range("--duration-s", args.duration_s, 0, math.inf, lo_open=True, hi_open=True,
                unit="s")
    check_range("--dt-s", args.dt_s, 0, math.inf, lo_open=True, hi_open=True, unit="s")


def _check_gap(gap_mm: float) -> float:
    return check_range("--gap-mm", gap_mm, 0, math.inf, lo_open=True, hi_open=True,
                       unit="mm") * 1e-3


def _initial(args, gaps_m: list[float]):
    from boringbar.simulate import Initial

    if args.ball_position_mm is not None and gaps_m:
        half = min(gaps_m) / 2 * 1e3
        check_range("--ball-position-mm", args.ball_position_mm, -half, half, unit="mm")
    return Initial(
        tip_displacement=args.tip_displacement_mm * 1e-3,
        tip_velocity=args.tip_velocity_m_s,
        ball_position=(args.ball_position_mm or 0.0) * 1e-3,
        ball_velocity=args.ball_velocity_m_s or 0.0,
    )


def _system_overrides(args) -> dict:
    """make_system keywords the user set (the preset decides the rest)."""
    kw = {"ball": args.ball, "restitution": args.restitution, "n_modes": args.modes,
          "friction_number": args.friction_number, "friction_force": args.friction_force_n,
          "tmd_design": args.tmd_design, "locked": args.locked or None}
    return {k: v for k, v in kw.items() if v is not None}


# --- simulate --------------------------------------------------------------------

def _cmd_simulate(args) -> int:
    from boringbar.forcing import Harmonic
    from boringbar.simulate import simulate
    from boringbar.system import make_system

    bars = _words(args.bar, "--bar", BAR_KINDS, ["ball"])
    if len(bars) != 1:
        raise ParameterError(f"--bar = {','.join(bars)!r}: simulate runs one bar "
                             f"(one of {', '.join(BAR_KINDS)})")
    bar = bars[0]
    _check_common(args, [bar])
    friction = _words(args.friction, "--friction", ("on", "off"), ["on"])
    if len(friction) != 1:
        raise ParameterError(f"--friction = {args.friction!r} must be one of on, off")
    friction_on = friction[0] == "on"
    if not friction_on and (args.friction_force_n is not None
                            or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    gap = _check_gap(0.5 if args.gap_mm is None else args.gap_mm)
    check_range("--force-n", args.force_n, 0, math.inf, hi_open=True, unit="N")
    check_range("--ratio", args.ratio, 0, math.inf, lo_open=True, hi_open=True)
    n_steps = int(round(args.duration_s / args.dt_s))
    record_every = args.record_every or max(1, n_steps // HISTORY_ROWS)
    check_range("--record-every", record_every, 1, max(n_steps, 1))

    kw = _system_overrides(args)
    if bar == "ball":
        kw.update(gap=gap, friction=friction_on)
    system = make_system(bar, args.preset, **kw)
    initial = _initial(args, [gap] if bar == "ball" else [])
    run = simulate(system, Harmonic(args.force_n, args.ratio), duration=args.duration_s,
                   dt=args.dt_s, initial=initial, record_every=record_every)

    from boringbar.io import write_json_atomic, write_netcdf_atomic
    from boringbar.plot import plot_run

    out = Path(args.out)
    files = {"netcdf": out / "run.nc", "png": out / "run.png", "summary": out / "summary.json"}
    ds = run.history_dataset()
    write_netcdf_atomic(ds, files["netcdf"])
    plot_run(ds, files["png"])
    summary = {**run.summary(), "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic({**summary, "config": run.config()}, files["summary"])
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_simulate_text(summary, run))
    return 0


def _simulate_text(s: dict, run) -> str:
    lines = [
        f"{s['bar']} bar, {s['preset']} preset: F0 = {s['force_n']:g} N, "
        f"Omega/omega_n = {s['ratio']:.4g} ({s['forcing_frequency_hz']:.2f} Hz)",
        f"  natural frequency  {s['natural_frequency_hz']:.2f} Hz",
        f"  tip RMS            {s['rms_tip_m'] * 1e3:.4g} mm (steady part)",
        f"  max |tip|          {s['max_abs_tip_m'] * 1e3:.4g} mm",
    ]
    if s["bar"] == "ball":
        lines.append(f"  pattern            {s['pattern']} "
                     f"({s['impacts_per_cycle']:.3g} impacts per cycle)")
        lines.append(f"  max |y|            {s['max_abs_rel_disp_m'] * 1e3:.4g} mm "
                     f"(walls at +-{run.system.damper.gap / 2 * 1e3:g} mm)")
    elif s["bar"] == "tmd":
        lines.append(f"  max stroke         {s['max_abs_rel_disp_m'] * 1e3:.4g} mm")
    if s["readings"]:
        lines.append(f"  published readings {', '.join(s['readings'])}")
    lines.append(f"  elapsed            {s['elapsed_s']:.2f} s")
    lines.append("  wrote " + ", ".join(s["files"].values()))
    return "\n".join(lines)


# --- sweep -----------------------------------------------------------------------

def _cmd_sweep(args) -> int:
    from boringbar.analysis.sweep import parse_range, sweep, sweep_summary

    bars = _words(args.bar, "--bar", BAR_KINDS, ["solid", "tmd", "ball"])
    _check_common(args, bars)
    gaps = [_check_gap(g) for g in _numbers(args.gap_mm or "0.5,0.1", "--gap-mm")]
    frictions = [w == "on" for w in _words(args.friction, "--friction", ("on", "off"),
                                           ["off", "on"])]
    if not any(frictions) and (args.friction_force_n is not None
                               or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    forces = _numbers(args.force_n, "--force-n")
    for f in forces:
        check_range("--force-n", f, 0, math.inf, hi_open=True, unit="N")
    ratios = parse_range(args.ratios, "--ratios")
    for r in ratios:
        check_range("--ratios", r, 0, math.inf, lo_open=True, hi_open=True)
    if args.workers is not None:
        check_range("--workers", args.workers, 1, 4096)

    cases = _sweep_cases(args, bars, gaps, frictions)
    initial = _initial(args, gaps if "ball" in bars else [])
    progress = None
    if not args.quiet and sys.stderr.isatty():
        def progress(done, total):
            end = "\n" if done == total else ""
            print(f"\r{PROG} sweep: {done}/{total} runs", end=end, file=sys.stderr, flush=True)
    ds = sweep(cases, ratios, forces, duration=args.duration_s, dt=args.dt_s,
               workers=args.workers, initial=initial, progress=progress)

    from boringbar.io import write_netcdf_atomic
    from boringbar.plot import plot_sweep

    out = Path(args.out)
    nc = write_netcdf_atomic(ds, out / "sweep.nc")
    pngs = plot_sweep(ds, out / "sweep.png")
    summary = {**sweep_summary(ds), "files": {"netcdf": str(nc), "png": [str(p) for p in pngs]}}
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_sweep_text(ds))
        print("wrote " + ", ".join([str(nc)] + [str(p) for p in pngs]))
    return 0


def _sweep_cases(args, bars, gaps, frictions) -> list:
    """published_cases, in the user's order; a friction override applies to the
    friction-on ball cases only (make_system would otherwise give the 'off'
    cases that friction too)."""
    from boringbar.analysis.sweep import published_cases

    kw = _system_overrides(args)
    cases = []
    for bar in bars:
        if bar != "ball":
            cases += published_cases((bar,), preset=args.preset, **kw)
            continue
        for gap in gaps:
            for fr in frictions:
                ov = kw if fr else {k: v for k, v in kw.items() if k != "friction_force"}
                cases += published_cases(("ball",), (gap,), (fr,), args.preset, **ov)
    return cases


def _short_pattern(name: str) -> str:
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
    for label, bar, gap, fr in zip(ds["case"].values, ds["bar"].values, ds["gap"].values,
                                   ds["friction"].values, strict=True):
        heads.append(f"ball {gap * 1e3:g}/{fr}" if bar == "ball" else str(label))
    width = max(14, *(len(h) + 2 for h in heads))
    lines = []
    for j, force in enumerate(ds["force"].values):
        lines.append(f"F0 = {force:g} N: tip RMS (mm) [pattern]; ball columns: gap mm/friction")
        lines.append("ratio ".rjust(8) + "".join(h.rjust(width) for h in heads))
        for k, ratio in enumerate(ds["ratio"].values):
            cells = []
            for i in range(len(heads)):
                pat = _short_pattern(ds["pattern"].values[i, j, k])
                cell = f"{ds['rms_tip_m'].values[i, j, k] * 1e3:.4f}"
                cells.append((cell + (f" [{pat}]" if pat else "")).rjust(width))
            lines.append(f"{ratio:7.3f} " + "".join(cells))
        lines.append("")
    lines.append("patterns: Ns = N symmetric impacts per period, Na/k = N asymmetric impacts "
                 "per k periods, st = sticking, 0 = no impact, 0+st = no impact with sticking, "
                 "nu = non-uniform")
    return "\n".join(lines)


# --- entry point -----------------------------------------------------------------

def _print_json(obj) -> None:
    import json

    from boringbar.io import jsonable

    print(json.dumps(jsonable(obj), allow_nan=False))


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 ok, 2 bad input, 1 I/O error)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else 0
    try:
        return args.func(args)
    except ValueError as exc:  # ParameterError is a ValueError
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"{PROG}: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


if __name__ == "__main__":
    sys.exit(main())
