"""``boringbar audit DIR``: the published claims judged against an existing
``boringbar paper`` output, without rerunning anything (docs/audit.md)."""

from __future__ import annotations

from boringbar.cli.options import Outcome
from boringbar.report.audit import audit, count_line


def add_audit(sub) -> None:
    p = sub.add_parser("audit", help="judge every published claim against a paper output",
                       description="Judge every claim of the published study against the "
                                   "files of an existing 'boringbar paper' output (DIR), under "
                                   "each preset: reproduced, partly, not reproduced or not "
                                   "available, with the measured numbers and the reason. "
                                   "Reruns nothing.")
    p.add_argument("dir", metavar="DIR", help="the output folder of boringbar paper")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true", help="no human summary")
    p.set_defaults(func=cmd_audit)


def cmd_audit(args) -> Outcome:
    result = audit(args.dir)

    def text(say) -> None:
        if result["quick"]:
            say("quick output: coarser grids and shorter runs than published")
        for preset in result["presets"]:
            say(count_line(result, preset))
        say("")
        width = max(max(len(p) for p in result["presets"]), 14)
        say(f"{'':<4} " + "  ".join(f"{p:<{width}}" for p in result["presets"]) + "  claim")
        for c in result["claims"]:
            cells = "  ".join(f"{c['verdict'][p]:<{width}}" for p in result["presets"])
            say(f"{c['id']:<4} {cells}  {_short(c['statement'])}")
        say("\n(--json, or the report's folded table, for each claim's numbers and the reason "
            "for its verdict)")

    return Outcome(result, text)


def _short(statement: str, width: int = 60) -> str:
    """A claim's statement cut to ``width`` characters at a word."""
    if len(statement) <= width:
        return statement
    return statement[:width].rsplit(" ", 1)[0] + " ..."
