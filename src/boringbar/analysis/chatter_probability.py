"""The chance of chatter: stability lobes over draws of what nobody measures well
(docs/chatter_probability.md).

A lobe study given an :class:`Uncertainty` (``LobesOptions(uncertainty=...)``) runs,
beside the deterministic lobes of the nominal bars, every (case, speed) column once
per draw d = 0 .. draws - 1 on a drawn bar and cut:

- each mode's stiffness K_i and damping ratio zeta_i times a lognormal factor of median
  1 and the given coefficient of variation (``stiffness_cov``, ``damping_cov``);
- a free or locked ball's friction force F_c uniform on ``friction_force_n`` (N) or on
  its nominal value times 1 +- ``friction_spread``, its restitution uniform on
  ``restitution`` or on its nominal value +- ``restitution_spread`` (within [0, 1]);
- a free ball's start uniform across its gap (``ball_start``:
  :attr:`~boringbar.analysis.verdict.VerdictOptions.ball_start`);
- with ``force_noise`` > 0, the cut's multiplicative force noise of that relative
  standard deviation, its stream ``noise_seed`` drawn too.

Draw d is a function of (``seed``, d) alone: each quantity has its own numpy stream
``default_rng([seed, d, stream])``, so a draw is the same whatever the bar, the speed,
the executor or the other quantities drawn.  Each draw's chatter-free depth at each
speed comes from a search over the lobes' depth grid, by their rule for the limit
(:func:`~boringbar.analysis.lobe_search.free_limit`):

- a bar without a free ball: the onset's search (:func:`~boringbar.analysis.
  lobe_search.growth_column`), seeded at the analytic limit of the drawn linear host;
- a free ball: one search on whether a cut is chatter-free (:func:`~boringbar.analysis.
  lobe_search.free_column`), which needs no onset of its own;
- a noisy cut, which has no growth rate to find (its noise keeps every mode vibrating):
  a search on the settled vibration alone (:func:`~boringbar.analysis.lobe_search.
  verdict_column`).

The draws of one speed run in blocks of :data:`DRAW_BLOCK`, in order, so that a ball's or
a noisy cut's search can start where the block's draws before it found their limits (the
median; the first draw of a block at the host's limit).  The seed decides only where a
search starts: where a draw's stability is monotone in depth, as the search assumes, it
finds the same limit from any seed (where it is not, one of the column's boundaries:
docs/chatter_probability.md).

P(chatter) at depth b is estimated by the fraction of draws whose chatter-free depth is
below b (:func:`chatter_probability`).  This is the right estimator because each draw's
stability is monotone in depth, as the search assumes: a draw chatters at b exactly when
its limit is below b, so the count is binomial with P(chatter at b) as its probability.
Its 95 % interval is Wilson's score interval (:func:`wilson_interval`).  The contour
P = q is the deepest cut whose estimate is at most q (:func:`limit_quantiles`, an order
statistic of the drawn limits), and the robust depth at ``probability`` p is that
contour for q = p.
"""

from __future__ import annotations

import json
import math
import statistics
from dataclasses import dataclass, replace

import numpy as np

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.cases import Case
from boringbar.analysis.design_interval import wilson
from boringbar.analysis.lobe_search import (
    BALL_STEP,
    free_column,
    free_limit,
    growth_column,
    verdict_column,
)
from boringbar.model.forcing import MAX_NOISE_SEED, MAX_NOISE_STD
from boringbar.model.perturb import perturbed
from boringbar.model.system import System
from boringbar.reference.stability import limit_at_speeds

