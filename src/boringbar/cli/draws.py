"""``boringbar lobes --draws N``: the chance of chatter's options on the command line
(:mod:`boringbar.analysis.chatter_probability`; docs/chatter_probability.md)."""

from __future__ import annotations

import numpy as np

from boringbar._validate import ParameterError, check_int, check_range
from boringbar.analysis.chatter_probability import (
    DAMPING_COV,
    FRICTION_SPREAD,
    MAX_DRAWS,
    PROBABILITY,
    RESTITUTION_SPREAD,
    STIFFNESS_COV,
    Uncertainty,
)
from boringbar.model.forcing import MAX_NOISE_STD

#: flag -> (attribute, default, lowest, highest, what the highest may not reach)
FLAGS = {
    "--stiffness-cov": ("stiffness_cov", STIFFNESS_COV, 0.0, 1.0, False),
    "--damping-cov": ("damping_cov", DAMPING_COV, 0.0, 10.0, False),
    "--friction-spread": ("friction_spread", FRICTION_SPREAD, 0.0, 1.0, False),
    "--restitution-spread": ("restitution_spread", RESTITUTION_SPREAD, 0.0, 1.0, False),
    "--force-noise": ("force_noise", 0.0, 0.0, MAX_NOISE_STD, True),
}


def add_draws(g) -> None:
    """The draws' flags (none drawn without --draws)."""
    g.add_argument("--draws", type=int, metavar="N",
                   help="also the lobes of N draws of what nobody measures well, and the "
                        "chance of chatter they give: its 5/50/95 %% contours on the figure, "
                        "P(chatter) with its Wilson 95 %% interval in DIR/lobes.nc "
                        "(--criterion growth; docs/chatter_probability.md)")
    g.add_argument("--seed", type=int, metavar="N",
                   help="the draws' seed: draw d is a function of (seed, d) (default: 0)")
    g.add_argument("--stiffness-cov", type=float, metavar="X",
                   help=f"coefficient of variation of each mode's stiffness (default: "
                        f"{STIFFNESS_COV:g})")
    g.add_argument("--damping-cov", type=float, metavar="X",
                   help=f"coefficient of variation of each mode's damping ratio (default: "
                        f"{DAMPING_COV:g})")
    g.add_argument("--friction-spread", type=float, metavar="X",
                   help=f"a ball's friction force uniform on its value times 1 +- X "
                        f"(default: {FRICTION_SPREAD:g})")
    g.add_argument("--restitution-spread", type=float, metavar="X",
                   help=f"a ball's restitution uniform on its value +- X (default: "
                        f"{RESTITUTION_SPREAD:g})")
    g.add_argument("--force-noise", type=float, metavar="X",
                   help="relative standard deviation of the cutting force's noise, in [0, 1) "
                        "(default: 0; measured in turning: 0.04-0.09; a noisy cut costs some "
                        "fifty times a quiet one)")
    g.add_argument("--fixed-ball-start", action="store_true",
                   help="start a free ball where the verdict does, not anywhere across its gap")
    g.add_argument("--probability", type=float, metavar="P",
                   help=f"the chance of chatter a robust depth allows, in (0, 1) (default: "
                        f"{PROBABILITY:g})")


def uncertainty_options(args) -> Uncertainty | None:
    """The draws of the command line, each flag checked under its name; None without
    --draws (then no other draw flag may be given)."""
    given = [f for f in ("--seed", "--probability", *FLAGS)
             if getattr(args, _attr(f)) is not None] + \
        (["--fixed-ball-start"] if args.fixed_ball_start else [])
    if args.draws is None:
        if given:
            raise ParameterError(f"{given[0]} needs --draws N (the number of draws)")
        return None
    check_int("--draws", args.draws, 1, MAX_DRAWS)
    seed = 0 if args.seed is None else check_int("--seed", args.seed, 0, 2**63 - 1)
    p = PROBABILITY if args.probability is None else args.probability
    check_range("--probability", p, 0.0, 1.0, lo_open=True, hi_open=True)
    values = {}
    for flag, (name, default, lo, hi, hi_open) in FLAGS.items():
        v = getattr(args, _attr(flag))
        values[name] = check_range(flag, default if v is None else v, lo, hi, hi_open=hi_open)
    return Uncertainty(draws=args.draws, seed=seed, ball_start=not args.fixed_ball_start,
                       probability=p, **values)


def _attr(flag: str) -> str:
    return flag.removeprefix("--").replace("-", "_")


def draws_text(ds) -> str:
    """The chance of chatter of a lobes Dataset in a few lines (empty without draws)."""
    if "robust_depth_m" not in ds:
        return ""
    p, n = float(ds.attrs["probability"]), int(ds.attrs["draws"])
    lines = []
    for i, label in enumerate(ds["case"].values):
        robust = ds["robust_depth_m"].values[i]
        if not np.isfinite(robust).any():
            lines.append(f"{label}: no draw chatters up to the deepest cut tried")
            continue
        j = int(np.nanargmin(robust))
        lines.append(f"{label}: robust depth (P(chatter) <= {p:g} over {n} draws) "
                     f"{robust[j] * 1e3:.4g} mm at {ds['rpm'].values[j]:g} rpm; the 5/50/95 % "
                     "contours are in lobes.nc (limit_depth_quantile_m) and on lobes.png")
    return "\n".join(lines)
