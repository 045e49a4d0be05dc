"""Impact-pattern classifier on synthetic impact sequences with known answers."""

import json

import numpy as np
import pytest

from boringbar._validate import ParameterError
from boringbar.simulate.patterns import PATTERN_LABELS, Pattern, classify

T = 1.0 / 461.0  # forcing period near the bar's first mode (s)
DT = 1e-6  # published step (s)
CYCLES = 200
WINDOW = (0.0, CYCLES * T)
NO_STICK = np.zeros((0, 2))


def sequence(phases, walls, cycles=CYCLES, k=1):
    """Impacts at ``phases`` (fractions of kT) on ``walls``, repeated every kT."""
    starts = np.arange(0, cycles, k)[:, None] * T
    times = (starts + np.asarray(phases)[None, :] * T).ravel()
    wall = np.tile(walls, len(starts))
    keep = times < WINDOW[1]
    return times[keep], wall[keep]


def run(times, walls, stick=NO_STICK, **kw):
    return classify(times, walls, stick, WINDOW, T, dt=DT, **kw)


def test_empty_is_no_impact():
    p = run(np.array([]), np.array([]))
    assert (p.label, p.name, p.n, p.k, p.impacts_per_cycle) == ("no impact", "no impact", 0, 0, 0)


def test_small_contact_time_is_still_no_impact():
    p = run(np.array([]), np.array([]), contact_time=0.005 * WINDOW[1])
    assert p.label == "no impact"
    assert p.contact_fraction == pytest.approx(0.005)


@pytest.mark.parametrize(
    "kw", [{"stick": np.array([[-1.0, 10 * T]])}, {"contact_time": 0.02 * CYCLES * T}]
)
def test_stick_or_contact_without_impacts(kw):
    p = run(np.array([]), np.array([]), **kw)
    assert p.label == "no impact with sticking"
    if "stick" in kw:  # clipped to the window
        assert p.stick_fraction == pytest.approx(10 / CYCLES)


def test_two_symmetric():
    p = run(*sequence([0.25, 0.75], [1, -1]))
    assert (p.label, p.n, p.k, p.name) == ("symmetric", 2, 1, "2 symmetric")
    assert p.impacts_per_cycle == pytest.approx(2.0)
    assert p.plus_per_cycle == pytest.approx(1.0) and p.minus_per_cycle == pytest.approx(1.0)


def test_two_symmetric_survives_one_step_jitter():
    times, walls = sequence([0.25, 0.75], [1, -1])
    rng = np.random.default_rng(0)
    p = run(times + rng.uniform(0.0, DT, times.size), walls)  # detected up to a step late
    assert p.name == "2 symmetric"


def test_jitter_beyond_tolerance_is_not_periodic():
    times, walls = sequence([0.25, 0.75], [1, -1])
    tol = 5 * DT + 1e-3 * T  # the documented default
    rng = np.random.default_rng(2)
    assert run(times + rng.uniform(-0.4, 0.4, times.size) * tol, walls).name == "2 symmetric"
    assert run(times + rng.uniform(-1.5, 1.5, times.size) * tol, walls).label == "non-uniform"


def test_alternating_offset_beyond_tolerance_is_period_two():
    times, walls = sequence([0.25, 0.75], [1, -1])
    tol = 5 * DT + 1e-3 * T
    odd_period = (np.arange(times.size) // 2) % 2
    assert run(times + 0.9 * tol * odd_period, walls).k == 1
    p = run(times + 1.1 * tol * odd_period, walls)
    assert (p.k, p.n, p.label) == (2, 4, "asymmetric")


def test_shift_off_half_period_is_asymmetric():
    tol = 5 * DT + 1e-3 * T
    assert run(*sequence([0.25, 0.75 + 2 * tol / T], [1, -1])).name == "2 asymmetric"
    assert run(*sequence([0.25, 0.75 + 0.5 * tol / T], [1, -1])).name == "2 symmetric"


def test_one_wall_only_is_asymmetric():
    p = run(*sequence([0.3], [1]))
    assert (p.name, p.n, p.k) == ("1 asymmetric", 1, 1)
    assert (p.plus_per_cycle, p.minus_per_cycle) == (pytest.approx(1.0), 0.0)


def test_period_two():
    p = run(*sequence([0.2, 1.4, 1.7], [1, 1, -1], k=2))
    assert (p.label, p.n, p.k, p.name) == ("asymmetric", 3, 2, "3 asymmetric (period 2)")
    assert p.impacts_per_cycle == pytest.approx(1.5)


def test_period_three_symmetric_with_shift_three_halves():
    # y(t + 3T/2) = -y(t) with period 3T: + at 0.1T, - at 1.6T.
    p = run(*sequence([0.1, 1.6], [1, -1], k=3))
    assert (p.name, p.k) == ("2 symmetric (period 3)", 3)


def test_period_above_max_k_is_non_uniform():
    times, walls = sequence([0.2, 1.4], [1, 1], k=2)
    assert run(times, walls, max_k=1).label == "non-uniform"


def test_random_times_are_non_uniform():
    rng = np.random.default_rng(1)
    times = np.sort(rng.uniform(*WINDOW, 2 * CYCLES))
    p = run(times, rng.choice([1, -1], times.size))
    assert (p.label, p.n, p.k, p.name) == ("non-uniform", 0, 0, "non-uniform")
    assert p.impacts_per_cycle == pytest.approx(2.0)


def test_impacts_that_stop_are_non_uniform():
    times, walls = sequence([0.25, 0.75], [1, -1])
    keep = times < 0.5 * WINDOW[1]
    assert run(times[keep], walls[keep]).label == "non-uniform"


def test_impacts_with_stick_are_sticking():
    stick = np.array([[0.1, 0.3], [0.6, 0.8]]) * WINDOW[1]
    p = run(*sequence([0.25, 0.75], [1, -1]), stick=stick)
    assert (p.label, p.name) == ("sticking", "sticking")
    assert p.stick_fraction == pytest.approx(0.4)
    assert run(*sequence([0.25], [1]), contact_time=0.05 * WINDOW[1]).label == "sticking"


def test_to_dict_is_json_and_labels_are_known():
    p = run(*sequence([0.2, 1.4, 1.7], [1, 1, -1], k=2))
    d = json.loads(json.dumps(p.to_dict()))
    assert d["name"] == "3 asymmetric (period 2)" and d["k"] == 2
    assert p.label in PATTERN_LABELS
    with pytest.raises(AttributeError):
        p.label = "x"  # frozen
    assert isinstance(p, Pattern)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"period": 0.0}, "period"),
        ({"window": (1.0, 1.0)}, "window"),
        ({"impact_walls": np.array([2])}, "impact_walls"),
        ({"impact_times": np.array([-1.0])}, "impact_times"),
        ({"max_k": 0}, "max_k"),
        ({"min_periods": 1}, "min_periods"),
        ({"stick_intervals": np.array([[2.0, 1.0]])}, "stick_intervals"),
    ],
)
def test_bad_arguments_name_the_parameter(kw, match):
    args = {
        "impact_times": np.array([0.1 * T]),
        "impact_walls": np.array([1]),
        "stick_intervals": NO_STICK,
        "window": WINDOW,
        "period": T,
    }
    extra = {key: kw.pop(key) for key in ("max_k", "min_periods") if key in kw}
    with pytest.raises(ParameterError, match=match):
        classify(**{**args, **kw}, **extra)


