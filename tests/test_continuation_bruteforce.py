"""Continuation against brute force: where the exact integrator's forward and backward
sweeps (``bb.bifurcation``) settle on the same period-1 orbit, the continued branch is
that orbit to 1e-8 relative; where they disagree, the branch's stability change bounds
the range of agreement."""

import numpy as np

import boringbar as bb
from boringbar import shooting as sh
from boringbar.analysis.continuation import ContinuationOptions, start_state
from boringbar.branch import continue_branch, flow_with
from boringbar.model.forcing import Harmonic
from boringbar.model.system import make_system
from boringbar.simulate import Integration


def _one_mode_case():
    """The one-mode physical bar, frictionless ball, gap 0.5 mm, ratio 1: brute force
    from rest settles on the symmetric two-impact orbit above ~30 N."""
    return make_system("ball", "physical", gap=0.5e-3, friction=False, n_modes=1)


def _sweep(system, values, duration=1.0):
    """Forward and backward exact sweeps, the last 20 % of each run sampled."""
    return bb.bifurcation(system, bb.BifurcationOptions("force", tuple(values), values[0], 1.0),
                          integration=Integration(duration, 1e-6, "exact", 0.2))


def _branch_at(fl, br, value):
    """The branch's orbit at exactly ``value``: Newton from the nearest branch point."""
    near = min(br.points, key=lambda p: abs(p.value - value))
    return sh.periodic_orbit(flow_with(fl, "force-n", value, fl), near.x)


def test_stable_branch_is_the_brute_force_orbit_where_both_sweeps_agree():
    system = _one_mode_case()
    values = (31.0, 33.0, 35.0)
    ds = _sweep(system, values)
    fl = sh.make_flow(system, Harmonic(values[0], ratio=1.0))
    x0 = start_state(system, ContinuationOptions(force_n=values[0], start="masri-caughey"), fl)
    br = continue_branch(fl, "force-n", x0, 35.5, step=0.2, max_points=40, max_step=0.3)
    assert br.stop == "end of range", br.stop
    agreed = 0
    for j, v in enumerate(values):
        sides = [ds.sel(direction=d).isel(value=j) for d in ("forward", "backward")]
        if not all(int(s["period"]) == 1 for s in sides):
            continue
        x, pr = _branch_at(fl, br, v)
        assert np.all(np.abs(sh.multipliers(pr)) < 1.0)
        w = fl.psi_tip @ x[:fl.n]
        for s in sides:
            samples = s["tip_displacement"].values
            samples = samples[np.isfinite(samples)]
            assert len(samples) > 50
            assert np.max(np.abs(samples - w)) <= 1e-8 * abs(w), (v, samples[-1], w)
        agreed += 1
    assert agreed >= 2
