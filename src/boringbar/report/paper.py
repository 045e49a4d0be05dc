"""``boringbar paper``: the whole published study (docs/model.md, section 6) under both
presets, and a report comparing them.

The study is a list of :class:`Step` s. Each step is one published analysis
expressed as the ``boringbar`` command that reruns it (so every figure in the
report can be reproduced by hand with the command shown beside it), run once
per preset into ``OUT/<preset>/<step>/``. Steps finish atomically: a step's
``summary.json`` is written last, after its NetCDF files and figures, and a
rerun of ``boringbar paper`` with the same options skips every step whose
summary is there with the same command, so an interrupted study resumes where
it stopped. ``--quick`` runs the same steps on coarser grids and shorter runs
(written in the report, and in each step's command).

Beside the published analyses, ``corrections`` measures what each correction
to the published equations (docs/model.md, section 8) changes
(:mod:`boringbar.report.corrections`). The report (:mod:`boringbar.report.html`)
is written last, from the files on disk.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from boringbar import __version__
from boringbar.io import jsonable, save_figure_atomic, write_json_atomic, write_netcdf_atomic
from boringbar.model.system import make_system
from boringbar.plot import plot_ladder
from boringbar.report.corrections import absorber_designs, impact_law_check, readings_ladder
from boringbar.report.html import write_report

PRESET_ORDER = ("paper", "physical")


@dataclass(frozen=True)
class Step:
    """One published analysis: ``argv`` is the ``boringbar`` command (without
    ``--preset``, ``--out`` and ``--json``) that reruns it."""

    key: str
    section: str
    title: str
    argv: tuple[str, ...]


def published_steps(quick: bool = False) -> list[Step]:
    """The steps of the published study (docs/model.md, section 6); ``quick``: coarser."""
    dur = ("--duration-s", "0.5") if quick else ()
    steps = [Step("sweep", "sweeps", "Frequency sweeps of tip RMS, F0 = 10 and 20 N",
                  ("sweep", "--force-n", "10,20",
                   "--ratios", "0.95:1.05:" + ("0.02" if quick else "0.01"), *dur))]
    # the published scan in full; the bisection search (the same limits on every
    # published case, docs) on a coarser speed grid with 1 s cuts in the quick version
    steps.append(Step("lobes", "lobes", "Stability lobes by time-domain simulation",
                      ("lobes", "--examples",
                       *(("--method", "search", "--rpm", "900:1600:100", "--duration-s", "1.0")
                         if quick else ("--method", "scan")))))
    for gap in ("0.1", "0.5"):
        for fr in ("off", "on"):
            steps.append(Step(
                f"bifurcation-gap{gap}-friction{fr}", "bifurcation",
                f"Bifurcation diagram over F0, gap {gap} mm, friction {fr}",
                ("bifurcation", "--bar", "ball", "--gap-mm", gap, "--friction", fr,
                 "--force-n", "5:50:" + ("5" if quick else "1"), "--ratio", "1.0", *dur)))
    grid = ("--displacement-mm", "-1.5:1.5:8", "--velocity-m-s", "-1.5:1.5:8") if quick else ()
    for key, force, ratio, fr, start in (("basins-10N-r1.01-off", "10", "1.01", "off", "0.5,0.5"),
                                         ("basins-10N-r1.01-on", "10", "1.01", "on", "1.0,1.0"),
                                         ("basins-20N-r1.00-off", "20", "1.00", "off", "0.5,0.5")):
        steps.append(Step(key, "basins",
                          f"Basins of attraction, {force} N, r = {ratio}, gap 0.5 mm, "
                          f"friction {fr}",
                          ("basins", "--bar", "ball", "--gap-mm", "0.5", "--friction", fr,
                           "--force-n", force, "--ratio", ratio, "--poincare-from", start,
                           *grid, *dur)))
    ratios = ("--ratios", "0.95:1.05:0.05") if quick else ("--ratios", "0.95:1.05:0.01")
    cuts = ("--cut-rpm", "1200", "--depths-mm", "0.05:0.10:0.01")
    for kind, extra in (("ball", cuts), ("friction_number", cuts), ("restitution", ()),
                        ("initial", ())):
        steps.append(Step(f"sensitivity-{kind}", "sensitivity",
                          f"Sensitivity to {kind.replace('_', ' ')}",
                          ("sensitivity", kind, "--bar", "ball", "--gap-mm", "0.5",
                           "--force-n", "10", *ratios, *extra, *dur)))
    return steps


def command_line(step: Step, preset: str, out: Path) -> str:
    """The shell command that reruns ``step`` by hand."""
    return " ".join(["boringbar", *step.argv, "--preset", preset, "--out", str(out)])


class StepFailed(RuntimeError):
    """A step's ``boringbar`` command exited non-zero (its one-line error inside)."""


