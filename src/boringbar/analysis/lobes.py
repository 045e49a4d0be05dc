"""Stability lobes by time-domain simulation (docs/model.md, sections 4 and 6).

Every grid point (spindle speed x depth of cut) is a regenerative-cutting run
of the kernel.  Two ways to find, at each speed, the depth where chatter
starts:

- ``scan`` (published): depths step, 2 step, 3 step ... until ``successive``
  (3) depths in a row chatter.  The first unstable depth and the limiting
  (chatter-free) depth, the last stable depth below it, are reported.
- ``search`` (faster): from a seed depth, steps of 1, 2, 4 ... grid depths
  up (or down) until a bracket [stable, chatter] is found, then bisection on
  the depth grid, then the ``successive - 1`` depths above the first
  unstable one are run to confirm the published rule; if one of them is
  stable (non-monotone stability) the search continues as a scan from there.
  The seed is the analytic (frequency-domain) limit of the linear host at
  that speed: the solid, TMD or locked-ball bar itself, and for the free
  ball the bare cavity bar (at the onset of chatter the vibration is far
  smaller than the gap, so the ball does not yet touch a wall).  A finite
  run can only place the simulated limit at or above the analytic one, so
  the seed sits just below the answer and few stable (full-length) runs
  are needed.
  It assumes that everything below the bracket it found is stable; where
  stability is not monotone in depth (a ball damper may chatter in a band
  and be stable above it) the scan can find a lower first unstable depth.
  :func:`compare_methods` lists where the two differ.

Each (case, speed) column is one task; tasks run on a thread pool (the kernel
releases the GIL).  Every verdict of every grid point that was run is kept.

Verdicts: the published criterion (the cutting force reaches zero: the tool
leaves the cut) and, beside it, bounded chatter (the steady vibration
amplitude exceeds ``bounded_fraction`` of the feed h_m, or the force reached
zero).  Lobe runs stop at the first zero of the force, so a chattering run
costs only the time to its first zero.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor, as_completed

import numpy as np
import xarray as xr

from boringbar import __version__
from boringbar._validate import (
    ParameterError,
    check_choice,
    check_int,
    check_positive,
    check_range,
)
from boringbar.analysis.sweep import Case
from boringbar.model.forcing import KR_ALUMINIUM, Regenerative
from boringbar.model.system import System
from boringbar.reference.stability import limit_at_speeds
from boringbar.simulate import INTEGRATORS, check_delay, simulate

PUBLISHED_RPM = np.arange(900.0, 1600.0 + 1e-9, 50.0)
PUBLISHED_DEPTH_STEP = 0.01e-3
#: Most depths on one speed's grid, max_depth / depth_step (published: 300); each
#: (case, speed, depth) holds a few numbers in the Dataset.
MAX_DEPTHS = 100_000
METHODS = ("scan", "search")
CRITERIA = ("zero", "bounded")
#: codes of the verdict arrays
NOT_RUN, CHATTER, STABLE = -1, 0, 1


def lobe_cut(case: Case, rpm: float, depth: float, opts: dict) -> dict:
    """One cut, stopped at the first zero of the force."""
    forcing = Regenerative(depth=depth, rpm=rpm, kr=opts["kr"], feed=opts["feed"],
                           revolutions=opts["revolutions"], interpolation=opts["interpolation"],
                           start=opts["start"], stop_at_zero=True,
                           bounded_fraction=opts["bounded_fraction"])
    run = simulate(case.system, forcing, duration=opts["duration"], dt=opts["dt"],
                   integrator=opts.get("integrator", "rk4"))
    c = run.cutting
    ball = case.system.kind == "ball"
    return {"zero": c["chatter"], "bounded": c["chatter"] or c["bounded_chatter"],
            "amplitude": c["amplitude_m"],
            "impacts": run.metrics["impacts_total"] if ball else -1,
            "max_rel_disp": run.metrics["max_abs_aux_all_m"] if ball else math.nan,
            "first_zero": math.nan if c["first_zero_time_s"] is None
            else c["first_zero_time_s"]}


def lobe_column(case: Case, rpm: float, opts: dict) -> dict:
    """All the runs at one speed, by the chosen method; returns {index: result}."""
    step, n_max = opts["depth_step"], opts["max_index"]
    key, need = opts["criterion"], opts["successive"]
    done: dict[int, dict] = {}

    def chatter(i: int) -> bool:
        if i not in done:
            done[i] = lobe_cut(case, rpm, i * step, opts)
        return done[i][key]

    def scan_from(i: int) -> None:
        run_of = 0
        while i <= n_max and run_of < need:
            run_of = run_of + 1 if chatter(i) else 0
            i += 1

    if opts["method"] == "scan":
        scan_from(1)
        return done
    # bracket [lo stable, hi chatter], growing away from the seed in doubling steps
    seed = min(max(1, opts["seeds"].get((case.label, rpm), 1)), n_max)
    if chatter(seed):
        lo, hi = seed, seed
        width = 1
        while lo > 0 and chatter(lo):
            hi, lo = lo, max(0, lo - width)
            width *= 2
    else:
        lo, hi = seed, seed + 1
        width = 1
        while hi <= n_max and not chatter(hi):
            lo, hi = hi, min(hi + width, n_max) if hi < n_max else n_max + 1
            width *= 2
        if hi > n_max:
            return done
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if chatter(mid):
            hi = mid
        else:
            lo = mid
    for i in range(hi + 1, min(hi + need, n_max + 1)):
        if not chatter(i):
            scan_from(i + 1)
            break
    return done


def _seeds(cases: list[Case], rpm: np.ndarray, kr: float, step: float) -> dict:
    """Grid index of the analytic limit of each case's linear host at each speed."""

    seeds = {}
    for case in cases:
        lim = limit_at_speeds(_linear_host(case.system), rpm, kr)
        for r, b in zip(rpm, lim, strict=True):
            if math.isfinite(b):
                seeds[(case.label, float(r))] = int(math.floor(b / step + 1e-9))
    return seeds


