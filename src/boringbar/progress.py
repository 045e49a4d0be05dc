"""Progress on stderr, in one place: a tqdm bar for the study runner and the
``progress(done, total)`` callbacks the analyses accept.

Drawn only where asked (the command line, without ``--quiet``: a bar where stderr is
a terminal, a line at each tenth of the work where it is a log); the library itself
never draws unless given a callback.
"""

from __future__ import annotations

import math
import sys
import time

from tqdm import tqdm


def progress_bar(total: int, *, done: int = 0, label: str = "points",
                 enabled: bool = True) -> tqdm:
    """A tqdm bar on stderr at ``done`` of ``total`` ``label``: rate and time left;
    ``bar.update(n)`` as work finishes, ``bar.close()`` at the end."""
    return tqdm(total=total, initial=done, unit=f" {label}", disable=not enabled,
                file=sys.stderr, dynamic_ncols=True, smoothing=0.1)


class ProgressCallback:
    """A ``progress(done, total)`` callback (what :func:`boringbar.sweep` and the other
    analyses call) drawing a :func:`progress_bar` labelled ``desc``."""

    def __init__(self, desc: str, label: str):
        self.desc, self.label, self.bar = desc, label, None

    def __call__(self, done: int, total: int) -> None:
        if self.bar is None:
            self.bar = progress_bar(total, label=self.label)
            self.bar.set_description(self.desc)
        self.bar.update(done - self.bar.n)
        if done >= total:
            self.bar.close()


class LineProgress:
    """A ``progress(done, total)`` callback for a log, where a bar's redrawing would be
    noise: a line on stderr at the first report and at each ``step`` of the work, with
    the time since it was made, as the work began ("boringbar lobes: 96/960 (case,
    speed) columns, 57 s")."""

    def __init__(self, desc: str, label: str, step: float = 0.1):
        self.desc, self.label, self.step = desc, label, step
        self.next, self.t0 = 0.0, time.perf_counter()

    def __call__(self, done: int, total: int) -> None:
        frac = done / total if total else 1.0
        if frac < self.next and done < total:
            return
        print(f"{self.desc}: {done}/{total} {self.label}, "
              f"{time.perf_counter() - self.t0:.3g} s", file=sys.stderr, flush=True)
        self.next = (math.floor(frac / self.step + 1e-9) + 1) * self.step
