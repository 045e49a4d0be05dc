"""Design search (analysis/design.py): Den Hartog's and Sims' optima recovered, a 1-D
search against brute force, the Monte Carlo statistic, resume after a kill, design files
and the command line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import optuna
import pytest
from cli_output import assert_one_line_error, json_out

from boringbar import ParameterError
from boringbar.analysis.design import candidate_system, design, evaluate, summary, summary_line
from boringbar.analysis.design_file import DesignFileError, design_from_dict
from boringbar.analysis.design_options import (
    DesignOptions,
    Uncertain,
    Variable,
    sampled_system,
    uncertain_samples,
)
from boringbar.analysis.lobes import DEPTH_TOLERANCE, LobesOptions, lobes
from boringbar.analysis.sweep import Case
from boringbar.cli.main import main
from boringbar.execute import Execution
from boringbar.model.dampers import den_hartog_parameters, sims_parameters
from boringbar.model.system import make_system, published_system_spec
from boringbar.model.system_file import parse_system
from boringbar.simulate import Integration

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
MASS = 0.01  # the absorber: mass ratio 0.052 on the bar below
TUNING = (Variable("tmd_frequency_ratio", 0.85, 1.15), Variable("tmd_damping_ratio", 0.02, 0.4))


@pytest.fixture(scope="module")
def host():
    """One undamped bending mode (Den Hartog's and Sims' host), absorber at the tip."""
    return parse_system({"bar": {"material": "steel", "damping_ratio": 0.0, "modes": 1,
                                 "sections": [{"end_mm": 200, "diameter_mm": 25}]},
                         "tmd": {"mass_kg": MASS, "position_mm": 200}}, "one mode")


def best(ds) -> dict:
    return summary(ds)["best"]


def test_den_hartog_is_recovered(host):
    bar = make_system("tmd", spec=host).bar
    dh = den_hartog_parameters(MASS, bar)
    f, zeta_a = dh["frequency_ratio"], dh["damping_ratio"] / dh["frequency_ratio"]  # c/(2 m wa)
    options = DesignOptions("tmd", TUNING, objective="frf_peak", trials=300, sampler="cmaes",
                            seed=3)
    ds = design(options, spec=host)
    b = best(ds)
    assert b["tmd_frequency_ratio"] == pytest.approx(f, rel=0.02)
    assert b["tmd_damping_ratio"] == pytest.approx(zeta_a, rel=0.02)
    at_dh = evaluate(host, options, {"tmd_frequency_ratio": f, "tmd_damping_ratio": zeta_a},
                     uncertain_samples(options)).statistic[0]
    assert summary(ds)["objective"] == pytest.approx(at_dh, rel=0.005)
    # Den Hartog's damping is the fixed-point approximation: the search may only beat it
    assert summary(ds)["objective"] <= at_dh * (1 + 1e-9)


def test_sims_is_recovered(host):
    bar = make_system("tmd", spec=host).bar
    sims = sims_parameters(MASS, bar)
    options = DesignOptions("tmd", TUNING, objective="min_real", trials=300, sampler="cmaes",
                            seed=3)
    b = best(design(options, spec=host))
    assert b["tmd_frequency_ratio"] == pytest.approx(sims["frequency_ratio"], rel=0.02)
    assert b["tmd_damping_ratio"] == pytest.approx(sims["damping_ratio"], rel=0.02)


def test_a_gap_search_finds_the_brute_force_best():
    spec = published_system_spec()
    options = DesignOptions("ball", (Variable("gap_m", 0.05e-3, 1e-3),), ratios=(0.98, 1.0, 1.02),
                            forces_n=(20.0,), duration_s=0.5, trials=20, seed=2)
    grid = np.linspace(0.05e-3, 1e-3, 20)
    samples = uncertain_samples(options)
    values = [evaluate(spec, options, {"gap_m": g}, samples).statistic[0] for g in grid]
    s = summary(design(options, spec=spec))
    step = grid[1] - grid[0]
    assert abs(s["best"]["gap_m"] - grid[int(np.argmin(values))]) <= step
    assert s["objective"] <= min(values) * 1.05


def test_zero_spread_equals_the_deterministic_objective():
    spec = published_system_spec()
    base = DesignOptions("ball", (Variable("gap_m", 0.05e-3, 1e-3),), ratios=(1.0,),
                         duration_s=0.3)
    fixed = DesignOptions("ball", base.variables, ratios=(1.0,), duration_s=0.3, samples=4,
                          uncertain=(Uncertain("restitution", "normal", 0.7, 0.0),
                                     Uncertain("damping_ratio", "uniform", 0.01, 0.01)))
    a = evaluate(spec, base, {"gap_m": 0.3e-3}, uncertain_samples(base))
    b = evaluate(spec, fixed, {"gap_m": 0.3e-3}, uncertain_samples(fixed))
    assert np.all(b.samples == a.statistic[0]) and b.statistic[0] == a.statistic[0]
    assert b.error[0] == 0.0


def test_the_sampling_error_shrinks_as_one_over_root_n(host):
    errors = []
    for n in (50, 200, 800):
        o = DesignOptions("tmd", TUNING, objective="frf_peak", samples=n, seed=5,
                          uncertain=(Uncertain("damping_ratio", "uniform", 0.0, 0.03),))
        errors.append(evaluate(host, o, {"tmd_frequency_ratio": 0.95,
                                         "tmd_damping_ratio": 0.13},
                               uncertain_samples(o)).error[0])
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.15)
    assert errors[1] / errors[2] == pytest.approx(2.0, rel=0.15)


def test_a_killed_search_resumes_to_the_same_trial_table(host, tmp_path):
    options = DesignOptions("tmd", TUNING, objective="frf_peak", trials=14, seed=7,
                            samples=3, uncertain=(Uncertain("damping_ratio", "uniform",
                                                            0.0, 0.02),))
    whole = design(options, spec=host, storage=tmp_path / "a.db")
    design(options, spec=host, storage=tmp_path / "b.db", stop_after=6)  # the kill
    study = optuna.load_study(study_name="boringbar-design",
                              storage=f"sqlite:///{tmp_path / 'b.db'}")
    study.ask()  # a trial that was running when the process died
    resumed = design(options, spec=host, storage=tmp_path / "b.db")
    for name in ("tmd_frequency_ratio", "tmd_damping_ratio", "statistic"):
        np.testing.assert_array_equal(resumed[name].values, whole[name].values)
    np.testing.assert_array_equal(resumed["objective_samples"].values,
                                  whole["objective_samples"].values)
    other = DesignOptions("tmd", TUNING, objective="min_real", trials=14, seed=7)
    with pytest.raises(ValueError, match="another design study"):
        design(other, spec=host, storage=tmp_path / "b.db")


def test_candidates_run_on_a_dask_cluster_as_on_threads():
    spec = published_system_spec()
    options = DesignOptions("ball", (Variable("gap_m", 0.05e-3, 1e-3),), ratios=(0.99, 1.01),
                            duration_s=0.2, trials=3, seed=4)
    a = design(options, spec=spec, execution=Execution("threads", 2))
    b = design(options, spec=spec, execution=Execution("dask", dask_local=1))
    np.testing.assert_array_equal(a["statistic"].values, b["statistic"].values)


# --- files and the command line -----------------------------------------------------------
@pytest.mark.parametrize(("patch", "words"), [
    ({"variables": {"gap_mm": [0.05, 3.0]}}, "variables.gap_mm"),
    ({"variables": {"gap_mm": [0.05]}}, "[low, high]"),
    ({"variables": {"colour": [1, 2]}}, "unknown variable"),
    ({"uncertain": {"restitution": {"triangular": [0.6, 0.8]}}}, "uncertain.restitution"),
    ({"design": {"bar": "ball", "objective": "frf_peak"}}, "linear bar"),
    ({"design": {"bar": "tmd", "trials": 0}}, "trials"),
    ({"extras": {}}, "unknown section"),
])
def test_bad_design_files_are_one_line(patch, words):
    d = {"design": {"bar": "ball"}, "variables": {"gap_mm": [0.05, 1.0]}}
    for k, v in patch.items():
        d[k] = v
    if "tmd" in str(patch.get("design", {})):
        d["variables"] = {"tmd_damping_ratio": [0.02, 0.3]}
    with pytest.raises(DesignFileError) as err:
        design_from_dict(d, "d.toml")
    assert words in str(err.value) and "\n" not in str(err.value)


def test_design_command_on_the_tmd_example(tmp_path, capsys):
    out = tmp_path / "d"
    argv = ["design", str(EXAMPLES / "design" / "steel_tmd.toml"), "--trials", "12", "--out",
            str(out), "--json"]
    assert main(argv) == 0
    s = json_out(capsys)
    assert {"best", "objective", "published_objective", "trials", "wall_time_s"} <= s.keys()
    assert s["trials"] == 12 and s["objective"] > 0
    assert "best design" in s["summary"]
    for f in ("design.nc", "trials.csv", "design.png", "best.png", "design.db"):
        assert (out / f).stat().st_size > 0
    assert main(argv) == 0  # rerun: resumes, nothing new to do
    assert json_out(capsys)["objective"] == s["objective"]


def test_design_command_bad_input(tmp_path, capsys):
    out = tmp_path / "out"
    assert_one_line_error(main, ["design", "missing.toml", "--out", str(out)], out,
                          "cannot read", capsys)


def test_a_pareto_search_spans_den_hartog_and_sims(host):
    """frf_peak against min_real: NSGA-II's front runs from Den Hartog's peak to Sims'
    trough, and no trial on it is dominated by another."""
    bar = make_system("tmd", spec=host).bar
    dh, sims = den_hartog_parameters(MASS, bar), sims_parameters(MASS, bar)
    options = DesignOptions("tmd", TUNING, objective=("frf_peak", "min_real"),
                            sampler="nsga2", trials=400, seed=3)
    ds = design(options, spec=host)
    samples = uncertain_samples(options)
    peak = evaluate(host, options, {"tmd_frequency_ratio": dh["frequency_ratio"],
                                    "tmd_damping_ratio": dh["damping_ratio"]
                                    / dh["frequency_ratio"]}, samples).statistic[0]
    trough = evaluate(host, options, {"tmd_frequency_ratio": sims["frequency_ratio"],
                                      "tmd_damping_ratio": sims["damping_ratio"]},
                      samples).statistic[1]
    front = ds["statistic"].values[ds["pareto"].values]
    assert front[:, 0].min() == pytest.approx(peak, rel=0.02)
    assert front[:, 1].min() == pytest.approx(trough, rel=0.02)
    for row in front:
        assert not np.any(np.all(front <= row, axis=1) & np.any(front < row, axis=1))
    assert len(summary(ds)["pareto"]) >= 2


def test_chatter_probability_of_a_cut():
    spec = published_system_spec()
    common = dict(objective="cut_amplitude", statistic="chatter_probability", samples=4,
                  duration_s=0.3, uncertain=(Uncertain("friction_force_n", "uniform",
                                                       0.0, 0.5),))
    gap = (Variable("gap_m", 0.05e-3, 1e-3),)
    shallow = DesignOptions("ball", gap, depth_m=0.005e-3, **common)
    deep = DesignOptions("ball", gap, depth_m=0.5e-3, **common)
    for options, p in ((shallow, 0.0), (deep, 1.0)):
        c = evaluate(spec, options, {"gap_m": 0.5e-3}, uncertain_samples(options))
        assert c.statistic[0] == p and c.error[0] == 0.0


def test_min_depth_is_the_lobes_search_of_the_candidate_to_one_percent():
    """min_depth runs the lobes' search on its geometric grid (each depth 1 % above the
    one below), so each speed's limit is bracketed to 1 % of itself, not to a step."""
    spec = published_system_spec()
    options = DesignOptions("tmd", (Variable("tmd_damping_ratio", 0.05, 0.3),),
                            objective="min_depth", rpms=(1000.0, 1400.0), max_depth_m=0.4e-3,
                            duration_s=0.3)
    assert options.depth_tolerance == DEPTH_TOLERANCE == 0.01
    values = {"tmd_damping_ratio": 0.02 + 0.03}
    c = evaluate(spec, options, values, uncertain_samples(options))
    system = candidate_system(spec, options, values)
    ds = lobes([Case("tmd", system, "tmd")],
               LobesOptions((1000.0, 1400.0), "search", "zero", None, 4e-4, analytic=False,
                            depth_tolerance=0.01),
               integration=Integration(0.3, 1e-6, "rk4"))
    assert ds.attrs["depth_grid"].startswith("depth_tolerance = 0.01")
    assert c.statistic[0] == min(float(ds["min_chatter_free_depth_m"].values[0]), 4e-4)
    limit, first = ds["limit_depth_m"].values[0], ds["first_unstable_depth_m"].values[0]
    found = np.isfinite(limit)  # a speed may not chatter up to max_depth_m
    assert found.any() and np.all(first[found] / limit[found] == pytest.approx(1.01, rel=1e-12))


