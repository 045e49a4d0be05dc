"""Sensitivity studies (docs/model.md, section 6): one parameter varied, everything else fixed.

A thin layer over the sweep: each value of the parameter becomes a
:class:`~boringbar.analysis.cases.Case` (built by
:func:`~boringbar.model.system.make_system`; for initial conditions, the same
system with its own ``initial``), and the harmonic runs are the sweep's plan over
all of them; cuts at a fixed spindle speed are one point per (value, depth), a
:func:`~boringbar.simulate.simulate` run with
``Regenerative(depth, rpm, stop_at_zero=False)``.  The contract:
:mod:`boringbar.analysis.base`.

Parameters (``kind``) and their published values:

- ``"ball"``: "carbide", "steel";
- ``"friction_number"``: 0.2, 0.4, 0.6, 0.8 -- the published
  rolling-resistance number, read as the preset reads it (``physical``:
  mm, F_c = mu m g / r_m; ``paper``: the paper's reading, F_c = mu m g /
  0.0075 with r_m in m); friction is on for this kind;
- ``"restitution"``: 0.6, 0.7, 0.8;
- ``"initial"``: initial conditions (W0 (m), W0' (m/s)[, y0 (m), y0' (m/s)])
  or :class:`~boringbar.simulate.Initial`; the system is fixed.

A rattling ball's RMS depends on where it starts: ``starts`` = K runs each harmonic
point again from K starts, the ball at rest at the centres of K equal bins across the
cavity (the bar at rest), beside the study's own run, so that a difference between two
values can be told from the spread over starts (:func:`above_spread`).
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, field, replace

import numpy as np
import xarray as xr

from boringbar._validate import (
    ParameterError,
    check_choice,
    check_int,
    check_positive,
    check_range,
)
from boringbar.analysis import sweep as sweep_mod
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.cases import Case
from boringbar.analysis.sweep import SweepOptions
from boringbar.execute import Execution
from boringbar.model.forcing import Regenerative
from boringbar.model.system import make_system
from boringbar.simulate import Initial, Integration, resolved_integrators, simulate
from boringbar.version import __version__

KINDS = ("ball", "friction_number", "restitution", "initial")
PUBLISHED_VALUES = {
    "ball": ("carbide", "steel"),
    "friction_number": (0.2, 0.4, 0.6, 0.8),
    "restitution": (0.6, 0.7, 0.8),
    "initial": ((0.5e-3, 0.5), (1.0e-3, 1.0)),
}


#: the most starts a harmonic run is repeated from
MAX_STARTS = 64


def start_positions(gap_m: float, starts: int) -> list[float]:
    """The ball's positions (m) of ``starts`` starts: the centres of ``starts`` equal
    bins across the cavity, -delta/2 .. delta/2 (``gap_m`` = delta), none at a wall."""
    half = 0.5 * gap_m
    return [half * (-1.0 + (2 * k + 1) / starts) for k in range(starts)]


@dataclass(frozen=True)
class Cuts:
    """Cuts at one spindle speed over a few depths of cut (published: 1200 rpm,
    0.05..0.10 mm).  ``rpm`` (rev/min), ``depths_m`` (m), ``duration_s`` (s) of each
    full-length run; ``options``: further :class:`~boringbar.model.forcing.Regenerative`
    fields (kr_pa, feed_m, start, ...)."""

    rpm: float = 1200.0
    depths_m: tuple[float, ...] = tuple(round((5 + i) * 1e-5, 12) for i in range(6))
    duration_s: float = 2.0
    options: dict = field(default_factory=dict)

    def __post_init__(self):
        check_positive("cuts rpm", self.rpm)
        if not len(self.depths_m):
            raise ParameterError("cuts depths_m = () must hold at least one depth of cut")
        for d in self.depths_m:
            check_positive("cuts depths_m", d, "m")
        check_positive("cuts duration_s", self.duration_s, "s")


def sensitivity_initial(value) -> Initial:
    if isinstance(value, Initial):
        return value
    try:
        return Initial(*(float(v) for v in value))
    except (TypeError, ValueError):
        raise ParameterError(f"initial condition = {value!r} must be an Initial or "
                             "(W0, W0'[, y0, y0'])") from None


def sensitivity_label(kind: str, value) -> str:
    if kind == "initial":
        i = sensitivity_initial(value)
        return (f"W0={i.tip_displacement_m:g}m W0'={i.tip_velocity_m_s:g}m/s "
                f"y0={i.ball_position_m:g}m y0'={i.ball_velocity_m_s:g}m/s")
    return f"{kind}={value}"


def sensitivity_cases(kind, values, bar, preset, gap, friction, overrides) -> list[Case]:
    cases = []
    for v in values:
        kw = dict(overrides)
        fr = friction
        if kind == "ball":
            kw["ball"] = v
        elif kind == "friction_number":
            kw["friction_number"] = check_range("friction_number", v, 0.0, 100.0)
            fr = True
        elif kind == "restitution":
            kw["restitution"] = check_range("restitution", v, 0.0, 1.0)
        if bar == "ball":
            system = make_system(bar, preset, gap_m=gap, friction=fr, **kw)
        else:
            system = make_system(bar, preset, **kw)
        label = "fixed system" if kind == "initial" else sensitivity_label(kind, v)
        cases.append(Case.of(system, label))
    return cases


@dataclass(frozen=True)
class SensitivityOptions:
    """What a sensitivity study varies and where it looks.

    ``kind``: one of :data:`KINDS` (the module doc); ``values``: its values
    (default: the published ones); harmonic runs over ``forces_n`` (N) x ``ratios``
    (Omega/omega_n), or, with ``cuts`` (a :class:`Cuts`), full-length cuts instead;
    ``starts``: 0, or 2 to :data:`MAX_STARTS` further starts of each harmonic run
    (:func:`start_positions`).
    """

    kind: str = "restitution"
    values: tuple | None = None
    forces_n: tuple[float, ...] = (10.0,)
    ratios: tuple[float, ...] = (1.0,)
    cuts: Cuts | None = None
    starts: int = 0

    def __post_init__(self):
        check_choice("kind", self.kind, KINDS)
        object.__setattr__(self, "starts", check_int("starts", self.starts, 0, MAX_STARTS))
        if self.starts == 1:
            raise ParameterError("starts = 1 must be 0 (the study's own start alone) or 2 to "
                                 f"{MAX_STARTS} (a spread of starts across the cavity)")
        if self.starts and self.kind == "initial":
            raise ParameterError(f"starts = {self.starts} conflicts with kind 'initial' (its "
                                 "values are the starts)")
        if self.starts and self.cuts is not None:
            raise ParameterError(f"starts = {self.starts} applies to the harmonic runs, not "
                                 "to cuts")
        values = PUBLISHED_VALUES[self.kind] if self.values is None else self.values
        if isinstance(values, str) or not len(values):
            raise ParameterError(f"values = {values!r} must hold at least one {self.kind}")
        if self.kind == "initial":
            values = [tuple(v) if isinstance(v, list) else v for v in values]
            for v in values:
                sensitivity_initial(v)  # validates
        object.__setattr__(self, "values", tuple(values))
        labels = self.labels()
        if len(set(labels)) != len(labels):
            raise ParameterError(f"values = {list(self.values)!r} must be distinct")
        sweep_options = SweepOptions(self.ratios, self.forces_n)  # validates both
        object.__setattr__(self, "ratios", sweep_options.ratios)
        object.__setattr__(self, "forces_n", sweep_options.forces_n)

    def labels(self) -> list[str]:
        return [sensitivity_label(self.kind, v) for v in self.values]


def plan(options: SensitivityOptions, integration: Integration, *, preset: str = "physical",
         bar: str = "ball", gap_m: float = 0.5e-3, friction: bool = True,
         overrides: dict | None = None) -> Plan:
    """One case per value (the system of ``preset``, ``bar``, ``gap_m``, ``friction`` and
    ``overrides`` for :func:`~boringbar.model.system.make_system`, with the value set);
    harmonic: the :func:`~boringbar.analysis.sweep.plan` of those cases; cuts: a point
    per (value, depth)."""
    integration = integration.with_step()
    overrides = dict(overrides or {})
    kind = options.kind
    if kind != "initial" and bar != "ball":
        raise ParameterError(f"bar = {bar!r}: kind = {kind!r} varies the ball damper; "
                             "it needs bar = 'ball'")
    varied = {"ball": "ball", "friction_number": "friction_number",
              "restitution": "restitution"}.get(kind)
    if varied in overrides:
        raise ParameterError(f"{varied} = {overrides[varied]!r} cannot be fixed while "
                             f"kind = {kind!r} varies it")
    if kind == "initial":
        fixed = sensitivity_cases(kind, [None], bar, preset, gap_m, friction, overrides)[0]
        cases = [replace(fixed, label=label, initial=sensitivity_initial(v))
                 for label, v in zip(options.labels(), options.values, strict=True)]
    else:
        cases = sensitivity_cases(kind, options.values, bar, preset, gap_m, friction, overrides)
    extra = {"kind": kind, "values": list(options.values), "labels": options.labels(),
             "starts": options.starts, "n_values": len(cases)}
    if options.cuts is None:
        p = sweep_mod.plan(cases + _started(cases, options.starts),
                           SweepOptions(options.ratios, options.forces_n), integration)
        p.context["mode"] = "harmonic"
        p.extra.update(extra)
        return p
    points = [(i, j) for i in range(len(cases)) for j in range(len(options.cuts.depths_m))]
    context = {"mode": "cuts", "cases": cases, "cuts": options.cuts,
               "integration": integration}
    return Plan(context, points, extra)


def _started(cases: list[Case], starts: int) -> list[Case]:
    """Each case again from each of ``starts`` starts (:func:`start_positions`), case by
    case: the runs after the cases' own in the sweep."""
    return [replace(c, label=f"{c.label}, start {k}", initial=Initial(ball_position_m=y))
            for c in cases for k, y in enumerate(start_positions(c.gap_m, starts))]


