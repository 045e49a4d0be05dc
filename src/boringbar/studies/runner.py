"""Run a study: chunks of its points on an executor, into a resumable store.

:func:`run_study` expands a :class:`~boringbar.studies.schema.Study` into its points
(:mod:`boringbar.studies.registry`), cuts the points not yet done into chunks and runs
them serially, on local processes or on a Dask cluster.  Every finished
chunk is written at once, atomically, to ``OUT.partial/`` (one pickle file
per chunk, beside a manifest holding the study's configuration hash), so a
run that is killed, even with SIGKILL, and started again with the same
study computes only the missing points.  When every point is done the
Dataset is assembled in point order, written to ``OUT`` atomically (a
temporary file or directory in the same folder, then a rename) and the
partial directory is removed.  Each point is a pure function of the study,
so the result is the same, bit for bit, whichever executor ran which chunk
and however often the run was interrupted.

Executors: ``serial`` (this process); ``processes`` (default: one worker
process per core; a worker that dies breaks the pool, which is recreated and
the unfinished chunks resubmitted); ``dask`` (``scheduler`` address, or
``dask_local`` = N starts a LocalCluster of N single-threaded worker processes;
tasks of a worker that dies are rerun by the scheduler).

Fault injection for tests: with ``BORINGBAR_FAULT_KILL_CHUNK=i`` and
``BORINGBAR_FAULT_MARKER=PATH`` in the environment, the first worker process
to start chunk ``i`` creates PATH and kills itself (``os._exit``); the serial
executor never does.  Nothing happens unless both are set.  With
``BORINGBAR_FAULT_STALL_CHUNK=i`` a worker that starts chunk ``i`` sleeps for ten
minutes instead, so a test that kills the run can be sure it is still running.
"""

from __future__ import annotations

import contextlib
import functools
import json
import logging
import math
import os
import pickle
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import xarray as xr

from boringbar._validate import ParameterError
from boringbar.execute import Execution, stream
from boringbar.io import atomic_path, fsync_dir, write_json_atomic, write_netcdf_atomic
from boringbar.progress import progress_bar
from boringbar.studies.registry import ANALYSES
from boringbar.studies.schema import Study, StudyError, output_format
from boringbar.version import __version__

log = logging.getLogger("boringbar.studies.runner")

#: the executors a study runs on (boringbar.execute; threads would not survive a kill)
EXECUTORS = ("serial", "processes", "dask")
MANIFEST = "manifest.json"


@dataclass
class RunReport:
    """What :func:`run_study` did (the CLI prints it as the summary line)."""

    out: str = ""
    analysis: str = ""
    points: int = 0
    computed: int = 0
    resumed: int = 0
    skipped: bool = False  #: OUT already held this study's finished result
    executor: str = ""
    workers: int = 0
    wall_time_s: float = 0.0
    restarts: list = field(default_factory=list)

    @property
    def rate(self) -> float:
        return self.computed / self.wall_time_s if self.wall_time_s > 0 else math.nan

    def line(self) -> str:
        if self.skipped:
            return (f"{self.analysis}: {self.out} already holds this study's result "
                    f"({self.points} points); nothing to do")
        resumed = f", {self.resumed} resumed" if self.resumed else ""
        return (f"{self.analysis}: {self.points} points ({self.computed} run{resumed}) in "
                f"{self.wall_time_s:.1f} s, {self.rate:.2f} points/s on {self.executor} "
                f"x{self.workers} -> {self.out}")

    def to_dict(self) -> dict:
        return {"out": self.out, "analysis": self.analysis, "points": self.points,
                "computed": self.computed, "resumed": self.resumed, "skipped": self.skipped,
                "executor": self.executor, "workers": self.workers,
                "wall_time_s": self.wall_time_s,
                "points_per_s": None if math.isnan(self.rate) else self.rate,
                "restarts": self.restarts}


# --- work done in a worker ---------------------------------------------------------

_PLANS: dict[str, tuple] = {}


def _planned(study: Study, key: str):
    """(analysis, plan) of ``study``, made once per process."""
    if key not in _PLANS:
        analysis = ANALYSES[study.analysis]
        plan = analysis.plan(study)
        _PLANS.clear()
        _PLANS[key] = (analysis, plan)
    return _PLANS[key]


def _maybe_die(chunk: int) -> None:
    stall = os.environ.get("BORINGBAR_FAULT_STALL_CHUNK")
    if stall is not None and int(stall) == chunk:
        time.sleep(600)
    target, marker = (os.environ.get("BORINGBAR_FAULT_KILL_CHUNK"),
                      os.environ.get("BORINGBAR_FAULT_MARKER"))
    if target is None or marker is None or int(target) != chunk:
        return
    try:
        fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return
    os.close(fd)
    os._exit(17)  # a real process death: no cleanup, no exception


def compute_chunk(study: Study, key: str, remote: bool, task: tuple[int, list]):
    """The results of the points ``indices`` of chunk ``task = (chunk, indices)`` of
    ``study`` (what every executor runs; ``remote``: in a worker, not this process)."""
    chunk, indices = task
    if remote:
        _maybe_die(chunk)
    analysis, plan = _planned(study, key)
    return chunk, [analysis.compute(plan.context, plan.points[i]) for i in indices]


