"""What a branch meets, located (docs/continuation.md): a change of the event
sequence (a grazing), located by bisection in p; a pair of multipliers crossing the
unit circle, located by bisection along the arclength: a fold (+1, the branch turns;
where the tangent's p component vanishes), a branch point (+1, the branch goes on;
with its branches' directions), a period doubling (-1) or a Neimark-Sacker bifurcation
(a complex pair)."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from boringbar.orbits.branch import (
    Branch,
    BranchPoint,
    Point,
    Walk,
    along,
    correct,
    crossings,
    event_kinds,
    flow_with,
    jacobian,
    tangent_at,
)
from boringbar.orbits.shooting import (
    Flow,
    OrbitRefused,
    advance,
    multipliers,
    periodic_orbit,
)


def locate_boundary(fl, name, ref, y, p_far, k, tol=1e-10):
    """Bisection in the parameter between y (unknowns (x, p), its event sequence) and
    ``p_far``, where the orbit has another sequence or is refused, down to ``tol`` of
    the distance: the last orbit with y's sequence (a :class:`Point`), the bracket's
    width, and whether the bracket's far end is a boundary.  Each trial is Newton at
    fixed p from the last good orbit (an arclength corrector's iterates would cross the
    non-smooth boundary and fail).  A trial far from the last good orbit can land on
    another orbit that coexists there (near a grazing the orbits born there are close by),
    or be refused in an iterate that strays (a slow impact on the way, where the orbit
    itself has none); so the far end is tried once more from the last good orbit, a
    bracket's width beyond it: if the old sequence goes on there, it is no boundary."""
    kinds = event_kinds(advance(flow_with(fl, name, y[-1], ref), y[:-1], k).events)
    lo, hi, x, last = y[-1], p_far, y[:-1], None
    width = abs(hi - lo)

    def trial(p):
        """(x, Period) of the orbit Newton finds at p from x, or None if refused."""
        try:
            return periodic_orbit(flow_with(fl, name, p, ref), x, k, max_iter=12, rms=False)
        except OrbitRefused:
            return None
    while abs(hi - lo) > max(tol * width, 4 * np.finfo(float).eps * abs(lo)):
        mid = 0.5 * (lo + hi)
        found = trial(mid)
        if found is not None and event_kinds(found[1].events) == kinds:
            lo, x, last = mid, found[0], Point(mid, found[0].copy(), multipliers(found[1]),
                                               found[1].events, fl.phase)
        else:
            hi = mid
    if last is None:
        return last, abs(hi - lo), True
    again = trial(lo + 2.0 * (hi - lo))
    return last, abs(hi - lo), again is None or event_kinds(again[1].events) != kinds


def at_section(fl: Flow, events, k: int) -> bool:
    """An event within 1e-6 T of the section (the start or the end of the k periods)."""
    t0 = fl.phase / fl.omega
    return any(min(t - t0, t0 + k * fl.period - t) < 1e-6 * fl.period for t, _ in events)


def record_turn(br: Branch, w: Walk, t_old, t_new, kinds) -> None:
    """A fold the multipliers did not show (the branch turned between its last two points:
    the tangent's p component changed sign, while several multipliers moved at once)."""
    if t_old[-1] * t_new[-1] < 0 and "fold" not in kinds:
        a, b = br.points[-2], br.points[-1]
        value = locate_fold(w, a, b)
        br.events.append(("fold", value if value is not None else 0.5 * (a.value + b.value)))


def record_crossing(br, a, b, w: Walk | None = None) -> list:
    """Record the stability changes between the points a and b; their kinds."""
    found = crossings(a.multipliers, b.multipliers)
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
        return float(np.sort(np.abs(multipliers(along(w, ya, ta, s)[1])))[::-1][i] - 1.0)
    try:
        s = brentq(g, 0.0, float(np.linalg.norm(d)), xtol=tol * np.linalg.norm(d), rtol=1e-15)
        return float(along(w, ya, ta, s)[0][-1])
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
    J = jacobian(w.fl, w.name, w.ref, y[:-1], y[-1], w.periods, pr, dp) * w.scale
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
