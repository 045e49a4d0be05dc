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
import sys
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from boringbar._validate import ParameterError, check_positive, check_range, check_values
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.poincare import METHOD, poincare_map
from boringbar.execute import Execution
from boringbar.model.dampers import ImpactDamper
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System
from boringbar.simulate import Initial, Integration, State, simulate
from boringbar.simulate.run_limits import check_steady_ratios
from boringbar.version import __version__

#: Parameters that change only the forcing, with their units.
FORCING_PARAMETERS = {"force": "N", "ratio": "1"}
DIRECTIONS = ("forward", "backward")
#: What the swept parameter leaves unset by default: 10 N at Omega = omega_n.
DEFAULT_FORCING = Harmonic(10.0, 1.0)
#: The published sweep: F0 = 5..50 N in 1 N steps.
PUBLISHED_FORCES = tuple(float(f) for f in range(5, 51))
CONTINUATION = ("each run starts from the previous run's final state; time runs on, or when "
                "Omega changes the next run starts at t' = (Omega t mod 2 pi) / Omega' so the "
                "forcing phase is continuous; backward starts from the forward sweep's final "
                "state")


def continued_state(state: State, omega_old: float, omega_new: float) -> State:
    """``state`` to continue a run at forcing frequency ``omega_new`` (rad/s) with
    the phase Omega t mod 2 pi kept: the same State if the frequency is unchanged
    (time runs on), else one at t' = (omega_old t mod 2 pi) / omega_new."""
    if omega_new == omega_old:
        return state
    phase = math.fmod(omega_old * state.t_s, 2 * math.pi)
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
        x[n - 2] = min(max(x[n - 2], -d.gap_m / 2), d.gap_m / 2)
        state = State(x, state.t_s)
    return state, False


def _point(system, parameter: str, value: float, base: Harmonic) -> tuple[System, Harmonic]:
    if parameter == "force":
        return system, replace(base, amplitude_n=value)
    if parameter == "ratio":
        return system, replace(base, ratio=value, frequency_hz=None)
    made = system(value)
    if not isinstance(made, System):
        raise ParameterError(
            f"the factory returned {made!r} for {parameter} = {value:g}; it must return a System"
        )
    return made, base


@dataclass(frozen=True)
class BifurcationOptions:
    """What a continuation sweeps and how its runs are judged.

    ``parameter``: "force" (F0, N) or "ratio" (Omega/omega_n) for a System; any
    other name for a factory ``value -> System`` (``units`` labels its values);
    ``values``: visited in the order given (strictly increasing or decreasing;
    default F0 = 5..50 N, published); the forcing the parameter does not set:
    ``force_n`` (N) at ``ratio`` (Omega/omega_n); ``backward``: then back through
    the values in reverse; verdicts: :meth:`PoincareMap.classify` with ``tol`` and
    ``max_k``.
    """

    parameter: str = "force"
    values: tuple[float, ...] = PUBLISHED_FORCES
    force_n: float = DEFAULT_FORCING.amplitude_n
    ratio: float = DEFAULT_FORCING.ratio
    backward: bool = True
    tol: float = 1e-3
    max_k: int = 16
    units: str | None = None

    def __post_init__(self):
        if not isinstance(self.parameter, str) or not self.parameter:
            raise ParameterError(f"parameter = {self.parameter!r} must be a name")
        v = np.atleast_1d(np.asarray(self.values, dtype=float))
        if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)):
            raise ParameterError(f"values = {self.values!r} must be a non-empty 1-D list of "
                                 "numbers")
        step = np.diff(v)
        if v.size > 1 and not (np.all(step > 0) or np.all(step < 0)):
            raise ParameterError(f"values = {v.tolist()!r} must be strictly increasing or "
                                 "strictly decreasing (the sweep visits them in order)")
        if self.parameter == "ratio":
            check_values("values", v.tolist(), 0.0, math.inf, lo_open=True)
        if self.parameter == "force":
            check_values("values", v.tolist(), 0.0, math.inf, unit="N")
        object.__setattr__(self, "values", tuple(v.tolist()))
        check_range("force_n", self.force_n, 0.0, math.inf, unit="N")
        check_range("ratio", self.ratio, 0.0, math.inf, lo_open=True)
        check_positive("tol", self.tol)
        check_range("max_k", self.max_k, 1, 64)

    @property
    def base_forcing(self) -> Harmonic:
        return Harmonic(self.force_n, self.ratio)

    def unit(self) -> str:
        """The units of the values."""
        return FORCING_PARAMETERS.get(self.parameter, self.units or "")


def _check_system(system, parameter: str) -> None:
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