def compute(context: dict, point):
    """A harmonic point (a sweep batch) or one cut (value, depth)."""
    if context["mode"] == "harmonic":
        return sweep_mod.compute(context, point)
    i, j = point
    cuts, integ = context["cuts"], context["integration"]
    return sensitivity_cut(context["cases"][i], cuts, cuts.depths_m[j], integ)


def sensitivity_cut(case: Case, cuts: Cuts, depth_m: float, integration: Integration) -> dict:
    """One full-length cut of ``case`` at ``depth_m`` (m): its chatter verdicts."""
    forcing = Regenerative(depth_m, cuts.rpm, stop_at_zero=False, **cuts.options)
    c = simulate(case.system, forcing, duration_s=cuts.duration_s, dt_s=integration.dt_s,
                 initial=case.initial or integration.initial,
                 integrator=integration.integrator, record_every=0,
                 stick_law=integration.stick_law).cutting
    return {"chatter": c["chatter"], "bounded_chatter": c["chatter"] or c["bounded_chatter"],
            "amplitude_m": c["amplitude_m"], "max_force_n": c["max_force_n"],
            "first_zero_time_s": math.nan if c["first_zero_time_s"] is None
            else c["first_zero_time_s"]}


def assemble(plan: Plan, results: list, attrs: dict | None = None):
    """The sweep Dataset (harmonic) or the cuts' verdicts over (value, depth_m), with the
    varied parameter as the leading dimension, named after its kind."""
    kind, values, labels = plan.extra["kind"], plan.extra["values"], plan.extra["labels"]
    cases = plan.context["cases"][:plan.extra["n_values"]]
    starts = None
    if plan.context["mode"] == "harmonic":
        ds = sweep_mod.assemble(plan, results, attrs)
        ds, starts = ds.isel(case=slice(0, len(cases))), ds.isel(case=slice(len(cases), None))
        ds.attrs["systems"] = json.dumps({c.label: c.system.to_dict() for c in cases})
    else:
        ds = _cuts_dataset(plan, results, attrs)
    coord = labels if kind == "initial" else values
    ds = ds.assign_coords({kind: ("case", coord), "case": ("case", labels)})
    if kind == "initial":
        ds.attrs.pop("initial", None)
        for name in ("tip_displacement_m", "tip_velocity_m_s", "ball_position_m",
                     "ball_velocity_m_s"):
            ds = ds.assign_coords({name: ("case", [getattr(c.initial, name) for c in cases])})
    ds = ds.swap_dims({"case": kind})
    if kind == "initial":
        ds = ds.drop_vars("case")  # the labels are the coordinate itself
    ds.attrs.update({"sensitivity": kind, "values": json.dumps([str(v) for v in values])})
    if plan.extra["starts"]:
        ds = _with_starts(ds, kind, starts, plan.extra["starts"], cases)
    return ds


