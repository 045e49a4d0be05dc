"""How sure a design search's improvement is: the best design against the file's own on
the same Monte Carlo draws (docs/design.md).

Every candidate is judged on the same samples of the uncertain parameters (common
random numbers), so the two designs' samples come in pairs, and the improvement's
interval is that of the paired differences:

- **mean**: a paired t interval (Welch's where the samples are not paired);
- **quantile**, **max**: a paired percentile bootstrap, the same resampled draws for
  both designs;
- **chatter_probability**: Newcombe's interval for the difference of two paired
  proportions (his method 10), built from each design's Wilson score interval.

The improvement is positive when the best design is better: the file's statistic less
the best's for an objective to minimise, the best's less the file's for one to
maximise.  One sample, or samples whose differences do not vary, give no interval:
:func:`improvement` says why instead.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.special

#: The confidence level of every interval of a design search.
CONFIDENCE = 0.95
#: Resamples of the paired bootstrap.
RESAMPLES = 2000
#: Resampled values held at once by the bootstrap (resamples x samples), to bound memory.
BOOTSTRAP_CHUNK = 2_000_000


def wilson(k: int, n: int, level: float = CONFIDENCE) -> tuple[float, float]:
    """Wilson's score interval of a proportion of ``k`` in ``n`` at ``level``."""
    z = scipy.special.ndtri(0.5 + level / 2)  # the normal quantile
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


def newcombe_paired(a: np.ndarray, b: np.ndarray,
                    level: float = CONFIDENCE) -> tuple[float, float]:
    """Newcombe's interval (1998, method 10) for P(a) - P(b) of the paired flags ``a``
    and ``b`` (one pair a sample): each proportion's Wilson interval, combined with the
    pairs' correlation phi (its numerator less n/2 when positive, as Newcombe's)."""
    a, b = np.asarray(a, dtype=bool), np.asarray(b, dtype=bool)
    n = len(a)
    both, only_a = int(np.sum(a & b)), int(np.sum(a & ~b))
    only_b, neither = int(np.sum(~a & b)), int(np.sum(~a & ~b))
    pa, pb = (both + only_a) / n, (both + only_b) / n
    la, ua = wilson(both + only_a, n, level)
    lb, ub = wilson(both + only_b, n, level)
    margins = (both + only_a) * (only_b + neither) * (both + only_b) * (only_a + neither)
    cross = both * neither - only_a * only_b
    if margins == 0 or 0 <= cross <= n / 2:
        phi = 0.0
    else:
        phi = (cross - n / 2 if cross > 0 else cross) / math.sqrt(margins)
    d = pa - pb
    low = math.sqrt(max(0.0, (pa - la) ** 2 - 2 * phi * (pa - la) * (ub - pb) + (ub - pb) ** 2))
    high = math.sqrt(max(0.0, (pb - lb) ** 2 - 2 * phi * (pb - lb) * (ua - pa) + (ua - pa) ** 2))
    return max(-1.0, d - low), min(1.0, d + high)


def paired_t(differences: np.ndarray, level: float = CONFIDENCE) -> tuple[float, float]:
    """The t interval of the mean of paired ``differences`` at ``level``."""
    d = np.asarray(differences, dtype=float)
    n = len(d)
    half = scipy.special.stdtrit(n - 1, 0.5 + level / 2) * np.std(d, ddof=1) / math.sqrt(n)
    return float(np.mean(d) - half), float(np.mean(d) + half)


