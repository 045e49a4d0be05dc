"""Frequency sweeps of tip RMS and impact pattern (docs/model.md, section 6).

Every (case, force, ratio) run is independent; with the published RK4 scheme,
runs of the same bar kind and mode count go in lock-step batches
(:func:`~boringbar.simulate.simulate_batch`, the same results as single runs,
bit for bit), each batch one point of the plan (the contract:
:mod:`boringbar.analysis.base`), run on an executor (default: a thread per core;
the kernels release the GIL).  Each run streams its metrics, no trajectory is
kept.  The result is an xarray Dataset with the full configuration in its
attributes.
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from boringbar._validate import check_range, check_values
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.cases import Case, as_cases
from boringbar.execute import Execution
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System
from boringbar.reference.stability import linear_host, natural_frequencies
from boringbar.simulate import (
    Initial,
    Integration,
    batch_key,
    resolve_integrator,
    simulate,
    simulate_batch,
)
from boringbar.simulate.kernels import BMAX
from boringbar.simulate.run_limits import check_steady_ratios
from boringbar.version import __version__

#: Runs per lock-step batch of the RK4 kernel (benchmarks/bench_batch.py).
BATCH = 16
#: The published sweep's frequency ratios, 0.95 to 1.05 in steps of 0.01.
PUBLISHED_RATIOS = tuple(round(0.95 + 0.01 * i, 12) for i in range(11))
#: The default sweep's step in Omega/omega_n (the published one's).
RATIO_STEP = 0.01
#: How far (relative) the default window reaches beyond a tuned mass damper's two
#: coupled natural frequencies, so that both peaks are drawn with their flanks.
PEAK_MARGIN = 0.05
#: The numeric results of every run.
NAMES = ("rms_tip_m", "max_abs_tip_m", "max_abs_rel_disp_m", "impacts_per_cycle",
         "energy_balance_relative")


def tmd_window(system: System) -> tuple[float, float]:
    """(lowest, highest) Omega/omega_n of the default window of a bar with a tuned mass
    damper: its two lowest undamped natural frequencies with the absorber (mode 1
    split in two; the whole modal host, not Den Hartog's one-mode estimate) over
    omega_n, PEAK_MARGIN beyond each.  A damped absorber's two peaks lie between those
    two frequencies: they start there with no damping and move towards each other,
    to the locked frequency omega_n / sqrt(1 + mu) with infinite damping; as in any
    damped resonance a peak may also sit a little beyond its undamped frequency (at
    most 0.6 % at the steel example's mass ratio 0.18, 2.3 % at 0.88:
    tests/test_defaults.py), inside the margin."""
    w = natural_frequencies(*linear_host(system))[:2] / system.reference_frequency_rad_s
    return float(w[0]) * (1.0 - PEAK_MARGIN), float(w[1]) * (1.0 + PEAK_MARGIN)


def default_ratios(cases: list[Case]) -> tuple[float, ...]:
    """The default sweep's Omega/omega_n: the published window 0.95 to 1.05, widened
    to :func:`tmd_window` of every case with a tuned mass damper, in steps of
    RATIO_STEP on the published grid (multiples of 0.01)."""
    lo, hi = PUBLISHED_RATIOS[0], PUBLISHED_RATIOS[-1]
    for case in cases:
        if case.system.kind == "tmd":
            a, b = tmd_window(case.system)
            lo, hi = min(lo, a), max(hi, b)
    first = math.floor(lo / RATIO_STEP + 1e-9)
    last = math.ceil(hi / RATIO_STEP - 1e-9)
    return tuple(round(RATIO_STEP * i, 12) for i in range(max(first, 1), last + 1))


@dataclass(frozen=True)
class SweepOptions:
    """A frequency sweep's grid: ``ratios`` Omega/omega_n of each case's host bar (> 0;
    None, the default: :func:`default_ratios` of the cases, the published 0.95 to
    1.05 widened to show a tuned mass damper's two peaks), ``forces_n`` F0 (N, >= 0),
    and ``batch``: with the RK4 integrator, runs of the same bar kind and mode count
    advanced together in lock-step (up to 16; 1: one at a time; the results are the
    same, bit for bit)."""

    ratios: tuple[float, ...] | None = None
    forces_n: tuple[float, ...] = (10.0,)
    batch: int = BATCH

    def __post_init__(self):
        if self.ratios is not None:
            object.__setattr__(self, "ratios", check_values("ratios", self.ratios, 0.0,
                                                            math.inf, lo_open=True))
        object.__setattr__(self, "forces_n", check_values("forces_n", self.forces_n, 0.0,
                                                          math.inf, unit="N"))
        check_range("batch", self.batch, 1, BMAX)


def plan(cases: list[Case], options: SweepOptions, integration: Integration) -> Plan:
    """Every (case, force, ratio) run; a point is a lock-step batch of them (the runs
    whose integrator is RK4, ``options.batch`` > 1: runs of one bar kind, mode count
    and ball motion, :func:`~boringbar.simulate.batch_key`, in (case, force, ratio)
    order) or one run; the options in the context carry
    their ratios (:func:`default_ratios` of the cases if none were given)."""
    integration = integration.with_step()
    cases = as_cases(cases, "cases")
    if options.ratios is None:
        options = replace(options, ratios=default_ratios(cases))
    for case in cases:  # every run has a steady part of one forcing period at least
        check_steady_ratios(case.system, options.ratios, integration.duration_s,
                            integration.steady_fraction, "Integration.duration_s")
    shape = (len(cases), len(options.forces_n), len(options.ratios))
    jobs = [(i, j, k) for i in range(shape[0]) for j in range(shape[1]) for k in range(shape[2])]
    integrators = [resolve_integrator(integration.integrator, c.system) for c in cases]
    rk4 = [i == "rk4" and options.batch > 1 for i in integrators]
    groups: dict[tuple, list] = {}
    points = []
    for ijk in jobs:
        system = cases[ijk[0]].system
        if rk4[ijk[0]]:
            groups.setdefault(batch_key(system), []).append(ijk)
        else:
            points.append([ijk])
    points = [g[a:a + options.batch] for g in groups.values()
              for a in range(0, len(g), options.batch)] + points
    context = {"cases": cases, "options": options, "integration": integration,
               "integrators": integrators, "batched": rk4}
    return Plan(context, points, {"shape": shape})


def compute(context: dict, point: list) -> list[dict]:
    """The runs of one point (a batch, or one run): their metrics and patterns."""
    cases, o, integ = context["cases"], context["options"], context["integration"]
    runs = [(cases[i].system, Harmonic(o.forces_n[j], o.ratios[k]),
             cases[i].initial or integ.initial) for i, j, k in point]
    if context["batched"][point[0][0]]:
        results = simulate_batch(runs, duration_s=integ.duration_s, dt_s=integ.dt_s,
                                 steady_fraction=integ.steady_fraction,
                                 stick_law=integ.stick_law)
    else:
        kw = integ.kwargs()
        results = [simulate(system, forcing, **{**kw, "initial": initial})
                   for system, forcing, initial in runs]
    return [_point(run) for run in results]


def _point(run) -> dict:
    s = run.summary()
    return {
        "rms_tip_m": math.nan if s["rms_tip_m"] is None else s["rms_tip_m"],
        "max_abs_tip_m": math.nan if s["max_abs_tip_m"] is None else s["max_abs_tip_m"],
        "max_abs_rel_disp_m": s["max_abs_rel_disp_m"],
        "impacts_per_cycle": math.nan if s["impacts_per_cycle"] is None
        else s["impacts_per_cycle"],
        "pattern": s["pattern"] or "",
        "energy_balance_relative": s["energy"]["balance_relative"],
    }


def assemble(plan: Plan, results: list[list[dict]], attrs: dict | None = None):
    """The sweep Dataset, dims (case, force_n, ratio), from the points' results in plan
    order; ``attrs`` go after the configuration's."""
    ctx = plan.context
    cases, o, integ = ctx["cases"], ctx["options"], ctx["integration"]
    shape = plan.extra["shape"]
    out = {k: np.full(shape, np.nan) for k in NAMES}
    pattern = np.full(shape, "", dtype=object)
    for point, res in zip(plan.points, results, strict=True):
        for ijk, r in zip(point, res, strict=True):
            for k in NAMES:
                out[k][ijk] = r[k]
            pattern[ijk] = r["pattern"]
    units = {"rms_tip_m": "m", "max_abs_tip_m": "m", "max_abs_rel_disp_m": "m",
             "impacts_per_cycle": "1/period", "energy_balance_relative": "1"}
    dims = ("case", "force_n", "ratio")
    data = {k: (dims, v, {"units": units[k]}) for k, v in out.items()}
    data["pattern"] = (dims, pattern.astype(str))
    data["natural_frequency_hz"] = (("case",), np.array(
        [c.system.reference_frequency_rad_s / (2 * math.pi) for c in cases]), {"units": "Hz"})
    return xr.Dataset(
        data,
        coords={
            "case": [c.label for c in cases],
            "force_n": ("force_n", np.array(o.forces_n), {"units": "N"}),
            "ratio": ("ratio", np.array(o.ratios),
                      {"long_name": "Omega / omega_n of the host bar"}),
            "bar": ("case", [c.bar for c in cases]),
            "gap_m": ("case", np.array([c.gap_m for c in cases]), {"units": "m"}),
            "friction": ("case", [c.friction for c in cases]),
            "integrator": ("case", ctx["integrators"],
                           {"long_name": "the integrator of the case's runs"}),
        },
        attrs={
            "title": "boringbar frequency sweep",
            "boringbar_version": __version__,
            "preset": ",".join(sorted({c.system.preset for c in cases})),
            "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
            "integrator": integ.integrator,
            "dt_s": integ.dt_s,
            "duration_s": integ.duration_s,
            "steady_fraction": integ.steady_fraction,
            "initial": json.dumps((integ.initial or Initial()).__dict__),
            "batch": o.batch if any(ctx["batched"]) else 1,
            **(attrs or {}),
        },
    )


def sweep(cases: list[Case], options: SweepOptions | None = None, *,
          integration: Integration | None = None, execution: Execution | None = None,
          progress=None):
    """Tip RMS and impact pattern against Omega/omega_n for every case and force.

    ``cases``: the bars: a :class:`~boringbar.model.system.System`, a sequence of them
    or a mapping of label to System (:func:`as_cases`; :func:`published_cases` gives
    the published ones); ``options``: the grid (:class:`SweepOptions`; default 10 N over
    the published ratios 0.95-1.05, widened to both peaks of a tuned mass damper:
    :func:`default_ratios`); ``integration``: how each run is integrated
    (:class:`~boringbar.simulate.Integration`); ``execution``: where the points run
    (:class:`~boringbar.execute.Execution`; default a thread per core);
    ``progress(done, total)`` is called as points finish.

    Returns an xarray Dataset with dims (case, force_n, ratio): ``rms_tip_m``,
    ``max_abs_tip_m``, ``max_abs_rel_disp_m``, ``impacts_per_cycle``, ``pattern``,
    ``energy_balance_relative``; the configuration in its attributes.  The results
    are the same, bit for bit, whatever the batch size and the executor.
    """
    options = options or SweepOptions()
    integration = integration or Integration()
    p = plan(cases, options, integration)
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    return assemble(p, results, execution_attrs(execution, wall))


def summary(ds) -> dict:
    """JSON-able summary of a sweep (what ``boringbar sweep --json`` prints)."""
    cases = []
    for i, label in enumerate(ds["case"].values):
        for j, force in enumerate(ds["force_n"].values):
            cases.append({
                "case": str(label),
                "bar": str(ds["bar"].values[i]),
                "gap_m": None if np.isnan(ds["gap_m"].values[i]) else float(ds["gap_m"].values[i]),
                "friction": str(ds["friction"].values[i]),
                "integrator": (str(ds["integrator"].values[i]) if "integrator" in ds.coords
                               else ds.attrs.get("integrator")),  # files before "auto"
                "force_n": float(force),
                "natural_frequency_hz": float(ds["natural_frequency_hz"].values[i]),
                "ratio": [float(r) for r in ds["ratio"].values],
                "rms_tip_m": [float(v) for v in ds["rms_tip_m"].values[i, j]],
                "pattern": [str(v) for v in ds["pattern"].values[i, j]],
                "impacts_per_cycle": [None if np.isnan(v) else float(v)
                                      for v in ds["impacts_per_cycle"].values[i, j]],
            })
    return {"preset": ds.attrs.get("preset"), "integrator": ds.attrs.get("integrator"),
            "wall_time_s": ds.attrs.get("wall_time_s"), "cases": cases}
