"""The analyses a study file can run, as a registry.

A study is a list of independent *points*, each computed by one pure,
deterministic function, and a Dataset assembled from the point results in
order.  An analysis is added by subclassing :class:`Analysis` and
implementing three methods, then registering it in ``ANALYSES``:

- ``plan(study) -> Plan``: the context (systems, options: everything every
  point needs, picklable) and the ordered list of points;
- ``compute(context, point) -> result``: one point (picklable; the same
  point always gives the same result, bit for bit, wherever it runs);
- ``assemble(study, plan, results) -> xarray.Dataset``: the ordered results
  into the analysis's Dataset (the same variables as the in-process
  function returns; wall-clock timings only in the attributes).

``options`` (the keys of ``[analysis]``), ``grid_keys`` (what ``[grid]``
may vary), ``default_axes`` and ``check`` describe its part of the schema.
The runner (:mod:`boringbar.studies.runner`) does the rest: chunking, executors,
resumable stores, progress.

The analyses reuse the per-point code of the in-process functions:
``sweep``: :func:`boringbar.analysis.sweep.compute` per lock-step batch of runs;
``lobes``: :func:`boringbar.analysis.lobes.compute` per (case, rpm) column;
``chatter_map``: :func:`boringbar.analysis.chatter_map.compute` per (case, rpm, depth)
cell;
``bifurcation``: :func:`boringbar.analysis.bifurcation.compute`, one case's whole
forward + backward continuation;
``basins``: :func:`boringbar.analysis.basins.compute`, a lock-step batch of grid
cells (or one cell), grouped at assembly;
``sensitivity``: one (value, force, ratio) harmonic run or one (value,
depth) cut.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from boringbar._validate import ParameterError, check_range
from boringbar.analysis import basins as basins_mod
from boringbar.analysis import bifurcation as bifurcation_mod
from boringbar.analysis import chatter_map as chatter_map_mod
from boringbar.analysis import lobes as lobes_mod
from boringbar.analysis import sensitivity as sensitivity_mod
from boringbar.analysis import sweep as sweep_mod
from boringbar.analysis.base import Plan
from boringbar.analysis.basins import MAX_BASIN_CELLS, BasinOptions, OperatingPoint, check_cells
from boringbar.analysis.bifurcation import BifurcationOptions
from boringbar.analysis.cases import MAX_GRID_VALUES, Case
from boringbar.analysis.chatter_map import ChatterMapOptions
from boringbar.analysis.chatter_probability import MAX_DRAWS, Uncertainty
from boringbar.analysis.lobes import LobesOptions
from boringbar.analysis.sensitivity import Cuts, SensitivityOptions
from boringbar.analysis.speeds import default_speeds
from boringbar.analysis.sweep import SweepOptions
from boringbar.analysis.verdict import VerdictOptions
from boringbar.model.dampers import ImpactDamper
from boringbar.model.forcing import MAX_DEPTH, Harmonic
from boringbar.model.system import make_system
from boringbar.simulate import (
    INTEGRATOR_CHOICES,
    Initial,
    Integration,
    check_friction_law,
    fixed_run_step,
)
from boringbar.simulate.run_limits import check_delay, check_step, check_steps
from boringbar.studies.schema import SECTION_OF, SYSTEM_KEYS, Setting, Study, StudyError


@dataclass(frozen=True)
class Range:
    """An option given as a list of numbers or {start, stop, step} (or, with
    ``count``, {start, stop, count}: count values, both ends included); ``empty``: an
    empty list is allowed too."""

    default: tuple
    count: bool = False
    lo: float | None = None
    lo_open: bool = False
    empty: bool = False

    def allowed(self) -> str:
        spec = "{start, stop, count}" if self.count else "a list of numbers or {start, stop, step}"
        if self.lo is not None:
            spec += f", every value {'>' if self.lo_open else '>='} {self.lo:g}"
        return spec

    def check(self, v):
        if self.count:
            if not isinstance(v, dict) or set(v) != {"start", "stop", "count"}:
                raise ValueError(self.allowed())
            lo, hi, n = v["start"], v["stop"], v["count"]
            if (not all(_finite(x) for x in (lo, hi)) or isinstance(n, bool)
                    or not isinstance(n, int) or not 1 <= n <= MAX_BASIN_CELLS or hi < lo):
                raise ValueError("{start, stop, count}: finite numbers with stop >= start and "
                                 f"an integer count in [1, {MAX_BASIN_CELLS}]")
            return {"start": float(lo), "stop": float(hi), "count": int(n)}
        if isinstance(v, dict):
            if set(v) != {"start", "stop", "step"}:
                raise ValueError(self.allowed())
            try:
                a, b, s = (float(v[x]) for x in ("start", "stop", "step"))
            except (TypeError, ValueError):
                raise ValueError(self.allowed()) from None
            if not (math.isfinite(a) and math.isfinite(b) and s > 0 and b >= a):
                raise ValueError("{start, stop, step}: finite numbers with step > 0 and "
                                 "stop >= start")
            n = math.floor((b - a) / s + 1e-9) + 1
            if n > MAX_GRID_VALUES:
                raise ValueError(f"{n:.3g} values; the allowed maximum is {MAX_GRID_VALUES}")
            v = [round(a + i * s, 12) for i in range(n)]
        if (not isinstance(v, list) or (not v and not self.empty) or len(v) > MAX_GRID_VALUES
                or not all(_finite(x) for x in v)):
            raise ValueError(self.allowed() + ", finite")
        v = [float(x) for x in v]
        if self.lo is not None and any((x <= self.lo) if self.lo_open else (x < self.lo)
                                       for x in v):
            raise ValueError(self.allowed())
        return tuple(v)


def _finite(x) -> bool:
    """A finite TOML number (not a boolean)."""
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class Values:
    """A list of values of any TOML scalar type (or lists of numbers)."""

    default: object = None

    def allowed(self) -> str:
        return "a non-empty list of distinct values"

    def check(self, v):
        if not isinstance(v, list) or not v:
            raise ValueError(self.allowed())
        return tuple(tuple(x) if isinstance(x, list) else x for x in v)


class Analysis:
    """The study adapter of an analysis module (module docstring): ``plan`` turns a
    study into the module's plan; points and assembly are the module's."""

    name = ""
    module: ModuleType  #: the analysis module (boringbar.analysis.*)
    options: dict = {}
    grid_keys: tuple = ()

    def default_axes(self, study: Study) -> dict:
        """Axes (key -> values) used when the study sets neither the key nor its axis;
        ``study`` is the file's, with its own axes only."""
        return {}

    def check(self, study: Study) -> None:
        """Raise ParameterError if the study cannot run (called by the loader):
        the plan, and the checks ``simulate`` would make of every run."""
        plan = self.plan(study)
        for system, omega, cutting in self.runs(plan):
            _check_run(study, system, omega, cutting)

    def runs(self, plan: Plan):
        """(System, largest forcing omega (rad/s), whether a cut) of the distinct runs."""
        return []

    def plan(self, study: Study) -> Plan:
        raise NotImplementedError

    def compute(self, context, point):
        return self.module.compute(context, point)

    def assemble(self, study: Study, plan: Plan, results: list):
        """The module's Dataset, with the study's provenance and the varied keys as
        coordinates along ``case``."""
        ds = self.module.assemble(plan, results, _provenance(study))
        return ds.assign_coords(_case_coords(plan.extra["values"]))

    def integrators(self) -> tuple:
        """The integrators a study of this analysis may choose."""
        return INTEGRATOR_CHOICES


