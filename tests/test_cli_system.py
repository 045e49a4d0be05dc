"""Your own bar on the command line: --system, --frf, ``boringbar modes`` and the
study files' system key, end to end on real files (short runs)."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from cli_output import assert_one_line_error, json_out

from boringbar.cli.main import main
from boringbar.model.modal_fit import ModalFit
from boringbar.model.system import System
from boringbar.model.system_file import load_system
from boringbar.studies.load import load_study, study_from_dict
from boringbar.studies.runner import run_study

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "systems"
CARBIDE = str(EXAMPLES / "carbide_ld10_tungsten.toml")
TMD = str(EXAMPLES / "steel_coolant_tmd.toml")
SHORT = ["--duration-s", "0.03"]


def test_modes_json_and_figure(tmp_path, capsys):
    out = tmp_path / "m"
    assert main(["modes", "--system", CARBIDE, "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert len(s["modes"]) == 3 and s["bar"] == "ball"
    for m in s["modes"]:
        assert {"frequency_hz", "modal_mass_kg", "psi_tip", "psi_ball", "psi_absorber"} <= m.keys()
    assert s["modes"][0]["psi_ball"] == pytest.approx(0.9177, abs=1e-3)
    assert s["modes"][0]["psi_absorber"] is None  # the file has no absorber
    assert 0 < s["tip_static_stiffness_n_m"] < s["modes"][0]["modal_stiffness_n_m"]
    assert (out / "modes.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert json.loads((out / "modes.json").read_text())["modes"] == s["modes"]


def test_modes_of_the_published_bar_under_the_paper_preset(tmp_path, capsys):
    assert main(["modes", "--preset", "paper", "--modes", "1", "--out", str(tmp_path),
                 "--json"]) == 0
    s = json_out(capsys)
    assert s["modes"][0]["frequency_hz"] == pytest.approx(461.0, rel=1e-12)
    assert s["system"] == "published"


@pytest.mark.parametrize(("system", "bar"), [(CARBIDE, "ball"), (TMD, "tmd")])
def test_simulate_runs_your_own_bar_and_the_result_rebuilds_it(tmp_path, capsys, system, bar):
    out = tmp_path / "run"
    assert main(["simulate", "--system", system, *SHORT, "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert s["bar"] == bar  # the file's damper is the default
    with xr.open_dataset(out / "run.nc") as ds:
        config = json.loads(ds.attrs["config"])
    rebuilt = System.from_dict(config["system"])
    assert rebuilt.spec.to_dict() == load_system(system).to_dict()
    assert rebuilt.bar.natural_frequency_hz == pytest.approx(s["natural_frequency_hz"])
    if bar == "ball":
        assert rebuilt.damper.gap_m == 0.3e-3 and rebuilt.damper.material == "tungsten"


def test_sweep_defaults_to_the_bars_the_file_has(tmp_path, capsys):
    assert main(["sweep", "--system", TMD, "--ratios", "0.9,1.0", "--force-n", "10", *SHORT,
                 "--out", str(tmp_path), "--json", "--quiet"]) == 0
    s = json_out(capsys)
    assert [c["bar"] for c in s["cases"]] == ["solid", "tmd"]
    assert main(["sweep", "--system", CARBIDE, "--ratios", "1.0", "--force-n", "20", *SHORT,
                 "--out", str(tmp_path / "c"), "--json", "--quiet"]) == 0
    s = json_out(capsys)
    # the file's ball as the file has it: its gap, and its friction (on)
    assert [c["case"] for c in s["cases"]] == ["solid", "ball gap=0.3mm friction=on"]


def test_lobes_take_a_system_file(tmp_path, capsys):
    assert main(["lobes", "--system", CARBIDE, "--bar", "solid", "--rpm", "2000",
                 "--max-depth-mm", "0.2", "--depth-step-mm", "0.05", "--duration-s", "0.2",
                 "--out", str(tmp_path), "--json", "--quiet"]) == 0
    s = json_out(capsys)
    assert s["cases"][0]["speeds"][0]["analytic_limit_m"] > 0


def test_a_study_file_names_its_system(tmp_path):
    (tmp_path / "bars").mkdir()
    (tmp_path / "bars" / "mine.toml").write_text(Path(CARBIDE).read_text())
    study = tmp_path / "study.toml"
    study.write_text('[study]\nanalysis = "sweep"\nsystem = "bars/mine.toml"\n'
                     '[forcing]\nforce_n = 20\n[run]\nduration_s = 0.03\n'
                     '[grid]\nratio = [1.0]\nkind = ["ball"]\n')
    s = load_study(study)
    assert s.value("gap_mm") == 0.3 and s.value("ball") == "tungsten"
    ds = run_study(s, out=tmp_path / "r.nc", executor="serial")
    systems = json.loads(ds.attrs["systems"])
    (system,) = systems.values()
    assert system["system_file"]["name"] == "carbide-32mm-LD10-tungsten-ball"
    assert json.loads(ds.attrs["study_config"])["system"]["ball"]["material"] == "tungsten"


def test_an_inline_system_table_and_the_path_give_the_same_study(tmp_path):
    inline = tomllib.loads(Path(CARBIDE).read_text())
    base = {"study": {"analysis": "sweep"}, "grid": {"ratio": [1.0], "kind": ["ball"]}}
    a = study_from_dict({**base, "system": inline}, str(tmp_path / "a.toml"))
    b = study_from_dict({**base, "study": {"analysis": "sweep", "system": CARBIDE}},
                        str(tmp_path / "a.toml"))
    assert a.config_hash() == b.config_hash()
    again = study_from_dict(a.to_dict())
    assert again.config_hash() == a.config_hash()


def test_frf_fit_replaces_the_fe_bar(tmp_path, capsys):
    fit = ModalFit(frequency_hz=[400.0, 2100.0], damping_ratio=[0.02, 0.03],
                   modal_stiffness_n_m=[2.0e6, 4.0e7], source={"file": "synthetic"})
    path = tmp_path / "fit.json"
    path.write_text(json.dumps(fit.to_dict()))
    out = tmp_path / "run"
    assert main(["simulate", "--frf", str(path), "--frf-ball-ratio", "0.6", *SHORT,
                 "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert s["natural_frequency_hz"] == pytest.approx(400.0)
    with xr.open_dataset(out / "run.nc") as ds:
        bar = json.loads(ds.attrs["config"])["system"]["bar"]
    assert bar["source"] == "frf-fit"
    np.testing.assert_allclose(bar["psi_damper"], [0.6, 0.6])
    k = np.array(bar["modal_stiffness_n_m"]) / np.array(bar["psi_tip"]) ** 2
    np.testing.assert_allclose(k, [2.0e6, 4.0e7])
    assert math.isclose(bar["damping_ratio"][1], 0.03)


@pytest.mark.parametrize(("argv", "name"), [
    (["simulate", "--system", "missing.toml"], "missing.toml"),
    (["simulate", "--system", CARBIDE, "--gap-mm", "1.5"], "gap"),
    (["simulate", "--system", TMD, "--bar", "ball"], "[cavity]"),
    (["simulate", "--frf", "fit.json"], "--frf-ball-ratio"),
    (["simulate", "--frf-ball-ratio", "0.5"], "--frf-ball-ratio applies only with --frf"),
    (["modes", "--system", CARBIDE, "--modes", "9"], "--modes"),
])
def test_bad_system_input_is_one_line(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, [*argv, "--out", str(out)], out, name, capsys)


def test_a_bad_system_file_is_one_line_naming_the_key(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(Path(CARBIDE).read_text().replace("position_mm = 300.0",
                                                     "position_mm = 315.0"))
    out = tmp_path / "out"
    assert_one_line_error(main, ["simulate", "--system", str(bad), "--out", str(out)], out,
                          "cavity.position_mm", capsys)
