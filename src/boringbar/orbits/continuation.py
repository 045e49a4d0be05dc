"""Pseudo-arclength continuation of a periodic orbit of P^k (docs/continuation.md).

The unknowns are (x, p): the orbit's state at the section's phase (0 by default)
and the parameter.  Each step predicts along the unit tangent of the branch (null
vector of [G_x, G_p] in scaled variables, :mod:`boringbar.orbits.branch`) and corrects
by Newton on G = 0 plus the arclength condition, so folds are passed.  The step adapts
(:func:`march`): halved when Newton fails, grown by 1.5 after quick convergence, held
where a stable branch's multipliers near the unit circle (:func:`circle_cap`).

The branch stops (with the reason) at the end of the range, where the orbit is
refused (stick, wall contact, a singular Newton matrix), or at a change of the
event sequence (impacts, reversals, a rolling ball's roll/slip switches), recorded as a
"grazing".  An event that comes near the Poincare section (or crosses it) moves the
section instead (:func:`_move_section`; the point is carried to the new phase).  The
multipliers of two points are paired; a pair crossing the unit circle is an event,
located by :mod:`boringbar.orbits.bifurcations`.
At a period doubling, :func:`switch_period_doubling` starts the period-2k branch.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from boringbar._validate import ParameterError
from boringbar.model.linalg import one_blas_thread
from boringbar.orbits.bifurcations import (
    at_section,
    locate_boundary,
    locate_period_doubling,
    record_crossing,
    record_turn,
)
from boringbar.orbits.branch import (
    MAX_STEP,
    STATE_SHARE,
    Branch,
    Point,
    Walk,
    check_parameter,
    check_steps,
    correct,
    crossings,
    event_kinds,
    flow_with,
    point_budget,
    residual,
    state_scale,
    tangent_at,
    value_of,
)
from boringbar.orbits.shooting import (
    Flow,
    OrbitRefused,
    SlowImpact,
    advance,
    carry,
    check_residual,
    free_phase,
    multipliers,
    newton_step,
    periodic_orbit,
)

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
    w = Walk(fl, name, fl, periods, state_scale(fl, y[:-1], span), lo, hi, step,
             max_points or point_budget(max_step), min_step, max_step, move_section, stop)
    t = np.zeros(fl.N + 1)
    t[-1] = np.sign(stop - p0)
    t = tangent_at(fl, name, fl, y, pr, w.scale, periods, t)
    first = Point(y[-1], y[:-1].copy(), multipliers(pr), pr.events, fl.phase)
    j = shorter_period(w, first)
    if j:
        br.stop = (f"refused at the start: the orbit found is of period {j}, not "
                   f"{periods} (continue it with periods = {j})")
        return br
    br.points.append(first)
    return march(w, br, y, t)


def _rescaled(w: Walk, x, t):
    """The walk with the scales of x, and the tangent t carried to them (unit length)."""
    scale = state_scale(w.fl, x, w.scale[-1])
    t = t * w.scale / scale
    return dataclasses.replace(w, scale=scale), t / np.linalg.norm(t)


def march(w: Walk, br: Branch, y: np.ndarray, t: np.ndarray) -> Branch:
    """Follow ``br`` from its last point y (unknowns (x, p)) along the unit tangent t
    (scaled) by predictor-corrector steps until p leaves [w.lo, w.hi] (at the far end,
    or back at the start after a fold), the branch closes on itself, the event sequence
    changes (located: a grazing), the orbit is refused or w.max_points.  The step grows
    by 1.5 after a corrector of at most 3 iterations, shrinks by 0.7 after one of 7 or
    more, is halved when the corrector fails, is held near the unit circle
    (:func:`circle_cap`) and is never more than w.max_step."""
    fl, name, ref, k = w.fl, w.name, w.ref, w.periods
    h = min(w.step, w.max_step)
    while len(br.points) < w.max_points:
        try:
            yn, prn, its = correct(fl, name, ref, y + h * t * w.scale, t, w.scale, k)
            same = event_kinds(prn.events) == event_kinds(br.points[-1].events)
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
            slowed = (_slowed_impact(w, br, y + h * t * w.scale)
                      if located is None and h / 2 < w.min_step else None)
            if slowed is not None:
                located = (None, abs(h * t[-1] * w.scale[-1]))
            if located is None:
                br.stop = (f"failure at {name} = {y[-1]:.10g}: {why} (step {h:.2g} of the "
                           "range)")
                return br
            kind = _boundary(br, w, located)
            if slowed is not None:
                br.stop += f"; one step on, {slowed}"
            moved = _move_section(br, w, t) if kind == "section" and w.move_section else None
            if moved is None:
                return br
            br.stop = ""
            w, y, t = moved
            fl, ref = w.fl, w.ref
            continue
        pt = Point(yn[-1], yn[:-1].copy(), multipliers(prn), prn.events, fl.phase)
        if _shorter_period(br, w, pt):
            return br
        kinds = record_crossing(br, br.points[-1], pt, w)
        br.points.append(pt)
        if _left_range(br, w) or _closed(br, w, yn, h):
            return br
        t_old, t = t, tangent_at(fl, name, ref, yn, prn, w.scale, k, t)
        record_turn(br, w, t_old, t, kinds)
        y = yn
        w, t = _rescaled(w, y[:-1], t)
        h_used = h
        h = min(w.max_step, h * 1.5) if its <= 3 else (h * 0.7 if its >= 7 else h)
        h = max(min(h, circle_cap(br.points[-2], pt, h_used)), w.min_step)
        if w.move_section and _near_section(flow_with(fl, name, pt.value, ref), pt.events):
            w, y, t = _move_section(br, w, t) or (w, y, t)
            fl, ref = w.fl, w.ref
    br.stop = (f"point budget of {w.max_points} reached at {name} = "
               f"{br.points[-1].value:.10g}")
    return br


#: A point of a period-k branch whose state returns after j < k periods to this fraction
#: of its size (each block's: the modes' u and u', the ball's or absorber's) is a
#: period-j orbit.  A true period-k orbit near the period doubling it was born at differs
#: from its period-j parent by about the square root of the distance to it, far above
#: this; the corrector's tolerance is 1e-11.
SHORTER_PERIOD_TOL = 1e-8


def _shorter_period(br: Branch, w: Walk, pt: Point) -> bool:
    """Whether the new point ``pt`` of a period-k branch (k > 1) is an orbit of a period
    j that divides k: the branch went through the period doubling it was born at onto
    the period-j family, which it would follow traversed k / j times over.  The branch
    stops there, before the point."""
    j = shorter_period(w, pt)
    if j:
        br.stop = (f"period {j} at {w.name} = {pt.value:.10g}: the branch went through its "
                   f"period doubling onto the period-{j} orbits (ended before them)")
    return bool(j)


def shorter_period(w: Walk, pt: Point) -> int:
    """The least period j < k, dividing k = w.periods, after which ``pt``'s state returns
    (SHORTER_PERIOD_TOL); 0 if none."""
    k = w.periods
    if k == 1:
        return 0
    fl = flow_with(w.fl, w.name, pt.value, w.ref)
    size = w.scale[:-1] * STATE_SHARE
    for j in (j for j in range(1, k) if k % j == 0):
        if np.max(np.abs(advance(fl, pt.x, j).x - pt.x) / size) < SHORTER_PERIOD_TOL:
            return j
    return 0


#: The least fraction of the last step that :func:`circle_cap` allows.
CIRCLE_FLOOR = 0.125


def circle_cap(a: Point, b: Point, h: float) -> float:
    """The next step's cap where a stable branch's largest multiplier, a complex pair,
    nears the unit circle: its modulus rose by c over the last step (h, from a to b) and
    is d below 1; with d < c a step of h could carry it out and back unseen (a pair that
    leaves the circle and returns within one step: the published bar's ball at gap
    0.1 mm, friction on, has a Neimark-Sacker interval of 1.2 N, 25.8 to 26.96 N, which
    a 1.7 N step stepped over), so the step is at most h d / c (at least CIRCLE_FLOOR h).
    Else no cap (inf): an unstable branch's short stable window, the milder miss, is
    left to the step's own bounds (capped both ways, a branch coming down onto the
    circle spent a quick study's ten points within 0.2 N of it), and so is a real
    multiplier's: one that reaches +1 and comes back is a fold, which the tangent's turn
    shows (record_turn)."""
    ma = float(np.max(np.abs(a.multipliers)))
    top = b.multipliers[int(np.argmax(np.abs(b.multipliers)))]
    mb = float(abs(top))
    c, d = mb - ma, 1.0 - mb
    if not (d > 0.0 and c > d and abs(top.imag) > 1e-9 * mb):
        return math.inf
    return h * max(d / c, CIRCLE_FLOOR)


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


def _slowed_impact(w: Walk, br: Branch, pred) -> SlowImpact | None:
    """The impact of the last orbit that slows below the capture threshold one smallest
    step on, or None: the map from the prediction ``pred`` (no Newton iterate, which may
    wander) refused at an impact of the last orbit's kind and time (to 1e-3 of the
    period).  Its speed falls to zero at its grazing, and below the threshold the
    simulation catches the ball: the branch ends at that grazing as the model resolves
    it.  Any other refusal is a failure."""
    try:
        residual(w.fl, w.name, w.ref, pred[:-1], pred[-1], w.periods)
    except SlowImpact as err:
        tol = 1e-3 * 2 * math.pi / w.fl.omega
        if any(kind == err.kind and abs(te - err.t) <= tol
               for te, kind in br.points[-1].events):
            return err
    except OrbitRefused:
        pass
    return None


def _beyond(w: Walk, y, p_far: float):
    """A change of the event sequence between y and ``p_far`` (:func:`locate_boundary`),
    or None (no orbit with the old sequence reaches past y, or it reaches all the way:
    no change there)."""
    if p_far == y[-1]:
        return None
    last, width, boundary = locate_boundary(w.fl, w.name, w.ref, y, p_far, w.periods)
    if last is None or abs(last.value - p_far) <= 2 * width:
        return None
    if not boundary and not at_section(flow_with(w.fl, w.name, last.value, w.ref),
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
    moved = dataclasses.replace(w, fl=fl, ref=ref, scale=state_scale(fl, x, w.scale[-1]))
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
        r, pr = residual(fl, name, ref, x, p0, k)
        dx = newton_step(pr.jacobian - np.eye(fl.N), -r)
        x = x + dx
        if np.max(np.abs(dx)) < 1e-12 * np.max(np.abs(x)):
            r, pr = residual(fl, name, ref, x, p0, k)
            check_residual(r, x, "Newton at the start value")
            return np.concatenate([x, [p0]]), pr
    raise OrbitRefused("Newton did not converge at the start value")


def _boundary(br, w: Walk, located) -> str:
    """Stop at a change of the event sequence located by :func:`locate_boundary`: its
    last orbit ends the branch, its parameter is the event's value: "section" if an
    event of that orbit is at the Poincare section (the same orbit goes on, but P is not
    smooth there), else "grazing" (an impact or reversal appears or vanishes)."""
    last, width = located
    if last is not None:
        record_crossing(br, br.points[-1], last, w)
        br.points.append(last)
    p = br.points[-1].value
    at = flow_with(w.fl, w.name, p, w.ref)
    kind = "section" if at_section(at, br.points[-1].events, w.periods) else "grazing"
    br.events.append((kind, float(p)))
    what = ("an event crosses the Poincare section's phase (a section at "
            "another phase would carry on)" if kind == "section" else "grazing")
    br.stop = (f"the event sequence changes at {br.parameter} = {p:.10g} "
               f"(bracket {width:.2g}; {what}): the branch is not followed across it")
    return kind


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
             if any(c[0] == "period-doubling" for c in crossings(a.multipliers, b.multipliers))]
    if not 0 <= which < len(pairs):
        raise ParameterError(f"which = {which} is not in [0, {len(pairs) - 1}]: the branch "
                             f"has {len(pairs)} period-doubling point(s)")
    fl, a, b = _on_one_section(fl, name, *pairs[which])
    p, x, v = locate_period_doubling(fl, name, a, b, k)
    span = abs(stop - p)
    if not span > 0:
        raise ParameterError(f"stop = {stop!r} equals the period-doubling value {p!r}")
    lo, hi = bounds or (p - span, p + span)
    w = Walk(fl, name, fl, 2 * k, state_scale(fl, x, span), lo, hi, step,
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
