"""Options and checks shared by the ``boringbar`` subcommands: the common option groups,
the parsing of lists and ranges, and progress lines."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.cases import MAX_GRID_VALUES, parse_range, published_cases
from boringbar.analysis.verdict import VerdictOptions
from boringbar.cli.orientation import add_orientation, check_orientation, orientation_overrides
from boringbar.execute import Execution
from boringbar.io import jsonable
from boringbar.model.contact import CONTACT_LAWS
from boringbar.model.cutting import KR_ALUMINIUM, WORKPIECES, CuttingLaw, cutting_law
from boringbar.model.dampers import (
    BALL_MOTIONS,
    MAX_FRICTION_FORCE,
    MU_KINETIC,
    MU_MAX,
    MU_STATIC,
)
from boringbar.model.forcing import (
    INTERPOLATIONS,
    MAX_FEED,
    MAX_KR,
    STARTS,
    check_force,
    check_lobe_speed,
    check_ratio,
)
from boringbar.model.measured_frf import CSV_SUFFIXES, UFF_SUFFIXES, read_frf
from boringbar.model.modal_fit import ModalFit
from boringbar.model.system import (
    BALLS,
    BAR_KINDS,
    FRICTION_READINGS,
    PRESETS,
    published_system_spec,
)
from boringbar.model.system_file import load_system
from boringbar.progress import LineProgress, ProgressCallback
from boringbar.simulate import (
    INTEGRATOR_CHOICES,
    MAX_INITIAL_DISPLACEMENT,
    MAX_INITIAL_VELOCITY,
    STEADY_FRACTION,
    STICK_LAWS,
    Initial,
    Integration,
    fixed_run_step,
)
from boringbar.simulate.run_limits import check_delay, check_step, check_steps

PROG = "boringbar"
#: Most worker threads or processes an option may ask for.
MAX_WORKERS = 4096
BALL_OPTIONS = ("gap_mm", "friction", "friction_force_n", "friction_number",
                "friction_reading", "friction_reaction", "ball", "restitution", "locked",
                "ball_position_mm", "ball_velocity_m_s", "static_ratio", "contact",
                "contact_stiffness", "ball_motion", "mu_static", "mu_kinetic")


def add_common(p: argparse.ArgumentParser, many: bool, harmonic: bool = True,
                initial: bool = True, ranges: bool = False) -> dict:
    """Options shared by every command; ``many``: the list forms of sweep and
    lobes; ``harmonic``: the F0 and Omega options; ``initial``: the initial
    conditions; ``ranges``: --gap-mm and --restitution also take
    START:STOP:STEP (bifurcation; strings, parsed by the command).  Returns
    the option groups by name, for command-specific options."""
    groups = {}
    lst = ", comma list" if many else ""
    g = p.add_argument_group("bar and damper")
    g.add_argument("--system", metavar="FILE.toml",
                   help="your own bar: a system file (docs/systems.md); default: the "
                        "published bar (examples/systems/published.toml)")
    g.add_argument("--frf", metavar="FIT.json",
                   help="a modal model fitted to a measured tip FRF (boringbar fit-frf) in "
                        "place of the FE bar; give --frf-ball-ratio / --frf-absorber-ratio "
                        "(lobes --analytic: also a measured FRF, .csv or .uff, as it is)")
    g.add_argument("--frf-ball-ratio", type=float, metavar="R",
                   help="psi(z_ball)/psi(tip) of every fitted mode (a tip FRF cannot know it)")
    g.add_argument("--frf-absorber-ratio", type=float, metavar="R",
                   help="psi(z_absorber)/psi(tip) of every fitted mode")
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
                        "(default: " + ("0.5,0.1; with --system, its gap" if many
                                      else "the system file's, 0.5 published") + ")")
    add_ball(g, lst, swept, ranges, many)
    g.add_argument("--modes", type=int, metavar="N",
                   help="retained bending modes (default: physical 2, paper 1)")
    g.add_argument("--tmd-design", choices=("given", "published", "den-hartog", "sims"),
                   help="TMD tuning: given (the system file's absorber; published: the same), "
                        "den-hartog or sims (default: physical the file's tuning, paper given)")
    add_orientation(p)

    g = groups["run"] = p.add_argument_group("forcing and integration")
    if harmonic and many:
        g.add_argument("--force-n", default="10,20", metavar="N,...",
                       help="harmonic force amplitudes F0 in N (default: 10,20)")
        g.add_argument("--ratios", metavar="START:STOP:STEP",
                       help="Omega/omega_n values, START:STOP:STEP (inclusive) or comma list "
                            "(default: 0.95:1.05:0.01, published, widened to both peaks of "
                            "a tuned mass damper)")
    elif harmonic:  # None: not given (a cut refuses them); defaults in cmd_simulate
        g.add_argument("--force-n", type=float, metavar="N",
                       help="harmonic force amplitude F0 in N (default: 10)")
        g.add_argument("--ratio", type=float, metavar="R",
                       help="Omega/omega_n of the host bar (default: 1.0)")
    g.add_argument("--duration-s", type=float, default=2.0, metavar="S",
                   help="simulated time in s (default: 2.0)")
    add_step(g)
    g.add_argument("--integrator", choices=INTEGRATOR_CHOICES, default="auto",
                   help="auto (default): exact for harmonic runs, rk4 under the paper "
                        "preset and in cuts; rk4: the published fixed-step scheme; exact: "
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
    g.add_argument("--out", metavar="DIR", help=OUT_HELP)
    g.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    g.add_argument("--quiet", action="store_true", help="no progress and no human summary")
    return groups


def add_ball(g, lst: str, swept: str, ranges: bool, many: bool) -> None:
    """The ball's options of :func:`add_common`: its friction, material, restitution,
    lock and contact law."""
    g.add_argument("--friction", metavar="on|off" + (",..." if many else ""),
                   help=f"ball friction{lst} (default: {'off,on' if many else 'on'}; with "
                        "--system, the file's ball's); its size depends on the preset")
    g.add_argument("--friction-force-n", type=float, metavar="N",
                   help="friction force F_c in N (overrides the preset's)")
    g.add_argument("--friction-number", type=float, metavar="X",
                   help="published rolling-resistance number (0.6 nominal), read as the "
                        "preset reads it")
    g.add_argument("--friction-reading", choices=FRICTION_READINGS,
                   help="how the published number is read: paper (as the paper computed it, "
                        "20.4 N) or rolling (a length in mm, 0.0204 N); default: the preset's")
    g.add_argument("--friction-reaction", choices=("reciprocal", "printed"),
                   help="the bar's friction reaction: reciprocal (-psi_d F_b) or printed "
                        "(+psi_d F_b, as published); default: the preset's")
    g.add_argument("--ball", choices=BALLS, help="ball material (default: carbide)")
    g.add_argument("--restitution", type=None if ranges else float,
                   metavar="E|START:STOP:STEP" if ranges else "E",
                   help=f"coefficient of restitution in [0, 1]{swept} (default: 0.7)")
    g.add_argument("--locked", action="store_true", help="fix the ball to the bar")
    g.add_argument("--static-ratio", type=float, metavar="X",
                   help="static friction limit F_s/F_c >= 1 of true stick-slip (default: 1; "
                        "other values need --integrator exact)")
    g.add_argument("--ball-motion", choices=BALL_MOTIONS,
                   help="how the ball moves: slide (default; the published model) or roll "
                        "(its spin a state: it rolls while --mu-static holds it, slips with "
                        "--mu-kinetic; the exact integrator takes it under harmonic forcing, "
                        "RK4 in cuts; docs/model.md, 2.7)")
    g.add_argument("--mu-static", type=float, metavar="MU",
                   help=f"a rolling ball's static floor friction coefficient, >= --mu-kinetic "
                        f"(default {MU_STATIC:g}; refused for a sliding ball)")
    g.add_argument("--mu-kinetic", type=float, metavar="MU",
                   help=f"a rolling ball's kinetic floor friction coefficient (default "
                        f"{MU_KINETIC:g})")
    g.add_argument("--contact", choices=CONTACT_LAWS,
                   help="how the ball meets its plugs: impact (default; the published "
                        "instantaneous law) or hertz (a compliant Hertz contact with "
                        "Hunt-Crossley damping for the restitution; needs --integrator rk4 "
                        "or auto; docs/model.md, section 2.6)")
    g.add_argument("--contact-stiffness", type=float, metavar="K",
                   help="a Hertz contact's stiffness K in N/m^1.5, > 0 (default: Hertz's "
                        "from the ball's and the plug's materials; refused with the impact "
                        "law)")


def check_rolling(args) -> None:
    """--mu-static and --mu-kinetic in [0, MU_MAX], the static at least the kinetic."""
    for name in ("mu_static", "mu_kinetic"):
        if getattr(args, name, None) is not None:
            check_range("--" + name.replace("_", "-"), getattr(args, name), 0, MU_MAX)
    mus = MU_STATIC if args.mu_static is None else args.mu_static
    muk = MU_KINETIC if args.mu_kinetic is None else args.mu_kinetic
    if (args.mu_static is not None or args.mu_kinetic is not None) and mus < muk:
        raise ParameterError(f"--mu-static = {mus:g} is below --mu-kinetic = {muk:g}: a ball "
                             "that slips with mu_kinetic is held by at least as much")


def add_cutting(g) -> None:
    """The cut's description, shared by simulate and lobes (docs/model.md, section 4).
    Defaults are None here (so simulate can refuse them without a cut) and
    applied in :func:`cut_options`."""
    g.add_argument("--kr-mpa", type=float, metavar="MPA",
                   help="the linear law's specific radial cutting force Kr in MPa (default: "
                        "850, aluminium, as published)")
    g.add_argument("--workpiece", metavar="NAME",
                   help="Kienzle's cutting law of a workpiece material, instead of --kr-mpa: "
                        f"{', '.join(WORKPIECES)} (docs/model.md, section 4.3)")
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


def add_verdict(g, knocks: str = "only the small 1 um knock") -> None:
    """How the converged verdict judges a cut (analysis/verdict.py; docs/chatter.md);
    ``knocks``: the starts a command takes without --knock-um, in words."""
    g.add_argument("--tolerance-um", type=float, metavar="UM",
                   help="largest settled tip peak-to-peak that is chatter-free, in um (a "
                        "surface-finish budget; default: 10)")
    g.add_argument("--knock-um", action="append", metavar="UM[,UM...]",
                   help="also start each cut from a knock of this tip amplitude in um (a "
                        "large disturbance; repeatable); the chatter-free depth must hold "
                        f"from every start (default: {knocks})")
    g.add_argument("--confidence", type=float, metavar="X",
                   help="confidence of a growth rate's sign, in (0.5, 1) (default: 0.99)")
    g.add_argument("--max-run-s", type=float, metavar="S",
                   help="the longest a cut runs before it is called undecided, in s "
                        "(default: 10)")


def add_step(g) -> None:
    """--dt-s and --stick-law: RK4's step and its law of a ball's friction."""
    g.add_argument("--dt-s", type=float, metavar="S",
                   help="RK4 time step in s; with --integrator exact, the step of the "
                        "recorded history (default: the published 1e-6; a cut judged by "
                        "the converged verdict: 2e-6, or finer for a bar with high modes)")
    g.add_argument("--stick-law", choices=STICK_LAWS,
                   help="how RK4 renders a ball's friction: sgn, the published "
                        "F_b = -F_c sgn(y'), or hold, which holds the ball exactly while "
                        "friction can (default: sgn for runs of fixed length, hold for a "
                        "cut judged by the converged verdict; docs/model.md, 5.1)")


def verdict_options(args) -> VerdictOptions:
    """The converged verdict's options of the command line, checked under its names."""
    d = VerdictOptions()
    tol = d.tolerance_m * 1e6 if args.tolerance_um is None else args.tolerance_um
    check_range("--tolerance-um", tol, 0.0, 1e6, lo_open=True, unit="um")
    knocks = [float(v) for k in args.knock_um or [] for v in str(k).split(",") if v.strip()]
    for k in knocks:
        check_range("--knock-um", k, 0.0, 1e4, lo_open=True, unit="um")
    conf = d.confidence if args.confidence is None else args.confidence
    check_range("--confidence", conf, 0.5, 0.999999, lo_open=True)
    cap = d.max_duration_s if args.max_run_s is None else args.max_run_s
    check_range("--max-run-s", cap, 0.0, 1000.0, lo_open=True, unit="s")
    # divided, not multiplied: 10 um is then 1e-05 m to the bit
    return VerdictOptions(confidence=conf, max_duration_s=cap, tolerance_m=tol / 1e6,
                          knocks_m=tuple(k / 1e6 for k in knocks),
                          stick_law=getattr(args, "stick_law", None) or d.stick_law)


