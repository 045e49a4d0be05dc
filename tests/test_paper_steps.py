"""``boringbar paper`` runs each step with the library; the command shown beside it in
the report must reproduce the same numbers.  For the cheapest steps of the quick
study, the step's library run and its command line write into two directories and
every NetCDF data variable must agree bit for bit."""

import numpy as np
import pytest
import xarray as xr

from boringbar.cli.main import build_parser, main
from boringbar.model.system import make_system
from boringbar.report.paper import COLUMNS, PRESET_ORDER, published_steps
from boringbar.simulate import resolve_integrator

STEPS = {s.key: s for s in published_steps(quick=True)}


@pytest.mark.parametrize("quick", [True, False])
def test_every_step_command_is_a_valid_command_line(quick):
    for step in published_steps(quick):
        for col in COLUMNS.values() if step.variants else [COLUMNS["paper"]]:
            argv = step.for_column(col.name).argv
            args = build_parser(argv[0]).parse_args([*argv, *col.flags, "--out", "x"])
            assert args.command == step.argv[0]


@pytest.mark.parametrize(("key", "column"), [("sensitivity-restitution", "paper"),
                                           ("basins-10N-r1.01-on", "paper"),
                                           ("sensitivity-restitution", "paper-reciprocal"),
                                           ("sensitivity-restitution",
                                            "physical-paper-friction"),
                                           ("sensitivity-restitution", "physical-rolling")])
def test_library_step_is_its_command_bit_for_bit(key, column, tmp_path):
    step, col = STEPS[key], COLUMNS[column]
    lib, cli = tmp_path / "library", tmp_path / "cli"
    summary = step.run(col, lib)
    assert main([*step.argv, *col.flags, "--out", str(cli), "--quiet"]) == 0
    ncs = sorted(p.name for p in lib.glob("*.nc"))
    assert ncs and ncs == sorted(p.name for p in cli.glob("*.nc"))
    assert summary["files"]["netcdf"] == str(lib / ncs[0])
    for name in ncs:
        with xr.open_dataset(lib / name) as a, xr.open_dataset(cli / name) as b:
            assert set(a.data_vars) == set(b.data_vars)
            for var in a.data_vars:
                if var == "elapsed_s":  # wall time of each run
                    continue
                u, v = a[var].values, b[var].values
                assert u.shape == v.shape, var
                if u.dtype.kind in "fc":
                    assert np.array_equal(u, v, equal_nan=True), var
                else:
                    assert np.array_equal(u, v), var
            skip = {"wall_time_s", "elapsed_s"}
            assert {k: str(v) for k, v in a.attrs.items() if k not in skip} == \
                {k: str(v) for k, v in b.attrs.items() if k not in skip}


def test_the_published_ball_dampers_take_rk4_under_paper_and_exact_under_physical():
    """Under "auto" the paper preset's published ball dampers take RK4 and the physical
    preset's the exact integrator (docs/model.md, 5.3)."""
    for gap in (0.1e-3, 0.5e-3):
        for friction in (False, True):
            assert [resolve_integrator("auto", make_system("ball", p, gap_m=gap, friction=friction))
                    for p in PRESET_ORDER] == ["rk4", "exact"]


@pytest.mark.parametrize("quick", [True, False])
def test_the_continuation_starts_after_the_diagrams_it_overlays(quick):
    """Two steps run at once: the continuation draws each bifurcation step's diagram
    under its branches, so it names those steps as the ones it comes after."""
    steps = {s.key: s for s in published_steps(quick)}
    diagrams = {k for k, s in steps.items() if s.section == "bifurcation"}
    assert len(diagrams) == 4 and set(steps["continuation"].after) == diagrams
    for step in steps.values():
        assert set(step.after) <= set(steps), step.key
