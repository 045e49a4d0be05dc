"""The objectives of a design study, each over the Monte Carlo samples of one candidate,
and the statistic of those samples with its sampling error (docs/design.md).

A candidate's runs go to the executors one sample at a time: a sample's band of
harmonic runs, its cut, or its speeds' limit searches is one task, coarse enough
that a process or Dask worker spends its time running.
"""

from __future__ import annotations

import math

import numpy as np

from boringbar.analysis.cases import Case
from boringbar.analysis.design_options import DesignOptions
from boringbar.analysis.lobes import lobes
from boringbar.analysis.verdict import judge
from boringbar.execute import Execution, run_points
from boringbar.model.forcing import Harmonic, Regenerative
from boringbar.model.system import System
from boringbar.reference.stability import system_receptance
from boringbar.simulate import STEADY_FRACTION, Initial, Integration, simulate
from boringbar.simulate.run_limits import check_steady_ratios

#: Frequency lines of the FRF objectives, over FRF_SPAN x the host's f1.
FRF_LINES = 6001
FRF_SPAN = (0.3, 2.0)
BOOTSTRAP = 400
#: Cuts take the published RK4 scheme (the exact cut is slower; docs/performance.md).
CUT_INTEGRATOR = "rk4"


def rms_runs(task) -> list[float]:
    """The tip RMS of one system over forces x ratios."""
    system, ratios, forces, initial, duration, integrator = task
    return [simulate(system, Harmonic(f, r), duration_s=duration, initial=initial,
                     integrator=integrator, record_every=0).rms_tip_m
            for f in forces for r in ratios]


def _cut(task) -> tuple[float, bool]:
    """(amplitude m, chatter) of one cut: under the converged verdict half the settled
    tip peak-to-peak and not chatter-free (undecided counts as chatter); under a fixed
    criterion the steady amplitude of a run of ``duration`` and the force reaching zero."""
    system, rpm, depth, duration, criterion = task
    cut = Regenerative(depth_m=depth, rpm=rpm)
    if criterion == "growth":
        v = judge(system, cut)
        return 0.5 * v.settled_pp_m, v.chatter_free is not True
    c = simulate(system, cut, duration_s=duration, integrator=CUT_INTEGRATOR,
                 record_every=0).cutting
    return float(c["amplitude_m"]), bool(c["chatter"])


def depth_lobes(cases: list[Case], options: DesignOptions,
                execution: Execution | None = None):
    """min_depth's lobes: each case's limit at ``options.rpms`` by the lobes' search
    (:meth:`DesignOptions.lobes_options`), cuts of ``options.duration_s`` by
    :data:`CUT_INTEGRATOR` (the lobes Dataset)."""
    return lobes(cases, options.lobes_options(),
                 integration=Integration(options.duration_s, None, CUT_INTEGRATOR),
                 execution=execution)


def _min_depth(task) -> float:
    """The minimum chatter-free depth (m) over the speeds, each speed's limit found by
    the lobes' search (:meth:`DesignOptions.lobes_options`), at most ``max_depth_m``."""
    system, options = task
    ds = depth_lobes([Case.of(system, "design")], options, Execution("serial"))
    # no chatter up to max_depth_m at any speed: the search knows only "at least that"
    return min(float(ds["min_chatter_free_depth_m"].values[0]), options.max_depth_m)


def frf_objective(system: System, objective: str) -> float:
    """The FRF peak |G| (m/N), or -min Re G (m/N), of a linear bar, on FRF_LINES
    lines over FRF_SPAN x the host's f1, refined by a parabola at the extreme."""
    wn = system.bar.natural_frequency_rad_s
    w = np.linspace(FRF_SPAN[0] * wn, FRF_SPAN[1] * wn, FRF_LINES)
    g = system_receptance(system, w)
    y = np.abs(g) if objective == "frf_peak" else -g.real
    i = int(np.clip(np.argmax(y), 1, len(y) - 2))
    a, b, c = y[i - 1], y[i], y[i + 1]
    denom = a - 2 * b + c
    return float(b - 0.125 * (a - c) ** 2 / denom) if denom < 0 else float(b)


def objective_samples(options: DesignOptions, objective: str,
                      sampled: list[tuple[System, Initial]],
                      execution: Execution | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The objective at each sample, and whether each chattered (cut_amplitude)."""
    if objective == "rms_band":
        check_steady_ratios(sampled[0][0], options.ratios, options.duration_s,
                            STEADY_FRACTION, "DesignOptions.duration_s")
        tasks = [(s, options.ratios, options.forces_n, ini, options.duration_s,
                  options.integrator) for s, ini in sampled]
        rms = np.array(run_points(rms_runs, tasks, execution=execution))
        return (rms.max(axis=1) if options.band == "worst" else rms.mean(axis=1)), None
    if objective == "cut_amplitude":
        tasks = [(s, options.rpm, options.depth_m, options.duration_s, options.criterion)
                 for s, _ in sampled]
        out = run_points(_cut, tasks, execution=execution)
        return np.array([a for a, _ in out]), np.array([c for _, c in out])
    if objective == "min_depth":
        return np.array(run_points(_min_depth, [(s, options) for s, _ in sampled],
                                   execution=execution)), None
    return np.array([frf_objective(s, objective) for s, _ in sampled]), None


def statistic(x: np.ndarray, options: DesignOptions,
              chatter: np.ndarray | None = None) -> tuple[float, float]:
    """The statistic of the samples ``x`` (or of ``chatter``) and its sampling error."""
    n = len(x)
    if options.statistic == "chatter_probability":
        p = float(np.mean(chatter))
        return p, math.sqrt(p * (1 - p) / n)
    if options.statistic == "max":
        return float(np.max(x)), 0.0
    if options.statistic == "mean":
        return float(np.mean(x)), float(np.std(x, ddof=1) / math.sqrt(n)) if n > 1 else 0.0
    q = float(np.quantile(x, options.quantile))
    if n == 1:
        return q, 0.0
    rng = np.random.default_rng(options.seed + 1)
    boot = np.quantile(x[rng.integers(0, n, (BOOTSTRAP, n))], options.quantile, axis=1)
    return q, float(np.std(boot, ddof=1))