def add_steady_fraction(group) -> None:
    group.add_argument("--steady-fraction", type=float, default=STEADY_FRACTION, metavar="F",
                       help="the last part of each run that is sampled (RMS, patterns, "
                            "Poincare samples), in (0, 1] (default: 0.8: the first 20 %% "
                            "dropped)")


def parse_words(values, name: str, choices, default) -> list[str]:
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


def parse_numbers(text: str, name: str) -> list[float]:
    """A comma list of at most MAX_GRID_VALUES numbers (each checked by the caller)."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ParameterError(f"{name} = {text!r} must be a comma-separated list of "
                             "numbers") from None
    if len(values) > MAX_GRID_VALUES:
        raise ParameterError(f"{name} has {len(values)} values; the allowed maximum is "
                             f"{MAX_GRID_VALUES}")
    return values


def check_common(args, bars: list[str]) -> None:
    resolve_files(args, bars)
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
        check_range("--friction-force-n", args.friction_force_n, 0, MAX_FRICTION_FORCE,
                    unit="N")
    if args.friction_number is not None:
        check_range("--friction-number", args.friction_number, 0, 100)
    if args.static_ratio is not None:
        check_range("--static-ratio", args.static_ratio, 1, math.inf, hi_open=True)
    if args.restitution is not None:
        check_range("--restitution", args.restitution, 0, 1)
    check_orientation(args, bars)
    check_rolling(args)
    if args.contact_stiffness is not None:
        check_range("--contact-stiffness", args.contact_stiffness, 0, math.inf, lo_open=True,
                    hi_open=True, unit="N/m^1.5")
    if args.modes is not None:
        check_range("--modes", args.modes, 1, 8)
    check_steps(args.duration_s, fixed_run_step(args.dt_s), ("--duration-s", "--dt-s"))


def system_spec(args):
    """The --system file, read once (``args.system_spec``; None: not given)."""
    if not hasattr(args, "system_spec"):
        args.system_spec = None if args.system is None else load_system(args.system)
    return args.system_spec


def default_bars(args, many: bool) -> list[str]:
    """The bars a command runs when --bar is not given: the ball damper (``many``:
    the solid bar, the TMD and the ball damper), of those the system file has.  With a
    fitted FRF (--frf FIT.json) a comparison takes the TMD and the ball only where their
    mode-shape ratio is given (a tip FRF cannot know them)."""
    spec = system_spec(args) or published_system_spec()
    have = ["solid"] + (["tmd"] if spec.tmd else []) + (["ball"] if spec.ball else [])
    if many:
        fitted = getattr(args, "frf", None) is not None and not _measured(args.frf)
        given = {"tmd": getattr(args, "frf_absorber_ratio", None),
                 "ball": getattr(args, "frf_ball_ratio", None)}
        return [b for b in have if not fitted or given.get(b, 0.0) is not None]
    return [have[-1]]


def _measured(frf: str) -> bool:
    """Whether --frf names a measured FRF (CSV or UFF), not a fit's modal_fit.json."""
    return Path(frf).suffix.lower() in CSV_SUFFIXES + UFF_SUFFIXES


