"""The orbit map: every branch of periodic orbits of one problem over one range, as a
tree (docs/continuation.md, "The orbit map").

A map starts from one orbit and from seeds (periodic attractors found by the exact
integrator, :mod:`boringbar.orbits.attractors`), each continued both ways across the range
(:func:`boringbar.orbits.branch.continue_branch`).  With switching on, every branch point of
a branch starts two children (the other branch, both ways from the point along the
direction the algebraic bifurcation equation gives), every period doubling of a
branch of period below ``max_period`` a child of twice its period
(:func:`boringbar.orbits.branch.switch_period_doubling`), and every grazing that ends a
branch a child on the other side (the orbit with the new impact sequence, if Newton
finds one there).  A branch, or a child, whose orbit is already on the map is not
followed again.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from boringbar.model.linalg import one_blas_thread
from boringbar.orbits.branch import (
    MAX_STEP,
    Branch,
    BranchPoint,
    Point,
    Walk,
    correct,
    flow_with,
    point_budget,
    tangent_at,
    value_of,
)
from boringbar.orbits.continuation import (
    continue_branch,
    march,
    switch_period_doubling,
)
from boringbar.orbits.shooting import (
    Flow,
    OrbitRefused,
    advance,
    carry,
    multipliers,
    periodic_orbit,
)

#: Events a branch can be born at ("start": the map's first orbit; "seed": an attractor).
BORN = ("start", "seed", "branch-point", "period-doubling", "grazing")
#: A state within this fraction of max |x| of a branch's (interpolated between two of its
#: points) is on that branch: the mirror image of an asymmetric orbit is O(1) away.
SAME_ORBIT = 2e-3


@dataclass
class MapBranch:
    """One branch of a map: the branch, its parent's index (None: a root), the event it
    was born at (kind, value) and the flow it was continued on (its starting flow)."""

    branch: Branch
    parent: int | None
    born: tuple
    flow: Flow
    #: The seed it was started from (its index among the map's seeds), if any.
    seed: int | None = None


@dataclass
class OrbitMap:
    """All branches of one problem over [lo, hi] in ``parameter``, and what the map
    left out (``notes``: duplicates dropped, the branch limit reached)."""

    parameter: str
    lo: float
    hi: float
    branches: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    #: Pairs of branches that are each other's mirror image (index -> index).
    mirrors: dict = field(default_factory=dict)


@dataclass(frozen=True)
class MapOptions:
    """How a map is grown: ``switch`` at branch points, period doublings and grazings;
    branches of period at most ``max_period``; at most ``max_branches`` followed (their
    mirror images not counted); the steps of
    every branch (relative to the range, as :func:`~boringbar.orbits.branch.continue_branch`)."""

    switch: bool = True
    max_period: int = 2
    max_branches: int = 24
    step: float = 0.02
    max_step: float = MAX_STEP
    min_step: float = 1e-4
    max_points: int | None = None


@one_blas_thread
def orbit_map(fl: Flow, name: str, x0, stop: float, *, seeds=(), periods: int = 1,
              other_end: float | None = None, options: MapOptions | None = None) -> OrbitMap:
    """The map of ``name`` from its value in ``fl`` to ``stop``: the orbit through x0 (a
    fixed point of P^periods, near) continued towards ``stop`` (and towards ``other_end``
    too, if given: the map then covers [other_end, stop] from a start inside it); every
    seed (value, x at phase 0, periods) not on it continued both ways; their children
    (module docstring).  A branch whose mirror image is on the map is that image mirrored
    (:func:`mirrored`), not continued again."""
    o = options or MapOptions()
    p0 = value_of(fl, name)
    ends = [stop] + ([other_end] if other_end is not None and other_end != p0 else [])
    om = OrbitMap(name, min(p0, *ends), max(p0, *ends))
    todo = [(None, ("start", p0), fl, _started(fl, name, x0, end, periods, o, om))
            for end in ends]
    for i, (value, x, k) in enumerate(seeds):
        at = flow_with(fl, name, value, fl)
        todo += [(None, ("seed", value), fl, _seeded(at, name, x, end, k, o, i, om))
                 for end in (om.lo, om.hi) if end != value]
    while todo:
        # a mirror image costs nothing (it is not continued), so only followed branches
        # count: with images counted, 24 branches were 12 orbits
        if len(om.branches) - len(om.mirrors) // 2 >= o.max_branches:
            left = ", ".join(f"{born[0]} at {born[1]:.6g}" for _, born, _, _ in todo)
            om.notes.append(f"branch limit of {o.max_branches} reached: {len(todo)} "
                            f"branch(es) not followed ({left})")
            break
        parent, born, flow, make = todo.pop(0)
        if (born[0] == "seed" and _known_seed(om, make)) or _by_symmetry(om, parent, born, make):
            continue
        br = _follow(om, born, make)
        if br is None:
            continue
        if _duplicate(om, br, parent):
            om.notes.append(f"the branch from the {born[0]} at {born[1]:.10g} retraces the "
                            "map: not kept")
            continue
        i = len(om.branches)
        _add(om, MapBranch(br, parent, born, flow, getattr(make, "seed", (0,) * 5)[4]
                           if born[0] == "seed" else None))
        if o.switch:
            todo += _children(om, i, o)
    return om


def _follow(om: OrbitMap, born: tuple, make) -> Branch | None:
    """The branch ``make`` continues, or None (noted) if it has no points."""
    try:
        br = make()
    except OrbitRefused as err:
        om.notes.append(f"no branch from the {born[0]} at {born[1]:.10g}: {err}")
        return None
    if not br.points:
        om.notes.append(f"no branch from the {born[0]} at {born[1]:.10g}: {br.stop}")
        return None
    return br


def _add(om: OrbitMap, mb: MapBranch) -> None:
    """Add mb; if its parent has a mirror image on the map, mb's image too (its parent
    that image): the children of a mirrored branch are the images of the original's."""
    om.branches.append(mb)
    i = len(om.branches) - 1
    if mb.parent is not None and mb.parent in om.mirrors:
        _add_mirror(om, i, om.mirrors[mb.parent])


