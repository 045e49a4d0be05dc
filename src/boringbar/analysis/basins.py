"""Basins of attraction over a grid of initial conditions (docs/model.md, section 6).

Every cell of an initial tip displacement x initial tip velocity grid is an
independent run of the kernel (the ball starts at ``ball_position`` with
relative velocity ``ball_velocity``, by default at rest and centred, as
published).  With the published RK4 scheme the cells advance in lock-step
batches of ``BATCH`` consecutive cells in grid order
(:func:`~boringbar.simulate.simulate_batch`, whose runs equal single runs bit
for bit); batches (or single cells) run on a thread pool (the kernel
releases the GIL) and are assembled by index, so serial, parallel and
unbatched runs give bit-identical results.  The end states are then
grouped into attractors, serially, in grid order.

Grouping (all tolerances in :class:`BasinTolerance`):

1. **Signature of a run.**  The stroboscopic Poincare samples (W, W') at
   Omega t = 0 mod 2 pi after dropping the first ``drop`` of the run are
   scaled by the run's amplitude scale A = sqrt(2) RMS(W) (W / A, W' /
   (Omega A); A is floored at ``floor`` so a bar at rest does not divide by
   zero).  On the last ``TAIL`` samples the smallest k = 1..``MAX_K`` with
   max |P[i + k] - P[i]| <= ``period`` is the run's period; its signature is
   then the k cluster centres (the mean of every k-th sample), sorted by
   (W, W') for display.  No such k: the run is *non-periodic*
   (quasi-periodic or chaotic-like) and has no point signature.
2. **Grouping.**
   - periodic runs are visited in grid order; each joins the first
     attractor whose leader (its first run, also its representative) has
     the same impact-pattern name and period, centres within ``match``
     (Hausdorff distance, scaled by the larger amplitude scale of the two:
     invariant to which point of a period-k cycle comes first) and RMS
     within ``rms`` of the larger; otherwise it starts a new attractor;
   - non-periodic runs with the same pattern name (usually 'non-uniform'),
     sorted by RMS, form one attractor until two neighbours' RMS differ by
     more than ``nonperiodic_rms`` of the larger (single linkage: an RMS
     band, so the spread of a chaotic attractor's RMS does not split it);
     its leader is its first run in grid order.
   Attractor ids are then ordered by basin fraction, largest first (ties:
   leader first in grid order).

The signature is the bar's (W, W') only: a frictionless ball that never
touches a wall floats at any position, and including it would split one bar
motion into a continuum.  A mirrored pair of orbits (y -> -y, W -> -W half a
period later) strobes at different points unless the orbit is itself
symmetric, so the two members of a symmetric pair are distinct attractors.
"""

from __future__ import annotations

import json
import math
import os
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import asdict, dataclass

import numpy as np

from boringbar import __version__
from boringbar._validate import ParameterError, check_int, check_positive, check_range
from boringbar.kernels.rk4_batch import BMAX
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System
from boringbar.simulate import Initial, simulate, simulate_batch

#: Largest period, in forcing periods, looked for in the strobe (as the pattern classifier).
MAX_K = 8
#: Poincare samples at the end of the run on which the period is judged.
TAIL = 50
#: Repetitions of the period needed in the tail.
MIN_REPEATS = 3
#: Published grid: tip displacement (m) and velocity (m/s), (start, stop, count).
PUBLISHED_DISPLACEMENT = (-1.5e-3, 1.5e-3, 30)
PUBLISHED_VELOCITY = (-1.5, 1.5, 30)
#: Most cells (runs) of one basin grid, displacement count x velocity count
#: (published: 900); a cell keeps its Poincare samples until they are grouped.
MAX_BASIN_CELLS = 1_000_000
#: Cells per lock-step batch of the RK4 kernel (benchmarks/bench_batch.py).
BATCH = 16


