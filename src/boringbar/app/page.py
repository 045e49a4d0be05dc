"""The design page: controls for one design, its views redrawn live, pin and compare,
export, and a design search (docs/app.md).

A :class:`Page` belongs to one browser session (or one notebook cell): it owns its
design, its pinned design, its thread pool and its figures, so two sessions share
nothing.  A control change makes a new :class:`Design` (checked as the command line
checks it; a bad value leaves the design as it was and shows the message), then every
view recomputes off the event loop, newest request first (:mod:`boringbar.app.jobs`),
and its figure's sources are replaced under the document lock.
"""

from __future__ import annotations

import asyncio
import io
import math
import time
from concurrent.futures import ThreadPoolExecutor
from functools import partial

import panel as pn

from boringbar.app import views
from boringbar.app.commands import commands
from boringbar.app.controls import Controls
from boringbar.app.design_state import Design
from boringbar.app.figures import (
    BarFigure,
    LobesFigure,
    ModesFigure,
    ResponseFigure,
    RunFigures,
    show_progress,
)
from boringbar.app.jobs import Latest, Superseded
from boringbar.app.search import SearchPanel

#: how often (ms) the page copies a running job's progress to its bar
POLL_MS = 250
#: the views, in the order they start (the single run first: it is the one a designer
#: watches while moving a control)
VIEWS = ("run", "lobes", "bar", "response")