def _done(path: Path, command: str) -> dict | None:
    """The finished step's record, if ``path`` holds one for ``command``."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return record if record.get("command") == command else None


def _step(where: Path, meta: dict, compute, say, label: str) -> dict:
    """One step of the study: its record from ``where/summary.json`` if a run of
    the same command finished there, else ``compute()`` (its summary), recorded
    with its wall time.  The record comes back with ``reused`` set."""
    record = _done(where / "summary.json", meta["command"])
    if record is not None:
        say(f"{label}: done before, kept")
        return {**record, "reused": True}
    t0 = time.perf_counter()
    summary = compute()
    record = {**meta, "wall_time_s": time.perf_counter() - t0, "summary": summary}
    write_json_atomic(jsonable(record), where / "summary.json")  # last: marks it done
    say(f"{label}: {record['wall_time_s']:.1f} s")
    return {**record, "reused": False}


def run_paper(out, run_step, *, quick: bool = False, presets=PRESET_ORDER, quiet: bool = False,
              log=None) -> dict:
    """Run every published analysis under each preset into ``out`` and write the
    report; returns the manifest (also ``out/manifest.json``).

    ``run_step(argv) -> dict`` runs one step's ``boringbar`` command line in this
    process and returns its ``--json`` summary, raising :class:`StepFailed` if it
    fails (:func:`boringbar.cli.main.run_json`; passed in, so this layer does not
    import the command line that sits on top of it)."""
    shown = Path(out)  # as the user wrote it, for the commands in the report
    out = shown.resolve()
    out.mkdir(parents=True, exist_ok=True)
    say = log or ((lambda msg: None) if quiet else (lambda msg: print(msg, file=sys.stderr,
                                                                      flush=True)))
    tic = time.perf_counter()
    steps = published_steps(quick)
    total = len(steps) * len(presets) + 1
    records = []
    for preset in presets:
        for step in steps:
            where = out / preset / step.key
            argv = [*step.argv, "--preset", preset, "--out", str(where)]
            meta = {"key": step.key, "section": step.section, "title": step.title,
                    "preset": preset,
                    "command": command_line(step, preset, shown / preset / step.key)}
            records.append(_step(where, meta, lambda argv=argv: run_step(argv), say,
                                 f"boringbar paper: [{len(records) + 1}/{total}] "
                                 f"{preset} {step.key}"))
    duration = 0.5 if quick else 2.0
    meta = {"key": "corrections", "section": "corrections",
            "title": "What the corrections to the published equations change",
            "preset": "both",
            "command": (f"boringbar.report.corrections: readings_ladder(duration={duration}), "
                        f"impact_law_check(), absorber_designs() for {', '.join(presets)}")}
    where = out / "corrections"
    records.append(_step(where, meta, lambda: _corrections(where, presets, duration), say,
                         f"boringbar paper: [{total}/{total}] corrections"))
    manifest = {
        "title": "boringbar: the published study rerun under the paper and physical presets",
        "boringbar_version": __version__,
        "quick": quick,
        "presets": list(presets),
        "command": "boringbar paper --out " + str(shown) + (" --quick" if quick else ""),
        "wall_time_s": time.perf_counter() - tic,
        "compute_time_s": sum(r["wall_time_s"] for r in records),
        "steps": records,
    }
    write_json_atomic(jsonable(manifest), out / "manifest.json")
    manifest["report"] = str(write_report(out, manifest))
    say(f"boringbar paper: report {manifest['report']} "
        f"({manifest['wall_time_s']:.0f} s)")
    return manifest


def _corrections(where: Path, presets, duration: float) -> dict:
    """The corrections measurements, into ``where``: the readings ladder, the impact
    law, and the absorber designs of each preset; returns their summary."""
    ladder = readings_ladder(duration=duration)
    nc = write_netcdf_atomic(ladder, where / "ladder.nc")
    png = save_figure_atomic(plot_ladder(ladder), where / "ladder.png")
    impact = impact_law_check(make_system("ball", "paper", gap=0.1e-3, friction=False))
    return {"ladder_netcdf": str(nc), "ladder_png": str(png), "impact_law": impact,
            "absorbers": {p: absorber_designs(p) for p in presets}}