def _linear_host(system):
    """The linear bar a cut sees at the onset of chatter: for the free ball the
    bare cavity bar (the ball is not touching yet), else the system itself."""

    if system.kind == "ball":
        return System(system.bar, None, system.preset, system.readings)
    return system


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


def lobes(cases: list[Case], rpm=PUBLISHED_RPM, *, method: str = "scan",
          depth_step: float = PUBLISHED_DEPTH_STEP, max_depth: float = 3e-3,
          successive: int = 3, criterion: str = "zero", kr: float = KR_ALUMINIUM,
          feed: float = 0.1e-3, revolutions: int = 3, interpolation: str = "cubic",
          start: str = "rest", bounded_fraction: float = 0.1, duration: float = 2.0,
          dt: float = 1e-6, workers: int | None = None, analytic: bool = True,
          progress=None, integrator: str = "rk4"):
    """Stability lobes of every case over ``rpm`` by time-domain simulation.

    Returns an xarray Dataset: per (case, rpm, depth) the verdict of every grid
    point that was run under both criteria (1 stable, 0 chatter, -1 not run),
    the steady amplitude and the time of the first zero of the force; per
    (case, rpm) the limiting (chatter-free) depth and the first unstable depth
    under the chosen ``criterion``; per case the minimum chatter-free depth;
    and, for the linear bars (solid, TMD, locked ball), the analytic limit.
    ``integrator``: "rk4" (published) or "exact" (see ``simulate``: the delayed surface
    from a history of step H = tau / ceil(tau / dt), the first zero of the force located).
    """
    if not cases:
        raise ParameterError("lobes needs at least one case")
    rpm = np.atleast_1d(np.asarray(rpm, dtype=float))
    workers = int(workers or os.cpu_count() or 1)
    opts = lobe_options(cases, rpm, method=method, depth_step=depth_step, max_depth=max_depth,
                    successive=successive, criterion=criterion, kr=kr, feed=feed,
                    revolutions=revolutions, interpolation=interpolation, start=start,
                    bounded_fraction=bounded_fraction, duration=duration, dt=dt,
                    integrator=integrator)
    for nm in sorted({c.system.bar.n_modes for c in cases}):  # warm the JIT once
        c0 = next(c for c in cases if c.system.bar.n_modes == nm)
        lobe_cut(c0, float(rpm[0]), depth_step, dict(opts, duration=2e-4))

    tic = time.perf_counter()
    columns: dict[tuple[int, int], dict] = {}
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futs = {pool.submit(lobe_column, case, float(r), opts): (i, j)
                for i, case in enumerate(cases) for j, r in enumerate(rpm)}
        for n_done, fut in enumerate(as_completed(futs), 1):
            columns[futs[fut]] = fut.result()
            if progress is not None:
                progress(n_done, len(futs))
    wall = time.perf_counter() - tic
    return lobes_dataset(cases, rpm, columns, opts, analytic,
                    {"workers": workers, "wall_time_s": wall})


