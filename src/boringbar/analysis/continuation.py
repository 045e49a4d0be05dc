"""Continuation of periodic orbits with their Floquet stability (docs/continuation.md).

One point of the plan is one orbit map (sequential by nature,
:func:`boringbar.orbits.orbit_map.orbit_map`): its first branch starts from a settled exact
simulation at the start value, from the Masri-Caughey closed form (one mode, no
friction) or from a given :class:`~boringbar.simulate.State` at phase 0; brute-force
attractors at a few values of the parameter seed more
(:mod:`boringbar.orbits.attractors`); the branches born at branch points, period doublings
and grazings are followed too; each attractor is checked against the map.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from boringbar._validate import ParameterError, check_choice, check_finite, check_int
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation
from boringbar.analysis.cut_continuation import CutContinuationOptions, cut_continuation
from boringbar.execute import Execution
from boringbar.model.dampers import Friction
from boringbar.model.forcing import Harmonic, Regenerative
from boringbar.model.system import System
from boringbar.orbits.attractors import (
    RETURN_TOL,
    SETTLED,
    periodic_attractors,
    return_distance,
    spread,
)
from boringbar.orbits.branch import (
    MAX_STEP,
    PARAMETERS,
    check_parameter,
    check_steps,
    flow_with,
    value_of,
)
from boringbar.orbits.orbit_map import MapOptions, attractor_check, orbit_map
from boringbar.orbits.shooting import (
    OrbitRefused,
    advance,
    carry,
    make_flow,
    one_blas_thread,
    state_size,
)
from boringbar.reference.masri_caughey import two_impact_orbit
from boringbar.simulate import Integration, simulate
from boringbar.version import __version__

STARTS = ("simulation", "masri-caughey", "state")
#: The continuation parameters a brute-force diagram sweeps (their bifurcation names).
BRUTE_FORCE = {"force-n": "force", "ratio": "ratio"}


@dataclass(frozen=True)
class ContinuationOptions:
    """``parameter`` (one of :data:`boringbar.orbits.branch.PARAMETERS`) continued from its value
    in the system/forcing to ``stop``; ``force_n`` and ``ratio``: the forcing;
    ``periods``: k of P^k; ``step``: the first step and ``max_step`` the largest, relative
    to the range; ``max_points``: the point budget (None: from ``max_step``,
    :func:`boringbar.orbits.branch.point_budget`);
    ``start``: "simulation" (``settle_periods`` periods of the exact integrator from
    rest, and as many again until the state returns to itself: SETTLE_STRETCHES),
    "masri-caughey" or "state" (``state``, at phase 0); ``min_step``: the
    smallest step the halving goes down to before the branch stops (relative);
    ``switch``, ``seeds``, ``max_branches``: the orbit map's (docs/continuation.md, "The
    orbit map"); ``other_end``: the map covers [other_end, stop] (either order), the
    first orbit inside it and continued both ways (None: [start value, stop]);
    ``return_periods``: the return check of every stable point (the exact integrator
    over that many periods from it, perturbed; 0: none)."""

    parameter: str = "force-n"
    stop: float = 5.0
    force_n: float = 30.0
    ratio: float = 1.0
    periods: int = 1
    step: float = 0.02
    max_points: int | None = None
    start: str = "simulation"
    settle_periods: int = 200
    state: tuple | None = None
    min_step: float = 1e-6
    max_step: float = MAX_STEP
    #: Follow the branches born at branch points, period doublings and grazings.
    switch: bool = True
    #: Parameter values (spread over the range) at which brute force seeds branches
    #: (the free ball; 0: none).
    seeds: int = 3
    max_branches: int = 24
    other_end: float | None = None
    #: The return check of every stable point: the exact integrator over this many
    #: periods from it, perturbed (0: none).
    return_periods: int = 200

    def __post_init__(self):
        check_choice("parameter", self.parameter, PARAMETERS)
        check_choice("start", self.start, STARTS)
        check_int("periods", self.periods, 1, 16)
        if self.max_points is not None:
            check_int("max_points", self.max_points, 2, 100000)
        check_int("settle_periods", self.settle_periods, 1, 100000)
        check_steps(self.step, self.min_step, self.max_step)
        check_int("seeds", self.seeds, 0, 50)
        check_int("max_branches", self.max_branches, 1, 1000)
        if self.other_end is not None:
            check_finite("other_end", self.other_end)
        check_int("return_periods", self.return_periods, 0, 100000)
        if self.start == "state" and self.state is None:
            raise ParameterError("start = 'state' needs state = (u..., u'..., y, y') (ball), "
                                 "(u..., u'..., x_a, x_a') (TMD) or (u..., u'...)")
        Harmonic(self.force_n, ratio=self.ratio)  # validates both


def plan(system: System, options: ContinuationOptions) -> Plan:
    """One point: the branch of ``system`` (any bar; the parameter must be one it has)."""
    check_parameter(system.kind, options.parameter)
    if options.other_end is not None:
        p0 = value_of(make_flow(system, Harmonic(options.force_n, ratio=options.ratio)),
                      options.parameter)
        if not min(options.other_end, options.stop) < p0 < max(options.other_end, options.stop):
            raise ParameterError(f"other_end = {options.other_end!r}: the start value {p0!r} "
                                 f"must lie strictly between it and stop = {options.stop!r}")
    return Plan({"system": system, "options": options}, [0])


def _check_masri_caughey(system: System, fl) -> None:
    """Masri and Caughey's orbit is a frictionless sliding ball's on a bar of one mode."""
    bar = system.bar
    two = bar.planes == 2
    wrong = [what for what, bad in (
        (f"a {system.kind} bar", system.kind != "ball"),
        ("two bending planes", two),
        (f"{bar.n_modes} modes", not two and bar.n_modes != 1),
        ("friction", fl.fc > 0), ("a rolling ball", fl.roll)) if bad]
    if wrong:
        raise ParameterError("start = 'masri-caughey' needs a sliding ball on one mode of one "
                             f"bending plane, without friction; this system has "
                             f"{', '.join(wrong)}")


def start_state(system: System, o: ContinuationOptions, fl) -> np.ndarray:
    """The first guess of the orbit's state at phase 0 (see the module docstring)."""
    if o.start == "state":
        if len(o.state) != fl.N:
            raise ParameterError(f"state has {len(o.state)} entries; the {system.kind} bar's "
                                 f"orbit has {fl.N} (docs/continuation.md, Shooting)")
        return np.asarray(o.state, float)
    if o.start == "masri-caughey":
        bar, ball = system.bar, system.damper
        _check_masri_caughey(system, fl)
        orbits = [o_ for o_ in two_impact_orbit(
            bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0], bar.psi_tip[0],
            bar.psi_damper[0], ball.mass_kg, ball.gap_m, ball.restitution, o.force_n, fl.omega)
            if o_.admissible]
        if not orbits:
            raise ParameterError(f"no admissible symmetric two-impact orbit at force_n = "
                                 f"{o.force_n} N, ratio = {o.ratio}")
        orb = orbits[0]
        h = 1e-9
        dy0 = float(orb.relative_displacement(h) - orb.relative_displacement(-h)) / (2 * h)
        return np.array([float(orb.modal_displacement(0.0)), float(orb.modal_velocity(0.0)),
                         float(orb.relative_displacement(0.0)), dy0])
    return _simulated_start(system, o, fl)


