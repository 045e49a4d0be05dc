"""The equations of motion as matrices (``boringbar.core.regime_matrix`` and
``impact_matrix``, which shooting linearises) against the slow reference written from
docs/model.md (tests/naive.py): A z is the right-hand side at any state of a regime
(the friction force held by the ball's sliding direction), R x the impact law.  Both
matrices are built from the definitions the RK4 kernel steps with, so this also checks
that those definitions are the model's."""

from __future__ import annotations

import dataclasses
import math

import naive
import numpy as np
import pytest

from boringbar import Harmonic, core, make_system
from boringbar.orbits import shooting as sh
from boringbar.orbits.branch import flow_with
from boringbar.simulate import layout as L
from boringbar.simulate import pack
from boringbar.simulate.kernels import (
    carried_kappa,
    impact_mass,
    impact_matrix_of,
    regime_matrix,
)

SYSTEMS = {
    "solid, 1 mode": lambda: make_system("solid", "paper", n_modes=1),
    "solid, 3 modes": lambda: make_system("solid", "physical", n_modes=3),
    "TMD, 2 modes": lambda: make_system("tmd", "physical"),
    "locked ball, 2 modes": lambda: make_system("ball", "physical", locked=True),
    "ball with friction, 1 mode": lambda: make_system("ball", "paper", gap_m=0.5e-3,
                                                      friction=True),
    "ball with friction, 3 modes": lambda: make_system("ball", "physical", gap_m=0.1e-3,
                                                       friction=True, n_modes=3),
    "ball, printed reaction": lambda: make_system("ball", "paper", friction=True,
                                                  friction_reaction="printed"),
}


def _states(n: int, sdir: float, rng, count: int = 5):
    """States of a realistic size (um, mm/s) with the ball's y' of sign sdir."""
    for _ in range(count):
        x = np.concatenate([rng.normal(0, 1e-5, n), rng.normal(0, 1e-2, n),
                            rng.normal(0, 1e-4, 1), rng.normal(0, 1e-2, 1)])
        x[2 * n + 1] = sdir * abs(x[2 * n + 1])
        yield x


@pytest.mark.parametrize("name", SYSTEMS)
def test_the_regime_matrix_is_the_models_right_hand_side(name):
    system = SYSTEMS[name]()
    omega = 0.97 * system.reference_frequency_rad_s
    p = pack(system, omega, 12.5, 1e-6)
    model = naive.Model.from_packed(p)
    n = model.n
    rng = np.random.default_rng(7)
    for sdir in (-1.0, 0.0, 1.0) if system.kind == "ball" else (0.0,):
        A = regime_matrix(p, sdir)
        assert A.shape == (2 * n + 5, 2 * n + 5)
        for x in _states(n, sdir, rng):
            t = rng.uniform(0, 1e-2)
            z = np.concatenate([x, [math.sin(omega * t), math.cos(omega * t), 1.0]])
            want = naive.rhs(model, t, x)
            got = (A @ z)[:2 * n + 2]
            scale = np.max(np.abs(want))
            assert np.max(np.abs(got - want)) <= 1e-12 * scale, (name, sdir)
            # the forcing's own rows: (sin, cos)' = Omega (cos, -sin), the constant's 0
            assert np.allclose((A @ z)[2 * n + 2:], [omega * z[-2], -omega * z[-3], 0.0],
                               rtol=1e-15, atol=0)


@pytest.mark.parametrize("name", [k for k in SYSTEMS if "ball with" in k or "printed" in k])
def test_the_impact_matrix_is_the_impact_law(name):
    system = SYSTEMS[name]()
    p = pack(system, system.reference_frequency_rad_s, 10.0, 1e-6)
    model = naive.Model.from_packed(p)
    n = model.n
    R = impact_matrix_of(p)
    rng = np.random.default_rng(3)
    for x in _states(n, 1.0, rng):
        x[2 * n] = model.half_gap
        want = naive.impact(model, x)
        assert np.max(np.abs(R @ x - want)) <= 1e-14 * np.max(np.abs(want))


