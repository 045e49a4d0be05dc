"""Pseudo-arclength continuation of a periodic orbit of P^k (docs/continuation.md).

The unknowns are (x, p): the orbit's state at the section's phase (0 by default)
and the parameter.  The residual G(x, p) = P^k(x; p) - x; G_x = monodromy - I
comes from the saltation matrices (:mod:`boringbar.shooting`), G_p by a central
difference in p.  Each step predicts along the unit tangent of the branch (null
vector of [G_x, G_p] in scaled variables) and corrects by Newton on G = 0 plus
the arclength condition, so folds are passed.  The step adapts: halved when
Newton fails, grown by 1.3 after quick convergence.

The branch stops (with the reason) at the end of the range, where the orbit is
refused (stick, wall contact, a singular Newton matrix), or at a change of the
impact/reversal sequence, located by bisection in p and recorded as a "grazing".
An event that comes near the Poincare section (or crosses it) moves the section
instead (:func:`_move_section`; the point is carried to the new phase).  The
multipliers of two points are paired; a pair crossing the unit circle is an event:
fold (+1, the branch turns; located where the tangent's p component vanishes),
branch point (+1, the branch goes on), period doubling (-1), Neimark-Sacker (a
complex pair), the last three located by bisection along the arclength.  At a
period doubling, :func:`switch_period_doubling` starts the period-2k branch.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, linear_sum_assignment

from boringbar._validate import ParameterError, check_range
from boringbar.shooting import (
    Flow,
    OrbitRefused,
    advance,
    carry,
    check_residual,
    free_phase,
    multipliers,
    newton_step,
    one_blas_thread,
    periodic_orbit,
)

#: The parameters a branch can follow (the CLI's names).
PARAMETERS = ("force-n", "ratio", "gap-mm", "restitution", "friction-force-n", "ball-mass-g")
#: Those that exist for each bar (:attr:`System.kind`): the solid and TMD bars have no
#: ball, the locked ball no gap, impacts or friction.
PARAMETERS_OF = {"ball": PARAMETERS, "locked": ("force-n", "ratio", "ball-mass-g"),
                 "solid": ("force-n", "ratio"), "tmd": ("force-n", "ratio")}


def check_parameter(kind: str, name: str) -> str:
    """``name`` if the bar ``kind`` has that parameter, else a ParameterError."""
    allowed = PARAMETERS_OF[kind]
    if name not in allowed:
        raise ParameterError(f"parameter = {name!r} is not one of {', '.join(allowed)} "
                             f"(the parameters of the {kind} bar)")
    return name


def flow_with(fl: Flow, name: str, value: float, ref: Flow) -> Flow:
    """``fl`` with the parameter ``name`` set to ``value`` (``ref``: the starting flow,
    for the scalings of the impact threshold)."""
    if name == "force-n":
        return dataclasses.replace(fl, amplitude=value)
    if name == "ratio":
        ratio0 = ref.omega / ref.reference
        return dataclasses.replace(fl, omega=value * ref.reference,
                                   v_impact=ref.v_impact * value / ratio0)
    if name == "gap-mm":
        half = value * 0.5e-3
        return dataclasses.replace(fl, half=half, v_impact=ref.v_impact * half / ref.half)
    if name == "restitution":
        return dataclasses.replace(fl, e=value)
    if name == "friction-force-n":
        ratio = ref.fs / ref.fc if ref.fc > 0 else 1.0
        return dataclasses.replace(fl, fc=value, fs=value * ratio)
    if name == "ball-mass-g":
        m = value * 1e-3
        return dataclasses.replace(fl, m=m, meff=1.0 / (1.0 / m + float(np.sum(
            fl.psi_d**2 / fl.M))))
    raise ParameterError(f"parameter = {name!r} is not one of {', '.join(PARAMETERS)}")


def value_of(fl: Flow, name: str) -> float:
    """The current value of parameter ``name`` in ``fl`` (CLI units)."""
    return {"force-n": fl.amplitude, "ratio": fl.omega / fl.reference, "gap-mm": fl.half * 2e3,
            "restitution": fl.e, "friction-force-n": fl.fc, "ball-mass-g": fl.m * 1e3}[name]


@dataclass
class Point:
    """One orbit of a branch."""

    value: float
    x: np.ndarray
    multipliers: np.ndarray
    events: list
    #: The forcing phase of the Poincare section x is on (rad).
    phase: float = 0.0

    @property
    def stable(self) -> bool:
        """All multipliers strictly inside the unit circle."""
        return bool(np.all(np.abs(self.multipliers) < 1.0))


@dataclass
class Branch:
    """A continued branch: its points, its events (kind, value) and why it stopped."""

    parameter: str
    periods: int
    points: list = field(default_factory=list)
    events: list = field(default_factory=list)
    stop: str = ""
    #: The orbit it branched from (a period-doubling point), if any.
    origin: Point | None = None
    #: How often the Poincare section was moved away from an event.
    section_moves: int = 0
    #: The located branch points (:class:`BranchPoint`), for branch switching.
    branch_points: list = field(default_factory=list)


@dataclass
class BranchPoint:
    """A branch point: the orbit there (unknowns (x, p), on the section ``phase``), the
    scales of the walk it was found on, the branch's tangent there and the other branch's
    (the second null vector of [G_x, G_p], both scaled and of unit length)."""

    y: np.ndarray
    phase: float
    scale: np.ndarray
    tangent: np.ndarray
    other: np.ndarray


def _residual(fl, name, ref, x, p, k):
    f = flow_with(fl, name, p, ref)
    pr = advance(f, x, k)
    return pr.x - x, pr


def _jacobian(fl, name, ref, x, p, k, pr, dp):
    """[G_x, G_p] at (x, p); G_p exact for force-n (:func:`~boringbar.shooting.
    force_derivative`, with the map), else by a central difference of step dp."""
    if name == "force-n" and pr.force_derivative is not None:
        gp = pr.force_derivative
    else:
        gp = (_residual(fl, name, ref, x, p + dp, k)[0]
              - _residual(fl, name, ref, x, p - dp, k)[0]) / (2 * dp)
    return np.column_stack([pr.jacobian - np.eye(fl.N), gp])


def _kinds(events):
    return tuple(k for _, k in events)


def correct(fl, name, ref, y0, tangent, scale, k, tol=1e-11, max_iter=12):
    """Newton on G = 0 and tangent . (y - y0) / scale = 0 from y0; (y, Period, iterations).
    Given up as soon as a step from the fourth on is larger than the one before: Newton
    is not converging there, and each further iteration costs three maps (most of a
    branch's time went into correctors that failed after all their iterations)."""
    y = y0.copy()
    dp = 1e-7 * max(abs(y0[-1]), 1e-3)
    last = np.inf
    for it in range(max_iter):
        r, pr = _residual(fl, name, ref, y[:-1], y[-1], k)
        Jx = _jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp)
        A = np.vstack([Jx * scale, tangent])
        rhs = -np.concatenate([r, [tangent @ ((y - y0) / scale)]])
        dy = newton_step(A, rhs) * scale
        y = y + dy
        size = float(np.max(np.abs(dy / scale)))
        if size < tol:
            r, pr = _residual(fl, name, ref, y[:-1], y[-1], k)
            check_residual(r, y[:-1], "the corrector")
            return y, pr, it + 1
        if it >= 3 and size > last:
            break
        last = size
    raise OrbitRefused("the corrector did not converge")