#: Draws by default: 32 give P(chatter) to about +-0.17 (Wilson's 95 % half-width at
#: P = 0.5); the contours at 5 % and 95 % are then the 2nd and 31st drawn limits.
DRAWS = 32
MAX_DRAWS = 100_000
#: Coefficient of variation of each mode's stiffness (assumption: a bar's clamping
#: changes its first frequency by a few per cent from one set-up to the next, and K ~ f^2).
STIFFNESS_COV = 0.03
#: Coefficient of variation of each mode's damping ratio (assumption: damping ratios
#: fitted to repeated tap tests scatter by tens of per cent).
DAMPING_COV = 0.2
#: Relative half-width of the ball's friction force (assumption: a rolling-resistance
#: length is known to a factor of about 2).
FRICTION_SPREAD = 0.5
#: Half-width of the ball's restitution (assumption: carbide on steel, 0.6-0.8).
RESTITUTION_SPREAD = 0.1
#: Relative standard deviation of the cutting force's noise: none by default (a noisy
#: cut is judged by its settled vibration, which costs some fifty times a quiet cut's
#: verdict and can pass a slow growth for settled: docs/chatter_probability.md);
#: 0.04-0.09 is what Fodor, Sykora and Bachrathy (Int J Adv Manuf Technol 2020,
#: doi:10.1007/s00170-020-05877-8) measured in orthogonal turning.
FORCE_NOISE = 0.0
#: The chance of chatter a robust depth allows.
PROBABILITY = 0.05
#: The contours P(chatter) = 5, 50 and 95 %.
QUANTILES = (0.05, 0.5, 0.95)
#: The confidence of P(chatter)'s Wilson interval.
WILSON_LEVEL = 0.95
#: The stream of each drawn quantity (:meth:`Uncertainty.draw`).
STREAMS = {"stiffness": 0, "damping": 1, "friction": 2, "restitution": 3, "ball_start": 4,
           "noise_seed": 5}
#: Draws of one speed run in order as one point (module doc): the block's later searches
#: start at the limits found before them.  Eight keep a speed's draws on several cores.
DRAW_BLOCK = 8
#: The first step (grid depths, 1 % each by default) of a search started at the block's
#: median limit: the drawn limits of a speed scatter by some tens of per cent.
SEEDED_STEP = 4


@dataclass(frozen=True)
class Draw:
    """One draw (:meth:`Uncertainty.draw`): the factors on each mode's stiffness and
    damping ratio, the ball's friction and restitution as uniform numbers ``friction_u``
    and ``restitution_u`` in [0, 1) (the system maps them to its own range), the ball's
    start ``ball_start`` (a fraction of the half gap, None: not drawn) and the force
    noise's ``noise_seed``."""

    index: int
    stiffness_scale: tuple[float, ...]
    damping_scale: tuple[float, ...]
    friction_u: float
    restitution_u: float
    ball_start: float | None
    noise_seed: int