def test_the_python_api_is_si_and_its_errors_say_so():
    """Lengths in m, no mm names; an error names the parameter, value and range in m."""
    with pytest.raises(ParameterError, match=r"gap_m high = 0.003 m is outside the allowed "
                                             r"range \(0.0001, 0.002\] m"):
        Variable("gap_m", 0.1e-3, 3e-3)
    with pytest.raises(ParameterError, match=r"depth_m = 2.0 m is outside the allowed range "
                                             r"\(0, 1\] m"):
        DesignOptions("ball", (Variable("gap_m", 0.1e-3, 0.5e-3),), depth_m=2.0)
    with pytest.raises(ParameterError, match="depth_tolerance = 0.9"):
        DesignOptions("ball", (Variable("gap_m", 0.1e-3, 0.5e-3),), depth_tolerance=0.9)
    with pytest.raises(ParameterError, match="'gap_mm' is not one of gap_m, "):
        Variable("gap_mm", 0.1, 0.5)
    with pytest.raises(ParameterError, match="'ball_position_mm' is not one of"):
        Uncertain("ball_position_mm", "uniform", -0.05, 0.05)
    with pytest.raises(TypeError, match="depth_mm"):
        DesignOptions("ball", (Variable("gap_m", 0.1e-3, 0.5e-3),), depth_mm=0.05)
    with pytest.raises(TypeError, match="depth_step_mm"):
        DesignOptions("ball", (Variable("gap_m", 0.1e-3, 0.5e-3),), depth_step_mm=0.01)


