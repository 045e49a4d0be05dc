"""A measured FRF's units: read from its CSV header (each header style gives the example's
receptance back), refused when they cannot be read, and a fit or an FRF whose stiffness
or frequencies no boring bar has is warned about (docs/frf.md)."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from cli_output import assert_one_line_error, json_out

from boringbar.analysis.frf_fit import fit_frf
from boringbar.cli.main import main
from boringbar.model.frf_units import ImplausibleFrfWarning, implausible_frf
from boringbar.model.measured_frf import FrfFileError, read_frf
from boringbar.model.modal_fit import ModalFit

MEASURED = Path(__file__).resolve().parents[1] / "examples" / "systems" / "measured_tip_frf.csv"
G = 9.80665  # m/s^2 per g


def example() -> tuple[np.ndarray, np.ndarray]:
    """The example's frequency (Hz) and receptance (m/N), parsed here without the reader:
    its lines that are neither comments nor its header."""
    lines = [line for line in MEASURED.read_text().splitlines() if not line.startswith("#")]
    assert lines[0] == "frequency_hz,real_m_per_n,imag_m_per_n"
    a = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return a[:, 0], a[:, 1] + 1j * a[:, 2]


F, H = example()
W = 2 * np.pi * F


def write(path: Path, header: str | None, *columns, encoding: str = "utf-8") -> Path:
    lines = ["# a tap test"] + ([header] if header is not None else [])
    lines += [",".join(repr(float(v)) for v in row) for row in zip(*columns, strict=True)]
    path.write_text("\n".join(lines) + "\n", encoding=encoding)
    return path


#: header -> the file's three columns, converted here from the example (Hz, m/N)
STYLES = {
    "f [kHz], Re [um/N], Im [um/N]": lambda: (F / 1e3, H.real * 1e6, H.imag * 1e6),
    "freq (Hz), magnitude (mm/N), phase (deg)":
        lambda: (F, np.abs(H) * 1e3, np.angle(H) * 180 / math.pi),
    "frequency_hz,magnitude_m_per_n,phase_rad": lambda: (F, np.abs(H), np.angle(H)),
    "Frequency [Hz], Re [µm/N], Im [μm/N]": lambda: (F, H.real * 1e6, H.imag * 1e6),
    "frequency_khz,real_mm_per_n,imag_mm_per_n": lambda: (F / 1e3, H.real * 1e3, H.imag * 1e3),
    "f [Hz], Re [micron/N], Im [microns/N]": lambda: (F, H.real * 1e6, H.imag * 1e6),
    "omega [rad/s], Re [m/N], Im [m/N]": lambda: (W, H.real, H.imag),
    "f/Hz, Re/(nm/N), Im/(nm/N)": lambda: (F, H.real * 1e9, H.imag * 1e9),
    "Re [mm/N], f [Hz], Im [mm/N]": lambda: (H.real * 1e3, F, H.imag * 1e3),
    "frequency_hz,mobility_real_m_s_per_n,mobility_imag_m_s_per_n":
        lambda: (F, (1j * W * H).real, (1j * W * H).imag),
    "f [Hz], Re [(m/s)/N], Im [m/(N s)]": lambda: (F, (1j * W * H).real, (1j * W * H).imag),
    "frequency_hz,accelerance_real_m_s2_per_n,accelerance_imag_m_s2_per_n":
        lambda: (F, (-W**2 * H).real, (-W**2 * H).imag),
    "f [Hz], |H| [(m/s^2)/N], phase [deg]":
        lambda: (F, np.abs(W**2 * H), np.angle(-W**2 * H, deg=True)),
    "inertance f [Hz], inertance Re [g/N], inertance Im [g/N]":
        lambda: (F, (-W**2 * H).real / G, (-W**2 * H).imag / G),
}


@pytest.mark.parametrize("header", STYLES)
def test_every_header_style_reads_the_examples_receptance(tmp_path, header):
    frf = read_frf(write(tmp_path / "tap.csv", header, *STYLES[header]()))
    np.testing.assert_allclose(frf.frequency_hz, F, rtol=1e-14)
    np.testing.assert_allclose(frf.receptance, H, rtol=1e-12, atol=0)
    assert frf.source["units"].endswith("(from the header)")


def test_the_source_says_how_the_file_was_read(tmp_path):
    khz = read_frf(write(tmp_path / "a.csv", "f [kHz], Re [um/N], Im [um/N]",
                         *STYLES["f [kHz], Re [um/N], Im [um/N]"]()))
    assert khz.source["units"] == "frequency kHz, real um/N, imag um/N (from the header)"
    assert khz.source["conversion"] == ("frequency x 1000 (kHz to Hz); receptance x 1e-06 "
                                        "(um/N to m/N)")
    assert khz.source["ordinate"] == "receptance"
    header = "frequency_hz,accelerance_real_m_s2_per_n,accelerance_imag_m_s2_per_n"
    acc = read_frf(write(tmp_path / "b.csv", header, *STYLES[header]()))
    assert acc.source["ordinate"] == "accelerance"
    assert acc.source["conversion"] == "receptance = accelerance / -omega^2"
    polar = read_frf(write(tmp_path / "c.csv", "freq (Hz), magnitude (mm/N), phase (deg)",
                           *STYLES["freq (Hz), magnitude (mm/N), phase (deg)"]()))
    assert "H = magnitude exp(i phase), phase x" in polar.source["conversion"]
    assert read_frf(MEASURED).source["conversion"] == "none"


def test_a_file_without_a_header_is_hz_and_m_per_n_and_says_so(tmp_path):
    frf = read_frf(write(tmp_path / "bare.csv", None, F, H.real, H.imag))
    np.testing.assert_array_equal(frf.frequency_hz, F)
    np.testing.assert_array_equal(frf.receptance, H)
    assert frf.source["units"] == "frequency Hz, real m/N, imag m/N assumed (no header)"


def test_blank_rows_are_skipped(tmp_path):
    path = write(tmp_path / "tap.csv", "f [Hz], Re [m/N], Im [m/N]", F, H.real, H.imag)
    path.write_text(",,\n  \n" + path.read_text() + ",,\n")
    np.testing.assert_array_equal(read_frf(path).receptance, H)


def test_a_latin1_file_with_a_micro_sign_and_a_byte_order_mark(tmp_path):
    cols = (F, H.real * 1e6, H.imag * 1e6)
    old = read_frf(write(tmp_path / "a.csv", "f [Hz], Re [µm/N], Im [µm/N]", *cols,
                         encoding="latin-1"))
    bom = read_frf(write(tmp_path / "b.csv", "f [Hz], Re [µm/N], Im [µm/N]", *cols,
                         encoding="utf-8-sig"))
    for frf in (old, bom):
        np.testing.assert_allclose(frf.receptance, H, rtol=1e-12, atol=0)


def test_mobility_at_0_hz_drops_that_line(tmp_path):
    f = np.r_[0.0, F]
    h = np.r_[H[0], H]
    frf = read_frf(write(tmp_path / "m.csv", "f [Hz], Re [(mm/s)/N], Im [(mm/s)/N]", f,
                         (1j * 2 * np.pi * f * h).real * 1e3, (1j * 2 * np.pi * f * h).imag * 1e3))
    np.testing.assert_array_equal(frf.frequency_hz, F)
    np.testing.assert_allclose(frf.receptance, H, rtol=1e-12, atol=0)
    assert "1 line(s) at 0 Hz dropped" in frf.source["conversion"]


@pytest.mark.parametrize(("header", "words"), [
    ("f [Hz],Re [uN],Im [uN]", "column 2 'Re [uN]': unit 'uN' is not one of the real units"),
    ("frequency,real,imag", "column 1 'frequency' states no unit"),
    ("frequency_hz,real,imaginary", "column 2 'real' states no unit"),
    ("f [1/s],Re [m/N],Im [m/N]", "column 1 'f [1/s]': unit '1/s'"),
    ("f [Hz],Re [N/m],Im [N/m]", "column 2 'Re [N/m]'"),
    ("f [Hz],mag [dB],phase [deg]", "column 2 'mag [dB]'"),
    ("f [Hz],mag [m/N],phase [grad]", "column 3 'phase [grad]'"),
    ("f [Hz],H [m/N],Im [m/N]", "column 2 'H [m/N]' names no column"),
    ("f [Hz],Re [m/N],Im [mm/N]", "two units (m/N, mm/N)"),
    ("f [Hz],accelerance Re [m/N],accelerance Im [m/N]",
     "column 2 'accelerance Re [m/N]': the name says accelerance"),
    ("f [Hz],Re [m/N],phase [deg]", "lack imag"),
    ("f [Hz],f [kHz],Re [m/N]", "columns 1 and 2 ('f [Hz]', 'f [kHz]') are both frequency"),
    ("f [Hz],Re [m/N],Im [m/N],coherence", "the header has 4 column(s)"),
])
def test_an_unreadable_header_is_refused_naming_the_column(tmp_path, header, words):
    cells = header.split(",")
    path = write(tmp_path / "bad.csv", header, *([F] * len(cells)))
    with pytest.raises(FrfFileError) as err:
        read_frf(path)
    message = str(err.value)
    assert words in message and "\n" not in message
    assert message.startswith(f"{path}: line 2 (header): ")


def test_the_refusal_lists_what_is_allowed(tmp_path):
    path = write(tmp_path / "bad.csv", "f [Hz],Re [inch/lbf],Im [inch/lbf]", F, F, F)
    with pytest.raises(FrfFileError, match=r"m/N, mm/N, um/N .* \(m/s\)/N; .* g/N"):
        read_frf(path)


# --- plausibility ------------------------------------------------------------------------
def test_static_stiffness_and_what_no_boring_bar_has():
    fit = ModalFit((480.0, 2350.0), (0.02, 0.03), (2.2e6, 6.0e7))
    assert fit.static_stiffness_n_m == pytest.approx(1 / (1 / 2.2e6 + 1 / 6.0e7), rel=1e-15)
    assert fit.implausible() == []
    (soft,) = ModalFit((480.0,), (0.02,), (2.2,)).implausible()
    assert soft.startswith("static tip stiffness 2.2 N/m is outside 1e5 to 1e9 N/m")
    (slow,) = ModalFit((0.48, 2.35), (0.02, 0.03), (2.2e6, 6.0e7)).implausible()
    assert slow.startswith("natural frequency 0.48, 2.35 Hz outside 20 to 20000 Hz")
    assert implausible_frf(F, H) == []
    assert "least dynamic stiffness" in implausible_frf(F, H * 1e6)[0]
    assert "highest peak 0.48 Hz" in implausible_frf(F / 1e3, H)[0]


def test_um_per_n_data_declared_m_per_n_warns_on_the_fit(tmp_path):
    wrong = read_frf(write(tmp_path / "wrong.csv", "frequency_hz,real_m_per_n,imag_m_per_n",
                           F, H.real * 1e6, H.imag * 1e6))
    soft = r"static tip stiffness 2\.1\d N/m is outside 1e5 to 1e9 N/m"
    with pytest.warns(ImplausibleFrfWarning, match=soft) as caught:
        fit, _ = fit_frf(wrong, 2)
    assert len(caught) == 1
    assert ("are the FRF's units right? It was read as frequency Hz, real m/N, imag m/N (from "
            "the header)") in str(caught[0].message)
    assert fit.quality["implausible"] == str(caught[0].message)


def test_the_example_fits_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error", ImplausibleFrfWarning)
        fit, _ = fit_frf(read_frf(MEASURED), 2)
    assert "implausible" not in fit.quality


# --- the command line --------------------------------------------------------------------
@pytest.mark.parametrize("command", [["fit-frf", "{}"], ["lobes", "--analytic", "--frf", "{}"]])
def test_an_unreadable_header_on_the_command_line_is_one_line(tmp_path, capsys, command):
    path = write(tmp_path / "tap.csv", "f [Hz],Re [uN],Im [uN]", F, H.real, H.imag)
    out = tmp_path / "out"
    argv = [a.format(path) for a in command] + ["--out", str(out)]
    assert_one_line_error(main, argv, out, "column 2 'Re [uN]'", capsys)


def test_fit_frf_in_the_wrong_units_warns_in_one_line(tmp_path, capsys):
    path = write(tmp_path / "tap.csv", "frequency_hz,real_m_per_n,imag_m_per_n",
                 F, H.real * 1e6, H.imag * 1e6)
    out = tmp_path / "fit"
    assert main(["fit-frf", str(path), "--modes", "2", "--out", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert line.startswith("boringbar: warning: ") and "static tip stiffness" in line
    summary = json.loads(captured.out)
    assert summary["quality"]["implausible"] in line
    assert json.loads((out / "modal_fit.json").read_text())["source"]["units"] == (
        "frequency Hz, real m/N, imag m/N (from the header)")


def test_lobes_from_an_frf_in_the_wrong_units_warn_in_one_line(tmp_path, capsys):
    path = write(tmp_path / "tap.csv", "f [Hz], Re [m/N], Im [m/N]", F / 1e3, H.real, H.imag)
    assert main(["lobes", "--analytic", "--frf", str(path), "--rpm", "1000",
                 "--out", str(tmp_path / "lobes"), "--json"]) == 0
    captured = capsys.readouterr()
    (line,) = captured.err.strip().splitlines()
    assert line.startswith("boringbar: warning: ") and "highest peak 0.48 Hz" in line
    assert json_out_of(captured.out)["measured_frf"]["implausible"] in line


def test_lobes_from_the_example_say_how_it_was_read_and_do_not_warn(tmp_path, capsys):
    assert main(["lobes", "--analytic", "--frf", str(MEASURED), "--rpm", "1000",
                 "--out", str(tmp_path), "--json"]) == 0
    s = json_out(capsys)
    assert s["measured_frf"]["units"] == "frequency Hz, real m/N, imag m/N (from the header)"
    assert "implausible" not in s["measured_frf"]


def json_out_of(stdout: str) -> dict:
    (line,) = stdout.strip().splitlines()
    return json.loads(line)
