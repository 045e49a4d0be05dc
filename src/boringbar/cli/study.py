"""``boringbar run STUDY.toml``: run a study file (see docs/studies.md); and
``boringbar paper``: the whole published study with its report (:mod:`boringbar.report.paper`).

Registered in :mod:`boringbar.cli.main` by :func:`add_run` and :func:`add_paper`; errors are
ParameterErrors (one line, exit code 2) like every other command.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from pathlib import Path

from boringbar._validate import ParameterError
from boringbar.cli.options import check_workers
from boringbar.io import jsonable
from boringbar.report.paper import COLUMN_ORDER, StepFailed, run_paper
from boringbar.studies.load import load_study
from boringbar.studies.runner import EXECUTORS, RunReport, run_study
from boringbar.studies.schema import output_format


def add_run(sub) -> None:
    p = sub.add_parser(
        "run", help="run a study file (TOML): many runs of one analysis, resumable",
        description="Run the study described in STUDY.toml (docs/studies.md): every point of "
                    "its grid, in chunks, serially, on local processes (default, every core) "
                    "or on a Dask cluster.  Finished chunks are kept in OUT.partial/ so the "
                    "same command after an interruption runs only what is missing; OUT (.nc "
                    "NetCDF or .zarr Zarr) is written atomically when everything is done, "
                    "with the resolved configuration, package version and run time in its "
                    "attributes.  A finished OUT of the same study is not recomputed.")
    p.add_argument("study", metavar="STUDY.toml", help="the study file")
    p.add_argument("--out", metavar="PATH",
                   help="result file, .nc or .zarr (default: [study] out, else NAME.nc)")
    p.add_argument("--executor", choices=EXECUTORS, default=None,
                   help="serial | processes (default) | dask")
    p.add_argument("--workers", type=int, metavar="N",
                   help="worker processes (default: every core)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of a Dask scheduler (implies --executor dask)")
    p.add_argument("--dask-local", type=int, metavar="N",
                   help="start a Dask LocalCluster of N workers (implies --executor dask)")
    p.add_argument("--chunk-size", type=int, metavar="N",
                   help="points per task (default: about four tasks per worker, at most 64)")
    p.add_argument("--quiet", action="store_true", help="no progress bar, no summary line")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (the run's report) on stdout")
    p.set_defaults(func=cmd_run)


def cmd_run(args: argparse.Namespace) -> int:
    study = load_study(args.study)
    if args.out is not None:
        output_format(Path(args.out), study.format, "--out")
    for name in ("workers", "dask_local", "chunk_size"):
        check_workers(getattr(args, name), "--" + name.replace("_", "-"))
    executor = args.executor
    if executor is None:
        executor = "dask" if (args.scheduler or args.dask_local) else "processes"
    report = RunReport()
    if not args.quiet:  # resume and worker-loss notes, one line each on stderr

        handler = logging.StreamHandler(sys.stderr)
        handler.setFormatter(logging.Formatter("boringbar run: %(message)s"))
        logger = logging.getLogger("boringbar.studies.runner")
        logger.addHandler(handler)
        logger.setLevel(logging.INFO)
    run_study(study, args.out, executor=executor, workers=args.workers,
              scheduler=args.scheduler, dask_local=args.dask_local, chunk_size=args.chunk_size,
              quiet=args.quiet or not sys.stderr.isatty(), report=report)
    if args.json:
        print(json.dumps(jsonable({"study": study.name, **report.to_dict()}), allow_nan=False))
        if not args.quiet:
            print(f"boringbar run: {report.line()}", file=sys.stderr)
    elif not args.quiet:
        print(f"boringbar run: {report.line()}")
    return 0


def add_paper(sub) -> None:
    p = sub.add_parser(
        "paper", help="rerun the whole published study under both presets, with an HTML report",
        description="Rerun every published analysis (docs/model.md, section 6: frequency sweeps, "
                    "stability lobes, bifurcation diagrams, basins of attraction, sensitivity) "
                    "under the paper and the physical preset, measure what each correction "
                    "to the published equations changes, and write DIR/report.html with the "
                    "two presets side by side.  Each analysis is one boringbar command (shown "
                    "in the report) writing DIR/<preset>/<analysis>/; finished analyses are "
                    "kept, so the same command after an interruption runs only the rest.")
    p.add_argument("--out", default="out/paper", metavar="DIR",
                   help="output directory (default: out/paper)")
    p.add_argument("--quick", action="store_true",
                   help="coarser grids and 0.5 s runs (1 s cuts): a few minutes on 2 cores")
    p.add_argument("--presets", default=",".join(COLUMN_ORDER), metavar="P,...",
                   help="columns to run, comma list: the presets paper, physical and the "
                        "audit's further columns paper-reciprocal (the printed reaction "
                        "corrected), physical-paper-friction (the published 20.4 N "
                        "friction, reciprocal), physical-rolling (a rolling ball); "
                        "default: all five")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (the manifest) on stdout")
    p.set_defaults(func=cmd_paper)


def cmd_paper(args: argparse.Namespace) -> int:
    presets = [w.strip() for w in args.presets.split(",") if w.strip()]
    bad = [w for w in presets if w not in COLUMN_ORDER]
    if bad or not presets or len(set(presets)) != len(presets):
        raise ParameterError(f"--presets = {args.presets!r}: a comma list of distinct "
                             f"columns from {', '.join(COLUMN_ORDER)}")
    try:
        manifest = run_paper(args.out, quick=args.quick, quiet=args.quiet,
                             presets=tuple(p for p in COLUMN_ORDER if p in presets))
    except StepFailed as exc:  # one analysis failed: the others finished are kept
        print(f"boringbar: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps(jsonable(manifest), allow_nan=False))
    elif not args.quiet:
        print(f"boringbar paper: wrote {manifest['report']}")
    return 0
