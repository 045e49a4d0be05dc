"""``simulate``: one time-domain run of a bar under harmonic or cutting forces.

The description objects (System, Harmonic) are packed into the kernel's
parameter vector here (layout in :mod:`boringbar.kernels.layout`); the
kernel streams its metrics; this module turns them into a labelled
:class:`Run`.
"""

from __future__ import annotations

import html
import importlib
import json
import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from boringbar._validate import (
    ParameterError,
    check_choice,
    check_finite,
    check_int,
    check_positive,
    check_range,
)
from boringbar.kernels import BMAX, run_exact, run_rk4, run_rk4_batch
from boringbar.kernels import layout as L
from boringbar.model.dampers import ImpactDamper, TunedMassDamper
from boringbar.model.forcing import Harmonic, Regenerative
from boringbar.model.system import System
from boringbar.patterns import Pattern, classify
from boringbar.run_limits import (
    MAX_STEPS,
    check_delay,
    check_history,
    check_step,
    check_steps,
    holds_a_period,
)
from boringbar.version import __version__

#: Impacts slower than this fraction of Omega delta/2 are contact, not impacts.
IMPACT_THRESHOLD = 1e-3
#: Stick intervals shorter than this fraction of the forcing period are not recorded.
STICK_MIN_PERIODS = 0.01
#: The time integrators: the published fixed-step RK4, or exact and event-driven.
INTEGRATORS = ("rk4", "exact")
#: ``integrator``: "auto" (the default; :func:`resolve_integrator` chooses) or INTEGRATORS.
INTEGRATOR_CHOICES = ("auto", *INTEGRATORS)

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


@dataclass(frozen=True)
class Integration:
    """How every run of an analysis is integrated (the options of :func:`simulate`).

    ``duration_s`` and ``dt_s`` (s) as published by default (2 s, 1e-6 s);
    ``integrator``: one of :data:`INTEGRATOR_CHOICES` ("auto", the default: per run,
    as :func:`resolve_integrator` says; "rk4", the published scheme; or "exact");
    ``steady_fraction``: the last part of each run over which RMS,
    patterns and Poincare samples are taken (0.8: the first 20 % dropped);
    ``initial``: the initial conditions of every run (default: at rest).
    """

    duration_s: float = 2.0
    dt_s: float = 1e-6
    integrator: str = "auto"
    steady_fraction: float = STEADY_FRACTION
    initial: Initial | None = None

    def __post_init__(self):
        check_positive("duration_s", self.duration_s, "s")
        check_positive("dt_s", self.dt_s, "s")
        check_choice("integrator", self.integrator, INTEGRATOR_CHOICES)
        check_range("steady_fraction", self.steady_fraction, 0.0, 1.0, lo_open=True)

    def kwargs(self) -> dict:
        """The keyword arguments of :func:`simulate` these options stand for."""
        return {"duration_s": self.duration_s, "dt_s": self.dt_s, "integrator": self.integrator,
                "steady_fraction": self.steady_fraction, "initial": self.initial,
                "record_every": 0}

    def to_dict(self) -> dict:
        return {"duration_s": self.duration_s, "dt_s": self.dt_s,
                "integrator": self.integrator, "steady_fraction": self.steady_fraction,
                "initial": (self.initial or Initial()).__dict__}


@dataclass(frozen=True, eq=False)
class State:
    """A run's final state, to continue from: x = [u, u', aux, aux'] (the modal
    coordinates and the damper's, SI) at time ``t_s`` (s)."""

    x: np.ndarray
    t_s: float

    def __post_init__(self):
        x = np.asarray(self.x, dtype=float)
        if x.ndim != 1 or not np.all(np.isfinite(x)):
            raise ParameterError(f"initial state x = {self.x!r} must be a 1-d array of finite "
                                 "numbers")
        check_finite("initial state t_s", self.t_s, "s")


#: Figure makers by what they draw ("run" -> plot_run), registered by boringbar.plot so
#: that Run.plot works without this layer importing matplotlib.
FIGURES: dict = {}


