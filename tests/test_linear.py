"""Linear tip FRFs and TMD tuning (boringbar.reference.linear) against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from boringbar._validate import ParameterError
from boringbar.model.bar import ModalModel, published_bar
from boringbar.model.dampers import (
    TunedMassDamper,
    absorber_mass_ratio,
    den_hartog_parameters,
    sims_parameters,
    sims_tuning,
)
from boringbar.reference.linear import (
    min_real_part,
    minimax_real_tuning,
    static_tip_compliance,
    tip_frf,
)

K_TIP = 1.5e6  # N/m, about the published bar's first-mode tip stiffness


def tap_bar(zeta: float = 0.01, absorber_ratio: float = 0.5) -> ModalModel:
    return ModalModel.from_tap_test(
        461.0, zeta, tip_stiffness_n_m=K_TIP, damper_ratio=0.5, absorber_ratio=absorber_ratio
    )


def absorber_mass_for(mu: float, bar: ModalModel) -> float:
    """The absorber mass giving mass ratio mu = m_a psi_a^2 / M on mode 1."""
    return mu * bar.mass_kg[0] / bar.psi_absorber[0] ** 2


def local_extrema(values: np.ndarray, kind: str) -> np.ndarray:
    v = values if kind == "min" else -values
    return np.flatnonzero((v[1:-1] < v[:-2]) & (v[1:-1] < v[2:])) + 1


# --- plain bar ------------------------------------------------------------------
def test_sdof_tip_frf_is_the_closed_form():
    bar = tap_bar().normalised([2.0])  # psi_L = 2: the psi_L^2 factor is exercised
    m, k, c, p = bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0], bar.psi_tip[0]
    w = np.linspace(0.0, 3.0, 301) * bar.natural_frequency_rad_s
    exact = p**2 / (k - m * w**2 + 1j * c * w)
    np.testing.assert_allclose(tip_frf(bar, w), exact, rtol=1e-12, atol=0)


def test_frf_keeps_the_shape_of_omega():
    bar = published_bar(True, 2)
    w = bar.natural_frequency_rad_s * np.ones((3, 4))
    assert tip_frf(bar, w).shape == (3, 4)
    assert np.ndim(tip_frf(bar, bar.natural_frequency_rad_s)) == 0


def test_frf_does_not_depend_on_the_mode_normalisation():
    bar = published_bar(False, 2)
    tmd = TunedMassDamper.den_hartog(0.39, bar)
    w = np.linspace(0.2, 7.0, 500) * bar.natural_frequency_rad_s
    ref = tip_frf(bar, w, tmd=tmd, added_mass_kg=0.026)
    for scale in ([2.0, 1.0], [2.0, -0.5]):
        other = tip_frf(bar.normalised(scale), w, tmd=tmd, added_mass_kg=0.026)
        np.testing.assert_allclose(other, ref, rtol=1e-11)


def test_static_tip_compliance_is_the_zero_frequency_receptance():
    bar = published_bar(True, 2)
    expected = sum(1.0 / bar.stiffness_n_m)  # psi_L = 1 in the FE normalisation
    assert static_tip_compliance(bar) == pytest.approx(expected, rel=1e-14)
    tmd = TunedMassDamper.den_hartog(0.2, bar)
    for kwargs in ({}, {"tmd": tmd}, {"added_mass_kg": 0.026}):
        assert tip_frf(bar, 0.0, **kwargs) == pytest.approx(static_tip_compliance(bar), rel=1e-12)


# --- locked ball: a rigid added mass at z_d --------------------------------------
def test_locked_mass_on_one_mode_is_the_closed_form():
    bar = tap_bar()
    m_ball = 0.026
    m, k, c = bar.mass_kg[0], bar.stiffness_n_m[0], bar.damping_n_s_m[0]
    m_tot = m + m_ball * bar.psi_damper[0] ** 2
    w = np.linspace(0.5, 1.5, 201) * bar.natural_frequency_rad_s
    exact = 1.0 / (k - m_tot * w**2 + 1j * c * w)
    np.testing.assert_allclose(tip_frf(bar, w, added_mass_kg=m_ball), exact, rtol=1e-12)


def test_locked_mass_lowers_the_undamped_resonance_to_sqrt_k_over_m_total():
    bar = tap_bar(zeta=0.0)
    m_ball = 0.026
    w_locked = math.sqrt(bar.stiffness_n_m[0] / (bar.mass_kg[0] + m_ball * bar.psi_damper[0] ** 2))
    g = tip_frf(bar, w_locked * np.array([1 - 1e-6, 1 + 1e-6]), added_mass_kg=m_ball).real
    assert g[0] > 1e4 * static_tip_compliance(bar) and g[1] < -1e4 * static_tip_compliance(bar)


def test_locked_mass_couples_two_modes():
    """The poles are the eigenvalues of (diag K, diag M + m psi_d psi_d^T)."""
    bar = published_bar(True, 2)
    bar = ModalModel(
        bar.mass_kg, bar.stiffness_n_m, [0.0, 0.0], bar.psi_tip, bar.psi_damper, bar.psi_absorber
    )
    m_ball = 0.2
    mass = np.diag(bar.mass_kg) + m_ball * np.outer(bar.psi_damper, bar.psi_damper)
    w_eig = np.sqrt(scipy.linalg.eigh(np.diag(bar.stiffness_n_m), mass, eigvals_only=True))
    assert not np.allclose(w_eig, bar.omegas_rad_s, rtol=1e-3)  # the mass does shift both
    big = 1e4 * static_tip_compliance(bar)
    for w in w_eig:
        g = tip_frf(bar, w * np.array([1 - 1e-7, 1 + 1e-7]), added_mass_kg=m_ball).real
        assert abs(g[0]) > big and abs(g[1]) > big and g[0] * g[1] < 0


# --- tuned mass damper ------------------------------------------------------------
def test_tmd_on_one_mode_is_the_closed_form():
    """G = psi_L^2 / (K - M w^2 + i w C - m_a w^2 psi_a^2 kc / (kc - m_a w^2))."""
    bar = tap_bar().normalised([0.3])
    tmd = TunedMassDamper(mass_kg=0.05, stiffness_n_m=4e5, damping_n_s_m=30.0,
                          position_m=bar.z_absorber_m)
    w = np.linspace(0.3, 2.0, 400) * bar.natural_frequency_rad_s
    kc = tmd.stiffness_n_m + 1j * w * tmd.damping_n_s_m
    absorber = tmd.mass_kg * w**2 * bar.psi_absorber[0] ** 2 * kc / (kc - tmd.mass_kg * w**2)
    host = bar.stiffness_n_m[0] - bar.mass_kg[0] * w**2 + 1j * w * bar.damping_n_s_m[0]
    exact = bar.psi_tip[0] ** 2 / (host - absorber)
    np.testing.assert_allclose(tip_frf(bar, w, tmd=tmd), exact, rtol=1e-12)


def test_tmd_elsewhere_than_the_models_absorber_point_is_refused():
    bar = tap_bar()
    tmd = TunedMassDamper(mass_kg=0.05, stiffness_n_m=4e5, damping_n_s_m=30.0, position_m=0.05)
    with pytest.raises(ParameterError, match="absorber position"):
        tip_frf(bar, 1000.0, tmd=tmd)


def test_den_hartog_parameters_are_the_textbook_formulas():
    bar = published_bar(False, 1)
    m_a = 0.39
    mu = m_a * bar.psi_absorber[0] ** 2 / bar.mass_kg[0]
    wn = math.sqrt(bar.stiffness_n_m[0] / bar.mass_kg[0])
    f = 1.0 / (1.0 + mu)
    zeta = math.sqrt(3.0 * mu / (8.0 * (1.0 + mu) ** 3))
    p = den_hartog_parameters(m_a, bar)
    assert p["mass_ratio"] == pytest.approx(mu, rel=1e-14)
    assert p["stiffness_n_m"] == pytest.approx(m_a * f**2 * wn**2, rel=1e-14)
    assert p["damping_n_s_m"] == pytest.approx(2.0 * zeta * m_a * wn, rel=1e-14)
    assert absorber_mass_ratio(m_a, bar) == pytest.approx(mu, rel=1e-14)
    assert 0.2 < mu < 0.35  # docs/model.md: about 0.25 at z_a = 96 mm


@pytest.mark.parametrize("mu", [0.05, 0.25])
def test_den_hartog_gives_equal_peaks_on_an_undamped_host(mu):
    """Den Hartog equalises the fixed points exactly; the peaks sit next to them,
    equal to within a fraction of a percent (0.15 % at mu = 0.25)."""
    bar = tap_bar(zeta=0.0)
    tmd = TunedMassDamper.den_hartog(absorber_mass_for(mu, bar), bar)
    w = np.linspace(0.5, 1.6, 200_001) * bar.natural_frequency_rad_s
    mag = np.abs(tip_frf(bar, w, tmd=tmd))
    peaks = mag[local_extrema(mag, "max")]
    assert len(peaks) == 2
    assert peaks.min() / peaks.max() > 0.99


def den_hartog_fixed_points(mu: float) -> np.ndarray:
    """His fixed points under his tuning f = 1/(1 + mu): g^2 = (1 -+ sqrt(mu/(2 + mu)))/(1 + mu),
    the roots of g^4 - 2 g^2 (1 + f^2 + mu f^2)/(2 + mu) + 2 f^2/(2 + mu) = 0 (omega / omega_n)."""
    root = math.sqrt(mu / (2 + mu))
    return np.sqrt((1 + np.array([-root, root])) / (1 + mu))


@pytest.mark.parametrize("mu", [0.05, 0.25])
def test_den_hartog_fixed_points_have_his_height_whatever_the_damping(mu):
    """On an undamped host every absorber damping passes through his two fixed points, at
    sqrt(1 + 2/mu) times the static compliance under his tuning.  Round-off only: the
    closed forms hold exactly, so 1e-9 (measured: 1e-15)."""
    bar = tap_bar(zeta=0.0)
    tmd = TunedMassDamper.den_hartog(absorber_mass_for(mu, bar), bar)
    w = den_hartog_fixed_points(mu) * bar.natural_frequency_rad_s
    height = math.sqrt(1 + 2 / mu) * static_tip_compliance(bar)
    for scale in (0.1, 1.0, 10.0):
        other = TunedMassDamper(tmd.mass_kg, tmd.stiffness_n_m, scale * tmd.damping_n_s_m,
                                tmd.position_m)
        np.testing.assert_allclose(np.abs(tip_frf(bar, w, tmd=other)), height, rtol=1e-9)


@pytest.mark.parametrize("mu", [0.05, 0.25])
def test_den_hartogs_peaks_stand_just_above_his_fixed_points(mu):
    """His damping (Brock's) makes the fixed points maxima only on average: the two peaks
    stand beside them, higher by 0.5 % at most (measured: 0.07 and 0.08 % at mu = 0.05, 0.26 and
    0.41 % at mu = 0.25)."""
    bar = tap_bar(zeta=0.0)
    tmd = TunedMassDamper.den_hartog(absorber_mass_for(mu, bar), bar)
    w = np.linspace(0.5, 1.6, 200_001) * bar.natural_frequency_rad_s
    mag = np.abs(tip_frf(bar, w, tmd=tmd)) / static_tip_compliance(bar)
    excess = mag[local_extrema(mag, "max")] / math.sqrt(1 + 2 / mu) - 1
    assert len(excess) == 2 and np.all((excess > 0) & (excess < 5e-3))


# --- Sims: equal real troughs -----------------------------------------------------
def real_troughs(bar, tmd) -> np.ndarray:
    w = np.linspace(0.4, 2.0, 200_001) * bar.natural_frequency_rad_s
    re = tip_frf(bar, w, tmd=tmd).real
    return re[local_extrema(re, "min")]


@pytest.mark.parametrize("mu", [0.05, 0.25, 0.75])
def test_sims_gives_equal_real_troughs_on_an_undamped_host(mu):
    bar = tap_bar(zeta=0.0)
    troughs = real_troughs(bar, sims_tuning(absorber_mass_for(mu, bar), bar))
    assert len(troughs) == 2
    assert troughs[0] == pytest.approx(troughs[1], rel=1e-6)  # grid-limited


def test_sims_parameters_small_mass_ratio_limit():
    """f -> 1 + sqrt(mu/8), zeta_a -> sqrt(3 mu / 8) as mu -> 0."""
    bar = tap_bar()
    mu = 1e-6
    p = sims_parameters(absorber_mass_for(mu, bar), bar)
    assert p["mass_ratio"] == pytest.approx(mu, rel=1e-12)
    assert p["frequency_ratio"] - 1.0 == pytest.approx(math.sqrt(mu / 8), rel=1e-2)
    assert p["damping_ratio"] == pytest.approx(math.sqrt(3 * mu / 8), rel=1e-3)
    tmd = sims_tuning(absorber_mass_for(mu, bar), bar)
    assert tmd.design == "sims" and tmd.position_m == bar.z_absorber_m


def test_sims_closed_form_is_the_exact_minimax_on_an_undamped_host():
    """Started from Den Hartog's tuning, the numerical minimax lands on Sims' (k_a, c_a)."""
    bar = tap_bar(zeta=0.0)
    m_a = absorber_mass_for(0.25, bar)
    sims = sims_tuning(m_a, bar)
    best = minimax_real_tuning(m_a, bar, start=TunedMassDamper.den_hartog(m_a, bar), xatol=1e-9)
    assert best.design == "minimax-real"
    assert best.stiffness_n_m == pytest.approx(sims.stiffness_n_m, rel=1e-5)
    assert best.damping_n_s_m == pytest.approx(sims.damping_n_s_m, rel=1e-4)
    assert min_real_part(bar, best)[0] == pytest.approx(min_real_part(bar, sims)[0], rel=1e-8)
    # and it beats Den Hartog's tuning at what Sims optimises (about 40 % here)
    dh = min_real_part(bar, TunedMassDamper.den_hartog(m_a, bar))[0]
    assert min_real_part(bar, sims)[0] > 1.3 * dh


def test_sims_is_within_two_percent_of_the_minimax_on_the_damped_bar():
    """The published solid bar, one mode (zeta = 0.01), the 0.39 kg absorber, mu = 0.28.

    Sims' closed form assumes an undamped host, so on the damped bar it is
    not exactly optimal: the minimax does better by 0.87 % here (2.8 % at
    mu = 0.05, 0.4 % at mu = 0.75 on a tap-test bar: the host's damping
    matters more when the absorber is small).  Hence the 2 % tolerance.
    """
    bar = published_bar(False, 1)
    sims = sims_tuning(0.39, bar)
    best = minimax_real_tuning(0.39, bar)
    re_sims, w_sims = min_real_part(bar, sims)
    re_best, _ = min_real_part(bar, best)
    assert re_best >= re_sims  # the minimax can only improve on its start
    assert re_best / re_sims == pytest.approx(1.0, abs=0.02)
    assert 1.0 < w_sims / bar.natural_frequency_rad_s < 1.4  # the upper trough
    assert best.stiffness_n_m == pytest.approx(sims.stiffness_n_m, rel=0.02)
    assert best.damping_n_s_m == pytest.approx(sims.damping_n_s_m, rel=0.02)


def test_second_mode_costs_the_single_mode_closed_form_about_eight_percent():
    """With two modes retained Sims' (mode-1) tuning is 8 % short of the minimax.

    Mode 2 is flexible at z_a (psi_a2 = -0.51 against psi_a1 = 0.32): its
    static compliance there adds about 11 % to mode 1's, which the
    single-mode closed form cannot see.  A regression check on that finding
    (measured 8.1 %), not a tolerance: use ``minimax_real_tuning`` on the
    multi-mode model when it matters.
    """
    bar = published_bar(False, 2)
    re_sims = min_real_part(bar, sims_tuning(0.39, bar))[0]
    re_best = min_real_part(bar, minimax_real_tuning(0.39, bar))[0]
    assert 0.05 < 1.0 - re_best / re_sims < 0.11


def test_min_real_part_refines_below_the_grid():
    bar = tap_bar()
    coarse = bar.natural_frequency_rad_s * np.linspace(0.5, 1.5, 41)
    value, w_min = min_real_part(bar, omega_rad_s=coarse)
    # SDOF: Re G = (K - M w^2) / ((K - M w^2)^2 + (C w)^2), minimum near w_n sqrt(1 + 2 zeta)
    fine = bar.natural_frequency_rad_s * np.linspace(1.0, 1.04, 400_001)
    exact = tip_frf(bar, fine).real.min()
    assert value == pytest.approx(exact, rel=1e-9)
    assert value == pytest.approx(-1.0 / (4 * 0.01 * (1 + 0.01) * K_TIP), rel=1e-3)
    assert w_min / bar.natural_frequency_rad_s == pytest.approx(math.sqrt(1.02), rel=1e-3)