@dataclass(frozen=True)
class BasinTolerance:
    """Tolerances of the attractor grouping, as fractions of the amplitude scale
    A = sqrt(2) RMS(W) (W) and Omega A (W'), or of the RMS (see the module doc).

    ``period`` 0.02: an impact is detected up to one step late, so the strobe of
    a periodic impact orbit jitters by about 2e-3 A at dt = 1e-6 s; ``match``
    0.05 between two runs' centres (taken on the tail, so settled); ``rms`` 0.15:
    the RMS is over the whole kept part and still carries the transient in a
    short run (+-6 % for a linear bar after 0.3 s), so it only separates orbits
    the centres cannot; ``nonperiodic_rms`` 0.10, the largest gap between
    neighbouring RMS values inside one non-periodic attractor (a chaotic run's
    RMS over 1.6 s spreads over +-15 %, continuously); ``floor`` (m), the
    smallest amplitude scale.
    """

    period: float = 0.02
    match: float = 0.05
    rms: float = 0.15
    nonperiodic_rms: float = 0.10
    floor: float = 1e-9

    def __post_init__(self):
        for name in ("period", "match", "rms", "nonperiodic_rms", "floor"):
            check_positive(f"tol.{name}", getattr(self, name))


@dataclass(frozen=True, eq=False)
class _Cell:
    """What one run leaves for the grouping."""

    rms: float
    scale: float  #: amplitude scale A (m)
    pattern: str
    impacts_per_cycle: float
    period: int  #: 0: non-periodic
    centres: np.ndarray  #: (k, 2) W (m), W' (m/s); the last MAX_K samples if non-periodic
    strobe: np.ndarray  #: (n, 2) the kept Poincare samples


def basin_grid(name: str, spec) -> np.ndarray:
    try:
        lo, hi, n = spec
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {spec!r} must be (start, stop, count)") from None
    check_range(f"{name} start", lo, -math.inf, math.inf, lo_open=True, hi_open=True)
    check_range(f"{name} stop", hi, float(lo), math.inf, hi_open=True)
    if isinstance(n, bool) or not isinstance(n, int | np.integer):
        raise ParameterError(f"{name} count = {n!r} must be an integer in [1, "
                             f"{MAX_BASIN_CELLS}]")
    check_int(f"{name} count", n, 1, MAX_BASIN_CELLS)
    return np.linspace(float(lo), float(hi), int(n))


def check_cells(n_displacement: int, n_velocity: int,
                names: tuple[str, str] = ("displacement", "velocity")) -> int:
    """The cells of a basin grid, n_displacement x n_velocity: at most
    :data:`MAX_BASIN_CELLS`, else ParameterError naming both axes."""
    cells = int(n_displacement) * int(n_velocity)
    if cells > MAX_BASIN_CELLS:
        raise ParameterError(f"{names[0]} count = {n_displacement} x {names[1]} count = "
                             f"{n_velocity} is {cells} runs; the allowed maximum is "
                             f"{MAX_BASIN_CELLS} cells")
    return cells


def signature(strobe: np.ndarray, scale: float, omega: float,
              tol: float = BasinTolerance.period) -> tuple[int, np.ndarray]:
    """(k, centres) of the Poincare samples ``strobe`` ((n, 2): W, W').

    k = the smallest period 1..MAX_K with max |P[i + k] - P[i]| <= ``tol`` on the
    last TAIL samples, scaled by ``scale`` (W) and ``omega * scale`` (W'), repeated
    at least MIN_REPEATS times; centres = the k means of every k-th sample, sorted
    by (W, W').  k = 0 (non-periodic): centres = the last MAX_K samples.
    """
    tail = strobe[-TAIL:]
    p = tail / np.array([scale, omega * scale])
    for k in range(1, MAX_K + 1):
        if len(p) < (MIN_REPEATS + 1) * k:
            break
        if np.max(np.abs(p[k:] - p[:-k])) <= tol:
            n = len(tail) - len(tail) % k  # whole cycles, ending at the last sample
            cyc = tail[len(tail) - n:].reshape(-1, k, 2).mean(axis=0)
            return k, cyc[np.lexsort((cyc[:, 1], cyc[:, 0]))]
    return 0, tail[-MAX_K:].copy()


def basin_run(system: System, forcing: Harmonic, initial: Initial, duration: float, dt: float,
         drop: float, tol: BasinTolerance, integrator: str = "rk4") -> _Cell:
    run = simulate(system, forcing, duration=duration, dt=dt, initial=initial,
                   steady_fraction=1.0 - drop, strobe=True, integrator=integrator)
    return _cell(run, dt, tol)


def _run_batch(system: System, forcing: Harmonic, initials: list[Initial], duration: float,
               dt: float, drop: float, tol: BasinTolerance) -> list[_Cell]:
    """The cells of ``initials`` advanced in lock-step (RK4): each equals :func:`basin_run`'s."""
    runs = simulate_batch([(system, forcing, ini) for ini in initials], duration=duration,
                          dt=dt, steady_fraction=1.0 - drop, strobe=True)
    return [_cell(run, dt, tol) for run in runs]