@dataclass(frozen=True, eq=False)
class Run:
    """The result of :func:`simulate` (frozen): streamed metrics, events and (if asked)
    history; :meth:`summary` and :meth:`config` as JSON-able dicts, :meth:`to_xarray`
    as a labelled Dataset.

    ``system`` and ``forcing`` as run; ``omega_rad_s``: forcing (or spindle) frequency
    (rad/s); ``dt_s``, ``t0_s``, ``duration_s`` (s) and ``steady_start_s`` (s), where RMS
    and patterns begin; ``metrics``: the streamed metrics; ``impacts`` (time, wall,
    relative velocity), ``sticks`` (start, end), ``strobe`` (Poincare samples) and
    ``history`` (t, W, W', aux, aux', force; None unless recorded); ``initial`` and
    ``final``: the states it started from and ended at; ``pattern``: the impact
    pattern; ``energy``: the energy flows and their balance; ``thresholds``: the
    pattern classifier's tolerances; ``integrator`` and ``elapsed_s`` (wall time).
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
    history: np.ndarray | None  #: (n, 6): t, W, W', aux, aux', force
    initial: State
    final: State
    pattern: Pattern | None
    elapsed_s: float
    energy: dict = field(default_factory=dict)
    thresholds: dict = field(default_factory=dict)
    integrator: str = "rk4"

    @property
    def rms_tip_m(self) -> float | None:
        """RMS of the sampled tip displacement W over the steady part (m); None for a
        harmonic run whose steady part holds less than one forcing period."""
        return self.metrics["rms_tip_m"] if self.steady else None

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
        ``fig``).  The plotting module sits above this one and registers itself
        (:data:`FIGURES`) when it is imported, here on first use: matplotlib is loaded
        only when a figure is drawn."""
        if "run" not in FIGURES:
            importlib.import_module("boringbar.plot")
        return FIGURES["run"](self, **kwargs)

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
            },
            coords={"time_s": (time, h[:, 0], {"units": "s"})},
            attrs={"config": json.dumps(self.config(), default=_plain),
                   "summary": json.dumps(self.summary(), default=_plain)},
        )
        if self.impacts.size:
            ds["impact_time_s"] = ("impact", self.impacts[:, 0], {"units": "s"})
            ds["impact_wall"] = ("impact", self.impacts[:, 1])
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


#: What the exact integrator's status codes mean (kernels/layout.py, EXACT_STATUS).
EXACT_STATUS_MESSAGES = {
    1: "the event cap was reached (too many impacts or switches for one run; shorten "
       "the run or continue it from its final state)",
    2: "stalled on events of zero length (the motion could not be continued past a "
       "chattering contact)",
}


def pack(system: System, omega: float, amplitude: float, dt: float) -> np.ndarray:
    """The kernel's parameter vector for ``system`` under F0 sin(omega t).

    ``omega`` = 0 (no harmonic force) refers the impact threshold to omega_n.
    """
    bar = system.bar
    n = bar.n_modes
    if n > L.NMAX:
        raise ParameterError(f"n_modes = {n} is outside the allowed range [1, {L.NMAX}]")
    p = L.empty_params()
    p[L.N_MODES] = n
    p[L.FORCING] = L.HARMONIC
    p[L.F0] = amplitude
    p[L.OMEGA] = omega
    p[L.M_:L.M_ + n] = bar.mass_kg
    p[L.K_:L.K_ + n] = bar.stiffness_n_m
    p[L.C_:L.C_ + n] = bar.damping_n_s_m
    p[L.PSI_L:L.PSI_L + n] = bar.psi_tip
    p[L.PSI_D:L.PSI_D + n] = bar.psi_damper
    p[L.PSI_A:L.PSI_A + n] = bar.psi_absorber
    p[L.REACTION] = 1.0
    d = system.damper
    kind = system.kind
    p[L.CASE] = {"solid": L.SOLID, "ball": L.BALL, "tmd": L.TMD, "locked": L.LOCKED}[kind]
    if isinstance(d, ImpactDamper):
        m = d.mass_kg
        meff = 1.0 / (1.0 / m + float(np.sum(bar.psi_damper**2 / bar.mass_kg)))
        p[L.BALL_MASS] = m
        p[L.HALF_GAP] = d.gap_m / 2
        p[L.RESTITUTION] = d.restitution
        p[L.FRICTION] = d.friction_force_n
        p[L.STATIC_FRICTION] = d.friction_force_n * d.friction.static_ratio
        p[L.REACTION] = 1.0 if d.friction.reaction == "reciprocal" else -1.0
        p[L.M_EFF] = meff
        ref = omega if omega > 0 else bar.natural_frequency_rad_s
        p[L.V_IMPACT] = IMPACT_THRESHOLD * ref * d.gap_m / 2
        # the sgn() law chatters about y' = 0 with steps of up to F_c dt / m_eff
        p[L.V_STICK] = p[L.V_IMPACT] + 2.0 * d.friction_force_n * dt / meff
        p[L.STICK_MIN] = STICK_MIN_PERIODS * 2 * math.pi / ref
    elif isinstance(d, TunedMassDamper):
        p[L.TMD_MASS] = d.mass_kg
        p[L.TMD_K] = d.stiffness_n_m
        p[L.TMD_C] = d.damping_n_s_m
    return p