def _add_mirror(om: OrbitMap, i: int, parent: int | None) -> bool:
    """Add the mirror image of branch i (with ``parent``) if the system maps i's first
    orbit onto an orbit (checked: P^k of the image is the image, 1e-9); whether it did."""
    mb = om.branches[i]
    image = mirrored(mb.flow, mb.branch)
    if image is None:
        return False
    om.branches.append(MapBranch(image, parent, mb.born, mb.flow, mb.seed))
    j = len(om.branches) - 1
    om.mirrors[i], om.mirrors[j] = j, i
    return True


def _by_symmetry(om: OrbitMap, parent, born: tuple, make) -> bool:
    """Whether the branch ``make`` would follow is the mirror image of one on the map, and
    so added as that image: the other direction at a branch point of a symmetric orbit
    (the pitchfork's two branches), or a seed whose image lies on a branch."""
    if getattr(make, "sibling", None) is not None:
        sib = [i for i, mb in enumerate(om.branches)
               if mb.parent == parent and mb.born == born and i not in om.mirrors]
        return bool(sib) and make.sibling() and _add_mirror(om, sib[0], parent)
    if getattr(make, "seed", None) is None:
        return False
    value, x, k, at, i = make.seed
    image = [j for j, mb in enumerate(om.branches) if mb.seed != i and j not in om.mirrors
             and on_branch(mb, value, -x, k, dataclasses.replace(at, phase=np.pi))]
    added = [_add_mirror(om, j, None) for j in image]
    return any(added)


def mirrored(fl: Flow, br: Branch) -> Branch | None:
    """The mirror image of ``br`` under the system's symmetry (y -> -y, u -> -u,
    t -> t + T/2: the walls, the forcing and the friction law are odd): each point
    (p, x at phase phi) becomes (p, -x at phase phi + pi), with the same multipliers, its
    events half a period later and the walls swapped.  None if the image of the first
    point is not a fixed point of P^k (1e-9 of |x|): the system is not symmetric."""
    first = br.points[0]
    at = flow_with(dataclasses.replace(fl, phase=(first.phase + np.pi) % (2 * np.pi)),
                   br.parameter, first.value, fl)
    if np.max(np.abs(advance(at, -first.x, br.periods).x + first.x)) > \
            1e-9 * np.max(np.abs(first.x)):
        return None
    swap = {"impact+": "impact-", "impact-": "impact+", "reversal": "reversal"}

    def image(pt: Point) -> Point:
        half = np.pi / flow_with(fl, br.parameter, pt.value, fl).omega
        return Point(pt.value, -pt.x, pt.multipliers,
                     [(t + half, swap[k]) for t, k in pt.events], (pt.phase + np.pi) % (2 * np.pi))
    return Branch(br.parameter, br.periods, [image(p) for p in br.points], list(br.events),
                  br.stop, None, br.section_moves)


