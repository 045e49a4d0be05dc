"""The bar model against closed forms that do not come from our code."""

import math

import numpy as np
import pytest
from threadpoolctl import threadpool_info

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.model import bar as bar_module
from boringbar.model.bar import ModalModel, Section, SteppedBar, published_bar
from boringbar.simulate import regimes

E, RHO, D, LEN = 200e9, 7850.0, 0.025, 0.2


def uniform_cantilever_f1() -> float:
    """(1.8751^2 / 2 pi) sqrt(EI / (rho A L^4)), the Euler-Bernoulli closed form."""
    beta1 = 1.875104068711961
    area = math.pi / 4 * D**2
    inertia = math.pi / 64 * D**4
    return beta1**2 / (2 * math.pi) * math.sqrt(E * inertia / (RHO * area * LEN**4))


def test_uniform_cantilever_matches_closed_form_and_converges():
    exact = uniform_cantilever_f1()
    errors = []
    for h in (0.1, 0.05, 0.025, 0.0125):
        bar = SteppedBar(sections=(Section(0.0, LEN, D),), max_element_length_m=h)
        f1 = bar.modes(1)[0][0] / (2 * math.pi)
        errors.append(abs(f1 / exact - 1))
    assert errors[-1] < 1e-6
    # Hermite cubics converge at O(h^4) in frequency: each halving gains > 8x
    for coarse, fine in zip(errors, errors[1:], strict=False):
        assert fine < coarse / 8
    default = SteppedBar(sections=(Section(0.0, LEN, D),))
    assert abs(default.modes(1)[0][0] / (2 * math.pi) / exact - 1) < 1e-3 * 0.1  # 0.01 %


def test_second_mode_of_uniform_cantilever():
    beta2 = 4.694091132974175
    bar = SteppedBar(sections=(Section(0.0, LEN, D),))
    f = bar.modes(2)[0] / (2 * math.pi)
    ratio = (beta2 / 1.875104068711961) ** 2  # 6.267
    assert f[1] / f[0] == pytest.approx(ratio, rel=1e-5)


def test_published_bar_converged_in_mesh_and_shapes():
    coarse = published_bar(True, 1, max_element_length_m=0.005)
    fine = published_bar(True, 1, max_element_length_m=0.00125)
    assert coarse.natural_frequency_hz == pytest.approx(fine.natural_frequency_hz, rel=1e-4)
    assert coarse.psi_tip[0] == 1.0
    assert 0.0 < coarse.psi_damper[0] < 1.0  # ball between clamp and tip
    assert coarse.psi_absorber[0] < coarse.psi_damper[0]  # absorber nearer the clamp
    solid = published_bar(False, 1)
    # removing material near the tip stiffens the first mode a little
    assert coarse.natural_frequency_hz > solid.natural_frequency_hz


def test_modal_quantities_do_not_depend_on_normalisation():
    m = published_bar(True, 2)
    s = m.normalised([2.5, -0.3])
    assert np.allclose(s.omegas_rad_s, m.omegas_rad_s, rtol=1e-13)
    assert s.tip_stiffness_n_m == pytest.approx(m.tip_stiffness_n_m, rel=1e-13)
    assert np.allclose(s.psi_damper / s.psi_tip, m.psi_damper / m.psi_tip, rtol=1e-13)


def test_tap_test_model():
    m = ModalModel.from_tap_test(461.0, 0.01, tip_stiffness_n_m=1.0e6, damper_ratio=0.5)
    assert m.natural_frequency_hz == pytest.approx(461.0, rel=1e-14)
    assert m.tip_stiffness_n_m == pytest.approx(1.0e6, rel=1e-14)
    assert m.tip_mass_kg == pytest.approx(1.0e6 / (2 * math.pi * 461.0) ** 2, rel=1e-14)
    with pytest.raises(ParameterError, match="frequency_hz"):
        ModalModel.from_tap_test(-1.0, tip_stiffness_n_m=1e6)


