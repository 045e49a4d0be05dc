"""The files of each analysis and its summary: what ``boringbar sweep``, ``lobes``,
``chatter-map``, ``bifurcation``, ``basins`` and ``sensitivity`` write into their ``--out``
directory, shared by those commands and by ``boringbar paper``
(:mod:`boringbar.report.paper`), so both write the same files the same way; and
what ``boringbar design`` writes.

Each ``*_files(ds, out)`` writes the analysis's NetCDF file and figures into
``out`` (atomically) and returns its summary (what ``--json`` prints), with the
paths written under ``"files"``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from boringbar.analysis.basins import summary as basins_summary
from boringbar.analysis.bifurcation import summary as bifurcation_summary
from boringbar.analysis.chatter_map import summary as chatter_map_summary
from boringbar.analysis.continuation import summary as continuation_summary
from boringbar.analysis.cut_continuation import cut_summary
from boringbar.analysis.design import sample_table, summary_line, trial_table
from boringbar.analysis.design import summary as design_summary
from boringbar.analysis.lobe_examples import examples_summary
from boringbar.analysis.lobes import summary as lobes_summary
from boringbar.analysis.sensitivity import summary as sensitivity_summary
from boringbar.analysis.sweep import summary as sweep_summary
from boringbar.io import atomic_path, save_figure_atomic, write_json_atomic, write_netcdf_atomic
from boringbar.plot import (
    plot_basins,
    plot_bifurcation,
    plot_lobe_examples,
    plot_sweep,
)
from boringbar.plot.chatter import plot_chatter_map
from boringbar.plot.cut_orbits import plot_cut_orbits
from boringbar.plot.design import plot_best, plot_design
from boringbar.plot.lobes import plot_lobes
from boringbar.plot.orbits import plot_continuation
from boringbar.plot.variations import plot_sensitivity


def integrators_used(ds) -> str:
    """The integrators that produced ``ds`` ("exact", "rk4" or both, comma-joined):
    per case where the analysis records it, else its ``integrator_used``."""
    used = {str(v) for v in np.atleast_1d(ds["integrator"].values)} if "integrator" in \
        ds.coords else set()
    used.update(w for w in str(ds.attrs.get("integrator_used", "")).split(",") if w)
    return ",".join(sorted(used))


def sweep_pngs(ds, out: Path) -> list[tuple[float, Path]]:
    """(force, file) of each sweep figure: ``out/sweep.png`` for one force, else one
    ``out/sweep_F<force>N.png`` per force."""
    forces = [float(f) for f in np.atleast_1d(ds["force_n"].values)]
    if len(forces) == 1:
        return [(forces[0], out / "sweep.png")]
    return [(f, out / f"sweep_F{f:g}N.png") for f in forces]


def sweep_files(ds, out) -> dict:
    """``out/sweep.nc`` and the sweep figures (:func:`sweep_pngs`); the summary."""
    out = Path(out)
    nc = write_netcdf_atomic(ds, out / "sweep.nc")
    pngs = [save_figure_atomic(plot_sweep(ds, f), path) for f, path in sweep_pngs(ds, out)]
    return {**sweep_summary(ds), "integrator_used": integrators_used(ds),
            "files": {"netcdf": str(nc), "png": [str(p) for p in pngs]}}


def lobes_files(ds, out, examples=None) -> dict:
    """``out/lobes.nc``, ``out/lobes.png`` and, given the ``examples`` dataset
    (:func:`boringbar.analysis.lobe_examples.examples`), ``out/examples.nc`` and
    ``out/examples.png``; the summary (with ``"examples"`` when given)."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "lobes.nc"),
             "png": save_figure_atomic(plot_lobes(ds), out / "lobes.png")}
    if examples is not None:
        files["examples_netcdf"] = write_netcdf_atomic(examples, out / "examples.nc")
        files["examples_png"] = save_figure_atomic(plot_lobe_examples(examples),
                                                    out / "examples.png")
    summary = {**lobes_summary(ds), "integrator_used": integrators_used(ds),
               "files": {k: str(v) for k, v in files.items()}}
    if examples is not None:
        summary["examples"] = examples_summary(examples)
    return summary


