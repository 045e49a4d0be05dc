"""Bifurcation diagrams by continuation (docs/model.md, section 6).

One run per parameter value, each started from the previous run's final
state: forward through ``values`` in the order given, then (``backward``)
back through them in reverse from the forward sweep's final state, so the
first backward run repeats the last forward value.  Coexisting attractors
show up as forward/backward disagreement (:func:`hysteresis_ranges`).

Continuation and the forcing phase.  The force is F0 sin(Omega t) with t the
absolute time, so a run continued with time running on (``initial =
run.final``, a :class:`~boringbar.simulate.State` that carries t) sees no
phase jump.  When Omega changes between runs (a ratio sweep, or a System
factory that changes omega_n) the same t would put the force at another
phase; the next run then starts at t' = (Omega t mod 2 pi) / Omega', so that
Omega' t' = Omega t mod 2 pi: the phase, not the time, is continuous.

System parameters other than the forcing go through a factory ``value ->
System``; the state vector is carried over when its size matches (else the
run restarts from ``initial`` and is flagged ``restarted``), with the ball's
position clipped into the new clearance.

A continuation is sequential by nature; each run streams (no history), so a
2 s run costs a few tenths of a second.  Samples and verdicts come from
:mod:`boringbar.analysis.poincare`.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from boringbar import __version__
from boringbar._validate import ParameterError, check_positive, check_range
from boringbar.analysis.poincare import METHOD, poincare_map
from boringbar.model.dampers import ImpactDamper
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System
from boringbar.simulate import Initial, State, simulate

#: Parameters that change only the forcing, with their units.
FORCING_PARAMETERS = {"force": "N", "ratio": "1"}
DIRECTIONS = ("forward", "backward")
#: What the swept parameter leaves unset by default: 10 N at Omega = omega_n.
DEFAULT_FORCING = Harmonic(10.0, 1.0)


def continued_state(state: State, omega_old: float, omega_new: float) -> State:
    """``state`` to continue a run at forcing frequency ``omega_new`` (rad/s) with
    the phase Omega t mod 2 pi kept: the same State if the frequency is unchanged
    (time runs on), else one at t' = (omega_old t mod 2 pi) / omega_new."""
    if omega_new == omega_old:
        return state
    phase = math.fmod(omega_old * state.t, 2 * math.pi)
    return State(np.array(state.x, dtype=float), phase / omega_new)


def _start(
    previous: State | None, initial, system: System, omega: float, omega_old: float
) -> tuple[Initial | State | None, bool]:
    """The next run's initial condition and whether the continuation restarted."""
    if previous is None:
        return initial, False
    n = 2 * system.bar.n_modes + 2
    if np.size(previous.x) != n:
        return initial, True
    state = continued_state(previous, omega_old, omega)
    d = system.damper
    if isinstance(d, ImpactDamper):
        x = np.array(state.x, dtype=float)
        x[n - 2] = min(max(x[n - 2], -d.gap / 2), d.gap / 2)
        state = State(x, state.t)
    return state, False


def _point(system, parameter: str, value: float, base: Harmonic) -> tuple[System, Harmonic]:
    if parameter == "force":
        return system, replace(base, amplitude=value)
    if parameter == "ratio":
        return system, replace(base, ratio=value, frequency_hz=None)
    made = system(value)
    if not isinstance(made, System):
        raise ParameterError(
            f"the factory returned {made!r} for {parameter} = {value:g}; it must return a System"
        )
    return made, base


def _check(system, parameter: str, values, base_forcing, duration, dt, drop) -> np.ndarray:
    if not isinstance(parameter, str) or not parameter:
        raise ParameterError(f"parameter = {parameter!r} must be a name")
    if parameter in FORCING_PARAMETERS:
        if not isinstance(system, System):
            raise ParameterError(
                f"parameter = {parameter!r} changes the forcing only: "
                f"system = {system!r} must be a System"
            )
    elif not callable(system) or isinstance(system, System):
        raise ParameterError(
            f"parameter = {parameter!r} is not one of "
            f"{', '.join(FORCING_PARAMETERS)}: pass a factory value -> System"
        )
    if not isinstance(base_forcing, Harmonic):
        raise ParameterError(f"base_forcing = {base_forcing!r} must be a Harmonic")
    v = np.atleast_1d(np.asarray(values, dtype=float))
    if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)):
        raise ParameterError(f"values = {values!r} must be a non-empty 1-D list of numbers")
    step = np.diff(v)
    if v.size > 1 and not (np.all(step > 0) or np.all(step < 0)):
        raise ParameterError(
            f"values = {v.tolist()!r} must be strictly increasing or "
            "strictly decreasing (the sweep visits them in order)"
        )
    check_positive("duration", duration, "s")
    check_positive("dt", dt, "s")
    check_range("drop", drop, 0.0, 1.0, hi_open=True)
    return v