def _check_run(study: Study, system, omega: float, cutting: bool) -> None:
    """What :func:`~boringbar.simulate.simulate` refuses, checked before any work."""
    d = system.damper
    dt = fixed_run_step(study.value("dt_s"))
    try:
        check_friction_law(system, study.value("integrator"))
    except ParameterError:
        raise ParameterError(f"key 'damper.static_ratio' = {d.friction.static_ratio!r}: the "
                             "rk4 integrator has only the sgn() law (static_ratio = 1); set "
                             "run.integrator = 'exact' for true stick-slip") from None
    try:
        check_step(system, omega, dt)
    except ParameterError as exc:
        raise ParameterError(f"key 'run.dt_s' = {dt!r}: {exc}") from None
    check_steps(study.value("duration_s"), dt, ("key 'run.duration_s'", "key 'run.dt_s'"))
    if isinstance(d, ImpactDamper):
        half = d.gap_m / 2 * 1e3
        check_range(f"key 'run.ball_position_mm' (within +-gap/2 of a {d.gap_m * 1e3:g} mm gap)",
                    study.value("ball_position_mm"), -half, half, unit="mm")
    if cutting:
        check_delay(60.0 * omega / (2 * math.pi), study.value("revolutions"), dt,
                    "key 'forcing.rpm'")


