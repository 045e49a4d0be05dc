"""Study files: the schema, its defaults and its errors (before any work)."""

import json
from pathlib import Path

import pytest

from boringbar.analysis.lobes import DEPTH_TOLERANCE, PUBLISHED_DEPTH_STEP
from boringbar.analysis.speeds import default_speeds
from boringbar.analysis.sweep import default_ratios, tmd_window
from boringbar.cli.main import main
from boringbar.studies.load import load_study, study_from_dict
from boringbar.studies.registry import ANALYSES
from boringbar.studies.schema import StudyError

EXAMPLES = sorted((Path(__file__).parent.parent / "examples" / "studies").glob("*.toml"))


def _write(tmp_path, text: str) -> Path:
    p = tmp_path / "study.toml"
    p.write_text(text)
    return p


def test_defaults_are_the_published_study():
    s = study_from_dict({"study": {"analysis": "sweep"}})
    assert s.preset == "physical" and s.value("gap_mm") == 0.5 and s.value("friction") is True
    assert s.value("force_n") == 10.0 and s.value("duration_s") == 2
    # the step unset: each analysis's own (the published 1e-6 s for a sweep's runs)
    assert s.value("dt_s") is None
    assert s.axes["ratio"][0] == 0.95 and s.axes["ratio"][-1] == 1.05 and len(s.axes["ratio"]) == 11
    lobes = study_from_dict({"study": {"analysis": "lobes"}})
    assert lobes.options["successive"] == 3  # the published rule; grid and speeds below
    bif = study_from_dict({"study": {"analysis": "bifurcation"}})
    assert bif.options["values"] == tuple(float(v) for v in range(5, 51))


def test_lobe_defaults_follow_the_studys_bars_as_the_library_does(tmp_path):
    """No rpm: the speeds of the study's bars, as ``lobes`` takes them (a boring job's over
    the bars' bore, not the published bar's 900..1600); no depth step: the search to 1 %
    on the geometric grid.
    A depth step given keeps the linear grid; a scan given no step, the published one."""
    text = (EXAMPLES[0].parent.parent / "systems" / "published.toml").read_text()
    assert "end_mm = 200.0" in text
    (tmp_path / "short.toml").write_text(text.replace("end_mm = 200.0", "end_mm = 180.0"))
    speeds = {}
    for name, system in (("published", {}), ("short", {"system": str(tmp_path / "short.toml")})):
        s = study_from_dict({"study": {"analysis": "lobes", **system},
                             "grid": {"kind": ["solid", "ball"]}})
        plan = ANALYSES["lobes"].plan(s)
        o = plan.context["options"]
        assert s.axes["rpm"] == default_speeds(plan.context["cases"]) == o.rpm
        assert (o.method, o.depth_step_m, o.depth_tolerance) == ("search", None, DEPTH_TOLERANCE)
        assert study_from_dict(json.loads(json.dumps(s.to_dict()))).axes == s.axes
        speeds[name] = s.axes["rpm"]
    # a boring job's speeds follow the bore (one diameter: one range of speeds), drawn
    # four to a lobe of each bar's first frequency
    assert speeds["short"][::len(speeds["short"]) - 1] == \
        speeds["published"][::len(speeds["published"]) - 1]
    assert speeds["published"] != tuple(900.0 + 50 * i for i in range(15))
    linear = ANALYSES["lobes"].plan(study_from_dict({"study": {"analysis": "lobes"},
                                                     "analysis": {"depth_step_mm": 0.02}}))
    assert linear.context["options"].depth_step_m == 0.02 * 1e-3
    scan = ANALYSES["lobes"].plan(study_from_dict({"study": {"analysis": "lobes"},
                                                   "analysis": {"method": "scan"}}))
    assert scan.context["options"].depth_step_m == PUBLISHED_DEPTH_STEP
    rpm = [900.0 + 50 * i for i in range(15)]
    assert study_from_dict({"study": {"analysis": "lobes"},
                            "grid": {"rpm": rpm}}).axes["rpm"] == tuple(rpm)


def test_sweep_defaults_follow_the_studys_bars_as_the_library_does():
    """No ratio axis: the ratios ``sweep`` takes for the study's bars, the published
    window for a ball bar and one holding both peaks of a tuned mass damper."""
    ball = study_from_dict({"study": {"analysis": "sweep"}})
    assert ball.axes["ratio"] == tuple(round(0.95 + 0.01 * i, 12) for i in range(11))
    tmd = study_from_dict({"study": {"analysis": "sweep"}, "grid": {"kind": ["tmd"]}})
    cases = ANALYSES["sweep"].plan(tmd).context["cases"]
    assert tmd.axes["ratio"] == default_ratios(cases)
    lo, hi = tmd_window(cases[0].system)
    assert tmd.axes["ratio"][0] <= lo < hi <= tmd.axes["ratio"][-1] and hi - lo > 0.2