class Page:
    """The page of one session, for ``design``."""

    def __init__(self, design: Design):
        self.design, self.pinned_views = design, {}  #: views of the pinned design
        self.changes = 0  #: designs made since the page opened (the status lines show it)
        self.pool = ThreadPoolExecutor(max_workers=2, thread_name_prefix="boringbar-app")
        self.jobs = {v: Latest(self.pool) for v in (*VIEWS, "simulated")}
        self.last: dict = {}  #: view -> its last data
        self.keys: dict = {}  #: view -> the inputs it was last drawn from
        self.seconds: dict = {}  #: view -> how long its last drawing took (s)
        self.figures = {"bar": BarFigure(), "modes": ModesFigure(), "run": RunFigures(),
                        "response": ResponseFigure(), "lobes": LobesFigure()}
        self.status = {v: pn.pane.Markdown("", css_classes=[f"status-{v}"], margin=(0, 10))
                       for v in (*VIEWS, "simulated")}
        self.command = {v: pn.pane.Markdown("", css_classes=[f"command-{v}"]) for v in VIEWS}
        self.modes_table = pn.pane.Markdown("")
        self.progress = pn.indicators.Progress(value=0, max=1, visible=False,
                                               sizing_mode="stretch_width")
        self.progress_seen = (0, 1)
        self.controls = Controls(design, self.changed)
        self.search = SearchPanel(self)
        self.layout = self._layout()
        self.doc = pn.state.curdoc
        pn.state.onload(self.start)

    # --- layout ---------------------------------------------------------------------
    def _layout(self):
        f = self.figures
        simulate = pn.widgets.Button(label="Simulate the ball bar's lobes", color="primary")
        simulate.on_click(self.simulate_lobes)
        pin = pn.widgets.Button(label="Pin this design", color="success")
        pin.on_click(self.pin)
        unpin = pn.widgets.Button(label="Unpin")
        unpin.on_click(self.unpin)
        export = pn.widgets.FileDownload(callback=self.export_file,
                                         filename=export_name(self.design),
                                         label="Export system file", color="warning")
        self.export = export
        bar = pn.Column("## The bar", f["bar"].fig, pn.Row(self.modes_table, f["modes"].fig),
                        self.status["bar"], self.command["bar"], sizing_mode="stretch_width")
        run = pn.Column("## One run", pn.Row(f["run"].tip, f["run"].aux),
                        pn.Row(f["run"].impacts, f["run"].energy), self.status["run"],
                        self.command["run"], sizing_mode="stretch_width")
        response = pn.Column("## Frequency response", f["response"].fig,
                             self.status["response"], self.command["response"],
                             sizing_mode="stretch_width")
        lobes = pn.Column("## Stability lobes", f["lobes"].fig, pn.Row(simulate, self.progress),
                          self.status["lobes"], self.status["simulated"],
                          self.command["lobes"], sizing_mode="stretch_width")
        side = pn.Column(self.controls.panel, pn.Row(pin, unpin), export, width=330)
        tabs = pn.Tabs(("Design", pn.Column(bar, run, sizing_mode="stretch_width")),
                       ("Response and lobes", pn.Column(response, lobes,
                                                        sizing_mode="stretch_width")),
                       ("Design search", self.search.panel), dynamic=True,
                       sizing_mode="stretch_width")
        return pn.Row(side, tabs, sizing_mode="stretch_width")

    # --- life cycle -----------------------------------------------------------------
    def start(self) -> None:
        """Draw every view of the first design and start the progress poll."""
        pn.state.add_periodic_callback(self.poll, period=POLL_MS)
        pn.state.execute(self.refresh_all)

    async def refresh_all(self) -> None:
        await asyncio.gather(*(self.refresh(v) for v in VIEWS), self.show_commands())

    def changed(self, design: Design) -> None:
        """A control made ``design`` (checked): redraw everything from it."""
        self.design, self.changes = design, self.changes + 1
        self.export.filename = export_name(design)
        self.jobs["simulated"].cancel()
        self.locked(self.figures["lobes"].show_simulated, None)
        self.status["simulated"].object = ""
        pn.state.execute(self.refresh_all)

    async def refresh(self, view: str) -> None:
        """Recompute ``view`` for the current design and redraw it (a newer change
        cancels this one; an error is shown in the view's status line)."""
        fn = {"bar": views.bar_view, "run": views.run_view,
              "response": views.response_view, "lobes": views.lobes_view}[view]
        t0, change = time.perf_counter(), self.changes
        key = views.inputs(view, self.design)
        if self.keys.get(view) == key:  # this change leaves the view as it is
            self.jobs[view].cancel()
            self.status[view].object = self.describe(view, self.last[view],
                                                     self.seconds[view], change)
            return
        self.status[view].object = "computing..."
        try:
            # the response's sweep is told to stop at its next point once superseded
            kw = {"progress": _quiet} if view == "response" else {}
            data = await self.jobs[view].run(fn, self.design, **kw)
        except (asyncio.CancelledError, Superseded):
            return
        except Exception as e:  # noqa: BLE001 (any failure is the view's message, not the server's)
            self.status[view].object = f"**{view}:** {e}"
            return
        self.last[view], self.keys[view] = data, key
        self.seconds[view] = time.perf_counter() - t0
        self.locked(self.draw, view, data, self.describe(view, data, self.seconds[view], change))

    def locked(self, fn, *args) -> None:
        """``fn(*args)``, which changes Bokeh models, under the session's document lock:
        on the server's next tick (a coroutine awaiting a job does not hold the lock);
        in a notebook at once."""
        doc = self.doc
        if doc is None or doc.session_context is None:
            fn(*args)
        else:
            doc.add_next_tick_callback(partial(fn, *args))

    def draw(self, view: str, data: dict, status: str | None = None) -> None:
        """Redraw ``view`` from ``data``, then show its ``status`` line on the tick after
        (a tick's changes go to the browser together, in no promised order, so the
        status naming a change follows the data it stands for)."""
        self._figures(view, data)
        if status is not None:
            self.locked(setattr, self.status[view], "object", status)

    def _figures(self, view: str, data: dict) -> None:
        pinned = self.pinned_views.get(view)
        if view == "bar":
            self.figures["bar"].show(data)
            self.figures["modes"].show(data)
            self.modes_table.object = modes_markdown(data)
        elif view == "run":
            self.figures["run"].show(data, pinned)
        elif view == "response":
            self.figures["response"].show(data, pinned)
        else:
            self.figures["lobes"].show(data, pinned)

    def describe(self, view: str, data: dict, seconds: float, change: int) -> str:
        """The view's status line: what it shows, of which change, and how long it took."""
        head = f"{self.design.name}, change {change}: drawn in {seconds:.2f} s"
        if view == "run":
            verdict = "" if data["chatter"] is None else \
                f", **{'chatter' if data['chatter'] else 'no chatter'}**"
            return (f"{head}; {data['bar']} bar, {data['integrator']}: tip RMS "
                    f"{data['rms_tip_mm']:.4g} mm, impact pattern **{data['pattern'] or '-'}**"
                    f"{verdict}")
        if view == "lobes":
            depths = ", ".join(f"{k} {v:.3g} mm" for k, v in data["depth_at_mm"].items())
            return f"{head}; chatter-free depth at {data['at_rpm']:g} rpm: {depths}"
        return head

    async def show_commands(self) -> None:
        """Each view's command line (built in the pool: it needs the design's bars)."""
        loop = asyncio.get_running_loop()
        lines = await loop.run_in_executor(self.pool, commands, self.design,
                                           self.export.filename)
        for view, text in lines.items():
            if view in self.command:
                self.command[view].object = f"```\n{text}\n```"

    # --- progress, pins, export, simulated lobes ------------------------------------
    def report(self, done: int, total: int) -> None:
        """A job's progress (from its worker thread); :meth:`poll` shows it."""
        self.progress_seen = (done, total)

    def poll(self) -> None:
        show_progress(self.progress, *self.progress_seen)
        self.search.poll()

    def pin(self, _event=None) -> None:
        """Keep the current design's views, drawn dashed beside the next ones."""
        self._pinned(dict(self.last))

    def unpin(self, _event=None) -> None:
        self._pinned({})

    def _pinned(self, kept_views: dict) -> None:
        """Pin ``kept_views`` (none: unpin) and redraw the views that show them."""
        self.pinned_views = kept_views
        for view in ("run", "response", "lobes"):
            if view in self.last:
                self.draw(view, self.last[view])

    def export_file(self):
        """The current design as a system file (FileDownload's callback)."""
        return io.StringIO(self.design.toml())

    async def simulate_lobes(self, _event=None) -> None:
        if self.design.spec.ball is None:
            self.status["simulated"].object = "this system has no ball to simulate"
            return
        t0 = time.perf_counter()
        self.progress.visible, self.progress_seen = True, (0, 1)
        self.status["simulated"].object = "simulating cuts..."
        try:
            sim = await self.jobs["simulated"].run(views.simulated_lobes, self.design,
                                                   progress=self.report)
        except (asyncio.CancelledError, Superseded):
            return
        except Exception as e:  # noqa: BLE001 (the view's message, not the server's)
            self.status["simulated"].object = f"**simulated lobes:** {e}"
            return
        finally:
            self.progress.visible = False
        self.locked(self.figures["lobes"].show_simulated, sim)
        depth = (f"{sim['depth_at_mm']:.3g} mm" if math.isfinite(sim["depth_at_mm"])
                 else f"above {sim['max_depth_mm']:g} mm (no chatter up to the deepest cut)")
        self.status["simulated"].object = (
            f"simulated cuts in {time.perf_counter() - t0:.1f} s: the ball bar's chatter-free "
            f"depth at {self.design.settings.rpm:g} rpm is {depth}; method: {sim['method']}")

    def close(self) -> None:
        """The session ended: stop its work and drop its files."""
        for job in self.jobs.values():
            job.cancel()
        self.pool.shutdown(wait=False, cancel_futures=True)
        self.search.close()

    def apply(self, design: Design) -> None:
        """Make ``design`` current, its controls showing it (the search's best)."""
        self.controls.show(design)
        self.changed(design)


def _quiet(done: int, total: int) -> None:
    """A progress callback that shows nothing (the job's own check is what matters)."""


def export_name(design: Design) -> str:
    """The exported system file's name (and the one the commands shown use)."""
    return f"{design.name}_design.toml"


def modes_markdown(view: dict) -> str:
    rows = "\n".join(f"| {i + 1} | {m['frequency_hz']:.1f} | {m['modal_mass_kg']:.4g} | "
                     f"{m['tip_stiffness_n_m'] / 1e6:.4g} |"
                     for i, m in enumerate(view["modes"]))
    return ("| mode | f (Hz) | modal mass (kg) | tip stiffness (N/µm) |\n|---|---|---|---|\n"
            f"{rows}\n\nstatic tip stiffness {view['static_stiffness_n_m'] / 1e6:.4g} N/µm")