def _cell(run, dt: float, tol: BasinTolerance) -> _Cell:
    keep = run.strobe[run.strobe[:, 0] >= run.steady_start - 0.5 * dt, 1:3]
    rms = run.rms_tip
    scale = max(math.sqrt(2.0) * rms, tol.floor) if math.isfinite(rms) else tol.floor
    k, centres = signature(keep, scale, run.omega, tol.period)
    p = run.pattern
    return _Cell(rms=rms, scale=scale, pattern="" if p is None else p.name,
                 impacts_per_cycle=math.nan if p is None else p.impacts_per_cycle,
                 period=k, centres=centres, strobe=keep)


def _hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    d = np.max(np.abs(a[:, None, :] - b[None, :, :]), axis=2)
    return float(max(d.min(axis=0).max(), d.min(axis=1).max()))


def _same(a: _Cell, b: _Cell, omega: float, tol: BasinTolerance) -> bool:
    """Two periodic runs on the same attractor (module doc, step 2)."""
    if a.pattern != b.pattern or a.period != b.period:
        return False
    drms = abs(a.rms - b.rms) / max(a.rms, b.rms, tol.floor)
    s = np.array([max(a.scale, b.scale), omega * max(a.scale, b.scale)])
    return drms <= tol.rms and _hausdorff(a.centres / s, b.centres / s) <= tol.match


def group(cells: list[_Cell], omega: float, tol: BasinTolerance) -> tuple[np.ndarray, list[int]]:
    """Attractor id per cell (ordered by basin size) and each attractor's leader cell."""
    label = np.full(len(cells), -1)
    leaders: list[int] = []
    for i, c in enumerate(cells):  # periodic: leader clustering in grid order
        if c.period == 0:
            continue
        for a, j in enumerate(leaders):
            if _same(c, cells[j], omega, tol):
                label[i] = a
                break
        else:
            label[i] = len(leaders)
            leaders.append(i)
    # non-periodic: per pattern, runs sorted by RMS split where two neighbours
    # differ by more than tol.nonperiodic_rms (single linkage: an RMS band)
    loose = [i for i, c in enumerate(cells) if c.period == 0]
    for pattern in sorted({cells[i].pattern for i in loose}):
        members = sorted((cells[i].rms, i) for i in loose if cells[i].pattern == pattern)
        band: list[int] = []
        for n, (rms, i) in enumerate(members):
            prev = members[n - 1][0] if n else None
            if band and abs(rms - prev) > tol.nonperiodic_rms * max(rms, prev, tol.floor):
                leaders.append(min(band))
                label[band] = len(leaders) - 1
                band = []
            band.append(i)
        leaders.append(min(band))
        label[band] = len(leaders) - 1
    counts = np.bincount(label, minlength=len(leaders))
    order = sorted(range(len(leaders)), key=lambda a: (-counts[a], leaders[a]))
    rank = np.empty(len(leaders), dtype=int)
    rank[order] = np.arange(len(leaders))
    return rank[label], [leaders[a] for a in order]


