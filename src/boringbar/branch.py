"""Pseudo-arclength continuation of a periodic orbit of P^k (docs/continuation.md).

The unknowns are (x, p): the orbit's state at phase 0 and the parameter.  The
residual G(x, p) = P^k(x; p) - x; G_x = monodromy - I comes from the saltation
matrices (:mod:`boringbar.shooting`), G_p by a central difference in p.  Each
step predicts along the unit tangent of the branch (null vector of [G_x, G_p] in
scaled variables) and corrects by Newton on G = 0 plus the arclength condition,
so folds are passed.  The step adapts: halved when Newton fails or the event
sequence changes, grown by 1.3 after quick convergence.

The branch stops (with the reason) at the end of the range, at a change of the
impact/reversal sequence (a grazing: recorded as an event), or where the orbit
is refused (stick, wall contact).  Multipliers crossing the unit circle between
two points are events: fold (+1), period doubling (-1), Neimark-Sacker (a complex
pair), located by the secant of the crossing multiplier's |mu| - 1.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from boringbar._validate import ParameterError
from boringbar.shooting import Flow, OrbitRefused, advance, multipliers

#: The parameters a branch can follow (the CLI's names).
PARAMETERS = ("force-n", "ratio", "gap-mm", "restitution", "friction-force-n", "ball-mass-g")


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


def _residual(fl, name, ref, x, p, k):
    f = flow_with(fl, name, p, ref)
    pr = advance(f, x, k)
    return pr.x - x, pr


def _jacobian(fl, name, ref, x, p, k, pr, dp):
    """[G_x, G_p] at (x, p); G_p by a central difference of step dp."""
    gp = (_residual(fl, name, ref, x, p + dp, k)[0]
          - _residual(fl, name, ref, x, p - dp, k)[0]) / (2 * dp)
    return np.column_stack([pr.jacobian - np.eye(fl.N), gp])


def _kinds(events):
    return tuple(k for _, k in events)


def correct(fl, name, ref, y0, tangent, scale, k, tol=1e-11, max_iter=12):
    """Newton on G = 0 and tangent . (y - y0) / scale = 0 from y0; (y, Period, iterations)."""
    y = y0.copy()
    dp = 1e-7 * max(abs(y0[-1]), 1e-3)
    for it in range(max_iter):
        r, pr = _residual(fl, name, ref, y[:-1], y[-1], k)
        Jx = _jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp)
        A = np.vstack([Jx * scale, tangent])
        rhs = -np.concatenate([r, [tangent @ ((y - y0) / scale)]])
        dy = np.linalg.solve(A, rhs) * scale
        y = y + dy
        if np.max(np.abs(dy / scale)) < tol:
            r, pr = _residual(fl, name, ref, y[:-1], y[-1], k)
            return y, pr, it + 1
    raise OrbitRefused("the corrector did not converge")


def tangent_at(fl, name, ref, y, pr, scale, k, previous=None):
    """The unit tangent (scaled variables) of the branch at y, oriented like ``previous``."""
    dp = 1e-7 * max(abs(y[-1]), 1e-3)
    Jx = _jacobian(fl, name, ref, y[:-1], y[-1], k, pr, dp) * scale
    t = np.linalg.svd(Jx)[2][-1]
    if previous is not None and t @ previous < 0:
        t = -t
    return t / np.linalg.norm(t)


def _crossing(m0, m1):
    """The bifurcation between two points' multipliers (kind or None): the change in the
    number outside the unit circle, classified by the crossing multiplier."""
    out0, out1 = np.sum(np.abs(m0) > 1.0), np.sum(np.abs(m1) > 1.0)
    if out0 == out1:
        return None, None
    i = int(np.argmin(np.abs(np.abs(m1) - 1.0)))
    mu = m1[i]
    if abs(mu.imag) > 1e-6 * abs(mu):
        kind = "neimark-sacker"
    else:
        kind = "fold" if mu.real > 0 else "period-doubling"
    j = int(np.argmin(np.abs(m0 - mu)))
    return kind, (abs(m0[j]) - 1.0, abs(mu) - 1.0)


def continue_branch(fl: Flow, name: str, x0: np.ndarray, stop: float, *, periods: int = 1,
                    step: float = 0.01, max_points: int = 200, min_step: float = 1e-6,
                    max_step: float = 0.1) -> Branch:
    """Continue the orbit through x0 (near a fixed point of P^periods) in parameter ``name``
    from its value in ``fl`` towards ``stop``; ``step`` etc. relative to |stop - start|."""
    ref = fl
    p0 = value_of(fl, name)
    span = abs(stop - p0)
    if not span > 0:
        raise ParameterError(f"range end {stop!r} equals the start value {p0!r}")
    br = Branch(name, periods)
    try:
        y, pr = _first(fl, name, ref, x0, p0, periods)
    except OrbitRefused as err:
        br.stop = f"refused at the start: {err}"
        return br
    scale = np.concatenate([np.maximum(np.abs(y[:-1]), 1e-3 * np.max(np.abs(y[:-1]))), [span]])
    t = np.zeros(fl.N + 1)
    t[-1] = np.sign(stop - p0)
    t = tangent_at(fl, name, ref, y, pr, scale, periods, t)
    br.points.append(Point(y[-1], y[:-1].copy(), multipliers(pr), pr.events))
    h = step
    while len(br.points) < max_points:
        pred = y + h * t * scale
        try:
            yn, prn, its = correct(fl, name, ref, pred, t, scale, periods)
            same = _kinds(prn.events) == _kinds(br.points[-1].events)
        except OrbitRefused as err:
            yn, same, why = None, False, str(err)
        if not same:
            if h / 2 >= min_step:
                h /= 2
                continue
            br.stop = why if yn is None else _grazing(br, yn)
            return br
        pt = Point(yn[-1], yn[:-1].copy(), multipliers(prn), prn.events)
        _record_crossing(br, br.points[-1], pt)
        if (pt.value - stop) * np.sign(stop - p0) > 0:
            br.stop = "end of range"
            br.points.append(pt)
            return br
        br.points.append(pt)
        t = tangent_at(fl, name, ref, yn, prn, scale, periods, t)
        y = yn
        h = min(max_step, h * 1.3) if its <= 4 else h
    br.stop = f"max_points = {max_points} reached"
    return br


def _first(fl, name, ref, x0, p0, k):
    """The orbit at the start value, by Newton on G(x, p0) = 0."""
    x = np.asarray(x0, float).copy()
    for _ in range(30):
        r, pr = _residual(fl, name, ref, x, p0, k)
        dx = np.linalg.solve(pr.jacobian - np.eye(fl.N), -r)
        x = x + dx
        if np.max(np.abs(dx)) < 1e-12 * np.max(np.abs(x)):
            r, pr = _residual(fl, name, ref, x, p0, k)
            return np.concatenate([x, [p0]]), pr
    raise OrbitRefused("Newton did not converge at the start value")


def _grazing(br, yn):
    """Stop at a change of the event sequence; recorded as a grazing event."""
    p = 0.5 * (br.points[-1].value + yn[-1])
    br.events.append(("grazing", float(p)))
    return (f"the impact/reversal sequence changes near {br.parameter} = {p:.6g} "
            "(grazing): the branch is not followed across it")


def _record_crossing(br, a, b):
    kind, g = _crossing(a.multipliers, b.multipliers)
    if kind is None:
        return
    s = g[0] / (g[0] - g[1]) if g[0] != g[1] else 0.5
    br.events.append((kind, float(a.value + s * (b.value - a.value))))