def tangent_at(fl, name, ref, y, pr, scale, k, previous=None):
    """The unit tangent (scaled variables) of the branch at y, oriented like ``previous``."""
    dp = 1e-7 * max(abs(y[-1]), 1e-3)
    Jx = _jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp) * scale
    t = np.linalg.svd(Jx)[2][-1]
    if previous is not None and t @ previous < 0:
        t = -t
    return t / np.linalg.norm(t)


def _crossings(m0, m1):
    """The bifurcations between two points' multipliers: [(kind, (|mu0| - 1, |mu1| - 1))].
    The multipliers are paired by least total distance; a pair whose modulus crosses 1 is
    a fold (real, positive), a period doubling (real, negative) or, once for a conjugate
    pair, a Neimark-Sacker, as the multiplier is outside the circle.  Pairing, not
    counting, sees two crossings in one step (a complex pair going back inside while a
    real multiplier leaves at a fold)."""
    rows, cols = linear_sum_assignment(np.abs(m0[:, None] - m1[None, :]))
    found = []
    for i, j in zip(rows, cols, strict=True):
        g0, g1 = abs(m0[i]) - 1.0, abs(m1[j]) - 1.0
        if (g0 > 0) == (g1 > 0):
            continue
        # classified by its value outside the circle (inside, a real multiplier may be
        # one of a complex pair that met on the real axis during the step)
        mu = m1[j] if g1 > 0 else m0[i]
        if abs(mu.imag) > 1e-6 * abs(mu):
            if mu.imag > 0:
                found.append(("neimark-sacker", (g0, g1)))
        else:
            found.append(("fold" if mu.real > 0 else "period-doubling", (g0, g1)))
    return found


@dataclass(frozen=True)
class Walk:
    """How a branch is followed: the flow and parameter (``ref``: the starting flow), P^k's
    k, the scales of (x, p), the range [lo, hi] of p, and the step control (scaled
    arclength, relative to the range)."""

    fl: Flow
    name: str
    ref: Flow
    periods: int
    scale: np.ndarray
    lo: float
    hi: float
    step: float = 0.02
    max_points: int = 200
    min_step: float = 1e-6
    max_step: float = 0.025
    #: Move the section away from an event that comes near it (else the branch stops
    #: where an event crosses it).
    move_section: bool = True
    #: The end of the range the branch walks towards (the other end is where it started;
    #: NaN: either end is the range's end, as for a branch switched to).
    stop: float = np.inf


#: The largest step, relative to the range, by default: at least 40 points cross the
#: range, so a multiplier that leaves the unit circle and comes back is seen.
MAX_STEP = 0.025
#: The default point budget allows this many crossings of the range at the largest step
#: (folds, and the state's own share of the arclength): the budget is a safety net, the
#: branch stops at the range's ends, a fold leaving it, a closed loop or a failure.
CROSSINGS = 12


#: The weight of the state's relative change in the arclength, against the parameter's
#: change relative to the range (:func:`_scale`).
STATE_SHARE = 0.25


def point_budget(max_step: float) -> int:
    """The default number of points of a branch whose steps are capped at ``max_step``
    (relative to the range)."""
    return int(np.ceil(CROSSINGS / max_step))


