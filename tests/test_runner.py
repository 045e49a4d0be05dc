"""Running studies: executors give identical arrays, interrupted runs resume to the
same file, dead workers are survived, finished studies are not recomputed.

Studies are tiny (0.02-0.05 s simulated) so the file stays fast; the Dask tests
start a real LocalCluster of worker processes.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from same_data import assert_same_data

from boringbar.execute import Execution
from boringbar.simulate import Integration
from boringbar.studies.load import load_study, study_from_dict
from boringbar.studies.registry import ANALYSES
from boringbar.studies.runner import RunReport, run_study
from boringbar.studies.schema import StudyError

SMALL = {"study": {"analysis": "sweep", "name": "small"},
         "run": {"duration_s": 0.02}, "analysis": {"batch": 1},  # a point per run
         "grid": {"gap_mm": [0.5, 0.1], "friction": ["off", "on"], "force_n": [10.0, 20.0],
                  "ratio": [0.99, 1.01]}}
PROVENANCE = ("run_finished_utc", "run_wall_time_s", "run_executor", "run_workers")


def assert_same_run(a: xr.Dataset, b: xr.Dataset) -> None:
    """The same data bit for bit and the same attributes but the run's provenance."""
    assert_same_data(a, b)
    strip = lambda attrs: {k: v for k, v in attrs.items() if k not in PROVENANCE}  # noqa: E731
    assert strip(a.attrs) == strip(b.attrs)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "small.nc"
    ds = run_study(study_from_dict(SMALL), out, executor="serial")
    return out, ds


def test_result_file_is_self_explaining(reference):
    out, ds = reference
    assert "elapsed_s" not in ds.data_vars  # timings are provenance, not data
    cfg = json.loads(ds.attrs["study_config"])
    assert cfg["grid"]["gap_mm"] == [0.5, 0.1] and cfg["run"]["duration_s"] == 0.02
    assert study_from_dict(cfg).config_hash() == ds.attrs["study_config_hash"]
    assert ds.attrs["boringbar_version"] and ds.attrs["run_finished_utc"].endswith("Z")
    assert dict(ds.sizes) == {"case": 4, "force_n": 2, "ratio": 2}
    assert not out.with_name("small.nc.partial").exists()
    assert not list(out.parent.glob(".*.tmp"))


def test_processes_give_identical_arrays(reference, tmp_path):
    ds = run_study(study_from_dict(SMALL), tmp_path / "p.nc", executor="processes", workers=2,
                   chunk_size=3)
    assert_same_run(ds, reference[1])


def test_dask_local_cluster_gives_identical_arrays(reference, tmp_path):
    pytest.importorskip("distributed")
    report = RunReport()
    ds = run_study(study_from_dict(SMALL), tmp_path / "d.nc", dask_local=2, report=report)
    assert report.executor == "dask" and report.computed == 16
    assert_same_run(ds, reference[1])


def test_zarr_store_equals_netcdf(reference, tmp_path):
    pytest.importorskip("zarr")
    ds = run_study(study_from_dict(SMALL), tmp_path / "z.zarr", executor="serial")
    assert (tmp_path / "z.zarr").is_dir()
    assert_same_run(ds, reference[1])


def test_finished_study_is_not_recomputed(reference, tmp_path, monkeypatch):
    out = tmp_path / "f.nc"
    out.write_bytes(reference[0].read_bytes())
    import boringbar.studies.runner as runner

    def boom(*a, **k):
        raise AssertionError("recomputed")

    monkeypatch.setattr(runner, "compute_chunk", boom)
    # as left by a run killed between writing OUT and removing its chunks
    stale = tmp_path / "f.nc.partial"
    stale.mkdir()
    (stale / "manifest.json").write_text(json.dumps(
        {"config_hash": reference[1].attrs["study_config_hash"]}))
    report = RunReport()
    ds = run_study(study_from_dict(SMALL), out, executor="serial", report=report)
    assert report.skipped and report.computed == 0
    assert not stale.exists()
    assert_same_run(ds, reference[1])


def test_other_study_at_out_is_refused(reference, tmp_path):
    out = tmp_path / "f.nc"
    out.write_bytes(reference[0].read_bytes())
    other = dict(SMALL, run={"duration_s": 0.03})
    with pytest.raises(StudyError, match="different study"):
        run_study(study_from_dict(other), out, executor="serial")
    part = tmp_path / "g.nc.partial"
    part.mkdir()
    (part / "manifest.json").write_text(json.dumps({"config_hash": "0" * 64}))
    with pytest.raises(StudyError, match="unfinished chunks of a different study"):
        run_study(study_from_dict(SMALL), tmp_path / "g.nc", executor="serial")