#: A simulated start runs ``settle_periods`` forcing periods from rest, and as many again,
#: up to this many stretches in all, until its state returns to itself over the orbit's
#: periods within SETTLED of its size (a transient can outlast the first stretch, and
#: Newton refuses to start from it).
SETTLE_STRETCHES = 4


def _simulated_start(system: System, o: ContinuationOptions, fl) -> np.ndarray:
    """The state at phase 0 after the exact integrator's settling (SETTLE_STRETCHES)."""
    forcing = Harmonic(o.force_n, ratio=o.ratio)
    dt = fl.period / math.ceil(fl.period / 1e-6)  # whole periods: the end is at phase 0
    state = None
    for _ in range(SETTLE_STRETCHES):
        run = simulate(system, forcing, duration_s=o.settle_periods * fl.period, dt_s=dt,
                       integrator="exact", initial=state, record_every=0)
        x = run.final.x[:fl.N]
        back = simulate(system, forcing, duration_s=o.periods * fl.period, dt_s=dt,
                        integrator="exact", initial=run.final, record_every=0)
        if np.max(np.abs(back.final.x[:fl.N] - x)) <= SETTLED * np.max(np.abs(x)):
            break
        state = run.final
    return x


@one_blas_thread
def compute(context: dict, point: int) -> dict:
    """The orbit map (:func:`boringbar.orbits.orbit_map.orbit_map`): per branch its points'
    value, state, strobe tip, RMS, multipliers, its events, parent and birth; the seeds'
    attractor check."""
    system, o = context["system"], context["options"]
    fl = make_flow(system, Harmonic(o.force_n, ratio=o.ratio))
    x0 = start_state(system, o, fl)
    seeds = [(v, a.x, a.periods) for v, a in _attractors(system, o, fl, o.seeds)]
    mo = MapOptions(o.switch, 2 * o.periods, o.max_branches, o.step, o.max_step, o.min_step,
                    o.max_points)
    om = orbit_map(fl, o.parameter, x0, o.stop, seeds=seeds, periods=o.periods,
                   other_end=o.other_end, options=mo)
    branches = [_branch_result(mb, fl, o) | {"return_distance_relative": _returns(system, o, mb),
                                             "mirror": om.mirrors.get(i, -1)}
                for i, mb in enumerate(om.branches)]
    # checked where no seed was taken (between the seeds' values), so that an attractor
    # on the map is not there merely because it started a branch
    check = [attractor_check(om, v, a.x, a.periods) | {"impacts": a.impacts}
             for v, a in _attractors(system, o, fl, 2 * o.seeds)]
    return {"branches": branches, "notes": om.notes, "check": check,
            "start": value_of(fl, o.parameter)}