def pack_cut(system: System, forcing: Regenerative, dt: float, w_static: float) -> np.ndarray:
    """The kernel's parameter vector for ``system`` in the cut ``forcing``: its law, noise
    and delay; ``w_static`` (m) the surface before the cut of a static start."""
    p = pack(system, 0.0, 0.0, dt)
    p[L.FORCING] = L.REGENERATIVE
    law = forcing.law
    p[L.KR_B] = law.kernel_coefficient(forcing.depth_m)
    p[L.CUT_MC] = law.exponent
    p[L.NOISE_STD] = forcing.force_noise
    p[L.NOISE_INTERVAL] = forcing.noise_interval_s
    p[L.NOISE_SEED] = forcing.noise_seed
    p[L.FEED] = forcing.feed_m
    p[L.TAU] = forcing.tau_s
    p[L.N_REV] = forcing.revolutions
    p[L.INTERP] = 1.0 if forcing.interpolation == "cubic" else 0.0
    p[L.STOP_AT_ZERO] = 1.0 if forcing.stop_at_zero else 0.0
    p[L.HIST_W0] = w_static if forcing.start == "static" else 0.0
    return p


def initial_state(system: System, initial: Initial) -> np.ndarray:
    """x = [u, u', aux, aux'] from tip and ball initial conditions."""
    bar = system.bar
    n = bar.n_modes
    x = np.zeros(2 * n + 2)
    x[0] = initial.tip_displacement_m / bar.psi_tip[0]
    x[n] = initial.tip_velocity_m_s / bar.psi_tip[0]
    d = system.damper
    if isinstance(d, ImpactDamper):
        check_range("initial ball_position_m", initial.ball_position_m, -d.gap_m / 2, d.gap_m / 2,
                    unit="m")
        x[2 * n] = initial.ball_position_m
        x[2 * n + 1] = 0.0 if d.locked else initial.ball_velocity_m_s
    elif isinstance(d, TunedMassDamper):
        x[2 * n] = float(bar.psi_absorber @ x[:n])
        x[2 * n + 1] = float(bar.psi_absorber @ x[n:2 * n])
    return x


def stored_energy(system: System, x: np.ndarray) -> float:
    """Kinetic + potential energy of state x (J)."""
    bar = system.bar
    n = bar.n_modes
    u, v = x[:n], x[n:2 * n]
    e = 0.5 * float(np.sum(bar.mass_kg * v**2) + np.sum(bar.stiffness_n_m * u**2))
    d = system.damper
    if isinstance(d, ImpactDamper):
        ud = x[2 * n + 1] + float(bar.psi_damper @ v)
        e += 0.5 * d.mass_kg * ud**2
    elif isinstance(d, TunedMassDamper):
        rel = x[2 * n] - float(bar.psi_absorber @ u)
        e += 0.5 * d.mass_kg * x[2 * n + 1] ** 2 + 0.5 * d.stiffness_n_m * rel**2
    return e


def stick_slip(system: System) -> bool:
    """Whether the ball's friction has a static limit above the sliding one (exact only)."""
    d = system.damper
    return isinstance(d, ImpactDamper) and d.friction.static_ratio != 1 and d.friction_force_n > 0


def resolve_integrator(integrator: str, system: System, cutting: bool = False) -> str:
    """``integrator``, or for "auto": "rk4" under the ``paper`` preset (the published
    scheme) and in cuts (``cutting``: RK4 is faster there, docs/exact.md) unless
    :func:`stick_slip`, else "exact" (exact at events, about 14x faster than RK4)."""
    check_choice("integrator", integrator, INTEGRATOR_CHOICES)
    if integrator != "auto":
        return integrator
    return "rk4" if (system.preset == "paper" or cutting) and not stick_slip(system) \
        else "exact"


def resolved_integrators(integrator: str, systems, cutting: bool = False) -> str:
    """What :func:`resolve_integrator` gives the runs of ``systems``, sorted and
    comma-joined ("exact", "rk4" or "exact,rk4"): a result's ``integrator_used``."""
    return ",".join(sorted({resolve_integrator(integrator, s, cutting) for s in systems}))


