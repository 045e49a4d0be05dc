"""``simulate``: one time-domain run of a bar under harmonic or cutting forces.

The description objects (System, Harmonic, Regenerative) are packed into the kernel's
parameter vector here (layout in :mod:`boringbar.simulate.layout`); the kernel streams
its metrics; this module turns them into a labelled :class:`~boringbar.simulate.run.Run`.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass

import numpy as np

from boringbar._validate import (
    ParameterError,
    check_choice,
    check_int,
    check_range,
)
from boringbar.model.contact import hertz_contact_time_s
from boringbar.model.dampers import GRAVITY, ImpactDamper, TunedMassDamper, spin_gain
from boringbar.model.forcing import Harmonic, Regenerative
from boringbar.model.system import System
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import (
    BMAX,
    Records,
    Steps,
    carried_kappa,
    hunt_crossley_alpha,
    impact_mass,
    run_exact,
    run_rk4,
    run_rk4_batch,
)
from boringbar.simulate.run import (
    AT_REST,
    HISTORY_ROWS,
    IMPACT_THRESHOLD,
    INTEGRATOR_CHOICES,
    MAX_EVENT_ROWS,
    STEADY_FRACTION,
    STICK_LAWS,
    STICK_MIN_PERIODS,
    Initial,
    IntegrationError,
    Run,
    State,
)
from boringbar.simulate.run_limits import (
    MAX_STEPS,
    check_delay,
    check_history,
    check_step,
    check_steps,
)


def pack(system: System, omega: float, amplitude: float, dt: float,
         stick_law: str = "sgn") -> np.ndarray:
    """The kernel's parameter vector for ``system`` under F0 sin(omega t), RK4's
    friction rendered by ``stick_law`` (:data:`STICK_LAWS`).

    ``omega`` = 0 (no harmonic force) refers the impact threshold to omega_n.
    """
    p = system_params(system).copy()
    p[L.FORCING] = L.HARMONIC
    p[L.F0] = amplitude
    p[L.OMEGA] = omega
    d = system.damper
    if isinstance(d, ImpactDamper):
        meff = p[L.M_EFF]
        ref = omega if omega > 0 else system.bar.natural_frequency_rad_s
        p[L.V_IMPACT] = IMPACT_THRESHOLD * ref * d.gap_m / 2
        # the sgn() law chatters about y' = 0 with steps of up to F_c dt / m_eff
        p[L.V_STICK] = p[L.V_IMPACT] + 2.0 * p[L.FRICTION] * dt / meff
        p[L.STICK_MIN] = STICK_MIN_PERIODS * 2 * math.pi / ref
        if rolling(system):
            p[L.ROLL_BAND] = roll_band(p, d, dt)
        elif stick_law == "hold" and p[L.FRICTION] > 0:
            p[L.STICK_BAND] = hold_band(p, dt)
    return p


#: Each system's slots of the parameter vector (:func:`system_params`), kept while the
#: system lives: a sweep packs one system for run after run.
_SYSTEM_PARAMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def system_params(system: System) -> np.ndarray:
    """The slots of the kernel's parameter vector that ``system`` alone sets (the bar's
    modes, the damper's, the case), the others zero; read-only, kept per system (a
    ``System`` is frozen: its fields and arrays cannot change)."""
    p = _SYSTEM_PARAMS.get(system)
    if p is None:
        p = _pack_system(system)
        p.flags.writeable = False
        _SYSTEM_PARAMS[system] = p
    return p


def _pack_system(system: System) -> np.ndarray:
    """:func:`system_params`, computed."""
    bar = system.bar
    n = bar.n_modes
    if n > L.NMAX:
        raise ParameterError(f"n_modes = {n} is outside the allowed range [1, {L.NMAX}]")
    p = L.empty_params()
    p[L.N_MODES] = n
    p[L.M_:L.M_ + n] = bar.mass_kg
    p[L.K_:L.K_ + n] = bar.stiffness_n_m
    p[L.C_:L.C_ + n] = bar.damping_n_s_m
    p[L.PSI_L:L.PSI_L + n] = bar.psi_tip
    p[L.PSI_D:L.PSI_D + n] = bar.psi_damper
    p[L.PSI_A:L.PSI_A + n] = bar.psi_absorber
    p[L.PSI_F:L.PSI_F + n] = bar.psi_force
    p[L.REACTION] = 1.0
    d = system.damper
    p[L.CASE] = L.CASE_OF_KIND[system.kind]
    if isinstance(d, ImpactDamper):
        p[L.BALL_MASS] = d.mass_kg
        p[L.HALF_GAP] = d.gap_m / 2
        p[L.RESTITUTION] = d.restitution
        p[L.FRICTION] = d.friction_force_n
        p[L.STATIC_FRICTION] = d.static_friction_force_n
        p[L.REACTION] = 1.0 if d.friction.reaction == "reciprocal" else -1.0
        p[L.M_EFF] = impact_mass(p)  # the core's carrying term, inverted
        if rolling(system):
            p[L.ROLL] = 1.0
            p[L.ROLL_STATIC], p[L.ROLL_KINETIC] = roll_forces(d)
        if hertz(system):
            p[L.CONTACT_K] = d.hertz_stiffness_n_m1_5
            p[L.CONTACT_ALPHA] = hunt_crossley_alpha(float(d.restitution))
    elif isinstance(d, TunedMassDamper):
        p[L.TMD_MASS] = d.mass_kg
        p[L.TMD_K] = d.stiffness_n_m
        p[L.TMD_C] = d.damping_n_s_m
    return p


def roll_forces(d: ImpactDamper) -> tuple[float, float]:
    """A rolling ball's friction forces mu_s m g and mu_k m g (N)."""
    return d.mu_static * d.mass_kg * GRAVITY, d.mu_kinetic * d.mass_kg * GRAVITY


