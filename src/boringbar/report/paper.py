"""``boringbar paper``: the whole published study (docs/model.md, section 6) under both
presets, and a report comparing them.

The study is a list of :class:`Step` s. Each step is one published analysis,
run with the library (its files written by :mod:`boringbar.report.outputs`, as
the commands write them) once per preset into ``OUT/<preset>/<step>/``, beside
the ``boringbar`` command that reruns it by hand (shown in the report with the
figure; tests/test_paper_steps.py checks that it gives the same numbers).  Steps
finish atomically: a step's ``summary.json`` is written last, after its NetCDF
files and figures, and a rerun of ``boringbar paper`` with the same options
skips every step whose summary is there with the same command, so an
interrupted study resumes where it stopped. ``--quick`` runs the same steps on
coarser grids and shorter runs (written in the report, and in each step's
command).

Beside the published analyses, ``corrections`` measures what each correction
to the published equations (docs/model.md, section 8) changes
(:mod:`boringbar.report.corrections`). The report (:mod:`boringbar.report.html`)
is written last, from the files on disk.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed, wait
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import xarray as xr

from boringbar._validate import ParameterError
from boringbar.analysis.basins import BasinOptions, basins
from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation, with_hysteresis
from boringbar.analysis.cases import parse_range, published_cases
from boringbar.analysis.continuation import ContinuationOptions, continuation
from boringbar.analysis.cut_continuation import CutContinuationOptions, cut_continuation
from boringbar.analysis.design import comparison, design
from boringbar.analysis.design_file import load_design
from boringbar.analysis.lobe_examples import examples as lobe_examples
from boringbar.analysis.lobes import PUBLISHED_RPM, LobesOptions, lobes
from boringbar.analysis.sensitivity import Cuts, SensitivityOptions, sensitivity, with_cuts
from boringbar.analysis.sweep import SweepOptions, sweep
from boringbar.execute import Execution
from boringbar.io import (
    jsonable,
    remove_stale_temporaries,
    save_figure_atomic,
    write_json_atomic,
    write_netcdf_atomic,
)
from boringbar.model.forcing import Regenerative
from boringbar.model.system import make_system
from boringbar.plot.variations import plot_ladder
from boringbar.report.corrections import absorber_designs, impact_law_check, readings_ladder
from boringbar.report.html import write_report
from boringbar.report.outputs import (
    basins_files,
    bifurcation_files,
    chatter_orbit_files,
    continuation_files,
    design_files,
    lobes_files,
    sensitivity_files,
    sweep_files,
)
from boringbar.simulate import HISTORY_ROWS, STEADY_FRACTION, Initial, Integration
from boringbar.version import __version__

PRESET_ORDER = ("paper", "physical")
#: The quick study's lobe speeds (rev/min): every fourth published speed. Half of the
#: quick study's time went to its lobes at every second one; docs/paper.md says what
#: the coarser grid changes.
QUICK_RPM = "1000:1600:200"
#: The published lobe grid, given on every lobes command of the study (the command's
#: own defaults follow the bar): its speeds (PUBLISHED_RPM) and 0.01 mm depth steps.
PUBLISHED_SPEEDS = "900:1600:50"
PUBLISHED_DEPTHS = ("--depth-step-mm", "0.01")
#: Steps computed at once (:func:`_run_steps`).
STEP_WORKERS = min(2, os.cpu_count() or 1)


@dataclass(frozen=True)
class Column:
    """One column of the study: a preset, with some of its published readings
    changed (``overrides``: :func:`~boringbar.model.system.make_system` keywords of
    the ball damper, as ``(name, value)`` pairs; none for the two presets).
    ``shares_frictionless``: the column's steps without friction are its preset's (a
    friction reading changes nothing there), so it shares their records; a rolling
    ball changes every step."""

    name: str
    preset: str
    overrides: tuple[tuple[str, str], ...] = ()
    description: str = ""
    shares_frictionless: bool = True

    @property
    def kw(self) -> dict:
        return dict(self.overrides)

    @property
    def flags(self) -> tuple[str, ...]:
        """The command-line flags that select this column."""
        extra = (w for k, v in self.overrides
                 for w in (FLAG_OF.get(k, "--" + k.replace("_", "-")), v))
        return ("--preset", self.preset, *extra)


#: The command-line flag of an override whose flag is not its keyword's name.
FLAG_OF = {"motion": "--ball-motion"}


#: The study's columns: the two presets, two presets with one friction reading
#: changed, which separate what the friction's size explains from what the printed
#: sign of the bar's reaction explains (docs/audit.md, "The further columns"), and the
#: physical preset with a rolling ball.
COLUMNS = {
    "paper": Column("paper", "paper", (), "as published"),
    "physical": Column("physical", "physical", (), "as physics demands"),
    "paper-reciprocal": Column(
        "paper-reciprocal", "paper", (("friction_reaction", "reciprocal"),),
        "the paper preset with the bar's friction reaction reciprocal (-psi_d F_b): "
        "the published 20.4 N friction, the printed sign corrected"),
    "physical-paper-friction": Column(
        "physical-paper-friction", "physical",
        (("friction_reading", "paper"), ("friction_reaction", "reciprocal")),
        "the physical preset with the friction force as the paper computed it (20.4 N "
        "for the carbide ball) and a reciprocal reaction"),
    "physical-rolling": Column(
        "physical-rolling", "physical", (("motion", "roll"),),
        "the physical preset with a rolling ball (docs/model.md, 2.7): its spin a state, "
        "rolling while mu_s m g holds it and slipping with mu_k m g beyond (0.2, 0.15)",
        shares_frictionless=False),
}
#: The further columns, in order.
VARIANT_ORDER = ("paper-reciprocal", "physical-paper-friction", "physical-rolling")
COLUMN_ORDER = PRESET_ORDER + VARIANT_ORDER

#: The command line's defaults, as the steps' commands leave them: the time step
#: (None: each analysis's own, the published 1e-6 s or a judged cut's), the integrator,
#: the sampled part of each run, the ball damper's gap (mm) and a cut's description
#: (``boringbar lobes`` and ``sensitivity``, SI).
DT_S = None
INTEGRATOR = "auto"
GAP_MM = 0.5
#: The sensitivity step's starts of the ball's harmonic runs (``--starts``): D4 compares the
#: steel and carbide balls' RMS at r = 1, both rattling, beyond their spread over starts.
BALL_STARTS = 8
CUT = {"kr_pa": 850.0 * 1e6, "feed_m": 0.1 * 1e-3, "revolutions": 3, "interpolation": "cubic",
       "start": "rest", "bounded_fraction": 0.1}


@dataclass(frozen=True)
class Step:
    """One published analysis: ``run(preset, out) -> summary`` computes it with the
    library and writes its files into ``out``; ``argv`` is the ``boringbar`` command
    (without ``--preset``, ``--out`` and ``--json``) that does the same by hand,
    shown in the report."""

    key: str
    section: str
    title: str
    argv: tuple[str, ...]
    run: Callable[[Column, Path], dict]
    #: whether a case of the step has friction on: the further columns change only
    #: the friction, so they rerun only these steps (the rest they share)
    friction: bool = True
    #: whether the further columns rerun it at all (the design searches do not)
    variants: bool = True
    #: what the further columns run instead, if not the same: (argv, run)
    lean: tuple | None = None
    #: the steps of the same column whose files it reads (it starts after them)
    after: tuple[str, ...] = ()

    def for_column(self, column: str) -> Step:
        """The step as ``column`` runs it (a further column: its lean version)."""
        if column in PRESET_ORDER or self.lean is None:
            return self
        return replace(self, argv=self.lean[0], run=self.lean[1], lean=None)


def _integration(duration_s: float, initial: Initial | None = None) -> Integration:
    return Integration(duration_s, DT_S, INTEGRATOR, STEADY_FRACTION, initial)


def _at_rest() -> Initial:
    """The initial conditions the command line gives sweep and bifurcation."""
    return Initial(0.0 * 1e-3, 0.0, 0.0 * 1e-3, 0.0)


def _sweep_cases(col: Column) -> list:
    """The cases of sweep and lobes by default: solid, TMD, and the ball damper at
    each gap (0.5, 0.1 mm) x friction (off, on), in the command line's order."""
    return published_cases(preset=col.preset, gaps_m=(0.5 * 1e-3, 0.1 * 1e-3), **col.kw)