@pytest.mark.parametrize("executor", ["processes", "dask"])
def test_a_worker_that_dies_is_survived(reference, tmp_path, monkeypatch, executor):
    if executor == "dask":
        pytest.importorskip("distributed")
    marker = tmp_path / "killed"
    monkeypatch.setenv("BORINGBAR_FAULT_KILL_CHUNK", "2")
    monkeypatch.setenv("BORINGBAR_FAULT_MARKER", str(marker))
    kw = {"dask_local": 2} if executor == "dask" else {"executor": "processes", "workers": 2}
    report = RunReport()
    ds = run_study(study_from_dict(SMALL), tmp_path / "w.nc", chunk_size=2, report=report, **kw)
    assert marker.exists()  # a worker process really died on chunk 2
    if executor == "processes":
        assert report.restarts
    assert_same_run(ds, reference[1])


def _study_file(tmp_path) -> Path:
    path = tmp_path / "kill.toml"
    path.write_text(
        '[study]\nanalysis = "sweep"\nname = "kill"\n[run]\nduration_s = 0.05\n'
        '[analysis]\nbatch = 1\n'
        '[grid]\ngap_mm = [0.5, 0.1]\nfriction = ["off", "on"]\n'
        'ratio = {start = 0.96, stop = 1.04, step = 0.01}\n')
    return path