def _with_starts(ds, kind: str, started, k: int, cases: list[Case]):
    """``ds`` with the runs from the starts: ``rms_tip_m_starts`` and ``pattern_starts``
    over (kind, start, force_n, ratio), the ball's start position on ``start``."""
    shape = (len(cases), k, ds.sizes["force_n"], ds.sizes["ratio"])
    dims = (kind, "start", "force_n", "ratio")
    return ds.assign(
        rms_tip_m_starts=(dims, started["rms_tip_m"].values.reshape(shape), {"units": "m"}),
        pattern_starts=(dims, started["pattern"].values.reshape(shape)),
    ).assign_coords(ball_position_start_m=(
        ("start",), np.array(start_positions(cases[0].gap_m, k)),
        {"units": "m", "long_name": "the ball's position at rest at the start"}))


def _cuts_dataset(plan: Plan, results: list, attrs: dict | None):
    ctx = plan.context
    cases, cuts, integ = ctx["cases"], ctx["cuts"], ctx["integration"]
    shape = (len(cases), len(cuts.depths_m))
    units = {"amplitude_m": "m", "max_force_n": "N", "first_zero_time_s": "s"}
    data = {k: (("case", "depth_m"), np.array([r[k] for r in results]).reshape(shape),
                {"units": units[k]} if k in units else {})
            for k in results[0]}
    return xr.Dataset(
        data,
        coords={"depth_m": ("depth_m", np.asarray(cuts.depths_m, dtype=float), {"units": "m"})},
        attrs={"title": "boringbar sensitivity (cuts)", "boringbar_version": __version__,
               "integrator": integ.integrator,
               "integrator_used": resolved_integrators(integ.integrator,
                                                       [c.system for c in cases], cutting=True),
               "rpm": cuts.rpm, "dt_s": integ.dt_s,
               "duration_s": cuts.duration_s, "forcing_options": json.dumps(cuts.options),
               "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
               **(attrs or {})},
    )