def chatter_map_files(ds, out) -> dict:
    """``out/chatter_map.nc`` and ``out/chatter_map.png``; the summary."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "chatter_map.nc"),
             "png": save_figure_atomic(plot_chatter_map(ds), out / "chatter_map.png")}
    return {**chatter_map_summary(ds), "files": {k: str(v) for k, v in files.items()}}


def bifurcation_files(ds, out) -> dict:
    """``out/bifurcation.nc`` and ``out/bifurcation.png``; the summary."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "bifurcation.nc"),
             "png": save_figure_atomic(plot_bifurcation(ds), out / "bifurcation.png")}
    return {**bifurcation_summary(ds), "integrator_used": integrators_used(ds),
            "files": {k: str(v) for k, v in files.items()}}


def basins_files(ds, out) -> dict:
    """``out/basins.nc`` and ``out/basins.png``; the summary."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "basins.nc"),
             "png": save_figure_atomic(plot_basins(ds), out / "basins.png")}
    return {**basins_summary(ds), "integrator_used": integrators_used(ds),
            "files": {k: str(v) for k, v in files.items()}}


def sensitivity_files(ds, out) -> dict:
    """``out/sensitivity.nc`` and ``out/sensitivity.png``; the summary."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / "sensitivity.nc"),
             "png": save_figure_atomic(plot_sensitivity(ds), out / "sensitivity.png")}
    return {**sensitivity_summary(ds), "integrator_used": integrators_used(ds),
            "files": {k: str(v) for k, v in files.items()}}


def design_files(ds, cmp: dict, out) -> dict:
    """``out/design.nc``, ``out/trials.csv`` (one row per trial:
    :func:`~boringbar.analysis.design.trial_table`), ``out/samples.csv`` (one row per
    trial and sample, then the file's design's: :func:`~boringbar.analysis.design.
    sample_table`), ``out/design.png`` (the trials against each variable, the Pareto
    front), ``out/best.png`` (the best design beside the file's own in the objective's
    terms: ``cmp`` of :func:`boringbar.analysis.design.comparison`, drawn by
    :func:`~boringbar.plot.design.plot_best`) and ``out/summary.json``; the summary,
    with its one-line statement under ``"summary"``."""
    out = Path(out)
    s = design_summary(ds)
    files = {"netcdf": write_netcdf_atomic(ds, out / "design.nc"),
             "csv": out / "trials.csv", "samples_csv": out / "samples.csv",
             "png": save_figure_atomic(plot_design(ds), out / "design.png"),
             "best_png": save_figure_atomic(plot_best(cmp, ds.attrs), out / "best.png"),
             "json": out / "summary.json"}
    for key, table in (("csv", trial_table(ds)), ("samples_csv", sample_table(ds))):
        with atomic_path(files[key]) as tmp:
            table.to_csv(tmp, index=False)
    summary = {**s, "summary": summary_line(s), "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic(summary, files["json"])
    return summary


def chatter_orbit_files(ds, out) -> dict:
    """``out/chatter_orbits.nc``, ``.png`` (the chatter orbit map) and ``.json`` (the
    summary, with the files): what ``boringbar continue --cut`` and the report write."""
    out = Path(out)
    summary = cut_summary(ds)
    summary["files"] = {
        "netcdf": str(write_netcdf_atomic(ds, out / "chatter_orbits.nc")),
        "png": str(save_figure_atomic(plot_cut_orbits(ds), out / "chatter_orbits.png",
                                      dpi=130))}
    write_json_atomic(summary, out / "chatter_orbits.json")
    return summary


def continuation_files(ds, out, name: str, overlay=None) -> dict:
    """``out/NAME.nc`` and ``out/NAME.png`` (the branches over ``overlay``, a bifurcation
    Dataset of the same case, if given); the summary, with ``overlay`` True or False."""
    out = Path(out)
    files = {"netcdf": write_netcdf_atomic(ds, out / f"{name}.nc"),
             "png": save_figure_atomic(plot_continuation(ds, overlay=overlay),
                                       out / f"{name}.png", dpi=110)}
    return {**continuation_summary(ds), "overlay": overlay is not None,
            "files": {k: str(v) for k, v in files.items()}}