def test_sigkill_then_resume_equals_uninterrupted_run(tmp_path):
    study = _study_file(tmp_path)
    out = tmp_path / "kill.nc"
    part = tmp_path / "kill.nc.partial"
    cmd = [sys.executable, "-m", "boringbar", "run", str(study), "--out", str(out),
           "--executor", "processes", "--workers", "2", "--chunk-size", "1", "--quiet"]
    # chunk 35 stalls, so the run is still going when it is killed, however fast
    # the other chunks finish
    env = dict(os.environ, BORINGBAR_FAULT_STALL_CHUNK="35")
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env)
    deadline = time.monotonic() + 120
    while len(list(part.glob("chunk-*.pkl"))) < 4:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no chunk finished in 120 s"
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    assert not out.exists()  # nothing finished-looking where the result belongs
    n_done = len(list(part.glob("chunk-*.pkl")))
    assert 4 <= n_done < 36

    rerun = subprocess.run(cmd[:-1] + ["--json"], capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stderr
    report = json.loads(rerun.stdout)
    assert report["resumed"] >= n_done and report["computed"] == 36 - report["resumed"]
    assert out.exists() and not part.exists()

    fresh = run_study(load_study(study), tmp_path / "fresh.nc", executor="serial")
    with xr.open_dataset(out) as resumed:
        assert_same_run(resumed.load(), fresh)


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    return True


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["TERM", "KILL"])
def test_a_stop_sent_to_the_main_process_alone_ends_its_workers(tmp_path, sig):
    """A scheduler or `kill PID` stops the main process alone.  SIGTERM is taken as
    Ctrl-C (exit 143, the workers ended with it); after SIGKILL each worker sees its
    parent gone and ends itself.  Either way no worker is left behind, and the finished
    chunks are kept."""
    study = _study_file(tmp_path)
    part = tmp_path / "kill.nc.partial"
    cmd = [sys.executable, "-m", "boringbar", "run", str(study), "--out",
           str(tmp_path / "kill.nc"), "--executor", "processes", "--workers", "2",
           "--chunk-size", "1", "--quiet"]
    env = dict(os.environ, BORINGBAR_FAULT_STALL_CHUNK="35")
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env)
    try:
        deadline = time.monotonic() + 120
        while len(list(part.glob("chunk-*.pkl"))) < 2:
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "no chunk finished in 120 s"
            time.sleep(0.05)
        os.kill(proc.pid, sig)
        _, err = proc.communicate(timeout=60)
        if sig == signal.SIGTERM:
            assert proc.returncode == 143 and err.decode().strip() == "boringbar: terminated"
        else:
            assert proc.returncode == -signal.SIGKILL
        deadline = time.monotonic() + 15
        while _group_alive(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not _group_alive(proc.pid), "a worker outlived its stopped parent"
        assert len(list(part.glob("chunk-*.pkl"))) >= 2
    finally:
        if _group_alive(proc.pid):
            os.killpg(proc.pid, signal.SIGKILL)


EXAMPLES = sorted((Path(__file__).parent.parent / "examples" / "studies").glob("*.toml"))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_studies_run_shortened(path, tmp_path):
    """Every shipped example runs end to end (runs shortened, grids thinned)."""
    import tomllib

    d = tomllib.loads(path.read_text())
    opts = d.get("analysis", {})
    if d["study"]["analysis"] == "chatter_map":  # its cuts run until their verdict, capped
        opts["max_run_s"] = 0.2
        if isinstance(opts.get("depths_mm"), dict):
            opts["depths_mm"] = [opts["depths_mm"]["start"], opts["depths_mm"]["stop"]]
    else:
        d.setdefault("run", {})["duration_s"] = 0.02
    for key in ("displacement_mm", "velocity_m_s"):
        if key in opts:
            opts[key]["count"] = 2
    if d["study"]["analysis"] == "bifurcation":
        opts["values"] = [5.0, 10.0]
    for key, axis in d.get("grid", {}).items():
        if isinstance(axis, dict):
            d["grid"][key] = [axis["start"], axis["stop"]]
    s = study_from_dict(d, str(path))
    report = RunReport()
    ds = run_study(s, tmp_path / ("out" + s.output_path().suffix), executor="serial",
                   report=report)
    assert report.computed == report.points > 0
    assert ds.attrs["study_name"] == s.name and ds.data_vars


def _in_process(name: str):
    """(study dict, the in-process function's Dataset) of the same tiny computation."""
    from boringbar.analysis.cases import Case
    from boringbar.model.system import make_system

    if name == "sweep":
        from boringbar.analysis.cases import published_cases
        from boringbar.analysis.sweep import SweepOptions, sweep

        cases = published_cases(bars=("solid", "ball"), gaps_m=(0.5e-3,))
        return ({"study": {"analysis": "sweep"}, "run": {"duration_s": 0.02},
                 "grid": {"kind": ["solid", "ball"], "friction": ["off", "on"],
                          "ratio": [0.99, 1.01]}},
                sweep(cases, SweepOptions([0.99, 1.01]), integration=Integration(duration_s=0.02),
                      execution=Execution(workers=1)))
    if name == "lobes":
        from boringbar.analysis.lobes import LobesOptions, lobes

        return ({"study": {"analysis": "lobes"}, "bar": {"kind": "solid"},
                 "run": {"duration_s": 0.05}, "grid": {"rpm": [1000.0, 1200.0]},
                 "analysis": {"depth_step_mm": 0.05, "max_depth_mm": 0.5}},
                lobes([Case("solid", make_system("solid"), "solid")],
                      LobesOptions([1000.0, 1200.0], depth_step_m=0.05e-3,
                                   max_depth_m=0.5e-3),  # the library's method: the search
                      integration=Integration(duration_s=0.05), execution=Execution(workers=1)))
    if name == "bifurcation":
        from boringbar.analysis.bifurcation import BifurcationOptions, bifurcation

        ref = bifurcation(make_system("ball"), BifurcationOptions("force", [5.0, 10.0]),
                          integration=Integration(duration_s=0.02))
        return ({"study": {"analysis": "bifurcation"}, "run": {"duration_s": 0.02},
                 "analysis": {"values": [5.0, 10.0]}},
                ref.expand_dims(case=["ball gap=0.5mm friction=on"]).assign_coords(
                    bar=("case", ["ball"]), gap_m=("case", [0.5e-3]),
                    friction=("case", ["on"])))
    if name == "chatter_map":
        from boringbar.analysis.chatter_map import ChatterMapOptions, chatter_map
        from boringbar.analysis.verdict import VerdictOptions

        return ({"study": {"analysis": "chatter_map"}, "bar": {"kind": "solid"},
                 "analysis": {"depths_mm": [0.03, 0.06], "knocks_um": [20]},
                 "grid": {"rpm": [1200]}},
                chatter_map(make_system("solid"),
                            ChatterMapOptions((1200.0,), (0.03e-3, 0.06e-3),
                                              verdict=VerdictOptions(knocks_m=(20e-6,))),
                            execution=Execution(workers=1)))
    if name == "basins":
        from boringbar.analysis.basins import BasinOptions, basins

        return ({"study": {"analysis": "basins"}, "run": {"duration_s": 0.02},
                 "analysis": {"displacement_mm": {"start": -1, "stop": 1, "count": 2},
                              "velocity_m_s": {"start": -1, "stop": 1, "count": 2}}},
                basins(make_system("ball"),
                       BasinOptions((-1e-3, 1e-3, 2), (-1.0, 1.0, 2), force_n=10.0, ratio=1.0),
                       integration=Integration(duration_s=0.02), execution=Execution(workers=1)))
    if name == "sensitivity":
        from boringbar.analysis.sensitivity import SensitivityOptions, sensitivity

        return ({"study": {"analysis": "sensitivity"}, "run": {"duration_s": 0.02},
                 "analysis": {"kind": "ball"}},
                sensitivity(SensitivityOptions("ball"), integration=Integration(duration_s=0.02),
                            execution=Execution(workers=1)))
    raise AssertionError(f"no in-process reference for the analysis {name!r}: add one")


@pytest.mark.parametrize("name", sorted(ANALYSES))
def test_study_result_equals_the_in_process_function(name, tmp_path):
    """A study gives the in-process function's variables and values, bit for bit
    (wall-clock timings aside), for every registered analysis."""
    d, ref = _in_process(name)
    ds = run_study(study_from_dict(d), tmp_path / "s.nc", executor="serial")
    ref = ref.drop_vars(["elapsed_s"], errors="ignore")
    assert set(ds.data_vars) == set(ref.data_vars)
    for k in ref.data_vars:
        x, y = ds[k].values, ref[k].values
        if k in ("tip_displacement_m", "tip_velocity_m_s"):
            x = x[..., : y.shape[-1]]
        assert x.shape == y.shape, k
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), k
    assert set(ref.coords) <= set(ds.coords)


