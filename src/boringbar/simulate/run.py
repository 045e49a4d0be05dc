"""The results and options of one run: :class:`Run` (frozen; ``.summary()``, ``.config()``,
``.to_xarray()``, ``.plot()``), its :class:`State`, the :class:`Initial` conditions and the
:class:`Integration` options every analysis shares."""

from __future__ import annotations

import functools
import html
import json
import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

import boringbar
from boringbar._validate import (
    ParameterError,
    check_choice,
    check_finite,
    check_positive,
    check_range,
)
from boringbar.model.forcing import Harmonic, Regenerative
from boringbar.model.system import System
from boringbar.simulate.patterns import Pattern, classify
from boringbar.simulate.run_limits import (
    holds_a_period,
)
from boringbar.version import __version__

#: Impacts slower than this fraction of Omega delta/2 are contact, not impacts.
IMPACT_THRESHOLD = 1e-3
#: Stick intervals shorter than this fraction of the forcing period are not recorded.
STICK_MIN_PERIODS = 0.01
#: The published RK4 step (s): every run of fixed length takes it unless told otherwise
#: (a judged cut takes the converged verdict's, :func:`~boringbar.analysis.verdict.judged_step`).
PUBLISHED_DT_S = 1e-6
#: The time integrators: the published fixed-step RK4, or exact and event-driven.
INTEGRATORS = ("rk4", "exact")
#: ``integrator``: "auto" (the default; :func:`resolve_integrator` chooses) or INTEGRATORS.
INTEGRATOR_CHOICES = ("auto", *INTEGRATORS)
#: How RK4 renders the ball's Coulomb friction (docs/model.md, section 5): "sgn", the
#: published F_b = -F_c sgn(y') at every stage, or "hold", the stick law (Karnopp's): the
#: ball is held with the bar while the force that carries it is at most F_s.  The exact
#: integrator always holds (its stick mode); "hold" is the converged verdict's law.
STICK_LAWS = ("sgn", "hold")

# Resource bounds: far beyond any study (the published runs are 2e6 steps, 922
# periods and 20000 history rows), small enough that a run's arrays fit in memory.
#: Most impact and stick rows kept (the counts in the metrics are always complete;
#: ``impacts_truncated`` says when the steady part had more impacts than this), and
#: most Poincare (strobe) samples, one per period (5 floats a row).
MAX_EVENT_ROWS = 10_000_000
#: History rows a run keeps by default (``record_every=None``): about this many, every
#: N-th step with N = steps // HISTORY_ROWS, so that ``.plot()`` and ``.to_xarray()``
#: work on any run in 1 MB (6 floats a row).
HISTORY_ROWS = 20000
#: The steady part of a run by default: its last 80 % (RMS, pattern, metrics).
STEADY_FRACTION = 0.8
#: Largest |initial tip displacement| (m) and |initial velocity| (m/s): a boring bar
#: 0.2 m long cannot deflect a metre; the bounds keep the arithmetic finite.
MAX_INITIAL_DISPLACEMENT = 1.0
MAX_INITIAL_VELOCITY = 1000.0


@dataclass(frozen=True)
class Initial:
    """Initial conditions (docs/model.md, section 1), SI.

    The bar starts with tip displacement/velocity W0, W0' carried by the first
    mode (u_1 = W0/psi_1(L), higher modes at rest); the ball at ``ball_position_m``
    y0 in [-delta/2, delta/2] with relative velocity y0'; the absorber at rest
    relative to the bar.  Default: everything at rest, ball centred.
    ``tip_displacement_m`` (m), ``tip_velocity_m_s`` (m/s), ``ball_position_m`` (m),
    ``ball_velocity_m_s`` (m/s).
    """

    tip_displacement_m: float = 0.0
    tip_velocity_m_s: float = 0.0
    ball_position_m: float = 0.0
    ball_velocity_m_s: float = 0.0

    def __post_init__(self):
        d, v = MAX_INITIAL_DISPLACEMENT, MAX_INITIAL_VELOCITY
        check_range("initial tip_displacement_m", self.tip_displacement_m, -d, d, unit="m")
        check_range("initial tip_velocity_m_s", self.tip_velocity_m_s, -v, v, unit="m/s")
        check_range("initial ball_position_m", self.ball_position_m, -d, d, unit="m")
        check_range("initial ball_velocity_m_s", self.ball_velocity_m_s, -v, v, unit="m/s")


#: Everything at rest, the ball centred: a run's start unless it is given one.
AT_REST = Initial()