def system_at(system: System, o: ContinuationOptions, value: float) -> tuple:
    """(system, forcing) of the problem with its parameter at ``value``: on the
    descriptions what :func:`boringbar.orbits.branch.flow_with` does to a flow, for the exact
    integrator's runs (a ball mass keeps the friction force F_c, as the flow does)."""
    name, forcing = o.parameter, Harmonic(o.force_n, ratio=o.ratio)
    if name == "force-n":
        return system, Harmonic(value, ratio=o.ratio)
    if name == "ratio":
        return system, Harmonic(o.force_n, ratio=value)
    d = system.damper
    if name == "gap-mm":
        d = dataclasses.replace(d, gap_m=value * 1e-3)
    elif name == "restitution":
        d = dataclasses.replace(d, restitution=value)
    elif name == "friction-force-n":
        f = d.friction
        ratio = f.static_ratio if f.kind != "none" else 1.0
        d = dataclasses.replace(d, friction=Friction("force", value, f.reaction, ratio))
    elif name == "ball-mass-g":
        f = d.friction
        d = dataclasses.replace(d, mass_kg=value * 1e-3, friction=Friction(
            "force", d.friction_force_n, f.reaction, f.static_ratio) if f.kind != "none" else f)
    return dataclasses.replace(system, damper=d), forcing