# The periodicity test as NumPy states it, the core's loop's truth
# (core/impact_pattern.cpp): whole-array shifts, folds and minima.
def numpy_periodicity(times, walls, tail, period, tol, max_k, min_periods):
    in_tail = times >= tail[0]
    times, walls = times[in_tail], walls[in_tail]
    for k in range(1, max_k + 1):
        if tail[1] - tail[0] < min_periods * k * period:
            break
        n = numpy_period_count(times, walls, k * period, tail, tol)
        if n:
            return n, k, numpy_symmetric(times[:n], walls[:n], period, k, tol)
    return 0, 0, False


def numpy_period_count(times, walls, span, tail, tol):
    if times.size < 2:
        return 0
    n = int(np.searchsorted(times, times[0] + span - tol))
    if n >= times.size or n == 0:
        return 0
    if not (times[0] <= tail[0] + span + tol and times[-1] >= tail[1] - span - tol):
        return 0
    if not np.array_equal(walls[n:], walls[:-n]):
        return 0
    return n if np.all(np.abs(times[n:] - times[:-n] - span) <= tol) else 0


def numpy_symmetric(times, walls, period, k, tol):
    span = k * period
    plus, minus = np.mod(times[walls == 1], span), np.mod(times[walls == -1], span)
    if plus.size != minus.size:
        return False

    def same(a, b):
        gap = np.abs(np.mod(a, span)[:, None] - b[None, :])
        gap = np.minimum(gap, span - gap)
        return bool(np.all(gap.min(axis=0) <= tol) and np.all(gap.min(axis=1) <= tol))

    return any(same(plus + s, minus) and same(minus + s, plus)
               for s in (2 * np.arange(k) + 1) * period / 2)


def jittered(rng, k):
    """A k-period sequence of 1-4 impacts a period on random walls, each time moved by up
    to about the tolerance (so that some pass and some fail), sometimes made symmetric."""
    m = int(rng.integers(1, 5))
    phases = np.sort(rng.uniform(0, 1, m))
    walls = rng.choice([-1.0, 1.0], m)
    if rng.uniform() < 0.7:  # the mirror image k T / 2 on (antisymmetric for k odd)
        phases = np.concatenate([phases / 2, phases / 2 + 0.5])
        walls = np.concatenate([walls, -walls])
    times, wall = sequence(phases, walls, k=k)
    tol = 5 * DT + 1e-3 * T
    times = times + rng.uniform(-1.0, 1.0, times.size) * tol * rng.uniform(0, 1.5)
    order = np.argsort(times)
    times, wall = times[order], wall[order].astype(float)
    inside = (times >= WINDOW[0]) & (times <= WINDOW[1])
    return times[inside], wall[inside]


def test_core_periodicity_is_numpy_s_on_jittered_and_random_sequences():
    rng = np.random.default_rng(7)
    tol = 5 * DT + 1e-3 * T
    tail = (WINDOW[1] - 50 * T, WINDOW[1])
    kinds = {"periodic": 0, "symmetric": 0, "none": 0}
    for i in range(900):
        if i % 3 == 2:  # random impacts: almost never periodic
            times = np.sort(rng.uniform(*WINDOW, int(rng.integers(0, 300))))
            walls = rng.choice([-1.0, 1.0], times.size)
        else:
            times, walls = jittered(rng, int(rng.choice([1, 1, 2, 3, 4])))
        want = numpy_periodicity(times, walls, tail, T, tol, 8, 3)
        p = run(times, walls)
        assert (p.n, p.k, p.label == "symmetric") == want, i
        kinds["none" if not want[1] else "symmetric" if want[2] else "periodic"] += 1
    assert min(kinds.values()) >= 50, kinds  # each outcome exercised