def lobe_options(cases: list[Case], rpm: np.ndarray, *, method: str, depth_step: float,
             max_depth: float, successive: int, criterion: str, kr: float, feed: float,
             revolutions: int, interpolation: str, start: str, bounded_fraction: float,
             duration: float, dt: float, integrator: str = "rk4") -> dict:
    """Check the lobe options (before any work) and pack what :func:`lobe_column` needs,
    the search's seeds included."""
    check_choice("method", method, METHODS)
    check_choice("criterion", criterion, CRITERIA)
    check_positive("depth_step", depth_step, "m")
    check_range("max_depth", max_depth, depth_step, 1.0, unit="m")
    check_int("successive", successive, 1, 100)
    check_choice("integrator", integrator, INTEGRATORS)
    for r in rpm:
        check_positive("rpm", r)
    n_max = int(math.floor(max_depth / depth_step + 1e-9))
    if n_max > MAX_DEPTHS:
        raise ParameterError(f"depth_step = {depth_step:g} m gives {n_max} depths up to "
                             f"max_depth = {max_depth:g} m; the allowed maximum is "
                             f"{MAX_DEPTHS} depths")
    opts = {"kr": kr, "feed": feed, "revolutions": revolutions, "interpolation": interpolation,
            "start": start, "bounded_fraction": bounded_fraction, "duration": duration,
            "dt": dt, "depth_step": depth_step, "max_index": n_max, "criterion": criterion,
            "successive": int(successive), "method": method, "integrator": integrator}
    # validate the cut description once, before any work
    Regenerative(depth=depth_step, rpm=float(rpm[0]), kr=kr, feed=feed,
                 revolutions=revolutions, interpolation=interpolation, start=start,
                 bounded_fraction=bounded_fraction)
    for r in rpm:
        check_delay(r, revolutions, dt)
    opts["seeds"] = _seeds(cases, rpm, kr, depth_step) if method == "search" else {}
    return opts


def lobes_dataset(cases: list[Case], rpm: np.ndarray, columns: dict, opts: dict, analytic: bool,
             attrs: dict):
    """The lobes Dataset from the columns ((case index, rpm index) -> {depth index:
    result} of :func:`lobe_column`); ``attrs`` go after the configuration's."""

    depth_step, criterion = opts["depth_step"], opts["criterion"]
    bounded_fraction, interpolation = opts["bounded_fraction"], opts["interpolation"]
    top = max((max(d) for d in columns.values() if d), default=1)
    depths = depth_step * np.arange(1, top + 1)
    shape = (len(cases), len(rpm), top)
    v_zero = np.full(shape, NOT_RUN, dtype=np.int8)
    v_bounded = np.full(shape, NOT_RUN, dtype=np.int8)
    amplitude = np.full(shape, np.nan)
    first_zero = np.full(shape, np.nan)
    impacts = np.full(shape, -1, dtype=np.int64)
    max_rel = np.full(shape, np.nan)
    n_runs = 0
    for (i, j), done in columns.items():
        for k, res in done.items():
            v_zero[i, j, k - 1] = CHATTER if res["zero"] else STABLE
            v_bounded[i, j, k - 1] = CHATTER if res["bounded"] else STABLE
            amplitude[i, j, k - 1] = res["amplitude"]
            first_zero[i, j, k - 1] = res["first_zero"]
            impacts[i, j, k - 1] = res["impacts"]
            max_rel[i, j, k - 1] = res["max_rel_disp"]
            n_runs += 1
    chosen = v_zero if criterion == "zero" else v_bounded
    limit = np.full(shape[:2], np.nan)
    first_unstable = np.full(shape[:2], np.nan)
    for i in range(shape[0]):
        for j in range(shape[1]):
            limit[i, j], first_unstable[i, j] = _limits(chosen[i, j], depths)
    ds = xr.Dataset(
        {
            "verdict": (("case", "rpm", "depth"), v_zero,
                        {"long_name": "published criterion: force reaches zero",
                         "codes": "1 stable, 0 chatter, -1 not run"}),
            "verdict_bounded": (("case", "rpm", "depth"), v_bounded,
                                {"long_name": f"bounded chatter: amplitude > "
                                 f"{bounded_fraction:g} h_m, or force reaches zero",
                                 "codes": "1 stable, 0 chatter, -1 not run"}),
            "amplitude": (("case", "rpm", "depth"), amplitude, {"units": "m"}),
            "first_zero_time": (("case", "rpm", "depth"), first_zero, {"units": "s"}),
            "impacts": (("case", "rpm", "depth"), impacts, {
                "long_name": "counted ball impacts over the run (-1: no ball or not run)"}),
            "max_rel_disp": (("case", "rpm", "depth"), max_rel, {
                "units": "m", "long_name": "largest |y|, the ball's excursion from the "
                                           "cavity centre, over the run (ball cases)"}),
            "limit_depth": (("case", "rpm"), limit, {"units": "m",
                            "long_name": "limiting (chatter-free) depth of cut"}),
            "first_unstable_depth": (("case", "rpm"), first_unstable, {"units": "m"}),
            "min_chatter_free_depth": (("case",), np.nanmin(np.where(
                np.isnan(limit), np.inf, limit), axis=1), {"units": "m"}),
        },
        coords={
            "case": [c.label for c in cases],
            "rpm": ("rpm", rpm, {"units": "rev/min"}),
            "depth": ("depth", depths, {"units": "m"}),
            "bar": ("case", [c.bar for c in cases]),
            "gap": ("case", np.array([c.gap for c in cases]), {"units": "m"}),
            "friction": ("case", [c.friction for c in cases]),
        },
        attrs={
            "title": "boringbar stability lobes (time domain)",
            "boringbar_version": __version__,
            "method": opts["method"],
            "criterion": criterion,
            "successive": opts["successive"],
            "integrator": opts.get("integrator", "rk4"),
            "delay_interpolation": interpolation,
            "start": opts["start"],
            "kr_pa": opts["kr"],
            "feed_m": opts["feed"],
            "revolutions": opts["revolutions"],
            "duration_s": opts["duration"],
            "dt_s": opts["dt"],
            "runs": n_runs,
            "preset": ",".join(sorted({c.system.preset for c in cases})),
            "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
            **attrs,
        },
    )
    if analytic:
        _add_analytic(ds, cases, rpm, opts["kr"])
    return ds