# --- the store -----------------------------------------------------------------------

def _format(study: Study, out: Path, given: bool) -> str:
    """The result's format: from the suffix of ``out`` (.nc or .zarr), which must
    match the study's ``format``."""
    try:
        return output_format(out, study.format, "out" if given else "key 'study.out'")
    except ParameterError as exc:
        raise StudyError(f"{study.source}: {exc}") from None


def _open(out: Path, fmt: str):
    if fmt == "zarr":
        with xr.open_zarr(out, consolidated=None) as ds:
            return ds.load()
    return xr.load_dataset(out)


def _finished(out: Path, fmt: str, key: str):
    """The finished result at ``out`` if it is this study's; None if ``out`` does not
    exist; StudyError if it holds something else."""
    if not out.exists():
        return None
    try:
        ds = _open(out, fmt)
    except Exception as exc:  # noqa: BLE001 - any unreadable file is refused the same way
        raise StudyError(f"{out} exists and is not a readable study result ({exc}); "
                         "remove it or choose another output") from None
    if ds.attrs.get("study_config_hash") != key:
        raise StudyError(f"{out} holds the result of a different study (configuration hash "
                         f"{str(ds.attrs.get('study_config_hash'))[:12]}, this study "
                         f"{key[:12]}); remove it or choose another output")
    return ds


class _Partial:
    """``OUT.partial/``: the manifest and one file per finished chunk."""

    def __init__(self, out: Path, study: Study, key: str, n_points: int):
        self.dir = out.with_name(out.name + ".partial")
        self.key = key
        manifest = self.dir / MANIFEST
        if manifest.exists():
            m = json.loads(manifest.read_text())
            if m.get("config_hash") != key:
                raise StudyError(
                    f"{self.dir} holds the unfinished chunks of a different study "
                    f"(configuration hash {str(m.get('config_hash'))[:12]}, this study "
                    f"{key[:12]}, from {m.get('source')}); run that study to finish it, or "
                    "remove the directory to start this one")
            if m.get("points", n_points) != n_points:
                raise StudyError(
                    f"{self.dir} holds chunks of this study cut into {m.get('points')} points "
                    f"by another version of boringbar (this one makes {n_points}); remove the "
                    "directory to start again")
        else:
            self.dir.mkdir(parents=True, exist_ok=True)

            write_json_atomic({"config_hash": key, "source": study.source,
                               "analysis": study.analysis, "points": n_points,
                               "boringbar_version": __version__, "config": study.to_dict()},
                              manifest)

    @staticmethod
    def belongs(directory: Path, key: str) -> bool:
        with contextlib.suppress(OSError, ValueError):
            return json.loads((directory / MANIFEST).read_text()).get("config_hash") == key
        return False

    def load(self) -> dict:
        """index -> result of every point already done."""
        done = {}
        for f in sorted(self.dir.glob("chunk-*.pkl")):
            try:
                with open(f, "rb") as fh:
                    rec = pickle.load(fh)
                if rec["config_hash"] != self.key:
                    continue
            except Exception:  # noqa: BLE001 - cannot happen with atomic writes; redo it
                log.warning("ignoring unreadable chunk file %s", f)
                continue
            done.update(zip(rec["indices"], rec["results"], strict=True))
        return done

    def save(self, indices: list, results: list) -> None:
        path = self.dir / f"chunk-{indices[0]:09d}-{indices[-1]:09d}.pkl"
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            pickle.dump({"config_hash": self.key, "indices": list(indices),
                         "results": results}, fh, protocol=pickle.HIGHEST_PROTOCOL)

    def remove(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)


def _write(ds, out: Path, fmt: str) -> None:
    if fmt == "netcdf":
        write_netcdf_atomic(ds, out)
        return
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp"))
    try:
        ds.to_zarr(tmp, mode="w", zarr_format=2, consolidated=True)
        os.replace(tmp, out)  # out does not exist (checked before the run)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    fsync_dir(out.parent)


# --- entry point ---------------------------------------------------------------------

