"""The ``boringbar`` command: ``simulate``, ``sweep``, ``lobes``, ``bifurcation``,
``basins`` and ``sensitivity``; ``run`` (study files) and ``paper`` (the whole
published study) are in :mod:`boringbar.cli_study`.

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
import json
import math
import re
import sys
import textwrap
from pathlib import Path

import numpy as np

from boringbar import __version__
from boringbar._validate import ParameterError, check_range
from boringbar.forcing import INTERPOLATIONS, STARTS
from boringbar.kernels.compile import notices as compile_notices
from boringbar.system import BALLS, BAR_KINDS, PRESETS, READINGS

PROG = "boringbar"
#: the time integrators (boringbar.simulate.INTEGRATORS; not imported here, which would
#: load numba before the arguments are even parsed)
INTEGRATORS = ("rk4", "exact")
#: Default history length of ``simulate`` (rows), when --record-every is not given.
HISTORY_ROWS = 20000
#: bifurcation's published sweep: F0 from 5 to 50 N in 1 N steps
PUBLISHED_FORCES = "5:50:1"
BALL_OPTIONS = ("gap_mm", "friction", "friction_force_n", "friction_number", "ball",
                "restitution", "locked", "ball_position_mm", "ball_velocity_m_s",
                "static_ratio")


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (exit code 2) instead of usage + error."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value starting with '-' and a digit is a value, not an option, so
        # ranges work unquoted: --displacement-mm -1.5:1.5:30 (argparse's own
        # pattern only knows plain negative numbers before Python 3.13)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

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
    _add_lobes(sub)
    _add_bifurcation(sub)
    _add_basins(sub)
    _add_sensitivity(sub)
    from boringbar.cli_study import add_paper, add_run

    add_run(sub)
    add_paper(sub)
    return parser


def _add_common(p: argparse.ArgumentParser, many: bool, harmonic: bool = True,
                initial: bool = True, ranges: bool = False) -> dict:
    """Options shared by every command; ``many``: the list forms of sweep and
    lobes; ``harmonic``: the F0 and Omega options; ``initial``: the initial
    conditions; ``ranges``: --gap-mm and --restitution also take
    START:STOP:STEP (bifurcation; strings, parsed by the command).  Returns
    the option groups by name, for command-specific options."""
    groups = {}
    lst = ", comma list" if many else ""
    g = p.add_argument_group("bar and damper")
    g.add_argument("--bar", action="append", metavar="solid|ball|tmd",
                   help="solid bar, ball damper or tuned mass damper"
                        + ("; repeatable or comma list (default: solid,tmd,ball)" if many
                           else " (default: ball)"))
    g.add_argument("--preset", choices=PRESETS, default="physical",
                   help="physical (default) or paper (the published readings)")
    swept = ", or START:STOP:STEP to sweep it" if ranges else ""
    g.add_argument("--gap-mm", metavar="MM" + (",..." if many else "|START:STOP:STEP" if ranges
                                               else ""),
                   type=None if many or ranges else float,
                   help=f"total ball clearance delta in mm{lst}{swept} "
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
    g.add_argument("--restitution", type=None if ranges else float,
                   metavar="E|START:STOP:STEP" if ranges else "E",
                   help=f"coefficient of restitution in [0, 1]{swept} (default: 0.7)")
    g.add_argument("--locked", action="store_true", help="fix the ball to the bar")
    g.add_argument("--static-ratio", type=float, metavar="X",
                   help="static friction limit F_s/F_c >= 1 of true stick-slip (default: 1; "
                        "other values need --integrator exact)")
    g.add_argument("--modes", type=int, metavar="N",
                   help="retained bending modes (default: physical 2, paper 1)")
    g.add_argument("--tmd-design", choices=("published", "den-hartog"),
                   help="TMD tuning (default: physical den-hartog, paper published)")

    g = groups["run"] = p.add_argument_group("forcing and integration")
    if harmonic and many:
        g.add_argument("--force-n", default="10,20", metavar="N,...",
                       help="harmonic force amplitudes F0 in N (default: 10,20)")
        g.add_argument("--ratios", default="0.95:1.05:0.01", metavar="START:STOP:STEP",
                       help="Omega/omega_n values, START:STOP:STEP (inclusive) or comma list "
                            "(default: 0.95:1.05:0.01)")
    elif harmonic:  # None: not given (a cut refuses them); defaults in _cmd_simulate
        g.add_argument("--force-n", type=float, metavar="N",
                       help="harmonic force amplitude F0 in N (default: 10)")
        g.add_argument("--ratio", type=float, metavar="R",
                       help="Omega/omega_n of the host bar (default: 1.0)")
    g.add_argument("--duration-s", type=float, default=2.0, metavar="S",
                   help="simulated time in s (default: 2.0)")
    g.add_argument("--dt-s", type=float, default=1e-6, metavar="S",
                   help="RK4 time step in s; with --integrator exact, the step of the "
                        "recorded history (default: 1e-6)")
    g.add_argument("--integrator", choices=INTEGRATORS, default="rk4",
                   help="rk4: the published fixed-step scheme (default); exact: "
                        "event-driven, exact between events (a cut: the delayed surface "
                        "from a history of step <= dt)")

    if initial:
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


def _add_cutting(g) -> None:
    """The cut's description, shared by simulate and lobes (MODEL.md section 4).
    Defaults are None here (so simulate can refuse them without a cut) and
    applied in :func:`_cut_options`."""
    g.add_argument("--kr-mpa", type=float, metavar="MPA",
                   help="specific radial cutting force Kr in MPa (default: 850, aluminium)")
    g.add_argument("--feed-mm", type=float, metavar="MM",
                   help="feed per revolution h_m in mm (default: 0.1)")
    g.add_argument("--revolutions", type=int, metavar="N",
                   help="past revolutions N in the chip-thickness minimum (default: 3)")
    g.add_argument("--delay-interp", choices=INTERPOLATIONS,
                   help="delayed W at RK4 stages: cubic Hermite (default) or linear")
    g.add_argument("--start", choices=STARTS,
                   help="rest (default, as published: the mean force arrives as a step) or "
                        "static (from the static deflection under the mean force)")
    g.add_argument("--bounded-fraction", type=float, metavar="X",
                   help="bounded chatter: steady amplitude above X h_m (default: 0.1)")


def _add_simulate(sub) -> None:
    p = sub.add_parser("simulate", help="one time-domain run under harmonic forcing or a cut",
                       description="One run; writes DIR/run.nc, DIR/run.png, DIR/summary.json. "
                                   "Harmonic forcing (--force-n, --ratio) by default; "
                                   "--rpm with --depth-mm runs a regenerative cut instead.")
    groups = _add_common(p, many=False)
    g = p.add_argument_group("regenerative cutting (instead of harmonic forcing)")
    g.add_argument("--rpm", type=float, metavar="RPM", help="spindle speed in rev/min")
    g.add_argument("--depth-mm", type=float, metavar="MM", help="depth of cut b in mm")
    _add_cutting(g)
    g.add_argument("--stop-at-zero", action="store_true",
                   help="end the run when the cutting force first reaches zero (chatter)")
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


def _add_lobes(sub) -> None:
    p = sub.add_parser("lobes", help="stability lobes by time-domain simulation of cuts",
                       description="Stability lobes of the published study (MODEL.md section "
                                   "6): depth of cut against spindle speed, every grid point a "
                                   "regenerative cut; writes DIR/lobes.nc and DIR/lobes.png "
                                   "(with --examples also DIR/examples.nc and "
                                   "DIR/examples.png).")
    groups = _add_common(p, many=True, harmonic=False, initial=False)
    g = p.add_argument_group("lobe grid")
    g.add_argument("--rpm", metavar="START:STOP:STEP",
                   help="spindle speeds in rev/min, START:STOP:STEP (inclusive) or comma list "
                        "(default: 900:1600:50, published)")
    g.add_argument("--depth-step-mm", type=float, default=0.01, metavar="MM",
                   help="depth-of-cut step in mm (default: 0.01)")
    g.add_argument("--max-depth-mm", type=float, default=3.0, metavar="MM",
                   help="deepest cut tried in mm (default: 3)")
    g.add_argument("--method", choices=("scan", "search"), default="scan",
                   help="scan: every depth upwards (default, published); search: doubling "
                        "and bisection (faster; assumes stability monotone below the bracket)")
    g.add_argument("--successive", type=int, default=3, metavar="N",
                   help="a speed's scan ends after N successive chattering depths (default: 3)")
    g.add_argument("--criterion", choices=("zero", "bounded"), default="zero",
                   help="chatter: the force reaches zero (default, published) or bounded "
                        "(also a steady amplitude above --bounded-fraction of the feed)")
    g = p.add_argument_group("regenerative cutting")
    _add_cutting(g)
    groups["run"].add_argument("--workers", type=int, metavar="N",
                               help="threads (default: every core)")
    groups["output"].add_argument("--examples", action="store_true",
                                  help="rerun a stable and an unstable grid point of the "
                                       "first case with history: DIR/examples.nc, "
                                       "DIR/examples.png")
    p.set_defaults(func=_cmd_lobes)


def _add_bifurcation(sub) -> None:
    p = sub.add_parser("bifurcation",
                       help="Poincare samples of the tip against F0 (or Omega/omega_n, gap, e)",
                       description="Bifurcation diagram by continuation (MODEL.md section 6): "
                                   "one run per value of the swept parameter, each from the "
                                   "previous run's final state (forcing phase continuous), "
                                   "forward and then backward; stroboscopic Poincare samples "
                                   "of the tip (Omega t = 0 mod 2 pi) after dropping the first "
                                   "--drop of each run.  Exactly one of --force-n, --ratio, "
                                   "--gap-mm, --restitution is swept, written START:STOP:STEP "
                                   "(inclusive) or as a comma list in sweep order; the others "
                                   "take one value.  Default: --force-n 5:50:1 at --ratio 1 "
                                   "(published).  Writes DIR/bifurcation.nc and "
                                   "DIR/bifurcation.png.")
    groups = _add_common(p, many=False, harmonic=False, ranges=True)
    g = groups["run"]
    g.add_argument("--force-n", metavar="N|START:STOP:STEP",
                   help=f"harmonic force amplitude F0 in N (default: {PUBLISHED_FORCES} swept, "
                        "published; 10 when another parameter is swept)")
    g.add_argument("--ratio", metavar="R|START:STOP:STEP",
                   help="Omega/omega_n of the host bar (default: 1.0)")
    _add_drop(g)
    g.add_argument("--no-backward", action="store_true",
                   help="forward sweep only (then no hysteresis ranges)")
    p.set_defaults(func=_cmd_bifurcation)


def _add_drop(group) -> None:
    group.add_argument("--drop", type=float, default=0.2, metavar="X",
                       help="fraction of each run dropped before sampling, in [0, 1) "
                            "(default: 0.2)")


def _add_basins(sub) -> None:
    p = sub.add_parser("basins", help="basins of attraction over initial tip displacement x "
                                      "velocity",
                       description="Basins of attraction (MODEL.md section 6): one run per "
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
    groups = _add_common(p, many=False, initial=False)
    g = groups["run"]
    _add_drop(g)
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


def _add_sensitivity(sub) -> None:
    from boringbar.analysis.sensitivity import KINDS

    p = sub.add_parser("sensitivity", help="tip RMS (and chatter of cuts) for several values "
                                           "of one parameter",
                       description="Sensitivity study (MODEL.md section 6): KIND varies one "
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
    groups = _add_common(p, many=False, harmonic=False, initial=False)
    g = groups["run"]
    g.add_argument("--values", metavar="V,...",
                   help="the values of KIND, comma list (default: the published ones)")
    g.add_argument("--force-n", default="10", metavar="N,...",
                   help="harmonic force amplitudes F0 in N, comma list (default: 10)")
    g.add_argument("--ratios", default="0.95:1.05:0.01", metavar="START:STOP:STEP",
                   help="Omega/omega_n values, START:STOP:STEP (inclusive) or comma list "
                        "(default: 0.95:1.05:0.01)")
    g.add_argument("--workers", type=int, metavar="N", help="threads (default: every core)")
    g = p.add_argument_group("regenerative cuts (only with --cut-rpm or --depths-mm)")
    g.add_argument("--cut-rpm", type=float, metavar="RPM",
                   help="spindle speed in rev/min (default: 1200, published)")
    g.add_argument("--depths-mm", metavar="START:STOP:STEP",
                   help="depths of cut in mm, START:STOP:STEP (inclusive) or comma list "
                        "(default: 0.05:0.10:0.01, published)")
    _add_cutting(g)
    p.set_defaults(func=_cmd_sensitivity)


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
        given = [o for o in BALL_OPTIONS if getattr(args, o, None) not in (None, False)]
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


def _cut_options(args) -> dict:
    """The cut options as Regenerative keywords (SI), checked, defaults applied."""
    kr = 850.0 if args.kr_mpa is None else args.kr_mpa
    feed = 0.1 if args.feed_mm is None else args.feed_mm
    revolutions = 3 if args.revolutions is None else args.revolutions
    fraction = 0.1 if args.bounded_fraction is None else args.bounded_fraction
    check_range("--kr-mpa", kr, 0, math.inf, lo_open=True, hi_open=True, unit="MPa")
    check_range("--feed-mm", feed, 0, math.inf, lo_open=True, hi_open=True, unit="mm")
    check_range("--revolutions", revolutions, 1, 50)
    check_range("--bounded-fraction", fraction, 0, math.inf, lo_open=True, hi_open=True)
    return {"kr": kr * 1e6, "feed": feed * 1e-3, "revolutions": revolutions,
            "interpolation": args.delay_interp or "cubic", "start": args.start or "rest",
            "bounded_fraction": fraction}


def _check_rpm(rpm: float, name: str = "--rpm") -> float:
    return check_range(name, rpm, 0, math.inf, lo_open=True, hi_open=True, unit="rpm")


def _system_overrides(args) -> dict:
    """make_system keywords the user set (the preset decides the rest)."""
    kw = {"ball": args.ball, "restitution": args.restitution, "n_modes": args.modes,
          "friction_number": args.friction_number, "friction_force": args.friction_force_n,
          "tmd_design": args.tmd_design, "locked": args.locked or None,
          "static_ratio": args.static_ratio}
    return {k: v for k, v in kw.items() if v is not None}


# --- simulate --------------------------------------------------------------------

def _cmd_simulate(args) -> int:
    from boringbar.simulate import simulate
    from boringbar.system import make_system

    bar, friction_on = _one_bar(args, "simulate")
    gap = _check_gap(0.5 if args.gap_mm is None else args.gap_mm)
    forcing = _simulate_forcing(args)
    n_steps = int(round(args.duration_s / args.dt_s))
    record_every = args.record_every or max(1, n_steps // HISTORY_ROWS)
    check_range("--record-every", record_every, 1, max(n_steps, 1))

    kw = _system_overrides(args)
    if bar == "ball":
        kw.update(gap=gap, friction=friction_on)
    system = make_system(bar, args.preset, **kw)
    initial = _initial(args, [gap] if bar == "ball" else [])
    run = simulate(system, forcing, duration=args.duration_s, dt=args.dt_s, initial=initial,
                   record_every=record_every, integrator=args.integrator)

    from boringbar.io import write_json_atomic, write_netcdf_atomic
    from boringbar.plot import plot_run

    out = Path(args.out)
    files = {"netcdf": out / "run.nc", "png": out / "run.png", "summary": out / "summary.json"}
    ds = _history_dataset(run)
    write_netcdf_atomic(ds, files["netcdf"])
    plot_run(ds, files["png"])
    summary = {**run.summary(), "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic({**summary, "config": run.config()}, files["summary"])
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_cut_text(summary) if "cutting" in summary else _simulate_text(summary, run))
    return 0


def _one_bar(args, command: str) -> tuple[str, bool]:
    """--bar and --friction of the commands that run one system, checked with
    the common options: (bar, friction on)."""
    bars = _words(args.bar, "--bar", BAR_KINDS, ["ball"])
    if len(bars) != 1:
        raise ParameterError(f"--bar = {','.join(bars)!r}: {command} runs one bar "
                             f"(one of {', '.join(BAR_KINDS)})")
    _check_common(args, bars)
    friction = _words(args.friction, "--friction", ("on", "off"), ["on"])
    if len(friction) != 1:
        raise ParameterError(f"--friction = {args.friction!r} must be one of on, off")
    friction_on = friction[0] == "on"
    if not friction_on and (args.friction_force_n is not None
                            or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    return bars[0], friction_on


#: simulate options that describe a cut (dest names); refused with harmonic forcing
CUT_ONLY = ("kr_mpa", "feed_mm", "revolutions", "delay_interp", "start", "bounded_fraction",
            "stop_at_zero")


def _simulate_forcing(args):
    """Harmonic(F0, ratio), or Regenerative when --rpm and --depth-mm are given."""
    from boringbar.forcing import Harmonic, Regenerative

    if args.rpm is not None:
        _check_rpm(args.rpm)
    if args.depth_mm is not None:
        check_range("--depth-mm", args.depth_mm, 0, math.inf, lo_open=True, hi_open=True,
                    unit="mm")
    if args.rpm is None and args.depth_mm is None:
        given = [o for o in CUT_ONLY if getattr(args, o) not in (None, False)]
        if given:
            raise ParameterError(f"--{given[0].replace('_', '-')} applies only to a cut "
                                 "(--rpm with --depth-mm)")
        force = 10.0 if args.force_n is None else args.force_n
        ratio = 1.0 if args.ratio is None else args.ratio
        check_range("--force-n", force, 0, math.inf, hi_open=True, unit="N")
        check_range("--ratio", ratio, 0, math.inf, lo_open=True, hi_open=True)
        return Harmonic(force, ratio)
    if args.rpm is None or args.depth_mm is None:
        have, need = ("--rpm", "--depth-mm") if args.depth_mm is None else ("--depth-mm",
                                                                            "--rpm")
        raise ParameterError(f"{have} needs {need}: a cut takes both")
    for name, value in (("--force-n", args.force_n), ("--ratio", args.ratio)):
        if value is not None:
            raise ParameterError(f"{name} = {value:g} is harmonic forcing and cannot be mixed "
                                 "with a cut (--rpm, --depth-mm): give one or the other")
    return Regenerative(depth=args.depth_mm * 1e-3, rpm=args.rpm,
                        stop_at_zero=args.stop_at_zero, **_cut_options(args))


def _history_dataset(run):
    """``run.history_dataset()``, with the metrics as plain Python numbers first.

    Workaround: the kernel's metrics are numpy floats, so ``Run.cutting``'s
    ``bounded_chatter`` comes out a numpy bool, which the ``json.dumps`` inside
    ``history_dataset`` refuses.  The values are unchanged.
    """
    run.metrics = {k: v.item() if isinstance(v, np.generic) else v
                   for k, v in run.metrics.items()}
    return run.history_dataset()


def _cut_text(s: dict) -> str:
    c = s["cutting"]
    cfg = "static start" if c["start"] == "static" else "from rest"
    lines = [
        f"{s['bar']} bar, {s['preset']} preset: cut at {c['rpm']:g} rpm "
        f"({s['forcing_frequency_hz']:.2f} Hz), depth {c['depth_m'] * 1e3:g} mm, {cfg}",
        f"  natural frequency  {s['natural_frequency_hz']:.2f} Hz",
    ]
    if c["chatter"]:
        lines.append(f"  verdict            CHATTER: the force first reaches zero at "
                     f"t = {c['first_zero_time_s']:.4g} s (the tool leaves the cut)")
    else:
        lines.append(f"  verdict            stable: the force never reaches zero in "
                     f"{s['duration_s']:g} s")
    lines += [
        f"  bounded chatter    {'yes' if c['bounded_chatter'] else 'no'} (steady amplitude "
        f"{c['amplitude_m'] * 1e3:.4g} mm, threshold {c['bounded_threshold_m'] * 1e3:.4g} mm)",
        f"  cutting force      mean {c['mean_force_n']:.4g} N, max {c['max_force_n']:.4g} N "
        f"({c['steps_with_zero_force']} steps at zero)",
        f"  tip                static deflection {c['static_deflection_m'] * 1e3:.4g} mm, "
        f"max |W| {s['max_abs_tip_m'] * 1e3:.4g} mm",
        f"  delay interp.      {c['delay_interpolation']}",
        f"  elapsed            {s['elapsed_s']:.2f} s",
        "  wrote " + ", ".join(s["files"].values()),
    ]
    return "\n".join(lines)


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

def _forces_and_ratios(args):
    """--force-n and --ratios lists, checked, and --workers checked."""
    from boringbar.analysis.sweep import parse_range

    forces = _numbers(args.force_n, "--force-n")
    for f in forces:
        check_range("--force-n", f, 0, math.inf, hi_open=True, unit="N")
    ratios = parse_range(args.ratios, "--ratios")
    for r in ratios:
        check_range("--ratios", r, 0, math.inf, lo_open=True, hi_open=True)
    if args.workers is not None:
        check_range("--workers", args.workers, 1, 4096)
    return forces, ratios


def _cmd_sweep(args) -> int:
    from boringbar.analysis.sweep import sweep, sweep_summary

    cases, bars, gaps = _many_cases(args)
    forces, ratios = _forces_and_ratios(args)

    initial = _initial(args, gaps if "ball" in bars else [])
    progress = _progress(args, "sweep", "runs")
    ds = sweep(cases, ratios, forces, duration=args.duration_s, dt=args.dt_s,
               workers=args.workers, initial=initial, progress=progress,
               integrator=args.integrator)

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


def _progress(args, command: str, what: str):
    """A progress(done, total) printer on a terminal's stderr, else None."""
    if args.quiet or not sys.stderr.isatty():
        return None

    def progress(done, total):
        end = "\n" if done == total else ""
        print(f"\r{PROG} {command}: {done}/{total} {what}", end=end, file=sys.stderr,
              flush=True)
    return progress


