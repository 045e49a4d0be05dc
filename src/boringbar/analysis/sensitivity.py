"""Sensitivity studies (MODEL.md section 6): one parameter varied, everything else fixed.

A thin layer over the existing machinery: each value of the parameter
becomes a :class:`~boringbar.analysis.sweep.Case` (built by
:func:`~boringbar.model.system.make_system`), and the harmonic runs are one
:func:`~boringbar.analysis.sweep.sweep` over all of them; cuts at a fixed
spindle speed are :func:`~boringbar.simulate.simulate` runs with
``Regenerative(depth, rpm, stop_at_zero=False)`` on a thread pool.

Parameters (``kind``) and their published values:

- ``"ball"``: "carbide", "steel";
- ``"friction_number"``: 0.2, 0.4, 0.6, 0.8 -- the published
  rolling-resistance number, read as the preset reads it (``physical``:
  mm, F_c = mu m g / r_m; ``paper``: the paper's reading, F_c = mu m g /
  0.0075 with r_m in m); friction is on for this kind;
- ``"restitution"``: 0.6, 0.7, 0.8;
- ``"initial"``: initial conditions (W0 (m), W0' (m/s)[, y0 (m), y0' (m/s)])
  or :class:`~boringbar.simulate.Initial`; the system is fixed.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from boringbar import __version__
from boringbar._validate import ParameterError, check_choice, check_positive, check_range
from boringbar.analysis.sweep import Case, sweep
from boringbar.model.forcing import Regenerative
from boringbar.model.system import make_system
from boringbar.simulate import Initial, simulate

KINDS = ("ball", "friction_number", "restitution", "initial")
PUBLISHED_VALUES = {
    "ball": ("carbide", "steel"),
    "friction_number": (0.2, 0.4, 0.6, 0.8),
    "restitution": (0.6, 0.7, 0.8),
    "initial": ((0.5e-3, 0.5), (1.0e-3, 1.0)),
}


@dataclass(frozen=True)
class Cuts:
    """Cuts at one spindle speed over a few depths of cut (published: 1200 rpm,
    0.05..0.10 mm).  ``rpm`` (rev/min), ``depths`` (m), ``duration`` (s) of each
    full-length run; ``options``: further :class:`~boringbar.model.forcing.Regenerative`
    fields (kr, feed, start, ...)."""

    rpm: float = 1200.0
    depths: tuple = tuple(round((5 + i) * 1e-5, 12) for i in range(6))
    duration: float = 2.0
    options: dict = field(default_factory=dict)

    def __post_init__(self):
        check_positive("cuts rpm", self.rpm)
        if not len(self.depths):
            raise ParameterError("cuts depths = () must hold at least one depth of cut")
        for d in self.depths:
            check_positive("cuts depth", d, "m")
        check_positive("cuts duration", self.duration, "s")


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
        return (f"W0={i.tip_displacement:g}m W0'={i.tip_velocity:g}m/s "
                f"y0={i.ball_position:g}m y0'={i.ball_velocity:g}m/s")
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
            system = make_system(bar, preset, gap=gap, friction=fr, **kw)
        else:
            system = make_system(bar, preset, **kw)
        label = "fixed system" if kind == "initial" else sensitivity_label(kind, v)
        cases.append(Case(label, system, bar, gap if bar == "ball" else math.nan,
                          ("on" if fr else "off") if bar == "ball" else "n/a"))
    return cases


def sensitivity(kind: str, values=None, *, preset: str = "physical", bar: str = "ball",
                gap: float = 0.5e-3, friction: bool = True, forces=(10.0,), ratios=(1.0,),
                cutting: Cuts | None = None, duration: float = 2.0, dt: float = 1e-6,
                workers: int | None = None, progress=None, integrator: str = "rk4",
                **overrides):
    """Vary one parameter (``kind``, see the module doc) over ``values`` (default:
    the published ones).

    Harmonic (``cutting`` None): the :func:`~boringbar.analysis.sweep.sweep`
    Dataset over ``forces`` (N) x ``ratios`` (Omega/omega_n) with a new leading
    dimension named ``kind`` holding the values (for "initial": their labels,
    with ``tip_displacement``, ``tip_velocity``, ``ball_position``,
    ``ball_velocity`` coordinates).  Cutting (a :class:`Cuts`): a Dataset over
    (``kind``, depth) with the chatter verdict (the force reached zero),
    bounded chatter, steady amplitude (m), first zero time (s) and peak force (N)
    of each full-length cut.  ``overrides`` go to
    :func:`~boringbar.model.system.make_system`; one result per value.  ``integrator``:
    "rk4" (published) or "exact" (see :func:`~boringbar.simulate.simulate`).
    """
    check_choice("kind", kind, KINDS)
    if kind != "initial" and bar != "ball":
        raise ParameterError(f"bar = {bar!r}: kind = {kind!r} varies the ball damper; "
                             "it needs bar = 'ball'")
    varied = {"ball": "ball", "friction_number": "friction_number",
              "restitution": "restitution"}.get(kind)
    if varied in overrides:
        raise ParameterError(f"{varied} = {overrides[varied]!r} cannot be fixed while "
                             f"kind = {kind!r} varies it")
    values = list(PUBLISHED_VALUES[kind] if values is None else values)
    if not values:
        raise ParameterError(f"values = {values!r} must hold at least one {kind}")
    if kind != "initial":
        cases = sensitivity_cases(kind, values, bar, preset, gap, friction, overrides)
        initials = [None] * len(values)
    else:
        initials = [sensitivity_initial(v) for v in values]
        cases = sensitivity_cases(kind, [None], bar, preset, gap, friction, overrides) * len(values)
    labels = [sensitivity_label(kind, v) for v in values]
    if len(set(labels)) != len(labels):
        raise ParameterError(f"values = {values!r} must be distinct")
    coord = labels if kind == "initial" else values
    if cutting is not None:
        ds = _cuts(cases, initials, cutting, dt, workers, integrator)
        ds = ds.assign_coords({kind: ("case", coord), "case": ("case", labels)})
    elif kind == "initial":
        import xarray as xr

        # sweep takes one initial condition: one sweep (over forces x ratios) each
        parts = [sweep(cases[:1], ratios, forces, duration=duration, dt=dt, workers=workers,
                       initial=ini, progress=progress, integrator=integrator)
                 for ini in initials]
        ds = xr.concat(parts, dim="case", data_vars="all", coords="different",
                       compat="equals", combine_attrs="override")
        ds = ds.assign_coords({kind: ("case", coord), "case": ("case", labels)})
        ds.attrs.pop("initial", None)
        for name in ("tip_displacement", "tip_velocity", "ball_position", "ball_velocity"):
            ds = ds.assign_coords({name: ("case", [getattr(i, name) for i in initials])})
    else:
        ds = sweep(cases, ratios, forces, duration=duration, dt=dt, workers=workers,
                   progress=progress, integrator=integrator)
        ds = ds.assign_coords({kind: ("case", coord)})
    ds = ds.swap_dims({"case": kind})
    if kind == "initial":
        ds = ds.drop_vars("case")  # the labels are the coordinate itself
    ds.attrs.update({"sensitivity": kind, "values": json.dumps([str(v) for v in values])})
    return ds


def sensitivity_cut(case: Case, initial: Initial | None, cuts: Cuts, depth: float, dt: float,
         integrator: str = "rk4") -> dict:
    forcing = Regenerative(depth, cuts.rpm, stop_at_zero=False, **cuts.options)
    c = simulate(case.system, forcing, duration=cuts.duration, dt=dt, initial=initial,
                 integrator=integrator).cutting
    return {"chatter": c["chatter"], "bounded_chatter": c["chatter"] or c["bounded_chatter"],
            "amplitude_m": c["amplitude_m"], "max_force_n": c["max_force_n"],
            "first_zero_time_s": math.nan if c["first_zero_time_s"] is None
            else c["first_zero_time_s"]}


def _cuts(cases, initials, cuts: Cuts, dt: float, workers: int | None,
          integrator: str = "rk4"):
    import xarray as xr

    workers = int(workers or os.cpu_count() or 1)
    check_range("workers", workers, 1, 4096)
    depths = np.asarray(cuts.depths, dtype=float)
    jobs = [(i, j) for i in range(len(cases)) for j in range(len(depths))]
    sensitivity_cut(cases[0], initials[0], Cuts(cuts.rpm, cuts.depths[:1], 50 * dt, cuts.options),
         depths[0], dt, integrator)  # validates and warms the JIT before fanning out
    tic = time.perf_counter()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(lambda ij: sensitivity_cut(cases[ij[0]], initials[ij[0]], cuts,
                                                depths[ij[1]], dt, integrator), jobs))
    wall = time.perf_counter() - tic
    shape = (len(cases), len(depths))
    units = {"amplitude_m": "m", "max_force_n": "N", "first_zero_time_s": "s"}
    data = {k: (("case", "depth"), np.array([r[k] for r in results]).reshape(shape),
                {"units": units[k]} if k in units else {})
            for k in results[0]}
    return xr.Dataset(
        data,
        coords={"depth": ("depth", depths, {"units": "m"})},
        attrs={"title": "boringbar sensitivity (cuts)", "boringbar_version": __version__,
               "integrator": integrator, "rpm": cuts.rpm, "dt_s": dt, "duration_s": cuts.duration,
               "workers": workers, "wall_time_s": wall,
               "forcing_options": json.dumps(cuts.options),
               "systems": json.dumps({c.label: c.system.to_dict() for c in cases})},
    )