def check_cut_law(forcing, integrator: str) -> None:
    """The exact integrator's cut is linear in the state: Kr b h without noise."""
    if integrator != "exact" or not isinstance(forcing, Regenerative):
        return
    law = forcing.law
    if not law.linear_law or forcing.force_noise > 0.0:
        what = law.describe() + (f" with force_noise = {forcing.force_noise:g}"
                                 if forcing.force_noise > 0.0 else "")
        raise ParameterError(f"integrator = 'exact' integrates a cut whose force is linear in "
                             f"the state (Kr b h, no force noise); this cut has {what}: use "
                             "integrator = 'rk4'")


def check_friction_law(system: System, integrator: str) -> None:
    """True stick-slip needs the exact integrator: RK4 has only the published sgn() law."""
    if integrator == "rk4" and stick_slip(system):
        raise ParameterError(f"friction static_ratio = {system.damper.friction.static_ratio!r}: "
                             "the rk4 integrator has only the sgn() law (static_ratio = 1); "
                             "use integrator = 'exact' for true stick-slip")


@dataclass(eq=False)
class _Setup:
    """One run, checked and packed for a kernel, and the arrays it fills."""

    system: System
    forcing: Harmonic | Regenerative
    integrator: str
    omega: float
    dt: float
    t0: float
    n_steps: int
    steady_steps: int
    record_every: int
    cutting: bool
    period: float
    w_static: float
    p: np.ndarray
    x: np.ndarray
    x_start: np.ndarray
    buf: np.ndarray | None
    imp: np.ndarray
    stick: np.ndarray
    stb: np.ndarray
    rec: np.ndarray
    met: np.ndarray


