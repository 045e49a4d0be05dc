"""The design page's search: ``boringbar design`` on the page's current system, its
trials shown as they finish, the best design applied to the page on request.

The search is a design file (lengths in mm, as the page's controls and every input
file give them), read by :func:`~boringbar.analysis.design_file.options_from_dict`, so
the file the page shows reruns the same search.  It runs :func:`boringbar.design` in
a thread of its own with its journal (Optuna's) in a folder of the session's; the page
reads the finished trials from that storage as they come (Optuna's own records, the
same the command keeps).
"""

from __future__ import annotations

import asyncio
import itertools
import shutil
import tempfile
import threading
import weakref
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from pathlib import Path

import optuna
import panel as pn
import tomli_w
from bokeh.models import ColumnDataSource

from boringbar._validate import ParameterError
from boringbar.analysis.design import (
    candidate_system,
    design,
    design_storage,
    summary,
    summary_line,
)
from boringbar.analysis.design_file import MM_PER_M, options_from_dict, to_file
from boringbar.analysis.design_options import OBJECTIVES as DESIGN_OBJECTIVES
from boringbar.analysis.design_options import objective_reading, shown
from boringbar.app.design_state import Design
from boringbar.app.figures import COLOURS, new_figure, show_progress
from boringbar.app.views import SIMULATED_CUT_S
from boringbar.execute import Execution
from boringbar.model.materials import MATERIALS
from boringbar.model.system_file import merged_sections

#: the page's search variables, as the design file names them: a ball damper's and a
#: tuned mass damper's (one search varies one damper)
BALL_VARIABLES = ("gap_mm", "ball_material", "ball_diameter_mm", "cavity_position_mm")
TMD_VARIABLES = ("tmd_mass_kg", "tmd_frequency_ratio", "tmd_damping_ratio")
VARIABLES = BALL_VARIABLES + TMD_VARIABLES
#: variable (the Python API's name, SI) -> the description's key it sets (mm)
KEYS = {"gap_m": "ball.gap_mm", "ball_material": "ball.material",
        "ball_diameter_m": "ball.diameter_mm", "cavity_position_m": "cavity.position_mm"}
#: the forcing ratios of the ball search's objective (worst tip RMS over them)
BAND = (0.96, 1.0, 1.04)
#: the page's objectives: words (the control's choices) -> objective
OBJECTIVES = {"worst tip RMS over the band (ball)": "rms_band",
              "chatter-free depth at the page's speed (ball)": "min_depth",
              "vibration of the page's cut (ball)": "cut_amplitude",
              "peak of the tip FRF (TMD)": "frf_peak"}
#: damper -> the objectives its search takes, the first by default
DAMPER_OBJECTIVES = {"ball": ("rms_band", "min_depth", "cut_amplitude"), "tmd": ("frf_peak",)}
#: objective -> the trials figure's axis label
JUDGED = {"rms_band": "mean worst tip RMS (mm)", "min_depth": "mean chatter-free depth (mm)",
          "cut_amplitude": "mean cut amplitude (mm)", "frf_peak": "peak of the tip FRF (um/N)"}
#: a chatter objective's search: cuts of CUT_S (the page's simulated lobes' length), each
#: speed's limit searched up to MAX_DEPTH_MM; the trials and samples the page offers first
#: (a trial of min_depth takes about a second a sample: docs/app.md)
CUT_S = SIMULATED_CUT_S
MAX_DEPTH_MM = 1.0
CHATTER_TRIALS, CHATTER_SAMPLES = 6, 2
#: the TMD search's ranges: mass (times the design's), frequency and damping ratio
TMD_RANGES = {"tmd_mass_kg": (0.5, 2.0), "tmd_frequency_ratio": (0.7, 1.1),
              "tmd_damping_ratio": (0.02, 0.4)}
STUDY = "boringbar-design"


def damper_of(names) -> str:
    """The damper a search of the variables ``names`` varies: "ball" or "tmd"."""
    for damper, own in (("ball", BALL_VARIABLES), ("tmd", TMD_VARIABLES)):
        if names and set(names) <= set(own):
            return damper
    raise ParameterError(f"variables = {list(names)}: choose a ball damper's "
                         f"({', '.join(BALL_VARIABLES)}) or a tuned mass damper's "
                         f"({', '.join(TMD_VARIABLES)}); a search varies one damper")


def variable(design: Design, name: str) -> list:
    """The design file's search range of ``name`` (one of :data:`VARIABLES`, mm) around
    the current design: the gap up to the cavity's room, the ball down to 60 % of its
    diameter, the cavity 30 mm either way within the section it sits in; the TMD's
    mass from half to twice the design's, its tuning over :data:`TMD_RANGES`."""
    data = design.data
    if name in TMD_RANGES:
        lo, hi = TMD_RANGES[name]
        scale = data["tmd"]["mass_kg"] if name == "tmd_mass_kg" else 1.0
        return [lo * scale, hi * scale]
    if name == "ball_material":
        return list(MATERIALS)
    if name == "gap_mm":
        return [0.05, design.spec.max_gap() * MM_PER_M]
    if name == "ball_diameter_mm":
        d = data["ball"]["diameter_mm"]
        return [max(1.0, 0.6 * d), d]
    c = data["cavity"]
    lo, hi = _host_span(data["bar"]["sections"], c["position_mm"])
    half = c["length_mm"] / 2
    return [max(lo + half, c["position_mm"] - 30), min(hi - half, c["position_mm"] + 30)]


