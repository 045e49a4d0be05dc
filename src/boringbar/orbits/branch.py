"""A branch of periodic orbits of P^k and the corrector that keeps a point on it
(docs/continuation.md): the parameters a branch follows, its points and events, the
residual G(x, p) = P^k(x; p) - x with its Jacobian [G_x, G_p], Newton's correction with
the arclength condition, the unit tangent, and the pairing of multipliers from one
point to the next.  :mod:`boringbar.orbits.continuation` walks a branch with these, and
:mod:`boringbar.orbits.bifurcations` locates what it meets on the way.

G_x = monodromy - I comes from the saltation matrices (:mod:`boringbar.orbits.shooting`),
G_p by a central difference in p.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from boringbar._validate import ParameterError, check_range
from boringbar.orbits.shooting import (
    Flow,
    OrbitRefused,
    advance,
    ball_scales,
    check_residual,
    newton_step,
    packed,
)
from boringbar.simulate.kernels import impact_mass

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
        if not m > 0.0:  # (a predictor's step past zero: no ball to carry)
            raise OrbitRefused(f"ball-mass-g = {value:.6g}: a ball needs a positive mass")
        # (a rolling ball's floor friction mu m g scales with its mass)
        moved = dataclasses.replace(fl, m=m, mus_n=fl.mus_n * m / fl.m,
                                    muk_n=fl.muk_n * m / fl.m)
        return dataclasses.replace(moved, meff=impact_mass(packed(moved)))
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


def residual(fl, name, ref, x, p, k):
    f = flow_with(fl, name, p, ref)
    pr = advance(f, x, k)
    return pr.x - x, pr


def jacobian(fl, name, ref, x, p, k, pr, dp):
    """[G_x, G_p] at (x, p); G_p exact for force-n (:func:`~boringbar.orbits.shooting.
    force_derivative`, with the map), else by a central difference of step dp."""
    if name == "force-n" and pr.force_derivative is not None:
        gp = pr.force_derivative
    else:
        gp = (residual(fl, name, ref, x, p + dp, k)[0]
              - residual(fl, name, ref, x, p - dp, k)[0]) / (2 * dp)
    return np.column_stack([pr.jacobian - np.eye(fl.N), gp])


def event_kinds(events):
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
        r, pr = residual(fl, name, ref, y[:-1], y[-1], k)
        Jx = jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp)
        A = np.vstack([Jx * scale, tangent])
        rhs = -np.concatenate([r, [tangent @ ((y - y0) / scale)]])
        dy = newton_step(A, rhs) * scale
        y = y + dy
        size = float(np.max(np.abs(dy / scale)))
        if size < tol:
            r, pr = residual(fl, name, ref, y[:-1], y[-1], k)
            check_residual(r, y[:-1], "the corrector")
            return y, pr, it + 1
        if it >= 3 and size > last:
            break
        last = size
    raise OrbitRefused("the corrector did not converge")


def tangent_at(fl, name, ref, y, pr, scale, k, previous=None):
    """The unit tangent (scaled variables) of the branch at y, oriented like ``previous``."""
    dp = 1e-7 * max(abs(y[-1]), 1e-3)
    Jx = jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp) * scale
    t = np.linalg.svd(Jx)[2][-1]
    if previous is not None and t @ previous < 0:
        t = -t
    return t / np.linalg.norm(t)


def crossings(m0, m1):
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
#: change relative to the range (:func:`scale`).
STATE_SHARE = 0.25


def point_budget(max_step: float) -> int:
    """The default number of points of a branch whose steps are capped at ``max_step``
    (relative to the range)."""
    return int(np.ceil(CROSSINGS / max_step))


def check_steps(step: float, min_step: float, max_step: float) -> None:
    """The step control's bounds (relative to the range): step and max_step in (0, 0.5],
    0 < min_step <= both, else a ParameterError naming the one out of range (a first step
    above max_step is cut to it)."""
    check_range("max_step", max_step, 0.0, 0.5, lo_open=True)
    check_range("step", step, 0.0, 0.5, lo_open=True)
    check_range("min_step", min_step, 0.0, min(step, max_step), lo_open=True)


def state_scale(fl: Flow, x, span):
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
        rest = np.maximum(rest, ball_scales(fl, om))
    sc = np.concatenate([sc, np.maximum(rest, 1e-3 * max(float(np.max(sc)), 1e-300))])
    return np.append(np.maximum(sc, 1e-300) / STATE_SHARE, span)


def along(w: Walk, ya, ta, s):
    """The branch point on the corrector's hyperplane through ya + s ta (scaled)."""
    return correct(w.fl, w.name, w.ref, ya + s * ta * w.scale, ta, w.scale, w.periods)