def test_calibration_keeps_mass_and_shape():
    m = published_bar(True, 1)
    c = m.with_first_frequency(461.0)
    assert c.natural_frequency_hz == pytest.approx(461.0, rel=1e-12)
    assert c.mass_kg[0] == m.mass_kg[0] and c.psi_damper[0] == m.psi_damper[0]


def test_bad_geometry_is_named():
    with pytest.raises(ValueError, match="contiguous"):
        SteppedBar(sections=(Section(0.0, 0.1, D), Section(0.11, 0.2, D)))
    with pytest.raises(ParameterError, match="section diameter"):
        Section(0.0, 0.1, -0.01)


def test_the_small_eigenproblems_run_on_one_blas_thread(monkeypatch):
    """The bar's eigensolve and the exact integrator's regimes see one BLAS thread (a
    thread pool only spins on matrices this small, boringbar/model/linalg.py); outside
    them the libraries keep their own."""
    seen = []

    def blas_threads():
        return {i["filepath"]: i["num_threads"] for i in threadpool_info()
                if i["user_api"] == "blas"}

    def recording(real):
        def wrapper(*args, **kwargs):
            seen.append(blas_threads())
            return real(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(bar_module.scipy.linalg, "eigh", recording(bar_module.scipy.linalg.eigh))
    monkeypatch.setattr(regimes.np.linalg, "eig", recording(regimes.np.linalg.eig))
    before = blas_threads()
    regimes.system_regimes.cache_clear()  # the regimes of an earlier test's bar are kept
    bar_module.kept_modal_model.cache_clear()  # and so is its modal model
    system = bb.make_system("ball", gap_m=0.123e-3)
    bb.simulate(system, bb.Harmonic(10.0), duration_s=0.01, record_every=0, integrator="exact")
    assert len(seen) >= 2 and seen[0] and all(set(s.values()) == {1} for s in seen), seen
    assert blas_threads() == before


def test_a_bars_modal_model_is_solved_once_and_each_system_owns_its_info(monkeypatch):
    """make_system solves the finite-element eigenproblem once per bar and arguments:
    systems on one bar share the solve (the same numbers), not the mutable ``info``."""
    calls = []
    real = bar_module.scipy.linalg.eigh

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(bar_module.scipy.linalg, "eigh", counting)
    bar_module.kept_modal_model.cache_clear()
    a = bb.make_system("ball", gap_m=0.1e-3).bar
    b = bb.make_system("ball", gap_m=0.3e-3).bar
    assert len(calls) == 1
    for name in ("mass_kg", "stiffness_n_m", "psi_damper", "psi_absorber"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    b.info["note"] = "mine"
    assert "note" not in a.info
    assert "note" not in bb.make_system("ball").bar.info
    bb.make_system("ball", n_modes=3)  # another model of the bar: solved
    assert len(calls) == 2


def test_a_mesh_finer_than_the_element_cap_is_refused_by_name():
    """A mesh of millions of elements would ask for a dense eigenproblem of terabytes: at
    most MAX_ELEMENTS, refused by name in Python and in a system file."""
    from boringbar.model.bar import MAX_ELEMENTS
    from boringbar.model.system_file import SystemFileError, loads_system, published_file_text

    with pytest.raises(ParameterError, match="max_element_length_m"):
        SteppedBar((Section(0.0, 0.2, 0.025),), 2e11, 7850.0, 0.01, 1e-6)
    finest = SteppedBar((Section(0.0, 0.2, 0.025),), 2e11, 7850.0, 0.01, 0.2 / MAX_ELEMENTS)
    assert finest.max_element_length_m == 0.2 / MAX_ELEMENTS
    text = published_file_text().replace("element_length_mm = 5.0", "element_length_mm = 0.001")
    with pytest.raises(SystemFileError, match="bar.element_length_mm"):
        loads_system(text, "fine.toml")