def _steps(o: MapOptions) -> dict:
    return {"step": o.step, "max_step": o.max_step, "min_step": o.min_step,
            "max_points": o.max_points}


def _started(fl: Flow, name: str, x0, end: float, k: int, o: MapOptions, om: OrbitMap):
    """The start branch from x0 towards ``end`` within the map's range."""
    def make():
        return continue_branch(fl, name, x0, end, periods=k, bounds=(om.lo, om.hi),
                               **_steps(o))
    return make


def _seeded(at: Flow, name: str, x, end: float, k: int, o: MapOptions, i: int, om: OrbitMap):
    """A branch from the i-th seed x (at phase 0, of period k) towards ``end`` within the
    map's range; the seed rides on the callable (``seed``) so the map can see whether it
    is already on a branch."""
    at = dataclasses.replace(at, phase=0.0)

    def make():
        return continue_branch(at, name, x, end, periods=k, bounds=(om.lo, om.hi),
                               **_steps(o))
    make.seed = (value_of(at, name), np.asarray(x, float), k, at, i)
    return make


def _known_seed(om: OrbitMap, make) -> bool:
    """Whether the seed of ``make`` is on a branch of the map (not one from itself)."""
    value, x, k, at, i = make.seed
    return any(on_branch(mb, value, x, k, at) for mb in om.branches if mb.seed != i)


def on_branch(mb: MapBranch, value: float, x, k: int, at: Flow) -> bool:
    """Whether the orbit through x (at the phase of the flow ``at``, of period k, at
    ``value``) is on the branch: its state, carried to the section of the branch's points
    around ``value``, within SAME_ORBIT of theirs interpolated linearly (for a branch of
    period 2k, either of the orbit's states there)."""
    br = mb.branch
    if br.periods % k:
        return False
    pts = br.points
    for a, b in zip(pts, pts[1:], strict=False):
        if not min(a.value, b.value) <= value <= max(a.value, b.value) or a.phase != b.phase:
            continue
        s = (value - a.value) / (b.value - a.value) if b.value != a.value else 0.0
        xi = a.x + s * (b.x - a.x)
        here = carry(at, x, a.phase)
        f = dataclasses.replace(at, phase=a.phase)
        states = [here] + [advance(f, here, j).x for j in range(1, br.periods)]
        size = float(np.max(np.abs(xi)))
        if any(np.max(np.abs(z - xi)) <= SAME_ORBIT * size for z in states):
            return True
    return False