def _sweep_run(forces: str, ratios: str, duration_s: float):
    def run(col: Column, out: Path) -> dict:
        options = SweepOptions(tuple(parse_range(ratios, "--ratios")),
                               tuple(float(f) for f in forces.split(",")))
        ds = sweep(_sweep_cases(col), options,
                   integration=_integration(duration_s, _at_rest()), execution=Execution())
        return sweep_files(ds, out)
    return run


def _lobes_run(method: str, rpm: str | None, duration_s: float, ball: str | None = None):
    def run(col: Column, out: Path) -> dict:
        cases = (_sweep_cases(col) if ball is None else
                 published_cases(("ball",), (0.5e-3, 0.1e-3), preset=col.preset, ball=ball,
                                 **col.kw))
        speeds = PUBLISHED_RPM if rpm is None else parse_range(rpm, "--rpm")
        # the criterion follows the preset, as on the command line: the published one
        # under paper, the converged verdict under physical (docs/chatter.md)
        options = LobesOptions(tuple(speeds), method, None, 0.01 * 1e-3, 3.0 * 1e-3, 3, **CUT)
        integration = _integration(duration_s)
        ds = lobes(cases, options, integration=integration, execution=Execution())
        exds = None if ball is not None else lobe_examples(ds, cases[0], options,
                                                           integration=integration,
                                                           rows=HISTORY_ROWS)
        return lobes_files(ds, out, exds)
    return run