def bifurcation(
    system: System | Callable[[float], System],
    parameter: str,
    values,
    *,
    base_forcing: Harmonic | None = None,
    duration: float = 2.0,
    dt: float = 1e-6,
    drop: float = 0.2,
    initial: Initial | State | None = None,
    backward: bool = True,
    tol: float = 1e-3,
    max_k: int = 16,
    units: str | None = None,
    progress=None,
    integrator: str = "rk4",
):
    """Continuation sweep of ``parameter`` over ``values`` with Poincare samples.

    ``parameter``: "force" (F0, N) or "ratio" (Omega/omega_n) with ``system`` a
    System; any other name with ``system`` a factory ``value -> System`` (e.g.
    ``lambda g: make_system("ball", gap=g)``; ``units`` labels the values).
    ``base_forcing`` (default 10 N at ratio 1) supplies what the parameter does
    not set.  Each run lasts
    ``duration`` (s) with step ``dt`` (s); its first ``drop`` of time is dropped
    from the Poincare samples, the RMS and the pattern.  The first forward run
    starts from ``initial`` (default: rest, ball centred); each later one from
    the previous run's final state (module docstring: phase continuity).
    Verdicts: :meth:`PoincareMap.classify` with ``tol``, ``max_k``.
    ``progress(done, total)`` is called after each run.  ``integrator``: "rk4"
    (published) or "exact" (see :func:`~boringbar.simulate.simulate`).

    Returns an xarray Dataset, dims (direction, value, sample): the Poincare
    samples ``tip_displacement`` W (m) and ``tip_velocity`` W' (m/s), NaN-padded;
    per (direction, value): ``verdict``, ``period`` (k, 0 if none), ``distinct``,
    ``zero_one_K`` and ``zero_one_signal`` (the coordinate it ran on),
    ``n_samples``, ``tolerance`` (relative, jitter included), ``rms_tip_m``,
    ``pattern``, ``impacts_per_cycle``, ``restarted``, ``start_time_s``,
    ``end_time_s``, ``elapsed_s``, ``omega`` (rad/s); the configuration (every
    value's System included) as JSON in the attributes.
    """
    base_forcing = DEFAULT_FORCING if base_forcing is None else base_forcing
    v = _check(system, parameter, values, base_forcing, duration, dt, drop)
    directions = DIRECTIONS if backward else DIRECTIONS[:1]
    records: dict[tuple[int, int], dict] = {}
    systems: dict[int, dict] = {}
    previous, omega_old = None, math.nan
    tic = time.perf_counter()
    for d, direction in enumerate(directions):
        order = range(len(v)) if direction == "forward" else range(len(v) - 1, -1, -1)
        for i in order:
            sys_i, forcing = _point(system, parameter, float(v[i]), base_forcing)
            omega = forcing.omega(sys_i.reference_frequency)
            start, restarted = _start(previous, initial, sys_i, omega, omega_old)
            run = simulate(
                sys_i,
                forcing,
                duration=duration,
                dt=dt,
                initial=start,
                steady_fraction=1.0 - drop,
                strobe=True,
                integrator=integrator,
            )
            records[d, i] = {**_record(run, drop, tol, max_k), "restarted": restarted}
            systems.setdefault(i, sys_i.to_dict())
            previous, omega_old = run.final, omega
            if progress is not None:
                progress(len(records), len(directions) * len(v))
    config = {
        "parameter": parameter,
        "values": v.tolist(),
        "base_forcing": base_forcing.to_dict(),
        "systems": [systems[i] for i in range(len(v))],
        "initial": _initial_dict(initial),
        "duration_s": duration,
        "dt_s": dt,
        "drop": drop,
        "tol": tol,
        "max_k": max_k,
        "integrator": integrator,
        "wall_time_s": time.perf_counter() - tic,
    }
    return _dataset(records, directions, v, FORCING_PARAMETERS.get(parameter, units or ""), config)


