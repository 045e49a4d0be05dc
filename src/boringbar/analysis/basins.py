"""Basins of attraction over a grid of initial conditions (docs/model.md, section 6).

Every cell of an initial tip displacement x initial tip velocity grid is an
independent run of the kernel (the ball starts at ``ball_position_m`` with
relative velocity ``ball_velocity_m_s``, by default at rest and centred, as
published).  With the published RK4 scheme the cells advance in lock-step
batches of ``BATCH`` consecutive cells in grid order
(:func:`~boringbar.simulate.simulate_batch`, whose runs equal single runs bit
for bit); batches (or single cells) are the points of the plan (the contract:
:mod:`boringbar.analysis.base`), run on an executor (default: a thread per
core; the kernel releases the GIL) and assembled in order, so serial,
parallel and unbatched runs give bit-identical results.  The end states are then
grouped into attractors, serially, in grid order.

Grouping (all tolerances in :class:`BasinTolerance`):

1. **Signature of a run.**  The stroboscopic Poincare samples (W, W') at
   Omega t = 0 mod 2 pi of the run's steady part (the last
   ``Integration.steady_fraction`` of it) are
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
import sys
from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from boringbar._validate import ParameterError, check_int, check_positive, check_range
from boringbar.analysis.base import Plan, execution_attrs, run_plan
from boringbar.analysis.cases import Case
from boringbar.analysis.poincare import poincare_map
from boringbar.execute import Execution
from boringbar.model.forcing import Harmonic
from boringbar.model.system import System
from boringbar.simulate import (
    Initial,
    Integration,
    resolve_integrator,
    resolved_integrators,
    simulate,
    simulate_batch,
)
from boringbar.simulate.kernels import BMAX
from boringbar.simulate.run_limits import check_steady_ratios
from boringbar.version import __version__

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
GROUPING = ("Poincare period and centres (Hausdorff, scaled by sqrt(2) RMS) + impact pattern + "
            "RMS; non-periodic runs by pattern + RMS band; mirrored orbit pairs are distinct "
            "attractors")


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
                names: tuple[str, str] = ("displacement_m", "velocity_m_s")) -> int:
    """The cells of a basin grid, n_displacement x n_velocity: at most
    :data:`MAX_BASIN_CELLS`, else ParameterError naming both axes."""
    cells = int(n_displacement) * int(n_velocity)
    if cells > MAX_BASIN_CELLS:
        raise ParameterError(f"{names[0]} count = {n_displacement} x {names[1]} count = "
                             f"{n_velocity} is {cells} runs; the allowed maximum is "
                             f"{MAX_BASIN_CELLS} cells")
    return cells


@dataclass(frozen=True)
class BasinOptions:
    """A basin map's grid and how its cells are judged.

    ``displacement_m`` (m) and ``velocity_m_s`` (m/s): initial tip displacement
    and velocity, (start, stop, count), both ends included (published: -1.5..1.5
    mm x -1.5..1.5 m/s, 30 x 30); the ball starts at ``ball_position_m`` (m) with
    relative velocity ``ball_velocity_m_s`` (m/s); the forcing F0 = ``force_n`` (N)
    at ``ratio`` (Omega/omega_n); ``tolerance``: :class:`BasinTolerance` of the
    grouping; ``batch``: with the RK4 integrator, cells advanced together in
    lock-step (up to 16), taken in grid order (1: one cell at a time; the results
    are the same, bit for bit); ``poincare_from``: (W0 (m), W0' (m/s)) of a run
    whose Poincare map :func:`basins` adds (:func:`with_poincare`), or None.
    """

    displacement_m: tuple = PUBLISHED_DISPLACEMENT
    velocity_m_s: tuple = PUBLISHED_VELOCITY
    ball_position_m: float = 0.0
    ball_velocity_m_s: float = 0.0
    force_n: float = 10.0
    ratio: float = 1.0
    tolerance: BasinTolerance = BasinTolerance()
    batch: int = BATCH
    poincare_from: tuple[float, float] | None = None

    def __post_init__(self):
        check_cells(len(basin_grid("displacement_m", self.displacement_m)),
                    len(basin_grid("velocity_m_s", self.velocity_m_s)),
                    ("displacement_m", "velocity_m_s"))
        check_range("ball_position_m", self.ball_position_m, -math.inf, math.inf,
                    lo_open=True, hi_open=True, unit="m")
        check_range("ball_velocity_m_s", self.ball_velocity_m_s, -math.inf, math.inf,
                    lo_open=True, hi_open=True, unit="m/s")
        check_range("force_n", self.force_n, 0.0, math.inf, hi_open=True, unit="N")
        check_range("ratio", self.ratio, 0.0, math.inf, lo_open=True, hi_open=True)
        if not isinstance(self.tolerance, BasinTolerance):
            raise ParameterError(f"tolerance = {self.tolerance!r} must be a BasinTolerance")
        check_range("batch", self.batch, 1, BMAX)
        if self.poincare_from is not None:
            try:
                w0, v0 = self.poincare_from
            except (TypeError, ValueError):
                raise ParameterError(f"poincare_from = {self.poincare_from!r} must be "
                                     "(W0 (m), W0' (m/s))") from None
            check_range("poincare_from W0", w0, -math.inf, math.inf, lo_open=True,
                        hi_open=True, unit="m")
            check_range("poincare_from W0'", v0, -math.inf, math.inf, lo_open=True,
                        hi_open=True, unit="m/s")

    @property
    def forcing(self) -> Harmonic:
        return Harmonic(self.force_n, self.ratio)

    def initials(self) -> list[Initial]:
        """The initial conditions of the cells, in grid order (displacement-major)."""
        return [Initial(float(w), float(v), self.ball_position_m, self.ball_velocity_m_s)
                for w in basin_grid("displacement_m", self.displacement_m)
                for v in basin_grid("velocity_m_s", self.velocity_m_s)]


@dataclass(frozen=True, eq=False)
class OperatingPoint:
    """One basin map of several (a study's grid): ``label``, the ``case``
    (:class:`~boringbar.analysis.cases.Case`) and its ``forcing``."""

    label: str
    case: Case
    forcing: Harmonic


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


def _cell(run, dt: float, tol: BasinTolerance) -> _Cell:
    keep = run.strobe[run.strobe[:, 0] >= run.steady_start_s - 0.5 * dt, 1:3]
    rms = run.rms_tip_m
    scale = max(math.sqrt(2.0) * rms, tol.floor) if math.isfinite(rms) else tol.floor
    k, centres = signature(keep, scale, run.omega_rad_s, tol.period)
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


def plan(system, options: BasinOptions, integration: Integration) -> Plan:
    """Every cell of every operating point (``system``: a System under
    ``options.forcing``, or a list of :class:`OperatingPoint`); a point is
    (operating point index, [cell indices]): a lock-step batch of ``options.batch``
    consecutive cells in grid order (RK4) or one cell."""
    integration = integration.with_step()
    if isinstance(system, list | tuple):
        operating = list(system)
    elif isinstance(system, System):
        operating = [OperatingPoint("", Case.of(system), options.forcing)]
    else:
        raise ParameterError(f"system = {system!r} must be a System (see make_system)")
    if not operating:
        raise ParameterError("basins needs at least one operating point")
    for op in operating:  # a steady part of one forcing period at least
        check_steady_ratios(op.case.system, (op.forcing.ratio,), integration.duration_s,
                            integration.steady_fraction, "Integration.duration_s")
    initials = options.initials()
    batched = [options.batch > 1 and resolve_integrator(
        integration.integrator, op.case.system) == "rk4" for op in operating]
    points = [(i, list(range(a, min(a + size, len(initials)))))
              for i, size in enumerate(options.batch if b else 1 for b in batched)
              for a in range(0, len(initials), size)]
    context = {"operating": operating, "options": options, "integration": integration,
               "batched": batched, "initials": initials,
               "w0": basin_grid("displacement_m", options.displacement_m),
               "v0": basin_grid("velocity_m_s", options.velocity_m_s)}
    return Plan(context, points)


def compute(context: dict, point: tuple[int, list[int]]) -> list[_Cell]:
    """The cells of one point (a lock-step batch, or one cell), in grid order."""
    op = context["operating"][point[0]]
    integ, tol = context["integration"], context["options"].tolerance
    initials = [context["initials"][j] for j in point[1]]
    if context["batched"][point[0]]:
        runs = simulate_batch([(op.case.system, op.forcing, ini) for ini in initials],
                              duration_s=integ.duration_s, dt_s=integ.dt_s,
                              steady_fraction=integ.steady_fraction, strobe=True,
                              stick_law=integ.stick_law)
    else:
        runs = [simulate(op.case.system, op.forcing, **{**integ.kwargs(), "initial": ini},
                         strobe=True) for ini in initials]
    return [_cell(run, integ.dt_s, tol) for run in runs]


def _padded(arrays: list[np.ndarray], n: int) -> np.ndarray:
    out = np.full((len(arrays), n, 2), np.nan)
    for i, a in enumerate(arrays):
        out[i, :len(a)] = a[:n]
    return out


def _dataset(system: System, forcing: Harmonic, cells: list[_Cell], context: dict,
             attrs: dict):
    """The Dataset of one operating point's cells (grid order), grouped."""
    o = context["options"]
    w0, v0, initials = context["w0"], context["v0"], context["initials"]
    label, leaders = group(cells, forcing.omega(system.reference_frequency_rad_s), o.tolerance)
    shape = (len(w0), len(v0))
    grid = ("displacement_m", "velocity_m_s")
    sig = _padded([c.centres for c in cells], MAX_K).reshape(*shape, MAX_K, 2)
    reps = [cells[j] for j in leaders]
    poincare = _padded([c.strobe for c in reps], max(len(c.strobe) for c in reps))
    counts = np.bincount(label, minlength=len(leaders))
    per_cell = lambda f: np.array([f(c) for c in cells]).reshape(shape)  # noqa: E731
    data = {
        "attractor": (grid, label.reshape(shape)),
        "rms_tip_m": (grid, per_cell(lambda c: c.rms), {"units": "m"}),
        "pattern": (grid, np.array([c.pattern for c in cells], dtype=str).reshape(shape)),
        "period": (grid, per_cell(lambda c: c.period),
                   {"long_name": "Poincare period in forcing periods; 0: non-periodic"}),
        "impacts_per_cycle": (grid, per_cell(lambda c: c.impacts_per_cycle)),
        "signature_tip_m": ((*grid, "point"), sig[..., 0], {"units": "m"}),
        "signature_tip_velocity_m_s": ((*grid, "point"), sig[..., 1], {"units": "m/s"}),
        "fraction": ("attractor_id", counts / len(cells)),
        "count": ("attractor_id", counts),
        "attractor_pattern": ("attractor_id", np.array([c.pattern for c in reps], dtype=str)),
        "attractor_period": ("attractor_id", np.array([c.period for c in reps])),
        "attractor_rms_tip_m": ("attractor_id", np.array([c.rms for c in reps]),
                                {"units": "m"}),
        "representative_tip_displacement_m": (
            "attractor_id", np.array([initials[j].tip_displacement_m for j in leaders]),
            {"units": "m"}),
        "representative_tip_velocity_m_s": (
            "attractor_id", np.array([initials[j].tip_velocity_m_s for j in leaders]),
            {"units": "m/s"}),
        "poincare_tip_m": (("attractor_id", "sample"), poincare[..., 0], {"units": "m"}),
        "poincare_tip_velocity_m_s": (("attractor_id", "sample"), poincare[..., 1],
                                      {"units": "m/s"}),
    }
    coords = {
        "displacement_m": ("displacement_m", w0, {"units": "m",
                                              "long_name": "initial tip displacement"}),
        "velocity_m_s": ("velocity_m_s", v0, {"units": "m/s",
                                              "long_name": "initial tip velocity"}),
        "attractor_id": np.arange(len(leaders)),
    }
    return xr.Dataset(data, coords=coords, attrs={
        "title": "boringbar basins of attraction", "boringbar_version": __version__,
        "preset": system.preset, "system": json.dumps(system.to_dict()),
        "forcing": json.dumps(forcing.to_dict()), "grouping": GROUPING, **attrs})


def _stack(parts: list, context: dict):
    """Basin Datasets of several operating points along a leading ``case`` dim, the
    attractors of each padded to the largest count (``count`` 0, ``attractor_period``
    -1, NaN and "" beyond its own)."""
    n_att = max(p.sizes["attractor_id"] for p in parts)
    n_sample = max(p.sizes["sample"] for p in parts)
    fill = {"count": 0, "attractor_period": -1, "attractor_pattern": ""}
    padded = []
    for p in parts:
        attrs = {k: p[k].attrs for k in p.variables}
        p = p.reindex(attractor_id=np.arange(n_att), fill_value=fill)
        p = p.pad(sample=(0, n_sample - p.sizes["sample"]))
        for k, a in attrs.items():
            p[k].attrs = a
        padded.append(p)
    ds = xr.concat(padded, dim="case", data_vars="all", coords="minimal",
                   compat="override", combine_attrs="drop")
    ops = context["operating"]
    ds = ds.assign_coords({
        "case": [op.label for op in ops],
        "bar": ("case", [op.case.bar for op in ops]),
        "gap_m": ("case", np.array([op.case.gap_m for op in ops]), {"units": "m"}),
        "friction": ("case", [op.case.friction for op in ops]),
        "force_n": ("case", np.array([op.forcing.amplitude_n for op in ops]), {"units": "N"}),
        "ratio": ("case", np.array([op.forcing.ratio for op in ops])),
    })
    ds.attrs = {k: v for k, v in parts[0].attrs.items() if k not in ("system", "forcing")}
    ds.attrs["systems"] = json.dumps({op.label: op.case.system.to_dict() for op in ops})
    ds.attrs["forcings"] = json.dumps({op.label: op.forcing.to_dict() for op in ops})
    return ds


def assemble(plan: Plan, results: list[list[_Cell]], attrs: dict | None = None):
    """The basins Dataset of the one operating point, or (several) theirs stacked along
    ``case`` (:func:`_stack`); ``attrs`` go after the configuration's."""
    ctx = plan.context
    o, integ = ctx["options"], ctx["integration"]
    cells: dict[int, list[_Cell]] = {}
    for (op, _), res in zip(plan.points, results, strict=True):
        cells.setdefault(op, []).extend(res)
    config = {"dt_s": integ.dt_s, "duration_s": integ.duration_s,
              "steady_fraction": integ.steady_fraction, "ball_position_m": o.ball_position_m,
              "ball_velocity_m_s": o.ball_velocity_m_s,
              "tolerances": json.dumps(asdict(o.tolerance)), "integrator": integ.integrator,
              "integrator_used": resolved_integrators(
                  integ.integrator, [op.case.system for op in ctx["operating"]]),
              "batch": o.batch if any(ctx["batched"]) else 1, **(attrs or {})}
    parts = [_dataset(op.case.system, op.forcing, cells[i], ctx, config)
             for i, op in enumerate(ctx["operating"])]
    return parts[0] if len(parts) == 1 else _stack(parts, ctx)


def basins(system: System, options: BasinOptions | None = None, *,
           integration: Integration | None = None, execution: Execution | None = None,
           progress=None):
    """Basins of attraction over initial tip displacement x tip velocity.

    ``system`` under F0 sin(Omega t) (``options.force_n``, ``options.ratio``);
    ``options``: :class:`BasinOptions` (the grid, the ball's start, the
    tolerances of the grouping (module docstring), the lock-step batch, and
    ``poincare_from``); ``integration``: each cell's duration, step, integrator and
    steady window (``steady_fraction``: the kept last part of each run; its
    ``initial`` is not used, the grid sets it); ``execution``: where the points
    (lock-step batches of cells, or cells) run; ``progress(done, total)`` as they
    finish.  The results are the same, bit for bit, whatever the batch, the
    executor and its workers.

    Returns an xarray Dataset with, per cell (dims displacement_m, velocity_m_s):
    ``attractor`` id, ``rms_tip_m``, ``pattern``, ``period`` (0: non-periodic),
    ``impacts_per_cycle`` and the final Poincare signature ``signature_tip_m``,
    ``signature_tip_velocity_m_s`` (dim point: the k centres, NaN beyond k; for a
    non-periodic run its last MAX_K samples); per
    attractor (dim attractor, ids ordered by basin size): ``fraction`` (sums to
    1), ``count``, ``pattern``, ``period``, ``rms_tip_m``, the representative's
    initial condition and its kept Poincare samples ``poincare_tip_m``,
    ``poincare_tip_velocity_m_s`` (dim sample); with ``options.poincare_from``,
    :func:`with_poincare`'s variables.
    """
    options = options or BasinOptions()
    integration = integration or Integration()
    p = plan(system, options, integration)
    results, wall = run_plan(sys.modules[__name__], p, execution, progress)
    ds = assemble(p, results, execution_attrs(execution, wall))
    if options.poincare_from is None:
        return ds
    w0, v0 = options.poincare_from
    return with_poincare(ds, system, options.forcing,
                         Initial(w0, v0, options.ball_position_m, options.ball_velocity_m_s),
                         integration)


def with_poincare(ds, system: System, forcing: Harmonic, initial: Initial,
                  integration: Integration | None = None):
    """``ds`` with the stroboscopic Poincare map of one run of ``system`` under
    ``forcing`` from ``initial`` (the samples of its steady part): the variables
    ``poincare_from_tip_m``, ``poincare_from_tip_velocity_m_s`` (dim
    poincare_sample) and, as JSON in the attribute ``poincare_from``, its initial
    condition, verdict, period, distinct points, samples, RMS and pattern."""
    integration = integration or Integration()
    run = simulate(system, forcing, **{**integration.kwargs(), "initial": initial},
                   strobe=True)
    pm = poincare_map(run, integration.steady_fraction)
    verdict = pm.classify()
    ds = ds.assign(
        poincare_from_tip_m=("poincare_sample", pm.tip_displacement,
                             {"units": "m", "long_name": "W at Omega t = 0 mod 2 pi, from "
                                                         "poincare_from"}),
        poincare_from_tip_velocity_m_s=("poincare_sample", pm.tip_velocity,
                                        {"units": "m/s", "long_name": "W' at Omega t = 0 mod "
                                                                      "2 pi, from "
                                                                      "poincare_from"}))
    poincare = {"tip_displacement_m": float(initial.tip_displacement_m),
                "tip_velocity_m_s": float(initial.tip_velocity_m_s),
                "ball_position_m": float(initial.ball_position_m),
                "ball_velocity_m_s": float(initial.ball_velocity_m_s),
                "verdict": verdict["verdict"], "period": int(verdict["k"]),
                "distinct": int(verdict["distinct"]), "n_samples": len(pm.time),
                "rms_tip_m": float(run.rms_tip_m),
                "pattern": "" if run.pattern is None else run.pattern.name}
    ds.attrs["poincare_from"] = json.dumps(poincare)
    return ds


def summary(ds) -> dict:
    """JSON-able summary of :func:`basins` (attractors largest basin first; the
    :func:`with_poincare` run where there is one)."""
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
        "grid": {"displacement_m": [float(ds["displacement_m"].values[0]),
                                    float(ds["displacement_m"].values[-1]),
                                    int(ds.sizes["displacement_m"])],
                 "velocity_m_s": [float(ds["velocity_m_s"].values[0]),
                                  float(ds["velocity_m_s"].values[-1]),
                                  int(ds.sizes["velocity_m_s"])]},
        "duration_s": ds.attrs.get("duration_s"),
        "workers": ds.attrs.get("workers"),
        "wall_time_s": ds.attrs.get("wall_time_s"),
        "attractors": attractors,
        "poincare_from": json.loads(ds.attrs["poincare_from"]) if "poincare_from" in ds.attrs
        else None,
    }
