"""The runs of one (bar, speed) column of a lobe study and the search over its depth
grid (:mod:`boringbar.analysis.lobes` states the methods and criteria).

A column is a dict {depth index: the run's result}; ``options`` is the study's
:class:`~boringbar.analysis.lobes.LobesOptions` and ``integration`` its
:class:`~boringbar.simulate.Integration`.

- Fixed-length criteria ("zero", published, and "bounded"): :func:`fixed_cut` runs a cut
  from ``options.start`` for the integration's duration, stopped at the first zero of
  the force; :func:`column` scans or searches the grid with it.
- The converged criterion ("growth"): :func:`growth_cut` judges a cut
  (:func:`boringbar.analysis.verdict.judge`); :func:`growth_column` finds the onset
  (the small-knock growth rate changes sign) by bracketing and bisection to adjacent
  grid depths, and, for a free ball, whose settled vibration may stay within the
  tolerance above the onset, the chatter-free depth by the same search as the
  fixed criteria.  An undecided run counts by the sign of its last growth rate; in the
  ball's search above the onset, a run left undecided with its onset growing is judged
  again with a cap :data:`RESOLVE_CAP` times the verdict's (:func:`run_longer`).
"""

from __future__ import annotations

import math
from dataclasses import replace

from boringbar.analysis.cases import Case
from boringbar.analysis.verdict import CHATTER as ONSET_CHATTER
from boringbar.analysis.verdict import STABLE as ONSET_STABLE
from boringbar.analysis.verdict import judge
from boringbar.simulate import Integration, simulate

#: codes of the verdict arrays
NOT_RUN, CHATTER, STABLE, UNDECIDED = -1, 0, 1, 2
#: The first step (grid depths) of a ball's chatter-free search up from its onset.
BALL_STEP = 8
#: The longer cap (times the verdict's ``max_duration_s``) of a ball's search above its
#: onset: a new cut there whose onset grows settles to it at once
#: (``VerdictOptions.settle_cap_s``), and an undecided run of the onset's search is judged
#: again with it.  Just above a friction ball's onset the vibration grows slowest and may
#: take far longer than the cap to settle at its bounded level (the carbide example at
#: 972 rpm: 59 s for 0.84 um p-p, its held growth jumped ahead).  A run ends where it
#: settles, so one long cap costs no more than a ladder of caps.
RESOLVE_CAP = 16.0


def fixed_cut(case: Case, rpm: float, depth: float, options, integration: Integration) -> dict:
    """One cut of fixed length, stopped at the first zero of the force: its verdicts
    under both fixed criteria and its metrics."""
    run = simulate(case.system, options.forcing(depth, rpm), duration_s=integration.duration_s,
                   dt_s=integration.dt_s, integrator=integration.integrator,
                   steady_fraction=integration.steady_fraction, record_every=0,
                   stick_law=integration.stick_law)
    c = run.cutting
    ball = case.system.kind == "ball"
    return {"zero": c["chatter"], "bounded": c["chatter"] or c["bounded_chatter"],
            "amplitude_m": c["amplitude_m"],
            "impacts": run.metrics["impacts_total"] if ball else -1,
            "max_rel_disp_m": run.metrics["max_abs_aux_all_m"] if ball else math.nan,
            "first_zero": math.nan if c["first_zero_time_s"] is None
            else c["first_zero_time_s"]}


def growth_cut(case: Case, rpm: float, depth: float, options, integration: Integration) -> dict:
    """One cut judged by the converged verdict: its onset and chatter-free codes, growth
    rate, settled vibration and the simulated time it took."""
    v = judge(case.system, options.forcing(depth, rpm, stop_at_zero=False), options.verdict,
              dt_s=integration.dt_s)
    onset = {ONSET_STABLE: STABLE, ONSET_CHATTER: CHATTER}.get(v.onset, UNDECIDED)
    free = UNDECIDED if v.chatter_free is None else (STABLE if v.chatter_free else CHATTER)
    return {"onset": onset, "verdict": free, "growth_rate_per_s": v.growth_rate_per_s,
            "growth_rate_se_per_s": v.growth_rate_se, "run_duration_s": v.duration_s,
            "settled_pp_m": v.settled_pp_m, "settled_rms_m": v.settled_rms_m}


def onset_chatters(res: dict) -> bool:
    """The onset chatters, or, undecided, its last growth rate is positive."""
    if res["onset"] == UNDECIDED:
        return res["growth_rate_per_s"] > 0
    return res["onset"] == CHATTER