def _many_cases(args) -> tuple[list, list[str], list[float]]:
    """The cases of sweep and lobes from --bar, --gap-mm, --friction and the
    overrides: (cases, bars, gaps in m)."""
    bars = _words(args.bar, "--bar", BAR_KINDS, ["solid", "tmd", "ball"])
    _check_common(args, bars)
    gaps = [_check_gap(g) for g in _numbers(args.gap_mm or "0.5,0.1", "--gap-mm")]
    frictions = [w == "on" for w in _words(args.friction, "--friction", ("on", "off"),
                                           ["off", "on"])]
    if not any(frictions) and (args.friction_force_n is not None
                               or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    return _sweep_cases(args, bars, gaps, frictions), bars, gaps


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


PATTERN_KEY = ("patterns: Ns = N symmetric impacts per period, Na/k = N asymmetric impacts "
               "per k periods, st = sticking, 0 = no impact, 0+st = no impact with sticking, "
               "nu = non-uniform")


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
    lines.append(PATTERN_KEY)
    return "\n".join(lines)


# --- lobes -----------------------------------------------------------------------

def _cmd_lobes(args) -> int:
    from boringbar.analysis.lobes import PUBLISHED_RPM, lobes, lobes_summary
    from boringbar.analysis.sweep import parse_range

    cases, _, _ = _many_cases(args)
    rpm = PUBLISHED_RPM if args.rpm is None else parse_range(args.rpm, "--rpm")
    for r in rpm:
        _check_rpm(r)
    step = check_range("--depth-step-mm", args.depth_step_mm, 0, math.inf, lo_open=True,
                       hi_open=True, unit="mm")
    check_range("--max-depth-mm", args.max_depth_mm, step, 1000, unit="mm")
    check_range("--successive", args.successive, 1, 100)
    if args.workers is not None:
        check_range("--workers", args.workers, 1, 4096)
    cut = _cut_options(args)
    ds = lobes(cases, rpm, method=args.method, depth_step=step * 1e-3,
               max_depth=args.max_depth_mm * 1e-3, successive=args.successive,
               criterion=args.criterion, duration=args.duration_s, dt=args.dt_s,
               workers=args.workers, progress=_progress(args, "lobes", "(case, speed) columns"),
               integrator=args.integrator, **cut)

    from boringbar.io import write_netcdf_atomic
    from boringbar.plot import plot_lobe_examples, plot_lobes

    out = Path(args.out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "lobes.nc"),
             "png": plot_lobes(ds, out / "lobes.png")}
    examples = []
    if args.examples:
        exds = _lobe_examples(ds, cases[0], args, cut)
        files["examples_netcdf"] = write_netcdf_atomic(exds, out / "examples.nc")
        files["examples_png"] = plot_lobe_examples(exds, out / "examples.png")
        examples = [{"example": str(e), "case": exds.attrs["case"],
                     "rpm": float(exds["rpm"].values[k]),
                     "depth_m": float(exds["depth"].values[k]),
                     "chatter": bool(exds["chatter"].values[k]),
                     "bounded_chatter": bool(exds["bounded_chatter"].values[k]),
                     "first_zero_time_s": float(exds["first_zero_time"].values[k])}
                    for k, e in enumerate(exds["example"].values)]
    summary = {**lobes_summary(ds), "files": {k: str(v) for k, v in files.items()}}
    if args.examples:
        summary["examples"] = examples
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_lobes_text(ds))
        for e in examples:
            verdict = (f"chatter (force first zero at {e['first_zero_time_s']:.3g} s)"
                       if e["chatter"] else "stable (force never zero)")
            print(f"example {e['example']}: {e['case']} at {e['rpm']:g} rpm, depth "
                  f"{e['depth_m'] * 1e3:g} mm: {verdict}")
        print("wrote " + ", ".join(str(v) for v in files.values()))
    return 0