def _bifurcation_run(gap_mm: str, friction: bool, forces: str, ratio: str, duration_s: float):
    def run(col: Column, out: Path) -> dict:
        values = parse_range(forces, "--force-n")
        system = make_system("ball", col.preset, gap_m=float(gap_mm) * 1e-3, friction=friction,
                             **col.kw)
        # the command line sets the swept option to its first value
        options = BifurcationOptions("force", tuple(values * 1.0), float(values[0]), float(ratio),
                                     backward=True, units="1")
        ds = with_hysteresis(bifurcation(system, options,
                                         integration=_integration(duration_s, _at_rest())))
        ds.attrs.update(preset=col.preset, bar="ball", swept_option="--force-n")
        return bifurcation_files(ds, out)
    return run


#: The continuation step's maps start from the settled orbit at this F0 (N).
CONTINUATION_START_N = 30.0


@dataclass(frozen=True)
class MapSettings:
    """The continuation step's orbit maps over [lo, hi] N: per branch at most
    ``max_points`` points (first step ``step`` of the range), brute force's attractors at
    ``seeds`` values seed branches (and at twice as many are checked), at most
    ``max_branches`` branches."""

    lo: float
    hi: float
    max_points: int
    seeds: int
    max_branches: int
    step: float = 0.05
    max_step: float = 0.025

    def options(self) -> ContinuationOptions:
        return ContinuationOptions(parameter="force-n", stop=self.hi, other_end=self.lo,
                                   force_n=CONTINUATION_START_N, ratio=1.0, step=self.step,
                                   max_step=self.max_step, max_points=self.max_points,
                                   seeds=self.seeds, max_branches=self.max_branches)

    def argv(self) -> tuple[str, ...]:
        """The ``boringbar continue`` flags of the same map."""
        return ("--ratio", "1.0", "--range", f"{self.lo:g}:{CONTINUATION_START_N:g}:{self.hi:g}",
                "--step", f"{self.step:g}", "--max-step", f"{self.max_step:g}",
                "--max-points", str(self.max_points), "--seeds", str(self.seeds),
                "--max-branches", str(self.max_branches))


