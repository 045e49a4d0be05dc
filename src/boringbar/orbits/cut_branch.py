"""The branch of chatter orbits born at a Hopf point of the cut (docs/continuation.md).

It starts where the steady cut loses stability: the Hopf point of the discretised
delay equation (:mod:`boringbar.orbits.cut_orbits`), found from the frequency-domain
limit of lobe j as a guess and solved at a vanishing amplitude on the cut linearised
about h_m.  In depth, the Hopf point is lobe j's (or the lowest lobe's) at the cut's
speed; in speed, it is where the lobes' boundary crosses the cut's depth, the crossing
within the speed range nearest the cut's speed.  The branch is followed by
pseudo-arclength continuation in the unknowns (nodes, T, and the depth or the delay
tau = 60 / rpm), each scaled to its size, with the Floquet multipliers at every point.
Along it are located, each by secant iterations on the arclength to 1e-10:

- ``fold``: the depth (or the speed) turns back (the tangent's last component changes
  sign);
- ``grazing``: the tool first leaves the cut (the thinnest chip reaches 0), or, on a
  ball bar, the ball first reaches a wall (no friction: the bar's excursion at the
  cavity reaches half the clearance) or first slips (friction: the bar's acceleration
  there reaches what friction can give the ball); a ball bar's branch stops there;
- ``period-doubling`` and ``neimark-sacker``: a multiplier leaves the unit circle
  through -1 or as a complex pair (located by linear interpolation of its modulus).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.optimize
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from boringbar.model.cutting import CuttingLaw
from boringbar.model.forcing import Regenerative
from boringbar.model.linalg import one_blas_thread
from boringbar.model.system import System
from boringbar.orbits.cut_orbits import (
    FREE,
    MULTIPLIERS,
    STEPS,
    CutModel,
    CutOrbitError,
    Orbit,
    amplitude,
    cut_model,
    jacobian,
    min_chip,
    multipliers,
    newton,
    node_forces,
    static_state,
)
from boringbar.reference.stability import limit_at_speeds

#: Arclength steps (scaled units: a tip amplitude of h_m is about one unit).
FIRST_STEP, MIN_STEP, MAX_STEP = 0.02, 1e-5, 0.25
#: The step grows by half after a corrector of at most this many (chord) iterations.
GROW_ITERATIONS = 5
#: The tangent's parameter component must exceed this on both sides of a fold (a linear
#: bar's branch stands vertical, its component round-off about 0).
FOLD_NOISE = 1e-7
#: The Hopf point's orbit has a tip amplitude of this fraction of h_m.
HOPF_AMPLITUDE = 1e-3
#: Multipliers this close to the unit circle count as on it: NEUTRAL in the cut (a linear
#: bar's neutral amplitude), CLIPPED where the tool leaves the cut.  There the clipped
#: chip's corners limit the discretised map's accuracy: a TMD bar's multipliers that sit
#: on the circle (the surface left uncut, carried from revolution to revolution) scatter
#: by up to 1.05e-4 about it from one orbit to the next (the published TMD bar at 500 rpm),
#: where a pair that truly leaves it moves smoothly (docs/continuation.md).
NEUTRAL, CLIPPED = 1e-6, 2e-4
#: A branch ends at this many points, or this many h_m of tip amplitude.
MAX_POINTS, MAX_AMPLITUDE = 200, 20.0
#: Secant iterations locating an event, and their tolerance on the arclength.
LOCATE_ITER, LOCATE_TOL = 30, 1e-10
#: Chord iterations of a corrector locating an event: at the tool's leaving the chip's
#: clipping has a corner, where the chord converges slowly.
LOCATE_NEWTON = 30
#: A step is halved where the tangent turns by more than acos(MIN_COS) (about 26 degrees)
#: over it.
MIN_COS = 0.9


@dataclass
class CutPoint:
    orbit: Orbit
    amplitude: float  #: half the tip's peak-to-peak (m)
    min_chip: float  #: thinnest chip before max(0, .) (m)
    multipliers: np.ndarray
    unstable: int  #: multipliers outside the unit circle (the neutral ones aside)
    ball_margin: float  #: > 0 while the ball keeps off its walls (or sticks); nan: no ball

    @property
    def neutral(self) -> float:
        """Multipliers within this of the unit circle count as on it."""
        return neutral_band(self.min_chip)


def neutral_band(chip: float) -> float:
    """The band about the unit circle of an orbit whose thinnest chip is ``chip`` (m):
    NEUTRAL in the cut, CLIPPED where the tool leaves it."""
    return NEUTRAL if chip > 0 else CLIPPED


@dataclass
class CutEvent:
    kind: str  #: hopf, fold, grazing, period-doubling, neimark-sacker
    depth: float  #: m
    amplitude: float  #: m
    frequency_hz: float
    rpm: float
    detail: str = ""  #: for grazing: tool-leaves-cut, ball-wall or ball-slips
    orbit: Orbit | None = field(default=None, repr=False)  #: the located orbit

    @classmethod
    def at(cls, kind: str, o: Orbit, amp: float, detail: str = "", keep: bool = True):
        """The event ``kind`` at orbit ``o`` of amplitude ``amp`` (m), kept with it."""
        return cls(kind, o.depth, amp, 1.0 / o.period, o.rpm, detail, o if keep else None)


@dataclass
class CutBranch:
    lobe: int
    points: list[CutPoint] = field(default_factory=list)
    events: list[CutEvent] = field(default_factory=list)
    stop: str = ""


# --- the ball's boundary on a linear host ----------------------------------------------
def ball_margin(system: System, model: CutModel, o: Orbit) -> float:
    """How far the orbit is from the ball's leaving the linear host (nan without a ball):
    no friction, half the clearance less the bar's excursion at the cavity (the ball
    rests, centred); friction, mu g less the bar's acceleration there (the ball is
    carried); each relative to its limit."""
    if system.kind != "ball":
        return math.nan
    bar = system.bar
    n = bar.n_modes
    ball = system.damper
    u = o.x[:, :n] @ bar.psi_damper
    if ball.friction_force_n > 0:
        acc = (o.x @ model.a.T + np.outer(node_forces(model, o), model.g))[:, len(model.g) // 2:]
        peak = float(np.max(np.abs(acc[:, :n] @ bar.psi_damper)))
        limit = ball.friction_force_n / ball.mass_kg
    else:
        peak = 0.5 * float(u.max() - u.min())
        limit = 0.5 * ball.gap_m
    return (limit - peak) / limit


# --- the start: the Hopf point ----------------------------------------------------------
def hopf_orbit(system: System, forcing: Regenerative, model: CutModel, lobe: int | None,
               steps: int = STEPS) -> Orbit:
    """The discretised Hopf point of lobe ``lobe`` (None: the lowest at this speed): an
    orbit of the cut linearised about h_m at a vanishing amplitude, its depth and period
    the Hopf point's; the frequency-domain limit is only the guess."""
    lin = linearised(model)
    lobes = None if lobe is None else [lobe]
    b, f = limit_at_speeds(system, forcing.rpm, lin.law.kr_pa, lobes=lobes,
                           with_frequency=True)
    if not np.isfinite(b):
        raise CutOrbitError(f"no lobe {'' if lobe is None else lobe} reaches {forcing.rpm} rpm")
    guess = _eigen_orbit(lin, float(b), float(f), 60.0 / forcing.rpm, steps,
                         HOPF_AMPLITUDE * model.feed)
    return fixed_amplitude(lin, guess, HOPF_AMPLITUDE * model.feed)[0]


