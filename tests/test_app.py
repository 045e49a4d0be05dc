"""The design page (docs/app.md): its design state and views against the command line
and closed forms, and the page itself served by ``boringbar app`` and driven in
Debian's headless Chromium by Playwright (no browser download)."""

from __future__ import annotations

import asyncio
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from bokeh.models import Legend, LinearScale

import boringbar as bb
from boringbar._validate import ParameterError
from boringbar.analysis.design import candidate_system, design, summary
from boringbar.analysis.design_file import load_design, options_from_dict
from boringbar.analysis.design_objectives import frf_objective
from boringbar.app import views
from boringbar.app.commands import commands
from boringbar.app.design_state import Design
from boringbar.app.figures import READOUT, LobesFigure
from boringbar.app.jobs import Latest, Superseded
from boringbar.app.search import (
    CHATTER_SAMPLES,
    CHATTER_TRIALS,
    JUDGED,
    best_changes,
    design_file,
    search_file,
)
from boringbar.app.server import page
from boringbar.execute import Execution, run_points
from boringbar.model.system_file import load_system, parse_system, published_system
from boringbar.reference.stability import limit_at_speeds

# a deprecation warned of in the page's own code fails these tests (the page built in this
# process has every widget; tests/test_app_notebook.py sets the same filter in its kernel)
pytestmark = [pytest.mark.filterwarnings(f"error::{w}:boringbar[.]app")
              for w in ("DeprecationWarning", "PendingDeprecationWarning")]

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
BOKEH_DATA = "n => Array.from(Bokeh.documents[0].get_model_by_name(n).data.y)"