def resolve_files(args, bars: list[str]) -> None:
    """Read --system and --frf once into ``args.system_spec`` and ``args.frf_modal``."""
    system_spec(args)
    args.frf_modal = args.frf_measured = None
    ratios = {"ball": ("--frf-ball-ratio", args.frf_ball_ratio),
              "tmd": ("--frf-absorber-ratio", args.frf_absorber_ratio)}
    if args.frf is None:
        given = [opt for opt, v in ratios.values() if v is not None]
        if given:
            raise ParameterError(f"{given[0]} applies only with --frf")
        return
    if _measured(args.frf):
        if not getattr(args, "analytic", False):
            raise ParameterError(f"--frf = {args.frf!r} is a measured FRF: fit it first "
                                 f"(boringbar fit-frf {args.frf}) and give its modal_fit.json, "
                                 "or draw its classical lobes with 'lobes --analytic'")
        args.frf_measured = read_frf(args.frf)
        return
    for bar in bars:
        if bar in ratios and ratios[bar][1] is None:
            raise ParameterError(f"--frf with --bar {bar} needs {ratios[bar][0]}: a tip FRF "
                                 "cannot know the mode shape there")
    for opt, value in ratios.values():
        if value is not None:
            check_range(opt, value, -10, 10)
    args.frf_modal = ModalFit.read(args.frf, "--frf").to_modal_model(
        *(1.0 if r is None else r for r in (args.frf_ball_ratio, args.frf_absorber_ratio)))