def speed_hopf_orbit(system: System, forcing: Regenerative, model: CutModel,
                     rpm_range: tuple[float, float], lobe: int | None,
                     steps: int = STEPS) -> Orbit:
    """The discretised Hopf point in speed at ``forcing``'s depth: the depth's Hopf
    orbit at the speed where lobe ``lobe``'s boundary (None: the lowest lobes') crosses
    that depth (:func:`hopf_speed`), solved again for the delay at that depth exactly; its
    free parameter is tau."""
    lin = linearised(model)
    rpm = hopf_speed(system, forcing.depth_m, lin.law.kr_pa, rpm_range, lobe, forcing.rpm)
    near = hopf_orbit(system, replace(forcing, rpm=rpm), model, lobe, steps)
    start = Orbit(near.x, near.period, forcing.depth_m, near.tau, "tau")
    return fixed_amplitude(lin, start, HOPF_AMPLITUDE * model.feed)[0]


#: Speeds sampled (geometrically) over a range to find where a lobe crosses a depth.
SPEED_SAMPLES = 2001


def hopf_speed(system: System, depth: float, kr: float, rpm_range: tuple[float, float],
               lobe: int | None, near: float) -> float:
    """The speed (rpm) within ``rpm_range`` where the frequency-domain limit of lobe
    ``lobe`` (None: the lowest lobes') equals ``depth`` (m), the crossing nearest ``near``
    in log speed; Brent's method between samples, to 1e-13 relative."""
    lobes = None if lobe is None else [lobe]

    def gap(rpm):
        return limit_at_speeds(system, rpm, kr, lobes=lobes) - depth

    r = np.geomspace(rpm_range[0], rpm_range[1], SPEED_SAMPLES)
    g = gap(r)
    ok = np.isfinite(g[:-1]) & np.isfinite(g[1:])
    cross = np.flatnonzero(ok & (np.sign(g[:-1]) != np.sign(g[1:])))
    if not cross.size:
        raise CutOrbitError(f"no lobe {'' if lobe is None else f'{lobe} '}crosses the depth "
                            f"{depth * 1e3:.6g} mm between {rpm_range[0]:g} and "
                            f"{rpm_range[1]:g} rpm")
    i = int(cross[np.argmin(np.abs(np.log(r[cross] / near)))])
    return float(scipy.optimize.brentq(lambda x: float(gap(x)), r[i], r[i + 1],
                                       xtol=1e-13 * r[i], rtol=1e-15))