def sensitivity(options: SensitivityOptions | None = None, *, preset: str = "physical",
                bar: str = "ball", gap_m: float = 0.5e-3, friction: bool = True,
                overrides: dict | None = None, integration: Integration | None = None,
                execution: Execution | None = None, progress=None):
    """Vary one parameter (``options.kind``, see the module doc) over its values.

    ``preset``, ``bar``, ``gap_m`` (m), ``friction`` and ``overrides`` (further
    :func:`~boringbar.model.system.make_system` arguments) describe the fixed
    system; ``integration`` and ``execution`` as for
    :func:`~boringbar.analysis.sweep.sweep`; ``progress(done, total)`` as points
    finish.

    Harmonic (``options.cuts`` None): the :func:`~boringbar.analysis.sweep.sweep`
    Dataset over forces x ratios with a leading dimension named after the kind
    holding the values (for "initial": their labels, with ``tip_displacement_m``,
    ``tip_velocity_m_s``, ``ball_position_m``, ``ball_velocity_m_s`` coordinates).  Cutting:
    a Dataset over (kind, depth_m) with the chatter verdict (the force reached
    zero), bounded chatter, steady amplitude (m), first zero time (s) and peak
    force (N) of each full-length cut.
    """
    options = options or SensitivityOptions()
    integration = integration or Integration()
    p = plan(options, integration, preset=preset, bar=bar, gap_m=gap_m, friction=friction,
             overrides=overrides)
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    return assemble(p, results, execution_attrs(execution, wall))