def _example_points(ds) -> list[tuple[str, float, float]]:
    """(name, rpm, depth) of a stable and an unstable grid point of the first case:
    the limiting and the first unstable depth at the speed of the minimum
    chatter-free depth (the stable one at the speed of the largest limit if the
    minimum is 0; only a stable one if nothing chattered)."""
    rpm = ds["rpm"].values
    limit = ds["limit_depth"].values[0]
    first = ds["first_unstable_depth"].values[0]
    if not np.isfinite(limit).any():  # no chatter up to the deepest cut tried
        run = ds["verdict"].values[0] >= 0
        j = len(rpm) // 2
        return [("stable", float(rpm[j]), float(ds["depth"].values[run[j]].max()))]
    j = int(np.nanargmin(limit))
    points = [("unstable", float(rpm[j]), float(first[j]))]
    if limit[j] <= 0:
        j = int(np.nanargmax(limit))
    if limit[j] > 0:
        points.insert(0, ("stable", float(rpm[j]), float(limit[j])))
    return points


def _lobe_examples(ds, case, args, cut: dict):
    """Rerun the example points with history (no stop at the first zero): one
    Dataset with dims (example, time)."""
    import pandas as pd
    import xarray as xr

    from boringbar.forcing import Regenerative
    from boringbar.simulate import simulate

    points = _example_points(ds)
    n_steps = int(round(args.duration_s / args.dt_s))
    parts = []
    for _, rpm, depth in points:
        run = simulate(case.system, Regenerative(depth=depth, rpm=rpm, **cut),
                       duration=args.duration_s, dt=args.dt_s,
                       record_every=max(1, n_steps // HISTORY_ROWS),
                       integrator=args.integrator)
        h = _history_dataset(run)
        h = h.drop_vars([v for v in ("impact_time", "impact_wall") if v in h])
        c = run.cutting
        h = h.assign_coords(rpm=rpm, depth=depth, chatter=bool(c["chatter"]),
                            bounded_chatter=bool(c["bounded_chatter"]),
                            first_zero_time=math.nan if c["first_zero_time_s"] is None
                            else float(c["first_zero_time_s"]),
                            mean_force=float(run.forcing.mean_force),
                            static_deflection=float(c["static_deflection_m"]))
        parts.append(h)
    exds = xr.concat(parts, dim=pd.Index([p[0] for p in points], name="example"),
                     coords="all", join="outer", combine_attrs="drop")
    exds["rpm"].attrs["units"] = "rev/min"
    for name in ("depth", "static_deflection"):
        exds[name].attrs["units"] = "m"
    exds["first_zero_time"].attrs["units"] = "s"
    exds["mean_force"].attrs.update(units="N", long_name="Kr b h_m")
    exds.attrs = {"title": "boringbar lobe examples: grid points rerun with history",
                  "case": str(case.label), "bar": case.bar, "gap_m": case.gap,
                  "friction": case.friction, "preset": case.system.preset,
                  "criterion": ds.attrs["criterion"],
                  "boringbar_version": ds.attrs["boringbar_version"],
                  "configs": "[" + ", ".join(p.attrs["config"] for p in parts) + "]",
                  "summaries": "[" + ", ".join(p.attrs["summary"] for p in parts) + "]"}
    return exds


def _lobes_text(ds) -> str:
    lines = []
    analytic = ds["analytic_limit"].values if "analytic_limit" in ds else None
    depths = ds["depth"].values
    chosen = ds["verdict" if ds.attrs["criterion"] == "zero" else "verdict_bounded"].values

    def mm(v: float) -> str:
        return f"{v * 1e3:.3f}" if math.isfinite(v) else "-"

    for i, label in enumerate(ds["case"].values):
        limit = ds["limit_depth"].values[i]
        first = ds["first_unstable_depth"].values[i]
        mcf = float(ds["min_chatter_free_depth"].values[i])
        at = (f" at {ds['rpm'].values[int(np.nanargmin(limit))]:g} rpm"
              if np.isfinite(limit).any() else "")
        lines.append(f"{label}: minimum chatter-free depth {mm(mcf)} mm{at}")
        lines.append(f"{'rpm':>8} {'limit (mm)':>12} {'first unstable (mm)':>20} "
                     f"{'analytic (mm)':>14}")
        islands = []
        for j, r in enumerate(ds["rpm"].values):
            a = math.nan if analytic is None else float(analytic[i, j])
            lines.append(f"{r:8g} {mm(limit[j]):>12} {mm(first[j]):>20} {mm(a):>14}")
            above = (depths > first[j]) & (chosen[i, j] == 1)
            if math.isfinite(first[j]) and above.any():
                islands.append(f"{r:g}")
        if islands:
            lines.append(f"  stable islands above the first unstable depth at "
                         f"{', '.join(islands)} rpm")
        lines.append("")
    lines.append(f"'-': no chatter up to the deepest cut tried (or no analytic limit); "
                 f"method {ds.attrs['method']}, criterion {ds.attrs['criterion']}, "
                 f"{ds.attrs['runs']} runs in {ds.attrs['wall_time_s']:.1f} s")
    return "\n".join(lines)


# --- bifurcation -----------------------------------------------------------------

#: What bifurcation can sweep: option -> (library parameter, SI per option unit,
#: allowed range (lo, hi, lo_open, hi_open), unit).
SWEEPABLE = {
    "--force-n": ("force", 1.0, (0.0, math.inf, False, True), "N"),
    "--ratio": ("ratio", 1.0, (0.0, math.inf, True, True), ""),
    "--gap-mm": ("gap", 1e-3, (0.0, math.inf, True, True), "mm"),
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
    from boringbar.analysis.sweep import parse_range

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


def _cmd_bifurcation(args) -> int:
    from boringbar.analysis.bifurcation import bifurcation, hysteresis_ranges
    from boringbar.forcing import Harmonic
    from boringbar.system import make_system

    args = argparse.Namespace(**vars(args))  # _swept turns the strings into numbers
    option, values = _swept(args)
    bar, friction_on = _one_bar(args, "bifurcation")
    check_range("--drop", args.drop, 0, 1, hi_open=True)
    parameter, si = SWEEPABLE[option][:2]
    gaps = values if option == "--gap-mm" else [0.5 if args.gap_mm is None else args.gap_mm]
    gaps = [_check_gap(g) for g in gaps]
    force = 10.0 if args.force_n is None else args.force_n
    ratio = 1.0 if args.ratio is None else args.ratio

    kw = _system_overrides(args)
    if bar == "ball":
        kw.update(gap=gaps[0], friction=friction_on)
    target = make_system(bar, args.preset, **kw)
    if parameter in ("gap", "restitution"):
        def target(value):  # the factory: one System per value
            return make_system(bar, args.preset, **{**kw, parameter: value})
    ds = bifurcation(target, parameter, values * si, base_forcing=Harmonic(force, ratio),
                     duration=args.duration_s, dt=args.dt_s, drop=args.drop,
                     initial=_initial(args, gaps if bar == "ball" else []),
                     backward=not args.no_backward, units="m" if parameter == "gap" else "1",
                     progress=_progress(args, "bifurcation", "runs"),
                     integrator=args.integrator)
    ranges = hysteresis_ranges(ds) if not args.no_backward else None
    ds.attrs.update(preset=args.preset, bar=bar, swept_option=option,
                    hysteresis_ranges=json.dumps(ranges),
                    hysteresis_note="parameter ranges (start, stop) in the parameter's SI "
                                    "units where the forward and backward Poincare sets "
                                    "differ (analysis.bifurcation.hysteresis_ranges)")

    from boringbar.io import write_netcdf_atomic
    from boringbar.plot import plot_bifurcation

    out = Path(args.out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "bifurcation.nc"),
             "png": plot_bifurcation(ds, out / "bifurcation.png")}
    summary = {**_bifurcation_summary(ds, ranges),
               "files": {k: str(v) for k, v in files.items()}}
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_bifurcation_text(ds, ranges))
        print("wrote " + ", ".join(str(v) for v in files.values()))
    return 0