#: An event closer than this (rad of forcing phase) to the section moves the section.
SECTION_MARGIN = 2.0 * np.pi / 16
#: At most this many moves of the section a branch.
MAX_SECTION_MOVES = 100


@one_blas_thread
def continue_branch(fl: Flow, name: str, x0: np.ndarray, stop: float, *, periods: int = 1,
                    step: float = 0.02, max_points: int | None = None, min_step: float = 1e-6,
                    max_step: float = MAX_STEP, move_section: bool = True,
                    bounds: tuple | None = None) -> Branch:
    """Continue the orbit through x0 (near a fixed point of P^periods) in parameter ``name``
    from its value in ``fl`` towards ``stop``; ``step`` (the first), ``min_step`` and
    ``max_step`` relative to |stop - start|; ``max_points`` by default from the largest
    step (:func:`point_budget`); ``move_section``: see :class:`Walk`; ``bounds``: the
    range (lo, hi), if not [start, stop] (a branch from inside the range)."""
    p0 = value_of(fl, check_parameter(fl.kind, name))
    span = abs(stop - p0)
    if not span > 0:
        raise ParameterError(f"range end {stop!r} equals the start value {p0!r}")
    check_steps(step, min_step, max_step)
    br = Branch(name, periods)
    try:
        y, pr = _first(fl, name, fl, x0, p0, periods)
    except OrbitRefused as err:
        br.stop = f"refused at the start: {err}"
        return br
    lo, hi = bounds or (min(p0, stop), max(p0, stop))
    w = Walk(fl, name, fl, periods, _scale(fl, y[:-1], span), lo, hi, step,
             max_points or point_budget(max_step), min_step, max_step, move_section, stop)
    t = np.zeros(fl.N + 1)
    t[-1] = np.sign(stop - p0)
    t = tangent_at(fl, name, fl, y, pr, w.scale, periods, t)
    br.points.append(Point(y[-1], y[:-1].copy(), multipliers(pr), pr.events, fl.phase))
    return march(w, br, y, t)


def check_steps(step: float, min_step: float, max_step: float) -> None:
    """The step control's bounds (relative to the range): step and max_step in (0, 0.5],
    0 < min_step <= both, else a ParameterError naming the one out of range (a first step
    above max_step is cut to it)."""
    check_range("max_step", max_step, 0.0, 0.5, lo_open=True)
    check_range("step", step, 0.0, 0.5, lo_open=True)
    check_range("min_step", min_step, 0.0, min(step, max_step), lo_open=True)


def _scale(fl: Flow, x, span):
    """The scales of (x, p): one per block of the state (u, u', and each further entry:
    y, y' or x_a, x_a'), its largest |x_i| (u and u' at least the other's size over
    Omega, times Omega; the ball's y and y' at least the half gap, times Omega), and the
    range's span for p.  Rescaled at every point, so the state's share of the arclength
    is its relative change, counted at STATE_SHARE of the parameter's (so the steps
    follow the parameter, and a state that doubles over the range does not take ten
    times the points)."""
    x = np.asarray(x, float)
    n, om = fl.n, fl.omega
    u, v = float(np.max(np.abs(x[:n]))), float(np.max(np.abs(x[n:2 * n])))
    sc = np.concatenate([np.full(n, max(u, v / om)), np.full(n, max(v, om * u))])
    rest = np.abs(x[2 * n:])
    if fl.ball:
        rest = np.maximum(rest, [fl.half, om * fl.half])
    sc = np.concatenate([sc, np.maximum(rest, 1e-3 * max(float(np.max(sc)), 1e-300))])
    return np.append(np.maximum(sc, 1e-300) / STATE_SHARE, span)


def _rescaled(w: Walk, x, t):
    """The walk with the scales of x, and the tangent t carried to them (unit length)."""
    scale = _scale(w.fl, x, w.scale[-1])
    t = t * w.scale / scale
    return dataclasses.replace(w, scale=scale), t / np.linalg.norm(t)


