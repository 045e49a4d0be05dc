"""Measured FRFs: reading (CSV, UFF58), the sdypy-EMA fit (its stabilisation diagram:
tests/test_frf_stabilisation.py), lobes straight from the FRF,
and the command line (fit-frf, lobes --frf --analytic)."""

from __future__ import annotations

import json
import math
import runpy
from pathlib import Path

import numpy as np
import pytest
import pyuff
from cli_output import assert_one_line_error, json_out

from boringbar.analysis.frf_fit import fit_frf
from boringbar.cli.main import main
from boringbar.model.bar import published_bar
from boringbar.model.measured_frf import (
    FrfFileError,
    MeasuredFrf,
    frf_csv_text,
    read_frf,
    uff58_dict,
)
from boringbar.model.modal_fit import ModalFit
from boringbar.reference.linear import tip_frf
from boringbar.reference.stability import limit_at_speeds, min_limit, sampled_limits

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"
MEASURED = EXAMPLES / "measured_tip_frf.csv"
KR = 850e6
GENERATOR = runpy.run_path(str(EXAMPLES / "make_measured_frf.py"))


def two_modes(noise: float, seed: int = 1) -> tuple[ModalFit, MeasuredFrf]:
    known = ModalFit((500.0, 2300.0), (0.02, 0.03), (2.0e6, 5.0e7))
    f = np.arange(50.0, 4000.0, 0.5)
    rng = np.random.default_rng(seed)
    n = (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / math.sqrt(2)
    return known, MeasuredFrf(f, known.tip_frf(f) * (1 + noise * n))


def rel(a, b) -> np.ndarray:
    return np.abs(np.asarray(a) / np.asarray(b) - 1)


# --- the fit --------------------------------------------------------------------------
def test_the_fit_recovers_a_known_two_mode_bar_through_one_percent_noise():
    known, measured = two_modes(0.01)
    fit, fitted = fit_frf(measured, 2)
    assert rel(fit.frequency_hz, known.frequency_hz).max() < 0.01
    assert rel(fit.modal_stiffness_n_m, known.modal_stiffness_n_m).max() < 0.02
    assert rel(fit.damping_ratio, known.damping_ratio).max() < 0.01
    assert fit.source["method"].startswith("sdypy-EMA LSCE")  # the band starts near 0 Hz
    assert fit.quality["relative_residual"] < 0.02  # the noise, not the model
    assert np.abs(fitted - measured.receptance).max() < 0.05 * np.abs(fitted).max()


def test_the_fit_is_exact_without_noise():
    known, measured = two_modes(0.0)
    fit, _ = fit_frf(measured, 2)
    assert rel(fit.frequency_hz, known.frequency_hz).max() < 1e-5
    assert rel(fit.damping_ratio, known.damping_ratio).max() < 1e-4
    assert rel(fit.modal_stiffness_n_m, known.modal_stiffness_n_m).max() < 1e-3


def test_round_trip_a_boringbar_frf_gives_the_bars_own_modes():
    bar = published_bar(True, 2)
    f = np.arange(100.0, 4000.0, 0.5)
    fit, _ = fit_frf(MeasuredFrf(f, tip_frf(bar, 2 * math.pi * f)), 2)
    assert rel(fit.frequency_hz, bar.omegas_rad_s / (2 * math.pi)).max() < 1e-4
    assert rel(fit.damping_ratio, bar.damping_ratio).max() < 1e-3
    assert rel(fit.modal_stiffness_n_m, bar.stiffness_n_m / bar.psi_tip**2).max() < 1e-3


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_more_noise_draws_stay_within_the_issue_tolerances(seed):
    known, measured = two_modes(0.01, seed)
    fit, _ = fit_frf(measured, 2)
    assert rel(fit.frequency_hz, known.frequency_hz).max() < 0.01
    assert rel(fit.damping_ratio, known.damping_ratio).max() < 0.01
    assert rel(fit.modal_stiffness_n_m, known.modal_stiffness_n_m).max() < 0.02


def test_a_band_away_from_0_hz_takes_lscf():
    known, measured = two_modes(0.0)
    fit, _ = fit_frf(measured, 1, band_hz=(1500.0, 3500.0))
    assert fit.source["method"].startswith("sdypy-EMA LSCF")
    assert fit.frequency_hz[0] == pytest.approx(2300.0, rel=1e-4)


# --- lobes straight from the FRF ---------------------------------------------------------
def test_lobes_from_a_single_mode_frf_meet_the_closed_form():
    k, zeta = 2.0e6, 0.02
    f = np.arange(100.0, 1000.0, 0.05)
    g = ModalFit((500.0,), (zeta,), (k,)).tip_frf(f)
    low = sampled_limits(2 * math.pi * f, g, [1000.0], KR)["min_limit"]
    assert low == pytest.approx(2 * k * zeta * (1 + zeta) / KR, rel=1e-4)


def test_lobes_from_the_noisy_example_meet_the_closed_form_of_its_first_mode():
    modes = GENERATOR["MODES"]
    m = read_frf(MEASURED)
    low = sampled_limits(m.omega, m.receptance, [1000.0], KR)["min_limit"]
    k, zeta = modes.modal_stiffness_n_m[0], modes.damping_ratio[0]
    assert low == pytest.approx(2 * k * zeta * (1 + zeta) / KR, rel=0.01)


def test_sampled_lobes_equal_the_models_lobes():
    bar = published_bar(True, 2)
    w = np.geomspace(2 * math.pi * 200, 2 * math.pi * 4000, 200_000)
    speeds = [900.0, 1250.0, 2000.0, 4500.0]
    s = sampled_limits(w, tip_frf(bar, w), speeds, KR)
    np.testing.assert_allclose(s["limit"], limit_at_speeds(bar, speeds, KR), rtol=1e-5)
    assert s["min_limit"] == pytest.approx(min_limit(bar, KR), rel=1e-6)


# --- files ------------------------------------------------------------------------------
def test_csv_and_uff58_round_trip(tmp_path):
    _, measured = two_modes(0.01)
    csv = tmp_path / "tap.csv"
    csv.write_text(frf_csv_text(measured, "a tap test"))
    back = read_frf(csv)
    np.testing.assert_array_equal(back.frequency_hz, measured.frequency_hz)
    np.testing.assert_array_equal(back.receptance, measured.receptance)
    uff = tmp_path / "tap.uff"
    pyuff.UFF(str(uff)).write_sets([uff58_dict(measured)], mode="overwrite")
    back = read_frf(uff)
    np.testing.assert_allclose(back.frequency_hz, measured.frequency_hz, rtol=1e-12)
    np.testing.assert_allclose(back.receptance, measured.receptance, rtol=1e-10)  # ASCII UFF


def test_uff58_accelerance_is_turned_into_receptance(tmp_path):
    _, measured = two_modes(0.0)
    accel = MeasuredFrf(measured.frequency_hz, -measured.omega**2 * measured.receptance)
    d = uff58_dict(accel)
    d["ordinate_spec_data_type"] = 12
    path = tmp_path / "accel.unv"
    pyuff.UFF(str(path)).write_sets([d], mode="overwrite")
    np.testing.assert_allclose(read_frf(path).receptance, measured.receptance, rtol=1e-10)


@pytest.mark.parametrize(("text", "words"), [
    ("1,2,3\n" * 30 + "4,5\n", "line 31 has 2 columns"),
    ("f [Hz],re [m/N],im [m/N]\n" + "".join(f"{i},1,x\n" for i in range(30)),
     "line 2 = '0,1,x'"),
    ("".join(f"{30 - i},1,1\n" for i in range(30)), "strictly increasing"),
    ("".join(f"{i},1,1\n" for i in range(5)), "5 frequency lines"),
])
def test_bad_csv_is_one_line(tmp_path, text, words):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(FrfFileError) as err:
        read_frf(path)
    assert words in str(err.value) and "\n" not in str(err.value)


# --- the command line ------------------------------------------------------------------
def test_fit_frf_command(tmp_path, capsys):
    out = tmp_path / "fit"
    assert main(["fit-frf", str(MEASURED), "--modes", "2", "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    modes = GENERATOR["MODES"]
    got = [m["frequency_hz"] for m in s["modes"]]
    assert rel(got, modes.frequency_hz).max() < 0.01
    assert {"frequency_hz", "damping_ratio", "modal_stiffness_n_m"} <= s["modes"][0].keys()
    assert ModalFit.read(out / "modal_fit.json").frequency_hz == tuple(got)
    for png in ("fit.png", "stabilisation.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the fit then drives a simulation in place of the FE bar
    assert main(["simulate", "--frf", str(out / "modal_fit.json"), "--frf-ball-ratio", "0.55",
                 "--duration-s", "0.02", "--out", str(tmp_path / "run"), "--json"]) == 0
    assert json_out(capsys)["natural_frequency_hz"] == pytest.approx(got[0])
    # a comparison from the fit takes the bars whose ratios are given: the solid bar
    # alone without them, and the ball beside it with its ratio
    fit = str(out / "modal_fit.json")
    assert main(["lobes", "--analytic", "--frf", fit, "--rpm", "1200", "--out",
                 str(tmp_path / "la"), "--json"]) == 0
    assert [c["case"] for c in json_out(capsys)["cases"]] == ["solid"]
    assert main(["lobes", "--analytic", "--frf", fit, "--frf-ball-ratio", "0.55", "--rpm",
                 "1200", "--out", str(tmp_path / "lb"), "--json"]) == 0
    cases = [c["case"].split(" ")[0] for c in json_out(capsys)["cases"]]
    assert cases[0] == "solid" and "ball" in cases and "tmd" not in cases


def test_lobes_analytic_from_the_measured_frf(tmp_path, capsys):
    assert main(["lobes", "--analytic", "--frf", str(MEASURED), "--rpm", "1000:3000:500",
                 "--out", str(tmp_path), "--json"]) == 0
    s = json_out(capsys)
    (case,) = s["cases"]
    modes = GENERATOR["MODES"]
    k, zeta = modes.modal_stiffness_n_m[0], modes.damping_ratio[0]
    assert case["min_limit_m"] == pytest.approx(2 * k * zeta * (1 + zeta) / KR, rel=0.01)
    assert all(sp["limit_m"] >= case["min_limit_m"] for sp in case["speeds"])
    assert json.loads((tmp_path / "lobes_analytic.json").read_text())["cases"] == s["cases"]


def test_lobes_analytic_of_the_published_bars(tmp_path, capsys):
    assert main(["lobes", "--analytic", "--rpm", "1200", "--out", str(tmp_path),
                 "--json"]) == 0
    s = json_out(capsys)
    by = {c["case"].split(" ")[0]: c for c in s["cases"]}
    assert set(by) == {"solid", "tmd", "ball"}  # the four free-ball cases share one FRF
    assert by["tmd"]["min_limit_m"] > 10 * by["solid"]["min_limit_m"]


@pytest.mark.parametrize(("argv", "name"), [
    (["fit-frf", "missing.csv"], "no such file"),
    (["fit-frf", "tap.xlsx"], "unknown FRF file type"),
    (["fit-frf", str(MEASURED), "--modes", "3"], "fewer than the 3 modes"),
    (["fit-frf", str(MEASURED), "--band-hz", "900:100"], "--band-hz"),
    (["simulate", "--frf", str(MEASURED)], "fit it first"),
    (["lobes", "--analytic", "--frf", str(MEASURED), "--planes", "2"], "measure it oriented"),
    (["lobes", "--analytic", "--frf", str(MEASURED), "--lead-angle-deg", "30"],
     "measure it oriented"),
])
def test_bad_frf_input_is_one_line(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, [*argv, "--out", str(out)], out, name, capsys)


def test_the_command_finds_the_modes_and_one_mode_is_the_most_flexible(tmp_path, capsys):
    """A clean FRF of a flexible 612 Hz mode and a stiffer 1879 Hz one: with no --modes
    the fit takes both modes of the stabilisation diagram; --modes 1 takes the
    flexible one (the one that sets chatter) and says that one mode leaves a third
    of the FRF unexplained."""
    f = np.linspace(50.0, 3000.0, 2951)
    h = ModalFit((612.0, 1879.0), (0.02, 0.02), (1e6, 5e6)).tip_frf(f)
    path = tmp_path / "two.csv"
    np.savetxt(path, np.c_[f, h.real, h.imag], delimiter=",",
               header="frequency_hz,real_m_per_n,imag_m_per_n", comments="")
    assert main(["fit-frf", str(path), "--out", str(tmp_path / "a"), "--json"]) == 0
    both = json_out(capsys)
    assert rel([m["frequency_hz"] for m in both["modes"]], [612.0, 1879.0]).max() < 1e-3
    assert both["quality"]["relative_residual"] < 1e-2 and "warning" not in both["quality"]
    assert main(["fit-frf", str(path), "--modes", "1", "--out", str(tmp_path / "b")]) == 0
    text = capsys.readouterr().out
    assert "612.00" in text and "1879" not in text
    assert "-- warning: relative residual 0.33 > 0.1" in text