@dataclass(frozen=True)
class Uncertainty:
    """What nobody measures well, as ``draws`` draws from ``seed`` (module doc).

    ``stiffness_cov``, ``damping_cov``: coefficient of variation (>= 0) of each mode's
    stiffness and damping ratio (lognormal factors of median 1); ``friction_force_n``:
    a ball's friction force F_c uniform on (low, high) N, or, None, on its nominal value
    times 1 +- ``friction_spread`` (in [0, 1]); ``restitution``: a ball's restitution
    uniform on (low, high), or, None, on its nominal value +- ``restitution_spread``
    (in [0, 1]); ``ball_start``: a free ball starts anywhere across its gap (False: where
    the verdict says); ``force_noise``: the cut's relative force noise (in [0, 1)); and
    ``probability``: the chance of chatter a robust depth allows (in (0, 1)).  Defaults
    and their sources: the module's constants (docs/chatter_probability.md).
    """

    draws: int = DRAWS
    seed: int = 0
    stiffness_cov: float = STIFFNESS_COV
    damping_cov: float = DAMPING_COV
    friction_spread: float | None = None
    friction_force_n: tuple[float, float] | None = None
    restitution_spread: float | None = None
    restitution: tuple[float, float] | None = None
    ball_start: bool = True
    force_noise: float = FORCE_NOISE
    probability: float = PROBABILITY

    def __post_init__(self):
        object.__setattr__(self, "draws", check_int("draws", self.draws, 1, MAX_DRAWS))
        object.__setattr__(self, "seed", check_int("seed", self.seed, 0, 2**63 - 1))
        check_range("stiffness_cov", self.stiffness_cov, 0.0, 1.0)
        check_range("damping_cov", self.damping_cov, 0.0, 10.0)
        object.__setattr__(self, "friction_spread", _spread(
            "friction_spread", self.friction_spread, "friction_force_n", self.friction_force_n,
            FRICTION_SPREAD))
        object.__setattr__(self, "restitution_spread", _spread(
            "restitution_spread", self.restitution_spread, "restitution", self.restitution,
            RESTITUTION_SPREAD))
        if self.friction_force_n is not None:
            object.__setattr__(self, "friction_force_n", _bounds(
                "friction_force_n", self.friction_force_n, math.inf, "N"))
        if self.restitution is not None:
            object.__setattr__(self, "restitution", _bounds("restitution", self.restitution,
                                                            1.0))
        if not isinstance(self.ball_start, bool):
            raise ParameterError(f"ball_start = {self.ball_start!r} must be True or False")
        check_range("force_noise", self.force_noise, 0.0, MAX_NOISE_STD, hi_open=True)
        check_range("probability", self.probability, 0.0, 1.0, lo_open=True, hi_open=True)

    def draw(self, index: int, n_modes: int) -> Draw:
        """Draw ``index`` for a bar of ``n_modes`` modes: a function of (seed, index)
        alone, each quantity from its own stream (a mode's factor does not depend on how
        many modes the bar keeps)."""
        check_int("draw index", index, 0, self.draws - 1)

        def rng(name: str) -> np.random.Generator:
            return np.random.default_rng([self.seed, index, STREAMS[name]])

        return Draw(index, _lognormal(rng("stiffness"), self.stiffness_cov, n_modes),
                    _lognormal(rng("damping"), self.damping_cov, n_modes),
                    float(rng("friction").random()), float(rng("restitution").random()),
                    float(rng("ball_start").uniform(-1.0, 1.0)) if self.ball_start else None,
                    int(rng("noise_seed").integers(0, MAX_NOISE_SEED)))

    def to_dict(self) -> dict:
        return {"draws": self.draws, "seed": self.seed, "stiffness_cov": self.stiffness_cov,
                "damping_cov": self.damping_cov, "friction_spread": self.friction_spread,
                "friction_force_n": None if self.friction_force_n is None
                else list(self.friction_force_n),
                "restitution_spread": self.restitution_spread,
                "restitution": None if self.restitution is None else list(self.restitution),
                "ball_start": self.ball_start, "force_noise": self.force_noise,
                "probability": self.probability}


def _spread(name: str, spread, range_name: str, bounds, default: float) -> float:
    """A relative spread in [0, 1], its default, or 0 where the range ``bounds`` is given
    instead (both given: a ParameterError)."""
    if bounds is not None:
        if spread is not None:
            raise ParameterError(f"{name} = {spread!r} and {range_name} = {bounds!r}: give "
                                 "one, a spread about the nominal value or a range")
        return 0.0
    return check_range(name, default if spread is None else spread, 0.0, 1.0)


def _bounds(name: str, bounds, hi: float, unit: str = "") -> tuple[float, float]:
    """(low, high) with 0 <= low <= high <= ``hi``."""
    if isinstance(bounds, str) or len(tuple(bounds)) != 2:
        raise ParameterError(f"{name} = {bounds!r} must be (low, high)")
    low, high = (float(v) for v in bounds)
    check_range(f"{name} low", low, 0.0, hi, unit=unit)
    check_range(f"{name} high", high, low, hi, unit=unit)
    return low, high


def _lognormal(rng: np.random.Generator, cov: float, n: int) -> tuple[float, ...]:
    """``n`` lognormal factors of median 1 and coefficient of variation ``cov``."""
    sigma = math.sqrt(math.log1p(cov * cov))
    return tuple(float(v) for v in np.exp(sigma * rng.standard_normal(n)))