def test_every_analysis_has_an_example_study():
    assert {load_study(p).analysis for p in EXAMPLES} == set(ANALYSES)


def test_basins_of_several_operating_points_stack_the_single_point_results(tmp_path):
    from boringbar.analysis.basins import BasinOptions, basins
    from boringbar.model.system import make_system

    grid = {"displacement_mm": {"start": -1, "stop": 1, "count": 2},
            "velocity_m_s": {"start": -1, "stop": 1, "count": 2}}
    ds = run_study(study_from_dict({"study": {"analysis": "basins"}, "run": {"duration_s": 0.02},
                                    "grid": {"friction": ["off", "on"], "force_n": [10, 20]},
                                    "analysis": grid}),
                   tmp_path / "b.nc", executor="serial")
    assert list(ds["case"].values)[3] == "ball gap=0.5mm friction=on F0=20N"
    ref = basins(make_system("ball", friction=True),
                 BasinOptions((-1e-3, 1e-3, 2), (-1.0, 1.0, 2), force_n=20.0, ratio=1.0),
                 integration=Integration(duration_s=0.02), execution=Execution(workers=1))
    one = ds.isel(case=3)
    for k in ref.data_vars:
        y = ref[k].values
        x = one[k].values[tuple(slice(0, n) for n in y.shape)]
        assert np.array_equal(x, y, equal_nan=y.dtype.kind == "f"), k
    assert int(ds["count"].sum()) == 4 * 4  # every cell of every operating point


def test_exact_integrator_study_equals_the_in_process_sweep(tmp_path):
    from boringbar.analysis.cases import published_cases
    from boringbar.analysis.sweep import SweepOptions, sweep

    d = {"study": {"analysis": "sweep"}, "run": {"duration_s": 0.02, "integrator": "exact"},
         "damper": {"static_ratio": 1.5}, "grid": {"ratio": [0.99, 1.01]}}
    ds = run_study(study_from_dict(d), tmp_path / "e.nc", executor="processes", workers=2)
    ref = sweep(published_cases(bars=("ball",), gaps_m=(0.5e-3,), frictions=(True,),
                                static_ratio=1.5),
                SweepOptions([0.99, 1.01]), execution=Execution(workers=1),
                integration=Integration(duration_s=0.02, integrator="exact"))
    assert ds.attrs["integrator"] == "exact"
    for k in ds.data_vars:
        assert np.array_equal(ds[k].values, ref[k].values,
                              equal_nan=ds[k].dtype.kind == "f"), k


def test_cli_run_json_then_skipped(tmp_path, capsys):
    from cli_output import json_out

    from boringbar.cli.main import main

    study = tmp_path / "s.toml"
    study.write_text('[study]\nanalysis = "sweep"\nname = "s"\nout = "res.nc"\n'
                     '[analysis]\nbatch = 1\n'
                     '[run]\nduration_s = 0.02\n[grid]\nratio = [0.99, 1.0]\n')
    assert main(["run", str(study), "--executor", "serial", "--json"]) == 0
    first = json_out(capsys)
    assert first["points"] == 2 and first["computed"] == 2 and not first["skipped"]
    assert first["out"] == str(tmp_path / "res.nc") and (tmp_path / "res.nc").exists()
    assert main(["run", str(study), "--json", "--quiet"]) == 0
    again = json_out(capsys)
    assert again["skipped"] and again["computed"] == 0
    assert main(["run", str(study), "--executor", "serial", "--scheduler", "tcp://x:1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("boringbar: error:") and "scheduler" in err
