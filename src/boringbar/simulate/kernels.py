"""The integrators: thin Python entry points over the compiled core (``boringbar.core``).

The core (C++, ``core/``) holds the integrators: the published RK4 scheme, one run and a
lock-step batch, and the exact event-driven integrator, harmonic and regenerative.  This
package packs what the core cannot compute itself and calls it:

- :mod:`.layout`: the packed parameter vector's and the metric vector's slots, read from
  the core;
- :mod:`.regimes`: the exact integrator's per-run setup (the core's regime matrices,
  diagonalised with LAPACK through NumPy, kept per system; the forcing's part from the
  core) and a cut's tables;
- :func:`run_rk4`, :func:`run_rk4_batch`, :func:`run_exact`: the three entry points, each
  given a run's span (:class:`Steps`) and the arrays it writes (:class:`Records`), with
  the array contract of ``boringbar.simulate`` (their only caller in the package);
- :func:`regime_matrix`, :func:`impact_matrix_of`: the equations of motion as matrices,
  built from the definitions the integrators step with (for shooting, in
  :mod:`boringbar.orbits`);
- :func:`carried_kappa`, :func:`impact_mass`: the ball's carrying term and the impact's
  effective mass, from the core;
- :func:`hunt_crossley_alpha`: a Hertz contact's damping for a restitution;
- :func:`cut_history_map`: a periodic cut orbit's linearised map on its delay history
  (its Floquet multipliers, in :mod:`boringbar.orbits.cut_orbits`).

Each entry point of the core takes one run description (``core.RK4Run``, ``core.RK4Batch``,
``core.ExactRun``), whose fields the functions here set.  Each array field declares its
dtype (float64; complex128 for a cut's tables) and refuses, when it is set, an array of
another dtype or a read-only output: arrays are never converted, so the run writes into the
caller's own.  When the run starts the core checks every array's shape and contiguity and
every scalar's range; it raises ``ValueError`` naming what it refuses, and releases the GIL
for the whole integration, so threads run in parallel.
"""

import dataclasses
import functools

import numpy as np

from boringbar import core
from boringbar.model.contact import check_hertz_restitution
from boringbar.simulate import layout as L
from boringbar.simulate.regimes import cut_tables, history_step, prepare

#: most runs in one call of run_rk4_batch
BMAX: int = core.BMAX

_NO_HISTORY = np.zeros((0, 2))


@dataclasses.dataclass(slots=True)
class Steps:
    """A run's span in steps of ``dt`` from ``t0``: ``n_steps`` steps, the steady part from
    step ``steady_start`` on, the history every ``record_every`` steps (0: none).  The exact
    integrator takes the same span as times: it ends at t0 + n_steps dt, its steady part
    starts at t0 + steady_start dt, it records every record_every dt."""

    t0: float
    dt: float
    n_steps: int
    steady_start: int
    record_every: int = 0


@dataclasses.dataclass(slots=True)
class Records:
    """What a run writes in place: ``rec`` (t, W, W', aux, aux', f every record_every steps;
    a rolling ball's spin after them), ``imp`` (t, wall, y'- of counted impacts in the
    steady part), ``stick`` (start, end of stick intervals in the steady part), ``strobe``
    (Poincare samples t, W, W', aux, aux' at t = STROBE_T0 + j STROBE_PERIOD), ``met``
    (metrics, see :mod:`.layout`; zeros, with STEADY_MAX_W = -inf and STEADY_MIN_W = +inf,
    for a fresh run); RK4's optional ``modes`` (a cut's (n_modes, 2): each mode's max and
    min of u_i over the steady steps, updated in place) and ``contact`` (a Hertz contact's
    rows: start, wall, v_in, duration, peak force, v_out of each counted contact that
    began in the steady part).  A batch's arrays have one leading row per run."""

    rec: np.ndarray
    imp: np.ndarray
    stick: np.ndarray
    strobe: np.ndarray
    met: np.ndarray
    modes: np.ndarray | None = None
    contact: np.ndarray | None = None


def _write_records(run, out: Records) -> None:
    """A single run's records (``core.RK4Run``'s and ``core.ExactRun``'s alike) from
    ``out``."""
    run.rec, run.imp, run.stick, run.strobe, run.met = (out.rec, out.imp, out.stick,
                                                        out.strobe, out.met)


def run_rk4(p, x, steps: Steps, out: Records, buf=None) -> None:
    """Advance ``x`` (in place) by ``steps`` of the published RK4 scheme, writing ``out``.
    ``buf``: a regenerative cut's circular history of W, W' at step ends, at least
    N_REV TAU / dt + 3 rows."""
    run = core.RK4Run()
    run.p, run.x, run.t0, run.dt = p, x, steps.t0, steps.dt
    run.n_steps, run.steady_start, run.rec_every = (steps.n_steps, steps.steady_start,
                                                    steps.record_every)
    _write_records(run, out)
    run.buf = _NO_HISTORY if buf is None else buf
    run.modes = out.modes
    run.contact = out.contact
    core.run_rk4(run)


