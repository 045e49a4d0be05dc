"""``boringbar paper``: the published study under both presets, end to end.

One quick study (about a minute on 2 cores) is started in a subprocess,
killed with SIGKILL after its first steps have finished, and run again to
the end with the same command; every test below reads what that left on
disk.  The report is opened in headless Chromium (Debian's ``chromium``,
installed by ``.ci/run``), which counts the figures that loaded.
"""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
from cli_output import assert_one_line_error

from boringbar.cli.main import main
from boringbar.io import atomic_path, remove_stale_temporaries
from boringbar.report.audit import audit
from boringbar.report.audit_data import VERDICTS
from boringbar.report.html import _mm, write_report
from boringbar.report.paper import (
    COLUMN_ORDER,
    COLUMNS,
    PRESET_ORDER,
    VARIANT_ORDER,
    published_steps,
)

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
STEPS = published_steps(quick=True)
# each preset runs every step; each further column every step but the design searches
N_STEPS = (len(STEPS) * len(PRESET_ORDER) + sum(s.variants for s in STEPS) * len(VARIANT_ORDER)
           + 1)  # + corrections


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper") / "out"
    cmd = [sys.executable, "-m", "boringbar", "paper", "--quick", "--out", str(out)]
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    deadline = time.monotonic() + 600
    while len(list(out.glob("*/*/summary.json"))) < 2:  # sweep and lobes of 'paper'
        assert proc.poll() is None, proc.stderr.read().decode()
        assert time.monotonic() < deadline
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    proc.stderr.close()
    finished = {(p.parent.parent.name, p.parent.name) for p in out.glob("*/*/summary.json")}
    killed = {"report": (out / "report.html").exists(),
              "manifest": (out / "manifest.json").exists()}
    rerun = subprocess.run([*cmd, "--json"], capture_output=True, text=True, timeout=900)
    assert rerun.returncode == 0, rerun.stderr
    lines = rerun.stdout.strip().splitlines()
    assert len(lines) == 1  # exactly one JSON object on stdout
    return {"out": out, "finished": finished, "killed": killed,
            "manifest": json.loads(lines[0]), "stderr": rerun.stderr}


def test_killed_study_resumes_with_only_the_missing_steps(study):
    assert study["killed"] == {"report": False, "manifest": False}  # written last
    assert len(study["finished"]) >= 2
    steps = study["manifest"]["steps"]
    assert len(steps) == N_STEPS
    reused = {(r["preset"], r["key"]) for r in steps if r["reused"]}
    assert reused == study["finished"]  # every finished step kept, nothing else
    assert study["stderr"].count("done before, kept") == len(study["finished"])
    assert study["manifest"]["compute_time_s"] > study["manifest"]["wall_time_s"]
    assert not list(study["out"].rglob("*.tmp"))  # atomic writes leave no temporaries