def test_a_design_file_is_in_mm_and_the_options_in_m():
    """The file's lengths (mm) are converted once, as every input file's; an error about
    a file's key is in the file's unit."""
    options, _ = design_from_dict({
        "design": {"bar": "ball", "depth_mm": 0.02, "max_depth_mm": 0.4,
                   "depth_tolerance": 0.02},
        "variables": {"gap_mm": [0.05, 1.0], "ball_diameter_mm": [8.0, 10.0]},
        "uncertain": {"ball_position_mm": {"normal": [0.0, 0.05]}}})
    assert options.variables == (Variable("gap_m", 0.05 * 1e-3, 1.0 * 1e-3),
                                 Variable("ball_diameter_m", 8.0 * 1e-3, 10.0 * 1e-3))
    assert options.uncertain == (Uncertain("ball_position_m", "normal", 0.0, 0.05 * 1e-3),)
    assert (options.depth_m, options.max_depth_m, options.depth_tolerance) == (
        0.02 * 1e-3, 0.4 * 1e-3, 0.02)
    for patch, words in (
            ({"variables": {"gap_mm": [0.05, 3.0]}},
             "key 'variables.gap_mm' = [0.05, 3.0]: gap_mm high = 3.0 mm is outside the "
             "allowed range (0.05, 2] mm"),
            ({"design": {"bar": "ball", "depth_mm": 2000.0}},
             "key 'design.depth_mm' = 2000.0 mm is outside the allowed range (0, 1000] mm"),
            ({"uncertain": {"ball_position_mm": {"uniform": [0.05, -0.05]}}},
             "ball_position_mm b = -0.05 is outside the allowed range [0.05, inf)"),
            ({"variables": {"gap_m": [0.05e-3, 1e-3]}}, "unknown variable; allowed: gap_mm"),
            ({"design": {"bar": "ball", "depth_step_mm": 0.01}}, "unknown key")):
        d = {"design": {"bar": "ball"}, "variables": {"gap_mm": [0.05, 1.0]}, **patch}
        with pytest.raises(DesignFileError) as err:
            design_from_dict(d, "d.toml")
        assert words in str(err.value) and "\n" not in str(err.value)