def drawn_system(system: System, draw: Draw, uncertainty: Uncertainty) -> System:
    """``system`` as ``draw`` makes it (module doc): its modes, and a ball's friction and
    restitution (a bar without a ball has none to draw)."""
    ball = system.damper if system.kind in ("ball", "locked") else None
    friction, restitution = {}, {}
    if ball is not None:
        u = uncertainty
        if u.friction_force_n is not None:
            lo, hi = u.friction_force_n
            friction = {"friction_force_n": lo + (hi - lo) * draw.friction_u}
        else:
            friction = {"friction_scale": 1.0 + u.friction_spread * (2 * draw.friction_u - 1)}
        lo, hi = u.restitution or (ball.restitution - u.restitution_spread,
                                   ball.restitution + u.restitution_spread)
        restitution = {"restitution": lo + (hi - lo) * draw.restitution_u}
    return perturbed(system, stiffness_scale=draw.stiffness_scale,
                     damping_scale=draw.damping_scale, **friction, **restitution)


@dataclass(frozen=True)
class DrawnOptions:
    """A lobe study's options as one draw cuts: the study's ``options``, with every cut
    carrying the draw's ``force_noise`` and ``noise_seed`` (what
    :func:`~boringbar.analysis.lobe_search.growth_cut` reads of them is the study's
    otherwise)."""

    options: object
    force_noise: float
    noise_seed: int

    def __getattr__(self, name: str):
        if name == "options":  # not yet set (unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.options, name)

    def forcing(self, depth_m: float, rpm: float, stop_at_zero: bool = True):
        """The study's cut at ``depth_m`` (m) and ``rpm``, with the draw's noise."""
        return replace(self.options.forcing(depth_m, rpm, stop_at_zero),
                       force_noise=self.force_noise, noise_seed=self.noise_seed)


def drawn_options(options, draw: Draw, uncertainty: Uncertainty, system: System):
    """The lobe ``options`` a draw cuts with: a free ball's start across its gap, and the
    force noise (:class:`DrawnOptions`) when there is any."""
    if draw.ball_start is not None and system.kind == "ball":
        options = replace(options, verdict=replace(options.verdict, ball_start=draw.ball_start))
    if uncertainty.force_noise > 0:
        return DrawnOptions(options, uncertainty.force_noise, draw.noise_seed)
    return options


def check(uncertainty, criterion: str | None) -> None:
    """A lobe study's ``uncertainty`` (None or an :class:`Uncertainty`) with its
    ``criterion``: draws are judged by the converged verdict alone."""
    if uncertainty is None:
        return
    if not isinstance(uncertainty, Uncertainty):
        raise ParameterError(f"uncertainty = {uncertainty!r} must be an Uncertainty")
    if criterion not in (None, "growth"):
        raise ParameterError(f"criterion = {criterion!r} with an uncertainty: the chance of "
                             "chatter is found by the converged verdict alone; use criterion "
                             "'growth'")


def points(n_cases: int, n_rpm: int, uncertainty: Uncertainty | None) -> list:
    """The drawn points (case index, rpm index, block of :data:`DRAW_BLOCK` draws) of a
    lobe study."""
    if uncertainty is None:
        return []
    blocks = math.ceil(uncertainty.draws / DRAW_BLOCK)
    return [(i, j, b) for i in range(n_cases) for j in range(n_rpm) for b in range(blocks)]


def block_draws(point: tuple[int, int, int], draws: int) -> range:
    """The draws of a drawn point's block."""
    b = point[2]
    return range(b * DRAW_BLOCK, min((b + 1) * DRAW_BLOCK, draws))


def compute(context: dict, point: tuple[int, int, int]) -> dict:
    """One drawn point (case index, rpm index, block): each of the block's draws in order
    (:func:`block_draws`), with its chatter-free depth (m, ``limit_depth_m``), the runs it
    took and their simulated time (s), as lists."""
    out: dict[str, list] = {"limit_depth_m": [], "runs": [], "run_duration_s": []}
    for d in block_draws(point, context["options"].uncertainty.draws):
        found = [v for v in out["limit_depth_m"] if math.isfinite(v)]
        for key, value in drawn_column(context, point[0], point[1], d, found).items():
            out[key].append(value)
    return out