def test_grid_forms_and_case_collapse():
    s = study_from_dict({"study": {"analysis": "sweep"}, "run": {"integrator": "rk4"},
                         "grid": {"kind": ["solid", "tmd", "ball"], "gap_mm": [0.5, 0.1],
                                  "friction": ["off", "on"],
                                  "ratio": {"start": 0.98, "stop": 1.02, "step": 0.02}}})
    assert s.axes["ratio"] == (0.98, 1.0, 1.02)
    plan = ANALYSES["sweep"].plan(s)
    labels = [c.label for c in plan.context["cases"]]
    # a solid or TMD bar has no gap or friction: one case each, as published_cases
    assert labels == ["solid", "tmd", "ball gap=0.5mm friction=off", "ball gap=0.5mm friction=on",
                      "ball gap=0.1mm friction=off", "ball gap=0.1mm friction=on"]
    # every (case, force, ratio) run once, in lock-step batches of one bar kind each
    assert sorted(r for point in plan.points for r in point) == [
        (i, 0, k) for i in range(6) for k in range(3)]
    assert [len(point) for point in plan.points] == [3, 3, 12]


def test_to_dict_round_trips_and_is_json():
    s = study_from_dict({"study": {"analysis": "basins", "name": "b"},
                         "analysis": {"displacement_mm": {"start": -1, "stop": 1, "count": 3}},
                         "forcing": {"ratio": 1.01}})
    d = json.loads(json.dumps(s.to_dict()))
    again = study_from_dict(d)
    assert again.config_hash() == s.config_hash() and again.to_dict() == s.to_dict()


@pytest.mark.parametrize("text, key, value, allowed", [
    ('[study]\nanalysis = "sweep"\n[damper]\ngapmm = 0.5\n', "damper.gapmm", "0.5",
     "unknown key"),
    ('[study]\nanalysis = "sweep"\n[damper]\ngap_mm = -0.5\n', "damper.gap_mm", "-0.5",
     "a number in (0, 2]"),
    ('[study]\nanalysis = "sweep"\n[damper]\ngap_mm = "wide"\n', "damper.gap_mm", "'wide'",
     "a number"),
    ('[study]\nanalysis = "sweep"\n[damper]\nball = "glass"\n', "damper.ball", "'glass'",
     "one of 'steel', 'carbide', 'heavy-metal', 'tungsten'"),
    ('[study]\nanalysis = "sweep"\n[bar]\nn_modes = 2.5\n', "bar.n_modes", "2.5", "an integer"),
    ('[study]\nanalysis = "swoop"\n', "study.analysis", "'swoop'", "'sweep'"),
    ('[study]\nanalysis = "sweep"\n[gird]\ngap_mm = [1]\n', "gird", "", "unknown section"),
    ('[study]\nanalysis = "lobes"\n[grid]\nforce_n = [10, 20]\n', "grid.force_n", "[10, 20]",
     "allowed axes"),
    ('[study]\nanalysis = "sweep"\n[grid]\ngap_mm = [0.5, 0.5]\n', "grid.gap_mm", "",
     "distinct"),
    ('[study]\nanalysis = "sweep"\n[grid]\nratio = {start = 1, stop = 0.9, step = 0.1}\n',
     "grid.ratio", "", "stop >= start"),
    ('[study]\nanalysis = "lobes"\n[analysis]\nmethod = "guess"\n', "analysis.method",
     "'guess'", "one of 'scan', 'search'"),
    ('[study]\nanalysis = "sweep"\n[analysis]\nmethod = "scan"\n', "analysis.method", "",
     "unknown key for a sweep study"),
    ('[study]\nanalysis = "sweep"\n[run]\nintegrator = "euler"\n', "run.integrator",
     "'euler'", "one of"),
    ('[study]\nanalysis = "sweep"\n[run]\ndt_s = 1e-4\n', "run.dt_s", "0.0001",
     "too coarse"),
    ('[study]\nanalysis = "sweep"\n[run]\nintegrator = "rk4"\n[damper]\nstatic_ratio = 1.5\n',
     "damper.static_ratio", "1.5", "integrator = 'exact'"),
])
def test_invalid_files_name_file_key_value_and_what_is_allowed(tmp_path, text, key, value,
                                                                allowed):
    path = _write(tmp_path, text)
    with pytest.raises(StudyError) as err:
        load_study(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: key '{key}'"), msg
    assert value in msg and allowed in msg and "\n" not in msg


def test_cli_rejects_a_bad_file_before_any_work(tmp_path, capsys):
    path = _write(tmp_path, '[study]\nanalysis = "sweep"\nout = "r.nc"\n[forcing]\nforce_n = -1\n')
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("boringbar: error:") and "forcing.force_n" in err and "-1" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "r.nc").exists() and not (tmp_path / "r.nc.partial").exists()


def test_not_toml(tmp_path):
    path = _write(tmp_path, "[study\n")
    with pytest.raises(StudyError, match="not valid TOML"):
        load_study(path)


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_examples_load_and_plan(path):
    s = load_study(path)
    assert ANALYSES[s.analysis].plan(s).points
