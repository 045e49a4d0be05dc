"""Periodic attractors by brute force, the seeds of an orbit map and its checks
(docs/continuation.md, "The orbit map").

The exact integrator is run from a spread of initial conditions (the bar at 0, 1/2 and
1 times its linear forced response without impacts, the ball at rest at -1/2, 0 and
1/2 of the half gap) for ``settle_periods`` forcing periods, ending at phase 0.  A
settled state that repeats after k <= ``max_period`` periods (to 1e-4 of its size) is
polished by Newton on P^k(x) = x (:func:`boringbar.orbits.shooting.periodic_orbit`) and kept
if Newton stays near it and the orbit is stable; attractors that are the same orbit
(the same state at phase 0 after some whole periods, to 1e-6) are merged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from boringbar.model.forcing import Harmonic
from boringbar.model.linalg import one_blas_thread
from boringbar.model.system import System
from boringbar.orbits.shooting import (
    Flow,
    OrbitRefused,
    advance,
    augmented,
    make_flow,
    multipliers,
    periodic_orbit,
)
from boringbar.simulate import State, simulate

#: A settled state repeating after k periods to this fraction of its size is tried as a
#: period-k orbit.
SETTLED = 1e-4
#: Two attractors are one orbit if their states at phase 0 (one of them advanced by whole
#: periods) agree to this fraction of the state's size.
SAME = 1e-6


@dataclass(frozen=True)
class Attractor:
    """A stable periodic orbit found by brute force: the state at phase 0, its period k,
    its impacts a period and its multipliers' largest modulus."""

    x: np.ndarray
    periods: int
    impacts: float
    radius: float


def linear_response(fl: Flow) -> np.ndarray:
    """The state at phase 0 of the bar's forced response without impacts, Im(X e^{i Omega
    t}) at t = 0: x' = A x + b sin(Omega t) with the core's A and b of the free ball (in
    flight the modes do not feel it; a rolling ball as it slips; the absorber and the
    locked ball as they act), so (i Omega - A) X = b."""
    N = fl.N
    A = augmented(fl, 0.0, 1.0 if fl.roll else 0.0)
    return np.linalg.solve(1j * fl.omega * np.eye(N) - A[:N, :N], A[:N, N]).imag


def initial_states(fl: Flow) -> list[np.ndarray]:
    """The spread of initial conditions (module docstring), each a state at phase 0."""
    n = fl.n
    lin = linear_response(fl)
    out = []
    for c in (0.0, 0.5, 1.0):
        for y in ((-0.5, 0.0, 0.5) if fl.ball else (0.0,)):
            x = np.zeros(fl.N)
            x[:2 * n] = c * lin[:2 * n]
            if fl.kind == "tmd":
                x[2 * n:] = c * lin[2 * n:]  # the absorber's part of the response
            if fl.ball:
                x[2 * n] = y * fl.half
                x[2 * n + 1] = -fl.psi_d @ x[n:2 * n]  # the ball at rest in space
            out.append(x)
    return out


@one_blas_thread
def periodic_attractors(system: System, forcing: Harmonic, *, settle_periods: int = 300,
                        max_period: int = 2) -> list[Attractor]:
    """The distinct stable periodic orbits of period <= ``max_period`` the exact integrator
    settles on from :func:`initial_states` (module docstring)."""
    fl = make_flow(system, forcing)
    dt = fl.period / math.ceil(fl.period / 1e-6)  # whole periods: the end is at phase 0
    found: list[Attractor] = []
    for x0 in initial_states(fl):
        try:
            run = simulate(system, forcing, duration_s=settle_periods * fl.period, dt_s=dt,
                           integrator="exact", initial=State(x0, 0.0), record_every=0)
        except (ValueError, RuntimeError):
            continue
        x = run.final.x[:fl.N]
        if any(_near(fl, x, a) for a in found):
            continue  # settled on one already found: no second Newton solve
        att = _settled(fl, x, max_period)
        if att is not None and not any(same_orbit(fl, att, a) for a in found):
            found.append(att)
    return found


def _near(fl: Flow, x, a: Attractor) -> bool:
    """Whether the settled state x is on the attractor a: within 10 SETTLED of one of its
    states at phase 0 (Newton from x would stay that near, :func:`_settled`)."""
    size = float(np.max(np.abs(a.x)))
    z = a.x
    for _ in range(a.periods):
        if np.max(np.abs(z - x)) <= 10 * SETTLED * size:
            return True
        z = advance(fl, z).x
    return False


def _settled(fl: Flow, x, max_period: int) -> Attractor | None:
    """The attractor the settled state x is on, or None (not periodic, refused, not
    stable, or Newton went elsewhere)."""
    size = float(np.max(np.abs(x)))
    for k in range(1, max_period + 1):
        try:
            pr = advance(fl, x, k)
            if np.max(np.abs(pr.x - x)) > SETTLED * size:
                continue
            xp, pr = periodic_orbit(fl, x, k, rms=False)
        except OrbitRefused:
            continue
        mu = multipliers(pr)
        if np.max(np.abs(xp - x)) <= 10 * SETTLED * size and np.max(np.abs(mu)) < 1.0:
            impacts = sum(kind.startswith("impact") for _, kind in pr.events) / k
            return Attractor(xp, k, impacts, float(np.max(np.abs(mu))))
    return None


def same_orbit(fl: Flow, a: Attractor, b: Attractor) -> bool:
    """Whether a and b are one orbit: the same period and b's state one of a's at phase 0."""
    if a.periods != b.periods:
        return False
    size = float(np.max(np.abs(a.x)))
    z = a.x
    for _ in range(a.periods):
        if np.max(np.abs(z - b.x)) <= SAME * size:
            return True
        z = advance(fl, z).x
    return False


def spread(lo: float, hi: float, count: int) -> list[float]:
    """``count`` values in the middles of equal parts of [lo, hi]."""
    return [lo + (hi - lo) * (i + 0.5) / count for i in range(count)]



#: The return check: the orbit's state perturbed by this fraction of each component...
RETURN_PERTURBATION = 1e-7
#: ... must be within this fraction of the state's size of it after the periods (the
#: attractor check's tolerance, :data:`boringbar.orbits.orbit_map.ON_BRANCH`).
RETURN_TOL = 1e-6


@one_blas_thread
def return_distance(system: System, forcing: Harmonic, x, phase: float, k: int,
                    periods: int = 200) -> float:
    """How far the exact integrator, started from the period-k orbit's state x at the
    forcing phase ``phase`` perturbed by RETURN_PERTURBATION of each component (signs
    alternating), ends from x after ``periods`` forcing periods (rounded up to whole
    multiples of k), relative to max |x|; inf if the run fails.  A stable orbit is an
    attractor if this is at most RETURN_TOL: its perturbation decays (as |mu|^periods)
    and the integrator's own orbit is the shooting map's to 1e-9 a period."""
    fl = make_flow(system, forcing)
    x = np.asarray(x, float)
    signs = np.where(np.arange(len(x)) % 2 == 0, 1.0, -1.0)
    start = x * (1.0 + RETURN_PERTURBATION * signs)
    n = -(-periods // k) * k
    dt = fl.period / math.ceil(fl.period / 1e-6)  # whole periods: the end is at the phase
    try:
        run = simulate(system, forcing, duration_s=n * fl.period, dt_s=dt, integrator="exact",
                       initial=State(start, phase / fl.omega), record_every=0)
    except (ValueError, RuntimeError):
        return math.inf
    return float(np.max(np.abs(run.final.x[:fl.N] - x)) / np.max(np.abs(x)))