def _attractors(system: System, o: ContinuationOptions, fl, count: int) -> list:
    """[(value, Attractor)]: brute force's periodic attractors at ``count`` values spread
    over the range (the middles of equal parts; the free ball, any parameter)."""
    if count == 0 or system.kind != "ball":
        return []
    ends = (value_of(fl, o.parameter), o.stop, *(() if o.other_end is None else (o.other_end,)))
    found = []
    for v in spread(min(ends), max(ends), count):
        found += [(v, a) for a in periodic_attractors(*system_at(system, o, v),
                                                      max_period=2 * o.periods)]
    return found


def _returns(system: System, o: ContinuationOptions, mb) -> list:
    """The return check of each stable point of a branch (NaN for the others):
    :func:`boringbar.orbits.attractors.return_distance` over ``o.return_periods``."""
    br = mb.branch
    if not o.return_periods:
        return [math.nan] * len(br.points)
    return [return_distance(*system_at(system, o, pt.value), pt.x, pt.phase, br.periods,
                            o.return_periods) if pt.stable else math.nan
            for pt in br.points]


def _branch_result(mb, fl, o: ContinuationOptions) -> dict:
    """One branch of the map as :func:`assemble` takes it."""
    br = mb.branch
    rms, states = [], []
    for pt in br.points:
        at = flow_with(dataclasses.replace(fl, phase=pt.phase), o.parameter, pt.value, fl)
        try:
            rms.append(advance(at, pt.x, br.periods, rms=True).rms_tip)
            states.append(carry(at, pt.x, 0.0))  # the section may have moved
        except OrbitRefused:
            rms.append(math.nan)
            states.append(np.full(fl.N, np.nan))
    n = fl.n
    return {"value": [pt.value for pt in br.points],
            "state": states,
            "strobe_tip_m": [float(fl.psi_tip @ x[:n]) for x in states],
            "section_phase": [pt.phase for pt in br.points],
            "rms_tip_m": rms,
            "multipliers": [pt.multipliers for pt in br.points],
            "stable": [pt.stable for pt in br.points],
            "events": br.events, "stop": br.stop, "periods": br.periods,
            "parent": -1 if mb.parent is None else mb.parent,
            "born_kind": mb.born[0], "born_value": float(mb.born[1])}


def assemble(plan: Plan, results: list[dict], attrs: dict | None = None) -> xr.Dataset:
    """Dims (branch, point, state, multiplier) and (branch, event); the multipliers as
    real and imaginary parts (NetCDF has no complex type); per branch its period, its
    parent (-1: a root) and the event it was born at (born_kind, born_value); the map's
    notes and attractor check in the attributes (JSON)."""
    r = results[0]
    if "branches" in r:
        parts = [assemble(plan, [b], attrs) for b in r["branches"]] or \
            [assemble(plan, [_empty(r)], attrs)]
        ds = concat_branches(parts)
        ds.attrs["notes"] = json.dumps(r["notes"])
        ds.attrs["attractor_check"] = json.dumps(r["check"])
        return ds
    o = plan.context["options"]
    n_state = state_size(plan.context["system"])
    # a branch refused at its start has no points: its arrays keep their shapes
    states = np.asarray(r["state"], float).reshape(len(r["value"]), -1) if r["value"] \
        else np.zeros((0, n_state))
    mults = np.asarray(r["multipliers"], complex).reshape(len(r["value"]), -1) \
        if r["value"] else np.zeros((0, n_state), complex)
    ds = xr.Dataset(
        {"value": (("branch", "point"), [r["value"]]),
         "state": (("branch", "point", "state"), [states]),
         "strobe_tip_m": (("branch", "point"), [r["strobe_tip_m"]]),
         "rms_tip_m": (("branch", "point"), [r["rms_tip_m"]]),
         "section_phase": (("branch", "point"),
                           [r.get("section_phase", [0.0] * len(r["value"]))]),
         "multiplier_real": (("branch", "point", "multiplier"), [mults.real]),
         "multiplier_imag": (("branch", "point", "multiplier"), [mults.imag]),
         "stable": (("branch", "point"), [r["stable"]]),
         "return_distance_relative": (("branch", "point"), [r.get(
             "return_distance_relative", [math.nan] * len(r["value"]))]),
         "event_kind": (("branch", "event"), [[k for k, _ in r["events"]]]),
         "event_value": (("branch", "event"), [[v for _, v in r["events"]]]),
         "periods": (("branch",), [r.get("periods", o.periods)]),
         "parent": (("branch",), [r.get("parent", -1)]),
         "born_kind": (("branch",), [r.get("born_kind", "start")]),
         # the branch of this one's mirror image (y -> -y, W -> -W half a period later):
         # a distinct orbit of the same RMS and range; -1: none on the map
         "mirror": (("branch",), [r.get("mirror", -1)]),
         "born_value": (("branch",), [r.get("born_value", r.get("start", math.nan))])},
        attrs={"boringbar_version": __version__, "parameter": o.parameter,
               "config": json.dumps({"system": plan.context["system"].to_dict(),
                                     "options": asdict(o)}),
               "stop_reasons": json.dumps([r["stop"]]), **(attrs or {})})
    return ds