def roll_band(p: np.ndarray, d: ImpactDamper, dt: float) -> float:
    """The band of slip y' - s inside which a rolling ball may roll: twice what its
    friction can change the slip by in one step, 2 (F_s + F_k) dt (1 / m_eff + 5 / (2 m)),
    so that a slip coming to rest ends a step inside it (as :func:`hold_band`)."""
    fs, fk = roll_forces(d)
    return 2.0 * (fs + fk) * dt * (1.0 / p[L.M_EFF] + spin_gain(d.mass_kg))


def system_impact_mass(system: System) -> float:
    """m_eff (kg) of the system's ball against the retained modes at the cavity, as the
    kernels take it (:func:`system_params`)."""
    return float(system_params(system)[L.M_EFF])


def hold_band(p: np.ndarray, dt: float) -> float:
    """The stick law's band of y' (m/s): twice what friction and the bar's drag can
    change y' by in one step while the ball can be held, (F_c + F_s) dt / m_eff, so that a
    slide coming to rest ends a step inside it."""
    if p[L.REACTION] < 0:
        if carried_kappa(p, p[L.REACTION]) <= 0:
            raise ParameterError("stick_law = 'hold' with the printed friction reaction needs "
                                 "a ball lighter than its share of the bar's modal mass; use "
                                 "stick_law = 'sgn'")
    return 2.0 * (p[L.FRICTION] + p[L.STATIC_FRICTION]) * dt / p[L.M_EFF]


def pack_cut(system: System, forcing: Regenerative, dt: float, w_static: float,
             stick_law: str = "sgn") -> np.ndarray:
    """The kernel's parameter vector for ``system`` in the cut ``forcing``: its law, noise
    and delay; ``w_static`` (m) the surface before the cut of a static start."""
    p = pack(system, 0.0, 0.0, dt, stick_law)
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


def state_size(system: System) -> int:
    """The kernel's state length: 2 n + 2, and a rolling ball's spin after it."""
    return 2 * system.bar.n_modes + 2 + (1 if rolling(system) else 0)


def initial_state(system: System, initial: Initial) -> np.ndarray:
    """x = [u, u', aux, aux'] from tip and ball initial conditions (a rolling ball's spin
    r omega after them, its y': it starts rolling)."""
    bar = system.bar
    n = bar.n_modes
    x = np.zeros(state_size(system))
    x[0] = initial.tip_displacement_m / bar.psi_tip[0]
    x[n] = initial.tip_velocity_m_s / bar.psi_tip[0]
    d = system.damper
    if isinstance(d, ImpactDamper):
        check_range("initial ball_position_m", initial.ball_position_m, -d.gap_m / 2, d.gap_m / 2,
                    unit="m")
        x[2 * n] = initial.ball_position_m
        x[2 * n + 1] = 0.0 if d.locked else initial.ball_velocity_m_s
        if rolling(system):
            x[2 * n + 2] = x[2 * n + 1]
    elif isinstance(d, TunedMassDamper):
        x[2 * n] = float(bar.psi_absorber @ x[:n])
        x[2 * n + 1] = float(bar.psi_absorber @ x[n:2 * n])
    return x


