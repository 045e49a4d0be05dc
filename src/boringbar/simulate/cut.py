"""A regenerative cut advanced window by window (:class:`CutStepper`), started in
progress and knocked at the tip (:func:`knocked_cut`): what the converged verdict of
:mod:`boringbar.analysis.verdict` runs."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from boringbar._validate import (
    ParameterError,
    check_int,
    check_range,
)
from boringbar.model.forcing import Regenerative
from boringbar.model.system import System
from boringbar.simulate import layout as L
from boringbar.simulate.engine import initial_state, setup_run
from boringbar.simulate.kernels import Records, Steps, run_rk4
from boringbar.simulate.run import MAX_INITIAL_DISPLACEMENT, Initial, State
from boringbar.simulate.run_limits import (
    MAX_STEPS,
)


def knocked_cut(system: System, forcing: Regenerative, knock_m: float,
                ball_position_m: float = 0.0) -> State:
    """The state of a cut in progress (every mode at its static deflection under the
    mean force, the absorber relaxed) just after a knock at the tip: an impulse J on
    the bar at the tip, every mode taking psi_tip,i J / M_i, with J such that the bar's
    first mode alone would vibrate at the tip with amplitude ``knock_m`` (m).  A free
    ball and an absorber keep their absolute velocity (at rest): the ball's relative
    velocity is minus the bar's at the cavity; it starts ``ball_position_m`` (m) from the
    cavity's centre.  Use it with ``forcing.start == "static"``, whose surface before
    the cut is the same static deflection."""
    check_range("knock_m", knock_m, 0.0, MAX_INITIAL_DISPLACEMENT, unit="m")
    bar, n = system.bar, system.bar.n_modes
    x = initial_state(system, Initial(ball_position_m=ball_position_m))
    x[:n] += bar.psi_force * forcing.mean_force_n / bar.stiffness_n_m
    impulse = knock_m * bar.natural_frequency_rad_s / float(np.sum(bar.psi_tip**2 / bar.mass_kg))
    x[n:2 * n] = bar.psi_tip * impulse / bar.mass_kg
    if system.kind == "tmd":
        x[2 * n] = float(bar.psi_absorber @ x[:n])
    elif system.kind == "ball":
        x[2 * n + 1] = -float(bar.psi_damper @ x[n:2 * n])
    return State(x, 0.0)


@dataclass(frozen=True)
class Window:
    """What one window of a cut advanced by :class:`CutStepper` did: ``t_end_s`` (s);
    the tip's extremes ``max_tip_m``, ``min_tip_m`` and its RMS about the window's mean
    ``rms_tip_m`` (m); ``left_cut``: the chip thickness reached zero in the window;
    ``impacts``: counted ball impacts; ``max_rel_m``: the ball's largest |y| (m), or the
    absorber's largest |stroke|; ``mode_half_pp``: half the peak-to-peak of each modal
    coordinate; ``max_force_n``: the largest cutting force (N); ``held``: RK4's stick law
    held the ball through every step; ``max_hold_n``: the largest friction force with
    which it held it (N; 0 where it never did)."""

    t_end_s: float
    max_tip_m: float
    min_tip_m: float
    rms_tip_m: float
    left_cut: bool
    impacts: int
    max_rel_m: float
    mode_half_pp: np.ndarray  #: half the peak-to-peak of each modal coordinate u_i
    max_force_n: float = math.nan  #: the largest cutting force (N)
    held: bool = False  #: the stick law held the ball through the window
    max_hold_n: float = 0.0  #: the largest friction force that held it (N)

    @property
    def half_pp_m(self) -> float:
        """Half the peak-to-peak tip displacement (m): the window's amplitude."""
        return 0.5 * (self.max_tip_m - self.min_tip_m)