def drawn_column(context: dict, i: int, j: int, d: int, found: list) -> dict:
    """Draw ``d``'s column of case ``i`` at speed ``j``: its chatter-free depth, the runs it
    took and their simulated time; ``found``: the limits (m) of the block's draws before
    it, where a ball's or a noisy cut's search starts (module doc)."""
    o, integration = context["options"], context["integration"]
    u, case, rpm = o.uncertainty, context["cases"][i], o.rpm[j]
    draw = u.draw(d, case.system.bar.n_modes)
    system = drawn_system(case.system, draw, u)
    drawn = drawn_options(o, draw, u, system)
    dcase = Case.of(system, case.label, case.initial)
    noisy = u.force_noise > 0
    searched = noisy or system.kind == "ball"  # its limit is not its host's
    seed, up_step = _seed(o, system, rpm, found if searched else [])
    if noisy:
        done = verdict_column(dcase, rpm, drawn, integration, seed, up_step)
    elif system.kind == "ball":
        done = free_column(dcase, rpm, drawn, integration, seed, up_step)
    else:
        done = growth_column(dcase, rpm, drawn, integration, seed)
    return {"limit_depth_m": free_limit(done, o.depths, noisy), "runs": len(done),
            "run_duration_s": float(sum(r["run_duration_s"] for r in done.values()))}


def _seed(options, system: System, rpm: float, found: list) -> tuple[int, int]:
    """(grid index, first step up) where a drawn column's search starts: the median of
    ``found`` (the block's limits so far), else the analytic limit of the drawn linear
    host (a ball's chatter-free depth is often well above it: the first step up is then
    the ball's, :data:`~boringbar.analysis.lobe_search.BALL_STEP`)."""
    if options.method != "search":
        return 1, 1
    if found:
        return options.index_below(statistics.median(found)), SEEDED_STEP
    host = float(limit_at_speeds(system.linear_host(), [rpm], options.analytic_kr_pa)[0])
    seed = options.index_below(host) if math.isfinite(host) else 1
    return seed, BALL_STEP if system.kind == "ball" else 1


# --- the probability arithmetic ------------------------------------------------------

def chatter_probability(limits: np.ndarray, depths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P, count): at each of ``depths`` the fraction (and number) of the drawn
    chatter-free depths ``limits`` (last axis: the draws; NaN: no chatter up to the
    deepest cut) below it."""
    ordered = np.sort(np.where(np.isnan(limits), np.inf, limits), axis=-1)
    flat = ordered.reshape(-1, ordered.shape[-1])
    count = np.array([np.searchsorted(row, depths, side="left") for row in flat])
    count = count.reshape(ordered.shape[:-1] + np.shape(depths))
    return count / limits.shape[-1], count


def wilson_interval(count, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Wilson's 95 % score interval (low, high) of a binomial proportion at each of
    ``count`` (successes out of ``n``): the design search's
    (:func:`~boringbar.analysis.design_interval.wilson`), tabulated for 0 .. n."""
    table = np.array([wilson(k, n, WILSON_LEVEL) for k in range(n + 1)])
    # exactly 0 (1) where no (every) draw chatters, as the interval is, not round-off
    table[0, 0], table[n, 1] = 0.0, 1.0
    count = np.asarray(count)
    return table[count, 0], table[count, 1]


def limit_quantiles(limits: np.ndarray, quantiles) -> np.ndarray:
    """The contour P(chatter) = q of each q of ``quantiles``: the deepest cut at which at
    most q N of the N drawn limits (last axis) lie below, the (floor(q N) + 1)-th smallest
    limit (NaN where that draw does not chatter up to the deepest cut).  Quantiles on a
    new last axis."""
    n = limits.shape[-1]
    ordered = np.sort(np.where(np.isnan(limits), np.inf, limits), axis=-1)
    k = [min(n - 1, math.floor(q * n + 1e-9)) for q in quantiles]
    out = ordered[..., k]
    return np.where(np.isinf(out), np.nan, out)