def basins(system: System, forcing: Harmonic, *, displacement=PUBLISHED_DISPLACEMENT,
           velocity=PUBLISHED_VELOCITY, duration: float = 2.0, dt: float = 1e-6,
           drop: float = 0.2, ball_position: float = 0.0, ball_velocity: float = 0.0,
           workers: int | None = None, progress=None,
           tol: BasinTolerance | None = None, integrator: str = "rk4", batch: int = BATCH):
    """Basins of attraction over initial tip displacement x tip velocity.

    ``displacement`` (m) and ``velocity`` (m/s): (start, stop, count), both ends
    included (published: -1.5..1.5 mm x -1.5..1.5 m/s, 30 x 30); each cell runs
    ``duration`` s with step ``dt`` s, the first ``drop`` of it dropped; the ball
    starts at ``ball_position`` (m) with relative velocity ``ball_velocity``
    (m/s).  ``workers``: threads (default: every core); ``progress(done, total)``
    is called as cells finish.  ``tol``: :class:`BasinTolerance`; the grouping is
    in the module docstring.  ``integrator``: "rk4" (published) or "exact".
    ``batch``: with "rk4", cells advanced together in lock-step
    (:func:`~boringbar.simulate.simulate_batch`, up to 16), taken in grid order
    so that a batch's cells do not depend on ``workers``; 1: one cell at a time.
    The results are the same, bit for bit, whatever ``batch`` and ``workers``.

    Returns an xarray Dataset with, per cell (dims displacement, velocity):
    ``attractor`` id, ``rms_tip_m``, ``pattern``, ``period`` (0: non-periodic),
    ``impacts_per_cycle`` and the final Poincare signature ``signature_tip_m``,
    ``signature_tip_velocity_m_s`` (dim point: the k centres, NaN beyond k; for a
    non-periodic run its last MAX_K samples); per
    attractor (dim attractor, ids ordered by basin size): ``fraction`` (sums to
    1), ``count``, ``pattern``, ``period``, ``rms_tip_m``, the representative's
    initial condition and its kept Poincare samples ``poincare_tip_m``,
    ``poincare_tip_velocity_m_s`` (dim sample).
    """
    import xarray as xr

    if not isinstance(system, System):
        raise ParameterError(f"system = {system!r} must be a System (see make_system)")
    if not isinstance(forcing, Harmonic):
        raise ParameterError(f"forcing = {forcing!r} must be a Harmonic (basins are of a "
                             "periodically forced system)")
    w0 = basin_grid("displacement", displacement)
    v0 = basin_grid("velocity", velocity)
    check_cells(len(w0), len(v0))
    check_positive("duration", duration, "s")
    check_range("drop", drop, 0.0, 1.0, hi_open=True)
    tol = BasinTolerance() if tol is None else tol
    if not isinstance(tol, BasinTolerance):
        raise ParameterError(f"tol = {tol!r} must be a BasinTolerance")
    workers = int(workers or os.cpu_count() or 1)
    check_range("workers", workers, 1, 4096)
    check_range("batch", batch, 1, BMAX)
    initials = [Initial(float(w), float(v), ball_position, ball_velocity)
                for w in w0 for v in v0]
    # validates everything else (dt, ball position) and warms the JIT before fanning out
    first = simulate(system, forcing, duration=min(duration, 50 * dt), dt=dt,
                     initial=initials[0], integrator=integrator)
    omega = first.omega
    batched = integrator == "rk4" and batch > 1
    if batched:  # the lock-step kernel of a full batch
        simulate_batch([(system, forcing, initials[0])] * min(batch, len(initials)),
                       duration=min(duration, 50 * dt), dt=dt)

    cells: list[_Cell | None] = [None] * len(initials)
    tic = time.perf_counter()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        if batched:
            futures = {pool.submit(_run_batch, system, forcing, initials[i:i + batch], duration,
                                   dt, drop, tol): i
                       for i in range(0, len(initials), batch)}
        else:
            futures = {pool.submit(basin_run, system, forcing, ini, duration, dt, drop, tol,
                                   integrator): i
                       for i, ini in enumerate(initials)}
        done = 0
        for fut in as_completed(futures):
            res = fut.result()
            res = res if isinstance(res, list) else [res]
            i = futures[fut]
            cells[i:i + len(res)] = res
            done += len(res)
            if progress is not None:
                progress(done, len(initials))
    wall = time.perf_counter() - tic
    label, leaders = group(cells, omega, tol)
    return basins_dataset(xr, system, forcing, w0, v0, cells, label, leaders, initials, {
        "dt_s": dt, "duration_s": duration, "drop": drop, "workers": workers,
        "wall_time_s": wall, "ball_position_m": ball_position,
        "ball_velocity_m_s": ball_velocity, "tolerances": json.dumps(asdict(tol)),
        "integrator": integrator, "batch": batch if batched else 1,
    })


def _padded(arrays: list[np.ndarray], n: int) -> np.ndarray:
    out = np.full((len(arrays), n, 2), np.nan)
    for i, a in enumerate(arrays):
        out[i, :len(a)] = a[:n]
    return out