def run_study(study: Study, out=None, *, executor: str = "processes", workers: int | None = None,
              scheduler: str | None = None, dask_local: int | None = None,
              chunk_size: int | None = None, quiet: bool = True, progress=None,
              report: RunReport | None = None):
    """Run ``study`` into ``out`` (``.nc`` NetCDF, ``.zarr`` Zarr; default the
    study's own output) and return the Dataset as written.

    ``executor``: "serial", "processes" (``workers`` processes, default every
    core) or "dask" (``scheduler`` address, or ``dask_local`` workers on a
    LocalCluster; giving either selects Dask).  ``chunk_size``: points per task
    (default: about four tasks per worker, at most 64 points).  ``quiet`` False
    draws a progress bar on stderr; ``progress(done, total)`` is called as chunks
    finish.  ``report``: a :class:`RunReport` filled in with what was done.

    Resumable: finished chunks are kept in ``OUT.partial/`` until the whole
    result is written; the same call after an interruption runs only the
    missing points.  If ``out`` already holds this study's finished result it
    is returned without running anything; if it holds anything else, or the
    partial directory belongs to another study, StudyError says what to do.
    """

    report = RunReport() if report is None else report
    execution = _execution(executor, workers, scheduler, dask_local)
    if chunk_size is not None and (isinstance(chunk_size, bool) or not isinstance(chunk_size, int)
                                   or chunk_size < 1):
        raise ParameterError(f"chunk_size = {chunk_size!r} must be an integer >= 1")
    fmt = _format(study, study.output_path(out), given=out is not None)
    out = study.output_path(out)
    key = study.config_hash()
    analysis = ANALYSES[study.analysis]
    report.__dict__.update(out=str(out), analysis=study.analysis,
                           executor=execution.executor, workers=execution.n_workers)
    tic = time.perf_counter()
    ds = _finished(out, fmt, key)
    plan = analysis.plan(study)  # validates everything before any work
    report.points = len(plan.points)
    if ds is not None:
        report.skipped = True
        stale = out.with_name(out.name + ".partial")
        if stale.is_dir() and _Partial.belongs(stale, key):
            shutil.rmtree(stale, ignore_errors=True)  # killed after OUT was written
        log.debug("%s already holds this study's result; not recomputed", out)
        return ds
    part = _Partial(out, study, key, len(plan.points))
    done = _run_missing(study, key, analysis, plan, part, execution, chunk_size,
                        quiet, progress, report)
    wall = time.perf_counter() - tic
    ds = analysis.assemble(study, plan, [done[i] for i in range(len(plan.points))])
    ds.attrs.update(_provenance(study, key, wall, execution, len(plan.points)))
    _write(ds, out, fmt)
    part.remove()
    report.wall_time_s = wall
    return _open(out, fmt)


def _execution(executor: str, workers, scheduler, dask_local) -> Execution:
    """The study's executor (a scheduler or a LocalCluster selects Dask)."""
    if scheduler is not None or dask_local is not None:
        if executor not in ("dask", "processes"):
            raise ParameterError(f"executor = {executor!r} conflicts with a Dask scheduler "
                                 "or LocalCluster (use executor 'dask')")
        executor = "dask"
    if executor not in EXECUTORS:
        raise ParameterError(f"executor = {executor!r} is not one of {', '.join(EXECUTORS)}")
    if executor == "dask" and scheduler is None and dask_local is None:
        dask_local = workers or os.cpu_count() or 1
    return Execution(executor, workers, scheduler, dask_local)


def _run_missing(study, key, analysis, plan, part, execution, chunk_size, quiet, progress,
                 report) -> dict:
    """Every point not in ``part`` yet, in chunks on ``execution``, each chunk saved to
    ``part`` as it finishes; index -> result of every point."""
    n = len(plan.points)
    done = part.load()
    report.resumed = len(done)
    missing = [i for i in range(n) if i not in done]
    if done:
        log.info("resuming %s: %d of %d points already done", part.dir, len(done), n)
    if chunk_size is None:
        chunk_size = max(1, min(64, math.ceil(len(missing) / (4 * execution.n_workers))))
    chunks = {c: missing[s:s + chunk_size]
              for c, s in enumerate(range(0, len(missing), chunk_size))}
    if chunks and execution.executor != "dask":
        # plan once here: forked workers inherit it
        _PLANS.clear()
        _PLANS[key] = (analysis, plan)
    bar = progress_bar(n, done=len(done), enabled=not quiet)

    def on_done(cid: int, results: list) -> None:
        idx = chunks[cid]
        part.save(idx, results)
        done.update(zip(idx, results, strict=True))
        report.computed += len(idx)
        bar.update(len(idx))
        if progress is not None:
            progress(len(done), n)

    def on_restart(msg: str) -> None:
        log.warning(msg)
        report.restarts.append(msg)

    fn = functools.partial(compute_chunk, study, key, execution.executor != "serial")
    try:
        stream(fn, {cid: (cid, idx) for cid, idx in chunks.items()},
               lambda cid, res: on_done(*res), execution=execution, on_restart=on_restart,
               task_name=f"boringbar-chunk-{key[:12]}")
    except ChildProcessError as exc:
        raise ChildProcessError(f"{exc} (the finished chunks are kept: run the same command "
                                "again to resume)") from None
    finally:
        bar.close()
    return done


def _provenance(study: Study, key: str, wall: float, execution: Execution, n: int) -> dict:
    """The result file's provenance attributes."""
    return {
        "boringbar_version": __version__,
        "study_name": study.name,
        "study_source": str(study.source),
        "study_config": json.dumps(study.to_dict(), sort_keys=True),
        "study_config_hash": key,
        "run_finished_utc": datetime.now(UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "run_wall_time_s": wall,
        "run_executor": execution.executor,
        "run_workers": execution.n_workers,
        "run_points": n,
    }
