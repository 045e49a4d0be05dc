"""The converged verdict of a simulated cut (docs/chatter.md).

A cut is judged by what its vibration does, not by whether a run of fixed length
happened to reach a threshold:

- **Onset** (small disturbances).  The cut starts in progress (the bar at its static
  deflection under the mean force, the surface cut at it) and is knocked at the tip
  (:func:`~boringbar.simulate.knocked_cut`, ``knock_m``, 1 um by default).  It runs
  window by window (whole revolutions, at least :data:`WINDOW_PERIODS` periods of the
  host bar's first mode), at ``onset_step_ratio`` times the judged step (the knock's
  vibration is linear; :func:`onset_step`); each window gives the tip's amplitude A_k
  (half its peak-to-peak).  The growth rate is the slope of ln A_k against time, fitted by least
  squares over the last quarter of the windows (at least 4) and over the quarter before
  it.  The log-envelope of a sum of decaying and growing modes is convex, so a slope
  only rises as the faster modes die out: a last-quarter slope above zero at the
  stated ``confidence`` (Student's t on the fit) is chatter at once; a slope below zero
  is stable only once it has stopped rising (the last slope plus three times its rise
  over the quarter before still below zero, at that confidence).  The tool leaving the
  cut (h = 0) after a small knock is chatter.  A run that reaches ``max_duration_s``
  undecided is ``undecided``, its last slope the best estimate.
- **The settled vibration**: an onset that chatters is run on at the judged step until
  the tip's peak-to-peak over the last quarter of the windows and over the quarter
  before agree within ``settle_tolerance`` (5 %), or it decays below the tolerance, or
  the tool leaves the cut in the last quarter.  A bar without a ball (solid, tuned mass damper,
  locked ball) is linear until the tool leaves the cut, so its vibration grows until it
  does: its onset decides.
- **Large disturbances**: each ``knocks_m`` starts the same cut knocked that hard and
  runs it until it settles.

The cut is **chatter-free** when, from every start tried, the settled vibration keeps
the tool in the cut and its peak-to-peak within ``tolerance_m``.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import special

from boringbar._validate import check_choice, check_int, check_range, check_values
from boringbar.model.forcing import Regenerative
from boringbar.model.system import System
from boringbar.simulate import STICK_LAWS, CutStepper, Window, knocked_cut, rolling
from boringbar.simulate.run_limits import shortest_period

#: A window holds whole revolutions and at least this many periods of the host bar's
#: first mode (a chatter near an absorber's lower peak, down to 2/3 f1, still shows
#: two cycles a window).
WINDOW_PERIODS = 3.0
#: The verdict's defaults: confidence of the growth rate's sign, the cap on a run, the
#: small knock, the surface-finish budget (tip peak-to-peak), the settling tolerance.
CONFIDENCE = 0.99
MAX_DURATION_S = 10.0
KNOCK_M = 1e-6
TOLERANCE_M = 10e-6
SETTLE_TOLERANCE = 0.05
MIN_SEGMENT = 6
#: An observable's amplitude is logged at least at AMP_ZERO (m): at LOG_ZERO it was 0
AMP_ZERO = 1e-300
LOG_ZERO = math.log(AMP_ZERO)
#: A judged cut's RK4 step (s), and at least this many steps in the shortest period of
#: a bar's modes and absorber (:func:`judged_step`).  With a ball held by the stick law
#: a friction-held vibration grows at the locked bar's root at any step, and no
#: chatter-free verdict changes on the carbide ball map from 5e-7 s to 1e-5 s nor on the
#: published one from 1e-6 s to 5e-6 s; an impacting ball's bounded vibration is what
#: stops the step at 2e-6 s (docs/chatter.md, "The step of a judged cut").
JUDGED_STEP_S = 2e-6
JUDGED_STEPS_PER_PERIOD = 25
#: Where judged cuts run when the caller leaves it to the analysis (Execution "auto"):
#: a process per core.  A judged cut goes window by window with Python between kernel
#: calls of a few tenths of a millisecond, where threads wait on each other for the GIL:
#: the published ball bar's P(chatter) over its first three lobes (32 draws) took 210 s
#: on two threads and 165 s on two processes (benchmarks/bench_chatter_probability.py).
EXECUTOR = "processes"
#: The onset runs at this multiple of the judged step, at most the step that keeps
#: JUDGED_STEPS_PER_PERIOD steps in the shortest period (:func:`onset_step`): a small
#: knock's vibration is linear (the bar, an absorber, a ball held by its friction or off
#: its walls), and its growth rate is the same at either step; the walls and the
#: settling, which the step decides, run at the judged step (docs/chatter.md).
ONSET_STEP_RATIO = 2.5
#: A slope still rising is extrapolated only once each rise is at most this fraction of
#: the one before (a geometric tail that has set in).
MAX_RISE_RATIO = 0.0
#: A knock whose every amplitude has fallen to this fraction of its first window's has
#: died out: what is left is a floor where slopes are noise (the arithmetic's round-off
#: on a heavily damped bar, a ball stuck by its friction chattering in the sgn() law).
DECAYED = 1e-3
#: A settled status: above the tolerance and not falling (a verdict that needs no more).
ABOVE = "above the tolerance"
#: A settled status: falling (below the tolerance, or a linear bar's stable knock).
DECAYING = "decaying"
#: Verdicts (LEVELLED: a vibration neither growing nor decaying, for the settling to judge).
STABLE, CHATTER, UNDECIDED, LEVELLED = "stable", "chatter", "undecided", "levelled"


@dataclass(frozen=True)
class VerdictOptions:
    """How a simulated cut is judged (module doc).

    ``confidence``: of the growth rate's sign (0.5-0.999999); ``max_duration_s`` (s):
    the cap on one run; ``knock_m`` (m): the small disturbance of the onset (a tip
    amplitude); ``tolerance_m`` (m): the largest settled tip peak-to-peak that is
    chatter-free (a surface-finish budget); ``knocks_m`` (m): larger disturbances tried
    too; ``settle_tolerance``: the settled peak-to-peak converged to this fraction;
    ``min_segment``: windows in each of the three segments whose slopes are compared (at
    least 4; a verdict needs three of them); ``ball_start``: where a free ball starts
    across its gap, a fraction of the half gap from the centre (-1 and 1: on a wall);
    ``stick_law``: how the RK4 cut renders a ball's friction
    (:data:`~boringbar.simulate.STICK_LAWS`): "hold" by default, which holds a ball with
    the bar exactly, so that a friction-held vibration grows at its linear host's rate
    whatever the step (docs/chatter.md, "The step of a judged cut"); "sgn" the published
    law, whose chatter about y' = 0 damps it by an amount that depends on the step;
    ``settle_cap_s`` (s): the cap on a run that goes on settling after its onset grew
    (None: ``max_duration_s``; the lobes' ball search gives its longer cap);
    ``onset_step_ratio``: the onset's RK4 step as a multiple of the judged step (1-10;
    :func:`onset_step`; 1 runs the whole cut at the judged step).
    """

    confidence: float = CONFIDENCE
    max_duration_s: float = MAX_DURATION_S
    knock_m: float = KNOCK_M
    tolerance_m: float = TOLERANCE_M
    knocks_m: tuple[float, ...] = ()
    settle_tolerance: float = SETTLE_TOLERANCE
    min_segment: int = MIN_SEGMENT
    ball_start: float = 0.0
    stick_law: str = "hold"
    settle_cap_s: float | None = None
    onset_step_ratio: float = ONSET_STEP_RATIO

    def __post_init__(self):
        check_range("confidence", self.confidence, 0.5, 0.999999, lo_open=True)
        check_range("max_duration_s", self.max_duration_s, 0.0, 1000.0, lo_open=True, unit="s")
        check_range("knock_m", self.knock_m, 0.0, 1e-3, lo_open=True, unit="m")
        check_range("tolerance_m", self.tolerance_m, 0.0, 1.0, lo_open=True, unit="m")
        if self.knocks_m:
            object.__setattr__(self, "knocks_m", check_values(
                "knocks_m", self.knocks_m, 0.0, 1e-2, lo_open=True, unit="m"))
        check_range("settle_tolerance", self.settle_tolerance, 0.0, 0.5, lo_open=True)
        check_int("min_segment", self.min_segment, 4, 10_000)
        check_range("ball_start", self.ball_start, -1.0, 1.0)
        check_choice("stick_law", self.stick_law, STICK_LAWS)
        if self.settle_cap_s is not None:
            check_range("settle_cap_s", self.settle_cap_s, self.max_duration_s, 1000.0,
                        unit="s")
        check_range("onset_step_ratio", self.onset_step_ratio, 1.0, 10.0)

    @property
    def settle_cap(self) -> float:
        """The cap (s) on a run that settles after a chattering onset."""
        return self.max_duration_s if self.settle_cap_s is None else self.settle_cap_s

    def to_dict(self) -> dict:
        return {"confidence": self.confidence, "max_duration_s": self.max_duration_s,
                "knock_m": self.knock_m, "tolerance_m": self.tolerance_m,
                "knocks_m": list(self.knocks_m), "settle_tolerance": self.settle_tolerance,
                "min_segment": self.min_segment, "ball_start": self.ball_start,
                "stick_law": self.stick_law, "onset_step_ratio": self.onset_step_ratio}


@dataclass(frozen=True)
class Settled:
    """The settled vibration of one start: ``pp_m`` and ``rms_m`` (m) of the tip over the
    last quarter of the windows, ``left_cut`` (the tool left the cut there), ``status``
    ("settled", "decaying": below the tolerance and still falling, or on a bar without
    a ball whose onset is stable and the tool in the cut, "left the cut",
    "undecided": the cap came first), ``duration_s`` (s) run."""

    pp_m: float
    rms_m: float
    left_cut: bool
    status: str
    duration_s: float


@dataclass(frozen=True)
class CutVerdict:
    """A cut judged (module doc).

    ``onset``: STABLE, CHATTER or UNDECIDED for a small knock; ``growth_rate_per_s``
    and its standard error ``growth_rate_se`` (1/s: the last quarter's slope of ln A);
    ``onset_duration_s`` (s): the run length that decided it; ``settled``: the settled
    vibration of each start (the small knock first, then ``knocks_m``; empty where the
    onset decides alone); ``chatter_free``: True, False or None (undecided)."""

    onset: str
    growth_rate_per_s: float
    growth_rate_se: float
    onset_duration_s: float
    chatter_free: bool | None
    settled: tuple[Settled, ...] = field(default_factory=tuple)

    @property
    def settled_pp_m(self) -> float:
        """The largest settled peak-to-peak over the starts (m; 0 for a stable onset)."""
        return max((s.pp_m for s in self.settled), default=0.0)

    @property
    def settled_rms_m(self) -> float:
        """The largest settled RMS over the starts (m; 0 for a stable onset)."""
        return max((s.rms_m for s in self.settled), default=0.0)

    @property
    def duration_s(self) -> float:
        """Simulated time spent on this verdict (s)."""
        return self.onset_duration_s + sum(s.duration_s for s in self.settled)


def window_steps(system: System, cut: Regenerative, dt_s: float) -> int:
    """Steps of one window: whole revolutions, at least WINDOW_PERIODS periods of the host
    bar's first mode."""
    period = 2 * math.pi / system.reference_frequency_rad_s
    revs = max(1, math.ceil(WINDOW_PERIODS * period / cut.tau_s - 1e-9))
    return max(1, int(round(revs * cut.tau_s / dt_s)))


def slopes(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares slopes of the columns of y (windows x observables) against t, and
    their standard errors."""
    # the means as np.mean forms them (the sum over the count), without its overhead:
    # every window of every cut fits a few of these
    n = len(t)
    tm = t - np.add.reduce(t) / n
    sxx = float(tm @ tm)
    yc = y - np.add.reduce(y, axis=0) / n
    b = (tm @ yc) / sxx
    r = yc - tm[:, None] * b
    return b, np.sqrt(np.add.reduce(r * r, axis=0) / (n - 2) / sxx)


@functools.lru_cache(maxsize=256)
def t_quantile(confidence: float, dof: int) -> float:
    """Student's t quantile of a two-sided ``confidence`` with ``dof`` degrees of freedom
    (kept: every window of every cut asks for one of a few)."""
    return float(special.stdtrit(dof, 0.5 + confidence / 2))


def segment(n: int, min_segment: int) -> int:
    """The length of each of the last three segments compared out of ``n`` windows: a
    sixth, so that they cover the latter half (at least ``min_segment``)."""
    return max(min_segment, n // 6)


def growth(t: np.ndarray, logs: np.ndarray, options: VerdictOptions,
           settles: bool = False) -> tuple[str, float, float]:
    """(verdict so far, growth rate, its standard error) from window ends ``t`` and the
    log amplitudes ``logs`` (windows x observables, :meth:`Track.logs`): CHATTER as soon as
    one observable grows at the confidence over the last two segments (one alone may be
    a beat over a floor of persistent small vibration), STABLE once every one decays and
    has stopped rising, LEVELLED (with ``settles``: a bar that can bound its vibration)
    once every one changes by less than ``settle_tolerance`` over the three segments,
    else UNDECIDED (not yet; module doc).  The rate is the largest observable's last
    slope."""
    n, m = len(t), segment(len(t), options.min_segment)
    if n < 3 * m:
        return UNDECIDED, math.nan, math.nan
    y = logs[n - 3 * m:]
    moving = np.add.reduce(y > LOG_ZERO, axis=0) > 0
    if not moving.all():
        # an observable at exactly zero over the segments (a bending plane that neither
        # the cut nor the ball reaches) can neither grow nor decay: it is no evidence
        if not moving.any():
            return STABLE, math.nan, math.nan  # nothing moves, so nothing grows
        y = y[:, moving]
    q = t_quantile(options.confidence, m - 2)
    span = t[-1] - t[n - 3 * m]
    t3 = t[n - 3 * m:]
    (b0s, _), (b1s, s1s), (b2s, s2s) = (slopes(t3[k * m:(k + 1) * m], y[k * m:(k + 1) * m])
                                        for k in (0, 1, 2))
    rates, stable, level = [], True, settles
    for b0, b1, s1, b2, s2 in zip(b0s.tolist(), b1s.tolist(), s1s.tolist(), b2s.tolist(),
                                  s2s.tolist(), strict=True):
        rates.append((b2, s2))
        if b2 - q * s2 > 0 and b1 - q * s1 > 0:
            return CHATTER, b2, s2
        # the first segment's scatter holds the curvature of a transient, which is
        # evidence of change, not noise: the rises are measured against the later two
        noise = (q * math.sqrt(2.0) * s1, q * math.hypot(s1, s2))
        stable = stable and b2 + rise_left(b0, b1, b2, noise) + q * s2 < 0
        level = level and max(abs(b0), abs(b1), abs(b2)) * span < options.settle_tolerance
    b, se = max(rates)
    return (STABLE if stable else LEVELLED if level else UNDECIDED), b, se


def observables(system: System, window: Window) -> np.ndarray:
    """What one window's growth is measured on: the tip's amplitude (half its
    peak-to-peak), each bending mode's and an absorber's stroke (its largest |x_a -
    psi_a u|; the absorber's static stroke is zero), so that a mode whose chatter grows
    under a larger one's decay shows at once."""
    tmd = [window.max_rel_m] if system.kind == "tmd" else []
    return np.concatenate(([window.half_pp_m], window.mode_half_pp, tmd))


def rise_left(b0: float, b1: float, b2: float, noise: tuple[float, float]) -> float:
    """How much further the slope may still rise, from three successive segments' slopes
    and the noise of each rise: the last rise where both rises are within their noise
    (the slope has levelled); else, while the rises shrink geometrically (each
    positive, the last at most MAX_RISE_RATIO of the one before), the tail of that
    series (Aitken's extrapolation); else infinity (not yet known: a slope that rose
    and fell again is a beat, not a trend)."""
    r1, r2 = b1 - b0, b2 - b1
    if abs(r1) <= noise[0] and r2 <= noise[1]:
        return max(r2, 0.0)
    if r1 > noise[0] and 0.0 < r2 <= MAX_RISE_RATIO * r1:
        return r2 * r2 / (r1 - r2)
    return math.inf


class Track:
    """The windows of a run as the verdict reads them, kept as they come (so that a
    window's test costs the same however long the run): each window's end time,
    observables (:func:`observables`) and their logs in growing arrays, the tip's
    extremes and mean square, and the last window that left the cut, struck a wall or
    ran with the ball not held."""

    def __init__(self, system: System, windows=()):
        self.system = system
        self.n = 0
        self._ends = np.empty(64)
        self._amps = self._logs = None
        self.tops: list[float] = []
        self.bottoms: list[float] = []
        self.squares: list[float] = []
        self.last_left = self.last_struck = self.last_loose = -1
        self.last: Window | None = None
        for w in windows:
            self.add(w)

    def add(self, w: Window) -> None:
        amp = observables(self.system, w)
        if self._amps is None:
            self._amps, self._logs = np.empty((64, amp.size)), np.empty((64, amp.size))
        if self.n == len(self._ends):
            self._ends = np.concatenate([self._ends, np.empty_like(self._ends)])
            self._amps = np.concatenate([self._amps, np.empty_like(self._amps)])
            self._logs = np.concatenate([self._logs, np.empty_like(self._logs)])
        k = self.n
        self._ends[k], self._amps[k] = w.t_end_s, amp
        self._logs[k] = np.log(np.maximum(amp, AMP_ZERO))
        self.tops.append(w.max_tip_m)
        self.bottoms.append(w.min_tip_m)
        self.squares.append(w.rms_tip_m**2)
        if w.left_cut:
            self.last_left = k
        if w.impacts:
            self.last_struck = k
        if not w.held:
            self.last_loose = k
        self.last = w
        self.n += 1

    @property
    def ends(self) -> np.ndarray:
        return self._ends[:self.n]

    @property
    def amps(self) -> np.ndarray:
        return self._amps[:self.n]

    @property
    def logs(self) -> np.ndarray:
        return self._logs[:self.n]

    def pp(self, start: int, stop: int) -> float:
        """The tip's peak-to-peak over windows ``start`` to ``stop`` - 1."""
        return max(self.tops[start:stop]) - min(self.bottoms[start:stop])


def onset(stepper: CutStepper, options: VerdictOptions) -> tuple[str, float, float, Track]:
    """Advance ``stepper`` (a knocked cut) until the growth rate's sign is decided or the
    cap: (verdict, rate, its error, the windows)."""
    track = Track(stepper.system)
    settles = bounds_small(stepper.system)
    verdict, rate, se = UNDECIDED, math.nan, math.nan
    while stepper.t_s < options.max_duration_s:
        track.add(stepper.advance())
        if track.last_left >= 0:
            return CHATTER, rate, se, track
        verdict, rate, se = growth(track.ends, track.logs, options, settles=settles)
        if verdict == LEVELLED:
            return UNDECIDED, rate, se, track
        if verdict != UNDECIDED:
            break
        if np.all(track.amps[-1] < DECAYED * track.amps[0]):
            return STABLE, rate, se, track  # below what a slope can be measured on
    return verdict, rate, se, track


def bounds_small(system: System) -> bool:
    """Whether a small vibration of ``system`` can settle without growing or dying out:
    a ball's friction bounds it (a frictionless ball off its walls leaves the bar linear)."""
    return system.kind == "ball" and system.damper.friction_force_n > 0


def settle(stepper: CutStepper, windows: list | Track, options: VerdictOptions, t0_s: float,
           onset_rate: float = math.nan, values: bool = True,
           linear_stable: bool = False) -> Settled:
    """Run ``stepper`` on until its vibration settles (module doc); ``windows`` so far,
    ``onset_rate`` (1/s) the growth rate of its onset where it chattered.

    Settled: the tool stayed in the cut over the last quarter of the windows, the
    peak-to-peak over it and over the quarter before agree within
    ``settle_tolerance``, and the amplitude's trend over the two changes it by less
    than that (every observable's, :func:`observables`); after a chattering onset also the
    fastest growth has fallen below half the onset's (a vibration still growing as it
    began has met nothing that bounds it).  Decaying: below the tolerance and every
    observable falling at the confidence.  Without ``values`` (a verdict that needs only
    which side of the tolerance the vibration settles on) a vibration above the
    tolerance over both quarters, its growth levelled and not falling is "above the
    tolerance" at once.  ``linear_stable``: a knock on a bar without a ball whose onset
    is stable: linear while the tool stays in the cut, so decaying, however slowly it
    shows, once the tool stays in the cut over both quarters and nothing grows."""
    tol = options.settle_tolerance
    track = windows if isinstance(windows, Track) else Track(stepper.system, windows)
    while True:
        n = track.n
        if n >= 2 * options.min_segment:
            m = max(options.min_segment, n // 4)
            pp, pp0 = track.pp(n - m, n), track.pp(n - 2 * m, n - m)
            rms = math.sqrt(sum(track.squares[n - m:]) / m)
            duration = stepper.t_s - t0_s
            if track.last_left >= n - m:
                return Settled(pp, rms, True, "left the cut", duration)
            t = track.ends[n - 2 * m:]
            b, se = slopes(t, track.logs[n - 2 * m:])
            fits = list(zip(b.tolist(), se.tolist(), strict=True))
            q = t_quantile(options.confidence, 2 * m - 2)
            # still growing: once the ball strikes, some amplitude certainly grows by more
            # than the settling tolerance over the span (the impacts' scatter is not
            # growth); before, after an onset that grew, at half the onset's rate (the
            # linear growth goes on); else only the trend below tells
            span = t[-1] - t[0]
            struck = track.last_struck >= n - 2 * m
            floor = (tol / span if struck else 0.5 * onset_rate if onset_rate > 0
                     else math.inf)
            growing = any(b - q * se >= floor for b, se in fits)
            trend = max(abs(b) for b, _ in fits) * span
            levelled = not growing
            if (linear_stable and track.last_left < n - 2 * m
                    and all(b - q * se < 0 for b, se in fits)):
                return Settled(pp, rms, False, DECAYING, duration)
            if levelled and abs(pp - pp0) <= tol * max(pp, pp0) and trend <= tol:
                return Settled(pp, rms, False, "settled", duration)
            if pp < options.tolerance_m and all(b + q * se < 0 for b, se in fits):
                return Settled(pp, rms, False, DECAYING, duration)
            if (not values and levelled and min(pp, pp0) > options.tolerance_m
                    and -tol < fits[0][0] * span):
                return Settled(pp, rms, False, ABOVE, duration)
            if stepper.t_s >= (options.settle_cap if onset_rate > 0 else options.max_duration_s):
                return Settled(pp, rms, False, UNDECIDED, duration)
            if onset_rate > 0 and fast_forward(stepper, track, options):
                track = Track(stepper.system)
        track.add(stepper.advance())


#: A growth that is linear is scaled up, not waited for, while its departure is below
#: this fraction of the room it has (the tool's to leave the cut, a free ball's to its
#: walls, a held ball's friction to its static limit).
LINEAR_ROOM = 0.98


def fast_forward(stepper: CutStepper, track: Track, options: VerdictOptions) -> bool:
    """Jump a linear growth ahead: while a knock grows (the onset chatters) and the tool
    has never left the cut, the run is linear where a frictionless ball has never touched
    a wall, or where the stick law has held a ball with friction through the latter half
    of the windows (the locked bar).  Its departure from the steady cut is then scaled up
    (CutStepper.scale) until it fills LINEAR_ROOM of the room left: the chip thickness's
    to zero (its largest departure from the feed, read off the largest force, against
    the feed), and the ball's to its wall, or the force that holds it to the static
    friction F_s.  The run is the same, reached sooner.  Whether it jumped."""
    system, cut = stepper.system, stepper.forcing
    if system.kind != "ball" or cut.force_noise > 0:
        return False
    if track.last_left >= 0 or track.last_struck >= 0:
        return False
    d, last = system.damper, track.last
    if d.friction_force_n > 0:
        if track.last_loose >= track.n // 2 or last.max_hold_n <= 0:
            return False
        ball_room = d.static_friction_force_n / last.max_hold_n
    else:
        y0 = abs(stepper.x_start[2 * system.bar.n_modes])
        ball_room = (d.gap_m / 2 - y0) / max(last.max_rel_m - y0, 1e-300)
    law = cut.law
    h_max = (last.max_force_n / law.kernel_coefficient(cut.depth_m)) ** (
        1.0 / (1.0 - law.exponent))
    factor = LINEAR_ROOM * min(ball_room, cut.feed_m / max(h_max - cut.feed_m, 1e-300))
    if factor < 1.05:
        return False
    stepper.scale(factor, held=d.friction_force_n > 0)
    return True


def _stepper(system: System, cut: Regenerative, dt_s: float, knock_m: float,
             options: VerdictOptions) -> CutStepper:
    cut = replace(cut, start="static", stop_at_zero=False)
    half = system.damper.gap_m / 2 if system.kind == "ball" else 0.0
    return CutStepper(system, cut, dt_s=dt_s, window_steps=window_steps(system, cut, dt_s),
                      initial=knocked_cut(system, cut, knock_m, options.ball_start * half),
                      stick_law=stick_law_of(system, options))


def stick_law_of(system: System, options: VerdictOptions) -> str:
    """The law of ``system``'s ball friction in its judged cuts: the options', but the
    sgn() law for a rolling ball (RK4's stick law holds a sliding ball only)."""
    return "sgn" if rolling(system) else options.stick_law


def onset_step(system: System, dt_s: float, ratio: float = ONSET_STEP_RATIO) -> float:
    """The RK4 step (s) of a judged cut's onset on ``system`` whose judged step is
    ``dt_s``: ``ratio`` times it, at most the step that keeps
    :data:`JUDGED_STEPS_PER_PERIOD` steps in the bar's shortest period, at least
    ``dt_s``."""
    return max(dt_s, min(ratio * dt_s, shortest_period(system) / JUDGED_STEPS_PER_PERIOD))


def judged_step(systems, dt_s: float | None = None) -> float:
    """The RK4 step (s) of the judged cuts of ``systems``: ``dt_s`` where given, else
    :data:`JUDGED_STEP_S`, or finer where a bar's highest mode or absorber would have
    fewer than :data:`JUDGED_STEPS_PER_PERIOD` steps a period."""
    if dt_s is not None:
        return float(dt_s)
    shortest = min(shortest_period(s) for s in systems)
    return min(JUDGED_STEP_S, shortest / JUDGED_STEPS_PER_PERIOD)


def verdict_attrs(options: VerdictOptions, systems) -> dict:
    """The verdict's options as a Dataset's attributes (lists as JSON); the stick law only
    where one of ``systems`` has a ball with friction, the only bar it concerns."""
    attrs = {k: (json.dumps(v) if isinstance(v, list) else v)
             for k, v in options.to_dict().items()}
    if not any(bounds_small(s) for s in systems):
        del attrs["stick_law"]
    return attrs


def step_text(attrs: dict) -> str:
    """How a judged cut was stepped, for a method line after its step (from a Dataset's
    attributes, which carry the verdict's options): the onset's coarser step, and how a
    ball's friction was rendered."""
    ratio = float(attrs.get("onset_step_ratio", 1.0))
    onset = f" (the onset at {ratio:g} dt)" if ratio != 1.0 else ""
    law = {"hold": " (a ball's friction by the stick law",
           "sgn": " (a ball's friction by the published sgn() law"}.get(
               attrs.get("stick_law"), "")
    if law:
        rolls = attrs.get("stick_law") == "hold" and _dampers_have(attrs, "motion", "roll")
        law += ", a rolling ball's by the sgn() law)" if rolls else ")"
    return onset + law + contact_text(attrs)


def _dampers_have(attrs: dict, key: str, value: str) -> bool:
    """Whether a ball of the Dataset's systems (attribute ``systems``, as JSON) has
    ``key`` = ``value``."""
    systems = attrs.get("systems")
    described = json.loads(systems) if isinstance(systems, str) else systems or {}
    return any((s.get("damper") or {}).get(key) == value
               for s in described.values() if isinstance(s, dict))


def contact_text(attrs: dict) -> str:
    """" (the ball's walls by a Hertz contact)" where a system of the Dataset's attributes
    (``systems``, as JSON) has one; else nothing (the impact law)."""
    return " (the ball's walls by a Hertz contact)" if _dampers_have(attrs, "contact",
                                                                     "hertz") else ""


def acceptable(s: Settled, options: VerdictOptions) -> bool | None:
    """Whether a settled vibration is chatter-free (None: undecided)."""
    if s.left_cut:
        return False
    if s.status in (UNDECIDED, ABOVE):
        return False if s.pp_m > options.tolerance_m else None
    return s.status == DECAYING or s.pp_m <= options.tolerance_m


def judge(system: System, cut: Regenerative, options: VerdictOptions | None = None, *,
          dt_s: float | None = None, values: bool = False) -> CutVerdict:
    """The converged verdict of ``cut`` on ``system`` (module doc), RK4 at ``dt_s``
    (None: :func:`judged_step`'s).
    ``values``: run every start until its vibration settles, even where it is already
    above the tolerance (the settled values themselves wanted, as by the chatter map);
    without it a vibration above the tolerance and not falling ends its run."""
    options = options or VerdictOptions()
    dt_s = judged_step([system], dt_s)
    if cut.force_noise > 0:
        stepper = _stepper(system, cut, dt_s, options.knock_m, options)
        return _noisy(system, cut, options, dt_s, stepper, values)
    stepper = _stepper(system, cut, onset_step(system, dt_s, options.onset_step_ratio),
                       options.knock_m, options)
    verdict, rate, se, windows = onset(stepper, options)
    if windows.last_struck >= 0 and stepper.dt_s != dt_s:
        # the ball reached a wall, whose impacts the judged step resolves: run it again
        stepper = _stepper(system, cut, dt_s, options.knock_m, options)
        verdict, rate, se, windows = onset(stepper, options)
    onset_s = stepper.t_s
    settled: list[Settled] = []
    if system.kind != "ball":  # linear until the tool leaves the cut: the onset decides
        ok = [{STABLE: True, CHATTER: False}.get(verdict)]
    elif verdict == STABLE:
        ok = [True]
    else:
        if stepper.dt_s != dt_s:
            stepper = stepper.refined(dt_s, window_steps(system, stepper.forcing, dt_s))
        settled.append(settle(stepper, windows, options, onset_s, rate, values))
        ok = [acceptable(settled[0], options)]
    big = knocked(system, cut, options, dt_s, values,
                  linear_stable=system.kind != "ball" and verdict == STABLE)
    settled += big
    ok += [acceptable(x, options) for x in big]
    return CutVerdict(verdict, rate, se, onset_s, _all_of(ok), tuple(settled))


def knocked(system: System, cut: Regenerative, options: VerdictOptions, dt_s: float,
            values: bool, linear_stable: bool = False) -> list:
    """The settled vibration from each large knock of ``options.knocks_m``
    (``linear_stable``: as :func:`settle` says)."""
    return [settle(_stepper(system, cut, dt_s, knock, options), [], options, 0.0,
                   values=values, linear_stable=linear_stable) for knock in options.knocks_m]


def _all_of(ok: list) -> bool | None:
    """True if every start is chatter-free, False if one is not, else None."""
    return False if False in ok else (None if None in ok else True)


def _noisy(system: System, cut: Regenerative, options: VerdictOptions, dt_s: float,
           stepper: CutStepper, values: bool) -> CutVerdict:
    """A cut whose force is noisy never falls silent: the noise keeps every mode
    vibrating, so a small knock's growth rate has no sign to find.  Every start is run
    until its vibration settles, and judged by it alone (onset UNDECIDED, its rate the
    settled run's)."""
    settled = [settle(stepper, [], options, 0.0, values=values),
               *knocked(system, cut, options, dt_s, values)]
    return CutVerdict(UNDECIDED, math.nan, math.nan, 0.0,
                      _all_of([acceptable(x, options) for x in settled]), tuple(settled))
