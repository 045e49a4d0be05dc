"""The ``boringbar`` command end to end, on real files (STYLE.md tier 4).

Runs are short (0.02-0.05 s simulated) so the file stays fast; the physics
is tested elsewhere, here only what the command promises: its files, its
JSON, its exit codes and its one-line errors.
"""

import argparse
import importlib
import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr
from cli_output import assert_one_line_error, json_out

from boringbar.cli.main import COMMANDS, TERM_GRACE_S, main

SIMULATE_KEYS = {"natural_frequency_hz", "rms_tip_m", "pattern", "impacts_per_cycle",
                 "max_abs_rel_disp_m", "preset", "integrator", "elapsed_s", "files"}


def test_simulate_json_files_and_config(tmp_path, capsys):
    out = tmp_path / "run"
    rc = main(["simulate", "--bar", "ball", "--gap-mm", "0.1", "--force-n", "20",
               "--duration-s", "0.05", "--out", str(out), "--json"])
    assert rc == 0
    s = json_out(capsys)
    assert SIMULATE_KEYS <= s.keys()
    assert s["preset"] == "physical" and s["integrator"] == "exact" and s["bar"] == "ball"
    assert s["rms_tip_m"] > 0 and isinstance(s["pattern"], str)
    assert 0 < s["max_abs_rel_disp_m"] <= 0.05e-3 + 1e-12  # never beyond the wall

    assert s["files"] == {"netcdf": str(out / "run.nc"), "png": str(out / "run.png"),
                          "summary": str(out / "summary.json")}
    for path in s["files"].values():
        assert Path(path).stat().st_size > 0
    assert (out / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporaries
    with xr.open_dataset(out / "run.nc") as ds:
        config = json.loads(ds.attrs["config"])
        assert config["system"]["damper"]["gap_m"] == pytest.approx(0.1e-3)
        assert config["forcing"]["amplitude_n"] == 20
        assert {"tip_displacement_m", "y_m", "force_n"} <= set(ds.data_vars)
        assert 20000 <= ds.sizes["time_s"] <= 40000  # default record_every: ~20000 rows
    saved = json.loads((out / "summary.json").read_text())
    assert saved["rms_tip_m"] == s["rms_tip_m"] and "config" in saved


@pytest.mark.parametrize("bar", ["solid", "tmd"])
def test_simulate_text_summary(tmp_path, capsys, bar):
    rc = main(["simulate", "--bar", bar, "--duration-s", "0.02", "--record-every", "10",
               "--out", str(tmp_path)])
    assert rc == 0
    text = capsys.readouterr().out
    assert f"{bar} bar" in text and "natural frequency" in text and "tip RMS" in text
    with xr.open_dataset(tmp_path / "run.nc") as ds:
        assert ds.sizes["time_s"] == 2000


def test_simulate_quiet_prints_nothing(tmp_path, capsys):
    assert main(["simulate", "--bar", "solid", "--duration-s", "0.01", "--quiet",
                 "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""
    assert (tmp_path / "run.nc").exists()


def test_sweep_files_and_json(tmp_path, capsys):
    out = tmp_path / "sweep"
    rc = main(["sweep", "--bar", "solid", "--bar", "ball", "--gap-mm", "0.1", "--friction",
               "off", "--ratios", "0.98:1.0:0.01", "--force-n", "10,20", "--duration-s",
               "0.05", "--workers", "2", "--out", str(out), "--json"])
    assert rc == 0
    captured = capsys.readouterr()
    # stdout is the JSON alone; a log (not a terminal) gets the progress lines on stderr
    assert all(line.startswith("boringbar sweep: ") and " batches of runs, " in line
               for line in captured.err.splitlines())
    s = json.loads(captured.out)
    assert len(s["cases"]) == 2 * 2  # (solid, ball) x (10 N, 20 N)
    for case in s["cases"]:
        assert case["ratio"] == pytest.approx([0.98, 0.99, 1.0])
        assert len(case["rms_tip_m"]) == len(case["pattern"]) == 3
    assert {c["bar"] for c in s["cases"]} == {"solid", "ball"}
    with xr.open_dataset(out / "sweep.nc") as ds:
        assert dict(ds.sizes) == {"case": 2, "force_n": 2, "ratio": 3}
        assert "systems" in ds.attrs
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["sweep_F10N.png", "sweep_F20N.png"]  # one figure per force
    assert s["files"]["png"] == [str(out / p) for p in pngs]


def test_sweep_table_one_force(tmp_path, capsys):
    rc = main(["sweep", "--bar", "tmd", "--ratios", "1.0", "--force-n", "10",
               "--duration-s", "0.02", "--out", str(tmp_path)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "F0 = 10 N" in text and "tmd" in text
    assert (tmp_path / "sweep.png").exists()


@pytest.mark.parametrize("argv, name", [
    (["simulate", "--gap-mm", "-0.1"], "--gap-mm"),
    (["simulate", "--restitution", "1.5"], "--restitution"),
    (["simulate", "--dt-s", "1e-3", "--duration-s", "0.01"], "dt"),
    (["simulate", "--no-such-option", "1"], "--no-such-option"),
    (["simulate", "--force-n", "ten"], "--force-n"),
    (["simulate", "--friction", "maybe"], "--friction"),
    (["simulate", "--bar", "solid", "--gap-mm", "0.1"], "--gap-mm"),
    (["simulate", "--ball-position-mm", "0.3"], "--ball-position-mm"),
    (["sweep", "--ratios", "1.05:0.95:0.01"], "--ratios"),
    (["sweep", "--ratios", "0.95-1.05"], "--ratios"),
    (["sweep", "--gap-mm", "0.5,-1"], "--gap-mm"),
    (["sweep", "--bar", "solid,boat"], "--bar"),
    ([], "COMMAND"),
])
def test_bad_input_one_line_exit_2(tmp_path, capsys, argv, name):
    out = tmp_path / "out"
    assert_one_line_error(main, argv + ["--out", str(out)] if argv else argv, out, name, capsys)


def test_console_script_and_module(tmp_path):
    script = Path(sys.executable).with_name("boringbar")
    if not script.exists():
        pytest.skip("console script not installed (pip install -e .)")
    proc = subprocess.run([str(script), "simulate", "--bar", "solid", "--duration-s", "0.02",
                           "--json", "--out", str(tmp_path)], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["bar"] == "solid"
    assert (tmp_path / "run.nc").exists()
    proc = subprocess.run([sys.executable, "-m", "boringbar", "simulate", "--restitution", "2"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.startswith("boringbar: error: --restitution")


def test_the_help_lines_are_the_commands_own_and_help_imports_no_command():
    """--help lists every command with the line its module gives it, without importing
    the modules (the design search's Optuna, the FRF fit's SciPy signal tools) or the
    analyses' xarray (the shared options parse their grids with analysis/cases.py)."""
    for name, (module, add, summary) in COMMANDS.items():
        parser = argparse.ArgumentParser()
        sub = parser.add_subparsers()
        getattr(importlib.import_module(module), add)(sub)
        own = {a.dest: a.help for a in sub._choices_actions}
        assert own[name] == summary, name
    code = ("import sys; from boringbar.cli.main import main; main(['--help']); "
            "print(*sorted(m for m in sys.modules if m.startswith('boringbar.cli.') "
            "and m not in ('boringbar.cli.main', 'boringbar.cli.options', "
            "'boringbar.cli.orientation')), "
            "'optuna' in sys.modules, 'scipy.signal' in sys.modules, 'xarray' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()[-1]
    assert out == "False False False"


def test_commands_without_out_write_to_their_own_folders(tmp_path, monkeypatch, capsys):
    """No --out: out/COMMAND/NAME (NAME the input file's, or published, and the bars
    given), so that one command's summary.json never replaces another's, nor one bar's
    another bar's."""
    monkeypatch.chdir(tmp_path)
    system = Path(__file__).resolve().parents[1] / "examples/systems/steel_coolant_tmd.toml"
    assert main(["simulate", "--force-n", "10", "--duration-s", "0.02", "--quiet"]) == 0
    assert main(["simulate", "--system", str(system), "--bar", "tmd", "--force-n", "10",
                 "--duration-s", "0.02", "--quiet"]) == 0
    assert main(["simulate", "--system", str(system), "--bar", "solid", "--force-n", "10",
                 "--duration-s", "0.02", "--quiet"]) == 0
    assert main(["modes", "--quiet"]) == 0
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*.json"))
    assert written == ["out/modes/published/modes.json",
                       "out/simulate/published/summary.json",
                       "out/simulate/steel_coolant_tmd-solid/summary.json",
                       "out/simulate/steel_coolant_tmd-tmd/summary.json"]


@pytest.mark.parametrize("command", [["simulate"], ["paper", "--quick"], ["sweep"]])
def test_an_out_that_is_a_file_is_refused_before_any_run(command, tmp_path, capsys):
    """--out naming a file, or a folder inside one, is bad input (exit 2, one line), found
    before the work runs, not an I/O error once it is done."""
    afile = tmp_path / "afile"
    afile.write_text("mine")
    for out in (afile, afile / "sub"):
        assert main([*command, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("boringbar: error: --out = ") and len(err.splitlines()) == 1
    assert afile.read_text() == "mine"


def test_an_unknown_option_points_to_its_command_s_help_and_a_near_name(capsys):
    assert main(["simulate", "--gapmm", "0.1"]) == 2
    err = capsys.readouterr().err
    assert err == ("boringbar: error: unrecognized arguments: --gapmm 0.1; did you mean "
                   "--gap-mm? (see 'boringbar simulate --help')\n")
    assert main(["lobes", "--frobnicate", "3"]) == 2
    assert capsys.readouterr().err.endswith("--frobnicate 3 (see 'boringbar lobes --help')\n")


def test_a_missing_fit_is_named_by_its_option(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["lobes", "--analytic", "--frf", str(tmp_path / "nosuch.json"), "--out",
                 str(out)]) == 2
    assert capsys.readouterr().err.startswith("boringbar: error: --frf = ")
    assert not out.exists()


def test_run_s_out_is_its_result_file_and_a_finished_one_is_kept(tmp_path, capsys):
    """run's --out names the result file (.nc), not a folder: a second run of a finished
    study keeps it (nothing recomputed), where the other commands refuse a file."""
    study = tmp_path / "s.toml"
    study.write_text('[study]\nanalysis = "sweep"\nname = "tiny"\n[run]\nduration_s = 0.01\n'
                     '[grid]\ngap_mm = [0.5]\nfriction = ["off"]\nforce_n = [10.0]\n'
                     'ratio = [1.0]\n')
    out = tmp_path / "r.nc"
    for _ in range(2):
        assert main(["run", str(study), "--out", str(out), "--executor", "serial",
                     "--quiet"]) == 0
    assert out.is_file()


def test_a_log_gets_a_progress_line_at_each_tenth_and_quiet_gets_none(tmp_path, capsys):
    """Where stderr is not a terminal (a job's log), a long command says how far it is in
    plain lines, about one a tenth of the work, the last at the end; --quiet says
    nothing."""
    argv = ["lobes", "--bar", "solid", "--rpm", "1000:1400:20", "--out", str(tmp_path)]
    assert main(argv) == 0
    lines = capsys.readouterr().err.strip().splitlines()
    assert 2 <= len(lines) <= 12
    assert all(line.startswith("boringbar lobes: ") and " (case, speed) columns, " in line
               for line in lines)
    assert lines[-1].startswith("boringbar lobes: 21/21 ")
    assert main([*argv, "--quiet"]) == 0
    assert capsys.readouterr().err == ""


# The one interruption lost wherever it lands after "ready": in the sleep, or on the
# inner loop's jump back (the outer try)
SWALLOWER = """
import sys, time
from boringbar.cli.main import _sigterm_as_interrupt
with _sigterm_as_interrupt():
    try:
        print("ready", flush=True)
        while True:
            try:
                time.sleep(0.05)
            except BaseException:  # as a weakref callback or a __del__ loses it
                pass
    except BaseException:
        while True:
            time.sleep(0.05)
"""


def test_a_sigterm_whose_interruption_is_lost_still_ends_the_process():
    """The interruption a SIGTERM raises can land where Python drops it (a weakref callback:
    a page's server kept serving); the default SIGTERM then ends the process after the
    grace period."""
    proc = subprocess.Popen([sys.executable, "-c", SWALLOWER], stdout=subprocess.PIPE,
                            text=True)
    assert proc.stdout.readline().strip() == "ready"
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=TERM_GRACE_S + 10) == -signal.SIGTERM