def _bifurcation_summary(ds, ranges) -> dict:
    """What ``bifurcation --json`` prints: per direction and value the W samples (m)."""
    config = json.loads(ds.attrs["config"])
    dirs = [str(d) for d in ds["direction"].values]

    def per_value(name: str, direction: str) -> list:
        return ds[name].sel(direction=direction).values.tolist()

    def samples(direction: str) -> list[list[float]]:
        row = ds.sel(direction=direction)
        return [w[:n].tolist() for w, n in zip(row["tip_displacement"].values,
                                               row["n_samples"].values, strict=True)]

    return {
        "parameter": ds.attrs["parameter"],
        "units": ds.attrs["units"],
        "values": ds["value"].values.tolist(),
        "preset": ds.attrs["preset"],
        "bar": ds.attrs["bar"],
        "base_forcing": config["base_forcing"],
        "duration_s": config["duration_s"],
        "dt_s": config["dt_s"],
        "drop": config["drop"],
        "forward": samples("forward"),
        "backward": samples("backward") if "backward" in dirs else None,
        "verdicts": {d: per_value("verdict", d) for d in dirs},
        "period": {d: per_value("period", d) for d in dirs},
        "rms_tip_m": {d: per_value("rms_tip_m", d) for d in dirs},
        "pattern": {d: per_value("pattern", d) for d in dirs},
        "hysteresis_ranges": None if ranges is None else [list(r) for r in ranges],
        "wall_time_s": ds.attrs["wall_time_s"],
    }


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
            pat = _short_pattern(row["pattern"].values)
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