def _continuation_run(settings: MapSettings):
    """The orbit maps in F0 of the four bifurcation cases (``settings``: from the settled
    orbit at CONTINUATION_START_N, with switching and seeds), each drawn over its
    bifurcation step's diagram if on disk."""
    def run(col: Column, out: Path) -> dict:
        cases = {}
        for gap in ("0.1", "0.5"):
            for fr in ("off", "on"):
                system = make_system("ball", col.preset, gap_m=float(gap) * 1e-3,
                                     friction=fr == "on", **col.kw)
                ds = continuation(system, options=settings.options())
                ds.attrs.update(preset=col.preset, bar="ball")
                nc = out.parent / f"bifurcation-gap{gap}-friction{fr}" / "bifurcation.nc"
                overlay = xr.load_dataset(nc) if nc.exists() else None
                cases[f"gap{gap}-friction{fr}"] = continuation_files(
                    ds, out, f"gap{gap}-friction{fr}", overlay)
        ncs = [c["files"]["netcdf"] for c in cases.values()]
        return {"start_n": CONTINUATION_START_N, "cases": cases,
                "files": {"netcdf": ncs[0], "netcdfs": ncs,
                          "png": [c["files"]["png"] for c in cases.values()]}}
    return run


#: The chatter orbits' speed (rev/min), the published cut's, and their depth range (mm).
CUT_ORBIT_RPM, CUT_ORBIT_RANGE_MM = "1200", "0:1"


def _cut_orbits_run(max_points: int):
    """The chatter orbit map of the published solid, absorber and ball bars (gap 0.5 mm,
    friction on) at CUT_ORBIT_RPM, as ``boringbar continue --cut`` makes it."""
    def run(col: Column, out: Path) -> dict:
        systems = {bar: make_system(bar, col.preset, **col.kw) for bar in ("solid", "tmd")}
        systems["ball"] = make_system("ball", col.preset, gap_m=GAP_MM * 1e-3, friction=True,
                                      **col.kw)
        lo, hi = (float(v) * 1e-3 for v in CUT_ORBIT_RANGE_MM.split(":"))
        forcing = Regenerative(depth_m=hi, rpm=float(CUT_ORBIT_RPM), kr_pa=CUT["kr_pa"],
                               feed_m=CUT["feed_m"], revolutions=CUT["revolutions"])
        ds = cut_continuation(systems, forcing, CutContinuationOptions(
            depth_range_m=(lo, hi), max_points=max_points))
        return chatter_orbit_files(ds, out)
    return run


def _grid(text: str) -> tuple[float, float, int]:
    lo, hi, n = text.split(":")
    return float(lo), float(hi), int(n)


def _basins_run(force: str, ratio: str, friction: bool, start: str, displacement_mm: str,
                velocity_m_s: str, duration_s: float):
    def run(col: Column, out: Path) -> dict:
        lo, hi, n = _grid(displacement_mm)
        w0, v0 = (float(v) for v in start.split(","))
        system = make_system("ball", col.preset, gap_m=GAP_MM * 1e-3, friction=friction,
                             **col.kw)
        options = BasinOptions((lo * 1e-3, hi * 1e-3, n), _grid(velocity_m_s), 0.0, 0.0,
                               float(force), float(ratio), poincare_from=(w0 * 1e-3, v0))
        ds = basins(system, options, integration=_integration(duration_s),
                    execution=Execution())
        ds.attrs.update(bar="ball")
        return basins_files(ds, out)
    return run


def _sensitivity_run(kind: str, force: str, ratios: str, cut_rpm: str | None,
                     depths_mm: str | None, duration_s: float, starts: int = 0):
    def run(col: Column, out: Path) -> dict:
        common = dict(preset=col.preset, bar="ball", gap_m=GAP_MM * 1e-3, friction=True,
                      overrides=col.kw, integration=_integration(duration_s),
                      execution=Execution())
        ds = sensitivity(SensitivityOptions(kind, None, (float(force),),
                                            tuple(parse_range(ratios, "--ratios")),
                                            starts=starts), **common)
        if cut_rpm is not None:
            depths = parse_range(depths_mm, "--depths-mm")
            cuts = Cuts(float(cut_rpm), tuple(float(d) * 1e-3 for d in depths), duration_s,
                        dict(CUT))
            ds = with_cuts(ds, sensitivity(SensitivityOptions(kind, None, cuts=cuts), **common))
        return sensitivity_files(ds, out)
    return run