#: --out's help: each command and each bar writes to its own folder by default, so that
#: no run overwrites another's files
OUT_HELP = ("output directory (default: out/COMMAND/NAME: NAME the input file's, or "
            "published, and the bars given with --bar where the command takes it; a rerun "
            "with other options writes over it)")


def default_out(args) -> Path:
    """out/COMMAND/NAME: NAME the stem of the command's input (its positional file, the
    --system file or the --frf fit), "published" without one, followed by the bars
    given with --bar ("published-tmd"), so that each bar's run keeps its own files."""
    source = (getattr(args, "file", None) or getattr(args, "system", None)
              or getattr(args, "frf", None))
    name = Path(source).stem if source else "published"
    bars = getattr(args, "bar", None)
    if isinstance(bars, list) and bars:
        name += "".join(f"-{w.strip()}" for b in bars for w in b.split(",") if w.strip())
    elif isinstance(bars, str):
        name += f"-{bars}"
    return Path("out") / args.command / name


def gap_default_mm(args) -> float:
    """The gap (mm) when --gap-mm is not given: the system file's (0.5 published)."""
    spec = args.system_spec or published_system_spec()
    return spec.data["ball"]["gap_mm"] if spec.ball is not None else 0.5


def friction_default(args) -> list[str] | None:
    """--friction when not given with --system: the file's ball's (``on`` unless its
    friction is ``none``), as its gap is; None without a file's ball (the study's)."""
    spec = system_spec(args)
    if spec is None or spec.ball is None:
        return None
    return ["off" if spec.ball.friction_kind == "none" else "on"]