def _setup(system, forcing, duration, dt, initial, record_every, steady_fraction, strobe,
           integrator) -> _Setup:
    """Check the arguments of :func:`simulate` and pack the run."""
    check_choice("integrator", integrator, INTEGRATOR_CHOICES)
    if not isinstance(system, System):
        raise ParameterError(f"system = {system!r} must be a System (see make_system)")
    if not isinstance(forcing, Harmonic | Regenerative):
        raise ParameterError(f"forcing = {forcing!r} must be a Harmonic or a Regenerative")
    integrator = resolve_integrator(integrator, system, isinstance(forcing, Regenerative))
    cutting = isinstance(forcing, Regenerative)
    check_friction_law(system, integrator)
    check_cut_law(forcing, integrator)
    check_range("steady_fraction", steady_fraction, 0.0, 1.0, lo_open=True)
    n_steps = check_steps(duration, dt)
    record_every = (max(1, n_steps // HISTORY_ROWS) if record_every is None
                    else check_int("record_every", record_every, 0, MAX_STEPS))
    omega = (2 * math.pi / forcing.tau_s if cutting
             else forcing.omega(system.reference_frequency_rad_s))
    check_step(system, omega, dt)
    if cutting:
        check_delay(forcing.rpm, forcing.revolutions, dt)
    if record_every:
        check_history(n_steps, record_every)

    if isinstance(initial, State):
        x = np.array(initial.x, dtype=float)
        if x.shape != (2 * system.bar.n_modes + 2,):
            raise ParameterError(f"initial state has {x.size} entries; this system needs "
                                 f"{2 * system.bar.n_modes + 2}")
        t0 = float(initial.t_s)
    else:
        x = initial_state(system, initial or Initial())
        t0 = 0.0
    w_static = 0.0
    if cutting:
        # static deflection under the mean force, mode by mode (absorber relaxed)
        bar = system.bar
        u_static = bar.psi_tip * forcing.mean_force_n / bar.stiffness_n_m
        w_static = float(bar.psi_tip @ u_static)
        if forcing.start == "static" and not isinstance(initial, State):
            # the static deflection plus whatever initial motion was asked for
            # (a perfect static start has nothing to grow from)
            n = bar.n_modes
            x[:n] += u_static
            if system.kind == "tmd":
                x[2 * n] += float(bar.psi_absorber @ u_static)
    x_start = x.copy()

    if cutting:
        p = pack_cut(system, forcing, dt, w_static)
        buf = np.zeros((check_delay(forcing.rpm, forcing.revolutions, dt), 2))
        period = 2 * math.pi / system.reference_frequency_rad_s
    else:
        p = pack(system, omega, forcing.amplitude_n, dt)
        buf = None
        period = 2 * math.pi / omega if omega > 0 else duration
    n_periods = duration / period
    steady_steps = int(round((1.0 - steady_fraction) * n_steps))
    if strobe:
        p[L.STROBE_PERIOD] = period
        p[L.STROBE_T0] = 0.0
    if strobe and n_periods + 2 > MAX_EVENT_ROWS:
        raise ParameterError(f"duration_s = {duration:g} s is {n_periods:.3g} periods of "
                             f"{period:g} s: at most {MAX_EVENT_ROWS:.0e} Poincare samples "
                             "(one a period) are kept; shorten the run")
    cap_imp = int(min(MAX_EVENT_ROWS, max(1000, 40 * n_periods)))
    imp = np.zeros((cap_imp, 3))
    stick = np.zeros((cap_imp, 2))
    stb = np.zeros((int(n_periods) + 2 if strobe else 0, 5))
    n_rec = n_steps // record_every if record_every else 0
    rec = np.zeros((n_rec, 6))
    met = np.zeros(L.MET_SIZE)
    met[L.STEADY_MAX_W] = -np.inf
    met[L.STEADY_MIN_W] = np.inf
    met[L.FIRST_ZERO_T] = -1.0

    return _Setup(system, forcing, integrator, omega, dt, t0, n_steps, steady_steps,
                  int(record_every), cutting, period, w_static, p, x, x_start, buf, imp, stick,
                  stb, rec, met)


def _run_kernel(su: _Setup) -> float:
    """Run the kernel of ``su`` in place; the wall time (s)."""
    p, x, t0, dt, n_steps, steady_steps = su.p, su.x, su.t0, su.dt, su.n_steps, su.steady_steps
    record_every, rec, imp, stick, stb, met = (su.record_every, su.rec, su.imp, su.stick, su.stb,
                                               su.met)
    tic = time.perf_counter()
    if su.integrator == "exact":
        t_reached = run_exact(p, x, t0, t0 + n_steps * dt, t0 + steady_steps * dt,
                              record_every * dt, rec, imp, stick, stb, met, dt=dt)
        # a cut stopped at its first zero finishes that step of dt
        met[L.STEPS_DONE] = min(n_steps, int(round((t_reached - t0) / dt)))
        if met[L.EXACT_STATUS] != 0:
            raise IntegrationError(int(met[L.EXACT_STATUS]), int(met[L.N_EVENTS]), t_reached)
    else:
        run_rk4(p, x, t0, dt, n_steps, steady_steps, int(record_every), rec, imp, stick, stb,
                met, su.buf)
    return time.perf_counter() - tic


def _result(su: _Setup, elapsed: float) -> Run:
    """The labelled :class:`Run` from a finished kernel run."""
    system, forcing, integrator, omega, dt, t0 = (su.system, su.forcing, su.integrator, su.omega,
                                                  su.dt, su.t0)
    steady_steps, record_every, cutting, period, w_static = (su.steady_steps, su.record_every,
                                                             su.cutting, su.period, su.w_static)
    p, x, x_start, imp, stick, stb, rec, met = (su.p, su.x, su.x_start, su.imp, su.stick, su.stb,
                                                su.rec, su.met)
    cap_imp = imp.shape[0]
    n_steps = int(met[L.STEPS_DONE])  # fewer if a cut stopped at its first h = 0
    n_imp = int(met[L.N_IMP_REC])
    n_stk = int(met[L.N_STICK_REC])
    t_end = t0 + n_steps * dt
    t_steady = t0 + steady_steps * dt
    n_st = met[L.N_STEADY]
    nan = math.nan
    # a cut stopped at its first zero may end before the steady part begins:
    # its steady statistics are then undefined (NaN), not zero
    metrics = {
        "rms_tip_m": math.sqrt(met[L.SUM_W2] / n_st) if n_st else nan,
        "mean_tip_m": float(met[L.SUM_W] / n_st) if n_st else nan,
        "max_abs_tip_m": float(met[L.MAX_ABS_W]) if n_st else nan,
        "max_abs_aux_m": float(met[L.MAX_ABS_AUX]) if n_st else nan,
        "max_abs_aux_all_m": float(met[L.MAX_ABS_AUX_ALL]),
        "rms_aux_m": math.sqrt(met[L.SUM_AUX2] / n_st) if n_st else nan,
        "impacts_plus": int(met[L.N_IMP_PLUS]),
        "impacts_minus": int(met[L.N_IMP_MINUS]),
        "impacts_total": int(met[L.N_IMP_ALL]),
        "micro_impacts": int(met[L.N_MICRO]),
        "contact_time_s": float(met[L.T_CONTACT]),
        "stick_time_s": float(met[L.T_STICK]),
        "impacts_truncated": bool(n_imp > cap_imp),
        "first_zero_time_s": float(met[L.FIRST_ZERO_T]) if met[L.FIRST_ZERO_T] >= 0 else None,
        "steps_with_zero_force": int(met[L.N_ZERO_STEPS]),
        "max_force_n": float(met[L.MAX_FORCE]),
        "mean_force_n": float(met[L.SUM_F] / n_st) if n_st else nan,
        "amplitude_m": float(max(0.0, (met[L.STEADY_MAX_W] - met[L.STEADY_MIN_W]) / 2))
        if n_st else nan,
        "static_deflection_m": w_static,
        "events": int(met[L.N_EVENTS]),
    }
    e0 = stored_energy(system, x_start)
    e1 = stored_energy(system, x)
    w_in = met[L.W_FORCE] + met[L.W_NONRECIP]
    dissipated = met[L.D_VISC] + met[L.D_IMPACT] + met[L.D_FRICTION]
    scale = max(abs(w_in), dissipated, abs(e1 - e0), e0, e1, 1e-300)
    energy = {
        "work_force_j": float(met[L.W_FORCE]),
        "work_nonreciprocal_friction_j": float(met[L.W_NONRECIP]),
        "dissipated_viscous_j": float(met[L.D_VISC]),
        "dissipated_impacts_j": float(met[L.D_IMPACT]),
        "dissipated_friction_j": float(met[L.D_FRICTION]),
        "stored_initial_j": e0,
        "stored_final_j": e1,
        "balance_residual_j": float(w_in - (e1 - e0) - dissipated),
        "balance_relative": float((w_in - (e1 - e0) - dissipated) / scale),
    }
    pattern = None  # none without a whole forcing period to classify
    if system.kind == "ball" and not cutting and holds_a_period(t_end - t_steady, period):
        pattern = classify(imp[:min(n_imp, cap_imp), 0], imp[:min(n_imp, cap_imp), 1],
                           stick[:min(n_stk, cap_imp)], (t_steady, t_end), period, dt=dt,
                           contact_time=met[L.T_CONTACT])
    thresholds = {
        "impact_velocity_m_s": float(p[L.V_IMPACT]),
        "stick_velocity_m_s": float(p[L.V_STICK]),
        "stick_min_duration_s": float(p[L.STICK_MIN]),
    }
    return Run(
        system=system, forcing=forcing, omega_rad_s=omega, dt_s=dt, t0_s=t0,
        duration_s=n_steps * dt, steady_start_s=t_steady, metrics=metrics,
        impacts=imp[:min(n_imp, cap_imp)].copy(),
        sticks=stick[:min(n_stk, cap_imp)].copy(),
        strobe=stb[:int(met[L.N_STROBE])].copy(),
        history=rec[:int(met[L.N_REC])].copy() if record_every else None,
        initial=State(x_start, t0), final=State(x.copy(), t_end), pattern=pattern,
        elapsed_s=elapsed, energy=energy, thresholds=thresholds, integrator=integrator,
    )


def simulate(system: System, forcing: Harmonic | Regenerative, *, duration_s: float = 2.0,
             dt_s: float = 1e-6,
             initial: Initial | State | None = None, record_every: int | None = None,
             steady_fraction: float = STEADY_FRACTION, strobe: bool = False,
             integrator: str = "auto") -> Run:
    """Integrate ``system`` under ``forcing`` with the published RK4 scheme or exactly.

    ``duration_s`` (s) and ``dt_s`` (s) as published by default (2 s, 1e-6 s);
    RMS and patterns use the last ``steady_fraction`` of the record.
    ``initial``: :class:`Initial`, or a previous run's ``final`` :class:`State`
    to continue it (time, hence forcing phase, runs on).  ``record_every`` N
    keeps every N-th step's state (None, the default: about :data:`HISTORY_ROWS`
    rows, enough to plot; 0: no history, as the analyses run); ``strobe`` keeps
    Poincare samples at Omega t = 0 mod 2 pi.

    Limits (a ParameterError names the parameter, its value and the maximum): every
    number finite (:mod:`boringbar.run_limits`); at most 1e10 steps duration_s / dt_s;
    at most 1e7 history rows (steps // record_every) and as many
    rows of a cut's delay history (revolutions 60 / rpm / dt_s); at most
    :data:`MAX_EVENT_ROWS` (1e7) Poincare samples.  Impacts and stick intervals beyond
    1e7 rows are counted in the metrics but not kept (``impacts_truncated``).

    ``integrator``: ``"auto"`` (the default: :func:`resolve_integrator`, exact for
    harmonic forcing, RK4 under the paper preset and in cuts), ``"rk4"`` (the
    published scheme, docs/model.md, section 5) or ``"exact"`` (event-driven, exact
    between events: the compiled core, `core/exact/`;
    under harmonic forcing ``dt_s`` is then only the step of the recorded history
    and of the duration and steady-window rounding, and the steady RMS is the
    exact integral over the window; in a cut the delayed surface comes from a
    history of step H = tau / ceil(tau / dt_s), interpolated as
    ``forcing.interpolation`` says (cubic Hermite in W, W': error O(H^4)), and
    the first zero of the force is located in time).  True stick-slip (a static friction limit,
    ``Friction(static_ratio > 1)``) needs ``"exact"``; a cut with Kienzle's law or with
    force noise needs ``"rk4"`` (the exact integrator's cut is linear in the state).
    """
    su = _setup(system, forcing, duration_s, dt_s, initial, record_every, steady_fraction, strobe,
                integrator)
    return _result(su, _run_kernel(su))


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
    x[:n] += bar.psi_tip * forcing.mean_force_n / bar.stiffness_n_m
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
    coordinate; ``max_force_n``: the largest cutting force (N)."""

    t_end_s: float
    max_tip_m: float
    min_tip_m: float
    rms_tip_m: float
    left_cut: bool
    impacts: int
    max_rel_m: float
    mode_half_pp: np.ndarray  #: half the peak-to-peak of each modal coordinate u_i
    max_force_n: float = math.nan  #: the largest cutting force (N)

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
    the forcing must not stop at the first zero of the force.
    """

    def __init__(self, system: System, forcing: Regenerative, *, dt_s: float, window_steps: int,
                 initial: Initial | State | None = None):
        if forcing.stop_at_zero:
            raise ParameterError("a cut advanced window by window runs on after the force "
                                 "reaches zero: give stop_at_zero = False")
        check_int("window_steps", window_steps, 1, MAX_STEPS)
        self.su = _setup(system, forcing, window_steps * dt_s, dt_s, initial, 0, 1.0, False,
                         "rk4")
        self.window_steps = window_steps
        self.t_s = self.su.t0
        self.modes = np.zeros((system.bar.n_modes, 2))

    def advance(self) -> Window:
        """Run one more window; what it did."""
        su, met = self.su, self.su.met
        for slot in (L.SUM_W2, L.SUM_W, L.N_STEADY, L.MAX_ABS_AUX, L.MAX_FORCE):
            met[slot] = 0.0
        met[L.STEADY_MAX_W], met[L.STEADY_MIN_W] = -np.inf, np.inf
        self.modes[:, 0], self.modes[:, 1] = -np.inf, np.inf
        zeros, impacts = met[L.N_ZERO_STEPS], met[L.N_IMP_ALL]
        run_rk4(su.p, su.x, self.t_s, su.dt, self.window_steps, 0, 0, su.rec, su.imp, su.stick,
                su.stb, met, su.buf, self.modes)
        self.t_s = su.t0 + met[L.STEPS_DONE] * su.dt
        n = met[L.N_STEADY]
        mean = met[L.SUM_W] / n
        return Window(self.t_s, float(met[L.STEADY_MAX_W]), float(met[L.STEADY_MIN_W]),
                      math.sqrt(max(met[L.SUM_W2] / n - mean * mean, 0.0)),
                      bool(met[L.N_ZERO_STEPS] > zeros), int(met[L.N_IMP_ALL] - impacts),
                      float(met[L.MAX_ABS_AUX]), 0.5 * (self.modes[:, 0] - self.modes[:, 1]),
                      float(met[L.MAX_FORCE]))

    @property
    def state(self) -> State:
        """The state reached (x and time)."""
        return State(self.su.x.copy(), self.t_s)

    @property
    def system(self) -> System:
        return self.su.system

    @property
    def forcing(self) -> Regenerative:
        return self.su.forcing

    @property
    def x_start(self) -> np.ndarray:
        """The state the cut started from (a copy)."""
        return self.su.x_start.copy()

    def scale(self, factor: float) -> None:
        """Scale the run's departure from its steady cut by ``factor``: the modal state
        about the static deflection (u about u_s, u' about 0), an absorber's about the
        bar, a ball's relative position about where it started, and the delay history
        about the static tip deflection.  Where the run is linear (the tool in the cut, a
        frictionless ball off the walls) the scaled state is the same run further on: a
        mode growing at rate s is ln(factor) / s seconds ahead."""
        su, n = self.su, self.su.system.bar.n_modes
        ref = su.x_start.copy()
        ref[n:2 * n] = 0.0
        ref[2 * n + 1] = 0.0
        if su.system.kind == "tmd":
            ref[2 * n] = float(su.system.bar.psi_absorber @ ref[:n])
        su.x[:] = ref + factor * (su.x - ref)
        su.buf[:, 0] = su.w_static + factor * (su.buf[:, 0] - su.w_static)
        su.buf[:, 1] *= factor


def simulate_stage_loop(system: System, forcing: Harmonic, *, duration_s: float = 2.0,
                        dt_s: float = 1e-6, initial: Initial | State | None = None,
                        record_every: int | None = None, steady_fraction: float = STEADY_FRACTION,
                        strobe: bool = False) -> Run:
    """:func:`simulate` (rk4) with every step through the RK4 stage loop.

    The kernel normally takes a step with no friction switch as one affine
    map (`core/linmap.hpp`); this runs the four stages every
    step instead: the same scheme, equal to round-off.  It is the reference
    of the map in tests/test_kernel.py and the baseline of
    benchmarks/bench_kernel.py.
    """
    su = _setup(system, forcing, duration_s, dt_s, initial, record_every, steady_fraction, strobe,
                "rk4")
    su.p[L.STAGE_LOOP] = 1.0
    return _result(su, _run_kernel(su))


def simulate_batch(runs, *, duration_s: float = 2.0, dt_s: float = 1e-6,
                   steady_fraction: float = STEADY_FRACTION, strobe: bool = False) -> list[Run]:
    """Several harmonic runs of the published RK4 scheme, in one call of the core.

    ``runs``: up to :data:`~boringbar.kernels.BMAX` triples (system,
    forcing, initial), as :func:`simulate` takes them, whose systems share the
    bar kind and the number of retained modes, whose forcings are
    :class:`Harmonic` (each its own amplitude and frequency) and whose initial
    conditions start at the same time (``Initial`` or ``None``: t = 0; a
    ``State``: its t_s).  ``duration_s``, ``dt_s``, ``steady_fraction`` and
    ``strobe`` are the batch's, as in :func:`simulate`.

    The runs go through one call of :func:`boringbar.kernels.run_rk4_batch`, which
    advances each with the single-run kernel, the GIL released once for all: each
    returned :class:`Run` equals ``simulate(system, forcing, initial=initial, ...)`` of
    its triple, bit for bit, except ``elapsed_s``, the batch's wall time shared equally
    (tests/test_batch.py).
    """
    runs = list(runs)
    if not runs:
        return []
    if len(runs) > BMAX:
        raise ParameterError(f"simulate_batch takes at most {BMAX} runs, not {len(runs)}")
    sus = []
    for system, forcing, initial in runs:
        if not isinstance(forcing, Harmonic):
            raise ParameterError(f"forcing = {forcing!r}: simulate_batch takes harmonic forcing "
                                 "only (regenerative cuts: simulate)")
        sus.append(_setup(system, forcing, duration_s, dt_s, initial, 0, steady_fraction, strobe,
                          "rk4"))
    first = sus[0]
    for su in sus[1:]:
        if (su.system.kind, su.system.bar.n_modes) != (first.system.kind,
                                                       first.system.bar.n_modes):
            raise ParameterError(f"simulate_batch: a {su.system.kind} bar with "
                                 f"{su.system.bar.n_modes} modes cannot share a batch with a "
                                 f"{first.system.kind} bar with {first.system.bar.n_modes}")
        if su.t0 != first.t0:
            raise ParameterError(f"simulate_batch: initial states at t = {su.t0:g} s and "
                                 f"{first.t0:g} s cannot share a batch")
    nb = len(sus)
    P = np.array([su.p for su in sus])
    X = np.array([su.x for su in sus])
    met = np.array([su.met for su in sus])
    # each run writes at most its own capacity (the kernel writes a row only while
    # its count is below the array's), so the rows kept are simulate()'s
    imp = np.zeros((nb, max(len(su.imp) for su in sus), 3))
    stick = np.zeros((nb, max(len(su.stick) for su in sus), 2))
    stb = np.zeros((nb, max(len(su.stb) for su in sus), 5))
    tic = time.perf_counter()
    run_rk4_batch(P, X, first.t0, first.dt, first.n_steps, first.steady_steps, imp, stick, stb,
                  met)
    elapsed = time.perf_counter() - tic
    for r, su in enumerate(sus):
        su.x[:] = X[r]
        su.met[:] = met[r]
        su.imp[:] = imp[r, :len(su.imp)]
        su.stick[:] = stick[r, :len(su.stick)]
        su.stb[:] = stb[r, :len(su.stb)]
    return [_result(su, elapsed / len(sus)) for su in sus]
