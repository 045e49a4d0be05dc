"""The FRF fit's stabilisation diagram: it finds exactly the modes of synthetic FRFs
made from known modal parameters (two and three modes, close modes, light noise),
none in noise, and its poles meet the stated criteria; --modes takes the most
flexible; the diagram is a figure beside the fit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from cli_output import assert_one_line_error, json_out

from boringbar import ParameterError
from boringbar.analysis.frf_fit import (
    FREQUENCY_STABLE,
    NEW,
    STABLE,
    STABLE_DAMPING,
    STABLE_FREQUENCY,
    fit_frf,
    fit_modes,
    stabilisation,
)
from boringbar.cli.main import main
from boringbar.model.bar import published_bar
from boringbar.model.measured_frf import MeasuredFrf, frf_csv_text
from boringbar.model.modal_fit import ModalFit
from boringbar.reference.linear import tip_frf

#: Known modal parameters: frequency (Hz), damping ratio, tip stiffness (N/m).
KNOWN = {
    "two modes": ModalFit((500.0, 2300.0), (0.02, 0.03), (2.0e6, 5.0e7)),
    "three modes": ModalFit((480.0, 1500.0, 3100.0), (0.02, 0.015, 0.03),
                            (2.0e6, 1.0e7, 4.0e7)),
    # 8 % apart, each half-power band 20 Hz wide: the peaks overlap
    "close modes": ModalFit((500.0, 540.0), (0.02, 0.02), (2.0e6, 3.0e6)),
}
#: What the fit meets at 1 % complex noise (relative): frequency, damping, stiffness.
TOLERANCE = {"frequency_hz": 1e-3, "damping_ratio": 0.02, "modal_stiffness_n_m": 0.02}


def synthetic(known: ModalFit, noise: float, seed: int = 1) -> MeasuredFrf:
    """The receptance of ``known`` at 1 Hz lines, 50 Hz to 4 kHz, times (1 + noise n),
    n complex Gaussian of unit RMS."""
    f = np.arange(50.0, 4000.0, 1.0)
    rng = np.random.default_rng(seed)
    n = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / math.sqrt(2)
    return MeasuredFrf(f, known.tip_frf(f) * (1 + noise * n), {"file": "synthetic.csv"})


def noise_only(seed: int = 1, lo_hz: float = 50.0) -> MeasuredFrf:
    f = np.arange(lo_hz, 4000.0, 1.0)
    rng = np.random.default_rng(seed)
    h = 1e-7 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
    return MeasuredFrf(f, h, {"file": "noise.csv"})


def assert_recovers(known: ModalFit, diagram) -> None:
    assert len(diagram.modes) == known.n_modes, [m.frequency_hz for m in diagram.modes]
    fit, _ = fit_modes(diagram)
    for name, tol in TOLERANCE.items():
        got, want = np.array(getattr(fit, name)), np.array(getattr(known, name))
        assert np.abs(got / want - 1).max() < tol, (name, got, want)


@pytest.mark.parametrize("case", sorted(KNOWN))
def test_the_diagram_finds_exactly_the_known_modes_through_light_noise(case):
    assert_recovers(KNOWN[case], stabilisation(synthetic(KNOWN[case], 0.01)))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(2, 11))
@pytest.mark.parametrize("case", sorted(KNOWN))
def test_more_noise_draws_find_the_same_modes(case, seed):
    assert_recovers(KNOWN[case], stabilisation(synthetic(KNOWN[case], 0.01, seed)))


def test_without_noise_the_modes_are_exact():
    known = KNOWN["three modes"]
    fit, _ = fit_frf(synthetic(known, 0.0))
    for name in TOLERANCE:
        got, want = np.array(getattr(fit, name)), np.array(getattr(known, name))
        assert np.abs(got / want - 1).max() < 1e-5, name


def test_a_boringbar_frf_gives_the_bars_own_modes_in_the_band():
    """The published bar's FE model (not a sum of modes written here) has its first
    two modes below 4 kHz: the diagram finds those two and no other."""
    bar = published_bar(True, 3)
    f = np.arange(100.0, 4000.0, 1.0)
    diagram = stabilisation(MeasuredFrf(f, tip_frf(bar, 2 * math.pi * f)))
    in_band = bar.omegas_rad_s[bar.omegas_rad_s / (2 * math.pi) < 4000.0] / (2 * math.pi)
    assert len(in_band) == 2
    np.testing.assert_allclose([m.frequency_hz for m in diagram.modes], in_band, rtol=1e-5)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_noise_alone_has_no_mode_and_the_fit_says_so(seed):
    diagram = stabilisation(noise_only(seed))
    assert diagram.modes == ()
    with pytest.raises(ParameterError, match="no stable mode in the band"):
        fit_modes(diagram)


def test_noise_alone_away_from_0_hz_has_no_mode_either():
    diagram = stabilisation(noise_only(1, lo_hz=1000.0))
    assert diagram.method == "lscf" and diagram.modes == ()


def test_every_pole_meets_the_stated_criteria():
    """Status against the order below, read from the diagram's own arrays: a stable
    pole has a pole one order down within 1 % in frequency and 5 % in damping, a
    pole stable in frequency one within 1 % in frequency only, a new pole none."""
    d = stabilisation(synthetic(KNOWN["two modes"], 0.01))
    assert {NEW, FREQUENCY_STABLE, STABLE} == set(d.status.tolist())
    for i in range(len(d.order)):
        below = d.order == d.order[i] - 1
        # the changes are relative to the pole below
        df = np.abs(d.frequency_hz[i] / d.frequency_hz[below] - 1)
        dz = np.abs(d.damping_ratio[i] / d.damping_ratio[below] - 1)
        near_f = df < STABLE_FREQUENCY
        both = near_f & (dz < STABLE_DAMPING)
        if d.status[i] == STABLE:
            assert both.any()
        elif d.status[i] == FREQUENCY_STABLE:
            assert near_f.any()
        else:
            assert not near_f.any()
    # a mode's column is stable at a third of the orders or more
    for k, m in enumerate(d.modes):
        assert m.stable_orders == np.count_nonzero((d.mode == k) & (d.status == STABLE))
        assert m.stable_orders >= math.ceil(d.max_order / 3)


def test_one_mode_is_the_most_flexible_not_the_first():
    """500 Hz: k 2 MN/m, zeta 5 % (peak |H| 1/(2 k zeta) = 5.0 um/N); 1300 Hz: stiffer
    (3 MN/m) but lightly damped (1 %), so its peak, 16.7 um/N, is the larger."""
    known = ModalFit((500.0, 1300.0), (0.05, 0.01), (2.0e6, 3.0e6))
    diagram = stabilisation(synthetic(known, 0.01))
    assert len(diagram.modes) == 2
    fit, _ = fit_modes(diagram, 1)
    assert fit.frequency_hz[0] == pytest.approx(1300.0, rel=1e-3)
    assert fit.modal_stiffness_n_m[0] == pytest.approx(3.0e6, rel=0.05)
    # one mode leaves the other's share of the FRF unexplained, and says so
    assert fit.quality["relative_residual"] > 0.1 and "warning" in fit.quality
    both, _ = fit_modes(diagram)
    assert both.quality["relative_residual"] < 0.02 and "warning" not in both.quality


def test_two_of_three_modes_are_the_two_most_flexible():
    """Peak receptances 1/(2 k zeta): 12.5, 0.83 and 25 um/N, so the first and the
    third, in that order of frequency."""
    known = ModalFit((480.0, 1500.0, 3100.0), (0.02, 0.03, 0.005), (2.0e6, 2.0e7, 4.0e6))
    d = stabilisation(synthetic(known, 0.01))
    assert len(d.modes) == 3
    fit, _ = fit_modes(d, 2)
    assert fit.frequency_hz == pytest.approx((480.0, 3100.0), rel=1e-3)
    assert fit.modal_stiffness_n_m == pytest.approx((2.0e6, 4.0e6), rel=0.05)


def test_more_modes_than_the_diagram_finds_is_refused():
    with pytest.raises(ParameterError, match="2 stable mode.* fewer than the 3 modes"):
        fit_frf(synthetic(KNOWN["two modes"], 0.01), 3)


def test_max_order_must_fit_the_band():
    short = MeasuredFrf(np.arange(100.0, 160.0, 1.0), np.ones(60) * 1e-7)
    with pytest.raises(ParameterError, match="max_order = 20 needs at least 82 lines"):
        stabilisation(short)
    with pytest.raises(ParameterError, match=r"max_order = 5 .*\[10, 200\]"):
        stabilisation(short, max_order=5)


def test_the_command_writes_the_diagram_and_reports_it(tmp_path, capsys):
    path = tmp_path / "three.csv"
    path.write_text(frf_csv_text(synthetic(KNOWN["three modes"], 0.01), "three modes"))
    out = tmp_path / "fit"
    assert main(["fit-frf", str(path), "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert len(s["modes"]) == 3
    diagram = s["quality"]["stabilisation"]
    assert [round(m["frequency_hz"]) for m in diagram["modes"]] == [480, 1500, 3100]
    assert diagram["stable_frequency"] == STABLE_FREQUENCY
    assert (out / "stabilisation.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert s["files"]["stabilisation"] == str(out / "stabilisation.png")


@pytest.mark.parametrize(("argv", "name"), [
    (["--max-order", "5"], "--max-order = 5"),
    (["--modes", "9"], "--modes = 9"),
])
def test_bad_orders_and_modes_are_one_line(tmp_path, capsys, argv, name):
    path = tmp_path / "two.csv"
    path.write_text(frf_csv_text(synthetic(KNOWN["two modes"], 0.0), "two modes"))
    out = tmp_path / "out"
    assert_one_line_error(main, ["fit-frf", str(path), *argv, "--out", str(out)], out,
                          name, capsys)


def test_a_noise_file_is_one_line(tmp_path, capsys):
    path = tmp_path / "noise.csv"
    path.write_text(frf_csv_text(noise_only(), "noise"))
    out = tmp_path / "out"
    assert_one_line_error(main, ["fit-frf", str(path), "--out", str(out)], out,
                          "no stable mode in the band", capsys)