def test_the_other_bars_have_no_impact():
    p = pack(make_system("tmd", "physical"), 1000.0, 10.0, 1e-6)
    assert np.array_equal(impact_matrix_of(p), np.eye(2 * int(p[L.N_MODES]) + 2))


def test_shooting_reads_the_cores_matrices_for_a_changed_flow():
    """A flow a continuation changed (flow_with: the restitution, the friction) is the one
    the matrices describe: shooting packs the flow's own values."""
    system = SYSTEMS["ball with friction, 1 mode"]()
    fl = sh.make_flow(system, Harmonic(10.0, 1.0))
    changed = dataclasses.replace(fl, e=0.3, fc=2 * fl.fc)
    R = sh.impact_matrix(changed)
    assert R[2 * fl.n + 1, 2 * fl.n + 1] == -0.3
    A0, A1 = sh.augmented(fl, 1.0), sh.augmented(changed, 1.0)
    col = fl.N + 2  # the held friction force's column
    assert np.allclose(A1[:, col], 2 * A0[:, col], rtol=1e-14, atol=0)


def test_the_carrying_term_is_the_cores_and_m_eff_its_inverse():
    """kappa = 1/m + share sum psi_d^2 / M (docs/model.md, 2.4 and 2.7) from the core, against
    the sum over three modes in NumPy; the packed m_eff is its inverse at the full share,
    and a continuation in the ball's mass takes its m_eff from it too; a step to a
    massless ball is a refused orbit, and the core refuses a massless ball or a share
    that is not a number."""
    system = SYSTEMS["ball with friction, 3 modes"]()
    p = pack(system, 1000.0, 10.0, 1e-6)
    m, psi, M = system.damper.mass_kg, system.bar.psi_damper, system.bar.mass_kg
    for share in (1.0, -1.0, 0.5):
        assert carried_kappa(p, share) == pytest.approx(1 / m + share * np.sum(psi**2 / M),
                                                        rel=1e-14)
    assert p[L.M_EFF] == impact_mass(p) == 1.0 / carried_kappa(p, 1.0)
    fl = sh.make_flow(system, Harmonic(10.0, 1.0))
    half = flow_with(fl, "ball-mass-g", m * 1e3 / 2, fl)
    assert half.meff == pytest.approx(1 / (2 / m + np.sum(psi**2 / M)), rel=1e-14)
    with pytest.raises(sh.OrbitRefused, match="positive mass"):
        flow_with(fl, "ball-mass-g", -1.0, fl)
    q = p.copy()
    q[L.BALL_MASS] = 0.0
    with pytest.raises(ValueError, match="BALL_MASS"):
        carried_kappa(q, 1.0)
    with pytest.raises(ValueError, match="share"):
        carried_kappa(p, math.nan)


@pytest.mark.parametrize("bad, match", [
    (np.zeros(3), "entries"),
    ("n0", r"N_MODES"),
    ("n99", r"N_MODES"),
    ("case9", r"CASE"),
])
def test_a_bad_parameter_vector_is_a_value_error(bad, match):
    p = pack(make_system("solid", "paper"), 1000.0, 10.0, 1e-6)
    if isinstance(bad, str):
        p = p.copy()
        slot, value = {"n0": (L.N_MODES, 0), "n99": (L.N_MODES, 99),
                       "case9": (L.CASE, 9)}[bad]
        p[slot] = value
    else:
        p = bad
    with pytest.raises(ValueError, match=match):
        regime_matrix(p, 0.0)
    with pytest.raises(ValueError, match=match):
        impact_matrix_of(p)
    with pytest.raises(ValueError, match=match):
        core.dashpots(p)