# --- shared pieces ----------------------------------------------------------------

#: System keys that matter for each bar kind (the others are ignored for it).
_RELEVANT = {
    "solid": ("kind", "n_modes", "z_absorber_mm"),
    "tmd": ("kind", "n_modes", "z_absorber_mm", "tmd_design", "tmd_mass_kg"),
    "ball": ("kind", "n_modes", "z_absorber_mm") + tuple(
        k for k in SYSTEM_KEYS if k not in ("kind", "n_modes", "z_absorber_mm", "tmd_design",
                                             "tmd_mass_kg")),
}


def make_study_system(preset: str, s: dict, spec=None):
    """The System of the flat bar + damper settings ``s`` (units as in the keys) of
    the system file ``spec`` (None: the published bar)."""

    kw = {"n_modes": s["n_modes"], "z_absorber_m": s["z_absorber_mm"] * 1e-3, "spec": spec}
    if s["kind"] == "tmd":
        kw.update(tmd_mass_kg=s["tmd_mass_kg"], tmd_design=s["tmd_design"])
    if s["kind"] == "ball":
        kw.update(gap_m=s["gap_mm"] * 1e-3, friction=s["friction"], ball=s["ball"],
                  restitution=s["restitution"], friction_number=s["friction_number"],
                  friction_force_n=s["friction_force_n"],
                  friction_reaction=s["friction_reaction"], locked=s["locked"])
        if s["static_ratio"] != 1.0:  # only where the system takes it
            kw["static_ratio"] = s["static_ratio"]
    return make_system(s["kind"], preset, **kw)


def _fmt(v) -> str:
    if isinstance(v, bool):
        return "on" if v else "off"
    return f"{v:g}" if isinstance(v, float) else str(v)


def study_cases(study: Study) -> tuple[list, dict]:
    """The cases (:class:`~boringbar.analysis.cases.Case`) of the system axes of
    ``study``, in the cartesian order of its grid, with settings that do not
    apply to a bar kind collapsed (a solid bar has no gap); and per varied key
    the value of each case (None where it does not apply)."""

    base = {k: study.value(k) for k in SYSTEM_KEYS}
    varied = [k for k in study.axes if k in SYSTEM_KEYS]
    seen, cases, values = set(), [], {k: [] for k in varied}
    for combo in itertools.product(*(study.axes[k] for k in varied)):
        s = dict(base, **dict(zip(varied, combo, strict=True)))
        relevant = _RELEVANT[s["kind"]]
        key = tuple((k, s[k]) for k in relevant)
        if key in seen:
            continue
        seen.add(key)
        if s["kind"] == "ball":
            label = f"ball gap={s['gap_mm']:g}mm friction={'on' if s['friction'] else 'off'}"
        else:
            label = s["kind"]
        extra = [k for k in varied if k not in ("kind", "gap_mm", "friction") and k in relevant]
        label += "".join(f" {k}={_fmt(s[k])}" for k in extra)
        system = make_study_system(study.preset, s, study.system)
        cases.append(Case.of(system, label))
        for k in varied:
            values[k].append(s[k] if k in relevant else None)
    return cases, values


def _case_coords(values: dict) -> dict:
    """Coordinates along ``case`` for the varied system keys (kind, gap and friction
    are the bar, gap and friction coordinates already)."""
    out = {}
    for k, vals in values.items():
        if k in ("kind", "gap_mm", "friction"):
            continue
        if all(v is None or (isinstance(v, int | float) and not isinstance(v, bool))
               for v in vals):
            out[k] = ("case", np.array([math.nan if v is None else float(v) for v in vals]))
        else:
            out[k] = ("case", np.array(["n/a" if v is None else _fmt(v) for v in vals]))
    return out