def stored_energy(system: System, x: np.ndarray) -> float:
    """Kinetic + potential energy of state x (J).

    In Python floats (a state holds a few entries: NumPy's per-call cost was most of a
    warm run's result), summed in NumPy's order for such short vectors (left to right
    from 0), so the figures keep their bits."""
    bar = system.bar
    n = bar.n_modes
    xs = x.tolist()
    u, v = xs[:n], xs[n:2 * n]
    kinetic = strain = 0.0
    for m, k, ui, vi in zip(bar.mass_kg.tolist(), bar.stiffness_n_m.tolist(), u, v,
                            strict=True):
        kinetic += m * (vi * vi)
        strain += k * (ui * ui)
    e = 0.5 * (kinetic + strain)
    d = system.damper
    if isinstance(d, ImpactDamper):
        ud = xs[2 * n + 1] + _dot(bar.psi_damper.tolist(), v)
        e += 0.5 * d.mass_kg * ud**2
        depth = abs(xs[2 * n]) - d.gap_m / 2
        if hertz(system) and depth > 0:  # the contact's elastic energy, 2/5 K d^2.5
            e += 0.4 * d.hertz_stiffness_n_m1_5 * depth**2.5
        if rolling(system):  # the spin's, I omega^2 / 2 = m s^2 / 5
            e += 0.2 * d.mass_kg * xs[2 * n + 2] ** 2
    elif isinstance(d, TunedMassDamper):
        rel = xs[2 * n] - _dot(bar.psi_absorber.tolist(), u)
        e += 0.5 * d.mass_kg * xs[2 * n + 1] ** 2 + 0.5 * d.stiffness_n_m * rel**2
    return e


def _dot(a: list, b: list) -> float:
    """sum a_i b_i, left to right from 0."""
    s = 0.0
    for ai, bi in zip(a, b, strict=True):
        s += ai * bi
    return s


def stick_slip(system: System) -> bool:
    """Whether the ball's friction has a static limit above the sliding one (exact only)."""
    d = system.damper
    return isinstance(d, ImpactDamper) and d.friction.static_ratio != 1 and d.friction_force_n > 0


def batch_key(system: System) -> tuple:
    """What the runs of one :func:`simulate_batch` share: the bar's kind, its mode count
    and whether its ball rolls (so that their states have one length)."""
    return system.kind, system.bar.n_modes, rolling(system)


def _batch_words(system: System) -> str:
    """'ball bar with 2 modes (a rolling ball)': the batch key in words."""
    return (f"{system.kind} bar with {system.bar.n_modes} modes"
            + (" (a rolling ball)" if rolling(system) else ""))


def rolling(system: System) -> bool:
    """Whether the ball of ``system`` rolls (its spin a state; docs/model.md, 2.7)."""
    d = system.damper
    return isinstance(d, ImpactDamper) and d.motion == "roll" and not d.locked


def hertz(system: System) -> bool:
    """Whether the ball of ``system`` meets its walls by a compliant (Hertz) contact."""
    d = system.damper
    return isinstance(d, ImpactDamper) and d.contact == "hertz" and not d.locked


def resolve_integrator(integrator: str, system: System, cutting: bool = False) -> str:
    """``integrator``, or for "auto": "rk4" under the ``paper`` preset (the published
    scheme), in cuts (``cutting``: RK4 is faster there, docs/exact.md) unless
    :func:`stick_slip`, and with a Hertz contact (:func:`hertz`), RK4's alone, else
    "exact" (exact at events, about 14x faster than RK4; a rolling ball's about 10x)."""
    check_choice("integrator", integrator, INTEGRATOR_CHOICES)
    if integrator == "exact" and hertz(system):
        raise ParameterError("integrator = 'exact' takes the impact law; a ball with contact "
                             "= 'hertz' needs integrator = 'rk4' (or 'auto')")
    if integrator != "auto":
        return integrator
    if hertz(system):
        return "rk4"
    return "rk4" if (system.preset == "paper" or cutting) and not stick_slip(system) \
        else "exact"