def plan(systems, options: BifurcationOptions, integration: Integration) -> Plan:
    """One point per continuation (sequential by nature): of ``systems``, a System or
    a factory ``value -> System`` (the Dataset of one), or a list of
    :class:`~boringbar.analysis.cases.Case` (their Datasets stacked along ``case``)."""
    integration = integration.with_step()
    cases = list(systems) if isinstance(systems, list | tuple) else None
    targets = [c.system for c in cases] if cases is not None else [systems]
    if not targets:
        raise ParameterError("bifurcation needs at least one system")
    for target in targets:
        _check_system(target, options.parameter)
        if isinstance(target, System):  # a steady part of one forcing period at least
            ratios = options.values if options.parameter == "ratio" else (options.ratio,)
            check_steady_ratios(target, ratios, integration.duration_s,
                                integration.steady_fraction, "Integration.duration_s")
    context = {"systems": targets, "options": options, "integration": integration}
    return Plan(context, list(range(len(targets))), {"cases": cases})


def compute(context: dict, i: int) -> dict:
    """The whole continuation (forward, then backward) of system ``i``: per run its
    record (:data:`_FIELDS`, Poincare points), and each value's System as a dict."""
    o, integ = context["options"], context["integration"]
    system, v = context["systems"][i], o.values
    directions = DIRECTIONS if o.backward else DIRECTIONS[:1]
    records: dict[tuple[int, int], dict] = {}
    systems: dict[int, dict] = {}
    used: set[str] = set()
    previous, omega_old = None, math.nan
    for d, direction in enumerate(directions):
        order = range(len(v)) if direction == "forward" else range(len(v) - 1, -1, -1)
        for j in order:
            sys_j, forcing = _point(system, o.parameter, v[j], o.base_forcing)
            omega = forcing.omega(sys_j.reference_frequency_rad_s)
            start, restarted = _start(previous, integ.initial, sys_j, omega, omega_old)
            run = simulate(sys_j, forcing, **{**integ.kwargs(), "initial": start},
                           strobe=True)
            records[d, j] = {**_record(run, integ.steady_fraction, o.tol, o.max_k),
                             "restarted": restarted}
            systems.setdefault(j, sys_j.to_dict())
            used.add(run.integrator)
            previous, omega_old = run.final, omega
    return {"records": records, "directions": directions,
            "systems": [systems[j] for j in range(len(v))], "integrators": sorted(used)}


def bifurcation(system: System | Callable[[float], System],
                options: BifurcationOptions | None = None, *,
                integration: Integration | None = None, execution: Execution | None = None,
                progress=None):
    """Continuation sweep of ``options.parameter`` over ``options.values`` with
    Poincare samples.

    ``system``: a System for "force" (F0, N) or "ratio" (Omega/omega_n); for any
    other parameter a factory ``value -> System`` (e.g. ``lambda g:
    make_system("ball", gap_m=g)``).  ``options``: :class:`BifurcationOptions`
    (default: F0 5..50 N at ratio 1, forward and backward).  ``integration``:
    each run's duration, step, integrator and steady window
    (``steady_fraction``: the Poincare samples, the RMS and the pattern are of the
    last part of each run); the first forward run starts from
    ``integration.initial`` (default: rest, ball centred; an
    :class:`~boringbar.simulate.Initial` or a :class:`~boringbar.simulate.State`),
    each later one from the previous run's final state (module docstring: phase
    continuity).  ``execution`` and ``progress(done, total)``: the contract's
    (one point: the whole continuation).

    Returns an xarray Dataset, dims (direction, value, sample): the Poincare
    samples ``tip_displacement_m`` W (m) and ``tip_velocity_m_s`` W' (m/s), NaN-padded;
    per (direction, value): ``verdict``, ``period`` (k, 0 if none), ``distinct``,
    ``zero_one_K`` and ``zero_one_signal`` (the coordinate it ran on),
    ``n_samples``, ``tolerance`` (relative, jitter included), ``rms_tip_m``,
    ``pattern``, ``impacts_per_cycle``, ``restarted``, ``start_time_s``,
    ``end_time_s``, ``omega_rad_s`` (rad/s); the configuration (every value's System
    included) as JSON in the attributes.
    """
    options = options or BifurcationOptions()
    integration = integration or Integration()
    p = plan(system, options, integration)
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    return assemble(p, results, execution_attrs(execution, wall))


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
    "omega_rad_s": (float, "rad/s"),
    "start_time_s": (float, "s"),
    "end_time_s": (float, "s"),
}


def _record(run, steady_fraction: float, tol: float, max_k: int) -> dict:
    """One run's Poincare samples, verdict and metrics (the fields of ``_FIELDS``)."""
    pm = poincare_map(run, steady_fraction)
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
        "rms_tip_m": run.rms_tip_m,
        "pattern": "" if run.pattern is None else run.pattern.name,
        "impacts_per_cycle": math.nan if run.pattern is None else run.pattern.impacts_per_cycle,
        "omega_rad_s": run.omega_rad_s,
        "start_time_s": run.t0_s,
        "end_time_s": run.final.t_s,
    }