def cli(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "boringbar", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.fixture(scope="module")
def published():
    return Design.of(published_system())


# --- the design state: checked as the command line checks ----------------------------
def test_a_bad_value_gets_the_command_lines_message(published, tmp_path):
    """The page's message for gap 30 mm is the line `boringbar modes --system FILE`
    prints for a file holding that gap (the file's name aside)."""
    with pytest.raises(ParameterError) as page:
        published.with_value("ball.gap_mm", 30.0)
    text = published.toml().replace("gap_mm = 0.5", "gap_mm = 30.0")
    assert "gap_mm = 30.0" in text
    (tmp_path / "published.toml").write_text(text)
    out = cli("modes", "--system", "published.toml", cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.strip() == f"boringbar: error: {page.value}"


def test_a_bad_setting_gets_the_command_lines_message(published):
    with pytest.raises(ParameterError) as page:
        published.with_settings(force_n=-3.0)
    out = cli("simulate", "--force-n", "-3")
    assert out.returncode == 2
    assert str(page.value) in out.stderr


def test_export_round_trips_through_the_system_file_reader(published, tmp_path):
    d = published.with_value("ball.gap_mm", 0.2).with_value("ball.material", "tungsten") \
        .with_value("cavity.position_mm", 110.0).with_value("ball.friction", ("force_n", 0.3))
    path = tmp_path / "mine.toml"
    path.write_text(d.toml())
    assert load_system(path).to_dict() == d.data
    out = cli("modes", "--system", str(path), "--json", "--out", str(tmp_path / "m"))
    assert out.returncode == 0, out.stderr
    f1 = json.loads(out.stdout)["modes"][0]["frequency_hz"]
    assert f1 == pytest.approx(views.bar_view(d)["modes"][0]["frequency_hz"], rel=1e-12)


def test_a_new_ball_material_takes_its_own_mass(published):
    """The published file gives the ball's mass (26 g); a tungsten ball of the same
    diameter weighs its density's share: 19300/14700 of the carbide's."""
    d = published.with_value("ball.material", "tungsten")
    assert "mass_g" not in d.data["ball"]
    m = d.systems["ball"].damper.mass_kg
    assert m == pytest.approx(19300 * math.pi / 6 * 0.015**3, rel=1e-12)


# --- the views -------------------------------------------------------------------------
def test_the_closed_form_response_matches_a_simulated_solid_bar(published):
    """The solid bar's curve (RMS = |G| F / sqrt 2) against a long time-domain run of
    the same bar at the curve's peak."""
    r = views.response_view(published)
    i = int(np.argmax(r["curves"]["solid"]))
    solid = published.systems["solid"]
    ratio = r["f_hz"][i] / (solid.reference_frequency_rad_s / (2 * math.pi))
    run = bb.simulate(solid, bb.Harmonic(amplitude_n=20.0, ratio=ratio), duration_s=3.0,
                      record_every=0)
    assert run.rms_tip_m * 1e3 == pytest.approx(r["curves"]["solid"][i], rel=2e-3)


def test_each_views_command_reproduces_it(published, tmp_path):
    """The run view's command line, on the exported file, gives the view's RMS."""
    d = published.with_value("ball.gap_mm", 0.3)
    name = "mine_design.toml"
    (tmp_path / name).write_text(d.toml())
    line = commands(d, name)["run"]
    out = cli(*line.split()[1:], "--json", "--out", "run", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["rms_tip_m"] * 1e3 == pytest.approx(
        views.run_view(d)["rms_tip_mm"], rel=1e-12)


def test_the_lobes_view_gives_each_bars_analytic_limit(published):
    """The depth at the design's speed is the frequency-domain limit of each bar (its
    agreement with simulated cuts is tests/test_chatter.py's); the curve spans the
    command line's default lobes and the design's speed; the TMD bar cuts deeper."""
    d = published.with_settings(rpm=1000.0)
    lv = views.lobes_view(d)
    for kind, system in d.systems.items():
        assert lv["depth_at_mm"][kind] == limit_at_speeds(system, [1000.0])[0] * 1e3
        assert lv["curves"][kind].shape == lv["rpm"].shape
    assert lv["rpm"][0] <= 1000.0  # the design speed inside the band
    assert lv["rpm"][-1] >= 60 * 525.2  # lobe 1 of the ball bar (f1 525.2 Hz)
    assert lv["depth_at_mm"]["tmd"] > lv["depth_at_mm"]["solid"]


def test_the_lobes_figure_reads_the_design_speed_on_a_linear_depth_axis(published):
    """The page's lobes: depth on a linear axis from 0 whose top fits the curves (lobe 1's
    peak cut, and said so), speed ticks labelled across the band, the legend below the
    plot, the design's speed a line with each bar's depth there marked and read out; the
    view's command marks it too."""
    lv = views.lobes_view(published)
    f = LobesFigure()
    f.show(lv, None)
    assert isinstance(f.fig.y_scale, LinearScale) and f.fig.y_range.start == 0
    floors = [float(np.min(c)) for c in lv["curves"].values()]
    peak = max(float(np.max(c)) for c in lv["curves"].values())
    assert 1.99 * max(floors) <= f.fig.y_range.end < peak  # the pockets in view, a peak cut
    assert f"peaks up to {peak:.3g} mm" in f.fig.title.text
    ticks = [t for t in f.fig.xaxis.ticker.ticks if f.fig.x_range.start <= t <= f.fig.x_range.end]
    assert min(ticks) <= 1.25 * lv["rpm"][0] and max(ticks) >= lv["rpm"][-1] / 1.25
    assert any(isinstance(m, Legend) for m in f.fig.below)  # off the curves
    assert not any(isinstance(m, Legend) for m in f.fig.center)
    assert f.speed.location == published.settings.rpm == 1200.0
    assert f.at.data["b"] == list(lv["depth_at_mm"].values())
    for kind, depth in lv["depth_at_mm"].items():
        assert f"{READOUT[kind]} {depth:.3g} mm" in f.readout.text
    assert f.readout.text.startswith("your speed 1200 rpm")
    assert "--at-rpm 1200" in commands(published, "p.toml")["lobes"]


def test_the_search_is_a_design_file_the_command_reads(published, tmp_path):
    search = search_file(published, ["gap_mm", "ball_material", "cavity_position_mm"], 5, 2)
    opts = options_from_dict(search)
    assert search["variables"]["gap_mm"][0] == 0.05  # the file in mm, the options in m
    assert opts.variables[0].name == "gap_m" and opts.variables[0].low == 0.05 * 1e-3
    (tmp_path / "mine_design.toml").write_text(published.toml())
    (tmp_path / "search.toml").write_text(design_file(search, "mine_design.toml"))
    read, spec = load_design(tmp_path / "search.toml")
    assert read == opts
    assert spec.to_dict() == published.data


def test_a_tmd_search_applies_the_absorber_it_found(published):
    """The page's TMD search (Den Hartog's criterion: the tip FRF's peak) and its best
    design put on the page: the page's TMD bar is the search's best candidate, so its
    FRF peak is the search's objective to the bit; a search mixing dampers is refused."""
    with pytest.raises(ParameterError, match="a search varies one damper"):
        search_file(published, ["gap_mm", "tmd_mass_kg"], 4, 1)
    no_tmd = Design.of(parse_system({k: v for k, v in published.data.items() if k != "tmd"},
                                    "no_tmd.toml"))
    with pytest.raises(ParameterError, match="this system has none"):
        search_file(no_tmd, ["tmd_damping_ratio"], 4, 1)
    search = search_file(published, ["tmd_frequency_ratio", "tmd_damping_ratio"], 6, 4)
    opts = options_from_dict(search)
    assert (opts.bar, opts.objective, opts.samples) == ("tmd", "frf_peak", 1)
    best = summary(design(opts, spec=published.spec, execution=Execution("serial")))
    page = published.with_values(best_changes(published, opts, best["best"]))
    assert page.data["tmd"]["tuning"] == "given"
    assert frf_objective(page.systems["tmd"], "frf_peak") == best["objective"]
    # the page's bar is the candidate's: the same absorber, the same host
    found = candidate_system(published.spec, opts, best["best"])
    assert page.systems["tmd"].damper.stiffness_n_m == found.damper.stiffness_n_m
    assert page.systems["tmd"].damper.damping_n_s_m == found.damper.damping_n_s_m


def test_the_pages_search_panel_runs_a_tmd_search_and_applies_it():
    """The search panel of a page (built as a notebook builds it): a TMD search fills
    the trials figure in the FRF peak's unit, and applying it puts the absorber found
    on the page with tuning "given"."""
    p = page(None)
    p.search.names.value = ["tmd_frequency_ratio", "tmd_damping_ratio"]
    p.search.trials.value = 4
    asyncio.run(p.search.start())
    assert p.search.objective.value == "frf_peak"  # the TMD's variables take its objective
    assert p.search.fig.yaxis.axis_label == JUDGED["frf_peak"]
    values = p.search.source.data["value"]
    assert len(values) == 4 and all(1.0 < v < 100.0 for v in values)  # um/N
    opts, s = p.search.result
    p.search.apply_best()
    assert p.design.data["tmd"]["tuning"] == "given"
    assert frf_objective(p.design.systems["tmd"], "frf_peak") * 1e6 == min(values)
    assert s["objective"] * 1e6 == min(values)


def test_the_pages_search_takes_a_chatter_objective(published, tmp_path):
    """The page's ball search can judge the chatter-free depth at the page's speed, or the
    page's cut; its file is one `boringbar design` reads, at the page's speed and depth;
    a TMD search refuses a ball's objective."""
    d = published.with_settings(rpm=1350.0, depth_mm=0.07)
    depth = options_from_dict(search_file(d, ["gap_mm"], 3, 2, "min_depth"))
    assert (depth.objective, depth.rpms, depth.samples) == ("min_depth", (1350.0,), 2)
    assert depth.lobes_options().rpm == (1350.0,)
    cut = options_from_dict(search_file(d, ["gap_mm"], 3, 2, "cut_amplitude"))
    assert (cut.objective, cut.rpm, cut.depth_m) == ("cut_amplitude", 1350.0, 0.07 * 1e-3)
    (tmp_path / "mine_design.toml").write_text(d.toml())
    (tmp_path / "search.toml").write_text(design_file(search_file(d, ["gap_mm"], 3, 2,
                                                                  "min_depth"), "mine_design.toml"))
    assert load_design(tmp_path / "search.toml")[0] == depth
    with pytest.raises(ParameterError, match="objective = 'min_depth': a tmd damper's search"):
        search_file(d, ["tmd_damping_ratio"], 3, 1, "min_depth")


def test_the_pages_chatter_search_keeps_the_deepest_and_few_runs():
    """Choosing min_depth brings the trials and samples down (a trial runs cuts), labels
    the trials figure, and the best so far is the deepest (min_depth is maximised)."""
    p = page(None)
    p.search.objective.value = "min_depth"
    assert (p.search.trials.value, p.search.samples.value) == (CHATTER_TRIALS, CHATTER_SAMPLES)
    p.search.trials.value, p.search.samples.value = 2, 1
    asyncio.run(p.search.start())
    assert p.search.fig.yaxis.axis_label == JUDGED["min_depth"]
    values = p.search.source.data["value"]
    assert len(values) == 2 and all(0.001 < v < 1.0 for v in values)  # mm
    opts, s = p.search.result
    assert opts.objective == "min_depth" and s["objective"] * 1e3 == max(values)
    assert f"{max(values):.4g} mm" in p.search.table.object
    assert "one sample: no interval" in p.search.text.object


def test_superseded_work_is_dropped_not_queued():
    """A progress callback that stops the work leaves the points not started unrun."""
    started = []

    def slow(x):
        started.append(x)
        time.sleep(0.05)
        return x

    def stop(done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_points(slow, list(range(40)), execution=Execution("threads", workers=2),
                   progress=stop)
    assert len(started) < 10


# --- in the browser ----------------------------------------------------------------------
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    if CHROMIUM is None:
        if os.environ.get("CI"):
            pytest.fail("CI must install Debian's chromium (.ci/run does)")
        pytest.skip("no chromium on this machine (apt-get install chromium)")
    port = _free_port()
    # the server's output goes to a file (a pipe nobody reads could fill and stall it)
    log = open(tmp_path_factory.mktemp("server") / "server.log", "w")  # noqa: SIM115
    proc = subprocess.Popen([sys.executable, "-m", "boringbar", "app", "--port", str(port)],
                            stdout=log, stderr=subprocess.STDOUT, text=True)
    url = f"http://127.0.0.1:{port}/"
    for _ in range(300):
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            break
        except OSError:
            time.sleep(0.1)
    yield url
    proc.terminate()
    proc.wait(timeout=10)
    log.close()


@pytest.fixture(scope="module")
def browser(server):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync"])
        yield b
        b.close()


def _open(browser, url):
    page = browser.new_context(accept_downloads=True).new_page()
    page.goto(url)
    page.wait_for_selector(".status-run >> text=change 0: drawn in", timeout=60_000)
    return page


def _reach(values) -> float:
    """How far the ball went from the cavity's centre (mm): at most half the gap, and
    close to it while it hits the walls (the history samples between impacts)."""
    return max(map(abs, values))


def _set(page, control: str, value: str) -> None:
    box = page.locator(f".ctl-{control} input")
    box.fill(value)
    box.press("Enter")


def test_the_page_redraws_when_the_gap_moves(browser, server):
    page = _open(browser, server)
    before = page.evaluate(BOKEH_DATA, "run-aux")
    assert 0.24 < _reach(before) <= 0.25  # the ball between the 0.5 mm gap's walls
    _set(page, "ball-gap_mm", "0.2")
    page.wait_for_selector(".status-run >> text=change 1: drawn in", timeout=30_000)
    after = page.evaluate(BOKEH_DATA, "run-aux")
    assert 0.09 < _reach(after) <= 0.1  # now between the 0.2 mm gap's walls
    page.get_by_text("Response and lobes").click()  # a tab's figures are drawn when shown
    page.wait_for_selector(".status-response >> text=change 1: drawn in", timeout=60_000)
    rms = page.evaluate(BOKEH_DATA, "response-ball")
    assert len(rms) == len(views.RESPONSE_RATIOS) and all(0 < y < 1 for y in rms)
    page.context.close()


def test_a_change_stops_the_simulated_lobes_and_the_page_answers(browser, server):
    """While the ball bar's lobes are simulated, the page answers a change: the views
    redraw, and the simulation, superseded, stops instead of finishing and drawing."""
    page = _open(browser, server)
    page.get_by_text("Response and lobes").click()
    page.wait_for_selector(".status-lobes >> text=change 0: drawn in", timeout=60_000)
    page.get_by_text("Simulate the ball bar's lobes").click()
    page.wait_for_selector(".status-simulated >> text=simulating cuts", timeout=30_000)
    _set(page, "ball-gap_mm", "0.3")
    page.wait_for_selector(".status-response >> text=change 1: drawn in", timeout=60_000)
    page.wait_for_selector(".status-lobes >> text=change 1: drawn in", timeout=30_000)
    page.wait_for_timeout(3000)  # had it gone on, its next points would be done by now
    simulated = page.locator(".status-simulated").evaluate(
        "e => (e.shadowRoot || e).textContent")
    assert "simulating" not in simulated and "simulated cuts in" not in simulated
    page.context.close()


def test_the_lobes_view_reads_out_the_design_speed(browser, server):
    """The design's speed on the page's lobes: its depths read out above the plot, and
    read again at a new speed."""
    page = _open(browser, server)
    page.get_by_text("Response and lobes").click()
    page.wait_for_selector(".status-lobes >> text=change 0: drawn in", timeout=60_000)
    text = "() => Bokeh.documents[0].get_model_by_name('lobes-readout').text"
    assert page.evaluate(text).startswith("your speed 1200 rpm (dash-dot line): solid ")
    _set(page, "rpm", "2000")
    page.wait_for_selector(".status-lobes >> text=change 1: drawn in", timeout=60_000)
    assert page.evaluate(text).startswith("your speed 2000 rpm (dash-dot line): solid ")
    assert page.evaluate("n => Array.from(Bokeh.documents[0].get_model_by_name(n).data.rpm)",
                         "lobes-at-rpm") == [2000, 2000, 2000]
    page.context.close()


def test_an_out_of_range_value_shows_the_message_and_keeps_the_design(browser, server):
    page = _open(browser, server)
    _set(page, "ball-gap_mm", "30")
    msg = page.locator(".control-error >> text=ball.gap_mm").inner_text()
    assert "must be a number in (0, 2] mm" in msg
    assert 0.24 < _reach(page.evaluate(BOKEH_DATA, "run-aux")) <= 0.25
    page.context.close()


def test_an_exported_design_runs_through_boringbar_modes(browser, server, tmp_path):
    page = _open(browser, server)
    _set(page, "ball-gap_mm", "0.35")
    page.wait_for_selector(".status-run >> text=change 1: drawn in", timeout=30_000)
    with page.expect_download() as download:
        page.get_by_text("Export system file").click()
    path = tmp_path / download.value.suggested_filename
    download.value.save_as(path)
    assert path.name == "published_design.toml"
    assert load_system(path).to_dict()["ball"]["gap_mm"] == 0.35
    out = cli("modes", "--system", str(path), "--out", str(tmp_path / "modes"))
    assert out.returncode == 0, out.stderr
    assert (tmp_path / "modes" / "modes.png").exists()
    page.context.close()


def test_two_sessions_are_independent(browser, server):
    one, two = _open(browser, server), _open(browser, server)
    _set(one, "ball-gap_mm", "0.2")
    one.wait_for_selector(".status-run >> text=change 1: drawn in", timeout=30_000)
    assert _reach(one.evaluate(BOKEH_DATA, "run-aux")) <= 0.1
    assert _reach(two.evaluate(BOKEH_DATA, "run-aux")) > 0.24
    assert two.locator(".ctl-ball-gap_mm input").input_value() == "0.5"
    assert two.locator(".status-run >> text=change 0: drawn in").count() == 1
    for p in (one, two):
        p.context.close()


def test_a_malformed_upload_gets_the_command_lines_message(browser, server, tmp_path):
    bad = tmp_path / "broken.toml"
    bad.write_text("[bar\nmaterial = 'steel'\n")
    out = cli("modes", "--system", str(bad))
    page = _open(browser, server)
    page.locator("input[type=file]").set_input_files(str(bad))
    msg = page.locator(".control-error >> text=not valid TOML").inner_text()
    assert out.stderr.strip().endswith(msg.split("broken.toml", 1)[1].strip())
    page.context.close()


def test_a_search_for_the_chatter_free_depth_shows_its_result(browser, server):
    """In the browser: choose the chatter objective, run a tiny search (1 trial of 2
    samples), and see its trial drawn and its result line, with the interval."""
    page = _open(browser, server)
    page.get_by_text("Design search", exact=True).click()
    page.locator(".search-objective select").select_option(
        label="chatter-free depth at the page's speed (ball)")
    trials = page.locator(".search-trials input")
    for _ in range(100):  # the page brings the trials down to 6 for a chatter objective
        if trials.input_value() == str(CHATTER_TRIALS):
            break
        page.wait_for_timeout(100)
    for control, value in (("trials", "1"), ("samples", "2")):
        box = page.locator(f".search-{control} input")
        box.fill(value)
        box.press("Enter")
    page.get_by_text("Start search").click()
    page.wait_for_selector(".search-status >> text=trial)", timeout=180_000)
    line = page.locator(".search-status").evaluate("e => (e.shadowRoot || e).textContent")
    assert "of min_depth over 2 samples" in line and "; 1 trial)" in line
    assert "95 % CI" in line
    values = page.evaluate("n => Array.from(Bokeh.documents[0].get_model_by_name(n)"
                           ".data.value)", "search-trials")
    assert len(values) == 1 and all(0.001 < v < 1.0 for v in values)  # depths in mm
    page.context.close()


def test_the_notebook_app_builds_the_same_page():
    layout = bb.design_page(Path(bb.__file__).parent / "model" / "published.toml")
    assert "published" in repr(layout)


def test_a_newer_request_cancels_the_one_before():
    """The first of two requests on one view is cancelled (a running one is told to
    stop at its next progress report), the second's result is what comes back."""
    pool = ThreadPoolExecutor(max_workers=2)
    job, stops = Latest(pool), []

    def work(tag, progress):
        for i in range(200):
            try:
                progress(i, 200)
            except Superseded:
                stops.append(tag)
                raise
            time.sleep(0.005)
        return tag

    async def both():
        first = asyncio.ensure_future(job.run(work, "first", progress=lambda d, t: None))
        await asyncio.sleep(0.05)
        second = await job.run(work, "second", progress=lambda d, t: None)
        with pytest.raises(asyncio.CancelledError):
            await first
        return second

    # a thread of its own: a test before may have left an event loop running in this one
    with ThreadPoolExecutor(max_workers=1) as runner:
        assert runner.submit(asyncio.run, both()).result() == "second"
    pool.shutdown(wait=True)
    assert stops == ["first"]  # stopped at its next point, not run to its end


def test_the_command_loads_panel_only_to_serve():
    """`boringbar app --help` answers without loading Panel; without the extra, the
    command says in one line what to install (exit 2)."""
    code = ("import sys\nfrom boringbar.cli.main import main\ntry:\n    main(['app', '--help'])\n"
            "except SystemExit:\n    pass\nprint('panel' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.splitlines()[-1] == "False"
    code = ("import sys\nsys.modules['panel'] = None  # as if the extra were not installed\n"
            "from boringbar.cli.main import main\nsys.exit(main(['app']))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert "panel is missing): pip install 'boringbar[app]'" in out.stderr


def test_the_server_binds_this_machine_unless_told(tmp_path):
    """--host exposes the page with a warning on stderr; the default prints none."""
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "boringbar", "app", "--port", str(port),
                             "--host", "0.0.0.0"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stderr.readline()
    finally:
        proc.terminate()
        proc.wait(timeout=10)
    assert "warning: serving on 0.0.0.0" in line
    out = cli("app", "--port", "70000")
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "--port" in out.stderr


def test_the_lobes_are_redrawn_when_the_ball_s_host_changes_and_not_with_the_gap():
    """The ball bar's analytic lobes are its linear host's: with friction the bar with
    its ball locked, so a heavier ball moves them and a gap does not."""
    base = Design.of(published_system())
    assert base.systems["ball"].linear_host().kind == "locked"
    heavier = base.with_value("ball.material", "tungsten")
    wider = base.with_value("ball.gap_mm", 0.3)
    assert views.inputs("lobes", wider) == views.inputs("lobes", base)
    assert views.inputs("lobes", heavier) != views.inputs("lobes", base)
    ball = lambda d: views.lobes_view(d)["curves"]["ball"]  # noqa: E731
    assert not np.array_equal(ball(heavier), ball(base))