# --- the Dataset ---------------------------------------------------------------------

def split(points_: list, results: list) -> tuple[list, list, list, list]:
    """(deterministic points, their results, drawn points, their results) of a lobe
    plan's points (the drawn ones have three indices)."""
    det = [n for n, p in enumerate(points_) if len(p) == 2]
    drawn = [n for n, p in enumerate(points_) if len(p) == 3]
    return ([points_[n] for n in det], [results[n] for n in det],
            [points_[n] for n in drawn], [results[n] for n in drawn])


def add_draws(ds, context: dict, drawn_points: list, results: list, fills: dict):
    """``ds`` (the deterministic lobes) with the draws' limits, P(chatter) and its Wilson
    interval over the depths, the contours and the robust depth; its depth axis extended
    to just above the deepest drawn limit (``fills``: each per-run variable's not-run
    value)."""
    cases, o = context["cases"], context["options"]
    u = o.uncertainty
    shape = (len(cases), len(o.rpm), u.draws)
    limits, runs, run_s = np.full(shape, np.nan), np.zeros(shape, np.int64), np.zeros(shape)
    for point, res in zip(drawn_points, results, strict=True):
        i, j = point[:2]
        d = list(block_draws(point, u.draws))
        limits[i, j, d], runs[i, j, d] = res["limit_depth_m"], res["runs"]
        run_s[i, j, d] = res["run_duration_s"]
    ds = _extend_depths(ds, o, limits, fills)
    prob, count = chatter_probability(limits, ds["depth_m"].values)
    low, high = wilson_interval(count, u.draws)
    dims3 = ("case", "rpm", "depth_m")
    ds = ds.assign_coords(draw=("draw", np.arange(u.draws)),
                          quantile=("quantile", np.array(QUANTILES)))
    robust = limit_quantiles(limits, [u.probability])[..., 0]
    ds = ds.assign({
        "draw_limit_depth_m": (("case", "rpm", "draw"), limits, {
            "units": "m", "long_name": "chatter-free depth of each draw"}),
        "draw_runs": (("case", "rpm", "draw"), runs, {"long_name": "cuts run for each draw"}),
        "chatter_probability": (dims3, prob, {
            "long_name": "P(chatter): the fraction of draws whose chatter-free depth is "
                         "below the depth"}),
        "chatter_probability_low": (dims3, low, {"long_name": "Wilson 95 % interval, low"}),
        "chatter_probability_high": (dims3, high, {"long_name": "Wilson 95 % interval, "
                                                                "high"}),
        "limit_depth_quantile_m": (("case", "rpm", "quantile"), limit_quantiles(
            limits, QUANTILES), {"units": "m", "long_name": "the deepest cut whose "
                                 "P(chatter) is at most the quantile (NaN: beyond the "
                                 "deepest cut)"}),
        "robust_depth_m": (("case", "rpm"), robust, {
            "units": "m", "long_name": f"the deepest cut whose P(chatter) is at most "
                                       f"{u.probability:g}"}),
        "min_robust_depth_m": (("case",), np.nanmin(np.where(np.isnan(robust), np.inf,
                                                             robust), axis=1), {"units": "m"}),
        **_draw_variables(cases, u),
    })
    ds.attrs.update(_attrs(u, runs, run_s))
    return ds


def _extend_depths(ds, options, limits: np.ndarray, fills: dict):
    """``ds`` on a depth grid that reaches the first grid depth above every drawn limit
    (the new depths not run: each variable's ``fills``)."""
    finite = limits[np.isfinite(limits)]
    top = ds.sizes["depth_m"]
    if finite.size:
        top = max(top, min(options.max_index, options.index_below(float(finite.max())) + 1))
    if top == ds.sizes["depth_m"]:
        return ds
    # the depths run keep their values bit for bit: the new ones are appended
    old = ds["depth_m"].values
    depths = np.concatenate([old, options.depths(np.arange(old.size + 1, top + 1))])
    return ds.reindex(depth_m=depths, fill_value={k: v for k, v in fills.items() if k in ds})


