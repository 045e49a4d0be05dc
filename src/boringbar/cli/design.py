"""``boringbar design FILE.toml``: a design search under uncertainty (docs/design.md)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from boringbar._validate import check_int
from boringbar.analysis.design import comparison, design
from boringbar.analysis.design_file import load_design
from boringbar.cli.options import OUT_HELP, Outcome, check_workers, progress_printer, wrote
from boringbar.execute import Execution
from boringbar.model.system import PRESETS
from boringbar.report.outputs import design_files


def add_design(sub) -> None:
    p = sub.add_parser("design", help="search for the best damper, robust to uncertainty",
                       description="Search a design study (docs/design.md) with Optuna: "
                                   "variables, an objective, uncertain parameters and a "
                                   "statistic. Writes DIR/design.nc, DIR/trials.csv (one "
                                   "row per trial), DIR/samples.csv (one row per trial "
                                   "and Monte Carlo sample, and the file's own design's), "
                                   "DIR/design.png, DIR/best.png (the best design beside "
                                   "the file's in the objective's own figure), "
                                   "DIR/summary.json and DIR/design.journal (the trials: a "
                                   "rerun resumes). The summary gives the improvement on "
                                   "the file's own design with its 95 %% confidence "
                                   "interval over the paired samples, and says 'within "
                                   "noise' when the interval holds 0.")
    p.add_argument("file", metavar="FILE.toml",
                   help="the design file (lengths in mm: gap_mm, depth_mm, ...)")
    p.add_argument("--trials", type=int, metavar="N", help="override the file's trials")
    p.add_argument("--preset", choices=PRESETS, help="override the file's preset")
    p.add_argument("--workers", type=int, metavar="N", help="threads (default: every core)")
    p.add_argument("--out", metavar="DIR", help=OUT_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true")
    p.set_defaults(func=cmd_design)


def cmd_design(args) -> Outcome:
    options, spec = load_design(args.file)
    if args.trials is not None:
        options = replace(options, trials=check_int("--trials", args.trials, 1, 100_000))
    if args.preset is not None:
        options = replace(options, preset=args.preset)
    check_workers(args.workers)
    execution = Execution("threads", args.workers)
    out = Path(args.out)
    ds = design(options, spec=spec, storage=out / "design.journal", execution=execution,
                progress=progress_printer(args, "design", "trials"))
    s = design_files(ds, comparison(spec, options, ds, execution=execution), out)

    def text(say) -> None:
        say(s["summary"])
        say(f"{s['trials']} trials in {s['wall_time_s']:.1f} s")
        say(wrote(s["files"]))

    return Outcome(s, text)
