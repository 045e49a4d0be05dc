"""``boringbar lobes`` and ``boringbar simulate --rpm`` end to end, on real files
(STYLE.md tier 4).

Runs are short (0.3 s simulated, a coarse depth grid) so the file stays fast;
the physics of lobes is tested elsewhere, here only what the commands
promise: their files, their JSON, their exit codes and their one-line errors.
"""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from cli_output import assert_one_line_error, json_out

import boringbar as bb
from boringbar.analysis.cases import published_cases
from boringbar.analysis.speeds import default_speeds
from boringbar.cli.main import main
from boringbar.model.system_file import load_system
from boringbar.plot import plot_lobes
from boringbar.reference.stability import limit_at_speeds

#: A solid-bar lobe grid that has both stable and chattering points in 0.3 s runs of the
#: published criterion.
SMALL = ["--bar", "solid", "--rpm", "1000:1100:50", "--duration-s", "0.3",
         "--max-depth-mm", "0.2", "--depth-step-mm", "0.02", "--criterion", "zero"]
PNG = b"\x89PNG\r\n\x1a\n"


def test_lobes_files_json_and_verdicts(tmp_path, capsys):
    out = tmp_path / "lobes"
    assert main(["lobes", *SMALL, "--method", "scan", "--workers", "2", "--out", str(out),
                 "--json"]) == 0
    s = json_out(capsys)
    assert s["method"] == "scan" and s["criterion"] == "zero"
    assert s["files"] == {"netcdf": str(out / "lobes.nc"), "png": str(out / "lobes.png")}
    assert (out / "lobes.png").read_bytes()[:8] == PNG
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries
    assert s["min_chatter_free_depth_m"] > 0
    (case,) = s["cases"]
    assert case["case"] == "solid" and case["min_chatter_free_depth_m"] > 0
    assert [v["rpm"] for v in case["speeds"]] == pytest.approx([1000, 1050, 1100])
    for speed in case["speeds"]:
        assert {"rpm", "limit_depth_m", "first_unstable_depth_m", "analytic_limit_m"} \
            <= speed.keys()
        assert speed["limit_depth_m"] < speed["first_unstable_depth_m"] <= 0.2e-3 + 1e-12
    with xr.open_dataset(out / "lobes.nc") as ds:
        verdict = ds["verdict"].values
        assert (verdict == 1).any() and (verdict == 0).any()  # stable and chatter points
        assert ds.sizes["rpm"] == 3 and ds.attrs["method"] == "scan"
        assert np.isfinite(ds["analytic_curve_m"].values).all()  # the solid bar is linear
        assert float(ds["min_chatter_free_depth_m"].values[0]) == pytest.approx(
            case["min_chatter_free_depth_m"])