def linearised(model: CutModel) -> CutModel:
    """The cut with its law linearised about h_m (dF/dh there, as the lobes take it): the
    same Hopf point, another mean force."""
    return CutModel(**{**model.__dict__,
                       "law": CuttingLaw.linear(model.law.linear_coefficient_pa(model.feed))})


def _eigen_orbit(model: CutModel, b: float, f: float, tau: float, m: int,
                 amp: float) -> Orbit:
    """The steady cut at delay ``tau`` (s) plus ``amp`` times the tip-normalised response
    at f (Hz), (i w - a) phi = g of the model's own matrices."""
    w = 2.0 * math.pi * f
    phi = np.linalg.solve(1j * w * np.eye(model.size) - model.a, model.g)
    phi = phi / (model.c @ phi)
    t = np.arange(m) / (m * f)
    x = static_state(model, b) + amp * np.real(phi[None, :] * np.exp(1j * w * t)[:, None])
    return Orbit(x, 1.0 / f, b, tau)


def fixed_amplitude(model: CutModel, o: Orbit, amp: float) -> tuple[Orbit, int]:
    """The orbit whose tip starts ``amp`` above its mean (W_0 - mean W = amp)."""
    m, s = o.x.shape
    row = np.zeros(m * s + 2)
    row[: m * s] = np.tile(-model.c / m, m)
    row[:s] += model.c

    def extra(y):
        w = y[: m * s].reshape(m, s) @ model.c
        return w[0] - w.mean() - amp, row

    return newton(model, o, extra)[:2]


# --- pseudo-arclength --------------------------------------------------------------------
@dataclass
class Walk:
    """What the walk along one branch carries: ``like`` an orbit of the branch (its
    shape, its free parameter and the held one's value), ``window`` the range of the free
    parameter as the branch reports it (:func:`reported`)."""

    system: System
    model: CutModel
    scale: np.ndarray  #: the size of every unknown: a step of 1 moves the tip about h_m
    like: Orbit
    window: tuple[float, float]