def _design_run(name: str, trials: int):
    def run(col: Column, out: Path) -> dict:
        options, spec = load_design(design_file(name))
        options = replace(options, trials=trials, preset=col.preset)
        execution = Execution("threads")
        ds = design(options, spec=spec, storage=out / "design.journal", execution=execution)
        return design_files(ds, comparison(spec, options, ds, execution=execution), out)
    return run


def design_file(name: str) -> str:
    """The path of a design file of the report (report/designs/NAME.toml)."""
    return str(resources.files("boringbar.report").joinpath("designs", f"{name}.toml"))


def published_steps(quick: bool = False) -> list[Step]:
    """The steps of the published study (docs/model.md, section 6); ``quick``: coarser."""
    duration = 0.5 if quick else 2.0
    dur = ("--duration-s", "0.5") if quick else ()
    ratios = "0.95:1.05:" + ("0.02" if quick else "0.01")
    steps = [Step("sweep", "sweeps", "Frequency sweeps of tip RMS, F0 = 10 and 20 N",
                  ("sweep", "--force-n", "10,20", "--ratios", ratios, *dur),
                  _sweep_run("10,20", ratios, duration))]
    # the published scan in full; the bisection search (the same limits on every
    # published case, docs) on a coarser speed grid with 1 s cuts in the quick version
    if quick:
        steps.append(Step("lobes", "lobes", "Stability lobes by time-domain simulation",
                          ("lobes", "--examples", "--method", "search", "--rpm",
                           QUICK_RPM, *PUBLISHED_DEPTHS, "--duration-s", "1.0"),
                          _lobes_run("search", QUICK_RPM, 1.0)))
    else:
        # the further columns take the bisection search: fewer runs than the scan for
        # the same 0.01 mm limits (docs/paper.md says what was compared)
        steps.append(Step("lobes", "lobes", "Stability lobes by time-domain simulation",
                          ("lobes", "--examples", "--method", "scan", "--rpm",
                           PUBLISHED_SPEEDS, *PUBLISHED_DEPTHS),
                          _lobes_run("scan", None, 2.0),
                          lean=(("lobes", "--examples", "--method", "search", "--rpm",
                                 PUBLISHED_SPEEDS, *PUBLISHED_DEPTHS),
                                _lobes_run("search", None, 2.0))))
    # a steel ball's lobes (the claim that it lowers the chatter-free depth), by the
    # bisection search on the published speeds: the same limits as the scan, cheaper
    steel_rpm = QUICK_RPM if quick else PUBLISHED_SPEEDS
    steel_s = 1.0 if quick else 2.0
    steps.append(Step("lobes-steel", "lobes", "Stability lobes with a steel ball",
                      ("lobes", "--bar", "ball", "--ball", "steel", "--method", "search",
                       "--rpm", steel_rpm, *PUBLISHED_DEPTHS,
                       *(("--duration-s", "1.0") if quick else ())),
                      _lobes_run("search", steel_rpm, steel_s, ball="steel"),
                      variants=False))  # the further columns judge D4 on the 1200 rpm cuts
    forces = "5:50:" + ("5" if quick else "1")
    for gap in ("0.1", "0.5"):
        for fr in ("off", "on"):
            steps.append(Step(
                f"bifurcation-gap{gap}-friction{fr}", "bifurcation",
                f"Bifurcation diagram over F0, gap {gap} mm, friction {fr}",
                ("bifurcation", "--bar", "ball", "--gap-mm", gap, "--friction", fr,
                 "--force-n", forces, "--ratio", "1.0", *dur),
                _bifurcation_run(gap, fr == "on", forces, "1.0", duration), friction=fr == "on"))
    # quick: steps up to a tenth of the range, 10 points a branch, 8 branches followed,
    # so that the maps cost a few seconds more than the single branches they replaced
    # (docs/continuation.md, "In the published study")
    maps = MapSettings(5.0, 50.0, 10, 3, 8, max_step=0.1) if quick else \
        MapSettings(5.0, 50.0, 40, 3, 24, max_step=0.025)
    steps.append(Step("continuation", "continuation",
                      "Orbit maps (continued periodic orbits) over the bifurcation diagrams",
                      ("continue", "--bar", "ball", "--gap-mm", "0.5", "--friction", "off",
                       *maps.argv()),
                      _continuation_run(maps), variants=False,
                      after=tuple(s.key for s in steps if s.section == "bifurcation")))
    orbits = 24 if quick else 200
    steps.append(Step("chatter-orbits", "chatter-orbits",
                      f"Chatter orbits of the cut at {CUT_ORBIT_RPM} rpm",
                      ("continue", "--cut", "--rpm", CUT_ORBIT_RPM, "--parameter", "depth-mm",
                       "--range", CUT_ORBIT_RANGE_MM, "--max-points", str(orbits)),
                      _cut_orbits_run(orbits), variants=False))
    cells = "-1.5:1.5:" + ("8" if quick else "30")
    grid = ("--displacement-mm", cells, "--velocity-m-s", cells) if quick else ()
    for key, force, ratio, fr, start in (("basins-10N-r1.01-off", "10", "1.01", "off", "0.5,0.5"),
                                         ("basins-10N-r1.01-on", "10", "1.01", "on", "1.0,1.0"),
                                         ("basins-20N-r1.00-off", "20", "1.00", "off", "0.5,0.5")):
        steps.append(Step(key, "basins",
                          f"Basins of attraction, {force} N, r = {ratio}, gap 0.5 mm, "
                          f"friction {fr}",
                          ("basins", "--bar", "ball", "--gap-mm", "0.5", "--friction", fr,
                           "--force-n", force, "--ratio", ratio, "--poincare-from", start,
                           *grid, *dur),
                          _basins_run(force, ratio, fr == "on", start, cells, cells, duration),
                          friction=fr == "on"))
    steps += _sensitivity_steps(quick, dur, duration)
    for name, trials, title in (("ball", 6 if quick else 12,
                                 "Better designs: the ball damper's gap and material"),
                                ("tmd", 60 if quick else 120,
                                 "Better designs: the absorber's tuning, FRF peak against "
                                 "chatter")):
        steps.append(Step(f"design-{name}", "design", title,
                          ("design", design_file(name), "--trials", str(trials)),
                          _design_run(name, trials), variants=False))
    return steps