def _integration(study: Study, steady_fraction: float = 0.8, initial=False) -> Integration:
    """The study's integration options (``[run]``), every run from ``initial`` (default
    the study's initial conditions)."""
    return Integration(study.value("duration_s"), study.value("dt_s"),
                       study.value("integrator"), steady_fraction,
                       _initial(study) if initial is False else initial)


def _initial(study: Study):
    return Initial(study.value("tip_displacement_mm") * 1e-3, study.value("tip_velocity_m_s"),
                   study.value("ball_position_mm") * 1e-3, study.value("ball_velocity_m_s"))


def _axis(study: Study, key: str) -> np.ndarray:
    return np.array(study.axes[key] if key in study.axes else [study.value(key)], dtype=float)


def _provenance(study: Study) -> dict:
    return {"study": study.name, "study_analysis": study.analysis}


# --- sweep ------------------------------------------------------------------------

_SWEEP_NAMES = ("rms_tip_m", "max_abs_tip_m", "max_abs_rel_disp_m", "impacts_per_cycle",
                "energy_balance_relative")


class Sweep(Analysis):
    """Frequency sweeps: tip RMS and impact pattern per (case, force, ratio)."""

    name = "sweep"
    module = sweep_mod
    #: batch: runs advanced together in lock-step (RK4), each batch one point of the
    #: study; 1 makes every run its own point (finer chunks, the same numbers)
    options = {"batch": Setting("int", sweep_mod.BATCH, 1, sweep_mod.BATCH)}
    grid_keys = SYSTEM_KEYS + ("force_n", "ratio")

    def default_axes(self, study):
        """The ratios ``sweep`` takes by default for the study's bars
        (:func:`~boringbar.analysis.sweep.default_ratios`: the published 0.95-1.05,
        widened to both peaks of a tuned mass damper)."""
        return {"ratio": list(sweep_mod.default_ratios(study_cases(study)[0]))}

    def plan(self, study):
        cases, values = study_cases(study)
        options = SweepOptions(tuple(_axis(study, "ratio")), tuple(_axis(study, "force_n")),
                               study.options["batch"])
        plan = sweep_mod.plan(cases, options, _integration(study))
        plan.extra["values"] = values
        return plan

    def runs(self, plan):
        c = plan.context
        return [(x.system, max(c["options"].ratios) * x.system.reference_frequency_rad_s, False)
                for x in c["cases"]]


# --- lobes ------------------------------------------------------------------------

#: The draws' keys of a lobes study, as Setting's (kind, default, lo, hi, lo_open): None,
#: the library's default (:class:`~boringbar.analysis.chatter_probability.Uncertainty`);
#: no draws without ``draws``.
DRAW_KEYS = {"draws": ("int", None, 1, MAX_DRAWS), "seed": ("int", None, 0, 2**63 - 1),
             "stiffness_cov": ("float", None, 0.0, 1.0), "damping_cov": ("float", None, 0.0, 10.0),
             "friction_spread": ("float", None, 0.0, 1.0),
             "restitution_spread": ("float", None, 0.0, 1.0),
             "force_noise": ("float", None, 0.0, 1.0), "ball_start": ("bool", None),
             "probability": ("float", None, 0.0, 1.0, True)}


def _cases_plan(study: Study, build) -> Plan:
    """``build(cases)``'s plan over the study's cases, with their values kept for the
    grid's coordinates."""
    cases, values = study_cases(study)
    plan = build(cases)
    plan.extra["values"] = values
    return plan


def _runs_at_top_speed(plan: Plan) -> list:
    """Each case's system at the plan's fastest speed (rad/s), as a cut
    (:meth:`Analysis.runs`)."""
    c = plan.context
    return [(x.system, 2 * math.pi * max(c["options"].rpm) / 60.0, True) for x in c["cases"]]