def fixed_run_step(dt_s: float | None) -> float:
    """The RK4 step (s) of a run of fixed length: ``dt_s``, or where it is None (not
    given) the published one (a judged cut's own step is coarser, so what this step
    passes, that one does too)."""
    return PUBLISHED_DT_S if dt_s is None else dt_s


@dataclass(frozen=True)
class Integration:
    """How every run of an analysis is integrated (the options of :func:`simulate`).

    ``duration_s`` (s) as published by default (2 s); ``dt_s`` (s): the RK4 step, None
    by default: the method's own, the published 1e-6 s (:data:`PUBLISHED_DT_S`) for a
    run of fixed length and the converged verdict's for a judged cut
    (:func:`~boringbar.analysis.verdict.judged_step`), which an analysis settles with
    :meth:`with_step`;
    ``integrator``: one of :data:`INTEGRATOR_CHOICES` ("auto", the default: per run,
    as :func:`resolve_integrator` says; "rk4", the published scheme; or "exact");
    ``steady_fraction``: the last part of each run over which RMS,
    patterns and Poincare samples are taken (0.8: the first 20 % dropped);
    ``initial``: the initial conditions of every run (default: at rest);
    ``stick_law``: how RK4 renders the ball's friction, one of :data:`STICK_LAWS`
    ("sgn", the published law, by default).
    """

    duration_s: float = 2.0
    dt_s: float | None = None
    integrator: str = "auto"
    steady_fraction: float = STEADY_FRACTION
    initial: Initial | None = None
    stick_law: str = "sgn"

    def __post_init__(self):
        check_positive("duration_s", self.duration_s, "s")
        if self.dt_s is not None:
            check_positive("dt_s", self.dt_s, "s")
        check_choice("integrator", self.integrator, INTEGRATOR_CHOICES)
        check_range("steady_fraction", self.steady_fraction, 0.0, 1.0, lo_open=True)
        check_choice("stick_law", self.stick_law, STICK_LAWS)

    @property
    def step_s(self) -> float:
        """The RK4 step of a run of fixed length (s): ``dt_s``, or the published one."""
        return fixed_run_step(self.dt_s)

    def with_step(self, default_s: float = PUBLISHED_DT_S) -> Integration:
        """These options with ``dt_s`` settled: as given, or ``default_s`` (s), the
        method's own (the published step by default, a judged cut's for a verdict; an
        analysis's plan settles it, so its runs and its record agree)."""
        return self if self.dt_s is not None else replace(self, dt_s=float(default_s))

    def kwargs(self) -> dict:
        """The keyword arguments of :func:`simulate` these options stand for."""
        return {"duration_s": self.duration_s, "dt_s": self.step_s, "integrator": self.integrator,
                "steady_fraction": self.steady_fraction, "initial": self.initial,
                "record_every": 0, "stick_law": self.stick_law}

    def to_dict(self) -> dict:
        return {"duration_s": self.duration_s, "dt_s": self.step_s,
                "integrator": self.integrator, "steady_fraction": self.steady_fraction,
                "initial": (self.initial or AT_REST).__dict__, "stick_law": self.stick_law}


@dataclass(frozen=True, eq=False)
class State:
    """A run's final state, to continue from: x = [u, u', aux, aux'] (the modal
    coordinates and the damper's, SI) at time ``t_s`` (s)."""

    x: np.ndarray
    t_s: float

    def __post_init__(self):
        x = np.asarray(self.x, dtype=float)
        # (all(map(isfinite)) over the few entries of a state: a third of np.isfinite's cost)
        if x.ndim != 1 or not all(map(math.isfinite, x.tolist())):
            raise ParameterError(f"initial state x = {self.x!r} must be a 1-d array of finite "
                                 "numbers")
        check_finite("initial state t_s", self.t_s, "s")