def _empty(r: dict) -> dict:
    """A branch without points (the map's start refused) for a map without branches."""
    return {"value": [], "state": [], "strobe_tip_m": [], "rms_tip_m": [], "multipliers": [],
            "stable": [], "events": [], "start": r["start"], "born_value": r["start"],
            "stop": "; ".join(dict.fromkeys(r["notes"])) or "no branch"}  # each once


def summary(ds: xr.Dataset) -> dict:
    """The JSON summary: ``branches`` (points, events, stop) and ``wall_time_s``."""
    branches = []
    stops = json.loads(ds.attrs["stop_reasons"])
    for b in range(ds.sizes["branch"]):
        d = ds.isel(branch=b)
        points = [{"value": float(d["value"][i]), "strobe_tip_m": float(d["strobe_tip_m"][i]),
                   "rms_tip_m": float(d["rms_tip_m"][i]), "stable": bool(d["stable"][i]),
                   "multipliers_abs": np.hypot(d["multiplier_real"][i].values,
                                               d["multiplier_imag"][i].values).tolist()}
                  for i in range(d.sizes["point"]) if np.isfinite(d["value"][i])]
        events = [{"kind": str(k), "value": float(v)}
                  for k, v in zip(d["event_kind"].values, d["event_value"].values, strict=True)
                  if str(k)]  # "": padding of a shorter branch's events
        branches.append({"points": points, "events": events, "stop": stops[b],
                         **_tree(d)})
    return {"parameter": ds.attrs["parameter"], "branches": branches,
            "notes": json.loads(ds.attrs.get("notes", "[]")),
            "attractor_check": json.loads(ds.attrs.get("attractor_check", "[]")),
            "return_check": return_check(ds),
            "wall_time_s": float(ds.attrs.get("wall_time_s", math.nan))}


def return_check(ds: xr.Dataset) -> dict:
    """The return check of the stable points (:func:`boringbar.orbits.attractors.return_distance`):
    how many were checked, the largest distance and those farther than RETURN_TOL (branch,
    value, distance): stable points that are not attractors of the exact integrator."""
    if "return_distance_relative" not in ds:
        return {"checked_count": 0, "largest_relative": None, "failed": []}
    d = ds["return_distance_relative"].values
    checked = np.isfinite(d) | np.isinf(d)
    failed = [{"branch": int(b), "value": float(ds["value"].values[b, i]),
               "distance_relative": float(d[b, i])}
              for b, i in zip(*np.nonzero(checked & ~(d <= RETURN_TOL)), strict=True)]
    return {"checked_count": int(checked.sum()),
            "largest_relative": float(np.max(d[checked])) if checked.any() else None,
            "failed": failed}