class Lobes(Analysis):
    """Stability lobes: every verdict of every (case, rpm) column.  The defaults are the
    library's (:class:`~boringbar.analysis.lobes.LobesOptions`): the speeds of the study's
    bars' lobes, the search to 1 % on the geometric depth grid (a scan, or a given
    ``depth_step_mm``: the linear grid)."""

    name = "lobes"
    module = lobes_mod
    options = {
        "method": Setting("str", "search", choices=lobes_mod.METHODS),
        "criterion": Setting("str", None, choices=lobes_mod.CRITERIA,
                             doc="default: growth (the converged verdict), zero (published) "
                                 "where every bar is the paper preset's"),
        "depth_step_mm": Setting("float", None, 0.0, 1.0, True,
                                 doc="a linear grid; default: none (the search's geometric "
                                     "grid, a scan's 0.01)"),
        "depth_tolerance": Setting("float", None, 0.0, 0.5, True,
                                   doc="the geometric grid's ratio; default 0.01"),
        "max_depth_mm": Setting("float", 3.0, 0.0, MAX_DEPTH * 1e3, True),
        "successive": Setting("int", 3, 1, 100),
        "analytic": Setting("bool", True),
        **{k: Setting(*v, doc="the chance of chatter (criterion 'growth'; "
                                 "docs/chatter_probability.md); default: the library's")
           for k, v in DRAW_KEYS.items()},
    }
    grid_keys = SYSTEM_KEYS + ("rpm",)

    def default_axes(self, study):
        """The speeds of the study's bars' lobes (:func:`~boringbar.analysis.lobes.
        default_speeds`, as ``lobes`` takes them)."""
        return {"rpm": default_speeds(study_cases(study)[0],
                                                study.value("workpiece"))}

    def plan(self, study):
        return _cases_plan(study, lambda cases: lobes_mod.plan(
            cases, _lobe_options(study), _integration(study, initial=None)))

    def runs(self, plan):
        return _runs_at_top_speed(plan)


def _uncertainty(study: Study) -> Uncertainty | None:
    """The draws of a lobes study's ``[analysis]`` (None without ``draws``)."""
    given = {k: study.options[k] for k in DRAW_KEYS if study.options[k] is not None}
    if "draws" not in given:
        if given:
            raise StudyError(f"{study.source}: key 'analysis.{next(iter(given))}' = "
                             f"{next(iter(given.values()))!r} needs analysis.draws (the "
                             "number of draws)")
        return None
    return Uncertainty(**given)


def _lobe_options(study: Study) -> LobesOptions:
    """The lobes options of the study's ``[analysis]`` (mm converted, checked under the
    file's keys) and ``[forcing]`` cut, at its speeds."""
    o = study.options
    step, tol = o["depth_step_mm"], o["depth_tolerance"]
    cut = _cut_options(study)
    try:
        grid = lobes_mod.depth_grid(o["method"], step, tol, ("key 'analysis.depth_step_mm'",
                                                             "key 'analysis.depth_tolerance'"))
        first = lobes_mod.DEPTH_FLOOR * 1e3 if grid == "geometric" else \
            lobes_mod.PUBLISHED_DEPTH_STEP * 1e3 if step is None else step
        check_range("key 'analysis.max_depth_mm'", o["max_depth_mm"], first, MAX_DEPTH * 1e3,
                    unit="mm", why=f"from the {grid} depth grid's first depth")
        return LobesOptions(tuple(_axis(study, "rpm")), o["method"], o["criterion"],
                            None if step is None else step * 1e-3, o["max_depth_mm"] * 1e-3,
                            o["successive"], **cut, analytic=o["analytic"],
                            depth_tolerance=tol, uncertainty=_uncertainty(study))
    except ParameterError as exc:
        raise StudyError(f"{study.source}: [analysis] {exc}") from None


# --- chatter map ------------------------------------------------------------------