#: Per-run outputs: name -> (dtype, units).
_FIELDS = {
    "verdict": (str, None),
    "period": (int, "1"),
    "distinct": (int, "1"),
    "n_samples": (int, "1"),
    "zero_one_K": (float, "1"),
    "zero_one_signal": (str, None),
    "tolerance": (float, "1"),
    "rms_tip_m": (float, "m"),
    "pattern": (str, None),
    "impacts_per_cycle": (float, "1/period"),
    "restarted": (bool, None),
    "omega": (float, "rad/s"),
    "start_time_s": (float, "s"),
    "end_time_s": (float, "s"),
    "elapsed_s": (float, "s"),
}


def _record(run, drop: float, tol: float, max_k: int) -> dict:
    """One run's Poincare samples, verdict and metrics (the fields of ``_FIELDS``)."""
    pm = poincare_map(run, drop)
    verdict = pm.classify(tol, max_k)
    return {
        "points": pm.points,
        "verdict": verdict["verdict"],
        "period": verdict["k"],
        "distinct": verdict["distinct"],
        "n_samples": len(pm.time),
        "zero_one_K": verdict["K"],
        "zero_one_signal": verdict["signal"] if np.isfinite(verdict["K"]) else "",
        "tolerance": tol + pm.jitter,
        "rms_tip_m": run.rms_tip,
        "pattern": "" if run.pattern is None else run.pattern.name,
        "impacts_per_cycle": math.nan if run.pattern is None else run.pattern.impacts_per_cycle,
        "omega": run.omega,
        "start_time_s": run.t0,
        "end_time_s": run.final.t,
        "elapsed_s": run.elapsed_s,
    }


def _dataset(records: dict, directions, values: np.ndarray, unit: str, config: dict):
    import xarray as xr

    shape = (len(directions), len(values))
    n_sample = max([len(r["points"]) for r in records.values()] + [1])
    samples = np.full(shape + (n_sample, 2), np.nan)
    fields = {k: np.zeros(shape, dtype=object if t is str else t) for k, (t, _) in _FIELDS.items()}
    for (d, i), rec in records.items():
        samples[d, i, : len(rec["points"])] = rec["points"]
        for k in fields:
            fields[k][d, i] = rec[k]
    dims2 = ("direction", "value")
    dims3 = dims2 + ("sample",)
    data = {
        "tip_displacement": (
            dims3,
            samples[..., 0],
            {"units": "m", "long_name": "W at Omega t = 0 mod 2 pi"},
        ),
        "tip_velocity": (
            dims3,
            samples[..., 1],
            {"units": "m/s", "long_name": "W' at Omega t = 0 mod 2 pi"},
        ),
    }
    for k, (t, u) in _FIELDS.items():
        a = fields[k].astype(str) if t is str else fields[k]
        data[k] = (dims2, a, {"units": u} if u else {})
    parameter = config["parameter"]
    return xr.Dataset(
        data,
        coords={
            "direction": list(directions),
            "value": ("value", values, {"long_name": parameter, "units": unit}),
        },
        attrs={
            "title": f"boringbar bifurcation diagram over {parameter}",
            "boringbar_version": __version__,
            "parameter": parameter,
            "units": unit,
            "dt_s": config["dt_s"],
            "duration_s": config["duration_s"],
            "drop": config["drop"],
            "wall_time_s": config["wall_time_s"],
            "classification": METHOD,
            "continuation": "each run starts from the previous run's final state; time runs "
            "on, or when Omega changes the next run starts at t' = (Omega t mod 2 pi) / "
            "Omega' so the forcing phase is continuous; backward starts from the forward "
            "sweep's final state",
            "config": json.dumps(config),
        },
    )


def _initial_dict(initial) -> dict | None:
    if initial is None:
        return None
    if isinstance(initial, State):
        return {"x": np.asarray(initial.x, dtype=float).tolist(), "t": float(initial.t)}
    return dict(initial.__dict__)


# --- forward vs backward -------------------------------------------------------------
#: Blocks a non-periodic cloud is cut into to estimate its statistics' noise.
BLOCKS = 8
#: A non-periodic difference counts beyond this many standard errors.
SIGMAS = 4.0


