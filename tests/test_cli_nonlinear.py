"""``boringbar bifurcation``, ``basins`` and ``sensitivity`` end to end, on real
files (STYLE.md tier 4).

Tiny problems (0.1-0.2 s runs, a few values, 3 x 3 grids): here only what the
commands promise (files, JSON, exit codes, one-line errors); the analyses are
tested in test_bifurcation.py and test_basins.py.
"""

import json
from pathlib import Path

import pytest
import xarray as xr
from cli_output import assert_one_line_error, json_out

from boringbar.cli.main import main

PNG = b"\x89PNG\r\n\x1a\n"


def _files_ok(files: dict, out) -> None:
    assert all(Path(path).stat().st_size > 0 for path in files.values())
    assert Path(files["png"]).read_bytes()[:8] == PNG
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries


def test_bifurcation_force_json_and_files(tmp_path, capsys):
    out = tmp_path / "bif"
    rc = main(["bifurcation", "--force-n", "10:14:2", "--duration-s", "0.2", "--out", str(out),
               "--json"])
    assert rc == 0
    s = json_out(capsys)
    assert {"parameter", "units", "values", "forward", "backward", "verdicts",
            "hysteresis_ranges", "files"} <= s.keys()
    assert s["parameter"] == "force" and s["units"] == "N"
    assert s["values"] == pytest.approx([10, 12, 14])
    for direction in ("forward", "backward"):
        assert len(s[direction]) == 3 and len(s["verdicts"][direction]) == 3
        assert all(len(w) > 10 and all(abs(x) < 5e-3 for x in w) for w in s[direction])
    assert all(len(r) == 2 and r[0] <= r[1] for r in s["hysteresis_ranges"])
    assert s["files"] == {"netcdf": str(out / "bifurcation.nc"),
                          "png": str(out / "bifurcation.png")}
    _files_ok(s["files"], out)
    with xr.open_dataset(out / "bifurcation.nc") as ds:
        assert list(ds["direction"].values) == ["forward", "backward"]
        assert ds.sizes["value"] == 3 and ds["tip_displacement_m"].attrs["units"] == "m"
        assert json.loads(ds.attrs["hysteresis_ranges"]) == s["hysteresis_ranges"]


def test_bifurcation_gap_sweep_forward_only_quiet(tmp_path, capsys):
    out = tmp_path / "gap"
    rc = main(["bifurcation", "--gap-mm", "0.1:0.3:0.1", "--force-n", "10", "--ratio", "1.01",
               "--duration-s", "0.1", "--no-backward", "--quiet", "--out", str(out)])
    assert rc == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    with xr.open_dataset(out / "bifurcation.nc") as ds:
        assert list(ds["direction"].values) == ["forward"]
        assert ds["value"].values == pytest.approx([0.1e-3, 0.2e-3, 0.3e-3])
        assert ds.attrs["parameter"] == "gap" and ds.attrs["units"] == "m"
        config = json.loads(ds.attrs["config"])
        assert [c["damper"]["gap_m"] for c in config["systems"]] == pytest.approx(
            [0.1e-3, 0.2e-3, 0.3e-3])
        assert config["base_forcing"]["amplitude_n"] == 10
    assert (out / "bifurcation.png").read_bytes()[:8] == PNG


def test_basins_json_fractions_and_files(tmp_path, capsys):
    out = tmp_path / "bas"
    rc = main(["basins", "--displacement-mm", "-1:1:3", "--velocity-m-s", "-1:1:3",
               "--duration-s", "0.2", "--workers", "2", "--out", str(out), "--json"])
    assert rc == 0
    s = json_out(capsys)
    assert {"attractors", "grid", "forcing", "poincare_from", "files"} <= s.keys()
    assert s["grid"]["displacement_m"] == pytest.approx([-1e-3, 1e-3, 3])
    assert s["grid"]["velocity_m_s"] == pytest.approx([-1, 1, 3])
    fractions = [a["fraction"] for a in s["attractors"]]
    assert sum(fractions) == pytest.approx(1.0)
    assert sum(a["count"] for a in s["attractors"]) == 9
    for a in s["attractors"]:
        assert {"pattern", "period", "rms_tip_m", "representative"} <= a.keys()
    p = s["poincare_from"]
    assert p["tip_displacement_m"] == pytest.approx(0.5e-3) and p["tip_velocity_m_s"] == 0.5
    assert p["n_samples"] > 10 and isinstance(p["verdict"], str)
    _files_ok(s["files"], out)
    with xr.open_dataset(out / "basins.nc") as ds:
        assert ds["attractor"].shape == (3, 3)
        assert ds.sizes["poincare_sample"] == p["n_samples"]


