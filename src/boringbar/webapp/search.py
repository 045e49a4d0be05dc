"""The design page's search: ``boringbar design`` on the page's current system, its
trials shown as they finish, the best design applied to the page on request.

The search runs :func:`boringbar.design` in a thread of its own with an SQLite
storage in a folder of the session's; the page reads the finished trials from that
storage as they come (Optuna's own records, the same the command keeps).
"""

from __future__ import annotations

import asyncio
import shutil
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import optuna
import panel as pn
import tomli_w
from bokeh.models import ColumnDataSource

from boringbar._validate import ParameterError
from boringbar.analysis.design import design, summary, summary_line
from boringbar.analysis.design_options import DesignOptions, Uncertain, Variable
from boringbar.execute import Execution
from boringbar.model.materials import MATERIALS
from boringbar.model.system_file import merged_sections
from boringbar.webapp.design_state import Design
from boringbar.webapp.figures import COLOURS, new_figure, show_progress

#: the page's search variables (those of a ball damper the page can apply)
VARIABLES = ("gap_mm", "ball_material", "ball_diameter_mm", "cavity_position_mm")
#: variable -> the description's key it sets
KEYS = {"gap_mm": "ball.gap_mm", "ball_material": "ball.material",
        "ball_diameter_mm": "ball.diameter_mm", "cavity_position_mm": "cavity.position_mm"}
#: the forcing ratios of the search's objective (worst tip RMS over them)
BAND = (0.96, 1.0, 1.04)
STUDY = "boringbar-design"


def variable(design: Design, name: str) -> Variable:
    """The search range of ``name`` around the current design: the gap up to the
    cavity's room, the ball down to 60 % of its diameter, the cavity 30 mm either way
    within the section it sits in."""
    data = design.data
    if name == "ball_material":
        return Variable(name, choices=tuple(MATERIALS))
    if name == "gap_mm":
        return Variable(name, 0.05, design.spec.max_gap() * 1e3)
    if name == "ball_diameter_mm":
        d = data["ball"]["diameter_mm"]
        return Variable(name, max(1.0, 0.6 * d), d)
    c = data["cavity"]
    lo, hi = _host_span(data["bar"]["sections"], c["position_mm"])
    half = c["length_mm"] / 2
    return Variable(name, max(lo + half, c["position_mm"] - 30), min(hi - half,
                                                                     c["position_mm"] + 30))


def _host_span(sections: list, z: float) -> tuple[float, float]:
    """The span (mm) of equal sections around ``z`` (where the cavity may move)."""
    z0 = 0.0
    for s in merged_sections(sections):
        if z0 <= z <= s["end_mm"]:
            return z0, s["end_mm"]
        z0 = s["end_mm"]
    raise ParameterError(f"cavity position {z:g} mm is outside the bar")


def options(design: Design, names, trials: int, samples: int) -> DesignOptions:
    """The search: the worst tip RMS over :data:`BAND` at the page's force, averaged
    over ``samples`` draws of friction (0-0.5 N) and restitution (the design's,
    +- 0.05)."""
    e = design.data["ball"]["restitution"]
    return DesignOptions(
        bar="ball", variables=tuple(variable(design, n) for n in names), objective="rms_band",
        ratios=BAND, forces_n=(design.settings.force_n,), duration_s=1.0,
        integrator="exact" if design.settings.preset == "physical" else "rk4",
        uncertain=(Uncertain("friction_force_n", "uniform", 0.0, 0.5),
                   Uncertain("restitution", "normal", e, 0.05)),
        samples=samples, trials=trials, preset=design.settings.preset)


def design_file(opts: DesignOptions, system_file: str) -> str:
    """``opts`` as a design file (``boringbar design FILE`` runs the same search)."""
    variables = {v.name: list(v.choices) if v.choices else [v.low, v.high]
                 for v in opts.variables}
    uncertain = {u.name: {u.distribution: [u.a, u.b]} for u in opts.uncertain}
    head = {k: getattr(opts, k) for k in ("bar", "preset", "objective", "band", "duration_s",
                                          "integrator", "samples", "statistic", "trials",
                                          "sampler", "seed")}
    return tomli_w.dumps({"design": {**head, "system": system_file, "ratios": list(opts.ratios),
                                     "forces_n": list(opts.forces_n)},
                          "variables": variables, "uncertain": uncertain})


