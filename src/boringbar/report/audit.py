"""The reproduction audit: every published claim (``claims.toml``) judged against the
data that ``boringbar paper`` wrote, under each preset.

A claim's verdict is computed from the files, never written in advance:

- **reproduced**: the claim holds, within the tolerance its check states;
- **partly**: the qualitative part holds and a number does not (the reason says
  by how much);
- **not reproduced**: the qualitative part fails (the reason says what the data
  show instead);
- **not available**: the output lacks what the check needs (a step missing).

The checks are in :mod:`boringbar.report.audit_checks`, the output folder's
reader in :mod:`boringbar.report.audit_data`; this module runs them and counts
the verdicts.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from importlib import resources

from boringbar.report.audit_checks import CHECKS
from boringbar.report.audit_data import VERDICTS, Evidence, Verdict


def load_claims() -> list[dict]:
    """The published claims, in order (report/claims.toml)."""
    text = resources.files("boringbar.report").joinpath("claims.toml").read_text()
    return tomllib.loads(text)["claim"]


def audit(out, checks: dict[str, Callable] | None = None) -> dict:
    """Judge every claim against the paper output in ``out``: ``claims`` (id,
    statement, published, conditions, source, and per preset the verdict,
    measured numbers, reason and figure), ``counts`` per preset and verdict,
    ``quick`` and ``presets``."""
    checks = CHECKS if checks is None else checks
    ev = Evidence(out)
    rows = []
    for claim in load_claims():
        check = checks[claim["id"]]
        per = {}
        for preset in ev.presets:
            try:
                per[preset] = check(ev, preset)
            except (KeyError, IndexError, TypeError, ValueError) as exc:
                per[preset] = Verdict("not available", reason=f"the output lacks what "
                                      f"this check reads ({type(exc).__name__}: {exc})")
        rows.append({**{k: claim[k] for k in ("id", "statement", "conditions", "source")},
                     "published": [{"name": n, "value": v, "unit": u}
                                   for n, v, u in claim["published"]],
                     "verdict": {p: v.verdict for p, v in per.items()},
                     "measured": {p: v.measured for p, v in per.items()},
                     "reason": {p: v.reason for p, v in per.items()},
                     "figure": {p: v.figure for p, v in per.items()}})
    counts = {p: {v: sum(r["verdict"][p] == v for r in rows) for v in VERDICTS}
              for p in ev.presets}
    return {"out": str(ev.out), "quick": ev.quick, "presets": ev.presets,
            "variants": list(ev.variants.values()), "claims": rows, "counts": counts}


def count_line(result: dict, preset: str) -> str:
    """'paper preset: 11 reproduced, 9 partly, 8 not, 1 not available' (a further
    column by its name alone)."""
    c = result["counts"][preset]
    variant = any(v["name"] == preset for v in result.get("variants", ()))
    name = preset if variant else f"{preset} preset"
    return (f"{name}: {c['reproduced']} reproduced, {c['partly']} partly, "
            f"{c['not reproduced']} not" + (f", {c['not available']} not available"
                                            if c["not available"] else ""))