def test_sensitivity_restitution_with_cuts(tmp_path, capsys):
    out = tmp_path / "sens"
    rc = main(["sensitivity", "restitution", "--values", "0.6,0.8", "--ratios", "0.99,1.01",
               "--duration-s", "0.2", "--depths-mm", "0.05,0.1", "--out", str(out), "--json"])
    assert rc == 0
    s = json_out(capsys)
    assert s["kind"] == "restitution" and s["values"] == [0.6, 0.8]
    assert len(s["harmonic"]) == 2
    for h in s["harmonic"]:
        assert h["ratio"] == pytest.approx([0.99, 1.01]) and len(h["rms_tip_m"]) == 2
        assert all(r > 0 for r in h["rms_tip_m"])
    cuts = s["cuts"]
    assert cuts["rpm"] == 1200 and cuts["depth_m"] == pytest.approx([0.05e-3, 0.1e-3])
    assert [len(r["chatter"]) for r in cuts["results"]] == [2, 2]
    _files_ok(s["files"], out)
    with xr.open_dataset(out / "sensitivity.nc") as ds:
        assert list(ds["restitution"].values) == [0.6, 0.8]
        assert {"rms_tip_m", "cut_chatter", "cut_amplitude_m"} <= set(ds.data_vars)


def test_sensitivity_from_starts_text_and_files(tmp_path, capsys):
    rc = main(["sensitivity", "ball", "--starts", "2", "--ratios", "1.0", "--duration-s", "0.1",
               "--preset", "paper", "--out", str(tmp_path)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "tip RMS (mm) over 3 starts: mean [least, largest]" in text
    with xr.open_dataset(tmp_path / "sensitivity.nc") as ds:
        assert ds["rms_tip_m_starts"].shape == (2, 2, 1, 1)
    assert (tmp_path / "sensitivity.png").read_bytes()[:8] == PNG


def test_sensitivity_initial_text(tmp_path, capsys):
    rc = main(["sensitivity", "initial", "--values", "0.5/0.5,0/0/0.1/0", "--ratios", "1.0",
               "--duration-s", "0.1", "--out", str(tmp_path)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "initial, F0 = 10 N" in text and "W0=0.0005m" in text
    assert (tmp_path / "sensitivity.png").read_bytes()[:8] == PNG


@pytest.mark.parametrize("argv, name", [
    (["bifurcation", "--force-n", "5:1:1"], "--force-n"),
    (["bifurcation", "--force-n", "5:10:1", "--ratio", "0.9:1.1:0.01"], "--ratio"),
    (["bifurcation", "--force-n", "20"], "--force-n"),
    (["bifurcation", "--force-n", "5,7,6"], "--force-n"),
    (["bifurcation", "--restitution", "0.5:1.2:0.1"], "--restitution"),
    (["bifurcation", "--bar", "solid", "--gap-mm", "0.1:0.3:0.1"], "--gap-mm"),
    (["bifurcation", "--steady-fraction", "0"], "--steady-fraction"),
    (["basins", "--displacement-mm", "1:2"], "--displacement-mm"),
    (["basins", "--velocity-m-s", "-1:1:0"], "--velocity-m-s"),
    (["basins", "--displacement-mm", "1:-1:3"], "--displacement-mm"),
    (["basins", "--poincare-from", "0.5"], "--poincare-from"),
    (["sensitivity", "restitution", "--values", "0.6,1.5"], "--values"),
    (["sensitivity", "restitution", "--restitution", "0.6"], "--restitution"),
    (["sensitivity", "friction_number", "--friction", "off"], "--friction"),
    (["sensitivity", "ball", "--bar", "solid"], "--bar"),
    (["sensitivity", "ball", "--kr-mpa", "800"], "--kr-mpa"),
    (["sensitivity", "initial", "--values", "1,2"], "--values"),
    (["sensitivity", "initial", "--starts", "4"], "--starts"),
    (["sensitivity", "boat"], "KIND"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, argv + ["--out", str(out)], out, name, capsys)
