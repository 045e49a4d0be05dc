"""``boringbar design FILE.toml``: a design search under uncertainty (docs/design.md)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from boringbar._validate import check_int
from boringbar.analysis.design import comparison, design, summary, summary_line
from boringbar.analysis.design_file import load_design
from boringbar.cli.options import Outcome, check_workers, progress_printer, wrote
from boringbar.execute import Execution
from boringbar.io import atomic_path, save_figure_atomic, write_json_atomic, write_netcdf_atomic
from boringbar.plot import plot_design, plot_design_comparison


def add_design(sub) -> None:
    p = sub.add_parser("design", help="search for the best damper, robust to uncertainty",
                       description="Search a design study (docs/design.md) with Optuna: "
                                   "variables, an objective, uncertain parameters and a "
                                   "statistic. Writes DIR/design.nc, DIR/trials.csv, "
                                   "DIR/design.png, DIR/best.png and DIR/design.db (the "
                                   "trials: a rerun resumes).")
    p.add_argument("file", metavar="FILE.toml", help="the design file")
    p.add_argument("--trials", type=int, metavar="N", help="override the file's trials")
    p.add_argument("--workers", type=int, metavar="N", help="threads (default: every core)")
    p.add_argument("--out", default="out", metavar="DIR")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_design)


def cmd_design(args) -> Outcome:
    options, spec = load_design(args.file)
    if args.trials is not None:
        options = replace(options, trials=check_int("--trials", args.trials, 1, 100_000))
    check_workers(args.workers)
    execution = Execution("threads", args.workers)
    out = Path(args.out)
    ds = design(options, spec=spec, storage=out / "design.db", execution=execution,
                progress=progress_printer(args, "design", "trials"))
    s = summary(ds)
    files = {"netcdf": out / "design.nc", "csv": out / "trials.csv",
             "png": out / "design.png", "best_png": out / "best.png",
             "json": out / "summary.json"}
    write_netcdf_atomic(ds, files["netcdf"])
    with atomic_path(files["csv"]) as tmp:
        ds.drop_vars("objective_samples").to_dataframe().to_csv(tmp)
    save_figure_atomic(plot_design(ds), files["png"])
    save_figure_atomic(plot_design_comparison(comparison(spec, options, s["best"],
                                                         execution=execution)),
                       files["best_png"])
    summary_ = {**s, "summary": summary_line(s), "files": {k: str(v) for k, v in files.items()}}
    write_json_atomic(summary_, files["json"])

    def text(say) -> None:
        say(summary_["summary"])
        say(f"{s['trials']} trials in {s['wall_time_s']:.1f} s")
        say(wrote(summary_["files"]))

    return Outcome(summary_, text)