def _arrays(result: dict, n_values: int, n_sample: int) -> dict:
    """One continuation's records as arrays over (direction, value[, sample]):
    ``samples`` (..., 2) NaN-padded to ``n_sample``, and each field of ``_FIELDS``."""
    shape = (len(result["directions"]), n_values)
    samples = np.full(shape + (n_sample, 2), np.nan)
    fields = {k: np.zeros(shape, dtype=object if t is str else t) for k, (t, _) in _FIELDS.items()}
    for (d, i), rec in result["records"].items():
        samples[d, i, : len(rec["points"])] = rec["points"]
        for k in fields:
            fields[k][d, i] = rec[k]
    return {"samples": samples,
            **{k: fields[k].astype(str) if t is str else fields[k]
               for k, (t, _) in _FIELDS.items()}}


def _data(arrays: list[dict], lead: tuple) -> dict:
    """The data variables of the stacked ``arrays`` (one per continuation) with the
    leading dims ``lead`` (() for one continuation, ("case",) for several)."""
    pick = (lambda k: arrays[0][k]) if not lead else (lambda k: np.stack([a[k] for a in arrays]))
    samples = pick("samples")
    dims2 = lead + ("direction", "value")
    dims3 = dims2 + ("sample",)
    data = {
        "tip_displacement_m": (dims3, samples[..., 0],
                             {"units": "m", "long_name": "W at Omega t = 0 mod 2 pi"}),
        "tip_velocity_m_s": (dims3, samples[..., 1],
                         {"units": "m/s", "long_name": "W' at Omega t = 0 mod 2 pi"}),
    }
    for k, (_, u) in _FIELDS.items():
        data[k] = (dims2, pick(k), {"units": u} if u else {})
    return data


def assemble(plan: Plan, results: list[dict], attrs: dict | None = None):
    """The bifurcation Dataset of one continuation (dims direction, value, sample), or,
    for a list of cases, theirs stacked along ``case``; ``attrs`` after the
    configuration's."""
    ctx, cases = plan.context, plan.extra["cases"]
    o, integ = ctx["options"], ctx["integration"]
    n_sample = max([len(r["points"]) for res in results for r in res["records"].values()]
                   + [1])
    arrays = [_arrays(r, len(o.values), n_sample) for r in results]
    data = _data(arrays, () if cases is None else ("case",))
    directions = results[0]["directions"]
    coords = {"direction": list(directions),
              "value": ("value", np.array(o.values), {"long_name": o.parameter,
                                                       "units": o.unit()})}
    config = {"parameter": o.parameter, "values": list(o.values),
              "base_forcing": o.base_forcing.to_dict(),
              "initial": _initial_dict(integ.initial), "duration_s": integ.duration_s,
              "dt_s": integ.dt_s, "steady_fraction": integ.steady_fraction, "tol": o.tol,
              "max_k": o.max_k, "integrator": integ.integrator}
    if cases is None:
        config["systems"] = results[0]["systems"]
        extra = {}
    else:
        coords.update({"case": [c.label for c in cases], "bar": ("case", [c.bar for c in cases]),
                       "gap_m": ("case", np.array([c.gap_m for c in cases]), {"units": "m"}),
                       "friction": ("case", [c.friction for c in cases])})
        extra = {"systems": json.dumps({c.label: r["systems"]
                                        for c, r in zip(cases, results, strict=True)})}
    return xr.Dataset(data, coords=coords, attrs={
        "title": f"boringbar bifurcation diagram over {o.parameter}",
        "boringbar_version": __version__, "parameter": o.parameter, "units": o.unit(),
        "preset": ",".join(sorted({r["systems"][0]["preset"] for r in results})),
        "dt_s": integ.dt_s, "duration_s": integ.duration_s,
        "steady_fraction": integ.steady_fraction, "integrator": integ.integrator,
        "integrator_used": ",".join(sorted({i for r in results for i in r["integrators"]})),
        "classification": METHOD, "continuation": CONTINUATION,
        "config": json.dumps(config), **extra, **(attrs or {})})


