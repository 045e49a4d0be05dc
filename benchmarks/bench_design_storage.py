"""What keeping a design search's trials on disk costs, through bb.design.

    .venv/bin/python benchmarks/bench_design_storage.py [--trials 60,200] [--repeat 3]

The published absorber's tuning (report/designs/tmd.toml: NSGA-II on the FRF peak and the
most negative real part, both closed forms, so that the storage's share shows), run with
``--trials`` trials three ways in one process, round robin, best of ``--repeat``: in
memory (nothing kept), in the journal file that ``boringbar design`` keeps
(``design_storage``), and in Optuna's SQLite (``RDBStorage``, written ahead to a log and
synced at checkpoints: the storage the design search kept before the journal). Each
storage a new file in a temporary folder; the same trial table from all three.
"""

from __future__ import annotations

import argparse
import sqlite3
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import optuna
from machine import describe

import boringbar as bb
from boringbar.analysis.design import design_storage
from boringbar.analysis.design_file import load_design
from boringbar.report.paper import design_file


def sqlite_storage(path: Path) -> optuna.storages.RDBStorage:
    def connect() -> sqlite3.Connection:
        connection = sqlite3.connect(path, check_same_thread=False)
        connection.execute("PRAGMA journal_mode=WAL")
        connection.execute("PRAGMA synchronous=NORMAL")
        return connection
    return optuna.storages.RDBStorage(f"sqlite:///{path}", engine_kwargs={"creator": connect})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", default="60,200")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    options, spec = load_design(design_file("tmd"))
    print(f"machine: {describe()}")
    folder = Path(tempfile.mkdtemp(prefix="bench-design-storage-"))
    kinds = {"memory": lambda p: None, "journal": lambda p: design_storage(p),
             "SQLite": sqlite_storage}
    for trials in (int(t) for t in args.trials.split(",")):
        o = replace(options, trials=trials)
        best, tables = {k: np.inf for k in kinds}, {}
        for r in range(args.repeat):
            for kind, make in kinds.items():
                storage = make(folder / f"{kind}-{trials}-{r}")
                tic = time.perf_counter()
                ds = bb.design(o, spec=spec, storage=storage)
                best[kind] = min(best[kind], time.perf_counter() - tic)
                tables[kind] = ds["statistic"].values
        same = all(np.array_equal(tables["memory"], t) for t in tables.values())
        print(f"{trials} trials: " + ", ".join(f"{k} {v:.2f} s" for k, v in best.items())
              + f"; journal/memory {best['journal'] / best['memory']:.2f}x, "
              f"SQLite/journal {best['SQLite'] / best['journal']:.2f}x; "
              f"same trial table: {same}")


if __name__ == "__main__":
    main()
