"""The chatter orbit map: each bar's branch of cut orbits from its Hopf point, in depth
at one speed or in speed at one depth (docs/continuation.md, "Chatter orbits").

:func:`cut_continuation` traces :func:`boringbar.orbits.cut_branch.trace` for one or more
systems and returns one Dataset: per case the branch's depth, speed, amplitude,
frequency, thinnest chip and stability (dims case, point) and its events (dims case,
event: kind, detail, depth, speed, amplitude, frequency).  :func:`cut_summary` is the
JSON.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.model.cutting import cutting_law
from boringbar.model.forcing import MAX_DEPTH, Regenerative
from boringbar.model.system import System
from boringbar.orbits.cut_branch import MAX_POINTS, CutBranch, nontrivial, trace
from boringbar.orbits.cut_orbits import STEPS, CutOrbitError
from boringbar.version import __version__

#: What every output says of how its branch was obtained.
METHOD = ("periodic orbits of the delay equation by a periodic discretisation "
          "(RK4, {steps} steps a period, cubic Hermite delays), pseudo-arclength {how} "
          "from the Hopf point, Floquet multipliers of the discretised map (ARPACK)")
#: A branch's parameter: the depth at the cut's speed, or the speed (rpm, continued as
#: the delay tau = 60 / rpm) at the cut's depth; what the method says of each.
PARAMETERS = {"depth": ("depth", "in depth"), "rpm": ("tau", "in speed at a fixed depth")}
#: The highest speed a speed range may reach (rpm).
MAX_RPM = 1e6


@dataclass(frozen=True)
class CutContinuationOptions:
    """``parameter``: what the branch is continued in (:data:`PARAMETERS`): "depth", at
    the cut's speed within ``depth_range_m`` (lo, hi; m), or "rpm", at the cut's depth
    within ``speed_range_rpm`` (lo, hi; rpm), from the Hopf point there nearest the cut's
    speed; ``lobe``: the Hopf point's lobe number j (None: the lowest lobes'); ``steps``:
    nodes a period; ``max_points``: a branch's budget."""

    depth_range_m: tuple[float, float] = (0.0, 1e-3)
    lobe: int | None = None
    steps: int = STEPS
    max_points: int = MAX_POINTS
    parameter: str = "depth"
    speed_range_rpm: tuple[float, float] | None = None

    def __post_init__(self):
        object.__setattr__(self, "depth_range_m", _pair(
            "depth_range_m", self.depth_range_m, 0.0, MAX_DEPTH, "m"))
        if self.parameter not in PARAMETERS:
            raise ParameterError(f"parameter = {self.parameter!r} must be one of "
                                 f"{', '.join(PARAMETERS)}")
        if self.parameter == "rpm" and self.speed_range_rpm is None:
            raise ParameterError("parameter 'rpm' needs speed_range_rpm = (lo, hi), the "
                                 "speeds the branch stays in (rev/min, > 0)")
        if self.speed_range_rpm is not None:
            pair = _pair("speed_range_rpm", self.speed_range_rpm, 0.0, MAX_RPM, "rev/min")
            check_range("speed_range_rpm low", pair[0], 0.0, MAX_RPM, lo_open=True,
                        unit="rev/min")
            object.__setattr__(self, "speed_range_rpm", pair)
        if self.lobe is not None:
            check_int("lobe", self.lobe, 0, 200)
        check_int("steps", self.steps, 40, 2000)
        check_int("max_points", self.max_points, 2, 10_000)



def _pair(name: str, value, lo: float, hi: float, unit: str) -> tuple[float, float]:
    """(low, high) with lo <= low < high <= hi."""
    try:
        a, b = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r} must be (lo, hi) in {unit}") from None
    check_range(f"{name} low", a, lo, hi, unit=unit)
    check_range(f"{name} high", b, a, hi, lo_open=True, unit=unit)
    return a, b


def cut_continuation(systems: System | dict[str, System], forcing: Regenerative,
                     options: CutContinuationOptions | None = None) -> xr.Dataset:
    """The chatter orbit branch of each of ``systems`` (a dict: name -> System; one System:
    named by its kind) at ``forcing``'s speed and law (its depth is ignored: the branch
    starts at the Hopf point); ``options``: :class:`CutContinuationOptions` (None: its
    defaults)."""
    if not isinstance(forcing, Regenerative):
        raise ParameterError(f"forcing = {forcing!r} must be a Regenerative cut")
    o = options or CutContinuationOptions()
    cases = {systems.kind: systems} if isinstance(systems, System) else dict(systems)
    start = time.perf_counter()
    branches = {name: _branch(s, forcing, o) for name, s in cases.items()}
    if not any(b.points for b in branches.values()):
        raise ParameterError("no branch to follow: " + "; ".join(
            f"{name}: {b.stop}" for name, b in branches.items()))
    return _assemble(cases, branches, forcing, o, time.perf_counter() - start)


def _branch(system: System, forcing: Regenerative, o: CutContinuationOptions) -> CutBranch:
    try:
        window = o.depth_range_m if o.parameter == "depth" else o.speed_range_rpm
        return trace(system, forcing, window, free=PARAMETERS[o.parameter][0], lobe=o.lobe,
                     steps=o.steps, max_points=o.max_points)
    except CutOrbitError as err:
        return CutBranch(lobe=-1 if o.lobe is None else o.lobe, stop=f"no branch: {err}")