def basins_dataset(xr, system, forcing, w0, v0, cells, label, leaders, initials, attrs):
    shape = (len(w0), len(v0))
    grid = ("displacement", "velocity")
    sig = _padded([c.centres for c in cells], MAX_K)
    sig = sig.reshape(*shape, MAX_K, 2)
    reps = [cells[j] for j in leaders]
    n_samples = max(len(c.strobe) for c in reps)
    poincare = _padded([c.strobe for c in reps], n_samples)
    counts = np.bincount(label, minlength=len(leaders))
    data = {
        "attractor": (grid, label.reshape(shape)),
        "rms_tip_m": (grid, np.array([c.rms for c in cells]).reshape(shape), {"units": "m"}),
        "pattern": (grid, np.array([c.pattern for c in cells], dtype=str).reshape(shape)),
        "period": (grid, np.array([c.period for c in cells]).reshape(shape),
                   {"long_name": "Poincare period in forcing periods; 0: non-periodic"}),
        "impacts_per_cycle": (grid, np.array([c.impacts_per_cycle for c in cells])
                              .reshape(shape)),
        "signature_tip_m": ((*grid, "point"), sig[..., 0], {"units": "m"}),
        "signature_tip_velocity_m_s": ((*grid, "point"), sig[..., 1], {"units": "m/s"}),
        "fraction": ("attractor_id", counts / len(cells)),
        "count": ("attractor_id", counts),
        "attractor_pattern": ("attractor_id", np.array([c.pattern for c in reps], dtype=str)),
        "attractor_period": ("attractor_id", np.array([c.period for c in reps])),
        "attractor_rms_tip_m": ("attractor_id", np.array([c.rms for c in reps]),
                                {"units": "m"}),
        "representative_tip_displacement_m": (
            "attractor_id", np.array([initials[j].tip_displacement for j in leaders]),
            {"units": "m"}),
        "representative_tip_velocity_m_s": (
            "attractor_id", np.array([initials[j].tip_velocity for j in leaders]),
            {"units": "m/s"}),
        "poincare_tip_m": (("attractor_id", "sample"), poincare[..., 0], {"units": "m"}),
        "poincare_tip_velocity_m_s": (("attractor_id", "sample"), poincare[..., 1],
                                      {"units": "m/s"}),
    }
    return xr.Dataset(
        data,
        coords={
            "displacement": ("displacement", w0, {"units": "m",
                                                  "long_name": "initial tip displacement"}),
            "velocity": ("velocity", v0, {"units": "m/s", "long_name": "initial tip velocity"}),
            "attractor_id": np.arange(len(leaders)),
        },
        attrs={
            "title": "boringbar basins of attraction",
            "boringbar_version": __version__,
            "preset": system.preset,
            "system": json.dumps(system.to_dict()),
            "forcing": json.dumps(forcing.to_dict()),
            "grouping": "Poincare period and centres (Hausdorff, scaled by sqrt(2) RMS) + "
                        "impact pattern + RMS; non-periodic runs by pattern + RMS band; "
                        "mirrored orbit pairs are distinct attractors",
            **attrs,
        },
    )


def basin_summary(ds) -> dict:
    """JSON-able summary of :func:`basins` (attractors largest basin first)."""
    attractors = []
    for a in ds["attractor_id"].values:
        k = int(ds["attractor_period"].values[a])
        pts = []
        if k:
            cell = np.argwhere(ds["attractor"].values == a)[0]
            w = ds["signature_tip_m"].values[cell[0], cell[1], :k]
            v = ds["signature_tip_velocity_m_s"].values[cell[0], cell[1], :k]
            pts = [[float(x), float(y)] for x, y in zip(w, v, strict=True)]
        attractors.append({
            "id": int(a),
            "fraction": float(ds["fraction"].values[a]),
            "count": int(ds["count"].values[a]),
            "pattern": str(ds["attractor_pattern"].values[a]),
            "periodic": bool(k),
            "period": k,
            "rms_tip_m": float(ds["attractor_rms_tip_m"].values[a]),
            "poincare_centres": pts,
            "representative": {
                "tip_displacement_m": float(ds["representative_tip_displacement_m"].values[a]),
                "tip_velocity_m_s": float(ds["representative_tip_velocity_m_s"].values[a]),
            },
        })
    return {
        "preset": ds.attrs.get("preset"),
        "forcing": json.loads(ds.attrs["forcing"]),
        "grid": {"displacement_m": [float(ds["displacement"].values[0]),
                                    float(ds["displacement"].values[-1]),
                                    int(ds.sizes["displacement"])],
                 "velocity_m_s": [float(ds["velocity"].values[0]),
                                  float(ds["velocity"].values[-1]), int(ds.sizes["velocity"])]},
        "duration_s": ds.attrs.get("duration_s"),
        "workers": ds.attrs.get("workers"),
        "wall_time_s": ds.attrs.get("wall_time_s"),
        "attractors": attractors,
    }
