"""The limits of one run, checked before it starts: the step against the fastest
period, the number of steps, the steady part against one forcing period, the history
and a cut's delay history against the memory they take.  Each error names the
parameter as its caller takes it (``duration_s``, ``--duration-s``, a file's key)."""

from __future__ import annotations

import math

from boringbar._validate import ParameterError, check_positive
from boringbar.model.dampers import TunedMassDamper
from boringbar.model.system import System

#: Smallest number of steps per period of the forcing and of the highest mode.
MIN_STEPS_PER_PERIOD = 20
#: Most time steps of one run, round(duration / dt) (the published run: 2e6).
MAX_STEPS = 10_000_000_000
#: Most history rows of one run, steps // record_every (6 floats a row: 480 MB), and
#: most rows of a cut's delay history, revolutions tau / dt (2 floats a row).
MAX_HISTORY_ROWS = 10_000_000


def shortest_period(system: System) -> float:
    """The shortest natural period (s) of ``system``: its highest retained mode's, or a
    tuned absorber's own where that is shorter."""
    periods = [2 * math.pi / w for w in system.bar.omegas_rad_s.tolist()]
    if isinstance(system.damper, TunedMassDamper):
        periods.append(2 * math.pi * math.sqrt(system.damper.mass_kg / system.damper.stiffness_n_m))
    return min(periods)


def check_step(system: System, omega: float, dt: float, name: str = "dt_s") -> None:
    """The step must resolve the forcing period and the highest retained mode
    (``name``: how the caller calls dt)."""
    check_positive(name, dt, "s")
    periods = [shortest_period(system)]
    if omega > 0:
        periods.append(2 * math.pi / omega)
    limit = min(periods) / MIN_STEPS_PER_PERIOD
    if dt > limit:
        raise ParameterError(f"{name} = {dt:g} s is too coarse: it must be in (0, {limit:.3g}] s "
                             f"({MIN_STEPS_PER_PERIOD} steps per period of the forcing and "
                             "of the highest retained mode)")


def check_steps(duration: float, dt: float, names: tuple[str, str] = ("duration_s", "dt_s")) -> int:
    """round(duration / dt), the run's number of steps: at least 1 and at most
    :data:`MAX_STEPS`, else ParameterError naming both (``names``: how the caller
    calls them, e.g. the CLI's options)."""
    d_name, dt_name = names
    check_positive(d_name, duration, "s")
    check_positive(dt_name, dt, "s")
    steps = duration / dt
    if steps > MAX_STEPS:
        raise ParameterError(f"{d_name} = {duration:g} s with {dt_name} = {dt:g} s is "
                             f"{steps:.3g} steps; the allowed maximum is {MAX_STEPS:.0e} steps "
                             "(shorten the run, or continue it from its final state)")
    n_steps = int(round(steps))
    if n_steps < 1:
        raise ParameterError(f"{d_name} = {duration:g} s is shorter than one step {dt_name} = "
                             f"{dt:g} s")
    return n_steps


def holds_a_period(span: float, period: float) -> bool:
    """A steady part ``span`` (s) long holds one forcing ``period`` (s), up to round-off:
    the one rule the checks before a run and a finished run's summary share."""
    return span >= period * (1.0 - 1e-9)


def check_steady(duration: float, steady_fraction: float, period: float,
                 name: str = "duration_s") -> None:
    """The steady part of a harmonic run, its last ``steady_fraction`` of ``duration``
    (s), must hold one forcing ``period`` (s) at least: a shorter one has no steady
    RMS or pattern to report. ``name``: the duration as the caller takes it.
    :func:`simulate` itself takes shorter runs (a state advanced by part of a period);
    the command line and the analyses' options check with this."""
    if not holds_a_period(steady_fraction * duration, period):
        raise ParameterError(f"{name} = {duration:g} s leaves a steady part of "
                             f"{steady_fraction * duration:.3g} s, shorter than one forcing "
                             f"period ({period:.3g} s): give {name} >= "
                             f"{period / steady_fraction:.3g} s")


def check_steady_ratios(system: System, ratios, duration: float, steady_fraction: float,
                        name: str = "duration_s") -> None:
    """:func:`check_steady` for the longest forcing period of ``ratios`` (Omega over the
    natural frequency of ``system``'s host): what an analysis checks before its runs."""
    period = 2 * math.pi / (min(ratios) * system.reference_frequency_rad_s)
    check_steady(duration, steady_fraction, period, name)


def check_history(n_steps: int, record_every: int, name: str = "record_every") -> int:
    """The number of history rows, n_steps // record_every: at most
    :data:`MAX_HISTORY_ROWS`, else ParameterError naming ``name``."""
    rows = n_steps // record_every
    if rows > MAX_HISTORY_ROWS:
        raise ParameterError(f"{name} = {record_every} keeps {rows} history rows of "
                             f"{n_steps} steps; the allowed maximum is {MAX_HISTORY_ROWS:.0e} "
                             f"rows ({name} >= {math.ceil(n_steps / MAX_HISTORY_ROWS)})")
    return rows


def check_delay(rpm: float, revolutions: int, dt: float, name: str = "rpm") -> int:
    """The rows of a cut's delay history, ceil(revolutions 60 / rpm / dt_s) + 3: the
    spindle period must hold 4 steps, and the rows be at most
    :data:`MAX_HISTORY_ROWS`, else ParameterError naming ``name`` (the speed)."""
    tau = 60.0 / check_positive(name, rpm, "rpm")
    if tau < 4 * dt:
        raise ParameterError(f"{name} = {rpm:g} rpm: dt = {dt:g} s must be under a quarter "
                             f"of the spindle period {tau:g} s")
    rows = revolutions * tau / dt + 3
    if rows > MAX_HISTORY_ROWS:
        raise ParameterError(f"{name} = {rpm:g} rpm: {revolutions} revolutions of {tau:g} s "
                             f"are {rows:.3g} steps of dt = {dt:g} s of delay history; the "
                             f"allowed maximum is {MAX_HISTORY_ROWS:.0e} (raise the speed "
                             "or dt)")
    return int(math.ceil(revolutions * tau / dt)) + 3