class ChatterMap(Analysis):
    """The chatter amplitude map: one point per (case, rpm, depth) cell, each judged by the
    converged verdict.  The defaults are the library's
    (:class:`~boringbar.analysis.chatter_map.ChatterMapOptions`): the boring speeds of the
    study's bars (``[forcing] workpiece``'s), 20 depths around their bare-bar limit, a
    small and a 20 um knock, a 10 um peak-to-peak tolerance.  Every cut starts in
    progress, knocked, and runs until its verdict: ``[forcing] start`` and ``depth_mm``
    and ``[run] duration_s`` do not apply (``max_run_s`` caps a run)."""

    name = "chatter_map"
    module = chatter_map_mod
    options = {
        "depths_mm": Range(None, lo=0.0, lo_open=True),
        "tolerance_um": Setting("float", VerdictOptions.tolerance_m * 1e6, 0.0, 1e6, True,
                                doc="the largest settled tip peak-to-peak that is chatter-free"),
        "knocks_um": Range((chatter_map_mod.LARGE_KNOCK_M * 1e6,), lo=0.0, lo_open=True,
                           empty=True),
        "confidence": Setting("float", VerdictOptions.confidence, 0.5, 0.999999, True),
        "max_run_s": Setting("float", VerdictOptions.max_duration_s, 0.0, 1000.0, True),
    }
    grid_keys = SYSTEM_KEYS + ("rpm",)

    def default_axes(self, study):
        """The speeds of the study's bars (:func:`~boringbar.analysis.chatter_map.
        map_speeds`, as ``chatter_map`` takes them)."""
        return {"rpm": chatter_map_mod.map_speeds(study_cases(study)[0],
                                                  study.value("workpiece"))}

    def plan(self, study):
        return _cases_plan(study, lambda cases: chatter_map_mod.plan(
            cases, _map_options(study), _integration(study, initial=None)))

    def runs(self, plan):
        return _runs_at_top_speed(plan)

    def integrators(self) -> tuple:
        """The converged verdict runs RK4."""
        return ("auto", "rk4")


#: Keys a chatter map's study does not take: the cut settings a map does not take, and
#: one depth (analysis.depths_mm gives the grid's).
_NOT_FOR_A_MAP = (*chatter_map_mod.NOT_FOR_A_MAP, "depth_mm")


def _map_options(study: Study) -> ChatterMapOptions:
    """The chatter map's options of the study's ``[analysis]`` (um and mm converted, checked
    under the file's keys) and ``[forcing]`` cut, at its speeds."""
    given = [k for k in _NOT_FOR_A_MAP if k in study.given]
    if given:
        raise StudyError(f"{study.source}: key '{SECTION_OF[given[0]]}.{given[0]}' = "
                         f"{study.value(given[0])!r}: a chatter map's cuts start in progress, "
                         "knocked, and run until their verdict (analysis.depths_mm gives the "
                         "depths, analysis.max_run_s caps a run)")
    o = study.options
    cut = {k: v for k, v in _cut_options(study).items() if k not in ("start", "bounded_fraction")}
    try:
        # rounded so that 20 um is the library's 20e-6 m, not a neighbour of it
        verdict = VerdictOptions(confidence=o["confidence"], max_duration_s=o["max_run_s"],
                                 tolerance_m=round(o["tolerance_um"] * 1e-6, 15),
                                 knocks_m=tuple(round(k * 1e-6, 15) for k in o["knocks_um"]))
        depths = None if o["depths_mm"] is None else tuple(round(d * 1e-3, 15)
                                                            for d in o["depths_mm"])
        return ChatterMapOptions(tuple(_axis(study, "rpm")), depths, **cut, verdict=verdict)
    except ParameterError as exc:
        raise StudyError(f"{study.source}: [analysis] {exc}") from None


# --- bifurcation ------------------------------------------------------------------

class Bifurcation(Analysis):
    """Bifurcation diagrams: one continuation (forward, then backward) per case."""

    name = "bifurcation"
    module = bifurcation_mod
    options = {
        "parameter": Setting("str", "force", choices=("force", "ratio")),
        "values": Range(tuple(float(f) for f in range(5, 51)), lo=0.0),
        "backward": Setting("bool", True),
        "tol": Setting("float", 1e-3, 0.0, 1.0, True),
        "max_k": Setting("int", 16, 1, 64),
    }
    grid_keys = SYSTEM_KEYS

    def plan(self, study):
        cases, values = study_cases(study)
        o = study.options
        v = np.asarray(o["values"], dtype=float)
        if o["parameter"] == "ratio" and np.any(v <= 0):
            raise ParameterError(f"analysis.values = {v.tolist()} must be > 0 for parameter "
                                 "'ratio'")
        try:
            options = BifurcationOptions(o["parameter"], tuple(v.tolist()),
                                         study.value("force_n"), study.value("ratio"),
                                         o["backward"], o["tol"], o["max_k"])
        except ParameterError as exc:
            raise StudyError(f"{study.source}: [analysis] {exc}") from None
        plan = bifurcation_mod.plan(cases, options,
                                    _integration(study, study.value("steady_fraction")))
        plan.extra["values"] = values
        return plan

    def runs(self, plan):
        o = plan.context["options"]
        r = max(o.values) if o.parameter == "ratio" else o.ratio
        return [(x.system, r * x.system.reference_frequency_rad_s, False)
                for x in plan.extra["cases"]]