# --- basins ----------------------------------------------------------------------

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
    check_range(f"{name} COUNT", n, 1, 10000)
    return lo, hi, n


def _pair(text: str, name: str) -> tuple[float, float]:
    values = _numbers(text, name)
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise ParameterError(f"{name} = {text!r} must be two numbers, MM,M/S")
    return values[0], values[1]


def _cmd_basins(args) -> int:
    from boringbar.analysis.basins import basin_summary, basins
    from boringbar.analysis.poincare import poincare_map
    from boringbar.forcing import Harmonic
    from boringbar.io import jsonable
    from boringbar.simulate import Initial, simulate
    from boringbar.system import make_system

    bar, friction_on = _one_bar(args, "basins")
    gap = _check_gap(0.5 if args.gap_mm is None else args.gap_mm)
    force = 10.0 if args.force_n is None else args.force_n
    ratio = 1.0 if args.ratio is None else args.ratio
    check_range("--force-n", force, 0, math.inf, hi_open=True, unit="N")
    check_range("--ratio", ratio, 0, math.inf, lo_open=True, hi_open=True)
    check_range("--drop", args.drop, 0, 1, hi_open=True)
    lo, hi, n = _grid(args.displacement_mm, "--displacement-mm")
    displacement = (lo * 1e-3, hi * 1e-3, n)
    velocity = _grid(args.velocity_m_s, "--velocity-m-s")
    w0, v0 = _pair(args.poincare_from, "--poincare-from")
    if args.workers is not None:
        check_range("--workers", args.workers, 1, 4096)
    y0 = 0.0
    if args.ball_position_mm is not None:
        y0 = check_range("--ball-position-mm", args.ball_position_mm, -gap / 2 * 1e3,
                         gap / 2 * 1e3, unit="mm") * 1e-3
    yv0 = args.ball_velocity_m_s or 0.0

    kw = _system_overrides(args)
    if bar == "ball":
        kw.update(gap=gap, friction=friction_on)
    system = make_system(bar, args.preset, **kw)
    forcing = Harmonic(force, ratio)
    ds = basins(system, forcing, displacement=displacement, velocity=velocity,
                duration=args.duration_s, dt=args.dt_s, drop=args.drop, ball_position=y0,
                ball_velocity=yv0, workers=args.workers,
                progress=_progress(args, "basins", "runs"), integrator=args.integrator)
    # the Poincare map beside the basins: data first, so it goes into basins.nc
    run = simulate(system, forcing, duration=args.duration_s, dt=args.dt_s,
                   initial=Initial(w0 * 1e-3, v0, y0, yv0), steady_fraction=1 - args.drop,
                   strobe=True, integrator=args.integrator)
    pm = poincare_map(run, args.drop)
    verdict = pm.classify()
    ds = ds.assign(
        poincare_from_tip_m=("poincare_sample", pm.tip_displacement,
                             {"units": "m", "long_name": "W at Omega t = 0 mod 2 pi, from "
                                                         "--poincare-from"}),
        poincare_from_tip_velocity_m_s=("poincare_sample", pm.tip_velocity,
                                        {"units": "m/s", "long_name": "W' at Omega t = 0 mod "
                                                                      "2 pi, from "
                                                                      "--poincare-from"}))
    poincare = {"tip_displacement_m": w0 * 1e-3, "tip_velocity_m_s": v0,
                "ball_position_m": y0, "ball_velocity_m_s": yv0,
                "verdict": verdict["verdict"], "period": verdict["k"],
                "distinct": verdict["distinct"], "n_samples": len(pm.time),
                "rms_tip_m": run.rms_tip,
                "pattern": "" if run.pattern is None else run.pattern.name}
    ds.attrs.update(bar=bar, poincare_from=json.dumps(jsonable(poincare)))

    from boringbar.io import write_netcdf_atomic
    from boringbar.plot import plot_basins

    out = Path(args.out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "basins.nc"),
             "png": plot_basins(ds, out / "basins.png")}
    summary = {**basin_summary(ds), "poincare_from": poincare,
               "files": {k: str(v) for k, v in files.items()}}
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_basins_text(summary))
        print("wrote " + ", ".join(str(v) for v in files.values()))
    return 0


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


