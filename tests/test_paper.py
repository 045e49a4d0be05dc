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

import numpy as np
import pytest
import xarray as xr
from cli_output import assert_one_line_error

from boringbar.cli.main import main
from boringbar.io import atomic_path, remove_stale_temporaries
from boringbar.plot import (
    plot_basins,
    plot_bifurcation,
    plot_lobe_examples,
    plot_lobes,
    plot_sweep,
)
from boringbar.plot.cut_orbits import plot_cut_orbits
from boringbar.plot.design import plot_design, plot_design_comparison
from boringbar.plot.orbits import plot_continuation
from boringbar.plot.style import smallest_text_px
from boringbar.plot.variations import plot_ladder, plot_sensitivity
from boringbar.report.audit import audit
from boringbar.report.audit_data import VERDICTS
from boringbar.report.html import _mm, write_report
from boringbar.report.paper import (
    COLUMNS,
    PRESET_ORDER,
    VARIANT_ORDER,
    published_steps,
    run_paper,
)

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
STEPS = published_steps(quick=True)
# each preset runs every step; each further column every step but the design searches
#: the columns the study here runs: all but the rolling ball's, whose steps take
#: another 30 s of CPU (test_the_rolling_ball_s_column below runs it alone)
STUDIED = tuple(c for c in PRESET_ORDER + VARIANT_ORDER if c != "physical-rolling")
VARIANTS = tuple(c for c in STUDIED if c in VARIANT_ORDER)
N_STEPS = (len(STEPS) * len(PRESET_ORDER) + sum(s.variants for s in STEPS) * len(VARIANTS)
           + 1)  # + corrections


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper") / "out"
    cmd = [sys.executable, "-m", "boringbar", "paper", "--quick", "--out", str(out),
           "--presets", ",".join(STUDIED)]
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
    dom = _chromium(tmp_path, "--dump-dom", report.as_uri())
    # the page's script counts the images that loaded with a width
    loaded = re.search(r'data-figures="(\d+)/(\d+)"', dom.stdout)
    assert loaded, dom.stderr[-2000:]
    assert int(loaded.group(1)) == int(loaded.group(2)) == len(srcs)
    shot = tmp_path / "report.png"
    _chromium(tmp_path, f"--screenshot={shot}", report.as_uri())
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 100_000


def _chromium(tmp_path, *args):
    """Headless Chromium at the window of a desktop browser (1400 px: the presets side by
    side); raises when it is not installed."""
    if CHROMIUM is None:
        if os.environ.get("CI"):
            pytest.fail("CI must install Debian's chromium (.ci/run does)")
        pytest.skip("no chromium on this machine (apt-get install chromium)")
    flags = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
             "--no-first-run", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", f"--user-data-dir={tmp_path / 'profile'}",
             "--virtual-time-budget=10000", "--window-size=1400,3000"]
    return subprocess.run([*flags, *args], capture_output=True, text=True, timeout=120)


def test_report_shows_the_figures_first_each_linked_to_its_png(study):
    html = (study["out"] / "report.html").read_text()
    audit_at = html.index("id='audit'")
    figures = [m.start() for m in re.finditer("<img ", html)]
    assert figures and max(figures) < audit_at  # every figure before the audit
    for anchor in ("sweeps", "lobes", "bifurcation", "basins", "sensitivity", "design"):
        assert html.index(f"id='{anchor}'") < audit_at
    linked = re.findall(r"<a class='fig' id='([^']+)' href=\"([^\"]+)\"[^>]*><img src=\"([^\"]+)\"",
                        html)
    assert len(linked) == len(figures)  # every figure, linked to its own full-size PNG
    assert all(href == src for _, href, src in linked)
    ids = {i for i, _, _ in linked}
    assert len(ids) == len(linked)
    # a verdict links to the figure it is judged on, in the page where it is shown
    targets = re.findall(r"<td class='v-\w+'><a href='#([^']+)'>", html)
    assert targets and set(targets) <= ids
    assert "white-space: pre-wrap" in html  # command boxes wrap instead of being cut


def test_report_text_is_readable_at_the_width_the_page_draws_each_figure(study, tmp_path):
    """Every figure rebuilt from its files: its smallest text, at the width Chromium draws
    the figure in a 1400 px window, is at least 10 px (the page's body text is 16 px)."""
    report = study["out"] / "report.html"
    dom = _chromium(tmp_path, "--dump-dom", report.as_uri()).stdout
    shown = {src: int(w) for src, w in re.findall(
        r'<img src="([^"]+)"[^>]*data-shown-width="(\d+)"', dom)}
    assert len(shown) == len(re.findall("<img ", report.read_text()))
    checked = {}
    for src, width in shown.items():
        fig = _figure_of(report.parent / src)
        checked[src] = smallest_text_px(fig, width)
    small = {src: round(px, 1) for src, px in checked.items() if px < 10}
    assert not small, small
    assert 500 < min(shown.values())  # side by side, not squeezed