class CutStepper:
    """A regenerative cut advanced window by window with the RK4 scheme, for a verdict
    that decides as the run goes (:mod:`boringbar.analysis.verdict`).

    One kernel call per window of ``window_steps`` steps of ``dt_s``; the kernel keeps
    the delay history between calls, so the windows together are one run, bit for bit
    (the core's continuation contract).  ``initial``: as :func:`simulate` takes it;
    the forcing must not stop at the first zero of the force; ``stick_law``: as
    :func:`simulate` takes it.
    """

    def __init__(self, system: System, forcing: Regenerative, *, dt_s: float, window_steps: int,
                 initial: Initial | State | None = None, stick_law: str = "sgn"):
        if forcing.stop_at_zero:
            raise ParameterError("a cut advanced window by window runs on after the force "
                                 "reaches zero: give stop_at_zero = False")
        check_int("window_steps", window_steps, 1, MAX_STEPS)
        self.su = setup_run(system, forcing, window_steps * dt_s, dt_s, initial, 0, 1.0, False,
                            "rk4", stick_law)
        self._made = (initial, stick_law)  # what refined() builds its stepper from
        self.window_steps = window_steps
        #: RK4's stick law holds a ball with friction (Window.held can be True): the run
        #: was packed with the law's band
        self.holds = bool(self.su.p[L.STICK_BAND] > 0)
        self.t_s = self._t_first = self.su.t0
        self.modes = np.zeros((system.bar.n_modes, 2))
        self._before = 0  # steps of a given history before the run's start

    def advance(self) -> Window:
        """Run one more window; what it did."""
        su, met = self.su, self.su.met
        for slot in (L.SUM_W2, L.SUM_W, L.N_STEADY, L.MAX_ABS_AUX, L.MAX_FORCE,
                     L.MAX_HOLD_FORCE):
            met[slot] = 0.0
        met[L.STEADY_MAX_W], met[L.STEADY_MIN_W] = -np.inf, np.inf
        self.modes[:, 0], self.modes[:, 1] = -np.inf, np.inf
        zeros, impacts, free = met[L.N_ZERO_STEPS], met[L.N_IMP_ALL], met[L.N_FREE_STEPS]
        run_rk4(su.p, su.x, Steps(self.t_s, su.dt, self.window_steps, 0),
                Records(su.rec, su.imp, su.stick, su.stb, met, modes=self.modes), su.buf)
        self.t_s = self._t_first + (met[L.STEPS_DONE] - self._before) * su.dt
        n = met[L.N_STEADY]
        mean = met[L.SUM_W] / n
        return Window(self.t_s, float(met[L.STEADY_MAX_W]), float(met[L.STEADY_MIN_W]),
                      math.sqrt(max(met[L.SUM_W2] / n - mean * mean, 0.0)),
                      bool(met[L.N_ZERO_STEPS] > zeros), int(met[L.N_IMP_ALL] - impacts),
                      float(met[L.MAX_ABS_AUX]), 0.5 * (self.modes[:, 0] - self.modes[:, 1]),
                      float(met[L.MAX_FORCE]), self.holds and met[L.N_FREE_STEPS] == free,
                      float(met[L.MAX_HOLD_FORCE]))

    def start_from(self, x: np.ndarray, history, left_cut: bool = False,
                   t_s: float | None = None) -> None:
        """Start the cut (before any window) from the state ``x`` with its past:
        ``history(t)`` -> (W, W') (m, m/s) of the tip at the times t <= 0 (s) before it, as
        the surface the tool meets (a periodic orbit's own, say).  ``left_cut``: the tool
        has left the cut before, so the surface is the lowest over every revolution of
        memory from the start (the run's first zero of the chip is then its start).
        ``t_s``: the time the run goes on from (s; None: the run's start)."""
        su = self.su
        if self.t_s != su.t0 or su.met[L.STEPS_DONE] != 0:
            raise ParameterError("start_from: the cut has already run")
        x = np.asarray(x, dtype=float)
        if x.shape != su.x.shape or not np.all(np.isfinite(x)):
            raise ParameterError(f"x must be {su.x.size} finite values, got {x.shape}")
        rows = len(su.buf)
        past = [np.broadcast_to(np.asarray(v, dtype=float), (rows,))
                for v in history(-np.arange(rows)[::-1] * su.dt)]
        if not all(np.all(np.isfinite(v)) for v in past):
            raise ParameterError("history(t) must give finite W and W' at every time asked")
        # node k of the cut sits in row k % rows: the newest, node rows - 1, is now
        su.buf[:, 0], su.buf[:, 1] = past
        su.x[:] = x
        su.met[L.STEPS_DONE] = rows - 1
        self._before = rows - 1
        if t_s is not None:
            self.t_s = self._t_first = float(t_s)
        if left_cut:
            su.met[L.FIRST_ZERO_T] = self.t_s

    def refined(self, dt_s: float, window_steps: int) -> CutStepper:
        """This cut run on at the step ``dt_s`` in windows of ``window_steps`` steps: a
        new stepper of the same system, cut and start (so :meth:`scale` scales about the
        same steady cut), carried on from this one's state and time, with its delay
        history interpolated onto the new step (:meth:`history`) and the tool's leaving
        of the cut, if it has left."""
        initial, stick_law = self._made
        new = CutStepper(self.system, self.forcing, dt_s=dt_s, window_steps=window_steps,
                         initial=initial, stick_law=stick_law)
        new.start_from(self.su.x.copy(), self.history,
                       left_cut=bool(self.su.met[L.FIRST_ZERO_T] >= 0), t_s=self.t_s)
        # a Hertz contact under way goes on with the damping it began with
        contact = [L.CONTACT_ON, L.CONTACT_WALL, L.CONTACT_T0, L.CONTACT_VIN, L.CONTACT_PEAK,
                   L.CONTACT_COUNTED, L.CONTACT_STEADY]
        new.su.met[contact] = self.su.met[contact]
        return new

    def history(self, t) -> tuple[np.ndarray, np.ndarray]:
        """(W, W') (m, m/s) of the tip at the times ``t`` <= 0 (s) before now, from the
        delay history: the cubic Hermite between its nodes from W and W', as the kernel
        reads the surface (before the cut's start, the surface before it, level)."""
        su = self.su
        rows, now = len(su.buf), int(su.met[L.STEPS_DONE])
        pos = now + np.asarray(t, dtype=float) / su.dt
        if np.any(pos > now + 1e-9) or np.any(pos < now - rows + 1 - 1e-9):
            raise ParameterError(f"history(t): t must lie within the {rows - 1} steps of "
                                 "memory before now")
        i = np.clip(np.floor(pos).astype(np.int64), now - rows + 1, now - 1)
        f = pos - i
        before = float(su.p[L.HIST_W0])

        def node(k):
            row = np.mod(k, rows)
            return (np.where(k >= 0, su.buf[row, 0], before),
                    np.where(k >= 0, su.buf[row, 1], 0.0) * su.dt)

        (w0, d0), (w1, d1) = node(i), node(i + 1)
        f2, f3 = f * f, f * f * f
        w = ((2 * f3 - 3 * f2 + 1) * w0 + (f3 - 2 * f2 + f) * d0 + (3 * f2 - 2 * f3) * w1
             + (f3 - f2) * d1)
        dw = ((6 * f2 - 6 * f) * w0 + (3 * f2 - 4 * f + 1) * d0 + (6 * f - 6 * f2) * w1
              + (3 * f2 - 2 * f) * d1) / su.dt
        return w, dw

    @property
    def state(self) -> State:
        """The state reached (x and time)."""
        return State(self.su.x.copy(), self.t_s)

    @property
    def system(self) -> System:
        return self.su.system

    @property
    def dt_s(self) -> float:
        """The RK4 step (s)."""
        return self.su.dt

    @property
    def forcing(self) -> Regenerative:
        return self.su.forcing

    @property
    def x_start(self) -> np.ndarray:
        """The state the cut started from (a copy)."""
        return self.su.x_start.copy()

    def scale(self, factor: float, held: bool = False) -> None:
        """Scale the run's departure from its steady cut by ``factor``: the modal state
        about the static deflection (u about u_s, u' about 0), an absorber's about the
        bar, a ball's relative position about where it started (``held``: a ball that
        the stick law holds stays where it is held), and the delay history about the
        static tip deflection.  Where the run is linear (the tool in the cut, a
        frictionless ball off the walls, a ball held by its friction) the scaled state is
        the same run further on: a mode growing at rate s is ln(factor) / s seconds
        ahead."""
        su, n = self.su, self.su.system.bar.n_modes
        ref = su.x_start.copy()
        ref[n:2 * n] = 0.0
        ref[2 * n + 1] = 0.0
        if su.system.kind == "tmd":
            ref[2 * n] = float(su.system.bar.psi_absorber @ ref[:n])
        if held:
            ref[2 * n:] = su.x[2 * n:]
        su.x[:] = ref + factor * (su.x - ref)
        su.buf[:, 0] = su.w_static + factor * (su.buf[:, 0] - su.w_static)
        su.buf[:, 1] *= factor