def check_gap(gap_mm: float, args) -> float:
    """--gap-mm (mm) checked against the room the bar's cavity leaves; returns metres."""
    spec = system_spec(args) or published_system_spec()
    why = "at most the cavity's depth less the ball" if spec.ball is not None else ""
    return check_range("--gap-mm", gap_mm, 0, spec.max_gap() * 1e3, lo_open=True,
                       unit="mm", why=why) * 1e-3


def check_dt(args, systems, ratio: float = 0.0) -> None:
    """--dt-s resolves the highest mode of every system and the forcing at ``ratio``
    (the largest Omega/omega_n; 0: only the modes)."""
    dt = fixed_run_step(args.dt_s)
    for system in systems:
        check_step(system, ratio * system.reference_frequency_rad_s, dt, "--dt-s")


def check_workers(workers, name: str = "--workers") -> None:
    if workers is not None:
        check_int(name, workers, 1, MAX_WORKERS)


def initial_conditions(args, gaps_m: list[float]):
    d, v = MAX_INITIAL_DISPLACEMENT * 1e3, MAX_INITIAL_VELOCITY
    if args.ball_position_mm is not None and gaps_m:
        half = min(gaps_m) / 2 * 1e3
        check_range("--ball-position-mm", args.ball_position_mm, -half, half, unit="mm")
    if args.ball_velocity_m_s is not None:
        check_range("--ball-velocity-m-s", args.ball_velocity_m_s, -v, v, unit="m/s")
    return Initial(
        tip_displacement_m=check_range("--tip-displacement-mm", args.tip_displacement_mm, -d, d,
                                     unit="mm") * 1e-3,
        tip_velocity_m_s=check_range("--tip-velocity-m-s", args.tip_velocity_m_s, -v, v,
                                 unit="m/s"),
        ball_position_m=(args.ball_position_mm or 0.0) * 1e-3,
        ball_velocity_m_s=args.ball_velocity_m_s or 0.0,
    )