def march(w: Walk, br: Branch, y: np.ndarray, t: np.ndarray) -> Branch:
    """Follow ``br`` from its last point y (unknowns (x, p)) along the unit tangent t
    (scaled) by predictor-corrector steps until p leaves [w.lo, w.hi] (at the far end,
    or back at the start after a fold), the branch closes on itself, the event sequence
    changes (located: a grazing), the orbit is refused or w.max_points.  The step grows
    by 1.5 after a corrector of at most 3 iterations, shrinks by 0.7 after one of 7 or
    more, is halved when the corrector fails, and is never more than w.max_step."""
    fl, name, ref, k = w.fl, w.name, w.ref, w.periods
    h = min(w.step, w.max_step)
    while len(br.points) < w.max_points:
        try:
            yn, prn, its = correct(fl, name, ref, y + h * t * w.scale, t, w.scale, k)
            same = _kinds(prn.events) == _kinds(br.points[-1].events)
        except OrbitRefused as err:
            yn, same, why = None, False, str(err)
        far = yn is not None and np.linalg.norm((yn - y) / w.scale) > 2.0 * h
        if far and same:
            # the corrector went to another orbit, far from the prediction: as a failure
            yn, same, why = None, False, "the corrector left the branch"
        if not same:
            located = _sequence_change(w, y, t, h, yn, far)
            if located is None and h / 2 >= w.min_step:
                h /= 2
                continue
            if located is None:
                br.stop = (f"failure at {name} = {y[-1]:.10g}: {why} (step {h:.2g} of the "
                           "range)")
                return br
            kind = _boundary(br, w, located)
            moved = _move_section(br, w, t) if kind == "section" and w.move_section else None
            if moved is None:
                return br
            br.stop = ""
            w, y, t = moved
            fl, ref = w.fl, w.ref
            continue
        pt = Point(yn[-1], yn[:-1].copy(), multipliers(prn), prn.events, fl.phase)
        kinds = _record_crossing(br, br.points[-1], pt, w)
        br.points.append(pt)
        if _left_range(br, w) or _closed(br, w, yn, h):
            return br
        t_old, t = t, tangent_at(fl, name, ref, yn, prn, w.scale, k, t)
        _record_turn(br, w, t_old, t, kinds)
        y = yn
        w, t = _rescaled(w, y[:-1], t)
        h = min(w.max_step, h * 1.5) if its <= 3 else (h * 0.7 if its >= 7 else h)
        h = max(h, w.min_step)
        if w.move_section and _near_section(flow_with(fl, name, pt.value, ref), pt.events):
            w, y, t = _move_section(br, w, t) or (w, y, t)
            fl, ref = w.fl, w.ref
    br.stop = (f"point budget of {w.max_points} reached at {name} = "
               f"{br.points[-1].value:.10g}")
    return br


def _sequence_change(w: Walk, y, t, h: float, yn, far: bool):
    """The change of the event sequence a failed step points to, located
    (:func:`locate_boundary`), or None.  The corrector found an orbit with another
    sequence: the change lies between y and it (between y and the prediction if the
    orbit is far from it: the state at the section jumps when an event crosses it, but
    another orbit may also lie there).  The corrector failed: only at the smallest step,
    within four such steps ahead."""
    if yn is not None:
        return _beyond(w, y, yn[-1] if not far else y[-1] + h * t[-1] * w.scale[-1])
    if h / 2 >= w.min_step:
        return None
    return _beyond(w, y, y[-1] + 4.0 * h * t[-1] * w.scale[-1])


def _beyond(w: Walk, y, p_far: float):
    """A change of the event sequence between y and ``p_far`` (:func:`locate_boundary`),
    or None (no orbit with the old sequence reaches past y, or it reaches all the way:
    no change there)."""
    if p_far == y[-1]:
        return None
    last, width, boundary = locate_boundary(w.fl, w.name, w.ref, y, p_far, w.periods)
    if last is None or abs(last.value - p_far) <= 2 * width:
        return None
    if not boundary and not _at_section(flow_with(w.fl, w.name, last.value, w.ref),
                                        last.events, w.periods):
        return None  # Newton jumped to a coexisting orbit: no boundary (smaller steps)
    return last, width


def _left_range(br: Branch, w: Walk) -> bool:
    """Whether the last point left [w.lo, w.hi]; the stop reason says at which end (the
    far one, or the start's after a fold turned the branch back)."""
    p = br.points[-1].value
    if w.lo <= p <= w.hi:
        return False
    end = w.lo if p < w.lo else w.hi
    folds = [v for kind, v in br.events if kind == "fold"]
    if end == w.stop or not folds or not np.isfinite(w.stop):
        br.stop = f"end of range at {br.parameter} = {end:.10g} (last point {p:.10g})"
    else:
        br.stop = (f"fold at {br.parameter} = {folds[-1]:.10g}: the branch turned and left "
                   f"the range at {br.parameter} = {end:.10g} (last point {p:.10g})")
    return True


def _closed(br: Branch, w: Walk, y, h: float) -> bool:
    """Whether the branch came back to its first point (a closed loop): within the step of
    it, in scaled variables, after at least four points."""
    first = br.points[0]
    if len(br.points) < 5 or first.phase != br.points[-1].phase:
        return False
    d = np.linalg.norm((y - np.append(first.x, first.value)) / w.scale)
    if d > h:
        return False
    br.stop = f"closed loop: back at the first point ({br.parameter} = {first.value:.10g})"
    return True


def _section_distance(fl: Flow, events, phase: float) -> float:
    """The smallest distance (rad of forcing phase) from ``phase`` to an event's phase."""
    d = [abs((fl.omega * t - phase + np.pi) % (2.0 * np.pi) - np.pi) for t, _ in events]
    return min(d) if d else np.pi


def _near_section(fl: Flow, events) -> bool:
    """An event within SECTION_MARGIN of the section's phase, and a phase at least twice
    as far from every event (with events all round the period, moving would not help)."""
    d0 = _section_distance(fl, events, fl.phase)
    return d0 < SECTION_MARGIN and _section_distance(fl, events, free_phase(fl, events)) > 2 * d0