def test_an_uncertain_friction_number_is_read_as_the_preset_reads_it():
    spec = published_system_spec()
    for preset, force in (("physical", 0.6e-3 * 0.026 * 9.81 / 0.0075),
                          ("paper", 0.6 * 0.026 * 9.81 / 0.0075)):
        system = make_system("ball", preset, spec=spec)
        sampled, _ = sampled_system(system, ("friction_number",), [0.6])
        assert sampled.damper.friction_force_n == pytest.approx(force, rel=1e-12)
        assert sampled.damper.friction_force_n == pytest.approx(system.damper.friction_force_n,
                                                              rel=1e-12)


def test_a_search_that_beat_nothing_says_so():
    """Fewer trials than a search needs can end worse than the file's own design: the
    summary then says no better design was found, and does not call the best tried best."""
    s = dict(best={"gap_m": 0.3e-3, "ball_material": "steel"}, statistic_name="mean",
             objective_name="rms_band", objective=1.2e-4, objective_error=3e-6,
             published_objective=1.0e-4, trials=6)
    worse = summary_line({**s, "improvement_percent": -20.0})
    assert worse.startswith("no design better than the file's own found in 6 trials")
    assert "20.0 % worse" in worse and "best design" not in worse
    assert "0.12 +- 0.003 mm against 0.1 mm" in worse  # read in mm, as the figures
    assert summary_line({**s, "improvement_percent": 12.0}).startswith(
        "best design gap = 0.3 mm, ball material = steel improves the objective by 12.0 %")