def _host_span(sections: list, z: float) -> tuple[float, float]:
    """The span (mm) of equal sections around ``z`` (where the cavity may move)."""
    z0 = 0.0
    for s in merged_sections(sections):
        if z0 <= z <= s["end_mm"]:
            return z0, s["end_mm"]
        z0 = s["end_mm"]
    raise ParameterError(f"cavity position {z:g} mm is outside the bar")


def search_file(design: Design, names, trials: int, samples: int,
                objective: str | None = None) -> dict:
    """The search as a design file (without its system). A ball damper's ``objective``
    (default rms_band), averaged over ``samples`` draws of friction (0-0.5 N) and
    restitution (the design's, +- 0.05): rms_band, the worst tip RMS over :data:`BAND`
    at the page's force; min_depth, the chatter-free depth at the page's speed (the
    lobes' search up to :data:`MAX_DEPTH_MM`, cuts of :data:`CUT_S`); cut_amplitude, the
    steady amplitude of the page's cut (speed and depth; :data:`CUT_S`). A tuned mass
    damper's: frf_peak, the peak of the tip FRF (Den Hartog's criterion; linear, so one
    sample)."""
    preset, damper = design.settings.preset, damper_of(names)
    part = {"ball": design.spec.ball, "tmd": design.spec.tmd}[damper]
    if part is None:
        raise ParameterError(f"variables {', '.join(names)} belong to a "
                             f"{'ball damper' if damper == 'ball' else 'tuned mass damper'};"
                             " this system has none")
    objective = objective or DAMPER_OBJECTIVES[damper][0]
    if objective not in DAMPER_OBJECTIVES[damper]:
        raise ParameterError(f"objective = {objective!r}: a {damper} damper's search on the "
                             f"page takes {', '.join(DAMPER_OBJECTIVES[damper])}")
    if damper == "tmd":
        return {"design": {"bar": "tmd", "preset": preset, "objective": "frf_peak",
                           "samples": 1, "trials": trials, "sampler": "tpe", "seed": 1},
                "variables": {n: variable(design, n) for n in names}}
    s = design.settings
    judged = {"rms_band": {"band": "worst", "ratios": list(BAND), "forces_n": [s.force_n],
                           "duration_s": 1.0,
                           "integrator": "exact" if preset == "physical" else "rk4"},
              "min_depth": {"rpms": [s.rpm], "max_depth_mm": MAX_DEPTH_MM, "duration_s": CUT_S},
              "cut_amplitude": {"rpm": s.rpm, "depth_mm": s.depth_mm, "duration_s": CUT_S}}
    return {"design": {"bar": "ball", "preset": preset, "objective": objective,
                       **judged[objective], "samples": samples, "statistic": "mean",
                       "trials": trials, "sampler": "tpe", "seed": 1},
            "variables": {n: variable(design, n) for n in names},
            "uncertain": {"friction_force_n": {"uniform": [0.0, 0.5]},
                          "restitution": {"normal": [design.data["ball"]["restitution"],
                                                     0.05]}}}


def design_file(search: dict, system_file: str) -> str:
    """The design file ``search`` (:func:`search_file`) that names the system file
    ``system_file``: ``boringbar design FILE`` runs the same search."""
    return tomli_w.dumps({**search, "design": {**search["design"], "system": system_file}})


