"""``boringbar compile``: compile every kernel specialisation ahead of time (a cluster
image, a fresh install), in parallel processes; cached ones are only loaded."""

from __future__ import annotations

import sys

from boringbar._validate import ParameterError, check_int
from boringbar.cli.options import Outcome
from boringbar.kernels.compile import KINDS, compile_all


def add_compile(sub) -> None:
    p = sub.add_parser(
        "compile", help="compile every numba kernel now (first use is then instant)",
        description="Compile every kernel specialisation the package uses (the exact "
                    "integrator, the RK4 kernel per mode count, the lock-step batch kernels) "
                    "into numba's on-disk cache, in parallel processes: what the first run "
                    "of each analysis would otherwise do.  Cached specialisations are "
                    "loaded, not compiled again.")
    p.add_argument("--kinds", default=",".join(KINDS), metavar="K,...",
                   help=f"which kernels, comma list of {', '.join(KINDS)} (default: all)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="compiling processes (default: every core)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_compile)


def cmd_compile(args) -> Outcome:
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise ParameterError(f"--kinds = {args.kinds!r}: a comma list of {', '.join(KINDS)}")
    if args.workers is not None:
        check_int("--workers", args.workers, 1, 4096)

    def progress(c, i, n):
        if not args.quiet and not args.json:
            print(f"[{i}/{n}] {c.name}: {c.status} in {c.seconds:.0f} s", file=sys.stderr,
                  flush=True)

    done = compile_all(tuple(kinds), workers=args.workers, progress=progress)
    summary = {"kernels": [{"name": c.name, "status": c.status, "seconds": c.seconds,
                            "cpu_seconds": c.cpu_seconds} for c in done],
               "compiled": sum(c.status == "compiled" for c in done),
               "cached": sum(c.status == "cached" for c in done)}

    def text(say) -> None:
        say(f"{summary['compiled']} kernels compiled, {summary['cached']} already cached")

    return Outcome(summary, text)