def _initial_dict(initial) -> dict | None:
    if initial is None:
        return None
    if isinstance(initial, State):
        return {"x": np.asarray(initial.x, dtype=float).tolist(), "t": float(initial.t_s)}
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
    pts = np.column_stack([row["tip_displacement_m"].values[:n],
                           row["tip_velocity_m_s"].values[:n]])
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
    they differ if k differs, if they strike a different number of times a period,
    or if a point of one orbit (its last k samples) has no point of the other within
    ``thr``.  One periodic: they differ unless
    every sample of the other run lies within ``thr`` of the orbit (an orbit
    whose step-grid scatter split it into clusters).  Neither periodic (two
    samplings of one chaotic attractor differ: the tip RMS of successive 2 s
    windows at 20 N, r = 1.0, gap 0.5 mm varies by 15 %): the RMS and the mean
    of W and W' over the samples differ by more than ``tol`` + ``SIGMAS``
    standard errors, estimated from ``BLOCKS`` contiguous blocks of each run.
    """
    rms = ds["rms_tip_m"].isel(value=i).values
    amp = math.sqrt(2) * max(float(np.nanmax(rms)), 1e-300)
    omega = float(ds["omega_rad_s"].sel(direction="forward").values[i])
    scale = np.array([amp, omega * amp])
    f, b = (_side(ds, d, i, scale) for d in DIRECTIONS)
    thr = max(tol, 2 * f["tolerance"], 2 * b["tolerance"])
    if f["periodic"] and b["periodic"]:
        k = f["k"]
        return (k != b["k"] or _other_impacts(ds, i)
                or _far(f["points"][-k:], b["points"][-k:], thr))
    if f["periodic"] or b["periodic"]:
        orbit, cloud = (f, b) if f["periodic"] else (b, f)
        return _far(orbit["points"][-orbit["k"] :], cloud["points"], thr)
    if min(len(f["points"]), len(b["points"])) < 2 * BLOCKS:
        return bool(np.any(np.abs(f["points"].mean(0) - b["points"].mean(0)) > tol))
    (mf, sf), (mb, sb) = _block_stats(f["points"]), _block_stats(b["points"])
    return bool(np.any(np.abs(mf - mb) > tol + SIGMAS * np.hypot(sf, sb)))


def _other_impacts(ds, i: int) -> bool:
    """Whether the two directions' runs at value index ``i`` strike a different number of
    times a period: one periodic orbit cannot, however near their Poincare points lie
    (the gap 0.1 mm ball's four- and six-impact orbits at 35 N, 2-4 % apart)."""
    ipc = ds["impacts_per_cycle"].isel(value=i).values if "impacts_per_cycle" in ds else []
    return len(ipc) == 2 and bool(np.all(np.isfinite(ipc))) and abs(ipc[0] - ipc[1]) >= 0.5


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


HYSTERESIS_NOTE = ("parameter ranges (start, stop) in the parameter's SI units where the "
                   "forward and backward Poincare sets differ "
                   "(analysis.bifurcation.hysteresis_ranges)")


def with_hysteresis(ds, tol: float = 0.02):
    """``ds`` with its :func:`hysteresis_ranges` (JSON, null without a backward sweep)
    in the attribute ``hysteresis_ranges``, as :func:`summary` and the plot read them."""
    ranges = hysteresis_ranges(ds, tol) if "backward" in list(ds["direction"].values) else None
    ds = ds.copy()
    ds.attrs.update(hysteresis_ranges=json.dumps(ranges), hysteresis_note=HYSTERESIS_NOTE)
    return ds


def summary(ds, ranges=None) -> dict:
    """JSON-able summary (what ``boringbar bifurcation --json`` prints): per direction
    and value the W samples (m), verdicts, periods, RMS and patterns; ``ranges``: the
    hysteresis ranges (default: those :func:`with_hysteresis` stored, if any)."""
    if ranges is None and ds.attrs.get("hysteresis_ranges") is not None:
        ranges = json.loads(ds.attrs["hysteresis_ranges"])
    config = json.loads(ds.attrs["config"])
    dirs = [str(d) for d in ds["direction"].values]

    def per_value(name: str, direction: str) -> list:
        return ds[name].sel(direction=direction).values.tolist()

    def samples(direction: str) -> list[list[float]]:
        row = ds.sel(direction=direction)
        return [w[:n].tolist() for w, n in zip(row["tip_displacement_m"].values,
                                               row["n_samples"].values, strict=True)]

    return {
        "parameter": ds.attrs["parameter"],
        "units": ds.attrs["units"],
        "values": ds["value"].values.tolist(),
        "preset": ds.attrs.get("preset"),
        "bar": ds.attrs.get("bar"),
        "base_forcing": config["base_forcing"],
        "duration_s": config["duration_s"],
        "dt_s": config["dt_s"],
        "steady_fraction": config["steady_fraction"],
        "forward": samples("forward"),
        "backward": samples("backward") if "backward" in dirs else None,
        "verdicts": {d: per_value("verdict", d) for d in dirs},
        "period": {d: per_value("period", d) for d in dirs},
        "rms_tip_m": {d: per_value("rms_tip_m", d) for d in dirs},
        "pattern": {d: per_value("pattern", d) for d in dirs},
        "hysteresis_ranges": None if ranges is None else [list(r) for r in ranges],
        "wall_time_s": ds.attrs.get("wall_time_s"),
    }