def _move_section(br: Branch, w: Walk, t: np.ndarray):
    """Move the Poincare section to the phase farthest from the events of the branch's
    last point and carry that point there (the multipliers do not change: the monodromies
    at two sections are similar): (walk, y, tangent), or None when the moves are used up
    or the orbit is refused at the new section.  The last point is replaced by its
    image; the tangent is the old one carried by the flow between the two sections."""
    pt = br.points[-1]
    at = flow_with(w.fl, w.name, pt.value, w.ref)
    if br.section_moves >= MAX_SECTION_MOVES:
        return None
    phase = free_phase(at, pt.events)
    try:
        dt = ((phase - at.phase) % (2.0 * np.pi)) / at.omega
        part = advance(at, pt.x, duration=dt)
        fl, ref = (dataclasses.replace(f, phase=phase) for f in (w.fl, w.ref))
        x, pr = periodic_orbit(flow_with(fl, w.name, pt.value, ref), part.x, w.periods,
                               rms=False)
    except OrbitRefused:
        return None
    moved = dataclasses.replace(w, fl=fl, ref=ref, scale=_scale(fl, x, w.scale[-1]))
    br.points[-1] = Point(pt.value, x, multipliers(pr), pr.events, phase)
    br.section_moves += 1
    y = np.append(x, pt.value)
    carried = np.append(part.jacobian @ (t[:-1] * w.scale[:-1]), t[-1] * w.scale[-1])
    return moved, y, tangent_at(fl, w.name, ref, y, pr, moved.scale, w.periods,
                                carried / moved.scale)


def _first(fl, name, ref, x0, p0, k):
    """The orbit at the start value, by Newton on G(x, p0) = 0."""
    x = np.asarray(x0, float).copy()
    for _ in range(30):
        r, pr = _residual(fl, name, ref, x, p0, k)
        dx = newton_step(pr.jacobian - np.eye(fl.N), -r)
        x = x + dx
        if np.max(np.abs(dx)) < 1e-12 * np.max(np.abs(x)):
            r, pr = _residual(fl, name, ref, x, p0, k)
            check_residual(r, x, "Newton at the start value")
            return np.concatenate([x, [p0]]), pr
    raise OrbitRefused("Newton did not converge at the start value")


def locate_boundary(fl, name, ref, y, p_far, k, tol=1e-10):
    """Bisection in the parameter between y (unknowns (x, p), its event sequence) and
    ``p_far``, where the orbit has another sequence or is refused, down to ``tol`` of
    the distance: the last orbit with y's sequence (a :class:`Point`), the bracket's
    width, and whether the bracket's far end is a boundary.  Each trial is Newton at
    fixed p from the last good orbit (an arclength corrector's iterates would cross the
    non-smooth boundary and fail).  A trial far from the last good orbit can land on
    another orbit that coexists there (near a grazing the orbits born there are close by);
    so a far end set by an orbit with another sequence (not by a refusal) is tried once
    more from the last good orbit, a bracket's width beyond it: if the old sequence goes
    on there, it is no boundary."""
    kinds = _kinds(advance(flow_with(fl, name, y[-1], ref), y[:-1], k).events)
    lo, hi, x, last = y[-1], p_far, y[:-1], None
    width = abs(hi - lo)

    def trial(p):
        """(x, Period) of the orbit Newton finds at p from x, or None if refused."""
        try:
            return periodic_orbit(flow_with(fl, name, p, ref), x, k, max_iter=12, rms=False)
        except OrbitRefused:
            return None
    jumped = False
    while abs(hi - lo) > max(tol * width, 4 * np.finfo(float).eps * abs(lo)):
        mid = 0.5 * (lo + hi)
        found = trial(mid)
        if found is not None and _kinds(found[1].events) == kinds:
            lo, x, last = mid, found[0], Point(mid, found[0].copy(), multipliers(found[1]),
                                               found[1].events, fl.phase)
        else:
            hi, jumped = mid, found is not None
    if last is None or not jumped:
        return last, abs(hi - lo), True
    again = trial(lo + 2.0 * (hi - lo))
    return last, abs(hi - lo), again is None or _kinds(again[1].events) != kinds


def _at_section(fl: Flow, events, k: int) -> bool:
    """An event within 1e-6 T of the section (the start or the end of the k periods)."""
    t0 = fl.phase / fl.omega
    return any(min(t - t0, t0 + k * fl.period - t) < 1e-6 * fl.period for t, _ in events)


def _boundary(br, w: Walk, located) -> str:
    """Stop at a change of the event sequence located by :func:`locate_boundary`: its
    last orbit ends the branch, its parameter is the event's value: "section" if an
    event of that orbit is at the Poincare section (the same orbit goes on, but P is not
    smooth there), else "grazing" (an impact or reversal appears or vanishes)."""
    last, width = located
    if last is not None:
        _record_crossing(br, br.points[-1], last, w)
        br.points.append(last)
    p = br.points[-1].value
    at = flow_with(w.fl, w.name, p, w.ref)
    kind = "section" if _at_section(at, br.points[-1].events, w.periods) else "grazing"
    br.events.append((kind, float(p)))
    what = ("an impact or reversal crosses the Poincare section's phase (a section at "
            "another phase would carry on)" if kind == "section" else "grazing")
    br.stop = (f"the impact/reversal sequence changes at {br.parameter} = {p:.10g} "
               f"(bracket {width:.2g}; {what}): the branch is not followed across it")
    return kind


def _record_turn(br: Branch, w: Walk, t_old, t_new, kinds) -> None:
    """A fold the multipliers did not show (the branch turned between its last two points:
    the tangent's p component changed sign, while several multipliers moved at once)."""
    if t_old[-1] * t_new[-1] < 0 and "fold" not in kinds:
        a, b = br.points[-2], br.points[-1]
        value = locate_fold(w, a, b)
        br.events.append(("fold", value if value is not None else 0.5 * (a.value + b.value)))