def not_free(res: dict) -> bool:
    """The cut is not chatter-free, or, undecided, its onset chatters."""
    if res["verdict"] == UNDECIDED:
        return onset_chatters(res)
    return res["verdict"] == CHATTER


def column(chatter, seed: int, n_max: int, method: str, need: int, up_step: int = 1) -> None:
    """Run grid indices through ``chatter(i) -> bool`` by ``method`` ("scan": upwards from
    1 until ``need`` chatter in a row; "search": bracket from ``seed`` (upwards in steps
    from ``up_step``, doubling), bisect, then confirm the ``need - 1`` indices above the
    first chattering one, scanning on where one is stable)."""

    def scan_from(i: int) -> None:
        run_of = 0
        while i <= n_max and run_of < need:
            run_of = run_of + 1 if chatter(i) else 0
            i += 1

    if method == "scan":
        scan_from(1)
        return
    lo, hi = bisect(chatter, *bracket(chatter, min(max(1, seed), n_max), n_max, up_step))
    if hi > n_max:
        return
    for i in range(hi + 1, min(hi + need, n_max + 1)):
        if not chatter(i):
            scan_from(i + 1)
            break


def bracket(chatter, seed: int, n_max: int, up_step: int = 1) -> tuple[int, int]:
    """[lo stable, hi chatter] grid indices, growing away from ``seed`` in doubling
    steps, the first one up ``up_step`` (hi = n_max + 1: nothing chattered up to the
    deepest cut)."""
    width = 1
    if chatter(seed):
        lo, hi = seed, seed
        while lo > 0 and chatter(lo):
            hi, lo = lo, max(0, lo - width)
            width *= 2
        return lo, hi
    lo, hi = seed, min(seed + up_step, n_max) if seed < n_max else n_max + 1
    width = up_step
    while hi <= n_max and not chatter(hi):
        lo, hi = hi, min(hi + width, n_max) if hi < n_max else n_max + 1
        width *= 2
    return lo, hi


def bisect(chatter, lo: int, hi: int) -> tuple[int, int]:
    """Adjacent [lo stable, hi chatter] indices inside a bracket."""
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if chatter(mid):
            hi = mid
        else:
            lo = mid
    return lo, hi


def growth_column(case: Case, rpm: float, options, integration: Integration,
                  seed: int = 1) -> dict:
    """The converged criterion's runs at one speed (module doc): {depth index: result}."""
    done: dict[int, dict] = {}

    def result(i: int, opts=options) -> dict:
        if i not in done:
            done[i] = growth_cut(case, rpm, options.depth(i), opts, integration)
        return done[i]

    n_max = options.max_index
    lo, hi = bisect(lambda i: onset_chatters(result(i)),
                    *bracket(lambda i: onset_chatters(result(i)), min(max(1, seed), n_max),
                             n_max))
    if lo > 0 and not_free(result(lo)):
        # below the onset a large knock keeps the tool leaving the cut (or a ball's
        # vibration above the tolerance): the chatter-free depth lies deeper down
        def chatter(i: int) -> bool:
            return not_free(result(i))

        bisect(chatter, *bracket(chatter, lo, n_max))
        return done
    if case.system.kind == "ball" and hi <= n_max:
        # a ball that bounds its vibration within the tolerance often does so well above
        # its onset: the search up from it starts with a step of BALL_STEP grid depths.
        # Its new cuts settle to the longer cap at once; one the onset's search ran to the
        # shorter cap, left undecided with its onset growing, is judged again.
        longer = longer_options(options)
        rerun: set[int] = set()

        def settled(i: int) -> dict:
            if i not in done:
                return result(i, longer)
            res = done[i]
            if (res["verdict"] == UNDECIDED and onset_chatters(res) and RESOLVE_CAP > 1
                    and i not in rerun):
                rerun.add(i)
                res = done[i] = run_longer(case, rpm, options.depth(i), options, integration)
            return res

        column(lambda i: not_free(settled(i)), hi, n_max, options.method, options.successive,
               BALL_STEP)
    return done


