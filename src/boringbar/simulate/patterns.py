"""Impact-pattern classifier (docs/model.md, section 6).

Labels the steady part of a harmonically forced run (forcing period T) from
its counted impact times, the walls hit, the stick intervals and the time in
contact.  It runs once for every run whose pattern is read, on a few thousand impacts;
the loop over them is the compiled core's (core/impact_pattern.cpp).

Tolerances (all stated here and in :func:`classify`):

- time tolerance ``time_tol = 5 dt + 1e-3 T`` by default: the published scheme
  detects an impact at the end of a step, up to one step ``dt`` late, so
  impact times carry a jitter of one step; 1e-3 T absorbs residual transients;
- stick time (clipped to the window) plus contact time (ball resting on a
  wall, sub-threshold micro-impacts) counts as sticking when it exceeds 1 % of
  the window: under the sgn() law friction chatters briefly whenever y'
  passes zero while the bar's acceleration at the ball is small, and such
  blips are not a sticking regime;
- periodicity is judged on the last ``min(window, 50 T)`` of the window and a
  period kT (k = 1..8) is accepted only if it repeats for at least
  ``min_periods`` (default 3) whole kT-windows there;
- 'symmetric' means y(t + s) = -y(t) for an odd multiple s of T/2, tested on
  the impact phases modulo kT in both directions within ``time_tol``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from boringbar import core
from boringbar._validate import ParameterError, check_nonnegative, check_positive

PATTERN_LABELS = (
    "no impact",
    "symmetric",
    "asymmetric",
    "sticking",
    "no impact with sticking",
    "non-uniform",
)
#: Length of the analysed tail, in forcing periods.
TAIL_PERIODS = 50
#: Repetitions of kT needed to accept period k when ``min_periods`` is None.
DEFAULT_MIN_PERIODS = 3
#: Stick plus contact time above this fraction of the window counts as sticking
#: (a sgn() friction law chatters briefly whenever y' passes zero while the bar's
#: acceleration at the ball is small; such blips are not a sticking regime).
CONTACT_FRACTION_THRESHOLD = 0.01


@dataclass(frozen=True)
class Pattern:
    """The impact pattern of one run's steady part.

    ``n`` impacts per ``k`` forcing periods (both 0 when not periodic or no
    impacts; for ``sticking`` they are filled in if the impacts are periodic);
    per-cycle counts are means over the whole window; fractions are of the
    window's duration.
    """

    label: str
    n: int
    k: int
    impacts_per_cycle: float
    plus_per_cycle: float
    minus_per_cycle: float
    stick_fraction: float
    contact_fraction: float

    @property
    def name(self) -> str:
        """Short human name: '2 symmetric', '3 asymmetric (period 2)', 'sticking'."""
        if self.label not in ("symmetric", "asymmetric"):
            return self.label
        suffix = f" (period {self.k})" if self.k > 1 else ""
        return f"{self.n} {self.label}{suffix}"

    def to_dict(self) -> dict:
        """JSON-able fields plus ``name``."""
        return {**asdict(self), "name": self.name}


def classify(
    impact_times: np.ndarray,
    impact_walls: np.ndarray,
    stick_intervals: np.ndarray,
    window: tuple[float, float],
    period: float,
    *,
    time_tol: float | None = None,
    dt: float = 0.0,
    contact_time: float = 0.0,
    max_k: int = 8,
    min_periods: int | None = None,
) -> Pattern:
    """Classify the impact pattern of a run's steady part (docs/model.md, section 6).

    Parameters (SI)
    ---------------
    impact_times : ascending times (s) of counted impacts, all inside ``window``.
    impact_walls : +1 or -1 per impact, the wall hit.
    stick_intervals : (n, 2) array of (start, end) times (s) with the ball not
        sliding relative to the bar; clipped to the window, assumed disjoint.
    window : (t_start, t_end) of the analysed steady part (s).
    period : forcing period T (s).
    time_tol : time tolerance (s); default ``5 * dt + 1e-3 * period``.
    dt : integrator step (s); impact times are quantised to it.
    contact_time : time (s) in the window with the ball resting on a wall.
    max_k : largest period, in forcing periods, tried (1..8 in the study).
    min_periods : whole kT-windows the period must repeat for in the tail
        (the last ``min(window, 50 T)``); default 3, at least 2.

    Rules: no impacts -> 'no impact', or 'no impact with sticking' if there is
    stick plus contact time > 1 % of the window; impacts with sticking
    -> 'sticking'.  Otherwise the smallest k <= max_k for which every impact is
    followed, n impacts later, by one on the same wall kT later within
    ``time_tol`` over the whole tail; 'symmetric' if the two walls have equal
    counts and y(t + s) = -y(t) for some s = (2j+1) T/2, j = 0..k-1: the - wall's
    impacts are the + wall's shifted by s and vice versa, within ``time_tol``
    (for k > 1 only k odd, s = kT/2 can pass), else 'asymmetric'; no such
    k -> 'non-uniform'.  Each kT-window is compared with
    the previous one, so a phase drift below ``time_tol`` per kT passes.
    """
    t_start, t_end = (float(v) for v in window)
    period = check_positive("period", period, "s")
    dt = check_nonnegative("dt", dt, "s")
    tol = 5.0 * dt + 1e-3 * period if time_tol is None else time_tol
    tol = check_nonnegative("time_tol", tol, "s")
    contact_time = check_nonnegative("contact_time", contact_time, "s")
    max_k = _check_int("max_k", max_k, 1)
    min_periods = _check_int(
        "min_periods", DEFAULT_MIN_PERIODS if min_periods is None else min_periods, 2
    )
    times, walls = _check_impacts(impact_times, impact_walls, t_start, t_end)
    intervals = _check_intervals(stick_intervals)

    duration = t_end - t_start
    cycles = duration / period
    stick_fraction = _stick_fraction(intervals, t_start, t_end) if len(intervals) else 0.0
    contact_fraction = contact_time / duration
    sticks = (stick_fraction + contact_fraction) > CONTACT_FRACTION_THRESHOLD

    n, k, symmetric = 0, 0, False
    if times.size:
        tail_start = t_end - min(duration, TAIL_PERIODS * period)
        n, k, symmetric = _periodicity(times, walls, (tail_start, t_end), period, tol, max_k,
                                       min_periods)

    n_plus = (times.size + round(float(walls.sum()))) // 2  # the walls are +1 and -1
    if not times.size:
        label = "no impact with sticking" if sticks else "no impact"
    elif sticks:
        label = "sticking"
    elif k == 0:
        label = "non-uniform"
    else:
        label = "symmetric" if symmetric else "asymmetric"
    return Pattern(
        label=label,
        n=n,
        k=k,
        impacts_per_cycle=float(times.size / cycles),
        plus_per_cycle=float(n_plus / cycles),
        minus_per_cycle=float((times.size - n_plus) / cycles),
        stick_fraction=stick_fraction,
        contact_fraction=float(contact_fraction),
    )


def _stick_fraction(intervals, t_start, t_end) -> float:
    """The share of the window (t_start, t_end) in the stick ``intervals``."""
    overlap = np.minimum(intervals[:, 1], t_end) - np.maximum(intervals[:, 0], t_start)
    return float(np.clip(overlap, 0.0, None).sum() / (t_end - t_start))


def _periodicity(times, walls, tail, period, tol, max_k, min_periods):
    """(n, k, symmetric) of the impacts in the ``tail``: the smallest period k T (k <=
    ``max_k``, repeating ``min_periods`` times in the tail) with its n impacts; (0, 0,
    False) if none.  The compiled core's loop (core/impact_pattern.cpp): every impact j
    + n on impact j's wall, k T later within ``tol``, where n is the count before t_0 + k T
    - tol, and the sequence reaching within k T of both ends of the tail (shift-based, so
    an impact jittering across a fold boundary does not change the count); symmetric if
    y(t + s) = -y(t) for some s = (2j+1) T/2, j = 0..k-1, the + wall's phases modulo k T
    shifted by s matching the - wall's and vice versa within ``tol`` (both directions make
    it the antisymmetry itself; for k > 1 only s = k T/2 with k odd can pass)."""
    # k and the repeat count beyond 1e6 find nothing in a tail of TAIL_PERIODS periods
    n, k, symmetric = core.impact_period(
        times, walls, float(tail[0]), float(tail[1]), float(period), float(tol), min(max_k, 10**6),
        min(min_periods, 10**6))
    return int(n), int(k), bool(symmetric)


def _check_int(name: str, value, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lo:
        raise ParameterError(f"{name} = {value!r} must be an integer >= {lo}")
    return int(value)


def _check_impacts(impact_times, impact_walls, t_start, t_end) -> tuple[np.ndarray, np.ndarray]:
    """The impacts as contiguous float arrays, once checked (the loop over them is the
    core's, ``core.impact_fault``)."""
    if not (math.isfinite(t_start) and math.isfinite(t_end) and t_end > t_start):
        raise ParameterError(
            f"window = ({t_start!r}, {t_end!r}) s must be finite with t_end > t_start"
        )
    times = np.asarray(impact_times, dtype=float)
    walls = np.asarray(impact_walls)
    if times.ndim != 1 or walls.shape != times.shape:
        raise ParameterError(
            f"impact_times (shape {times.shape}) and impact_walls "
            f"(shape {walls.shape}) must be 1-D of equal length"
        )
    times = np.ascontiguousarray(times)
    try:
        walls = np.ascontiguousarray(walls, dtype=float)
    except (TypeError, ValueError):
        fault = 1
    else:
        fault = core.impact_fault(times, walls, float(t_start), float(t_end))
    if fault == 1:
        raise ParameterError(f"impact_walls = {np.unique(walls)!r} must hold only +1 and -1")
    if fault == 2:
        raise ParameterError(
            f"impact_times must be ascending inside window "
            f"[{t_start:g}, {t_end:g}] s; got [{times[0]:g}, {times[-1]:g}] s"
        )
    return times, walls


def _check_intervals(stick_intervals) -> np.ndarray:
    intervals = np.asarray(stick_intervals, dtype=float)
    if intervals.size == 0:
        return np.zeros((0, 2))
    if intervals.ndim != 2 or intervals.shape[1] != 2 or np.any(intervals[:, 1] < intervals[:, 0]):
        raise ParameterError(
            f"stick_intervals (shape {intervals.shape}) must be (n, 2) "
            "rows of (start, end) with end >= start"
        )
    return intervals
