"""One time-domain run of a bar: :func:`simulate` (harmonic forcing or a regenerative cut,
by the RK4 scheme or exactly) -> :class:`Run`; :func:`simulate_batch`; a cut advanced
window by window (:class:`CutStepper`); the impact-pattern classifier (:mod:`.patterns`)
and the checks of a run before it starts (:mod:`.run_limits`).

- :mod:`.run`: Run, State, Initial, Integration and the run's limits;
- :mod:`.engine`: packing for the compiled core, the integrator's choice, simulate;
- :mod:`.cut`: knocked_cut, Window, CutStepper.
"""

from boringbar.simulate.cut import CutStepper, Window, knocked_cut
from boringbar.simulate.engine import (
    RunSetup,
    batch_key,
    check_cut_law,
    check_friction_law,
    hertz,
    initial_state,
    pack,
    pack_cut,
    resolve_integrator,
    resolved_integrators,
    rolling,
    run_kernel,
    run_result,
    setup_run,
    simulate,
    simulate_batch,
    simulate_stage_loop,
    state_size,
    stick_slip,
    stored_energy,
)
from boringbar.simulate.run import (
    EXACT_STATUS_MESSAGES,
    HISTORY_ROWS,
    IMPACT_THRESHOLD,
    INTEGRATOR_CHOICES,
    INTEGRATORS,
    MAX_EVENT_ROWS,
    MAX_INITIAL_DISPLACEMENT,
    MAX_INITIAL_VELOCITY,
    PUBLISHED_DT_S,
    STEADY_FRACTION,
    STICK_LAWS,
    STICK_MIN_PERIODS,
    Initial,
    Integration,
    IntegrationError,
    Run,
    State,
    fixed_run_step,
)

__all__ = [
    "EXACT_STATUS_MESSAGES", "HISTORY_ROWS", "IMPACT_THRESHOLD", "INTEGRATORS",
    "INTEGRATOR_CHOICES", "MAX_EVENT_ROWS", "MAX_INITIAL_DISPLACEMENT", "MAX_INITIAL_VELOCITY",
    "PUBLISHED_DT_S", "fixed_run_step",
    "STEADY_FRACTION", "STICK_LAWS", "STICK_MIN_PERIODS", "CutStepper", "Initial", "Integration",
    "IntegrationError", "Run", "RunSetup", "State", "Window", "check_cut_law",
    "batch_key", "check_friction_law", "hertz", "initial_state", "rolling", "state_size",
    "knocked_cut",
    "pack", "pack_cut",
    "resolve_integrator", "resolved_integrators", "run_kernel", "run_result", "setup_run",
    "simulate", "simulate_batch", "simulate_stage_loop", "stick_slip", "stored_energy",
]
