"""Progress on stderr, in one place: a tqdm bar for the study runner and the
``progress(done, total)`` callbacks the analyses accept.

Drawn only where asked (the command line: stderr is a terminal and not
``--quiet``); the library itself never draws unless given a callback.
"""

from __future__ import annotations

import sys

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