def _assemble(cases: dict, branches: dict, forcing: Regenerative, o: CutContinuationOptions,
              wall: float) -> xr.Dataset:
    names = list(cases)
    n_pt = max([len(b.points) for b in branches.values()] + [1])
    n_ev = max([len(b.events) for b in branches.values()] + [1])

    def pad(values, n, fill=math.nan):
        return list(values) + [fill] * (n - len(values))

    pts = {k: [] for k in ("depth_m", "rpm", "amplitude_m", "frequency_hz", "min_chip_m",
                           "largest_multiplier", "stable")}
    evs = {k: [] for k in ("event_kind", "event_detail", "event_depth_m", "event_rpm",
                           "event_amplitude_m", "event_frequency_hz")}
    for name in names:
        b = branches[name]
        pts["depth_m"].append(pad([p.orbit.depth for p in b.points], n_pt))
        pts["rpm"].append(pad([p.orbit.rpm for p in b.points], n_pt))
        pts["amplitude_m"].append(pad([p.amplitude for p in b.points], n_pt))
        pts["frequency_hz"].append(pad([1.0 / p.orbit.period for p in b.points], n_pt))
        pts["min_chip_m"].append(pad([p.min_chip for p in b.points], n_pt))
        pts["largest_multiplier"].append(pad(
            [float(np.max(np.abs(nontrivial(p.multipliers)))) for p in b.points], n_pt))
        pts["stable"].append(pad([p.unstable == 0 for p in b.points], n_pt, False))
        evs["event_kind"].append(pad([e.kind for e in b.events], n_ev, ""))
        evs["event_detail"].append(pad([e.detail for e in b.events], n_ev, ""))
        evs["event_depth_m"].append(pad([float(e.depth) for e in b.events], n_ev))
        evs["event_rpm"].append(pad([float(e.rpm) for e in b.events], n_ev))
        evs["event_amplitude_m"].append(pad([float(e.amplitude) for e in b.events], n_ev))
        evs["event_frequency_hz"].append(pad([float(e.frequency_hz) for e in b.events], n_ev))
    data = {k: (("case", "point"), v) for k, v in pts.items()}
    data.update({k: (("case", "event"), v) for k, v in evs.items()})
    data["kind"] = (("case",), [cases[n].kind for n in names])
    config = {"forcing": {"rpm": forcing.rpm, "feed_m": forcing.feed_m,
                          "revolutions": forcing.revolutions,
                          "law": cutting_law(forcing.kr_pa, forcing.workpiece).to_dict()},
              "options": asdict(o), "systems": {n: s.to_dict() for n, s in cases.items()}}
    return xr.Dataset(data, coords={"case": names}, attrs={
        "boringbar_version": __version__, "parameter": o.parameter,
        "rpm": float(forcing.rpm), "depth_m": float(forcing.depth_m),
        "preset": ",".join(sorted({s.preset for s in cases.values()})),
        "method": METHOD.format(steps=o.steps, how=PARAMETERS[o.parameter][1]),
        "wall_time_s": wall,
        "stop_reasons": json.dumps([branches[n].stop for n in names]),
        "config": json.dumps(config)})




def cut_summary(ds: xr.Dataset) -> dict:
    """The JSON of the map: what it was continued in (``parameter``: depth or rpm, with
    the cut's speed or depth), per case its events (depth and amplitude in mm, speed in
    rpm), points and stop; the method; the wall time."""
    stops = json.loads(ds.attrs["stop_reasons"])
    cases = []
    for i, name in enumerate(ds["case"].values):
        d = ds.isel(case=i)
        keep = np.isfinite(d["depth_m"].values)
        events = [{"kind": str(k), "detail": str(t), "depth_mm": float(b) * 1e3,
                   "rpm": float(r), "amplitude_mm": float(a) * 1e3, "frequency_hz": float(f)}
                  for k, t, b, r, a, f in zip(
                      d["event_kind"].values, d["event_detail"].values,
                      d["event_depth_m"].values, d["event_rpm"].values,
                      d["event_amplitude_m"].values, d["event_frequency_hz"].values,
                      strict=True)
                  if str(k)]
        cases.append({"case": str(name), "kind": str(d["kind"].values), "events": events,
                      "points": int(keep.sum()), "stop": stops[i],
                      "depth_mm": (d["depth_m"].values[keep] * 1e3).tolist(),
                      "rpm": d["rpm"].values[keep].tolist(),
                      "amplitude_mm": (d["amplitude_m"].values[keep] * 1e3).tolist(),
                      "stable": d["stable"].values[keep].astype(bool).tolist()})
    held = ({"rpm": float(ds.attrs["rpm"])} if ds.attrs["parameter"] == "depth"
            else {"depth_mm": float(ds.attrs["depth_m"]) * 1e3})
    return {"parameter": ds.attrs["parameter"], **held, "method": ds.attrs["method"],
            "cases": cases, "wall_time_s": float(ds.attrs["wall_time_s"])}