def _sensitivity_steps(quick: bool, dur: tuple, duration: float) -> list[Step]:
    """The published study's sensitivity steps: each kind at 10 N over the ratios near
    resonance; the ball and the friction number with cuts at 1200 rpm too."""
    ratios = "0.95:1.05:" + ("0.05" if quick else "0.01")
    cut_rpm, depths = "1200", "0.05:0.10:0.01"
    steps = []
    for kind in ("ball", "friction_number", "restitution", "initial"):
        cut = kind in ("ball", "friction_number")
        extra = ("--cut-rpm", cut_rpm, "--depths-mm", depths) if cut else ()
        # the steel ball's RMS against the carbide's (D4), both rattling: over starts
        starts = BALL_STARTS if kind == "ball" else 0
        extra += ("--starts", str(starts)) if starts else ()
        steps.append(Step(f"sensitivity-{kind}", "sensitivity",
                          f"Sensitivity to {kind.replace('_', ' ')}",
                          ("sensitivity", kind, "--bar", "ball", "--gap-mm", "0.5",
                           "--force-n", "10", "--ratios", ratios, *extra, *dur),
                          _sensitivity_run(kind, "10", ratios, cut_rpm if cut else None,
                                           depths if cut else None, duration, starts)))
    return steps


def command_line(step: Step, column: str, out: Path) -> str:
    """The shell command that reruns ``step`` of ``column`` (a preset, or one of the
    further columns of :data:`COLUMNS`) by hand."""
    return " ".join(["boringbar", *step.argv, *COLUMNS[column].flags, "--out", str(out)])


class StepFailed(RuntimeError):
    """A step failed (its one-line error inside)."""