@dataclass(frozen=True, eq=False)
class Run:
    """The result of :func:`simulate` (frozen): streamed metrics, events and (if asked)
    history; :meth:`summary` and :meth:`config` as JSON-able dicts, :meth:`to_xarray`
    as a labelled Dataset.

    ``system`` and ``forcing`` as run; ``omega_rad_s``: forcing (or spindle) frequency
    (rad/s); ``dt_s``, ``t0_s``, ``duration_s`` (s) and ``steady_start_s`` (s), where RMS
    and patterns begin; ``metrics``: the streamed metrics; ``impacts`` (time, wall,
    relative velocity), ``sticks`` (start, end), ``strobe`` (Poincare samples) and
    ``history`` (t, W, W', aux, aux', force, and a rolling ball's spin; None unless
    recorded); ``initial`` and
    ``final``: the states it started from and ended at; ``contacts``: a Hertz
    contact's impacts in the steady part (start, wall, v_in, duration, peak force,
    v_out; none under the impact law); ``pattern``: the impact
    pattern; ``energy``: the energy flows and their balance; ``thresholds``: the
    pattern classifier's tolerances and the stick law's band; ``integrator``,
    ``stick_law`` (RK4's friction law, :data:`STICK_LAWS`) and ``elapsed_s`` (wall time).
    """

    system: System
    forcing: Harmonic | Regenerative
    omega_rad_s: float  #: forcing frequency, or spindle frequency for cutting (rad/s)
    dt_s: float
    t0_s: float
    duration_s: float
    steady_start_s: float  #: start of the steady part (s)
    metrics: dict
    impacts: np.ndarray  #: (n, 3): time, wall (+1/-1), relative velocity before
    sticks: np.ndarray  #: (n, 2): start, end of stick intervals in the steady part
    strobe: np.ndarray  #: (n, 5): Poincare samples t, W, W', aux, aux'
    #: (n, 6): t, W, W', aux, aux', force; a rolling ball's (n, 7), its spin r omega last
    history: np.ndarray | None
    initial: State
    final: State
    elapsed_s: float
    energy: dict = field(default_factory=dict)
    thresholds: dict = field(default_factory=dict)
    integrator: str = "rk4"
    stick_law: str = "sgn"
    #: (n, 6): a Hertz contact's impacts: start (s), wall, v_in (m/s), duration (s),
    #: peak force (N), v_out (m/s); None where a Hertz run kept no rows (a batch's)
    contacts: np.ndarray | None = field(default_factory=lambda: np.zeros((0, 6)))

    @property
    def hertz(self) -> bool:
        """The ball meets its walls by a compliant (Hertz) contact."""
        return getattr(self.system.damper, "contact", "impact") == "hertz"

    @property
    def contact(self) -> dict | None:
        """A Hertz contact's impacts in the steady part: their count, durations (s) and
        peak forces (N), median and largest, the restitution they gave (v_out / v_in,
        median) and the largest contact force of the whole run (N); None under the
        impact law.  ``rows_kept``: False where the run kept no rows (a batch's: its
        statistics are then None)."""
        if not self.hertz:
            return None
        c = self.contacts if self.contacts is not None else np.full((0, 6), np.nan)

        def stat(col, f):
            return float(f(c[:, col])) if len(c) else None

        return {"stiffness_n_m1_5": self.system.damper.hertz_stiffness_n_m1_5,
                "rows_kept": self.contacts is not None,
                "n_impacts": len(c) if self.contacts is not None else None,
                "duration_median_s": stat(3, np.median), "duration_max_s": stat(3, np.max),
                "peak_force_median_n": stat(4, np.median), "peak_force_max_n": stat(4, np.max),
                "restitution_ratio": (float(np.median(c[:, 5] / c[:, 2])) if len(c)
                                       else None),
                "max_force_whole_run_n": self.metrics["max_contact_force_n"]}

    @property
    def rms_tip_m(self) -> float | None:
        """RMS of the sampled tip displacement W over the steady part (m); None for a
        harmonic run whose steady part holds less than one forcing period."""
        return self.metrics["rms_tip_m"] if self.steady else None

    @functools.cached_property
    def pattern(self) -> Pattern | None:
        """The impact pattern of the steady part: a ball bar's under harmonic forcing whose
        steady part holds a forcing period, else None.  Classified when first read (an
        analysis that reads only the metrics does not pay for it)."""
        if self.system.kind != "ball" or not isinstance(self.forcing, Harmonic) \
                or not self.steady:
            return None
        return classify(self.impacts[:, 0], self.impacts[:, 1], self.sticks,
                        (self.steady_start_s, self.final.t_s), 2 * math.pi / self.omega_rad_s,
                        dt=self.dt_s, contact_time=self.metrics["contact_time_s"])

    @property
    def steady(self) -> bool:
        """The steady part holds one forcing period at least (a cut: always)."""
        return not isinstance(self.forcing, Harmonic) or holds_a_period(
            self.final.t_s - self.steady_start_s, 2 * math.pi / self.omega_rad_s)

    def config(self) -> dict:
        return {
            "boringbar_version": __version__,
            "system": self.system.to_dict(),
            "forcing": self.forcing.to_dict(),
            "omega_rad_s": self.omega_rad_s,
            "integrator": self.integrator,
            "stick_law": self.stick_law,
            "delay_interpolation": getattr(self.forcing, "interpolation", None),
            "dt_s": self.dt_s,
            "t0_s": self.t0_s,
            "duration_s": self.duration_s,
            "steady_start_s": self.steady_start_s,
            "thresholds": self.thresholds,
        }

    @property
    def steady_periods(self) -> float | None:
        """Forcing periods in the steady part of a harmonic run (None for a cut)."""
        if not isinstance(self.forcing, Harmonic):
            return None
        return (self.final.t_s - self.steady_start_s) * self.omega_rad_s / (2 * math.pi)

    def summary(self) -> dict:
        """JSON-able summary (what ``boringbar simulate --json`` prints).  A harmonic
        run whose steady part holds less than one forcing period has no steady RMS,
        peak or pattern: those are None, with a warning saying why."""
        m = self.metrics
        sys = self.system
        periods, steady = self.steady_periods, self.steady
        if not steady:
            warnings.warn(f"the steady part of this run ({self.final.t_s - self.steady_start_s:.3g}"
                          f" s) holds {periods:.2f} of a forcing period: no steady RMS, peak "
                          "or pattern (give duration_s >= one period / steady_fraction)",
                          RuntimeWarning, stacklevel=2)
        return {
            "bar": sys.kind,
            "preset": sys.preset,
            "readings": list(sys.readings),
            "integrator": self.integrator,
            "natural_frequency_hz": sys.reference_frequency_rad_s / (2 * math.pi),
            "forcing_frequency_hz": self.omega_rad_s / (2 * math.pi),
            "ratio": self.omega_rad_s / sys.reference_frequency_rad_s,
            "force_n": getattr(self.forcing, "amplitude_n", None),
            "steady_periods": periods,
            "rms_tip_m": self.rms_tip_m,
            "max_abs_tip_m": m["max_abs_tip_m"] if steady else None,
            "pattern": None if self.pattern is None else self.pattern.name,
            "impacts_per_cycle": None if self.pattern is None else
            self.pattern.impacts_per_cycle,
            "max_abs_rel_disp_m": m["max_abs_aux_m"],
            "contact_time_s": m["contact_time_s"],
            "stick_time_s": m["stick_time_s"],
            "energy": self.energy,
            "dt_s": self.dt_s,
            "duration_s": self.duration_s,
            "elapsed_s": self.elapsed_s,
            "final_time_s": self.final.t_s,
            "final_phase_rad": (self.omega_rad_s * self.final.t_s) % (2 * math.pi),
            **({"cutting": self.cutting} if isinstance(self.forcing, Regenerative) else {}),
            **({"contact": self.contact} if self.hertz else {}),
        }

    @property
    def cutting(self) -> dict:
        """Chatter verdicts of a regenerative run (docs/model.md, section 4)."""
        m = self.metrics
        f = self.forcing
        return {
            "depth_m": f.depth_m,
            "rpm": f.rpm,
            "chatter": m["first_zero_time_s"] is not None,
            "first_zero_time_s": m["first_zero_time_s"],
            "steps_with_zero_force": m["steps_with_zero_force"],
            "max_force_n": m["max_force_n"],
            "mean_force_n": m["mean_force_n"],
            "amplitude_m": m["amplitude_m"],
            "bounded_chatter": bool(m["amplitude_m"] > f.bounded_fraction * f.feed_m),
            "bounded_threshold_m": f.bounded_fraction * f.feed_m,
            "static_deflection_m": m["static_deflection_m"],
            "cutting_law": f.law.describe(),
            "force_at_feed_n": f.mean_force_n,
            "force_noise": f.force_noise,
            "delay_interpolation": f.interpolation,
            "start": f.start,
        }

    def _repr_html_(self) -> str:
        """The run as a notebook shows it: what was run and its main results, in mm."""
        with warnings.catch_warnings():  # the table says it itself
            warnings.simplefilter("ignore", RuntimeWarning)
            s = self.summary()
        rows = [("bar", f"{s['bar']} ({s['preset']} preset)"),
                ("forcing", f"F0 = {s['force_n']:g} N at Omega/omega_n = {s['ratio']:.4g} "
                            f"({s['forcing_frequency_hz']:.2f} Hz)" if s["force_n"] is not None
                 else f"cut at {self.forcing.rpm:g} rpm, depth {self.forcing.depth_m * 1e3:g} mm"),
                ("tip RMS (steady part)", _mm(s["rms_tip_m"])),
                ("max |tip|", _mm(s["max_abs_tip_m"])),
                ("impact pattern", s["pattern"] or "-"),
                ("integrator", f"{s['integrator']}, {s['duration_s']:g} s in "
                               f"{s['elapsed_s']:.3g} s"),
                ("history", "none (record_every=0)" if self.history is None
                 else f"{len(self.history)} rows: .plot(), .to_xarray()")]
        if "cutting" in s:
            rows.insert(2, ("chatter", "yes" if s["cutting"]["chatter"] else "no"))
        body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                       f"<td style='text-align:left'>{html.escape(str(v))}</td></tr>"
                       for k, v in rows)
        return f"<table><caption>boringbar Run</caption>{body}</table>"

    def plot(self, **kwargs):
        """The run's figure (a matplotlib Figure; needs ``record_every``): what
        :func:`boringbar.plot.plot_run` draws, with its ``kwargs`` (``zoom_periods``,
        ``fig``).  The plotting package sits above this one and is reached through the
        package's lazy ``boringbar.plot``: matplotlib is loaded only when a figure is drawn."""
        return boringbar.plot.plot_run(self, **kwargs)

    def to_xarray(self):
        """The decimated history as an xarray Dataset (needs ``record_every``), with the
        configuration and the summary as JSON in its attributes."""
        if self.history is None:
            raise ValueError("no history was recorded (record_every=0): run simulate(..., "
                             "record_every=None) for the default history")
        import xarray as xr  # here: a run needs xarray only to be written
        h = self.history
        aux = "y" if self.system.kind in ("ball", "locked") else "absorber_stroke"
        time = ("time_s",)
        ds = xr.Dataset(
            {
                "tip_displacement_m": (time, h[:, 1], {"units": "m"}),
                "tip_velocity_m_s": (time, h[:, 2], {"units": "m/s"}),
                f"{aux}_m": (time, h[:, 3], {"units": "m"}),
                f"{aux}_velocity_m_s": (time, h[:, 4], {"units": "m/s"}),
                "force_n": (time, h[:, 5], {"units": "N"}),
                **({"ball_spin_m_s": (time, h[:, 6], {
                    "units": "m/s", "long_name": "the rolling ball's spin r omega: its "
                    "surface's speed about its centre (y' while it rolls without slip)"})}
                   if h.shape[1] > 6 else {}),
            },
            coords={"time_s": (time, h[:, 0], {"units": "s"})},
            attrs={"config": json.dumps(self.config(), default=_plain),
                   "summary": json.dumps(self.summary(), default=_plain)},
        )
        if self.impacts.size:
            ds["impact_time_s"] = ("impact", self.impacts[:, 0], {
                "units": "s", "long_name": "time of each impact in the steady part"})
            ds["impact_wall"] = ("impact", self.impacts[:, 1], {
                "long_name": "the wall struck: +1 at y = +gap/2, -1 at y = -gap/2"})
        if self.contacts is not None and self.contacts.size:
            c = self.contacts
            for col, name, unit in ((0, "contact_start_s", "s"), (2, "contact_speed_in_m_s", "m/s"),
                                    (3, "contact_duration_s", "s"),
                                    (4, "contact_peak_force_n", "N"),
                                    (5, "contact_speed_out_m_s", "m/s")):
                ds[name] = ("contact", c[:, col], {"units": unit})
        return ds


def _mm(value_m: float | None) -> str:
    """A length (m) as the notebook shows it: mm, or why there is none."""
    return "none: the steady part is shorter than one period" if value_m is None \
        else f"{value_m * 1e3:.4g} mm"


def _plain(value):
    """A numpy scalar as the Python number it holds (for json.dumps)."""
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


class IntegrationError(RuntimeError):
    """The exact integrator could not finish a run: ``status`` is the kernel's code
    (:data:`EXACT_STATUS_MESSAGES`), ``events`` the events it had handled and
    ``t_reached`` (s) where it stopped; the message says what happened and what to do."""

    def __init__(self, status: int, events: int, t_reached: float):
        self.status, self.events, self.t_reached = status, events, t_reached
        super().__init__(f"exact integrator: {EXACT_STATUS_MESSAGES.get(status, 'unknown')} "
                         f"(status {status}, after {events} events, at t = {t_reached:.6g} s)")


#: What the exact integrator's status codes mean (simulate/layout.py, EXACT_STATUS).
EXACT_STATUS_MESSAGES = {
    1: "the event cap was reached (too many impacts or switches for one run; shorten "
       "the run or continue it from its final state)",
    2: "stalled on events of zero length (the motion could not be continued past a "
       "chattering contact)",
}