def _record_crossing(br, a, b, w: Walk | None = None) -> list:
    """Record the stability changes between the points a and b; their kinds."""
    found = _crossings(a.multipliers, b.multipliers)
    kinds = []
    for kind, g in found:
        # the secant of |mu| - 1, kept between the two points
        s = min(max(g[0] / (g[0] - g[1]), 0.0), 1.0) if g[0] != g[1] else 0.5
        value = float(a.value + s * (b.value - a.value))
        turned = locate_fold(w, a, b) if kind == "fold" and w is not None else None
        if kind == "fold" and w is not None and turned is None:
            # a +1 multiplier where the branch does not turn: a branch point (here the
            # symmetric orbit's symmetry-breaking pitchfork), not a fold
            kind = "branch-point"
        located = locate_branch_point(w, a, b) if kind == "branch-point" else None
        if turned is not None:
            value = turned
        elif located is not None:
            value = float(located.y[-1])
            br.branch_points.append(located)
        elif len(found) == 1 and w is not None:
            value = locate_crossing(w, a, b, value)
        br.events.append((kind, value))
        kinds.append(kind)
    return kinds


def _along(w: Walk, ya, ta, s):
    """The branch point on the corrector's hyperplane through ya + s ta (scaled)."""
    return correct(w.fl, w.name, w.ref, ya + s * ta * w.scale, ta, w.scale, w.periods)


def locate_crossing(w: Walk, a: Point, b: Point, fallback: float, tol: float = 1e-12) -> float:
    """The parameter where a multiplier crosses the unit circle between the branch points
    a and b (one crossing between them): Brent's method, on the arclength of the corrector
    from a (its hyperplanes normal to the chord a -> b), on |mu| - 1 of the crossing
    multiplier (the (n_a + 1)-th largest in modulus going out, the n_a-th going in, n_a
    the number outside at a).  ``fallback`` (the secant) if the corrector fails.  (A
    branch point is placed by :func:`locate_branch_point`: there the corrector's matrix
    is singular.)"""
    ya, yb = np.append(a.x, a.value), np.append(b.x, b.value)
    d = (yb - ya) / w.scale
    ta = d / np.linalg.norm(d)
    n_a = int(np.sum(np.abs(a.multipliers) > 1.0))
    i = n_a if np.sum(np.abs(b.multipliers) > 1.0) > n_a else n_a - 1

    def g(s):
        return float(np.sort(np.abs(multipliers(_along(w, ya, ta, s)[1])))[::-1][i] - 1.0)
    try:
        s = brentq(g, 0.0, float(np.linalg.norm(d)), xtol=tol * np.linalg.norm(d), rtol=1e-15)
        return float(_along(w, ya, ta, s)[0][-1])
    except (OrbitRefused, ValueError):
        return fallback


#: Where the bordered test function of a branch point is sampled, as fractions of the
#: step from the secant's estimate (with the two points themselves): far enough from the
#: branch point for the corrector to converge (its matrix is singular there).
BP_NODES = (-0.3, -0.15, 0.15, 0.3)


def locate_branch_point(w: Walk, a: Point, b: Point) -> BranchPoint | None:
    """The branch point between the branch points a and b, or None if the bordered test
    function keeps its sign.  Along the chord a -> b (hyperplanes normal to it at
    arclength s, each solved by the corrector from the secant of the two nearest solved
    ones), the corrector's matrix A(s) = [G_x, G_p; t^T] turns singular at the branch
    point; g(s), the last entry of the solution of the bordered system
    [[A, b], [c^T, 0]] z = e (b, c: A's singular vectors of least singular value at a),
    is smooth and changes sign there.  It is sampled at a, b and BP_NODES around the
    secant's zero, and the zero of the polynomial through the samples is the branch
    point; the polynomial through the orbits solved there gives its orbit.  No Newton
    solve is made close to it, where A is too near singular for the corrector."""
    ya, yb = np.append(a.x, a.value), np.append(b.x, b.value)
    d = (yb - ya) / w.scale
    length = float(np.linalg.norm(d))
    ta = d / length
    solved = {0.0: ya, length: yb}
    border = np.linalg.svd(_corrector_matrix(w, ya, ta))
    g = _test_function(w, ta, solved, border[0][:, -1], border[2][-1])
    ga, gb = g(0.0), g(length)
    if ga * gb > 0:
        return None
    guess = length * ga / (ga - gb)
    nodes, values = [0.0, length], [ga, gb]
    for q in BP_NODES:
        try:
            values.append(g(guess + q * length))
            nodes.append(guess + q * length)
        except OrbitRefused:
            continue
    fit = np.polynomial.Polynomial.fit(nodes, values, len(nodes) - 1)
    roots = [r.real for r in fit.roots() if abs(r.imag) < 1e-9 * length]
    if not roots:
        return None
    s0 = min(roots, key=lambda r: abs(r - guess))
    if not 0.0 <= s0 <= length:
        return None
    ys = np.array([solved[q] for q in nodes]) / w.scale
    paths = [np.polynomial.Polynomial.fit(nodes, ys[:, i], len(nodes) - 1)
             for i in range(ys.shape[1])]
    y = np.array([f(s0) for f in paths]) * w.scale
    slope = np.array([f.deriv()(s0) for f in paths])
    return _branch_point(w, y, slope / np.linalg.norm(slope))


