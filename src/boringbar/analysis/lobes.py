"""Stability lobes by time-domain simulation (docs/chatter.md; docs/model.md, sections 4
and 6).

Every grid point (spindle speed x depth of cut) is a regenerative-cutting run
of the kernel.

The grid follows the bar unless it is given.  The speeds (:func:`lobe_speeds`)
span the lobes of the bars' first natural frequency f1: a one-tooth boring
bar's lobe pockets sit near 60 f1 / k rpm, k = 1, 2, ..., and the default
speeds run from k = 0.9 to 6.1, evenly spaced in k (10 speeds per lobe).
The depths are either a linear grid (``depth_step_m``, the published 0.01
mm) or, by default, a geometric one: each depth ``depth_tolerance`` (1 %)
above the one below, from 1 micrometre, so a limit is found to 1 % of itself
whatever its size.

How a cut is judged (``criterion``):

- ``growth`` (the default for every bar not built by the ``paper`` preset): the
  converged verdict of :mod:`boringbar.analysis.verdict`.  The onset is where the
  growth rate of a small knock changes sign; the chatter-free depth is the largest
  depth whose settled vibration keeps the tool in the cut and its peak-to-peak within
  the tolerance, from every start tried.  For a bar without a free ball the two are
  one: it is linear until the tool leaves the cut.  The limit is the onset's depth
  interpolated in the growth rate between the two adjacent grid depths whose onsets
  differ, or, for a free ball that bounds the vibration within the tolerance above
  its onset, the last chatter-free grid depth.
- ``zero`` (published; the default when every bar is built by the ``paper`` preset):
  a run of the integration's duration (2 s) from ``start`` chatters if the cutting
  force reaches zero (the tool leaves the cut).  A finite run places this limit
  above the true one where the vibration grows slowly (docs/chatter.md).
- ``bounded``: as ``zero``, or the steady amplitude exceeds ``bounded_fraction`` of
  the feed.

Two ways to find, at each speed, the depth where chatter starts:

- ``scan`` (published): depths step, 2 step, 3 step ... until ``successive``
  (3) depths in a row chatter.  The first unstable depth and the limiting
  (chatter-free) depth, the last stable depth below it, are reported.
- ``search`` (the default): from a seed depth, steps of 1, 2, 4 ... grid depths
  up (or down) until a bracket [stable, chatter] is found, then bisection on
  the depth grid, then the ``successive - 1`` depths above the first
  unstable one are run to confirm the published rule; if one of them is
  stable (non-monotone stability) the search continues as a scan from there.
  The seed is the analytic (frequency-domain) limit of the linear host at
  that speed: the solid, TMD or locked-ball bar itself, and for the free
  ball (at the onset of chatter the vibration is far smaller than the gap, so
  the ball does not yet touch a wall) the bar carrying it where friction holds
  it, the bare cavity bar without friction (System.linear_host).  It only
  sets where the search starts: the runs decide.
  It assumes that everything below the bracket it found is stable; where
  stability is not monotone in depth (a ball damper may chatter in a band
  and be stable above it) the scan can find a lower first unstable depth.
  :func:`compare_methods` lists where the two differ.  (``growth`` searches the
  onset without the confirmation: its growth rate is continuous in depth.)

Each (case, speed) column is one point of the plan (the contract:
:mod:`boringbar.analysis.base`), run on an executor (default: a thread per
core; the kernel releases the GIL).  Every verdict of every grid point that
was run is kept.  :func:`examples` reruns a stable and an unstable grid point
with history.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from boringbar._validate import (
    ParameterError,
    check_choice,
    check_int,
    check_positive,
    check_range,
)
from boringbar.analysis import chatter_probability, lobe_search, verdict
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.cases import Case, as_cases
from boringbar.analysis.chatter_probability import Uncertainty
from boringbar.analysis.lobe_search import (
    CHATTER,
    NOT_RUN,
    STABLE,
    UNDECIDED,
    column,
    fixed_cut,
    growth_column,
    not_free,
    onset_chatters,
    onset_depth,
)
from boringbar.analysis.speeds import check_speeds, default_speeds
from boringbar.analysis.verdict import VerdictOptions, judged_step, step_text, verdict_attrs
from boringbar.execute import Execution
from boringbar.model.cutting import CutLawFields, CuttingLaw
from boringbar.model.forcing import INTERPOLATIONS, KR_ALUMINIUM, STARTS, Regenerative
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import (
    Integration,
    check_cut_law,
    check_friction_law,
    resolve_integrator,
    resolved_integrators,
)
from boringbar.simulate.run_limits import check_delay
from boringbar.version import __version__

PUBLISHED_RPM = np.arange(900.0, 1600.0 + 1e-9, 50.0)
PUBLISHED_DEPTH_STEP = 0.01e-3
#: The default depth grid's relative step: a limit found to 1 % of itself.
DEPTH_TOLERANCE = 0.01
#: The shallowest depth of the geometric grid (m): far below any insert's edge radius.
DEPTH_FLOOR = 1e-6
#: Most depths on one speed's grid (published: 300; the default geometric grid up
#: to 3 mm: 805); each (case, speed, depth) holds a few numbers in the Dataset.
MAX_DEPTHS = 100_000
METHODS = ("scan", "search")
CRITERIA = ("growth", "zero", "bounded")


def depth_grid(method: str, step, tolerance,
               names: tuple[str, str] = ("depth_step_m", "depth_tolerance")) -> str:
    """The depth grid a lobe study climbs: "linear" with a ``step`` given, or for a
    scan given neither (the published step); else "geometric" (the search's default,
    or a ``tolerance`` given).  Both given: a ParameterError naming ``names``."""
    if step is not None and tolerance is not None:
        raise ParameterError(f"{names[0]} = {step!r} and {names[1]} = {tolerance!r}: give "
                             "one, a linear grid's step or a geometric grid's ratio")
    linear = step is not None or (method == "scan" and tolerance is None)
    return "linear" if linear else "geometric"


def grid_index(depth: float, step: float | None, tolerance: float | None) -> int:
    """The deepest index of a depth grid (linear of ``step`` m, or geometric of
    relative step ``tolerance`` from DEPTH_FLOOR with ``step`` None) whose depth is at
    most ``depth`` (m; 0: none).  Of ``max_depth_m``: the number of depths."""
    if step is not None:
        return int(math.floor(depth / step + 1e-9))
    if depth < DEPTH_FLOOR:
        return 0
    return int(math.floor(math.log(depth / DEPTH_FLOOR) / math.log1p(tolerance) + 1e-9)) + 1


@dataclass(frozen=True)
class LobesOptions(CutLawFields):
    """A lobe study's grid, rule and cut.

    ``rpm``: spindle speeds (rev/min, > 0, increasing; None, the default: the
    bars' lobes, :func:`lobe_speeds`; the published ones are :data:`PUBLISHED_RPM`);
    ``method``: "search" (default) or "scan" (published; module doc);
    ``criterion``: "growth" (the converged verdict), "zero" (published: a fixed run's
    force reaches zero) or "bounded"; None (the default): "zero" where every bar is
    built by the ``paper`` preset, else "growth" (:func:`criterion_for`);
    ``verdict``: how "growth" judges a cut (:class:`~boringbar.analysis.verdict.
    VerdictOptions`: confidence, cap, small knock, tolerance, larger knocks);
    depths ``depth_step_m``, 2 ``depth_step_m``, ... up to ``max_depth_m`` (m), or,
    with ``depth_step_m`` None (the default), a geometric grid from
    :data:`DEPTH_FLOOR` in relative steps of ``depth_tolerance`` (default 1 %; a scan
    given neither takes the published 0.01 mm step: it climbs the grid one depth at
    a time; :func:`depth_grid`);
    ``successive``: chattering depths in a row that end a scan.  The cut
    (:class:`~boringbar.model.forcing.Regenerative`): ``kr_pa`` (Pa), ``feed_m``
    (m), ``revolutions``, ``interpolation``, ``start`` (of the fixed-length criteria;
    "growth" starts every cut in progress and knocked), ``bounded_fraction`` (of
    the feed), ``workpiece`` (Kienzle's law of a material, or a CuttingLaw, in place of
    ``kr_pa``'s linear law).  ``analytic``: add the frequency-domain limits of the
    linear hosts (with the law's slope at the feed for Kr, :attr:`analytic_kr_pa`).
    ``uncertainty``: also the lobes of draws of the bars and cuts, and the chance of
    chatter they give (:class:`~boringbar.analysis.chatter_probability.Uncertainty`;
    criterion "growth" only; docs/chatter_probability.md).
    """

    rpm: tuple[float, ...] | None = None
    method: str = "search"
    criterion: str | None = None
    depth_step_m: float | None = None
    max_depth_m: float = 3e-3
    successive: int = 3
    kr_pa: float = KR_ALUMINIUM
    feed_m: float = 0.1e-3
    revolutions: int = 3
    interpolation: str = "cubic"
    start: str = "rest"
    bounded_fraction: float = 0.1
    analytic: bool = True
    depth_tolerance: float | None = None
    verdict: VerdictOptions = VerdictOptions()
    workpiece: str | CuttingLaw | None = None
    uncertainty: Uncertainty | None = None

    def __post_init__(self):
        if self.rpm is not None:
            object.__setattr__(self, "rpm", check_speeds("rpm", self.rpm))
        check_choice("method", self.method, METHODS)
        if self.criterion is not None:
            check_choice("criterion", self.criterion, CRITERIA)
        if not isinstance(self.verdict, VerdictOptions):
            raise ParameterError(f"verdict = {self.verdict!r} must be a VerdictOptions")
        if depth_grid(self.method, self.depth_step_m, self.depth_tolerance) == "linear":
            step = PUBLISHED_DEPTH_STEP if self.depth_step_m is None else self.depth_step_m
            object.__setattr__(self, "depth_step_m", check_positive("depth_step_m", step, "m"))
        else:
            tol = DEPTH_TOLERANCE if self.depth_tolerance is None else self.depth_tolerance
            object.__setattr__(self, "depth_tolerance", check_range(
                "depth_tolerance", tol, 0.0, 0.5, lo_open=True))
        check_range("max_depth_m", self.max_depth_m, self.depth(1), 1.0, unit="m")
        check_int("successive", self.successive, 1, 100)
        check_choice("interpolation", self.interpolation, INTERPOLATIONS)
        check_choice("start", self.start, STARTS)
        if self.max_index > MAX_DEPTHS:
            raise ParameterError(f"{self.grid_text()} gives {self.max_index} depths up to "
                                 f"max_depth_m = {self.max_depth_m:g} m; the allowed "
                                 f"maximum is {MAX_DEPTHS} depths")
        # the cut's own fields (each speed is checked above)
        self.forcing(self.depth(1), self.rpm[0] if self.rpm else 1000.0)
        chatter_probability.check(self.uncertainty, self.criterion)

    @property
    def max_index(self) -> int:
        """The deepest grid index tried (depth :meth:`depths` of it)."""
        return self.index_below(self.max_depth_m)

    def depths(self, index) -> np.ndarray:
        """The depths (m) of grid indices ``index`` (1, 2, ...): index x depth_step_m,
        or DEPTH_FLOOR (1 + depth_tolerance)^(index - 1)."""
        i = np.asarray(index, dtype=float)
        if self.depth_step_m is not None:
            return self.depth_step_m * i
        return DEPTH_FLOOR * np.exp(math.log1p(self.depth_tolerance) * (i - 1.0))

    def depth(self, index: int) -> float:
        """The depth (m) of one grid index, as :meth:`depths` gives it."""
        return float(self.depths(index))

    def index_below(self, depth_m: float) -> int:
        """The deepest grid index whose depth is at most ``depth_m`` (m; 0: none)."""
        return grid_index(depth_m, self.depth_step_m, self.depth_tolerance)

    def grid_text(self) -> str:
        """The depth grid in words (the Dataset's ``depth_grid`` attribute)."""
        if self.depth_step_m is not None:
            return f"depth_step_m = {self.depth_step_m:g} m"
        return (f"depth_tolerance = {self.depth_tolerance:g} (geometric from "
                f"{DEPTH_FLOOR:g} m)")

    def forcing(self, depth_m: float, rpm: float, stop_at_zero: bool = True) -> Regenerative:
        """The cut at ``depth_m`` (m) and ``rpm``."""
        return Regenerative(depth_m=depth_m, rpm=rpm, kr_pa=self.kr_pa, feed_m=self.feed_m,
                            revolutions=self.revolutions, interpolation=self.interpolation,
                            start=self.start, stop_at_zero=stop_at_zero,
                            bounded_fraction=self.bounded_fraction, workpiece=self.workpiece)


def criterion_for(systems) -> str:
    """The default criterion of a study of ``systems``: "zero" (published) when every one
    is built by the ``paper`` preset, so the published study reruns as published, else
    "growth" (the converged verdict)."""
    return "zero" if all(s.preset == "paper" for s in systems) else "growth"


def run_length_text(ds) -> str:
    """How long each cut of a lobes Dataset ran, in words (summaries and figures)."""
    a = ds.attrs
    if a["criterion"] == "growth":
        mean = float(a.get("mean_run_s", math.nan))
        ball = ("bar" in ds.coords and "ball" in ds["bar"].values
                and lobe_search.RESOLVE_CAP > 1)
        longer = (f", {lobe_search.longer_cap_s(a['max_duration_s']):g} s for a ball's run "
                  "settling after its onset chattered" if ball else "")
        return (f"each cut until its verdict is {a['confidence']:g}-certain (at most "
                f"{a['max_duration_s']:g} s{longer}; {mean:.2g} s on average)")
    return f"each cut {a['duration_s']:g} s from {a['start']}"


def method_text(ds) -> str:
    """The method of a lobes Dataset in one line: criterion, search, integrator, run
    length (every summary line and figure names it)."""
    a = ds.attrs
    crit = {"growth": "converged verdict: chatter-free depth = the largest depth whose "
                      "settled vibration keeps the tool in the cut and within "
                      f"{a.get('tolerance_m', math.nan) * 1e6:g} um p-p from every start "
                      f"tried ({starts_text(a)})",
            "zero": "published criterion (the force reaches zero)",
            "bounded": f"bounded chatter (amplitude > {a.get('bounded_fraction', 0.1):g} "
                       "h_m, or the force reaches zero)"}[a["criterion"]]
    return (f"{crit}; {a['method']} on {a['depth_grid']}; {a['integrator_used']} at dt = "
            f"{a['dt_s']:g} s{step_text(a)}; {run_length_text(ds)}")


def starts_text(attrs: dict) -> str:
    """The starts a converged verdict tried, in words: the small knock, and the large
    ones (``knocks_m``, a JSON list in the attributes)."""
    knocks = json.loads(attrs.get("knocks_m", "[]"))
    big = "".join(f", a {k * 1e6:g} um knock" for k in knocks)
    return f"a {attrs.get('knock_m', math.nan) * 1e6:g} um knock{big}"


def _seeds(cases: list[Case], options: LobesOptions) -> dict:
    """Grid index of the analytic limit of each case's linear host at each speed."""

    seeds = {}
    for case in cases:
        lim = limit_at_speeds(case.system.linear_host(), options.rpm, options.analytic_kr_pa)
        for r, b in zip(options.rpm, lim, strict=True):
            if math.isfinite(b):
                seeds[(case.label, float(r))] = options.index_below(b)
    return seeds


def _limits(verdicts: np.ndarray, depths: np.ndarray) -> tuple[float, float]:
    """(limiting depth, first unstable depth) of one column: the first depth that
    chatters, and the last stable depth below it (0 if none).  Stable islands
    above the first unstable depth stay in the verdicts."""
    idx = np.flatnonzero(verdicts == CHATTER)
    if idx.size == 0:
        return math.nan, math.nan
    first = idx[0]
    below = np.flatnonzero(verdicts[:first] == STABLE)
    limit = depths[below[-1]] if below.size else 0.0
    return float(limit), float(depths[first])


def plan(cases: list[Case], options: LobesOptions, integration: Integration) -> Plan:
    """A point per (case, rpm) column; the search's seeds (the analytic limit of each
    case's linear host) in the context, and the options with their speeds (the
    cases' lobes, :func:`default_speeds`, if none were given) and their criterion
    (:func:`criterion_for`, if none was given)."""
    cases = as_cases(cases, "cases")
    if integration.initial is not None:
        raise ParameterError(f"initial = {integration.initial!r}: a cut starts as "
                             "options.start says (rest or static), not from initial "
                             "conditions")
    if options.rpm is None:
        options = replace(options, rpm=default_speeds(cases, options.workpiece))
    if options.criterion is None:
        options = replace(options, criterion=criterion_for([c.system for c in cases]))
    chatter_probability.check(options.uncertainty, options.criterion)
    if options.criterion == "growth":  # the step settled once: the runs and the record agree
        integration = integration.with_step(judged_step([c.system for c in cases]))
        _check_growth(cases, integration, options.verdict)
    integration = integration.with_step()
    rpm = np.asarray(options.rpm, dtype=float)
    for r in rpm:
        check_delay(r, options.revolutions, integration.dt_s)
    for case in cases:  # a law the integrator cannot take, refused before any run
        check_cut_law(options.forcing(options.depth(1), float(rpm[0])),
                      resolve_integrator(integration.integrator, case.system, cutting=True))
    context = {"cases": cases, "options": options, "integration": integration,
               "seeds": _seeds(cases, options) if options.method == "search" else {}}
    points = [(i, j) for i in range(len(cases)) for j in range(len(rpm))]
    points += chatter_probability.points(len(cases), len(rpm), options.uncertainty)
    return Plan(context, points)


def _check_growth(cases: list[Case], integration: Integration, options: VerdictOptions) -> None:
    """The converged verdict advances a cut window by window with the RK4 scheme."""
    if integration.integrator == "exact":
        raise ParameterError("integrator = 'exact' with criterion 'growth': the converged "
                             "verdict advances each cut window by window with the RK4 "
                             "scheme; use integrator 'rk4' or 'auto', or a fixed-length "
                             "criterion ('zero', 'bounded') with 'exact'")
    for c in cases:  # true stick-slip needs the stick law
        check_friction_law(c.system, "rk4", verdict.stick_law_of(c.system, options))


def compute(context: dict, point: tuple[int, int]) -> dict:
    """The column of one (case index, rpm index): {depth index: result}; of a drawn
    point (case index, rpm index, block of draws): :func:`.chatter_probability.compute`."""
    if len(point) == 3:
        return chatter_probability.compute(context, point)
    i, j = point
    o, integration = context["options"], context["integration"]
    case, rpm = context["cases"][i], o.rpm[j]
    seed = context["seeds"].get((case.label, rpm), 1)
    if o.criterion == "growth":
        return growth_column(case, rpm, o, integration, seed)
    done: dict[int, dict] = {}

    def chatter(k: int) -> bool:
        if k not in done:
            done[k] = fixed_cut(case, rpm, o.depth(k), o, integration)
        return done[k][o.criterion]

    column(chatter, seed, o.max_index, o.method, o.successive)
    return done


#: The per-run arrays of each criterion family: name -> (fill, dtype).
FIXED_ARRAYS = {"zero": (NOT_RUN, np.int8), "bounded": (NOT_RUN, np.int8),
                "amplitude_m": (np.nan, float), "first_zero": (np.nan, float),
                "impacts": (-1, np.int64), "max_rel_disp_m": (np.nan, float)}
GROWTH_ARRAYS = {"verdict": (NOT_RUN, np.int8), "onset": (NOT_RUN, np.int8),
                 "growth_rate_per_s": (np.nan, float), "growth_rate_se_per_s": (np.nan, float),
                 "run_duration_s": (np.nan, float), "settled_pp_m": (np.nan, float),
                 "settled_rms_m": (np.nan, float)}


def _grid(plan: Plan, results: list[dict]) -> tuple[np.ndarray, dict, int]:
    """(depths, per-run arrays over (case, rpm, depth), number of runs) of the columns."""
    o = plan.context["options"]
    top = max((max(d) for d in results if d), default=1)
    shape = (len(plan.context["cases"]), len(o.rpm), top)
    kinds = GROWTH_ARRAYS if o.criterion == "growth" else FIXED_ARRAYS
    arrays = {name: np.full(shape, fill, dtype=dtype) for name, (fill, dtype) in kinds.items()}
    n_runs = 0
    for (i, j), done in zip(plan.points, results, strict=True):
        for k, res in done.items():
            for name, a in arrays.items():
                v = res[name]
                if name in ("zero", "bounded"):
                    v = CHATTER if v else STABLE
                a[i, j, k - 1] = v
            n_runs += 1
    return o.depths(np.arange(1, top + 1)), arrays, n_runs


CODES = "1 stable, 0 chatter, -1 not run"
GROWTH_CODES = "1 stable, 0 chatter, 2 undecided (the cap came first), -1 not run"


def _fixed_variables(a: dict, bounded_fraction: float) -> dict:
    """The per-run data variables of a fixed-length criterion."""
    dims = ("case", "rpm", "depth_m")
    return {
        "verdict": (dims, a["zero"], {"long_name": "published criterion: force reaches zero",
                                      "codes": CODES}),
        "verdict_bounded": (dims, a["bounded"], {
            "long_name": f"bounded chatter: amplitude > {bounded_fraction:g} h_m, or force "
                         "reaches zero", "codes": CODES}),
        "amplitude_m": (dims, a["amplitude_m"], {"units": "m"}),
        "first_zero_time_s": (dims, a["first_zero"], {"units": "s"}),
        "impacts": (dims, a["impacts"], {
            "long_name": "counted ball impacts over the run (-1: no ball or not run)"}),
        "max_rel_disp_m": (dims, a["max_rel_disp_m"], {
            "units": "m", "long_name": "largest |y|, the ball's excursion from the cavity "
                                       "centre, over the run (ball cases)"}),
    }


def _growth_variables(a: dict) -> dict:
    """The per-run data variables of the converged verdict."""
    dims = ("case", "rpm", "depth_m")
    return {
        "verdict": (dims, a["verdict"], {
            "long_name": "chatter-free: the settled vibration keeps the tool in the cut and "
                         "within the tolerance from every start", "codes": GROWTH_CODES}),
        "onset": (dims, a["onset"], {
            "long_name": "onset: a small knock dies out (1) or grows (0)",
            "codes": GROWTH_CODES}),
        "growth_rate_per_s": (dims, a["growth_rate_per_s"], {
            "units": "1/s", "long_name": "growth rate of the knock's amplitude"}),
        "growth_rate_se_per_s": (dims, a["growth_rate_se_per_s"], {"units": "1/s"}),
        "run_duration_s": (dims, a["run_duration_s"], {
            "units": "s", "long_name": "simulated time the verdict took"}),
        "settled_pp_m": (dims, a["settled_pp_m"], {
            "units": "m", "long_name": "settled tip peak-to-peak (0: the knock dies out)"}),
        "settled_rms_m": (dims, a["settled_rms_m"], {"units": "m"}),
    }


def _column_limits(plan: Plan, results: list[dict], depths: np.ndarray, a: dict):
    """(limit, first unstable, onset) depths per (case, rpm)."""
    o = plan.context["options"]
    shape = (len(plan.context["cases"]), len(o.rpm))
    limit, first, onset = (np.full(shape, np.nan) for _ in range(3))
    for (i, j), done in zip(plan.points, results, strict=True):
        if o.criterion != "growth":
            chosen = a["zero" if o.criterion == "zero" else "bounded"][i, j]
            limit[i, j], first[i, j] = _limits(chosen, depths)
            continue
        onset[i, j] = onset_depth(done, o.depths)
        free, grows = (np.full(len(depths), NOT_RUN, dtype=np.int8) for _ in range(2))
        for k, res in done.items():  # an undecided run counts as the search counted it
            free[k - 1] = CHATTER if not_free(res) else STABLE
            grows[k - 1] = CHATTER if onset_chatters(res) else STABLE
        limit[i, j], first[i, j] = _limits(free, depths)
        if first[i, j] == _limits(grows, depths)[1]:
            limit[i, j] = onset[i, j]  # the chatter-free depth is the onset itself
    return limit, first, onset


def _limit_variables(limit, first, onset, growth: bool) -> dict:
    """The per-column and per-case data variables."""
    out = {
        "limit_depth_m": (("case", "rpm"), limit, {
            "units": "m", "long_name": "limiting (chatter-free) depth of cut"}),
        "first_unstable_depth_m": (("case", "rpm"), first, {"units": "m"}),
        "min_chatter_free_depth_m": (("case",), np.nanmin(np.where(
            np.isnan(limit), np.inf, limit), axis=1), {"units": "m"}),
    }
    if growth:
        out["onset_depth_m"] = (("case", "rpm"), onset, {
            "units": "m", "long_name": "onset: depth where a small knock's growth rate "
                                       "crosses zero"})
    return out


def assemble(plan: Plan, results: list[dict], attrs: dict | None = None):
    """The lobes Dataset from the columns (:func:`compute` results in plan order);
    ``attrs`` go after the configuration's."""
    ctx = plan.context
    cases, o = ctx["cases"], ctx["options"]
    growth = o.criterion == "growth"
    points, results, drawn_points, drawn = chatter_probability.split(plan.points, results)
    plan = Plan(ctx, points, plan.extra)
    depths, a, n_runs = _grid(plan, results)
    limit, first, onset = _column_limits(plan, results, depths, a)
    variables = _growth_variables(a) if growth else _fixed_variables(a, o.bounded_fraction)
    ds = xr.Dataset(
        {**variables, **_limit_variables(limit, first, onset, growth)},
        coords={
            "case": [c.label for c in cases],
            "rpm": ("rpm", np.asarray(o.rpm, dtype=float), {"units": "rev/min"}),
            "depth_m": ("depth_m", depths, {"units": "m"}),
            "bar": ("case", [c.bar for c in cases]),
            "gap_m": ("case", np.array([c.gap_m for c in cases]), {"units": "m"}),
            "friction": ("case", [c.friction for c in cases]),
        },
        attrs={**_attrs(plan, n_runs), **(attrs or {})},
    )
    if growth:
        ds.attrs["mean_run_s"] = float(np.nanmean(a["run_duration_s"])) if n_runs else 0.0
    ds.attrs["method_text"] = method_text(ds)
    if o.analytic:
        _add_analytic(ds, cases, np.asarray(o.rpm, dtype=float), o.analytic_kr_pa)
    if o.uncertainty is not None:
        fills = {name: fill for name, (fill, _) in GROWTH_ARRAYS.items()}
        ds = chatter_probability.add_draws(ds, ctx, drawn_points, drawn, fills)
    return ds


def _attrs(plan: Plan, n_runs: int) -> dict:
    """The configuration a lobes Dataset carries."""
    cases, o, integ = (plan.context[k] for k in ("cases", "options", "integration"))
    growth = (verdict_attrs(o.verdict, [c.system for c in cases]) if o.criterion == "growth"
              else {})
    return {
        "title": "boringbar stability lobes (time domain)",
        "boringbar_version": __version__,
        "method": o.method,
        "depth_grid": o.grid_text(),
        "criterion": o.criterion,
        "successive": o.successive,
        "integrator": integ.integrator,
        "integrator_used": resolved_integrators(integ.integrator, [c.system for c in cases],
                                                cutting=True),
        "delay_interpolation": o.interpolation,
        "start": o.start if o.criterion != "growth" else "in progress, knocked",
        **({"kr_pa": o.kr_pa} if o.law.linear_law else
           {"workpiece": o.law.workpiece or "given", "kc11_pa": o.law.kc11_pa,
            "mc": o.law.mc, "radial_ratio": o.law.radial_ratio}),
        "cutting_law": o.law.describe(),
        "analytic_kr_pa": o.analytic_kr_pa,
        "feed_m": o.feed_m,
        "revolutions": o.revolutions,
        # a fixed-length cut's settings; the verdict runs each cut until it decides
        **({} if o.criterion == "growth" else {
            "bounded_fraction": o.bounded_fraction, "duration_s": integ.duration_s,
            "steady_fraction": integ.steady_fraction}),
        "dt_s": integ.dt_s,
        "runs": n_runs,
        "preset": ",".join(sorted({c.system.preset for c in cases})),
        "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
        **growth,
    }


def lobes(cases: list[Case], options: LobesOptions | None = None, *,
          integration: Integration | None = None, execution: Execution | None = None,
          progress=None):
    """Stability lobes of every case over ``options.rpm`` by time-domain simulation.

    ``cases``: the bars: a System, a sequence of them or a mapping of label to System
    (:func:`~boringbar.analysis.cases.as_cases`; the published ones:
    :func:`~boringbar.analysis.cases.published_cases`); ``options``: :class:`LobesOptions`
    (default: the search to 1 % over the bars' first lobes; the published scan is
    ``LobesOptions(PUBLISHED_RPM, "scan")``); ``integration``: duration, step and integrator
    of each cut (:class:`~boringbar.simulate.Integration`; "exact": the delayed
    surface from a history of step H = tau / ceil(tau / dt), the first zero of the
    force located; no initial conditions: a cut starts as ``options.start`` says);
    ``execution``: where the (case, rpm) columns run (default: judged cuts a process per
    core, :data:`.verdict.EXECUTOR`, others a thread); ``progress(done, total)`` too.

    Returns an xarray Dataset: per (case, rpm, depth_m) the verdict of every grid
    point that was run under both criteria (1 stable, 0 chatter, -1 not run),
    the steady amplitude and the time of the first zero of the force; per
    (case, rpm) the limiting (chatter-free) depth and the first unstable depth
    under the chosen criterion; per case the minimum chatter-free depth;
    and, with ``options.analytic``, for the linear bars (solid, TMD, locked
    ball) the analytic limit.
    """
    options = options or LobesOptions()
    integration = integration or Integration()
    p = plan(cases, options, integration)
    growth = p.context["options"].criterion == "growth"
    execution = (execution or Execution()).resolve(verdict.EXECUTOR if growth else "threads")
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    return assemble(p, results, execution_attrs(execution, wall))


#: The analytic curve about a single speed spans this fraction of it either side.
ONE_SPEED_SPAN = 0.1


def _add_analytic(ds, cases: list[Case], rpm: np.ndarray, kr: float) -> None:
    """The frequency-domain limit of the linear bars (NaN for the free ball), and of
    every case's linear host (System.linear_host: for the free ball the bar a small
    vibration sees, the ball held by its friction or, without friction, not acting)."""

    # evenly spaced in 1/rpm, the lobe number's axis: every lobe drawn as finely (about
    # one speed, over ONE_SPEED_SPAN of it either side)
    lo, hi = rpm.min(), rpm.max()
    if lo == hi:
        lo, hi = lo * (1 - ONE_SPEED_SPAN), hi * (1 + ONE_SPEED_SPAN)
    fine = 1.0 / np.linspace(1.0 / hi, 1.0 / lo, max(200, 20 * len(rpm)))[::-1]
    on_grid = np.full((len(cases), len(rpm)), np.nan)
    curve = np.full((len(cases), len(fine)), np.nan)
    host_grid = np.full((len(cases), len(rpm)), np.nan)
    for i, case in enumerate(cases):
        host_grid[i] = limit_at_speeds(case.system.linear_host(), rpm, kr)
        if case.system.kind in ("solid", "tmd", "locked"):
            on_grid[i] = host_grid[i]
            curve[i] = limit_at_speeds(case.system, fine, kr)
    ds["analytic_limit_m"] = (("case", "rpm"), on_grid, {"units": "m"})
    ds["host_analytic_limit_m"] = (("case", "rpm"), host_grid, {
        "units": "m", "long_name": "analytic limit of the linear host (for the free ball: the "
                                   "bar carrying it by friction, or without it if none)"})
    ds.coords["fine_rpm"] = ("fine_rpm", fine, {"units": "rev/min"})
    ds["analytic_curve_m"] = (("case", "fine_rpm"), curve, {"units": "m"})


def summary(ds) -> dict:
    """JSON-able summary (what ``boringbar lobes --json`` prints): the method in words
    and its settings, and per case and speed the chatter-free depth (with the onset's,
    under the converged verdict, and the analytic limits where known)."""
    out = []
    onset = "onset_depth_m" in ds
    for i, label in enumerate(ds["case"].values):
        out.append({
            "case": str(label),
            "min_chatter_free_depth_m": _num(ds["min_chatter_free_depth_m"].values[i]),
            "speeds": [{"rpm": float(r),
                        "limit_depth_m": _num(ds["limit_depth_m"].values[i, j]),
                        "first_unstable_depth_m": _num(ds["first_unstable_depth_m"].values[i, j]),
                        **({"onset_depth_m": _num(ds["onset_depth_m"].values[i, j])}
                           if onset else {}),
                        **({"analytic_limit_m": _num(ds["analytic_limit_m"].values[i, j]),
                            "host_analytic_limit_m":
                                _num(ds["host_analytic_limit_m"].values[i, j])}
                           if "analytic_limit_m" in ds else {})}
                       for j, r in enumerate(ds["rpm"].values)],
        })
    a = ds.attrs
    return {"method": a["method"], "criterion": a["criterion"],
            "method_text": a["method_text"], "integrator": a["integrator_used"],
            "dt_s": float(a["dt_s"]), "run_length": run_length_text(ds),
            **({"verdict": {k: a[k] for k in ("confidence", "max_duration_s", "knock_m",
                                              "tolerance_m", "settle_tolerance")},
                "undecided_runs": int((ds["verdict"].values == UNDECIDED).sum())}
               if a["criterion"] == "growth" else {"duration_s": float(a["duration_s"])}),
            "runs": int(a["runs"]), "wall_time_s": float(a["wall_time_s"]),
            "min_chatter_free_depth_m": _num(np.nanmin(ds["min_chatter_free_depth_m"].values)),
            "cases": out,
            **({"chatter_probability": chatter_probability.summary(ds)}
               if "chatter_probability" in ds else {})}


def _num(v) -> float | None:
    v = float(v)
    return None if not math.isfinite(v) else v


def compare_methods(scan, search) -> list[dict]:
    """Speeds where the search's limit differs from the published scan's, and why:
    every depth the scan found unstable below the search's limit is a point the
    search assumed stable (stability is not monotone in depth there)."""
    diffs = []
    for i, label in enumerate(scan["case"].values):
        for j, r in enumerate(scan["rpm"].values):
            a = float(scan["limit_depth_m"].values[i, j])
            b = float(search["limit_depth_m"].values[i, j])
            if not (a == b or (math.isnan(a) and math.isnan(b))):
                v = scan["verdict"].values[i, j]
                d = scan["depth_m"].values
                lower = [float(d[k]) for k in range(len(d))
                         if v[k] == CHATTER and (math.isnan(b) or d[k] <= b)]
                diffs.append({"case": str(label), "rpm": float(r), "scan_limit_m": a,
                              "search_limit_m": b, "scan_unstable_below_search_m": lower})
    return diffs