def run_rk4_batch(P, X, steps: Steps, out: Records) -> None:
    """Advance the rows of ``X`` by ``steps`` of RK4 (no history): every row of ``P`` a
    harmonic run of the same mode count and case, at most :data:`BMAX` rows, each advanced
    as :func:`run_rk4` would (the same bits); ``out``'s arrays with one leading row per
    run."""
    if steps.record_every or out.modes is not None or out.contact is not None:
        raise ValueError("run_rk4_batch keeps no history, no modes' extremes and no contact "
                         "rows (run_rk4's)")
    run = core.RK4Batch()
    run.P, run.x, run.t0, run.dt = P, X, steps.t0, steps.dt
    run.n_steps, run.steady_start = steps.n_steps, steps.steady_start
    run.imp, run.stick, run.strobe, run.met = out.imp, out.stick, out.strobe, out.met
    core.run_rk4_batch(run)


def run_exact(p, x, steps: Steps, out: Records, prep=None) -> float:
    """Advance ``x`` exactly over the span of ``steps``, writing ``out`` as :func:`run_rk4`
    does, but the steady sums are integrals (docs/exact.md).  ``prep``:
    :func:`.regimes.prepare`'s ``core.ExactSetup``, computed here if not given.  A
    regenerative cut's history step is H = tau / ceil(tau / dt); a cut stopped at its
    first zero finishes that step of dt, the unit of N_ZERO_STEPS.  Returns the time
    reached."""
    if out.modes is not None or out.contact is not None:
        raise ValueError("run_exact keeps no modes' extremes and no contact rows (RK4's)")
    run = core.ExactRun()
    run.prep = setup = prepare(p) if prep is None else prep
    t0, dt = steps.t0, steps.dt
    if int(p[L.FORCING]) == L.REGENERATIVE:
        if not dt > 0.0:
            raise ValueError(f"exact integrator: a regenerative cut needs dt > 0, not {dt}")
        run.H = history_step(float(p[L.TAU]), float(dt))
        run.tabE, run.tabP = cut_tables(setup, p, run.H)
    run.p, run.x, run.t0 = p, x, t0
    run.t_end, run.t_steady = t0 + steps.n_steps * dt, t0 + steps.steady_start * dt
    run.rec_dt = steps.record_every * dt
    _write_records(run, out)
    run.dt = dt
    return core.run_exact(run)


def regime_matrix(p: np.ndarray, sdir: float, fdir: float = 0.0) -> np.ndarray:
    """A of z' = A z between impacts, z = [X (2n + 2 entries, as the integrators keep the
    state, and a rolling ball's spin), sin Omega t, cos Omega t, 1], for the packed
    parameters ``p``, the ball sliding in direction ``sdir`` (-1, 0 or 1: F_b = -F_c sdir
    held) and a rolling ball slipping with the slip's sign ``fdir`` (-1, 1: its floor's
    friction -mu_k N fdir held) or rolled (0); built from RK4's stage derivative at the
    unit vectors."""
    return core.regime_matrix(np.ascontiguousarray(p, float), float(sdir), float(fdir))


def impact_matrix_of(p: np.ndarray) -> np.ndarray:
    """R with X+ = R X- at an impact of the ball bar of ``p`` (the identity for the other
    bars), from the wall's impact law."""
    return core.impact_matrix(np.ascontiguousarray(p, float))


def carried_kappa(p: np.ndarray, share: float) -> float:
    """kappa = 1/m + share sum psi_d,i^2 / M_i (1/kg) of the ball of the packed ``p``
    carried with the bar, with the ``share`` of the reaction on it (1: reciprocal): the
    force that moves it per unit of relative acceleration, from the core's equations of
    motion (which hold and roll the ball with it)."""
    return core.carried_kappa(np.ascontiguousarray(p, float), float(share))


def impact_mass(p: np.ndarray) -> float:
    """m_eff (kg) of an impact of the ball of the packed ``p`` (docs/model.md, 2.4): the
    inverse of its carrying term at the reaction's full share."""
    return 1.0 / carried_kappa(p, 1.0)


@functools.lru_cache(maxsize=256)
def hunt_crossley_alpha(restitution: float) -> float:
    """alpha = chi v_in of the Hunt-Crossley damping whose free impact restores
    ``restitution`` (model/contact.py), from the core; kept per restitution."""
    return core.hunt_crossley_alpha(check_hertz_restitution(restitution))


def hunt_crossley_restitution(alpha: float) -> float:
    """The restitution of a free Hunt-Crossley impact with ``alpha`` = chi v_in, from the
    core (RK4 at a dimensionless step of 1e-4)."""
    return core.hunt_crossley_restitution(float(alpha))


def cut_history_map(d, cols, base, weights, c, cv, v, periods: int) -> np.ndarray:
    """A periodic cut orbit's linearised map on its delay history, ``periods`` periods:
    ``v`` = [the (W, W') pairs of the history's nodes, oldest first; node 0's state].
    ``d`` (m, s, s): each step's derivative in its node; ``cols`` (m, K, s): in each
    delayed W it reads, at the period's nodes ``base`` (m, K) and base + 1 (negative: the
    history) with the Hermite ``weights`` (m, K, 4) on (W_j, W'_j, W_j+1, W'_j+1);
    W = ``c`` . x, W' = ``cv`` . x.  Every delay must reach back at least one step."""
    return core.cut_history_map(d, cols, base, weights, c, cv,
                                np.ascontiguousarray(v, dtype=float), int(periods))


__all__ = ["BMAX", "Records", "Steps", "carried_kappa", "cut_history_map",
           "hunt_crossley_alpha", "hunt_crossley_restitution", "impact_mass",
           "impact_matrix_of", "prepare", "regime_matrix", "run_exact", "run_rk4",
           "run_rk4_batch"]