def _corrector_matrix(w: Walk, y, normal) -> np.ndarray:
    """[G_x, G_p; normal^T] at y, in the walk's scaled variables (G_p with a step of 1e-5
    of p: its truncation error 1e-10, its rounding 1e-11, relative)."""
    pr = advance(flow_with(w.fl, w.name, y[-1], w.ref), y[:-1], w.periods)
    dp = 1e-5 * max(abs(y[-1]), 1e-3)
    J = _jacobian(w.fl, w.name, w.ref, y[:-1], y[-1], w.periods, pr, dp) * w.scale
    return np.vstack([J, normal])


def _test_function(w: Walk, ta, solved: dict, b, c):
    """g(s) of :func:`locate_branch_point`; ``solved`` collects the orbits it solves."""
    def g(s):
        if s not in solved:
            near = sorted(solved, key=lambda q: abs(q - s))[:2]
            y0, y1 = solved[near[0]], solved[near[1]]
            guess = y0 + (s - near[0]) / (near[1] - near[0]) * (y1 - y0)
            solved[s] = correct(w.fl, w.name, w.ref, guess, ta, w.scale, w.periods)[0]
        A = _corrector_matrix(w, solved[s], ta)
        M = np.block([[A, b[:, None]], [c[None, :], np.zeros((1, 1))]])
        rhs = np.zeros(len(M))
        rhs[-1] = 1.0
        return float(np.linalg.solve(M, rhs)[-1])
    return g


def _branch_point(w: Walk, y, tangent) -> BranchPoint:
    """The :class:`BranchPoint` at y.  The null space of [G_x, G_p] is two-dimensional
    there: the branch's tangent phi1 and phi2 orthogonal to it.  The other branch's
    tangent is the second root of the algebraic bifurcation equation
    psi . G''[a phi1 + b phi2, a phi1 + b phi2] = 0 (psi: the left null vector; the first
    root is phi1, so psi . G''[phi1, phi1] = 0): (a, b) = (-c11 ... ) with
    c12 = psi . G''[phi1, phi2], c22 = psi . G''[phi2, phi2], i.e. -c22 phi1 + 2 c12 phi2.
    (At a symmetry-breaking pitchfork that is the eigenvector of the +1 multiplier with
    p fixed; phi2 alone mixes in some of the branch's own direction.)"""
    u, _, vt = np.linalg.svd(_corrector_matrix(w, y, np.zeros(len(y)))[:-1])
    null, psi = vt[-2:], u[:, -1]
    q = null @ tangent
    phi1 = null.T @ (q / np.linalg.norm(q))
    phi2 = null.T @ np.array([-q[1], q[0]]) / np.linalg.norm(q)
    c12, c22 = (_second_derivative(w, y, psi, phi1, phi2),
                _second_derivative(w, y, psi, phi2, phi2))
    other = -c22 * phi1 + 2.0 * c12 * phi2
    if not np.linalg.norm(other) > 0:
        other = phi2
    return BranchPoint(y, w.fl.phase, w.scale.copy(), phi1, other / np.linalg.norm(other))


def _second_derivative(w: Walk, y, psi, d1, d2, h: float = 1e-4) -> float:
    """psi . G''[d1, d2] at y (d1, d2 scaled), by central differences of step h."""
    def G(dy):
        z = y + dy * w.scale
        return advance(flow_with(w.fl, w.name, z[-1], w.ref), z[:-1], w.periods).x - z[:-1]
    total = (G(h * (d1 + d2)) - G(h * (d1 - d2)) - G(h * (d2 - d1)) + G(-h * (d1 + d2)))
    return float(psi @ total) / (4.0 * h * h)


def locate_fold(w: Walk, a: Point, b: Point, tol: float = 1e-12) -> float | None:
    """The parameter of the fold between the branch points a and b: where the p component
    of the branch's unit tangent vanishes, found by Brent's method on the arclength s of
    the corrector from a (its hyperplane through a + s t_a; s from 0 to b's).  Both points
    lie on the same side of a fold, so the secant of |mu| - 1 between them is off by
    O(step^2).  None if the p component keeps its sign (the branch does not turn) or the
    corrector fails on the way."""
    fl, name, ref, k, scale = w.fl, w.name, w.ref, w.periods, w.scale
    ya, yb = np.append(a.x, a.value), np.append(b.x, b.value)
    try:
        pr = advance(flow_with(fl, name, a.value, ref), a.x, k)
        ta = tangent_at(fl, name, ref, ya, pr, scale, k, (yb - ya) / scale)
        sb = float(ta @ ((yb - ya) / scale))

        def along(s):
            y, prs, _ = correct(fl, name, ref, ya + s * ta * scale, ta, scale, k)
            return y, tangent_at(fl, name, ref, y, prs, scale, k, ta)[-1]
        if ta[-1] * along(sb)[1] > 0:
            return None
        s = brentq(lambda s: along(s)[1], 0.0, sb, xtol=tol * sb, rtol=1e-15)
        return float(along(s)[0][-1])
    except OrbitRefused:
        return None


