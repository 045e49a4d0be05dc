"""Frequency sweeps of tip RMS and impact pattern (MODEL.md section 6).

Every (case, force, ratio) point is an independent run of the numba kernel
(which releases the GIL), executed on a thread pool with one worker per core;
with the published RK4 scheme, points of the same bar kind and mode count go
in lock-step batches (:func:`~boringbar.simulate.simulate_batch`, the same
results as single runs, bit for bit).  Each run streams its metrics, no
trajectory is kept.  The result is an
xarray Dataset with the full configuration in its attributes.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np

from boringbar import __version__
from boringbar._validate import ParameterError, check_range
from boringbar.kernels.rk4_batch import BMAX
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System, make_system
from boringbar.simulate import Initial, simulate, simulate_batch

#: Points per lock-step batch of the RK4 kernel (benchmarks/bench_batch.py).
BATCH = 16
#: Most values of one START:STOP:STEP range or list (:func:`parse_range`; the
#: published sweep has 11 ratios, the bifurcation 46 forces).
MAX_GRID_VALUES = 100_000


@dataclass(frozen=True, eq=False)
class Case:
    """One bar of a sweep: a label, the System, and what distinguishes it."""

    label: str
    system: System
    bar: str
    gap: float = math.nan
    friction: str = "n/a"


def published_cases(bars=("solid", "tmd", "ball"), gaps=(0.5e-3, 0.1e-3),
                    frictions=(False, True), preset: str = "physical", **overrides) -> list[Case]:
    """The bars of the published sweeps: solid, TMD, and the ball damper for
    every gap x friction.  ``overrides`` go to :func:`make_system`."""
    cases = []
    for bar in bars:
        if bar == "ball":
            for gap in gaps:
                for fr in frictions:
                    s = make_system("ball", preset, gap=gap, friction=fr, **overrides)
                    label = f"ball gap={gap * 1e3:g}mm friction={'on' if fr else 'off'}"
                    cases.append(Case(label, s, "ball", gap, "on" if fr else "off"))
        else:
            kw = {k: v for k, v in overrides.items() if k in ("n_modes", "z_absorber",
                                                               "tmd_mass", "tmd_design",
                                                               "modal")}
            cases.append(Case(bar, make_system(bar, preset, **kw), bar))
    return cases


def parse_range(text: str, name: str = "ratios") -> np.ndarray:
    """'0.95:1.05:0.01' (inclusive) or '0.95,1.0,1.05' -> array."""
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not (math.isfinite(start) and math.isfinite(stop) and step > 0
                    and stop >= start):
                raise ValueError
            n = math.floor((stop - start) / step + 1e-9) + 1
            if n > MAX_GRID_VALUES:
                raise ParameterError(f"{name} = {text!r} has {n:.3g} values; the allowed "
                                     f"maximum is {MAX_GRID_VALUES}")
            return np.round(start + step * np.arange(n), 12)
        values = np.array([float(v) for v in text.split(",")])
    except (ValueError, OverflowError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(f"{name} = {text!r} must be START:STOP:STEP with STEP > 0 and "
                             "STOP >= START, or a comma-separated list of numbers") from None
    if len(values) > MAX_GRID_VALUES or not np.all(np.isfinite(values)):
        raise ParameterError(f"{name} = {text!r} must be at most {MAX_GRID_VALUES} finite "
                             "numbers")
    return values


def sweep_point(case: Case, force: float, ratio: float, duration: float, dt: float,
         initial: Initial | None, integrator: str = "rk4") -> dict:
    run = simulate(case.system, Harmonic(force, ratio), duration=duration, dt=dt,
                   initial=initial, integrator=integrator)
    return _point(run)


def _batch(points: list[tuple[Case, float, float]], duration: float, dt: float,
           initial: Initial | None) -> list[dict]:
    """(case, force, ratio) points of one bar kind and mode count, advanced in
    lock-step (RK4): each equals :func:`sweep_point`'s."""
    runs = simulate_batch([(c.system, Harmonic(f, r), initial) for c, f, r in points],
                          duration=duration, dt=dt)
    return [_point(run) for run in runs]


def _point(run) -> dict:
    s = run.summary()
    return {
        "rms_tip_m": s["rms_tip_m"],
        "max_abs_tip_m": s["max_abs_tip_m"],
        "max_abs_rel_disp_m": s["max_abs_rel_disp_m"],
        "impacts_per_cycle": math.nan if s["impacts_per_cycle"] is None
        else s["impacts_per_cycle"],
        "pattern": s["pattern"] or "",
        "energy_balance_relative": s["energy"]["balance_relative"],
        "elapsed_s": s["elapsed_s"],
    }