def _duplicate(om: OrbitMap, br: Branch, parent: int | None) -> bool:
    """A branch that retraces the map: the middles of its first and later halves both
    lie on branches other than its parent, with as many events a period (next to a
    grazing an orbit comes within SAME_ORBIT of the one with an impact fewer: the
    four-impact branch of the issue's case was dropped as the three-impact one).  A
    branch that only joins a known one is kept: the period-2 orbits born at 21.63 N in
    the issue's case, stable at first, join those born at a grazing at 22.37 N, and
    were dropped whole when the later half alone decided."""
    if len(br.points) < 4:
        return False
    half = len(br.points) // 2
    return all(_on_others(om, br, pts[len(pts) // 2], parent)
               for pts in (br.points[:half], br.points[half:]))


def _on_others(om: OrbitMap, br: Branch, pt: Point, parent: int | None) -> bool:
    """Whether the orbit pt of ``br`` lies on a branch of the map other than ``parent``
    with as many events a period."""
    rate = len(pt.events) / br.periods
    others = [mb for i, mb in enumerate(om.branches) if i != parent and mb.branch.points
              and len(mb.branch.points[0].events) / mb.branch.periods == rate]
    if not others:
        return False
    at = dataclasses.replace(others[0].flow, phase=pt.phase)
    at = flow_with(at, br.parameter, pt.value, others[0].flow)
    x0 = carry(at, pt.x, 0.0)
    at0 = dataclasses.replace(at, phase=0.0)
    return any(on_branch(mb, pt.value, x0, br.periods, at0) for mb in others)


def _children(om: OrbitMap, i: int, o: MapOptions) -> list:
    """The branches born on branch i (see the module docstring), as (parent, born, flow,
    make) to be followed."""
    mb = om.branches[i]
    br, fl = mb.branch, mb.flow
    out = []
    for bp in br.branch_points:
        out += [(i, ("branch-point", float(bp.y[-1])), fl, _switched(fl, br, bp, sign, om, o))
                for sign in (1.0, -1.0)]
    doublings = [v for kind, v in br.events if kind == "period-doubling"]
    if 2 * br.periods <= o.max_period and not (mb.born[0] == "period-doubling" and
                                               len(br.events) and br.origin is not None):
        out += [(i, ("period-doubling", v), fl, _doubled(fl, br, j, om, o))
                for j, v in enumerate(doublings)]
    if "(bracket" in br.stop and "grazing" in br.stop and len(br.points) >= 2:
        out.append((i, ("grazing", br.events[-1][1]), fl, _grazed(fl, br, om, o)))
    return out


def _switched(fl: Flow, br: Branch, bp: BranchPoint, sign: float, om: OrbitMap,
              o: MapOptions):
    """The other branch at the branch point bp, started along sign * bp.other; the second
    direction knows (``sibling``) whether the branch point's orbit is symmetric, so that
    its branch is the first's mirror image."""
    def make():
        return switch_branch_point(fl, br.parameter, br, bp, sign, (om.lo, om.hi), o)
    if sign < 0:
        make.sibling = lambda: symmetric(fl, br.parameter, bp)
    return make


def symmetric(fl: Flow, name: str, bp: BranchPoint) -> bool:
    """Whether the orbit at the branch point is its own mirror image: x(phase + pi) = -x."""
    at = flow_with(dataclasses.replace(fl, phase=bp.phase), name, bp.y[-1], fl)
    x = bp.y[:-1]
    return bool(np.max(np.abs(carry(at, x, (bp.phase + np.pi) % (2 * np.pi)) + x))
                <= 1e-7 * np.max(np.abs(x)))


@one_blas_thread
def switch_branch_point(fl: Flow, name: str, br: Branch, bp: BranchPoint, sign: float,
                        bounds: tuple, o: MapOptions | None = None) -> Branch:
    """The other branch through the branch point bp of ``br`` (continued from ``fl``),
    followed from it along sign * bp.other (the corrector's hyperplanes normal to that
    direction meet ``br`` only O(sqrt(step)) away) within ``bounds``."""
    o = o or MapOptions()
    at = dataclasses.replace(fl, phase=bp.phase)
    t = sign * bp.other
    w = Walk(at, name, fl, br.periods, bp.scale, bounds[0], bounds[1], o.step,
             o.max_points or point_budget(o.max_step), o.min_step, o.max_step, stop=np.nan)
    new = Branch(name, br.periods, events=[("branch-point", float(bp.y[-1]))])
    h = min(o.step, o.max_step)
    try:
        y, pr, _ = correct(at, name, fl, bp.y + h * t * w.scale, t, w.scale, br.periods)
    except OrbitRefused as err:
        new.stop = f"refused at the start: {err}"
        return new
    new.points.append(Point(y[-1], y[:-1].copy(), multipliers(pr), pr.events, bp.phase))
    return march(w, new, y, tangent_at(at, name, fl, y, pr, w.scale, br.periods, t))


def _doubled(fl: Flow, br: Branch, which: int, om: OrbitMap, o: MapOptions):
    """The period-doubled branch at the ``which``-th doubling of ``br``."""
    def make():
        stop = om.hi if br.points[-1].value >= br.points[0].value else om.lo
        return switch_period_doubling(fl, br.parameter, br, stop, which=which,
                                      step=min(o.step, 0.002), max_points=o.max_points,
                                      min_step=min(o.min_step, 0.002),
                                      max_step=o.max_step, bounds=(om.lo, om.hi))
    return make


#: How far past a grazing (of the range) the orbit with the new impact sequence is sought
#: (closest first; too close, its new impact can be slower than the capture threshold).
GRAZING_STEPS = (1e-6, 1e-5, 1e-4, 1e-3, 3e-3, 1e-2)



def _grazed(fl: Flow, br: Branch, om: OrbitMap, o: MapOptions):
    """The branch on the other side of the grazing that ends ``br``: Newton at fixed p
    just past it from its last orbit; a branch refused at the start if none is found."""
    def make():
        return cross_grazing(fl, br, (om.lo, om.hi), o)
    return make


@one_blas_thread
def cross_grazing(fl: Flow, br: Branch, bounds: tuple, o: MapOptions | None = None) -> Branch:
    """The orbit past the grazing that ends ``br`` (continued from ``fl``), with another
    event sequence, continued on towards the end of ``bounds`` the branch was heading to."""
    o = o or MapOptions()
    last, before = br.points[-1], br.points[-2]
    sign = 1.0 if last.value >= before.value else -1.0
    end = bounds[1] if sign > 0 else bounds[0]
    at = dataclasses.replace(fl, phase=last.phase)
    kinds = [k for _, k in last.events]
    why = "no orbit with another impact sequence found past the grazing"
    for d in GRAZING_STEPS:
        p = last.value + sign * d * (bounds[1] - bounds[0])
        if (p - end) * sign >= 0:
            break
        try:
            x, pr = periodic_orbit(flow_with(at, br.parameter, p, fl), last.x, br.periods,
                                   rms=False, damped=True)
        except OrbitRefused as err:
            why = str(err)
            continue
        if [k for _, k in pr.events] != kinds:
            new = continue_branch(flow_with(at, br.parameter, p, fl), br.parameter, x, end,
                                  periods=br.periods, **_steps(o))
            new.events.insert(0, ("grazing", float(last.value)))
            return new
    return Branch(br.parameter, br.periods, events=[("grazing", float(last.value))],
                  stop=f"refused at the start: {why}")


#: An attractor is on a branch if Newton there, from the branch's nearest point, gives
#: its state at phase 0 to this fraction of the state's size.
ON_BRANCH = 1e-6


def attractor_check(om: OrbitMap, value: float, x, k: int) -> dict:
    """Whether the periodic attractor through x (phase 0, period k, at ``value``) lies on
    a stable branch of the map: Newton at ``value`` from each branch's nearest point (on
    that point's section, carried to phase 0) compared with x and its images after whole
    periods; the branch (index) and the relative distance, or None and the nearest
    distance found."""
    best, where = np.inf, None
    for i, mb in enumerate(om.branches):
        br = mb.branch
        if br.periods % k or not br.points:
            continue
        d = _distance(mb, value, x)
        if d is not None and d[0] < best:
            best, where = d[0], (i if d[1] else None)
    ok = where is not None and best <= ON_BRANCH
    return {"value": float(value), "periods": int(k), "branch": where if ok else None,
            "distance": float(best), "on_stable_branch": bool(ok)}


def _distance(mb: MapBranch, value: float, x):
    """(relative distance, stable) of the branch's orbit at ``value`` nearest x, or None:
    Newton there from each point that begins a stretch of the branch through ``value``
    (a branch that folds passes a value more than once)."""
    br, fl = mb.branch, mb.flow
    pts = br.points
    starts = [a for a, b in zip(pts, pts[1:], strict=False)
              if min(a.value, b.value) <= value <= max(a.value, b.value)]
    found = [d for d in (_distance_from(br, fl, near, value, x) for near in starts)
             if d is not None]
    return min(found) if found else None


def _distance_from(br: Branch, fl: Flow, near: Point, value: float, x):
    """(relative distance from x, stable) of the orbit Newton finds at ``value`` from the
    branch point ``near``, carried to phase 0 (and its images after whole periods)."""
    at = flow_with(dataclasses.replace(fl, phase=near.phase), br.parameter, value, fl)
    try:
        xb, pr = periodic_orbit(at, near.x, br.periods, rms=False)
        z = carry(at, xb, 0.0)
    except OrbitRefused:
        return None
    at0 = dataclasses.replace(at, phase=0.0)
    size = float(np.max(np.abs(x)))
    d = np.inf
    for _ in range(br.periods):
        d = min(d, float(np.max(np.abs(z - x))) / size)
        z = advance(at0, z).x
    return d, bool(np.all(np.abs(multipliers(pr)) < 1.0))