def _minus_one(fl, name, ref, x, p, k):
    """The period-k orbit at p (Newton from x), its Period and |mu| - 1 of the multiplier
    nearest -1."""
    x, pr = periodic_orbit(flow_with(fl, name, p, ref), x, k, rms=False)
    mu = multipliers(pr)
    return x, pr, float(abs(mu[np.argmin(np.abs(mu + 1.0))]) - 1.0)


def locate_period_doubling(fl, name, a: Point, b: Point, k: int, tol: float = 1e-13):
    """The period-doubling point between the branch points a and b (its multiplier nearest
    -1 crosses the unit circle): (p, x, unit eigenvector of the -1 multiplier), by the
    Illinois variant of regula falsi on |mu| - 1 of the period-k orbits at fixed p."""
    pa, xa, ga = a.value, *_minus_one(fl, name, fl, a.x, a.value, k)[::2]
    pb, xb, gb = b.value, *_minus_one(fl, name, fl, b.x, b.value, k)[::2]
    if ga * gb > 0:
        raise OrbitRefused(f"no multiplier crosses -1 between {name} = {pa:.8g} and {pb:.8g}")
    side, p_old = 0, np.inf
    for _ in range(60):
        p = (pa * gb - pb * ga) / (gb - ga)
        x, pr, g = _minus_one(fl, name, fl, xa + (xb - xa) * (p - pa) / (pb - pa), p, k)
        if g == 0.0 or abs(p - p_old) <= tol * max(abs(p), 1.0):
            break
        p_old = p
        if g * gb > 0:
            pb, xb, gb = p, x, g
            ga, side = (ga / 2 if side == -1 else ga), -1
        else:
            pa, xa, ga = p, x, g
            gb, side = (gb / 2 if side == 1 else gb), 1
    mu, vecs = np.linalg.eig(pr.jacobian)
    v = np.real(vecs[:, int(np.argmin(np.abs(mu + 1.0)))])
    return p, x, v / np.linalg.norm(v)


def _on_one_section(fl: Flow, name: str, a: Point, b: Point):
    """(flow, a, b) with the flow's section at b's and a carried there if it was on
    another (the section moved between them)."""
    at_b = dataclasses.replace(fl, phase=b.phase)
    if a.phase != b.phase:
        at_a = flow_with(dataclasses.replace(fl, phase=a.phase), name, a.value, fl)
        a = dataclasses.replace(a, x=carry(at_a, a.x, b.phase), phase=b.phase)
    return at_b, a, b


@one_blas_thread
def switch_period_doubling(fl: Flow, name: str, br: Branch, stop: float, *, which: int = 0,
                           step: float = 0.01, max_points: int | None = None,
                           min_step: float = 1e-6, max_step: float = MAX_STEP,
                           bounds: tuple | None = None) -> Branch:
    """The period-2k branch born at the ``which``-th period-doubling point of ``br`` (period
    k, continued in ``name`` from ``fl``): located, then started along the eigenvector v
    of the -1 multiplier (the tangent (v, 0)) and continued as a fixed point of P^2k
    while p stays between the point and ``stop``, or on the other side within the same
    distance (a subcritical doubling turns back), or within ``bounds`` (lo, hi) if
    given.  Its first event is the doubling."""
    k = br.periods
    pairs = [(a, b) for a, b in zip(br.points, br.points[1:], strict=False)
             if any(c[0] == "period-doubling" for c in _crossings(a.multipliers, b.multipliers))]
    if not 0 <= which < len(pairs):
        raise ParameterError(f"which = {which} is not in [0, {len(pairs) - 1}]: the branch "
                             f"has {len(pairs)} period-doubling point(s)")
    fl, a, b = _on_one_section(fl, name, *pairs[which])
    p, x, v = locate_period_doubling(fl, name, a, b, k)
    span = abs(stop - p)
    if not span > 0:
        raise ParameterError(f"stop = {stop!r} equals the period-doubling value {p!r}")
    lo, hi = bounds or (p - span, p + span)
    w = Walk(fl, name, fl, 2 * k, _scale(fl, x, span), lo, hi, step,
             max_points or point_budget(max_step), min_step, max_step, stop=stop)
    pr = advance(flow_with(fl, name, p, fl), x, k)
    # (v, 0), orthogonal to the period-k branch: the step's hyperplane meets that branch
    # only O(sqrt(step)) away, so the corrector lands on the new one (O(step) away)
    y0 = np.concatenate([x, [p]])
    along = tangent_at(fl, name, fl, y0, pr, w.scale, k)
    t = np.concatenate([v / w.scale[:-1], [0.0]])
    t -= (t @ along) * along
    t /= np.linalg.norm(t)
    new = Branch(name, 2 * k, events=[("period-doubling", float(p))],
                 origin=Point(p, x, multipliers(pr), pr.events, fl.phase))
    try:
        y, pr, _ = correct(fl, name, fl, y0 + step * t * w.scale, t, w.scale, 2 * k)
    except OrbitRefused as err:
        new.stop = f"refused at the start: {err}"
        return new
    new.points.append(Point(y[-1], y[:-1].copy(), multipliers(pr), pr.events, fl.phase))
    return march(w, new, y, tangent_at(fl, name, fl, y, pr, w.scale, 2 * k, t))
