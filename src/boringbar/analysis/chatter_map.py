"""The chatter amplitude map: what a cut's vibration does at every speed and depth
(docs/chatter_map.md).

Every cell of a grid of spindle speeds x depths of cut, for every bar (case), is one cut
judged by the converged verdict (:func:`boringbar.analysis.verdict.judge`, RK4):

- the **onset**: does a small knock grow (its growth rate, and its sign once certain);
- the **settled vibration** of each start, the small knock and then each large knock of
  ``verdict.knocks_m``: the tip's peak-to-peak and RMS once converged in run length, and
  whether the tool left the cut.  A knock that dies out settles at 0.  A bar without a
  free ball is linear until the tool leaves the cut, so a small knock that grows on it is
  not run on: it grows until the tool leaves the cut (``left_cut``, its peak-to-peak
  unknown, NaN);
- **chatter-free**: from every start the settled vibration keeps the tool in the cut and
  its tip peak-to-peak within ``verdict.tolerance_m``.

Per (case, speed) the map gives the **chatter-free depth**, the largest depth of the grid
such that every depth of the grid up to it is chatter-free (0: the shallowest is not; the
deepest depth: every one is), and the **onset depth**, where a small knock's growth rate
crosses zero, interpolated between the two grid depths where the onset turns from
stable to chatter (:func:`~boringbar.analysis.lobe_search.onset_depth`).  Where a lobe
study (:mod:`boringbar.analysis.lobes`) searches each speed for its limit, the map runs
every cell: how large the vibration a ball bounds above its onset is, and where a large
knock makes a cut chatter that a small one leaves stable.

Each (case, speed, depth) cell is one point of the plan (the contract:
:mod:`boringbar.analysis.base`), in grid order.  Hundreds of cells share a few workers, so
the order does not matter to the wall time (benchmarks/bench_chatter_map.py: a list
schedule of the measured cells on 2 workers ends within 0.2 % of the ideal in grid
order).
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from boringbar._validate import ParameterError, check_values
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.cases import Case, as_cases
from boringbar.analysis.lobe_search import CHATTER, STABLE, UNDECIDED, onset_depth
from boringbar.analysis.speeds import boring_speeds, check_speeds, lobe_speeds
from boringbar.analysis.verdict import CHATTER as ONSET_CHATTER
from boringbar.analysis.verdict import (
    EXECUTOR,
    CutVerdict,
    Settled,
    VerdictOptions,
    acceptable,
    judge,
    judged_step,
    step_text,
    stick_law_of,
    verdict_attrs,
)
from boringbar.analysis.verdict import STABLE as ONSET_STABLE
from boringbar.execute import Execution
from boringbar.model.cutting import KR_ALUMINIUM, CutLawFields, CuttingLaw
from boringbar.model.forcing import MAX_DEPTH, Regenerative
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import Integration, check_friction_law
from boringbar.simulate.run_limits import check_delay
from boringbar.version import __version__

#: Speeds of the default grid, evenly spaced in 1/rpm (the lobe number's axis).
MAP_SPEEDS = 30
#: The lobe numbers k = 60 f1 / rpm the default speeds span for a bar without a diameter
#: (a modal fit of a measured FRF, a tap test): lobes 1 to 3 of its first mode.
MAP_LOBES = (0.9, 3.1)
#: Depths of the default grid, evenly spaced over this span in multiples of the smallest
#: analytic limit of the cases' linear hosts over the speeds (the bare-bar limit, below
#: which a linear bar never chatters; a ball's onset and the vibration it bounds lie
#: above it).
DEPTHS = 20
DEPTH_SPAN = (0.5, 3.0)
#: The default large knock (m, a tip amplitude): twice the default tolerance, so a
#: knock that dies out passes through vibration the finish would not accept, as a hard
#: spot in the workpiece or the entry into a cut gives.
LARGE_KNOCK_M = 20e-6
#: The cut settings (simulate's keywords) a map does not take: every cut starts in
#: progress, knocked, and runs until its verdict (at most max_run_s).
NOT_FOR_A_MAP = ("duration_s", "start", "bounded_fraction")
#: The name of the first start.
SMALL_KNOCK = "small knock"
#: The settled statuses: a small knock's that dies out, then the verdict's own
#: (:class:`~boringbar.analysis.verdict.Settled`).
DIED_OUT, SETTLED, LEFT_CUT, UNDECIDED_STATUS = (
    "died out", "settled", "left the cut", "undecided")
CODES = "1 chatter-free (stable), 0 not (chatter), 2 undecided (the cap came first)"


@dataclass(frozen=True)
class ChatterMapOptions(CutLawFields):
    """A chatter map's grid, cut and verdict.

    ``rpm``: spindle speeds (rev/min, increasing; None, the default: :func:`map_speeds`,
    the speeds at which a carbide insert bores the ``workpiece`` with the cases' bars,
    or for a bar without a diameter lobes 1 to 3 of its first mode); ``depths_m``:
    depths of cut (m, increasing; None, the default: :func:`map_depths`, DEPTHS depths
    from 0.5 to 3 times the smallest analytic limit of the cases' linear hosts).  The cut
    (:class:`~boringbar.model.forcing.Regenerative`; it starts in progress, at the static
    deflection, and is knocked): ``kr_pa`` (Pa; the linear law's Kr), ``feed_m`` (m),
    ``revolutions``, ``interpolation``, ``workpiece`` (Kienzle's law of a material, or a
    CuttingLaw, in place of ``kr_pa``).  ``verdict``: how each cell is judged
    (:class:`~boringbar.analysis.verdict.VerdictOptions`; by default with one large knock
    of :data:`LARGE_KNOCK_M`).
    """

    rpm: tuple[float, ...] | None = None
    depths_m: tuple[float, ...] | None = None
    kr_pa: float = KR_ALUMINIUM
    feed_m: float = 0.1e-3
    revolutions: int = 3
    interpolation: str = "cubic"
    workpiece: str | CuttingLaw | None = None
    verdict: VerdictOptions = VerdictOptions(knocks_m=(LARGE_KNOCK_M,))

    def __post_init__(self):
        if self.rpm is not None:
            object.__setattr__(self, "rpm", check_speeds("rpm", self.rpm))
        if self.depths_m is not None:
            object.__setattr__(self, "depths_m", check_depths("depths_m", self.depths_m))
        if not isinstance(self.verdict, VerdictOptions):
            raise ParameterError(f"verdict = {self.verdict!r} must be a VerdictOptions")
        # the cut's own fields, checked by the cut
        self.forcing(self.depths_m[0] if self.depths_m else 1e-4,
                     self.rpm[0] if self.rpm else 1000.0)

    @property
    def starts(self) -> tuple[str, ...]:
        """The names of the starts: the small knock, then each large knock."""
        return (SMALL_KNOCK,) + tuple(f"knock {k * 1e6:g} um" for k in self.verdict.knocks_m)

    def forcing(self, depth_m: float, rpm: float) -> Regenerative:
        """The cut at ``depth_m`` (m) and ``rpm``, in progress and run on past a zero of the
        force (as the verdict runs it)."""
        return Regenerative(depth_m=depth_m, rpm=rpm, kr_pa=self.kr_pa, feed_m=self.feed_m,
                            revolutions=self.revolutions, interpolation=self.interpolation,
                            start="static", stop_at_zero=False, workpiece=self.workpiece)


def check_depths(name: str, depths_m) -> tuple[float, ...]:
    """Depths of cut (m): in (0, MAX_DEPTH], increasing, each once."""
    depths = check_values(name, np.atleast_1d(depths_m).tolist(), 0.0, MAX_DEPTH,
                          lo_open=True, unit="m")
    if np.any(np.diff(depths) <= 0):
        raise ParameterError(f"{name} = {list(depths)} must increase, each depth once")
    return depths


def map_speeds(cases: list[Case], workpiece: str | CuttingLaw | None = None,
               n: int = MAP_SPEEDS) -> tuple[float, ...]:
    """The default speeds of a map (rev/min): ``n`` speeds evenly spaced in 1/rpm from the
    lowest to the highest :func:`~boringbar.analysis.lobes.boring_speeds` of the cases'
    bars (their bores: the speeds a boring job runs), or, when a bar has no diameter,
    :func:`~boringbar.analysis.lobes.lobe_speeds` over lobes 1 to 3 (:data:`MAP_LOBES`)
    of the cases' first modes."""
    try:
        ranges = [boring_speeds(c.system, workpiece, n).rpm for c in cases]
    except ParameterError:  # a bar known by its modes alone has no bore
        f1 = [c.system.reference_frequency_rad_s / (2 * math.pi) for c in cases]
        per_lobe = max(1, round((n - 1) / (MAP_LOBES[1] - MAP_LOBES[0])))
        return lobe_speeds(f1, MAP_LOBES, per_lobe)
    if all(r == ranges[0] for r in ranges):
        return tuple(ranges[0])
    lo, hi = min(r[0] for r in ranges), max(r[-1] for r in ranges)
    return tuple(float(r) for r in np.unique(np.round(1.0 / np.linspace(1 / lo, 1 / hi, n))))


def host_limits(cases: list[Case], rpm, kr_pa: float) -> np.ndarray:
    """The analytic limit (m) of each case's linear host at each speed (case x rpm): the
    bar itself, or for a free ball the bar a small vibration sees (System.linear_host:
    the ball held by its friction, or without friction not acting)."""
    return np.array([limit_at_speeds(c.system.linear_host(), np.asarray(rpm, dtype=float),
                                     kr_pa) for c in cases])


def map_depths(limits_m: np.ndarray, n: int = DEPTHS,
               span: tuple[float, float] = DEPTH_SPAN) -> tuple[float, ...]:
    """The default depths (m): ``n`` evenly spaced from span[0] to span[1] times the
    smallest of the analytic limits ``limits_m`` (of :func:`host_limits`), rounded to
    0.1 um."""
    finite = limits_m[np.isfinite(limits_m) & (limits_m > 0)]
    if not finite.size:
        raise ParameterError("the cases' linear hosts have no analytic limit at these speeds "
                             "to place the default depths on: give depths_m")
    b = float(finite.min())
    return tuple(float(d) for d in np.round(np.linspace(span[0] * b, span[1] * b, n), 7))


def _check_integration(cases: list[Case], integration: Integration,
                       options: VerdictOptions) -> None:
    """The converged verdict advances each cut window by window with the RK4 scheme."""
    if integration.integrator == "exact":
        raise ParameterError("integrator = 'exact': the chatter map judges each cut by the "
                             "converged verdict, which advances it window by window with the "
                             "RK4 scheme; use integrator 'rk4' or 'auto'")
    if integration.initial is not None:
        raise ParameterError(f"initial = {integration.initial!r}: every cut of a chatter map "
                             "starts in progress and knocked, not from initial conditions")
    for c in cases:  # true stick-slip needs the stick law
        check_friction_law(c.system, "rk4", stick_law_of(c.system, options))


def resolved(cases: list[Case], options: ChatterMapOptions) -> tuple[ChatterMapOptions, dict]:
    """``options`` with their speeds and depths (the defaults where None), and where each
    came from in words."""
    source = {"rpm_source": "given", "depth_source": "given"}
    if options.rpm is None:
        options = replace(options, rpm=map_speeds(cases, options.workpiece))
        source["rpm_source"] = _speeds_text(cases, options.workpiece)
    if options.depths_m is None:
        limits = host_limits(cases, options.rpm, options.analytic_kr_pa)
        options = replace(options, depths_m=map_depths(limits))
        source["depth_source"] = (f"{DEPTHS} depths from {DEPTH_SPAN[0]:g} to "
                                  f"{DEPTH_SPAN[1]:g} x the smallest bare-bar limit")
    return options, source


def _speeds_text(cases: list[Case], workpiece) -> str:
    try:
        for c in cases:
            boring_speeds(c.system, workpiece, 2)
    except ParameterError:
        return f"lobes {MAP_LOBES[0]:g} to {MAP_LOBES[1]:g} of the first mode"
    name = workpiece.workpiece if isinstance(workpiece, CuttingLaw) else workpiece
    return f"boring speeds of a carbide insert ({name or 'default range'})"


def plan(cases, options: ChatterMapOptions, integration: Integration) -> Plan:
    """A point per (case, speed, depth) cell; the options with their speeds and depths
    resolved (:func:`resolved`) in the context, the linear hosts' analytic limits at the
    speeds in ``extra``."""
    cases = as_cases(cases, "cases")
    integration = integration.with_step(judged_step([c.system for c in cases]))
    _check_integration(cases, integration, options.verdict)
    options, source = resolved(cases, options)
    for r in options.rpm:
        check_delay(r, options.revolutions, integration.dt_s)
    limits = host_limits(cases, options.rpm, options.analytic_kr_pa)
    points = [(i, j, k) for i in range(len(cases)) for j in range(len(options.rpm))
              for k in range(len(options.depths_m))]
    context = {"cases": cases, "options": options, "integration": integration}
    return Plan(context, points, {"host_limit_m": limits, **source})


def compute(context: dict, point: tuple[int, int, int]) -> dict:
    """The verdict of one (case, speed, depth) cell (:func:`cell`)."""
    i, j, k = point
    o = context["options"]
    case = context["cases"][i]
    v = judge(case.system, o.forcing(o.depths_m[k], o.rpm[j]), o.verdict,
              dt_s=context["integration"].dt_s, values=True)
    return cell(v, o.verdict)


def _code(ok: bool | None) -> int:
    return UNDECIDED if ok is None else (STABLE if ok else CHATTER)


def cell(v: CutVerdict, options: VerdictOptions) -> dict:
    """A verdict as a cell of the map: onset and chatter-free codes, growth rate and the
    settled vibration of each start (:func:`starts`)."""
    onset = {ONSET_STABLE: STABLE, ONSET_CHATTER: CHATTER}.get(v.onset, UNDECIDED)
    return {"onset": onset, "growth_rate_per_s": v.growth_rate_per_s,
            "growth_rate_se_per_s": v.growth_rate_se, "onset_duration_s": v.onset_duration_s,
            "chatter_free": _code(v.chatter_free), "starts": starts(v, options)}


def starts(v: CutVerdict, options: VerdictOptions) -> list[dict]:
    """The settled vibration of each start (the small knock, then each large knock): where
    the verdict did not run the small knock on, its onset says what it does (module doc)."""
    n_own = len(v.settled) - len(options.knocks_m)
    own = v.settled[:n_own]
    if own:
        first = _start(own[0], options, v.onset_duration_s)
    elif v.onset == ONSET_STABLE:
        first = _start(Settled(0.0, 0.0, False, DIED_OUT, 0.0), options, v.onset_duration_s)
    else:  # a linear bar: a growing knock leaves the cut (CHATTER), or undecided
        left = v.onset == ONSET_CHATTER
        first = {"pp_m": math.nan, "rms_m": math.nan, "left_cut": left,
                 "status": LEFT_CUT if left else UNDECIDED_STATUS,
                 "duration_s": v.onset_duration_s, "chatter_free": CHATTER if left else UNDECIDED}
    return [first] + [_start(s, options, 0.0) for s in v.settled[n_own:]]


def _start(s: Settled, options: VerdictOptions, before_s: float) -> dict:
    ok = True if s.status == DIED_OUT else acceptable(s, options)
    return {"pp_m": s.pp_m, "rms_m": s.rms_m, "left_cut": s.left_cut, "status": s.status,
            "duration_s": before_s + s.duration_s, "chatter_free": _code(ok)}


# --- assembly -------------------------------------------------------------------------

CELL_ARRAYS = {"onset": np.int8, "growth_rate_per_s": float, "growth_rate_se_per_s": float,
               "onset_duration_s": float, "chatter_free": np.int8}
START_ARRAYS = {"pp_m": float, "rms_m": float, "left_cut": bool, "status": object,
                "duration_s": float, "chatter_free": np.int8}


def _arrays(plan: Plan, results: list[dict]) -> tuple[dict, dict]:
    """The cells' results as arrays over (case, rpm, depth) and (case, rpm, depth, start)."""
    o = plan.context["options"]
    shape = (len(plan.context["cases"]), len(o.rpm), len(o.depths_m))
    cells = {k: np.empty(shape, dtype=t) for k, t in CELL_ARRAYS.items()}
    per_start = {k: np.empty(shape + (len(o.starts),), dtype=t) for k, t in START_ARRAYS.items()}
    for point, res in zip(plan.points, results, strict=True):
        for k, a in cells.items():
            a[point] = res[k]
        for s, start in enumerate(res["starts"]):
            for k, a in per_start.items():
                a[point + (s,)] = start[k]
    return cells, per_start


def chatter_free_depth(codes: np.ndarray, depths: np.ndarray) -> tuple[float, float]:
    """(the largest depth such that every depth up to it is chatter-free, the first depth
    that is not: chatter or undecided) of one column of codes; (0, the shallowest) if
    the shallowest is not chatter-free, (the deepest, NaN) if every depth is."""
    bad = np.flatnonzero(codes != STABLE)
    if not bad.size:
        return float(depths[-1]), math.nan
    return (float(depths[bad[0] - 1]) if bad[0] else 0.0), float(depths[bad[0]])


def _column_depths(cells: dict, per_start: dict, depths: np.ndarray) -> dict:
    """Per (case, rpm): the chatter-free depth, the first depth that is not, the onset
    depth; per (case, rpm, start) the chatter-free depth from that start alone."""
    n_case, n_rpm, _, n_start = per_start["chatter_free"].shape
    free, first, onset = (np.full((n_case, n_rpm), np.nan) for _ in range(3))
    by_start = np.full((n_case, n_rpm, n_start), np.nan)
    grid = dict(enumerate(depths, start=1))
    for i in range(n_case):
        for j in range(n_rpm):
            free[i, j], first[i, j] = chatter_free_depth(cells["chatter_free"][i, j], depths)
            for s in range(n_start):
                by_start[i, j, s] = chatter_free_depth(per_start["chatter_free"][i, j, :, s],
                                                       depths)[0]
            done = {k + 1: {"onset": cells["onset"][i, j, k],
                            "growth_rate_per_s": cells["growth_rate_per_s"][i, j, k]}
                    for k in range(len(depths))}
            onset[i, j] = onset_depth(done, grid.__getitem__)
    return {"free": free, "first": first, "onset": onset, "by_start": by_start}


def _cell_variables(cells: dict, per_start: dict) -> dict:
    """The per-cell and per-start data variables."""
    dims, sdims = ("case", "rpm", "depth_m"), ("case", "rpm", "depth_m", "start")
    return {
        "onset": (dims, cells["onset"], {
            "long_name": "onset: a small knock dies out (1) or grows (0)", "codes": CODES}),
        "growth_rate_per_s": (dims, cells["growth_rate_per_s"], {
            "units": "1/s", "long_name": "growth rate of a small knock's amplitude"}),
        "growth_rate_se_per_s": (dims, cells["growth_rate_se_per_s"], {"units": "1/s"}),
        "onset_duration_s": (dims, cells["onset_duration_s"], {
            "units": "s", "long_name": "simulated time the onset's verdict took"}),
        "chatter_free": (dims, cells["chatter_free"], {
            "long_name": "chatter-free: from every start the settled vibration keeps the tool "
                         "in the cut and its tip peak-to-peak within the tolerance",
            "codes": CODES}),
        "settled_pp_m": (sdims, per_start["pp_m"], {
            "units": "m", "long_name": "settled tip peak-to-peak (0: the knock dies out; NaN: "
                                       "not run on, see settled_status)"}),
        "settled_rms_m": (sdims, per_start["rms_m"], {"units": "m"}),
        "settled_status": (sdims, per_start["status"].astype(str), {
            "long_name": "died out, settled, decaying (still falling: below the tolerance, or "
                         "a bar without a ball whose small knock dies out, the tool in the "
                         "cut), "
                         "left the cut (for a bar without a ball whose small knock grows: "
                         "linear until it leaves the cut, not run on), undecided"}),
        "left_cut": (sdims, per_start["left_cut"], {
            "long_name": "the tool leaves the cut in the settled vibration"}),
        "run_duration_s": (sdims, per_start["duration_s"], {
            "units": "s", "long_name": "simulated time of the start (the small knock's with "
                                       "its onset)"}),
        "chatter_free_by_start": (sdims, per_start["chatter_free"], {
            "long_name": "chatter-free from this start", "codes": CODES}),
    }


def _column_variables(d: dict, limits: np.ndarray) -> dict:
    cols = ("case", "rpm")
    return {
        "chatter_free_depth_m": (cols, d["free"], {
            "units": "m", "long_name": "the largest depth of the grid such that every depth "
                                       "up to it is chatter-free"}),
        "first_not_free_depth_m": (cols, d["first"], {
            "units": "m", "long_name": "the shallowest depth that is not chatter-free "
                                       "(chatter or undecided; NaN: none)"}),
        "chatter_free_depth_by_start_m": (("case", "rpm", "start"), d["by_start"], {
            "units": "m", "long_name": "the chatter-free depth from this start alone"}),
        "onset_depth_m": (cols, d["onset"], {
            "units": "m", "long_name": "onset: depth where a small knock's growth rate "
                                       "crosses zero (0: at or below the shallowest)"}),
        "host_analytic_limit_m": (cols, limits, {
            "units": "m", "long_name": "analytic limit of the linear host (for the free "
                                       "ball: held by its friction, or without it if none)"}),
        "min_chatter_free_depth_m": (("case",), np.nanmin(d["free"], axis=1), {
            "units": "m"}),
    }


def _curve(cases: list[Case], rpm: np.ndarray, kr_pa: float) -> tuple[np.ndarray, np.ndarray]:
    """(speeds, host limits over them): the linear hosts' lobes between the map's speeds,
    evenly spaced in 1/rpm."""
    fine = 1.0 / np.linspace(1.0 / rpm.max(), 1.0 / rpm.min(), max(200, 20 * len(rpm)))[::-1]
    return fine, host_limits(cases, fine, kr_pa)


def assemble(plan: Plan, results: list[dict], attrs: dict | None = None) -> xr.Dataset:
    """The chatter map's Dataset from the cells' results (in plan order); ``attrs`` go
    after the configuration's."""
    cases, o = plan.context["cases"], plan.context["options"]
    depths, rpm = np.asarray(o.depths_m), np.asarray(o.rpm, dtype=float)
    cells, per_start = _arrays(plan, results)
    limits = plan.extra["host_limit_m"]
    fine, curve = _curve(cases, rpm, o.analytic_kr_pa)
    ds = xr.Dataset(
        {**_cell_variables(cells, per_start),
         **_column_variables(_column_depths(cells, per_start, depths), limits),
         "host_analytic_curve_m": (("case", "fine_rpm"), curve, {"units": "m"})},
        coords={
            "case": [c.label for c in cases],
            "rpm": ("rpm", rpm, {"units": "rev/min"}),
            "depth_m": ("depth_m", depths, {"units": "m"}),
            "start": list(o.starts),
            "knock_m": ("start", np.array((o.verdict.knock_m,) + o.verdict.knocks_m), {
                "units": "m", "long_name": "tip amplitude of the start's knock"}),
            "bar": ("case", [c.bar for c in cases]),
            "gap_m": ("case", np.array([c.gap_m for c in cases]), {"units": "m"}),
            "friction": ("case", [c.friction for c in cases]),
            "fine_rpm": ("fine_rpm", fine, {"units": "rev/min"}),
        },
        attrs={**_attrs(plan, per_start), **(attrs or {})},
    )
    ds.attrs["method_text"] = method_text(ds)
    return ds


def _attrs(plan: Plan, per_start: dict) -> dict:
    """The configuration a chatter map carries."""
    cases, o, integ = (plan.context[k] for k in ("cases", "options", "integration"))
    law = o.law
    run = per_start["duration_s"]
    return {
        "title": "boringbar chatter amplitude map (converged verdict)",
        "boringbar_version": __version__,
        "criterion": "growth",
        "integrator_used": "rk4",
        "dt_s": integ.dt_s,
        **verdict_attrs(o.verdict, [c.system for c in cases]),
        "starts": json.dumps(list(o.starts)),
        "rpm_source": plan.extra["rpm_source"],
        "depth_source": plan.extra["depth_source"],
        "start": "in progress (static deflection), knocked",
        **({"kr_pa": o.kr_pa} if law.linear_law else
           {"workpiece": law.workpiece or "given", "kc11_pa": law.kc11_pa, "mc": law.mc,
            "radial_ratio": law.radial_ratio}),
        "cutting_law": law.describe(),
        "analytic_kr_pa": o.analytic_kr_pa,
        "feed_m": o.feed_m,
        "revolutions": o.revolutions,
        "delay_interpolation": o.interpolation,
        "cells": len(plan.points),
        "simulated_s": float(np.nansum(run)),
        "mean_run_s": float(np.nansum(run)) / max(1, len(plan.points)),
        "preset": ",".join(sorted({c.system.preset for c in cases})),
        "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
    }


def method_text(ds) -> str:
    """The method of a chatter map in one line: criterion, starts, tolerance, integrator,
    run length (its summary and figure name it)."""
    a = ds.attrs
    starts = json.loads(a["starts"])
    return (f"converged verdict (a {a['knock_m'] * 1e6:g} um knock's growth rate, "
            f"{a['confidence']:g}-certain; every start, {', '.join(starts)}, run until its tip "
            f"p-p settles to {a['settle_tolerance'] * 100:g} %); chatter-free: in the cut and "
            f"within {a['tolerance_m'] * 1e6:g} um p-p from every start; RK4, dt = "
            f"{a['dt_s']:g} s{step_text(a)}, at most {a['max_duration_s']:g} s a run "
            f"({a['mean_run_s']:.2g} s a cell on average)")


def summary(ds) -> dict:
    """JSON-able summary (what ``boringbar chatter-map --json`` prints): the method and
    its settings, and per case and speed the chatter-free, first not chatter-free and
    onset depths and the bare-bar limit."""
    a = ds.attrs
    cases = []
    for i, label in enumerate(ds["case"].values):
        cases.append({
            "case": str(label),
            "min_chatter_free_depth_m": _num(ds["min_chatter_free_depth_m"].values[i]),
            "speeds": [{"rpm": float(r),
                        **{k: _num(ds[k].values[i, j])
                           for k in ("chatter_free_depth_m", "first_not_free_depth_m",
                                     "onset_depth_m", "host_analytic_limit_m")}}
                       for j, r in enumerate(ds["rpm"].values)]})
    return {"method_text": a["method_text"], "criterion": a["criterion"],
            "integrator": a["integrator_used"], "dt_s": float(a["dt_s"]),
            "verdict": {k: a[k] for k in ("confidence", "max_duration_s", "knock_m",
                                          "tolerance_m", "settle_tolerance")},
            "knocks_m": json.loads(a["knocks_m"]), "starts": json.loads(a["starts"]),
            "n_cells": int(a["cells"]),
            "n_undecided": int((ds["chatter_free"].values == UNDECIDED).sum()),
            "mean_run_s": float(a["mean_run_s"]),
            "wall_time_s": float(a.get("wall_time_s", math.nan)),
            "depths_m": [float(d) for d in ds["depth_m"].values],
            "cases": cases}


def _num(v) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


def chatter_map(cases, options: ChatterMapOptions | None = None, *,
                integration: Integration | None = None, execution: Execution | None = None,
                progress=None) -> xr.Dataset:
    """The chatter amplitude map of every case over ``options.rpm`` x ``options.depths_m``
    (module doc; docs/chatter_map.md).

    ``cases``: the bars: a System, a sequence of them or a mapping of label to System
    (:func:`~boringbar.analysis.cases.as_cases`); ``options``:
    :class:`ChatterMapOptions` (default: the boring speeds of the bars and 20 depths
    around their bare-bar limit, a small and a 20 um knock, 10 um p-p tolerance);
    ``integration``: its ``dt_s`` is the RK4 step of every cut (None, the default: the
    verdict's, :func:`~boringbar.analysis.verdict.judged_step`; its duration is not used:
    each cut runs until its verdict, at most ``verdict.max_duration_s``; integrator "rk4"
    or "auto", no initial conditions); ``execution``: where the cells run (default a
    process per core, :data:`~boringbar.analysis.verdict.EXECUTOR`);
    ``progress(done, total)`` as cells finish.

    Returns an xarray Dataset: per (case, rpm, depth_m) the onset and chatter-free codes
    (1 yes, 0 no, 2 undecided) and the growth rate; per start as well the settled tip
    peak-to-peak and RMS, its status and whether the tool left the cut; per (case, rpm)
    the chatter-free depth, the first depth that is not, the onset depth and the linear
    host's analytic limit (with its curve over ``fine_rpm``); per case the minimum
    chatter-free depth.
    """
    options = options or ChatterMapOptions()
    integration = integration or Integration()
    p = plan(cases, options, integration)
    execution = (execution or Execution()).resolve(EXECUTOR)
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    return assemble(p, results, execution_attrs(execution, wall))