def reported(o: Orbit) -> float:
    """The free parameter as a branch reports it: the depth (m) or the speed (rpm)."""
    return o.depth if o.free == "depth" else o.rpm


def _scale(hopf: Orbit) -> np.ndarray:
    """Each unknown's size: a node's components by their spread on the Hopf orbit scaled
    to a tip amplitude of h_m (over the root of the node count, so that the nodes together
    weigh as one), T and the free parameter by their values."""
    spread = np.max(np.abs(hopf.x - hopf.x.mean(axis=0)), axis=0) / HOPF_AMPLITUDE
    spread = np.where(spread > 0, spread, np.max(spread))
    m = hopf.steps
    return np.concatenate([np.tile(spread * math.sqrt(m), m), [hopf.period, hopf.parameter]])


def tangent(w: Walk, o: Orbit, previous: np.ndarray) -> np.ndarray:
    """The unit tangent (scaled unknowns) at ``o``, on ``previous``'s side."""
    jac = jacobian(w.model, o)
    last = sp.csr_matrix((previous / w.scale)[None, :])
    rhs = np.zeros(jac.shape[0] + 1)
    rhs[-1] = 1.0
    return _oriented(w, spla.spsolve(sp.vstack([jac, last], format="csc"), rhs), previous)


def _unit(w: Walk, lu, previous: np.ndarray) -> np.ndarray:
    """The tangent from the corrector's last matrix: [J; t] tau = (0, 1), with J taken
    at the corrector's last refactorised iterate (the predictor, mostly): close enough
    to predict the next point and to tell the side of a fold, which is then located with
    the exact :func:`tangent`."""
    rhs = np.zeros(lu.shape[0])
    rhs[-1] = 1.0
    return _oriented(w, lu.solve(rhs), previous)