# --- basins -----------------------------------------------------------------------

class Basins(Analysis):
    """Basins of attraction: one point per (operating point, lock-step batch of cells).

    One operating point (no grid) gives exactly the Dataset of
    :func:`~boringbar.analysis.basins.basins`; several (a grid over bar, damper,
    ``force_n`` or ``ratio``) give those Datasets stacked along a leading
    ``case`` dimension, the attractors of each padded to the largest count
    (``count`` 0, ``attractor_period`` -1, NaN and "" beyond its own).
    """

    name = "basins"
    module = basins_mod
    options = {
        "displacement_mm": Range({"start": -1.5, "stop": 1.5, "count": 30}, count=True),
        "velocity_m_s": Range({"start": -1.5, "stop": 1.5, "count": 30}, count=True),
    }
    grid_keys = SYSTEM_KEYS + ("force_n", "ratio")

    def plan(self, study):
        cases, values = study_cases(study)
        forces, ratios = _axis(study, "force_n"), _axis(study, "ratio")
        operating = []
        for case in cases:
            for f in forces:
                for r in ratios:
                    label = case.label
                    if "force_n" in study.axes:
                        label += f" F0={f:g}N"
                    if "ratio" in study.axes:
                        label += f" r={r:g}"
                    operating.append(OperatingPoint(label, case, Harmonic(float(f), float(r))))
        d, v = study.options["displacement_mm"], study.options["velocity_m_s"]
        check_cells(d["count"], v["count"], ("key 'analysis.displacement_mm'",
                                             "key 'analysis.velocity_m_s'"))
        try:
            options = BasinOptions((d["start"] * 1e-3, d["stop"] * 1e-3, d["count"]),
                                   (v["start"], v["stop"], v["count"]),
                                   study.value("ball_position_mm") * 1e-3,
                                   study.value("ball_velocity_m_s"))
        except ParameterError as exc:
            raise StudyError(f"{study.source}: [analysis] {exc}") from None
        integration = _integration(study, study.value("steady_fraction"), initial=None)
        plan = basins_mod.plan(operating, options, integration)
        plan.extra.update(values=values, case_index=[cases.index(op.case) for op in operating])
        return plan

    def runs(self, plan):
        return [(op.case.system, op.forcing.omega(op.case.system.reference_frequency_rad_s), False)
                for op in plan.context["operating"]]

    def assemble(self, study, plan, results):
        ds = basins_mod.assemble(plan, results, _provenance(study))
        if "case" not in ds.dims:  # one operating point: exactly basins()'s Dataset
            return ds
        idx = plan.extra["case_index"]
        return ds.assign_coords({k: ("case", [v[i] for i in idx])
                                 for k, (_, v) in _case_coords(plan.extra["values"]).items()})


# --- sensitivity ------------------------------------------------------------------