def test_a_sliding_direction_other_than_minus_one_zero_or_one_is_refused():
    p = pack(make_system("ball", "paper", friction=True), 1000.0, 10.0, 1e-6)
    with pytest.raises(ValueError, match="sdir"):
        regime_matrix(p, 0.5)


def test_a_rolling_ball_s_regime_matrices_are_the_roll_law():
    """A rolling ball's matrices (docs/model.md, 2.7) against the sliding ball's (checked
    above against the slow reference) and the roll law written here: slipping, the
    floor's friction F = -mu_k N sgn(y' - s) is a constant force on the ball (y'' gains
    kappa_1 F, kappa_1 = 1/m + sum psi_d^2 / M), on the bar (u_i'' loses psi_d,i F / M_i)
    and on the spin (s' = -5/(2m) F); rolled, F is what keeps y'' = s', so
    F = -y''_slide / (kappa_1 + 5/(2m)) at every state."""
    system = make_system("ball", "physical", gap_m=0.1e-3, friction=True, motion="roll")
    omega = 0.97 * system.reference_frequency_rad_s
    p = pack(system, omega, 12.5, 1e-6)
    slide_p = p.copy()
    slide_p[L.ROLL] = 0.0
    n = int(p[L.N_MODES])
    M, psi = p[L.M_:L.M_ + n], p[L.PSI_D:L.PSI_D + n]
    m = p[L.BALL_MASS]
    kappa1, kroll = 1.0 / m + float(np.sum(psi**2 / M)), 2.5 / m
    js, nz = 2 * n + 2, 2 * n + 6  # the spin's row; the augmented size
    keep_x = np.r_[np.arange(2 * n + 2), nz - 3 + np.arange(3)]  # z without the spin
    rng = np.random.default_rng(11)
    for sdir in (-1.0, 1.0):
        S = regime_matrix(slide_p, sdir)
        for fdir in (-1.0, 1.0):
            A = regime_matrix(p, sdir, fdir)
            assert A.shape == (nz, nz)
            F = -p[L.ROLL_KINETIC] * fdir
            want = S.copy()
            want[n:2 * n, -1] -= psi * F / M
            want[2 * n + 1, -1] += kappa1 * F
            np.testing.assert_allclose(A[np.ix_(keep_x, keep_x)], want, rtol=1e-12,
                                       atol=1e-12 * np.max(np.abs(want)))
            assert A[js, -1] == pytest.approx(-kroll * F, rel=1e-14)
            assert not np.any(A[js, :-1]) and not np.any(A[:, js])
        A = regime_matrix(p, sdir, 0.0)
        for x in _states(n, sdir, rng):
            t = rng.uniform(0, 1e-2)
            z = np.concatenate([x, [math.sin(omega * t), math.cos(omega * t), 1.0]])
            zs = np.r_[z[:2 * n + 2], z[-3:]]
            slide = S @ zs
            F = -slide[2 * n + 1] / (kappa1 + kroll)
            got = A @ np.r_[z[:2 * n + 2], 0.0, z[-3:]]
            want = np.r_[slide[:2 * n + 2], -kroll * F, slide[-3:]]
            want[n:2 * n] -= psi * F / M
            want[2 * n + 1] += kappa1 * F
            scale = np.max(np.abs(want[:2 * n + 3]))
            assert np.max(np.abs(got - want)) <= 1e-12 * scale
            assert got[js] == pytest.approx(got[2 * n + 1], rel=1e-12)  # y'' = s'


def test_a_floor_direction_is_refused_for_a_ball_that_does_not_roll():
    p = pack(make_system("ball", "physical", friction=True), 1000.0, 10.0, 1e-6)
    with pytest.raises(ValueError, match="fdir must be 0"):
        regime_matrix(p, 1.0, 1.0)
    with pytest.raises(ValueError, match="fdir"):
        regime_matrix(pack(make_system("ball", motion="roll"), 1000.0, 10.0, 1e-6), 1.0, 0.5)