def cut_options(args) -> dict:
    """The cut options as Regenerative keywords (SI), checked, defaults applied: the law
    is ``workpiece`` (--workpiece, Kienzle's) or ``kr_pa`` (--kr-mpa, linear), not both."""
    workpiece = getattr(args, "workpiece", None)
    if workpiece is not None and args.kr_mpa is not None:
        raise ParameterError(f"--kr-mpa = {args.kr_mpa:g} (the linear law) and --workpiece = "
                             f"{workpiece!r} (Kienzle's law): give one")
    if workpiece is not None and workpiece not in WORKPIECES:
        raise ParameterError(f"--workpiece = {workpiece!r} is not a known material; the known "
                             f"ones are {', '.join(WORKPIECES)}")
    if workpiece is not None and getattr(args, "integrator", None) == "exact":
        raise ParameterError(f"--workpiece = {workpiece!r} (Kienzle's law) needs --integrator "
                             "rk4 or auto: the exact integrator's cut is linear in the state")
    kr = 850.0 if args.kr_mpa is None else args.kr_mpa
    feed = 0.1 if args.feed_mm is None else args.feed_mm
    revolutions = 3 if args.revolutions is None else args.revolutions
    fraction = 0.1 if args.bounded_fraction is None else args.bounded_fraction
    check_range("--kr-mpa", kr, 0, MAX_KR * 1e-6, lo_open=True, unit="MPa")
    check_range("--feed-mm", feed, 0, MAX_FEED * 1e3, lo_open=True, unit="mm")
    check_int("--revolutions", revolutions, 1, 50)
    check_range("--bounded-fraction", fraction, 0, math.inf, lo_open=True, hi_open=True)
    law = {"workpiece": workpiece} if workpiece is not None else {"kr_pa": kr * 1e6}
    return {**law, "feed_m": feed * 1e-3, "revolutions": revolutions,
            "interpolation": args.delay_interp or "cubic", "start": args.start or "rest",
            "bounded_fraction": fraction}


def cut_law(cut: dict) -> CuttingLaw:
    """The cutting law of :func:`cut_options`' keywords."""
    return cutting_law(cut.get("kr_pa", KR_ALUMINIUM), cut.get("workpiece"))


def check_rpm(rpm: float, args, name: str = "--rpm") -> float:
    """A spindle speed: positive, its period at least 4 steps of --dt-s, its delay
    history (--revolutions) within the allowed rows."""
    revolutions = 3 if args.revolutions is None else args.revolutions
    check_int("--revolutions", revolutions, 1, 50)
    check_delay(rpm, revolutions, fixed_run_step(args.dt_s), name)
    return float(rpm)


AT_RPM_HELP = ("your spindle speed in rev/min (> 0): added to the speeds exactly (the grid "
               "reaches it if it lies outside), marked on the figure with each bar's "
               "chatter-free depth there, which the summary reads out (JSON: at_rpm, and "
               "depth_at_rpm_m per case)")


def with_speed(rpm, at_rpm: float | None) -> tuple[float, ...]:
    """The speeds ``rpm`` with the user's speed ``at_rpm`` (``--at-rpm``; None: none)
    among them exactly: in place of a speed within round-off of it, else inserted in
    order, so the grid reaches it when it lies outside and its depth is computed, not
    interpolated between two speeds."""
    rpm = [float(r) for r in rpm]
    if at_rpm is None:
        return tuple(rpm)
    at_rpm = check_lobe_speed("--at-rpm", at_rpm)
    return tuple(sorted([r for r in rpm if not math.isclose(r, at_rpm, rel_tol=1e-9)]
                        + [float(at_rpm)]))


def system_overrides(args) -> dict:
    """make_system keywords the user set (the preset decides the rest)."""
    kw = {"ball": args.ball, "restitution": args.restitution, "n_modes": args.modes,
          "friction_number": args.friction_number, "friction_force_n": args.friction_force_n,
          "friction_reading": args.friction_reading,
          "friction_reaction": args.friction_reaction,
          "tmd_design": args.tmd_design, "locked": args.locked or None,
          "static_ratio": args.static_ratio, "spec": args.system_spec,
          "contact": args.contact, "contact_stiffness_n_m1_5": args.contact_stiffness,
          "motion": args.ball_motion, "mu_static": args.mu_static,
          "mu_kinetic": args.mu_kinetic,
          **orientation_overrides(args),
          "modal": args.frf_modal}
    return {k: v for k, v in kw.items() if v is not None}