def verdict_column(case: Case, rpm: float, options, integration: Integration, seed: int,
                   up_step: int) -> dict:
    """One column's runs searched on whether each cut is chatter-free alone, every cut
    judged by ``options`` as given: :func:`column` (bracket from ``seed`` with a first
    step ``up_step``, bisection, the ``successive`` confirmation) on :func:`not_free`."""
    done: dict[int, dict] = {}

    def chatter(i: int) -> bool:
        if i not in done:
            done[i] = growth_cut(case, rpm, options.depth(i), options, integration)
        return not_free(done[i])

    column(chatter, seed, options.max_index, options.method, options.successive, up_step)
    return done


def free_column(case: Case, rpm: float, options, integration: Integration, seed: int,
                up_step: int) -> dict:
    """A free ball's runs at one speed for its chatter-free depth alone
    (:func:`verdict_column`), every cut judged as the ball's search above its onset
    judges (:func:`longer_options`).  A cut below the onset decays as it would in the
    onset's search, and one above settles as it would above it, so where the column's
    stability is monotone in depth its chatter-free depth (:func:`free_limit`) is the
    lobes', found without the onset's own bisection (the draws of
    :mod:`.chatter_probability`, which need no onset; where it is not, the two may stop
    at different boundaries)."""
    return verdict_column(case, rpm, longer_options(options), integration, seed, up_step)


def longer_options(options):
    """``options`` whose verdict follows a run that settles after its onset grew to the
    longer cap (:data:`RESOLVE_CAP`; unchanged where it is 1)."""
    if RESOLVE_CAP <= 1:
        return options
    cap = longer_cap_s(options.verdict.max_duration_s)
    return replace(options, verdict=replace(options.verdict, settle_cap_s=cap))


def run_longer(case: Case, rpm: float, depth: float, options,
               integration: Integration) -> dict:
    """:func:`growth_cut` with a cap :data:`RESOLVE_CAP` times the verdict's (at most
    1000 s): a run that had not settled by the cap, judged again."""
    longer = replace(options, verdict=replace(
        options.verdict, max_duration_s=longer_cap_s(options.verdict.max_duration_s)))
    return growth_cut(case, rpm, depth, longer, integration)


def longer_cap_s(max_duration_s: float) -> float:
    """The cap (s) of :func:`run_longer` for a verdict capped at ``max_duration_s``."""
    return min(RESOLVE_CAP * max_duration_s, 1000.0)


def onset_depth(done: dict, depth) -> float:
    """The depth (m) where the onset's growth rate crosses zero: linear interpolation of
    the rate between the deepest index whose onset is stable and the next one, which
    chatters (within that 1-step bracket; NaN: no chatter up to the deepest cut; 0: the
    shallowest cut chatters)."""
    chatters = sorted(i for i, r in done.items() if onset_chatters(r))
    if not chatters:
        return math.nan
    hi = chatters[0]
    lo = max((i for i in done if i < hi and not onset_chatters(done[i])), default=0)
    if lo == 0:
        return 0.0
    a, b = done[lo]["growth_rate_per_s"], done[hi]["growth_rate_per_s"]
    d_lo, d_hi = float(depth(lo)), float(depth(hi))
    if not (math.isfinite(a) and math.isfinite(b)) or b <= a or hi - lo > 1:
        return d_lo
    return d_lo + (d_hi - d_lo) * min(1.0, max(0.0, -a / (b - a)))


def free_limit(done: dict, depths, noisy: bool = False) -> float:
    """The chatter-free depth (m) of one column's runs ``done`` ({grid index: run},
    ``depths`` the grid's depths of indices), searched on the chatter-free verdict alone
    (:func:`free_column`, the draws' columns), as the deterministic lobes take it: the
    last chatter-free depth below the first that is not (an undecided settled vibration
    counts by its onset), or the onset itself where the first is the onset's; a noisy
    cut's by its settled vibration alone.  NaN: no chatter up to the deepest cut."""
    order = sorted(done)
    if noisy:
        free = [CHATTER if not_free(done[k]) else STABLE for k in order]
    else:
        free = [done[k]["onset"] if done[k]["verdict"] == UNDECIDED else done[k]["verdict"]
                for k in order]
    first = next((n for n, code in enumerate(free) if code == CHATTER), None)
    if first is None:
        return math.nan
    below = [order[n] for n in range(first) if free[n] == STABLE]
    limit = float(depths(below[-1])) if below else 0.0
    onsets = [k for k in order if done[k]["onset"] in (CHATTER, UNDECIDED)]
    if not noisy and onsets and onsets[0] == order[first]:
        return onset_depth(done, depths)
    return limit