class SearchPanel:
    """The search's controls, live trial table and figure, for ``page``."""

    def __init__(self, page):
        self.page, self.result, self.stop = page, None, threading.Event()
        self.folder: Path | None = None  # made by the first search (:meth:`storage_path`)
        self.pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="boringbar-search")
        self.storage, self.seen, self.done, self.study = None, 0, (0, 1), None
        self.judged = "rms_band"
        self.names = pn.widgets.MultiChoice(
            label="variables (one damper's)", options=list(VARIABLES),
            value=["gap_mm", "ball_material"] if page.design.spec.ball is not None or
            page.design.spec.tmd is None else ["tmd_frequency_ratio", "tmd_damping_ratio"])
        self.objective = pn.widgets.Select(label="objective", options=OBJECTIVES,
                                           value=DAMPER_OBJECTIVES[_damper(self.names.value)][0],
                                           css_classes=["search-objective"])
        self.trials = pn.widgets.IntInput(label="trials", value=12, start=1, end=500,
                                          css_classes=["search-trials"])
        self.samples = pn.widgets.IntInput(label="Monte Carlo samples", value=4, start=1, end=64,
                                           css_classes=["search-samples"])
        self.names.param.watch(self._names_changed, "value")
        self.objective.param.watch(self._objective_changed, "value")
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
        self.source = ColumnDataSource({"trial": [], "value": []}, name="search-trials")
        self.fig = new_figure("trials: the objective as they finish", "trial",
                              JUDGED[self.judged])
        self.dots = self.fig.scatter("trial", "value", source=self.source, size=8,
                                     color=COLOURS["ball"])
        self.file = pn.pane.Markdown("")
        self.panel = pn.Column(
            "## Design search", pn.Row(self.names, self.objective, self.trials, self.samples),
            pn.Row(self.go, self.halt, self.best), self.progress, self.text, self.fig,
            self.table, self.file, sizing_mode="stretch_width")

    async def start(self, _event=None) -> None:
        d = self.page.design
        try:
            search = search_file(d, self.names.value, self.trials.value, self.samples.value,
                                 self.objective.value)
            opts = options_from_dict(search, "the search")
        except ParameterError as e:
            self.text.object = f"**search:** {e}"
            return
        self.judged = opts.objective
        self.page.locked(self.label_figure, opts.objective, opts.bar)
        self.stop.clear()
        self.storage = self.storage_path()
        self.seen, self.result, self.done, self.study = 0, None, (0, opts.trials), None
        self.page.locked(setattr, self.source, "data", {"trial": [], "value": []})
        self.go.disabled, self.halt.disabled, self.best.disabled = True, False, True
        self.file.object = ("Reproduce with `boringbar design search.toml`, where "
                            "search.toml is:\n```toml\n"
                            f"{design_file(search, self.page.export.filename)}```")
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
        self.result = (opts, summary(ds))
        self.best.disabled = False
        self.text.object = summary_line(self.result[1])

    def label_figure(self, objective: str, damper: str) -> None:
        """The trials figure for a search of ``objective`` on ``damper`` (a Bokeh model:
        under the lock)."""
        self.fig.yaxis.axis_label = JUDGED[objective]
        self.dots.glyph.fill_color = self.dots.glyph.line_color = COLOURS[damper]

    def _names_changed(self, event) -> None:
        """Variables of the other damper: its default objective (a TMD search takes the FRF
        peak, a ball search not)."""
        damper = _damper(event.new)
        if damper is not None and self.objective.value not in DAMPER_OBJECTIVES[damper]:
            self.objective.value = DAMPER_OBJECTIVES[damper][0]

    def _objective_changed(self, event) -> None:
        """A chatter objective runs cuts, each trial seconds a sample: the trials and
        samples come down to :data:`CHATTER_TRIALS` and :data:`CHATTER_SAMPLES` (the
        user may raise them again)."""
        if event.new in ("min_depth", "cut_amplitude"):
            self.trials.value = min(self.trials.value, CHATTER_TRIALS)
            self.samples.value = min(self.samples.value, CHATTER_SAMPLES)

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
                                           storage=design_storage(self.storage, writer=False))
        done = self.study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
        if len(done) == self.seen:
            return
        new = done[self.seen:]
        self.seen = len(done)
        unit, factor = objective_reading(self.judged, "mean")
        self.source.stream({"trial": [t.number for t in new],
                            "value": [t.values[0] * factor for t in new]})
        pick = max if DESIGN_OBJECTIVES[self.judged][1] == "maximize" else min
        best = pick(done, key=lambda t: t.values[0])
        self.table.object = (f"best so far: trial {best.number}, " + ", ".join(
            shown(k, v) for k, v in best.params.items())
            + f": {best.values[0] * factor:.4g} {unit}")

    def storage_path(self) -> Path:
        """A new journal file for a search, in the session's folder: made at the first
        search (a page that never searches leaves nothing on disk) and removed when the
        session closes or, at the latest, when the interpreter exits."""
        if self.folder is None:
            self.folder = Path(tempfile.mkdtemp(prefix="boringbar-app-"))
            weakref.finalize(self, shutil.rmtree, self.folder, True)
        return next(path for k in itertools.count()
                    if not (path := self.folder / f"search{k}.journal").exists())

    def close(self) -> None:
        self.stop.set()
        self.pool.shutdown(wait=False, cancel_futures=True)
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)

    def apply_best(self, _event=None) -> None:
        if self.result is None:
            return
        opts, s = self.result
        d = self.page.design
        try:
            d = d.with_values(best_changes(d, opts, s["best"]))
        except ParameterError as e:
            self.text.object = f"**cannot apply the best design:** {e}"
            return
        self.page.apply(d)
        self.text.object = f"applied to the page: {summary_line(s)}"


def best_changes(design: Design, opts, best: dict) -> dict:
    """The description's changes (key -> value, the file's units) that make ``design``
    the search's ``best``: a ball damper's variables as they are; a tuned mass
    damper's as the search built its absorber (mass, stiffness and damping, given)."""
    if opts.bar == "tmd":
        t = candidate_system(design.spec, opts, best).damper
        return {"tmd.mass_kg": t.mass_kg, "tmd.stiffness_n_m": t.stiffness_n_m,
                "tmd.damping_n_s_m": t.damping_n_s_m, "tmd.tuning": "given"}
    return {KEYS[name]: to_file(name, value) for name, value in best.items()}


def _damper(names) -> str | None:
    """The damper of the variables ``names``, or None for no or mixed variables."""
    try:
        return damper_of(names)
    except ParameterError:
        return None


class _Stopped(Exception):
    """The user stopped the search."""