def _side(ds, direction: str, i: int, scale: np.ndarray) -> dict:
    """One direction's verdict and scaled Poincare samples at value index ``i``."""
    row = ds.sel(direction=direction).isel(value=i)
    n = int(row["n_samples"])
    k = int(row["period"])
    pts = np.column_stack([row["tip_displacement"].values[:n], row["tip_velocity"].values[:n]])
    periodic = k > 0 and (
        str(row["verdict"].values).startswith("period-")
        or str(row["verdict"].values) == "transient"
    )
    return {
        "k": k,
        "periodic": periodic,
        "points": pts / scale,
        "tolerance": float(row["tolerance"]),
    }


def _far(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    """Some point of ``a`` has no point of ``b`` within ``tol`` (Chebyshev), or vice versa."""
    gap = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=2)
    return bool(gap.min(axis=1).max() > tol or gap.min(axis=0).max() > tol)


def _block_stats(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error over BLOCKS contiguous blocks of the RMS and the
    mean of each coordinate."""
    n = len(z) // BLOCKS * BLOCKS
    blocks = z[len(z) - n :].reshape(BLOCKS, -1, z.shape[1])
    stats = np.concatenate([np.sqrt(np.mean(blocks**2, axis=1)), blocks.mean(axis=1)], axis=1)
    return stats.mean(axis=0), stats.std(axis=0, ddof=1) / math.sqrt(BLOCKS)


def point_differs(ds, i: int, tol: float = 0.02) -> bool:
    """Whether the forward and backward Poincare sets at value index ``i`` differ.

    Coordinates are scaled: W by A = sqrt(2) x the larger tip RMS of the two
    runs, W' by Omega A; ``thr`` = max(``tol``, 2 x either run's clustering
    tolerance).  Both periodic (period-k, or transient settling onto period-k):
    they differ if k differs or a point of one orbit (its last k samples) has
    no point of the other within ``thr``.  One periodic: they differ unless
    every sample of the other run lies within ``thr`` of the orbit (an orbit
    whose step-grid scatter split it into clusters).  Neither periodic (two
    samplings of one chaotic attractor differ: the tip RMS of successive 2 s
    windows at 20 N, r = 1.0, gap 0.5 mm varies by 15 %): the RMS and the mean
    of W and W' over the samples differ by more than ``tol`` + ``SIGMAS``
    standard errors, estimated from ``BLOCKS`` contiguous blocks of each run.
    """
    rms = ds["rms_tip_m"].isel(value=i).values
    amp = math.sqrt(2) * max(float(np.nanmax(rms)), 1e-300)
    omega = float(ds["omega"].sel(direction="forward").values[i])
    scale = np.array([amp, omega * amp])
    f, b = (_side(ds, d, i, scale) for d in DIRECTIONS)
    thr = max(tol, 2 * f["tolerance"], 2 * b["tolerance"])
    if f["periodic"] and b["periodic"]:
        k = f["k"]
        return k != b["k"] or _far(f["points"][-k:], b["points"][-k:], thr)
    if f["periodic"] or b["periodic"]:
        orbit, cloud = (f, b) if f["periodic"] else (b, f)
        return _far(orbit["points"][-orbit["k"] :], cloud["points"], thr)
    if min(len(f["points"]), len(b["points"])) < 2 * BLOCKS:
        return bool(np.any(np.abs(f["points"].mean(0) - b["points"].mean(0)) > tol))
    (mf, sf), (mb, sb) = _block_stats(f["points"]), _block_stats(b["points"])
    return bool(np.any(np.abs(mf - mb) > tol + SIGMAS * np.hypot(sf, sb)))


def hysteresis_ranges(ds, tol: float = 0.02) -> list[tuple[float, float]]:
    """Parameter ranges (start, stop), ascending, where forward and backward
    Poincare sets differ (:func:`point_differs`); a single value gives
    (v, v).  Needs a dataset swept with ``backward=True``."""
    if "backward" not in list(ds["direction"].values):
        raise ParameterError(
            "the dataset has no backward sweep: run bifurcation(..., backward=True)"
        )
    check_positive("tol", tol)
    values = ds["value"].values
    order = np.argsort(values)
    ranges: list[tuple[float, float]] = []
    current: list[float] | None = None
    for i in order:
        if point_differs(ds, int(i), tol):
            if current is None:
                current = [float(values[i]), float(values[i])]
            else:
                current[1] = float(values[i])
        elif current is not None:
            ranges.append((current[0], current[1]))
            current = None
    if current is not None:
        ranges.append((current[0], current[1]))
    return ranges
