"""The chatter amplitude map (analysis/chatter_map.py): its Dataset and codes, the solid
bar's chatter-free depth against the lobes' limit, what a ball bounds and what a large
knock does, executors, the command line and the study file.

Grids are a few cells each; the cells of the carbide example's ball bar are chosen where
the verdicts are clear (a knock that dies out, a growing one the ball holds at about
1 um, a 20 um knock that takes the tool out of the cut).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from cli_output import assert_one_line_error, json_out

import boringbar as bb
from boringbar.analysis import chatter_map as cm
from boringbar.analysis.verdict import VerdictOptions
from boringbar.cli.chatter_map import map_text, map_verdict
from boringbar.cli.main import build_parser, main
from boringbar.execute import Execution
from boringbar.studies.load import study_from_dict
from boringbar.studies.runner import run_study
from boringbar.studies.schema import StudyError

CARBIDE = Path(__file__).resolve().parents[1] / "examples" / "systems" / \
    "carbide_ld10_tungsten.toml"
PNG = b"\x89PNG\r\n\x1a\n"
#: The carbide ball bar at 1000 rpm (bare-bar limit 0.0485 mm): 0.03 mm, a knock dies
#: out; 0.058 mm, a small knock dies out but a 20 um one leaves the cut; 0.068 mm, a small
#: knock grows and the ball holds it at about 1.2 um p-p.
BALL_RPM = (1000.0,)
BALL_DEPTHS_M = (0.03e-3, 0.058e-3, 0.068e-3)
ATTRS_OF_WHERE = ("executor", "workers", "wall_time_s")


@pytest.fixture(scope="module")
def ball():
    return bb.variants(bb.load_system(CARBIDE))["ball"]


@pytest.fixture(scope="module")
def ball_map(ball):
    """Three cells of the ball bar, a small and a 20 um knock (the default verdict)."""
    return bb.chatter_map(ball, bb.ChatterMapOptions(rpm=BALL_RPM, depths_m=BALL_DEPTHS_M))


def test_the_dataset_holds_every_cell_and_start_with_its_codes(ball_map):
    ds = ball_map
    assert dict(ds.sizes) == {"case": 1, "rpm": 1, "depth_m": 3, "start": 2,
                              "fine_rpm": ds.sizes["fine_rpm"]}
    assert list(ds["start"].values) == ["small knock", "knock 20 um"]
    assert ds["knock_m"].values == pytest.approx([1e-6, 20e-6])
    for name in ("onset", "chatter_free", "chatter_free_by_start"):
        assert set(np.unique(ds[name].values)) <= {0, 1, 2}, name
    statuses = {"died out", "settled", "decaying", "left the cut", "undecided"}
    assert set(np.unique(ds["settled_status"].values)) <= statuses
    # chatter-free from every start, and from every start alone
    per_start = ds["chatter_free_by_start"].values
    assert np.array_equal(ds["chatter_free"].values, per_start.min(axis=-1))
    # the column: every depth up to the chatter-free depth is chatter-free
    assert ds["chatter_free"].values[0, 0].tolist() == [1, 0, 0]
    assert float(ds["chatter_free_depth_m"].values[0, 0]) == BALL_DEPTHS_M[0]
    assert float(ds["first_not_free_depth_m"].values[0, 0]) == BALL_DEPTHS_M[1]
    onset = float(ds["onset_depth_m"].values[0, 0])
    assert BALL_DEPTHS_M[1] < onset < BALL_DEPTHS_M[2]  # interpolated in the growth rate
    a = ds.attrs
    assert a["criterion"] == "growth" and a["integrator_used"] == "rk4" and a["cells"] == 3
    assert json.loads(a["knocks_m"]) == [20e-6] and a["tolerance_m"] == 10e-6
    assert "chatter-free" in a["method_text"] and "RK4" in a["method_text"]
    assert a["boringbar_version"] == bb.__version__
    assert json.loads(json.dumps(cm.summary(ds)))["n_cells"] == 3


def test_a_ball_holds_a_growing_vibration_within_the_tolerance(ball_map):
    """0.068 mm at 1000 rpm: the small knock grows (onset chatter), yet it settles at about
    1 um peak-to-peak, in the cut: chatter-free from the small knock."""
    cell = ball_map.isel(case=0, rpm=0, depth_m=2)
    small = cell.sel(start="small knock")
    assert int(cell["onset"]) == 0 and float(cell["growth_rate_per_s"]) > 0
    assert str(small["settled_status"].values) == "settled"
    assert 0.1e-6 < float(small["settled_pp_m"]) < 10e-6 and not bool(small["left_cut"])
    assert int(small["chatter_free_by_start"]) == 1
    assert float(small["settled_rms_m"]) < float(small["settled_pp_m"])


def test_a_large_knock_never_makes_a_cell_more_chatter_free(ball_map):
    """Chatter-free needs every start: where the small knock alone is not, neither is the
    cell; at 0.058 mm a 20 um knock takes the tool out of the cut where a small one dies
    out."""
    ds = ball_map
    free = ds["chatter_free"].values
    small = ds["chatter_free_by_start"].sel(start="small knock").values
    assert not np.any((small == 0) & (free != 0))
    assert not np.any((free == 1) & (small != 1))
    by_start = ds["chatter_free_depth_by_start_m"].values
    assert np.all(ds["chatter_free_depth_m"].values <= by_start.min(axis=-1))
    cell = ds.isel(case=0, rpm=0, depth_m=1)
    assert int(cell["onset"]) == 1 and int(cell["chatter_free"]) == 0
    assert str(cell["settled_status"].sel(start="small knock").values) == "died out"
    assert bool(cell["left_cut"].sel(start="knock 20 um"))


def test_a_solid_bar_s_chatter_free_depth_is_its_lobes_limit():
    """A linear bar: the map's chatter-free depth is the lobes' limit (the same verdict) to
    the grid's resolution; below it a knock dies out (0 p-p), above it the tool leaves the
    cut."""
    solid = bb.make_system("solid")
    rpm = (1000.0, 1200.0)
    limits = bb.lobes(solid, bb.LobesOptions(rpm=rpm, verdict=VerdictOptions()))
    lobe_limit = limits["limit_depth_m"].values[0]
    depths = tuple(np.round(np.linspace(0.7, 1.3, 7) * lobe_limit.min(), 7))
    ds = bb.chatter_map(solid, bb.ChatterMapOptions(rpm=rpm, depths_m=depths,
                                                    verdict=VerdictOptions()))
    free = ds["chatter_free_depth_m"].values[0]
    first = ds["first_not_free_depth_m"].values[0]
    for j in range(len(rpm)):
        assert free[j] <= lobe_limit[j] * 1.01  # the lobes' 1 % geometric grid
        if math.isfinite(first[j]):
            assert lobe_limit[j] <= first[j] * 1.01
    pp = ds["settled_pp_m"].sel(start="small knock").values[0]
    left = ds["left_cut"].sel(start="small knock").values[0]
    below = ds["depth_m"].values[None, :] <= free[:, None]
    assert np.all(pp[below] == 0) and not left[below].any()
    assert below.any() and (~below).any() and left[~below].all()


def test_serial_and_threads_give_identical_datasets():
    solid = bb.make_system("solid")
    options = bb.ChatterMapOptions(rpm=(1000.0, 1100.0), depths_m=(0.03e-3, 0.06e-3),
                                   verdict=VerdictOptions(knocks_m=(20e-6,)))
    serial = bb.chatter_map(solid, options, execution=Execution("serial"))
    threads = bb.chatter_map(solid, options, execution=Execution("threads", 2))
    for ds in (serial, threads):
        for key in ATTRS_OF_WHERE:
            del ds.attrs[key]
    xr.testing.assert_identical(serial, threads)


def test_the_default_grid_follows_the_bars():
    """Default speeds: the boring speeds of the bar (30, evenly spaced in 1/rpm); a bar
    known by its modes alone: its lobes 1 to 3.  Default depths: 20 from 0.5 to 3 times
    the smallest bare-bar limit."""
    ball = bb.variants(bb.load_system(CARBIDE))["ball"]
    case = [bb.Case.of(ball)]
    rpm = cm.map_speeds(case)
    assert rpm == bb.boring_speeds(ball, n=30).rpm
    tapped = bb.make_system("solid", modal=bb.ModalModel.from_tap_test(
        frequency_hz=300.0, tip_stiffness_n_m=3e6))
    lobes = cm.map_speeds([bb.Case.of(tapped)])
    assert len(lobes) == 30
    assert lobes[0] == pytest.approx(60 * 300 / 3.1, abs=1) and lobes[-1] == 60 * 300 / 0.9
    limits = cm.host_limits(case, rpm, 850e6)
    depths = cm.map_depths(limits)
    assert len(depths) == 20
    assert depths[0] == pytest.approx(0.5 * np.nanmin(limits), abs=1e-7)
    assert depths[-1] == pytest.approx(3 * np.nanmin(limits), abs=1e-7)


@pytest.mark.parametrize("kwargs, name", [
    ({"depths_m": (0.0,)}, "depths_m"),
    ({"depths_m": (2e-5, 1e-5)}, "depths_m"),
    ({"rpm": (-1.0,)}, "rpm"),
    ({"workpiece": "unobtainium"}, "unobtainium"),
    ({"verdict": {"tolerance_m": 1e-5}}, "verdict"),
])
def test_options_name_the_bad_value(kwargs, name):
    with pytest.raises(bb.ParameterError, match=name):
        bb.ChatterMapOptions(**kwargs)


def test_the_exact_integrator_is_refused_before_any_run():
    with pytest.raises(bb.ParameterError, match="exact"):
        bb.chatter_map(bb.make_system("solid"), bb.ChatterMapOptions(rpm=(1000.0,),
                                                                     depths_m=(1e-5,)),
                       integration=bb.Integration(integrator="exact"))


# --- the command line ---------------------------------------------------------------

SMALL = ["--bar", "solid", "--rpm", "1000,1200", "--depth-mm", "0.03:0.06:2"]


def test_the_command_writes_its_files_and_json(tmp_path, capsys):
    out = tmp_path / "map"
    assert main(["chatter-map", *SMALL, "--workers", "2", "--out", str(out), "--json"]) == 0
    s = json_out(capsys)
    assert s["files"] == {"netcdf": str(out / "chatter_map.nc"),
                          "png": str(out / "chatter_map.png")}
    assert (out / "chatter_map.png").read_bytes()[:8] == PNG
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries
    assert s["starts"] == ["small knock", "knock 20 um"] and s["n_cells"] == 4  # the default
    (case,) = s["cases"]
    assert [v["rpm"] for v in case["speeds"]] == [1000.0, 1200.0]
    with xr.open_dataset(out / "chatter_map.nc") as ds:
        assert ds.sizes["depth_m"] == 2 and ds["depth_m"].values == pytest.approx([3e-5, 6e-5])
        assert float(ds["min_chatter_free_depth_m"].values[0]) == pytest.approx(
            case["min_chatter_free_depth_m"])
        text = map_text(ds.load())
    assert "chatter-free (mm)" in text and "bare-bar limit (mm)" in text
    assert "method: converged verdict" in text


@pytest.mark.parametrize("argv, knocks_m", [
    ([], (20e-6,)), (["--small-knock-only"], ()), (["--knock-um", "5,50"], (5e-6, 50e-6))])
def test_the_command_s_starts_are_the_library_s_unless_given(argv, knocks_m):
    args = build_parser("chatter-map").parse_args(["chatter-map", *argv])
    assert map_verdict(args).knocks_m == knocks_m and map_verdict(args).tolerance_m == 10e-6


@pytest.mark.parametrize("extra, name", [
    (["--tolerance-um", "0"], "--tolerance-um"),
    (["--depth-mm", "-0.01"], "--depth-mm"),
    (["--depth-mm", "0.05:0.02:3"], "--depth-mm"),
    (["--depth-mm", "0.02:0.05:0"], "--depth-mm"),
    (["--depth-mm", "0.05,0.02"], "--depth-mm"),
    (["--workpiece", "unobtainium"], "--workpiece"),
    (["--knock-um", "-1"], "--knock-um"),
    (["--rpm", "0"], "--rpm"),
    (["--duration-s", "1"], "--duration-s"),
    (["--start", "static"], "--start"),
    (["--integrator", "exact"], "exact"),
    (["--workers", "0"], "--workers"),
    (["--small-knock-only", "--knock-um", "5"], "--small-knock-only"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, extra, name):
    out = tmp_path / "map"
    argv = ["chatter-map", "--bar", "solid", "--rpm", "1000", "--depth-mm", "0.03",
            *extra, "--out", str(out)]
    assert_one_line_error(main, argv, out, name, capsys)


# --- the study file -----------------------------------------------------------------

STUDY = {"study": {"analysis": "chatter_map", "name": "tiny_map"},
         "bar": {"kind": "solid"},
         "analysis": {"depths_mm": [0.03, 0.06], "knocks_um": []},
         "grid": {"rpm": [1000, 1200]}}


def test_the_study_adapter_gives_the_function_s_dataset(tmp_path):
    study = study_from_dict(STUDY)
    ds = run_study(study, tmp_path / "tiny_map.nc", executor="serial")
    direct = bb.chatter_map(bb.make_system("solid"), bb.ChatterMapOptions(
        rpm=(1000.0, 1200.0), depths_m=(0.03e-3, 0.06e-3), verdict=VerdictOptions()))
    for name, var in direct.data_vars.items():
        xr.testing.assert_equal(ds[name], var)
    assert ds.attrs["study_analysis"] == "chatter_map"
    assert ds.attrs["method_text"] == direct.attrs["method_text"]
    again = run_study(study, tmp_path / "tiny_map.nc", executor="serial")  # done: read back
    xr.testing.assert_identical(ds, again)


def test_a_study_refuses_what_a_map_does_not_take():
    with pytest.raises(StudyError, match="forcing.start"):
        study_from_dict({**STUDY, "forcing": {"start": "static"}})
    with pytest.raises(StudyError, match="run.integrator"):
        study_from_dict({**STUDY, "run": {"integrator": "exact"}})
    with pytest.raises(StudyError, match="analysis.depths_mm"):
        study_from_dict({**STUDY, "analysis": {"depths_mm": [0.0]}})
    default = study_from_dict({"study": {"analysis": "chatter_map"}, "bar": {"kind": "solid"},
                               "grid": {"rpm": [1000]}})
    assert default.options["knocks_um"] == (20.0,) and default.options["depths_mm"] is None