class SearchPanel:
    """The search's controls, live trial table and figure, for ``page``."""

    def __init__(self, page):
        self.page, self.result, self.stop = page, None, threading.Event()
        self.folder = Path(tempfile.mkdtemp(prefix="boringbar-app-"))
        self.pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="boringbar-search")
        self.storage, self.seen, self.done, self.study = None, 0, (0, 1), None
        self.names = pn.widgets.MultiChoice(label="variables", options=list(VARIABLES),
                                            value=["gap_mm", "ball_material"])
        self.trials = pn.widgets.IntInput(label="trials", value=12, start=1, end=500)
        self.samples = pn.widgets.IntInput(label="Monte Carlo samples", value=4, start=1, end=64)
        self.go = pn.widgets.Button(label="Start search", color="primary")
        self.halt = pn.widgets.Button(label="Stop", disabled=True)
        self.best = pn.widgets.Button(label="Apply the best design", disabled=True,
                                      color="success")
        self.go.on_click(self.start)
        self.halt.on_click(lambda _e: self.stop.set())
        self.best.on_click(self.apply_best)
        self.progress = pn.indicators.Progress(value=0, max=1, sizing_mode="stretch_width")
        self.text = pn.pane.Markdown("", css_classes=["search-status"])
        self.table = pn.pane.Markdown("")
        self.source = ColumnDataSource({"trial": [], "rms": []})
        self.fig = new_figure("trials: the objective as they finish", "trial",
                           "mean worst tip RMS (mm)")
        self.fig.scatter("trial", "rms", source=self.source, size=8, color=COLOURS["ball"])
        self.file = pn.pane.Markdown("")
        self.panel = pn.Column(
            "## Design search", pn.Row(self.names, self.trials, self.samples),
            pn.Row(self.go, self.halt, self.best), self.progress, self.text, self.fig,
            self.table, self.file, sizing_mode="stretch_width")

    async def start(self, _event=None) -> None:
        d = self.page.design
        if d.spec.ball is None:
            self.text.object = "the search varies a ball damper; this system has none"
            return
        try:
            opts = options(d, self.names.value, self.trials.value, self.samples.value)
        except ParameterError as e:
            self.text.object = f"**search:** {e}"
            return
        self.stop.clear()
        self.storage = self.folder / f"search{len(list(self.folder.iterdir()))}.sqlite"
        self.seen, self.result, self.done, self.study = 0, None, (0, opts.trials), None
        self.page.locked(setattr, self.source, "data", {"trial": [], "rms": []})
        self.go.disabled, self.halt.disabled, self.best.disabled = True, False, True
        self.file.object = ("Reproduce with `boringbar design search.toml`, where "
                            "search.toml is:\n```toml\n"
                            f"{design_file(opts, self.page.export.filename)}```")
        self.text.object = f"searching {len(opts.variables)} variables in {opts.trials} trials"
        loop = asyncio.get_running_loop()
        try:
            ds = await loop.run_in_executor(self.pool, partial(
                design, opts, spec=d.spec, storage=self.storage,
                execution=Execution("threads"), progress=self._progress))
        except _Stopped:
            self.text.object = f"stopped after {self.seen} trials"
            return
        except Exception as e:  # noqa: BLE001 (a failed search is reported; the page lives on)
            self.text.object = f"**search failed:** {e}"
            return
        finally:
            self.go.disabled, self.halt.disabled = False, True
        self.page.locked(self.poll)  # the last trials (the figure is a Bokeh model)
        self.result = (d, summary(ds))
        self.best.disabled = False
        self.text.object = summary_line(self.result[1])

    def _progress(self, done: int, total: int) -> None:
        """From the search's thread: kept for :meth:`poll`, which draws it."""
        self.done = (done, total)
        if self.stop.is_set():
            raise _Stopped

    def poll(self) -> None:
        """Show the trials finished since the last poll (read from the storage)."""
        show_progress(self.progress, *self.done)
        if self.storage is None or self.done[0] == 0:
            return  # read the storage only once the search made it (it has a trial)
        if self.study is None:
            self.study = optuna.load_study(study_name=STUDY,
                                           storage=f"sqlite:///{self.storage}")
        done = self.study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        if len(done) == self.seen:
            return
        new = done[self.seen:]
        self.seen = len(done)
        self.source.stream({"trial": [t.number for t in new],
                            "rms": [t.values[0] * 1e3 for t in new]})
        best = min(done, key=lambda t: t.values[0])
        self.table.object = ("best so far: trial " f"{best.number}, " + ", ".join(
            f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
            for k, v in best.params.items()) + f": {best.values[0] * 1e3:.4g} mm")

    def close(self) -> None:
        self.stop.set()
        self.pool.shutdown(wait=False, cancel_futures=True)
        shutil.rmtree(self.folder, ignore_errors=True)

    def apply_best(self, _event=None) -> None:
        if self.result is None:
            return
        _, s = self.result
        d = self.page.design
        try:  # the ball and the cavity before the gap, whose room they set
            for name in sorted(s["best"], key=lambda n: n == "gap_mm"):
                d = d.with_value(KEYS[name], s["best"][name])
        except ParameterError as e:
            self.text.object = f"**cannot apply the best design:** {e}"
            return
        self.page.apply(d)
        self.text.object = f"applied to the page: {summary_line(s)}"


class _Stopped(Exception):
    """The user stopped the search."""