def one_bar(args, command: str) -> tuple[str, bool]:
    """--bar and --friction of the commands that run one system, checked with
    the common options: (bar, friction on)."""
    bars = parse_words(args.bar, "--bar", BAR_KINDS, default_bars(args, many=False))
    if len(bars) != 1:
        raise ParameterError(f"--bar = {','.join(bars)!r}: {command} runs one bar "
                             f"(one of {', '.join(BAR_KINDS)})")
    check_common(args, bars)
    friction = parse_words(args.friction, "--friction", ("on", "off"),
                           friction_default(args) or ["on"])
    if len(friction) != 1:
        raise ParameterError(f"--friction = {args.friction!r} must be one of on, off")
    friction_on = friction[0] == "on"
    if not friction_on and (args.friction_force_n is not None
                            or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    return bars[0], friction_on


#: simulate options that describe a cut (dest names); refused with harmonic forcing
CUT_ONLY = ("kr_mpa", "workpiece", "feed_mm", "revolutions", "delay_interp", "start",
            "bounded_fraction", "stop_at_zero")


def forces_and_ratios(args):
    """--force-n and --ratios lists, checked (ratios None: not given), and --workers
    checked."""

    forces = parse_numbers(args.force_n, "--force-n")
    for f in forces:
        check_force(f)
    ratios = None if args.ratios is None else parse_range(args.ratios, "--ratios")
    for r in () if ratios is None else ratios:
        check_ratio(r, "--ratios")
    check_workers(args.workers)
    return forces, ratios


def progress_printer(args, command: str, what: str):
    """A progress(done, total) callback: a bar on a terminal's stderr, a line at each tenth
    of the work where stderr is a log (a long job's file or a scheduler's), None with
    --quiet."""
    if args.quiet:
        return None
    if not sys.stderr.isatty():
        return LineProgress(f"{PROG} {command}", what)
    return ProgressCallback(f"{PROG} {command}", what)


def many_cases(args) -> tuple[list, list[str], list[float]]:
    """The cases of sweep and lobes from --bar, --gap-mm, --friction and the
    overrides: (cases, bars, gaps in m)."""
    bars = parse_words(args.bar, "--bar", BAR_KINDS, default_bars(args, many=True))
    check_common(args, bars)
    default = "0.5,0.1" if args.system is None else repr(gap_default_mm(args))
    gaps = [check_gap(g, args) for g in parse_numbers(args.gap_mm or default, "--gap-mm")]
    frictions = [w == "on" for w in parse_words(args.friction, "--friction", ("on", "off"),
                                           friction_default(args) or ["off", "on"])]
    if not any(frictions) and (args.friction_force_n is not None
                               or args.friction_number is not None):
        raise ParameterError("--friction off conflicts with --friction-force-n / "
                             "--friction-number")
    return _sweep_cases(args, bars, gaps, frictions), bars, gaps


def _sweep_cases(args, bars, gaps, frictions) -> list:
    """published_cases, in the user's order; a friction override applies to the
    friction-on ball cases only (make_system would otherwise give the 'off'
    cases that friction too)."""

    kw = system_overrides(args)
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


PATTERN_KEY = ("patterns: Ns = N symmetric impacts per period, Na/k = N asymmetric impacts "
               "per k periods, st = sticking, 0 = no impact, 0+st = no impact with sticking, "
               "nu = non-uniform")


def wrote(files: dict) -> str:
    """The line naming the files a command wrote (a value may be a list of paths)."""
    paths = [p for v in files.values() for p in (v if isinstance(v, list) else [v])]
    return "wrote " + ", ".join(map(str, paths))


def print_json(obj) -> None:
    print(json.dumps(jsonable(obj), allow_nan=False))


@dataclass(frozen=True)
class Outcome:
    """What a command produced: its ``summary`` (the --json object) and ``text(say)``,
    which says the human-readable report line by line (``say`` is print, or a
    collector)."""

    summary: dict
    text: Callable[[Callable[[str], None]], None]

    def report(self, args) -> None:
        """Print the summary as JSON (--json), or the text unless --quiet."""
        if args.json:
            print_json(self.summary)
        elif not args.quiet:
            self.text(print)


def warn_line(message: str) -> None:
    """Say ``message`` as one warning line on stderr: the command goes on, its results
    are written, but they look wrong."""
    print(f"{PROG}: warning: {' '.join(message.split())}", file=sys.stderr)


def integration(args, initial=None, steady_fraction: float = STEADY_FRACTION) -> Integration:
    """The integration options of a command (--duration-s, --dt-s, --integrator; a step
    not given is left to each analysis: Integration.dt_s None)."""
    return Integration(args.duration_s, args.dt_s, args.integrator, steady_fraction, initial,
                       getattr(args, "stick_law", None) or "sgn")


def execution(args) -> Execution:
    """Where a command's points run: the analysis's choice (Execution "auto": a process
    per core for judged cuts, else a thread), on every core or --workers."""
    return Execution(workers=args.workers)
