"""A command's first run on a new machine: its wall time on an empty numba cache, and
each kernel compile within it.

    .venv/bin/python benchmarks/first_use.py simulate --out /tmp/first
    .venv/bin/python benchmarks/first_use.py simulate --integrator rk4 --out /tmp/first
    .venv/bin/python benchmarks/first_use.py paper --quick --out /tmp/first-paper

The arguments are a ``boringbar`` command line, run in this process through the
command line's own entry point with ``NUMBA_CACHE_DIR`` a new empty directory (what
a fresh clone has; pip's install is not included).  Every outermost ``numba:compile``
event of this process prints a line (clock, compiled function, wall and CPU
seconds; the callees it compiled are inside it), then the totals: the wall time,
the time spent compiling and its share.  Worker processes' compiles (a sweep's
process pool) are not seen; the published study warms its kernels in this process
first.
"""

from __future__ import annotations

import os
import sys
import tempfile
import threading
import time

# one new cache for this run, also in the processes it spawns (which import this module
# again, as __mp_main__: they must not make a cache of their own)
os.environ.setdefault("BORINGBAR_FIRST_USE_CACHE", tempfile.mkdtemp(prefix="numba-first-use-"))
os.environ["NUMBA_CACHE_DIR"] = os.environ["BORINGBAR_FIRST_USE_CACHE"]

_T0 = time.perf_counter()  # the command line's import is timed too

from numba.core import event  # noqa: E402

from boringbar.cli.main import main as cli  # noqa: E402


class Compiles(event.Listener):
    """Prints and sums the outermost compiles of each thread."""

    def __init__(self):
        self.depth: dict[int, int] = {}
        self.start: dict[int, tuple] = {}
        self.total = 0.0

    def on_start(self, ev):
        k = threading.get_ident()
        self.depth[k] = self.depth.get(k, 0) + 1
        if self.depth[k] == 1:
            func = getattr((ev.data or {}).get("dispatcher"), "py_func", None)
            name = f"{getattr(func, '__module__', '?')}.{getattr(func, '__name__', '?')}"
            self.start[k] = (name, time.perf_counter(), time.process_time())

    def on_end(self, ev):
        k = threading.get_ident()
        self.depth[k] -= 1
        if self.depth[k] == 0:
            name, wall, cpu = self.start.pop(k)
            wall = time.perf_counter() - wall
            self.total += wall
            print(f"first_use: {time.strftime('%H:%M:%S')} compiled {name}: {wall:.1f} s "
                  f"({time.process_time() - cpu:.1f} s CPU)", file=sys.stderr, flush=True)


def main(argv: list[str]) -> int:
    compiles = Compiles()
    event.register("numba:compile", compiles)
    load = os.getloadavg()[0]
    rc = cli(argv)
    wall = time.perf_counter() - _T0
    print(f"first_use: boringbar {' '.join(argv)}: {wall:.1f} s wall (exit {rc}), "
          f"{compiles.total:.1f} s compiling ({compiles.total / wall:.0%}); "
          f"load {load:.1f} at the start", file=sys.stderr)
    return 0 if rc in (0, None) else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