def _oriented(w: Walk, dy: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """The solution ``dy`` of [J; t] tau = (0, 1) as a unit tangent in scaled unknowns, on
    ``previous``'s side."""
    t = dy / w.scale
    t /= np.linalg.norm(t)
    return t if t @ previous >= 0 else -t


def corrected(w: Walk, y: np.ndarray, t: np.ndarray, ds: float, max_iter: int = 8):
    """The orbit on the plane normal to ``t`` at ``ds`` from ``y`` (scaled units), the
    corrector's iterations and its last factorisation (:func:`newton`)."""
    pred = y + ds * w.scale * t
    row = t / w.scale

    def extra(yy):
        return row @ (yy - pred), row

    return newton(w.model, w.like.at(pred), extra, max_iter=max_iter)


def point(w: Walk, o: Orbit) -> CutPoint:
    mu = whole_pairs(multipliers(w.model, o, MULTIPLIERS + 1), MULTIPLIERS)
    chip = min_chip(w.model, o)
    unstable = int(np.sum(np.abs(nontrivial(mu)) > 1.0 + neutral_band(chip)))
    return CutPoint(orbit=o, amplitude=amplitude(w.model, o), min_chip=chip,
                    multipliers=mu, unstable=unstable,
                    ball_margin=ball_margin(w.system, w.model, o))


def whole_pairs(mu: np.ndarray, count: int) -> np.ndarray:
    """The ``count`` largest of the multipliers ``mu`` (by modulus, largest first, at
    least count + 1 of them), or count + 1 where the count-th is one of a complex pair:
    a pair is never split, so that one leaving the unit circle counts twice."""
    last = mu[count - 1]
    paired = (abs(last.imag) > 1e-9 * abs(last)
              and abs(mu[count] - np.conj(last)) <= 1e-6 * abs(last))
    return mu[: count + 1] if paired else mu[:count]


#: The phase shift's multiplier is real and within this of 1.  (Not to round-off: a
#: shift by part of a step is not a symmetry of the discretised orbit, and where the tool
#: leaves the cut the clipped chip's corners put the multiplier 1e-4 to 1e-3 off 1.)
#: Where no real multiplier is as close, it lies below those computed, which are kept.
TRIVIAL = 1e-2


def nontrivial(mu: np.ndarray) -> np.ndarray:
    """The multipliers less the phase shift's: the real one nearest 1, within TRIVIAL."""
    real = np.abs(mu.imag) <= 1e-9 * np.abs(mu)
    gap = np.where(real, np.abs(mu - 1.0), np.inf)
    i = int(np.argmin(gap))
    return np.delete(mu, i) if gap[i] < TRIVIAL else mu


@one_blas_thread
def trace(system: System, forcing: Regenerative, window: tuple[float, float], *,
          free: str = "depth", lobe: int | None = None, steps: int = STEPS,
          max_points: int = MAX_POINTS) -> CutBranch:
    """The branch of chatter orbits of ``system`` under ``forcing``'s cut born at the Hopf
    point of ``lobe`` (None: the lowest), continued in ``free`` (:data:`FREE`): "depth" at
    ``forcing``'s speed within the depths ``window`` (m), or "tau" at ``forcing``'s depth
    within the speeds ``window`` (rpm), from the Hopf point there nearest ``forcing``'s
    speed."""
    if free not in FREE:
        raise ValueError(f"free = {free!r} must be one of {', '.join(FREE)}")
    model = cut_model(system, forcing)
    if free == "depth":
        hopf = hopf_orbit(system, forcing, model, lobe, steps)
    else:
        hopf = speed_hopf_orbit(system, forcing, model, window, lobe, steps)
    br = CutBranch(lobe=-1 if lobe is None else lobe)
    br.events.append(CutEvent.at("hopf", hopf, 0.0, keep=False))
    if not window[0] <= reported(hopf) <= window[1]:
        br.stop = (f"the Hopf point, {hopf.depth * 1e3:.6g} mm, is outside the depth range "
                   f"{window[0] * 1e3:.6g}-{window[1] * 1e3:.6g} mm")
        return br
    w = Walk(system, model, _scale(hopf), hopf, window)
    shift = static_state(model, hopf.depth) - static_state(linearised(model), hopf.depth)
    base = replace(hopf, x=hopf.x + shift)
    a, _ = fixed_amplitude(model, base, 1e-2 * model.feed)
    b, _ = fixed_amplitude(model, a, 2e-2 * model.feed)
    t = (b.unknowns() - a.unknowns()) / w.scale
    t = tangent(w, a, t / np.linalg.norm(t))
    first = point(w, a)
    br.points.append(first)
    if first.ball_margin < 0:  # the ball leaves its host between the Hopf point and here
        br.events.append(_ball_from_hopf(w, a, first))
        br.stop = _ball_stop(system)
        return br
    _walk(w, br, a, t, max_points)
    return br


def _ball_stop(system: System) -> str:
    what = "slips" if system.damper.friction_force_n > 0 else "reaches a wall"
    return (f"the ball {what} here and leaves the linear host; the branch beyond, with the "
            "ball moving, is not followed")


def _ball_from_hopf(w: Walk, a: Orbit, first: CutPoint) -> CutEvent:
    """The ball's boundary between the Hopf point (margin 1 at amplitude 0) and the first
    orbit: secant iterations in the amplitude, each orbit solved at a fixed amplitude."""
    amp0, m0 = 0.0, 1.0
    amp1, m1 = _start_amplitude(w, a), first.ball_margin
    o = a
    for _ in range(LOCATE_ITER):
        amp = amp1 - m1 * (amp1 - amp0) / (m1 - m0)
        o, _ = fixed_amplitude(w.model, o, amp)
        m = ball_margin(w.system, w.model, o)
        amp0, m0, amp1, m1 = amp1, m1, amp, m
        if abs(amp1 - amp0) < LOCATE_TOL * abs(amp1) or m == 0.0:
            break
    detail = "ball-slips" if w.system.damper.friction_force_n > 0 else "ball-wall"
    return CutEvent.at("grazing", o, amplitude(w.model, o), detail, keep=False)


def _start_amplitude(w: Walk, o: Orbit) -> float:
    """W_0 - mean W: the amplitude fixed_amplitude holds."""
    tipw = o.x @ w.model.c
    return float(tipw[0] - tipw.mean())


def _walk(w: Walk, br: CutBranch, o: Orbit, t: np.ndarray, max_points: int) -> None:
    ds = FIRST_STEP
    while len(br.points) < max_points:
        try:
            nxt, its, lu = corrected(w, o.unknowns(), t, ds)
        except CutOrbitError:
            ds *= 0.5
            if ds < MIN_STEP:
                br.stop = "the step fell below its minimum (no orbit found ahead)"
                return
            continue
        if _start_amplitude(w, nxt) < 0:
            _returned(w, br, o)
            return
        tn = _unit(w, lu, t)
        if _folds(t, tn) and tn @ t < MIN_COS and ds > MIN_STEP:
            # the branch turns sharply at a fold within the step: the fold would be
            # located along a tangent that no longer meets the branch
            ds *= 0.5
            continue
        pa, pb = br.points[-1], point(w, nxt)
        known = len(br.events)
        stop = _events(w, br, (o, t, pa), (nxt, tn, pb))
        # the located orbits join the branch, so that its curve passes through them
        br.points.extend(point(w, e.orbit) for e in br.events[known:] if e.orbit is not None)
        br.points.append(pb)
        if stop:
            br.stop = stop
            return
        stop = _outside(w, pb)
        if stop:
            br.stop = stop
            return
        o, t = nxt, tn
        ds = min(ds * 1.5, MAX_STEP) if its <= GROW_ITERATIONS else ds
    br.stop = f"{max_points} points"


def _returned(w: Walk, br: CutBranch, o: Orbit) -> None:
    """The step past ``o`` went through zero amplitude (the phase condition's half-period
    shift): the branch returns to the steady cut at a second Hopf point, the orbit of
    HOPF_AMPLITUDE h_m on the cut itself (the first is solved on the cut linearised about
    h_m; at that amplitude the two differ by O(A^2), nothing for a linear law)."""
    hopf, _ = fixed_amplitude(w.model, o, HOPF_AMPLITUDE * w.model.feed)
    br.events.append(CutEvent.at("hopf", hopf, 0.0, "return"))
    br.points.append(point(w, hopf))
    br.stop = "the branch returns to the steady cut at a second Hopf point"


def _outside(w: Walk, p: CutPoint) -> str:
    lo, hi = w.window
    if not lo <= reported(p.orbit) <= hi:
        return f"the {'depth' if w.like.free == 'depth' else 'speed'} left its range"
    if p.amplitude > MAX_AMPLITUDE * w.model.feed:
        return f"the tip amplitude passed {MAX_AMPLITUDE:g} h_m"
    return ""


# --- events ----------------------------------------------------------------------------------
def _events(w: Walk, br: CutBranch, a: tuple, b: tuple) -> str:
    """Locate what happened between points ``a`` and ``b`` (orbit, tangent, CutPoint);
    a ball's leaving its linear host ends the branch: the stop's reason."""
    (oa, ta, pa), (ob, tb, pb) = a, b
    ends = (oa, ob, ta)
    if _folds(ta, tb) and _folds(tangent(w, oa, ta), tangent(w, ob, tb)):
        # (confirmed by the exact tangents: the corrector's, taken off the branch, is off
        # by about 1e-4 in its last component, as much as a vertical branch's tilt)
        br.events.append(_located(w, ends, "fold", "",
                                  lambda o, t: t[-1], ta[-1], tb[-1]))
    if pa.min_chip * pb.min_chip < 0:
        br.events.append(_located(w, ends, "grazing", "tool-leaves-cut",
                                  lambda o, t: min_chip(w.model, o), pa.min_chip, pb.min_chip))
    for ev in _crossings(pa, pb):
        br.events.append(ev)
    if pa.ball_margin * pb.ball_margin < 0:
        ball = w.system.damper
        detail = "ball-slips" if ball.friction_force_n > 0 else "ball-wall"
        br.events.append(_located(w, ends, "grazing", detail,
                                  lambda o, t: ball_margin(w.system, w.model, o),
                                  pa.ball_margin, pb.ball_margin))
        return _ball_stop(w.system)
    return ""


def _folds(ta: np.ndarray, tb: np.ndarray) -> bool:
    """Whether the free parameter (the tangents' last component) turns back between
    tangents ``ta`` and ``tb``."""
    return bool(ta[-1] * tb[-1] < 0 and min(abs(ta[-1]), abs(tb[-1])) > FOLD_NOISE)


def _located(w: Walk, ends: tuple, kind: str, detail: str, fn, fa: float,
             fb: float) -> CutEvent:
    """The event where fn(orbit, tangent) = 0 between two orbits of the branch, ``ends``
    = (oa, ob, ta): sought on the planes normal to oa's tangent ``ta``, or, where those
    miss the branch (a corner between, as where the tool re-enters the cut), on the
    planes normal to the chord from oa to ob, which meet it between the two."""
    oa, ob, ta = ends
    y = oa.unknowns()
    chord = (ob.unknowns() - y) / w.scale
    try:
        return _regula_falsi(w, oa, ta, ta, kind, detail, fn, (fa, fb), float(ta @ chord))
    except CutOrbitError:
        span = float(np.linalg.norm(chord))
        return _regula_falsi(w, oa, chord / span, ta, kind, detail, fn, (fa, fb), span)


def _regula_falsi(w: Walk, oa: Orbit, normal: np.ndarray, ta: np.ndarray, kind: str,
                  detail: str, fn, values: tuple[float, float], span: float) -> CutEvent:
    """Illinois regula falsi on the arclength s in (0, ``span``) along ``normal`` (scaled
    units) from ``oa``, each orbit on the plane normal to it there; tangents oriented
    along ``ta``."""
    fa, fb = values
    lo, hi = 0.0, span
    y, o = oa.unknowns(), oa
    for _ in range(LOCATE_ITER):
        s = hi - fb * (hi - lo) / (fb - fa)
        o = corrected(w, y, normal, s, LOCATE_NEWTON)[0]
        f = fn(o, tangent(w, o, ta))
        if f * fb < 0:
            lo, fa = hi, fb
        else:
            fa *= 0.5
        hi, fb = s, f
        if abs(hi - lo) < LOCATE_TOL * span or f == 0.0:
            break
    return CutEvent.at(kind, o, amplitude(w.model, o), detail)


def _crossings(pa: CutPoint, pb: CutPoint) -> list[CutEvent]:
    """Period doublings and Neimark-Sacker points between two points: a multiplier through
    -1 or a complex pair through the unit circle, placed where its modulus passes 1 + the
    neutral band (linearly between the two)."""
    if pa.unstable == pb.unstable:
        return []
    more = pa if pa.unstable > pb.unstable else pb
    mus = nontrivial(more.multipliers)
    out = mus[np.abs(mus) > 1.0 + more.neutral]
    mu = out[np.argmin(np.abs(out))]
    if abs(mu.imag) > 1e-6 * abs(mu):
        kind = "neimark-sacker"
    elif mu.real < 0:
        kind = "period-doubling"
    else:
        return []  # through +1: a fold, located from the tangent
    # where the crossing multiplier (the k-th largest, k the larger count outside) passes
    # the band's edge, linearly between the two points
    edge, k = 1.0 + more.neutral, more.unstable
    ma, mb = (float(np.sort(np.abs(nontrivial(p.multipliers)))[::-1][k - 1])
              for p in (pa, pb))
    f = min(1.0, max(0.0, (edge - ma) / (mb - ma))) if mb != ma else 0.5
    at = [float(x + f * (y - x)) for x, y in ((pa.orbit.depth, pb.orbit.depth),
                                               (pa.amplitude, pb.amplitude),
                                               (1 / pa.orbit.period, 1 / pb.orbit.period),
                                               (pa.orbit.rpm, pb.orbit.rpm))]
    return [CutEvent(kind, *at)]
