"""Poincare maps of one run and a verdict on the sample cloud (docs/model.md, section 6).

Two sections of a harmonically forced run (forcing period T = 2 pi / Omega):

- **stroboscopic** (:func:`poincare_map`): tip displacement W and velocity W'
  at Omega t = 0 mod 2 pi, as the kernel samples them (cubic Hermite inside
  the step), after dropping the first ``drop`` fraction of the run's time;
- **at impacts** (:func:`impact_map`): for each counted impact on one wall,
  the forcing phase Omega t mod 2 pi and the relative velocity y' just before
  it.  The kernel records only impact times, walls and velocities, so this
  is the classic impact map (phase, impact velocity), not (W, W') at impact.

The verdict (:func:`classify_cloud`) comes in three stages:

1. **Distinct points.**  Leader clustering in the scaled coordinates: the
   first sample opens a cluster, each later sample joins the first cluster
   whose leader is within ``tol`` in every scaled coordinate (Chebyshev
   distance; circular coordinates wrap), else opens a new one.  The label
   sequence is then tested for a period p <= ``max_k`` (labels[i + p] ==
   labels[i] for all i, repeated at least ``MIN_REPEATS`` times): that is
   ``period-p``, and ``distinct`` is the number of clusters.
2. **Transient.**  If the whole cloud is not periodic but its last half is,
   the orbit is still settling onto period-p within the record: ``transient``
   (with that p).
3. **0-1 test for chaos** (Gottwald & Melbourne, SIAM J. Appl. Dyn. Syst. 8
   (2009) 129-145, the correlation method with the oscillatory term
   subtracted) on one coordinate's samples (:meth:`PoincareMap.classify`:
   the widest-spread one, or W), median over
   ``ZERO_ONE_C`` frequencies c drawn in (pi/5, 4 pi/5) with a fixed seed:
   K <= ``K_REGULAR`` -> ``quasi-periodic`` (bounded motion of the
   translation variables: the points lie on a closed curve or torus);
   K >= ``K_CHAOTIC`` -> ``chaotic-like`` (diffusive: a strange attractor,
   or a transient too long for the record); in between, or with fewer than
   ``ZERO_ONE_MIN_SAMPLES`` samples, ``undetermined``.

Tolerances for simulated runs: the published scheme detects an impact at the
end of a step, up to one step ``dt`` late; as T / dt is not an integer, every
impact lands at a different point of the step grid and the stroboscopic
samples of an exactly periodic impacting orbit scatter (peak to peak, in
units of Omega dt relative to each coordinate's scale) by up to 2.7 in W'
and 0.5 in y on the two-impact orbit at 30 N (physical, gap 0.5 mm), and by
0.3 in W', 3.9 in y and 4.8 in y' on the 4-impact orbit at 20 N (paper, gap
0.1 mm), at dt = 1e-6 and 5e-7 alike.  Runs with a free ball therefore
cluster with ``tol + JITTER_STEPS * Omega * dt`` (2.4 % at dt = 1e-6 near
460 Hz); linear runs (solid, TMD, locked ball) with ``tol`` alone.  An orbit
whose scatter is near that tolerance can split into clusters that do not
repeat, and its W samples then look like noise to the 0-1 test: read
``distinct`` and K beside the verdict.  Scales: the run's steady half-range A
of W for W, Omega A for W'; delta/2 for y and the largest |y'| at impact for
y' (absorber: its largest steady stroke, and Omega times that); 1 rad for the
impact phase, the largest |y'| for the impact velocity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from boringbar._validate import ParameterError, check_positive, check_range

#: Stroboscopic samples scatter by up to this many Omega dt (relative) when the
#: run has impacts (one-step-late impact detection, see the module docstring).
JITTER_STEPS = 8.0
#: A period p is accepted only if the label sequence shows it this many times.
MIN_REPEATS = 3
#: Fewest samples for the 0-1 test; fewer give 'undetermined'.
ZERO_ONE_MIN_SAMPLES = 200
#: The 0-1 test of a verdict uses at most the last this many samples (its cost
#: grows as N^2).
ZERO_ONE_MAX_SAMPLES = 5000
#: Number of random frequencies c in (pi/5, 4 pi/5) of the 0-1 test.
ZERO_ONE_C = 100
#: 0-1 test thresholds: K <= K_REGULAR is regular, K >= K_CHAOTIC chaotic.
K_REGULAR = 0.3
K_CHAOTIC = 0.7

VERDICTS = ("period-k", "transient", "quasi-periodic", "chaotic-like", "undetermined")

METHOD = (
    "leader clustering (Chebyshev distance <= tol in scaled coordinates) and the "
    f"shortest label period p <= max_k repeated >= {MIN_REPEATS} times -> period-p; "
    "last half periodic only -> transient; otherwise Gottwald-Melbourne 0-1 test "
    f"(correlation method, median over {ZERO_ONE_C} c in (pi/5, 4pi/5), n_cut = N/10) on "
    f"one coordinate (the widest-spread relative to its scale): K <= {K_REGULAR} "
    f"quasi-periodic, K >= {K_CHAOTIC} chaotic-like, else (or N < {ZERO_ONE_MIN_SAMPLES}) "
    "undetermined"
)


# --- the 0-1 test ----------------------------------------------------------------
def zero_one_test(signal, *, n_c: int = ZERO_ONE_C, seed: int = 0) -> float:
    """Gottwald-Melbourne 0-1 test for chaos: K near 0 regular, near 1 chaotic.

    For each c, p_c(n) = sum_{j<=n} phi_j cos(j c), q_c(n) = sum phi_j sin(j c);
    the mean square displacement M_c(n) over j = 1..N - n_cut, minus the
    oscillatory term (E phi)^2 (1 - cos n c) / (1 - cos c), is correlated with
    n = 1..n_cut (n_cut = N / 10); K is the median correlation over ``n_c``
    values of c drawn uniformly in (pi/5, 4 pi/5) with ``seed``
    (Gottwald & Melbourne 2009, section 3).  Needs a few hundred samples.
    """
    phi = np.asarray(signal, dtype=float).ravel()
    n = phi.size
    if n < 20 or not np.all(np.isfinite(phi)):
        raise ParameterError(f"signal has {n} samples (finite ones needed, at least 20)")
    if np.ptp(phi) == 0.0:
        return 0.0  # a constant is the most regular signal there is
    c = np.random.default_rng(seed).uniform(math.pi / 5, 4 * math.pi / 5, n_c)
    j = np.arange(1, n + 1)
    p = np.cumsum(phi * np.cos(np.outer(c, j)), axis=1)
    q = np.cumsum(phi * np.sin(np.outer(c, j)), axis=1)
    n_cut = max(n // 10, 2)
    m = n - n_cut
    lags = np.arange(1, n_cut + 1)
    msd = np.empty((n_c, n_cut))
    for i, lag in enumerate(lags):
        msd[:, i] = np.mean(
            (p[:, lag : lag + m] - p[:, :m]) ** 2 + (q[:, lag : lag + m] - q[:, :m]) ** 2, axis=1
        )
    v_osc = phi.mean() ** 2 * (1 - np.cos(np.outer(c, lags))) / (1 - np.cos(c))[:, None]
    d = msd - v_osc
    x = lags - lags.mean()
    dc = d - d.mean(axis=1, keepdims=True)
    denom = np.sqrt(np.sum(x**2) * np.sum(dc**2, axis=1))
    k = np.where(denom > 0, dc @ x / np.where(denom > 0, denom, 1.0), 0.0)
    return float(np.median(k))


# --- clustering and the verdict -----------------------------------------------------
def _leader_clusters(z: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    """Cluster label of each row of scaled points ``z`` (tolerance 1 after scaling)."""
    labels = np.empty(len(z), dtype=int)
    leaders: list[np.ndarray] = []
    for i, point in enumerate(z):
        if leaders:
            diff = np.abs(np.asarray(leaders) - point)
            diff = np.where(wrap > 0, np.minimum(diff, np.abs(wrap - diff)), diff)
            near = np.flatnonzero(np.all(diff <= 1.0, axis=1))
            if near.size:
                labels[i] = near[0]
                continue
        labels[i] = len(leaders)
        leaders.append(point)
    return labels


def _label_period(labels: np.ndarray, max_k: int) -> int:
    """Shortest p <= max_k with labels[i + p] == labels[i], seen MIN_REPEATS times; else 0."""
    for p in range(1, max_k + 1):
        if len(labels) < MIN_REPEATS * p:
            break
        if np.array_equal(labels[p:], labels[:-p]):
            return p
    return 0


def classify_cloud(
    points, scale, tol: float = 1e-3, max_k: int = 16, *, wrap=None, signal=None
) -> dict:
    """Verdict on a Poincare sample cloud: period-k, transient, quasi-periodic,
    chaotic-like or undetermined (method in the module docstring).

    ``points``: (n, d) samples in time order (a 1-D array is one coordinate).
    ``scale``: a positive number or one per coordinate, in the points' units;
    two samples are the same point when they differ by at most ``tol * scale``
    in every coordinate.  ``wrap``: per coordinate, the period of a circular
    coordinate (e.g. 2 pi for a phase) or 0.  ``signal``: the series for the
    0-1 test (default: the first coordinate).

    Returns a dict: ``verdict`` (one of :data:`VERDICTS`, with 'period-k'
    written as e.g. 'period-2'), ``k`` (the period, 0 if none), ``distinct``
    (clusters in the whole cloud), ``points`` (the last k samples for a
    period-k or transient verdict, else empty: the orbit's points, settled as
    far as the record allows), ``K`` (0-1 test, NaN if not run), ``n`` and
    ``method``.
    """
    z = np.asarray(points, dtype=float)
    if z.ndim == 1:
        z = z[:, None]
    if z.ndim != 2 or not np.all(np.isfinite(z)):
        raise ParameterError(f"points (shape {z.shape}) must be a finite (n, d) array")
    d = z.shape[1]
    scale = np.broadcast_to(np.asarray(scale, dtype=float), (d,))
    if not np.all((scale > 0) & np.isfinite(scale)):
        raise ParameterError(f"scale = {scale.tolist()!r} must be positive and finite")
    tol = check_positive("tol", tol)
    max_k = int(check_range("max_k", max_k, 1, 10_000))
    wrap = np.zeros(d) if wrap is None else np.broadcast_to(np.asarray(wrap, float), (d,))
    step = tol * scale
    out = {
        "verdict": "undetermined",
        "k": 0,
        "distinct": 0,
        "points": z[:0],
        "K": math.nan,
        "n": len(z),
        "method": METHOD,
    }
    if len(z) == 0:
        return out
    labels = _leader_clusters(z / step, wrap / step)
    out["distinct"] = int(labels.max() + 1)
    k = _label_period(labels, max_k)
    if k:
        return {**out, "verdict": f"period-{k}", "k": k, "points": z[-k:]}
    half = z[len(z) // 2 :]
    k = _label_period(_leader_clusters(half / step, wrap / step), max_k)
    if k:
        return {**out, "verdict": "transient", "k": k, "points": z[-k:]}
    phi = z[:, 0] if signal is None else np.asarray(signal, dtype=float)
    if len(phi) < ZERO_ONE_MIN_SAMPLES:
        return out
    big_k = zero_one_test(phi[-ZERO_ONE_MAX_SAMPLES:])
    verdict = (
        "quasi-periodic"
        if big_k <= K_REGULAR
        else "chaotic-like"
        if big_k >= K_CHAOTIC
        else "undetermined"
    )
    return {**out, "verdict": verdict, "K": big_k}


# --- the two sections of a run --------------------------------------------------
def jitter_tolerance(run) -> float:
    """Extra relative tolerance for the step-grid jitter of a run with impacts."""
    return JITTER_STEPS * run.omega_rad_s * run.dt_s if run.system.kind == "ball" else 0.0


@dataclass(frozen=True, eq=False)
class PoincareMap:
    """Stroboscopic samples (Omega t = 0 mod 2 pi) of one run's retained part.

    The verdict uses the whole sampled state: (W, W') and, for a free ball or
    an absorber, the auxiliary pair (y, y') or (stroke, stroke rate); the
    ball's state separates irregular impact sequences that barely move the
    bar (the published non-uniform patterns at gap 0.1 mm scatter W by ~2 % of
    its amplitude but y across the whole clearance).
    """

    time: np.ndarray  #: sample times (s)
    tip_displacement: np.ndarray  #: W (m)
    tip_velocity: np.ndarray  #: W' (m/s)
    aux: np.ndarray  #: (n, 2) ball y, y' (or absorber stroke and its rate)
    omega: float  #: Omega (rad/s)
    scale: np.ndarray  #: scales of the columns of ``cloud`` (their units)
    jitter: float  #: extra relative tolerance (see :func:`jitter_tolerance`)

    @property
    def points(self) -> np.ndarray:
        """(n, 2): W (m), W' (m/s)."""
        return np.column_stack([self.tip_displacement, self.tip_velocity])

    @property
    def cloud(self) -> np.ndarray:
        """(n, d): the sampled state the verdict uses (W, W'[, aux, aux'])."""
        if len(self.scale) == 2:
            return self.points
        return np.column_stack([self.points, self.aux])

    def classify(self, tol: float = 1e-3, max_k: int = 16, signal: str = "widest") -> dict:
        """:func:`classify_cloud` of :attr:`cloud` with tolerance ``tol`` + jitter.

        ``signal``: the 0-1 test's series, "W" or "widest" (default): the
        coordinate with the largest peak-to-peak spread relative to its scale.
        On the gap-0.1 mm ball the irregular part of the motion lives in the
        ball (y spreads over the clearance, W by ~2 %); K from W then wanders
        between 0.3 and 0.9 from one force to the next while K from y is 1.0.
        The result's ``signal`` names the coordinate used.
        """
        if signal not in ("widest", "W"):
            raise ParameterError(f"signal = {signal!r} is not one of widest, W")
        cloud = self.cloud
        names = ("W", "W'", "aux", "aux'")
        j = 0
        if signal == "widest" and len(cloud):
            j = int(np.argmax(np.ptp(cloud, axis=0) / self.scale))
        out = classify_cloud(cloud, self.scale, tol + self.jitter, max_k, signal=cloud[:, j])
        return {**out, "signal": names[j]}


def _scales(run, samples: np.ndarray) -> np.ndarray:
    """W: the run's steady half-range A; W': Omega A; ball y: delta/2, y': the
    largest |y'| before an impact (Omega delta/2 without impacts); absorber
    stroke: its steady largest |stroke|, rate: Omega times that."""
    amp = run.metrics.get("amplitude_m", math.nan)
    if not (math.isfinite(amp) and amp > 0):
        amp = float(np.max(np.abs(samples[:, 1]))) if len(samples) else 0.0
    amp = max(amp, 1e-300)
    scale = [amp, run.omega_rad_s * amp]
    kind = run.system.kind
    if kind == "ball":
        half = run.system.damper.gap_m / 2
        vmax = float(np.max(np.abs(run.impacts[:, 2]))) if len(run.impacts) else 0.0
        scale += [half, max(vmax, run.omega_rad_s * half)]
    elif kind == "tmd":
        stroke = run.metrics.get("max_abs_aux_m", math.nan)
        stroke = stroke if math.isfinite(stroke) and stroke > 0 else 1e-300
        scale += [stroke, run.omega_rad_s * stroke]
    return np.array(scale)


def poincare_map(run, steady_fraction: float = 0.8) -> PoincareMap:
    """Stroboscopic Poincare map of ``run`` (simulated with ``strobe=True``): the
    samples in the last ``steady_fraction`` of the run's time."""
    drop = 1.0 - check_range("steady_fraction", steady_fraction, 0.0, 1.0, lo_open=True)
    if run.strobe.size == 0 and run.duration_s * run.omega_rad_s > 4 * math.pi:
        raise ParameterError("the run has no stroboscopic samples: simulate it with strobe=True")
    s = run.strobe[run.strobe[:, 0] >= run.t0_s + drop * run.duration_s]
    return PoincareMap(
        time=s[:, 0],
        tip_displacement=s[:, 1],
        tip_velocity=s[:, 2],
        aux=s[:, 3:5],
        omega=run.omega_rad_s,
        scale=_scales(run, s),
        jitter=jitter_tolerance(run),
    )


@dataclass(frozen=True, eq=False)
class ImpactMap:
    """Impacts on one wall (or both): forcing phase and relative velocity before."""

    time: np.ndarray  #: impact times (s)
    phase: np.ndarray  #: Omega t mod 2 pi (rad)
    velocity: np.ndarray  #: relative velocity y' just before the impact (m/s)
    wall: np.ndarray  #: +1 / -1 per impact
    omega: float
    jitter: float

    @property
    def points(self) -> np.ndarray:
        """(n, 2): phase (rad), velocity (m/s)."""
        return np.column_stack([self.phase, self.velocity])

    def classify(self, tol: float = 1e-3, max_k: int = 16) -> dict:
        """:func:`classify_cloud` of (phase, velocity): phase on a 1 rad scale
        (circular), velocity on the largest |y'|; the 0-1 test runs on the
        velocities.  k counts impacts on the wall(s) per repetition, not periods."""
        if len(self.velocity) == 0:
            return classify_cloud(np.zeros((0, 2)), 1.0, tol, max_k)
        vscale = max(float(np.max(np.abs(self.velocity))), 1e-300)
        return classify_cloud(
            self.points,
            [1.0, vscale],
            tol + self.jitter,
            max_k,
            wrap=[2 * math.pi, 0.0],
            signal=self.velocity,
        )


def impact_map(run, wall: int | None = 1, steady_fraction: float = 1.0) -> ImpactMap:
    """Impact map of ``run``: the impacts counted in its steady part (the last
    ``steady_fraction`` of :func:`~boringbar.simulate.simulate`) on ``wall``
    (+1, -1, or None for both), and of those only the ones in the last
    ``steady_fraction`` here of the run's time (default: all)."""
    if wall not in (1, -1, None):
        raise ParameterError(f"wall = {wall!r} is not one of 1, -1, None")
    drop = 1.0 - check_range("steady_fraction", steady_fraction, 0.0, 1.0, lo_open=True)
    imp = run.impacts
    keep = imp[:, 0] >= run.t0_s + drop * run.duration_s
    if wall is not None:
        keep &= imp[:, 1] == wall
    imp = imp[keep]
    return ImpactMap(
        time=imp[:, 0],
        phase=np.mod(run.omega_rad_s * imp[:, 0], 2 * math.pi),
        velocity=imp[:, 2],
        wall=imp[:, 1].astype(int),
        omega=run.omega_rad_s,
        jitter=jitter_tolerance(run),
    )