def test_every_published_analysis_under_both_presets(study):
    steps = study["manifest"]["steps"]
    keys = {r["key"] for r in steps}
    for key in ("sweep", "lobes", "bifurcation-gap0.1-frictionoff", "basins-20N-r1.00-off",
                "sensitivity-restitution", "corrections"):
        assert key in keys
    for rec in steps:
        if rec["key"] == "corrections":
            continue
        # a further column's step without friction is its preset's record, shared
        column = COLUMNS[rec.get("shared_from", rec["preset"])]
        assert rec["command"].startswith("boringbar ") and " ".join(column.flags) in \
            rec["command"]
        with xr.open_dataset(rec["summary"]["files"]["netcdf"]) as ds:
            assert ds.attrs["preset"] == column.preset  # each file says what it is
            if column.overrides and "design" not in rec["key"]:
                # a further column's file carries its friction: the paper's, reciprocal
                assert '"kind": "paper-number", "value": 0.6, "reaction": "reciprocal"' in \
                    str(ds.attrs), rec["key"]
        for png in _pngs(rec["summary"]["files"]):
            assert Path(png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_numbers_are_the_files_numbers(study):
    out = study["out"]
    html = (out / "report.html").read_text()
    for preset in PRESET_ORDER:
        with xr.open_dataset(out / preset / "lobes" / "lobes.nc") as ds:
            for case, depth in zip(ds["case"].values, ds["min_chatter_free_depth_m"].values,
                                   strict=True):
                assert f"<td>{case}</td><td>{_mm(depth)}</td>" in html
    with xr.open_dataset(out / "corrections" / "ladder.nc") as ladder:
        rms = float(ladder["rms_tip_m"].sel(rung="physical").values[0])
        assert f"<td>{_mm(rms)} [" in html
    # the printed impact law is the one that breaks momentum and creates energy
    imp = json.loads((out / "corrections" / "summary.json").read_text())["summary"][
        "impact_law"]
    assert imp["momentum_change_max"]["corrected"] < 1e-12
    assert imp["momentum_change_max"]["printed"] > 0.1
    assert imp["impacts_gaining_energy"]["corrected"] == 0
    assert imp["impacts_gaining_energy"]["printed"] > 0
    for anchor in ("sweeps", "lobes", "bifurcation", "basins", "sensitivity", "corrections",
                   "cannot"):
        assert f"id='{anchor}'" in html


def test_report_is_rebuilt_from_the_files_alone(study):
    out = study["out"]
    before = (out / "report.html").read_text()
    assert write_report(out) == out / "report.html"
    assert (out / "report.html").read_text() == before


def test_report_renders_every_figure_in_headless_chromium(study, tmp_path):
    if CHROMIUM is None:
        if os.environ.get("CI"):
            pytest.fail("CI must install Debian's chromium (.ci/run does)")
        pytest.skip("no chromium on this machine (apt-get install chromium)")
    report = study["out"] / "report.html"
    html = report.read_text()
    srcs = re.findall(r'<img src="([^"]+)"', html)
    assert len(srcs) >= 2 * 12
    for src in srcs:  # relative links, so the folder can be moved or served
        assert not Path(src).is_absolute() and (report.parent / src).is_file()
    flags = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}",
             "--virtual-time-budget=10000"]
    dom = subprocess.run([*flags, "--dump-dom", report.as_uri()], capture_output=True,
                         text=True, timeout=120)
    # the page's script counts the images that loaded with a width
    loaded = re.search(r'data-figures="(\d+)/(\d+)"', dom.stdout)
    assert loaded, dom.stderr[-2000:]
    assert int(loaded.group(1)) == int(loaded.group(2)) == len(srcs)
    shot = tmp_path / "report.png"
    subprocess.run([*flags, "--window-size=1400,3000", f"--screenshot={shot}",
                    report.as_uri()], capture_output=True, timeout=120)
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 100_000


def test_bad_presets_is_one_line_error(tmp_path, capsys):
    out = tmp_path / "p"
    assert_one_line_error(main, ["paper", "--presets", "paper,nope", "--out", str(out)], out,
                          "--presets", capsys)


def _pngs(files: dict) -> list[str]:
    out = []
    for key, value in files.items():
        if "png" in key:
            out += value if isinstance(value, list) else [value]
    return out


def test_the_audit_judges_every_claim_of_this_output(study, capsys):
    """boringbar audit on the quick study: 29 claims, a verdict under each preset; the
    report opens with the same table (tests/test_audit.py tests each check)."""
    out = study["out"]
    assert main(["audit", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["quick"] is True and s["presets"] == list(COLUMN_ORDER)
    assert len(s["claims"]) == 29
    for c in s["claims"]:
        assert {"id", "verdict", "published", "measured"} <= c.keys()
        assert set(c["verdict"]) == set(COLUMN_ORDER)
        assert all(v in VERDICTS for v in c["verdict"].values())
        # every claim has a verdict under both presets
        assert all(c["verdict"][p] != "not available" for p in PRESET_ORDER), c["id"]
    for column in COLUMN_ORDER:
        assert sum(s["counts"][column].values()) == 29
    assert s == json.loads(json.dumps(audit(out)))  # the command is the function
    html = (out / "report.html").read_text()
    assert html.index("id='audit'") < html.index("id='cannot'") < html.index("id='sweeps'")
    assert html.count("class='v-") == len(COLUMN_ORDER) * 29


def test_a_step_rerun_removes_what_a_kill_mid_write_left(tmp_path):
    """A temporary of an atomic write interrupted by a kill is removed when its step
    runs again; finished files and other names stay."""
    (tmp_path / "lobes.nc").write_text("finished")
    (tmp_path / "notes.tmp").write_text("not ours: no leading dot")
    left = tmp_path / ".lobes.png.8h_zunot.tmp"
    left.write_text("half a figure")
    with atomic_path(tmp_path / "run.json") as tmp:
        tmp.write_text("{}")
    assert remove_stale_temporaries(tmp_path) == [left]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lobes.nc", "notes.tmp", "run.json"]