# --- sensitivity -----------------------------------------------------------------

#: sensitivity: the option each KIND replaces
KIND_OPTIONS = {"ball": ("ball", "--ball"), "restitution": ("restitution", "--restitution"),
                "friction_number": ("friction_number", "--friction-number")}


def _sensitivity_values(args, bar: str, gap: float):
    """--values as the library takes them (SI), or None for the published ones."""
    from boringbar.system import BALLS

    kind, text = args.kind, args.values
    if text is None:
        return None
    if kind == "ball":
        return _words(text, "--values", BALLS, [])
    if kind != "initial":
        values = _numbers(text, "--values")
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


def _cmd_sensitivity(args) -> int:
    from boringbar.analysis.sensitivity import Cuts, sensitivity
    from boringbar.analysis.sweep import parse_range

    kind = args.kind
    bar, friction_on = _one_bar(args, f"sensitivity {kind}")
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
    gap = _check_gap(0.5 if args.gap_mm is None else args.gap_mm)
    values = _sensitivity_values(args, bar, gap)
    forces, ratios = _forces_and_ratios(args)
    cuts = None
    if args.cut_rpm is not None or args.depths_mm is not None:
        rpm = _check_rpm(1200.0 if args.cut_rpm is None else args.cut_rpm, "--cut-rpm")
        depths = parse_range(args.depths_mm or "0.05:0.10:0.01", "--depths-mm")
        for d in depths:
            check_range("--depths-mm", d, 0, math.inf, lo_open=True, hi_open=True, unit="mm")
        cuts = Cuts(rpm, tuple(float(d) * 1e-3 for d in depths), args.duration_s,
                    _cut_options(args))
    else:
        given = [o for o in CUT_ONLY if getattr(args, o, None) not in (None, False)]
        if given:
            raise ParameterError(f"--{given[0].replace('_', '-')} applies only to cuts "
                                 "(--cut-rpm or --depths-mm)")

    common = dict(preset=args.preset, bar=bar, gap=gap, friction=friction_on,
                  duration=args.duration_s, dt=args.dt_s, workers=args.workers,
                  integrator=args.integrator, **_system_overrides(args))
    ds = sensitivity(kind, values, forces=forces, ratios=ratios,
                     progress=_progress(args, f"sensitivity {kind}", "runs"), **common)
    if cuts is not None:
        ds = _with_cuts(ds, sensitivity(kind, values, cutting=cuts, **common))

    from boringbar.io import write_netcdf_atomic
    from boringbar.plot import plot_sensitivity

    out = Path(args.out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "sensitivity.nc"),
             "png": plot_sensitivity(ds, out / "sensitivity.png")}
    summary = {**_sensitivity_summary(ds), "files": {k: str(v) for k, v in files.items()}}
    if args.json:
        _print_json(summary)
    elif not args.quiet:
        print(_sensitivity_text(summary))
        print("wrote " + ", ".join(str(v) for v in files.values()))
    return 0