def sweep(cases: list[Case], ratios, forces=(10.0,), *, duration: float = 2.0,
          dt: float = 1e-6, workers: int | None = None, initial: Initial | None = None,
          progress=None, integrator: str = "rk4", batch: int = BATCH):
    """Tip RMS and impact pattern against Omega/omega_n for every case and force.

    Returns an xarray Dataset with dims (case, force, ratio).  ``workers``:
    threads (default: every core).  ``progress(done, total)`` is called as
    points finish.  ``integrator``: "rk4" (published) or "exact" (see ``simulate``).
    ``batch``: with "rk4", points of the same bar kind and mode count advanced
    together in lock-step (:func:`~boringbar.simulate.simulate_batch`, up to 16),
    taken in (case, force, ratio) order; 1: one point at a time.  The results are
    the same, bit for bit, whatever ``batch`` and ``workers`` (``elapsed_s`` of a
    batched point is its share of its batch's time).
    """
    if not cases:
        raise ParameterError("sweep needs at least one case")
    ratios = np.atleast_1d(np.asarray(ratios, dtype=float))
    forces = np.atleast_1d(np.asarray(forces, dtype=float))
    for r in ratios:
        check_range("ratio", r, 0.0, math.inf, lo_open=True, hi_open=True)
    workers = int(workers or os.cpu_count() or 1)
    check_range("workers", workers, 1, 4096)
    check_range("batch", batch, 1, BMAX)
    shape = (len(cases), len(forces), len(ratios))
    names = ("rms_tip_m", "max_abs_tip_m", "max_abs_rel_disp_m", "impacts_per_cycle",
             "energy_balance_relative", "elapsed_s")
    out = {k: np.full(shape, np.nan) for k in names}
    pattern = np.full(shape, "", dtype=object)
    jobs = [(i, j, k) for i in range(shape[0]) for j in range(shape[1])
            for k in range(shape[2])]
    batched = integrator == "rk4" and batch > 1
    if batched:
        # points of one bar kind and mode count share a batch, in job order
        groups: dict[tuple, list] = {}
        for ijk in jobs:
            system = cases[ijk[0]].system
            groups.setdefault((system.kind, system.bar.n_modes), []).append(ijk)
        batches = [g[a:a + batch] for g in groups.values() for a in range(0, len(g), batch)]
    # warm the JIT once per kernel before fanning out (compilation is not
    # thread-parallel and would otherwise be repeated); batched, the kernel of each
    # batch size the group's batches use (it is compiled per size: warming another
    # size would compile one that no batch runs)
    warm = {(c.system.kind if batched else "", c.system.bar.n_modes): c for c in cases}
    for key, c0 in warm.items():
        if batched:
            g = groups[key]
            for size in sorted({min(batch, len(g) - a) for a in range(0, len(g), batch)}):
                simulate_batch([(c0.system, Harmonic(1.0, 1.0), None)] * size,
                               duration=2e-5, dt=1e-6)
        else:
            simulate(c0.system, Harmonic(1.0, 1.0), duration=2e-5, dt=1e-6,
                     integrator=integrator)
    tic = time.perf_counter()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        if batched:
            futures = {pool.submit(_batch, [(cases[i], forces[j], ratios[k]) for i, j, k in b],
                                   duration, dt, initial): b for b in batches}
        else:
            futures = {pool.submit(sweep_point, cases[i], forces[j], ratios[k], duration, dt,
                                   initial, integrator): [(i, j, k)] for i, j, k in jobs}
        done = 0
        for fut in as_completed(futures):
            results = fut.result()
            results = results if isinstance(results, list) else [results]
            for (i, j, k), res in zip(futures[fut], results, strict=True):
                for key in names:
                    out[key][i, j, k] = res[key]
                pattern[i, j, k] = res["pattern"]
            done += len(results)
            if progress is not None:
                progress(done, len(jobs))
    wall = time.perf_counter() - tic
    return sweep_dataset(cases, forces, ratios, out, pattern, {
        "integrator": integrator,
        "batch": batch if batched else 1,
        "dt_s": dt,
        "duration_s": duration,
        "workers": workers,
        "wall_time_s": wall,
        "initial": json.dumps((initial or Initial()).__dict__),
    })


def sweep_dataset(cases: list[Case], forces: np.ndarray, ratios: np.ndarray, out: dict,
             pattern: np.ndarray, attrs: dict):
    """The sweep Dataset from the per-point arrays ``out`` (name -> (case, force,
    ratio) array) and ``pattern``; ``attrs`` go after the configuration's."""
    import xarray as xr

    units = {"rms_tip_m": "m", "max_abs_tip_m": "m", "max_abs_rel_disp_m": "m",
             "impacts_per_cycle": "1/period", "elapsed_s": "s", "energy_balance_relative": "1"}
    dims = ("case", "force", "ratio")
    data = {k: (dims, v, {"units": units[k]}) for k, v in out.items()}
    data["pattern"] = (dims, pattern.astype(str))
    data["natural_frequency_hz"] = (("case",), np.array(
        [c.system.reference_frequency / (2 * math.pi) for c in cases]), {"units": "Hz"})
    ds = xr.Dataset(
        data,
        coords={
            "case": [c.label for c in cases],
            "force": ("force", forces, {"units": "N"}),
            "ratio": ("ratio", ratios, {"long_name": "Omega / omega_n of the host bar"}),
            "bar": ("case", [c.bar for c in cases]),
            "gap": ("case", np.array([c.gap for c in cases]), {"units": "m"}),
            "friction": ("case", [c.friction for c in cases]),
        },
        attrs={
            "title": "boringbar frequency sweep",
            "boringbar_version": __version__,
            "preset": ",".join(sorted({c.system.preset for c in cases})),
            "systems": json.dumps({c.label: c.system.to_dict() for c in cases}),
            **attrs,
        },
    )
    return ds


def sweep_summary(ds) -> dict:
    """JSON-able summary of a sweep (what ``boringbar sweep --json`` prints)."""
    cases = []
    for i, label in enumerate(ds["case"].values):
        for j, force in enumerate(ds["force"].values):
            cases.append({
                "case": str(label),
                "bar": str(ds["bar"].values[i]),
                "gap_m": None if np.isnan(ds["gap"].values[i]) else float(ds["gap"].values[i]),
                "friction": str(ds["friction"].values[i]),
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