def welch_t(x: np.ndarray, y: np.ndarray, level: float = CONFIDENCE) -> tuple[float, float]:
    """Welch's t interval of mean(x) - mean(y), two samples that are not paired."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    vx, vy = np.var(x, ddof=1) / len(x), np.var(y, ddof=1) / len(y)
    dof = (vx + vy) ** 2 / (vx**2 / (len(x) - 1) + vy**2 / (len(y) - 1))
    half = scipy.special.stdtrit(dof, 0.5 + level / 2) * math.sqrt(vx + vy)
    d = float(np.mean(x) - np.mean(y))
    return d - half, d + half


def sample_statistic(x: np.ndarray, statistic: str, quantile: float, axis=None):
    """The ``statistic`` (mean, quantile q = ``quantile``, or max) of the samples ``x``."""
    if statistic == "mean":
        return np.mean(x, axis=axis)
    if statistic == "max":
        return np.max(x, axis=axis)
    return np.quantile(x, quantile, axis=axis)


def paired_bootstrap(x: np.ndarray, y: np.ndarray, statistic: str, quantile: float,
                     seed: int, level: float = CONFIDENCE) -> tuple[float, float]:
    """The percentile bootstrap interval of stat(x) - stat(y), the pairs (x_i, y_i)
    resampled together :data:`RESAMPLES` times (seeded by ``seed``)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    n = len(x)
    rng = np.random.default_rng(seed)
    step = max(1, BOOTSTRAP_CHUNK // n)
    diffs = []
    for start in range(0, RESAMPLES, step):
        idx = rng.integers(0, n, (min(step, RESAMPLES - start), n))
        diffs.append(sample_statistic(x[idx], statistic, quantile, axis=1)
                     - sample_statistic(y[idx], statistic, quantile, axis=1))
    d = np.concatenate(diffs)
    lo, hi = np.quantile(d, [0.5 - level / 2, 0.5 + level / 2])
    return float(lo), float(hi)


def improvement(best: np.ndarray, published: np.ndarray, statistic: str, *,
                maximize: bool = False, quantile: float = 0.9, seed: int = 0,
                best_chatter: np.ndarray | None = None,
                published_chatter: np.ndarray | None = None, paired: bool = True,
                level: float = CONFIDENCE) -> dict:
    """The best design's improvement on the file's own design, with its interval.

    ``best``, ``published``: each design's objective samples (the same draws, in the
    same order, when ``paired``); ``statistic``: mean, quantile (``quantile``), max or
    chatter_probability (of the flags ``best_chatter``, ``published_chatter``);
    ``maximize``: the objective's direction; ``seed``: the bootstrap's.

    Returns ``improvement`` (positive: the best is better; the objective's SI unit),
    ``interval`` ((low, high) at ``level``, or None), ``method``, ``significant``
    (the interval excludes 0; None without an interval) and ``note`` (why there is no
    interval, else None)."""
    sign = -1.0 if maximize else 1.0  # the improvement is the file's less the best's
    if statistic == "chatter_probability":
        b, p = np.asarray(best_chatter, dtype=bool), np.asarray(published_chatter, dtype=bool)
        gain = float(np.mean(p) - np.mean(b))
        n = len(b)
        method = "Newcombe's paired interval"
    else:
        b, p = np.asarray(best, dtype=float), np.asarray(published, dtype=float)
        gain = float(sign * (sample_statistic(p, statistic, quantile)
                             - sample_statistic(b, statistic, quantile)))
        n = min(len(b), len(p))
        method = (("paired t" if paired else "Welch t") if statistic == "mean"
                  else f"paired bootstrap, {RESAMPLES} resamples")
    out = {"improvement": gain, "interval": None, "method": method, "significant": None,
           "note": None, "level": level}
    if n < 2:
        return {**out, "method": None, "note": "one sample: no interval"}
    if statistic == "chatter_probability":
        lo, hi = newcombe_paired(p, b, level)
    elif statistic == "mean" and not paired:
        lo, hi = (sign * v for v in welch_t(p, b, level))
    elif statistic == "mean":
        lo, hi = (sign * v for v in paired_t(p - b, level))
    else:
        lo, hi = (sign * v for v in paired_bootstrap(p, b, statistic, quantile, seed, level))
    lo, hi = min(lo, hi), max(lo, hi)
    if not (hi > lo):  # every pair differs by the same: the samples show no spread
        return {**out, "method": None,
                "note": f"the {n} samples' differences do not vary: no interval"}
    return {**out, "interval": (lo, hi), "significant": bool(lo > 0 or hi < 0)}