def _done(path: Path, command: str) -> dict | None:
    """The finished step's record, if ``path`` holds one for ``command``."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("command") == command else None


def _step(where: Path, meta: dict, compute, say, label: str) -> dict:
    """One step of the study: its record from ``where/summary.json`` if a run of
    the same command finished there, else ``compute()`` (its summary), recorded
    with its wall time.  The record comes back with ``reused`` set."""
    record = _done(where / "summary.json", meta["command"])
    if record is not None:
        say(f"{label}: done before, kept")
        return {**record, "reused": True}
    remove_stale_temporaries(where)  # of a run of this step killed mid-write
    t0 = time.perf_counter()
    summary = compute()
    record = {**meta, "wall_time_s": time.perf_counter() - t0, "summary": summary}
    write_json_atomic(jsonable(record), where / "summary.json")  # last: marks it done
    say(f"{label}: {record['wall_time_s']:.1f} s")
    return {**record, "reused": False}


def run_paper(out, *, quick: bool = False, presets=COLUMN_ORDER, quiet: bool = False,
              log=None) -> dict:
    """Run every published analysis under each preset (and each further column of
    :data:`COLUMNS` named in ``presets``) into ``out`` and write the report; returns
    the manifest (also ``out/manifest.json``).  A further column reruns the steps
    with friction and shares the others with its preset's records, where that preset
    ran; it skips the steps marked ``variants=False`` (the design searches, the
    continuation, the steel ball's lobes).  A step that fails (bad input or an I/O
    error) raises :class:`StepFailed`; the steps finished before it are kept."""
    shown = Path(out)  # as the user wrote it, for the commands in the report
    out = shown.resolve()
    out.mkdir(parents=True, exist_ok=True)
    say = log or ((lambda msg: None) if quiet else (lambda msg: print(msg, file=sys.stderr,
                                                                      flush=True)))
    tic = time.perf_counter()
    steps = published_steps(quick)
    plan = _plan(steps, presets)
    total = sum(1 for *_, shared in plan if shared is None) + 1
    jobs = []
    for column, step in [(c, s) for c, s, shared in plan if shared is None]:
        step = step.for_column(column)
        meta = {"key": step.key, "section": step.section, "title": step.title,
                "preset": column,
                "command": command_line(step, column, shown / column / step.key)}
        label = f"boringbar paper: [{len(jobs) + 1}/{total}] {column} {step.key}"
        jobs.append((column, step.key, out / column / step.key, meta, label))
    done = _run_steps(jobs, quick, say)
    # in _plan's order; a step a further column shares is its preset's record
    records = [done[(column, step.key)] if shared is None else
               {**done[(shared, step.key)], "preset": column, "shared_from": shared,
                "reused": False} for column, step, shared in plan]
    base = [p for p in presets if p in PRESET_ORDER]
    records.append(_corrections_step(out, base, quick, say, total))
    manifest = {
        "title": "boringbar: the published study rerun under the paper and physical presets",
        "boringbar_version": __version__,
        "quick": quick,
        "presets": base,
        "variants": [{"name": c, "preset": COLUMNS[c].preset,
                      "overrides": COLUMNS[c].kw, "description": COLUMNS[c].description}
                     for c in presets if c in VARIANT_ORDER],
        "command": "boringbar paper --out " + str(shown) + (" --quick" if quick else "") + (
            "" if tuple(presets) == COLUMN_ORDER else " --presets " + ",".join(presets)),
        "wall_time_s": time.perf_counter() - tic,
        "compute_time_s": sum(r["wall_time_s"] for r in records if "shared_from" not in r),
        "steps": records,
    }
    write_json_atomic(jsonable(manifest), out / "manifest.json")
    manifest["report"] = str(write_report(out, manifest))
    say(f"boringbar paper: report {manifest['report']} "
        f"({manifest['wall_time_s']:.0f} s)")
    return manifest


def _run_steps(jobs: list[tuple], quick: bool, say) -> dict:
    """Each job's record, by (column, step key): those finished before read back,
    the others computed STEP_WORKERS at a time in worker processes (a step's runs
    fill the cores, but its searches, figures and files are serial, so a second
    step keeps the other core busy), each after the steps it reads (``Step.after``).
    The first step that fails cancels those not started and raises; the steps
    finished are kept on disk."""
    done, todo = {}, []
    for column, key, where, meta, label in jobs:
        record = _done(where / "summary.json", meta["command"])
        if record is None:
            todo.append((column, key, where, meta, label))
        else:
            say(f"{label}: done before, kept")
            done[(column, key)] = {**record, "reused": True}
    if len(todo) < 2 or STEP_WORKERS < 2:
        for job in todo:
            done[job[:2]] = _worker_step(quick, *job, say)[0]
        return done
    context = multiprocessing.get_context("spawn")  # no fork of a threaded parent
    after = {s.key: s.after for s in published_steps(quick)}
    with ProcessPoolExecutor(STEP_WORKERS, mp_context=context) as pool:
        futures: dict = {}
        try:
            for job in todo:
                for key in after[job[1]]:  # the files it reads are written first
                    wait([f for f, k in futures.items() if k == (job[0], key)])
                futures[pool.submit(_worker_step, quick, *job)] = job[:2]
            for future in as_completed(futures):
                record, messages = future.result()
                for message in messages:
                    say(message)
                done[futures[future]] = record
        except BaseException:
            pool.shutdown(cancel_futures=True)
            raise
    return done


def _worker_step(quick: bool, column: str, key: str, where: Path, meta: dict, label: str,
                 say=None) -> tuple[dict, list[str]]:
    """One step computed (in a worker process): its record, and the lines it said
    (said at once if ``say`` is given)."""
    step = next(s for s in published_steps(quick) if s.key == key).for_column(column)
    messages: list[str] = []
    record = _step(where, meta, _compute(step, COLUMNS[column], where, meta["command"]),
                   say or messages.append, label)
    return record, messages


def _plan(steps: list[Step], presets) -> list[tuple[str, Step, str | None]]:
    """(column, step, the column whose record it shares or None) in the study's order
    (the manifest's, the report's and the computing's): every
    preset's steps, then each further column's: those with friction rerun, those without
    shared with its preset where that preset runs."""
    unknown = [p for p in presets if p not in COLUMNS]
    if unknown:
        raise ParameterError(f"presets = {unknown[0]!r} must be one of "
                             f"{', '.join(COLUMN_ORDER)}")
    plan = []
    for column in (c for c in COLUMN_ORDER if c in presets):
        preset = COLUMNS[column].preset
        for step in steps:
            if column in PRESET_ORDER:
                plan.append((column, step, None))
            elif step.variants:
                shares = COLUMNS[column].shares_frictionless and not step.friction
                shared = preset if shares and preset in presets else None
                plan.append((column, step, shared))
    return plan


def _corrections_step(out: Path, presets, quick: bool, say, total: int) -> dict:
    """The corrections measurements as the study's last step (its record)."""
    duration = 0.5 if quick else 2.0
    meta = {"key": "corrections", "section": "corrections",
            "title": "What the corrections to the published equations change",
            "preset": "both",
            "command": (f"boringbar.report.corrections: readings_ladder(duration={duration}), "
                        f"impact_law_check(), absorber_designs() for {', '.join(presets)}")}
    where = out / "corrections"
    return _step(where, meta, lambda: _corrections(where, presets, duration), say,
                 f"boringbar paper: [{total}/{total}] corrections")


def _compute(step: Step, column: Column, where: Path, command: str):
    """``step.run(column, where)`` as a ``compute()`` of :func:`_step`; a bad value
    or an I/O error becomes :class:`StepFailed` naming the step's command."""
    def compute() -> dict:
        try:
            return step.run(column, where)
        except (ValueError, OSError) as exc:
            message = " ".join(str(exc).split()) or type(exc).__name__
            raise StepFailed(f"{command} failed: {message}") from None
    return compute


def _corrections(where: Path, presets, duration: float) -> dict:
    """The corrections measurements, into ``where``: the readings ladder, the impact
    law, and the absorber designs of each preset; returns their summary."""
    ladder = readings_ladder(duration=duration)
    nc = write_netcdf_atomic(ladder, where / "ladder.nc")
    png = save_figure_atomic(plot_ladder(ladder), where / "ladder.png")
    impact = impact_law_check(make_system("ball", "paper", gap_m=0.1e-3, friction=False))
    return {"ladder_netcdf": str(nc), "ladder_png": str(png), "impact_law": impact,
            "absorbers": {p: absorber_designs(p) for p in presets}}