def rms_at_ratio(entry: dict, ratio: float) -> list[float]:
    """The tip RMS values (m) of a summary's harmonic ``entry`` at the ratio nearest
    ``ratio``: its own run's, then its starts' where it has them."""
    k = int(np.argmin(np.abs(np.asarray(entry["ratio"]) - ratio)))
    starts = entry.get("starts")
    return [entry["rms_tip_m"][k]] + ([r[k] for r in starts["rms_tip_m"]] if starts else [])


def above_spread(a: list[float], b: list[float]) -> tuple[bool, float, float]:
    """Whether the values ``a`` lie above ``b`` beyond their spread: the difference of
    their means beyond twice its standard error (from each list's sample variance; one
    value each: the plain comparison).  Returns that, the difference and its error."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    diff = float(a.mean() - b.mean())
    var = sum(float(np.var(x, ddof=1)) / x.size for x in (a, b) if x.size > 1)
    se = math.sqrt(var)
    return diff > 2.0 * se, diff, se


def with_cuts(ds, cuts):
    """The harmonic and the cut results in one Dataset: the cut variables and
    attributes prefixed ``cut_``."""
    cuts = cuts.rename({k: f"cut_{k}" for k in cuts.data_vars})
    keep = ("rpm", "duration_s", "wall_time_s", "forcing_options", "title")
    attrs = {f"cut_{k}": v for k, v in cuts.attrs.items() if k in keep}
    merged = xr.merge([ds, cuts.drop_vars([c for c in ("case",) if c in cuts.coords])],
                      combine_attrs="override")
    merged.attrs.update(attrs)
    return merged


def summary(ds) -> dict:
    """JSON-able summary of a sensitivity Dataset (what ``boringbar sensitivity --json``
    prints; the cut results where :func:`with_cuts` merged them in)."""
    kind = ds.attrs["sensitivity"]
    labels = [str(v) for v in ds[kind].values]
    values = [v.item() if isinstance(v, np.generic) else v for v in ds[kind].values]
    harmonic = []
    for i, value in enumerate(values):
        for j, force in enumerate(ds["force_n"].values):
            harmonic.append({"value": value, "force_n": float(force),
                             "ratio": ds["ratio"].values.tolist(),
                             "rms_tip_m": ds["rms_tip_m"].values[i, j].tolist(),
                             "pattern": [str(p) for p in ds["pattern"].values[i, j]]})
            if "rms_tip_m_starts" in ds:  # per start, per ratio
                harmonic[-1]["starts"] = {
                    "ball_position_m": ds["ball_position_start_m"].values.tolist(),
                    "rms_tip_m": ds["rms_tip_m_starts"].values[i, :, j].tolist(),
                    "pattern": ds["pattern_starts"].values[i, :, j].tolist()}
    summary = {"kind": kind, "values": values, "preset": ds.attrs.get("preset"),
               "harmonic": harmonic, "cuts": None, "wall_time_s": ds.attrs.get("wall_time_s")}
    if kind == "initial":
        summary["initial"] = [{name: float(ds[name].values[i]) for name in
                               ("tip_displacement_m", "tip_velocity_m_s", "ball_position_m",
                                "ball_velocity_m_s")} for i in range(len(labels))]
    if "cut_chatter" in ds:
        summary["cuts"] = {
            "rpm": ds.attrs["cut_rpm"], "depth_m": ds["depth_m"].values.tolist(),
            "results": [{"value": value,
                         **{k: ds[f"cut_{k}"].values[i].tolist()
                            for k in ("chatter", "bounded_chatter", "amplitude_m",
                                      "max_force_n", "first_zero_time_s")}}
                        for i, value in enumerate(values)]}
    return summary