#: The least number of RK4 steps a Hertz contact at 1 m/s may last (check_contact_step).
CONTACT_STEPS = 10


def check_contact_step(system: System, dt: float) -> None:
    """A Hertz contact must last :data:`CONTACT_STEPS` steps of ``dt`` (s) at least at
    1 m/s (faster than any impact of these bars; the duration goes as v^-1/5): RK4
    resolves it then, and stays stable on the contact's stiffness."""
    if not hertz(system):
        return
    tc = hertz_contact_time_s(system_impact_mass(system),
                              system.damper.hertz_stiffness_n_m1_5, 1.0)
    if dt > tc / CONTACT_STEPS:
        raise ParameterError(f"dt_s = {dt:g} s is too long for the Hertz contact: an impact "
                             f"at 1 m/s lasts {tc:.3g} s, and RK4 needs {CONTACT_STEPS} steps "
                             f"of it (dt_s <= {tc / CONTACT_STEPS:.3g} s)")


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


def check_friction_law(system: System, integrator: str, stick_law: str = "sgn") -> None:
    """True stick-slip needs the exact integrator or RK4's stick law: the published sgn()
    law has no static limit.  RK4's stick law is a sliding ball's: a rolling one's rolling
    resistance takes the sgn() law."""
    check_choice("stick_law", stick_law, STICK_LAWS)
    if integrator == "rk4" and stick_law == "hold" and rolling(system):
        raise ParameterError("stick_law = 'hold' with a rolling ball (motion = 'roll'): RK4 "
                             "renders its rolling resistance by the sgn() law only; use "
                             "stick_law = 'sgn', or integrator = 'exact' (harmonic forcing), "
                             "which holds the ball exactly")
    if integrator == "rk4" and stick_law == "sgn" and stick_slip(system):
        raise ParameterError(f"friction static_ratio = {system.damper.friction.static_ratio!r}: "
                             "the rk4 integrator's sgn() law has no static limit "
                             "(static_ratio = 1); use stick_law = 'hold' or integrator = "
                             "'exact' for true stick-slip")


@dataclass(eq=False)
class RunSetup:
    """One run, checked and packed for a kernel, and the arrays it fills (the record
    arrays imp, stick, stb and rec hold rows only as far as met counts them)."""

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
    stick_law: str = "sgn"
    contact: np.ndarray | None = None  # a Hertz contact's rows (None: the impact law)