class Sensitivity(Analysis):
    """One parameter varied (``kind``): harmonic runs per (value, force, ratio), each
    again from ``starts`` starts, or (``cuts = true``) full-length cuts per (value, depth)
    at ``[forcing] rpm``."""

    name = "sensitivity"
    module = sensitivity_mod
    options = {
        "kind": Setting("str", "restitution",
                        choices=("ball", "friction_number", "restitution", "initial")),
        "values": Values(None),
        "cuts": Setting("bool", False),
        "depths_mm": Range((0.05, 0.06, 0.07, 0.08, 0.09, 0.1), lo=0.0, lo_open=True),
        "starts": Setting("int", 0, 0, sensitivity_mod.MAX_STARTS),
    }
    grid_keys = ("force_n", "ratio")

    def plan(self, study):
        o = study.options
        kind = o["kind"]
        s = {k: study.value(k) for k in SYSTEM_KEYS}
        varied = {"ball": "ball", "friction_number": "friction_number",
                  "restitution": "restitution"}.get(kind)
        if varied and varied in study.given:
            raise StudyError(f"{study.source}: key 'damper.{varied}' = "
                             f"{study.value(varied)!r}: cannot be fixed while analysis.kind "
                             f"= {kind!r} varies it")
        cuts = None
        if o["cuts"]:
            cuts = Cuts(study.value("rpm"), tuple(round(d * 1e-3, 15) for d in o["depths_mm"]),
                        study.value("duration_s"), _cut_options(study))
        try:
            options = SensitivityOptions(kind, o["values"], tuple(_axis(study, "force_n")),
                                         tuple(_axis(study, "ratio")), cuts, o["starts"])
            return sensitivity_mod.plan(
                options, _integration(study, initial=_initial_or_none(study)),
                preset=study.preset, bar=s["kind"], gap_m=s["gap_mm"] * 1e-3,
                friction=s["friction"], overrides=_overrides(s, varied, study.system))
        except ParameterError as exc:
            raise StudyError(f"{study.source}: [analysis] {exc}") from None

    def runs(self, plan):
        c = plan.context
        if c["mode"] == "cuts":
            return [(x.system, 2 * math.pi * c["cuts"].rpm / 60.0, True) for x in c["cases"]]
        return [(x.system, max(c["options"].ratios) * x.system.reference_frequency_rad_s, False)
                for x in c["cases"]]

    def assemble(self, study, plan, results):
        return sensitivity_mod.assemble(plan, results, _provenance(study))  # no case dim


def _overrides(s: dict, varied: str | None, spec=None) -> dict:
    """make_system arguments of the flat settings ``s`` beyond kind, gap and friction
    (without the ``varied`` one), of the system file ``spec``."""
    overrides = {"n_modes": s["n_modes"], "z_absorber_m": s["z_absorber_mm"] * 1e-3,
                 "spec": spec}
    if s["kind"] == "ball":
        overrides.update(ball=s["ball"], restitution=s["restitution"],
                         friction_number=s["friction_number"],
                         friction_force_n=s["friction_force_n"],
                         friction_reaction=s["friction_reaction"], locked=s["locked"])
    if s["kind"] == "tmd":
        overrides.update(tmd_mass_kg=s["tmd_mass_kg"], tmd_design=s["tmd_design"])
    overrides.pop(varied, None)
    return overrides


def _cut_options(study: Study) -> dict:
    """The cut of the study's ``[forcing]`` (SI), as :class:`LobesOptions` and
    :class:`~boringbar.model.forcing.Regenerative` fields: its law ``workpiece``
    (Kienzle's) or ``kr_mpa`` (linear), not both."""
    workpiece = study.value("workpiece")
    if workpiece is not None and "kr_mpa" in study.given:
        raise StudyError(f"{study.source}: keys 'forcing.kr_mpa' = {study.value('kr_mpa')!r} "
                         f"(the linear law) and 'forcing.workpiece' = {workpiece!r} (Kienzle's "
                         "law): give one")
    if workpiece is not None and study.value("integrator") == "exact":
        raise StudyError(f"{study.source}: key 'forcing.workpiece' = {workpiece!r}: Kienzle's "
                         "law needs run.integrator = 'rk4' or 'auto' (the exact integrator's "
                         "cut is linear in the state)")
    law = {"workpiece": workpiece} if workpiece is not None else \
        {"kr_pa": study.value("kr_mpa") * 1e6}
    return {**law, "feed_m": study.value("feed_mm") * 1e-3,
            "revolutions": study.value("revolutions"),
            "interpolation": study.value("interpolation"), "start": study.value("start"),
            "bounded_fraction": study.value("bounded_fraction")}



def _initial_or_none(study: Study):
    ini = _initial(study)
    return None if all(v == 0.0 for v in ini.__dict__.values()) else ini


ANALYSES: dict[str, Analysis] = {a.name: a for a in (Sweep(), Lobes(), ChatterMap(),
                                                      Bifurcation(), Basins(), Sensitivity())}