def _figure_of(png: Path):
    """The figure of ``png`` drawn again from the files beside it (a design's best.png
    from a comparison of the same kind: its numbers are not stored)."""
    name, here = png.name, png.parent
    if name.startswith("sweep"):
        ds = _open(here / "sweep.nc")
        force = re.search(r"_F([\d.]+)N", name)
        return plot_sweep(ds, float(force.group(1)) if force else None)
    if name == "best.png":
        ds = _open(here / "design.nc")
        x = np.linspace(0.8, 1.2, 5)
        return plot_design_comparison({"x": x, "quantity": "rms_tip_m", "force_n": 10.0,
                                       "bar": ds.attrs["bar"],
                                       "curves": {"best design": 1e-4 + 0 * x}}, ds.attrs)
    if here.name == "continuation":
        return plot_continuation(_open(png.with_suffix(".nc")))
    draw = {"lobes.png": (plot_lobes, "lobes.nc"), "examples.png": (plot_lobe_examples,
                                                                    "examples.nc"),
            "bifurcation.png": (plot_bifurcation, "bifurcation.nc"),
            "basins.png": (plot_basins, "basins.nc"),
            "sensitivity.png": (plot_sensitivity, "sensitivity.nc"),
            "design.png": (plot_design, "design.nc"), "ladder.png": (plot_ladder, "ladder.nc"),
            "chatter_orbits.png": (plot_cut_orbits, "chatter_orbits.nc")}
    function, nc = draw[name]
    return function(_open(here / nc))


def _open(path):
    with xr.open_dataset(path) as ds:
        return ds.load()


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
    assert s["quick"] is True and s["presets"] == list(STUDIED)
    assert len(s["claims"]) == 29
    for c in s["claims"]:
        assert {"id", "verdict", "published", "measured"} <= c.keys()
        assert set(c["verdict"]) == set(STUDIED)
        assert all(v in VERDICTS for v in c["verdict"].values())
        # every claim has a verdict under both presets
        assert all(c["verdict"][p] != "not available" for p in PRESET_ORDER), c["id"]
    for column in STUDIED:
        assert sum(s["counts"][column].values()) == 29
    assert s == json.loads(json.dumps(audit(out)))  # the command is the function
    html = (out / "report.html").read_text()
    assert html.index("id='sweeps'") < html.index("id='audit'") < html.index("id='cannot'")
    # the audit opens with the verdicts counted, one row a column, one cell a verdict
    counts = html[html.index("<table class='counts'>"):]
    counts = counts[:counts.index("</table>")]
    variants = {v["name"] for v in s["variants"]}
    for column in STUDIED:
        head = column if column in variants else f"{column} preset"
        row = re.search(rf"<tr><td>{re.escape(head)}</td>(.*?)</tr>", counts)
        assert row, head
        assert [int(n) for n in re.findall(r">(\d+)</td>", row.group(1))] == \
            [s["counts"][column][v] for v in VERDICTS]
    # and the full table folded below it
    table = html[html.index("<details class='audit'>"):]
    table = table[:table.index("</details>")]
    assert table.count("class='v-") == len(STUDIED) * 29


@pytest.mark.slow
def test_the_rolling_ball_s_column(tmp_path):
    """The audit's "physical, rolling" column beside its preset (about 70 s): every step
    a further column runs, each rerun with the rolling ball (the ball rolls with its
    floor's friction even where the rolling resistance is off, so no step is the
    preset's), its command selecting the rolling ball, and a verdict on every claim."""
    out = tmp_path / "out"
    manifest = run_paper(out, quick=True, presets=("physical", "physical-rolling"), quiet=True)
    rolled = [r for r in manifest["steps"] if r["preset"] == "physical-rolling"]
    assert len(rolled) == sum(s.variants for s in STEPS)
    assert not any("shared_from" in r for r in rolled)
    assert all("--preset physical --ball-motion roll" in r["command"] for r in rolled)
    assert manifest["command"].endswith("--presets physical,physical-rolling")
    s = audit(out)
    assert s["presets"] == ["physical", "physical-rolling"]
    assert sum(s["counts"]["physical-rolling"].values()) == 29
    with xr.open_dataset(next(r for r in rolled if r["key"] == "sweep")["summary"]["files"]
                         ["netcdf"]) as ds:
        assert '"motion": "roll"' in str(ds.attrs)


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