def setup_run(system, forcing, duration, dt, initial, record_every, steady_fraction, strobe,
           integrator, stick_law: str = "sgn") -> RunSetup:
    """Check the arguments of :func:`simulate` and pack the run."""
    check_choice("integrator", integrator, INTEGRATOR_CHOICES)
    if not isinstance(system, System):
        raise ParameterError(f"system = {system!r} must be a System (see make_system)")
    if not isinstance(forcing, Harmonic | Regenerative):
        raise ParameterError(f"forcing = {forcing!r} must be a Harmonic or a Regenerative")
    integrator = resolve_integrator(integrator, system, isinstance(forcing, Regenerative))
    cutting = isinstance(forcing, Regenerative)
    check_friction_law(system, integrator, stick_law)
    check_cut_law(forcing, integrator)
    check_range("steady_fraction", steady_fraction, 0.0, 1.0, lo_open=True)
    n_steps = check_steps(duration, dt)
    record_every = (max(1, n_steps // HISTORY_ROWS) if record_every is None
                    else check_int("record_every", record_every, 0, MAX_STEPS))
    omega = (2 * math.pi / forcing.tau_s if cutting
             else forcing.omega(system.reference_frequency_rad_s))
    check_step(system, omega, dt)
    check_contact_step(system, dt)
    if cutting:
        check_delay(forcing.rpm, forcing.revolutions, dt)
    if record_every:
        check_history(n_steps, record_every)

    if isinstance(initial, State):
        x = np.array(initial.x, dtype=float)
        if x.shape != (state_size(system),):
            raise ParameterError(f"initial state has {x.size} entries; this system needs "
                                 f"{state_size(system)}")
        t0 = float(initial.t_s)
    else:
        x = initial_state(system, initial or AT_REST)
        t0 = 0.0
    w_static = 0.0
    if cutting:
        # static deflection under the mean force, mode by mode (absorber relaxed)
        bar = system.bar
        u_static = bar.psi_force * forcing.mean_force_n / bar.stiffness_n_m
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
        p = pack_cut(system, forcing, dt, w_static, stick_law)
        buf = np.zeros((check_delay(forcing.rpm, forcing.revolutions, dt), 2))
        period = 2 * math.pi / system.reference_frequency_rad_s
    else:
        p = pack(system, omega, forcing.amplitude_n, dt, stick_law)
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
    # not zeroed (zeroing the 2 s run's 1.5 MB cost more than the rest of the setup): a
    # kernel writes a row before it counts it in met, and only counted rows are read
    imp = np.empty((cap_imp, 3))
    stick = np.empty((cap_imp, 2))
    stb = np.empty((int(n_periods) + 2 if strobe else 0, 5))
    n_rec = n_steps // record_every if record_every else 0
    rec = np.empty((n_rec, 7 if rolling(system) else 6))  # a rolling ball's spin last
    met = np.zeros(L.MET_SIZE)
    met[L.STEADY_MAX_W] = -np.inf
    met[L.STEADY_MIN_W] = np.inf
    met[L.FIRST_ZERO_T] = -1.0

    contact = np.empty((cap_imp, L.CONTACT_NCOL)) if hertz(system) else None
    return RunSetup(system, forcing, integrator, omega, dt, t0, n_steps, steady_steps,
                  int(record_every), cutting, period, w_static, p, x, x_start, buf, imp, stick,
                  stb, rec, met, stick_law, contact)


def run_kernel(su: RunSetup) -> float:
    """Run the kernel of ``su`` in place; the wall time (s)."""
    met = su.met
    steps = Steps(su.t0, su.dt, su.n_steps, su.steady_steps, int(su.record_every))
    out = Records(su.rec, su.imp, su.stick, su.stb, met, contact=su.contact)
    tic = time.perf_counter()
    if su.integrator == "exact":
        t_reached = run_exact(su.p, su.x, steps, out)
        # a cut stopped at its first zero finishes that step of dt
        met[L.STEPS_DONE] = min(su.n_steps, int(round((t_reached - su.t0) / su.dt)))
        if met[L.EXACT_STATUS] != 0:
            raise IntegrationError(int(met[L.EXACT_STATUS]), int(met[L.N_EVENTS]), t_reached)
    else:
        run_rk4(su.p, su.x, steps, out, su.buf)
    return time.perf_counter() - tic


def run_metrics(m: list, n_imp: int, cap_imp: int, w_static: float) -> dict:
    """The streamed metrics by name, from ``m``, the metric vector as a list of floats
    (one conversion instead of one per slot)."""
    n_st = m[L.N_STEADY]
    nan = math.nan
    # a cut stopped at its first zero may end before the steady part begins:
    # its steady statistics are then undefined (NaN), not zero.  The exact integrator's
    # int W^2 dt is a closed form whose terms cancel; over a run of a step or two from
    # rest it is round-off, and may come out below zero (-5e-35 m^2 s over 1 us): an RMS
    # of 0 there, not a domain error
    return {
        "rms_tip_m": math.sqrt(max(m[L.SUM_W2], 0.0) / n_st) if n_st else nan,
        "mean_tip_m": m[L.SUM_W] / n_st if n_st else nan,
        "max_abs_tip_m": m[L.MAX_ABS_W] if n_st else nan,
        "max_abs_aux_m": m[L.MAX_ABS_AUX] if n_st else nan,
        "max_abs_aux_all_m": m[L.MAX_ABS_AUX_ALL],
        "rms_aux_m": math.sqrt(max(m[L.SUM_AUX2], 0.0) / n_st) if n_st else nan,
        "impacts_plus": int(m[L.N_IMP_PLUS]),
        "impacts_minus": int(m[L.N_IMP_MINUS]),
        "impacts_total": int(m[L.N_IMP_ALL]),
        "micro_impacts": int(m[L.N_MICRO]),
        "contact_time_s": m[L.T_CONTACT],
        "stick_time_s": m[L.T_STICK],
        "impacts_truncated": n_imp > cap_imp,
        "first_zero_time_s": m[L.FIRST_ZERO_T] if m[L.FIRST_ZERO_T] >= 0 else None,
        "steps_with_zero_force": int(m[L.N_ZERO_STEPS]),
        "max_force_n": m[L.MAX_FORCE],
        "mean_force_n": m[L.SUM_F] / n_st if n_st else nan,
        "amplitude_m": max(0.0, (m[L.STEADY_MAX_W] - m[L.STEADY_MIN_W]) / 2) if n_st else nan,
        "static_deflection_m": w_static,
        "events": int(m[L.N_EVENTS]),
        "max_contact_force_n": m[L.MAX_CONTACT_FORCE],
    }


def run_energy(m: list, e0: float, e1: float) -> dict:
    """The energy flows of ``m`` (the metric vector as a list) and their balance between
    the stored energies ``e0`` at the start and ``e1`` at the end (J)."""
    w_in = m[L.W_FORCE] + m[L.W_NONRECIP]
    dissipated = m[L.D_VISC] + m[L.D_IMPACT] + m[L.D_FRICTION]
    scale = max(abs(w_in), dissipated, abs(e1 - e0), e0, e1, 1e-300)
    return {
        "work_force_j": m[L.W_FORCE],
        "work_nonreciprocal_friction_j": m[L.W_NONRECIP],
        "dissipated_viscous_j": m[L.D_VISC],
        "dissipated_impacts_j": m[L.D_IMPACT],
        "dissipated_friction_j": m[L.D_FRICTION],
        "stored_initial_j": e0,
        "stored_final_j": e1,
        "balance_residual_j": float(w_in - (e1 - e0) - dissipated),
        "balance_relative": float((w_in - (e1 - e0) - dissipated) / scale),
    }


def _contacts(su: RunSetup, m: list) -> np.ndarray | None:
    """The contact rows of a run: none under the impact law; None where a Hertz run kept
    none (a batch's)."""
    if su.contact is None:
        return None if hertz(su.system) else np.zeros((0, L.CONTACT_NCOL))
    return su.contact[:min(int(m[L.N_CONTACT_REC]), len(su.contact))].copy()


def _history(rec: np.ndarray, n_rows: int) -> np.ndarray:
    """The run's ``n_rows`` history rows: ``rec`` itself when it is full (each run has its
    own; a copy's 960 kB of fresh pages cost a warm 2 s exact call about 0.7 ms here)."""
    return rec if n_rows == len(rec) else rec[:n_rows].copy()


def run_result(su: RunSetup, elapsed: float) -> Run:
    """The labelled :class:`Run` from a finished kernel run."""
    system, dt, t0, x, imp, stick, m = su.system, su.dt, su.t0, su.x, su.imp, su.stick, \
        su.met.tolist()
    cap_imp = imp.shape[0]
    n_steps = int(m[L.STEPS_DONE])  # fewer if a cut stopped at its first h = 0
    n_imp = min(int(m[L.N_IMP_REC]), cap_imp)
    n_stk = min(int(m[L.N_STICK_REC]), cap_imp)
    t_end = t0 + n_steps * dt
    t_steady = t0 + su.steady_steps * dt
    p = su.p
    thresholds = {
        "impact_velocity_m_s": float(p[L.V_IMPACT]),
        "stick_velocity_m_s": float(p[L.V_STICK]),
        "stick_min_duration_s": float(p[L.STICK_MIN]),
        "stick_band_m_s": float(p[L.STICK_BAND]),
    }
    return Run(
        system=system, forcing=su.forcing, omega_rad_s=su.omega, dt_s=dt, t0_s=t0,
        duration_s=n_steps * dt, steady_start_s=t_steady,
        metrics=run_metrics(m, int(m[L.N_IMP_REC]), cap_imp, su.w_static),
        impacts=imp[:n_imp].copy(), sticks=stick[:n_stk].copy(),
        strobe=su.stb[:int(m[L.N_STROBE])].copy(),
        history=_history(su.rec, int(m[L.N_REC])) if su.record_every else None,
        initial=State(su.x_start, t0), final=State(x.copy(), t_end),
        elapsed_s=elapsed,
        energy=run_energy(m, stored_energy(system, su.x_start), stored_energy(system, x)),
        thresholds=thresholds, integrator=su.integrator, stick_law=su.stick_law,
        contacts=_contacts(su, m),
    )


def simulate(system: System, forcing: Harmonic | Regenerative, *, duration_s: float = 2.0,
             dt_s: float = 1e-6,
             initial: Initial | State | None = None, record_every: int | None = None,
             steady_fraction: float = STEADY_FRACTION, strobe: bool = False,
             integrator: str = "auto", stick_law: str = "sgn") -> Run:
    """Integrate ``system`` under ``forcing`` with the published RK4 scheme or exactly.

    ``duration_s`` (s) and ``dt_s`` (s) as published by default (2 s, 1e-6 s); the run
    takes the whole number of steps nearest duration_s / dt_s (its config records the
    duration run: to continue whole forcing periods, give a dt_s that divides them);
    RMS and patterns use the last ``steady_fraction`` of the record.
    ``initial``: :class:`Initial`, or a previous run's ``final`` :class:`State`
    to continue it (time, hence forcing phase, runs on).  ``record_every`` N
    keeps every N-th step's state (None, the default: about :data:`HISTORY_ROWS`
    rows, enough to plot; 0: no history, as the analyses run); ``strobe`` keeps
    Poincare samples at Omega t = 0 mod 2 pi.

    Limits (a ParameterError names the parameter, its value and the maximum): every
    number finite (:mod:`boringbar.simulate.run_limits`); at most 1e10 steps duration_s / dt_s;
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
    ``Friction(static_ratio > 1)``) needs ``"exact"`` or RK4's stick law; a cut with
    Kienzle's law or with force noise needs ``"rk4"`` (the exact integrator's cut is
    linear in the state).

    ``stick_law``: how RK4 renders the ball's friction (:data:`STICK_LAWS`): ``"sgn"``,
    the published F_b = -F_c sgn(y'), whose chatter about y' = 0 holds the ball to first
    order in the step, or ``"hold"``, the stick law, which holds it exactly (the exact
    integrator always does).
    """
    su = setup_run(system, forcing, duration_s, dt_s, initial, record_every, steady_fraction,
                   strobe, integrator, stick_law)
    return run_result(su, run_kernel(su))


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
    su = setup_run(system, forcing, duration_s, dt_s, initial, record_every, steady_fraction,
                   strobe, "rk4")
    su.p[L.STAGE_LOOP] = 1.0
    return run_result(su, run_kernel(su))


def simulate_batch(runs, *, duration_s: float = 2.0, dt_s: float = 1e-6,
                   steady_fraction: float = STEADY_FRACTION, strobe: bool = False,
                   stick_law: str = "sgn") -> list[Run]:
    """Several harmonic runs of the published RK4 scheme, in one call of the core.

    ``runs``: up to :data:`~boringbar.simulate.kernels.BMAX` triples (system,
    forcing, initial), as :func:`simulate` takes them, whose systems share the
    bar kind, the number of retained modes and the ball's motion (:func:`batch_key`),
    whose forcings are
    :class:`Harmonic` (each its own amplitude and frequency) and whose initial
    conditions start at the same time (``Initial`` or ``None``: t = 0; a
    ``State``: its t_s).  ``duration_s``, ``dt_s``, ``steady_fraction`` and
    ``strobe`` and ``stick_law`` are the batch's, as in :func:`simulate`.

    The runs go through one call of :func:`boringbar.simulate.kernels.run_rk4_batch`, which
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
        sus.append(setup_run(system, forcing, duration_s, dt_s, initial, 0, steady_fraction, strobe,
                             "rk4", stick_law))
    first = sus[0]
    for su in sus[1:]:
        if batch_key(su.system) != batch_key(first.system):
            raise ParameterError(f"simulate_batch: a {_batch_words(su.system)} cannot "
                                 f"share a batch with a {_batch_words(first.system)}")
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
    run_rk4_batch(P, X, Steps(first.t0, first.dt, first.n_steps, first.steady_steps),
                  Records(np.zeros((0, 6)), imp, stick, stb, met))
    elapsed = time.perf_counter() - tic
    for r, su in enumerate(sus):
        su.x[:] = X[r]
        su.met[:] = met[r]
        su.imp[:] = imp[r, :len(su.imp)]
        su.stick[:] = stick[r, :len(su.stick)]
        su.stb[:] = stb[r, :len(su.stb)]
        su.contact = None  # a batch keeps no contact rows
    return [run_result(su, elapsed / len(sus)) for su in sus]