def _tree(d: xr.Dataset) -> dict:
    """A branch's place in the map: its period, parent (None: a root) and birth."""
    if "parent" not in d:
        return {}
    parent = int(d["parent"])
    mirror = int(d["mirror"]) if "mirror" in d else -1  # (files written before it)
    return {"periods": int(d["periods"]), "parent": None if parent < 0 else parent,
            "born": {"kind": str(d["born_kind"].values), "value": float(d["born_value"])},
            "mirror": None if mirror < 0 else mirror}


def continuation(system: System, forcing: Harmonic | Regenerative | None = None, *,
                 options: ContinuationOptions | CutContinuationOptions | None = None,
                 execution: Execution | None = None) -> xr.Dataset:
    """Continue a periodic orbit of ``system`` under ``forcing`` (its F0 and ratio override
    ``options``'): a Dataset of branches with their state, strobe tip displacement, RMS,
    Floquet multipliers, stability and events (kind, value); see
    :class:`ContinuationOptions` and docs/continuation.md.  ``execution``: the
    contract's (one point: the branch).

    Under a :class:`~boringbar.model.forcing.Regenerative` cut, the branch of chatter orbits
    from a Hopf point, in depth at its speed or in speed at its depth
    (:func:`boringbar.analysis.cut_continuation.cut_continuation`, options
    :class:`~boringbar.analysis.cut_continuation.CutContinuationOptions`)."""
    if isinstance(forcing, Regenerative):
        if options is not None and not isinstance(options, CutContinuationOptions):
            raise ParameterError("a cut's continuation takes CutContinuationOptions")
        return cut_continuation(system, forcing, options)
    options = options or ContinuationOptions()
    if forcing is not None:
        if forcing.ratio is None:
            raise ParameterError("forcing: give the frequency as ratio for continuation")
        options = ContinuationOptions(**{**asdict(options), "force_n": forcing.amplitude_n,
                                         "ratio": forcing.ratio})
    p = plan(system, options)
    results, wall = run_plan(sys.modules[__name__], p, execution)
    return assemble(p, results, execution_attrs(execution, wall))


def brute_force(system: System, options: ContinuationOptions, start: float, n_values: int = 21,
                integration: Integration | None = None) -> xr.Dataset:
    """The brute-force bifurcation diagram of the branch's case (``bb.bifurcation``, from
    rest, forward and backward) over ``n_values`` values from ``start`` to
    ``options.stop``, for the overlay of :func:`~boringbar.plot.orbits.plot_continuation`;
    ``integration``: default exact, 1 s runs, the last half sampled."""
    if options.parameter not in BRUTE_FORCE:
        raise ParameterError(f"parameter = {options.parameter!r}: a brute-force overlay sweeps "
                             f"{' or '.join(BRUTE_FORCE)} only")
    check_int("n_values", n_values, 2, 1000)
    values = tuple(np.linspace(start, options.stop, n_values).tolist())
    name = BRUTE_FORCE[options.parameter]
    bf = BifurcationOptions(name, values, options.force_n, options.ratio, backward=True)
    return bifurcation(system, bf, integration=integration or Integration(1.0, 1e-6, "exact", 0.5))


def concat_branches(datasets: list[xr.Dataset]) -> xr.Dataset:
    """Continuation Datasets stacked along ``branch`` (shorter branches NaN-padded, their
    missing events of kind ""), with every branch's stop reason."""
    indexed = [d.assign_coords(point=np.arange(d.sizes["point"]),
                               event=np.arange(d.sizes["event"])) for d in datasets]
    ds = xr.concat(indexed, dim="branch", join="outer", combine_attrs="override",
                   fill_value={"event_kind": "", "event_value": np.nan, "stable": False,
                               "value": np.nan})
    ds = ds.drop_vars(["point", "event"]).reset_coords()  # "state" stays a data variable
    ds.attrs["stop_reasons"] = json.dumps([r for d in datasets
                                           for r in json.loads(d.attrs["stop_reasons"])])
    return ds