def _draw_variables(cases: list, u: Uncertainty) -> dict:
    """Each draw's factors and, per case, its ball's friction force and restitution."""
    n_modes = max(c.system.bar.n_modes for c in cases)
    draws = [u.draw(d, n_modes) for d in range(u.draws)]
    friction = np.full((len(cases), u.draws), np.nan)
    restitution = np.full((len(cases), u.draws), np.nan)
    for i, case in enumerate(cases):
        if case.system.kind in ("ball", "locked"):
            for d, draw in enumerate(draws):
                damper = drawn_system(case.system, draw, u).damper
                friction[i, d], restitution[i, d] = damper.friction_force_n, damper.restitution
    start = [math.nan if w.ball_start is None else w.ball_start for w in draws]
    return {
        "draw_stiffness_scale": (("draw", "mode"), np.array([w.stiffness_scale for w in draws]),
                                 {"long_name": "factor on each mode's stiffness"}),
        "draw_damping_scale": (("draw", "mode"), np.array([w.damping_scale for w in draws]),
                               {"long_name": "factor on each mode's damping ratio"}),
        "draw_friction_force_n": (("case", "draw"), friction, {"units": "N"}),
        "draw_restitution": (("case", "draw"), restitution, {}),
        "draw_ball_start": (("draw",), np.array(start), {
            "long_name": "a free ball's start, a fraction of the half gap from the centre"}),
        "draw_noise_seed": (("draw",), np.array([w.noise_seed for w in draws], np.int64), {}),
    }


def _attrs(u: Uncertainty, runs: np.ndarray, run_s: np.ndarray) -> dict:
    """The draws' settings and cost, as attributes."""
    return {"uncertainty": json.dumps(u.to_dict()), "draws": u.draws, "draw_seed": u.seed,
            "stiffness_cov": u.stiffness_cov, "damping_cov": u.damping_cov,
            "friction_spread": u.friction_spread, "restitution_spread": u.restitution_spread,
            "ball_start_drawn": int(u.ball_start), "force_noise": u.force_noise,
            "probability": u.probability, "draw_runs_total": int(runs.sum()),
            "draw_mean_run_s": float(run_s.sum() / max(int(runs.sum()), 1))}


def summary(ds) -> dict:
    """The chance of chatter of a lobes Dataset with draws, JSON-able: the draws'
    settings and per case and speed the robust depth, the contours and the drawn
    limits in order (P(chatter) at depth b is the fraction of them below b), and
    P(chatter) with its Wilson interval at the nominal chatter-free depth."""
    a = ds.attrs
    cases = []
    for i, label in enumerate(ds["case"].values):
        speeds = []
        for j, r in enumerate(ds["rpm"].values):
            lim = ds["draw_limit_depth_m"].values[i, j]
            nominal = float(ds["limit_depth_m"].values[i, j])
            p, count = chatter_probability(lim, np.array([nominal]))
            lo, hi = wilson_interval(count, lim.size)
            speeds.append({
                "rpm": float(r), "robust_depth_m": _num(ds["robust_depth_m"].values[i, j]),
                "contours": [{"quantile": float(q), "depth_m": _num(v)} for q, v in zip(
                    QUANTILES, ds["limit_depth_quantile_m"].values[i, j], strict=True)],
                "draw_limit_depth_m": [_num(v) for v in np.sort(lim)],
                "chatter_probability_at_limit": None if math.isnan(nominal) else float(p[0]),
                "chatter_probability_at_limit_low": None if math.isnan(nominal) else float(lo[0]),
                "chatter_probability_at_limit_high":
                    None if math.isnan(nominal) else float(hi[0])})
        cases.append({"case": str(label),
                      "min_robust_depth_m": _num(ds["min_robust_depth_m"].values[i]),
                      "speeds": speeds})
    return {"uncertainty": json.loads(a["uncertainty"]), "probability": float(a["probability"]),
            "draw_runs": int(a["draw_runs_total"]), "cases": cases}


def _num(v) -> float | None:
    v = float(v)
    return None if not math.isfinite(v) else v
