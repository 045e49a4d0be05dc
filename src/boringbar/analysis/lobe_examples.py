"""Example cuts of a lobes study: a stable and an unstable grid point of its first case
rerun with history, not stopped at the first zero of the force, for the report's and
the command's figures of what a cut near the limit does."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from boringbar.analysis.cases import Case
from boringbar.analysis.lobes import LobesOptions
from boringbar.simulate import Integration, simulate

#: History rows of an example rerun (about; every n-th step is kept).
EXAMPLE_ROWS = 20000


def example_points(ds) -> list[tuple[str, float, float]]:
    """(name, rpm, depth) of a stable and an unstable grid point of the first case:
    the limiting and the first unstable depth at the speed of the minimum
    chatter-free depth (the stable one at the speed of the largest limit if the
    minimum is 0; only a stable one if nothing chattered)."""
    rpm = ds["rpm"].values
    limit = ds["limit_depth_m"].values[0]
    first = ds["first_unstable_depth_m"].values[0]
    if not np.isfinite(limit).any():  # no chatter up to the deepest cut tried
        run = ds["verdict"].values[0] >= 0
        j = len(rpm) // 2
        return [("stable", float(rpm[j]), float(ds["depth_m"].values[run[j]].max()))]
    j = int(np.nanargmin(limit))
    points = [("unstable", float(rpm[j]), float(first[j]))]
    if limit[j] <= 0:
        j = int(np.nanargmax(limit))
    if limit[j] > 0:
        points.insert(0, ("stable", float(rpm[j]), float(limit[j])))
    return points


def _example_run(case: Case, rpm: float, depth: float, options: LobesOptions,
                 integration: Integration, rows: int):
    """One grid point rerun with history (no stop at the first zero) as a Dataset."""
    n_steps = int(round(integration.duration_s / integration.dt_s))
    run = simulate(case.system, options.forcing(depth, rpm, stop_at_zero=False),
                   duration_s=integration.duration_s, dt_s=integration.dt_s,
                   record_every=max(1, n_steps // rows), integrator=integration.integrator,
                   steady_fraction=integration.steady_fraction, stick_law=integration.stick_law)
    h = run.to_xarray()
    h = h.drop_vars([v for v in ("impact_time_s", "impact_wall") if v in h])
    c = run.cutting
    return h.assign_coords(rpm=rpm, depth_m=depth, chatter=bool(c["chatter"]),
                           bounded_chatter=bool(c["bounded_chatter"]),
                           first_zero_time_s=math.nan if c["first_zero_time_s"] is None
                           else float(c["first_zero_time_s"]),
                           mean_force_n=float(run.forcing.mean_force_n),
                           static_deflection_m=float(c["static_deflection_m"]))


def examples(ds, case: Case, options: LobesOptions | None = None, *,
             integration: Integration | None = None, rows: int = EXAMPLE_ROWS):
    """The :func:`example_points` of the lobes Dataset ``ds`` (of ``case``, its first
    case, cut as ``options`` and ``integration`` say: those of the lobes) rerun with
    history of about ``rows`` rows, not stopped at the first zero of the force:
    one Dataset with dims (example, time_s)."""
    options = options or LobesOptions()
    integration = (integration or Integration()).with_step()
    points = example_points(ds)
    parts = [_example_run(case, rpm, depth, options, integration, rows)
             for _, rpm, depth in points]
    exds = xr.concat(parts, dim=pd.Index([p[0] for p in points], name="example"),
                     coords="all", join="outer", combine_attrs="drop")
    exds["rpm"].attrs["units"] = "rev/min"
    for name in ("depth_m", "static_deflection_m"):
        exds[name].attrs["units"] = "m"
    exds["first_zero_time_s"].attrs["units"] = "s"
    exds["mean_force_n"].attrs.update(units="N", long_name="the cutting law at the feed, F(h_m)")
    exds.attrs = {"title": "boringbar lobe examples: grid points rerun with history",
                  "case": str(case.label), "bar": case.bar, "gap_m": case.gap_m,
                  "friction": case.friction, "preset": case.system.preset,
                  "criterion": ds.attrs["criterion"],
                  "boringbar_version": ds.attrs["boringbar_version"],
                  "configs": "[" + ", ".join(p.attrs["config"] for p in parts) + "]",
                  "summaries": "[" + ", ".join(p.attrs["summary"] for p in parts) + "]"}
    return exds


def examples_summary(exds) -> list[dict]:
    """JSON-able list of the examples of :func:`examples`."""
    return [{"example": str(e), "case": exds.attrs["case"],
             "rpm": float(exds["rpm"].values[k]),
             "depth_m": float(exds["depth_m"].values[k]),
             "chatter": bool(exds["chatter"].values[k]),
             "bounded_chatter": bool(exds["bounded_chatter"].values[k]),
             "first_zero_time_s": float(exds["first_zero_time_s"].values[k])}
            for k, e in enumerate(exds["example"].values)]
