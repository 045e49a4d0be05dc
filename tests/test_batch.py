"""The batch kernel (boringbar.simulate.kernels.run_rk4_batch) against the single-run kernel.

Every run of a batch must give what ``simulate`` gives for it alone: every
streamed metric, the impact rows, the stick intervals, the strobe samples and
the final state.  Both kernels do the same operations in the same order and
the strobe interpolation's roundings are pinned (core/rk4.hpp), so the
comparison is bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from boringbar import Harmonic, Initial, make_system, simulate
from boringbar._validate import ParameterError
from boringbar.analysis.sweep import SweepOptions
from boringbar.execute import Execution
from boringbar.model.forcing import Regenerative
from boringbar.simulate import Integration, simulate_batch
from boringbar.simulate import layout as L
from boringbar.simulate.kernels import BMAX, Records, Steps, run_rk4_batch

DURATION = 0.06  # 60,000 steps: several hundred impacts, stick, 25+ strobe periods


def assert_same_run(a, b):
    """Two Runs equal in everything the kernel produces (elapsed time aside)."""
    assert a.metrics.keys() == b.metrics.keys()
    for k, v in a.metrics.items():
        w = b.metrics[k]
        assert (v == w) or (isinstance(v, float) and math.isnan(v) and math.isnan(w)), k
    for k, v in a.energy.items():
        assert v == b.energy[k], k
    np.testing.assert_array_equal(a.impacts, b.impacts)
    np.testing.assert_array_equal(a.sticks, b.sticks)
    np.testing.assert_array_equal(a.strobe, b.strobe)
    np.testing.assert_array_equal(a.final.x, b.final.x)
    assert a.final.t_s == b.final.t_s
    assert (a.pattern is None) == (b.pattern is None)
    if a.pattern is not None:
        assert a.pattern.name == b.pattern.name


def check_batch(jobs, duration_s=DURATION, **kw):
    batch = simulate_batch(jobs, duration_s=duration_s, strobe=True, **kw)
    assert len(batch) == len(jobs)
    singles = [simulate(s, f, initial=i, duration_s=duration_s, strobe=True, integrator="rk4",
                        **kw) for s, f, i in jobs]
    for one, many in zip(singles, batch, strict=True):
        assert_same_run(one, many)
    return singles


def varied(system, forces=(10.0, 20.0), ratios=(0.97, 1.0, 1.01, 1.04)):
    """Runs of one system that differ in force, frequency and initial state."""
    jobs = []
    for j, (f, r) in enumerate((f, r) for f in forces for r in ratios):
        jobs.append((system, Harmonic(f, r), Initial(0.2e-3 * (j % 3 - 1), 0.3 * (j % 2))))
    return jobs


@pytest.mark.parametrize("preset, n_modes", [("paper", 1), ("physical", 2)])
@pytest.mark.parametrize("friction", [False, True])
def test_ball_batches_equal_single_runs(preset, n_modes, friction):
    system = make_system("ball", preset, gap_m=0.5e-3, friction=friction, n_modes=n_modes)
    runs = check_batch(varied(system))
    assert sum(r.metrics["impacts_total"] for r in runs) > 50
    if friction:
        assert sum(len(r.sticks) for r in runs) > 0


@pytest.mark.parametrize("bar", ["solid", "tmd", "locked"])
@pytest.mark.parametrize("preset, n_modes", [("paper", 1), ("physical", 2)])
def test_solid_tmd_and_locked_batches_equal_single_runs(bar, preset, n_modes):
    if bar == "locked":
        system = make_system("ball", preset, gap_m=0.5e-3, locked=True, n_modes=n_modes)
    else:
        system = make_system(bar, preset, n_modes=n_modes)
    assert system.kind == bar
    # 8 runs: the paper bars' batches then compile once for this test and the sweep's
    check_batch(varied(system))


def test_runs_that_impact_at_different_steps_and_differ_in_the_damper():
    """Small gap, different starts, gaps and restitutions in one batch: the walls are
    hit at different steps by different runs (the per-run event path)."""
    jobs = []
    for j, (gap, e) in enumerate([(0.1e-3, 0.7), (0.1e-3, 0.6), (0.5e-3, 0.8), (0.2e-3, 0.7),
                                  (0.1e-3, 0.7)]):
        s = make_system("ball", "paper", gap_m=gap, friction=j % 2 == 0, restitution=e)
        jobs.append((s, Harmonic(10.0 + 5 * j, 1.0 + 0.01 * j),
                     Initial(0.3e-3 * j, -0.2 * j, ball_position_m=gap / 2 * (j - 2) / 3)))
    runs = check_batch(jobs)
    first = [r.impacts[0, 0] for r in runs if len(r.impacts)]
    assert len(set(first)) >= 4, "the runs should hit the walls at different times"
    counts = [r.metrics["impacts_total"] for r in runs]
    assert len(set(counts)) >= 4


def test_a_batch_continues_from_states_and_any_batch_size_gives_the_same_run():
    system = make_system("ball", "paper", gap_m=0.5e-3, friction=True)
    jobs = varied(system, forces=(10.0,), ratios=(0.99, 1.01, 1.03))
    first = simulate_batch(jobs, duration_s=0.02, strobe=True)
    # continued from the end states (t0 = 0.02 s, forcing phase carried on)
    again = [(s, f, run.final) for (s, f, _), run in zip(jobs, first, strict=True)]
    check_batch(again, duration_s=0.03)
    # a run's results do not depend on its batch's size or companions
    alone = simulate_batch(jobs[1:2], duration_s=0.02, strobe=True)[0]
    assert_same_run(alone, first[1])


def test_full_batch_and_kernel_arguments():
    system = make_system("ball", "paper", gap_m=0.5e-3, friction=True)
    jobs = varied(system, forces=(10.0, 15.0, 20.0, 25.0), ratios=(0.98, 1.0, 1.02, 1.04))
    assert len(jobs) == BMAX
    check_batch(jobs, duration_s=0.02)
    with pytest.raises(ParameterError, match="at most"):
        simulate_batch(jobs + jobs[:1], duration_s=0.01)
    with pytest.raises(ParameterError, match="cannot share a batch"):
        simulate_batch([jobs[0], (make_system("solid", "paper"), Harmonic(10.0, 1.0), None)],
                       duration_s=0.01)
    with pytest.raises(ParameterError, match="harmonic"):
        simulate_batch([(system, Regenerative(depth_m=1e-4, rpm=1000.0), None)], duration_s=0.01)
    P = np.zeros((2, L.P_SIZE))
    P[:, L.N_MODES] = 1
    P[1, L.CASE] = L.BALL
    with pytest.raises(ValueError, match="share the mode count, the case"):
        run_rk4_batch(P, np.zeros((2, 4)), Steps(0.0, 1e-6, 1, 0),
                      Records(np.zeros((2, 0, 6)), np.zeros((2, 1, 3)), np.zeros((2, 1, 2)),
                              np.zeros((2, 0, 5)), np.zeros((2, L.MET_SIZE))))


def test_basins_and_sweep_are_the_same_batched_or_not():
    """Batches (in grid / job order, padded) change nothing in the results, whatever
    the workers; an uneven grid leaves a partial last batch."""
    from boringbar.analysis.basins import BasinOptions, basins
    from boringbar.analysis.cases import published_cases
    from boringbar.analysis.sweep import sweep

    system = make_system("ball", "paper", gap_m=0.5e-3, friction=True)
    grid = {"displacement_m": (-1e-3, 1e-3, 3), "velocity_m_s": (-1.0, 1.0, 5),
            "force_n": 10.0, "ratio": 1.01}
    short = Integration(duration_s=0.03)
    one = basins(system, BasinOptions(**grid, batch=1), integration=short,
                 execution=Execution(workers=1))
    for batch in (4, 16):  # 4 batches, the last of 3 cells; one batch of 15
        many = basins(system, BasinOptions(**grid, batch=batch), integration=short,
                      execution=Execution(workers=2))
        assert (one.attrs["batch"], many.attrs["batch"]) == (1, batch)
        for k in one.data_vars:
            np.testing.assert_array_equal(one[k].values, many[k].values, err_msg=k)

    cases = published_cases(preset="paper")  # solid, tmd and four ball dampers
    ratios = [0.98, 1.0, 1.02]
    short, two = Integration(duration_s=0.02), Execution(workers=2)
    one = sweep(cases, SweepOptions(ratios, (10.0, 20.0), batch=1), integration=short,
                execution=two)
    many = sweep(cases, SweepOptions(ratios, (10.0, 20.0), batch=16), integration=short,
                 execution=two)
    assert (one.attrs["batch"], many.attrs["batch"]) == (1, 16)
    for k in one.data_vars:
        np.testing.assert_array_equal(one[k].values, many[k].values, err_msg=k)