def test_lobes_search_and_examples(tmp_path, capsys):
    out = tmp_path / "lobes"
    assert main(["lobes", *SMALL, "--method", "search", "--examples", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "limit (mm)" in text and "first unstable (mm)" in text and "analytic (mm)" in text
    assert "example stable" in text and "example unstable" in text
    for name in ("lobes.nc", "lobes.png", "examples.nc", "examples.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "examples.png").read_bytes()[:8] == PNG
    with xr.open_dataset(out / "lobes.nc") as ds:
        assert ds.attrs["method"] == "search"
        limit = ds["limit_depth_m"].values[0]
        first = ds["first_unstable_depth_m"].values[0]
    with xr.open_dataset(out / "examples.nc") as ex:
        assert list(ex["example"].values) == ["stable", "unstable"]
        assert list(ex["chatter"].values) == [False, True]
        j = int(np.nanargmin(limit))  # the speed of the minimum chatter-free depth
        assert ex["depth_m"].values == pytest.approx([limit[j], first[j]])
        assert ex["time_s"].values[-1] == pytest.approx(0.3, rel=1e-3)  # not stopped at zero
        assert {"tip_displacement_m", "force_n"} <= set(ex.data_vars)


def test_lobes_default_to_the_bars_speeds_and_one_percent_depths(tmp_path, capsys):
    """Without --rpm, --depth-step-mm and --criterion: the speeds of the bar's lobes 1 to 5
    (analysis.lobes.default_speeds), the converged verdict, and the search to 1 % of
    each limit: the limit (the growth rate's zero) within 1 % below the first depth
    that chatters."""
    out = tmp_path / "lobes"
    assert main(["lobes", "--bar", "solid", "--max-depth-mm", "0.5", "--out", str(out),
                 "--json"]) == 0
    s = json_out(capsys)
    assert s["method"] == "search" and s["criterion"] == "growth"
    assert "converged verdict" in s["method_text"]
    expected = default_speeds(published_cases(("solid",)))
    assert [v["rpm"] for v in s["cases"][0]["speeds"]] == list(expected)
    for v in s["cases"][0]["speeds"]:
        if v["limit_depth_m"]:
            assert 1.0 < v["first_unstable_depth_m"] / v["limit_depth_m"] <= 1.01 + 1e-9
    with xr.open_dataset(out / "lobes.nc") as ds:
        assert ds.attrs["depth_grid"].startswith("depth_tolerance = 0.01")


def test_analytic_lobes_default_to_the_bars_speeds(tmp_path, capsys):
    """--analytic without --rpm: the same speeds as the simulated lobes (the bar's lobes
    1 to 5), for the published bar and for a bar of one's own, not a fixed band."""
    mine = Path(__file__).resolve().parents[1] / "examples/systems/carbide_ld10_tungsten.toml"
    speeds = {}
    for name, extra in (("published", []), ("mine", ["--system", str(mine)])):
        assert main(["lobes", "--analytic", "--bar", "solid", *extra,
                     "--out", str(tmp_path / name), "--json"]) == 0
        speeds[name] = [v["rpm"] for v in json_out(capsys)["cases"][0]["speeds"]]
    assert speeds["published"] == list(default_speeds(published_cases(("solid",))))
    spec = load_system(mine)
    assert speeds["mine"] == list(default_speeds(published_cases(("solid",), spec=spec)))
    assert speeds["mine"][0] < speeds["published"][0]  # a longer, softer bar: slower lobes


def test_lobes_at_rpm_outside_the_grid_joins_it_and_is_read_out(tmp_path, capsys):
    """--at-rpm beyond --rpm: the speed is cut too (its limit computed, not interpolated),
    the JSON reads it out, and lobes.nc keeps it for the figure drawn again."""
    out = tmp_path / "lobes"
    assert main(["lobes", *SMALL, "--method", "scan", "--at-rpm", "1150", "--out", str(out),
                 "--json"]) == 0
    s = json_out(capsys)
    assert s["at_rpm"] == 1150
    (case,) = s["cases"]
    assert [v["rpm"] for v in case["speeds"]] == [1000, 1050, 1100, 1150]
    assert case["depth_at_rpm_m"] == case["speeds"][3]["limit_depth_m"]
    assert 0 < case["depth_at_rpm_m"] < 0.2e-3
    # the grid's speed beside it (the last speed has one), for a speed that drifts
    assert case["at_rpm_neighbours"] == [{"rpm": 1100.0,
                                          "limit_depth_m": case["speeds"][2]["limit_depth_m"]}]
    with xr.open_dataset(out / "lobes.nc") as ds:
        assert ds.attrs["at_rpm"] == 1150
        readout = plot_lobes(ds.load()).axes[0].texts[0].get_text()
    assert readout == f"your speed 1150 rpm: {case['depth_at_rpm_m'] * 1e3:.3g} mm"


def test_lobes_at_rpm_in_the_summary_line(tmp_path, capsys):
    assert main(["lobes", *SMALL[:2], "--rpm", "1100", "--at-rpm", "1100", *SMALL[4:],
                 "--out", str(tmp_path)]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    assert line.startswith("solid: minimum chatter-free depth ")
    assert line.endswith(" at 1100 rpm; at your speed 1100 rpm: " + line.split()[4] + " mm")
    assert main(["lobes", *SMALL, "--at-rpm", "1050", "--out", str(tmp_path / "b")]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    assert " (grid neighbours 1000 rpm: " in line and ", 1100 rpm: " in line


def test_analytic_lobes_at_rpm_below_the_default_speeds_joins_them(tmp_path, capsys):
    """A speed below the bars' default speeds joins them, exactly, and each bar's
    frequency-domain limit there is read out."""
    cases = published_cases(("solid", "tmd"))
    expected = default_speeds(cases)
    at = float(round(0.6 * expected[0]))
    assert main(["lobes", "--analytic", "--bar", "solid,tmd", "--at-rpm", f"{at:g}",
                 "--out", str(tmp_path), "--json"]) == 0
    s = json_out(capsys)
    assert s["at_rpm"] == at
    for case, system in zip(s["cases"], cases, strict=True):
        assert [v["rpm"] for v in case["speeds"]] == [at, *expected]
        assert case["depth_at_rpm_m"] == case["speeds"][0]["limit_m"]
        assert case["depth_at_rpm_m"] == pytest.approx(
            limit_at_speeds(system.system, [at])[0], rel=1e-9)
    main(["lobes", "--analytic", "--bar", "solid", "--at-rpm", f"{at:g}", "--out",
          str(tmp_path)])
    first = capsys.readouterr().out.splitlines()[0]
    depth = s["cases"][0]["depth_at_rpm_m"] * 1e3
    assert first.endswith(f"; at your speed {at:g} rpm: {depth:.4g} mm")


def test_simulate_cut_stop_at_zero_reports_chatter(tmp_path, capsys):
    out = tmp_path / "cut"
    assert main(["simulate", "--bar", "solid", "--rpm", "1200", "--depth-mm", "0.2",
                 "--stop-at-zero", "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    c = s["cutting"]
    assert c["chatter"] is True and c["rpm"] == 1200 and c["depth_m"] == pytest.approx(2e-4)
    assert 0 < c["first_zero_time_s"] == pytest.approx(s["duration_s"])  # stopped there
    assert (out / "run.png").read_bytes()[:8] == PNG
    with xr.open_dataset(out / "run.nc") as ds:
        assert json.loads(ds.attrs["config"])["forcing"]["type"] == "regenerative"
        assert ds["force_n"].values.max() > 0


def test_simulate_cut_text(tmp_path, capsys):
    assert main(["simulate", "--bar", "solid", "--rpm", "1200", "--depth-mm", "0.02",
                 "--duration-s", "0.05", "--delay-interp", "linear", "--start", "static",
                 "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "cut at 1200 rpm" in text and "stable" in text and "linear" in text


@pytest.mark.parametrize("argv, name", [
    (["simulate", "--rpm", "0", "--depth-mm", "0.1"], "--rpm"),
    (["simulate", "--rpm", "1200", "--depth-mm", "-1"], "--depth-mm"),
    (["simulate", "--rpm", "1200", "--depth-mm", "0.1", "--ratio", "1.0"], "--ratio"),
    (["simulate", "--rpm", "1200", "--depth-mm", "0.1", "--force-n", "10"], "--force-n"),
    (["simulate", "--rpm", "1200"], "--depth-mm"),
    (["simulate", "--kr-mpa", "900"], "--kr-mpa"),
    (["simulate", "--rpm", "1200", "--depth-mm", "0.1", "--revolutions", "0"],
     "--revolutions"),
    (["lobes", "--rpm", "0"], "--rpm"),
    (["lobes", "--tolerance-um", "0"], "--tolerance-um"),
    (["lobes", "--tolerance-um", "-5"], "--tolerance-um"),
    (["lobes", "--knock-um", "-1"], "--knock-um"),
    (["lobes", "--confidence", "1.5"], "--confidence"),
    (["lobes", "--max-run-s", "0"], "--max-run-s"),
    (["lobes", "--rpm", "1600:900:50"], "--rpm"),
    (["lobes", "--depth-step-mm", "0"], "--depth-step-mm"),
    (["lobes", "--depth-tolerance", "0"], "--depth-tolerance"),
    (["lobes", "--depth-tolerance", "1e-7"], "--depth-tolerance"),
    (["lobes", "--rpm", "1200,1000"], "--rpm"),
    (["lobes", "--depth-step-mm", "0.01", "--depth-tolerance", "0.02"],
     "--depth-step-mm = 0.01 and --depth-tolerance = 0.02: give one"),
    (["lobes", "--max-depth-mm", "0.0005"], "--max-depth-mm"),  # below the 1 um grid
    (["lobes", "--method", "scan", "--max-depth-mm", "0.001"], "--max-depth-mm"),
    (["lobes", "--feed-mm", "-0.1"], "--feed-mm"),
    (["lobes", "--method", "guess"], "--method"),
    (["lobes", "--bar", "solid", "--gap-mm", "0.1"], "--gap-mm"),
    (["lobes", "--at-rpm", "0"], "--at-rpm = 0"),
    (["lobes", "--at-rpm", "-1200"], "--at-rpm"),
    (["lobes", "--at-rpm", "nan"], "--at-rpm"),
    (["lobes", "--at-rpm", "fast"], "--at-rpm"),
    (["lobes", "--at-rpm", "0.01"], "--at-rpm"),  # a delay history past the allowed rows
    (["lobes", "--analytic", "--at-rpm", "0"], "--at-rpm = 0"),
    # a simulated cut's option, which the closed form would leave unread
    (["lobes", "--analytic", "--tolerance-um", "-1"], "--tolerance-um with --analytic"),
    (["lobes", "--analytic", "--examples"], "--examples with --analytic"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, argv + ["--out", str(out)], out, name, capsys)


def test_a_free_ball_s_table_gives_its_linear_host_s_analytic_limit(tmp_path, capsys):
    """The free ball has no analytic limit of its own; its row gives its linear host's
    (here, without friction, the bare cavity bar), starred and explained."""
    assert main(["lobes", "--bar", "ball", "--friction", "off", "--rpm", "1200", "--out",
                 str(tmp_path)]) == 0
    text = capsys.readouterr().out
    host = bb.make_system("ball", friction=False).linear_host()
    limit = float(limit_at_speeds(host, [1200.0])[0])
    row = next(line for line in text.splitlines() if line.strip().startswith("1200"))
    assert row.split()[3] == f"{limit * 1e3:.4g}*"
    assert "*: the free ball's linear host" in text