def _with_cuts(ds, cuts):
    """The harmonic and the cut results in one Dataset: the cut variables and
    attributes prefixed ``cut_``."""
    import xarray as xr

    cuts = cuts.rename({k: f"cut_{k}" for k in cuts.data_vars})
    keep = ("rpm", "duration_s", "wall_time_s", "forcing_options", "title")
    attrs = {f"cut_{k}": v for k, v in cuts.attrs.items() if k in keep}
    merged = xr.merge([ds, cuts.drop_vars([c for c in ("case",) if c in cuts.coords])],
                      combine_attrs="override")
    merged.attrs.update(attrs)
    return merged


def _sensitivity_summary(ds) -> dict:
    kind = ds.attrs["sensitivity"]
    labels = [str(v) for v in ds[kind].values]
    values = [v.item() if isinstance(v, np.generic) else v for v in ds[kind].values]
    harmonic = []
    for i, value in enumerate(values):
        for j, force in enumerate(ds["force"].values):
            harmonic.append({"value": value, "force_n": float(force),
                             "ratio": ds["ratio"].values.tolist(),
                             "rms_tip_m": ds["rms_tip_m"].values[i, j].tolist(),
                             "pattern": [str(p) for p in ds["pattern"].values[i, j]]})
    summary = {"kind": kind, "values": values, "preset": ds.attrs.get("preset"),
               "harmonic": harmonic, "cuts": None, "wall_time_s": ds.attrs.get("wall_time_s")}
    if kind == "initial":
        summary["initial"] = [{name: float(ds[name].values[i]) for name in
                               ("tip_displacement", "tip_velocity", "ball_position",
                                "ball_velocity")} for i in range(len(labels))]
    if "cut_chatter" in ds:
        summary["cuts"] = {
            "rpm": ds.attrs["cut_rpm"], "depth_m": ds["depth"].values.tolist(),
            "results": [{"value": value,
                         **{k: ds[f"cut_{k}"].values[i].tolist()
                            for k in ("chatter", "bounded_chatter", "amplitude_m",
                                      "max_force_n", "first_zero_time_s")}}
                        for i, value in enumerate(values)]}
    return summary


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
                pat = _short_pattern(h["pattern"][k])
                cells.append((f"{h['rms_tip_m'][k] * 1e3:.4f}"
                              + (f" [{pat}]" if pat else "")).rjust(width))
            lines.append(f"{ratio:7.3f} " + "".join(cells))
        lines.append("")
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


# --- entry point -----------------------------------------------------------------

def _print_json(obj) -> None:
    from boringbar.io import jsonable

    print(json.dumps(jsonable(obj), allow_nan=False))


def main(argv=None) -> int:
    """Run the command line; returns the exit code (0 ok, 2 bad input, 1 I/O error)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors
        return exc.code if isinstance(exc.code, int) else 0
    compile_notices(not getattr(args, "quiet", False))  # --quiet: no compile notice either
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