def _add_analytic(ds, cases: list[Case], rpm: np.ndarray, kr: float) -> None:
    """The frequency-domain limit of the linear bars (NaN for the free ball), and of
    every case's linear host (the bare cavity bar for the free ball, which is the
    bar the cut sees while the ball does not touch a wall)."""

    fine = np.linspace(rpm.min(), rpm.max(), max(200, 20 * len(rpm)))
    on_grid = np.full((len(cases), len(rpm)), np.nan)
    curve = np.full((len(cases), len(fine)), np.nan)
    host_grid = np.full((len(cases), len(rpm)), np.nan)
    for i, case in enumerate(cases):
        host_grid[i] = limit_at_speeds(_linear_host(case.system), rpm, kr)
        if case.system.kind in ("solid", "tmd", "locked"):
            on_grid[i] = host_grid[i]
            curve[i] = limit_at_speeds(case.system, fine, kr)
    ds["analytic_limit"] = (("case", "rpm"), on_grid, {"units": "m"})
    ds["host_analytic_limit"] = (("case", "rpm"), host_grid, {
        "units": "m", "long_name": "analytic limit of the linear host (bare cavity bar for "
                                   "the free ball)"})
    ds.coords["rpm_fine"] = ("rpm_fine", fine, {"units": "rev/min"})
    ds["analytic_curve"] = (("case", "rpm_fine"), curve, {"units": "m"})


def lobes_summary(ds) -> dict:
    """JSON-able summary (what ``boringbar lobes --json`` prints)."""
    out = []
    for i, label in enumerate(ds["case"].values):
        out.append({
            "case": str(label),
            "min_chatter_free_depth_m": _num(ds["min_chatter_free_depth"].values[i]),
            "speeds": [{"rpm": float(r),
                        "limit_depth_m": _num(ds["limit_depth"].values[i, j]),
                        "first_unstable_depth_m": _num(ds["first_unstable_depth"].values[i, j]),
                        **({"analytic_limit_m": _num(ds["analytic_limit"].values[i, j]),
                            "host_analytic_limit_m":
                                _num(ds["host_analytic_limit"].values[i, j])}
                           if "analytic_limit" in ds else {})}
                       for j, r in enumerate(ds["rpm"].values)],
        })
    return {"method": ds.attrs["method"], "criterion": ds.attrs["criterion"],
            "runs": int(ds.attrs["runs"]), "wall_time_s": float(ds.attrs["wall_time_s"]),
            "min_chatter_free_depth_m": _num(np.nanmin(ds["min_chatter_free_depth"].values)),
            "cases": out}


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
            a = float(scan["limit_depth"].values[i, j])
            b = float(search["limit_depth"].values[i, j])
            if not (a == b or (math.isnan(a) and math.isnan(b))):
                v = scan["verdict"].values[i, j]
                d = scan["depth"].values
                lower = [float(d[k]) for k in range(len(d))
                         if v[k] == CHATTER and (math.isnan(b) or d[k] <= b)]
                diffs.append({"case": str(label), "rpm": float(r), "scan_limit_m": a,
                              "search_limit_m": b, "scan_unstable_below_search_m": lower})
    return diffs
