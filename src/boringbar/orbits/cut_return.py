"""A compiled cut started on a chatter orbit with the orbit's own history: the return
check of a branch (docs/continuation.md, "Chatter orbits of the cut").

A periodic orbit of the cut is its own past, so a simulation that starts on it needs
not only the orbit's state but its surface: the tip's W and W' over the revolutions of
memory before the start, which :meth:`~boringbar.simulate.CutStepper.start_from` lays
into the compiled RK4 kernel's delay history.  The run then shows what the orbit's
Floquet multipliers say: a stable orbit holds its amplitude period after period (an
attractor), an unstable one is left at the rate of its largest multiplier.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from boringbar._validate import ParameterError, check_int
from boringbar.model.forcing import Regenerative
from boringbar.model.system import System
from boringbar.orbits.cut_orbits import Orbit, cut_model, min_chip, w_at
from boringbar.simulate import CutStepper

#: The relative step of the central difference that gives the history's W'.
SLOPE_STEP = 1e-4


def follow(system: System, forcing: Regenerative, orbit: Orbit, periods: int,
           dt_s: float = 1e-6, per_window: int = 4, knock: float = 0.0) -> np.ndarray:
    """Half the tip's peak-to-peak (m) over each window of ``per_window`` of the orbit's
    periods (as near as whole steps of ``dt_s`` go), ``periods`` periods in all, of
    ``system``'s cut at ``orbit.depth`` started on ``orbit`` with its own history (the
    cut of ``forcing``'s speed, law and memory), its departure from the orbit's mean
    scaled by 1 + ``knock`` (0: on the orbit).  A solid or TMD bar's orbits: their state
    is the kernel's (the modes, then the absorber's absolute displacement as its
    auxiliary coordinate); a ball bar's host carries its ball, which the kernel frees."""
    if system.kind not in ("solid", "tmd"):
        raise ParameterError(f"system kind {system.kind!r}: the return check starts a "
                             "solid or TMD bar's cut on its orbit")
    check_int("periods", periods, 1, 10**6)
    check_int("per_window", per_window, 1, periods)
    model = cut_model(system, forcing)
    cut = replace(forcing, depth_m=orbit.depth, start="static", stop_at_zero=False)
    steps = max(1, round(per_window * orbit.period / dt_s))
    stepper = CutStepper(system, cut, dt_s=dt_s, window_steps=steps)
    mean = orbit.x.mean(axis=0)
    x = kernel_state(system, mean + (1.0 + knock) * (orbit.x[0] - mean))
    w_mean = float(model.c @ mean)

    def history(t):
        h = SLOPE_STEP * orbit.period / orbit.steps
        w = w_at(model, orbit, t)
        wd = (w_at(model, orbit, t + h) - w_at(model, orbit, t - h)) / (2 * h)
        return w_mean + (1.0 + knock) * (w - w_mean), (1.0 + knock) * wd

    stepper.start_from(x, history, left_cut=min_chip(model, orbit) < 0)
    return np.array([stepper.advance().half_pp_m
                     for _ in range(math.ceil(periods / per_window))])


def kernel_state(system: System, state: np.ndarray) -> np.ndarray:
    """The compiled kernel's state [u, u', aux, aux'] of an orbit's node state (q, q'),
    q the bar's modal coordinates, then a TMD's absolute displacement."""
    n = system.bar.n_modes
    d = len(state) // 2
    x = np.zeros(2 * n + 2)
    x[:n], x[n:2 * n] = state[:n], state[d:d + n]
    if d > n:
        x[2 * n], x[2 * n + 1] = state[n], state[d + n]
    return x
